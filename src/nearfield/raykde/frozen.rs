//! [`estimate_frozen`]: the kernels an estimate chose applied to other rays, batch by batch: the
//! kernel-matched truth of docs/quality-metrics.md ("Ray files").

use glam::DVec3;
use rayon::prelude::*;

use super::gather::{CameraAcc, Gather, Levels};
use super::{FrozenKernels, KdeScan};
use crate::nearfield::binning::NearestDirection;
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{LuminanceImage, MemorySource, Scan};

/// Rays handed to [`estimate_frozen`] in batches: origin (m), unit direction, luminous flux (lm).
pub type RayBatch = Vec<(DVec3, DVec3, f64)>;

/// The operator `base` applied to other rays: the same cameras and images, each ray weighted with
/// the angular widths `base` gives its direction (its own histogram's k-nearest-neighbour angles,
/// also where `base` had no ray), and each pixel spread with the spatial level `base` chose for
/// it. Applied to many more rays of the same light field this is `base`'s expectation, the
/// **kernel-matched truth** of docs/quality-metrics.md ("Ray files"). `next` yields the rays
/// (their fluxes summing to the flux the estimate is to hold) until it returns `None`.
///
/// # Errors
/// What `next` returns; [`NearfieldError::InvalidArgument`] when no ray carries flux.
pub fn estimate_frozen(
    base: &KdeScan,
    next: &mut dyn FnMut() -> Result<Option<RayBatch>>,
    progress: &(dyn Fn(&str, f64) + Sync),
) -> Result<KdeScan> {
    let set = &base.scan.set;
    let k = set.intrinsics;
    let px = (k.width as usize) * (k.height as usize);
    if base.kernels.level.len() != set.cameras.len() || base.kernels.level.iter().any(|l| l.len() != px) {
        return Err(NearfieldError::invalid(
            "estimate",
            "its spatial kernel levels were not kept (estimate with KdeOptions::keep_kernel_levels)",
        ));
    }
    let mut bw = base.frozen.bw.clone();
    let dirs = &base.frozen.directions;
    let mut accs: Vec<CameraAcc> = set.cameras.iter().map(|_| CameraAcc::new(k.width)).collect();
    let (mut rays_seen, mut flux, mut flux2) = (0u64, 0.0f64, 0.0f64);
    while let Some(batch) = next()? {
        let usable = |r: &(DVec3, DVec3, f64)| r.2 > 0.0 && r.2.is_finite() && r.0.is_finite() && r.1.is_finite();
        let get = |i: usize| batch.get(i).copied().filter(usable);
        let cells = bw.cell_rays(&get, batch.len());
        bw.cover(&cells);
        let gather = Gather {
            bw: &bw,
            cells: &cells,
            rays: &get,
            radius_m: base.frozen.radius_m,
        };
        accs.par_iter_mut()
            .zip(set.cameras.par_iter())
            .zip(dirs.par_iter())
            .for_each(|((acc, cam), d)| gather.gather(acc, cam, *d, &k));
        for r in batch.iter().filter(|r| usable(r)) {
            flux += r.2;
            flux2 += r.2 * r.2;
        }
        rays_seen += batch.len() as u64;
        progress("kernel-matched rays", rays_seen as f64);
    }
    if flux <= 0.0 {
        return Err(NearfieldError::invalid("rays", "no ray with a positive luminous flux"));
    }
    let pixel_area = base.kernels.pixel_m * base.kernels.pixel_m;
    let images: Vec<LuminanceImage> = accs
        .into_par_iter()
        .enumerate()
        .map(|(i, acc)| {
            let level = base.kernels.level[i].as_slice();
            let mut img = acc.finish(Levels::Given(level)).0;
            for v in &mut img.data {
                *v = (f64::from(*v) / pixel_area) as f32;
            }
            img
        })
        .collect();
    let (omega, _) = NearestDirection::new(dirs).solid_angles();
    let flux_images: f64 = images
        .iter()
        .zip(&omega)
        .map(|(img, o)| img.data.iter().map(|v| f64::from(*v)).sum::<f64>() * pixel_area * o)
        .sum();
    let mut report = base.report.clone();
    report.rays = rays_seen;
    report.effective_rays = flux * flux / flux2;
    report.flux_lm = flux;
    report.flux_from_images_lm = flux_images;
    report.cameras_lit = images.iter().filter(|i| i.data.iter().any(|v| *v > 0.0)).count();
    report.undersampled_pixels = 0;
    report.warnings = Vec::new();
    Ok(KdeScan {
        scan: Scan {
            set: set.clone(),
            source: Box::new(MemorySource { images }),
        },
        report,
        proxy: base.proxy.clone(),
        kernels: base.kernels.clone(),
        frozen: FrozenKernels {
            bw,
            ..base.frozen.clone()
        },
    })
}
