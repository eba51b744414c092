//! Camera layouts on the capture sphere: `rigo` (a near-field goniophotometer's meridians), `fibonacci`
//! and `grid`. All are deterministic for a seed. Directions are unit vectors from the capture centre in
//! the luminaire frame; [`cameras`] turns them into [`Camera`]s looking at the centre.

use glam::DVec3;

use super::error::{NearfieldError, Result};
use super::rayset::{Camera, CaptureSphere, Hemisphere};

/// Which cameras a layout places.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Layout {
    /// A near-field goniophotometer: cameras along meridians (constant φ), evenly spaced in θ, so they
    /// crowd towards the poles; every meridian starts at the pole (coincident positions there); a
    /// slight deterministic jitter away from the poles; two hemispheres that overlap by
    /// `overlap_deg` beyond the equator. `per_hemisphere` ≈ 28,000 at full size.
    Rigo {
        /// Cameras per hemisphere (approximate: rounded to whole meridians × rows).
        per_hemisphere: usize,
        /// Overlap beyond the equator (degrees), e.g. 2.
        overlap_deg: f64,
        /// Jitter amplitude (degrees, uniform ±), e.g. 0.05.
        jitter_deg: f64,
    },
    /// `count` cameras on a Fibonacci (golden-angle) spiral over the whole sphere: near-uniform.
    Fibonacci {
        /// Number of cameras.
        count: usize,
    },
    /// A regular (φ, θ) grid: `phi_steps` meridians × `theta_steps` rows, θ from 0° to 180° inclusive
    /// (the poles appear once each).
    Grid {
        /// Meridians (φ steps over 360°).
        phi_steps: usize,
        /// Rows (θ steps over 0…180°, both ends included).
        theta_steps: usize,
    },
}

/// Upper bound on cameras a layout may request (10⁶: far above any real scan, small enough to allocate).
pub const MAX_CAMERAS: usize = 1_000_000;

/// SplitMix64: a tiny deterministic generator (jitter only; no statistical claims needed).
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A uniform value in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Direction of photometric angles φ (= C) and θ (= γ from nadir), degrees.
pub fn direction_deg(phi_deg: f64, theta_deg: f64) -> DVec3 {
    let (p, t) = (phi_deg.to_radians(), theta_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), -t.cos())
}

/// The directions of a layout with the hemisphere each belongs to.
pub fn directions(layout: &Layout, seed: u64) -> Result<Vec<(DVec3, Hemisphere)>> {
    let hemi = |d: DVec3| {
        if d.z <= 0.0 {
            Hemisphere::Lower
        } else {
            Hemisphere::Upper
        }
    };
    match *layout {
        Layout::Fibonacci { count } => {
            check_count("fibonacci count", count)?;
            let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
            Ok((0..count)
                .map(|i| {
                    let z = 1.0 - (2.0 * i as f64 + 1.0) / count as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let a = golden * i as f64;
                    let d = DVec3::new(r * a.cos(), r * a.sin(), z);
                    (d, hemi(d))
                })
                .collect())
        }
        Layout::Grid { phi_steps, theta_steps } => {
            if phi_steps == 0 || theta_steps < 2 {
                return Err(NearfieldError::invalid("grid", "needs ≥ 1 φ step and ≥ 2 θ steps"));
            }
            check_count("grid size", phi_steps.saturating_mul(theta_steps))?;
            let mut out = Vec::new();
            for j in 0..theta_steps {
                let t = 180.0 * j as f64 / (theta_steps - 1) as f64;
                let n = if j == 0 || j == theta_steps - 1 { 1 } else { phi_steps };
                for i in 0..n {
                    let d = direction_deg(360.0 * i as f64 / phi_steps as f64, t);
                    out.push((d, hemi(d)));
                }
            }
            Ok(out)
        }
        Layout::Rigo {
            per_hemisphere,
            overlap_deg,
            jitter_deg,
        } => {
            check_count("rigo cameras per hemisphere", per_hemisphere)?;
            if !(0.0..=30.0).contains(&overlap_deg) || !(0.0..=5.0).contains(&jitter_deg) {
                return Err(NearfieldError::invalid("rigo", "overlap must be 0…30° and jitter 0…5°"));
            }
            let (meridians, rows) = rigo_dims(per_hemisphere, overlap_deg);
            // Rows from the pole to exactly 90° + overlap, so the hemispheres overlap at the equator.
            let dtheta = (90.0 + overlap_deg) / (rows - 1) as f64;
            let mut rng = SplitMix64::new(seed);
            let mut out = Vec::with_capacity(2 * meridians * rows);
            for (h, sign) in [(Hemisphere::Lower, 1.0), (Hemisphere::Upper, -1.0)] {
                for m in 0..meridians {
                    let phi0 = 360.0 * m as f64 / meridians as f64;
                    for k in 0..rows {
                        let mut theta = k as f64 * dtheta;
                        let mut phi = phi0;
                        if k > 0 {
                            theta += jitter_deg * (2.0 * rng.next_f64() - 1.0);
                            phi += jitter_deg * (2.0 * rng.next_f64() - 1.0);
                        }
                        let theta = if sign > 0.0 { theta } else { 180.0 - theta };
                        out.push((direction_deg(phi, theta), h));
                    }
                }
            }
            Ok(out)
        }
    }
}

/// Meridians and rows per hemisphere of a `rigo` layout: square cells at the equator
/// (meridians · rows ≈ N, 360°/meridians = (90° + overlap)/rows).
fn rigo_dims(per_hemisphere: usize, overlap_deg: f64) -> (usize, usize) {
    let span = 90.0 + overlap_deg;
    let meridians = ((per_hemisphere as f64 * 360.0 / span).sqrt().round() as usize).max(3);
    let rows = (per_hemisphere / meridians).max(2);
    (meridians, rows)
}

fn check_count(name: &str, n: usize) -> Result<()> {
    if n == 0 || n > MAX_CAMERAS {
        return Err(NearfieldError::invalid(name, format!("{n} is outside 1…{MAX_CAMERAS}")));
    }
    Ok(())
}

/// Cameras on `sphere` for a layout, each looking at the centre, labelled `cam N`.
///
/// In a `rigo` layout every meridian starts at the pole, and, as on a real goniophotometer, the
/// camera there is turned about its optical axis with its meridian (its image axes continue those of
/// the next camera along the meridian), so the pole cameras share a position but not an orientation.
pub fn cameras(sphere: &CaptureSphere, layout: &Layout, seed: u64) -> Result<Vec<Camera>> {
    let mut cams: Vec<Camera> = directions(layout, seed)?
        .into_iter()
        .enumerate()
        .map(|(i, (d, h))| Camera::on_sphere(sphere, d, h, format!("cam {i}")))
        .collect();
    if let Layout::Rigo {
        per_hemisphere,
        overlap_deg,
        ..
    } = *layout
    {
        let (meridians, rows) = rigo_dims(per_hemisphere, overlap_deg);
        for (i, c) in cams.iter_mut().enumerate() {
            if i % rows != 0 {
                continue;
            }
            let m = (i / rows) % meridians;
            let phi = (360.0 * m as f64 / meridians as f64).to_radians();
            // The next camera along the meridian has image up ≈ ±(cos φ, sin φ, 0) (sign of forward.z):
            // keep the pole camera's axes continuous with it.
            let forward = c.forward;
            let down = -DVec3::new(phi.cos(), phi.sin(), 0.0) * forward.z.signum();
            c.down = (down - forward * forward.dot(down)).normalize();
            c.right = c.down.cross(forward).normalize();
        }
    }
    Ok(cams)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigo_full_size_is_about_28000_per_hemisphere_and_deterministic() {
        let l = Layout::Rigo {
            per_hemisphere: 28_000,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        };
        let a = directions(&l, 7).unwrap();
        let b = directions(&l, 7).unwrap();
        assert_eq!(a, b);
        let lower = a.iter().filter(|(_, h)| *h == Hemisphere::Lower).count();
        assert!((27_000..=29_000).contains(&lower), "{lower}");
        // Overlap: some lower-hemisphere cameras sit above the equator.
        assert!(a.iter().any(|(d, h)| *h == Hemisphere::Lower && d.z > 0.01));
        // Even a small layout reaches past the equator from both sides.
        let small = directions(
            &Layout::Rigo {
                per_hemisphere: 500,
                overlap_deg: 2.0,
                jitter_deg: 0.0,
            },
            1,
        )
        .unwrap();
        let top_of_lower = small
            .iter()
            .filter(|(_, h)| *h == Hemisphere::Lower)
            .map(|(d, _)| d.z)
            .fold(f64::MIN, f64::max);
        assert!(
            (top_of_lower - 2f64.to_radians().sin()).abs() < 1e-9,
            "lower rows end at 92°: {top_of_lower}"
        );
        assert!(a.iter().all(|(d, _)| (d.length() - 1.0).abs() < 1e-12));
    }

    #[test]
    fn rigo_pole_cameras_share_a_position_but_turn_with_their_meridian() {
        let sphere = CaptureSphere {
            centre_m: DVec3::ZERO,
            radius_m: 1.0,
        };
        let l = Layout::Rigo {
            per_hemisphere: 400,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        };
        let cams = cameras(&sphere, &l, 1).unwrap();
        let poles: Vec<&Camera> = cams.iter().filter(|c| c.position_m.z < -0.999_999).collect();
        assert!(poles.len() > 3);
        for c in &cams {
            c.validate().unwrap();
        }
        for pair in poles.windows(2) {
            assert!((pair[0].position_m - pair[1].position_m).length() < 1e-12);
            assert!((pair[0].down - pair[1].down).length() > 1e-3, "orientations differ");
        }
        // Continuous with the next camera along each meridian (rows are consecutive indices).
        for (i, c) in cams.iter().enumerate() {
            if c.position_m.z.abs() > 0.999_999 {
                assert!(
                    c.down.dot(cams[i + 1].down) > 0.95,
                    "camera {i}: rows are ~10° apart here"
                );
            }
        }
    }

    #[test]
    fn fibonacci_is_near_uniform() {
        let d = directions(&Layout::Fibonacci { count: 1000 }, 0).unwrap();
        let mean: DVec3 = d.iter().map(|(v, _)| *v).sum::<DVec3>() / 1000.0;
        assert!(mean.length() < 0.01);
    }

    #[test]
    fn bad_counts_are_errors() {
        assert!(directions(&Layout::Fibonacci { count: 0 }, 0).is_err());
        assert!(directions(
            &Layout::Grid {
                phi_steps: usize::MAX,
                theta_steps: 3
            },
            0
        )
        .is_err());
    }
}
