//! The synthetic goniophotometer: analytic luminaires with exact ground truth, rendered by exact ray
//! casting into the images a near-field goniophotometer would record.
//!
//! - [`Luminaire`]: geometry and emission of an analytic luminaire, its luminance along any ray
//!   ([`Luminaire::radiance`]), its luminous intensity ([`Luminaire::intensity_cd`]) and flux
//!   ([`Luminaire::flux_lm`]) in closed form (or, for the mirror reflector, by a documented
//!   high-accuracy integral), its bounding box and a proxy mesh of its emitting surfaces.
//! - [`luminaire`]: the registry by name ([`NAMES`]: `disc`, `rect`, `star-panel`, `two-planes`,
//!   `strips`, `led-dots`, `cos1`, `cos10`, `cos100`, `reflector`, `peak`).
//! - [`raycast`]: pinhole renders (capture cameras, novel eyes) and orthographic renders (ground truth
//!   of luminous intensity: I(ω) = Σ L·ΔA), with optional n×n supersampling; only pixels inside the
//!   projection of the bounding box are ray-cast.
//! - [`scan`]: [`SynthOptions`], [`synth_scan`] (a [`Scan`](super::Scan) whose images are rendered on
//!   demand by a [`SynthSource`]) and the parallel [`render_all`].
//! - [`proxy`]: proxy meshes and their glTF 2.0 binary (GLB) form.
//!
//! Frame and units are lumiview's (docs/conventions.md): metres, cd/m², cd, lm; nadir −Z, C0 +X.
//! Every luminaire here emits downwards (into z < its emitting plane) unless stated. The geometry,
//! luminance functions and formulas are written out in docs/synthetic.md.

pub mod emit;
mod luminaires;
pub mod proxy;
pub mod raycast;
mod reflector;
pub mod scan;
mod two_planes;

use glam::DVec3;

use super::error::{NearfieldError, Result};

pub use luminaires::{CosineDisc, LambertDisc, LambertRect, LedDots, Peak, StarPanel, Strips};
pub use proxy::ProxyMesh;
pub use raycast::{ortho_intensity, pixel_bounds, render_ortho, render_pinhole, OrthoView, PixelRect};
pub use reflector::{FluxBudget, Reflector};
pub use scan::{framing_intrinsics, intrinsics_for_fov, render_all, synth_scan, synth_set, SynthOptions, SynthSource};
pub use two_planes::TwoPlanes;

/// An axis-aligned box in the luminaire frame (m). Planar luminaires have zero thickness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner (m).
    pub min: DVec3,
    /// Upper corner (m).
    pub max: DVec3,
}

impl Aabb {
    /// The box's eight corners.
    pub fn corners(&self) -> [DVec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            DVec3::new(a.x, a.y, a.z),
            DVec3::new(b.x, a.y, a.z),
            DVec3::new(a.x, b.y, a.z),
            DVec3::new(b.x, b.y, a.z),
            DVec3::new(a.x, a.y, b.z),
            DVec3::new(b.x, a.y, b.z),
            DVec3::new(a.x, b.y, b.z),
            DVec3::new(b.x, b.y, b.z),
        ]
    }

    /// The box's centre.
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Radius of the smallest sphere around [`Aabb::centre`] that holds the box.
    pub fn radius(&self) -> f64 {
        0.5 * (self.max - self.min).length()
    }

    /// Whether `p` lies inside the box or on its boundary.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// An analytic luminaire of the synthetic goniophotometer.
///
/// Implementations are deterministic and free of noise; they are `Send + Sync` so images render on
/// all cores.
pub trait Luminaire: Send + Sync + std::fmt::Debug {
    /// The registry name (`disc`, `rect`, ...).
    fn name(&self) -> &str;

    /// One line on geometry and emission (dimensions in mm or m, luminances in cd/m²).
    fn description(&self) -> String;

    /// Luminance (cd/m²) arriving at `origin` from direction `dir`, i.e. seen along the ray
    /// `origin + t·dir`, t > 0 (`dir` points from the eye into the scene; any positive length, it is
    /// normalised where the value depends on it). 0 where the ray meets no emitting surface, meets a
    /// surface's non-emitting back or a black housing, or escapes. Exact: no noise, no sampling.
    fn radiance(&self, origin: DVec3, dir: DVec3) -> f64;

    /// Luminous intensity (cd) emitted towards the unit direction `dir` (from the luminaire towards
    /// the observer; photometric (C, γ) is `(sin γ cos C, sin γ sin C, −cos γ)`), in the far field:
    /// I(ω) = ∫ L dA⊥ over the luminaire's visible projected area. `dir` is normalised; a zero or
    /// non-finite `dir` gives 0.
    fn intensity_cd(&self, dir: DVec3) -> f64;

    /// Luminous flux (lm): ∫ I dω over the sphere.
    fn flux_lm(&self) -> f64;

    /// Whether [`Luminaire::intensity_cd`] and [`Luminaire::flux_lm`] are closed forms (true) or
    /// documented numerical integrals (false: the mirror reflector).
    fn closed_form(&self) -> bool {
        true
    }

    /// A box holding every surface that can emit or reflect light towards an observer; rays that
    /// miss it see 0 cd/m².
    fn bounds(&self) -> Aabb;

    /// The largest luminance (cd/m²) any ray can see.
    fn max_luminance(&self) -> f64;

    /// Where close-up views of the luminaire look (m): the centre of its finest feature where that
    /// lies off the centre (`peak`'s spot, the `led-dots` dot nearest the centre), else the centre of
    /// [`Luminaire::bounds`]. A crop about the bounds' centre of an 8 × 4 dot array shows the gap
    /// between four dots, and one of `peak` misses its spot.
    fn feature_centre(&self) -> DVec3 {
        self.bounds().centre()
    }

    /// A triangle mesh of the surfaces where the luminance appears (for parallax-correct reprojection).
    fn proxy(&self) -> ProxyMesh;
}

/// The registry names of the analytic luminaires, in documentation order.
pub const NAMES: &[&str] = &[
    "disc",
    "rect",
    "star-panel",
    "two-planes",
    "strips",
    "led-dots",
    "cos1",
    "cos10",
    "cos100",
    "reflector",
    "peak",
];

/// The analytic luminaire registered as `name` (see [`NAMES`] and docs/synthetic.md).
///
/// Errors: an unknown name ([`NearfieldError::InvalidArgument`] on `luminaire`, listing the names).
pub fn luminaire(name: &str) -> Result<Box<dyn Luminaire>> {
    Ok(match name {
        "disc" => Box::new(LambertDisc::standard()),
        "rect" => Box::new(LambertRect::standard()),
        "star-panel" => Box::new(StarPanel::standard()),
        "two-planes" => Box::new(TwoPlanes::standard()),
        "strips" => Box::new(Strips::standard()),
        "led-dots" => Box::new(LedDots::standard()),
        "cos1" => Box::new(CosineDisc::new("cos1", 1.0)?),
        "cos10" => Box::new(CosineDisc::new("cos10", 10.0)?),
        "cos100" => Box::new(CosineDisc::new("cos100", 100.0)?),
        "reflector" => Box::new(Reflector::standard()),
        "peak" => Box::new(Peak::standard()),
        _ => {
            return Err(NearfieldError::invalid(
                "luminaire",
                format!("unknown name '{name}'; expected one of: {}", NAMES.join(", ")),
            ))
        }
    })
}

/// The unit version of `dir`, or `None` when it is zero or not finite.
pub(crate) fn unit(dir: DVec3) -> Option<DVec3> {
    let l = dir.length();
    (l.is_finite() && l > 0.0).then(|| dir / l)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_resolves_and_unknown_names_are_errors() {
        for n in NAMES {
            let l = luminaire(n).unwrap();
            assert_eq!(l.name(), *n);
            assert!(l.flux_lm() > 0.0 && l.flux_lm().is_finite(), "{n}");
            assert!(l.max_luminance() > 0.0, "{n}");
        }
        let e = luminaire("nope").unwrap_err().to_string();
        assert!(
            e.contains("luminaire") && e.contains("nope") && e.contains("disc"),
            "{e}"
        );
    }

    #[test]
    fn aabb_helpers() {
        let b = Aabb {
            min: DVec3::new(-1.0, -2.0, 0.0),
            max: DVec3::new(1.0, 2.0, 0.0),
        };
        assert_eq!(b.centre(), DVec3::ZERO);
        assert!((b.radius() - 5f64.sqrt()).abs() < 1e-12);
        assert!(b.contains(DVec3::new(1.0, 0.0, 0.0)) && !b.contains(DVec3::new(0.0, 0.0, 0.1)));
        assert_eq!(b.corners().len(), 8);
    }
}
