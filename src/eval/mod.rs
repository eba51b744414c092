//! The near-field quality harness: synthetic luminaires scanned, packed, rendered on the GPU from
//! novel views in every selection mode, and compared with the exact ray-caster, by the definitions of
//! docs/quality-metrics.md (the contract; [`metrics`] implements its per-view part).
//!
//! [`evaluate`] runs one luminaire and returns a [`LuminaireReport`]; [`format_table`] prints reports
//! as the table `lumiview eval` shows; [`write_triptych`] writes a view as render | reference | error.

pub mod metrics;
pub mod rayconv;
pub mod rays;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DVec2, DVec3, Mat4};

use crate::gpu::nearfield::{NearfieldOptions, NearfieldSettings};
use crate::gpu::{GpuError, HostCamera, RenderOptions, RenderTarget, Renderer, TargetDesc};
use crate::nearfield::layout::Layout;
use crate::nearfield::pack::{write_pack, Pack, PackOptions};
use crate::nearfield::proxy::triangles_of;
use crate::nearfield::select::SelectionMode;
use crate::nearfield::synth::{self, render_ortho, render_pinhole, Luminaire, OrthoView, SynthOptions, SynthSource};
use crate::nearfield::{Camera, Intrinsics, RayImageSet, Scan};

pub use metrics::{aggregate, compare_view, compare_view_with_margin, SetMetrics, ViewMetrics};

/// A rendering mode the harness compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EvalMode {
    /// The reference viewer: nearest camera, no proxy.
    Nearest,
    /// Four-nearest inverse-distance blend, no proxy.
    Idw4,
    /// Continuous (barycentric) selection, no proxy.
    Continuous,
    /// Continuous selection with the luminaire's proxy mesh.
    ContinuousProxy,
}

impl EvalMode {
    /// All modes, reference first.
    pub const ALL: [EvalMode; 4] = [
        EvalMode::Nearest,
        EvalMode::Idw4,
        EvalMode::Continuous,
        EvalMode::ContinuousProxy,
    ];

    /// Short label.
    pub fn label(self) -> &'static str {
        match self {
            EvalMode::Nearest => SelectionMode::Nearest.name(),
            EvalMode::Idw4 => SelectionMode::Idw4.name(),
            EvalMode::Continuous => SelectionMode::Continuous.name(),
            EvalMode::ContinuousProxy => "continuous+proxy",
        }
    }

    fn settings(self) -> NearfieldSettings {
        match self {
            EvalMode::Nearest => NearfieldSettings {
                mode: SelectionMode::Nearest,
                proxy: false,
            },
            EvalMode::Idw4 => NearfieldSettings {
                mode: SelectionMode::Idw4,
                proxy: false,
            },
            EvalMode::Continuous => NearfieldSettings {
                mode: SelectionMode::Continuous,
                proxy: false,
            },
            EvalMode::ContinuousProxy => NearfieldSettings {
                mode: SelectionMode::Continuous,
                proxy: true,
            },
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
    /// Where the worst views are written as images (render | reference | error), if anywhere.
    pub images_dir: Option<PathBuf>,
    /// Samples per capture pixel along each axis: 1 point-samples the captures (the contract), N
    /// averages N × N samples over each pixel, as a sensor integrates (for docs/nearfield-rendering.md
    /// "Known limits"; not held to the thresholds).
    pub capture_samples: u32,
    /// View pixels across the smallest feature; `None`: the contract's [`feature_px`] (views are at
    /// most the smallest feature / this apart).
    pub feature_view_px: Option<f64>,
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

/// Where continuous + proxy and `nearest` both sit at the storage's quantisation (fp16 tiles: 2⁻¹¹
/// relative), "not worse" allows this much (docs/quality-metrics.md, "Thresholds").
pub const TIE_FLOOR: f64 = 1.0 / 2048.0;

/// The luminaire the contract reports without thresholds.
pub const NO_THRESHOLD: &str = "reflector";

/// How a luminaire's report stands against the quality contract (docs/quality-metrics.md,
/// "Thresholds"): continuous + proxy under the thresholds, with two measured views per
/// unmeasured one in each set, drawing the sweep's light, and not worse than `nearest` on any metric.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Verdict {
    /// What fails, one line each (empty: the contract is met).
    pub failures: Vec<String>,
    /// Metrics where continuous + proxy is worse than `nearest` by no more than [`TIE_FLOOR`].
    pub ties: Vec<String>,
    /// Comparisons that do not apply (change 9: a `nearest` that draws none of the sweep's light).
    pub not_compared: Vec<String>,
}

/// The contract's verdict on `rep`; `None` where it does not apply: the report lacks `nearest` or
/// continuous + proxy, or the luminaire is [`NO_THRESHOLD`].
pub fn verdict(rep: &LuminaireReport) -> Option<Verdict> {
    let find = |label: &str| rep.modes.iter().find(|m| m.mode == label);
    let (c, n) = (
        find(EvalMode::ContinuousProxy.label())?,
        find(EvalMode::Nearest.label())?,
    );
    if rep.name == NO_THRESHOLD {
        return None;
    }
    let mut v = Verdict::default();
    let mut below = |what: String, value: Option<f64>, limit: f64| match value {
        Some(x) if x < limit => {}
        Some(x) => v.failures.push(format!("{what} {x:.4} ≥ {limit}")),
        None => v.failures.push(format!("{what} n/a")),
    };
    for (set, what) in [
        (&c.outside, "outside"),
        (&c.inside, "inside"),
        (&c.held_out, "held-out"),
    ] {
        below(format!("{what} log RMSE"), set.log_rmse, 0.01);
        below(format!("{what} median"), set.median_rel, 0.02);
    }
    below("flux error".into(), Some(c.flux_error), 0.01);
    below("jump".into(), Some(c.jump), 0.02);
    for (set, what) in [
        (&c.outside, "outside"),
        (&c.inside, "inside"),
        (&c.held_out, "held-out"),
    ] {
        if set.views == 0 || set.views < 2 * set.unmeasured {
            v.failures.push(format!(
                "{what}: {} views measured, {} unmeasured",
                set.views, set.unmeasured
            ));
        }
    }
    let (lo, hi) = c.sweep_light;
    if !lo.is_nan() && (lo < 0.9 || hi > 1.1) {
        v.failures.push(format!(
            "draws {:.1}–{:.1} % of the sweep's light",
            100.0 * lo,
            100.0 * hi
        ));
    }
    let mut not_worse = |what: &str, a: Option<f64>, b: Option<f64>| match (a, b) {
        (None, _) => v.failures.push(format!("{what} n/a")),
        // A nearest value of n/a (no interior left) counts as worse than any number.
        (Some(_), None) => {}
        (Some(a), Some(b)) if a <= b => {}
        (Some(a), Some(b)) if a <= b + TIE_FLOOR => v.ties.push(what.into()),
        (Some(a), Some(b)) => v.failures.push(format!("{what} {a:.6} worse than nearest's {b:.6}")),
    };
    not_worse("outside log RMSE", c.outside.log_rmse, n.outside.log_rmse);
    not_worse("outside median", c.outside.median_rel, n.outside.median_rel);
    not_worse("outside p95", c.outside.p95_rel, n.outside.p95_rel);
    not_worse("inside log RMSE", c.inside.log_rmse, n.inside.log_rmse);
    not_worse("inside median", c.inside.median_rel, n.inside.median_rel);
    not_worse("inside doubled", c.inside.doubled, n.inside.doubled);
    not_worse("held-out log RMSE", c.held_out.log_rmse, n.held_out.log_rmse);
    not_worse(
        "silhouette",
        Some(c.outside.silhouette_px),
        Some(n.outside.silhouette_px),
    );
    not_worse("intensity median", Some(c.intensity_median), Some(n.intensity_median));
    not_worse("intensity max", Some(c.intensity_max), Some(n.intensity_max));
    not_worse("flux", Some(c.flux_error), Some(n.flux_error));
    // Change 9: a nearest that draws under 1 % of the sweep's light in every frame drew none of it.
    if n.sweep_light.1.is_nan() || n.sweep_light.1 >= 0.01 {
        not_worse("jump", Some(c.jump), Some(n.jump));
    } else {
        v.not_compared.push(format!(
            "jump (nearest draws at most {:.4} % of the sweep's light)",
            100.0 * n.sweep_light.1
        ));
    }
    Some(v)
}

/// Results of one mode on one luminaire.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModeReport {
    /// The mode's label.
    pub mode: String,
    /// Views outside the capture sphere.
    pub outside: SetMetrics,
    /// Views inside it.
    pub inside: SetMetrics,
    /// Held-out capture cameras.
    pub held_out: SetMetrics,
    /// Median relative intensity error over the direction grid.
    pub intensity_median: f64,
    /// Largest relative intensity error.
    pub intensity_max: f64,
    /// Relative flux error against the same quadrature of the ray-caster's orthographic intensities.
    pub flux_error: f64,
    /// Largest excess change per sweep step (render change − reference change), as a fraction.
    pub jump: f64,
    /// The least and the most light the mode draws in a sweep frame, as fractions of the
    /// reference's, over the pixels the jump sums (Σ R_k / Σ T_k; NaN for a dark sweep): a mode that
    /// draws under 1 % of it in every frame has no jump to compare (docs/quality-metrics.md,
    /// change 9).
    pub sweep_light: (f64, f64),
    /// Index of the worst outside view (by log RMSE or, lacking it, silhouette).
    pub worst_view: Option<usize>,
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

/// Results on one luminaire.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LuminaireReport {
    /// The luminaire.
    pub name: String,
    /// Capture cameras (after holding out 10 %).
    pub cameras: usize,
    /// Capture image side (px).
    pub capture_px: u32,
    /// Capture pitch at the centre (mm).
    pub pitch_mm: f64,
    /// View pitch at the luminaire's centre (mm): the capture pitch, or finer where the capture cap
    /// leaves the smallest feature under 6 pixels.
    pub view_pitch_mm: f64,
    /// Notes (relaxed rules, moved eyes).
    pub notes: Vec<String>,
    /// The reference quadrature's own flux error against the closed form (point sampling + directions).
    pub quadrature_flux_error: f64,
    /// Per mode.
    pub modes: Vec<ModeReport>,
}

/// A view: pose and intrinsics.
#[derive(Debug, Clone)]
pub struct View {
    /// Camera (position, basis).
    pub camera: Camera,
    /// Intrinsics.
    pub intrinsics: Intrinsics,
    /// How far (px) interior pixels keep from silhouettes and steps: 2, or 2·s where the view is s
    /// times finer than the captures ([`compare_view_with_margin`]).
    pub margin_px: usize,
}

fn direction(gamma_deg: f64, c_deg: f64) -> DVec3 {
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

/// Renders luminance (cd/m²) of every instance in `r` from a pinhole view.
pub fn render_view(r: &mut Renderer, targets: &mut Vec<RenderTarget>, view: &View) -> Result<Vec<f32>, GpuError> {
    let k = &view.intrinsics;
    let near = 0.01f32;
    let far = (view.camera.position_m.length() + 3.0) as f32;
    let cam = HostCamera::from_pinhole(&view.camera, k, near, far);
    render_with(r, targets, &cam, k.width, k.height)
}

fn render_with(
    r: &mut Renderer,
    targets: &mut Vec<RenderTarget>,
    cam: &HostCamera,
    w: u32,
    h: u32,
) -> Result<Vec<f32>, GpuError> {
    let pos = match targets.iter().position(|t| t.desc.width == w && t.desc.height == h) {
        Some(p) => p,
        None => {
            targets.push(RenderTarget::new(&r.ctx, &TargetDesc::luminance(w, h))?);
            if targets.len() > 8 {
                targets.remove(0);
            }
            targets.len() - 1
        }
    };
    let t = &mut targets[pos];
    r.render(t, cam, &RenderOptions::default())?;
    t.read_luminance(&r.ctx)
}

/// Errors of the harness.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The GPU side failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The synthetic or pack side failed.
    #[error(transparent)]
    Nearfield(#[from] crate::nearfield::NearfieldError),
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
    fn view_pitch(&self, eye: DVec3, target: DVec3) -> f64 {
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
    fn view(&self, eye: DVec3, target: DVec3, max_px: u32) -> View {
        let pitch = self.view_pitch(eye, target);
        let mut v = framed_view(eye, target, self.rb, pitch, max_px);
        v.margin_px = margin_px(self.pitch_m / pitch);
        v
    }
}

/// The interior margin (px) of a view `s` times finer than the captures: 2 capture pixels, rounded.
fn margin_px(s: f64) -> usize {
    ((2.0 * s.max(1.0)).round() as usize).max(2)
}

/// The scan of one luminaire: pack, held-out cameras, pitch.
struct Prepared {
    lum: Arc<dyn Luminaire>,
    pack: Arc<Pack>,
    held_out: Vec<(Camera, Intrinsics)>,
    pitch_m: f64,
    view_pitch_m: f64,
    /// The smallest feature (m) and the view pixels across it, where the luminaire has one.
    feature: Option<(f64, f64)>,
    /// The exponent n − 1 of a cosⁿ lobe's luminance, where the luminaire is one.
    lobe: Option<f64>,
    capture_px: u32,
    per_hemisphere: usize,
    rb: f64,
    notes: Vec<String>,
}

fn prepare(name: &str, cfg: &EvalConfig, progress: &dyn Fn(&str)) -> Result<Prepared, EvalError> {
    let lum: Arc<dyn Luminaire> = Arc::from(synth::luminaire(name)?);
    let b = lum.bounds();
    let rb = b.centre().length() + b.radius();
    let mut notes = Vec::new();
    let wanted = smallest_feature_m(name).map_or(0.002, |f| (f / feature_px(name)).min(0.002));
    let view_px = cfg.feature_view_px.unwrap_or(feature_px(name));
    // Image side that frames the bounding sphere at 80 % fill with this pitch at the centre.
    let alpha = (rb / cfg.radius_m).asin();
    let need_px = (2.0 * cfg.radius_m * alpha.tan() / (synth::scan::DEFAULT_FILL * wanted)).ceil() as u32;
    let capture_px = need_px.clamp(32, cfg.max_capture_px);
    if need_px > cfg.max_capture_px {
        notes.push(format!(
            "captures capped at {} px (the pitch rule asks {need_px} px)",
            cfg.max_capture_px
        ));
    }
    if cfg.capture_samples > 1 {
        notes.push(format!(
            "captures average {0} × {0} samples per pixel (the contract point-samples them)",
            cfg.capture_samples
        ));
    }
    if view_px != feature_px(name) && smallest_feature_m(name).is_some() {
        notes.push(format!(
            "views resolve the smallest feature with {view_px} px (the contract: {})",
            feature_px(name)
        ));
    }
    let per_hemisphere = cameras_per_hemisphere(name, cfg.per_hemisphere);
    if per_hemisphere != cfg.per_hemisphere {
        notes.push(format!(
            "{per_hemisphere} cameras per hemisphere (its {:.1}° lobe asks for ≤ 1/8 of it between cameras)",
            angular_feature_deg(name).unwrap_or(0.0)
        ));
    }
    let opts = SynthOptions {
        luminaire: name.into(),
        layout: Layout::Rigo {
            per_hemisphere,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        radius_m: cfg.radius_m,
        size: (capture_px, capture_px),
        ..SynthOptions::default()
    };
    let (_, set) = synth::synth_set(&opts)?;
    let pitch_m = cfg.radius_m / set.intrinsics.focal_px.x;
    // Views resolve the smallest feature with 6 pixels even where the capture cap does not.
    let view_pitch_m = smallest_feature_m(name).map_or(pitch_m, |f| pitch_m.min(f / view_px));
    // Hold out every tenth camera.
    let mut kept = Vec::new();
    let mut held_out = Vec::new();
    for (i, c) in set.cameras.iter().enumerate() {
        if i % 10 == 9 {
            held_out.push((c.clone(), *set.intrinsics_of(i)));
        } else {
            kept.push(c.clone());
        }
    }
    let kept_set = RayImageSet {
        sphere: set.sphere,
        intrinsics: set.intrinsics,
        cameras: kept,
    };
    std::fs::create_dir_all(&cfg.work_dir).map_err(|e| crate::nearfield::NearfieldError::io(&cfg.work_dir, e))?;
    let path = cfg.work_dir.join(if cfg.capture_samples > 1 {
        format!(
            "{name}-rigo{per_hemisphere}-{capture_px}px-{}x{0}.lvpack",
            cfg.capture_samples
        )
    } else {
        format!("{name}-rigo{per_hemisphere}-{capture_px}px.lvpack")
    });
    let reuse = Pack::open(&path)
        .ok()
        .filter(|p| p.image_count() == kept_set.cameras.len() && p.rayset().cameras == kept_set.cameras);
    let pack = match reuse {
        Some(p) => p,
        None => {
            progress(&format!(
                "{name}: scanning {} cameras at {capture_px}² px ({:.2} mm pitch) and packing",
                kept_set.cameras.len(),
                pitch_m * 1e3
            ));
            let source = SynthSource::new(lum.clone(), kept_set.clone(), cfg.capture_samples.max(1))?;
            let scan = Scan {
                set: kept_set,
                source: Box::new(source),
            };
            write_pack(&scan, &path, &PackOptions::default(), &|_, _| {})?;
            Pack::open(&path)?
        }
    };
    Ok(Prepared {
        lum,
        pack: Arc::new(pack),
        held_out,
        pitch_m,
        view_pitch_m,
        feature: smallest_feature_m(name).map(|f| (f, view_px)),
        lobe: lobe_exponent(name).map(|n| n - 1.0),
        capture_px,
        per_hemisphere,
        rb,
        notes,
    })
}

/// Evaluates one synthetic luminaire in every configured mode.
pub fn evaluate(
    r: &mut Renderer,
    name: &str,
    cfg: &EvalConfig,
    progress: &dyn Fn(&str),
) -> Result<LuminaireReport, EvalError> {
    let p = prepare(name, cfg, progress)?;
    let lum = p.lum.as_ref();
    let proxy = triangles_of(&lum.proxy());
    // Everything resident where it fits (the pool is capped at MAX_POOL_PAGES pages): the harness
    // measures the rendering, and the contract's finest scans (strips: 3,485 cameras of 2,354² px)
    // need more than the default budget for one view.
    let opts = NearfieldOptions {
        budget_bytes: 4 << 30,
        ..NearfieldOptions::default()
    };
    let id = r.add_pack(p.pack.clone(), Some(proxy), &opts)?;
    let inst = r.add_instance(id, Mat4::IDENTITY)?;
    let result = evaluate_loaded(r, inst, &p, cfg, progress);
    r.remove_luminaire(id)?;
    let (modes, quad, mut notes) = result?;
    notes.extend(p.notes.iter().cloned());
    Ok(LuminaireReport {
        name: name.into(),
        cameras: p.pack.image_count(),
        capture_px: p.capture_px,
        pitch_mm: p.pitch_m * 1e3,
        view_pitch_mm: p.view_pitch_m * 1e3,
        notes,
        quadrature_flux_error: quad,
        modes,
    })
}

type Loaded = (Vec<ModeReport>, f64, Vec<String>);

fn evaluate_loaded(
    r: &mut Renderer,
    inst: crate::gpu::InstanceId,
    p: &Prepared,
    cfg: &EvalConfig,
    progress: &dyn Fn(&str),
) -> Result<Loaded, EvalError> {
    let lum = p.lum.as_ref();
    let centre = lum.bounds().centre();
    // Views look at the finest feature (the centre where it has none off the centre).
    let target = lum.feature_centre();
    let mut notes = Vec::new();
    let mut targets = Vec::new();
    // Views and their references.
    let mut outside = Vec::new();
    let mut inside = Vec::new();
    for &(g, c) in &cfg.directions_deg {
        let w = direction(g, c);
        for &d in &cfg.outside_m {
            outside.push(p.view(centre + w * d, target, cfg.max_view_px));
        }
        for &d in &cfg.inside_m {
            let min = p.rb + 0.05;
            let d2 = if d < min {
                notes.push(format!("inside eye at {d} m moved out to {min:.3} m"));
                min
            } else {
                d
            };
            inside.push(p.view(centre + w * d2, target, cfg.max_view_px));
        }
    }
    notes.dedup();
    let n_held = cfg.held_out_views.min(p.held_out.len());
    let held: Vec<View> = (0..n_held)
        .map(|i| {
            let (c, k) = &p.held_out[i * p.held_out.len() / n_held.max(1)];
            // From the removed camera's pose at the views' pitch where that is finer than the
            // captures' (a feature the captures resolve with few pixels has no interior at their
            // pitch), cropped about the principal point like the other views.
            let s = (p.pitch_m / p.view_pitch(c.position_m, target)).max(1.0);
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
        .collect();
    progress(&format!(
        "{}: ray-casting {} reference views",
        lum.name(),
        outside.len() + inside.len() + held.len()
    ));
    // Luminance under 10⁻⁷ of the luminaire's largest is dark (change 8): cos¹⁰⁰ seen from γ 55°
    // is 10⁻²⁴ of its peak, which f32 still holds but nobody sees.
    let dark = (1e-7 * lum.max_luminance()) as f32;
    let reference = |v: &View| -> Result<Vec<f32>, EvalError> {
        let mut img = render_pinhole(lum, &v.camera, &v.intrinsics, 1)?.data;
        for x in &mut img {
            if *x < dark {
                *x = 0.0;
            }
        }
        Ok(img)
    };
    let refs_out: Vec<Vec<f32>> = outside.iter().map(reference).collect::<Result<_, _>>()?;
    let refs_in: Vec<Vec<f32>> = inside.iter().map(reference).collect::<Result<_, _>>()?;
    let refs_held: Vec<Vec<f32>> = held.iter().map(reference).collect::<Result<_, _>>()?;
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
        .map(|w| Ok((w, reference_ortho_intensity(lum, w, centre, p.rb, cfg.ortho_px)?)))
        .collect::<Result<_, EvalError>>()?;
    let fib: Vec<(DVec3, f64)> = fib
        .into_iter()
        .filter(|w| w.z < 0.0)
        .map(|w| Ok((w, reference_ortho_intensity(lum, w, centre, p.rb, cfg.ortho_px)?)))
        .collect::<Result<_, EvalError>>()?;
    let quad_weight = 4.0 * std::f64::consts::PI / cfg.flux_directions as f64;
    let phi_t: f64 = fib.iter().map(|(_, i)| i).sum::<f64>() * quad_weight;
    let quad = (phi_t - lum.flux_lm()).abs() / lum.flux_lm();
    // Sweep.
    let spacing = (4.0 * std::f64::consts::PI / (2.0 * p.per_hemisphere as f64))
        .sqrt()
        .to_degrees();
    let steps = ((cfg.sweep_spacings * spacing / cfg.sweep_step_deg).ceil() as usize).max(2);
    let sweep: Vec<View> = (0..=steps)
        .map(|k| {
            let w = direction(40.0, 10.0 + k as f64 * cfg.sweep_step_deg);
            p.view(centre + w * 2.0, target, cfg.max_sweep_px)
        })
        .collect();
    progress(&format!("{}: ray-casting {} sweep references", lum.name(), sweep.len()));
    let refs_sweep: Vec<Vec<f32>> = sweep.iter().map(reference).collect::<Result<_, _>>()?;
    let mut reports = Vec::new();
    for mode in &cfg.modes {
        progress(&format!("{}: rendering {}", lum.name(), mode.label()));
        r.set_nearfield_settings(inst, mode.settings())?;
        let mut set = |views: &[View], refs: &[Vec<f32>]| -> Result<Vec<ViewMetrics>, EvalError> {
            let mut out = Vec::new();
            for (v, t) in views.iter().zip(refs) {
                let img = render_view(r, &mut targets, v)?;
                let k = &v.intrinsics;
                out.push(compare_view_with_margin(
                    &img,
                    t,
                    k.width as usize,
                    k.height as usize,
                    v.margin_px,
                ));
            }
            Ok(out)
        };
        let m_out = set(&outside, &refs_out)?;
        let m_in = set(&inside, &refs_in)?;
        let m_held = set(&held, &refs_held)?;
        let worst_view = m_out
            .iter()
            .enumerate()
            .max_by(|a, b| {
                let key = |m: &ViewMetrics| m.log_rmse.unwrap_or(f64::INFINITY);
                key(a.1).total_cmp(&key(b.1))
            })
            .map(|(i, _)| i);
        if let Some(dir) = &cfg.images_dir {
            let worst_in = m_in
                .iter()
                .enumerate()
                .max_by(|a, b| {
                    let key = |m: &ViewMetrics| m.log_rmse.unwrap_or(f64::INFINITY);
                    key(a.1).total_cmp(&key(b.1))
                })
                .map(|(i, _)| i);
            for (tag, views, refs, which) in [
                ("outside", &outside, &refs_out, worst_view),
                ("inside", &inside, &refs_in, worst_in),
            ] {
                if let Some(i) = which {
                    let img = render_view(r, &mut targets, &views[i])?;
                    let k = &views[i].intrinsics;
                    let f = dir.join(format!(
                        "{}-{}-{tag}-worst.png",
                        lum.name(),
                        mode.label().replace('+', "-")
                    ));
                    std::fs::create_dir_all(dir)
                        .and_then(|_| write_triptych(&f, &img, &refs[i], k.width as usize, k.height as usize))
                        .map_err(|e| crate::nearfield::NearfieldError::io(&f, e))?;
                }
            }
        }
        // Intensity.
        let mut errs = Vec::new();
        for (w, i_t) in &grid {
            let i_hat = ortho_intensity(r, &mut targets, *w, centre, p.rb, cfg.ortho_px)?;
            errs.push((i_hat - i_t).abs() / i_t);
        }
        errs.sort_by(|a, b| a.total_cmp(b));
        let mut phi_hat = 0.0;
        for (w, _) in &fib {
            phi_hat += ortho_intensity(r, &mut targets, *w, centre, p.rb, cfg.ortho_px)?;
        }
        phi_hat *= quad_weight;
        // Sweep.
        let mut prev: Option<Vec<f32>> = None;
        let mut jump: f64 = 0.0;
        let mut sweep_light = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, v) in sweep.iter().enumerate() {
            let img = render_view(r, &mut targets, v)?;
            if let Some(a) = &prev {
                let (t0, t1) = (&refs_sweep[k - 1], &refs_sweep[k]);
                let lmax = t0.iter().cloned().fold(0.0f32, f32::max);
                let mask: Vec<bool> = t0.iter().zip(t1).map(|(x, y)| x.max(*y) > 1e-3 * lmax).collect();
                let jr = metrics::relative_change(a, &img, &mask);
                let jt = metrics::relative_change(t0, t1, &mask);
                jump = jump.max(jr - jt);
                let sum = |img: &[f32]| -> f64 {
                    img.iter()
                        .zip(&mask)
                        .filter(|(_, m)| **m)
                        .map(|(x, _)| f64::from(*x))
                        .sum()
                };
                // Both frames of the step (so the first and the last count too).
                for (frame, reference) in [(a.as_slice(), t0), (img.as_slice(), t1)] {
                    let truth = sum(reference);
                    if truth > 0.0 {
                        let f = sum(frame) / truth;
                        sweep_light = (sweep_light.0.min(f), sweep_light.1.max(f));
                    }
                }
            }
            prev = Some(img);
        }
        if !sweep_light.0.is_finite() {
            sweep_light = (f64::NAN, f64::NAN);
        }
        reports.push(ModeReport {
            mode: mode.label().into(),
            outside: aggregate(&m_out),
            inside: aggregate(&m_in),
            held_out: aggregate(&m_held),
            intensity_median: errs.get(errs.len().saturating_sub(1) / 2).copied().unwrap_or(f64::NAN),
            intensity_max: errs.last().copied().unwrap_or(f64::NAN),
            flux_error: (phi_hat - phi_t).abs() / phi_t,
            jump,
            sweep_light,
            worst_view,
        });
    }
    Ok((reports, quad, notes))
}

/// The ray-caster's Σ T · p² over the pixels of [`ortho_intensity`]'s view (one ray through each pixel
/// centre, as the GPU rasterises them).
pub(crate) fn reference_ortho_intensity(
    lum: &dyn Luminaire,
    w: DVec3,
    centre: DVec3,
    rb: f64,
    px: u32,
) -> Result<f64, EvalError> {
    let size = px.max(8);
    let view = OrthoView {
        direction: w,
        centre_m: centre,
        pixel_m: 2.0 * rb / f64::from(size - 2),
        width: size,
        height: size,
    };
    let pixel = view.pixel_m;
    let img = render_ortho(lum, &view, 1)?;
    Ok(img.data.iter().map(|v| f64::from(*v)).sum::<f64>() * pixel * pixel)
}

/// Î(ω) = Σ L · p² over an orthographic render along −ω framing a sphere of radius `rb` with `px`
/// pixels a side (1 pixel of margin each side).
pub(crate) fn ortho_intensity(
    r: &mut Renderer,
    targets: &mut Vec<RenderTarget>,
    w: DVec3,
    centre: DVec3,
    rb: f64,
    px: u32,
) -> Result<f64, EvalError> {
    let size = px.max(8);
    let pixel = 2.0 * rb / f64::from(size - 2);
    let cam = HostCamera::from_ortho(w, centre, pixel, size, size, rb + 0.05);
    let img = render_with(r, targets, &cam, size, size)?;
    Ok(img.iter().map(|v| f64::from(*v)).sum::<f64>() * pixel * pixel)
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

fn fmt_opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("n/a".into(), |x| format!("{:.*}", digits, x * scale))
}

/// The reports as a text table (one row per luminaire and mode).
pub fn format_table(reports: &[LuminaireReport]) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<11} {:<17} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>7} {:>7}\n",
        "luminaire",
        "mode",
        "logRMSE",
        "med%",
        "p95%",
        "sil px",
        "in lRMSE",
        "in med%",
        "dbl%",
        "held lR",
        "I med%",
        "I max%",
        "flux%",
        "jump%",
        "swp lt%"
    ));
    for rep in reports {
        for m in &rep.modes {
            s.push_str(&format!(
                "{:<11} {:<17} {:>8} {:>8} {:>8} {:>8.2} {:>8} {:>8} {:>8} {:>8} {:>8.3} {:>8.3} {:>8.3} {:>7.3} {:>7.1}\n",
                rep.name,
                m.mode,
                fmt_opt(m.outside.log_rmse, 1.0, 4),
                fmt_opt(m.outside.median_rel, 100.0, 3),
                fmt_opt(m.outside.p95_rel, 100.0, 2),
                m.outside.silhouette_px,
                fmt_opt(m.inside.log_rmse, 1.0, 4),
                fmt_opt(m.inside.median_rel, 100.0, 3),
                fmt_opt(m.inside.doubled, 100.0, 2),
                fmt_opt(m.held_out.log_rmse, 1.0, 4),
                m.intensity_median * 100.0,
                m.intensity_max * 100.0,
                m.flux_error * 100.0,
                m.jump * 100.0,
                m.sweep_light.1 * 100.0,
            ));
        }
        s.push_str(&format!(
            "{:<11} ({} cameras, {}² px, {:.3} mm pitch, views {:.3} mm; views measured outside/inside/held-out {}; quadrature flux error {:.3} %{})\n",
            "",
            rep.cameras,
            rep.capture_px,
            rep.pitch_mm,
            rep.view_pitch_mm,
            rep.modes.first().map_or(String::from("-"), |m| {
                let f = |s: &SetMetrics| format!("{}/{}", s.views, s.views + s.unmeasured);
                format!("{} {} {}", f(&m.outside), f(&m.inside), f(&m.held_out))
            }),
            rep.quadrature_flux_error * 100.0,
            if rep.notes.is_empty() {
                String::new()
            } else {
                format!("; {}", rep.notes.join("; "))
            }
        ));
        if let Some(v) = verdict(rep) {
            let mut line = if v.failures.is_empty() {
                "contract met by continuous+proxy".to_string()
            } else {
                format!("contract NOT met: {}", v.failures.join("; "))
            };
            if !v.ties.is_empty() {
                line.push_str(&format!("; ties with nearest within 2⁻¹¹: {}", v.ties.join(", ")));
            }
            if !v.not_compared.is_empty() {
                line.push_str(&format!("; not compared: {}", v.not_compared.join(", ")));
            }
            s.push_str(&format!("{:<11} {line}\n", ""));
        } else if rep.name == NO_THRESHOLD {
            s.push_str(&format!("{:<11} no threshold (reported only)\n", ""));
        }
    }
    s
}

/// Writes render | reference | relative error (red = render too bright, blue = too dark, full at
/// ±10 %) side by side as an 8-bit PNG; luminance is shown on a log scale over 4 decades below the
/// reference maximum.
pub fn write_triptych(path: &Path, render: &[f32], reference: &[f32], w: usize, h: usize) -> std::io::Result<()> {
    let lmax = reference.iter().cloned().fold(0.0f32, f32::max).max(1e-30);
    let tone = |v: f32| -> u8 {
        if v <= 0.0 {
            return 0;
        }
        let t = ((v / lmax).log10() + 4.0) / 4.0;
        (t.clamp(0.0, 1.0) * 255.0) as u8
    };
    let mut rgb = vec![0u8; 3 * w * 3 * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (a, b) = (render[i], reference[i]);
            let row = y * 3 * w;
            let ta = tone(a);
            let tb = tone(b);
            rgb[3 * (row + x)..3 * (row + x) + 3].copy_from_slice(&[ta, ta, ta]);
            rgb[3 * (row + w + x)..3 * (row + w + x) + 3].copy_from_slice(&[tb, tb, tb]);
            let e = if b > 1e-3 * lmax { (a - b) / b } else { 0.0 };
            let m = ((e.abs() / 0.1).min(1.0) * 255.0) as u8;
            let px = if e > 0.0 { [m, 0, 0] } else { [0, 0, m] };
            rgb[3 * (row + 2 * w + x)..3 * (row + 2 * w + x) + 3].copy_from_slice(&px);
        }
    }
    let f = std::fs::File::create(path)?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(f), 3 * w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header().map_err(std::io::Error::other)?;
    wr.write_image_data(&rgb).map_err(std::io::Error::other)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(log_rmse: f64, median: f64) -> SetMetrics {
        SetMetrics {
            views: 4,
            unmeasured: 1,
            log_rmse: Some(log_rmse),
            median_rel: Some(median),
            p95_rel: Some(median),
            doubled: Some(0.0),
            ..SetMetrics::default()
        }
    }

    fn mode(label: &str, log_rmse: f64, median: f64, jump: f64, light: f64) -> ModeReport {
        ModeReport {
            mode: label.into(),
            outside: set(log_rmse, median),
            inside: set(log_rmse, median),
            held_out: set(log_rmse, median),
            intensity_median: median,
            intensity_max: median,
            flux_error: median,
            jump,
            sweep_light: (light, light),
            worst_view: None,
        }
    }

    fn report(name: &str, c: ModeReport, n: ModeReport) -> LuminaireReport {
        LuminaireReport {
            name: name.into(),
            modes: vec![n, c],
            ..LuminaireReport::default()
        }
    }

    #[test]
    fn the_verdict_holds_thresholds_ties_and_the_sweep_light_rule() {
        let good = || mode("continuous+proxy", 0.001, 0.001, 0.001, 1.0);
        // Better everywhere.
        let v = verdict(&report("disc", good(), mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert_eq!(v, Verdict::default());
        // Worse than nearest by less than 2⁻¹¹: a tie; by more: a failure.
        let v = verdict(&report("cos100", good(), mode("nearest", 1.0, 0.0008, 0.05, 1.0))).unwrap();
        assert!(v.failures.is_empty(), "{v:?}");
        assert!(v.ties.contains(&"outside median".to_string()), "{v:?}");
        let v = verdict(&report("cos100", good(), mode("nearest", 1.0, 0.0001, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("outside median")), "{v:?}");
        // A threshold: median 3 % fails even where nearest is worse.
        let bad = mode("continuous+proxy", 0.001, 0.03, 0.001, 1.0);
        let v = verdict(&report("rect", bad, mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("outside median")), "{v:?}");
        // Change 9: a jump over nearest's is compared while nearest draws the sweep's light …
        let jumpy = || mode("continuous+proxy", 0.001, 0.001, 0.005, 0.95);
        let v = verdict(&report("peak", jumpy(), mode("nearest", 1.0, 0.5, 0.0, 0.02))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("jump")), "{v:?}");
        // … and not where it draws none of it.
        let v = verdict(&report("peak", jumpy(), mode("nearest", 1.0, 0.5, 0.0, 1e-6))).unwrap();
        assert!(v.failures.is_empty() && v.not_compared.len() == 1, "{v:?}");
        // Continuous + proxy must draw the sweep's light itself.
        let dim = mode("continuous+proxy", 0.001, 0.001, 0.001, 0.5);
        let v = verdict(&report("disc", dim, mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.contains("sweep's light")), "{v:?}");
        // Too few measured views.
        let mut few = good();
        few.inside.unmeasured = 3;
        let v = verdict(&report("disc", few, mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("inside:")), "{v:?}");
        // The reflector has no thresholds.
        assert!(verdict(&report("reflector", good(), mode("nearest", 1.0, 0.5, 0.05, 1.0))).is_none());
    }
}
