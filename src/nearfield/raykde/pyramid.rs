//! The spatial half of the ray-file estimate: one camera's rays splatted into an image, then, per
//! pixel, the finest level of an image pyramid whose neighbourhood holds `k_s` rays (a
//! k-nearest-neighbour balloon estimator with a smooth, quantised-then-blended width).
//!
//! Level 0 is the bilinear splat (each ray shared among its four nearest pixel centres) on a grid of
//! the next power of two ≥ the image side. Level k is level k−1 blurred by [1 2 1]/4 in x and y and
//! summed over 2 × 2 blocks, so every level holds the same total (light spread past the image's own
//! side is cut off there, as at any image border). The pilot reads a level's counts at a base pixel
//! by bilinear interpolation, divided by the 4^k base pixels a level-k pixel covers; the spread
//! takes a level back to the base pixels by k steps of B-spline subdivision (`Level::up`), which
//! keeps the total and the spot round. The resulting kernel is close to a Gaussian of σ ≈
//! [`LEVEL_SIGMA_PX`] · 2^k base pixels (measured in the tests); a kernel that size holds about
//! `4π σ²` pixels' worth of rays, which is how a level's ray count is judged. Between two levels
//! the estimate is blended by where k_s falls between their counts (in logarithms), so the width
//! varies continuously.

use glam::DVec2;

/// σ in base pixels of the level-k kernel divided by 2^k (level 0's bilinear tent is narrower).
pub const LEVEL_SIGMA_PX: f64 = 0.7;

/// The level that spreads a source smaller than a pixel: level 0 is the bilinear splat's tent,
/// one pixel wide, which the renderer's bilinear magnification shows as a diamond; level 1 (σ ≈ 1.4
/// px, four pixels across) is round in the image but still a rounded square once magnified; level
/// 2 (σ ≈ 2.8 px) is the first that renders as a round spot. (Extended sources keep the level their
/// rays choose, 0 included: a small bright feature's core is sharper at level 0.)
pub const POINT_LEVEL: f64 = 2.0;

/// Pixels' worth of rays a kernel of σ = `LEVEL_SIGMA_PX` · 2^k holds, over 4^k: 4π σ² / 4^k.
const AREA_FACTOR: f64 = 4.0 * std::f64::consts::PI * LEVEL_SIGMA_PX * LEVEL_SIGMA_PX;

/// A camera's accumulation grids, on a side of the next power of two (so every level covers the
/// grid exactly and keeps its total), read back on the image's `px` × `px`.
#[derive(Debug, Clone)]
pub struct Pyramid {
    px: usize,
    /// Side of the grids: the next power of two ≥ px.
    side: usize,
    /// Σ flux · angular kernel per base pixel.
    w: Vec<f64>,
    /// Σ angular weight (rays, counted by their angular kernel weight) per base pixel.
    c: Vec<f64>,
}

/// The per-pixel estimate of one camera.
#[derive(Debug, Clone)]
pub struct Estimate {
    /// Σ flux · angular kernel per base pixel (divide by the pixel area for luminance).
    pub density: Vec<f64>,
    /// The level used per pixel (0 = finest); σ = `LEVEL_SIGMA_PX` · 2^level base pixels.
    pub level: Vec<f32>,
    /// Lit pixels whose kernel reached the top level without k_s rays.
    pub undersampled: u64,
    /// Σ of the splatted weights (the camera's rays, by angular weight).
    pub total: f64,
    /// (kernel σ in base pixels, weight) of the light splatted, binned by eighths of a level: the
    /// widths the light actually spreads with.
    pub mass_sigma: Vec<(f64, f64)>,
}

/// One level: a square grid of side `n` with its values.
/// Either grid may be empty: the pilot's levels carry only the counts, the spread's only the
/// values.
struct Level {
    n: usize,
    w: Vec<f64>,
    c: Vec<f64>,
}

impl Level {
    /// Blurs by [1 2 1]/4 in x and y (clamped at the border: the total is kept) and sums 2 × 2 (an
    /// empty grid stays empty).
    fn down(&self) -> Level {
        let n = self.n;
        let taps = |i: usize| [(i.saturating_sub(1), 0.25), (i, 0.5), ((i + 1).min(n - 1), 0.25)];
        let blur = |v: &[f64]| scatter_separable(v, n, n, taps);
        let m = n.div_ceil(2);
        let sum = |v: &[f64]| -> Vec<f64> {
            if v.is_empty() {
                return Vec::new();
            }
            let b = blur(v);
            let mut out = vec![0.0; m * m];
            for y in 0..n {
                for x in 0..n {
                    out[(y / 2) * m + x / 2] += b[y * n + x];
                }
            }
            out
        };
        Level {
            n: m,
            w: sum(&self.w),
            c: sum(&self.c),
        }
    }

    /// The inverse step of [`Level::down`] for the spread: each value shared among the 4 × 4 cells
    /// of a grid twice as fine around it with weights [1 3 3 1]/8 in x and y (the quadratic
    /// B-spline's subdivision: smooth and separable, so that k steps after k `down`s give a round,
    /// nearly Gaussian kernel where a bilinear read of the coarse grid gave a square; border
    /// shares folded back in, so the total is kept).
    fn up(&self) -> Level {
        let n = self.n;
        let m = 2 * n;
        const W: [f64; 4] = [0.125, 0.375, 0.375, 0.125];
        // Clamped at the border, so the shares folded back keep the total.
        let taps = |i: usize| {
            let fine = |d: usize| (2 * i + d).saturating_sub(1).min(m - 1);
            [(fine(0), W[0]), (fine(1), W[1]), (fine(2), W[2]), (fine(3), W[3])]
        };
        let expand = |v: &[f64]| scatter_separable(v, n, m, taps);
        Level {
            n: m,
            w: expand(&self.w),
            c: Vec::new(),
        }
    }

    /// The count at base pixel centre (bx, by) of a level 2^k coarser, read bilinearly.
    fn count(&self, k: u32, bx: usize, by: usize) -> f64 {
        let s = f64::from(1u32 << k);
        let fx = ((bx as f64 + 0.5) / s - 0.5).clamp(0.0, (self.n - 1) as f64);
        let fy = ((by as f64 + 0.5) / s - 0.5).clamp(0.0, (self.n - 1) as f64);
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.n - 1), (y0 + 1).min(self.n - 1));
        let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
        let at = |x: usize, y: usize| self.c[y * self.n + x];
        let a = at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx;
        let b = at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx;
        a * (1.0 - ty) + b * ty
    }
}

impl Pyramid {
    /// Empty grids of `px` × `px` base pixels.
    pub fn new(px: u32) -> Self {
        let px = px.max(1) as usize;
        let side = px.next_power_of_two();
        Self {
            px,
            side,
            w: vec![0.0; side * side],
            c: vec![0.0; side * side],
        }
    }

    /// The image side (px).
    pub fn side_px(&self) -> u32 {
        self.px as u32
    }

    /// Adds a ray at image position `uv` (pixels, origin at the top-left corner, pixel centres at
    /// half integers) with weight `w` and count weight `c`, shared bilinearly among the four nearest
    /// pixel centres. Positions outside the image are dropped; returns whether it landed.
    pub fn splat(&mut self, uv: DVec2, w: f64, c: f64) -> bool {
        let (fx, fy) = (uv.x - 0.5, uv.y - 0.5);
        let n = self.px as f64;
        if !(fx > -1.0 && fy > -1.0 && fx < n && fy < n) {
            return false;
        }
        let stride = self.side;
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        for (dx, dy, k) in [
            (0.0, 0.0, (1.0 - tx) * (1.0 - ty)),
            (1.0, 0.0, tx * (1.0 - ty)),
            (0.0, 1.0, (1.0 - tx) * ty),
            (1.0, 1.0, tx * ty),
        ] {
            let (x, y) = (x0 + dx, y0 + dy);
            if x >= 0.0 && y >= 0.0 && x < n && y < n {
                let i = y as usize * stride + x as usize;
                self.w[i] += w * k;
                self.c[i] += c * k;
            }
        }
        true
    }

    /// The per-pixel estimate. A pilot pass finds, at each pixel, the finest level whose
    /// neighbourhood holds `k_s` rays (blended between levels; or `fixed_level` everywhere); then
    /// the light splatted at each pixel is spread with its own pixel's kernel (a sample-point
    /// estimator: a bright spot keeps its narrow kernel while the sparse pixels around it spread
    /// only their own light, and the total is kept exactly).
    pub fn estimate(self, k_s: f64, fixed_level: Option<f64>) -> Estimate {
        let (px, side) = (self.px, self.side);
        let total: f64 = self.c.iter().sum();
        let base_w = self.w;
        // The pilot's levels: counts only (the light is spread by `finish`).
        let mut levels = vec![Level {
            n: side,
            w: Vec::new(),
            c: self.c,
        }];
        while levels[levels.len() - 1].n > 1 {
            let next = levels[levels.len() - 1].down();
            levels.push(next);
        }
        let top = levels.len() - 1;
        let mut level = vec![0.0f32; side * side];
        let mut undersampled = 0u64;
        if total <= 0.0 {
            return Estimate {
                density: vec![0.0; px * px],
                level: vec![0.0; px * px],
                undersampled,
                total,
                mass_sigma: Vec::new(),
            };
        }
        for by in 0..px {
            for bx in 0..px {
                let i = by * side + bx;
                let count = |k: usize| levels[k].count(k as u32, bx, by) * AREA_FACTOR;
                let l = match fixed_level {
                    Some(f) => f.clamp(0.0, top as f64),
                    None => {
                        let mut prev = count(0);
                        if prev >= k_s {
                            0.0
                        } else {
                            let mut found = None;
                            for k in 1..=top {
                                let cur = count(k);
                                if cur >= k_s {
                                    let t = if prev > 0.0 && cur > prev {
                                        ((k_s / prev).ln() / (cur / prev).ln()).clamp(0.0, 1.0)
                                    } else {
                                        1.0
                                    };
                                    found = Some((k - 1) as f64 + t);
                                    break;
                                }
                                prev = cur;
                            }
                            found.unwrap_or_else(|| {
                                if base_w[i] > 0.0 {
                                    undersampled += 1;
                                }
                                top as f64
                            })
                        }
                    }
                };
                level[i] = l as f32;
            }
        }
        finish(px, side, base_w, level, undersampled, total)
    }

    /// The per-pixel estimate with the kernel levels given (`level`: `px` × `px`, row-major), as
    /// another estimate chose them: the same operator applied to other rays (a kernel-matched
    /// reference). A `level` of the wrong length is read as far as it goes, the rest at level 0.
    pub fn estimate_at(self, level: &[f32]) -> Estimate {
        let (px, side) = (self.px, self.side);
        let total: f64 = self.c.iter().sum();
        let mut side_level = vec![0.0f32; side * side];
        for y in 0..px {
            for x in 0..px {
                side_level[y * side + x] = level.get(y * px + x).copied().unwrap_or(0.0);
            }
        }
        finish(px, side, self.w, side_level, 0, total)
    }
}

/// Spreads the splatted light `base_w` (`side` × `side`) with the per-pixel levels and crops to
/// `px` × `px`.
fn finish(px: usize, side: usize, base_w: Vec<f64>, level: Vec<f32>, undersampled: u64, total: f64) -> Estimate {
    let spread = spread_by_level(side, &base_w, &level);
    let mut mass_sigma = vec![0.0f64; MASS_BINS];
    for (w, l) in base_w.iter().zip(&level) {
        if *w > 0.0 {
            mass_sigma[mass_bin(f64::from(*l))] += w;
        }
    }
    let crop = |v: &[f64]| -> Vec<f64> {
        (0..px)
            .flat_map(|y| v[y * side..y * side + px].iter().copied())
            .collect()
    };
    let density = crop(&spread);
    let level = (0..px)
        .flat_map(|y| level[y * side..y * side + px].iter().copied())
        .collect();
    Estimate {
        density,
        level,
        undersampled,
        total,
        mass_sigma: mass_sigma
            .iter()
            .enumerate()
            .filter(|(_, w)| **w > 0.0)
            .map(|(b, w)| (LEVEL_SIGMA_PX * 2f64.powf(bin_level(b)), *w))
            .collect(),
    }
}

/// Bins of the light's kernel levels for reports: eighths of a level from 0 to 16.
const MASS_BINS: usize = 129;

fn mass_bin(level: f64) -> usize {
    ((level * 8.0).round().max(0.0) as usize).min(MASS_BINS - 1)
}

fn bin_level(b: usize) -> f64 {
    b as f64 / 8.0
}

/// Scatters the `n` × `n` grid `v` into an `m` × `m` one, separably: each value's share `w` goes to
/// every `(j, w)` of `taps(i)` along x, then the same along y (zeros skipped). [`Level::down`]'s
/// blur and [`Level::up`]'s subdivision.
fn scatter_separable<const K: usize>(
    v: &[f64],
    n: usize,
    m: usize,
    taps: impl Fn(usize) -> [(usize, f64); K],
) -> Vec<f64> {
    let mut t = vec![0.0; n * m];
    for y in 0..n {
        for x in 0..n {
            let a = v[y * n + x];
            if a == 0.0 {
                continue;
            }
            for (j, w) in taps(x) {
                t[y * m + j] += w * a;
            }
        }
    }
    let mut u = vec![0.0; m * m];
    for y in 0..n {
        let to = taps(y);
        for x in 0..m {
            let a = t[y * m + x];
            if a == 0.0 {
                continue;
            }
            for (j, w) in to {
                u[j * m + x] += w * a;
            }
        }
    }
    u
}

/// Spreads the values `w` of a `px` × `px` grid (`px` a power of two), each with the kernel of its
/// own pixel's level (`level`, fractional levels split linearly between the two neighbours), and
/// sums the results: the estimator's spatial operator, applied to any grid (the splatted rays, or
/// a reference). The total is kept.
pub fn spread_by_level(px: usize, w: &[f64], level: &[f32]) -> Vec<f64> {
    let top = levels_for(px);
    let mut parts: Vec<Vec<f64>> = vec![Vec::new(); top + 1];
    for (i, (&v, &l)) in w.iter().zip(level).enumerate() {
        if v == 0.0 {
            continue;
        }
        let l = f64::from(l).clamp(0.0, top as f64);
        let k0 = l.floor() as usize;
        let t = l - k0 as f64;
        for (k, share) in [(k0, 1.0 - t), ((k0 + 1).min(top), t)] {
            if share > 0.0 {
                if parts[k].is_empty() {
                    parts[k] = vec![0.0; px * px];
                }
                parts[k][i] += v * share;
            }
        }
    }
    let mut out = vec![0.0; px * px];
    for (k, part) in parts.into_iter().enumerate() {
        if part.is_empty() {
            continue;
        }
        let mut lv = Level {
            n: px,
            w: part,
            c: Vec::new(),
        };
        for _ in 0..k {
            lv = lv.down();
        }
        for _ in 0..k {
            lv = lv.up();
        }
        for (o, v) in out.iter_mut().zip(&lv.w) {
            *o += v;
        }
    }
    out
}

/// The number of halvings from `px` down to one pixel.
fn levels_for(px: usize) -> usize {
    let mut n = px.max(1);
    let mut k = 0;
    while n > 1 {
        n = n.div_ceil(2);
        k += 1;
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Second moment (σ², px²) of the level-k response to one ray at `uv`, per axis.
    fn response_sigma(k: f64, uv: DVec2, px: u32) -> (f64, f64) {
        let mut p = Pyramid::new(px);
        p.splat(uv, 1.0, 1.0);
        let e = p.estimate(1.0, Some(k));
        let n = px as usize;
        let total: f64 = e.density.iter().sum();
        let (mut mx, mut my) = (0.0, 0.0);
        for y in 0..n {
            for x in 0..n {
                let v = e.density[y * n + x] / total;
                mx += v * (x as f64 + 0.5);
                my += v * (y as f64 + 0.5);
            }
        }
        let mut var = 0.0;
        for y in 0..n {
            for x in 0..n {
                let v = e.density[y * n + x] / total;
                var += v * ((x as f64 + 0.5 - mx).powi(2) + (y as f64 + 0.5 - my).powi(2)) / 2.0;
            }
        }
        (var.sqrt(), total)
    }

    #[test]
    fn every_level_keeps_the_total_and_its_kernel_doubles() {
        for k in 1..=4 {
            let mut sum = 0.0;
            let mut count = 0.0;
            for (x, y) in [(64.3, 64.7), (63.9, 65.2), (64.5, 64.5), (65.1, 63.6)] {
                let (s, total) = response_sigma(f64::from(k), DVec2::new(x, y), 128);
                assert!((total - 1.0).abs() < 1e-9, "level {k}: total {total}");
                sum += s;
                count += 1.0;
            }
            let s = sum / count / f64::from(1u32 << k);
            assert!((s - LEVEL_SIGMA_PX).abs() < 0.15, "level {k}: σ / 2^k = {s}");
        }
    }

    /// The radius (px) where an n × n density about its centroid falls to `level` of its value
    /// there, averaged over the four axis directions and over the four diagonal ones (bilinear
    /// samples every 0.05 px).
    fn contour_radii(e: &Estimate, n: usize, level: f64) -> (f64, f64) {
        let total: f64 = e.density.iter().sum();
        let (mut mx, mut my) = (0.0, 0.0);
        for (i, v) in e.density.iter().enumerate() {
            mx += v * ((i % n) as f64 + 0.5) / total;
            my += v * ((i / n) as f64 + 0.5) / total;
        }
        let sample = |x: f64, y: f64| -> f64 {
            let (fx, fy) = (x - 0.5, y - 0.5);
            let (x0, y0) = (fx.floor().max(0.0) as usize, fy.floor().max(0.0) as usize);
            let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
            let at = |x: usize, y: usize| e.density[y.min(n - 1) * n + x.min(n - 1)];
            (at(x0, y0) * (1.0 - tx) + at(x0 + 1, y0) * tx) * (1.0 - ty)
                + (at(x0, y0 + 1) * (1.0 - tx) + at(x0 + 1, y0 + 1) * tx) * ty
        };
        let half = level * sample(mx, my);
        let radius = |deg: f64| -> f64 {
            let (dx, dy) = (deg.to_radians().cos(), deg.to_radians().sin());
            let mut r = 0.0;
            while r < n as f64 / 2.0 && sample(mx + r * dx, my + r * dy) >= half {
                r += 0.05;
            }
            r
        };
        let mean = |a: [f64; 4]| a.iter().map(|&d| radius(d)).sum::<f64>() / 4.0;
        (mean([0.0, 90.0, 180.0, 270.0]), mean([45.0, 135.0, 225.0, 315.0]))
    }

    #[test]
    fn one_ray_spreads_into_a_round_spot() {
        // A point source renders as a spot of its kernel: round, not the diamond of a bilinear
        // read of the coarse level (which measured a diagonal / axis radius of 0.88 at half the
        // maximum, level 3). Level 2 is the kernel of a source smaller than a pixel (POINT_LEVEL).
        assert_eq!(POINT_LEVEL, 2.0);
        for k in 1..=5u32 {
            for c in [60usize, 64, 67] {
                let mut p = Pyramid::new(128);
                p.splat(DVec2::new(c as f64 + 0.5, c as f64 + 0.5), 1.0, 1.0);
                let e = p.estimate(1.0, Some(f64::from(k)));
                for level in [0.5, 0.1] {
                    let (axes, diagonals) = contour_radii(&e, 128, level);
                    let ratio = diagonals / axes;
                    eprintln!(
                        "level {k}, pixel {c}, contour {level}: {axes:.2} px along the axes, {diagonals:.2} along \
                         the diagonals: {ratio:.3}"
                    );
                    assert!(
                        (0.9..=1.1).contains(&ratio),
                        "level {k}, pixel {c}, contour {level}: {ratio}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_side_that_is_not_a_power_of_two_keeps_the_light_and_its_place() {
        // One ray at the centre of a 140 px image spread at every level: nothing lost (the image
        // is wide enough) until the kernel reaches the border, and the centroid stays put.
        for k in 0..=5 {
            let mut p = Pyramid::new(140);
            p.splat(DVec2::new(70.0, 70.0), 1.0, 1.0);
            let e = p.estimate(1.0, Some(f64::from(k)));
            let total: f64 = e.density.iter().sum();
            assert!((total - 1.0).abs() < 0.02, "level {k}: {total}");
            let cx: f64 = (0..140 * 140)
                .map(|i| e.density[i] * ((i % 140) as f64 + 0.5))
                .sum::<f64>()
                / total;
            assert!((cx - 70.0).abs() < 1.0, "level {k}: centroid x {cx}");
        }
    }

    #[test]
    fn dense_regions_keep_fine_kernels_and_sparse_ones_widen() {
        // 4000 rays on one pixel, 40 spread thinly elsewhere: the spot stays at level ≤ 1.
        let mut p = Pyramid::new(64);
        for _ in 0..4000 {
            p.splat(DVec2::new(20.5, 20.5), 1.0, 1.0);
        }
        for i in 0..40 {
            p.splat(
                DVec2::new(40.0 + (i % 8) as f64 * 2.0, 40.0 + (i / 8) as f64 * 3.0),
                1.0,
                1.0,
            );
        }
        let e = p.estimate(100.0, None);
        assert!(e.level[20 * 64 + 20] <= 1.0, "{}", e.level[20 * 64 + 20]);
        assert!(e.level[45 * 64 + 45] >= 2.0, "{}", e.level[45 * 64 + 45]);
        let total: f64 = e.density.iter().sum();
        assert!((total - 4040.0).abs() < 0.05 * 4040.0, "{total}");
    }
}
