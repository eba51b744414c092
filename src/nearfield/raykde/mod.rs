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
//! width ∝ N^(−1/6)); the spatial kernel holds k_s = 4·√N_eff rays per pixel neighbourhood (noise
//! ~1/√k_s, σ ∝ N^(−1/8), a 4-D density's rate) at the finest pyramid level that reaches them; the
//! footprint pool holds k_S = √(k_s·N_eff) rays. Cameras sit about 0.7 intensity widths apart. The
//! widths chosen are reported ([`KdeReport`]) and kept ([`KernelMaps`]) so a reference can be
//! convolved with the same kernels (docs/quality-metrics.md, "Ray files"); docs/rayfiles.md has the
//! rules and the measured figures.
//!
//! - `virtual_scan.rs`: [`estimate`], a ray file to a virtual scan (the rays, their outliers, the
//!   layout, the image size, the report);
//! - `gather.rs`: what one camera gathers: the rays its kernels reach, splatted into its pyramid;
//! - `frozen.rs`: [`estimate_frozen`], the same kernels applied to other rays (kernel-matched truth);
//! - `bandwidth.rs`, `pyramid.rs`, `hull.rs`: the kernel widths, the spatial estimate, the proxy.

pub mod bandwidth;
mod frozen;
mod gather;
pub mod hull;
pub mod pyramid;
mod virtual_scan;

use glam::DVec3;

pub use self::frozen::{estimate_frozen, RayBatch};
pub use self::virtual_scan::estimate;

use self::bandwidth::Bandwidths;
use self::pyramid::LEVEL_SIGMA_PX;
use super::error::{NearfieldError, Result};
use super::rayset::Scan;
use super::synth::proxy::ProxyMesh;
use super::tm25::RayFlux;

/// Upper bound on the pixels of all images together (2²⁶ f32 = 256 MiB, as for binning).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 26;

/// Largest image side chosen automatically (px).
pub const MAX_AUTO_PX: u32 = 256;

/// Pixels of all images together when the size is chosen automatically (2²⁴ f32 = 64 MiB).
pub const AUTO_TOTAL_PIXELS: u64 = 1 << 24;

/// Most virtual cameras.
pub const MAX_CAMERAS: usize = 20_000;

/// Default rays per spatial kernel: k_s = `DEFAULT_B` · √N_eff (8 until 2026-11-27, which
/// over-smoothed: docs/rayfiles.md, "Convergence").
pub const DEFAULT_B: f64 = 4.0;

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
    /// What the rays' flux values mean: scaled to the header's total where it states one (the
    /// default), or the rays' own values.
    pub ray_flux: RayFlux,
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
