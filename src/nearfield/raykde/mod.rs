//! Ray files as light fields: a kernel density estimate of the luminance a TM-25 ray set implies,
//! laid out as the images of a virtual near-field scan (so the near-field renderer draws it from any
//! eye), with a proxy built from the ray origins.
//!
//! A ray set is a sample of the light field: ray r leaves point `x_r` in direction `k_r` carrying
//! flux Φ_r, drawn (in a measurement) with density ∝ the luminance L(x, k) in line space. Camera i
//! (direction `d_i` on a virtual capture sphere, pinhole projection `π_i`) gets the image
//!
//! ```text
//!   L_i(u) = I_i · S_i(u) / A_px
//!   I_i    = Σ_r Φ_r · K_a(∠(k_r, d_i); h_I,r)                                (cd)
//!   S_i(u) = Σ_r Φ_r · K_a(∠(k_r, d_i); h_S,r) · K_s(u − π_i(x_r); σ) · (r_s / z_r)²  / Σ_r Φ_r · K_a(…; h_S,r)
//! ```
//!
//! a fine **intensity** times a normalised **footprint** pooled from a wider angular window.
//! `K_a(θ; h)` is a spherical Epanechnikov kernel normalised over the sphere (1/sr), `K_s` the
//! spatial kernel of an image pyramid ([`pyramid`]), `A_px` a pixel's footprint on the plane through
//! the sphere's centre and `(r_s / z_r)²` corrects it to the ray's depth. The ray's **origin**, on
//! the emitting surface, is where the camera sees its light.
//!
//! **Bandwidths** follow the data ([`bandwidth`]), each ray carrying the widths of its own direction
//! (sample-point estimators: every kernel normalised per ray, the flux kept). With N_eff effective
//! rays (Σ Φ)²/Σ Φ²: the intensity width holds k_I = 0.5·N_eff^(2/3) rays (a 2-D density's rate,
//! width ∝ N^(−1/6)); the spatial kernel holds k_s = 8·√N_eff rays per pixel neighbourhood (noise
//! ~1/√k_s, σ ∝ N^(−1/8), a 4-D density's rate) at the finest pyramid level that reaches them; the
//! footprint pool holds k_S = √(k_s·N_eff) rays. Cameras sit about 0.7 intensity widths apart. The
//! widths chosen are reported ([`KdeReport`]) and kept ([`KernelMaps`]) so a reference can be
//! convolved with the same kernels (docs/quality-metrics.md, "Ray files"); docs/rayfiles.md has the
//! rules and the measured figures.

pub mod bandwidth;
pub mod hull;
pub mod pyramid;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use self::bandwidth::{angular_kernel, Bandwidths, RayGet, RaySummary};
use self::pyramid::{Pyramid, LEVEL_SIGMA_PX};
use super::binning::NearestDirection;
use super::error::{NearfieldError, Result};
use super::rayset::{Camera, CaptureSphere, Hemisphere, Intrinsics, LuminanceImage, MemorySource, RayImageSet, Scan};
use super::synth::proxy::ProxyMesh;
use super::tm25::{LuminousSource, RayFile};

/// Upper bound on the pixels of all images together (2²⁶ f32 = 256 MiB, as for binning).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 26;

/// Largest image side chosen automatically (px).
pub const MAX_AUTO_PX: u32 = 256;

/// Pixels of all images together when the size is chosen automatically (2²⁴ f32 = 64 MiB).
pub const AUTO_TOTAL_PIXELS: u64 = 1 << 24;

/// Most virtual cameras.
pub const MAX_CAMERAS: usize = 20_000;

/// Default rays per spatial kernel: k_s = `DEFAULT_B` · √N_eff.
pub const DEFAULT_B: f64 = 8.0;

/// Default rays per intensity kernel: k_I = `DEFAULT_BI` · N_eff^(2/3) (a 2-D estimate's rate).
pub const DEFAULT_BI: f64 = 0.5;

/// Most virtual cameras chosen automatically.
pub const MAX_AUTO_CAMERAS: usize = 6000;

/// Choices; everything `None` is chosen from the data.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct KdeOptions {
    /// Rays per spatial kernel k_s (default `DEFAULT_B` · √N_eff).
    pub rays_per_kernel: Option<f64>,
    /// Rays per intensity kernel k_I (default `DEFAULT_BI` · N_eff^(2/3)).
    pub rays_per_intensity_kernel: Option<f64>,
    /// A fixed intensity kernel half-width (degrees) instead of the k-nearest-neighbour one.
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
    /// Keep the spatial kernel level of every pixel ([`KernelMaps::level`], as much memory as the
    /// images), which [`estimate_frozen`] needs; otherwise they are dropped camera by camera.
    pub keep_kernel_levels: bool,
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
    /// Rays per footprint kernel k_S (the angular pool of the spatial estimate).
    pub rays_per_angular_kernel: f64,
    /// Rays per intensity kernel k_I.
    pub rays_per_intensity_kernel: f64,
    /// Intensity kernel half-width of the rays (degrees; weighted by their flux).
    pub angular_kernel_deg: Spread,
    /// Footprint kernel half-width of the rays (degrees): how far apart in direction the rays that
    /// shape one camera's image may travel.
    pub footprint_kernel_deg: Spread,
    /// Spatial kernel σ of the light (metres; weighted by the flux each pixel spreads).
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
    /// Σ L·A·Ω over the cameras with their Voronoi solid angles (lm): the layout's quadrature of
    /// the estimate, which itself holds the rays' flux.
    pub flux_from_images_lm: f64,
    /// Pixels whose kernel reached the whole image without k_s rays (under-sampled cameras).
    pub undersampled_pixels: u64,
    /// What the user should know.
    pub warnings: Vec<String>,
}

/// The kernel widths used, per camera and pixel, for kernel-matched references.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelMaps {
    /// Weighted intensity half-width of the rays each camera gathered (radians; each ray carries
    /// the width of its own direction: a sample-point estimator).
    pub angular_rad: Vec<f64>,
    /// Weighted footprint half-width of the rays each camera's image was shaped from (radians).
    pub footprint_rad: Vec<f64>,
    /// Spatial kernel level per camera and pixel, row-major like the images: σ =
    /// [`LEVEL_SIGMA_PX`] · 2^level pixels ([`KernelMaps::spatial_m`]). Empty unless
    /// [`KdeOptions::keep_kernel_levels`] was set.
    pub level: Vec<Vec<f32>>,
    /// Pixel size on the object plane (m).
    pub pixel_m: f64,
}

impl KernelMaps {
    /// Spatial σ of camera `i`'s pixels (metres), row-major like the images; empty for no camera.
    pub fn spatial_m(&self, i: usize) -> Vec<f32> {
        self.level.get(i).map_or_else(Vec::new, |l| {
            l.iter()
                .map(|v| (LEVEL_SIGMA_PX * 2f64.powf(f64::from(*v)) * self.pixel_m) as f32)
                .collect()
        })
    }
}

/// One camera's image, its kernel level per pixel, its under-sampled pixels, the weighted intensity
/// and footprint widths of the rays it gathered (rad), and (σ in px, weight) of its lit pixels.
type CameraEstimate = (LuminanceImage, Vec<f32>, u64, (f64, f64), Vec<(f64, f64)>);

/// What every camera's estimate reads.
struct Gather<'a> {
    bw: &'a Bandwidths,
    cells: &'a bandwidth::CellRays,
    rays: RayGet<'a>,
    /// Capture radius (m): the depth at which a pixel's footprint is `A_px`.
    radius_m: f64,
}

/// What one camera has gathered: the splatted image and the sums of its angular kernels.
struct CameraAcc {
    pyr: Pyramid,
    /// Σ flux × intensity kernel (lm/sr).
    intensity: f64,
    /// Σ weight × intensity width, Σ weight (for the camera's mean intensity width).
    ih: f64,
    iw: f64,
    /// The same for the footprint widths.
    fh: f64,
    fw: f64,
    /// Σ footprint weight of the rays that landed in the image.
    w_in: f64,
}

/// How a camera's spatial kernels are chosen.
enum Levels<'a> {
    /// From its own rays: k_s per kernel, or one fixed level.
    Choose { k_s: f64, fixed: Option<f64> },
    /// Given per pixel (another estimate's).
    Given(&'a [f32]),
}

impl CameraAcc {
    fn new(px: u32) -> Self {
        Self {
            pyr: Pyramid::new(px),
            intensity: 0.0,
            ih: 0.0,
            iw: 0.0,
            fh: 0.0,
            fw: 0.0,
            w_in: 0.0,
        }
    }

    /// The image as Σ flux × angular kernel per pixel (lm/sr; divide by the pixel's footprint for
    /// cd/m²) and the kernel level per pixel.
    fn finish(self, levels: Levels<'_>) -> CameraEstimate {
        let px = self.pyr.side_px();
        let est = match levels {
            Levels::Choose { k_s, fixed } => self.pyr.estimate(k_s, fixed),
            Levels::Given(l) => self.pyr.estimate_at(l),
        };
        // Normalised so that Σ L · A_px(z) over the image is the intensity.
        let scale = if self.w_in > 0.0 {
            self.intensity / self.w_in
        } else {
            0.0
        };
        let image = LuminanceImage {
            width: px,
            height: px,
            data: est.density.iter().map(|w| (*w * scale) as f32).collect(),
        };
        let h_cam = if self.iw > 0.0 { self.ih / self.iw } else { 0.0 };
        let f_cam = if self.fw > 0.0 { self.fh / self.fw } else { 0.0 };
        let mass = est.mass_sigma.into_iter().map(|(s, w)| (s, w * scale)).collect();
        (image, est.level, est.undersampled, (h_cam, f_cam), mass)
    }
}

impl Gather<'_> {
    /// Adds the rays reaching one camera (direction `dir` from the sphere's centre, intrinsics
    /// `k`) to what it has gathered.
    fn gather(&self, acc: &mut CameraAcc, cam: &Camera, dir: DVec3, k: &Intrinsics) {
        // The intensity (lm/sr) from the intensity kernels; the footprint from the wider pool.
        for (r, h, hi) in self.bw.rays_reaching(self.cells, dir) {
            let Some((x, kd, f)) = (self.rays)(r as usize) else {
                continue;
            };
            let theta = kd.dot(dir).clamp(-1.0, 1.0).acos();
            if theta < hi {
                let w = f * (1.0 - (theta / hi).powi(2)) * angular_kernel(hi);
                acc.intensity += w;
                acc.ih += w * hi;
                acc.iw += w;
            }
            if theta >= h {
                continue;
            }
            let a = 1.0 - (theta / h).powi(2);
            let xc = cam.to_camera(x - cam.position_m);
            let Some(uv) = k.project(xc) else {
                continue;
            };
            let w = f * a * angular_kernel(h);
            // A pixel's footprint at the ray's depth z is A_px · (z / r_s)²: the light spreads over
            // that, so it counts (r_s / z)² towards the luminance.
            let depth = (self.radius_m / xc.z.max(1e-9)).powi(2);
            if acc.pyr.splat(uv, w * depth, a) {
                acc.w_in += w;
            }
            acc.fh += w * h;
            acc.fw += w;
        }
    }

    /// The estimate of one camera with its own kernels.
    fn camera(&self, cam: &Camera, dir: DVec3, k: &Intrinsics, k_s: f64, fixed: Option<f64>) -> CameraEstimate {
        let mut acc = CameraAcc::new(k.width);
        self.gather(&mut acc, cam, dir, k);
        acc.finish(Levels::Choose { k_s, fixed })
    }
}

/// The kernels an estimate chose, kept so that the same operator can be applied to other rays
/// ([`estimate_frozen`]): the angular widths as a function of a ray's direction, the cameras'
/// directions and the capture radius (the spatial levels per pixel are in [`KernelMaps`]).
#[derive(Debug, Clone)]
pub struct FrozenKernels {
    bw: Bandwidths,
    directions: Vec<DVec3>,
    radius_m: f64,
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
    /// The kernels, for applying the same estimate to other rays.
    pub frozen: FrozenKernels,
}

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
    let fixed_level = opts
        .spatial_kernel_m
        .map(|s| (s / pixel_m / LEVEL_SIGMA_PX).log2().max(0.0));
    progress("estimating", 0.2);
    let per_camera: Vec<CameraEstimate> = cameras
        .par_iter()
        .enumerate()
        .map(|(i, cam)| {
            let est = gather.camera(cam, dirs[i], &intrinsics, k_s, fixed_level);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n.is_multiple_of(16) {
                progress("estimating", 0.2 + 0.7 * n as f64 / m as f64);
            }
            est
        })
        .collect();
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
    let grow = (2.0 * spatial_spread.p90).max(3.0 * pixel_m);
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
    pos("rays-per-intensity-kernel", o.rays_per_intensity_kernel, 1.0, 1e9)?;
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
