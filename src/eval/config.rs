//! What the harness does: the modes it compares ([`EvalMode`]), its configuration ([`EvalConfig`],
//! docs/quality-metrics.md "Evaluation set-up"), and the contract's per-luminaire rules that size the
//! captures and views: the smallest feature and the pixels across it ([`smallest_feature_m`],
//! [`feature_px`]), a cosⁿ lobe's angular feature and the cameras it asks for
//! ([`angular_feature_deg`], [`cameras_per_hemisphere`]).

use std::path::PathBuf;

use crate::gpu::nearfield::NearfieldSettings;
use crate::nearfield::select::SelectionMode;
use crate::nearfield::synth;

/// A rendering mode the harness compares: a camera selection, with or without the luminaire's proxy
/// mesh. The modes follow [`SelectionMode::ALL`], so a new selection mode is compared without a change
/// here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EvalMode {
    /// How cameras are chosen and weighted.
    pub selection: SelectionMode,
    /// Whether the luminaire's proxy mesh reprojects the captures (parallax-correct).
    pub proxy: bool,
}

impl EvalMode {
    /// The reference viewer: nearest camera, no proxy.
    pub const NEAREST: EvalMode = EvalMode {
        selection: SelectionMode::Nearest,
        proxy: false,
    };

    /// Continuous selection with the luminaire's proxy mesh: the mode the quality contract holds.
    pub const CONTINUOUS_PROXY: EvalMode = EvalMode {
        selection: SelectionMode::Continuous,
        proxy: true,
    };

    /// All modes, reference first: every selection mode without the proxy, in [`SelectionMode::ALL`]'s
    /// order, then [`EvalMode::CONTINUOUS_PROXY`].
    pub const ALL: [EvalMode; SelectionMode::ALL.len() + 1] = {
        let mut all = [EvalMode::CONTINUOUS_PROXY; SelectionMode::ALL.len() + 1];
        let mut i = 0;
        while i < SelectionMode::ALL.len() {
            all[i] = EvalMode {
                selection: SelectionMode::ALL[i],
                proxy: false,
            };
            i += 1;
        }
        all
    };

    /// Short label: the selection's [`SelectionMode::name`], with `+proxy` where the proxy is used
    /// (`nearest`, `idw4`, `continuous`, `continuous+proxy`).
    pub fn label(self) -> String {
        if self.proxy {
            format!("{}+proxy", self.selection.name())
        } else {
            self.selection.name().to_string()
        }
    }

    pub(super) fn settings(self) -> NearfieldSettings {
        NearfieldSettings {
            mode: self.selection,
            proxy: self.proxy,
        }
    }
}

/// What the harness does (docs/quality-metrics.md, "Evaluation set-up").
#[derive(Debug, Clone, PartialEq)]
pub struct EvalConfig {
    /// `rigo` cameras per hemisphere of the scan.
    pub per_hemisphere: usize,
    /// Capture radius (m).
    pub radius_m: f64,
    /// Largest capture image side (px); the pitch rule is relaxed (and the report says so) beyond it.
    pub max_capture_px: u32,
    /// Largest view side (px): larger views are cropped to their centre (a close-up).
    pub max_view_px: u32,
    /// Eye distances (m) outside the capture sphere.
    pub outside_m: Vec<f64>,
    /// Eye distances (m) inside it.
    pub inside_m: Vec<f64>,
    /// View directions (γ, C) in degrees.
    pub directions_deg: Vec<(f64, f64)>,
    /// Held-out views (at most).
    pub held_out_views: usize,
    /// Fibonacci directions of the flux quadrature over the sphere.
    pub flux_directions: usize,
    /// Side (px) of the orthographic views, which frame the bounding sphere (the pitch follows).
    pub ortho_px: u32,
    /// Sweep: camera spacings covered, and the step (degrees).
    pub sweep_spacings: f64,
    /// Sweep step (degrees).
    pub sweep_step_deg: f64,
    /// Largest sweep view side (px).
    pub max_sweep_px: u32,
    /// Modes compared.
    pub modes: Vec<EvalMode>,
    /// Where packs are written.
    pub work_dir: PathBuf,
    /// Where the worst views are written as images (render | reference | error), and the
    /// reconstructed proxy as `NAME-rec-proxy.glb`, if anywhere.
    pub images_dir: Option<PathBuf>,
    /// Samples per capture pixel along each axis: 1 point-samples the captures (the contract), N
    /// averages N × N samples over each pixel, as a sensor integrates (for docs/nearfield-rendering.md
    /// "Known limits"; not held to the thresholds).
    pub capture_samples: u32,
    /// View pixels across the smallest feature; `None`: the contract's [`feature_px`] (views are at
    /// most the smallest feature / this apart).
    pub feature_view_px: Option<f64>,
    /// Also render continuous selection with the proxy reconstructed from the scan (docs/proxy.md),
    /// reported as `continuous+rec-proxy`.
    pub reconstructed_proxy: bool,
}

impl Default for EvalConfig {
    fn default() -> Self {
        EvalConfig {
            per_hemisphere: 2000,
            radius_m: synth::scan::DEFAULT_RADIUS_M,
            max_capture_px: 1024,
            max_view_px: 256,
            outside_m: vec![1.5, 2.5, 5.0],
            inside_m: vec![0.3, 0.6, 1.0],
            directions_deg: vec![(0.0, 10.0), (30.0, 100.0), (55.0, 200.0), (75.0, 300.0)],
            held_out_views: 12,
            flux_directions: 96,
            ortho_px: 1024,
            sweep_spacings: 3.0,
            sweep_step_deg: 0.05,
            max_sweep_px: 128,
            modes: EvalMode::ALL.to_vec(),
            work_dir: std::env::temp_dir().join("lumiview-eval"),
            images_dir: None,
            capture_samples: 1,
            feature_view_px: None,
            reconstructed_proxy: false,
        }
    }
}

/// The smallest feature (m) of a synthetic luminaire the captures must resolve (docs/synthetic.md):
/// strip width, dot diameter, tile gap, peak diameter; `None` for smooth luminaires.
pub fn smallest_feature_m(name: &str) -> Option<f64> {
    match name {
        "strips" => Some(0.001),
        "led-dots" => Some(0.003),
        "peak" => Some(0.005),
        "two-planes" => Some(0.010),
        "star-panel" => Some(0.010),
        "reflector" => Some(0.006),
        _ => None,
    }
}

/// Pixels across a luminaire's smallest feature that its captures and views need (the contract's
/// pitch rule, change 7): 20 for a compact feature (a dot, a spot: a disc d pixels across has about
/// π(d/2 − 2√2)² interior pixels, 50 of them need d ≥ 13.6, and seen at γ 55° with a margin of
/// 2 capture pixels from a step (peak) it needs d ≈ 20), 6 for an elongated one (a strip, a gap, a
/// spoke: its interior is a band along it).
pub fn feature_px(name: &str) -> f64 {
    match name {
        "led-dots" | "peak" => 20.0,
        _ => 6.0,
    }
}

/// Largest change of ln L per view pixel across a cosⁿ lobe (change 8): 4 steps of it stay within
/// the interior test's factor 1.25 (ln 1.25 = 0.223) with room to spare.
pub const LOBE_STEP: f64 = 0.04;

/// The exponent n of a synthetic luminaire's cosⁿ intensity lobe (`cos10`, `cos100`; `None` for the
/// others: `cos1` is Lambertian).
pub fn lobe_exponent(name: &str) -> Option<f64> {
    match name {
        "cos10" => Some(10.0),
        "cos100" => Some(100.0),
        _ => None,
    }
}

/// The angular feature (degrees) of a synthetic luminaire's directional distribution that the camera
/// layout must resolve: the half-power half-width of a cosⁿ lobe, acos(0.5^(1/n)); `None` for
/// luminaires whose luminance does not depend on the direction (Lambertian) or has no lobe to sample
/// (the reflector's highlights are judged without a threshold).
pub fn angular_feature_deg(name: &str) -> Option<f64> {
    let n = lobe_exponent(name)?;
    Some(0.5f64.powf(1.0 / n).acos().to_degrees())
}

/// `rigo` cameras per hemisphere for a luminaire: `base`, or more where its angular feature asks for a
/// spacing of at most 1/8 of it (spacing ≈ √(2π / N) rad for N cameras per hemisphere), capped at the
/// full-size layout of 28,000.
pub fn cameras_per_hemisphere(name: &str, base: usize) -> usize {
    let Some(f) = angular_feature_deg(name) else {
        return base;
    };
    let spacing = (f / 8.0).to_radians();
    let need = (2.0 * std::f64::consts::PI / (spacing * spacing)).ceil() as usize;
    base.max(need.min(28_000))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_modes_follow_the_selection_modes_then_continuous_with_the_proxy() {
        let n = SelectionMode::ALL.len();
        assert_eq!(EvalMode::ALL[0], EvalMode::NEAREST, "the reference first");
        for (m, s) in EvalMode::ALL[..n].iter().zip(SelectionMode::ALL) {
            assert_eq!(m.label(), s.name());
            assert_eq!(m.settings(), NearfieldSettings { mode: s, proxy: false });
        }
        assert_eq!(EvalMode::ALL[n], EvalMode::CONTINUOUS_PROXY);
        assert_eq!(EvalMode::CONTINUOUS_PROXY.label(), "continuous+proxy");
        assert_eq!(
            EvalMode::CONTINUOUS_PROXY.settings(),
            NearfieldSettings {
                mode: SelectionMode::Continuous,
                proxy: true
            }
        );
    }
}
