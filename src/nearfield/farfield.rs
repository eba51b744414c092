//! The far-field intensity of a scanned luminaire, from its luminance images and poses: what lets a
//! near-field scan light a scene (`scene`, `gpu::scene`) and be written as an IES file
//! (`lumiview convert SCAN -o far.ies`).
//!
//! Promises:
//! - The estimator is the light field's own: every pixel ray of every camera carries the flux
//!   `L · dG` with the étendue `dG = |p − c|² · ω_cam · max(0, e·s) · Ω_px` (ω_cam the solid angle of
//!   the camera's spherical Voronoi cell on the capture sphere, s the camera's direction from the
//!   capture centre c, e the ray's emission direction (from the luminaire towards the camera), Ω_px
//!   the pixel's solid angle `1 / (f_x f_y |d|³)`). The flux of all rays is the scan's flux
//!   ([`FarField::flux_lm`]); it does not assume a photometric distance, so a luminaire as large as
//!   the capture sphere allows has the same far field as a point.
//! - Intensity is that flux per solid angle, smoothed on the sphere by a von Mises–Fisher kernel
//!   (normalised: flux is kept) whose width σ ([`FarField::bandwidth_deg`]) is 0.6 × the side of
//!   the 98th-percentile camera cell (the widest gaps between cameras set it): cameras spaced Δ
//!   apart sample the light field's positions R·Δ apart, and a kernel of 0.6 Δ leaves the ripple
//!   of a regular layout below 0.2 %. Uneven layouts (a meridian goniophotometer's crowded poles)
//!   are evened out by dividing by the cameras' own quadrature of the kernel, D(e) = Σ ω_i K(e, s_i)
//!   (measured: +4 % at the pole of a 200-camera meridian scan without it, −1 % with it). The far
//!   field cannot show detail finer than σ; docs/scene-lighting.md has the measured error.
//! - It is tabulated on a Type C web (C 0…360°, γ 0…180°, no symmetry) at a step of at most σ / 2
//!   (0.5, 1, 2 or 2.5°), the luminaire frame of docs/conventions.md (the capture sphere's frame).
//! - Scans with more than twice [`FarFieldOptions::max_cameras`] cameras use about that many, the
//!   ones nearest a Fibonacci set of directions (each with its Voronoi cell in the subset), with
//!   their pixels summed in blocks of at most a quarter of the histogram's cell.
//! - The luminous extent ([`FarField::extent_m`]) is measured from the six cameras nearest the
//!   axes: the lit pixels' (≥ 1 % of the image's peak) rays cut the plane through the capture centre
//!   across the camera's direction; each axis takes its span from the view with the most lit
//!   pixels among those that show it (an edge-on view of a flat source shows a sliver). Spans
//!   below 1 mm or two pixel footprints are 0. The IES text gives it as the luminous opening (a box, centred on the
//!   photometric centre), so penumbrae take the luminaire's size.
//! - Directions no camera covers (a one-hemisphere scan) get no light, with a warning naming the
//!   share of the sphere missing; a camera's cell is capped at 4 × the median cell. A scan without
//!   a lit pixel has a far field of 0 cd, with a warning: it lights nothing.

use glam::DVec3;
use rayon::prelude::*;

use super::binning::NearestDirection;
use super::error::{NearfieldError, Result};
use super::raykde::bandwidth::fibonacci;
use super::rayset::{ImageSource, RayImageSet};
use crate::photometry::{load_from_text, web, LoadOptions, Photometry};

/// Options of [`FarField::estimate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FarFieldOptions {
    /// Scans of more than twice this many cameras (default 4096) use a subset of about this many,
    /// spread over the sphere.
    pub max_cameras: usize,
    /// Kernel width σ in degrees; `None` chooses it from the camera spacing.
    pub bandwidth_deg: Option<f64>,
}

impl Default for FarFieldOptions {
    fn default() -> Self {
        Self {
            max_cameras: 4096,
            bandwidth_deg: None,
        }
    }
}

/// A scan's far-field intensity on a Type C web.
#[derive(Debug, Clone)]
pub struct FarField {
    /// C angles (degrees), 0…360 inclusive.
    pub c_deg: Vec<f64>,
    /// γ angles (degrees), 0…180 inclusive.
    pub gamma_deg: Vec<f64>,
    /// Intensity (cd), one row of `gamma_deg.len()` values per C angle.
    pub candela: Vec<Vec<f64>>,
    /// Flux of every pixel ray (lm).
    pub flux_lm: f64,
    /// The kernel's width σ (degrees).
    pub bandwidth_deg: f64,
    /// Cameras read.
    pub cameras_used: usize,
    /// Share of the sphere of directions within 2 √(median camera cell) of a camera (0…1): what the
    /// layout covers.
    pub covered_fraction: f64,
    /// Luminous extent along X, Y, Z of the luminaire frame (m).
    pub extent_m: DVec3,
    /// Things a user should know (sparse coverage), naming the scan.
    pub warnings: Vec<String>,
}

/// Histogram of ray flux over (C, γ) cells, `2n × n` cells of 180/n degrees.
struct Histogram {
    n: usize,
    flux: Vec<f64>,
}

impl Histogram {
    fn new(cell_deg: f64) -> Self {
        let n = (180.0 / cell_deg).ceil().max(1.0) as usize;
        Self {
            n,
            flux: vec![0.0; 2 * n * n],
        }
    }

    fn cell_of(&self, e: DVec3) -> usize {
        let (c, g) = web::angles_of(e.to_array());
        let step = 180.0 / self.n as f64;
        let gi = ((g / step) as usize).min(self.n - 1);
        let ci = ((c / step) as usize).min(2 * self.n - 1);
        gi * 2 * self.n + ci
    }

    fn centre(&self, cell: usize) -> (f64, f64) {
        let step = 180.0 / self.n as f64;
        let (gi, ci) = (cell / (2 * self.n), cell % (2 * self.n));
        ((ci as f64 + 0.5) * step, (gi as f64 + 0.5) * step)
    }
}

/// The direction of (C, γ) in degrees (docs/conventions.md), as a vector.
fn direction(c_deg: f64, g_deg: f64) -> DVec3 {
    DVec3::from_array(web::direction(c_deg, g_deg))
}

/// The normalised von Mises–Fisher kernel K(e, s) = norm · exp(κ (e·s − 1)), cut at `reach` (rad).
struct Kernel {
    kappa: f64,
    norm: f64,
    reach: f64,
}

impl Kernel {
    /// Σ w · K(d, s) over the weighted directions `items` (s, w) at every node d of the web,
    /// one row of `c_deg` values per γ.
    fn web(&self, items: &[(DVec3, f64)], c_deg: &[f64], gamma_deg: &[f64]) -> Vec<Vec<f64>> {
        let cos_reach = self.reach.cos();
        gamma_deg
            .par_iter()
            .map(|&g| {
                // Only items within reach of the row in γ can reach one of its nodes.
                let near: Vec<&(DVec3, f64)> = items
                    .iter()
                    .filter(|(s, _)| ((-s.z).clamp(-1.0, 1.0).acos().to_degrees() - g).abs().to_radians() <= self.reach)
                    .collect();
                c_deg
                    .iter()
                    .map(|&c| {
                        let d = direction(c, g);
                        near.iter()
                            .map(|(s, w)| {
                                let cos = d.dot(*s);
                                if cos < cos_reach {
                                    0.0
                                } else {
                                    w * self.norm * (self.kappa * (cos - 1.0)).exp()
                                }
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect()
    }
}

/// Indices of at most `max` cameras spread over the sphere: the camera nearest each of `max`
/// Fibonacci directions, without repeats, in camera order.
fn camera_subset(dirs: &[DVec3], max: usize) -> Vec<usize> {
    if dirs.len() <= 2 * max {
        return (0..dirs.len()).collect();
    }
    let lookup = NearestDirection::new(dirs);
    let mut keep = vec![false; dirs.len()];
    for q in fibonacci(max) {
        if let Some(j) = lookup.nearest(q) {
            keep[j] = true;
        }
    }
    (0..dirs.len()).filter(|&i| keep[i]).collect()
}

impl FarField {
    /// Estimates the far field of the scan `set` whose images `images` gives (cd/m²).
    /// `progress(fraction)` is called as cameras are read.
    ///
    /// Errors: an image that cannot be read or does not match its camera's intrinsics (naming the
    /// camera), rays whose flux is not finite (`scan`), `max_cameras` 0 or a bandwidth outside
    /// 0.1…30° (`options`). A scan without a lit pixel is a far field of 0 cd with a warning.
    pub fn estimate(
        set: &RayImageSet,
        images: &dyn ImageSource,
        opts: &FarFieldOptions,
        progress: &(dyn Fn(f64) + Sync),
    ) -> Result<FarField> {
        if opts.max_cameras == 0 {
            return Err(NearfieldError::invalid("options", "max_cameras must be at least 1"));
        }
        if let Some(b) = opts.bandwidth_deg {
            if !(0.1..=30.0).contains(&b) {
                return Err(NearfieldError::invalid(
                    "options",
                    format!("bandwidth {b}° is outside 0.1…30°"),
                ));
            }
        }
        let centre = set.sphere.centre_m;
        let all_dirs: Vec<DVec3> = set.cameras.iter().map(|c| c.direction_from(centre)).collect();
        let used = camera_subset(&all_dirs, opts.max_cameras);
        let dirs: Vec<DVec3> = used.iter().map(|&i| all_dirs[i]).collect();
        // Exact Voronoi cells; a cell reaching beyond ~85° (the open side of a one-hemisphere
        // scan) is capped below, so it needs no sampled estimate.
        let lookup = NearestDirection::new(&dirs);
        let cells: Vec<Option<f64>> = (0..dirs.len())
            .into_par_iter()
            .map(|i| lookup.cell_solid_angle(i))
            .collect();
        let mut sorted: Vec<f64> = cells.iter().flatten().copied().filter(|w| *w > 0.0).collect();
        sorted.sort_by(f64::total_cmp);
        let Some(&median) = sorted.get(sorted.len() / 2) else {
            return Err(NearfieldError::invalid(
                "scan",
                "no camera has a direction from the capture centre",
            ));
        };
        let p98 = sorted[(sorted.len() * 49 / 50).min(sorted.len() - 1)];
        let cap = 4.0 * median;
        let omega: Vec<f64> = cells.iter().map(|w| w.unwrap_or(cap).min(cap)).collect();
        // Pixel angle: the smallest 1/f of any camera (rad).
        let pixel_rad = used
            .iter()
            .map(|&i| {
                let k = set.intrinsics_of(i);
                1.0 / k.focal_px.x.max(k.focal_px.y)
            })
            .fold(f64::INFINITY, f64::min);
        let sigma_deg = match opts.bandwidth_deg {
            Some(b) => b,
            None => (0.6 * p98.sqrt().to_degrees())
                .clamp(0.25, 30.0)
                .max(3.0 * pixel_rad.to_degrees()),
        };
        let sigma = sigma_deg.to_radians();
        let mut hist = Histogram::new((sigma_deg / 4.0).max(0.05));
        let cell_rad = (180.0 / hist.n as f64).to_radians();
        let name = images
            .input_files()
            .first()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| "the scan".into());

        // Rays → histogram, cameras in chunks (bounded memory), each camera's lit blocks in parallel.
        let done = std::sync::atomic::AtomicUsize::new(0);
        let mut total_flux = 0.0;
        let block = ((0.25 * cell_rad / pixel_rad.max(1e-9)).floor() as u32).clamp(1, 64);
        let subset: Vec<usize> = (0..used.len()).collect();
        for chunk in subset.chunks(64) {
            let sparse: Vec<Result<Vec<(usize, f64)>>> = chunk
                .par_iter()
                .map(|&u| {
                    let (i, w) = (used[u], omega[u]);
                    let cam = &set.cameras[i];
                    let k = set.intrinsics_of(i);
                    let img = images.image(i)?;
                    img.validate(&cam.label, k)?;
                    let s = all_dirs[i];
                    let r2 = (cam.position_m - centre).length_squared();
                    let mut out = Vec::new();
                    for by in (0..img.height).step_by(block as usize) {
                        for bx in (0..img.width).step_by(block as usize) {
                            let mut sum = 0.0;
                            for y in by..(by + block).min(img.height) {
                                for x in bx..(bx + block).min(img.width) {
                                    let l = f64::from(img.get(x, y));
                                    if l > 0.0 && l.is_finite() {
                                        let d = k.ray_camera(f64::from(x) + 0.5, f64::from(y) + 0.5);
                                        let len = d.length();
                                        let omega_px = 1.0 / (k.focal_px.x * k.focal_px.y * len * len * len);
                                        sum += l * omega_px;
                                    }
                                }
                            }
                            if sum <= 0.0 {
                                continue;
                            }
                            let cx = f64::from(bx) + 0.5 * f64::from(block.min(img.width - bx));
                            let cy = f64::from(by) + 0.5 * f64::from(block.min(img.height - by));
                            let e = -cam.to_world(k.ray_camera(cx, cy)).normalize();
                            let flux = sum * r2 * w * e.dot(s).max(0.0);
                            if flux > 0.0 {
                                out.push((hist.cell_of(e), flux));
                            }
                        }
                    }
                    let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    if n.is_multiple_of(16) {
                        progress(0.9 * n as f64 / used.len() as f64);
                    }
                    Ok(out)
                })
                .collect();
            for cam in sparse {
                for (cell, f) in cam? {
                    hist.flux[cell] += f;
                    total_flux += f;
                }
            }
        }
        if !total_flux.is_finite() {
            return Err(NearfieldError::invalid(
                "scan",
                format!("{name}: the rays' flux is not finite (a luminance or a camera pose out of range)"),
            ));
        }
        let mut warnings = Vec::new();
        if total_flux <= 0.0 {
            warnings.push(format!(
                "{name}: no camera sees a lit pixel: its far field is 0 cd everywhere and it lights nothing"
            ));
        }

        // Histogram → web through the normalised kernel.
        let step = [0.5, 1.0, 2.0, 2.5]
            .into_iter()
            .rev()
            .find(|s| *s <= sigma_deg / 2.0)
            .unwrap_or(0.5);
        let nc = (360.0 / step).round() as usize;
        let ng = (180.0 / step).round() as usize;
        let c_deg: Vec<f64> = (0..=nc).map(|i| i as f64 * step).collect();
        let gamma_deg: Vec<f64> = (0..=ng).map(|i| i as f64 * step).collect();
        let kappa = 1.0 / (sigma * sigma);
        let kernel = Kernel {
            kappa,
            norm: kappa / (2.0 * std::f64::consts::PI * (1.0 - (-2.0 * kappa).exp())),
            reach: 4.0 * sigma,
        };
        let cells: Vec<(DVec3, f64)> = hist
            .flux
            .iter()
            .enumerate()
            .filter(|(_, f)| **f > 0.0)
            .map(|(i, f)| {
                let (c, g) = hist.centre(i);
                (direction(c, g), *f)
            })
            .collect();
        let rows = kernel.web(&cells, &c_deg, &gamma_deg);
        // The cameras' own quadrature of the kernel, D(e) = Σ ω_i K(e, s_i) (1 for a perfect one):
        // dividing by it removes the bias of uneven layouts (a meridian layout's pole).
        let cameras: Vec<(DVec3, f64)> = dirs.iter().copied().zip(omega.iter().copied()).collect();
        let density = kernel.web(&cameras, &c_deg, &gamma_deg);
        let candela: Vec<Vec<f64>> = (0..c_deg.len())
            .map(|ci| {
                rows.iter()
                    .zip(&density)
                    .map(|(r, d)| if d[ci] > 0.0 { r[ci] / d[ci] } else { r[ci] })
                    .collect()
            })
            .collect();
        progress(0.95);

        // Coverage: directions within 2 √(median cell) of some camera.
        let near_enough = (2.0 * median.sqrt()).cos();
        let samples = 20_000;
        let covered = fibonacci(samples)
            .into_iter()
            .filter(|q| lookup.nearest(*q).is_some_and(|j| dirs[j].dot(*q) >= near_enough))
            .count();
        let covered_fraction = covered as f64 / samples as f64;
        if covered_fraction < 0.99 {
            warnings.push(format!(
                "{name}: the cameras cover {:.1} % of the sphere of directions; light towards the rest is \
                 missing from the far field",
                100.0 * covered_fraction
            ));
        }
        let extent_m = luminous_extent(set, images, &lookup, &dirs, &used)?;
        progress(1.0);
        Ok(FarField {
            c_deg,
            gamma_deg,
            candela,
            flux_lm: total_flux,
            bandwidth_deg: sigma_deg,
            cameras_used: used.len(),
            covered_fraction,
            extent_m,
            warnings,
        })
    }

    /// Intensity (cd) towards (C, γ) in degrees, bilinear on the web.
    pub fn intensity(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        let step_c = self.c_deg[1] - self.c_deg[0];
        let step_g = self.gamma_deg[1] - self.gamma_deg[0];
        let c = c_deg.rem_euclid(360.0) / step_c;
        let g = gamma_deg.clamp(0.0, 180.0) / step_g;
        let (ci, gi) = (
            (c as usize).min(self.c_deg.len() - 2),
            (g as usize).min(self.gamma_deg.len() - 2),
        );
        let (fc, fg) = (c - ci as f64, g - gi as f64);
        let at = |i: usize, j: usize| self.candela[i][j];
        (1.0 - fc) * ((1.0 - fg) * at(ci, gi) + fg * at(ci, gi + 1))
            + fc * ((1.0 - fg) * at(ci + 1, gi) + fg * at(ci + 1, gi + 1))
    }

    /// The far field as a [`Photometry`] (through [`FarField::to_ies`], so it is what the IES
    /// file holds), named `name`.
    ///
    /// Errors: the text does not parse (a defect: it is written here), as the photometry error.
    pub fn photometry(&self, name: &str) -> std::result::Result<Photometry, crate::photometry::PhotometryError> {
        let file = format!("{name} (far field).ies");
        load_from_text(&self.to_ies(name), &file, &LoadOptions::default())
    }

    /// The far field as IES LM-63-2002 text: absolute photometry (lamp lumens −1), Type C, metres,
    /// the luminous extent as the opening (a box; width along Y, length along X), `name` in the
    /// `[LUMINAIRE]` keyword.
    pub fn to_ies(&self, name: &str) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let one_line: String = name.chars().map(|c| if c.is_control() { ' ' } else { c }).collect();
        let _ = writeln!(s, "IESNA:LM-63-2002");
        let _ = writeln!(s, "[TEST] far field of a near-field scan, estimated by lumiview");
        let _ = writeln!(s, "[MANUFAC] lumiview");
        let _ = writeln!(s, "[LUMINAIRE] {one_line}");
        let _ = writeln!(
            s,
            "[OTHER] kernel {:.3} deg, {} cameras, flux of the rays {:.6e} lm, {:.1} % of directions covered",
            self.bandwidth_deg,
            self.cameras_used,
            self.flux_lm,
            100.0 * self.covered_fraction
        );
        let _ = writeln!(s, "TILT=NONE");
        let _ = writeln!(
            s,
            "1 -1 1 {} {} 1 2 {:.6} {:.6} {:.6}",
            self.gamma_deg.len(),
            self.c_deg.len(),
            self.extent_m.y,
            self.extent_m.x,
            self.extent_m.z
        );
        let _ = writeln!(s, "1 1 0");
        let list = |s: &mut String, v: &[f64]| {
            for (i, x) in v.iter().enumerate() {
                let sep = if i % 10 == 9 || i + 1 == v.len() { "\n" } else { " " };
                let _ = write!(s, "{x:.6e}{sep}");
            }
        };
        list(&mut s, &self.gamma_deg);
        list(&mut s, &self.c_deg);
        for row in &self.candela {
            list(&mut s, row);
        }
        s
    }
}

/// The luminous extent along X, Y, Z (m) from the cameras nearest ±X, ±Y, ±Z (see the module
/// promises).
fn luminous_extent(
    set: &RayImageSet,
    images: &dyn ImageSource,
    lookup: &NearestDirection,
    dirs: &[DVec3],
    used: &[usize],
) -> Result<DVec3> {
    let centre = set.sphere.centre_m;
    // Per axis: the span seen by the view with the most lit pixels among those showing it (an
    // edge-on view of a flat source shows a sliver), and the pixel footprint there.
    let mut span = [(0usize, 0.0f64, 0.0f64); 3];
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut a = DVec3::ZERO;
            a[axis] = sign;
            let Some(j) = lookup.nearest(a) else { continue };
            if dirs[j].dot(a) < 10f64.to_radians().cos() {
                continue;
            }
            let i = used[j];
            let cam = &set.cameras[i];
            let k = set.intrinsics_of(i);
            let img = images.image(i)?;
            img.validate(&cam.label, k)?;
            let peak = img
                .data
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(0.0f32, f32::max);
            if peak <= 0.0 {
                continue;
            }
            let s = dirs[j];
            let footprint = (cam.position_m - centre).length() / k.focal_px.x.min(k.focal_px.y);
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            let mut lit = 0usize;
            for y in 0..img.height {
                for x in 0..img.width {
                    if img.get(x, y) < 0.01 * peak {
                        continue;
                    }
                    lit += 1;
                    let d = cam.to_world(k.ray_camera(f64::from(x) + 0.5, f64::from(y) + 0.5));
                    let den = d.dot(s);
                    if den.abs() < 1e-9 {
                        continue;
                    }
                    let t = (centre - cam.position_m).dot(s) / den;
                    let p = cam.position_m + t * d - centre;
                    for q in 0..3 {
                        lo[q] = lo[q].min(p[q]);
                        hi[q] = hi[q].max(p[q]);
                    }
                }
            }
            for q in (0..3).filter(|q| *q != axis) {
                if hi[q] >= lo[q] && lit > span[q].0 {
                    span[q] = (lit, hi[q] - lo[q], footprint);
                }
            }
        }
    }
    Ok(DVec3::from_array(span.map(|(_, v, px)| {
        if v.is_finite() && v >= 1e-3 && v >= 2.0 * px {
            v
        } else {
            0.0
        }
    })))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearfield::layout::Layout;
    use crate::nearfield::synth::scan::{synth_scan, SynthOptions};

    fn scan(name: &str, cameras: usize, px: u32) -> crate::nearfield::rayset::Scan {
        synth_scan(&SynthOptions {
            luminaire: name.into(),
            layout: Layout::Fibonacci { count: cameras },
            size: (px, px),
            ..SynthOptions::default()
        })
        .unwrap()
    }

    #[test]
    fn a_lambertian_disc_has_its_cosine_far_field_and_flux() {
        let s = scan("disc", 1500, 48);
        let lum = crate::nearfield::synth::luminaire("disc").unwrap();
        let ff = FarField::estimate(&s.set, s.source.as_ref(), &FarFieldOptions::default(), &|_| {}).unwrap();
        let flux = lum.flux_lm();
        assert!((ff.flux_lm / flux - 1.0).abs() < 0.01, "{} vs {flux}", ff.flux_lm);
        let i0 = lum.intensity_cd(DVec3::NEG_Z);
        for g in [0.0, 20.0, 40.0, 60.0] {
            let want = lum.intensity_cd(direction(30.0, g));
            let got = ff.intensity(30.0, g);
            assert!((got - want).abs() < 0.02 * i0, "γ {g}: {got} vs {want}");
        }
        assert!(ff.warnings.is_empty(), "{:?}", ff.warnings);
        // The disc lies in z = 0: its extent is its diameter in X and Y and none in Z.
        let b = lum.bounds();
        assert!(
            (ff.extent_m.x / (b.max.x - b.min.x) - 1.0).abs() < 0.1,
            "{:?} vs {b:?}",
            ff.extent_m
        );
        assert_eq!(ff.extent_m.z, 0.0);
        // As photometry: the same intensities, flux and opening.
        let p = ff.photometry("disc scan").unwrap();
        for (c, g) in [(0.0, 0.0), (30.0, 40.0), (200.0, 75.0)] {
            let (a, b) = (p.intensity(c, g), ff.intensity(c, g));
            assert!((a - b).abs() <= 1e-5 * i0, "({c}, {g}): {a} vs {b}");
        }
        assert!((p.flux_lm() / flux - 1.0).abs() < 0.01, "{} vs {flux}", p.flux_lm());
        assert!((p.opening.size_x_m - ff.extent_m.x).abs() < 1e-6 && p.opening.height_m == 0.0);
    }

    /// One hemisphere of cameras: the downward disc keeps its flux, and the warning names the
    /// scan and the missing half. All images dark: 0 cd everywhere, a warning, photometry that loads.
    #[test]
    fn partial_and_dark_scans_are_said_not_hidden() {
        use crate::nearfield::rayset::MemorySource;
        let s = scan("disc", 600, 24);
        let lower: Vec<usize> = (0..s.set.cameras.len())
            .filter(|&i| s.set.cameras[i].position_m.z < 0.0)
            .collect();
        let mut set = s.set.clone();
        set.cameras = lower.iter().map(|&i| s.set.cameras[i].clone()).collect();
        let images = MemorySource {
            images: lower.iter().map(|&i| s.source.image(i).unwrap()).collect(),
        };
        let ff = FarField::estimate(&set, &images, &FarFieldOptions::default(), &|_| {}).unwrap();
        let flux = crate::nearfield::synth::luminaire("disc").unwrap().flux_lm();
        assert!((ff.flux_lm / flux - 1.0).abs() < 0.02, "{} vs {flux}", ff.flux_lm);
        assert!(
            ff.covered_fraction > 0.4 && ff.covered_fraction < 0.7,
            "{}",
            ff.covered_fraction
        );
        assert_eq!(ff.warnings.len(), 1, "{:?}", ff.warnings);
        assert!(
            ff.warnings[0].contains("of the sphere of directions"),
            "{:?}",
            ff.warnings
        );

        let dark = MemorySource {
            images: images
                .images
                .iter()
                .map(|im| crate::nearfield::rayset::LuminanceImage::zeros(im.width, im.height))
                .collect(),
        };
        let ff = FarField::estimate(&set, &dark, &FarFieldOptions::default(), &|_| {}).unwrap();
        assert_eq!(ff.flux_lm, 0.0);
        assert!(ff.candela.iter().flatten().all(|v| *v == 0.0));
        assert!(
            ff.warnings.iter().any(|w| w.contains("lights nothing")),
            "{:?}",
            ff.warnings
        );
        let p = ff.photometry("dark").unwrap();
        assert_eq!(p.intensity(0.0, 0.0), 0.0);
    }
}
