//! Summary statistics of a ray file ([`RayStats`], printed by `lumiview info`): sums, bounding box and
//! the direction distribution.

use glam::DVec3;

use super::rays::RayFile;
use super::spectral::LuminousSource;

/// Summary statistics of a ray file (`lumiview info`).
#[derive(Debug, Clone, PartialEq)]
pub struct RayStats {
    /// Number of rays.
    pub count: u64,
    /// Σ luminous flux of the rays (lm), when available.
    pub luminous_sum_lm: Option<f64>,
    /// Σ radiant flux column (W), when present.
    pub radiant_sum_w: Option<f64>,
    /// Smallest and largest per-ray flux of the weight used below.
    pub flux_range: (f64, f64),
    /// Which flux the direction statistics weigh by: "luminous", "radiant" or "count".
    pub weight: &'static str,
    /// Bounding box of the start points (m).
    pub bbox_min_m: DVec3,
    /// Bounding box of the start points (m).
    pub bbox_max_m: DVec3,
    /// Largest distance of a start point from the origin (m).
    pub max_radius_m: f64,
    /// Flux-weighted mean of the unit directions (its length: 1 = collimated, 0 = symmetric).
    pub mean_direction: DVec3,
    /// Share of the weight travelling upwards (kz > 0).
    pub upward_fraction: f64,
    /// Share of the weight per 10° band of the angle from +Z (index 0: 0–10°, ..., 17: 170–180°).
    pub polar_histogram: [f64; 18],
    /// Largest angle between a ray and the mean direction (degrees); 180 when the mean is zero.
    pub max_angle_from_mean_deg: f64,
    /// Largest |‖k‖ − 1| of the stored directions (they are normalised on use).
    pub max_direction_norm_error: f64,
    /// Smallest and largest wavelength of the rays (nm), when known.
    pub wavelength_range_nm: Option<(f64, f64)>,
}

impl RayFile {
    /// Sums, bounding box and direction distribution (one pass over the rays).
    pub fn stats(&self) -> RayStats {
        let has_lum = !matches!(self.luminous, LuminousSource::Unavailable);
        let has_rad = self.columns.radiant.is_some();
        let weight = if has_lum {
            "luminous"
        } else if has_rad {
            "radiant"
        } else {
            "count"
        };
        let (mut lum, mut rad, mut total) = (0.0, 0.0, 0.0);
        let mut flux_range = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut max_radius_m = 0.0f64;
        let mut mean = DVec3::ZERO;
        let mut up = 0.0;
        let mut hist = [0.0; 18];
        let mut max_norm_err = 0.0f64;
        let mut wl: Option<(f64, f64)> = None;
        for (i, r) in self.rays().enumerate() {
            let w = if has_lum {
                r.luminous_lm.unwrap_or(0.0)
            } else {
                r.radiant_w.unwrap_or(1.0)
            };
            lum += r.luminous_lm.unwrap_or(0.0);
            rad += r.radiant_w.unwrap_or(0.0);
            total += w;
            flux_range = (flux_range.0.min(w), flux_range.1.max(w));
            lo = lo.min(r.position_m);
            hi = hi.max(r.position_m);
            max_radius_m = max_radius_m.max(r.position_m.length());
            mean += w * r.direction;
            if r.direction.z > 0.0 {
                up += w;
            }
            let theta = r.direction.z.clamp(-1.0, 1.0).acos().to_degrees();
            hist[((theta / 10.0) as usize).min(17)] += w;
            if let Some(rec) = self.record(i) {
                let n = rec[3..6].iter().map(|v| (*v as f64).powi(2)).sum::<f64>().sqrt();
                max_norm_err = max_norm_err.max((n - 1.0).abs());
            }
            if let Some(l) = r.wavelength_nm {
                wl = Some(wl.map_or((l, l), |(a, b)| (a.min(l), b.max(l))));
            }
        }
        let n = self.len();
        if total > 0.0 {
            mean /= total;
            up /= total;
            for h in &mut hist {
                *h /= total;
            }
        }
        let m = mean.normalize_or_zero();
        let max_angle_from_mean_deg = if m == DVec3::ZERO {
            180.0
        } else {
            self.rays()
                .map(|r| r.direction.dot(m).clamp(-1.0, 1.0).acos().to_degrees())
                .fold(0.0, f64::max)
        };
        if n == 0 {
            lo = DVec3::ZERO;
            hi = DVec3::ZERO;
            flux_range = (0.0, 0.0);
        }
        RayStats {
            count: n as u64,
            luminous_sum_lm: has_lum.then_some(lum),
            radiant_sum_w: has_rad.then_some(rad),
            flux_range,
            weight,
            bbox_min_m: lo,
            bbox_max_m: hi,
            max_radius_m,
            mean_direction: mean,
            upward_fraction: up,
            polar_histogram: hist,
            max_angle_from_mean_deg,
            max_direction_norm_error: max_norm_err,
            wavelength_range_nm: wl,
        }
    }
}
