//! `lumiview synth`: the synthetic goniophotometer on the command line — list the analytic
//! luminaires, print their exact photometry, write a scan (manifest + images), benchmark rendering,
//! write the proxy mesh, or render an orthographic ground-truth view. See docs/synthetic.md.

use std::path::{Path, PathBuf};
use std::time::Instant;

use lumiview::nearfield::layout::direction_deg;
use lumiview::nearfield::synth::{self, render_ortho, Luminaire, OrthoView, SynthOptions};
use lumiview::nearfield::Scan;
use rayon::prelude::*;
use serde_json::json;

use super::{print_report, CliResult};

/// Arguments of `lumiview synth`.
#[derive(clap::Args, Debug)]
pub struct SynthArgs {
    /// Analytic luminaire: disc, rect, star-panel, two-planes, strips, led-dots, cos1, cos10, cos100,
    /// reflector, peak.
    pub luminaire: Option<String>,
    /// List the luminaires with their flux and exit.
    #[arg(long)]
    pub list: bool,
    /// Camera layout: rigo:N (N cameras per hemisphere; 28000 is full size), fibonacci:N, grid:P,T
    /// (P meridians × T rows). Required for a scan (-o DIR or --dry-run).
    #[arg(long, value_name = "LAYOUT")]
    pub layout: Option<String>,
    /// Image size in pixels.
    #[arg(long, value_name = "WxH", default_value = "1216x1021")]
    pub size: String,
    /// Vertical field of view in degrees (default: frame the luminaire, its bounding sphere spanning
    /// 80 % of the shorter side).
    #[arg(long, value_name = "DEG")]
    pub fov_deg: Option<f64>,
    /// Capture radius in metres.
    #[arg(long, value_name = "M", default_value_t = 1.117)]
    pub radius: f64,
    /// Seed of the layout's jitter.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Rays per pixel: N×N (1 = point sample at the pixel centre).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub supersample: u32,
    /// Output: a directory for a scan (manifest + .pf images), or with --ortho an image (.pfm float
    /// luminance, or .png with a 4-decade log scale for viewing).
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Render every image of the scan without writing it and report the speed.
    #[arg(long)]
    pub dry_run: bool,
    /// Write the proxy mesh of the emitting surfaces as glTF binary (.glb).
    #[arg(long, value_name = "FILE.glb")]
    pub proxy: Option<PathBuf>,
    /// Orthographic ground-truth view from the direction C,GAMMA in degrees (lumiview's frame); prints
    /// Σ L·ΔA against the exact intensity.
    #[arg(long, value_name = "C,GAMMA", allow_hyphen_values = true)]
    pub ortho: Option<String>,
    /// Pixel size of --ortho in millimetres.
    #[arg(long, value_name = "MM", default_value_t = 0.5)]
    pub pixel_mm: f64,
    /// Forward-trace this many rays (1e6 and 1000000 both work, up to 5e7) from the luminaire into
    /// a TM-25 ray file (-o FILE.tm25ray; x, y, z in mm, direction, luminous flux in lm), with
    /// --seed: a measured ray file's stand-in with an exact reference (docs/rayfiles.md).
    #[arg(long, value_name = "N")]
    pub rays: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `--rays N -o FILE.tm25ray`: forward-traces the rays and writes them, with a progress bar.
fn rays(args: &SynthArgs, lum: &dyn Luminaire, n: &str) -> Result<String, Box<dyn std::error::Error>> {
    let count = crate::commands::eval::parse_count("--rays", n)?;
    let path = args
        .output
        .as_ref()
        .ok_or("--rays needs -o FILE.tm25ray for the ray file")?;
    if !(has_ext(path, "tm25ray") || has_ext(path, "tm25")) {
        return Err(format!("-o {}: expected a .tm25ray file for --rays", path.display()).into());
    }
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:>14} [{bar:40}] {percent:>3} %")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message("forward-tracing");
    let t = Instant::now();
    let rays = lumiview::nearfield::synth::emit::emit_rays(lum, count, args.seed, &|f| {
        bar.set_position((f * 1000.0) as u64);
    })?;
    bar.finish_and_clear();
    let bytes = rays.to_tm25(&format!(
        "lumiview synth {} --rays {count} --seed {}",
        lum.name(),
        args.seed
    ))?;
    drop(rays);
    std::fs::write(path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(format!(
        "wrote {}: {count} rays of '{}' ({:.1} MB, {:.1} lm exact), forward-traced in {:.1} s\n",
        path.display(),
        lum.name(),
        bytes.len() as f64 / 1e6,
        lum.flux_lm(),
        t.elapsed().as_secs_f64()
    ))
}

/// Parses `C,GAMMA` in degrees (γ within 0…180).
fn parse_direction(text: &str) -> Result<(f64, f64), String> {
    let bad = || format!("--ortho `{text}`: expected C,GAMMA in degrees, e.g. 0,30");
    let (c, g) = text.split_once(',').ok_or_else(bad)?;
    let c: f64 = c.trim().parse().map_err(|_| bad())?;
    let g: f64 = g.trim().parse().map_err(|_| bad())?;
    if !c.is_finite() || !g.is_finite() || !(0.0..=180.0).contains(&g) {
        return Err(format!(
            "--ortho `{text}`: GAMMA must lie within 0…180° and both be finite"
        ));
    }
    Ok((c, g))
}

/// The synthetic scan the arguments describe (cameras + on-demand renderer). This is the hook for
/// other outputs (e.g. `.lvpack`): build the scan here and hand it to the writer.
pub fn build_scan(args: &SynthArgs) -> Result<Scan, Box<dyn std::error::Error>> {
    let name = args
        .luminaire
        .as_deref()
        .ok_or("a luminaire name is required (see --list)")?;
    let layout = args
        .layout
        .as_deref()
        .ok_or("--layout is required for a scan, e.g. --layout rigo:28000 (full size) or fibonacci:200")?;
    let opts = SynthOptions {
        luminaire: name.to_string(),
        layout: crate::commands::parse_layout(layout)?,
        radius_m: args.radius,
        size: crate::commands::parse_size_px(&args.size)?,
        fov_deg: args.fov_deg,
        intrinsics: None,
        supersample: args.supersample,
        seed: args.seed,
    };
    Ok(synth::synth_scan(&opts)?)
}

/// Runs `lumiview synth`.
pub fn synth(args: &SynthArgs) -> CliResult {
    if args.list {
        return list(args.json);
    }
    let name = args
        .luminaire
        .as_deref()
        .ok_or("a luminaire name is required (see `lumiview synth --list`)")?;
    let lum = synth::luminaire(name)?;
    let mut did = false;
    let mut out = String::new();
    if let Some(p) = &args.proxy {
        if !has_ext(p, "glb") {
            return Err(format!("--proxy {}: expected a .glb file", p.display()).into());
        }
        let mesh = lum.proxy();
        mesh.write_glb(p)?;
        out.push_str(&format!(
            "wrote {}: proxy of '{}', {} surfaces, {} triangles (glTF Y up)\n",
            p.display(),
            name,
            mesh.surfaces.len(),
            mesh.triangle_count()
        ));
        did = true;
    }
    if let Some(n) = &args.rays {
        out.push_str(&rays(args, lum.as_ref(), n)?);
        did = true;
    } else if let Some(dir) = &args.ortho {
        out.push_str(&ortho(args, lum.as_ref(), dir)?);
        did = true;
    } else if args.dry_run || args.output.is_some() {
        out.push_str(&scan(args)?);
        did = true;
    }
    if !did {
        out.push_str(&summary(lum.as_ref(), args.json)?);
    }
    print_report(&out)
}

fn has_ext(p: &Path, ext: &str) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext))
}

fn list(as_json: bool) -> CliResult {
    let mut rows = Vec::new();
    for n in synth::NAMES {
        let l = synth::luminaire(n)?;
        rows.push((n.to_string(), l.description(), l.flux_lm(), l.closed_form()));
    }
    let text = if as_json {
        let v: Vec<_> = rows
            .iter()
            .map(|(n, d, f, c)| json!({"name": n, "description": d, "flux_lm": f, "closed_form": c}))
            .collect();
        format!("{}\n", serde_json::to_string_pretty(&v)?)
    } else {
        let mut s = String::new();
        for (n, d, f, c) in rows {
            s.push_str(&format!("{n:<11} {f:>12.3} lm{}  {d}\n", if c { "  " } else { " ~" }));
        }
        s.push_str("(~: flux by a documented numerical integral, see docs/synthetic.md)\n");
        s
    };
    print_report(&text)
}

fn summary(lum: &dyn Luminaire, as_json: bool) -> Result<String, Box<dyn std::error::Error>> {
    let b = lum.bounds();
    let gammas = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 89.0];
    let cd: Vec<(f64, f64)> = gammas
        .iter()
        .map(|&g| (g, lum.intensity_cd(direction_deg(0.0, g))))
        .collect();
    if as_json {
        let v = json!({
            "name": lum.name(),
            "description": lum.description(),
            "flux_lm": lum.flux_lm(),
            "closed_form": lum.closed_form(),
            "max_luminance_cd_m2": lum.max_luminance(),
            "bounds_m": {"min": [b.min.x, b.min.y, b.min.z], "max": [b.max.x, b.max.y, b.max.z]},
            "intensity_c0": cd.iter().map(|(g, i)| json!({"gamma": g, "cd": i})).collect::<Vec<_>>(),
        });
        return Ok(format!("{}\n", serde_json::to_string_pretty(&v)?));
    }
    let mut s = format!(
        "{}: {}\nflux            {:.4} lm{}\nmax luminance   {} cd/m²\nbounds (m)      x {}…{}, y {}…{}, z {}…{}\n",
        lum.name(),
        lum.description(),
        lum.flux_lm(),
        if lum.closed_form() {
            " (closed form)"
        } else {
            " (numerical integral)"
        },
        lum.max_luminance(),
        b.min.x,
        b.max.x,
        b.min.y,
        b.max.y,
        b.min.z,
        b.max.z
    );
    for (g, i) in cd {
        s.push_str(&format!("I(C0, γ {g:>4}°) {i:.4} cd\n"));
    }
    Ok(s)
}

fn ortho(args: &SynthArgs, lum: &dyn Luminaire, text: &str) -> Result<String, Box<dyn std::error::Error>> {
    let (c, g) = parse_direction(text)?;
    let out = args.output.as_ref().ok_or("--ortho needs -o FILE (.pfm or .png)")?;
    if !(has_ext(out, "pfm") || has_ext(out, "png")) {
        return Err(format!("-o {}: --ortho writes .pfm or .png", out.display()).into());
    }
    if !(args.pixel_mm.is_finite() && args.pixel_mm > 0.0) {
        return Err(format!("--pixel-mm {}: must be finite and > 0", args.pixel_mm).into());
    }
    let dir = direction_deg(c, g);
    let view = OrthoView::framing(&lum.bounds(), dir, args.pixel_mm * 1e-3)?;
    let t0 = Instant::now();
    let img = render_ortho(lum, &view, args.supersample)?;
    let secs = t0.elapsed().as_secs_f64();
    let sum: f64 = img.data.iter().map(|&v| f64::from(v)).sum::<f64>() * view.pixel_area_m2();
    let exact = lum.intensity_cd(dir);
    if has_ext(out, "pfm") {
        write_pfm(out, img.width, img.height, &img.data)?;
    } else {
        write_log_png(out, img.width, img.height, &img.data, lum.max_luminance())?;
    }
    let rel = if exact > 0.0 {
        format!("{:+.4} %", 100.0 * (sum - exact) / exact)
    } else {
        "—".into()
    };
    Ok(format!(
        "wrote {}: orthographic view of '{}' from C {c}°, γ {g}°, {} × {} px of {} mm, {}×{} rays/px ({secs:.2} s)\n\
         Σ L·ΔA          {sum:.6} cd\nexact I(C, γ)   {exact:.6} cd{}\ndifference      {rel}\n",
        out.display(),
        lum.name(),
        img.width,
        img.height,
        args.pixel_mm,
        args.supersample,
        args.supersample,
        if lum.closed_form() { "" } else { " (numerical integral)" },
    ))
}

fn scan(args: &SynthArgs) -> Result<String, Box<dyn std::error::Error>> {
    if let Some(out) = &args.output {
        if has_ext(out, "lvpack") {
            return Err(format!(
                "-o {}: .lvpack output is not wired yet (commands::synth::build_scan returns the scan to pack)",
                out.display()
            )
            .into());
        }
    }
    let scan = build_scan(args)?;
    let n = scan.set.cameras.len();
    let k = scan.set.intrinsics;
    if args.dry_run {
        let t0 = Instant::now();
        let source = scan.source.as_ref();
        let (lit, total) = (0..n)
            .into_par_iter()
            .map(|i| {
                source.image(i).map(|img| {
                    (
                        img.data.iter().filter(|v| **v > 0.0).count() as u64,
                        img.data.len() as u64,
                    )
                })
            })
            .try_reduce(|| (0, 0), |a, b| Ok((a.0 + b.0, a.1 + b.1)))?;
        let secs = t0.elapsed().as_secs_f64();
        return Ok(format!(
            "rendered {n} images of {}×{} px in {secs:.2} s: {:.1} images/s on {} threads; {:.2} % of pixels lit\n",
            k.width,
            k.height,
            n as f64 / secs.max(1e-9),
            rayon::current_num_threads(),
            100.0 * lit as f64 / (total.max(1)) as f64
        ));
    }
    let dir = args.output.as_ref().ok_or("-o DIR is required to write a scan")?;
    write_scan_dir(dir, &scan)
}

/// Writes the scan as `manifest.json` plus one `.pf` image per camera (`nearfield::manifest`).
fn write_scan_dir(dir: &Path, scan: &Scan) -> Result<String, Box<dyn std::error::Error>> {
    let n = scan.set.cameras.len();
    let k = scan.set.intrinsics;
    let bar = indicatif::ProgressBar::new(n as u64);
    let t0 = Instant::now();
    let manifest = lumiview::nearfield::manifest::write_scan(dir, scan, &|done, _| {
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    Ok(format!(
        "wrote {}: {n} images of {}×{} px ({:.1} images/s rendered and written)\n",
        manifest.display(),
        k.width,
        k.height,
        n as f64 / secs.max(1e-9)
    ))
}

/// Writes a grayscale Portable Float Map (`Pf`, little-endian, rows bottom to top).
fn write_pfm(path: &Path, width: u32, height: u32, data: &[f32]) -> Result<(), String> {
    let mut bytes = format!("Pf\n{width} {height}\n-1.0\n").into_bytes();
    bytes.reserve(data.len() * 4);
    for row in (0..height as usize).rev() {
        let line = data
            .get(row * width as usize..(row + 1) * width as usize)
            .ok_or_else(|| format!("{}: image data shorter than its size", path.display()))?;
        for v in line {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).map_err(|e| format!("{}: cannot write file: {e}", path.display()))
}

/// Writes an 8-bit grey PNG on a log scale: black at 10⁻⁴·`max`, white at `max`.
fn write_log_png(path: &Path, width: u32, height: u32, data: &[f32], max: f64) -> Result<(), String> {
    let err = |e: String| format!("{}: cannot write PNG: {e}", path.display());
    let lmax = max.max(f64::MIN_POSITIVE).log10();
    let pixels: Vec<u8> = data
        .iter()
        .map(|&v| {
            let v = f64::from(v);
            if v <= 0.0 {
                0
            } else {
                (((v.log10() - lmax + 4.0) / 4.0).clamp(0.0, 1.0) * 255.0).round() as u8
            }
        })
        .collect();
    let file = std::fs::File::create(path).map_err(|e| err(e.to_string()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| err(e.to_string()))?;
    w.write_image_data(&pixels).map_err(|e| err(e.to_string()))?;
    w.finish().map_err(|e| err(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use lumiview::nearfield::layout::Layout;

    #[test]
    fn layouts_sizes_and_directions_parse() {
        assert!(matches!(
            crate::commands::parse_layout("rigo:28000"),
            Ok(Layout::Rigo {
                per_hemisphere: 28000,
                ..
            })
        ));
        assert_eq!(
            crate::commands::parse_layout("fibonacci:10"),
            Ok(Layout::Fibonacci { count: 10 })
        );
        assert_eq!(
            crate::commands::parse_layout("grid:36,19"),
            Ok(Layout::Grid {
                phi_steps: 36,
                theta_steps: 19
            })
        );
        for bad in ["rigo", "rigo:x", "grid:3", "spiral:4", "fibonacci:-1"] {
            assert!(
                matches!(crate::commands::parse_layout(bad), Err(e) if e.contains("--layout")),
                "{bad}"
            );
        }
        assert_eq!(crate::commands::parse_size_px("64x48"), Ok((64, 48)));
        assert!(crate::commands::parse_size_px("0x4").is_err() && crate::commands::parse_size_px("64").is_err());
        assert_eq!(parse_direction("90,30"), Ok((90.0, 30.0)));
        assert!(parse_direction("0,190").is_err() && parse_direction("a,b").is_err());
    }
}
