//! What every mode is compared with ([`References`]): the views of one luminaire (outside and inside
//! the capture sphere, from held-out cameras, along the continuity sweep) with the exact ray-caster's
//! image of each, dark pixels zeroed, and the orthographic intensity and flux directions with the
//! ray-caster's intensity over the same pixels as the render, and the flux they give.

use glam::DVec3;

use super::config::EvalConfig;
use super::prepare::Prepared;
use super::render::reference_ortho_intensity;
use super::views::{direction, fibonacci, View};
use super::EvalError;
use crate::nearfield::synth::{render_pinhole, Luminaire};

/// Views and the ray-caster's image of each (luminance, cd/m², row-major), in the same order.
pub(super) struct Referenced {
    /// The views.
    pub(super) views: Vec<View>,
    /// The reference image of each view.
    pub(super) refs: Vec<Vec<f32>>,
}

/// The orthographic directions, each with the ray-caster's Σ T·p² over the same orthographic pixels as
/// the render ([`reference_ortho_intensity`]), and the reference flux they give.
pub(super) struct OrthoReferences {
    /// The intensity directions: a (γ, C) grid, kept where the closed form is above 1 % of its maximum.
    pub(super) intensity: Vec<(DVec3, f64)>,
    /// The flux directions: the lower hemisphere of `cfg.flux_directions` Fibonacci directions.
    pub(super) flux: Vec<(DVec3, f64)>,
    /// The quadrature weight of one flux direction (sr): 4π / `cfg.flux_directions`.
    pub(super) quad_weight: f64,
    /// The reference flux (lm): the quadrature of the ray-caster's intensities.
    pub(super) phi_t: f64,
    /// The reference flux's own relative error against the luminaire's closed form.
    pub(super) quadrature_flux_error: f64,
}

/// Everything a mode is measured against.
pub(super) struct References {
    /// The bounding box's centre, where the orthographic views look.
    pub(super) centre: DVec3,
    /// Views from outside the capture sphere.
    pub(super) outside: Referenced,
    /// Views from inside it.
    pub(super) inside: Referenced,
    /// Views from held-out capture cameras.
    pub(super) held: Referenced,
    /// The continuity sweep's frames.
    pub(super) sweep: Referenced,
    /// Intensity and flux.
    pub(super) ortho: OrthoReferences,
    /// Notes on the views (inside eyes moved out).
    pub(super) notes: Vec<String>,
}

/// The exact ray-caster's luminance of a view, with dark pixels set to 0.
struct Reference<'a> {
    lum: &'a dyn Luminaire,
    /// Luminance (cd/m²) below which a pixel is dark.
    dark: f32,
}

impl<'a> Reference<'a> {
    fn new(lum: &'a dyn Luminaire) -> Self {
        // Luminance under 10⁻⁷ of the luminaire's largest is dark (change 8): cos¹⁰⁰ seen from γ 55°
        // is 10⁻²⁴ of its peak, which f32 still holds but nobody sees.
        let dark = (1e-7 * lum.max_luminance()) as f32;
        Reference { lum, dark }
    }

    fn image(&self, v: &View) -> Result<Vec<f32>, EvalError> {
        let mut img = render_pinhole(self.lum, &v.camera, &v.intrinsics, 1)?.data;
        for x in &mut img {
            if *x < self.dark {
                *x = 0.0;
            }
        }
        Ok(img)
    }

    /// `views` with their images (the first error stops).
    fn referenced(&self, views: Vec<View>) -> Result<Referenced, EvalError> {
        let refs = views.iter().map(|v| self.image(v)).collect::<Result<_, _>>()?;
        Ok(Referenced { views, refs })
    }
}

/// Ray-casts the references of `p`'s luminaire for `cfg`: the views first, then the orthographic
/// directions, then the sweep, reporting each stage through `progress`.
pub(super) fn references(p: &Prepared, cfg: &EvalConfig, progress: &dyn Fn(&str)) -> Result<References, EvalError> {
    let lum = p.lum.as_ref();
    let centre = lum.bounds().centre();
    // Views look at the finest feature (the centre where it has none off the centre).
    let target = lum.feature_centre();
    let eyes = p.eye_views(cfg, centre, target);
    let held = p.held_out_views(cfg, target);
    progress(&format!(
        "{}: ray-casting {} reference views",
        lum.name(),
        eyes.outside.len() + eyes.inside.len() + held.len()
    ));
    let reference = Reference::new(lum);
    let outside = reference.referenced(eyes.outside)?;
    let inside = reference.referenced(eyes.inside)?;
    let held = reference.referenced(held)?;
    let ortho = ortho_references(lum, p.rb, centre, cfg, progress)?;
    let sweep = p.sweep_views(cfg, centre, target);
    progress(&format!("{}: ray-casting {} sweep references", lum.name(), sweep.len()));
    let sweep = reference.referenced(sweep)?;
    Ok(References {
        centre,
        outside,
        inside,
        held,
        sweep,
        ortho,
        notes: eyes.notes,
    })
}

/// The intensity and flux directions of `lum` with their references, from orthographic views framing
/// the sphere of radius `rb` about `centre`.
fn ortho_references(
    lum: &dyn Luminaire,
    rb: f64,
    centre: DVec3,
    cfg: &EvalConfig,
    progress: &dyn Fn(&str),
) -> Result<OrthoReferences, EvalError> {
    // Intensity and flux directions.
    let grid: Vec<DVec3> = [0.0, 45.0, 90.0]
        .iter()
        .flat_map(|c| [0.0, 10.0, 25.0, 40.0, 55.0, 70.0, 80.0].map(|g| direction(g, *c)))
        .collect();
    let fib = fibonacci(cfg.flux_directions);
    let i_max = grid.iter().map(|w| lum.intensity_cd(*w)).fold(0.0, f64::max);
    // The intensity directions (closed form above 1 % of the maximum) and the flux directions (lower
    // hemisphere), each with the ray-caster's Σ T·p² over the same orthographic pixels as the render.
    progress(&format!("{}: ray-casting the orthographic references", lum.name()));
    let grid: Vec<(DVec3, f64)> = grid
        .into_iter()
        .filter(|w| lum.intensity_cd(*w) > 1e-2 * i_max)
        .map(|w| Ok((w, reference_ortho_intensity(lum, w, centre, rb, cfg.ortho_px)?)))
        .collect::<Result<_, EvalError>>()?;
    let fib: Vec<(DVec3, f64)> = fib
        .into_iter()
        .filter(|w| w.z < 0.0)
        .map(|w| Ok((w, reference_ortho_intensity(lum, w, centre, rb, cfg.ortho_px)?)))
        .collect::<Result<_, EvalError>>()?;
    let quad_weight = 4.0 * std::f64::consts::PI / cfg.flux_directions as f64;
    let phi_t: f64 = fib.iter().map(|(_, i)| i).sum::<f64>() * quad_weight;
    let quad = (phi_t - lum.flux_lm()).abs() / lum.flux_lm();
    Ok(OrthoReferences {
        intensity: grid,
        flux: fib,
        quad_weight,
        phi_t,
        quadrature_flux_error: quad,
    })
}
