//! Ray files as light fields: a kernel density estimate of the luminance a TM-25 ray set implies,
//! laid out as the images of a virtual near-field scan (so the near-field renderer draws it from any
//! eye), with a proxy built from the ray origins.
//!
//! A ray set is a sample of the light field: ray r leaves point `x_r` in direction `k_r` carrying
//! flux Φ_r, drawn (in a measurement) with density ∝ the luminance L(x, k) in line space. The
//! estimate at camera i (direction `d_i` on a virtual capture sphere) and image point u is
//!
//! ```text
//!   L̂_i(u) = Σ_r Φ_r · K_a(∠(k_r, d_i); h_a,i) · K_s(u − π_i(x_r); h_s(u)) / A_px
//! ```
//!
//! with `π_i` the camera's pinhole projection (the ray's origin, which lies on the emitting surface,
//! is where camera i sees its light), `K_a` a normalised spherical Epanechnikov kernel (1/sr) and
//! `K_s` a normalised spatial kernel (1/px), `A_px` a pixel's footprint (m²): lm/(sr·m²) = cd/m².
//!
//! **Bandwidths** follow the data ([`bandwidth`]): with N_eff effective rays (Σ Φ)²/Σ Φ², a kernel
//! holds k_s = B·√N_eff rays (B = 8 by default), so each estimate averages about k_s rays (noise
//! ~ 1/√k_s) while both widths shrink as N_eff^(−1/8), the rate of a 4-D density estimate. The
//! angular width at camera i is the k-nearest-neighbour angle holding k_a = √(k_s·N_eff) rays
//! (the same share of the directions as k_s is of those rays' positions), capped at 3× the
//! flux-weighted median; the spatial width at pixel u is the smallest level of an image pyramid whose
//! neighbourhood of u holds k_s of the camera's rays ([`pyramid`]). Both are adaptive: dense
//! directions and bright spots get narrow kernels, sparse ones wide kernels. Cameras are placed
//! where the angular kernel needs them (spacing about half of it), so the renderer's interpolation
//! between cameras adds little blur. The estimate conserves flux up to kernel tails outside the
//! images; the remainder is corrected globally and reported.
//!
//! The widths chosen are reported ([`KdeReport`]) and kept per camera and pixel ([`KernelMaps`]) so
//! a reference can be convolved with the same kernel (docs/quality-metrics.md, ray files).

pub mod bandwidth;
pub mod hull;
pub mod pyramid;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use self::bandwidth::{angular_kernel, Bandwidths, RaySummary};
use self::pyramid::{Pyramid, LEVEL_SIGMA_PX};
use super::binning::NearestDirection;
use super::error::{NearfieldError, Result};
use super::rayset::{Camera, CaptureSphere, Hemisphere, Intrinsics, LuminanceImage, MemorySource, RayImageSet, Scan};
use super::synth::proxy::ProxyMesh;
use super::tm25::{LuminousSource, RayFile};

/// Upper bound on the pixels of all images together (2²⁶ f32 = 256 MiB, as for binning).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 26;

/// Most virtual cameras.
pub const MAX_CAMERAS: usize = 20_000;

/// Default rays per kernel: k_s = `DEFAULT_B` · √N_eff.
pub const DEFAULT_B: f64 = 8.0;

/// Choices; everything `None` is chosen from the data.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KdeOptions {
    /// Rays per kernel k_s (default `DEFAULT_B` · √N_eff).
    pub rays_per_kernel: Option<f64>,
    /// A fixed angular kernel half-width (degrees) instead of the k-nearest-neighbour one.
    pub angular_kernel_deg: Option<f64>,
    /// A fixed spatial kernel σ (metres) instead of the pyramid's adaptive one.
    pub spatial_kernel_m: Option<f64>,
    /// Number of virtual cameras (default: from the angular kernel).
    pub cameras: Option<usize>,
    /// Image size in pixels (square; default: from the spatial kernel and the source's size).
    pub image_px: Option<u32>,
    /// Capture sphere radius in metres (default max(1.1 m, 8 × the source's radius)).
    pub radius_m: Option<f64>,
    /// Scale the rays' luminous fluxes to sum to the header's luminous flux.
    pub scale_to_header_flux: bool,
}

/// Three quantiles of a reported width.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Spread {
    /// 10th percentile (flux-weighted).
    pub p10: f64,
    /// Median (flux-weighted).
    pub median: f64,
    /// 90th percentile (flux-weighted).
    pub p90: f64,
}

/// What the estimate did, for the user to judge what the data supports.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct KdeReport {
    /// Rays in the file.
    pub rays: u64,
    /// Effective number of rays, (Σ Φ)² / Σ Φ² (= `rays` for equal-flux rays).
    pub effective_rays: f64,
    /// Σ luminous flux of the rays after any scaling (lm).
    pub flux_lm: f64,
    /// Rays per spatial kernel k_s.
    pub rays_per_kernel: f64,
    /// Rays per angular kernel k_a.
    pub rays_per_angular_kernel: f64,
    /// Angular kernel half-width over the lit cameras (degrees).
    pub angular_kernel_deg: Spread,
    /// Spatial kernel σ over the lit pixels (metres).
    pub spatial_kernel_m: Spread,
    /// Virtual cameras.
    pub cameras: usize,
    /// Cameras whose image holds light.
    pub cameras_lit: usize,
    /// Image size (px, square).
    pub image_px: u32,
    /// Full field of view (degrees).
    pub fov_deg: f64,
    /// Pixel size on the object plane (m).
    pub pixel_m: f64,
    /// Capture sphere radius (m).
    pub radius_m: f64,
    /// Radius of the ray origins about their centre (m).
    pub source_radius_m: f64,
    /// Σ L·A·Ω over all images before the flux correction (lm).
    pub flux_from_images_lm: f64,
    /// Factor applied to every image so that they hold the rays' flux (1 = nothing lost).
    pub flux_correction: f64,
    /// Pixels whose kernel reached the whole image without k_s rays (under-sampled cameras).
    pub undersampled_pixels: u64,
    /// What the user should know.
    pub warnings: Vec<String>,
}

/// The kernel widths used, per camera and pixel, for kernel-matched references.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelMaps {
    /// Angular half-width per camera (radians).
    pub angular_rad: Vec<f64>,
    /// Spatial σ per camera and pixel (metres), row-major like the images.
    pub spatial_m: Vec<Vec<f32>>,
}

/// A ray set turned into a virtual scan.
#[derive(Debug)]
pub struct KdeScan {
    /// Cameras, intrinsics and images.
    pub scan: Scan,
    /// What was chosen and measured.
    pub report: KdeReport,
    /// The convex hull of the ray origins, grown by the spatial kernel (luminaire frame, m).
    pub proxy: ProxyMesh,
    /// The kernel widths.
    pub kernels: KernelMaps,
}

/// The rays of a file as plain numbers (metres, unit directions, lm), in file order.
struct Rays<'a> {
    file: &'a RayFile,
    scale: f64,
}

impl Rays<'_> {
    fn len(&self) -> usize {
        self.file.len()
    }

    /// Origin, direction and luminous flux of ray `i` (`None` for a ray without flux).
    fn get(&self, i: usize) -> Option<(DVec3, DVec3, f64)> {
        let r = self.file.ray(i)?;
        let f = r.luminous_lm? * self.scale;
        (f > 0.0 && f.is_finite() && r.position_m.is_finite() && r.direction.is_finite()).then_some((
            r.position_m,
            r.direction,
            f,
        ))
    }
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
/// beyond [`MAX_CAMERAS`] / [`MAX_TOTAL_PIXELS`].
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
    let raw = Rays { file, scale: 1.0 };
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
    let scale = if opts.scale_to_header_flux {
        match file.header().luminous_flux_lm {
            Some(h) if h > 0.0 => h / sum,
            _ => {
                return Err(NearfieldError::invalid(
                    "scale-to-header-flux",
                    format!("{}: needs a positive header luminous flux", path.display()),
                ))
            }
        }
    } else {
        1.0
    };
    let rays = Rays { file, scale };
    let flux = sum * scale;
    let n_eff = sum * sum / sum2;
    if (count as usize) < raw.len() {
        warnings.push(format!(
            "{}: {} of {} rays carry no usable luminous flux (zero, negative or not finite) and are ignored",
            path.display(),
            raw.len() - count as usize,
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
    let px = layout.image_px;
    let total_px = u64::from(px) * u64::from(px) * cameras.len() as u64;
    if total_px > MAX_TOTAL_PIXELS {
        return Err(NearfieldError::invalid(
            "image-px",
            format!(
                "{} cameras × {px}² px = {total_px} pixels exceed the in-memory limit of {MAX_TOTAL_PIXELS}",
                cameras.len()
            ),
        ));
    }
    let focal = f64::from(px) / 2.0 / (layout.fov_deg.to_radians() / 2.0).tan();
    let intrinsics = Intrinsics {
        width: px,
        height: px,
        principal_px: DVec2::splat(f64::from(px) / 2.0),
        focal_px: DVec2::splat(focal),
    };
    intrinsics.validate("ray file estimate")?;
    let pixel_m = layout.radius_m / focal;
    let pixel_area = pixel_m * pixel_m;
    // Which rays each camera gathers: by fine direction cell.
    progress("angular kernels", 0.2);
    let cells = bw.cell_rays(&get, rays.len());
    let dirs: Vec<DVec3> = layout.directions.clone();
    let h_a: Vec<f64> = dirs.iter().map(|d| bw.angular_at(*d, opts)).collect();
    let k_s = bw.rays_per_kernel;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let m = cameras.len();
    let per_camera: Vec<(LuminanceImage, Vec<f32>, u64, f64)> = cameras
        .par_iter()
        .enumerate()
        .map(|(i, cam)| {
            let (kernel_norm, h) = (angular_kernel(h_a[i]), h_a[i]);
            let mut pyr = Pyramid::new(px);
            for r in bw.cells_within(&cells, dirs[i], h) {
                let Some((x, k, f)) = rays.get(r as usize) else {
                    continue;
                };
                let cos = k.dot(dirs[i]).clamp(-1.0, 1.0);
                let theta = cos.acos();
                if theta >= h {
                    continue;
                }
                let a = 1.0 - (theta / h).powi(2);
                let Some(uv) = intrinsics.project(cam.to_camera(x - cam.position_m)) else {
                    continue;
                };
                pyr.splat(uv, f * a * kernel_norm, a);
            }
            let fixed_level = opts
                .spatial_kernel_m
                .map(|s| (s / pixel_m / LEVEL_SIGMA_PX).log2().max(0.0));
            let est = pyr.estimate(k_s, fixed_level);
            let image = LuminanceImage {
                width: px,
                height: px,
                data: est.density.iter().map(|w| (*w / pixel_area) as f32).collect(),
            };
            let sigma: Vec<f32> = est
                .level
                .iter()
                .map(|l| (LEVEL_SIGMA_PX * 2f64.powf(f64::from(*l)) * pixel_m) as f32)
                .collect();
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n % 64 == 0 {
                progress("estimating", 0.2 + 0.7 * n as f64 / m as f64);
            }
            (image, sigma, est.undersampled, est.total)
        })
        .collect();
    // Flux held by the images, with each camera's Voronoi solid angle.
    let lookup = NearestDirection::new(&dirs);
    let (omega, _) = lookup.solid_angles();
    let flux_images: f64 = per_camera
        .iter()
        .zip(&omega)
        .map(|((img, ..), o)| img.data.iter().map(|v| f64::from(*v)).sum::<f64>() * pixel_area * o)
        .sum();
    let correction = if flux_images > 0.0 { flux / flux_images } else { 1.0 };
    if !(0.9..=1.1).contains(&correction) {
        warnings.push(format!(
            "{}: the kernel estimate held {:.1} % of the rays' flux before correction (kernels reaching past the \
             images or the capture sphere's cameras too sparse for the angular kernel)",
            path.display(),
            100.0 / correction
        ));
    }
    let mut images = Vec::with_capacity(m);
    let mut sigmas = Vec::with_capacity(m);
    let mut undersampled = 0u64;
    let mut lit = 0usize;
    let mut spatial_samples = Vec::new();
    for (img, sigma, under, _) in per_camera {
        let mut img = img;
        for v in &mut img.data {
            *v = (f64::from(*v) * correction) as f32;
        }
        if img.data.iter().any(|v| *v > 0.0) {
            lit += 1;
        }
        for (v, s) in img.data.iter().zip(&sigma).step_by(7) {
            if *v > 0.0 {
                spatial_samples.push((f64::from(*s), f64::from(*v)));
            }
        }
        undersampled += under;
        images.push(img);
        sigmas.push(sigma);
    }
    let cam_light: Vec<f64> = images
        .iter()
        .map(|i| i.data.iter().map(|v| f64::from(*v)).sum::<f64>())
        .collect();
    let angular_spread = spread(h_a.iter().zip(&cam_light).map(|(h, w)| (h.to_degrees(), *w)).collect());
    let spatial_spread = spread(spatial_samples);
    if undersampled > 0 {
        warnings.push(format!(
            "{}: {undersampled} lit pixels in cameras holding fewer than {k_s:.0} rays: their kernel is the whole \
             image (too few rays for the requested detail in those directions)",
            path.display()
        ));
    }
    progress("proxy", 0.95);
    let grow = 2.0 * spatial_spread.p90.max(pixel_m);
    let proxy = source.proxy(grow, "ray origins, grown by two spatial kernels");
    let report = KdeReport {
        rays: raw.len() as u64,
        effective_rays: n_eff,
        flux_lm: flux,
        rays_per_kernel: k_s,
        rays_per_angular_kernel: bw.rays_per_angular_kernel,
        angular_kernel_deg: angular_spread,
        spatial_kernel_m: spatial_spread,
        cameras: m,
        cameras_lit: lit,
        image_px: px,
        fov_deg: layout.fov_deg,
        pixel_m,
        radius_m: layout.radius_m,
        source_radius_m: source.radius,
        flux_from_images_lm: flux_images,
        flux_correction: correction,
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
            spatial_m: sigmas,
        },
    })
}

fn check_options(o: &KdeOptions) -> Result<()> {
    let pos = |name: &'static str, v: Option<f64>, lo: f64, hi: f64| -> Result<()> {
        match v {
            Some(x) if !(x.is_finite() && x >= lo && x <= hi) => {
                Err(NearfieldError::invalid(name, format!("{x} is outside {lo}…{hi}")))
            }
            _ => Ok(()),
        }
    };
    pos("rays-per-kernel", o.rays_per_kernel, 1.0, 1e9)?;
    pos("angular-kernel", o.angular_kernel_deg, 0.01, 90.0)?;
    pos("spatial-kernel", o.spatial_kernel_m, 1e-9, 10.0)?;
    pos("radius", o.radius_m, 1e-4, 1e4)?;
    if let Some(c) = o.cameras {
        if !(12..=MAX_CAMERAS).contains(&c) {
            return Err(NearfieldError::invalid(
                "cameras",
                format!("{c} is outside 12…{MAX_CAMERAS}"),
            ));
        }
    }
    if let Some(p) = o.image_px {
        if !(8..=1024).contains(&p) {
            return Err(NearfieldError::invalid("image-px", format!("{p} is outside 8…1024")));
        }
    }
    Ok(())
}
