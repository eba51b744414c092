//! Camera selection for near-field rendering: which capture cameras, with which weights, serve a view
//! direction `u` (a unit vector from the capture-sphere centre, luminaire frame).
//!
//! # Modes
//! - [`SelectionMode::Nearest`]: the camera whose direction is nearest to `u` (great-circle angle).
//! - [`SelectionMode::Idw4`]: the 4 nearest cameras, weights ∝ 1 / angle (a camera closer than
//!   10⁻⁷ rad takes weight 1 alone), normalised to sum 1.
//! - [`SelectionMode::Continuous`] (default): barycentric weights over the spherical Delaunay
//!   triangulation of the camera directions. Continuous (C0) in `u`, exact for data linear in the
//!   direction, and reduces to the camera itself at a camera direction.
//!
//! Nearest and Idw4 ignore cameras farther than [`Selection::max_gap_rad`] from `u`; Continuous
//! returns nothing inside a *hole*. Either way an empty [`Weights`] means "nothing was measured here".
//!
//! # Build ([`Selection::build`])
//! 1. **Vertices.** dᵢ = unit(cameraᵢ.position − centre). Cameras within `merge_tol_rad` of each other
//!    ([`RayImageSet::coincident_groups`], e.g. the meridian starts at a pole) become one vertex whose
//!    camera is the group's lowest index. Vertices are the unique directions in camera order.
//! 2. **Spherical Delaunay triangulation** = the convex hull of the unit vectors. Vertex 0 is rotated to
//!    +Z and every other vertex is projected stereographically from it, (x, y) = (X, Y) / (1 − Z), and
//!    triangulated in the plane by `delaunator`. This is exact, not an approximation: stereographic
//!    projection maps circles on the sphere to circles in the plane (circles through the pole to
//!    lines) and the side of a circumcircle not holding the pole to the disc's inside, so a spherical
//!    triangle has an empty circumcap iff its image has an empty circumcircle. The triangles with
//!    vertex 0 are those whose circumcircles pass through the pole, i.e. straight lines with an empty
//!    half-plane: the planar convex-hull edges. One triangle `(p0, hull[i], hull[i+1])` per hull edge
//!    closes the sphere. Every triangle (a, b, c) is oriented with det(a, b, c) = a · (b × c) > 0
//!    (counter-clockwise seen from outside), and the result is checked to be a closed sphere
//!    (T = 2V − 4, every vertex used, every edge shared by two triangles with opposite directions).
//! 3. **Holes.** The circumradius R_t of a triangle is the angle from its circumcentre (the unit normal
//!    of its plane on the side of a + b + c) to a vertex. With R_med the median of R_t, a triangle is a
//!    hole when R_t > `hole_factor` · R_med: it spans a region no camera measured (e.g. the unmeasured
//!    hemisphere of a one-hemisphere scan). `max_gap_rad = hole_factor · R_med` bounds Nearest/Idw4 the
//!    same way. When the camera directions do not surround the centre (their convex hull misses it,
//!    e.g. only a cap of the sphere was measured), the hull faces seen from the centre are *folded*:
//!    in the triangulation's own orientation det ≤ 0, and their great-circle triangles would cover the
//!    measured region a second time. Folded triangles are holes and are left out of every cell list,
//!    so the measured region stays covered once; the unmeasured region then has no triangle, and a
//!    query there returns nothing, except within a cell of the measured border, where the fallback
//!    below clamps to the nearest border triangle. See [`SelectionStats::folded`].
//! 4. **Grid.** Cells over (φ, θ) with φ = atan2(u.y, u.x) ∈ [0, 2π), θ = acos(u.z) ∈ [0, π] (θ from
//!    +Z here, whatever the photometric convention): n_theta = clamp(⌈180° / cell_deg⌉, 4, 2048) rows,
//!    n_phi = 2 · n_theta columns; cell_deg defaults to half the median edge of the non-hole triangles,
//!    clamped to 0.1°…5°. Cell of u: i = min(⌊φ / 2π · n_phi⌋, n_phi − 1),
//!    j = min(⌊θ / π · n_theta⌋, n_theta − 1), index j · n_phi + i ([`Selection::cell_of`]). Each cell is
//!    covered by a cap around the direction of its centre (φ, θ), of radius
//!    ρ = 1.01 · (largest angle to its corners and edge midpoints) + 2·10⁻⁵ rad; the margins absorb a
//!    GPU's fp32 cell computation (a point near a cell border may land in the neighbouring cell).
//! 5. **Candidate lists** per cell, conservative for any point of the cell's cap:
//!    - triangles whose spherical triangle meets the cap (the cap centre is inside, or within ρ of an
//!      edge arc), holes included so that a query in a hole finds the hole, sorted by the angle from
//!      the cell centre to the circumcentre (likely hits first). A triangle containing x in the cap
//!      meets the cap, so it is listed.
//!    - for k = 1 and k = 4: the vertices within min(d_k(c) + 2ρ, max_gap + ρ) of the cap centre c,
//!      where d_k(c) is the angle from c to its k-th nearest vertex. Proof: for x in the cap,
//!      d_k(x) ≤ d_k(c) + ρ (the k nearest of c are within d_k(c) + ρ of x), so each of x's k nearest is
//!      within d_k(x) ≤ d_k(c) + ρ of x, hence within d_k(c) + 2ρ of c. A vertex that the query keeps is
//!      also within max_gap of x, hence within max_gap + ρ of c.
//!
//!      That bound is loose (it is tight only when x moves straight away from c's nearest vertices),
//!      and near the poles of a meridian layout, where cells are long and thin, it lists whole rings.
//!      A second, exact test removes a vertex v when k vertices w (taken among the 32 nearest to c)
//!      each *dominate* it over a region: w is strictly nearer than v to every point of a cap (c', r),
//!      i.e. the cap lies beyond their bisecting great circle, c' · (w − v) > |w − v| · sin r. v is
//!      dropped when that holds over the whole cell cap, or over each piece of the cell's cover (the
//!      cell split into about square pieces, each covered by a cap with the same fp32 margin). Then
//!      every point the query may bring to this cell has k vertices strictly nearer than v, all of
//!      which the query also keeps (nearer than v, so within max_gap whenever v is): v is never among
//!      the k selected, and the lists stay conservative. On the 56,000-camera layout this brings the
//!      mean 4-nearest list from about 14 to about 8 entries, and the nearest list from 7.3 to 3.
//!
//!    The range queries use the cells themselves as buckets (a cap visits the cells of its φ/θ range),
//!    and everything runs on all cores (rayon).
//!
//! # Queries ([`Selection::select`]; the GPU shader mirrors them on the same tables)
//! - Continuous: over the cell's triangles compute e = (u · (b × c), u · (c × a), u · (a × b)) and
//!   m = min(e). Take the first triangle with m ≥ 0, else (rounding at edges) the one with the largest
//!   m, the first on ties. A hole gives nothing; otherwise w = max(e, 0) / Σ max(e, 0) — the planar
//!   barycentrics of the point where the ray u meets the triangle's plane, continuous across edges —
//!   on the cameras of a, b, c, zero weights dropped.
//! - Nearest / Idw4: over the cell's k = 1 / k = 4 list, keep the 1 / 4 vertices with the largest u · d
//!   (strictly larger replaces, so the earlier list entry, the lower vertex id, wins a tie), skipping
//!   those with u · d < cos(max_gap). Idw4 weights are ∝ 1 / angle with the angle computed as
//!   atan2(|u × d|, u · d) on the CPU and 2·asin(|u − d| / 2) in the shader (both accurate for small
//!   angles, unlike acos(u · d) in fp32).
//!
//! # GPU layout ([`Selection::gpu_data`]; little-endian 4-byte words)
//! - `triangles`: 3 × `[f32; 4]` per triangle t = (a, b, c): `[(b×c).xyz, camera(a)]`,
//!   `[(c×a).xyz, camera(b)]`, `[(a×b).xyz, camera(c)]`, the camera index stored bit-for-bit in the
//!   f32 (`f32::from_bits`); a hole carries [`HOLE_CAMERA`] (0xFFFF_FFFF) in all three.
//! - `vertices`: `[d.xyz, camera]` per vertex (camera bit-cast the same way).
//! - `tri_offsets`/`tri_items`, `near1_offsets`/`near1_items`, `near4_offsets`/`near4_items`: the three
//!   CSR tables; cell c's list is `items[offsets[c]..offsets[c + 1]]`; `offsets` has cells + 1 entries.
//!   Triangle lists hold triangle indices, near lists vertex indices (ascending).
//! - `n_phi`, `n_theta` (u32) and `cos_max_gap` (f32, cos of max_gap clamped to π).
//!
//! # Parts
//! - this file: [`SelectionMode`] (every `match` on it), [`Selection`]: its build, candidate lists
//!   and queries;
//! - `options.rs`: [`SelectionOptions`], checked before a build;
//! - `weights.rs`: [`Weights`], what a query returns;
//! - `stats.rs`: [`SelectionStats`], the summary for reports;
//! - `triangulation.rs`, `spherical.rs`: the vertices, the spherical Delaunay triangulation, the
//!   geometry of spherical triangles and caps;
//! - `grid.rs`, `tables.rs`: the cell grid and the per-cell candidate lists (CSR);
//! - `quadratic.rs`: the quadratic stencils of the continuous mode;
//! - `gpu.rs`: [`Selection::gpu_data`], the tables as the shader reads them;
//! - `view.rs`: the view geometry the near-field pass culls with (content ball, view cells);
//! - `lit_bound/`: the bounding polygon of the lit pixels (each mode's reach ρ) and its rasters.

mod gpu;
mod grid;
pub mod lit_bound;
mod options;
pub mod quadratic;
mod spherical;
mod stats;
mod tables;
mod triangulation;
pub mod view;
mod weights;

use std::collections::BTreeSet;
use std::f64::consts::PI;

use glam::DVec3;

pub use gpu::{SelectionGpu, HOLE_CAMERA, QUADRATIC_ENTRIES};
pub use grid::{MAX_THETA_CELLS, MIN_THETA_CELLS};
pub use options::SelectionOptions;
pub use stats::SelectionStats;
pub use weights::Weights;

use self::grid::CellGrid;
use self::spherical::{angle, circumcap, SphericalTriangle};
use self::tables::{near_lists, triangle_lists, Csr};
use self::triangulation::{spherical_delaunay, vertices};
use crate::nearfield::error::Result;
use crate::nearfield::rayset::RayImageSet;

/// How cameras are chosen and weighted for a view direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum SelectionMode {
    /// The single nearest camera (great-circle angle).
    Nearest,
    /// The 4 nearest cameras, weights ∝ 1 / angle.
    Idw4,
    /// Barycentric weights over the spherical Delaunay triangle holding the direction.
    #[default]
    Continuous,
}

impl SelectionMode {
    /// Every mode, in index order. Adding a mode touches three files: this one (the enum, its
    /// functions below — index, name, [`SelectionMode::reach`], [`SelectionMode::blends_triangles`]
    /// — and its candidate lists and CPU selection: [`Selection::build`], [`Selection::select`],
    /// [`Selection::cell_candidates`], [`Selection::cameras_of_cells`]), the shader's branches on
    /// `SELECTION` (shaders/nearfield/shade.wgsl; its `SELECTION_<NAME>` constant is generated from
    /// the enum) and the C API's `LUMI_SELECTION_*` constant (src/ffi/instance.rs, checked against
    /// [`SelectionMode::index`] at compile time). The evaluation's modes follow [`Self::ALL`].
    pub const ALL: [SelectionMode; 3] = [SelectionMode::Nearest, SelectionMode::Idw4, SelectionMode::Continuous];

    /// The mode's one number: the near-field shader's `SELECTION` pipeline constant and the C API's
    /// `LUMI_SELECTION_*` value.
    pub const fn index(self) -> u32 {
        match self {
            SelectionMode::Nearest => 0,
            SelectionMode::Idw4 => 1,
            SelectionMode::Continuous => 2,
        }
    }

    /// The mode with index `i`, if any.
    pub fn from_index(i: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.index() == i)
    }

    /// The mode's name on the command line and in reports: `nearest`, `idw4`, `continuous`.
    pub const fn name(self) -> &'static str {
        match self {
            SelectionMode::Nearest => "nearest",
            SelectionMode::Idw4 => "idw4",
            SelectionMode::Continuous => "continuous",
        }
    }

    /// The mode named `name` (as [`SelectionMode::name`] spells it), if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// ρ_j, the farthest (great-circle angle, rad) a direction that selects camera j in this mode
    /// can lie from j's vertex, from j's geometry (the bounding polygon of the lit pixels,
    /// [`lit_bound`], draws only where a selectable camera can be selected): nearest: the largest
    /// circumradius around j, which bounds j's Voronoi cell; idw4: the selection's max gap;
    /// continuous: j's longest edge to a neighbour in a non-hole triangle (a point of a triangle is
    /// nearest its farthest vertex at a vertex).
    pub const fn reach(self, r: &Reach) -> f64 {
        match self {
            SelectionMode::Nearest => r.circumradius,
            SelectionMode::Idw4 => r.max_gap,
            SelectionMode::Continuous => r.longest_edge,
        }
    }

    /// The mode blends over Delaunay triangles (the bounding polygon then needs the triangles whose
    /// three cameras are all selectable), rather than over cameras of a cell.
    pub const fn blends_triangles(self) -> bool {
        matches!(self, SelectionMode::Continuous)
    }
}

/// A camera's geometric reaches on the sphere of directions (rad), from which each mode's ρ
/// ([`SelectionMode::reach`]) is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// The largest circumradius of the triangles around the camera's vertex, at most `max_gap`.
    pub circumradius: f64,
    /// The selection's largest gap between cameras.
    pub max_gap: f64,
    /// The longest edge from the camera's vertex in a non-hole triangle.
    pub longest_edge: f64,
}

/// The selection tables of a scan: triangulation, holes, cell grid and per-cell candidate lists.
/// Immutable once built; queries are `&self` and may run from several threads.
#[derive(Debug, Clone)]
pub struct Selection {
    cameras: usize,
    merged_groups: usize,
    dirs: Vec<DVec3>,
    vertex_camera: Vec<u32>,
    tris: Vec<[u32; 3]>,
    /// (b × c, c × a, a × b) of each triangle.
    cross: Vec<[DVec3; 3]>,
    circumcap: Vec<(DVec3, f64)>,
    hole: Vec<bool>,
    folded: Vec<bool>,
    median_circumradius: f64,
    median_edge: f64,
    max_gap: f64,
    cos_max_gap: f64,
    grid: CellGrid,
    tri_cells: Csr,
    near1: Csr,
    near4: Csr,
    /// Per triangle: its quadratic stencil ([`quadratic`]), where it has one.
    stencils: Vec<Option<quadratic::Stencil>>,
}

/// The median of `v` (the upper one for an even count; NaN when empty). Sorts `v`.
fn median(v: &mut [f64]) -> f64 {
    v.sort_unstable_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

impl Selection {
    /// Builds the tables for the cameras of `set` (see the module docs for the steps).
    ///
    /// Errors: invalid options (named field); a non-finite capture centre (`capture sphere`); a
    /// non-finite camera position, a camera at the centre, fewer than 4 distinct directions, or
    /// directions all on one circle through the first camera (`cameras`).
    pub fn build(set: &RayImageSet, opts: &SelectionOptions) -> Result<Self> {
        opts.validate()?;
        let v = vertices(set, opts.merge_tol_rad)?;
        let mesh = spherical_delaunay(&v.dirs)?;
        let dirs = v.dirs;
        let corners = |t: &[u32; 3]| t.map(|i| dirs[i as usize]);
        let sph: Vec<SphericalTriangle> = mesh
            .tris
            .iter()
            .map(|t| {
                let [a, b, c] = corners(t);
                SphericalTriangle::new(a, b, c)
            })
            .collect();
        let cross: Vec<[DVec3; 3]> = mesh
            .tris
            .iter()
            .map(|t| {
                let [a, b, c] = corners(t);
                [b.cross(c), c.cross(a), a.cross(b)]
            })
            .collect();
        let caps: Vec<(DVec3, f64)> = mesh
            .tris
            .iter()
            .map(|t| {
                let [a, b, c] = corners(t);
                circumcap(a, b, c)
            })
            .collect();
        let median_circumradius = median(&mut caps.iter().map(|c| c.1).collect::<Vec<_>>());
        let max_gap = opts.hole_factor * median_circumradius;
        let hole: Vec<bool> = caps
            .iter()
            .zip(&mesh.folded)
            .map(|(c, &f)| f || c.1 > max_gap)
            .collect();
        let mut edges: Vec<(u32, u32)> = mesh
            .tris
            .iter()
            .zip(&hole)
            .filter(|(_, h)| !**h)
            .flat_map(|(t, _)| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let median_edge = median(
            &mut edges
                .iter()
                .map(|&(a, b)| angle(dirs[a as usize], dirs[b as usize]))
                .collect::<Vec<_>>(),
        );
        let cell_deg = opts.cell_deg.unwrap_or_else(|| {
            let c = 0.5 * median_edge.to_degrees();
            if c.is_finite() {
                c.clamp(0.1, 5.0)
            } else {
                5.0
            }
        });
        let grid = CellGrid::for_cell_deg(cell_deg);
        let listed: Vec<bool> = mesh.folded.iter().map(|f| !f).collect();
        let tri_cells = triangle_lists(&grid, &sph, &caps, &listed)?;
        let r0 = if median_edge.is_finite() { median_edge } else { 0.1 };
        let (near1, near4) = near_lists(&grid, &dirs, max_gap, r0)?;
        let stencils = quadratic::stencils(&dirs, &mesh.tris, &cross, &hole);
        Ok(Self {
            cameras: set.cameras.len(),
            merged_groups: v.merged_groups,
            vertex_camera: v.camera,
            dirs,
            tris: mesh.tris,
            cross,
            circumcap: caps,
            hole,
            folded: mesh.folded,
            median_circumradius,
            median_edge,
            max_gap,
            cos_max_gap: max_gap.min(PI).cos(),
            grid,
            tri_cells,
            near1,
            near4,
            stencils,
        })
    }

    /// The quadratic stencil of triangle `t` ([`quadratic`]): `None` for a hole, a triangle at the
    /// edge of the mesh or next to a hole, or one out of range.
    pub fn stencil(&self, t: usize) -> Option<&quadratic::Stencil> {
        self.stencils.get(t).and_then(|s| s.as_ref())
    }

    /// The cameras and weights for the view direction `u` (normalised here; a zero or non-finite `u`
    /// gives no cameras). See the module docs for each mode.
    pub fn select(&self, mode: SelectionMode, u: DVec3) -> Weights {
        let Some(u) = unit(u) else {
            return Weights::EMPTY;
        };
        match mode {
            SelectionMode::Continuous => self.continuous(u),
            SelectionMode::Nearest => self.nearest(u, 1),
            SelectionMode::Idw4 => self.nearest(u, 4),
        }
    }

    fn continuous(&self, u: DVec3) -> Weights {
        let Some(t) = self.find_triangle(u) else {
            return Weights::EMPTY;
        };
        if self.hole[t] {
            return Weights::EMPTY;
        }
        let e = self.edge_values(t, u).map(|x| x.max(0.0));
        let s = e[0] + e[1] + e[2];
        let mut w = Weights::EMPTY;
        if !s.is_finite() || s <= 0.0 {
            return w;
        }
        for (k, &x) in e.iter().enumerate() {
            if x > 0.0 {
                w.push(self.vertex_camera[self.tris[t][k] as usize], x / s);
            }
        }
        w
    }

    fn nearest(&self, u: DVec3, k: usize) -> Weights {
        let list = if k == 1 {
            self.near1.list(self.cell_of(u))
        } else {
            self.near4.list(self.cell_of(u))
        };
        // Largest cosines first; a strictly larger cosine displaces, so ties keep the earlier entry.
        let mut best: [(f64, u32); 4] = [(f64::NEG_INFINITY, u32::MAX); 4];
        let mut n = 0usize;
        for &v in list {
            let c = u.dot(self.dirs[v as usize]);
            if c < self.cos_max_gap {
                continue;
            }
            if let Some(pos) = best[..k].iter().position(|b| c > b.0) {
                best.copy_within(pos..k - 1, pos + 1);
                best[pos] = (c, v);
                n = (n + 1).min(k);
            }
        }
        let mut w = Weights::EMPTY;
        if n == 0 {
            return w;
        }
        let cam = |v: u32| self.vertex_camera[v as usize];
        let angles: Vec<f64> = best[..n].iter().map(|b| angle(u, self.dirs[b.1 as usize])).collect();
        if k == 1 || angles[0] < 1e-7 {
            w.push(cam(best[0].1), 1.0);
            return w;
        }
        let s: f64 = angles.iter().map(|a| 1.0 / a).sum();
        for (b, a) in best[..n].iter().zip(&angles) {
            w.push(cam(b.1), 1.0 / a / s);
        }
        w
    }

    /// e = (u · (b × c), u · (c × a), u · (a × b)) of triangle `t`.
    fn edge_values(&self, t: usize, u: DVec3) -> [f64; 3] {
        self.cross[t].map(|n| u.dot(n))
    }

    /// The triangle the Continuous query lands on for `u` (normalised here): the first in its cell's list
    /// that contains `u` (min e ≥ 0), else the one with the largest min e; `None` when the cell lists no
    /// triangle or `u` is zero or not finite. It may be a hole.
    pub fn find_triangle(&self, u: DVec3) -> Option<usize> {
        let u = unit(u)?;
        let mut best = f64::NEG_INFINITY;
        let mut found = None;
        for &t in self.tri_cells.list(self.cell_of(u)) {
            let e = self.edge_values(t as usize, u);
            let m = e[0].min(e[1]).min(e[2]);
            if m > best {
                best = m;
                found = Some(t as usize);
                if m >= 0.0 {
                    break;
                }
            }
        }
        found
    }

    /// The grid cell of the unit vector `u` (see the module docs for the formula).
    pub fn cell_of(&self, u: DVec3) -> usize {
        self.grid.cell_of(u)
    }

    /// Calls `f` with every grid cell that may hold a point within `r` radians of the unit vector `u`
    /// (a superset; see the module docs' grid).
    pub fn for_each_cell_near(&self, u: DVec3, r: f64, f: impl FnMut(usize)) {
        self.grid.for_each_cell_near(u, r, f);
    }

    /// Grid size (n_phi, n_theta).
    pub fn grid(&self) -> (u32, u32) {
        (self.grid.n_phi, self.grid.n_theta)
    }

    /// Number of grid cells (n_phi · n_theta).
    pub fn cells(&self) -> usize {
        self.grid.cells()
    }

    /// The candidate list of `cell` for `mode`: triangle indices (Continuous) or vertex indices
    /// (Nearest: k = 1, Idw4: k = 4). Empty for a cell out of range.
    pub fn cell_candidates(&self, mode: SelectionMode, cell: usize) -> &[u32] {
        match mode {
            SelectionMode::Continuous => self.tri_cells.list(cell),
            SelectionMode::Nearest => self.near1.list(cell),
            SelectionMode::Idw4 => self.near4.list(cell),
        }
    }

    /// Every camera that a `mode` query in any of `cells` could return (for GPU residency), ascending.
    /// Cells out of range are ignored.
    pub fn cameras_of_cells(&self, mode: SelectionMode, cells: impl Iterator<Item = usize>) -> Vec<u32> {
        let mut out = BTreeSet::new();
        for cell in cells {
            let list = self.cell_candidates(mode, cell);
            match mode {
                SelectionMode::Continuous => {
                    for &t in list {
                        if !self.hole[t as usize] {
                            out.extend(self.tris[t as usize].iter().map(|&v| self.vertex_camera[v as usize]));
                            // The quadratic correction samples the neighbours across its edges too.
                            if let Some(st) = self.stencil(t as usize) {
                                out.extend(st.neighbours.iter().map(|&v| self.vertex_camera[v as usize]));
                            }
                        }
                    }
                }
                SelectionMode::Nearest | SelectionMode::Idw4 => {
                    out.extend(list.iter().map(|&v| self.vertex_camera[v as usize]));
                }
            }
        }
        out.into_iter().collect()
    }

    /// Unit direction of each vertex.
    pub fn vertex_directions(&self) -> &[DVec3] {
        &self.dirs
    }

    /// The camera of each vertex (the lowest index of its coincident group).
    pub fn vertex_camera(&self) -> &[u32] {
        &self.vertex_camera
    }

    /// The triangles (vertex indices, det(a, b, c) > 0).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.tris
    }

    /// Whether triangle `t` is a hole (false when out of range).
    pub fn is_hole(&self, t: usize) -> bool {
        self.hole.get(t).copied().unwrap_or(false)
    }

    /// Whether triangle `t` is folded (a hole no cell lists; see the module docs).
    pub fn is_folded(&self, t: usize) -> bool {
        self.folded.get(t).copied().unwrap_or(false)
    }

    /// Circumcentre (unit) and circumradius (rad) of triangle `t`.
    pub fn circumcap(&self, t: usize) -> Option<(DVec3, f64)> {
        self.circumcap.get(t).copied()
    }

    /// The gap (rad) beyond which Nearest/Idw4 ignore a camera: `hole_factor` · median circumradius.
    pub fn max_gap_rad(&self) -> f64 {
        self.max_gap
    }
}

/// `u` normalised, or `None` when zero or not finite.
fn unit(u: DVec3) -> Option<DVec3> {
    let len = u.length();
    (len.is_finite() && len > 0.0).then(|| u / len)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn each_mode_has_one_index_and_one_name() {
        for (i, m) in SelectionMode::ALL.into_iter().enumerate() {
            assert_eq!(m.index() as usize, i, "ALL is in index order");
            assert_eq!(SelectionMode::from_index(m.index()), Some(m));
            assert_eq!(SelectionMode::from_name(m.name()), Some(m));
        }
        assert_eq!(SelectionMode::from_index(3), None);
        assert_eq!(SelectionMode::from_name("Nearest"), None, "names are exact");
    }
    use crate::nearfield::layout::{cameras, Layout};
    use crate::nearfield::rayset::{CaptureSphere, Intrinsics};
    use glam::DVec2;

    pub(super) fn set(layout: Layout) -> RayImageSet {
        let sphere = CaptureSphere {
            centre_m: DVec3::new(0.1, -0.2, 0.3),
            radius_m: 2.0,
        };
        RayImageSet {
            sphere,
            intrinsics: Intrinsics {
                width: 8,
                height: 8,
                principal_px: DVec2::splat(4.0),
                focal_px: DVec2::splat(8.0),
            },
            cameras: cameras(&sphere, &layout, 1).unwrap(),
        }
    }

    #[test]
    fn an_off_centre_sphere_uses_directions_from_its_centre() {
        let s = set(Layout::Fibonacci { count: 200 });
        let sel = Selection::build(&s, &SelectionOptions::default()).unwrap();
        for (v, d) in sel.vertex_directions().iter().enumerate() {
            let cam = &s.cameras[sel.vertex_camera()[v] as usize];
            assert!((cam.direction_from(s.sphere.centre_m) - *d).length() < 1e-12);
        }
        // At a camera's own direction every mode returns that camera alone.
        for c in [0usize, 17, 123, 199] {
            let u = s.cameras[c].direction_from(s.sphere.centre_m);
            for mode in [SelectionMode::Nearest, SelectionMode::Idw4, SelectionMode::Continuous] {
                let w = sel.select(mode, u);
                assert!((w.weight_of(c as u32) - 1.0).abs() < 1e-9, "{mode:?} {c}: {w:?}");
            }
        }
    }

    #[test]
    fn bad_query_vectors_give_nothing() {
        let sel = Selection::build(&set(Layout::Fibonacci { count: 100 }), &SelectionOptions::default()).unwrap();
        for u in [DVec3::ZERO, DVec3::NAN, DVec3::new(f64::INFINITY, 0.0, 0.0)] {
            for mode in [SelectionMode::Nearest, SelectionMode::Idw4, SelectionMode::Continuous] {
                assert!(sel.select(mode, u).is_empty());
            }
        }
        // A non-unit query is normalised.
        let a = sel.select(SelectionMode::Continuous, DVec3::new(0.3, 0.4, 0.5));
        let b = sel.select(SelectionMode::Continuous, DVec3::new(3.0, 4.0, 5.0));
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b.iter()) {
            assert_eq!(x.0, y.0);
            assert!((x.1 - y.1).abs() < 1e-12);
        }
        assert!(sel.cell_candidates(SelectionMode::Idw4, usize::MAX).is_empty());
        assert!(sel
            .cameras_of_cells(SelectionMode::Continuous, [usize::MAX].into_iter())
            .is_empty());
    }
}
