//! Flat parts of a carved proxy moved onto the plane the cameras agree on (luminance consistency).
//!
//! Carving puts a flat emitter's surface only to within about a cell (its collapsed lens sits a
//! fraction of a cell off, and its two sheets alternate); a view at a grazing angle turns a depth
//! error δ into a sideways error δ / tan(elevation), so a star's sector edges are drawn doubled. The
//! images themselves say where the surface is: at the true depth, every camera sees the same pattern
//! at the same points of the surface.
//!
//! Promises:
//! - Each connected part of the mesh is fitted by a plane (least squares: its vertices' centroid
//!   and the covariance's smallest eigenvector), then fitted again to the vertices within
//!   [`FLAT_MAX_CELLS`] cells of it, twice. A part is flat when at least [`MIN_INLIERS`] of its
//!   vertices are such inliers, they lie within [`FLAT_RMS_CELLS`] cells RMS of their plane and
//!   span at least [`MIN_SPAN_CELLS`] cells; only its inliers are moved. The parts that are not
//!   flat on their own are then tried once more together, as one part (coplanar small features:
//!   led-dots' 3 mm dots are 3 units across); what is still not flat is left as it is.
//! - A part whose inliers make a line (spread at most [`LINE_WIDTH_UNITS`] across their longest
//!   axis in both other directions: a 1 mm strip carves to a lens about as thick as it is wide,
//!   and its least-squares plane stands on edge) takes its normal from the light instead
//!   (`light_normal`): across the axis, the light-weighted mean direction to the cameras that see
//!   it lit, or where that cancels (lit on both sides) the direction of the most light.
//! - For a flat part, the plane is moved along its normal by the offset in ±[`SEARCH_CELLS`] cells
//!   that minimises the luminance disagreement of the cameras that see it at least
//!   [`MIN_ELEVATION_DEG`] above its plane: points of the part (its vertices on the plane, up to
//!   [`MAX_POINTS`]) are projected into each camera, each camera's samples are divided by their
//!   mean (so an emitter that is brighter in some directions is not penalised), and the cost is the
//!   sum over points of the variance across cameras. A coarse scan (0.05 cell) is refined about its
//!   best (0.005 cell). The part's vertices are then projected onto the moved plane.
//! - The part's other vertices (a lens that carving could not take off the middle of a source wider
//!   than the cameras' grazing rows reach under) are moved onto the plane where the cameras
//!   disagree less there than where they are (their luminance over each camera's mean on the
//!   plane); a feature standing off the plane, which the cameras see consistently where it is,
//!   stays.
//! - Then its outline (the rim where the part's two collapsed sheets fold onto each other) goes to
//!   the median of where the light falls to half its inside value, as each camera above 30° sees
//!   it along each rim vertex's outward in-plane direction (`snap_outline`, `half_light`): carving leaves the rim about a cell
//!   out, and a capture pixel half on the source is half lit, so that rim drew light where there
//!   is none. Where other light lies beyond the rim (a tile in front of a lit back plane), it goes
//!   to the median of where each camera sees the step from the light inside to the light beyond
//!   (`step_edge`). Each move's length along its vertex's outward direction is averaged
//!   with the outline neighbours' ([`OUTLINE_SMOOTHING_PASSES`]), and the sheet's vertices left beyond the new outline (within 3
//!   units, behind a moved outline vertex) are pulled back onto it.
//! - Then each small part of it (connected, at most [`SMALL_PART_UNITS`] across: a 3 mm LED dot),
//!   whose flattened lens folds over itself, is redrawn from the images (`small_parts`): a polygon
//!   along the half-light outline of the cameras' median map, scaled to the area the cameras' light
//!   gives (each camera's light over the part divided by its largest value, the median over
//!   cameras), on both sheets.
//! - A line part is redrawn whole as a flat band instead (`line_part`): slices
//!   [`LINE_SLICE_UNITS`] apart, each between the half-light points of the cameras' median across
//!   it, its width scaled as a small part's area, averaged over [`LINE_SMOOTHING_SLICES`]
//!   neighbours; runs broken where the light falls below half (a gap), ended at the half-light
//!   points along the middle. The band's plane is first moved, tilted along the axis and rolled
//!   about it to where the cameras agree best at its edges (`line_depth`): the light gives the
//!   normal to a few degrees only, and a view 10° above a 1 mm strip's plane drawn 0.1 mm deep
//!   draws the strip half off itself. The band's edges are only as good as the images: a strip
//!   narrower than their pixels comes out a pixel wide (docs/proxy.md, known limits).
//! - A camera counts for a point only when the other parts of the mesh do not hide the point from
//!   it (`Sight`): a tile in front of a back plane shows the cameras it hides the plane from its
//!   own light, which is no evidence about the plane.
//! - Distances are in units of the larger of the carving's cell and the capture pixel's footprint
//!   at the centre (`unit_m`).
//! - A part whose cameras are too few (fewer than 3 seeing it lit), whose cost does not fall by
//!   [`MIN_GAIN`] from the fitted plane, or whose least cost is at the end of the search range and
//!   lower by less than [`EDGE_MIN_GAIN`] (no minimum: a uniform beam seen within 25°) keeps the
//!   fitted plane (still flattened).

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use super::mesh::{components, components_of, members, Mesh};
use crate::nearfield::bvh::ProxyBvh;
use crate::nearfield::rayset::{Camera, Intrinsics, LuminanceImage};

/// A part is flat within this RMS distance to its plane, in cells.
pub const FLAT_RMS_CELLS: f64 = 0.6;
/// ... and within this largest distance, in cells.
pub const FLAT_MAX_CELLS: f64 = 1.5;
/// ... and when at least this fraction of its vertices lies within [`FLAT_MAX_CELLS`] of the
/// plane (the others, an unflattened blob or rim, stay where they are) ...
pub const MIN_INLIERS: f64 = 0.5;
/// ... and when its in-plane spread (standard deviation along its wider axis) is at least this
/// many cells.
pub const MIN_SPAN_CELLS: f64 = 3.0;
/// The offset is searched within ± this many cells of the fitted plane.
pub const SEARCH_CELLS: f64 = 2.0;
/// Cameras at least this far above the plane (degrees) are consulted.
pub const MIN_ELEVATION_DEG: f64 = 10.0;
/// Points of a part sampled, at most.
pub const MAX_POINTS: usize = 2000;
/// The offset found is used when it lowers the disagreement by at least this fraction.
pub const MIN_GAIN: f64 = 0.02;

/// A plane whose least disagreement lies at the end of the search range moves there only when
/// that lowers the disagreement by at least this fraction.
pub const EDGE_MIN_GAIN: f64 = 0.25;

/// An outline is snapped only where the light 3 units outside it is below this fraction of the
/// light inside (an edge against darkness).
pub const DARK_BEYOND: f64 = 0.1;

/// Where other light lies beyond an outline, a camera sees a step there when its light inside and
/// beyond differ by at least this fraction of the larger (the outline step's second case, [`refine_flat_parts`]).
pub const STEP_CONTRAST: f64 = 0.3;

/// ... and the outline is snapped when at least this many cameras see the step.
pub const MIN_STEP_CAMERAS: usize = 5;

/// A camera the refinement reads: pose, intrinsics and image.
#[derive(Debug, Clone)]
pub struct Shot {
    /// Pose (luminaire frame, m).
    pub camera: Camera,
    /// Intrinsics.
    pub intrinsics: Intrinsics,
    /// Luminance (cd/m²).
    pub image: Crop,
}

/// An image as the refinement holds it: f16 relative to its largest value, half the memory of
/// f32 (the refinement holds up to [`super::REFINE_PIXELS`] pixels at once), and of each row only
/// the pixels from its first lit one to its last (the rest read as dark, as they are: a crop holds
/// the box around the content, and a disc's rows within it are 0.4–0.8 of that box on the
/// synthetic scans; with noise everywhere, as in a real scan, every row is kept). The relative
/// precision, 2⁻¹¹, is far below the disagreement between cameras that the refinement weighs;
/// values below 2⁻²⁴ of the largest read as dark.
#[derive(Debug, Clone)]
pub struct Crop {
    width: u32,
    height: u32,
    /// The image's largest finite value (cd/m²; 1 for a dark image).
    scale: f32,
    /// Per row: where its pixels start in `data`, its first lit column and one past its last.
    rows: Vec<[u32; 3]>,
    data: Vec<half::f16>,
}

impl Crop {
    /// `img` held as f16 (non-finite and negative values as dark).
    pub fn of(img: &LuminanceImage) -> Self {
        let clean = |v: f32| if v.is_finite() { v.max(0.0) } else { 0.0 };
        let max = img.data.iter().fold(0.0f32, |m, v| m.max(clean(*v)));
        let scale = if max > 0.0 { max } else { 1.0 };
        let w = img.width as usize;
        let value = |v: f32| half::f16::from_f32(clean(v) / scale);
        let lit = |v: &f32| value(*v).to_f32() != 0.0;
        let mut rows = Vec::with_capacity(img.height as usize);
        let mut data = Vec::new();
        for row in img.data.chunks(w.max(1)).take(img.height as usize) {
            let first = row.iter().position(lit).unwrap_or(0);
            let end = row.iter().rposition(lit).map_or(first, |k| k + 1);
            rows.push([data.len() as u32, first as u32, end as u32]);
            data.extend(row[first..end].iter().map(|v| value(*v)));
        }
        data.shrink_to_fit();
        Self {
            width: img.width,
            height: img.height,
            scale,
            rows,
            data,
        }
    }

    /// Luminance (cd/m²) of pixel (x, y), inside the image.
    fn get(&self, x: u32, y: u32) -> f32 {
        let Some(&[at, first, end]) = self.rows.get(y as usize) else {
            return 0.0;
        };
        if x < first || x >= end {
            return 0.0;
        }
        self.data[(at + x - first) as usize].to_f32() * self.scale
    }
}

/// What [`refine_flat_parts`] did to one flat part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneFit {
    /// Vertices of the part within [`FLAT_MAX_CELLS`] of its plane, moved onto it.
    pub vertices: usize,
    /// Its other vertices moved onto the plane because the cameras agree better there.
    pub absorbed: usize,
    /// RMS distance of its vertices to the fitted plane before (m).
    pub rms_m: f64,
    /// Offset chosen along the plane's normal (m; 0 when the cameras did not decide).
    pub offset_m: f64,
    /// Disagreement at the fitted plane and at the chosen one (the second ≤ the first).
    pub cost: [f64; 2],
    /// Cameras consulted.
    pub cameras: usize,
    /// A point of the plane the part was put on (m, luminaire frame).
    pub point_m: DVec3,
    /// The plane's unit normal.
    pub normal: DVec3,
    /// Small parts of it redrawn from the images ([`SMALL_PART_UNITS`]), or 1 where the part is a
    /// line redrawn as a band.
    pub redrawn: usize,
}

/// Flattens every flat part of `mesh` onto the plane its cameras agree on and snaps its outline
/// (see the module's promises); `voxel_m` is the unit: the larger of the carving's cell and the
/// capture pixel's footprint. Returns what was done for each flat part.
pub fn refine_flat_parts(mesh: &mut Mesh, voxel_m: f64, shots: &[Shot]) -> Vec<PlaneFit> {
    let comp = components(mesh);
    let parts = members(&comp);
    let mut fits = Vec::new();
    // Small parts to redraw, applied at the end (the parts' vertex lists index the mesh as it is).
    let mut redraws = Vec::new();
    // Parts not flat on their own (too small to span a plane: a 3 mm dot is 3 units across), tried
    // again together: coplanar small features (led-dots' 32 dots) share one plane.
    let mut rest: Vec<u32> = Vec::new();
    for (&id, part) in &parts {
        match fit_part(mesh, &comp, &[id], part, voxel_m, shots, &mut redraws) {
            Some(fit) => fits.push(fit),
            // Vertices used by triangles only (an unused vertex is its own part).
            None if part.len() >= 4 => rest.push(id),
            None => {}
        }
    }
    if rest.len() >= 2 {
        let together: Vec<usize> = rest.iter().flat_map(|id| parts[id].iter().copied()).collect();
        fits.extend(fit_part(mesh, &comp, &rest, &together, voxel_m, shots, &mut redraws));
    }
    // Carving can break a strip into pieces, and each piece's band then covers the whole strip:
    // a band along a longer one (or an equal one drawn earlier) is not drawn.
    for j in 0..redraws.len() {
        let Some(b) = redraws[j].line else { continue };
        let lb = (b.1 - b.0).length();
        let covered = redraws.iter().enumerate().any(|(i, r)| {
            r.line.is_some_and(|a| {
                let la = (a.1 - a.0).length();
                i != j && !r.faces.is_empty() && (la > lb || (la == lb && i < j)) && band_along(a, b, voxel_m)
            })
        });
        if covered {
            redraws[j].vertices.clear();
            redraws[j].faces.clear();
        }
    }
    // Pieces of a strip that were not lines themselves (a few cells long) lie under its band:
    // whatever lies wholly within a band (a unit beyond its edges and ends, a unit off its plane)
    // is not drawn.
    let bands: Vec<(DVec3, DVec3, f64)> = redraws
        .iter()
        .filter(|r| !r.faces.is_empty())
        .filter_map(|r| r.line)
        .collect();
    if !bands.is_empty() {
        let within = |p: DVec3| {
            bands.iter().any(|&(a0, a1, half)| {
                let len = (a1 - a0).length();
                let d = (a1 - a0) / len.max(1e-12);
                let v = p - a0;
                let t = v.dot(d);
                t >= -voxel_m && t <= len + voxel_m && (v - t * d).length() <= half + voxel_m
            })
        };
        let in_bands: std::collections::HashSet<usize> =
            redraws.iter().flat_map(|r| r.triangles.iter().copied()).collect();
        let under: Vec<usize> = (0..mesh.triangles.len())
            .filter(|k| !in_bands.contains(k))
            .filter(|&k| mesh.triangles[k].iter().all(|&i| within(mesh.vertices[i as usize])))
            .collect();
        for r in &mut redraws {
            if r.line.is_none() && !r.vertices.is_empty() && r.vertices.iter().all(|&p| within(p)) {
                r.vertices.clear();
                r.faces.clear();
            }
        }
        if !under.is_empty() {
            redraws.push(Redraw {
                triangles: under,
                vertices: Vec::new(),
                faces: Vec::new(),
                line: None,
            });
        }
    }
    if !redraws.is_empty() {
        let dropped: std::collections::HashSet<usize> =
            redraws.iter().flat_map(|r| r.triangles.iter().copied()).collect();
        let mut vertices = std::mem::take(&mut mesh.vertices);
        let mut triangles: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .enumerate()
            .filter(|(k, _)| !dropped.contains(k))
            .map(|(_, t)| *t)
            .collect();
        for r in &redraws {
            let base = vertices.len() as u32;
            vertices.extend(&r.vertices);
            for [a, b, c] in &r.faces {
                // Both sheets, as every flat part has.
                triangles.push([base + a, base + b, base + c]);
                triangles.push([base + a, base + c, base + b]);
            }
        }
        *mesh = super::mesh::compacted(&vertices, triangles);
    }
    fits
}

/// Parts of a flat part's plane at most this many units across (in the plane) are redrawn from
/// the images (`small_parts`): carving leaves a part a few cells across as a crumpled lens, and
/// flattened it folds over itself, so its outline cannot be followed vertex by vertex.
pub const SMALL_PART_UNITS: f64 = 8.0;

/// A part redrawn: the triangles it replaces (indices into the mesh's triangles) and the
/// polygon that replaces them on the plane: its vertices (m) and triangles (indices into them, one
/// sheet; both are drawn).
struct Redraw {
    triangles: Vec<usize>,
    vertices: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
    /// A line's band: the middle of its first and last ends and its largest half width (m).
    line: Option<(DVec3, DVec3, f64)>,
}

impl Redraw {
    /// A star-shaped polygon: a fan from `centre` over `ring`.
    fn fan(triangles: Vec<usize>, centre: DVec3, ring: &[DVec3]) -> Self {
        let n = ring.len() as u32;
        let mut vertices = vec![centre];
        vertices.extend(ring);
        Self {
            triangles,
            vertices,
            faces: (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect(),
            line: None,
        }
    }
}

/// Whether the band `b` (its ends' middles) lies along the band `a`, within `unit` of its line,
/// parallel within 2°, over at least half of `b`'s length.
fn band_along(a: (DVec3, DVec3, f64), b: (DVec3, DVec3, f64), unit: f64) -> bool {
    let (la, lb) = ((a.1 - a.0).length(), (b.1 - b.0).length());
    if la <= 0.0 || lb <= 0.0 {
        return false;
    }
    let (da, db) = ((a.1 - a.0) / la, (b.1 - b.0) / lb);
    if da.dot(db).abs() < 2f64.to_radians().cos() {
        return false;
    }
    let off = |q: DVec3| {
        let v = q - a.0;
        (v - v.dot(da) * da).length()
    };
    if off(b.0) > unit || off(b.1) > unit {
        return false;
    }
    let (t0, t1) = ((b.0 - a.0).dot(da), (b.1 - a.0).dot(da));
    let overlap = t0.max(t1).min(la) - t0.min(t1).max(0.0);
    overlap >= 0.5 * lb
}

/// [`refine_flat_parts`] for one part: the vertices `part` of the connected components `ids`
/// (`comp` gives each vertex's component); `None` when it is not flat.
fn fit_part(
    mesh: &mut Mesh,
    comp: &[u32],
    ids: &[u32],
    part: &[usize],
    voxel_m: f64,
    shots: &[Shot],
    redraws: &mut Vec<Redraw>,
) -> Option<PlaneFit> {
    if part.len() < 16 {
        return None;
    }
    let idx = part;
    // Robust fit: the plane of all vertices, then of those within FLAT_MAX_CELLS of it (a
    // part may carry an unflattened blob or rim, which stays as it is).
    let all: Vec<DVec3> = idx.iter().map(|&i| mesh.vertices[i]).collect();
    let (c0, n0, _) = plane_of(&all)?;
    let near = |c: DVec3, n: DVec3| -> Vec<usize> {
        (0..all.len())
            .filter(|&k| (all[k] - c).dot(n).abs() <= FLAT_MAX_CELLS * voxel_m)
            .collect()
    };
    let first = near(c0, n0);
    let (c1, n1, _) = plane_of(&first.iter().map(|&k| all[k]).collect::<Vec<_>>())?;
    let inliers = near(c1, n1);
    if (inliers.len() as f64) < MIN_INLIERS * all.len() as f64 {
        return None;
    }
    let mut idx: Vec<usize> = inliers.iter().map(|&k| idx[k]).collect();
    let mut pts: Vec<DVec3> = inliers.iter().map(|&k| all[k]).collect();
    let (centre, mut normal, spread) = plane_of(&pts)?;
    // The rest of the mesh hides parts of this one from some cameras (a tile in front of a
    // back plane): those cameras see other light there and do not vote.
    let mut sight = None;
    // A part that is a line (a 1 mm strip carves to a lens about as thick as it is wide) has no
    // plane of its own: the cameras' light says which way it faces.
    let mut line = None;
    if let Some(axis) = line_axis(&pts, voxel_m) {
        let s = sight.insert(Sight::without(mesh, comp, ids, voxel_m));
        if let Some(n) = light_normal(&pts, centre, axis, shots, s) {
            normal = n;
            line = Some(axis);
            let inliers = near(centre, normal);
            if (inliers.len() as f64) < MIN_INLIERS * all.len() as f64 {
                return None;
            }
            idx = inliers.iter().map(|&k| part[k]).collect();
            pts = inliers.iter().map(|&k| all[k]).collect();
        }
    }
    let dist: Vec<f64> = pts.iter().map(|p| (*p - centre).dot(normal)).collect();
    let rms = (dist.iter().map(|d| d * d).sum::<f64>() / dist.len() as f64).sqrt();
    if rms > FLAT_RMS_CELLS * voxel_m || spread < MIN_SPAN_CELLS * voxel_m {
        return None;
    }
    let step = (pts.len() / MAX_POINTS).max(1);
    let on_plane: Vec<DVec3> = pts
        .iter()
        .zip(&dist)
        .step_by(step)
        .map(|(p, d)| *p - *d * normal)
        .collect();
    let seeing: Vec<&Shot> = shots
        .iter()
        .filter(|s| {
            let to = s.camera.position_m - centre;
            (to.dot(normal) / to.length()).abs() >= MIN_ELEVATION_DEG.to_radians().sin()
        })
        .collect();
    let sight = sight.unwrap_or_else(|| Sight::without(mesh, comp, ids, voxel_m));
    let vis = sight.rows(&on_plane, &seeing);
    let (offset_m, cost) = best_offset(&on_plane, normal, voxel_m, &seeing, &vis);
    for (&i, d) in idx.iter().zip(&dist) {
        mesh.vertices[i] -= (*d - offset_m) * normal;
    }
    // The part's other vertices (a lens carving could not take off the middle of a wide
    // source) go onto the plane too where the cameras agree better there than where they are.
    let mut absorbed = 0;
    let mut redrawn = 0;
    let plane_pts: Vec<DVec3> = on_plane.iter().map(|p| *p + offset_m * normal).collect();
    if let Some((means, lit)) = camera_means(&plane_pts, &seeing, &vis) {
        let is_inlier: std::collections::HashSet<usize> = idx.iter().copied().collect();
        let outliers: Vec<usize> = part.iter().copied().filter(|i| !is_inlier.contains(i)).collect();
        let onto: Vec<Option<DVec3>> = outliers
            .par_iter()
            .map(|&i| {
                let v = mesh.vertices[i];
                let flat = v - ((v - centre).dot(normal) - offset_m) * normal;
                let there = point_disagreement(flat, &seeing, &means, &lit, &sight.row(flat, &seeing))?;
                match point_disagreement(v, &seeing, &means, &lit, &sight.row(v, &seeing)) {
                    Some(here) if here < there => None,
                    _ => Some(flat),
                }
            })
            .collect();
        for (&i, p) in outliers.iter().zip(onto) {
            if let Some(p) = p {
                mesh.vertices[i] = p;
                absorbed += 1;
            }
        }
        let on: std::collections::HashSet<usize> = part
            .iter()
            .copied()
            .filter(|&i| ((mesh.vertices[i] - centre).dot(normal) - offset_m).abs() < 1e-9 + 1e-6 * voxel_m)
            .collect();
        if let Some(axis) = line {
            // A line's flattened lens folds over itself along its whole length, as a small
            // part's does: it is redrawn whole, as a band.
            let triangles: Vec<usize> = (0..mesh.triangles.len())
                .filter(|&k| ids.contains(&comp[mesh.triangles[k][0] as usize]))
                .collect();
            let plane = (centre + offset_m * normal, normal);
            if let Some(band) = line_part(
                mesh,
                part,
                triangles,
                plane,
                axis,
                voxel_m,
                (&seeing, &sight),
                &means,
                &lit,
                false,
            ) {
                redrawn = 1;
                redraws.push(band);
            }
        } else {
            snap_outline(mesh, &on, (centre, normal), voxel_m, (&seeing, &sight), &means, &lit);
            let small = small_parts(mesh, &on, normal, voxel_m, (&seeing, &sight), &means, &lit);
            redrawn = small.len();
            redraws.extend(small);
        }
    }
    Some(PlaneFit {
        absorbed,
        vertices: idx.len(),
        rms_m: rms,
        offset_m,
        cost,
        cameras: seeing.len(),
        point_m: centre + offset_m * normal,
        normal,
        redrawn,
    })
}

/// Moves the outline of a flattened part (the vertices `on` its plane, given as `(centre,
/// normal)`) to where the cameras that look at the plane from above 30° (seen from `centre`) see
/// its light fall to half: the rim where the
/// part's two collapsed sheets fold onto each other (an edge between two of its triangles facing
/// opposite ways) is right to about a cell, and a capture pixel half on the source is half lit, so
/// an outline a cell too far out draws that half-lit rim as light. Each fold vertex looks along
/// its outward in-plane direction, from 3 units inside to 3 outside, at the mean over those
/// cameras of their luminance over their mean; where the profile 3 units out is dark (below
/// [`DARK_BEYOND`] of its largest value inside), it moves to where the profile first falls below
/// half that value.
fn snap_outline(
    mesh: &mut Mesh,
    on: &std::collections::HashSet<usize>,
    (centre, normal): (DVec3, DVec3),
    voxel_m: f64,
    (shots, sight): (&[&Shot], &Sight),
    means: &[f64],
    lit: &[usize],
) {
    // Ordered maps: the sums below (outward directions, averaged moves) then add in the same order
    // on every run, and so does the simplification that follows (a reconstruction is reproducible).
    use std::collections::BTreeMap;
    let steep: Vec<usize> = lit
        .iter()
        .copied()
        .filter(|&j| {
            let to = shots[j].camera.position_m - centre;
            (to.dot(normal) / to.length()).abs() >= 30f64.to_radians().sin()
        })
        .collect();
    if steep.len() < 3 {
        return;
    }
    // The part's triangles around each vertex, as compressed rows in mesh order: vertex x's are
    // `tris[start[x]..start[x + 1]]`. 12 bytes a triangle: the part can be the whole unsimplified
    // mesh (10⁵ triangles), and this is the reconstruction's peak (a sorted list of edges, maps of
    // vectors and a stable sort's scratch held 14 MB for the full-size disc).
    let n = mesh.vertices.len();
    let on_plane = |t: &[u32; 3]| t.iter().all(|&i| on.contains(&(i as usize)));
    let mut start = vec![0u32; n + 1];
    for t in mesh.triangles.iter().filter(|t| on_plane(t)) {
        for &i in t {
            start[i as usize + 1] += 1;
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut tris = vec![0u32; start[n] as usize];
    let mut fill = start.clone();
    for (k, t) in mesh.triangles.iter().enumerate().filter(|(_, t)| on_plane(t)) {
        for &i in t {
            tris[fill[i as usize] as usize] = k as u32;
            fill[i as usize] += 1;
        }
    }
    drop(fill);
    let tris_of = |x: u32| &tris[start[x as usize] as usize..start[x as usize + 1] as usize];
    // The side of the plane a triangle faces (`None`: degenerate).
    let facing = |t: &[u32; 3]| -> Option<i8> {
        let [a, b, c] = mesh.corners(t);
        let n = (b - a).cross(c - a);
        (n.length_squared() >= 1e-24).then_some(if n.dot(normal).is_sign_negative() { -1 } else { 1 })
    };
    let mut outward: BTreeMap<u32, DVec3> = BTreeMap::new();
    let mut along: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    // Each edge (p, q), p < q, in that order, with its two triangles (mesh order) facing opposite
    // ways: a fold.
    for p in 0..n as u32 {
        let mut qs: Vec<u32> = tris_of(p)
            .iter()
            .map(|&k| &mesh.triangles[k as usize])
            .filter(|t| facing(t).is_some())
            .flat_map(|t| t.iter().copied().filter(|&q| q > p))
            .collect();
        qs.sort_unstable();
        qs.dedup();
        for q in qs {
            // The edge's triangles that are not degenerate, with their facings.
            let mut both = tris_of(p)
                .iter()
                .map(|&k| &mesh.triangles[k as usize])
                .filter(|t| t.contains(&q))
                .filter_map(|t| Some((t, facing(t)?)));
            let (Some((t0, f0)), Some((_, f1)), None) = (both.next(), both.next(), both.next()) else {
                continue;
            };
            if f0 == f1 {
                continue;
            }
            along.entry(p).or_default().push(q);
            along.entry(q).or_default().push(p);
            let (vp, vq) = (mesh.vertices[p as usize], mesh.vertices[q as usize]);
            let mut u = normal.cross(vq - vp).normalize_or_zero();
            let third = t0.iter().copied().find(|&i| i != p && i != q).unwrap_or(p);
            let inner = mesh.vertices[third as usize] - 0.5 * (vp + vq);
            if u.dot(inner) > 0.0 {
                u = -u;
            }
            for v in [p, q] {
                *outward.entry(v).or_insert(DVec3::ZERO) += u;
            }
        }
    }
    // Neighbours on the plane: the other corners of each vertex's triangles.
    let triangles = &mesh.triangles;
    let around_of = |x: u32| {
        tris_of(x)
            .iter()
            .flat_map(move |&k| triangles[k as usize].into_iter().filter(move |&w| w != x))
    };
    // Each outline vertex's move along its outward direction (m, + outwards), and whether its edge
    // lies against darkness (else against other light beyond, a step edge).
    let moves: Vec<(u32, (f64, bool))> = outward
        .par_iter()
        .filter_map(|(&v, &u)| {
            let u = u.normalize_or_zero();
            if u == DVec3::ZERO {
                return None;
            }
            let x = mesh.vertices[v as usize];
            let ts: Vec<f64> = (-30..=30).map(|k| f64::from(k) * 0.1 * voxel_m).collect();
            // Each steep camera's luminance over its mean along the line, and their mean.
            let per: Vec<Vec<Option<f64>>> = steep
                .iter()
                .filter(|&&j| sight.clear(x, shots[j]))
                .map(|&j| {
                    ts.iter()
                        .map(|t| seen(shots[j], x + *t * u).map(|v| v / means[j]))
                        .collect()
                })
                .collect();
            let l: Vec<Option<f64>> = (0..ts.len())
                .map(|k| {
                    let vals: Vec<f64> = per.iter().filter_map(|p| p[k]).collect();
                    (vals.len() >= 3).then(|| vals.iter().sum::<f64>() / vals.len() as f64)
                })
                .collect();
            let inside = l[..=30].iter().flatten().copied().fold(0.0, f64::max);
            if inside <= 0.0 {
                return None;
            }
            if l[ts.len() - 1].is_none_or(|v| v > DARK_BEYOND * inside) {
                // Other light lies beyond (another part behind, seen past the edge): each camera
                // sees a step from this part's light to that light at the edge, wherever that
                // light comes from.
                return step_edge(&ts, &per).map(|t| (v, (t, false)));
            }
            // Each camera's own half-light point, their median: the mean of the cameras' profiles
            // is wider than each (they are registered to a fraction of a unit), so across a small
            // part it never reaches the light inside and its half-light point lay outside the edge.
            let halves: Vec<f64> = per.iter().filter_map(|p| half_light(&ts, p)).collect();
            if halves.len() >= 3 {
                return middle(halves).map(|h| (v, (h, true)));
            }
            half_light(&ts, &l).map(|t| (v, (t, true)))
        })
        .collect();
    // Each vertex's edge comes from a few dozen cameras' pixels and is noisy by about a quarter of
    // a unit: the moves are averaged with the outline neighbours' (twice), as a straight edge's are
    // alike. Against darkness, the moves' lengths along each vertex's own outward direction are
    // averaged, not the vectors: around a small part (a 3 mm dot, about eight outline vertices) the
    // neighbours' outward directions differ by about 45°, and averaging the vectors shrank a radial
    // move to about 0.64 of itself after two passes; rendered with those dots, led-dots'
    // orthographic intensity was 16.6 % low (median over directions; 2.6 % with the lengths
    // averaged, docs/proxy.md). A step edge's moves stay averaged as vectors: with lengths, the
    // corners of two-planes' tiles drew twice the doubled pixels.
    let dark: std::collections::BTreeSet<u32> = moves.iter().filter(|m| m.1 .1).map(|m| m.0).collect();
    let out = |v: &u32| outward[v].normalize_or_zero();
    let mut moves: BTreeMap<u32, DVec3> = moves.into_iter().map(|(v, (t, _))| (v, t * out(&v))).collect();
    for _ in 0..OUTLINE_SMOOTHING_PASSES {
        moves = moves
            .keys()
            .map(|&v| {
                let near = along
                    .get(&v)
                    .into_iter()
                    .flatten()
                    .filter_map(|w| Some((w, moves.get(w)?)));
                if dark.contains(&v) {
                    let (sum, k) = near.fold((moves[&v].dot(out(&v)), 1.0), |(s, k), (w, d)| {
                        (s + d.dot(out(w)), k + 1.0)
                    });
                    (v, sum / k * out(&v))
                } else {
                    let (sum, k) = near.fold((moves[&v], 1.0), |(s, k), (_, d)| (s + *d, k + 1.0));
                    (v, sum / k)
                }
            })
            .collect();
    }
    // The sheet's vertices next to the outline may now lie beyond it (carving left the rim a cell
    // out, with a ring of vertices between the old rim and the new one): each on-plane vertex within
    // 3 units of an outline vertex that moved inwards, behind it along the outline's outward
    // direction there (the mean over it and its outline neighbours two steps either way; within a
    // unit of that line), is pulled back onto the new outline, by at most as far as the outline
    // vertex moved.
    // Per vertex: how far back, along which direction.
    let mut pull: BTreeMap<u32, (f64, DVec3)> = BTreeMap::new();
    for (&v, d) in &moves {
        let mut u = outward[&v].normalize_or_zero();
        for w in along.get(&v).into_iter().flatten() {
            u += outward[w].normalize_or_zero();
            for x in along.get(w).into_iter().flatten() {
                u += outward[x].normalize_or_zero();
            }
        }
        let u = u.normalize_or_zero();
        let inwards = -d.dot(u);
        if u == DVec3::ZERO || inwards <= 0.0 {
            continue;
        }
        let (old, new) = (mesh.vertices[v as usize], mesh.vertices[v as usize] + *d);
        let mut seen = std::collections::HashSet::from([v]);
        let mut ring = vec![v];
        while !ring.is_empty() {
            let mut next = Vec::new();
            for x in ring {
                for w in around_of(x) {
                    if !seen.insert(w) || moves.contains_key(&w) {
                        continue;
                    }
                    let p = mesh.vertices[w as usize];
                    if (p - old).length() > 3.0 * voxel_m {
                        continue;
                    }
                    next.push(w);
                    let e = (p - new).dot(u);
                    let aside = ((p - new) - e * u).length();
                    let e = e.min(inwards);
                    if e > 0.0 && aside <= voxel_m && pull.get(&w).is_none_or(|x| e > x.0) {
                        pull.insert(w, (e, u));
                    }
                }
            }
            ring = next;
        }
    }
    for (v, d) in moves {
        mesh.vertices[v as usize] += d;
    }
    for (w, (e, u)) in pull {
        mesh.vertices[w as usize] -= e * u;
    }
}

/// The small parts of a flattened part, redrawn from the images: connected groups of the triangles
/// whose corners all lie `on` the plane (normal `normal`), at most [`SMALL_PART_UNITS`] units
/// across. For each, the cameras of `lit` at least 30° above the plane that see it past the other
/// parts sample a grid over it (0.1 unit, 3 units beyond it) as luminance over their mean
/// (`means`); the median over cameras at each point is the part's map. Its light is the region
/// connected to the map's largest value where some camera sees at least [`SMALL_PART_FLOOR`] of
/// the largest value any sees and six times its own noise (a lower camera's pixels reach further
/// across the plane; the noise from the samples in the grid's outer unit); a part
/// whose light reaches the grid's border is not isolated and stays as it is. The outline is where
/// the map falls to half its largest value, looked for along rays from the light's centroid, a
/// polygon of as many corners as the simplification keeps
/// ([`super::simplify::OUTLINE_TOLERANCE_UNITS`]), scaled about the centroid to the part's area:
/// each camera's light over the region divided by its largest value (the light of a pixel wholly
/// on the part; a pixel's blur spreads the light but does not change its sum), the median over
/// cameras (each camera's pixels sample the part's area with an error of a few per cent; the
/// scale held within 0.7–1.4, the polygon's area within 0.49–1.96 of the outline's). The
/// half-light outline alone lies inside a curved rim (the blur of a capture pixel across it: a
/// 3 mm dot through 0.95 mm pixels came out 3 % small); followed vertex by vertex, the crumpled
/// rim came out 3–28 % too large.
fn small_parts(
    mesh: &Mesh,
    on: &std::collections::HashSet<usize>,
    normal: DVec3,
    unit: f64,
    (shots, sight): (&[&Shot], &Sight),
    means: &[f64],
    lit: &[usize],
) -> Vec<Redraw> {
    use glam::DVec2;
    let tris: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&k| mesh.triangles[k].iter().all(|&i| on.contains(&(i as usize))))
        .collect();
    let Some(&first) = tris.first() else {
        return Vec::new();
    };
    // Connected groups of those triangles.
    let comp = components_of(mesh.vertices.len(), tris.iter().map(|&k| &mesh.triangles[k]));
    let mut groups: std::collections::BTreeMap<u32, Vec<usize>> = std::collections::BTreeMap::new();
    for &k in &tris {
        groups.entry(comp[mesh.triangles[k][0] as usize]).or_default().push(k);
    }
    drop(comp);
    let p0 = mesh.vertices[mesh.triangles[first][0] as usize];
    let e1 = normal.any_orthonormal_vector();
    let e2 = normal.cross(e1);
    let to2 = |p: DVec3| DVec2::new((p - p0).dot(e1), (p - p0).dot(e2));
    let to3 = |q: DVec2| p0 + q.x * e1 + q.y * e2;
    let groups: Vec<Vec<usize>> = groups.into_values().collect();
    groups
        .into_par_iter()
        .filter_map(|triangles| {
            let (lo, hi) = triangles
                .iter()
                .flat_map(|&k| mesh.triangles[k])
                .map(|i| to2(mesh.vertices[i as usize]))
                .fold(
                    (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
                    |(lo, hi), q| (lo.min(q), hi.max(q)),
                );
            if (hi - lo).length() > SMALL_PART_UNITS * unit {
                return None;
            }
            let mid = to3(0.5 * (lo + hi));
            let cams: Vec<usize> = lit
                .iter()
                .copied()
                .filter(|&j| {
                    let to = shots[j].camera.position_m - mid;
                    (to.dot(normal) / to.length()).abs() >= 30f64.to_radians().sin() && sight.clear(mid, shots[j])
                })
                .collect();
            if cams.len() < 3 {
                return None;
            }
            // The grid: n × n points h apart from `corner`.
            let h = 0.1 * unit;
            let half = 0.5 * (hi - lo).max_element() + 3.0 * unit;
            let n = (2.0 * half / h).ceil() as usize;
            let corner = 0.5 * (lo + hi) - DVec2::splat(half);
            let at = |g: usize| corner + h * DVec2::new((g % n) as f64 + 0.5, (g / n) as f64 + 0.5);
            // Each camera's samples (a camera that does not see the whole grid is left out).
            let vals: Vec<Vec<f64>> = cams
                .iter()
                .filter_map(|&j| {
                    (0..n * n)
                        .map(|g| Some(seen(shots[j], to3(at(g)))? / means[j]))
                        .collect()
                })
                .collect();
            if vals.len() < 3 {
                return None;
            }
            let map: Vec<f64> = (0..n * n)
                .map(|g| middle(vals.iter().map(|c| c[g]).collect()).unwrap_or(0.0))
                .collect();
            let (top, top_g) = map
                .iter()
                .enumerate()
                .fold((0.0, 0), |(m, k), (g, &v)| if v > m { (v, g) } else { (m, k) });
            if top <= 0.0 {
                return None;
            }
            // The light: where some camera sees it above its floor, connected to the largest value
            // (a camera's pixels reach further across the plane the lower it looks: the median's
            // region would cut the light of the lowest). A camera's floor is SMALL_PART_FLOOR of
            // the largest value any camera sees, or six times its noise where that is more: the
            // median magnitude of its samples in the grid's outer unit (at least 2 units from the
            // part) over that of a half-normal distribution; 0 in a noise-free image.
            let most = vals.iter().flatten().copied().fold(0.0, f64::max);
            let edge = 10.min(n / 4);
            let outer = |g: usize| {
                let (x, y) = (g % n, g / n);
                x < edge || y < edge || x >= n - edge || y >= n - edge
            };
            let floors: Vec<f64> = vals
                .iter()
                .map(|c| light_floor((0..n * n).filter(|&g| outer(g)).map(|g| c[g]), most))
                .collect();
            let reach = |g: usize| vals.iter().zip(&floors).any(|(c, f)| c[g] >= *f);
            let mut light = vec![false; n * n];
            let mut stack = vec![top_g];
            light[top_g] = true;
            while let Some(g) = stack.pop() {
                let (x, y) = (g % n, g / n);
                if x == 0 || y == 0 || x == n - 1 || y == n - 1 {
                    return None;
                }
                for q in [g - 1, g + 1, g - n, g + n] {
                    if !light[q] && reach(q) {
                        light[q] = true;
                        stack.push(q);
                    }
                }
            }
            let areas: Vec<f64> = vals
                .iter()
                .filter_map(|c| {
                    let (sum, peak) = (0..n * n)
                        .filter(|&g| light[g])
                        .fold((0.0, 0.0f64), |(s, p), g| (s + c[g], p.max(c[g])));
                    (peak > 0.0).then(|| sum * h * h / peak)
                })
                .collect();
            if areas.len() < 3 {
                return None;
            }
            let area = middle(areas)?;
            let (sum, weight) = (0..n * n)
                .filter(|&g| light[g])
                .fold((DVec2::ZERO, 0.0), |(s, w), g| (s + map[g] * at(g), w + map[g]));
            let c = sum / weight;
            // The map between grid points (bilinear; 0 beyond the grid).
            let value = |q: DVec2| -> f64 {
                let f = (q - corner) / h - DVec2::splat(0.5);
                let (x0, y0) = (f.x.floor(), f.y.floor());
                if x0 < 0.0 || y0 < 0.0 || x0 + 1.0 >= n as f64 || y0 + 1.0 >= n as f64 {
                    return 0.0;
                }
                let (fx, fy) = (f.x - x0, f.y - y0);
                let g = y0 as usize * n + x0 as usize;
                (1.0 - fy) * ((1.0 - fx) * map[g] + fx * map[g + 1])
                    + fy * ((1.0 - fx) * map[g + n] + fx * map[g + n + 1])
            };
            // Corners: where the simplification would remove none (the sagitta of two corners'
            // chord above 1.5 × its tolerance).
            let radius = (area / std::f64::consts::PI).sqrt();
            let tol = 1.5 * super::simplify::OUTLINE_TOLERANCE_UNITS * unit;
            let corners = if tol >= radius {
                8
            } else {
                ((std::f64::consts::TAU / (1.0 - tol / radius).acos()).floor() as usize).clamp(8, 64)
            };
            let step = 0.05 * unit;
            let ring: Vec<DVec2> = (0..corners)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / corners as f64;
                    let d = DVec2::new(a.cos(), a.sin());
                    let mut prev = value(c);
                    let mut r = 0.0;
                    while r < 2.0 * half {
                        let next = value(c + (r + step) * d);
                        if next < 0.5 * top {
                            let t = if prev > next {
                                (prev - 0.5 * top) / (prev - next)
                            } else {
                                0.0
                            };
                            return Some(c + (r + t * step) * d);
                        }
                        (prev, r) = (next, r + step);
                    }
                    None
                })
                .collect::<Option<_>>()?;
            let poly = (0..corners)
                .map(|k| 0.5 * (ring[k] - c).perp_dot(ring[(k + 1) % corners] - c))
                .sum::<f64>();
            if poly <= 0.0 {
                return None;
            }
            let s = (area / poly).sqrt().clamp(0.7, 1.4);
            let ring: Vec<DVec3> = ring.iter().map(|q| to3(c + s * (*q - c))).collect();
            Some(Redraw::fan(triangles, to3(c), &ring))
        })
        .collect()
}

/// Slices of a line part (`line_part`) are this many units apart along it.
pub const LINE_SLICE_UNITS: f64 = 2.0;

/// Most slices a line part's band is extended by beyond the part at either end (where carving
/// broke a strip into pieces: 300 mm at 1.5 mm units takes 100).
pub const MAX_LINE_SLICES: usize = 4096;

/// A line part's slices are averaged with this many neighbours on each side (within a run).
pub const LINE_SMOOTHING_SLICES: usize = 3;

/// A line part (the vertices `part`, on the plane `(point, normal)`, along `axis`) redrawn as a
/// band from the images, replacing `triangles`: slices [`LINE_SLICE_UNITS`] apart across it, each
/// drawn between the half-light points of the median over the cameras (above 30°, clear of the
/// rest of the mesh) of their luminance over their mean, its width scaled to the width the
/// cameras' light gives (each camera's light across the slice over its largest value, the median
/// over cameras; the scale held within 0.7-1.4, as a small part's). A run of slices is broken
/// where the median's peak falls below half the slices' median peak (a gap); each run's ends are
/// at the half-light points along its middle. `None` when no slice is seen by 3 cameras.
#[allow(clippy::too_many_arguments)]
fn line_part(
    mesh: &Mesh,
    part: &[usize],
    triangles: Vec<usize>,
    (point, normal): (DVec3, DVec3),
    axis: DVec3,
    unit: f64,
    (shots, sight): (&[&Shot], &Sight),
    means: &[f64],
    lit: &[usize],
    depth_fitted: bool,
) -> Option<Redraw> {
    use glam::DVec2;
    let a = (axis - axis.dot(normal) * normal).normalize_or_zero();
    if a == DVec3::ZERO {
        return None;
    }
    let b = normal.cross(a);
    let to2 = |p: DVec3| DVec2::new((p - point).dot(a), (p - point).dot(b));
    let to3 = |q: DVec2| point + q.x * a + q.y * b;
    let (lo, hi) = part.iter().map(|&i| to2(mesh.vertices[i])).fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), q| (lo.min(q), hi.max(q)),
    );
    // Samples a tenth of a unit apart, or a fifth of the cameras' pixel where their images are
    // finer than the unit (the median footprint at the part's middle).
    let mid = to3(0.5 * (lo + hi));
    let px: Vec<f64> = lit
        .iter()
        .map(|&j| (shots[j].camera.position_m - mid).length() / shots[j].intrinsics.focal_px.max_element())
        .collect();
    let h = middle(px).map_or(0.1 * unit, |p| (0.2 * p).min(0.1 * unit));
    let margin = 3.0 * unit;
    let (s0, s1) = (lo.y - margin, hi.y + margin);
    let n = ((s1 - s0) / h).ceil() as usize + 1;
    let across = |k: usize| s0 + h * k as f64;
    let cams_at = |p: DVec3| -> Vec<usize> {
        lit.iter()
            .copied()
            .filter(|&j| {
                let to = shots[j].camera.position_m - p;
                (to.dot(normal) / to.length()).abs() >= 30f64.to_radians().sin() && sight.clear(p, shots[j])
            })
            .collect()
    };
    // Each camera's samples along a line of points (a camera that does not see all of them is
    // left out), and their median.
    let samples = |cams: &[usize], pts: &[DVec3]| -> Vec<Vec<f64>> {
        cams.iter()
            .filter_map(|&j| pts.iter().map(|p| Some(seen(shots[j], *p)? / means[j])).collect())
            .collect()
    };
    let median = |vals: &[Vec<f64>], k: usize| middle(vals.iter().map(|c| c[k]).collect()).unwrap_or(0.0);
    /// A slice: along, middle and half width across (m), its median's peak, its cameras.
    struct Slice {
        t: f64,
        mid: f64,
        half: f64,
        top: f64,
        cams: Vec<usize>,
    }
    let count = (((hi.x - lo.x) / (LINE_SLICE_UNITS * unit)).round() as usize).max(1);
    let slice_at = |t: f64| -> Option<Slice> {
        {
            let cams = cams_at(to3(DVec2::new(t, 0.5 * (lo.y + hi.y))));
            let pts: Vec<DVec3> = (0..n).map(|i| to3(DVec2::new(t, across(i)))).collect();
            let vals = samples(&cams, &pts);
            if vals.len() < 3 {
                return None;
            }
            let map: Vec<f64> = (0..n).map(|i| median(&vals, i)).collect();
            let (top, peak) = map
                .iter()
                .enumerate()
                .fold((0.0, 0), |(m, p), (i, &v)| if v > m { (v, i) } else { (m, p) });
            if top <= 0.0 {
                return Some(Slice {
                    t,
                    mid: 0.0,
                    half: 0.0,
                    top: 0.0,
                    cams,
                });
            }
            // Half light on each side of the peak (within the margin).
            let left = (1..=peak).rev().find(|&i| map[i - 1] < 0.5 * top).map(|i| {
                let (x, y) = (map[i], map[i - 1]);
                across(i) - h * (x - 0.5 * top) / (x - y)
            })?;
            let right = (peak..n - 1).find(|&i| map[i + 1] < 0.5 * top).map(|i| {
                let (x, y) = (map[i], map[i + 1]);
                across(i) + h * (x - 0.5 * top) / (x - y)
            })?;
            // The light across: where some camera sees it above its floor (as in `small_parts`:
            // SMALL_PART_FLOOR of the most, or six times the camera's noise from its outer unit
            // on both sides), connected to the peak.
            let most = vals.iter().flatten().copied().fold(0.0, f64::max);
            let edge = 10.min(n / 4);
            let floors: Vec<f64> = vals
                .iter()
                .map(|c| light_floor(c[..edge].iter().chain(&c[n - edge..]).copied(), most))
                .collect();
            let reach = |i: usize| vals.iter().zip(&floors).any(|(c, f)| c[i] >= *f);
            let first = (0..=peak).rev().take_while(|&i| reach(i)).last().unwrap_or(peak);
            let last = (peak..n).take_while(|&i| reach(i)).last().unwrap_or(peak);
            if first == 0 || last == n - 1 {
                return None;
            }
            let widths: Vec<f64> = vals
                .iter()
                .filter_map(|c| {
                    let (sum, most) = c[first..=last]
                        .iter()
                        .fold((0.0, 0.0f64), |(s, m), v| (s + v, m.max(*v)));
                    (most > 0.0).then(|| sum * h / most)
                })
                .collect();
            if widths.len() < 3 {
                return None;
            }
            let width = middle(widths)?;
            let scale = (width / (right - left)).clamp(0.7, 1.4);
            Some(Slice {
                t,
                mid: 0.5 * (left + right),
                half: 0.5 * scale * (right - left),
                top,
                cams,
            })
        }
    };
    let step_t = (hi.x - lo.x) / count as f64;
    let mut slices: Vec<Option<Slice>> = (0..count)
        .into_par_iter()
        .map(|k| slice_at(lo.x + step_t * (k as f64 + 0.5)))
        .collect();
    if !depth_fitted {
        // The band's edges, where every camera sees half its light when the band is at the
        // strip's depth: a plane a fraction of a unit off (carving's lens, the fit's tilt along a
        // 300 mm strip) moves each camera's view of an edge by that over the tangent of its
        // elevation, and a view 10° above it draws a 1 mm strip 0.1 mm deep half off itself.
        let edges: Vec<Edge> = slices
            .iter()
            .flatten()
            .filter(|s| s.top > 0.0)
            .flat_map(|s| {
                [-1.0, 1.0].map(|side| Edge {
                    t: s.t,
                    s: side * s.half,
                    p: to3(DVec2::new(s.t, s.mid + side * s.half)),
                })
            })
            .collect();
        if let Some([dz, slope, roll]) = line_depth(&edges, normal, unit, h, (shots, sight), means, lit) {
            // The plane moved by dz at the middle, tilted by `slope` along the axis and by `roll`
            // across it (the light gives its facing to a few degrees only).
            let tm = 0.5 * (lo.x + hi.x);
            let sm: Vec<f64> = slices.iter().flatten().filter(|s| s.top > 0.0).map(|s| s.mid).collect();
            let centre = to3(DVec2::new(tm, middle(sm).unwrap_or(0.0)));
            let axis = (a + slope * normal).normalize();
            let normal = (normal - slope * a - roll * b).normalize();
            let point = centre + dz * normal;
            return line_part(
                mesh,
                part,
                triangles,
                (point, normal),
                axis,
                unit,
                (shots, sight),
                means,
                lit,
                true,
            );
        }
    }
    let typical = middle(slices.iter().flatten().map(|s| s.top).filter(|t| *t > 0.0).collect())?;
    // The band goes on beyond the part while the light does: carving can break a strip narrower
    // than its cells into pieces, and each piece's band then covers the whole strip (the copies
    // are merged in `refine_flat_parts`), its gaps included.
    let lit_slice = |s: &Option<Slice>| s.as_ref().is_some_and(|s| s.top >= 0.5 * typical);
    let extend = |from: f64, dir: f64| -> Vec<Option<Slice>> {
        let mut more = Vec::new();
        while more.len() < MAX_LINE_SLICES {
            let s = slice_at(from + dir * step_t * (more.len() + 1) as f64);
            if !lit_slice(&s) {
                break;
            }
            more.push(s);
        }
        more
    };
    let first_t = lo.x + 0.5 * step_t;
    let last_t = lo.x + step_t * (count as f64 - 0.5);
    let before = if lit_slice(&slices[0]) {
        extend(first_t, -1.0)
    } else {
        Vec::new()
    };
    let after = if slices.last().is_some_and(lit_slice) {
        extend(last_t, 1.0)
    } else {
        Vec::new()
    };
    slices = before.into_iter().rev().chain(slices).chain(after).collect();
    // Runs of lit slices.
    let mut runs: Vec<Vec<&Slice>> = Vec::new();
    let mut open = false;
    for s in &slices {
        match s {
            Some(s) if s.top >= 0.5 * typical => {
                if !open {
                    runs.push(Vec::new());
                    open = true;
                }
                if let Some(r) = runs.last_mut() {
                    r.push(s);
                }
            }
            _ => open = false,
        }
    }
    // Where the light along a run's middle falls to half its typical peak, walking from the
    // slice `s` by `dir` (at most one slice and the margin).
    let end = |s: &Slice, dir: f64| -> f64 {
        let step = 0.5 * h;
        let reach = 0.5 * LINE_SLICE_UNITS * unit + margin;
        let k = (reach / step).ceil() as usize;
        let pts: Vec<DVec3> = (0..=k)
            .map(|i| to3(DVec2::new(s.t + dir * step * i as f64, s.mid)))
            .collect();
        let vals = samples(&s.cams, &pts);
        if vals.len() < 3 {
            return s.t + dir * 0.5 * LINE_SLICE_UNITS * unit;
        }
        let prof: Vec<f64> = (0..=k).map(|i| median(&vals, i)).collect();
        let half = 0.5 * typical;
        (0..k)
            .find(|&i| prof[i] >= half && prof[i + 1] < half)
            .map_or(s.t + dir * 0.5 * LINE_SLICE_UNITS * unit, |i| {
                s.t + dir * step * (i as f64 + (prof[i] - half) / (prof[i] - prof[i + 1]))
            })
    };
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut ends: Option<(DVec3, DVec3, f64)> = None;
    for run in runs {
        let (Some(first), Some(last)) = (run.first(), run.last()) else {
            continue;
        };
        // Each slice's middle and width averaged with its neighbours' within LINE_SMOOTHING_SLICES
        // (in the run): each is the median of a few cameras' half-light points, a hundredth of a
        // millimetre apart from slice to slice along a straight strip.
        let smooth: Vec<(f64, f64, f64)> = (0..run.len())
            .map(|k| {
                let w = &run[k.saturating_sub(LINE_SMOOTHING_SLICES)..(k + LINE_SMOOTHING_SLICES + 1).min(run.len())];
                let n = w.len() as f64;
                (
                    run[k].t,
                    w.iter().map(|s| s.mid).sum::<f64>() / n,
                    w.iter().map(|s| s.half).sum::<f64>() / n,
                )
            })
            .collect();
        let (f, l) = (smooth[0], smooth[smooth.len() - 1]);
        let mut stations: Vec<(f64, f64, f64)> = vec![(end(first, -1.0), f.1, f.2)];
        stations.extend(smooth.iter().copied());
        stations.push((end(last, 1.0), l.1, l.2));
        let at = |s: &(f64, f64, f64)| to3(DVec2::new(s.0, s.1));
        if let (Some(s0), Some(s1)) = (stations.first(), stations.last()) {
            let half = stations.iter().map(|s| s.2).fold(ends.map_or(0.0, |e| e.2), f64::max);
            ends = Some((ends.map_or(at(s0), |e| e.0), at(s1), half));
        }
        let base = vertices.len() as u32;
        for &(t, mid, half) in &stations {
            vertices.push(to3(DVec2::new(t, mid - half)));
            vertices.push(to3(DVec2::new(t, mid + half)));
        }
        for k in 0..stations.len() as u32 - 1 {
            let (l0, r0, l1, r1) = (base + 2 * k, base + 2 * k + 1, base + 2 * k + 2, base + 2 * k + 3);
            faces.push([l0, l1, r1]);
            faces.push([l0, r1, r0]);
        }
    }
    (!faces.is_empty()).then_some(Redraw {
        triangles,
        vertices,
        faces,
        line: ends,
    })
}

/// The depth of a line part's band, from its edge points `edges` (each with its place along the
/// axis, m): the offset along `normal` at the middle and the slope along the axis (m per m) that
/// minimise the cameras' disagreement at the edges (as [`point_disagreement`]), searched within a
/// unit in steps of `h`, then a tenth of it, the slope within a unit over the half length; `None`
/// when fewer than 3 cameras decide or the least disagreement is not [`MIN_GAIN`] below the
/// plane's own.
fn line_depth(
    edges: &[Edge],
    normal: DVec3,
    unit: f64,
    h: f64,
    (shots, sight): (&[&Shot], &Sight),
    means: &[f64],
    lit: &[usize],
) -> Option<[f64; 3]> {
    if edges.len() < 4 {
        return None;
    }
    let (t0, t1) = edges
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), e| (a.min(e.t), b.max(e.t)));
    let tm = 0.5 * (t0 + t1);
    let half = (0.5 * (t1 - t0)).max(unit);
    let width = edges.iter().map(|e| e.s.abs()).fold(0.0, f64::max).max(h);
    let vis: Vec<Vec<bool>> = edges.par_iter().map(|e| sight.row(e.p, shots)).collect();
    let cost = |[dz, slope, roll]: [f64; 3]| -> f64 {
        edges
            .par_iter()
            .zip(&vis)
            .filter_map(|(e, row)| {
                point_disagreement(
                    e.p + (dz + slope * (e.t - tm) + roll * e.s) * normal,
                    shots,
                    means,
                    lit,
                    row,
                )
            })
            .sum()
    };
    let at_zero = cost([0.0; 3]);
    if at_zero <= 0.0 {
        return None;
    }
    let search = |centre: f64, step: f64, reach: f64, f: &dyn Fn(f64) -> f64| -> f64 {
        let n = (reach / step).round() as i64;
        (-n..=n)
            .map(|k| centre + k as f64 * step)
            .map(|x| (x, f(x)))
            .fold(
                (centre, f64::INFINITY),
                |best, (x, c)| if c < best.1 { (x, c) } else { best },
            )
            .0
    };
    // Coordinate descent: the offset, the slope, the roll (within ±30°), then each again finer.
    let mut x = [0.0; 3];
    let steps = [h, h / half, 0.5 * h / width];
    let reach = [unit, unit / half, 30f64.to_radians().tan()];
    for pass in 0..2 {
        for k in 0..3 {
            let (step, span) = if pass == 0 {
                (steps[k], reach[k])
            } else {
                (0.1 * steps[k], 2.0 * steps[k])
            };
            x[k] = search(x[k], step, span, &|v| {
                let mut y = x;
                y[k] = v;
                cost(y)
            });
        }
    }
    (cost(x) < (1.0 - MIN_GAIN) * at_zero).then_some(x)
}

/// An edge point of a line part's band: along and across its axis from the band's middle (m), and
/// where it is.
struct Edge {
    t: f64,
    s: f64,
    p: DVec3,
}

/// The middle value of `v` (the upper of the two of an even count); `None` when `v` is empty.
fn middle(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let k = v.len() / 2;
    Some(*v.select_nth_unstable_by(k, f64::total_cmp).1)
}

/// A camera's floor under a small part's or a line's light: [`SMALL_PART_FLOOR`] of `most` (the
/// largest value any camera sees there), or six times the camera's noise where that is more: the
/// median magnitude of its samples `outer` (beyond the part) over that of a half-normal
/// distribution (0.674); 0 in a noise-free image.
fn light_floor(outer: impl Iterator<Item = f64>, most: f64) -> f64 {
    let sigma = middle(outer.map(f64::abs).collect()).map_or(0.0, |m| m / 0.674_49);
    (SMALL_PART_FLOOR * most).max(f64::from(super::mask::NOISE_SIGMAS) * sigma)
}

/// The floor (a fraction of the largest value) of a small part's light in `small_parts`.
pub const SMALL_PART_FLOOR: f64 = 0.001;

/// Where a profile across an edge against darkness (`profile` at the offsets `ts`, from 3 units
/// inside to 3 outside) falls to half its largest value inside (offsets ≤ 0), searching outwards
/// from that largest value; `None` when it does not.
fn half_light(ts: &[f64], profile: &[Option<f64>]) -> Option<f64> {
    let mid = ts.len() / 2;
    let inside = profile[..=mid].iter().flatten().copied().fold(0.0, f64::max);
    if inside <= 0.0 {
        return None;
    }
    let half = 0.5 * inside;
    let peak = profile[..=mid].iter().position(|v| *v == Some(inside))?;
    (peak..ts.len() - 1).find_map(|k| match (profile[k], profile[k + 1]) {
        (Some(a), Some(b)) if a >= half && b < half => Some(ts[k] + (ts[k + 1] - ts[k]) * (a - half) / (a - b)),
        _ => None,
    })
}

/// Passes of averaging an outline vertex's move with its outline neighbours' ([`refine_flat_parts`]'s
/// outline step).
pub const OUTLINE_SMOOTHING_PASSES: usize = 2;

/// Where a part's edge lies along a line across it when other light lies beyond it (a tile in front
/// of a lit back plane): `per` holds each camera's luminance over its mean at the offsets `ts`
/// (from 3 units inside to 3 outside, in steps of 0.1). A camera whose mean over the outer unit
/// inside (`ts` ≤ −2 units) and over the outer unit beyond (≥ +2) differ by at least
/// [`STEP_CONTRAST`] of the larger sees a step: its edge is where its profile first crosses the
/// middle of the two, searching from 2 units inside to 2 outside. The edge is the median of those
/// cameras' edges, when at least [`MIN_STEP_CAMERAS`] see one and they agree within a unit
/// (interquartile range); `None` otherwise.
fn step_edge(ts: &[f64], per: &[Vec<Option<f64>>]) -> Option<f64> {
    let n = ts.len();
    let (lo, hi) = (n / 6, n - 1 - n / 6);
    let mean = |p: &[Option<f64>]| -> Option<f64> {
        let v: Vec<f64> = p.iter().copied().collect::<Option<_>>()?;
        Some(v.iter().sum::<f64>() / v.len() as f64)
    };
    let mut edges: Vec<f64> = per
        .iter()
        .filter_map(|p| {
            let (a, b) = (mean(&p[..=lo])?, mean(&p[hi..])?);
            if (a - b).abs() < STEP_CONTRAST * a.max(b) {
                return None;
            }
            let mid = 0.5 * (a + b);
            (lo..hi).find_map(|k| {
                let (x, y) = (p[k]? - mid, p[k + 1]? - mid);
                (x.signum() != y.signum()).then(|| ts[k] + (ts[k + 1] - ts[k]) * x / (x - y))
            })
        })
        .collect();
    if edges.len() < MIN_STEP_CAMERAS {
        return None;
    }
    edges.sort_by(f64::total_cmp);
    let q = |f: f64| edges[((edges.len() - 1) as f64 * f).round() as usize];
    let unit = 10.0 * (ts[1] - ts[0]);
    (q(0.75) - q(0.25) <= unit).then(|| q(0.5))
}

/// Centroid, unit normal (smallest principal axis) and the standard deviation along the largest
/// axis of `pts`; `None` for a degenerate set.
pub(crate) fn plane_of(pts: &[DVec3]) -> Option<(DVec3, DVec3, f64)> {
    let (c, cov) = covariance(pts);
    let (values, vectors) = symmetric_eigen(cov);
    let (mut lo, mut hi) = (0, 0);
    for k in 1..3 {
        if values[k] < values[lo] {
            lo = k;
        }
        if values[k] > values[hi] {
            hi = k;
        }
    }
    let normal = vectors[lo].normalize_or_zero();
    (normal != DVec3::ZERO && values[hi] > 0.0).then(|| (c, normal, values[hi].sqrt()))
}

/// A part's points spread at most this far (standard deviation, units) across their longest axis
/// in both other directions make a line (a strip's lens), whose plane the points do not give.
pub const LINE_WIDTH_UNITS: f64 = 1.5;

/// The longest principal axis of `pts` when they make a line ([`LINE_WIDTH_UNITS`]); `None`
/// otherwise.
fn line_axis(pts: &[DVec3], unit: f64) -> Option<DVec3> {
    let (values, vectors) = eigen_descending(covariance(pts).1);
    (values[0].sqrt() >= MIN_SPAN_CELLS * unit && values[1].max(0.0).sqrt() <= LINE_WIDTH_UNITS * unit)
        .then(|| vectors[0].normalize_or_zero())
        .filter(|a| *a != DVec3::ZERO)
}

/// Centroid and covariance of `pts` (not empty).
fn covariance(pts: &[DVec3]) -> (DVec3, DMat3) {
    let n = pts.len() as f64;
    let c = pts.iter().sum::<DVec3>() / n;
    let mut cov = DMat3::ZERO;
    for p in pts {
        let d = *p - c;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    (c, cov * (1.0 / n))
}

/// [`symmetric_eigen`] with the values in decreasing order.
fn eigen_descending(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let (values, vectors) = symmetric_eigen(m);
    let mut order = [0, 1, 2];
    order.sort_by(|a, b| values[*b].total_cmp(&values[*a]));
    (order.map(|k| values[k]), order.map(|k| vectors[k]))
}

/// The way a line part (points `pts` about `centre`, along `axis`) faces, from the light the
/// cameras see on it: across the axis, the light-weighted mean of the directions to the cameras
/// (an emitter lit on one side), or, when those cancel (lit on both sides), the direction of the
/// most light (a strip narrower than a pixel shows light in proportion to its width seen, |cos|
/// of the angle from its normal). `None` when fewer than 3 cameras see light on it or the light
/// favours no direction.
fn light_normal(pts: &[DVec3], centre: DVec3, axis: DVec3, shots: &[Shot], sight: &Sight) -> Option<DVec3> {
    let step = (pts.len() / 500).max(1);
    let pts: Vec<DVec3> = pts.iter().step_by(step).copied().collect();
    let all: Vec<&Shot> = shots.iter().collect();
    let vis = sight.rows(&pts, &all);
    let (means, lit) = camera_means(&pts, &all, &vis)?;
    let across = |j: usize| {
        let d = (all[j].camera.position_m - centre).normalize_or_zero();
        d - d.dot(axis) * axis
    };
    let (mut first, mut weight, mut second) = (DVec3::ZERO, 0.0, DMat3::ZERO);
    for &j in &lit {
        let d = across(j);
        first += means[j] * d;
        weight += means[j] * d.length();
        second += DMat3::from_cols(d * d.x, d * d.y, d * d.z) * means[j];
    }
    if weight <= 0.0 {
        return None;
    }
    if first.length() >= 0.3 * weight {
        return Some(first.normalize());
    }
    let (values, vectors) = eigen_descending(second);
    let n = vectors[0] - vectors[0].dot(axis) * axis;
    (values[0] >= 1.2 * values[1] && n.length() > 0.5).then(|| n.normalize())
}

/// Eigenvalues and unit eigenvectors of a symmetric 3 × 3 matrix: the values in closed form
/// (Smith 1961), each vector as the longest cross product of two rows of M − λI.
fn symmetric_eigen(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let a = m.to_cols_array_2d();
    let p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let values = if p1 <= 1e-30 * (q * q).max(1e-300) {
        [a[0][0], a[1][1], a[2][2]]
    } else {
        let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let b = (m - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
        let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
        let phi = r.acos() / 3.0;
        let big = q + 2.0 * p * phi.cos();
        let small = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
        [big, 3.0 * q - big - small, small]
    };
    let vector = |l: f64| -> DVec3 {
        let r = m - DMat3::from_diagonal(DVec3::splat(l));
        let (r0, r1, r2) = (r.row(0), r.row(1), r.row(2));
        let c = [r0.cross(r1), r0.cross(r2), r1.cross(r2)];
        let best = c
            .iter()
            .copied()
            .max_by(|x, y| x.length_squared().total_cmp(&y.length_squared()));
        match best {
            Some(v) if v.length_squared() > 1e-300 => v.normalize(),
            // A repeated value: any vector orthogonal to the rows that are not zero.
            _ => [r0, r1, r2]
                .into_iter()
                .find(|v| v.length_squared() > 1e-300)
                .map_or(DVec3::X, |v| v.any_orthonormal_vector()),
        }
    };
    (values, values.map(vector))
}

/// Which cameras see a point of one part past the rest of the mesh.
struct Sight {
    /// The other parts' triangles; `None` when there are none (or more than a hierarchy holds,
    /// `bvh::MAX_TRIANGLES`: then every camera counts, as without this test).
    others: Option<ProxyBvh>,
    /// Segment parameters within this of either end do not count (the point's own surface, a
    /// fraction of a unit from it, is not an occluder).
    eps: f32,
}

impl Sight {
    /// The occluders of the parts `ids` (`comp` gives each vertex's part): every other part's
    /// triangles.
    fn without(mesh: &Mesh, comp: &[u32], ids: &[u32], voxel_m: f64) -> Self {
        let soup: Vec<[f32; 3]> = mesh
            .triangles
            .iter()
            .filter(|t| !ids.contains(&comp[t[0] as usize]))
            .flat_map(|t| mesh.corners(t).map(|v| v.as_vec3().to_array()))
            .collect();
        Self {
            others: ProxyBvh::build(&soup).ok(),
            eps: (0.5 * voxel_m) as f32,
        }
    }

    /// Whether camera `s` sees `p` past the other parts.
    fn clear(&self, p: DVec3, s: &Shot) -> bool {
        let Some(bvh) = &self.others else { return true };
        let len = (s.camera.position_m - p).length().max(1e-9) as f32;
        !bvh.occluded(p.as_vec3(), s.camera.position_m.as_vec3(), self.eps / len)
    }

    /// [`Self::clear`] for every camera of `shots`.
    fn row(&self, p: DVec3, shots: &[&Shot]) -> Vec<bool> {
        shots.iter().map(|s| self.clear(p, s)).collect()
    }

    /// [`Self::row`] for every point.
    fn rows(&self, pts: &[DVec3], shots: &[&Shot]) -> Vec<Vec<bool>> {
        pts.par_iter().map(|p| self.row(*p, shots)).collect()
    }
}

/// Bilinear luminance at pixel coordinates (u, v) (pixel centres at +0.5), `None` outside.
fn sample(img: &Crop, u: f64, v: f64) -> Option<f64> {
    let (x, y) = (u - 0.5, v - 0.5);
    if !(x >= 0.0 && y >= 0.0 && x <= f64::from(img.width) - 1.0 && y <= f64::from(img.height) - 1.0) {
        return None;
    }
    let (x0, y0) = (x.floor() as u32, y.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(img.width - 1), (y0 + 1).min(img.height - 1));
    let (fx, fy) = (x - f64::from(x0), y - f64::from(y0));
    let g = |x: u32, y: u32| f64::from(img.get(x, y));
    Some((1.0 - fy) * ((1.0 - fx) * g(x0, y0) + fx * g(x1, y0)) + fy * ((1.0 - fx) * g(x0, y1) + fx * g(x1, y1)))
}

/// Camera `s`'s luminance at point `p` (luminaire frame), `None` outside its image.
fn seen(s: &Shot, p: DVec3) -> Option<f64> {
    let uv = s.intrinsics.project(s.camera.to_camera(p - s.camera.position_m))?;
    sample(&s.image, uv.x, uv.y)
}

/// Each camera's mean luminance over `pts`, and which cameras see light there (a mean above 10⁻³
/// of the brightest); `None` when fewer than 3 do.
fn camera_means(pts: &[DVec3], shots: &[&Shot], vis: &[Vec<bool>]) -> Option<(Vec<f64>, Vec<usize>)> {
    let means: Vec<f64> = (0..shots.len())
        .into_par_iter()
        .map(|j| {
            let (sum, k) = pts
                .iter()
                .zip(vis)
                .filter(|(_, row)| row[j])
                .filter_map(|(p, _)| seen(shots[j], *p))
                .fold((0.0, 0usize), |(a, k), v| (a + v, k + 1));
            if k == 0 {
                0.0
            } else {
                sum / k as f64
            }
        })
        .collect();
    let brightest = means.iter().copied().fold(0.0, f64::max);
    let lit: Vec<usize> = (0..shots.len()).filter(|&j| means[j] > 1e-3 * brightest).collect();
    (lit.len() >= 3 && brightest > 0.0).then_some((means, lit))
}

/// The variance, across the cameras `lit`, of their luminance at `p` over their mean; `None` when
/// fewer than 3 of them see `p`.
fn point_disagreement(p: DVec3, shots: &[&Shot], means: &[f64], lit: &[usize], vis: &[bool]) -> Option<f64> {
    let vals: Vec<f64> = lit
        .iter()
        .filter(|&&j| vis[j])
        .filter_map(|&j| seen(shots[j], p).map(|v| v / means[j]))
        .collect();
    if vals.len() < 3 {
        return None;
    }
    let m = vals.iter().sum::<f64>() / vals.len() as f64;
    Some(vals.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / vals.len() as f64)
}

/// The cameras' disagreement about the points `pts` moved by `dz` along `normal`: Σ over points
/// (seen by at least 3 cameras) of the variance across cameras of the luminance over that camera's
/// mean; `None` when fewer than 3 cameras see light.
fn disagreement(pts: &[DVec3], normal: DVec3, dz: f64, shots: &[&Shot], vis: &[Vec<bool>]) -> Option<f64> {
    let moved: Vec<DVec3> = pts.iter().map(|p| *p + dz * normal).collect();
    let (means, lit) = camera_means(&moved, shots, vis)?;
    Some(
        moved
            .par_iter()
            .zip(vis)
            .filter_map(|(p, row)| point_disagreement(*p, shots, &means, &lit, row))
            .sum(),
    )
}

/// The offset (m) in ±[`SEARCH_CELLS`] cells with the least disagreement, and the disagreement at 0
/// and there; 0 when the cameras do not decide (see the module's promises) or the least is at the
/// end of the range and lower by less than [`EDGE_MIN_GAIN`].
fn best_offset(pts: &[DVec3], normal: DVec3, voxel_m: f64, shots: &[&Shot], vis: &[Vec<bool>]) -> (f64, [f64; 2]) {
    let Some(at_zero) = disagreement(pts, normal, 0.0, shots, vis) else {
        return (0.0, [0.0, 0.0]);
    };
    let mut best = (0.0, at_zero);
    let coarse = 0.05 * voxel_m;
    let n = (SEARCH_CELLS * voxel_m / coarse).round() as i64;
    for k in -n..=n {
        let dz = k as f64 * coarse;
        if let Some(c) = disagreement(pts, normal, dz, shots, vis) {
            if c < best.1 {
                best = (dz, c);
            }
        }
    }
    if best.0.abs() >= (n as f64 - 0.5) * coarse && best.1 > (1.0 - EDGE_MIN_GAIN) * at_zero {
        // The least disagreement at the end of the range is no minimum: it only falls that way,
        // and by little (cos100, uniform and seen only within 25° of its axis: 2.4 % less 2 units
        // out, where the outline its carving gave was within 0.1 mm). Falling by much, it points
        // to the surface beyond (a floating lens bottom under a sparsely scanned disc: 99 %).
        return (0.0, [at_zero, at_zero]);
    }
    let fine = 0.005 * voxel_m;
    let centre = best.0;
    for k in -10..=10 {
        let dz = centre + k as f64 * fine;
        if let Some(c) = disagreement(pts, normal, dz, shots, vis) {
            if c < best.1 {
                best = (dz, c);
            }
        }
    }
    if best.1 > (1.0 - MIN_GAIN) * at_zero {
        return (0.0, [at_zero, at_zero]);
    }
    (best.0, [at_zero, best.1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crops_keep_each_rows_lit_span_and_read_as_the_whole_image() {
        // A lit ellipse with dark rows above and below, a NaN, a negative and a value too small
        // for f16 beside it: every pixel reads as the whole image held as f16 would.
        let (w, h) = (61u32, 40u32);
        let mut img = LuminanceImage::zeros(w, h);
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = ((f64::from(x) - 30.0) / 25.0, (f64::from(y) - 20.0) / 12.0);
                if dx * dx + dy * dy <= 1.0 {
                    img.data[(y * w + x) as usize] = 100.0 + (x * 7 + y * 13) as f32;
                }
            }
        }
        img.data[(20 * w + 2) as usize] = f32::NAN;
        img.data[(20 * w + 3) as usize] = -5.0;
        img.data[(21 * w + 1) as usize] = 1e-9;
        let crop = Crop::of(&img);
        let max = img
            .data
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f32, f32::max);
        for y in 0..h {
            for x in 0..w {
                let v = img.data[(y * w + x) as usize];
                let v = if v.is_finite() { v.max(0.0) } else { 0.0 };
                let want = half::f16::from_f32(v / max).to_f32() * max;
                assert_eq!(crop.get(x, y), want, "({x}, {y})");
            }
        }
        assert!(
            crop.data.len() < (w * h) as usize * 3 / 4,
            "{} of {} pixels",
            crop.data.len(),
            w * h
        );
    }
    use crate::nearfield::rayset::Camera;

    #[test]
    fn eigen_of_a_rotated_diagonal_matrix() {
        let r = DMat3::from_rotation_y(0.3) * DMat3::from_rotation_x(0.7);
        let m = r * DMat3::from_diagonal(DVec3::new(1.0, 4.0, 9.0)) * r.transpose();
        let (values, vectors) = symmetric_eigen(m);
        for k in 0..3 {
            let mv = m * vectors[k];
            assert!((mv - values[k] * vectors[k]).length() < 1e-9, "{k}: {values:?}");
            assert!((vectors[k].length() - 1.0).abs() < 1e-9);
        }
        let mut s = values;
        s.sort_by(f64::total_cmp);
        assert!((s[0] - 1.0).abs() < 1e-9 && (s[2] - 9.0).abs() < 1e-9, "{s:?}");
    }

    /// Profiles from −3 to +3 units in steps of 0.1, each camera stepping at `edge` from `inside`
    /// to `beyond` over one unit (a pixel's blur), `None` where `hidden`.
    fn profile(edge: f64, inside: f64, beyond: f64) -> Vec<Option<f64>> {
        (-30..=30)
            .map(|k| {
                let t = f64::from(k) * 0.1;
                let w = (t - edge + 0.5).clamp(0.0, 1.0);
                Some(inside + (beyond - inside) * w)
            })
            .collect()
    }

    /// Across a small part the cameras' profiles, each registered a little off, average to a wider
    /// and lower bump: its half-light point lies outside the edge, each camera's does not.
    #[test]
    fn a_small_parts_edge_is_each_cameras_half_light_point() {
        let ts: Vec<f64> = (-30..=30).map(|k| f64::from(k) * 0.1).collect();
        // A part from −1.5 to 0 units (the rim vertex at 0), each camera's profile blurred over a
        // unit and shifted by up to ±0.6 units.
        let shifts = [-0.6, -0.3, 0.0, 0.3, 0.6];
        let per: Vec<Vec<Option<f64>>> = shifts
            .iter()
            .map(|s| {
                ts.iter()
                    .map(|&t| {
                        let up = (t - (-1.5 + s) + 0.5).clamp(0.0, 1.0);
                        let down = (t - s + 0.5).clamp(0.0, 1.0);
                        Some(up - down)
                    })
                    .collect()
            })
            .collect();
        let mut halves: Vec<f64> = per.iter().filter_map(|p| half_light(&ts, p)).collect();
        halves.sort_by(f64::total_cmp);
        assert!(halves[2].abs() < 0.05, "{halves:?}");
        let mean: Vec<Option<f64>> = (0..ts.len())
            .map(|k| Some(per.iter().filter_map(|p| p[k]).sum::<f64>() / per.len() as f64))
            .collect();
        let wide = half_light(&ts, &mean).unwrap();
        assert!(wide > 0.05, "{wide}");
        // A step against darkness: half-way down the blur; no fall: none.
        assert!(half_light(&ts, &profile(0.7, 1.0, 0.0)).is_some_and(|t| (t - 0.7).abs() < 0.05));
        assert_eq!(half_light(&ts, &profile(0.7, 1.0, 1.0)), None);
    }

    #[test]
    fn a_step_edge_is_where_the_cameras_see_the_step() {
        let ts: Vec<f64> = (-30..=30).map(|k| f64::from(k) * 0.1).collect();
        // A tile (1.0) before a back plane whose light differs from camera to camera, some
        // brighter, some darker, and one camera that sees no contrast.
        let mut per: Vec<Vec<Option<f64>>> = [(0.4, 3.0), (0.35, 0.2), (0.45, 2.0), (0.4, 0.1), (0.4, 4.0), (0.3, 0.3)]
            .iter()
            .map(|&(e, b)| profile(e, 1.0, b))
            .collect();
        per.push(profile(0.4, 1.0, 1.05));
        let e = step_edge(&ts, &per).expect("an edge");
        assert!((e - 0.4).abs() < 0.06, "{e}");
        // Too few cameras see a step, or they disagree by more than a unit: no edge.
        assert_eq!(step_edge(&ts, &per[..4]), None);
        let scattered: Vec<Vec<Option<f64>>> = [-1.8, -1.0, 0.0, 1.0, 1.8, -1.5]
            .iter()
            .map(|&e| profile(e, 1.0, 3.0))
            .collect();
        assert_eq!(step_edge(&ts, &scattered), None);
        // A camera whose image does not hold the whole line inside (its mean there is unknown)
        // does not count.
        let mut gaps = per.clone();
        for p in &mut gaps[..2] {
            p[5] = None;
        }
        assert_eq!(step_edge(&ts, &gaps[..6]), None);
    }

    #[test]
    fn a_part_behind_another_is_hidden_from_the_cameras_it_lies_behind() {
        // Part 0: a square at z = 0; part 1: a square at z = 0.05 behind it (cameras at z < 0).
        let square = |z: f64, h: f64| -> Vec<DVec3> {
            vec![
                DVec3::new(-h, -h, z),
                DVec3::new(h, -h, z),
                DVec3::new(h, h, z),
                DVec3::new(-h, h, z),
            ]
        };
        let mut vertices = square(0.0, 0.02);
        vertices.extend(square(0.05, 0.1));
        let mesh = Mesh {
            vertices,
            triangles: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
        };
        let comp = components(&mesh);
        assert_ne!(comp[0], comp[4]);
        let shot = |eye: DVec3| Shot {
            camera: Camera::looking_at(eye, DVec3::ZERO, "test"),
            intrinsics: Intrinsics {
                width: 8,
                height: 8,
                principal_px: glam::DVec2::splat(4.0),
                focal_px: glam::DVec2::splat(8.0),
            },
            image: Crop::of(&LuminanceImage::zeros(8, 8)),
        };
        let below = shot(DVec3::new(0.0, 0.0, -1.0));
        let aside = shot(DVec3::new(1.0, 0.0, -0.3));
        let back = Sight::without(&mesh, &comp, &[comp[4]], 0.001);
        let p = DVec3::new(0.0, 0.0, 0.05);
        assert!(!back.clear(p, &below), "the front square hides the back one's middle");
        assert!(back.clear(p, &aside));
        assert!(back.clear(DVec3::new(0.08, 0.0, 0.05), &below));
        // The front square is in front of everything: no camera is hidden from it by the back.
        let front = Sight::without(&mesh, &comp, &[comp[0]], 0.001);
        assert!(front.clear(DVec3::ZERO, &below) && front.clear(DVec3::ZERO, &aside));
    }
}
