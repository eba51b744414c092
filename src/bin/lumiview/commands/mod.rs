//! The subcommands. Each returns an error whose text names the file or argument at fault.

/// Appends formatted text to a report string (formatting into a `String` cannot fail).
macro_rules! out {
    ($s:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = write!($s, $($arg)*);
    }};
}

/// Appends a formatted line to a report string.
macro_rules! outln {
    ($s:expr) => {{
        $s.push('\n');
    }};
    ($s:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($s, $($arg)*);
    }};
}

// The macros above are visible in the submodules declared below (textual macro scope).
mod cameras;
mod convert;
mod eval;
mod info;
mod isolux;
mod lut;
mod pack;
mod plot;
mod proxy;
mod rays;
mod render;
mod scene;
mod solid;
mod synth;

use std::path::{Path, PathBuf};

use lumiview::photometry::{self, LoadOptions, Photometry};
use serde_json::json;

pub use cameras::{cameras, CamerasArgs};
pub use convert::{convert, ConvertArgs};
pub use eval::{eval, eval_rays, EvalArgs, EvalRaysArgs};
pub use info::info;
pub use isolux::{isolux, IsoluxArgs};
pub use lut::{lut, LutArgs};
pub use pack::{pack, PackArgs};
pub use plot::{plot, PlotArgs};
pub use proxy::{proxy, ProxyArgs};
pub use rays::{rays2scan, Rays2scanArgs};
pub use render::{render, RenderArgs};
pub use scene::{scene, SceneArgs};
pub use solid::{solid, SolidArgs};
pub use synth::{synth, SynthArgs};

use crate::LoadArgs;

/// Parses a camera layout: `rigo:N` (N cameras per hemisphere, 2° overlap, 0.05° jitter),
/// `fibonacci:N` or `grid:P,T`.
pub fn parse_layout(text: &str) -> Result<lumiview::nearfield::layout::Layout, String> {
    use lumiview::nearfield::layout::Layout;
    let bad = || format!("--layout `{text}`: expected rigo:N, fibonacci:N or grid:P,T, e.g. rigo:28000");
    let (kind, rest) = text.split_once(':').ok_or_else(bad)?;
    let num = |s: &str| s.trim().parse::<usize>().map_err(|_| bad());
    match kind.trim().to_ascii_lowercase().as_str() {
        "rigo" => Ok(Layout::Rigo {
            per_hemisphere: num(rest)?,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        }),
        "fibonacci" => Ok(Layout::Fibonacci { count: num(rest)? }),
        "grid" => {
            let (p, t) = rest.split_once(',').ok_or_else(bad)?;
            Ok(Layout::Grid {
                phi_steps: num(p)?,
                theta_steps: num(t)?,
            })
        }
        _ => Err(bad()),
    }
}

/// Parses an image size `WxH` in pixels, each side within 1…65536.
pub fn parse_size_px(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("--size `{text}`: expected WxH in pixels within 1…65536, e.g. 1216x1021");
    let (w, h) = text.split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if !(1..=65_536).contains(&w) || !(1..=65_536).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

/// Result of a subcommand.
pub type CliResult = Result<(), Box<dyn std::error::Error>>;

/// Writes a report to stdout; a closed pipe (`| head`) is not an error, and nothing panics.
pub fn print_report(text: &str) -> CliResult {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(format!("cannot write to stdout: {e}").into()),
        _ => Ok(()),
    }
}

/// Reads a photometric file with the command-line load options and prints its warnings on
/// stderr. Options that do not apply to the file are errors naming the option and why.
pub fn load(file: &Path, args: &LoadArgs) -> Result<Photometry, Box<dyn std::error::Error>> {
    let p = load_quiet(file, args)?;
    for w in &p.warnings {
        eprintln!("lumiview: warning: {w}");
    }
    Ok(p)
}

/// [`load`] without printing the warnings (for reports that list them themselves).
pub fn load_quiet(file: &Path, args: &LoadArgs) -> Result<Photometry, Box<dyn std::error::Error>> {
    if args.lamp_set == Some(0) {
        return Err("--lamp-set counts from 1".into());
    }
    let opts = LoadOptions {
        tilt_deg: args.tilt,
        lamp_set: args.lamp_set.unwrap_or(1) - 1,
        ..LoadOptions::default()
    };
    let p = photometry::load(file, &opts)?;
    check_options_apply(&p, args)?;
    Ok(p)
}

/// `--tilt` needs an IES file with a TILT table; `--lamp-set` needs an EULUMDAT file.
fn check_options_apply(p: &Photometry, args: &LoadArgs) -> Result<(), String> {
    let is_ies = matches!(p.format, photometry::FileFormat::Ies(_));
    if args.tilt.is_some() {
        if !is_ies {
            return Err(format!(
                "--tilt: {} is EULUMDAT, which has no lamp-tilt table (only IES files with TILT=INCLUDE or \
                 TILT=<file> do)",
                p.source
            ));
        }
        if p.tilt.is_none() {
            return Err(format!(
                "--tilt: {} has TILT=NONE: its output does not depend on lamp tilt, so there is no factor to apply",
                p.source
            ));
        }
    }
    if is_ies && args.lamp_set.is_some_and(|n| n != 1) {
        return Err(format!(
            "--lamp-set: {} is an IES file, which has one lamp configuration (lamp sets are EULUMDAT's)",
            p.source
        ));
    }
    Ok(())
}

/// The files named on the command line, with each directory replaced by the photometric files
/// (`.ies`, `.ldt`, any case) in it and its subdirectories, sorted by path.
pub fn expand_inputs(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>, depth: usize) -> Result<(), String> {
        if depth > 16 {
            return Err(format!("{}: folders nested more than 16 deep", dir.display()));
        }
        let rd = std::fs::read_dir(dir).map_err(|e| format!("{}: cannot list the folder: {e}", dir.display()))?;
        let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
        entries.sort();
        for p in entries {
            let meta = std::fs::symlink_metadata(&p).map_err(|e| format!("{}: {e}", p.display()))?;
            if meta.is_dir() {
                walk(&p, out, depth + 1)?;
            } else if meta.is_file() && is_photometric_name(&p) {
                out.push(p);
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let before = out.len();
            walk(p, &mut out, 0)?;
            if out.len() == before {
                return Err(format!("{}: the folder holds no .ies or .ldt file", p.display()));
            }
        } else {
            out.push(p.clone());
        }
    }
    if out.is_empty() {
        return Err("no input file given".into());
    }
    Ok(out)
}

/// True for a file name ending in `.ies` or `.ldt` (any case).
fn is_photometric_name(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("ies") || e.eq_ignore_ascii_case("ldt"))
}

/// One CSV line (RFC 4180): fields with a comma, quote or line break are quoted, quotes doubled.
pub fn csv_row<I: IntoIterator<Item = String>>(fields: I) -> String {
    fields
        .into_iter()
        .map(|f| {
            if f.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", f.replace('"', "\"\""))
            } else {
                f
            }
        })
        .collect::<Vec<_>>()
        .join(",")
}

/// Parses `FROM:TO:STEP` (degrees) into the list of angles.
pub fn angle_range(text: &str, arg: &str) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = text.split(':').collect();
    let bad = || format!("--{arg} `{text}`: expected FROM:TO:STEP in degrees, e.g. 0:345:15");
    if parts.len() != 3 {
        return Err(bad());
    }
    let nums: Vec<f64> = parts
        .iter()
        .map(|p| p.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<Vec<_>>>()
        .ok_or_else(bad)?;
    let (from, to, step) = (nums[0], nums[1], nums[2]);
    if step <= 0.0 || to < from || (to - from) / step > 100_000.0 {
        return Err(bad());
    }
    let n = ((to - from) / step + 1e-9).floor() as usize;
    Ok((0..=n).map(|i| from + i as f64 * step).collect())
}

/// Parses `C,GAMMA` in degrees.
fn direction_arg(text: &str) -> Result<(f64, f64), String> {
    let bad = || format!("--at `{text}`: expected C,GAMMA in degrees, e.g. --at 0,45");
    let (c, g) = text.split_once(',').ok_or_else(bad)?;
    let c: f64 = c.trim().parse().map_err(|_| bad())?;
    let g: f64 = g.trim().parse().map_err(|_| bad())?;
    if !c.is_finite() || !g.is_finite() || !(0.0..=180.0).contains(&g) {
        return Err(format!(
            "--at `{text}`: GAMMA must be within 0…180° and both angles finite"
        ));
    }
    Ok((c, g))
}

/// Rounds for display without losing meaningful digits.
fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1000.0 {
        format!("{v:.1}")
    } else if v.abs() >= 1.0 {
        format!("{v:.3}")
    } else {
        format!("{v:.5}")
    }
}

/// `lumiview sample`.
pub fn sample(file: &Path, at: &[String], as_json: bool, args: &LoadArgs) -> CliResult {
    let mut out = String::new();
    let dirs = at.iter().map(|a| direction_arg(a)).collect::<Result<Vec<_>, _>>()?;
    let p = load(file, args)?;
    let samples: Vec<(f64, f64, f64)> = dirs.iter().map(|&(c, g)| (c, g, p.intensity(c, g))).collect();
    if as_json {
        let v = json!({
            "unit": "cd",
            "samples": samples.iter().map(|(c, g, cd)| json!({"c": c, "gamma": g, "cd": cd})).collect::<Vec<_>>(),
        });
        outln!(out, "{}", serde_json::to_string(&v)?);
    } else {
        outln!(out, "{:>10} {:>10} {:>14}", "C (°)", "γ (°)", "I (cd)");
        for (c, g, cd) in samples {
            outln!(out, "{c:>10} {g:>10} {:>14}", fmt_num(cd));
        }
    }
    print_report(&out)
}

/// `lumiview luminance FILE…`: one file prints a table (text or JSON); several files or a folder
/// write one CSV table `file,c_deg,gamma_deg,luminance_cd_m2,error` (JSON lines with `--json`),
/// continuing past a file that cannot be read (one row naming it, with the error).
pub fn luminance(files: &[PathBuf], as_json: bool, c: &str, gamma: &str, args: &LoadArgs) -> CliResult {
    let cs = angle_range(c, "c")?;
    let gs = angle_range(gamma, "gamma")?;
    if gs.iter().any(|g| !(0.0..=180.0).contains(g)) {
        return Err(format!("--gamma `{gamma}`: angles must lie within 0…180°").into());
    }
    const MAX_CELLS: usize = 1_000_000;
    if cs.len() * gs.len() > MAX_CELLS {
        return Err(format!(
            "--c `{c}` × --gamma `{gamma}` asks for {} × {} values; at most {MAX_CELLS} per table",
            cs.len(),
            gs.len()
        )
        .into());
    }
    let inputs = expand_inputs(files)?;
    /// Luminance in cd/m² per [γ][C]; `None` where the opening is seen edge-on.
    type Table = Vec<Vec<Option<f64>>>;
    let table_of = |file: &Path| -> Result<(Photometry, Table), Box<dyn std::error::Error>> {
        let p = load(file, args)?;
        if p.opening.is_point() {
            return Err(format!(
                "{}: the luminous opening is a point (no dimensions in the file), so luminance is undefined",
                p.source
            )
            .into());
        }
        let table = gs
            .iter()
            .map(|&g| cs.iter().map(|&c| p.luminance(c, g)).collect())
            .collect();
        Ok((p, table))
    };
    let mut out = String::new();
    if inputs.len() > 1 || files.iter().any(|f| f.is_dir()) {
        if !as_json {
            outln!(out, "file,c_deg,gamma_deg,luminance_cd_m2,error");
        }
        let mut failed = 0usize;
        for file in &inputs {
            match table_of(file) {
                Ok((p, table)) => {
                    if as_json {
                        let v = json!({"file": p.source, "unit": "cd/m2", "c": cs, "gamma": gs, "table": table});
                        outln!(out, "{}", serde_json::to_string(&v)?);
                        continue;
                    }
                    for (g, row) in gs.iter().zip(&table) {
                        for (c, v) in cs.iter().zip(row) {
                            let v = v.map_or(String::new(), |v| format!("{v}"));
                            outln!(
                                out,
                                "{}",
                                csv_row([p.source.clone(), format!("{c}"), format!("{g}"), v, String::new()])
                            );
                        }
                    }
                }
                Err(e) => {
                    failed += 1;
                    eprintln!("lumiview: error: {}: {e}", file.display());
                    if as_json {
                        outln!(
                            out,
                            "{}",
                            json!({"file": file.display().to_string(), "error": e.to_string()})
                        );
                    } else {
                        let row = [
                            file.display().to_string(),
                            String::new(),
                            String::new(),
                            String::new(),
                            e.to_string(),
                        ];
                        outln!(out, "{}", csv_row(row));
                    }
                }
            }
        }
        print_report(&out)?;
        if failed > 0 {
            return Err(format!("{failed} of {} files could not be read (named above)", inputs.len()).into());
        }
        return Ok(());
    }
    let (p, table) = table_of(&inputs[0])?;
    if as_json {
        let v = json!({"unit": "cd/m2", "c": cs, "gamma": gs, "table": table});
        outln!(out, "{}", serde_json::to_string(&v)?);
        return print_report(&out);
    }
    outln!(
        out,
        "luminance in cd/m² of {} ({:?} opening)",
        p.source,
        p.opening.shape
    );
    out!(out, "{:>7}", "γ \\ C");
    for c in &cs {
        out!(out, "{c:>8}");
    }
    outln!(out);
    for (g, row) in gs.iter().zip(&table) {
        out!(out, "{g:>7}");
        for v in row {
            match v {
                Some(v) => out!(out, "{:>8}", format!("{v:.0}")),
                None => out!(out, "{:>8}", "—"),
            }
        }
        outln!(out);
    }
    print_report(&out)
}
