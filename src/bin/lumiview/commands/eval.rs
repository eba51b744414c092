//! `lumiview eval`: the near-field quality harness (docs/quality-metrics.md). Synthetic luminaires are
//! scanned, packed, rendered on the GPU in every selection mode from views outside and inside the
//! capture sphere, from held-out capture cameras, orthographically (intensity, flux) and along a sweep
//! in 0.05° steps, and compared with the exact ray-caster; the table goes to stdout, the worst views
//! to `--images` as PNGs.

use std::path::PathBuf;
use std::sync::LazyLock;

use clap::Args;
use lumiview::eval::{evaluate, format_table, EvalConfig, EvalMode};
use lumiview::gpu::{ContextDesc, Renderer};
use lumiview::nearfield::synth::NAMES;

use super::CliResult;

/// Every mode's label, comma-separated: `--modes`' default.
static ALL_MODES: LazyLock<String> = LazyLock::new(|| EvalMode::ALL.map(|m| m.label()).join(","));

/// Arguments of `lumiview eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Synthetic luminaires to evaluate (repeat or comma-separate); default: all of them.
    #[arg(long = "luminaire", value_delimiter = ',', value_name = "NAME")]
    pub luminaires: Vec<String>,
    /// Modes to compare: nearest, idw4, continuous, continuous+proxy (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = ALL_MODES.as_str())]
    pub modes: Vec<String>,
    /// `rigo` capture cameras per hemisphere (10 % are held out).
    #[arg(long, default_value_t = 2000)]
    pub cameras: usize,
    /// Largest capture image side in pixels (the pitch rule is relaxed beyond it, and the table says so).
    #[arg(long, default_value_t = 1024)]
    pub max_capture_px: u32,
    /// Largest view side in pixels (larger views are cropped to their centre).
    #[arg(long, default_value_t = 256)]
    pub max_view_px: u32,
    /// Camera spacings the continuity sweep covers (0.05° steps).
    #[arg(long, default_value_t = 3.0)]
    pub sweep_spacings: f64,
    /// Side of the orthographic views for intensity and flux, in pixels (they frame the bounding sphere).
    #[arg(long, default_value_t = 1024)]
    pub ortho_px: u32,
    /// Samples per capture pixel along each axis: 1 point-samples (the quality contract), N averages
    /// N × N over each pixel as a sensor does (docs/nearfield-rendering.md, "Known limits").
    #[arg(long, default_value_t = 1)]
    pub capture_samples: u32,
    /// View pixels across a luminaire's smallest feature (default: the contract's, 20 for a dot or a
    /// spot, 6 for a strip or a gap).
    #[arg(long)]
    pub feature_px: Option<f64>,
    /// Also render continuous selection with the proxy reconstructed from the scan (docs/proxy.md),
    /// as `continuous+rec-proxy`, beside the true proxy (continuous+proxy) and none (continuous).
    #[arg(long)]
    pub reconstructed_proxy: bool,
    /// Where synthetic scans are packed and cached (reused when the cameras match).
    #[arg(long, default_value = "target/eval")]
    pub work_dir: PathBuf,
    /// Write the worst outside and inside view of each luminaire and mode here as PNGs
    /// (render | reference | relative error), and with --reconstructed-proxy the proxy as
    /// NAME-rec-proxy.glb.
    #[arg(long, value_name = "DIR")]
    pub images: Option<PathBuf>,
    /// Also write the table here.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
}

fn parse_mode(s: &str) -> Result<EvalMode, String> {
    EvalMode::ALL
        .into_iter()
        .find(|m| m.label() == s.trim())
        .ok_or_else(|| {
            let names: Vec<String> = EvalMode::ALL.iter().map(|m| m.label()).collect();
            format!("--modes: unknown mode '{s}'; expected {}", names.join(", "))
        })
}

/// Runs `lumiview eval`.
pub fn eval(a: &EvalArgs) -> CliResult {
    let names: Vec<String> = if a.luminaires.is_empty() {
        NAMES.iter().map(|s| s.to_string()).collect()
    } else {
        a.luminaires.clone()
    };
    for n in &names {
        if !NAMES.contains(&n.as_str()) {
            return Err(format!("--luminaire: unknown name '{n}'; expected one of: {}", NAMES.join(", ")).into());
        }
    }
    let modes = a.modes.iter().map(|m| parse_mode(m)).collect::<Result<Vec<_>, _>>()?;
    if a.cameras < 20 {
        return Err(format!("--cameras {}: expected at least 20 per hemisphere", a.cameras).into());
    }
    if !(a.sweep_spacings.is_finite() && a.sweep_spacings > 0.0) {
        return Err(format!("--sweep-spacings {}: expected a positive number", a.sweep_spacings).into());
    }
    if !(64..=4096).contains(&a.ortho_px) {
        return Err(format!("--ortho-px {}: expected 64…4096", a.ortho_px).into());
    }
    if !(1..=8).contains(&a.capture_samples) {
        return Err(format!("--capture-samples {}: expected 1…8", a.capture_samples).into());
    }
    if let Some(f) = a.feature_px.filter(|f| !(f.is_finite() && (1.0..=64.0).contains(f))) {
        return Err(format!("--feature-px {f}: expected 1…64").into());
    }
    let cfg = EvalConfig {
        per_hemisphere: a.cameras,
        ortho_px: a.ortho_px,
        capture_samples: a.capture_samples,
        feature_view_px: a.feature_px,
        reconstructed_proxy: a.reconstructed_proxy,
        max_capture_px: a.max_capture_px.max(32),
        max_view_px: a.max_view_px.max(16),
        sweep_spacings: a.sweep_spacings,
        modes,
        work_dir: a.work_dir.clone(),
        images_dir: a.images.clone(),
        ..EvalConfig::default()
    };
    let mut r = Renderer::new(&ContextDesc::default())?;
    eprintln!("lumiview eval on {}", r.ctx.caps.adapter_name);
    let progress = |m: &str| eprintln!("  {m}");
    let mut reports = Vec::new();
    for n in &names {
        let rep = evaluate(&mut r, n, &cfg, &progress)?;
        // Print as we go: a full run takes a while.
        eprint!("{}", format_table(std::slice::from_ref(&rep)));
        reports.push(rep);
    }
    let table = format_table(&reports);
    print!("{table}");
    if let Some(o) = &a.output {
        std::fs::write(o, &table).map_err(|e| format!("{}: {e}", o.display()))?;
    }
    Ok(())
}

/// Arguments of `lumiview eval-rays`.
#[derive(Args, Debug)]
pub struct EvalRaysArgs {
    /// Synthetic luminaires (repeat or comma-separate).
    #[arg(
        long = "luminaire",
        value_delimiter = ',',
        value_name = "NAME",
        default_value = "disc,led-dots,cos10,two-planes"
    )]
    pub luminaires: Vec<String>,
    /// Ray counts N (comma-separated; 1e5 and 100000 both work), each ≤ 5e7.
    #[arg(long, value_delimiter = ',', default_value = "1e4,1e5,1e6,1e7")]
    pub rays: Vec<String>,
    /// Rays of the kernel-matched truth per estimated ray.
    #[arg(long, default_value_t = 20.0)]
    pub truth_factor: f64,
    /// Most rays of a kernel-matched truth (forward-traced in batches of 4 million).
    #[arg(long, default_value = "2e7")]
    pub truth_max: String,
    /// Side of the orthographic views for the flux, in pixels.
    #[arg(long, default_value_t = 128)]
    pub ortho_px: u32,
    /// Where the packs are written (overwritten).
    #[arg(long, default_value = "target/eval-rays")]
    pub work_dir: PathBuf,
    /// Write each row's first outside view here as PNGs (estimate | truth | relative error, ±10 %
    /// full scale), against each truth.
    #[arg(long, value_name = "DIR")]
    pub images: Option<PathBuf>,
    /// Also write the table here.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
}

pub(crate) fn parse_count(what: &str, s: &str) -> Result<u64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{what} '{s}': expected a number of rays such as 1e6"))?;
    if !(v.is_finite() && v >= 100.0 && v <= lumiview::nearfield::synth::emit::MAX_RAYS as f64) {
        return Err(format!(
            "{what} '{s}': expected 100…{}",
            lumiview::nearfield::synth::emit::MAX_RAYS
        ));
    }
    Ok(v.round() as u64)
}

/// Runs `lumiview eval-rays`: the ray-file convergence table of docs/quality-metrics.md ("Ray
/// files").
pub fn eval_rays(a: &EvalRaysArgs) -> CliResult {
    use lumiview::eval::rayconv::{format_table, run, RayConvConfig};
    for n in &a.luminaires {
        if !NAMES.contains(&n.as_str()) {
            return Err(format!("--luminaire: unknown name '{n}'; expected one of: {}", NAMES.join(", ")).into());
        }
    }
    let rays = a
        .rays
        .iter()
        .map(|s| parse_count("--rays", s))
        .collect::<Result<Vec<_>, _>>()?;
    if !(a.truth_factor.is_finite() && (1.0..=1000.0).contains(&a.truth_factor)) {
        return Err(format!("--truth-factor {}: expected 1…1000", a.truth_factor).into());
    }
    let truth_max = parse_count("--truth-max", &a.truth_max)?;
    if !(64..=4096).contains(&a.ortho_px) {
        return Err(format!("--ortho-px {}: expected 64…4096", a.ortho_px).into());
    }
    let cfg = RayConvConfig {
        rays,
        truth_factor: a.truth_factor,
        truth_max_rays: truth_max,
        ortho_px: a.ortho_px,
        work_dir: a.work_dir.clone(),
        images_dir: a.images.clone(),
        ..RayConvConfig::default()
    };
    let mut r = Renderer::new(&ContextDesc::default())?;
    eprintln!("lumiview eval-rays on {}", r.ctx.caps.adapter_name);
    let start = std::time::Instant::now();
    let progress = |m: &str| eprintln!("  [{:>6.0} s] {m}", start.elapsed().as_secs_f64());
    let mut rows = Vec::new();
    let mut failed = Vec::new();
    for n in &a.luminaires {
        let mut done = Vec::new();
        let result = run(&mut r, n, &cfg, &progress, &mut |row| {
            // Print as we go: a full run takes a while.
            eprint!("{}", format_table(std::slice::from_ref(row)));
            done.push(row.clone());
        });
        // A luminaire that fails (e.g. too few effective rays) is named; the others still run.
        if let Err(e) = result {
            eprintln!("lumiview: error: {n}: {e}");
            failed.push(format!("FAIL {n}: {e}"));
        }
        rows.extend(done);
    }
    let mut table = format_table(&rows);
    for f in &failed {
        table.push_str(f);
        table.push('\n');
    }
    print!("{table}");
    if let Some(o) = &a.output {
        std::fs::write(o, &table).map_err(|e| format!("{}: {e}", o.display()))?;
    }
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!("{} of {} luminaires failed", failed.len(), a.luminaires.len()).into())
    }
}
