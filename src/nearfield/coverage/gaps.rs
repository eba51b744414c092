//! The gap statistics of a scan's cameras: per-hemisphere counts, coincident positions, and the
//! distribution of the angle from a direction to its nearest camera over the whole sphere (median,
//! 95th percentile and maximum over [`STATS_SAMPLES`] uniformly spread directions; the maximum is
//! then refined towards the nearest vertex of the cameras' spherical Voronoi diagram, where the
//! true maximum lies), and the map of that angle the picture draws.

use glam::DVec3;
use rayon::prelude::*;

use super::{CameraIndex, Coverage};
use crate::nearfield::rayset::{Hemisphere, RayImageSet};

/// Uniformly spread directions (a Fibonacci sphere) over which the gap statistics are taken.
pub const STATS_SAMPLES: usize = 1 << 18;

/// Photometric angles (φ, θ) in degrees of a unit direction (φ in 0…360).
fn angles_deg(d: DVec3) -> [f64; 2] {
    [
        d.y.atan2(d.x).to_degrees().rem_euclid(360.0),
        (-d.z).clamp(-1.0, 1.0).acos().to_degrees(),
    ]
}

/// Direction of photometric angles in degrees.
fn dir_deg(phi: f64, theta: f64) -> DVec3 {
    let (p, t) = (phi.to_radians(), theta.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), -t.cos())
}

/// The `i`-th of `n` Fibonacci-sphere directions (equal-area spread).
pub(super) fn fibonacci(i: usize, n: usize) -> DVec3 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let a = golden * i as f64;
    DVec3::new(r * a.cos(), r * a.sin(), z)
}

/// Summary of a scan's camera coverage.
#[derive(Debug, Clone, PartialEq)]
pub struct CoverageStats {
    /// Cameras in the scan.
    pub cameras: usize,
    /// Cameras tagged [`Hemisphere::Lower`].
    pub lower: usize,
    /// Cameras tagged [`Hemisphere::Upper`].
    pub upper: usize,
    /// Groups of cameras at the same position (within 10⁻⁶ rad), e.g. meridian starts at the poles.
    pub coincident_groups: usize,
    /// Cameras in those groups.
    pub cameras_in_coincident_groups: usize,
    /// Median over the sphere of the angle from a direction to its nearest camera, degrees.
    pub median_gap_deg: f64,
    /// 95th percentile of that angle, degrees.
    pub p95_gap_deg: f64,
    /// Largest angle found (sampled, then refined at Voronoi vertices), degrees: no direction found
    /// is farther from every camera.
    pub max_gap_deg: f64,
    /// Where the largest angle was found, (φ, θ) in degrees.
    pub max_gap_at_deg: [f64; 2],
    /// Directions sampled for the statistics.
    pub samples: usize,
}

impl Coverage {
    /// Analyses the cameras of `set` (O(n log n) plus [`STATS_SAMPLES`] queries, on all cores).
    pub fn new(set: &RayImageSet) -> Self {
        let dirs: Vec<DVec3> = set
            .cameras
            .iter()
            .map(|c| c.direction_from(set.sphere.centre_m))
            .collect();
        let hemispheres: Vec<Hemisphere> = set.cameras.iter().map(|c| c.hemisphere).collect();
        let index = CameraIndex::new(&dirs);
        let groups = set.coincident_groups(1e-6);
        let lower = hemispheres.iter().filter(|h| **h == Hemisphere::Lower).count();
        let mut stats = CoverageStats {
            cameras: dirs.len(),
            lower,
            upper: dirs.len() - lower,
            coincident_groups: groups.len(),
            cameras_in_coincident_groups: groups.iter().map(Vec::len).sum(),
            median_gap_deg: f64::NAN,
            p95_gap_deg: f64::NAN,
            max_gap_deg: f64::NAN,
            max_gap_at_deg: [f64::NAN; 2],
            samples: STATS_SAMPLES,
        };
        if !index.is_empty() {
            let gaps: Vec<f64> = (0..STATS_SAMPLES)
                .into_par_iter()
                .map(|i| index.nearest(fibonacci(i, STATS_SAMPLES)).map_or(f64::NAN, |(_, a)| a))
                .collect();
            let mut order: Vec<usize> = (0..STATS_SAMPLES).collect();
            order.sort_unstable_by(|&a, &b| gaps[a].total_cmp(&gaps[b]));
            let at = |q: f64| gaps[order[((STATS_SAMPLES - 1) as f64 * q).round() as usize]];
            stats.median_gap_deg = at(0.5).to_degrees();
            stats.p95_gap_deg = at(0.95).to_degrees();
            // Refine from the 64 widest sampled gaps towards the Voronoi vertices near them.
            let (max, where_) = order
                .iter()
                .rev()
                .take(64)
                .collect::<Vec<_>>()
                .par_iter()
                .map(|&&i| refine_gap(&index, &dirs, fibonacci(i, STATS_SAMPLES)))
                .reduce(|| (f64::NEG_INFINITY, DVec3::Z), |a, b| if b.0 > a.0 { b } else { a });
            stats.max_gap_deg = max.to_degrees();
            stats.max_gap_at_deg = angles_deg(where_);
        }
        Self {
            stats,
            dirs,
            hemispheres,
            index,
            radius_m: set.sphere.radius_m,
        }
    }

    /// The nearest-camera index.
    pub fn index(&self) -> &CameraIndex {
        &self.index
    }

    /// The angle (degrees) from each pixel centre of an equirectangular `width × height` map to its
    /// nearest camera: column c at φ = (c + 0.5)·360°/width, row r at θ = 180° − (r + 0.5)·180°/height
    /// (row 0 at the zenith). NaN when the scan has no camera.
    pub fn angle_map(&self, width: usize, height: usize) -> Vec<f32> {
        let mut out = vec![f32::NAN; width * height];
        if width == 0 {
            return out;
        }
        out.par_chunks_mut(width).enumerate().for_each(|(r, row)| {
            let theta = 180.0 - (r as f64 + 0.5) * 180.0 / height as f64;
            for (c, v) in row.iter_mut().enumerate() {
                let phi = (c as f64 + 0.5) * 360.0 / width as f64;
                if let Some((_, a)) = self.index.nearest(dir_deg(phi, theta)) {
                    *v = a.to_degrees() as f32;
                }
            }
        });
        out
    }
}

/// Refines a wide gap: moves from `q` to the spherical circumcentre of its three nearest distinct
/// cameras (a Voronoi vertex when no other camera is closer), a few times. Returns the largest
/// nearest-camera angle met (rad) and where; every value returned is a true nearest-camera angle.
fn refine_gap(index: &CameraIndex, dirs: &[DVec3], q0: DVec3) -> (f64, DVec3) {
    let Some((_, a0)) = index.nearest(q0) else {
        return (f64::NEG_INFINITY, q0);
    };
    let mut best = (a0, q0);
    let mut q = q0;
    for _ in 0..16 {
        let mut pts: Vec<DVec3> = Vec::with_capacity(3);
        for (i, _) in index.k_nearest(q, 16) {
            let p = dirs[i].normalize_or_zero();
            if pts.iter().all(|x| (*x - p).length() > 1e-9) {
                pts.push(p);
                if pts.len() == 3 {
                    break;
                }
            }
        }
        if pts.len() < 3 {
            break;
        }
        let n = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
        if n.length() < 1e-15 {
            break;
        }
        let mut v = n.normalize();
        if v.dot(q) < 0.0 {
            v = -v;
        }
        let Some((_, a)) = index.nearest(v) else {
            break;
        };
        if a > best.0 {
            best = (a, v);
        }
        if (v - q).length() < 1e-12 {
            break;
        }
        q = v;
    }
    best
}
