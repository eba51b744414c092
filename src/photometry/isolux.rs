//! Illuminance on a horizontal floor plane below a luminaire, sampled on a square grid, and its
//! isolux lines (lines of equal illuminance).
//!
//! Promises:
//! - The floor is the plane z = −H of the luminaire frame (docs/conventions.md): H metres below the
//!   photometric centre, the luminaire aimed as measured (nadir straight down). Floor coordinates
//!   are x along C0 (+X), y along C90 (+Y), origin directly below the photometric centre, seen from
//!   above with C counter-clockwise.
//! - At a floor point (x, y) the illuminance is the point-source (far-field) formula
//!   `E = I(C, γ) · cos³γ / H²` in lux, with `C = atan2(y, x)` and `tan γ = r / H`,
//!   r = √(x² + y²) — the same as `I · cos(incidence) / d²` with d the distance to the point.
//!   I is [`Photometry::intensity`] (absolute cd, interpolated on the web); no inter-reflection,
//!   no maintenance factor, no near-field correction (valid where d is several times the luminous
//!   opening).
//! - The grid is symmetric about the origin and contains it: points `k · step` for
//!   k = −K…K on both axes, K = ⌈extent / step⌉, so it covers at least ±extent.
//! - Isolux levels follow the 1-2-5 series from just below the maximum down to 1 % of it.
//!
//! ```
//! use lumiview::photometry::isolux::{illuminance_lx, IsoluxGrid, IsoluxOptions};
//! use lumiview::photometry::{load_from_text, LoadOptions};
//!
//! // An isotropic 1000 cd downlight (rotational symmetry, γ 0–90°).
//! let ies = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1000 1000\n";
//! let p = load_from_text(ies, "iso.ies", &LoadOptions::default())?;
//! let e = illuminance_lx(&p, 2.0, 0.0, 0.0);
//! assert!((e - 1000.0 / 4.0).abs() < 1e-9); // lx directly below, E = I / H²
//! let grid = IsoluxGrid::new(&p, &IsoluxOptions { height_m: 2.0, extent_m: Some(4.0), step_m: Some(0.5) })?;
//! assert_eq!(grid.points_per_side(), 17);
//! assert_eq!(grid.levels(), vec![5.0, 10.0, 20.0, 50.0, 100.0, 200.0]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt::Write as _;

use rayon::prelude::*;

use super::contour::{contour_lines, Polyline};
use super::luminaire::Photometry;
use super::web::angles_of;
use crate::draw::ticks::trim_number;

/// The fraction of the maximum illuminance down to which isolux levels are drawn and the automatic
/// extent reaches.
pub const LOWEST_LEVEL_FRACTION: f64 = 0.01;

/// The automatic extent never exceeds this multiple of the mounting height (γ ≈ 84°).
pub const MAX_AUTO_EXTENT_PER_HEIGHT: f64 = 10.0;

/// The automatic extent is at least this multiple of the mounting height.
pub const MIN_AUTO_EXTENT_PER_HEIGHT: f64 = 0.5;

/// Grid intervals across the half-width when no step is given (201 × 201 points).
pub const DEFAULT_INTERVALS_PER_HALF_WIDTH: usize = 100;

/// Most grid points along one side (about 4 million points in all).
pub const MAX_POINTS_PER_SIDE: usize = 2001;

/// Where and how finely to sample the floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IsoluxOptions {
    /// Distance from the photometric centre down to the floor plane, metres; finite and > 0.
    pub height_m: f64,
    /// Half-width of the square grid, metres; `None` for [`auto_extent_m`].
    pub extent_m: Option<f64>,
    /// Grid spacing, metres; `None` for extent / [`DEFAULT_INTERVALS_PER_HALF_WIDTH`].
    pub step_m: Option<f64>,
}

/// An option of [`IsoluxGrid::new`] out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IsoluxError {
    /// The mounting height is not a finite number greater than 0.
    #[error("mounting height {height_m} m: must be a finite number greater than 0")]
    Height {
        /// The height given, metres.
        height_m: f64,
    },
    /// The extent is not a finite number greater than 0.
    #[error("grid extent {extent_m} m: must be a finite number greater than 0")]
    Extent {
        /// The extent given, metres.
        extent_m: f64,
    },
    /// The step is not a finite number greater than 0.
    #[error("grid step {step_m} m: must be a finite number greater than 0")]
    Step {
        /// The step given, metres.
        step_m: f64,
    },
    /// The step is larger than the half-width of the grid.
    #[error("grid step {step_m} m is larger than the grid's half-width {extent_m} m")]
    StepExceedsExtent {
        /// The step, metres.
        step_m: f64,
        /// The half-width, metres.
        extent_m: f64,
    },
    /// The step is so small that the grid would have too many points.
    #[error(
        "grid step {step_m} m over ±{extent_m} m gives {points_per_side} points per side; at most \
         {MAX_POINTS_PER_SIDE}"
    )]
    TooManyPoints {
        /// The step, metres.
        step_m: f64,
        /// The half-width, metres.
        extent_m: f64,
        /// Points per side the grid would have.
        points_per_side: usize,
    },
}

/// The illuminance in lux at the floor point (x, y) (metres, floor frame of the module docs) for
/// a floor `height_m` below the photometric centre: `I(C, γ) · cos³γ / H²`.
///
/// Returns 0 for a non-finite or negative intensity or a height that is not finite and > 0.
pub fn illuminance_lx(p: &Photometry, height_m: f64, x_m: f64, y_m: f64) -> f64 {
    if !(height_m.is_finite() && height_m > 0.0) {
        return 0.0;
    }
    let (c_deg, gamma_deg) = angles_of([x_m, y_m, -height_m]);
    let cd = p.intensity(c_deg, gamma_deg);
    if !(cd.is_finite() && cd > 0.0) {
        return 0.0;
    }
    // cos γ = H / d, so I · cos³γ / H² = I · H / d³.
    let d_m = (x_m * x_m + y_m * y_m + height_m * height_m).sqrt();
    cd * height_m / (d_m * d_m * d_m)
}

/// The half-width of the floor square worth plotting, metres: where the illuminance falls below
/// [`LOWEST_LEVEL_FRACTION`] of its maximum, plus 10 %, rounded up to a round number
/// (1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8 × 10ⁿ), within [`MIN_AUTO_EXTENT_PER_HEIGHT`]…
/// [`MAX_AUTO_EXTENT_PER_HEIGHT`] × H before rounding.
///
/// Samples γ every 0.25° up to the cap and C every 2.5°. A luminaire that sends no light onto the
/// floor gets 3 × H. `height_m` must be finite and > 0 (else the result is 0).
pub fn auto_extent_m(p: &Photometry, height_m: f64) -> f64 {
    if !(height_m.is_finite() && height_m > 0.0) {
        return 0.0;
    }
    let gamma_cap_deg = MAX_AUTO_EXTENT_PER_HEIGHT.atan().to_degrees();
    let gammas: Vec<f64> = (0..)
        .map(|i| f64::from(i) * 0.25)
        .take_while(|g| *g <= gamma_cap_deg)
        .collect();
    // (E in lx, r in m) along every sampled direction.
    let samples: Vec<(f64, f64)> = (0..144)
        .flat_map(|k| {
            let c_deg = f64::from(k) * 2.5;
            gammas.iter().map(move |&g| {
                let cd = p.intensity(c_deg, g);
                let cos = g.to_radians().cos();
                let e = if cd.is_finite() { cd.max(0.0) * cos.powi(3) } else { 0.0 } / (height_m * height_m);
                (e, height_m * g.to_radians().tan())
            })
        })
        .collect();
    let max = samples.iter().map(|s| s.0).fold(0.0, f64::max);
    if max <= 0.0 {
        return 3.0 * height_m;
    }
    let reach_m = samples
        .iter()
        .filter(|s| s.0 >= LOWEST_LEVEL_FRACTION * max)
        .map(|s| s.1)
        .fold(0.0, f64::max);
    let wanted = (1.1 * reach_m).clamp(
        MIN_AUTO_EXTENT_PER_HEIGHT * height_m,
        MAX_AUTO_EXTENT_PER_HEIGHT * height_m,
    );
    round_up(wanted)
}

/// The smallest value of the series 1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8 × 10ⁿ not below `v` (> 0).
fn round_up(v: f64) -> f64 {
    let exponent = v.log10().floor() as i32;
    for m in [1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0] {
        let candidate = decimal(m, exponent);
        if candidate >= v * (1.0 - 1e-12) {
            return candidate;
        }
    }
    decimal(1.0, exponent + 1)
}

/// `mantissa × 10^exponent`, dividing for negative exponents so that 1.5 × 10⁻¹ is the double
/// nearest 0.15 (as the literal is), not 0.15000000000000002.
pub(crate) fn decimal(mantissa: f64, exponent: i32) -> f64 {
    if exponent >= 0 {
        mantissa * 10f64.powi(exponent)
    } else {
        mantissa / 10f64.powi(-exponent)
    }
}

/// The isolux levels for a maximum illuminance, ascending: the 1-2-5 series values below the
/// maximum and at least [`LOWEST_LEVEL_FRACTION`] of it (six: the range spans two decades). Empty
/// for a maximum that is not finite and > 0.
pub fn isolux_levels(max_lx: f64) -> Vec<f64> {
    if !(max_lx.is_finite() && max_lx > 0.0) {
        return Vec::new();
    }
    let lowest = LOWEST_LEVEL_FRACTION * max_lx * (1.0 - 1e-9);
    let top = max_lx * (1.0 - 1e-9);
    let mut exponent = lowest.log10().floor() as i32;
    let mut levels = Vec::new();
    while 10f64.powi(exponent) <= top {
        for m in [1.0, 2.0, 5.0] {
            let v = decimal(m, exponent);
            if v >= lowest && v < top {
                levels.push(v);
            }
        }
        exponent += 1;
    }
    levels
}

/// The largest illuminance on the grid and where it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaxPoint {
    /// Illuminance, lx.
    pub e_lx: f64,
    /// Floor x (along C0), metres.
    pub x_m: f64,
    /// Floor y (along C90), metres.
    pub y_m: f64,
}

/// The isolux lines of one level, in floor metres.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoluxContour {
    /// The illuminance of the lines, lx.
    pub level_lx: f64,
    /// The lines: points in floor metres (x along C0, y along C90).
    pub lines: Vec<Polyline>,
}

/// Illuminance sampled on the floor grid.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoluxGrid {
    /// Distance from the photometric centre down to the floor, metres.
    pub height_m: f64,
    /// The half-width asked for (or chosen automatically), metres.
    pub extent_m: f64,
    /// Grid spacing, metres.
    pub step_m: f64,
    /// K: the grid runs over k · step for k = −K…K on each axis.
    pub half_points: usize,
    /// Illuminance in lx, row-major from the lowest y: `e_lx[iy * n + ix]` at
    /// (`coordinate_m(ix)`, `coordinate_m(iy)`), n = [`IsoluxGrid::points_per_side`].
    pub e_lx: Vec<f64>,
}

impl IsoluxGrid {
    /// Samples the illuminance of `p` on the floor grid described by `opts`.
    ///
    /// # Errors
    /// [`IsoluxError`] naming the option that is out of range: height, extent or step not finite
    /// and > 0, a step larger than the half-width, or more than [`MAX_POINTS_PER_SIDE`] points per
    /// side.
    pub fn new(p: &Photometry, opts: &IsoluxOptions) -> Result<Self, IsoluxError> {
        let height_m = opts.height_m;
        if !(height_m.is_finite() && height_m > 0.0) {
            return Err(IsoluxError::Height { height_m });
        }
        let extent_m = match opts.extent_m {
            Some(e) if e.is_finite() && e > 0.0 => e,
            Some(e) => return Err(IsoluxError::Extent { extent_m: e }),
            None => auto_extent_m(p, height_m),
        };
        let step_m = match opts.step_m {
            Some(s) if s.is_finite() && s > 0.0 => s,
            Some(s) => return Err(IsoluxError::Step { step_m: s }),
            None => extent_m / DEFAULT_INTERVALS_PER_HALF_WIDTH as f64,
        };
        if step_m > extent_m * (1.0 + 1e-9) {
            return Err(IsoluxError::StepExceedsExtent { step_m, extent_m });
        }
        let half = (extent_m / step_m - 1e-9).ceil().max(1.0);
        let points_per_side = 2.0 * half + 1.0;
        if points_per_side > MAX_POINTS_PER_SIDE as f64 {
            return Err(IsoluxError::TooManyPoints {
                step_m,
                extent_m,
                points_per_side: if points_per_side < usize::MAX as f64 {
                    points_per_side as usize
                } else {
                    usize::MAX
                },
            });
        }
        let half_points = half as usize;
        let n = 2 * half_points + 1;
        let coordinate = |i: usize| (i as f64 - half_points as f64) * step_m;
        let mut e_lx = vec![0.0; n * n];
        e_lx.par_chunks_mut(n).enumerate().for_each(|(iy, row)| {
            let y_m = coordinate(iy);
            for (ix, e) in row.iter_mut().enumerate() {
                *e = illuminance_lx(p, height_m, coordinate(ix), y_m);
            }
        });
        Ok(IsoluxGrid {
            height_m,
            extent_m,
            step_m,
            half_points,
            e_lx,
        })
    }

    /// Grid points along one side, 2K + 1.
    pub fn points_per_side(&self) -> usize {
        2 * self.half_points + 1
    }

    /// Floor coordinate of grid index `i` (either axis), metres: (i − K) · step.
    pub fn coordinate_m(&self, i: usize) -> f64 {
        (i as f64 - self.half_points as f64) * self.step_m
    }

    /// Half-width actually covered, metres: K · step (≥ the extent asked for).
    pub fn half_width_m(&self) -> f64 {
        self.half_points as f64 * self.step_m
    }

    /// Illuminance in lx at grid indices (ix, iy); `None` outside the grid.
    pub fn at(&self, ix: usize, iy: usize) -> Option<f64> {
        let n = self.points_per_side();
        (ix < n && iy < n).then(|| self.e_lx[iy * n + ix])
    }

    /// The largest illuminance on the grid and its floor position (the first in row order when
    /// several points share it).
    pub fn max(&self) -> MaxPoint {
        let n = self.points_per_side();
        let (i, e) =
            self.e_lx.iter().copied().enumerate().fold(
                (0, f64::NEG_INFINITY),
                |best, (i, e)| if e > best.1 { (i, e) } else { best },
            );
        MaxPoint {
            e_lx: e.max(0.0),
            x_m: self.coordinate_m(i % n),
            y_m: self.coordinate_m(i / n),
        }
    }

    /// The isolux levels of this grid: [`isolux_levels`] of its maximum.
    pub fn levels(&self) -> Vec<f64> {
        isolux_levels(self.max().e_lx)
    }

    /// The isolux lines at each of `levels_lx`, in floor metres (marching squares with linear
    /// interpolation, `photometry::contour`).
    pub fn contours(&self, levels_lx: &[f64]) -> Vec<IsoluxContour> {
        let n = self.points_per_side();
        levels_lx
            .iter()
            .map(|&level_lx| {
                let mut lines = contour_lines(&self.e_lx, n, n, level_lx);
                for line in &mut lines {
                    for p in &mut line.points {
                        *p = [self.grid_to_m(p[0]), self.grid_to_m(p[1])];
                    }
                }
                IsoluxContour { level_lx, lines }
            })
            .collect()
    }

    fn grid_to_m(&self, g: f64) -> f64 {
        (g - self.half_points as f64) * self.step_m
    }

    /// The grid as CSV text: header `x_m,y_m,E_lx`, then one row per point, y ascending, x
    /// ascending within a y. Coordinates to 1 nm, illuminance to 6 significant digits.
    pub fn to_csv(&self) -> String {
        let n = self.points_per_side();
        let mut s = String::with_capacity(n * n * 24 + 16);
        s.push_str("x_m,y_m,E_lx\n");
        let coords: Vec<String> = (0..n).map(|i| fmt_coordinate(self.coordinate_m(i))).collect();
        for (iy, row) in self.e_lx.chunks(n).enumerate() {
            for (ix, &e) in row.iter().enumerate() {
                let _ = writeln!(s, "{},{},{}", coords[ix], coords[iy], fmt_significant(e, 6));
            }
        }
        s
    }
}

/// A coordinate rounded to 1 nm, trailing zeros dropped (`0.21`, not `0.21000000000000002`).
fn fmt_coordinate(v: f64) -> String {
    trim_number(format!("{v:.9}"))
}

/// `v` with `digits` significant digits in plain decimal notation, trailing zeros dropped.
pub(crate) fn fmt_significant(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_finite() { "0".to_string() } else { format!("{v}") };
    }
    let decimals = (digits - 1 - v.abs().log10().floor() as i32).clamp(0, 15) as usize;
    trim_number(format!("{v:.decimals$}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photometry::{load_from_text, LoadOptions};

    /// A rotationally symmetric IES file with the given intensities at γ = 0, 10, …, 90°.
    fn downlight(cd: &[f64; 10]) -> Photometry {
        let gammas: Vec<String> = (0..10).map(|i| format!("{}", i * 10)).collect();
        let values: Vec<String> = cd.iter().map(|v| format!("{v}")).collect();
        let ies = format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 10 1 1 2 0 0 0\n1 1 10\n{}\n0\n{}\n",
            gammas.join(" "),
            values.join(" ")
        );
        match load_from_text(&ies, "test.ies", &LoadOptions::default()) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn isotropic_source_follows_the_inverse_square_and_cosine_laws() {
        let p = downlight(&[1000.0; 10]);
        let h = 2.5;
        assert!((illuminance_lx(&p, h, 0.0, 0.0) - 160.0).abs() < 1e-9);
        // At r = H (γ = 45°): cos³45° / H².
        let at_45 = 1000.0 * 0.5f64.sqrt().powi(3) / (h * h);
        for (x, y) in [(h, 0.0), (0.0, -h), (h / 2f64.sqrt(), h / 2f64.sqrt())] {
            assert!((illuminance_lx(&p, h, x, y) - at_45).abs() < 1e-9, "({x}, {y})");
        }
        assert_eq!(illuminance_lx(&p, 0.0, 0.0, 0.0), 0.0);
        assert_eq!(illuminance_lx(&p, f64::NAN, 0.0, 0.0), 0.0);
    }

    #[test]
    fn levels_are_1_2_5_down_to_one_percent() {
        assert_eq!(isolux_levels(292.0), [5.0, 10.0, 20.0, 50.0, 100.0, 200.0]);
        assert_eq!(isolux_levels(100.0), [1.0, 2.0, 5.0, 10.0, 20.0, 50.0]);
        assert_eq!(isolux_levels(0.73), [0.01, 0.02, 0.05, 0.1, 0.2, 0.5]);
        assert_eq!(isolux_levels(1234.5), [20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]);
        assert!(isolux_levels(0.0).is_empty());
        assert!(isolux_levels(f64::NAN).is_empty());
        assert_eq!(isolux_levels(100.0001), [2.0, 5.0, 10.0, 20.0, 50.0, 100.0]);
    }

    #[test]
    fn round_numbers_for_the_extent() {
        assert_eq!(round_up(2.92), 3.0);
        assert_eq!(round_up(3.0), 3.0);
        assert_eq!(round_up(3.01), 4.0);
        assert_eq!(round_up(0.13), 0.15);
        assert_eq!(round_up(81.0), 100.0);
    }

    #[test]
    fn grid_is_symmetric_contains_the_origin_and_covers_the_extent() {
        let p = downlight(&[1000.0, 900.0, 800.0, 600.0, 400.0, 200.0, 100.0, 50.0, 10.0, 0.0]);
        let opts = IsoluxOptions {
            height_m: 3.0,
            extent_m: Some(10.0),
            step_m: Some(0.3),
        };
        let g = IsoluxGrid::new(&p, &opts).map_err(|e| e.to_string());
        assert!(g.is_ok(), "{g:?}");
        let Ok(g) = g else { return };
        assert_eq!(g.half_points, 34); // ⌈10 / 0.3⌉
        assert_eq!(g.points_per_side(), 69);
        assert!(g.half_width_m() >= 10.0);
        assert_eq!(g.coordinate_m(34), 0.0);
        let m = g.max();
        assert_eq!((m.x_m, m.y_m), (0.0, 0.0));
        assert!((m.e_lx - 1000.0 / 9.0).abs() < 1e-9);
        // Rotational symmetry: E(x, y) = E(−y, x).
        let n = g.points_per_side();
        for (ix, iy) in [(40, 30), (3, 60), (50, 34)] {
            let (a, b) = (g.at(ix, iy), g.at(n - 1 - iy, ix));
            assert!(a.zip(b).is_some_and(|(a, b)| (a - b).abs() < 1e-9), "{a:?} {b:?}");
        }
        let csv = g.to_csv();
        assert!(csv.starts_with("x_m,y_m,E_lx\n-10.2,-10.2,"), "{}", &csv[..40]);
        assert_eq!(csv.lines().count(), 1 + n * n);
        assert!(csv.contains("\n0,0,111.111\n"));
    }

    #[test]
    fn contours_of_a_downlight_are_rings() {
        let p = downlight(&[1000.0; 10]);
        let opts = IsoluxOptions {
            height_m: 2.0,
            extent_m: Some(8.0),
            step_m: Some(0.04),
        };
        let Ok(g) = IsoluxGrid::new(&p, &opts) else {
            panic!("grid")
        };
        let levels = g.levels();
        assert_eq!(levels, [5.0, 10.0, 20.0, 50.0, 100.0, 200.0]);
        for c in g.contours(&levels) {
            assert_eq!(c.lines.len(), 1, "{} lx", c.level_lx);
            // E = 1000 · H / (r² + H²)^1.5 = level → r.
            let r = ((1000.0 * 2.0 / c.level_lx).powf(2.0 / 3.0) - 4.0).sqrt();
            let line = &c.lines[0];
            assert!(line.closed);
            for q in &line.points {
                assert!(
                    (q[0].hypot(q[1]) - r).abs() < 0.01 * r.max(0.2),
                    "{} lx at {q:?}, r {r}",
                    c.level_lx
                );
            }
        }
    }

    #[test]
    fn automatic_extent_reaches_one_percent() {
        // Isotropic 1000 cd: E/E0 = cos³γ = 0.01 at γ ≈ 77.6° → r ≈ 4.55 H → ×1.1 → 5 H → 15 m.
        let p = downlight(&[1000.0; 10]);
        assert_eq!(auto_extent_m(&p, 3.0), 15.0);
        // No light downwards at all.
        let dark = downlight(&[0.0; 10]);
        assert_eq!(auto_extent_m(&dark, 2.0), 6.0);
    }

    #[test]
    fn options_out_of_range_are_named() {
        let p = downlight(&[1000.0; 10]);
        let bad = |height_m, extent_m, step_m| {
            IsoluxGrid::new(
                &p,
                &IsoluxOptions {
                    height_m,
                    extent_m,
                    step_m,
                },
            )
            .err()
        };
        assert_eq!(bad(0.0, None, None), Some(IsoluxError::Height { height_m: 0.0 }));
        assert!(matches!(bad(f64::NAN, None, None), Some(IsoluxError::Height { .. })));
        assert!(matches!(bad(2.0, Some(-1.0), None), Some(IsoluxError::Extent { .. })));
        assert!(matches!(
            bad(2.0, Some(1.0), Some(f64::INFINITY)),
            Some(IsoluxError::Step { .. })
        ));
        assert!(matches!(
            bad(2.0, Some(1.0), Some(2.0)),
            Some(IsoluxError::StepExceedsExtent { .. })
        ));
        assert!(matches!(
            bad(2.0, Some(100.0), Some(0.001)),
            Some(IsoluxError::TooManyPoints {
                points_per_side: 200_001,
                ..
            })
        ));
        assert!(matches!(
            bad(2.0, Some(1e300), Some(1e-300)),
            Some(IsoluxError::TooManyPoints { .. })
        ));
    }

    #[test]
    fn numbers_in_the_csv() {
        assert_eq!(fmt_coordinate(0.21000000000000002), "0.21");
        assert_eq!(fmt_coordinate(-3.0), "-3");
        assert_eq!(fmt_coordinate(-1e-12), "0");
        assert_eq!(fmt_significant(292.0111111, 6), "292.011");
        assert_eq!(fmt_significant(0.0123456789, 6), "0.0123457");
        assert_eq!(fmt_significant(1234567.0, 6), "1234567");
        assert_eq!(fmt_significant(0.0, 6), "0");
    }
}
