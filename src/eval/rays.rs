//! Ray files against their own far field: the luminous intensity a ray set holds, binned by
//! direction on a 5° (C, γ) grid, compared with the intensity read from orthographic GPU renders of
//! its kernel estimate (`nearfield::raykde`), Î(ω) = Σ L · p² over a view along −ω, averaged over
//! the bin as the bin averages the rays: four renders per bin at the nodes of the two-point
//! Gauss–Legendre rule in C and cos γ (the bin's solid-angle measure), exact where the intensity
//! varies as a cubic across the bin. (A render at the bin's centre alone differs from the bin's
//! mean wherever the intensity curves within 5°: the point source's central bins by 8–15 %.)
//!
//! The binned reference has its own noise: a bin holding n rays is uncertain by about 1/√n, so
//! each row reports n, and the summary gives the errors over the bins the contract counts (those
//! holding ≥ 1 % of the peak bin's intensity) with the reference's expected noise beside them.

use std::path::Path;
use std::sync::Arc;

use glam::{DVec3, Mat4};

use super::{ortho_intensity, EvalError};
use crate::gpu::nearfield::{NearfieldOptions, NearfieldSettings};
use crate::gpu::{LuminaireId, Renderer};
use crate::nearfield::pack::{write_pack, Pack, PackOptions};
use crate::nearfield::proxy::triangles_of;
use crate::nearfield::raykde::KdeScan;
use crate::nearfield::select::SelectionMode;
use crate::nearfield::tm25::RayFile;
use crate::photometry::web::{angles_of, direction};

/// Bin width of the reference, degrees (C and γ).
pub const BIN_DEG: f64 = 5.0;

/// One compared direction.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct IntensityRow {
    /// C of the bin centre, degrees.
    pub c_deg: f64,
    /// γ of the bin centre, degrees.
    pub gamma_deg: f64,
    /// The rays' intensity: flux in the bin / its solid angle (cd).
    pub rays_cd: f64,
    /// Rays in the bin.
    pub rays_in_bin: u64,
    /// Effective rays in the bin, (Σ Φ)² / Σ Φ² (the bin's relative noise is 1/√ of it).
    pub effective_rays_in_bin: f64,
    /// The render's Σ L · p², averaged over the bin's solid angle (cd).
    pub render_cd: f64,
}

/// The comparison over a ray file's far field.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct IntensityCheck {
    /// Every compared bin.
    pub rows: Vec<IntensityRow>,
    /// The peak binned intensity (cd).
    pub peak_cd: f64,
    /// Bins at or above 1 % of the peak.
    pub counted: usize,
    /// Median of |render / rays − 1| over the counted bins.
    pub median_rel: f64,
    /// 95th percentile of the same.
    pub p95_rel: f64,
    /// Median over the counted bins of the reference's own relative noise, 1/√n (n the bin's
    /// effective rays).
    pub median_reference_noise: f64,
    /// Median over the counted bins of |render − rays| / the bin's own noise (rays / √n): about
    /// 0.67 where the difference is the bins' Poisson noise alone (the median of |z| for a
    /// standard normal z), more where the estimate is off by more than the rays can tell.
    pub median_z: f64,
    /// 95th percentile of the same (about 1.96 for noise alone).
    pub p95_z: f64,
    /// Per 5° γ ring holding ≥ 1 % of the peak ring intensity: (γ centre, the rays' mean
    /// intensity over the ring, the renders' mean over the ring's compared bins, rays in the ring).
    pub rings: Vec<(f64, f64, f64, u64)>,
    /// Median of |render / rays − 1| over the rings (far less noisy than single bins).
    pub ring_median_rel: f64,
    /// 95th percentile of the same.
    pub ring_p95_rel: f64,
}

/// One 5° bin of a ray set's far field.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bin {
    /// Flux in the bin / its solid angle (cd).
    pub intensity_cd: f64,
    /// Rays in the bin.
    pub rays: u64,
    /// Effective rays, (Σ Φ)² / Σ Φ².
    pub effective_rays: f64,
}

/// The rays' intensity per 5° (C, γ) bin, indexed `[ic * 36 + ig]`, with every ray's flux times
/// `flux_scale` (the estimate's scaling to the header's flux, or 1).
pub fn binned_intensity(file: &RayFile, flux_scale: f64) -> Vec<Bin> {
    let nc = (360.0 / BIN_DEG) as usize;
    let ng = (180.0 / BIN_DEG) as usize;
    let mut flux = vec![(0.0f64, 0u64, 0.0f64); nc * ng];
    for i in 0..file.len() {
        let Some(r) = file.ray(i) else { continue };
        let Some(f) = r.luminous_lm.filter(|f| *f > 0.0 && f.is_finite()) else {
            continue;
        };
        let (c, g) = angles_of(r.direction.to_array());
        let ic = ((c / BIN_DEG) as usize).min(nc - 1);
        let ig = ((g / BIN_DEG) as usize).min(ng - 1);
        let b = &mut flux[ic * ng + ig];
        b.0 += f * flux_scale;
        b.1 += 1;
        b.2 += (f * flux_scale).powi(2);
    }
    let mut bins = vec![Bin::default(); nc * ng];
    for ic in 0..nc {
        for ig in 0..ng {
            let (g0, g1) = (
                (ig as f64 * BIN_DEG).to_radians(),
                ((ig + 1) as f64 * BIN_DEG).to_radians(),
            );
            let omega = BIN_DEG.to_radians() * (g0.cos() - g1.cos());
            let (f, n, f2) = flux[ic * ng + ig];
            bins[ic * ng + ig] = Bin {
                intensity_cd: f / omega,
                rays: n,
                effective_rays: if f2 > 0.0 { f * f / f2 } else { 0.0 },
            };
        }
    }
    bins
}

/// The mean of `f` over the 5° bin centred at (`c_deg`, `gamma_deg`) by the rule the check
/// renders with ([`check_intensity`]): four nodes of the two-point Gauss–Legendre rule in C and
/// cos γ. For a closed-form intensity beside a [`IntensityRow`].
pub fn bin_mean(c_deg: f64, gamma_deg: f64, f: impl Fn(DVec3) -> f64) -> f64 {
    let (ic, ig) = (
        (c_deg / BIN_DEG).floor() as usize,
        (gamma_deg / BIN_DEG).floor() as usize,
    );
    gauss_nodes(ic, ig)
        .iter()
        .map(|(c, g)| {
            let d = direction(*c, *g);
            0.25 * f(DVec3::new(d[0], d[1], d[2]))
        })
        .sum()
}

/// The four directions (C, γ in degrees) of the two-point Gauss–Legendre rule over bin (ic, ig) in
/// C and cos γ, each of weight 1/4 of the bin's mean.
fn gauss_nodes(ic: usize, ig: usize) -> [(f64, f64); 4] {
    let t = 0.5 / 3f64.sqrt();
    let c = |s: f64| (ic as f64 + 0.5 + s) * BIN_DEG;
    let (u0, u1) = (
        (ig as f64 * BIN_DEG).to_radians().cos(),
        ((ig + 1) as f64 * BIN_DEG).to_radians().cos(),
    );
    let g = |s: f64| ((u0 + u1) / 2.0 + s * (u1 - u0)).clamp(-1.0, 1.0).acos().to_degrees();
    [(c(-t), g(-t)), (c(t), g(-t)), (c(-t), g(t)), (c(t), g(t))]
}

/// Packs the estimate into `pack_path`, renders orthographic views over the bins in every
/// `c_step_deg`-th C column (a multiple of 5°; four per bin, [`bin_mean`]'s nodes), and compares
/// their mean with the binned rays.
///
/// # Errors
/// GPU or pack failures ([`EvalError`]).
pub fn check_intensity(
    r: &mut Renderer,
    file: &RayFile,
    est: KdeScan,
    pack_path: &Path,
    c_step_deg: f64,
    progress: &dyn Fn(&str),
) -> Result<IntensityCheck, EvalError> {
    let rb = proxy_reach(&est, est.scan.set.sphere.centre_m, 0.0);
    let centre = est.scan.set.sphere.centre_m;
    let flux_lm = est.report.flux_lm;
    progress("packing the estimate");
    let id = add_bound_estimate(r, &est, pack_path, &PackOptions::default(), 2 << 30)?;
    // The estimate may have scaled the rays to the header's flux: the reference follows.
    let raw: f64 = (0..file.len())
        .filter_map(|i| file.ray(i)?.luminous_lm)
        .filter(|f| *f > 0.0 && f.is_finite())
        .sum();
    let binned = binned_intensity(file, if raw > 0.0 { flux_lm / raw } else { 1.0 });
    let ng = (180.0 / BIN_DEG) as usize;
    let peak_cd = binned.iter().map(|b| b.intensity_cd).fold(0.0, f64::max);
    let step = ((c_step_deg / BIN_DEG).round() as usize).max(1);
    let mut rows = Vec::new();
    let mut targets = Vec::new();
    let columns: Vec<usize> = (0..(360.0 / BIN_DEG) as usize).step_by(step).collect();
    for (n, &ic) in columns.iter().enumerate() {
        progress(&format!("rendering C column {} of {}", n + 1, columns.len()));
        for ig in 0..ng {
            let bin = binned[ic * ng + ig];
            let i_rays = bin.intensity_cd;
            if i_rays < 0.01 * peak_cd {
                continue;
            }
            let (c, g) = ((ic as f64 + 0.5) * BIN_DEG, (ig as f64 + 0.5) * BIN_DEG);
            let mut i_render = 0.0;
            for (cn, gn) in gauss_nodes(ic, ig) {
                let d = direction(cn, gn);
                i_render += 0.25 * ortho_intensity(r, &mut targets, DVec3::new(d[0], d[1], d[2]), centre, rb, 96)?;
            }
            rows.push(IntensityRow {
                c_deg: c,
                gamma_deg: g,
                rays_cd: i_rays,
                rays_in_bin: bin.rays,
                effective_rays_in_bin: bin.effective_rays,
                render_cd: i_render,
            });
        }
    }
    r.remove_luminaire(id)?;
    let mut rel: Vec<f64> = rows.iter().map(|r| (r.render_cd / r.rays_cd - 1.0).abs()).collect();
    let mut noise: Vec<f64> = rows
        .iter()
        .map(|r| 1.0 / r.effective_rays_in_bin.max(1.0).sqrt())
        .collect();
    let mut z: Vec<f64> = rows
        .iter()
        .zip(&noise)
        .map(|(r, n)| (r.render_cd - r.rays_cd).abs() / (r.rays_cd * n))
        .collect();
    // Rings: the rays' flux over all C of a γ band over its solid angle, against the mean of the
    // renders in that band (every compared C column).
    let nc = (360.0 / BIN_DEG) as usize;
    let mut rings = Vec::new();
    let ring_peak = (0..ng)
        .map(|ig| (0..nc).map(|ic| binned[ic * ng + ig].intensity_cd).sum::<f64>() / nc as f64)
        .fold(0.0, f64::max);
    for ig in 0..ng {
        let i_ring = (0..nc).map(|ic| binned[ic * ng + ig].intensity_cd).sum::<f64>() / nc as f64;
        let n_ring: u64 = (0..nc).map(|ic| binned[ic * ng + ig].rays).sum();
        let g = (ig as f64 + 0.5) * BIN_DEG;
        let rendered: Vec<f64> = rows
            .iter()
            .filter(|r| (r.gamma_deg - g).abs() < 1e-9)
            .map(|r| r.render_cd)
            .collect();
        // Only rings whose every compared column was rendered (all above 1 % of the peak bin).
        if i_ring >= 0.01 * ring_peak && rendered.len() == columns.len() {
            let mean = rendered.iter().sum::<f64>() / rendered.len() as f64;
            rings.push((g, i_ring, mean, n_ring));
        }
    }
    let mut ring_rel: Vec<f64> = rings.iter().map(|(_, a, b, _)| (b / a - 1.0).abs()).collect();
    let q = |v: &mut Vec<f64>, p: f64| {
        if v.is_empty() {
            return f64::NAN;
        }
        v.sort_by(f64::total_cmp);
        v[((p * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)]
    };
    Ok(IntensityCheck {
        counted: rows.len(),
        median_rel: q(&mut rel, 0.5),
        p95_rel: q(&mut rel, 0.95),
        median_reference_noise: q(&mut noise, 0.5),
        median_z: q(&mut z, 0.5),
        p95_z: q(&mut z, 0.95),
        ring_median_rel: q(&mut ring_rel, 0.5),
        ring_p95_rel: q(&mut ring_rel, 0.95),
        rings,
        rows,
        peak_cd,
    })
}

/// The farthest point of `est`'s proxy from `centre` (at least `at_least`), × 1.02: a frame that
/// holds all of the estimate's light, which reaches past the ray origins by its kernels (m).
pub(crate) fn proxy_reach(est: &KdeScan, centre: DVec3, at_least: f64) -> f64 {
    est.proxy
        .surfaces
        .iter()
        .flat_map(|s| s.positions.iter())
        .map(|p| (*p - centre).length())
        .fold(at_least, f64::max)
        * 1.02
}

/// Packs `est` to `pack_path` with `pack` and adds it to `r` with its proxy as a bound, one
/// instance at the origin drawn with continuous selection and the proxy, as `render` and `pack`
/// show ray files. Returns the luminaire (remove it when done).
pub(crate) fn add_bound_estimate(
    r: &mut Renderer,
    est: &KdeScan,
    pack_path: &Path,
    pack: &PackOptions,
    budget_bytes: u64,
) -> Result<LuminaireId, EvalError> {
    write_pack(&est.scan, pack_path, pack, &|_, _| {})?;
    let opts = NearfieldOptions {
        budget_bytes,
        proxy_is_bound: true,
        ..NearfieldOptions::default()
    };
    let id = r.add_pack(Arc::new(Pack::open(pack_path)?), Some(triangles_of(&est.proxy)), &opts)?;
    let shown = r.add_instance(id, Mat4::IDENTITY).and_then(|inst| {
        r.set_nearfield_settings(
            inst,
            NearfieldSettings {
                mode: SelectionMode::Continuous,
                proxy: true,
            },
        )
    });
    if let Err(e) = shown {
        r.remove_luminaire(id)?;
        return Err(e.into());
    }
    Ok(id)
}
