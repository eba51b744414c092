//! `lumiview proxy`: the proxy a scan renders with when it comes without a mesh, written as glTF for
//! inspection; with --synth, the reconstruction of synthetic luminaires measured against their true
//! proxies (the Chamfer table of docs/proxy.md).

use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use lumiview::nearfield::manifest::{load_scan, ImportOptions};
use lumiview::nearfield::pack::Pack;
use lumiview::nearfield::proxy::{mesh_of_triangles, triangles_of};
use lumiview::nearfield::reconstruct::{
    chamfer, reconstruct, ReconstructOptions, Reconstruction, CAPTURE_SUPERSAMPLE, MIN_COVERAGE,
};
use lumiview::nearfield::scanfile::{self, ScanFileKind};
use lumiview::nearfield::synth::{self, synth_scan, SynthOptions};
use lumiview::nearfield::Scan;
use lumiview::source::{self, SourceKind};
use serde_json::json;

use super::{print_report, CliResult};

/// `lumiview proxy`.
#[derive(Args, Debug)]
pub struct ProxyArgs {
    /// Input: scan manifest(s) (.json, e.g. one per hemisphere) or a .lvpack (reconstructed from
    /// its images; --stored writes the proxy it holds), or a TM-25 ray file (the hull of its ray
    /// origins, the proxy it renders with). Omit with --synth.
    pub input: Vec<PathBuf>,
    /// Output: FILE.glb, or with --synth a folder (NAME.glb per luminaire and table.csv).
    #[arg(short = 'o', long = "output", value_name = "FILE.glb|DIR")]
    pub output: PathBuf,
    /// Synthetic luminaires to scan, reconstruct and compare with their true proxies: names
    /// separated by commas, or `all`.
    #[arg(long, value_name = "NAMES|all")]
    pub synth: Option<String>,
    /// Camera layout for --synth (rigo:N per hemisphere, fibonacci:N, grid:P,T).
    #[arg(long, default_value = "rigo:300", value_name = "LAYOUT")]
    pub layout: String,
    /// Image size WxH in pixels for --synth.
    #[arg(long, default_value = "256x256", value_name = "WxH")]
    pub size: String,
    /// Rays per pixel edge of the --synth captures (a camera integrates over its pixel; 1 samples
    /// the pixel centre only and misses surfaces seen edge-on).
    #[arg(long, default_value_t = CAPTURE_SUPERSAMPLE, value_name = "N")]
    pub supersample: u32,
    /// A .lvpack: write the proxy it stores instead of reconstructing one.
    #[arg(long)]
    pub stored: bool,
    /// Most cameras read (spread evenly over the sphere).
    #[arg(long, default_value_t = ReconstructOptions::default().max_cameras, value_name = "N")]
    pub max_cameras: usize,
    /// Most cells per axis of the finest carving level.
    #[arg(long, default_value_t = ReconstructOptions::default().max_cells, value_name = "N")]
    pub max_cells: usize,
    /// A pixel is lit at or above this fraction of its image's maximum (and above the image's
    /// noise floor).
    #[arg(long, default_value_t = ReconstructOptions::default().lit_relative, value_name = "F")]
    pub lit_relative: f32,
    /// Dark cameras within this angle (degrees) of a surface's plane do not carve it.
    #[arg(long, default_value_t = ReconstructOptions::default().grazing_deg, value_name = "DEG")]
    pub grazing_deg: f64,
    /// Parts of the carved volume thinner than this fraction of its diameter (a flat emitter's
    /// lens) are collapsed onto their middle; 0 keeps the carved surface.
    #[arg(long, default_value_t = ReconstructOptions::default().thin_fraction, value_name = "F")]
    pub thin_fraction: f64,
    /// Experimental: carve again with the directional rule when the one-sided rule's mesh explains
    /// too little of the light (beams, small features; slow, large meshes: docs/proxy.md).
    #[arg(long)]
    pub directional: bool,
    /// Leave flat parts where carving put them (no plane from luminance consistency).
    #[arg(long)]
    pub no_refine: bool,
    /// Keep both sheets of each flat part and all their triangles (no simplification).
    #[arg(long)]
    pub no_simplify: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

impl ProxyArgs {
    fn options(&self) -> ReconstructOptions {
        ReconstructOptions {
            max_cameras: self.max_cameras,
            max_cells: self.max_cells,
            grazing_deg: self.grazing_deg,
            lit_relative: self.lit_relative,
            thin_fraction: self.thin_fraction,
            directional_fallback: self.directional,
            refine_flat: !self.no_refine,
            simplify: !self.no_simplify,
            ..ReconstructOptions::default()
        }
    }
}

/// Runs `lumiview proxy`.
pub fn proxy(args: &ProxyArgs) -> CliResult {
    args.options().validate()?;
    match &args.synth {
        Some(names) => {
            if !args.input.is_empty() {
                return Err("give either input files or --synth, not both".into());
            }
            synth_table(args, names)
        }
        None => from_file(args),
    }
}

/// A progress bar for reconstruction's stages ("masks", "carving"), labelled `prefix`; hidden
/// when `quiet`. [`show_stage`] moves it.
pub(super) fn bar(quiet: bool, prefix: &str) -> ProgressBar {
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::with_draw_target(Some(1), ProgressDrawTarget::stderr())
    };
    if let Ok(style) = ProgressStyle::with_template("{prefix} {msg:8} {bar:40} {pos}/{len} [{elapsed_precise}]") {
        bar.set_style(style);
    }
    bar.set_prefix(prefix.to_string());
    bar
}

/// Shows reconstruction's progress `(stage, done, total)` on `bar`.
pub(super) fn show_stage(bar: &ProgressBar, stage: &str, done: usize, total: usize) {
    bar.set_message(stage.to_string());
    bar.set_length(total as u64);
    bar.set_position(done as u64);
}

fn run(
    scan: &Scan,
    opts: &ReconstructOptions,
    bar: &ProgressBar,
) -> lumiview::nearfield::error::Result<Reconstruction> {
    reconstruct(&scan.set, &|i| scan.source.image(i), opts, &|stage, done, total| {
        show_stage(bar, stage, done, total)
    })
}

fn report_json(rec: &Reconstruction) -> serde_json::Value {
    let r = &rec.report;
    json!({
        "cameras_read": r.cameras_read,
        "cameras_used": r.cameras_used,
        "content_radius_m": r.content_radius_m,
        "voxel_m": r.voxel_m,
        "cells_per_axis": r.cells_per_axis,
        "occupied_cells": r.occupied_cells,
        "triangles": r.triangles,
        "tests": r.tests,
        "mask_bytes": r.mask_bytes,
        "coverage": r.coverage,
        "collapsed_vertices": r.collapsed_vertices,
        "collapsed_coverage": r.collapsed_coverage,
        "stray_triangles": r.stray_triangles,
        "directional": r.directional,
        "grazing_deg": r.grazing_deg,
        "lit_relative": r.lit_relative,
        "lit_pixels": r.lit_pixels,
        "noise_floored_cameras": r.noise_floored,
        "flat_parts": r.flat_parts.iter().map(|f| json!({
            "vertices": f.vertices,
            "absorbed": f.absorbed,
            "rms_mm": f.rms_m * 1e3,
            "offset_mm": f.offset_m * 1e3,
            "disagreement": f.cost,
            "cameras": f.cameras,
            "small_parts_redrawn": f.redrawn,
        })).collect::<Vec<_>>(),
        "simplified": {
            "triangles_before": r.simplified.triangles_before,
            "vertices_collapsed": r.simplified.vertices_collapsed,
        },
        "seconds": {"masks": r.seconds[0], "carving": r.seconds[1], "mesh": r.seconds[2], "refining": r.seconds[3]},
    })
}

/// One input file: reconstruct (or read the stored / ray-file proxy) and write it.
fn from_file(args: &ProxyArgs) -> CliResult {
    let Some(file) = args.input.first() else {
        return Err("nothing to reconstruct: give a scan manifest, an .lvpack, a ray file or --synth NAMES".into());
    };
    lumiview::files::ensure_not_input(&args.output, args.input.iter().map(PathBuf::as_path))?;
    let kind = source::detect(file)?;
    let name = file
        .file_stem()
        .map_or("scan".into(), |s| s.to_string_lossy().into_owned());
    let stored = |triangles: Vec<[f32; 3]>, what: &str| -> CliResult {
        if triangles.is_empty() {
            return Err(format!("{}: {what} is empty", file.display()).into());
        }
        mesh_of_triangles(&name, what, &triangles).write_glb(&args.output)?;
        let mut out = String::new();
        if args.json {
            outln!(
                out,
                "{}",
                json!({"file": args.output.display().to_string(), "source": what, "triangles": triangles.len() / 3})
            );
        } else {
            outln!(
                out,
                "wrote {}: {} ({} triangles)",
                args.output.display(),
                what,
                triangles.len() / 3
            );
        }
        print_report(&out)
    };
    let scan = match kind {
        SourceKind::RayFile => {
            if args.input.len() > 1 {
                return Err("give one ray file".into());
            }
            let mut warnings = Vec::new();
            let (_, _, proxy) = scanfile::scan_from_file_with_warnings(file, ScanFileKind::RayFile, &mut warnings)?;
            for w in &warnings {
                eprintln!("lumiview: warning: {w}");
            }
            let p = proxy.ok_or_else(|| format!("{}: the ray file gave no proxy", file.display()))?;
            return stored(p.triangles, &p.source);
        }
        SourceKind::Pack => {
            if args.input.len() > 1 {
                return Err("give one .lvpack".into());
            }
            let pack = Pack::open(file)?;
            if args.stored {
                let p = pack.proxy().cloned().ok_or_else(|| {
                    format!(
                        "{}: the pack stores no proxy (leave out --stored to reconstruct one)",
                        file.display()
                    )
                })?;
                return stored(p.triangles, &p.source);
            }
            pack.into_scan()
        }
        SourceKind::Manifest => load_scan(
            &args.input,
            &ImportOptions {
                skip_bad: false,
                verify_pixels: false,
            },
        )?,
        _ => {
            return Err(format!(
                "{}: not a near-field scan (a scan manifest, .lvpack or TM-25 ray file); photometric files have no \
                 near-field images to reconstruct from",
                file.display()
            )
            .into())
        }
    };
    if args.stored {
        return Err("--stored applies to a .lvpack".into());
    }
    let bar = bar(args.quiet, "proxy:");
    let rec = run(&scan, &args.options(), &bar);
    bar.finish_and_clear();
    let rec = rec?;
    if rec.mesh.triangles.is_empty() {
        return Err(format!(
            "{}: no luminous surface survived carving ({} cameras, {:.2} mm cells)",
            file.display(),
            rec.report.cameras_used,
            rec.report.voxel_m * 1e3
        )
        .into());
    }
    rec.mesh.to_proxy_mesh(&name, "reconstructed").write_glb(&args.output)?;
    let r = &rec.report;
    if r.coverage < MIN_COVERAGE {
        eprintln!(
            "lumiview: warning: {}: the proxy explains only {:.1} % of the lit pixels; `pack` and `render` would not \
             use it (below {:.0} %)",
            file.display(),
            r.coverage * 100.0,
            MIN_COVERAGE * 100.0
        );
    }
    let mut out = String::new();
    if args.json {
        let mut j = report_json(&rec);
        j["file"] = json!(args.output.display().to_string());
        outln!(out, "{}", serde_json::to_string_pretty(&j)?);
    } else {
        outln!(
            out,
            "wrote {}: {} triangles from {} of {} cameras, {} cells per axis of {:.2} mm, {:.1} % of the lit pixels \
             explained, {:.1} s",
            args.output.display(),
            r.triangles,
            r.cameras_used,
            r.cameras_read,
            r.cells_per_axis,
            r.voxel_m * 1e3,
            r.coverage * 100.0,
            r.seconds.iter().sum::<f64>()
        );
    }
    print_report(&out)
}

/// One row of the --synth table.
struct Row {
    name: String,
    diam_mm: f64,
    footprint_mm: f64,
    rec: Reconstruction,
    mean_mm: f64,
    rec_to_true_mm: f64,
    true_to_rec_mm: f64,
    p95_mm: f64,
    max_mm: f64,
}

impl Row {
    /// The issue-17 limit: 1 % of the bounding diameter or two capture-pixel footprints, whichever
    /// is larger (mm).
    fn limit_mm(&self) -> f64 {
        (0.01 * self.diam_mm).max(2.0 * self.footprint_mm)
    }
}

/// --synth: scan each luminaire, reconstruct, compare with the true proxy, print the table.
fn synth_table(args: &ProxyArgs, names: &str) -> CliResult {
    let names: Vec<String> = if names.trim() == "all" {
        synth::NAMES.iter().map(|s| s.to_string()).collect()
    } else {
        names
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    };
    for n in &names {
        synth::luminaire(n)?;
    }
    let layout = super::parse_layout(&args.layout)?;
    let size = super::parse_size_px(&args.size)?;
    std::fs::create_dir_all(&args.output)
        .map_err(|e| format!("{}: cannot create the folder: {e}", args.output.display()))?;
    let mut rows = Vec::new();
    for name in &names {
        let opts = SynthOptions {
            luminaire: name.clone(),
            layout,
            size,
            supersample: args.supersample,
            ..SynthOptions::default()
        };
        let scan = synth_scan(&opts)?;
        let lum = synth::luminaire(name)?;
        let bar = bar(args.quiet, &format!("{name}:"));
        let rec = run(&scan, &args.options(), &bar);
        bar.finish_and_clear();
        let rec = rec?;
        let truth = triangles_of(&lum.proxy());
        let diam_mm = 2.0 * lum.bounds().radius() * 1e3;
        // One capture pixel's footprint at the capture centre (m), the finest the images resolve.
        let k = scan.set.intrinsics_of(0);
        let footprint_mm = opts.radius_m / k.focal_px.x.max(k.focal_px.y) * 1e3;
        let soup = rec.mesh.soup();
        let row = if soup.is_empty() {
            Row {
                name: name.clone(),
                diam_mm,
                footprint_mm,
                rec,
                mean_mm: f64::INFINITY,
                rec_to_true_mm: f64::INFINITY,
                true_to_rec_mm: f64::INFINITY,
                p95_mm: f64::INFINITY,
                max_mm: f64::INFINITY,
            }
        } else {
            rec.mesh
                .to_proxy_mesh(name, "reconstructed")
                .write_glb(&args.output.join(format!("{name}.glb")))?;
            let c = chamfer(&soup, &truth, 200_000);
            Row {
                name: name.clone(),
                diam_mm,
                footprint_mm,
                rec,
                mean_mm: c.mean_m * 1e3,
                rec_to_true_mm: c.mean_ab_m * 1e3,
                true_to_rec_mm: c.mean_ba_m * 1e3,
                p95_mm: c.p95_m * 1e3,
                max_mm: c.max_m * 1e3,
            }
        };
        if !args.quiet && !args.json {
            eprintln!("{}", row_text(&row));
        }
        rows.push(row);
    }
    let csv = table_csv(&rows, args);
    let csv_path = args.output.join("table.csv");
    std::fs::write(&csv_path, &csv).map_err(|e| format!("{}: {e}", csv_path.display()))?;
    let mut out = String::new();
    if args.json {
        let j: Vec<_> = rows
            .iter()
            .map(|r| {
                let mut j = report_json(&r.rec);
                j["luminaire"] = json!(r.name);
                j["diameter_mm"] = json!(r.diam_mm);
                j["footprint_mm"] = json!(r.footprint_mm);
                j["chamfer_mean_mm"] = json!(finite(r.mean_mm));
                j["rec_to_true_mm"] = json!(finite(r.rec_to_true_mm));
                j["true_to_rec_mm"] = json!(finite(r.true_to_rec_mm));
                j["chamfer_p95_mm"] = json!(finite(r.p95_mm));
                j["chamfer_max_mm"] = json!(finite(r.max_mm));
                j["limit_mm"] = json!(r.limit_mm());
                j["pass"] = json!(r.p95_mm <= r.limit_mm());
                j
            })
            .collect();
        outln!(out, "{}", serde_json::to_string_pretty(&j)?);
    } else {
        outln!(
            out,
            "Reconstructed proxy against the true proxy ({}, {} px, supersample {}; Chamfer distance in mm, \
             200,000 samples each way)",
            args.layout,
            args.size,
            args.supersample
        );
        outln!(out, "{}", header_text());
        for r in &rows {
            outln!(out, "{}", row_text(r));
        }
        outln!(
            out,
            "limit: the larger of 1 % of the bounding diameter and two capture-pixel footprints at the centre"
        );
        outln!(out, "wrote {} and NAME.glb per luminaire", csv_path.display());
    }
    print_report(&out)
}

/// The carving rule the kept mesh came from (the one-sided rule with its grazing tolerance), with
/// the masks' threshold when they were made deeper than the default.
fn rule_name(r: &lumiview::nearfield::reconstruct::ReconstructReport) -> String {
    let rule = if r.directional {
        "dir".into()
    } else {
        format!("1s {:.0}°", r.grazing_deg)
    };
    if r.lit_relative < ReconstructOptions::default().lit_relative {
        format!("{rule} {:.0e}", r.lit_relative)
    } else {
        rule
    }
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

fn header_text() -> String {
    format!(
        "{:<11} {:>8} {:>6} {:>7} {:>9} {:>7} {:>7} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>7} {:>7} {:>5} {:>7}",
        "luminaire",
        "diam mm",
        "px mm",
        "cell mm",
        "triangles",
        "cover %",
        "rule",
        "collapsed",
        "mean",
        "rec→true",
        "true→rec",
        "p95",
        "max",
        "p95 %",
        "limit",
        "pass",
        "s"
    )
}

fn row_text(r: &Row) -> String {
    let rep = &r.rec.report;
    format!(
        "{:<11} {:>8.1} {:>6.2} {:>7.2} {:>9} {:>7.1} {:>7} {:>9} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>7.2} {:>7.2} {:>5} {:>7.1}",
        r.name,
        r.diam_mm,
        r.footprint_mm,
        rep.voxel_m * 1e3,
        rep.triangles,
        rep.coverage * 100.0,
        rule_name(rep),
        rep.collapsed_vertices,
        r.mean_mm,
        r.rec_to_true_mm,
        r.true_to_rec_mm,
        r.p95_mm,
        r.max_mm,
        r.p95_mm / r.diam_mm * 100.0,
        r.limit_mm(),
        if r.p95_mm <= r.limit_mm() { "yes" } else { "no" },
        rep.seconds.iter().sum::<f64>()
    )
}

fn table_csv(rows: &[Row], args: &ProxyArgs) -> String {
    let mut s = format!(
        "# lumiview proxy --synth: layout {}, {} px, supersample {}; Chamfer distances in mm\n\
         luminaire,diameter_mm,footprint_mm,cell_mm,cameras_used,triangles,coverage,rule,collapsed_vertices,chamfer_mean_mm,rec_to_true_mm,true_to_rec_mm,chamfer_p95_mm,chamfer_max_mm,p95_percent_of_diameter,limit_mm,pass,seconds\n",
        args.layout, args.size, args.supersample
    );
    for r in rows {
        let rep = &r.rec.report;
        s.push_str(&format!(
            "{},{:.2},{:.3},{:.3},{},{},{:.4},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{:.2}\n",
            r.name,
            r.diam_mm,
            r.footprint_mm,
            rep.voxel_m * 1e3,
            rep.cameras_used,
            rep.triangles,
            rep.coverage,
            rule_name(rep),
            rep.collapsed_vertices,
            r.mean_mm,
            r.rec_to_true_mm,
            r.true_to_rec_mm,
            r.p95_mm,
            r.max_mm,
            r.p95_mm / r.diam_mm * 100.0,
            r.limit_mm(),
            r.p95_mm <= r.limit_mm(),
            rep.seconds.iter().sum::<f64>()
        ));
    }
    s
}
