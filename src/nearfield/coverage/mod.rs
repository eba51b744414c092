//! Camera coverage of a scan: how well the cameras cover the directions around the luminaire.
//! [`Coverage::new`] analyses a scan's cameras once; the statistics ([`CoverageStats`]), the
//! nearest-camera index and the picture all come from that one analysis. Distances are
//! great-circle angles, never planar (Δφ, Δθ).
//!
//! - `index.rs`: [`CameraIndex`], nearest-camera queries (a k-d tree over the unit directions);
//! - `gaps.rs`: [`CoverageStats`], the angle from a direction to its nearest camera over the sphere;
//! - `picture.rs`: [`Coverage::to_png`], the camera positions on two discs and the angle map.

mod gaps;
mod index;
mod picture;

use glam::DVec3;

use super::rayset::Hemisphere;

pub use self::gaps::{CoverageStats, STATS_SAMPLES};
pub use self::index::CameraIndex;
pub use self::picture::{MAX_WIDTH_PX, MIN_WIDTH_PX};

/// The coverage analysis of a scan: stats plus what the picture needs.
#[derive(Debug, Clone)]
pub struct Coverage {
    /// The statistics.
    pub stats: CoverageStats,
    /// Unit directions of the cameras from the capture centre.
    dirs: Vec<DVec3>,
    /// Their hemisphere tags.
    hemispheres: Vec<Hemisphere>,
    /// Nearest-camera index over `dirs`.
    index: CameraIndex,
    /// Capture sphere radius (m), for the title.
    radius_m: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearfield::layout::{cameras, Layout};
    use crate::nearfield::rayset::{CaptureSphere, Intrinsics, RayImageSet};
    use glam::DVec2;

    fn set_of(layout: Layout) -> RayImageSet {
        let sphere = CaptureSphere {
            centre_m: DVec3::ZERO,
            radius_m: 1.0,
        };
        RayImageSet {
            sphere,
            intrinsics: Intrinsics {
                width: 8,
                height: 8,
                principal_px: DVec2::splat(4.0),
                focal_px: DVec2::splat(8.0),
            },
            cameras: cameras(&sphere, &layout, 1).unwrap(),
        }
    }

    #[test]
    fn one_hemisphere_leaves_a_90_degree_gap() {
        // A grid whose rows stop at the equator: the zenith is 90° from every camera.
        let mut set = set_of(Layout::Grid {
            phi_steps: 36,
            theta_steps: 37,
        });
        set.cameras.retain(|c| c.position_m.z <= 1e-9);
        let cov = Coverage::new(&set);
        assert!((cov.stats.max_gap_deg - 90.0).abs() < 0.05, "{:?}", cov.stats);
        assert!(cov.stats.max_gap_at_deg[1] > 179.0, "{:?}", cov.stats);
        assert_eq!(cov.stats.upper, 0);
    }

    #[test]
    fn fibonacci_gap_is_small_and_the_picture_renders() {
        let set = set_of(Layout::Fibonacci { count: 4000 });
        let cov = Coverage::new(&set);
        // Mean spacing √(4π/4000) ≈ 3.2°; gaps are about half of it.
        assert!(
            cov.stats.max_gap_deg < 3.0 && cov.stats.median_gap_deg > 0.5,
            "{:?}",
            cov.stats
        );
        assert!(cov.stats.median_gap_deg < cov.stats.p95_gap_deg);
        let png = cov.to_png(800).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert!(cov.to_png(100).is_err());
    }
}
