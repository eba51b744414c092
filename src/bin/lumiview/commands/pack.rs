//! Subcommands on `.lvpack` near-field stores: `pack` (write one) and `info` (describe one).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use lumiview::nearfield::manifest::{load_scan, ImportOptions};
use lumiview::nearfield::pack::{write_pack, Pack, PackOptions, PackProxy, PackStats, Threshold, MAX_PAGE_BYTES};
use lumiview::nearfield::reconstruct::CAPTURE_SUPERSAMPLE;
use lumiview::nearfield::scanfile::{self, ScanFileKind};
use lumiview::nearfield::synth::{synth_scan, SynthOptions};
use lumiview::nearfield::{Hemisphere, Scan};
use lumiview::source::{self, SourceKind};
use serde_json::json;

use super::{print_report, CliResult};

/// `lumiview pack`: store a scan as a tiled `.lvpack` file.
#[derive(Args, Debug)]
pub struct PackArgs {
    /// Input: scan manifest(s) (.json; e.g. one per hemisphere), an IES TM-25 ray file (a kernel
    /// estimate of its light field, cameras and kernels chosen from the data, stored with the hull
    /// of its ray origins as the proxy; `lumiview rays2scan` sets the estimate's options) or an
    /// existing .lvpack (repacked with the options given, its proxy kept). Omit with --synth.
    pub input: Vec<PathBuf>,
    /// Output file (.lvpack).
    #[arg(short = 'o', long = "output", value_name = "FILE.lvpack")]
    pub output: PathBuf,
    /// Tile edge in pixels (1…64).
    #[arg(long, default_value_t = 8, value_name = "PX")]
    pub tile: u32,
    /// Keep only tiles with a value above this: cd/m² (`0.5` or `abs:0.5`) or a fraction of each
    /// image's maximum (`rel:1e-4`). The default 0 keeps every nonzero pixel (lossless about zeros).
    #[arg(long, default_value = "0", value_name = "CD_M2|rel:FRACTION")]
    pub threshold: String,
    /// Largest pool page in MiB (1…128).
    #[arg(long, default_value_t = 128, value_name = "MIB")]
    pub page_mib: u64,
    /// Render the scan with the synthetic goniophotometer: the luminaire's name (disc, rect,
    /// star-panel, two-planes, strips, led-dots, cos1, cos10, cos100, reflector, peak).
    #[arg(long, value_name = "LUMINAIRE")]
    pub synth: Option<String>,
    /// Camera layout for --synth: rigo:N (N per hemisphere), fibonacci:N or grid:P,T (default
    /// rigo:28000).
    #[arg(long, value_name = "LAYOUT")]
    pub layout: Option<String>,
    /// Image size WxH in pixels for --synth (default 1216x1021).
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// Capture sphere radius in metres for --synth (default 1.117).
    #[arg(long, value_name = "M")]
    pub radius: Option<f64>,
    /// A proxy mesh (glTF 2.0, luminaire frame) to store in the pack (version 2), used by `render`
    /// and `lumi_luminaire_load` unless they are given another; it replaces one the input has.
    /// Without it, a scan manifest's or --synth scan's proxy is reconstructed from its images
    /// (docs/proxy.md; `lumiview proxy` writes it for inspection).
    #[arg(long, value_name = "FILE.glb", conflicts_with = "no_proxy")]
    pub proxy: Option<PathBuf>,
    /// Store no proxy: neither reconstruct one nor keep the input's.
    #[arg(long)]
    pub no_proxy: bool,
    /// The --proxy mesh encloses the light instead of being its surface (as `rays2scan` writes a
    /// ray file's `proxy.glb`): the renderer then samples the images plainly.
    #[arg(long, requires = "proxy")]
    pub proxy_bound: bool,
    /// Manifests: drop bad images (missing, unreadable, wrong size, bad pose) with a warning
    /// instead of failing.
    #[arg(long)]
    pub skip_bad_images: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The scan the arguments describe, a description for the metadata, and the proxy to store.
type Input = (Scan, String, Option<PackProxy>);

/// --synth's default camera layout.
const DEFAULT_SYNTH_LAYOUT: &str = "rigo:28000";

/// The synthetic scan --synth asks for (`None` without --synth).
fn synth_options(args: &PackArgs) -> Result<Option<SynthOptions>, Box<dyn std::error::Error>> {
    let Some(name) = &args.synth else { return Ok(None) };
    let d = SynthOptions::default();
    Ok(Some(SynthOptions {
        luminaire: name.clone(),
        layout: crate::commands::parse_layout(args.layout.as_deref().unwrap_or(DEFAULT_SYNTH_LAYOUT))?,
        radius_m: args.radius.unwrap_or(d.radius_m),
        size: args
            .size
            .as_deref()
            .map(crate::commands::parse_size_px)
            .transpose()?
            .unwrap_or(d.size),
        ..d
    }))
}

/// The scan the arguments describe, with a description for the metadata and the proxy to store: a
/// scan manifest's or --synth scan's reconstructed from its images unless --proxy or --no-proxy is
/// given, a ray file's or pack's its own.
fn input_scan(args: &PackArgs) -> Result<Input, Box<dyn std::error::Error>> {
    let reconstruct = args.proxy.is_none() && !args.no_proxy;
    if let Some(opts) = synth_options(args)? {
        if !args.input.is_empty() {
            return Err("give either input files or --synth, not both".into());
        }
        let desc = format!(
            "synthetic {} ({}, {}x{} px, r = {} m)",
            opts.luminaire,
            args.layout.as_deref().unwrap_or(DEFAULT_SYNTH_LAYOUT),
            opts.size.0,
            opts.size.1,
            opts.radius_m
        );
        // The synthetic goniophotometer samples pixel centres; a real camera integrates over its
        // pixels and sees a surface edge-on. Reconstruct from captures that do (only the ≤ 1024
        // cameras reconstruction reads are rendered so).
        let proxy = if reconstruct {
            let captures = synth_scan(&SynthOptions {
                supersample: CAPTURE_SUPERSAMPLE,
                ..opts.clone()
            })?;
            reconstructed_proxy(&captures, &desc, args.quiet)?
        } else {
            None
        };
        return Ok((synth_scan(&opts)?, desc, proxy));
    }
    let Some(file) = args.input.first() else {
        return Err("nothing to pack: give a scan manifest, a ray file, an .lvpack or --synth LUMINAIRE".into());
    };
    let kind = source::detect(file)?;
    if !matches!(kind, SourceKind::Pack | SourceKind::RayFile) {
        let opts = ImportOptions {
            skip_bad: args.skip_bad_images,
            verify_pixels: false,
        };
        let scan = load_scan(&args.input, &opts)?;
        let names: Vec<String> = args.input.iter().map(|p| p.display().to_string()).collect();
        let desc = format!("scan manifest {}", names.join(" + "));
        let proxy = if reconstruct {
            reconstructed_proxy(&scan, &desc, args.quiet)?
        } else {
            None
        };
        return Ok((scan, desc, proxy));
    }
    for (given, name) in [
        (args.layout.is_some(), "--layout"),
        (args.size.is_some(), "--size"),
        (args.radius.is_some(), "--radius"),
    ] {
        if given {
            return Err(format!(
                "{name} applies to --synth (a .lvpack keeps its cameras; a ray file's estimate chooses them from the \
                 data: set them with `lumiview rays2scan`, then `lumiview pack DIR/scan.json --proxy DIR/proxy.glb \
                 --proxy-bound`)"
            )
            .into());
        }
    }
    if args.input.len() > 1 {
        return Err("several inputs are only allowed for scan manifests (one per hemisphere)".into());
    }
    if kind == SourceKind::Pack {
        let pack = Pack::open(file)?;
        let desc = format!("repacked from {} ({})", file.display(), pack.metadata().source);
        let proxy = pack.proxy().cloned();
        return Ok((pack.into_scan(), desc, proxy));
    }
    // A TM-25 ray file: as `lumi_luminaire_load` and `render` read it.
    let mut warnings = Vec::new();
    let input = scanfile::scan_from_file_with_warnings(file, ScanFileKind::RayFile, &mut warnings)?;
    for w in &warnings {
        eprintln!("lumiview: warning: {w}");
    }
    Ok(input)
}

/// The proxy reconstructed from `scan`'s images, with a progress bar and a line on stderr.
fn reconstructed_proxy(scan: &Scan, what: &str, quiet: bool) -> Result<Option<PackProxy>, Box<dyn std::error::Error>> {
    let bar = super::proxy::bar(quiet, "proxy:");
    let mut warnings = Vec::new();
    let rec = lumiview::nearfield::reconstruct::scan_proxy(
        scan,
        what,
        &|stage, done, total| super::proxy::show_stage(&bar, stage, done, total),
        &mut warnings,
    );
    bar.finish_and_clear();
    for w in &warnings {
        eprintln!("lumiview: warning: {w}");
    }
    let Some(rec) = rec? else { return Ok(None) };
    if !quiet {
        let r = &rec.report;
        eprintln!(
            "proxy: reconstructed from {} of {} cameras, {:.2} mm cells, {} triangles in {:.1} s (--no-proxy: none)",
            r.cameras_used,
            r.cameras_read,
            r.voxel_m * 1e3,
            r.triangles,
            r.seconds.iter().sum::<f64>()
        );
    }
    Ok(Some(rec.to_pack_proxy()))
}

fn stats_json(path: &Path, s: &PackStats, secs: f64) -> serde_json::Value {
    json!({
        "file": path.display().to_string(),
        "images": s.images,
        "empty_images": s.empty_images,
        "tiles_kept": s.tiles_kept,
        "tiles_f32": s.tiles_f32,
        "pages": s.pages,
        "bytes": s.bytes,
        "pool_bytes": s.pool_bytes,
        "tile_table_bytes": s.tile_table_bytes,
        "pixels": s.pixels,
        "pixels_kept": s.pixels_kept,
        "dense_f16_bytes": s.dense_f16_bytes,
        "csr_bytes": s.csr_bytes,
        "ratio_to_dense_f16": s.ratio_to_dense_f16(),
        "ratio_to_csr": s.ratio_to_csr(),
        "seconds": secs,
        "images_per_second": s.images as f64 / secs.max(1e-9),
    })
}

/// Runs `lumiview pack`.
pub fn pack(args: &PackArgs) -> CliResult {
    if !(1..=MAX_PAGE_BYTES >> 20).contains(&args.page_mib) {
        return Err(format!("--page-mib {}: must be within 1…128", args.page_mib).into());
    }
    let threshold = Threshold::parse(&args.threshold)?;
    // Never replace an input: the manifests, ray file or pack given, the proxy mesh (a manifest's
    // images and a pack's own file are checked by write_pack).
    lumiview::files::ensure_not_input(
        &args.output,
        args.input.iter().chain(args.proxy.iter()).map(PathBuf::as_path),
    )?;
    let (scan, source, proxy) = input_scan(args)?;
    let proxy = match &args.proxy {
        Some(path) => Some(PackProxy {
            triangles: lumiview::nearfield::proxy::load_gltf(path)?,
            bound: args.proxy_bound,
            source: format!("{}", path.display()),
        }),
        None if args.no_proxy => None,
        None => proxy,
    };
    let opts = PackOptions {
        tile_size: args.tile,
        threshold,
        page_bytes: args.page_mib << 20,
        chunk_images: 0,
        source,
        proxy,
    };
    let n = scan.set.cameras.len() as u64;
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::with_draw_target(Some(n), ProgressDrawTarget::stderr())
    };
    if let Ok(style) =
        ProgressStyle::with_template("packing {bar:40} {pos}/{len} images [{elapsed_precise}, {per_sec}, eta {eta}]")
    {
        bar.set_style(style);
    }
    let start = Instant::now();
    let stats = write_pack(&scan, &args.output, &opts, &|done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    let stats = stats?;
    let secs = start.elapsed().as_secs_f64();
    let mut out = String::new();
    if args.json {
        outln!(
            out,
            "{}",
            serde_json::to_string_pretty(&stats_json(&args.output, &stats, secs))?
        );
    } else {
        outln!(
            out,
            "wrote {}: {} images ({} empty), {} tiles ({} exact f32), {} pages, {} bytes",
            args.output.display(),
            stats.images,
            stats.empty_images,
            stats.tiles_kept,
            stats.tiles_f32,
            stats.pages,
            stats.bytes
        );
        outln!(
            out,
            "footprint {:.4} × dense fp16 ({} bytes), {:.3} × CSR ({} bytes)",
            stats.ratio_to_dense_f16(),
            stats.dense_f16_bytes,
            stats.ratio_to_csr(),
            stats.csr_bytes
        );
        outln!(
            out,
            "time      {secs:.2} s, {:.1} images/s",
            stats.images as f64 / secs.max(1e-9)
        );
    }
    print_report(&out)
}

fn mib(b: u64) -> String {
    format!("{:.2} MiB", b as f64 / (1u64 << 20) as f64)
}

/// `lumiview info FILE.lvpack [--verify]`.
pub fn info_pack(file: &Path, as_json: bool, verify: bool) -> CliResult {
    let pack = Pack::open(file)?;
    let report = if verify { Some(pack.verify()?) } else { None };
    let m = pack.metadata();
    let set = pack.rayset();
    let l = pack.layout();
    let own = set.cameras.iter().filter(|c| c.intrinsics.is_some()).count();
    let lower = set.cameras.iter().filter(|c| c.hemisphere == Hemisphere::Lower).count();
    let upper = set.cameras.len() - lower;
    let grid_tiles: u64 = pack
        .images()
        .iter()
        .map(|e| u64::from(e.width.div_ceil(l.tile_size)) * u64::from(e.height.div_ceil(l.tile_size)))
        .sum();
    let bytes = pack.file_len();
    let f = &m.footprint;
    let ratio = |a: u64, b: u64| if b == 0 { f64::NAN } else { a as f64 / b as f64 };
    let k = &set.intrinsics;
    let thr = &m.encoding.threshold;
    let thr_text = match thr.kind {
        lumiview::nearfield::pack::format::ThresholdKind::Absolute if thr.value == 0.0 => {
            "0 cd/m² (every nonzero pixel kept)".to_string()
        }
        lumiview::nearfield::pack::format::ThresholdKind::Absolute => format!("{} cd/m²", thr.value),
        lumiview::nearfield::pack::format::ThresholdKind::Relative => {
            format!("{} × each image's maximum", thr.value)
        }
    };
    let mut out = String::new();
    if as_json {
        let v = json!({
            "file": file.display().to_string(),
            "format": m.format,
            "version": m.version,
            "created_by": m.created_by,
            "source": m.source,
            "cameras": {"total": set.cameras.len(), "lower": lower, "upper": upper, "own_intrinsics": own},
            "capture_sphere": {"centre_m": set.sphere.centre_m.to_array(), "radius_m": set.sphere.radius_m},
            "intrinsics": {
                "width": k.width, "height": k.height,
                "principal_px": k.principal_px.to_array(), "focal_px": k.focal_px.to_array(),
            },
            "encoding": {
                "scheme": m.encoding.scheme,
                "tile_size": l.tile_size,
                "slot_bytes": l.entry_bytes,
                "max_relative_error": m.encoding.max_relative_error,
                "threshold": {"kind": thr.kind, "value": thr.value},
            },
            "tiles": {
                "kept": m.tiles.kept, "f32": m.tiles.f32, "grid": grid_tiles,
                "empty_images": m.tiles.empty_images,
            },
            "pages": {
                "count": l.page_count, "slots_per_page": l.slots_per_page,
                "slots_total": l.slots_total, "page_bytes_max": m.pages.page_bytes_max,
            },
            "footprint": {
                "bytes": bytes, "pool_bytes": f.pool_bytes, "tile_table_bytes": f.tile_table_bytes,
                "pixels": f.pixels, "pixels_kept": f.pixels_kept,
                "dense_f16_bytes": f.dense_f16_bytes, "csr_bytes": f.csr_bytes,
                "ratio_to_dense_f16": ratio(bytes, f.dense_f16_bytes), "ratio_to_csr": ratio(bytes, f.csr_bytes),
            },
            "sections": pack.sections().iter().map(|s| json!({
                "name": s.name, "offset": s.offset, "length": s.length, "crc32": format!("{:08x}", s.crc32),
            })).collect::<Vec<_>>(),
            "verify": report.map(|r| json!({"ok": true, "pages": r.pages, "bytes": r.bytes, "tiles": r.tiles})),
        });
        outln!(out, "{}", serde_json::to_string_pretty(&v)?);
        return print_report(&out);
    }
    outln!(out, "file              {}", file.display());
    outln!(out, "format            lvpack {} ({})", m.version, m.created_by);
    if !m.source.is_empty() {
        outln!(out, "source            {}", m.source);
    }
    outln!(
        out,
        "cameras           {} ({lower} lower, {upper} upper hemisphere{})",
        set.cameras.len(),
        if own > 0 {
            format!("; {own} with their own intrinsics")
        } else {
            String::new()
        }
    );
    let c = set.sphere.centre_m;
    outln!(
        out,
        "capture sphere    r = {} m, centre ({}, {}, {}) m",
        set.sphere.radius_m,
        c.x,
        c.y,
        c.z
    );
    outln!(
        out,
        "intrinsics        {} × {} px, principal point ({}, {}) px, focal length ({}, {}) px",
        k.width,
        k.height,
        k.principal_px.x,
        k.principal_px.y,
        k.focal_px.x,
        k.focal_px.y
    );
    outln!(
        out,
        "encoding          {0} × {0} px tiles, fp16 × per-tile 2^k scale ({1}-byte slots), exact f32 for tiles beyond fp16's range; max relative error {2:.4} %",
        l.tile_size,
        l.entry_bytes,
        m.encoding.max_relative_error * 100.0
    );
    outln!(out, "threshold         {thr_text}");
    outln!(
        out,
        "tiles             {} kept of {} ({:.2} %), {} exact f32; {} empty images",
        m.tiles.kept,
        grid_tiles,
        100.0 * ratio(m.tiles.kept, grid_tiles),
        m.tiles.f32,
        m.tiles.empty_images
    );
    outln!(
        out,
        "pages             {} (≤ {} each, {} slots per page), pool {}",
        l.page_count,
        mib(m.pages.page_bytes_max),
        l.slots_per_page,
        mib(f.pool_bytes)
    );
    outln!(
        out,
        "footprint         {} bytes = {:.4} × dense fp16 ({}), {:.3} × CSR ({})",
        bytes,
        ratio(bytes, f.dense_f16_bytes),
        mib(f.dense_f16_bytes),
        ratio(bytes, f.csr_bytes),
        mib(f.csr_bytes)
    );
    outln!(
        out,
        "sections          {:<14} {:>14} {:>14}  crc32",
        "name",
        "offset",
        "bytes"
    );
    let pages: Vec<_> = pack.sections().iter().filter(|s| s.name.starts_with("page.")).collect();
    for s in pack
        .sections()
        .iter()
        .filter(|s| !s.name.starts_with("page.") || pages.len() <= 8)
    {
        outln!(
            out,
            "                  {:<14} {:>14} {:>14}  {:08x}",
            s.name,
            s.offset,
            s.length,
            s.crc32
        );
    }
    if pages.len() > 8 {
        let total: u64 = pages.iter().map(|s| s.length).sum();
        outln!(
            out,
            "                  {:<14} {:>14} {:>14}",
            format!("{} pages", pages.len()),
            "",
            total
        );
    }
    if let Some(r) = report {
        outln!(
            out,
            "verify            ok: {} pages and all padding, {} checked; {} tiles decoded, every value finite and ≥ 0",
            r.pages,
            mib(r.bytes),
            r.tiles
        );
    }
    print_report(&out)
}
