//! The binning pass: every ray to its nearest camera and the pixel where it crosses that camera's
//! object plane, luminance from the summed flux per pixel, and a report of what was used and dropped.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::nearest::NearestDirection;
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::layout::{self, Layout};
use crate::nearfield::rayset::{CaptureSphere, Intrinsics, LuminanceImage, MemorySource, RayImageSet, Scan};
use crate::nearfield::tm25::{LuminousSource, Ray, RayFile, RayFlux};

/// Upper bound on the pixels of all binned images together (2²⁶ f32 = 256 MiB).
pub const MAX_TOTAL_PIXELS: u64 = 1 << 26;

/// How to bin: the virtual capture sphere, camera layout and image geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct BinningOptions {
    /// The capture sphere (luminaire frame = the ray file's frame, metres).
    pub sphere: CaptureSphere,
    /// Camera layout on the sphere.
    pub layout: Layout,
    /// Seed of the layout (jitter of `rigo`).
    pub seed: u64,
    /// Image width (px).
    pub width: u32,
    /// Image height (px).
    pub height: u32,
    /// Full horizontal field of view (degrees, square pixels); `None` fits the widest object-plane
    /// crossing of any ray (+2 %) into the image.
    pub fov_deg: Option<f64>,
    /// What the rays' flux values mean: scaled to the header's total where it states one (the
    /// default; TM-25 ray fluxes are relative weights in files that give the total), or the rays'
    /// own values.
    pub ray_flux: RayFlux,
}

impl Default for BinningOptions {
    fn default() -> Self {
        Self {
            sphere: CaptureSphere {
                centre_m: DVec3::ZERO,
                radius_m: 1.1,
            },
            layout: Layout::Fibonacci { count: 1000 },
            seed: 0,
            width: 64,
            height: 64,
            fov_deg: None,
            ray_flux: RayFlux::Header,
        }
    }
}

/// What the binning did, for the user to judge the images' noise.
#[derive(Debug, Clone, PartialEq)]
pub struct BinningReport {
    /// How each ray's luminous flux was obtained.
    pub luminous_source: LuminousSource,
    /// Factor applied to every ray's luminous flux (1, or header flux / Σ rays).
    pub flux_scale: f64,
    /// Rays in the file.
    pub rays_total: u64,
    /// Rays that landed in a pixel.
    pub rays_used: u64,
    /// Rays with no camera within 90° of their direction (dropped).
    pub rays_behind: u64,
    /// Rays whose object-plane crossing falls outside the image (dropped).
    pub rays_outside_image: u64,
    /// Σ luminous flux of all rays after scaling (lm).
    pub flux_total_lm: f64,
    /// Σ luminous flux of the rays that landed in a pixel (lm).
    pub flux_used_lm: f64,
    /// Σ luminous flux of the rays dropped for lack of a camera (lm).
    pub flux_behind_lm: f64,
    /// Σ luminous flux of the rays outside the images (lm).
    pub flux_outside_image_lm: f64,
    /// Σ over cameras and pixels of L·A·Ω_i, from the f32 images (lm): equals `flux_used_lm`.
    pub flux_from_images_lm: f64,
    /// Rays per camera, in camera order.
    pub rays_per_camera: Vec<u64>,
    /// Voronoi solid angle Ω_i per camera (sr); they sum to 4π.
    pub solid_angle_sr: Vec<f64>,
    /// Cameras that received no ray.
    pub cameras_with_zero_rays: usize,
    /// Cameras at the same direction as an earlier one (within [`NearestDirection::MERGE_CHORD`],
    /// e.g. the meridian starts at a pole): they get no ray and Ω = 0, the earlier one gets all.
    pub cameras_merged: usize,
    /// Pixels (over all images) that received at least one ray.
    pub lit_pixels: u64,
    /// Mean rays per lit pixel.
    pub rays_per_lit_pixel_mean: f64,
    /// Median rays per lit pixel.
    pub rays_per_lit_pixel_median: f64,
    /// Most rays in one pixel.
    pub rays_per_lit_pixel_max: u64,
    /// Pixel footprint on the object plane, (r_s/f_x)(r_s/f_y) (m²).
    pub pixel_area_m2: f64,
    /// Focal length (px), the same in x and y.
    pub focal_px: f64,
    /// Full horizontal field of view (degrees).
    pub fov_deg: f64,
    /// Whether the solid angles are exact spherical Voronoi cells (else sampled with 2²² directions,
    /// for layouts with cells wider than ~85°).
    pub solid_angles_exact: bool,
    /// Cameras that received rays but have a zero solid angle (possible only with sampled solid angles;
    /// their Ω was set to one sample's 4π/2²²).
    pub cameras_with_tiny_cells: usize,
}

/// The binned scan plus its report.
#[derive(Debug)]
pub struct BinnedScan {
    /// Cameras, intrinsics and the images (a [`MemorySource`]).
    pub scan: Scan,
    /// Counts and sums.
    pub report: BinningReport,
}

/// Per-thread accumulator of the binning pass.
#[derive(Default)]
struct Acc {
    hits: Vec<(u64, f64)>,
    behind: (u64, f64),
    outside: (u64, f64),
    total: f64,
}

impl Acc {
    fn merge(mut self, mut o: Acc) -> Acc {
        if self.hits.len() < o.hits.len() {
            std::mem::swap(&mut self.hits, &mut o.hits);
        }
        self.hits.append(&mut o.hits);
        self.behind = (self.behind.0 + o.behind.0, self.behind.1 + o.behind.1);
        self.outside = (self.outside.0 + o.outside.0, self.outside.1 + o.outside.1);
        self.total += o.total;
        self
    }
}

/// Where a ray meets camera `cam`'s object plane, in that camera's (x right, y down) metres; `None`
/// when it travels away from the camera's side (k·d ≤ 0).
fn plane_crossing(p: DVec3, k: DVec3, d: DVec3, centre: DVec3, right: DVec3, down: DVec3) -> Option<DVec2> {
    let kd = k.dot(d);
    if kd <= 1e-9 {
        return None;
    }
    let t = (centre - p).dot(d) / kd;
    let q = p + t * k - centre;
    Some(DVec2::new(q.dot(right), q.dot(down)))
}

/// Bins the rays of `file` into the images of a virtual scan (see the module documentation).
pub fn bin_rays(file: &RayFile, opts: &BinningOptions) -> Result<BinnedScan> {
    let sphere = opts.sphere;
    if !sphere.radius_m.is_finite() || sphere.radius_m <= 0.0 || !sphere.centre_m.is_finite() {
        return Err(NearfieldError::invalid(
            "radius",
            format!(
                "{} m: the capture sphere needs a finite radius > 0 and a finite centre",
                sphere.radius_m
            ),
        ));
    }
    if opts.width == 0 || opts.height == 0 || opts.width > 65_536 || opts.height > 65_536 {
        return Err(NearfieldError::invalid(
            "size",
            format!("{}×{} px is outside 1…65536", opts.width, opts.height),
        ));
    }
    if let Some(f) = opts.fov_deg {
        if !(f.is_finite() && f > 0.0 && f < 179.0) {
            return Err(NearfieldError::invalid("fov", format!("{f}° must lie in (0, 179)")));
        }
    }
    if matches!(file.luminous_source(), LuminousSource::Unavailable) {
        return Err(NearfieldError::Unsupported {
            path: file.path().to_path_buf(),
            message: "the rays carry radiant flux only and the file gives neither both header fluxes nor any \
                      spectral information, so luminous flux (and luminance) cannot be computed"
                .into(),
        });
    }
    let cameras = layout::cameras(&sphere, &opts.layout, opts.seed)?;
    let (w, h) = (opts.width, opts.height);
    let px_per_image = w as u64 * h as u64;
    let total_px = px_per_image.saturating_mul(cameras.len() as u64);
    if total_px > MAX_TOTAL_PIXELS {
        return Err(NearfieldError::invalid(
            "size",
            format!(
                "{} cameras × {w}×{h} px = {total_px} pixels exceed the in-memory limit of {MAX_TOTAL_PIXELS}; \
                 use fewer cameras or smaller images",
                cameras.len()
            ),
        ));
    }
    let dirs: Vec<DVec3> = cameras.iter().map(|c| c.direction_from(sphere.centre_m)).collect();
    let lookup = NearestDirection::new(&dirs);

    let n = file.len();
    let scale = match opts.ray_flux {
        RayFlux::Header => file.header_scale().map_or(1.0, |h| h.factor),
        RayFlux::Rays => 1.0,
    };

    // Field of view: given, or fitted to the widest crossing.
    let r_s = sphere.radius_m;
    let crossing = |ray: &Ray| -> Option<(usize, DVec2)> {
        let cam = lookup.nearest(ray.direction)?;
        let c = &cameras[cam];
        let q = plane_crossing(
            ray.position_m,
            ray.direction,
            dirs[cam],
            sphere.centre_m,
            c.right,
            c.down,
        )?;
        Some((cam, q))
    };
    let focal_px = match opts.fov_deg {
        Some(fov) => (w as f64 / 2.0) / (fov.to_radians() / 2.0).tan(),
        None => {
            let ext = (0..n)
                .into_par_iter()
                .filter_map(|i| crossing(&file.ray(i)?))
                .map(|(_, q)| q.abs())
                .reduce(|| DVec2::ZERO, DVec2::max);
            let ext = ext.max(DVec2::splat(1e-3)) * 1.02;
            ((w as f64 / 2.0) * r_s / ext.x).min((h as f64 / 2.0) * r_s / ext.y)
        }
    };
    let fov_deg = 2.0 * ((w as f64 / 2.0) / focal_px).atan().to_degrees();
    let intrinsics = Intrinsics {
        width: w,
        height: h,
        principal_px: DVec2::new(w as f64 / 2.0, h as f64 / 2.0),
        focal_px: DVec2::splat(focal_px),
    };
    intrinsics.validate("rays2scan")?;

    let acc = (0..n)
        .into_par_iter()
        .fold(Acc::default, |mut acc, i| {
            let Some(ray) = file.ray(i) else { return acc };
            let flux = ray.luminous_lm.unwrap_or(0.0) * scale;
            acc.total += flux;
            let Some((cam, q)) = crossing(&ray) else {
                acc.behind = (acc.behind.0 + 1, acc.behind.1 + flux);
                return acc;
            };
            let u = intrinsics.principal_px.x + focal_px * q.x / r_s;
            let v = intrinsics.principal_px.y + focal_px * q.y / r_s;
            if !(u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64) {
                acc.outside = (acc.outside.0 + 1, acc.outside.1 + flux);
                return acc;
            }
            let key = cam as u64 * px_per_image + (v as u64) * w as u64 + u as u64;
            acc.hits.push((key, flux));
            acc
        })
        .reduce(Acc::default, Acc::merge);
    let Acc {
        mut hits,
        behind,
        outside,
        total,
    } = acc;
    hits.par_sort_unstable_by_key(|h| h.0);

    let (mut omega, solid_angles_exact) = lookup.solid_angles();
    let one_sample = 4.0 * std::f64::consts::PI / (1u64 << 22) as f64;
    let pixel_area_m2 = (r_s / focal_px) * (r_s / focal_px);

    let mut images: Vec<LuminanceImage> = cameras.iter().map(|_| LuminanceImage::zeros(w, h)).collect();
    let mut rays_per_camera = vec![0u64; cameras.len()];
    let mut runs: Vec<u64> = Vec::new();
    let mut flux_used = 0.0;
    let mut tiny = 0usize;
    let mut s = 0;
    while s < hits.len() {
        let key = hits[s].0;
        let mut e = s;
        let mut sum = 0.0;
        while e < hits.len() && hits[e].0 == key {
            sum += hits[e].1;
            e += 1;
        }
        let cam = (key / px_per_image) as usize;
        let pix = (key % px_per_image) as usize;
        if omega[cam] <= 0.0 {
            omega[cam] = one_sample;
            tiny += 1;
        }
        let l = sum / (pixel_area_m2 * omega[cam]);
        if let Some(px) = images[cam].data.get_mut(pix) {
            *px = l as f32;
        }
        rays_per_camera[cam] += (e - s) as u64;
        runs.push((e - s) as u64);
        flux_used += sum;
        s = e;
    }
    let flux_from_images_lm: f64 = images
        .iter()
        .zip(&omega)
        .map(|(im, o)| im.data.iter().map(|v| *v as f64).sum::<f64>() * pixel_area_m2 * o)
        .sum();
    let lit = runs.len() as u64;
    let rays_used = hits.len() as u64;
    let max_run = runs.iter().copied().max().unwrap_or(0);
    let median = if runs.is_empty() {
        0.0
    } else {
        let mid = runs.len() / 2;
        let (_, m, _) = runs.select_nth_unstable(mid);
        let m = *m as f64;
        if runs.len().is_multiple_of(2) {
            let lower = runs[..mid].iter().copied().max().unwrap_or(0) as f64;
            0.5 * (lower + m)
        } else {
            m
        }
    };
    let report = BinningReport {
        luminous_source: file.luminous_source().clone(),
        flux_scale: scale,
        rays_total: n as u64,
        rays_used,
        rays_behind: behind.0,
        rays_outside_image: outside.0,
        flux_total_lm: total,
        flux_used_lm: flux_used,
        flux_behind_lm: behind.1,
        flux_outside_image_lm: outside.1,
        flux_from_images_lm,
        cameras_with_zero_rays: rays_per_camera.iter().filter(|c| **c == 0).count(),
        cameras_merged: (0..cameras.len()).filter(|i| lookup.is_merged(*i)).count(),
        rays_per_camera,
        solid_angle_sr: omega,
        lit_pixels: lit,
        rays_per_lit_pixel_mean: if lit > 0 { rays_used as f64 / lit as f64 } else { 0.0 },
        rays_per_lit_pixel_median: median,
        rays_per_lit_pixel_max: max_run,
        pixel_area_m2,
        focal_px,
        fov_deg,
        solid_angles_exact,
        cameras_with_tiny_cells: tiny,
    };
    let set = RayImageSet {
        sphere,
        intrinsics,
        cameras,
    };
    set.validate()?;
    Ok(BinnedScan {
        scan: Scan {
            set,
            source: Box::new(MemorySource { images }),
        },
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearfield::tm25::{encode, Tm25Header};

    #[test]
    fn a_collimated_beam_lands_in_one_pixel_with_the_right_luminance() {
        // 4 rays of 0.25 lm each, all along −Z from the origin, into a 6-camera grid (poles + 4).
        let h = Tm25Header::default();
        let mut rec = Vec::new();
        for _ in 0..4 {
            rec.extend_from_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.25]);
        }
        let f = RayFile::from_bytes(&encode(&h, &rec).unwrap(), "beam").unwrap();
        let opts = BinningOptions {
            layout: Layout::Grid {
                phi_steps: 4,
                theta_steps: 3,
            },
            width: 8,
            height: 8,
            fov_deg: Some(10.0),
            ..BinningOptions::default()
        };
        let b = bin_rays(&f, &opts).unwrap();
        let r = &b.report;
        assert_eq!(r.rays_used, 4);
        assert_eq!(r.lit_pixels, 1);
        assert_eq!(r.rays_per_lit_pixel_median, 4.0);
        // The nadir camera (θ = 0, index 0) gets the beam.
        assert_eq!(r.rays_per_camera[0], 4);
        assert_eq!(r.cameras_with_zero_rays, 5);
        let img = b.scan.source.image(0).unwrap();
        let l = img.get(4, 4) as f64;
        let want = 1.0 / (r.pixel_area_m2 * r.solid_angle_sr[0]);
        assert!((l - want).abs() < 1e-6 * want, "{l} vs {want}");
        assert!((r.flux_from_images_lm - 1.0).abs() < 1e-6);
        let total: f64 = r.solid_angle_sr.iter().sum();
        assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-9);
    }
}
