//! Where the harness looks from: a [`View`] (pose, intrinsics, interior margin), a view framing the
//! luminaire's bounding sphere at a pitch ([`framed_view`]), the pitch a luminaire's features and lobe
//! ask for (`Prepared::view_pitch`), and directions on the sphere: photometric (γ, C) and near-uniform
//! ([`fibonacci`]).

use glam::{DVec2, DVec3};

use super::config::{EvalConfig, LOBE_STEP};
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

/// The views from eyes outside and inside the capture sphere ([`Prepared::eye_views`]).
pub(super) struct EyeViews {
    /// From every direction at every outside distance.
    pub(super) outside: Vec<View>,
    /// From every direction at every inside distance.
    pub(super) inside: Vec<View>,
    /// Inside eyes moved out of the bounding sphere, one line each (duplicates in a row dropped).
    pub(super) notes: Vec<String>,
}

impl Prepared {
    /// Views from every configured direction (γ, C) at each outside and inside eye distance from
    /// `centre`, looking at `target`; an inside eye closer than the bounding sphere + 5 cm is moved out
    /// to it (and noted).
    pub(super) fn eye_views(&self, cfg: &EvalConfig, centre: DVec3, target: DVec3) -> EyeViews {
        let mut notes = Vec::new();
        let mut outside = Vec::new();
        let mut inside = Vec::new();
        for &(g, c) in &cfg.directions_deg {
            let w = direction(g, c);
            for &d in &cfg.outside_m {
                outside.push(self.view(centre + w * d, target, cfg.max_view_px));
            }
            for &d in &cfg.inside_m {
                let min = self.rb + 0.05;
                let d2 = if d < min {
                    notes.push(format!("inside eye at {d} m moved out to {min:.3} m"));
                    min
                } else {
                    d
                };
                inside.push(self.view(centre + w * d2, target, cfg.max_view_px));
            }
        }
        notes.dedup();
        EyeViews { outside, inside, notes }
    }

    /// Views from up to `cfg.held_out_views` held-out capture cameras (evenly drawn from them), each
    /// cropped about `target`; cameras facing away from the luminaire's lit side are left out.
    pub(super) fn held_out_views(&self, cfg: &EvalConfig, target: DVec3) -> Vec<View> {
        let n_held = cfg.held_out_views.min(self.held_out.len());
        (0..n_held)
            .map(|i| {
                let (c, k) = &self.held_out[i * self.held_out.len() / n_held.max(1)];
                // From the removed camera's pose at the views' pitch where that is finer than the
                // captures' (a feature the captures resolve with few pixels has no interior at their
                // pitch), cropped about the principal point like the other views.
                let s = (self.pitch_m / self.view_pitch(c.position_m, target)).max(1.0);
                let side = |n: u32| ((f64::from(n) * s).ceil() as u32).clamp(8, cfg.max_view_px.max(8));
                let (w, h) = if s > 1.0 {
                    (side(k.width), side(k.height))
                } else {
                    (k.width, k.height)
                };
                // The crop is centred on the feature's pixel, kept inside the image.
                let full = DVec2::new(f64::from(k.width), f64::from(k.height)) * s;
                let crop = DVec2::new(f64::from(w), f64::from(h));
                let rel = target - c.position_m;
                let z = rel.dot(c.forward).max(1e-9);
                let at = k.principal_px * s + k.focal_px * s * DVec2::new(rel.dot(c.right), rel.dot(c.down)) / z;
                let shift = (at - 0.5 * crop).clamp(DVec2::ZERO, (full - crop).max(DVec2::ZERO));
                View {
                    camera: c.clone(),
                    intrinsics: Intrinsics {
                        width: w,
                        height: h,
                        principal_px: k.principal_px * s - shift,
                        focal_px: k.focal_px * s,
                    },
                    margin_px: margin_px(s),
                }
            })
            // Held-out cameras that see nothing (the dark hemisphere) measure nothing.
            .filter(|v| v.camera.forward.z > 0.05)
            .collect()
    }

    /// The continuity sweep: eyes 2 m from `centre` at γ 40°, C from 10° in `cfg.sweep_step_deg`
    /// steps over `cfg.sweep_spacings` camera spacings (at least 2 steps), looking at `target`.
    pub(super) fn sweep_views(&self, cfg: &EvalConfig, centre: DVec3, target: DVec3) -> Vec<View> {
        let spacing = (4.0 * std::f64::consts::PI / (2.0 * self.per_hemisphere as f64))
            .sqrt()
            .to_degrees();
        let steps = ((cfg.sweep_spacings * spacing / cfg.sweep_step_deg).ceil() as usize).max(2);
        (0..=steps)
            .map(|k| {
                let w = direction(40.0, 10.0 + k as f64 * cfg.sweep_step_deg);
                self.view(centre + w * 2.0, target, cfg.max_sweep_px)
            })
            .collect()
    }
}
