//! The angular half of the ray-file estimate and the virtual camera layout: a histogram of the ray
//! directions on a fine Fibonacci grid; two k-nearest-neighbour angles per direction, a narrow one
//! holding k_I rays for the intensity and a wide one holding k_S rays for the spatial footprint;
//! cameras placed about one intensity width apart; each camera's rays found through the grid
//! cells near it. Each ray carries the widths of its own direction (sample-point estimators, so
//! the kernels are normalised per ray and the flux is kept).

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use super::hull::SourceCloud;
use super::{KdeOptions, DEFAULT_B, DEFAULT_BI, MAX_AUTO_CAMERAS, MAX_CAMERAS, MAX_TOTAL_PIXELS};
use crate::nearfield::binning::NearestDirection;
use crate::nearfield::error::{NearfieldError, Result};

/// Access to ray `i`: origin (m), unit direction, luminous flux (lm); `None` to skip it.
pub type RayGet<'a> = &'a (dyn Fn(usize) -> Option<(DVec3, DVec3, f64)> + Sync);

/// Angle bins of the k-nearest-neighbour search (0 to the search radius).
const ANGLE_BINS: usize = 1024;

/// Fine cells per bucket of the k-nearest-neighbour search (about).
const CELLS_PER_BUCKET: usize = 24;

/// Fine directions per effective ray (at least 2,000, at most 40,000 directions): the finest
/// angular width is 1.5 cells, so a beam of many rays gets kernels that fine.
const FINE_PER_RAY: f64 = 0.5;

/// An intensity width grows past the flux-weighted median width only as far as it must to hold
/// this share of k_I rays ([`Bandwidths::intensity_width`]), and never past [`POOL_CAP`] medians.
/// Where rays are sparse (the flank of a beam, an emitter's horizon) a k-nearest-neighbour width
/// grows, and a wide kernel there moves the flux of the rays it holds outwards, past the edge of
/// the emission: the measured LED's intensity 12.5–17.5° above its horizon read 10 % low with
/// k-nearest-neighbour widths up to 3 medians, and the point source's 12.5° ring 18 % high. Held
/// at the median width there, they are within 2.5 % and 5 %; but in the far tails of a beam (a
/// cos¹⁰ lobe at 55°, 0.4 % of its peak) a kernel of median width holds a handful of rays, whose
/// noise doubled the convergence harness's log RMSE: there the kernel widens to hold this share.
const MIN_INTENSITY_SHARE: f64 = 0.1;

/// The footprint pool's cap (a multiple of its flux-weighted median width).
const POOL_CAP: f64 = 3.0;

/// A direction is dark where fewer than this share of an intensity kernel's rays lie within the
/// median intensity width of it (its intensity is then under about 1 % of one at the median
/// width's density); the layout spaces its cameras by the widest intensity width ([`POOL_CAP`]
/// medians) there.
/// Elsewhere they sit about 0.7 intensity widths apart: on a beam's flank the intensity falls by
/// 10× within a few kernel widths, and cameras spaced for the dark side there read it 20 % high
/// between them (the point source's 12.5° ring).
const DARK_SHARE: f64 = 0.01;

/// Directions at which the angular width is computed exactly for the layout (the others take
/// their nearest one's).
const COARSE_DIRECTIONS: usize = 3000;

/// Normalisation of the spherical Epanechnikov kernel K(θ) = c · (1 − (θ/h)²), θ < h, so that
/// ∫ K dω = 1 over the sphere: c = 1 / (2π (1 − 2 sin h / h + 2 (1 − cos h) / h²)) (1/sr).
pub fn angular_kernel(h: f64) -> f64 {
    let i = if h < 1e-3 {
        h * h / 4.0 - h.powi(4) / 72.0
    } else {
        1.0 - 2.0 * h.sin() / h + 2.0 * (1.0 - h.cos()) / (h * h)
    };
    1.0 / (2.0 * PI * i)
}

/// Fibonacci directions on the unit sphere.
pub fn fibonacci(n: usize) -> Vec<DVec3> {
    let golden = PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}

/// Counts of a ray set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RaySummary {
    /// Rays (indices 0…n−1 of the accessor).
    pub n: usize,
    /// Effective rays, (Σ Φ)² / Σ Φ².
    pub n_eff: f64,
    /// Σ luminous flux (lm).
    pub flux_lm: f64,
}

/// The direction histogram and the widths chosen from it.
#[derive(Debug, Clone)]
pub struct Bandwidths {
    /// Rays per spatial kernel k_s.
    pub rays_per_kernel: f64,
    /// Rays per footprint kernel k_S (the angular pool of the spatial estimate).
    pub rays_per_angular_kernel: f64,
    /// Rays per intensity kernel k_I.
    pub rays_per_intensity_kernel: f64,
    fine: NearestDirection,
    fine_dirs: Vec<DVec3>,
    /// Effective rays per fine cell.
    counts: Vec<f64>,
    /// Fine cells holding rays.
    lit: Vec<usize>,
    /// Angular radius of a fine cell (rad).
    cell_radius: f64,
    /// The lit cells grouped by direction, for the k-nearest-neighbour search.
    buckets: Buckets,
    /// Narrowest and widest angular half-width allowed (rad).
    h_min: f64,
    h_max: f64,
    /// The angular width at the coarse directions, and those directions (for the layout).
    coarse: NearestDirection,
    coarse_h: Vec<f64>,
    /// The footprint (spatial pool) half-width of the rays in each fine cell (rad): the
    /// k-nearest-neighbour angle holding k_S rays about the cell's direction.
    cell_h: Vec<f64>,
    /// The intensity half-width of the rays in each fine cell (rad), holding k_I rays.
    cell_hi: Vec<f64>,
    /// Widest intensity width allowed (rad).
    hi_max: f64,
    /// The flux-weighted median of the k-nearest-neighbour intensity widths (rad).
    hi_median: f64,
    /// A fixed intensity width (rad), where the user gave one.
    fixed_hi: Option<f64>,
    /// Effective rays, (Σ Φ)² / Σ Φ².
    n_eff: f64,
    /// Mean flux per effective ray (lm).
    flux_per_ray: f64,
    source_radius: f64,
}

/// Where the virtual cameras sit and what they see.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Unit directions from the sphere's centre to the cameras.
    pub directions: Vec<DVec3>,
    /// Capture sphere radius (m).
    pub radius_m: f64,
    /// Full field of view (degrees).
    pub fov_deg: f64,
    /// Image side (px).
    pub image_px: u32,
}

/// Each fine cell's rays (compressed rows).
#[derive(Debug, Clone)]
pub struct CellRays {
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl Bandwidths {
    /// Builds the direction histogram of the rays (`get`, `n` of them) and chooses k_s and k_a
    /// (module docs of `raykde`).
    ///
    /// # Errors
    /// [`NearfieldError::InvalidArgument`] when the ray set is too small to estimate anything.
    pub fn choose(
        get: RayGet<'_>,
        rays: RaySummary,
        opts: &KdeOptions,
        source: &SourceCloud,
        warnings: &mut Vec<String>,
        path: &Path,
    ) -> Result<Self> {
        let RaySummary {
            n,
            n_eff,
            flux_lm: flux,
        } = rays;
        if n_eff < 16.0 {
            return Err(NearfieldError::invalid(
                "rays",
                format!(
                    "{}: {n_eff:.1} effective rays: too few to estimate a luminance",
                    path.display()
                ),
            ));
        }
        let k_s = opts
            .rays_per_kernel
            .unwrap_or(DEFAULT_B * n_eff.sqrt())
            .min(n_eff / 4.0)
            .max(1.0);
        let k_a = (k_s * n_eff).sqrt().clamp(k_s, n_eff);
        let k_i = opts
            .rays_per_intensity_kernel
            .unwrap_or(DEFAULT_BI * n_eff.powf(2.0 / 3.0))
            .clamp(1.0, k_a);
        let n_fine = ((n_eff * FINE_PER_RAY) as usize).clamp(2000, 40_000);
        let fine_dirs = fibonacci(n_fine);
        let fine = NearestDirection::new(&fine_dirs);
        let flux_per_ray = flux / n_eff;
        let counts = (0..n)
            .into_par_iter()
            .fold(
                || vec![0.0f64; n_fine],
                |mut acc, i| {
                    if let Some((_, k, f)) = get(i) {
                        if let Some(j) = fine.nearest(k) {
                            acc[j] += f / flux_per_ray;
                        }
                    }
                    acc
                },
            )
            .reduce(
                || vec![0.0f64; n_fine],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        let lit: Vec<usize> = (0..n_fine).filter(|&j| counts[j] > 0.0).collect();
        let cell_radius = (4.0 * PI / n_fine as f64 / PI).sqrt() * 1.2;
        let coarse_dirs = fibonacci(COARSE_DIRECTIONS);
        let buckets = Buckets::new(&fine_dirs, &lit, &counts);
        let mut me = Self {
            rays_per_kernel: k_s,
            rays_per_angular_kernel: k_a,
            rays_per_intensity_kernel: k_i,
            fine,
            fine_dirs,
            counts,
            lit,
            cell_radius,
            buckets,
            h_min: 1.5 * cell_radius,
            h_max: PI / 2.0,
            coarse: NearestDirection::new(&coarse_dirs),
            coarse_h: Vec::new(),
            cell_h: Vec::new(),
            cell_hi: Vec::new(),
            hi_max: PI / 2.0,
            hi_median: PI / 2.0,
            fixed_hi: opts.angular_kernel_deg.map(f64::to_radians),
            n_eff,
            flux_per_ray,
            source_radius: source.radius,
        };
        // The flux-weighted median width of the lit directions (caps are multiples of it).
        let median = |k: f64| -> f64 {
            let raw: Vec<(f64, f64)> = coarse_dirs.par_iter().map(|d| me.knn_angle(*d, k)).collect();
            let mut lit_h: Vec<(f64, f64)> = raw.into_iter().filter(|(_, w)| *w > 0.0).collect();
            lit_h.sort_by(|a, b| a.0.total_cmp(&b.0));
            let total: f64 = lit_h.iter().map(|p| p.1).sum();
            let mut acc = 0.0;
            for (h, w) in &lit_h {
                acc += w;
                if acc >= total / 2.0 {
                    return *h;
                }
            }
            PI / 2.0
        };
        let (m_a, m_i) = (median(k_a), median(k_i));
        let cap = |m: f64, f: f64| (f * m).clamp(me.h_min, PI / 2.0);
        me.h_max = cap(m_a, POOL_CAP);
        me.hi_max = cap(m_i, POOL_CAP).min(me.h_max);
        me.hi_median = m_i.clamp(me.h_min, me.hi_max);
        let fixed = opts.angular_kernel_deg.map(f64::to_radians);
        let widths: Vec<(usize, f64, f64)> = me
            .lit
            .par_iter()
            .map(|&j| {
                let d = me.fine_dirs[j];
                let hs = me.knn_angle(d, k_a).0.clamp(me.h_min, me.h_max);
                let hi = fixed.unwrap_or_else(|| me.intensity_width(d));
                (j, hs.max(hi), hi)
            })
            .collect();
        me.cell_h = vec![0.0; n_fine];
        me.cell_hi = vec![0.0; n_fine];
        for (j, hs, hi) in widths {
            me.cell_h[j] = hs;
            me.cell_hi[j] = hi;
        }
        // The layout plans with the intensity widths, and spaces the cameras wider where nothing is
        // emitted (dark directions would otherwise take as many cameras as lit ones).
        me.coarse_h = coarse_dirs
            .par_iter()
            .map(|d| {
                fixed.unwrap_or_else(|| {
                    if me.knn_angle(*d, DARK_SHARE * k_i).0 > me.hi_median {
                        me.hi_max
                    } else {
                        me.intensity_width(*d)
                    }
                })
            })
            .collect();
        if n_eff < 1000.0 {
            warnings.push(format!(
                "{}: {n_eff:.0} effective rays: the estimate is very coarse (kernels of {k_s:.0} rays)",
                path.display()
            ));
        }
        Ok(me)
    }

    /// The intensity half-width at `d` (rad): the k-nearest-neighbour angle holding k_I rays, but
    /// past the flux-weighted median width only as far as holding [`MIN_INTENSITY_SHARE`] of k_I
    /// needs, within [h_min, hi_max].
    fn intensity_width(&self, d: DVec3) -> f64 {
        let k = self.rays_per_intensity_kernel;
        let h = self.knn_angle(d, k).0;
        let h = if h > self.hi_median {
            h.min(self.knn_angle(d, MIN_INTENSITY_SHARE * k).0.max(self.hi_median))
        } else {
            h
        };
        h.clamp(self.h_min, self.hi_max)
    }

    /// The k-nearest-neighbour angle about `d` holding `k` rays (rad), and the rays within the
    /// fine cell nearest `d` (a weight for medians over directions).
    fn knn_angle(&self, d: DVec3, k: f64) -> (f64, f64) {
        let Some(reach) = self.buckets.reach(d, k) else {
            return (PI, 0.0);
        };
        // Every cell within `reach` of d is in a bucket whose centre is within reach + its radius.
        let mut hist = [0.0f64; ANGLE_BINS];
        let top = reach.min(PI);
        let scan = (reach + self.buckets.radius).min(PI).cos();
        for (b, cells) in self.buckets.cells.iter().enumerate() {
            if cells.is_empty() || d.dot(self.buckets.dirs[b]) < scan {
                continue;
            }
            for &j in cells {
                let j = j as usize;
                let a = d.dot(self.fine_dirs[j]).clamp(-1.0, 1.0).acos();
                if a <= top {
                    let i = ((a / top) * ANGLE_BINS as f64) as usize;
                    hist[i.min(ANGLE_BINS - 1)] += self.counts[j];
                }
            }
        }
        let mut acc = 0.0;
        for (b, c) in hist.iter().enumerate() {
            if acc + c >= k {
                let t = if *c > 0.0 { (k - acc) / c } else { 1.0 };
                let h = (b as f64 + t) * top / ANGLE_BINS as f64;
                let own = self.fine.nearest(d).map_or(0.0, |j| self.counts[j]);
                return (h, own);
            }
            acc += c;
        }
        (PI, 0.0)
    }

    /// Up to `n` cameras (indices into `dirs`) nearest the fine cells holding the most rays, each
    /// once: where the spatial detail is judged for the image size.
    pub fn brightest_cameras(&self, dirs: &[DVec3], n: usize) -> Vec<usize> {
        let near = NearestDirection::new(dirs);
        let mut cells: Vec<usize> = self.lit.clone();
        cells.sort_by(|a, b| self.counts[*b].total_cmp(&self.counts[*a]));
        let mut out: Vec<usize> = Vec::new();
        for j in cells {
            if let Some(i) = near.nearest(self.fine_dirs[j]) {
                if !out.contains(&i) {
                    out.push(i);
                    if out.len() == n {
                        break;
                    }
                }
            }
        }
        out
    }

    /// (footprint half-width, intensity half-width, effective rays) of the lit cells (rad), for
    /// reports.
    pub fn widths(&self) -> Vec<(f64, f64, f64)> {
        self.lit
            .iter()
            .map(|&j| (self.cell_h[j], self.cell_hi[j], self.counts[j]))
            .collect()
    }

    /// The width the layout plans with at `d`: the nearest coarse direction's.
    fn planned(&self, d: DVec3, opts: &KdeOptions) -> f64 {
        match opts.angular_kernel_deg {
            Some(h) => h.to_radians(),
            None => self
                .coarse
                .nearest(d)
                .and_then(|i| self.coarse_h.get(i).copied())
                .unwrap_or(self.h_max),
        }
    }

    /// The camera layout, capture radius, field of view and image size.
    ///
    /// # Errors
    /// [`NearfieldError::InvalidArgument`] when the options ask for more than the limits hold.
    pub fn layout(&self, opts: &KdeOptions) -> Result<Layout> {
        let r_src = self.source_radius.max(5e-4);
        let radius_m = opts.radius_m.unwrap_or((8.0 * r_src).max(1.1));
        // Expected spatial σ: k_s of the k_a rays of a camera, spread over the source's disc.
        let sigma = r_src * (self.rays_per_kernel / self.rays_per_angular_kernel).sqrt();
        let half = r_src + 3.0 * sigma;
        let fov_deg = 2.0 * (1.05 * half / radius_m).atan().to_degrees();
        let image_px = opts
            .image_px
            .unwrap_or_else(|| ((2.0 * half / (sigma / 2.0)).ceil() as u32).clamp(32, 256));
        let directions = match opts.cameras {
            Some(m) => fibonacci(m),
            None => self.adaptive_directions(opts, image_px),
        };
        let total = u64::from(image_px) * u64::from(image_px) * directions.len() as u64;
        if directions.len() > MAX_CAMERAS || total > MAX_TOTAL_PIXELS {
            return Err(NearfieldError::invalid(
                "cameras",
                format!(
                    "{} cameras of {image_px}² px exceed the limits ({MAX_CAMERAS} cameras, {MAX_TOTAL_PIXELS} pixels)",
                    directions.len()
                ),
            ));
        }
        Ok(Layout {
            directions,
            radius_m,
            fov_deg,
            image_px,
        })
    }

    /// Cameras about 0.7 intensity widths apart: a greedy variable-radius Poisson-disc
    /// selection over the fine directions, narrowest widths first; spread wider when the limits
    /// would be exceeded.
    fn adaptive_directions(&self, opts: &KdeOptions, image_px: u32) -> Vec<DVec3> {
        let limit = MAX_AUTO_CAMERAS.min((MAX_TOTAL_PIXELS / (u64::from(image_px) * u64::from(image_px))) as usize);
        let mut order: Vec<(f64, DVec3)> = self.fine_dirs.iter().map(|d| (self.planned(*d, opts), *d)).collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut factor = 0.7;
        loop {
            let picked = poisson(&order, factor, limit);
            if let Some(p) = picked {
                if p.len() >= 12 {
                    return p;
                }
                return fibonacci(12.max(p.len()));
            }
            factor *= 1.3;
        }
    }

    /// Each fine cell's rays.
    pub fn cell_rays(&self, get: RayGet<'_>, n: usize) -> CellRays {
        let cell: Vec<u32> = (0..n)
            .into_par_iter()
            .map(|i| {
                get(i)
                    .and_then(|(_, k, _)| self.fine.nearest(k))
                    .map_or(u32::MAX, |j| j as u32)
            })
            .collect();
        let m = self.fine_dirs.len();
        let mut starts = vec![0u32; m + 1];
        for &c in &cell {
            if c != u32::MAX {
                starts[c as usize + 1] += 1;
            }
        }
        for j in 0..m {
            starts[j + 1] += starts[j];
        }
        let mut fill = starts.clone();
        let mut items = vec![0u32; starts[m] as usize];
        for (i, &c) in cell.iter().enumerate() {
            if c != u32::MAX {
                let slot = &mut fill[c as usize];
                items[*slot as usize] = i as u32;
                *slot += 1;
            }
        }
        CellRays { starts, items }
    }

    /// The rays whose kernels can reach direction `d`: those of the fine cells within their own
    /// footprint width (plus a cell's radius) of `d`, with their (footprint, intensity) widths
    /// (rad; the intensity width is the narrower).
    pub fn rays_reaching<'a>(&'a self, cells: &'a CellRays, d: DVec3) -> impl Iterator<Item = (u32, f64, f64)> + 'a {
        self.lit
            .iter()
            .filter(move |&&j| self.fine_dirs[j].dot(d) >= (self.cell_h[j] + self.cell_radius).min(PI).cos())
            .flat_map(move |&j| {
                let (s, e) = (cells.starts[j] as usize, cells.starts[j + 1] as usize);
                let (h, hi) = (self.cell_h[j], self.cell_hi[j]);
                cells.items[s..e].iter().map(move |&r| (r, h, hi))
            })
    }

    /// Gives every fine cell that other rays fall in (`cells`, from [`Self::cell_rays`] of those
    /// rays), and that holds none of this estimate's rays, the widths this estimate would have
    /// given a ray there (the k-nearest-neighbour angles of its own histogram, clamped as for its
    /// own rays), so that the same operator applies to those rays ([`super::estimate_frozen`]).
    /// The histogram itself is not changed.
    pub fn cover(&mut self, cells: &CellRays) {
        let m = self.fine_dirs.len();
        let new: Vec<usize> = (0..m)
            .filter(|&j| cells.starts[j + 1] > cells.starts[j] && self.cell_h[j] <= 0.0)
            .collect();
        let widths: Vec<(usize, f64, f64)> = new
            .par_iter()
            .map(|&j| {
                let d = self.fine_dirs[j];
                let hs = self
                    .knn_angle(d, self.rays_per_angular_kernel)
                    .0
                    .clamp(self.h_min, self.h_max);
                let hi = self.fixed_hi.unwrap_or_else(|| self.intensity_width(d));
                (j, hs.max(hi), hi)
            })
            .collect();
        for (j, hs, hi) in widths {
            self.cell_h[j] = hs;
            self.cell_hi[j] = hi;
            self.lit.push(j);
        }
    }

    /// Effective rays (Σ Φ)² / Σ Φ².
    pub fn effective_rays(&self) -> f64 {
        self.n_eff
    }

    /// Mean flux per effective ray (lm).
    pub fn flux_per_ray(&self) -> f64 {
        self.flux_per_ray
    }
}

/// The lit fine cells grouped by the nearest of a few hundred to a few thousand bucket directions:
/// a k-nearest-neighbour search first finds, from the buckets' counts, a radius that surely holds
/// k rays, then histograms only the cells of the buckets that radius reaches (it visited every lit
/// cell for every direction before: O(cells²)).
#[derive(Debug, Clone)]
struct Buckets {
    dirs: Vec<DVec3>,
    /// The farthest a member cell lies from its bucket's direction (rad).
    radius: f64,
    cells: Vec<Vec<u32>>,
    /// Effective rays per bucket.
    counts: Vec<f64>,
}

impl Buckets {
    fn new(fine_dirs: &[DVec3], lit: &[usize], counts: &[f64]) -> Self {
        let n = (fine_dirs.len() / CELLS_PER_BUCKET).clamp(12, 4000);
        let dirs = fibonacci(n);
        let near = NearestDirection::new(&dirs);
        let mut cells = vec![Vec::new(); n];
        let mut sums = vec![0.0; n];
        let mut radius = 0.0f64;
        for &j in lit {
            if let Some(b) = near.nearest(fine_dirs[j]) {
                cells[b].push(j as u32);
                sums[b] += counts[j];
                radius = radius.max(fine_dirs[j].dot(dirs[b]).clamp(-1.0, 1.0).acos());
            }
        }
        Self {
            dirs,
            radius: radius + 1e-9,
            cells,
            counts: sums,
        }
    }

    /// A radius about `d` (rad) that holds at least `k` rays, or `None` when all of them hold fewer.
    fn reach(&self, d: DVec3, k: f64) -> Option<f64> {
        const BINS: usize = 512;
        let mut hist = [0.0f64; BINS];
        let mut total = 0.0;
        for (b, c) in self.counts.iter().enumerate() {
            if *c > 0.0 {
                let a = d.dot(self.dirs[b]).clamp(-1.0, 1.0).acos();
                hist[((a / PI * BINS as f64) as usize).min(BINS - 1)] += c;
                total += c;
            }
        }
        if total < k {
            return None;
        }
        let mut acc = 0.0;
        for (i, c) in hist.iter().enumerate() {
            acc += c;
            if acc >= k {
                // Every cell of the buckets up to here lies within this angle of d.
                return Some((i + 1) as f64 * PI / BINS as f64 + self.radius);
            }
        }
        Some(PI)
    }
}

/// Greedy Poisson-disc selection: a direction is kept when no kept one lies within `factor` × its
/// width. `None` when more than `limit` would be kept.
fn poisson(order: &[(f64, DVec3)], factor: f64, limit: usize) -> Option<Vec<DVec3>> {
    // A uniform grid over [−1, 1]³ of chord-sized cells finds the kept neighbours.
    let min_h = order.first().map_or(0.1, |o| o.0) * factor;
    let cell = (2.0 * (min_h / 2.0).sin()).max(1e-3);
    let g = ((2.0 / cell).ceil() as usize).clamp(1, 256);
    let key = |d: DVec3| {
        let c = |x: f64| (((x + 1.0) / 2.0 * g as f64) as usize).min(g - 1);
        (c(d.x), c(d.y), c(d.z))
    };
    let mut grid: std::collections::HashMap<(usize, usize, usize), Vec<usize>> = std::collections::HashMap::new();
    let mut kept: Vec<DVec3> = Vec::new();
    for &(h, d) in order {
        let r = (factor * h).min(std::f64::consts::PI);
        let chord = 2.0 * (r / 2.0).sin();
        let span = ((chord / (2.0 / g as f64)).ceil() as isize).max(1);
        let (cx, cy, cz) = key(d);
        let mut free = true;
        'search: for dx in -span..=span {
            for dy in -span..=span {
                for dz in -span..=span {
                    let (x, y, z) = (cx as isize + dx, cy as isize + dy, cz as isize + dz);
                    if x < 0 || y < 0 || z < 0 || x >= g as isize || y >= g as isize || z >= g as isize {
                        continue;
                    }
                    if let Some(v) = grid.get(&(x as usize, y as usize, z as usize)) {
                        if v.iter().any(|&k| (kept[k] - d).length() < chord) {
                            free = false;
                            break 'search;
                        }
                    }
                }
            }
        }
        if free {
            grid.entry(key(d)).or_default().push(kept.len());
            kept.push(d);
            if kept.len() > limit {
                return None;
            }
        }
    }
    Some(kept)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_angular_kernel_integrates_to_one() {
        for h in [0.01f64, 0.2, 1.0, 2.5] {
            let c = angular_kernel(h);
            let n = 20_000;
            let mut s = 0.0;
            for i in 0..n {
                let t = (i as f64 + 0.5) / n as f64 * h;
                s += c * (1.0 - (t / h).powi(2)) * 2.0 * PI * t.sin() * h / n as f64;
            }
            assert!((s - 1.0).abs() < 1e-6, "h {h}: {s}");
        }
    }

    #[test]
    fn the_bucketed_neighbour_search_finds_the_brute_force_angle() {
        // A narrow beam (half the rays within 5° of +z) over a sparse hemisphere.
        let n = 20_000;
        let mut dirs = Vec::with_capacity(n);
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut u = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for i in 0..n {
            let (ct, phi) = if i % 2 == 0 {
                (1.0 - u() * (1.0 - 5f64.to_radians().cos()), 2.0 * PI * u())
            } else {
                (u(), 2.0 * PI * u())
            };
            let st = (1.0 - ct * ct).sqrt();
            dirs.push(DVec3::new(st * phi.cos(), st * phi.sin(), ct));
        }
        let get = |i: usize| Some((DVec3::ZERO, dirs[i], 1.0));
        let source = SourceCloud::of(|_| Some(DVec3::ZERO), 1);
        let bw = Bandwidths::choose(
            &get,
            RaySummary {
                n,
                n_eff: n as f64,
                flux_lm: n as f64,
            },
            &KdeOptions::default(),
            &source,
            &mut Vec::new(),
            Path::new("test"),
        )
        .unwrap();
        let brute = |d: DVec3, k: f64| -> f64 {
            let mut v: Vec<(f64, f64)> = bw
                .lit
                .iter()
                .map(|&j| (d.dot(bw.fine_dirs[j]).clamp(-1.0, 1.0).acos(), bw.counts[j]))
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut acc = 0.0;
            for (a, c) in v {
                acc += c;
                if acc >= k {
                    return a;
                }
            }
            PI
        };
        for (i, d) in fibonacci(300).into_iter().enumerate() {
            for k in [50.0, 700.0, 12_000.0] {
                let (got, _) = bw.knn_angle(d, k);
                let want = brute(d, k);
                // The histogram resolves the angle to within one bin of its search radius.
                assert!(
                    (got - want).abs() <= 0.01 * want.max(0.05) + bw.cell_radius * 0.05,
                    "direction {i}, k {k}: {got} against {want}"
                );
            }
        }
    }

    #[test]
    fn poisson_keeps_the_spacing() {
        let d = fibonacci(4000);
        let order: Vec<(f64, DVec3)> = d.iter().map(|v| (0.2, *v)).collect();
        let kept = poisson(&order, 0.5, 10_000).unwrap();
        for (i, a) in kept.iter().enumerate() {
            for b in &kept[i + 1..] {
                assert!(a.dot(*b).clamp(-1.0, 1.0).acos() >= 0.1 - 1e-9);
            }
        }
        // About 4π / (spacing² · √3/2) directions.
        let expect = 4.0 * PI / (0.1f64 * 0.1 * 0.866);
        assert!(
            (kept.len() as f64) > 0.4 * expect && (kept.len() as f64) < 1.2 * expect,
            "{}",
            kept.len()
        );
    }
}
