//! Subcommands on IES TM-25 ray files: `info` and `rays2scan`.

use std::path::{Path, PathBuf};

use clap::Args;
use glam::DVec3;
use lumiview::nearfield::binning::{bin_rays, BinningOptions, BinningReport};
use lumiview::nearfield::raykde::{estimate, KdeOptions};
use lumiview::nearfield::tm25::{RayFile, RayFlux, RayStats};
use lumiview::nearfield::CaptureSphere;
use lumiview::nearfield::Scan;
use serde_json::{json, Value};

use super::{print_report, CliResult};

/// `--ray-flux`: what a ray file's flux values mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RayFluxArg {
    /// The header's total flux, where it states one and the rays' sum differs by more than 1 %.
    Header,
    /// The rays' own values.
    Rays,
}

impl From<RayFluxArg> for RayFlux {
    fn from(a: RayFluxArg) -> Self {
        match a {
            RayFluxArg::Header => RayFlux::Header,
            RayFluxArg::Rays => RayFlux::Rays,
        }
    }
}

/// `lumiview rays2scan`: turn a TM-25 ray file into the luminance images of a virtual scan.
#[derive(Args, Debug)]
pub struct Rays2scanArgs {
    /// IES TM-25 ray file (.tm25ray).
    pub file: PathBuf,
    /// Output: a directory, or the scan manifest path (`…/scan.json`) whose directory receives it.
    /// With `--method kde` the proxy mesh from the ray origins is written beside it as `proxy.glb`.
    #[arg(short = 'o', long = "output", value_name = "DIR|scan.json")]
    pub output: PathBuf,
    /// `kde`: a kernel density estimate of the light field with kernels, cameras and image size
    /// chosen from the data (docs/rayfiles.md); `histogram`: each ray into the pixel of its
    /// nearest camera (noisy unless millions of rays land in each camera).
    #[arg(long, default_value = "kde", value_name = "kde|histogram")]
    pub method: String,
    /// kde: rays per spatial kernel (default 4·√N: noise about 1/√ of it).
    #[arg(long, value_name = "K")]
    pub rays_per_kernel: Option<f64>,
    /// kde: rays per intensity kernel (default 0.5·N^(2/3)).
    #[arg(long, value_name = "K")]
    pub rays_per_intensity_kernel: Option<f64>,
    /// kde: a fixed intensity kernel half-width in degrees instead of the adaptive one.
    #[arg(long, value_name = "DEG")]
    pub angular_kernel: Option<f64>,
    /// kde: a fixed spatial kernel σ in millimetres instead of the adaptive one.
    #[arg(long, value_name = "MM")]
    pub spatial_kernel: Option<f64>,
    /// kde: number of virtual cameras (default: from the angular kernel).
    #[arg(long, value_name = "N")]
    pub cameras: Option<usize>,
    /// kde: image side in pixels (default: from the spatial kernel).
    #[arg(long, value_name = "PX")]
    pub image_px: Option<u32>,
    /// histogram: camera layout: `fibonacci:N`, `grid:P,T` (P meridians × T rows, poles once) or
    /// `rigo:N` (N cameras per hemisphere, meridians, 2° overlap, 0.05° jitter); default fibonacci:1000.
    #[arg(long, value_name = "KIND:N")]
    pub layout: Option<String>,
    /// Capture sphere radius in metres (kde default: max(1.1, 8 × the source's radius); histogram:
    /// 1.1).
    #[arg(long, value_name = "M")]
    pub radius: Option<f64>,
    /// histogram: capture sphere centre `X,Y,Z` in metres, in the ray file's frame (kde: the centre
    /// of the ray origins).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub centre: Option<String>,
    /// histogram: image size in pixels, `WxH` (default 64x64).
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// histogram: full horizontal field of view in degrees (square pixels), or `auto` to fit every ray.
    #[arg(long, value_name = "DEG|auto")]
    pub fov: Option<String>,
    /// histogram: seed of the layout's jitter (`rigo`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// What the rays' flux values mean: `header` (default) scales them to the header's total
    /// flux where it states one and their sum differs by more than 1 % (TM-25 ray fluxes are then
    /// relative weights; a warning names both), `rays` keeps the rays' own values.
    #[arg(long, value_enum, default_value_t = RayFluxArg::Header)]
    pub ray_flux: RayFluxArg,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Estimate and report, but write nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// kde: render the estimate orthographically on the GPU over the 5° direction bins every 15°
    /// of C (four views per bin, averaged as the bin averages its rays) and compare the intensity
    /// with the rays binned by direction (cd); prints the median and 95th percentile error over the
    /// bins holding ≥ 1 % of the peak, beside the bins' own noise, and over 5° γ rings.
    #[arg(long)]
    pub check: bool,
}

/// Parses `X,Y,Z`.
fn parse_centre(text: &str) -> Result<DVec3, String> {
    let bad = || format!("--centre `{text}`: expected X,Y,Z in metres, e.g. 0,0,0");
    let v: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<Vec<_>>>()
        .ok_or_else(bad)?;
    match v[..] {
        [x, y, z] => Ok(DVec3::new(x, y, z)),
        _ => Err(bad()),
    }
}

fn opt_num(v: Option<f64>) -> Value {
    v.map_or(Value::Null, |v| json!(v))
}

fn vec3(v: DVec3) -> Value {
    json!([v.x, v.y, v.z])
}

/// Σ ray flux against the header's total, as a relative difference (when both are known).
fn relative(sum: Option<f64>, header: Option<f64>) -> Option<f64> {
    match (sum, header) {
        (Some(s), Some(h)) if h > 0.0 => Some(s / h - 1.0),
        _ => None,
    }
}

/// "+0.0001 % vs the header" for small differences, "10000 × the header's" for large ones.
fn versus_header(d: f64) -> String {
    if d.abs() < 0.5 {
        format!("{:+.4} % vs the header", 100.0 * d)
    } else {
        format!("{:.6} × the header's", 1.0 + d)
    }
}

/// `lumiview info FILE.tm25ray`.
pub fn info_rayfile(file: &Path, as_json: bool) -> CliResult {
    let f = RayFile::read(file)?;
    let h = f.header();
    let s = f.stats();
    let lum_vs_header = relative(s.luminous_sum_lm, h.luminous_flux_lm);
    let rad_vs_header = relative(s.radiant_sum_w, h.radiant_flux_w);
    if as_json {
        let v = json!({
            "file": file.display().to_string(),
            "format": "IES TM-25",
            "header": {
                "version": h.version,
                "creation_method": h.creation_method.name(),
                "creation_method_code": h.creation_method.as_i32(),
                "luminous_flux_lm": opt_num(h.luminous_flux_lm),
                "radiant_flux_w": opt_num(h.radiant_flux_w),
                "ray_count": h.ray_count,
                "date": h.date,
                "ray_start_position": h.ray_start_position,
                "spectral_identifier": h.spectral.as_i32(),
                "spectral_kind": h.spectral.name(),
                "single_wavelength_nm": opt_num(h.single_wavelength_nm),
                "min_wavelength_nm": opt_num(h.min_wavelength_nm),
                "max_wavelength_nm": opt_num(h.max_wavelength_nm),
                "spectral_table_count": h.spectral_tables.len(),
                "additional_item_count": h.additional_columns.len(),
                "additional_text_bytes": h.additional_text_bytes,
                "ray_data_offset": h.ray_data_offset,
                "items_per_ray": h.items_per_ray(),
            },
            "flags": h.flags.entries().iter().map(|(k, v)| (k.to_string(), json!(v))).collect::<serde_json::Map<_, _>>(),
            "columns": h.column_names(),
            "description": h.description.entries().iter().map(|(k, v)| json!({"field": k, "value": v})).collect::<Vec<_>>(),
            "spectral_tables": h.spectral_tables.iter().map(|t| json!({
                "points": t.wavelengths_nm.len(),
                "min_nm": t.wavelengths_nm.iter().copied().reduce(f64::min),
                "max_nm": t.wavelengths_nm.iter().copied().reduce(f64::max),
                "peak_nm": t.peak_nm(),
                "luminous_efficacy_lm_per_w": t.luminous_efficacy(),
            })).collect::<Vec<_>>(),
            "additional_columns": h.additional_columns,
            "additional_text": h.additional_text,
            "luminous_flux_rule": {"key": f.luminous_source().key(), "description": f.luminous_source().describe()},
            "rays": stats_json(&s),
            "ray_flux_vs_header": {
                "luminous_relative_difference": lum_vs_header,
                "radiant_relative_difference": rad_vs_header,
            },
            "warnings": f.warnings(),
        });
        return print_report(&format!("{}\n", serde_json::to_string_pretty(&v)?));
    }
    let mut out = String::new();
    outln!(out, "file              {}", file.display());
    outln!(out, "format            IES TM-25 ray file, version {}", h.version);
    outln!(out, "creation method   {}", h.creation_method.name());
    outln!(
        out,
        "date              {}",
        if h.date.is_empty() { "—" } else { &h.date }
    );
    let unknown = |v: Option<f64>, unit: &str| v.map_or("unknown (NaN)".to_string(), |v| format!("{v} {unit}"));
    outln!(out, "luminous flux     {} (header)", unknown(h.luminous_flux_lm, "lm"));
    outln!(out, "radiant flux      {} (header)", unknown(h.radiant_flux_w, "W"));
    outln!(
        out,
        "rays              {} × {} items ({} bytes each) from offset {}",
        h.ray_count,
        h.items_per_ray(),
        4 * h.items_per_ray(),
        h.ray_data_offset
    );
    outln!(out, "columns           {}", h.column_names().join(", "));
    outln!(out, "ray start pos.    {} (code; 0 = unknown)", h.ray_start_position);
    outln!(out, "spectral data     {} ({})", h.spectral.as_i32(), h.spectral.name());
    let nm = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v} nm"));
    outln!(
        out,
        "wavelengths       single {}, min {}, max {}",
        nm(h.single_wavelength_nm),
        nm(h.min_wavelength_nm),
        nm(h.max_wavelength_nm)
    );
    let flags: Vec<String> = h
        .flags
        .entries()
        .iter()
        .map(|(k, v)| format!("{k} {}", u8::from(*v)))
        .collect();
    outln!(out, "flags             {}", flags.join(", "));
    for (k, v) in h.description.entries() {
        if !v.is_empty() {
            outln!(out, "  {k:<24}{}", v.replace('\n', " / "));
        }
    }
    for (i, t) in h.spectral_tables.iter().enumerate() {
        let lo = t.wavelengths_nm.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = t.wavelengths_nm.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        outln!(
            out,
            "spectral table {}  {} points, {lo}–{hi} nm, peak {}, luminous efficacy {}",
            i + 1,
            t.wavelengths_nm.len(),
            nm(t.peak_nm()),
            t.luminous_efficacy().map_or("—".into(), |k| format!("{k:.2} lm/W"))
        );
    }
    if !h.additional_columns.is_empty() {
        outln!(out, "additional cols   {}", h.additional_columns.join(", "));
    }
    if !h.additional_text.is_empty() {
        outln!(out, "additional text   {}", h.additional_text.replace('\n', " / "));
    }
    outln!(out, "luminous per ray  {}", f.luminous_source().describe());
    if let Some(sum) = s.luminous_sum_lm {
        out!(out, "Σ ray lum. flux   {sum:.6} lm");
        if let Some(d) = lum_vs_header {
            out!(out, " ({})", versus_header(d));
        }
        outln!(out);
    }
    if let Some(sum) = s.radiant_sum_w {
        out!(out, "Σ ray rad. flux   {sum:.6} W");
        if let Some(d) = rad_vs_header {
            out!(out, " ({})", versus_header(d));
        }
        outln!(out);
    }
    outln!(
        out,
        "ray flux range    {:.6e} … {:.6e} ({})",
        s.flux_range.0,
        s.flux_range.1,
        s.weight
    );
    let (lo, hi) = (s.bbox_min_m, s.bbox_max_m);
    outln!(
        out,
        "bounding box      x {:.4}…{:.4}, y {:.4}…{:.4}, z {:.4}…{:.4} mm",
        lo.x * 1e3,
        hi.x * 1e3,
        lo.y * 1e3,
        hi.y * 1e3,
        lo.z * 1e3,
        hi.z * 1e3
    );
    outln!(
        out,
        "                  = x {:.6}…{:.6}, y {:.6}…{:.6}, z {:.6}…{:.6} m; farthest start {:.6} m from the origin",
        lo.x,
        hi.x,
        lo.y,
        hi.y,
        lo.z,
        hi.z,
        s.max_radius_m
    );
    let m = s.mean_direction;
    outln!(
        out,
        "mean direction    ({:.4}, {:.4}, {:.4}), length {:.4} ({}-weighted; 1 = collimated, 2/3 = Lambertian)",
        m.x,
        m.y,
        m.z,
        m.length(),
        s.weight
    );
    outln!(
        out,
        "upward (kz > 0)   {:.2} % of the {} flux; widest ray {:.2}° from the mean direction",
        100.0 * s.upward_fraction,
        s.weight,
        s.max_angle_from_mean_deg
    );
    outln!(out, "angle from +Z     share of flux per 10° band:");
    for (i, v) in s.polar_histogram.iter().enumerate() {
        if *v > 0.0 {
            let band = format!("{}–{}°", 10 * i, 10 * i + 10);
            outln!(out, "  {band:<16}{:>7.3} %", 100.0 * v);
        }
    }
    if let Some((a, b)) = s.wavelength_range_nm {
        outln!(out, "ray wavelengths   {a}–{b} nm");
    }
    for w in f.warnings() {
        outln!(out, "warning           {w}");
    }
    print_report(&out)
}

fn stats_json(s: &RayStats) -> Value {
    json!({
        "count": s.count,
        "luminous_flux_sum_lm": s.luminous_sum_lm,
        "radiant_flux_sum_w": s.radiant_sum_w,
        "flux_range": [s.flux_range.0, s.flux_range.1],
        "weight": s.weight,
        "bbox_min_m": vec3(s.bbox_min_m),
        "bbox_max_m": vec3(s.bbox_max_m),
        "bbox_min_mm": vec3(s.bbox_min_m * 1e3),
        "bbox_max_mm": vec3(s.bbox_max_m * 1e3),
        "max_start_radius_m": s.max_radius_m,
        "mean_direction": vec3(s.mean_direction),
        "upward_fraction": s.upward_fraction,
        "polar_histogram_10deg_from_plus_z": s.polar_histogram,
        "max_angle_from_mean_deg": s.max_angle_from_mean_deg,
        "max_direction_norm_error": s.max_direction_norm_error,
        "wavelength_range_nm": s.wavelength_range_nm.map(|(a, b)| [a, b]),
    })
}

fn report_json(file: &Path, manifest: Option<&Path>, r: &BinningReport) -> Value {
    let rays = &r.rays_per_camera;
    json!({
        "file": file.display().to_string(),
        "manifest": manifest.map(|p| p.display().to_string()),
        "luminous_flux_rule": {"key": r.luminous_source.key(), "description": r.luminous_source.describe()},
        "flux_scale": r.flux_scale,
        "cameras": rays.len(),
        "rays": {
            "total": r.rays_total,
            "used": r.rays_used,
            "behind_every_camera": r.rays_behind,
            "outside_image": r.rays_outside_image,
            "per_camera_min": rays.iter().min(),
            "per_camera_mean": if rays.is_empty() { 0.0 } else { r.rays_used as f64 / rays.len() as f64 },
            "per_camera_max": rays.iter().max(),
            "cameras_with_zero_rays": r.cameras_with_zero_rays,
            "cameras_merged": r.cameras_merged,
            "lit_pixels": r.lit_pixels,
            "per_lit_pixel_mean": r.rays_per_lit_pixel_mean,
            "per_lit_pixel_median": r.rays_per_lit_pixel_median,
            "per_lit_pixel_max": r.rays_per_lit_pixel_max,
        },
        "flux_lm": {
            "total": r.flux_total_lm,
            "used": r.flux_used_lm,
            "behind_every_camera": r.flux_behind_lm,
            "outside_image": r.flux_outside_image_lm,
            "from_images": r.flux_from_images_lm,
        },
        "geometry": {
            "fov_deg": r.fov_deg,
            "focal_px": r.focal_px,
            "pixel_area_m2": r.pixel_area_m2,
            "solid_angle_sr_min": r.solid_angle_sr.iter().copied().reduce(f64::min),
            "solid_angle_sr_max": r.solid_angle_sr.iter().copied().reduce(f64::max),
            "solid_angles_exact": r.solid_angles_exact,
            "cameras_with_tiny_cells": r.cameras_with_tiny_cells,
        },
    })
}

fn report_text(file: &Path, manifest: Option<&Path>, r: &BinningReport) -> String {
    let mut out = String::new();
    let rays = &r.rays_per_camera;
    outln!(out, "ray file          {}", file.display());
    outln!(out, "luminous per ray  {}", r.luminous_source.describe());
    if r.flux_scale != 1.0 {
        outln!(
            out,
            "flux scale        × {:.6e} (the rays' sum to the header's total flux)",
            r.flux_scale
        );
    }
    out!(
        out,
        "cameras           {} ({} with no ray",
        rays.len(),
        r.cameras_with_zero_rays
    );
    if r.cameras_merged > 0 {
        out!(
            out,
            "; {} at the direction of an earlier one, merged into it",
            r.cameras_merged
        );
    }
    outln!(
        out,
        "), Ω {:.3e}…{:.3e} sr ({})",
        r.solid_angle_sr
            .iter()
            .copied()
            .filter(|o| *o > 0.0)
            .fold(f64::INFINITY, f64::min),
        r.solid_angle_sr.iter().copied().fold(0.0, f64::max),
        if r.solid_angles_exact {
            "exact Voronoi cells"
        } else {
            "sampled Voronoi cells"
        }
    );
    outln!(
        out,
        "image             fov {:.4}°, f = {:.2} px, pixel footprint {:.4e} m² ({:.4} mm square)",
        r.fov_deg,
        r.focal_px,
        r.pixel_area_m2,
        r.pixel_area_m2.sqrt() * 1e3
    );
    outln!(
        out,
        "rays              {} used of {} ({} behind every camera, {} outside the image)",
        r.rays_used,
        r.rays_total,
        r.rays_behind,
        r.rays_outside_image
    );
    outln!(
        out,
        "rays per camera   min {}, mean {:.2}, max {}",
        rays.iter().min().unwrap_or(&0),
        if rays.is_empty() {
            0.0
        } else {
            r.rays_used as f64 / rays.len() as f64
        },
        rays.iter().max().unwrap_or(&0)
    );
    outln!(
        out,
        "rays per lit px   mean {:.2}, median {}, max {} ({} lit pixels)",
        r.rays_per_lit_pixel_mean,
        r.rays_per_lit_pixel_median,
        r.rays_per_lit_pixel_max,
        r.lit_pixels
    );
    let pct = |v: f64| {
        if r.flux_total_lm > 0.0 {
            100.0 * v / r.flux_total_lm
        } else {
            0.0
        }
    };
    outln!(
        out,
        "flux              {:.6} lm in the rays, {:.6} lm binned ({:.4} %), Σ L·A·Ω of the images {:.6} lm",
        r.flux_total_lm,
        r.flux_used_lm,
        pct(r.flux_used_lm),
        r.flux_from_images_lm
    );
    if let Some(m) = manifest {
        outln!(out, "written           {}", m.display());
    }
    out
}

/// Where the scan goes: `-o DIR` or `-o DIR/scan.json`.
fn output_dir(output: &Path) -> PathBuf {
    let is_json = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if is_json {
        match output.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    } else {
        output.to_path_buf()
    }
}

/// Writes the binned scan (`manifest.json` + `images/NNNNN.pf`) into `dir`; when `-o` named a
/// `.json` file other than `manifest.json`, the manifest is renamed to it. Returns the manifest path.
fn write_scan_files(dir: &Path, output: &Path, scan: &Scan) -> Result<PathBuf, Box<dyn std::error::Error>> {
    let n = scan.set.cameras.len() as u64;
    let bar = indicatif::ProgressBar::new(n);
    let manifest = lumiview::nearfield::manifest::write_scan(dir, scan, &|done, _| {
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    let wanted = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if wanted && output.file_name() != manifest.file_name() {
        std::fs::rename(&manifest, output)
            .map_err(|e| format!("{}: cannot rename {}: {e}", output.display(), manifest.display()))?;
        return Ok(output.to_path_buf());
    }
    Ok(manifest)
}

/// `lumiview rays2scan`.
pub fn rays2scan(args: &Rays2scanArgs) -> CliResult {
    match args.method.as_str() {
        "kde" => rays2scan_kde(args),
        "histogram" => rays2scan_histogram(args),
        m => Err(format!("--method `{m}`: expected kde or histogram").into()),
    }
}

fn rays2scan_histogram(args: &Rays2scanArgs) -> CliResult {
    for (given, name) in [
        (args.rays_per_kernel.is_some(), "--rays-per-kernel"),
        (args.rays_per_intensity_kernel.is_some(), "--rays-per-intensity-kernel"),
        (args.angular_kernel.is_some(), "--angular-kernel"),
        (args.spatial_kernel.is_some(), "--spatial-kernel"),
        (args.cameras.is_some(), "--cameras"),
        (args.image_px.is_some(), "--image-px"),
        (args.check, "--check"),
    ] {
        if given {
            return Err(format!("{name} applies to --method kde").into());
        }
    }
    let layout = crate::commands::parse_layout(args.layout.as_deref().unwrap_or("fibonacci:1000"))?;
    let (width, height) = crate::commands::parse_size_px(args.size.as_deref().unwrap_or("64x64"))?;
    let centre = parse_centre(args.centre.as_deref().unwrap_or("0,0,0"))?;
    let fov = args.fov.as_deref().unwrap_or("auto");
    let fov_deg = if fov.trim().eq_ignore_ascii_case("auto") {
        None
    } else {
        Some(
            fov.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("--fov `{fov}`: expected degrees or `auto`"))?,
        )
    };
    let opts = BinningOptions {
        sphere: CaptureSphere {
            centre_m: centre,
            radius_m: args.radius.unwrap_or(1.1),
        },
        layout,
        seed: args.seed.unwrap_or(0),
        width,
        height,
        fov_deg,
        ray_flux: args.ray_flux.into(),
    };
    let file = RayFile::read(&args.file)?;
    let binned = bin_rays(&file, &opts)?;
    let r = &binned.report;
    for w in sparse_warnings(&args.file, r) {
        eprintln!("lumiview: warning: {w}");
    }
    let dir = output_dir(&args.output);
    let written = if args.dry_run {
        None
    } else {
        Some(write_scan_files(&dir, &args.output, &binned.scan)?)
    };
    if args.json {
        let v = report_json(&args.file, written.as_deref(), r);
        print_report(&format!("{}\n", serde_json::to_string_pretty(&v)?))
    } else {
        print_report(&report_text(&args.file, written.as_deref(), r))
    }
}

/// Warnings when a histogram is too sparse to show the source.
fn sparse_warnings(file: &Path, r: &BinningReport) -> Vec<String> {
    let mut w = Vec::new();
    let cams = r.rays_per_camera.len().max(1);
    let empty = r.cameras_with_zero_rays.saturating_sub(r.cameras_merged);
    if empty * 10 > cams {
        w.push(format!(
            "{}: {empty} of {cams} cameras ({:.0} %) received no ray: views near them show nothing \
             (--method kde estimates every camera from its neighbours' rays)",
            file.display(),
            100.0 * empty as f64 / cams as f64
        ));
    }
    if r.rays_per_lit_pixel_median < 10.0 && r.lit_pixels > 0 {
        w.push(format!(
            "{}: a median of {:.1} rays per lit pixel: the images are speckle, not the source (--method kde)",
            file.display(),
            r.rays_per_lit_pixel_median
        ));
    }
    w
}

fn rays2scan_kde(args: &Rays2scanArgs) -> CliResult {
    for (given, name) in [
        (args.layout.is_some(), "--layout"),
        (args.centre.is_some(), "--centre"),
        (args.size.is_some(), "--size"),
        (args.fov.is_some(), "--fov"),
        (args.seed.is_some(), "--seed"),
    ] {
        if given {
            return Err(format!(
                "{name} applies to --method histogram (kde chooses the layout and images from the data; see \
                 --cameras and --image-px)"
            )
            .into());
        }
    }
    let opts = KdeOptions {
        rays_per_kernel: args.rays_per_kernel,
        rays_per_intensity_kernel: args.rays_per_intensity_kernel,
        angular_kernel_deg: args.angular_kernel,
        spatial_kernel_m: args.spatial_kernel.map(|mm| mm / 1000.0),
        cameras: args.cameras,
        image_px: args.image_px,
        radius_m: args.radius,
        ray_flux: args.ray_flux.into(),
        keep_kernel_levels: false,
    };
    let file = RayFile::read(&args.file)?;
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:>18} [{bar:40}] {percent:>3} %")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let est = estimate(&file, &opts, &|stage, f| {
        bar.set_message(stage.to_string());
        bar.set_position((f * 1000.0) as u64);
    })?;
    bar.finish_and_clear();
    for w in &est.report.warnings {
        eprintln!("lumiview: warning: {w}");
    }
    let dir = output_dir(&args.output);
    let written = if args.dry_run {
        None
    } else {
        let m = write_scan_files(&dir, &args.output, &est.scan)?;
        est.proxy.write_glb(&dir.join("proxy.glb"))?;
        Some(m)
    };
    if args.check {
        let mut renderer = lumiview::gpu::Renderer::new(&lumiview::gpu::ContextDesc::default())?;
        let tmp = std::env::temp_dir().join(format!("lumiview-check-{}.lvpack", std::process::id()));
        let r = est.report.clone();
        let result = lumiview::eval::rays::check_intensity(&mut renderer, &file, est, &tmp, 15.0, &|m| {
            eprintln!("lumiview: {m}");
        });
        let _ = std::fs::remove_file(&tmp);
        let c = result?;
        if args.json {
            let mut v = serde_json::to_value(&r)?;
            v["file"] = json!(args.file.display().to_string());
            v["manifest"] = json!(written.as_ref().map(|p| p.display().to_string()));
            v["proxy"] = json!(written.as_ref().map(|_| dir.join("proxy.glb").display().to_string()));
            v["check"] = serde_json::to_value(&c)?;
            return print_report(&format!("{}\n", serde_json::to_string_pretty(&v)?));
        }
        let mut t = kde_text(&args.file, written.as_deref(), &r, &dir);
        t.push_str(&format!(
            "far field         {} bins of 5° compared (≥ 1 % of the peak {:.4} cd; the render averaged over each bin): \
             |render / rays − 1| median {:.2} %, 95th percentile {:.2} % (the rays' own noise per bin: median {:.2} %; \
             the difference in units of it: median {:.2}, 95th percentile {:.2}, where noise alone gives 0.67 and 1.96)\n",
            c.counted,
            c.peak_cd,
            100.0 * c.median_rel,
            100.0 * c.p95_rel,
            100.0 * c.median_reference_noise,
            c.median_z,
            c.p95_z
        ));
        t.push_str(&format!(
            "far field, rings  {} γ rings of 5° (the mean over C, ≥ 1 % of the peak): median {:.2} %, 95th percentile \
             {:.2} %\n",
            c.rings.len(),
            100.0 * c.ring_median_rel,
            100.0 * c.ring_p95_rel
        ));
        return print_report(&t);
    }
    let r = &est.report;
    if args.json {
        let mut v = serde_json::to_value(r)?;
        v["file"] = json!(args.file.display().to_string());
        v["manifest"] = json!(written.as_ref().map(|p| p.display().to_string()));
        v["proxy"] = json!(written.as_ref().map(|_| dir.join("proxy.glb").display().to_string()));
        return print_report(&format!("{}\n", serde_json::to_string_pretty(&v)?));
    }
    print_report(&kde_text(&args.file, written.as_deref(), r, &dir))
}

/// The text report of a kernel estimate.
fn kde_text(file: &Path, written: Option<&Path>, r: &lumiview::nearfield::raykde::KdeReport, dir: &Path) -> String {
    let mut t = String::new();
    t.push_str(&format!("ray file          {}\n", file.display()));
    t.push_str(&format!(
        "rays              {} ({:.0} effective), {:.6} lm\n",
        r.rays, r.effective_rays, r.flux_lm
    ));
    t.push_str(&format!(
        "kernels           {:.0} rays per intensity kernel, {:.0} per spatial kernel of a footprint pooled from {:.0}\n",
        r.rays_per_intensity_kernel, r.rays_per_kernel, r.rays_per_angular_kernel
    ));
    let s = &r.angular_kernel_deg;
    t.push_str(&format!(
        "intensity kernel  half-width {:.2}° median ({:.2}°–{:.2}°, 10–90 % of the flux)\n",
        s.median, s.p10, s.p90
    ));
    let s = &r.footprint_kernel_deg;
    t.push_str(&format!(
        "footprint pool    half-width {:.2}° median ({:.2}°–{:.2}°)\n",
        s.median, s.p10, s.p90
    ));
    let s = &r.spatial_kernel_m;
    t.push_str(&format!(
        "spatial kernel    σ {:.3} mm median ({:.3}–{:.3} mm)\n",
        s.median * 1e3,
        s.p10 * 1e3,
        s.p90 * 1e3
    ));
    t.push_str(&format!(
        "virtual scan      {} cameras ({} lit) on a {:.3} m sphere, {}² px, fov {:.3}°, {:.4} mm per pixel\n",
        r.cameras,
        r.cameras_lit,
        r.radius_m,
        r.image_px,
        r.fov_deg,
        r.pixel_m * 1e3
    ));
    t.push_str(&format!(
        "flux              {:.6} lm in the cameras' quadrature of the estimate ({:.2} % of the rays')\n",
        r.flux_from_images_lm,
        100.0 * r.flux_from_images_lm / r.flux_lm
    ));
    t.push_str(&format!(
        "source            radius {:.3} mm about the origins' centre\n",
        r.source_radius_m * 1e3
    ));
    if let Some(m) = written {
        t.push_str(&format!(
            "wrote             {} and {}\n",
            m.display(),
            dir.join("proxy.glb").display()
        ));
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use lumiview::nearfield::layout::Layout;

    #[test]
    fn argument_parsers() {
        assert_eq!(
            crate::commands::parse_layout("fibonacci:12"),
            Ok(Layout::Fibonacci { count: 12 })
        );
        assert_eq!(
            crate::commands::parse_layout("grid:8,5"),
            Ok(Layout::Grid {
                phi_steps: 8,
                theta_steps: 5
            })
        );
        assert!(matches!(
            crate::commands::parse_layout("rigo:100"),
            Ok(Layout::Rigo {
                per_hemisphere: 100,
                ..
            })
        ));
        assert!(crate::commands::parse_layout("grid:8").is_err() && crate::commands::parse_layout("hex:3").is_err());
        assert_eq!(crate::commands::parse_size_px("640x480"), Ok((640, 480)));
        assert!(crate::commands::parse_size_px("0x4").is_err() && crate::commands::parse_size_px("64").is_err());
        assert_eq!(parse_centre("0,-1,2.5"), Ok(DVec3::new(0.0, -1.0, 2.5)));
        assert!(parse_centre("0,1").is_err());
        assert_eq!(output_dir(Path::new("out/scan.json")), PathBuf::from("out"));
        assert_eq!(output_dir(Path::new("scan.json")), PathBuf::from("."));
        assert_eq!(output_dir(Path::new("out")), PathBuf::from("out"));
    }
}
