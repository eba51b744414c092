//! Where the harness looks from: a [`View`] (pose, intrinsics, interior margin), a view framing the
//! luminaire's bounding sphere at a pitch ([`framed_view`]), the pitch a luminaire's features and lobe
//! ask for (`Prepared::view_pitch`), and directions on the sphere: photometric (γ, C) and near-uniform
//! ([`fibonacci`]).

use glam::{DVec2, DVec3};

use super::config::LOBE_STEP;
use super::prepare::Prepared;
use crate::nearfield::{Camera, Intrinsics};

/// A view: pose and intrinsics.
#[derive(Debug, Clone)]
pub struct View {
    /// Camera (position, basis).
    pub camera: Camera,
    /// Intrinsics.
    pub intrinsics: Intrinsics,
    /// How far (px) interior pixels keep from silhouettes and steps: 2, or 2·s where the view is s
    /// times finer than the captures ([`compare_view_with_margin`](super::compare_view_with_margin)).
    pub margin_px: usize,
}

pub(super) fn direction(gamma_deg: f64, c_deg: f64) -> DVec3 {
    let (g, c) = (gamma_deg.to_radians(), c_deg.to_radians());
    DVec3::new(g.sin() * c.cos(), g.sin() * c.sin(), -g.cos())
}

/// A view from `eye` looking at `target` with pixel pitch `pitch_m` at the target, framing a sphere
/// of radius `rb` (cropped to `max_px`).
pub fn framed_view(eye: DVec3, target: DVec3, rb: f64, pitch_m: f64, max_px: u32) -> View {
    let to = target - eye;
    let d = to.length();
    let f = d / pitch_m;
    let half_angle = (rb / d).min(0.999).asin();
    let size = ((2.0 * f * half_angle.tan() / 0.9).ceil() as u32).clamp(8, max_px.max(8));
    View {
        camera: Camera::looking_at(eye, target, "view"),
        intrinsics: Intrinsics {
            width: size,
            height: size,
            principal_px: DVec2::splat(0.5 * f64::from(size)),
            focal_px: DVec2::splat(f),
        },
        margin_px: 2,
    }
}

impl Prepared {
    /// The pitch (m, at the feature) of a view along the unit direction `forward`: the captures', or
    /// finer where the smallest feature as the view sees it, foreshortened by the cosine between the
    /// view and the luminaire's axis (its features lie in planes z = const), would get fewer pixels
    /// than its rule asks (changes 2 and 7 of docs/quality-metrics.md).
    ///
    /// For a cosⁿ lobe (change 8) the pitch is also fine enough that the luminance changes by at most
    /// [`LOBE_STEP`] per pixel: across a view from distance d a pixel turns the direction to the eye
    /// by pitch / d, and ln L = (n − 1) ln cos γ changes by (n − 1) tan γ per radian.
    pub(super) fn view_pitch(&self, eye: DVec3, target: DVec3) -> f64 {
        let to = target - eye;
        let forward = to.normalize_or_zero();
        let pitch = self.feature.map_or(self.pitch_m, |(f, px)| {
            self.pitch_m.min(f * forward.z.abs().max(0.05) / px)
        });
        match self.lobe {
            Some(k) => {
                let c = forward.z.abs().clamp(0.05, 1.0);
                let tan = (1.0 - c * c).sqrt() / c;
                let rate = k * tan / to.length().max(1e-3);
                if rate > 0.0 {
                    pitch.min(LOBE_STEP / rate).max(pitch / 8.0)
                } else {
                    pitch
                }
            }
            None => pitch,
        }
    }

    /// A view along `forward` at [`Prepared::view_pitch`], from `eye` looking at `target`, with its
    /// interior margin.
    pub(super) fn view(&self, eye: DVec3, target: DVec3, max_px: u32) -> View {
        let pitch = self.view_pitch(eye, target);
        let mut v = framed_view(eye, target, self.rb, pitch, max_px);
        v.margin_px = margin_px(self.pitch_m / pitch);
        v
    }
}

/// The interior margin (px) of a view `s` times finer than the captures: 2 capture pixels, rounded.
pub(super) fn margin_px(s: f64) -> usize {
    ((2.0 * s.max(1.0)).round() as usize).max(2)
}

/// `n` near-uniform directions on the sphere (Fibonacci spiral).
pub fn fibonacci(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let rho = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            DVec3::new(rho * a.cos(), rho * a.sin(), z)
        })
        .collect()
}
