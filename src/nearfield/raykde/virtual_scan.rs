//! [`estimate`]: a ray file turned into a virtual scan (see the module docs of [`super`]): the
//! usable rays and their outliers, the bandwidths and the camera layout, the image size, every
//! camera's estimate, and the report of what was chosen.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::bandwidth::{Bandwidths, RaySummary};
use super::gather::{CameraEstimate, Gather};
use super::pyramid::{LEVEL_SIGMA_PX, POINT_LEVEL};
use super::{
    check_options, hull, FrozenKernels, KdeOptions, KdeReport, KdeScan, KernelMaps, Spread, AUTO_TOTAL_PIXELS,
    MAX_AUTO_PX, MAX_TOTAL_PIXELS,
};
use crate::nearfield::binning::NearestDirection;
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{Camera, CaptureSphere, Hemisphere, Intrinsics, MemorySource, RayImageSet, Scan};
use crate::nearfield::tm25::{LuminousSource, RayFile, RayFlux};

/// The least the bounding proxy grows past the ray origins, in capture pixels, where the kernels
/// follow the rays: a level-0 kernel reaches a pixel past its ray and the renderer's bilinear read
/// one more (3 leaves a margin). A kernel fixed at one level (given by the user, or a source smaller
/// than a pixel, [`POINT_LEVEL`]) reaches [`FIXED_REACH_SIGMAS`] of its σ plus that pixel of the
/// read. A proxy that ends sooner cuts off light: the point source lost 6 % of its intensity with
/// 3 pixels at level 1.
const PROXY_MIN_GROW_PX: f64 = 3.0;

/// How far a kernel of one level spreads, in its σ: it leaves 3·10⁻⁴ of its light beyond 3.6 σ
/// at level 1 and 10⁻⁴ beyond 3.9 σ at level 2 (measured on one ray).
const FIXED_REACH_SIGMAS: f64 = 4.0;

/// The rays of a file as plain numbers (metres, unit directions, lm), in file order.
struct Rays<'a> {
    file: &'a RayFile,
    scale: f64,
    /// Rays starting farther than this from `centre` are outliers, left out (m).
    reach: f64,
    centre: DVec3,
}

impl Rays<'_> {
    fn len(&self) -> usize {
        self.file.len()
    }

    /// Origin, direction and luminous flux of ray `i` (`None` for a ray without flux).
    fn get(&self, i: usize) -> Option<(DVec3, DVec3, f64)> {
        let r = self.file.ray(i)?;
        let f = r.luminous_lm? * self.scale;
        let near = (r.position_m - self.centre).length() <= self.reach;
        (f > 0.0 && f.is_finite() && r.position_m.is_finite() && r.direction.is_finite() && near).then_some((
            r.position_m,
            r.direction,
            f,
        ))
    }
}

/// The centre of the ray origins (per-axis median of an even sample of at most 2¹⁶) and the
/// distance beyond which an origin is an outlier: 10 × the 99.9th percentile of the sample's
/// distances from that centre, at least 1 cm.
fn origin_reach(rays: &Rays<'_>) -> (DVec3, f64) {
    let n = rays.len();
    let stride = n.div_ceil(1 << 16).max(1);
    let pts: Vec<DVec3> = (0..n)
        .step_by(stride)
        .filter_map(|i| rays.get(i).map(|r| r.0))
        .collect();
    if pts.is_empty() {
        return (DVec3::ZERO, f64::INFINITY);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let c = DVec3::new(
        median(pts.iter().map(|p| p.x).collect()),
        median(pts.iter().map(|p| p.y).collect()),
        median(pts.iter().map(|p| p.z).collect()),
    );
    let mut d: Vec<f64> = pts.iter().map(|p| (*p - c).length()).collect();
    d.sort_by(f64::total_cmp);
    let q = d[((d.len() - 1) as f64 * 0.999) as usize];
    (c, (10.0 * q).max(0.01))
}

/// Flux-weighted quantiles of `(value, weight)` pairs.
fn spread(mut v: Vec<(f64, f64)>) -> Spread {
    v.retain(|(x, w)| x.is_finite() && *w > 0.0);
    if v.is_empty() {
        return Spread::default();
    }
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = v.iter().map(|p| p.1).sum();
    let at = |q: f64| {
        let mut acc = 0.0;
        for (x, w) in &v {
            acc += w;
            if acc >= q * total {
                return *x;
            }
        }
        v[v.len() - 1].0
    };
    Spread {
        p10: at(0.1),
        median: at(0.5),
        p90: at(0.9),
    }
}

/// Turns a ray file into a virtual scan by kernel density estimation (see the module docs).
/// `progress` receives a stage name and the fraction done.
///
/// # Errors
/// [`NearfieldError::Unsupported`] when the rays carry no luminous flux and none can be derived;
/// [`NearfieldError::InvalidArgument`] for an empty ray set, options out of range, or a layout
/// beyond [`MAX_CAMERAS`](super::MAX_CAMERAS) / [`MAX_TOTAL_PIXELS`].
pub fn estimate(file: &RayFile, opts: &KdeOptions, progress: &(dyn Fn(&str, f64) + Sync)) -> Result<KdeScan> {
    let path = file.path().to_path_buf();
    if matches!(file.luminous_source(), LuminousSource::Unavailable) {
        return Err(NearfieldError::Unsupported {
            path,
            message: "the rays carry radiant flux only and the file gives neither both header fluxes nor any \
                      spectral information, so luminous flux (and luminance) cannot be computed"
                .into(),
        });
    }
    check_options(opts)?;
    let mut warnings = Vec::new();
    let all = Rays {
        file,
        scale: 1.0,
        reach: f64::INFINITY,
        centre: DVec3::ZERO,
    };
    // Where the rays start: the per-axis median of an even sample of the origins, and the 99.9th
    // percentile of their distance from it. Origins beyond 10 times that (and 1 cm) are outliers
    // (one stray ray would otherwise set the image's field of view and empty every image).
    let (centre, reach) = origin_reach(&all);
    let raw = Rays {
        file,
        scale: 1.0,
        reach,
        centre,
    };
    let (sum, sum2, count) = (0..raw.len())
        .into_par_iter()
        .filter_map(|i| raw.get(i))
        .map(|(_, _, f)| (f, f * f, 1u64))
        .reduce(|| (0.0, 0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
    if count == 0 || sum <= 0.0 {
        return Err(NearfieldError::invalid(
            "rays",
            format!("{}: no ray with a positive luminous flux", path.display()),
        ));
    }
    let scale = match opts.ray_flux {
        RayFlux::Header => file.header_scale().map_or(1.0, |h| {
            warnings.push(h.describe(&path));
            h.factor
        }),
        RayFlux::Rays => 1.0,
    };
    let rays = Rays {
        file,
        scale,
        reach,
        centre,
    };
    let flux = sum * scale;
    let n_eff = sum * sum / sum2;
    let outliers = (0..all.len())
        .into_par_iter()
        .filter(|&i| all.get(i).is_some() && raw.get(i).is_none())
        .count();
    if outliers > 0 {
        warnings.push(format!(
            "{}: {outliers} rays start more than {:.6} m from the others' centre (10 × the 99.9th percentile of \
             their distances): left out as outliers",
            path.display(),
            reach
        ));
    }
    if (count as usize) + outliers < raw.len() {
        warnings.push(format!(
            "{}: {} of {} rays carry no usable luminous flux (zero, negative or not finite) and are ignored",
            path.display(),
            raw.len() - count as usize - outliers,
            raw.len()
        ));
    }
    progress("source geometry", 0.0);
    let source = hull::SourceCloud::of(|i| rays.get(i).map(|r| r.0), rays.len());
    let get = |i: usize| rays.get(i);
    let summary = RaySummary {
        n: rays.len(),
        n_eff,
        flux_lm: flux,
    };
    let bw = Bandwidths::choose(&get, summary, opts, &source, &mut warnings, &path)?;
    progress("cameras", 0.1);
    let layout = bw.layout(opts)?;
    let sphere = CaptureSphere {
        centre_m: source.centre,
        radius_m: layout.radius_m,
    };
    let cameras: Vec<Camera> = layout
        .directions
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let h = if d.z < 0.0 {
                Hemisphere::Lower
            } else {
                Hemisphere::Upper
            };
            Camera::on_sphere(&sphere, *d, h, format!("kde {i}"))
        })
        .collect();
    progress("angular kernels", 0.15);
    let cells = bw.cell_rays(&get, rays.len());
    let dirs: Vec<DVec3> = layout.directions.clone();
    let k_s = bw.rays_per_kernel;
    let intrinsics_for = |px: u32| {
        let focal = f64::from(px) / 2.0 / (layout.fov_deg.to_radians() / 2.0).tan();
        Intrinsics {
            width: px,
            height: px,
            principal_px: DVec2::splat(f64::from(px) / 2.0),
            focal_px: DVec2::splat(focal),
        }
    };
    let gather = Gather {
        bw: &bw,
        cells: &cells,
        rays: &get,
        radius_m: layout.radius_m,
    };
    // Image size: given, or from a pilot at 256 px of the brightest directions, so that the finer
    // tenth of the light's kernels spans at least a pixel and a half.
    let px = match opts.image_px {
        Some(p) => p,
        None => {
            let pilot_px = 256;
            let k = intrinsics_for(pilot_px);
            let pixel = layout.radius_m / k.focal_px.x;
            let mut samples = Vec::new();
            for i in bw.brightest_cameras(&dirs, 8) {
                let est = gather.camera(&cameras[i], dirs[i], &k, k_s, None);
                samples.extend(est.4.into_iter().map(|(s, w)| (s * pixel, w)));
            }
            let sigma = spread(samples).p10.max(pixel);
            let half_width = layout.radius_m * (layout.fov_deg.to_radians() / 2.0).tan();
            ((2.0 * half_width * 1.5 / sigma).ceil() as u32).clamp(32, MAX_AUTO_PX)
        }
    };
    let budget = if opts.image_px.is_some() {
        MAX_TOTAL_PIXELS
    } else {
        AUTO_TOTAL_PIXELS
    };
    let px = px
        .min(((budget / cameras.len().max(1) as u64) as f64).sqrt() as u32)
        .max(8);
    let intrinsics = intrinsics_for(px);
    intrinsics.validate("ray file estimate")?;
    let pixel_m = layout.radius_m / intrinsics.focal_px.x;
    let pixel_area = pixel_m * pixel_m;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let m = cameras.len();
    // A source smaller than a capture pixel (a far-field ray file: every ray from one point) has no
    // shape for the spatial kernels to follow: it is spread as a round spot, at the first level
    // that renders round (the rays would choose level 0, a diamond when magnified).
    let point = source.radius < 0.5 * pixel_m;
    let fixed_level = opts
        .spatial_kernel_m
        .map(|s| (s / pixel_m / LEVEL_SIGMA_PX).log2().max(0.0))
        .or(point.then_some(POINT_LEVEL));
    progress("estimating", 0.2);
    let per_camera: Vec<CameraEstimate> = cameras
        .par_iter()
        .enumerate()
        .map(|(i, cam)| {
            let mut est = gather.camera(cam, dirs[i], &intrinsics, k_s, fixed_level);
            if !opts.keep_kernel_levels {
                // As large as the image: held for every camera only when an evaluation asks.
                est.1 = Vec::new();
            }
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n.is_multiple_of(16) {
                progress("estimating", 0.2 + 0.7 * n as f64 / m as f64);
            }
            est
        })
        .collect();
    // The rays' index by direction (4 bytes a ray) is not read again.
    drop(cells);
    // Flux held by the images, with each camera's Voronoi solid angle.
    let lookup = NearestDirection::new(&dirs);
    let (omega, _) = lookup.solid_angles();
    let flux_images: f64 = per_camera
        .iter()
        .zip(&omega)
        .map(|((img, ..), o)| img.data.iter().map(|v| f64::from(*v)).sum::<f64>() * o)
        .sum();
    // The continuous estimate holds every ray's flux (normalised kernels); the cameras sample it,
    // and their Voronoi quadrature of it is a check on the layout, not a correction.
    let quadrature = flux_images / flux;
    if !(0.8..=1.2).contains(&quadrature) {
        warnings.push(format!(
            "{}: the cameras' quadrature holds {:.1} % of the rays' flux: the layout is coarse for the angular kernel",
            path.display(),
            100.0 * quadrature
        ));
    }
    let mut images = Vec::with_capacity(m);
    let mut levels = Vec::with_capacity(m);
    let mut h_a = Vec::with_capacity(m);
    let mut h_f = Vec::with_capacity(m);
    let mut undersampled = 0u64;
    let mut lit = 0usize;
    let mut spatial_samples = Vec::new();
    for (img, level, under, h_cam, mass_sigma) in per_camera {
        let mut img = img;
        for v in &mut img.data {
            *v = (f64::from(*v) / pixel_area) as f32;
        }
        if img.data.iter().any(|v| *v > 0.0) {
            lit += 1;
        }
        spatial_samples.extend(mass_sigma.into_iter().map(|(s, w)| (s * pixel_m, w)));
        undersampled += under;
        h_a.push(h_cam.0);
        h_f.push(h_cam.1);
        images.push(img);
        if opts.keep_kernel_levels {
            levels.push(level);
        }
    }
    let widths = bw.widths();
    let angular_spread = spread(widths.iter().map(|(_, h, w)| (h.to_degrees(), *w)).collect());
    let footprint_spread = spread(widths.iter().map(|(h, _, w)| (h.to_degrees(), *w)).collect());
    let spatial_spread = spread(spatial_samples);
    if undersampled > 0 {
        warnings.push(format!(
            "{}: {undersampled} lit pixels in cameras holding fewer than {k_s:.0} rays: their kernel is the whole \
             image (too few rays for the requested detail in those directions)",
            path.display()
        ));
    }
    progress("proxy", 0.95);
    let min_grow_px = match fixed_level {
        Some(l) => (FIXED_REACH_SIGMAS * LEVEL_SIGMA_PX * 2f64.powf(l) + 1.0).max(PROXY_MIN_GROW_PX),
        None => PROXY_MIN_GROW_PX,
    };
    let grow = (2.0 * spatial_spread.p90).max(min_grow_px * pixel_m);
    let proxy = source.proxy(grow, "ray origins, grown by two spatial kernels");
    let report = KdeReport {
        rays: raw.len() as u64,
        effective_rays: n_eff,
        flux_lm: flux,
        rays_per_kernel: k_s,
        rays_per_angular_kernel: bw.rays_per_angular_kernel,
        rays_per_intensity_kernel: bw.rays_per_intensity_kernel,
        angular_kernel_deg: angular_spread,
        footprint_kernel_deg: footprint_spread,
        spatial_kernel_m: spatial_spread,
        cameras: m,
        cameras_lit: lit,
        image_px: px,
        fov_deg: layout.fov_deg,
        pixel_m,
        radius_m: layout.radius_m,
        source_radius_m: source.radius,
        flux_from_images_lm: flux_images,
        undersampled_pixels: undersampled,
        warnings,
    };
    let set = RayImageSet {
        sphere,
        intrinsics,
        cameras,
    };
    set.validate()?;
    progress("done", 1.0);
    Ok(KdeScan {
        scan: Scan {
            set,
            source: Box::new(MemorySource { images }),
        },
        report,
        proxy,
        kernels: KernelMaps {
            angular_rad: h_a,
            footprint_rad: h_f,
            level: levels,
            pixel_m,
        },
        frozen: FrozenKernels {
            bw,
            directions: dirs,
            radius_m: layout.radius_m,
        },
    })
}
