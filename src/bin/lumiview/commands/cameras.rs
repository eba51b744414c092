//! `lumiview cameras`: where a scan's cameras sit and how well they cover the sphere: summary
//! statistics (cameras per hemisphere, coincident positions, nearest-camera angle) and a PNG
//! (camera positions on two equal-area discs; map of the angle to the nearest camera).

use std::path::PathBuf;

use clap::Args;
use lumiview::nearfield::coverage::{Coverage, MAX_WIDTH_PX, MIN_WIDTH_PX};
use lumiview::nearfield::manifest::{load_scan_with_report, ImportOptions, ImportReport};
use lumiview::nearfield::RayImageSet;
use serde_json::json;

use super::{print_report, CliResult};

/// How a scan is read from manifests (shared by the commands that take scans).
#[derive(Args, Debug, Clone)]
pub struct ScanImportArgs {
    /// Drop bad images (missing or unreadable file, wrong size, bad pose, duplicate pose, and with
    /// --verify-images bad pixel values) with a warning instead of failing.
    #[arg(long)]
    pub skip_bad_images: bool,
    /// Read every image's pixels while importing and check that they are finite and ≥ 0 (slower;
    /// otherwise only headers are read).
    #[arg(long)]
    pub verify_images: bool,
}

impl ScanImportArgs {
    /// The library's import options.
    pub fn options(&self) -> ImportOptions {
        ImportOptions {
            skip_bad: self.skip_bad_images,
            verify_pixels: self.verify_images,
        }
    }
}

/// Arguments of `lumiview cameras`.
#[derive(Args, Debug)]
pub struct CamerasArgs {
    /// The scan: manifest(s) (.json), e.g. one per hemisphere (merged).
    #[arg(required = true, value_name = "SCAN")]
    pub scan: Vec<PathBuf>,
    /// Write the coverage picture to this PNG file.
    #[arg(short, long, value_name = "OUTPUT.png")]
    pub output: Option<PathBuf>,
    /// Picture width in pixels (the height is about 0.39 × the width).
    #[arg(long, value_name = "PIXELS", default_value_t = 1600)]
    pub size: u32,
    /// Print the statistics as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub import: ScanImportArgs,
}

/// Reads the cameras of a scan given on the command line, with the import's report. Manifests
/// (.json) for now; other scan containers plug in here.
pub fn load_ray_image_set(
    scan: &[PathBuf],
    import: &ScanImportArgs,
) -> Result<(RayImageSet, ImportReport), Box<dyn std::error::Error>> {
    // A single `.lvpack` carries its cameras; a TM-25 ray file has none of its own: it shows the
    // virtual scan it is binned into (the one `render` draws); otherwise manifests.
    use lumiview::source::{self, Source, SourceKind, SourceOptions};
    for one in scan {
        match source::detect(one)? {
            SourceKind::Pack if scan.len() == 1 => {
                let pack = lumiview::nearfield::pack::Pack::open(one)?;
                return Ok((pack.rayset().clone(), ImportReport::default()));
            }
            SourceKind::RayFile if scan.len() == 1 => {
                let Source::Scan { pack, cached } =
                    source::open(one, SourceKind::RayFile, &SourceOptions::default(), &mut Vec::new())?
                else {
                    return Err(format!("{}: not a scan", one.display()).into());
                };
                eprintln!(
                    "lumiview: note: {} is a TM-25 ray file, which has no cameras: these are the cameras of the \
                     virtual scan it is binned into for `render`{} (`lumiview rays2scan` chooses others)",
                    one.display(),
                    cached.map_or(String::new(), |p| format!(", cached at {}", p.display()))
                );
                return Ok((pack.rayset().clone(), ImportReport::default()));
            }
            SourceKind::Manifest => {}
            kind @ (SourceKind::Pack | SourceKind::RayFile) => {
                return Err(format!(
                    "{}: a {} cannot be combined with other scan files",
                    one.display(),
                    if kind == SourceKind::Pack {
                        ".lvpack"
                    } else {
                        "TM-25 ray file"
                    }
                )
                .into())
            }
            SourceKind::Photometry => {
                return Err(format!(
                    "{}: not a near-field scan: expected a .lvpack, a scan manifest (.json) or a TM-25 ray file",
                    one.display()
                )
                .into())
            }
        }
    }
    let (scan, report) = load_scan_with_report(scan, &import.options())?;
    Ok((scan.set, report))
}

/// Runs `lumiview cameras`.
pub fn cameras(args: &CamerasArgs) -> CliResult {
    // Check what needs no file first.
    if let Some(out) = &args.output {
        let png = out
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !png {
            return Err(format!("-o {}: the coverage picture is written as .png", out.display()).into());
        }
    }
    if !(MIN_WIDTH_PX..=MAX_WIDTH_PX).contains(&args.size) {
        return Err(format!(
            "--size {}: must be within {MIN_WIDTH_PX}…{MAX_WIDTH_PX} pixels",
            args.size
        )
        .into());
    }
    let (set, report) = load_ray_image_set(&args.scan, &args.import)?;
    for w in &report.warnings {
        eprintln!("lumiview: warning: {w}");
    }
    let cov = Coverage::new(&set);
    if let Some(out) = &args.output {
        cov.write_png(args.size, out)?;
    }
    let st = &cov.stats;
    let k = &set.intrinsics;
    let mut text = String::new();
    if args.json {
        let v = json!({
            "scan": args.scan.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "cameras": st.cameras,
            "lower": st.lower,
            "upper": st.upper,
            "sphere": {"radius_m": set.sphere.radius_m, "centre_m": set.sphere.centre_m.to_array()},
            "image_size_px": [k.width, k.height],
            "coincident_groups": st.coincident_groups,
            "cameras_in_coincident_groups": st.cameras_in_coincident_groups,
            "nearest_camera_deg": {
                "median": finite(st.median_gap_deg),
                "p95": finite(st.p95_gap_deg),
                "max": finite(st.max_gap_deg),
                "max_at": {"phi": finite(st.max_gap_at_deg[0]), "theta": finite(st.max_gap_at_deg[1])},
                "samples": st.samples,
            },
            "dropped_images": report.dropped,
            "warnings": report.warnings,
            "info": report.info,
            "output": args.output.as_ref().map(|p| p.display().to_string()),
        });
        outln!(text, "{}", serde_json::to_string_pretty(&v)?);
        return print_report(&text);
    }
    let names: Vec<String> = args.scan.iter().map(|p| p.display().to_string()).collect();
    outln!(text, "scan               {}", names.join(" + "));
    outln!(
        text,
        "cameras            {} (lower hemisphere {}, upper {})",
        st.cameras,
        st.lower,
        st.upper
    );
    let c = set.sphere.centre_m;
    outln!(
        text,
        "capture sphere     radius {} m, centre ({}, {}, {}) m",
        set.sphere.radius_m,
        c.x,
        c.y,
        c.z
    );
    outln!(
        text,
        "images             {} × {} px, focal ({}, {}) px",
        k.width,
        k.height,
        k.focal_px.x,
        k.focal_px.y
    );
    outln!(
        text,
        "coincident groups  {} ({} cameras at shared positions)",
        st.coincident_groups,
        st.cameras_in_coincident_groups
    );
    outln!(
        text,
        "nearest camera     median {:.3}°, 95 % {:.3}°, max {:.3}° at φ {:.2}°, θ {:.2}° ({} uniform directions; \
         max refined at Voronoi vertices)",
        st.median_gap_deg,
        st.p95_gap_deg,
        st.max_gap_deg,
        st.max_gap_at_deg[0],
        st.max_gap_at_deg[1],
        st.samples
    );
    if report.dropped > 0 {
        outln!(text, "dropped images     {} (see the warnings)", report.dropped);
    }
    for i in &report.info {
        outln!(text, "note               {i}");
    }
    if let Some(out) = &args.output {
        outln!(text, "wrote              {}", out.display());
    }
    print_report(&text)
}

/// A JSON number, or null when not finite.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}
