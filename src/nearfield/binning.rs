//! Binning TM-25 rays into the luminance images of a virtual near-field goniophotometer.
//!
//! Cameras sit on a capture sphere (centre `c`, radius `r_s`) in a [`Layout`]; camera `i` at
//! direction `d_i` from the centre looks at the centre. A ray (start `p`, unit direction `k`, flux Φ)
//! leaving the luminaire towards direction `k` is what the camera whose direction is closest to `k`
//! would see:
//!
//! 1. **Camera**: the nearest camera by great-circle angle, `argmax_i k·d_i` (exact, through a bucket
//!    grid over the unit vectors; ties go to the lower index, so coincident pole cameras after the
//!    first get no rays). Each ray goes to exactly one camera, so flux is neither lost nor counted
//!    twice; rays with `k·d_i ≤ 0` for every camera (possible only for very sparse layouts) are
//!    dropped and reported.
//! 2. **Pixel**: where the ray's line crosses the camera's *object plane* (through `c`, perpendicular
//!    to `d_i`): `q = p + t·k`, `t = (c − p)·d_i / (k·d_i)`, projected with the pinhole of camera `i`.
//!    The object plane lies at distance `r_s` from the pinhole, so its pixel footprint is the same
//!    for every pixel, `A = (r_s/f_x)(r_s/f_y)`. Approximation: the ray is imaged as if it reached
//!    the pinhole along the camera's own line of sight through `q`; the angle between `k` and that
//!    line (at most about the Voronoi cell radius plus the source's angular size) is ignored.
//! 3. **Luminance**: `L = Φ_pixel / (A · Ω_i)`, where `Ω_i` is the solid angle of the directions
//!    assigned to camera `i`: its spherical Voronoi cell, computed exactly
//!    ([`NearestDirection::cell_solid_angle`]; sampled only for layouts so sparse that a cell reaches
//!    past ~85° from its camera). So
//!    `Σ_i Σ_pixels L·A·Ω_i = Σ Φ` of the rays that land inside an image: the binning conserves flux
//!    up to rays outside the field of view (reported) and f32 rounding.
//!
//! The images are noisy: a camera receives `rays × Ω_i / 4π` rays spread over its lit pixels; the
//! [`BinningReport`] says how many rays landed per lit pixel.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::error::{NearfieldError, Result};
use super::layout::{self, Layout};
use super::rayset::{CaptureSphere, Intrinsics, LuminanceImage, MemorySource, RayImageSet, Scan};
use super::tm25::{LuminousSource, Ray, RayFile};

/// Upper bound on the pixels of all binned images together (2²⁶ f32 = 256 MiB).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 26;

/// Nearest unit vector among a fixed set, by great-circle angle, in about O(1) per query: the unit
/// vectors are bucketed in a uniform grid over the cube [−1, 1]³ and searched shell by shell around
/// the query's cell until no unvisited cell can hold a closer one.
#[derive(Debug, Clone)]
pub struct NearestDirection {
    dirs: Vec<DVec3>,
    merged: Vec<bool>,
    grid: usize,
    cell: f64,
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl NearestDirection {
    /// Buckets `dirs` (normalised here; zero vectors are never returned). Directions closer than
    /// [`NearestDirection::MERGE_CHORD`] to an earlier one (e.g. the meridian starts at a pole, equal
    /// up to rounding) are merged into it: only the lowest index of such a group is ever returned.
    pub fn new(dirs: &[DVec3]) -> Self {
        let dirs: Vec<DVec3> = dirs.iter().map(|d| d.normalize_or_zero()).collect();
        // About one direction per occupied cell: the sphere crosses ~4π/h² cells of size h = 2/g.
        let grid = ((dirs.len() as f64 / 2.0).sqrt().ceil() as usize).clamp(1, 128);
        let cell = 2.0 / grid as f64;
        let mut me = Self {
            merged: dirs.iter().map(|d| *d == DVec3::ZERO).collect(),
            dirs,
            grid,
            cell,
            starts: Vec::new(),
            items: Vec::new(),
        };
        me.bucket();
        let mut near = Vec::new();
        let mut any = false;
        for i in 0..me.dirs.len() {
            if me.merged[i] {
                continue;
            }
            near.clear();
            let c = me.coords(me.dirs[i]);
            me.shell(c, 0, &mut near);
            me.shell(c, 1, &mut near);
            let di = me.dirs[i];
            if near
                .iter()
                .any(|&j| j < i && !me.merged[j] && (me.dirs[j] - di).length() < Self::MERGE_CHORD)
            {
                me.merged[i] = true;
                any = true;
            }
        }
        if any {
            me.bucket();
        }
        me
    }

    /// Chord distance below which two directions count as one (10⁻⁹, about 6·10⁻⁸ degrees).
    pub const MERGE_CHORD: f64 = 1e-9;

    /// (Re)builds the buckets from the directions not merged away.
    fn bucket(&mut self) {
        let cells = self.grid * self.grid * self.grid;
        let mut counts = vec![0u32; cells + 1];
        let keys: Vec<Option<usize>> = (0..self.dirs.len())
            .map(|i| (!self.merged[i]).then(|| self.key(self.coords(self.dirs[i]))))
            .collect();
        for k in keys.iter().flatten() {
            counts[*k + 1] += 1;
        }
        for i in 0..cells {
            counts[i + 1] += counts[i];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; counts[cells] as usize];
        for (i, k) in keys.iter().enumerate() {
            if let Some(k) = k {
                items[fill[*k] as usize] = i as u32;
                fill[*k] += 1;
            }
        }
        self.starts = counts;
        self.items = items;
    }

    /// Whether direction `i` was merged into an earlier one (or is zero) and is never returned.
    pub fn is_merged(&self, i: usize) -> bool {
        self.merged.get(i).copied().unwrap_or(true)
    }

    fn coords(&self, d: DVec3) -> [usize; 3] {
        let c = |v: f64| (((v + 1.0) / self.cell).floor().max(0.0) as usize).min(self.grid - 1);
        [c(d.x), c(d.y), c(d.z)]
    }

    fn key(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.grid + y) * self.grid + x
    }

    /// Number of directions.
    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    /// Whether there are no directions.
    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }

    /// The (normalised) direction `i`.
    pub fn direction(&self, i: usize) -> Option<DVec3> {
        self.dirs.get(i).copied()
    }

    /// Index of the direction nearest to `k` (unit), ties to the lower index; `None` when empty or
    /// `k` is not finite.
    pub fn nearest(&self, k: DVec3) -> Option<usize> {
        if !k.is_finite() || self.items.is_empty() {
            return None;
        }
        let c = self.coords(k);
        let g = self.grid as isize;
        let mut best: Option<(f64, usize)> = None;
        for r in 0..g {
            for dz in -r..=r {
                for dy in -r..=r {
                    for dx in -r..=r {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != r {
                            continue;
                        }
                        let (x, y, z) = (c[0] as isize + dx, c[1] as isize + dy, c[2] as isize + dz);
                        if x < 0 || y < 0 || z < 0 || x >= g || y >= g || z >= g {
                            continue;
                        }
                        let key = self.key([x as usize, y as usize, z as usize]);
                        let (s, e) = (self.starts[key] as usize, self.starts[key + 1] as usize);
                        for &i in &self.items[s..e] {
                            let i = i as usize;
                            let d2 = (self.dirs[i] - k).length_squared();
                            if best.is_none_or(|(b, bi)| d2 < b || (d2 == b && i < bi)) {
                                best = Some((d2, i));
                            }
                        }
                    }
                }
            }
            // Any direction not yet visited is at least r cells (r·h) away from k.
            if let Some((b, _)) = best {
                let reach = r as f64 * self.cell;
                if b <= reach * reach {
                    break;
                }
            }
        }
        best.map(|(_, i)| i)
    }

    /// Generators in the cells at Chebyshev distance exactly `r` from cell `c`.
    fn shell(&self, c: [usize; 3], r: isize, out: &mut Vec<usize>) {
        let g = self.grid as isize;
        for dz in -r..=r {
            for dy in -r..=r {
                for dx in -r..=r {
                    if dx.abs().max(dy.abs()).max(dz.abs()) != r {
                        continue;
                    }
                    let (x, y, z) = (c[0] as isize + dx, c[1] as isize + dy, c[2] as isize + dz);
                    if x < 0 || y < 0 || z < 0 || x >= g || y >= g || z >= g {
                        continue;
                    }
                    let key = self.key([x as usize, y as usize, z as usize]);
                    let (s, e) = (self.starts[key] as usize, self.starts[key + 1] as usize);
                    out.extend(self.items[s..e].iter().map(|i| *i as usize));
                }
            }
        }
    }

    /// Exact solid angle (sr) of direction `i`'s spherical Voronoi cell (0 for a merged direction),
    /// or `None` when the cell reaches more than ~85° from its generator (very sparse sets).
    ///
    /// The cell is the intersection of the half-spaces `x·(d_i − d_j) ≥ 0`; in the gnomonic projection
    /// around `d_i` each is a half-plane, so the cell is a convex polygon clipped from a large square.
    /// Neighbours are gathered shell by shell from the bucket grid until every unvisited generator
    /// is farther than twice the cell's radius (so it cannot clip it). The area is the sum of the
    /// spherical triangles (d_i, v_k, v_k+1) (Van Oosterom–Strackee).
    pub fn cell_solid_angle(&self, i: usize) -> Option<f64> {
        let di = *self.dirs.get(i)?;
        if self.merged[i] {
            return Some(0.0);
        }
        let (e1, e2) = di.any_orthonormal_pair();
        const LIMIT: f64 = 11.43; // tan 85°
        let c = self.coords(di);
        let mut cands: Vec<usize> = Vec::new();
        let mut r = 0isize;
        loop {
            self.shell(c, r, &mut cands);
            let mut poly = vec![
                DVec2::new(-LIMIT, -LIMIT),
                DVec2::new(LIMIT, -LIMIT),
                DVec2::new(LIMIT, LIMIT),
                DVec2::new(-LIMIT, LIMIT),
            ];
            for &j in &cands {
                if j == i {
                    continue;
                }
                let n = di - self.dirs[j];
                poly = clip(&poly, n.dot(e1), n.dot(e2), n.dot(di));
                if poly.is_empty() {
                    return Some(0.0);
                }
            }
            let verts: Vec<DVec3> = poly.iter().map(|p| (di + p.x * e1 + p.y * e2).normalize()).collect();
            let reach = verts.iter().map(|v| (*v - di).length()).fold(0.0, f64::max);
            let searched_all = r + 1 >= self.grid as isize;
            if searched_all || 2.0 * reach <= r as f64 * self.cell {
                if poly.iter().any(|p| p.x.abs().max(p.y.abs()) >= LIMIT * (1.0 - 1e-9)) {
                    return None;
                }
                let mut area = 0.0;
                for k in 0..verts.len() {
                    let (a, b) = (verts[k], verts[(k + 1) % verts.len()]);
                    let num = di.dot(a.cross(b)).abs();
                    let den = 1.0 + di.dot(a) + a.dot(b) + b.dot(di);
                    area += 2.0 * num.atan2(den);
                }
                return Some(area);
            }
            r += 1;
        }
    }

    /// Solid angle (sr) of every direction's spherical Voronoi cell, exact
    /// ([`NearestDirection::cell_solid_angle`]) where every cell stays within ~85° of its generator,
    /// else estimated by sampling 2²² directions; returns the values and whether they are exact.
    pub fn solid_angles(&self) -> (Vec<f64>, bool) {
        let exact: Option<Vec<f64>> = (0..self.dirs.len())
            .into_par_iter()
            .map(|i| self.cell_solid_angle(i))
            .collect();
        match exact {
            Some(v) => (v, true),
            None => (self.voronoi_solid_angles(1 << 22), false),
        }
    }

    /// Solid angle (sr) of each direction's spherical Voronoi cell, estimated from `samples`
    /// Fibonacci-lattice directions (each worth 4π/`samples` sr). They sum to 4π.
    pub fn voronoi_solid_angles(&self, samples: usize) -> Vec<f64> {
        let m = samples.max(1);
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let n = self.dirs.len();
        let counts = (0..m)
            .into_par_iter()
            .fold(
                || vec![0u64; n],
                |mut acc, i| {
                    let z = 1.0 - (2.0 * i as f64 + 1.0) / m as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let a = golden * i as f64;
                    if let Some(j) = self.nearest(DVec3::new(r * a.cos(), r * a.sin(), z)) {
                        acc[j] += 1;
                    }
                    acc
                },
            )
            .reduce(
                || vec![0u64; n],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        let w = 4.0 * std::f64::consts::PI / m as f64;
        counts.into_iter().map(|c| c as f64 * w).collect()
    }
}

/// Clips a convex polygon (gnomonic coordinates) to the half-plane `a·u + b·v + c ≥ 0`.
fn clip(poly: &[DVec2], a: f64, b: f64, c: f64) -> Vec<DVec2> {
    let side = |p: DVec2| a * p.x + b * p.y + c;
    let mut out = Vec::with_capacity(poly.len() + 1);
    for k in 0..poly.len() {
        let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(p);
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            let t = sp / (sp - sq);
            out.push(p + (q - p) * t);
        }
    }
    out
}

/// How to bin: the virtual capture sphere, camera layout and image geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct BinningOptions {
    /// The capture sphere (luminaire frame = the ray file's frame, metres).
    pub sphere: CaptureSphere,
    /// Camera layout on the sphere.
    pub layout: Layout,
    /// Seed of the layout (jitter of `rigo`).
    pub seed: u64,
    /// Image width (px).
    pub width: u32,
    /// Image height (px).
    pub height: u32,
    /// Full horizontal field of view (degrees, square pixels); `None` fits the widest object-plane
    /// crossing of any ray (+2 %) into the image.
    pub fov_deg: Option<f64>,
    /// Scale the rays' luminous fluxes so that they sum to the header's luminous flux (for files whose
    /// ray fluxes are relative weights). Off by default: ray values are used as they are.
    pub scale_to_header_flux: bool,
}

impl Default for BinningOptions {
    fn default() -> Self {
        Self {
            sphere: CaptureSphere {
                centre_m: DVec3::ZERO,
                radius_m: 1.1,
            },
            layout: Layout::Fibonacci { count: 1000 },
            seed: 0,
            width: 64,
            height: 64,
            fov_deg: None,
            scale_to_header_flux: false,
        }
    }
}

/// What the binning did, for the user to judge the images' noise.
#[derive(Debug, Clone, PartialEq)]
pub struct BinningReport {
    /// How each ray's luminous flux was obtained.
    pub luminous_source: LuminousSource,
    /// Factor applied to every ray's luminous flux (1, or header flux / Σ rays).
    pub flux_scale: f64,
    /// Rays in the file.
    pub rays_total: u64,
    /// Rays that landed in a pixel.
    pub rays_used: u64,
    /// Rays with no camera within 90° of their direction (dropped).
    pub rays_behind: u64,
    /// Rays whose object-plane crossing falls outside the image (dropped).
    pub rays_outside_image: u64,
    /// Σ luminous flux of all rays after scaling (lm).
    pub flux_total_lm: f64,
    /// Σ luminous flux of the rays that landed in a pixel (lm).
    pub flux_used_lm: f64,
    /// Σ luminous flux of the rays dropped for lack of a camera (lm).
    pub flux_behind_lm: f64,
    /// Σ luminous flux of the rays outside the images (lm).
    pub flux_outside_image_lm: f64,
    /// Σ over cameras and pixels of L·A·Ω_i, from the f32 images (lm): equals `flux_used_lm`.
    pub flux_from_images_lm: f64,
    /// Rays per camera, in camera order.
    pub rays_per_camera: Vec<u64>,
    /// Voronoi solid angle Ω_i per camera (sr); they sum to 4π.
    pub solid_angle_sr: Vec<f64>,
    /// Cameras that received no ray.
    pub cameras_with_zero_rays: usize,
    /// Cameras at the same direction as an earlier one (within [`NearestDirection::MERGE_CHORD`],
    /// e.g. the meridian starts at a pole): they get no ray and Ω = 0, the earlier one gets all.
    pub cameras_merged: usize,
    /// Pixels (over all images) that received at least one ray.
    pub lit_pixels: u64,
    /// Mean rays per lit pixel.
    pub rays_per_lit_pixel_mean: f64,
    /// Median rays per lit pixel.
    pub rays_per_lit_pixel_median: f64,
    /// Most rays in one pixel.
    pub rays_per_lit_pixel_max: u64,
    /// Pixel footprint on the object plane, (r_s/f_x)(r_s/f_y) (m²).
    pub pixel_area_m2: f64,
    /// Focal length (px), the same in x and y.
    pub focal_px: f64,
    /// Full horizontal field of view (degrees).
    pub fov_deg: f64,
    /// Whether the solid angles are exact spherical Voronoi cells (else sampled with 2²² directions,
    /// for layouts with cells wider than ~85°).
    pub solid_angles_exact: bool,
    /// Cameras that received rays but have a zero solid angle (possible only with sampled solid angles;
    /// their Ω was set to one sample's 4π/2²²).
    pub cameras_with_tiny_cells: usize,
}

/// The binned scan plus its report.
#[derive(Debug)]
pub struct BinnedScan {
    /// Cameras, intrinsics and the images (a [`MemorySource`]).
    pub scan: Scan,
    /// Counts and sums.
    pub report: BinningReport,
}

/// Per-thread accumulator of the binning pass.
#[derive(Default)]
struct Acc {
    hits: Vec<(u64, f64)>,
    behind: (u64, f64),
    outside: (u64, f64),
    total: f64,
}

impl Acc {
    fn merge(mut self, mut o: Acc) -> Acc {
        if self.hits.len() < o.hits.len() {
            std::mem::swap(&mut self.hits, &mut o.hits);
        }
        self.hits.append(&mut o.hits);
        self.behind = (self.behind.0 + o.behind.0, self.behind.1 + o.behind.1);
        self.outside = (self.outside.0 + o.outside.0, self.outside.1 + o.outside.1);
        self.total += o.total;
        self
    }
}

/// Where a ray meets camera `cam`'s object plane, in that camera's (x right, y down) metres; `None`
/// when it travels away from the camera's side (k·d ≤ 0).
fn plane_crossing(p: DVec3, k: DVec3, d: DVec3, centre: DVec3, right: DVec3, down: DVec3) -> Option<DVec2> {
    let kd = k.dot(d);
    if kd <= 1e-9 {
        return None;
    }
    let t = (centre - p).dot(d) / kd;
    let q = p + t * k - centre;
    Some(DVec2::new(q.dot(right), q.dot(down)))
}

/// Bins the rays of `file` into the images of a virtual scan (see the module documentation).
pub fn bin_rays(file: &RayFile, opts: &BinningOptions) -> Result<BinnedScan> {
    let sphere = opts.sphere;
    if !sphere.radius_m.is_finite() || sphere.radius_m <= 0.0 || !sphere.centre_m.is_finite() {
        return Err(NearfieldError::invalid(
            "radius",
            format!(
                "{} m: the capture sphere needs a finite radius > 0 and a finite centre",
                sphere.radius_m
            ),
        ));
    }
    if opts.width == 0 || opts.height == 0 || opts.width > 65_536 || opts.height > 65_536 {
        return Err(NearfieldError::invalid(
            "size",
            format!("{}×{} px is outside 1…65536", opts.width, opts.height),
        ));
    }
    if let Some(f) = opts.fov_deg {
        if !(f.is_finite() && f > 0.0 && f < 179.0) {
            return Err(NearfieldError::invalid("fov", format!("{f}° must lie in (0, 179)")));
        }
    }
    if matches!(file.luminous_source(), LuminousSource::Unavailable) {
        return Err(NearfieldError::Unsupported {
            path: file.path().to_path_buf(),
            message: "the rays carry radiant flux only and the file gives neither both header fluxes nor any \
                      spectral information, so luminous flux (and luminance) cannot be computed"
                .into(),
        });
    }
    let cameras = layout::cameras(&sphere, &opts.layout, opts.seed)?;
    let (w, h) = (opts.width, opts.height);
    let px_per_image = w as u64 * h as u64;
    let total_px = px_per_image.saturating_mul(cameras.len() as u64);
    if total_px > MAX_TOTAL_PIXELS {
        return Err(NearfieldError::invalid(
            "size",
            format!(
                "{} cameras × {w}×{h} px = {total_px} pixels exceed the in-memory limit of {MAX_TOTAL_PIXELS}; \
                 use fewer cameras or smaller images",
                cameras.len()
            ),
        ));
    }
    let dirs: Vec<DVec3> = cameras.iter().map(|c| c.direction_from(sphere.centre_m)).collect();
    let lookup = NearestDirection::new(&dirs);

    let n = file.len();
    let scale = if opts.scale_to_header_flux {
        let sum: f64 = (0..n).into_par_iter().filter_map(|i| file.ray(i)?.luminous_lm).sum();
        match file.header().luminous_flux_lm {
            Some(hf) if hf > 0.0 && sum > 0.0 => hf / sum,
            _ => {
                return Err(NearfieldError::invalid(
                    "scale-to-header-flux",
                    format!(
                        "{}: needs a positive header luminous flux and rays with flux",
                        file.path().display()
                    ),
                ))
            }
        }
    } else {
        1.0
    };

    // Field of view: given, or fitted to the widest crossing.
    let r_s = sphere.radius_m;
    let crossing = |ray: &Ray| -> Option<(usize, DVec2)> {
        let cam = lookup.nearest(ray.direction)?;
        let c = &cameras[cam];
        let q = plane_crossing(
            ray.position_m,
            ray.direction,
            dirs[cam],
            sphere.centre_m,
            c.right,
            c.down,
        )?;
        Some((cam, q))
    };
    let focal_px = match opts.fov_deg {
        Some(fov) => (w as f64 / 2.0) / (fov.to_radians() / 2.0).tan(),
        None => {
            let ext = (0..n)
                .into_par_iter()
                .filter_map(|i| crossing(&file.ray(i)?))
                .map(|(_, q)| q.abs())
                .reduce(|| DVec2::ZERO, DVec2::max);
            let ext = ext.max(DVec2::splat(1e-3)) * 1.02;
            ((w as f64 / 2.0) * r_s / ext.x).min((h as f64 / 2.0) * r_s / ext.y)
        }
    };
    let fov_deg = 2.0 * ((w as f64 / 2.0) / focal_px).atan().to_degrees();
    let intrinsics = Intrinsics {
        width: w,
        height: h,
        principal_px: DVec2::new(w as f64 / 2.0, h as f64 / 2.0),
        focal_px: DVec2::splat(focal_px),
    };
    intrinsics.validate("rays2scan")?;

    let acc = (0..n)
        .into_par_iter()
        .fold(Acc::default, |mut acc, i| {
            let Some(ray) = file.ray(i) else { return acc };
            let flux = ray.luminous_lm.unwrap_or(0.0) * scale;
            acc.total += flux;
            let Some((cam, q)) = crossing(&ray) else {
                acc.behind = (acc.behind.0 + 1, acc.behind.1 + flux);
                return acc;
            };
            let u = intrinsics.principal_px.x + focal_px * q.x / r_s;
            let v = intrinsics.principal_px.y + focal_px * q.y / r_s;
            if !(u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64) {
                acc.outside = (acc.outside.0 + 1, acc.outside.1 + flux);
                return acc;
            }
            let key = cam as u64 * px_per_image + (v as u64) * w as u64 + u as u64;
            acc.hits.push((key, flux));
            acc
        })
        .reduce(Acc::default, Acc::merge);
    let Acc {
        mut hits,
        behind,
        outside,
        total,
    } = acc;
    hits.par_sort_unstable_by_key(|h| h.0);

    let (mut omega, solid_angles_exact) = lookup.solid_angles();
    let one_sample = 4.0 * std::f64::consts::PI / (1u64 << 22) as f64;
    let pixel_area_m2 = (r_s / focal_px) * (r_s / focal_px);

    let mut images: Vec<LuminanceImage> = cameras.iter().map(|_| LuminanceImage::zeros(w, h)).collect();
    let mut rays_per_camera = vec![0u64; cameras.len()];
    let mut runs: Vec<u64> = Vec::new();
    let mut flux_used = 0.0;
    let mut tiny = 0usize;
    let mut s = 0;
    while s < hits.len() {
        let key = hits[s].0;
        let mut e = s;
        let mut sum = 0.0;
        while e < hits.len() && hits[e].0 == key {
            sum += hits[e].1;
            e += 1;
        }
        let cam = (key / px_per_image) as usize;
        let pix = (key % px_per_image) as usize;
        if omega[cam] <= 0.0 {
            omega[cam] = one_sample;
            tiny += 1;
        }
        let l = sum / (pixel_area_m2 * omega[cam]);
        if let Some(px) = images[cam].data.get_mut(pix) {
            *px = l as f32;
        }
        rays_per_camera[cam] += (e - s) as u64;
        runs.push((e - s) as u64);
        flux_used += sum;
        s = e;
    }
    let flux_from_images_lm: f64 = images
        .iter()
        .zip(&omega)
        .map(|(im, o)| im.data.iter().map(|v| *v as f64).sum::<f64>() * pixel_area_m2 * o)
        .sum();
    let lit = runs.len() as u64;
    let rays_used = hits.len() as u64;
    let max_run = runs.iter().copied().max().unwrap_or(0);
    let median = if runs.is_empty() {
        0.0
    } else {
        let mid = runs.len() / 2;
        let (_, m, _) = runs.select_nth_unstable(mid);
        let m = *m as f64;
        if runs.len().is_multiple_of(2) {
            let lower = runs[..mid].iter().copied().max().unwrap_or(0) as f64;
            0.5 * (lower + m)
        } else {
            m
        }
    };
    let report = BinningReport {
        luminous_source: file.luminous_source().clone(),
        flux_scale: scale,
        rays_total: n as u64,
        rays_used,
        rays_behind: behind.0,
        rays_outside_image: outside.0,
        flux_total_lm: total,
        flux_used_lm: flux_used,
        flux_behind_lm: behind.1,
        flux_outside_image_lm: outside.1,
        flux_from_images_lm,
        cameras_with_zero_rays: rays_per_camera.iter().filter(|c| **c == 0).count(),
        cameras_merged: (0..cameras.len()).filter(|i| lookup.is_merged(*i)).count(),
        rays_per_camera,
        solid_angle_sr: omega,
        lit_pixels: lit,
        rays_per_lit_pixel_mean: if lit > 0 { rays_used as f64 / lit as f64 } else { 0.0 },
        rays_per_lit_pixel_median: median,
        rays_per_lit_pixel_max: max_run,
        pixel_area_m2,
        focal_px,
        fov_deg,
        solid_angles_exact,
        cameras_with_tiny_cells: tiny,
    };
    let set = RayImageSet {
        sphere,
        intrinsics,
        cameras,
    };
    set.validate()?;
    Ok(BinnedScan {
        scan: Scan {
            set,
            source: Box::new(MemorySource { images }),
        },
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearfield::tm25::{encode, Tm25Header};

    #[test]
    fn nearest_matches_brute_force() {
        let dirs: Vec<DVec3> = layout::directions(&Layout::Fibonacci { count: 500 }, 0)
            .unwrap()
            .into_iter()
            .map(|(d, _)| d)
            .collect();
        let nd = NearestDirection::new(&dirs);
        let mut rng = layout::SplitMix64::new(3);
        for _ in 0..2000 {
            let k = DVec3::new(
                rng.next_f64() * 2.0 - 1.0,
                rng.next_f64() * 2.0 - 1.0,
                rng.next_f64() * 2.0 - 1.0,
            )
            .normalize();
            let brute = (0..dirs.len())
                .max_by(|&a, &b| dirs[a].dot(k).total_cmp(&dirs[b].dot(k)))
                .unwrap();
            assert_eq!(nd.nearest(k), Some(brute));
        }
        // Sparse sets: the search must widen until it is sure.
        let nd = NearestDirection::new(&[DVec3::X, -DVec3::X]);
        assert_eq!(nd.nearest(DVec3::new(0.1, 1.0, 0.0).normalize()), Some(0));
        assert_eq!(nd.nearest(-DVec3::Z + DVec3::X * -0.01), Some(1));
        let omega = NearestDirection::new(&[DVec3::Z, -DVec3::Z]).voronoi_solid_angles(10_000);
        assert!((omega[0] - 2.0 * std::f64::consts::PI).abs() < 1e-9);
    }

    #[test]
    fn exact_cells_tile_the_sphere_and_match_sampling() {
        let four_pi = 4.0 * std::f64::consts::PI;
        for l in [
            Layout::Fibonacci { count: 300 },
            Layout::Grid {
                phi_steps: 12,
                theta_steps: 7,
            },
            Layout::Rigo {
                per_hemisphere: 600,
                overlap_deg: 2.0,
                jitter_deg: 0.05,
            },
        ] {
            let d: Vec<DVec3> = layout::directions(&l, 1).unwrap().into_iter().map(|x| x.0).collect();
            let nd = NearestDirection::new(&d);
            let (exact, is_exact) = nd.solid_angles();
            assert!(is_exact, "{l:?}");
            let total: f64 = exact.iter().sum();
            assert!((total - four_pi).abs() < 1e-9, "{l:?}: {total}");
            let sampled = nd.voronoi_solid_angles(1 << 20);
            for (i, (e, s)) in exact.iter().zip(&sampled).enumerate() {
                // Sampling error: about 1/√(samples per cell) of the boundary's share.
                assert!(
                    (e - s).abs() < 0.05 * e.max(4.0 * four_pi / (1 << 16) as f64),
                    "{l:?} cell {i}: {e} vs {s}"
                );
            }
        }
        // Hemispheres are too wide for the gnomonic clip: sampled instead.
        let (h, is_exact) = NearestDirection::new(&[DVec3::Z, -DVec3::Z]).solid_angles();
        assert!(!is_exact && (h[0] - 0.5 * four_pi).abs() < 1e-9);
        // A regular octahedron: 8 equal faces' duals, 6 cells of 4π/6.
        let oct = [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
        let nd = NearestDirection::new(&oct);
        for i in 0..6 {
            let a = nd.cell_solid_angle(i).unwrap();
            assert!((a - four_pi / 6.0).abs() < 1e-12, "{a}");
        }
    }

    #[test]
    fn coincident_directions_go_to_the_first() {
        let nd = NearestDirection::new(&[DVec3::Z, DVec3::X, DVec3::Z]);
        assert_eq!(nd.nearest(DVec3::new(0.01, 0.0, 1.0).normalize()), Some(0));
        let o = nd.voronoi_solid_angles(4096);
        assert_eq!(o[2], 0.0);
        assert_eq!(nd.cell_solid_angle(2), Some(0.0));
    }

    #[test]
    fn a_collimated_beam_lands_in_one_pixel_with_the_right_luminance() {
        // 4 rays of 0.25 lm each, all along −Z from the origin, into a 6-camera grid (poles + 4).
        let h = Tm25Header::default();
        let mut rec = Vec::new();
        for _ in 0..4 {
            rec.extend_from_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.25]);
        }
        let f = RayFile::from_bytes(&encode(&h, &rec).unwrap(), "beam").unwrap();
        let opts = BinningOptions {
            layout: Layout::Grid {
                phi_steps: 4,
                theta_steps: 3,
            },
            width: 8,
            height: 8,
            fov_deg: Some(10.0),
            ..BinningOptions::default()
        };
        let b = bin_rays(&f, &opts).unwrap();
        let r = &b.report;
        assert_eq!(r.rays_used, 4);
        assert_eq!(r.lit_pixels, 1);
        assert_eq!(r.rays_per_lit_pixel_median, 4.0);
        // The nadir camera (θ = 0, index 0) gets the beam.
        assert_eq!(r.rays_per_camera[0], 4);
        assert_eq!(r.cameras_with_zero_rays, 5);
        let img = b.scan.source.image(0).unwrap();
        let l = img.get(4, 4) as f64;
        let want = 1.0 / (r.pixel_area_m2 * r.solid_angle_sr[0]);
        assert!((l - want).abs() < 1e-6 * want, "{l} vs {want}");
        assert!((r.flux_from_images_lm - 1.0).abs() < 1e-6);
        let total: f64 = r.solid_angle_sr.iter().sum();
        assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-9);
    }
}
