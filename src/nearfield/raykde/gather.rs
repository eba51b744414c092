//! What one virtual camera gathers: the rays its angular kernels reach, weighted and splatted into
//! its image pyramid, and the image and kernel widths it turns into (used by [`super::estimate`]
//! and [`super::estimate_frozen`]).

use glam::DVec3;

use super::bandwidth::{self, angular_kernel, Bandwidths, RayGet};
use super::pyramid::Pyramid;
use crate::nearfield::rayset::{Camera, Intrinsics, LuminanceImage};

/// One camera's image, its kernel level per pixel, its under-sampled pixels, the weighted intensity
/// and footprint widths of the rays it gathered (rad), and (σ in px, weight) of its lit pixels.
pub(super) type CameraEstimate = (LuminanceImage, Vec<f32>, u64, (f64, f64), Vec<(f64, f64)>);

/// What every camera's estimate reads.
pub(super) struct Gather<'a> {
    pub(super) bw: &'a Bandwidths,
    pub(super) cells: &'a bandwidth::CellRays,
    pub(super) rays: RayGet<'a>,
    /// Capture radius (m): the depth at which a pixel's footprint is `A_px`.
    pub(super) radius_m: f64,
}

/// What one camera has gathered: the splatted image and the sums of its angular kernels.
pub(super) struct CameraAcc {
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
pub(super) enum Levels<'a> {
    /// From its own rays: k_s per kernel, or one fixed level.
    Choose { k_s: f64, fixed: Option<f64> },
    /// Given per pixel (another estimate's).
    Given(&'a [f32]),
}

impl CameraAcc {
    pub(super) fn new(px: u32) -> Self {
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
    pub(super) fn finish(self, levels: Levels<'_>) -> CameraEstimate {
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
    pub(super) fn gather(&self, acc: &mut CameraAcc, cam: &Camera, dir: DVec3, k: &Intrinsics) {
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
    pub(super) fn camera(
        &self,
        cam: &Camera,
        dir: DVec3,
        k: &Intrinsics,
        k_s: f64,
        fixed: Option<f64>,
    ) -> CameraEstimate {
        let mut acc = CameraAcc::new(k.width);
        self.gather(&mut acc, cam, dir, k);
        acc.finish(Levels::Choose { k_s, fixed })
    }
}
