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
mod eval;
mod lut;
mod pack;
mod plot;
mod rays;
mod render;
mod solid;
mod synth;

use std::path::Path;

use lumiview::photometry::{self, LoadOptions, Photometry};
use serde_json::json;

pub use cameras::{cameras, CamerasArgs};
pub use eval::{eval, EvalArgs};
pub use lut::{lut, LutArgs};
pub use pack::{pack, PackArgs};
pub use plot::{plot, PlotArgs};
pub use rays::{rays2scan, Rays2scanArgs};
pub use render::{render, RenderArgs};
pub use solid::{solid, SolidArgs};
pub use synth::{synth, SynthArgs};

use crate::LoadArgs;

/// What kind of input file `info` was given.
enum FileKind {
    /// IES or EULUMDAT.
    Photometry,
    /// IES TM-25 ray file.
    RayFile,
    /// lumiview `.lvpack` near-field store.
    Pack,
}

/// Detects the kind of a file by its first bytes (`nearfield::scanfile`: "TM25", "LVPACK"), else
/// photometry (whose reader reports an unreadable file).
fn detect_kind(file: &Path) -> FileKind {
    use lumiview::nearfield::scanfile::{detect, ScanFileKind};
    match detect(file) {
        Ok(Some(ScanFileKind::RayFile)) => FileKind::RayFile,
        Ok(Some(ScanFileKind::Pack)) => FileKind::Pack,
        _ => FileKind::Photometry,
    }
}

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

/// Reads a photometric file with the command-line load options.
pub fn load(file: &Path, args: &LoadArgs) -> Result<Photometry, Box<dyn std::error::Error>> {
    if args.lamp_set == 0 {
        return Err("--lamp-set counts from 1".into());
    }
    let opts = LoadOptions {
        tilt_deg: args.tilt,
        lamp_set: args.lamp_set - 1,
        ..LoadOptions::default()
    };
    Ok(photometry::load(file, &opts)?)
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

/// `lumiview info`; `verify` (`--verify`) checks every page of a `.lvpack`.
pub fn info(file: &Path, as_json: bool, verify: bool, args: &LoadArgs) -> CliResult {
    let kind = detect_kind(file);
    if verify && !matches!(kind, FileKind::Pack) {
        return Err(format!("{}: --verify applies to .lvpack files", file.display()).into());
    }
    match kind {
        FileKind::Photometry => {}
        FileKind::RayFile => return rays::info_rayfile(file, as_json),
        FileKind::Pack => return pack::info_pack(file, as_json, verify),
    }
    let mut out = String::new();
    let p = load(file, args)?;
    let (max_cd, max_c, max_g) = p.web.max_intensity();
    let flux = p.flux_lm();
    let o = &p.opening;
    if as_json {
        let v = json!({
            "file": p.source,
            "format": p.format.name(),
            "labels": p.labels.iter().map(|(k, v)| json!({"key": k, "value": v})).collect::<Vec<_>>(),
            "photometric_type": format!("{:?}", p.photometric_type),
            "symmetry": format!("{:?}", p.symmetry),
            "grid": {
                "native_horizontal": p.native_size.0,
                "native_vertical": p.native_size.1,
                "web_c": p.web.c_angles().len(),
                "web_gamma": p.web.gamma_angles().len(),
                "gamma_range_deg": [p.web.gamma_range().0, p.web.gamma_range().1],
            },
            "lamp_count": p.lamp_count,
            "absolute_photometry": p.lamp_flux_lm.is_none(),
            "lamp_flux_lm": p.lamp_flux_lm,
            "multiplier": p.multiplier,
            "candela_scale": p.candela_scale,
            "input_watts": p.input_watts,
            "max_intensity_cd": max_cd,
            "max_intensity_at_deg": {"c": max_c, "gamma": max_g},
            "integrated_flux_lm": flux,
            "downward_flux_lm": p.web.flux_between(0.0, 90.0),
            "integrated_lor": p.integrated_lor(),
            "declared_lor": p.declared_lor,
            "declared_luminaire_flux_lm": p.declared_luminaire_flux_lm,
            "opening": {
                "shape": format!("{:?}", o.shape),
                "length_m": o.length_m,
                "width_m": o.width_m,
                "height_m": o.height_m,
                "side_heights_m": o.side_heights_m,
            },
            "luminaire_size_m": p.luminaire_size_m,
            "tilt": p.tilt.as_ref().map(|t| json!({
                "geometry": t.lamp_to_luminaire_geometry,
                "angles_deg": t.angles_deg,
                "factors": t.factors,
            })),
            "tilt_applied_deg": p.tilt_applied_deg,
            "warnings": p.warnings,
        });
        outln!(out, "{}", serde_json::to_string_pretty(&v)?);
        return print_report(&out);
    }
    outln!(out, "file              {}", p.source);
    outln!(out, "format            {}", p.format.name());
    for (k, v) in &p.labels {
        let v = v.replace('\n', " / ");
        if v.is_empty() {
            continue;
        }
        if k.is_empty() {
            outln!(out, "label             {v}");
        } else {
            outln!(out, "  {k:<16}{v}");
        }
    }
    outln!(out, "photometric type  {:?}", p.photometric_type);
    outln!(out, "symmetry          {:?}", p.symmetry);
    outln!(
        out,
        "grid              {} horizontal × {} vertical angles as stored; web {} C × {} γ (γ {}–{}°)",
        p.native_size.0,
        p.native_size.1,
        p.web.c_angles().len(),
        p.web.gamma_angles().len(),
        p.web.gamma_range().0,
        p.web.gamma_range().1
    );
    match p.lamp_flux_lm {
        Some(f) => outln!(
            out,
            "lamps             {} lamp(s), {} lm rated in total",
            p.lamp_count,
            fmt_num(f)
        ),
        None => outln!(out, "lamps             {} lamp(s), absolute photometry", p.lamp_count),
    }
    outln!(
        out,
        "multiplier        {} (total factor to cd: {})",
        fmt_num(p.multiplier),
        fmt_num(p.candela_scale)
    );
    if let Some(t) = &p.tilt {
        outln!(
            out,
            "tilt              {} angles ({:?}), applied at {}",
            t.angles_deg.len(),
            t.source,
            p.tilt_applied_deg
                .map_or("the measured orientation".to_string(), |a| format!("{a}°"))
        );
    }
    outln!(
        out,
        "max intensity     {} cd at C {}°, γ {}°",
        fmt_num(max_cd),
        fmt_num(max_c),
        fmt_num(max_g)
    );
    out!(out, "integrated flux   {} lm", fmt_num(flux));
    if let Some(lor) = p.integrated_lor() {
        out!(out, " ({:.1} % of lamp flux)", lor * 100.0);
    }
    outln!(out);
    if let Some(f) = p.declared_luminaire_flux_lm {
        outln!(
            out,
            "declared flux     {} lm (LOR {})",
            fmt_num(f),
            p.declared_lor.map_or("—".into(), |l| format!("{:.1} %", l * 100.0))
        );
    }
    outln!(
        out,
        "opening           {:?} {} × {} × {} m (length × width × height)",
        o.shape,
        fmt_num(o.length_m),
        fmt_num(o.width_m),
        fmt_num(o.height_m)
    );
    if o.side_heights_m.iter().any(|h| *h > 0.0) {
        let [a, b, c, d] = o.side_heights_m;
        outln!(out, "side heights      C0 {a} m, C90 {b} m, C180 {c} m, C270 {d} m");
    }
    if let Some([l, w, h]) = p.luminaire_size_m {
        outln!(out, "luminaire size    {l} × {w} × {h} m");
    }
    for w in &p.warnings {
        outln!(out, "warning           {w}");
    }
    print_report(&out)
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

/// `lumiview luminance`.
pub fn luminance(file: &Path, as_json: bool, c: &str, gamma: &str, args: &LoadArgs) -> CliResult {
    let mut out = String::new();
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
    let p = load(file, args)?;
    if p.opening.is_point() {
        return Err(format!(
            "{}: the luminous opening is a point (no dimensions in the file), so luminance is undefined",
            p.source
        )
        .into());
    }
    let table: Vec<Vec<Option<f64>>> = gs
        .iter()
        .map(|&g| cs.iter().map(|&c| p.luminance(c, g)).collect())
        .collect();
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
