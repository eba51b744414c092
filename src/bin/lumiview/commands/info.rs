//! `lumiview info`: the summary of a photometric file (format, labels, grid, lamps, peak, flux,
//! beam and field angles, zonal lumens, light output ratios, CIE flux code, opening, warnings), of a
//! TM-25 ray file or of an `.lvpack`. Several files or a folder give one table: CSV, or JSON lines
//! with `--json`.

use std::path::{Path, PathBuf};

use lumiview::photometry::summary::Summary;
use lumiview::photometry::Photometry;
use serde_json::{json, Value};

use super::{csv_row, expand_inputs, fmt_num, load_quiet, pack, print_report, rays, CliResult};
use crate::LoadArgs;
use lumiview::source::{self, SourceKind};

/// `lumiview info FILE…`; `verify` (`--verify`) checks every page of a `.lvpack`.
pub fn info(files: &[PathBuf], as_json: bool, verify: bool, args: &LoadArgs) -> CliResult {
    let inputs = expand_inputs(files)?;
    if inputs.len() == 1 && !files.iter().any(|f| f.is_dir()) {
        return info_one(&inputs[0], as_json, verify, args);
    }
    if verify {
        return Err("--verify applies to one .lvpack file at a time".into());
    }
    info_table(&inputs, as_json, args)
}

fn info_one(file: &Path, as_json: bool, verify: bool, args: &LoadArgs) -> CliResult {
    let kind = source::detect(file)?;
    if verify && !matches!(kind, SourceKind::Pack) {
        return Err(format!("{}: --verify applies to .lvpack files", file.display()).into());
    }
    match kind {
        // A manifest goes to the photometry reader, which says it is not IES or EULUMDAT.
        SourceKind::Photometry | SourceKind::Manifest => {}
        SourceKind::RayFile => return rays::info_rayfile(file, as_json),
        SourceKind::Pack => return pack::info_pack(file, as_json, verify),
    }
    let p = load_quiet(file, args)?;
    let s = p.summary();
    if as_json {
        let text = serde_json::to_string_pretty(&info_json(&p, &s))?;
        return print_report(&format!("{text}\n"));
    }
    print_report(&info_text(&p, &s))
}

/// The JSON object of one photometric file.
fn info_json(p: &Photometry, s: &Summary) -> Value {
    let o = &p.opening;
    json!({
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
        "max_intensity_cd": s.peak.cd,
        "max_intensity_at_deg": {"c": s.peak.c_deg, "gamma": s.peak.gamma_deg},
        "integrated_flux_lm": s.flux_lm,
        "downward_flux_lm": s.downward_flux_lm,
        "upward_flux_lm": s.upward_flux_lm,
        "downward_flux_fraction": s.downward_fraction,
        "integrated_lor": p.integrated_lor(),
        "dlor": s.dlor,
        "ulor": s.ulor,
        "declared_lor": p.declared_lor,
        "declared_luminaire_flux_lm": p.declared_luminaire_flux_lm,
        "beam_field": s.spreads,
        "zonal_flux": s.zones,
        "zonal_flux_cumulative": s.cumulative_zones,
        "cie_flux_code": s.cie_flux_code.map(|c| json!({
            "code": c.text(),
            "n1": c.n1, "n2": c.n2, "n3": c.n3, "n4": c.n4, "n5": c.n5,
            "per_luminaire_flux": c.per_luminaire_flux,
        })),
        "opening": {
            "shape": format!("{:?}", o.shape),
            "size_x_m": o.size_x_m,
            "size_y_m": o.size_y_m,
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
    })
}

fn angle_or_dash(v: Option<f64>) -> String {
    v.map_or("—".to_string(), |a| format!("{a:.1}°"))
}

fn percent_or_dash(v: Option<f64>) -> String {
    v.map_or("—".to_string(), |a| format!("{:.1} %", a * 100.0))
}

/// The text report of one photometric file.
fn info_text(p: &Photometry, s: &Summary) -> String {
    let mut out = String::new();
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
            outln!(out, "  {k:<16} {v}");
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
        fmt_num(s.peak.cd),
        fmt_num(s.peak.c_deg),
        fmt_num(s.peak.gamma_deg)
    );
    out!(out, "integrated flux   {} lm", fmt_num(s.flux_lm));
    if let Some(lor) = p.integrated_lor() {
        out!(out, " ({:.1} % of lamp flux)", lor * 100.0);
    }
    outln!(out);
    if let Some(f) = p.declared_luminaire_flux_lm {
        outln!(
            out,
            "declared flux     {} lm (LOR {})",
            fmt_num(f),
            percent_or_dash(p.declared_lor)
        );
    }
    outln!(
        out,
        "DLOR / ULOR       {} / {}{}; downward flux fraction {:.1} %",
        percent_or_dash(s.dlor),
        percent_or_dash(s.ulor),
        if s.dlor.is_none() {
            " (absolute photometry: no lamp flux)"
        } else {
            ""
        },
        s.downward_fraction * 100.0
    );
    for sp in &s.spreads {
        let edges = |e: Option<[f64; 2]>| e.map_or(String::new(), |[a, b]| format!(" ({a:.1}° … {b:.1}°)"));
        outln!(
            out,
            "{:<18}beam {}{}, field {}{} (50 % / 10 % of {} cd)",
            format!("{} plane", sp.plane),
            angle_or_dash(sp.beam_deg),
            edges(sp.beam_edges_deg),
            angle_or_dash(sp.field_deg),
            edges(sp.field_edges_deg),
            fmt_num(sp.max_cd)
        );
    }
    outln!(out, "zonal flux        γ zone          lm    % lamp  % luminaire");
    for z in s.zones.iter().chain(&s.cumulative_zones) {
        outln!(
            out,
            "                  {:<9} {:>9.1} {:>9} {:>12.1}",
            format!("{}–{}°", z.from_deg, z.to_deg),
            z.flux_lm,
            z.percent_lamp.map_or("—".to_string(), |v| format!("{v:.1}")),
            z.percent_luminaire
        );
    }
    match &s.cie_flux_code {
        Some(c) => outln!(
            out,
            "CIE flux code     {}{}",
            c.text(),
            if c.per_luminaire_flux {
                " (absolute photometry: N4, N5 per luminaire flux)"
            } else {
                ""
            }
        ),
        None => outln!(out, "CIE flux code     — (no downward flux)"),
    }
    let o = &p.opening;
    outln!(
        out,
        "opening           {:?} {} × {} × {} m (along X = C0–C180 × Y = C90–C270 × height)",
        o.shape,
        fmt_num(o.size_x_m),
        fmt_num(o.size_y_m),
        fmt_num(o.height_m)
    );
    if o.side_heights_m.iter().any(|h| *h > 0.0) {
        let [a, b, c, d] = o.side_heights_m;
        outln!(
            out,
            "side heights      faces seen from C0 {a} m, C90 {b} m, C180 {c} m, C270 {d} m"
        );
    }
    if let Some([x, y, h]) = p.luminaire_size_m {
        outln!(out, "luminaire size    {x} × {y} × {h} m (X × Y × height)");
    }
    for w in &p.warnings {
        outln!(out, "warning           {w}");
    }
    out
}

/// The CSV columns of `info` over several files.
const COLUMNS: &[&str] = &[
    "file",
    "format",
    "luminaire",
    "symmetry",
    "max_cd",
    "max_c_deg",
    "max_gamma_deg",
    "flux_lm",
    "lamp_flux_lm",
    "lor",
    "dlor",
    "ulor",
    "beam_c0_c180_deg",
    "field_c0_c180_deg",
    "beam_c90_c270_deg",
    "field_c90_c270_deg",
    "zone_0_30_lm",
    "zone_30_40_lm",
    "zone_40_60_lm",
    "zone_60_90_lm",
    "zone_90_180_lm",
    "cie_flux_code",
    "opening_shape",
    "opening_x_m",
    "opening_y_m",
    "opening_height_m",
    "warnings",
    "error",
];

/// A luminaire's name for the table: the EULUMDAT luminaire name or IES `[LUMINAIRE]`/`[LUMCAT]`.
fn luminaire_name(p: &Photometry) -> String {
    let find = |key: &str| {
        p.labels
            .iter()
            .find(|(k, v)| k.eq_ignore_ascii_case(key) && !v.trim().is_empty())
            .map(|(_, v)| v.trim().replace('\n', " "))
    };
    find("luminaire name")
        .or_else(|| find("LUMINAIRE"))
        .or_else(|| find("LUMCAT"))
        .unwrap_or_default()
}

fn info_table(inputs: &[PathBuf], as_json: bool, args: &LoadArgs) -> CliResult {
    let mut out = String::new();
    if !as_json {
        outln!(out, "{}", csv_row(COLUMNS.iter().map(|s| s.to_string())));
    }
    let mut failed = 0usize;
    for file in inputs {
        match load_quiet(file, args) {
            Ok(p) => {
                let s = p.summary();
                if as_json {
                    outln!(out, "{}", serde_json::to_string(&info_json(&p, &s))?);
                    continue;
                }
                let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x}"));
                let sp = |i: usize| (&s.spreads[i].beam_deg, &s.spreads[i].field_deg);
                let (b0, f0) = sp(0);
                let (b90, f90) = sp(1);
                let mut row = vec![
                    p.source.clone(),
                    p.format.name(),
                    luminaire_name(&p),
                    format!("{:?}", p.symmetry),
                    format!("{}", s.peak.cd),
                    format!("{}", s.peak.c_deg),
                    format!("{}", s.peak.gamma_deg),
                    format!("{}", s.flux_lm),
                    opt(p.lamp_flux_lm),
                    opt(p.integrated_lor()),
                    opt(s.dlor),
                    opt(s.ulor),
                    opt(*b0),
                    opt(*f0),
                    opt(*b90),
                    opt(*f90),
                ];
                row.extend(s.zones.iter().map(|z| format!("{}", z.flux_lm)));
                row.push(s.cie_flux_code.map(|c| c.text()).unwrap_or_default());
                row.push(format!("{:?}", p.opening.shape));
                row.push(format!("{}", p.opening.size_x_m));
                row.push(format!("{}", p.opening.size_y_m));
                row.push(format!("{}", p.opening.height_m));
                row.push(p.warnings.join("; "));
                row.push(String::new());
                outln!(out, "{}", csv_row(row));
                for w in &p.warnings {
                    eprintln!("lumiview: warning: {w}");
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
                    let mut row = vec![String::new(); COLUMNS.len()];
                    row[0] = file.display().to_string();
                    row[COLUMNS.len() - 1] = e.to_string();
                    outln!(out, "{}", csv_row(row));
                }
            }
        }
    }
    print_report(&out)?;
    if failed > 0 {
        return Err(format!("{failed} of {} files could not be read (named above)", inputs.len()).into());
    }
    Ok(())
}
