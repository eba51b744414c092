//! The polar intensity diagram: PNG renders compared with goldens in `tests/golden/` (per-channel
//! tolerance plus an outlier budget), SVG well-formedness, and the geometry of the curves checked
//! against intensities sampled independently of the plot model.
//!
//! Regenerate the goldens after an intended change with
//! `LUMIVIEW_BLESS=1 cargo test --test plot_golden`, look at them, and commit them.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use lumiview::photometry::plot::{write_plot, PlotError, PlotOptions, PlotUnit, PolarPlot};
use lumiview::photometry::{load, LoadOptions, Photometry};
use tiny_skia::Pixmap;

/// Width of the golden images, pixels (small, to keep the repository light).
const GOLDEN_SIZE: u32 = 600;
/// Largest per-channel difference (0–255) that still counts as equal.
const CHANNEL_TOLERANCE: u8 = 16;
/// Fraction of pixels allowed beyond the tolerance (anti-aliasing differences across CPUs).
const OUTLIER_BUDGET: f64 = 0.001;

const LUXCORE: &str = "tests/data/misc/luxcore_ASA_15M_R2.ies";
const LDT_C90: &str = "tests/data/photometric-viewer/ldt/symmetry_to_c90c270.ldt";

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn photometry(path: &str) -> Photometry {
    load(&repo(path), &LoadOptions::default()).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn plot(path: &str, unit: PlotUnit, size_px: u32) -> PolarPlot {
    PolarPlot::new(&photometry(path), &PlotOptions { unit, size_px }).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Renders `file` and compares it with `tests/golden/<name>.png`, or rewrites the golden when
/// `LUMIVIEW_BLESS=1`.
fn check_golden(name: &str, file: &str, unit: PlotUnit) {
    let actual = plot(file, unit, GOLDEN_SIZE).to_pixmap().unwrap();
    let golden_path = repo(&format!("tests/golden/{name}.png"));
    if std::env::var("LUMIVIEW_BLESS").is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(repo("tests/golden")).unwrap();
        actual.save_png(&golden_path).unwrap();
        eprintln!("blessed {}", golden_path.display());
        return;
    }
    let failures = repo("target/golden-failures");
    let save_actual = || {
        std::fs::create_dir_all(&failures).unwrap();
        let p = failures.join(format!("{name}-actual.png"));
        actual.save_png(&p).unwrap();
        p
    };
    let golden = match Pixmap::load_png(&golden_path) {
        Ok(g) => g,
        Err(e) => {
            let p = save_actual();
            panic!(
                "{}: cannot read the golden ({e}); the render is at {}. \
                 Create the goldens with LUMIVIEW_BLESS=1 cargo test --test plot_golden",
                golden_path.display(),
                p.display()
            );
        }
    };
    if (golden.width(), golden.height()) != (actual.width(), actual.height()) {
        let p = save_actual();
        panic!(
            "{name}: size {}×{} differs from the golden's {}×{}; the render is at {}",
            actual.width(),
            actual.height(),
            golden.width(),
            golden.height(),
            p.display()
        );
    }
    let (w, h) = (actual.width(), actual.height());
    let mut diff = Pixmap::new(w, h).unwrap();
    let mut outliers = 0usize;
    let mut worst = 0u8;
    for (i, (a, g)) in actual.data().chunks(4).zip(golden.data().chunks(4)).enumerate() {
        let d = a.iter().zip(g).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
        worst = worst.max(d);
        // Diff image: outliers red, smaller differences grey, equal pixels white.
        let px = if d > CHANNEL_TOLERANCE {
            outliers += 1;
            [255, 0, 0, 255]
        } else {
            let v = 255 - d.saturating_mul(8);
            [v, v, v, 255]
        };
        diff.data_mut()[i * 4..i * 4 + 4].copy_from_slice(&px);
    }
    let budget = (OUTLIER_BUDGET * f64::from(w * h)).floor() as usize;
    if outliers > budget {
        let actual_path = save_actual();
        let diff_path = failures.join(format!("{name}-diff.png"));
        diff.save_png(&diff_path).unwrap();
        panic!(
            "{name}: {outliers} pixels differ from {} by more than {CHANNEL_TOLERANCE} (budget {budget}, \
             largest difference {worst}); actual: {}, diff: {}. If the change is intended, \
             regenerate with LUMIVIEW_BLESS=1 cargo test --test plot_golden",
            golden_path.display(),
            actual_path.display(),
            diff_path.display()
        );
    }
}

#[test]
fn golden_asymmetric_roadway_luminaire_in_cd() {
    check_golden("plot_luxcore_ASA_15M_R2", LUXCORE, PlotUnit::Candela);
}

#[test]
fn golden_absolute_ldt_in_cd_per_klm() {
    check_golden("plot_symmetry_to_c90c270_cdklm", LDT_C90, PlotUnit::CandelaPerKilolumen);
}

/// Checks that the tags of an XML text are balanced; returns the element names seen.
fn balanced_tags(xml: &str) -> Vec<String> {
    let mut stack: Vec<String> = Vec::new();
    let mut seen = Vec::new();
    let mut rest = xml;
    while let Some(start) = rest.find('<') {
        let end = rest[start..].find('>').expect("unterminated tag") + start;
        let tag = &rest[start + 1..end];
        assert!(!tag.contains('<'), "`<` inside a tag: {tag}");
        let text = &rest[..start];
        assert!(!text.contains('>'), "stray `>` in text: {text}");
        for (i, _) in text.match_indices('&') {
            let entity = &text[i..text[i..].find(';').map_or(text.len(), |j| i + j + 1)];
            assert!(
                ["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].contains(&entity),
                "bad entity in text: {entity}"
            );
        }
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop().as_deref(), Some(name.trim()), "mismatched </{name}>");
        } else if !tag.starts_with('?') && !tag.starts_with('!') {
            let name = tag
                .split_whitespace()
                .next()
                .unwrap_or("")
                .trim_end_matches('/')
                .to_string();
            assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes in <{tag}>");
            seen.push(name.clone());
            if !tag.ends_with('/') {
                stack.push(name);
            }
        }
        rest = &rest[end + 1..];
    }
    assert!(rest.trim().is_empty(), "text after the root element");
    assert!(stack.is_empty(), "unclosed elements: {stack:?}");
    seen
}

#[test]
fn svg_is_well_formed_and_has_both_curves() {
    let plot = plot(LUXCORE, PlotUnit::Candela, 800);
    let svg = plot.to_svg();
    assert!(
        svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""),
        "{}",
        &svg[..80]
    );
    assert!(svg.trim_end().ends_with("</svg>"));
    let elements = balanced_tags(&svg);
    assert_eq!(elements.iter().filter(|e| *e == "svg").count(), 1);
    assert!(
        elements.iter().filter(|e| *e == "text").count() > 30,
        "γ, ring, legend and caption labels"
    );
    for id in ["curve-c0-c180", "curve-c90-c270"] {
        let at = svg
            .find(&format!("<path id=\"{id}\""))
            .unwrap_or_else(|| panic!("no {id} path"));
        let path = &svg[at..at + svg[at..].find("/>").unwrap()];
        // Two half-planes sampled every 0.5°: 2 × 361 vertices.
        assert_eq!(path.matches(" L").count() + 1, 722, "{id}: vertex count");
        assert!(path.contains(" Z\""), "{id}: closed");
    }
    // The SVG draws the model's own points.
    let first = plot.curves[0].points[0];
    assert!(
        svg.contains(&format!("d=\"M{} {}", trim(first[0]), trim(first[1]))),
        "first point"
    );
    // Labels readers rely on.
    for needle in [
        ">0°<",
        ">90°<",
        ">180°<",
        ">cd<",
        "C0–C180 plane",
        "(right: C0, left: C180)",
        "Max. intensity 6019 cd at C 65°, γ 62.5°",
    ] {
        assert!(svg.contains(needle), "missing {needle}");
    }
    assert!(
        svg.contains("ASA SERIES 150W PULSE START MH TYPE 2 FULL CUTOFF"),
        "title from [LUMINAIRE]"
    );
}

fn trim(v: f64) -> String {
    let s = format!("{v:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn is_red(p: [u8; 4]) -> bool {
    p[0] > 150 && p[1] < 110 && p[2] < 110
}

fn pixel(pm: &Pixmap, x: f64, y: f64) -> [u8; 4] {
    let c = pm
        .pixel(x.round() as u32, y.round() as u32)
        .expect("inside the image")
        .demultiply();
    [c.red(), c.green(), c.blue(), c.alpha()]
}

/// Whether a strongly red pixel lies within `r` pixels of (x, y).
fn red_near(pm: &Pixmap, x: f64, y: f64, r: i32) -> bool {
    (-r..=r).any(|dy| (-r..=r).any(|dx| is_red(pixel(pm, x + f64::from(dx), y + f64::from(dy)))))
}

/// The C0–C180 curve reaches, along the direction of its maximum, exactly the radius its
/// intensity gives — C0 on the right, C180 on the left, γ = 0 at the bottom — and nothing red lies
/// beyond it.
#[test]
fn png_curve_reaches_the_radius_of_its_maximum() {
    let p = photometry(LUXCORE);
    let plot = plot(LUXCORE, PlotUnit::Candela, 800);
    let pm = plot.to_pixmap().unwrap();
    for (c_deg, side) in [(0.0, 1.0), (180.0, -1.0)] {
        // The maximum of this half-plane away from the nadir (where the dashed C90 curve lies on
        // top), sampled from the web, not from the plot model.
        let (gamma, cd) = (40..=180)
            .map(|i| f64::from(i) * 0.5)
            .map(|g| (g, p.web.sample(c_deg, g)))
            .fold((0.0, 0.0), |best, s| if s.1 > best.1 { s } else { best });
        assert!(gamma > 45.0 && gamma < 60.0, "C{c_deg}: peak at γ {gamma}");
        let r = cd / plot.outer_value * plot.radius;
        let a = gamma.to_radians();
        let dir = [side * a.sin(), a.cos()]; // γ measured from straight down
        let at = |d: f64| [plot.centre[0] + dir[0] * d, plot.centre[1] + dir[1] * d];
        let [x, y] = at(r);
        assert!(
            red_near(&pm, x, y, 2),
            "C{c_deg}: no C0–C180 curve at γ {gamma}, {cd} cd, ({x:.0}, {y:.0})"
        );
        let mut d = r + 5.0;
        while d < plot.radius {
            let [x, y] = at(d);
            assert!(
                !is_red(pixel(&pm, x, y)),
                "C{c_deg}: red beyond the maximum at ({x:.0}, {y:.0})"
            );
            d += 1.0;
        }
    }
    // The C0 side is the brighter one for this luminaire (C0 γ 52.5° 2735 cd; C180 1666 cd at the
    // nadir, 1464 cd at γ 55°).
    assert!(plot.curves[0].right.iter().copied().fold(0.0, f64::max) > 2700.0);
    assert!(plot.curves[0].left.iter().copied().fold(0.0, f64::max) < 1700.0);
}

#[test]
fn rings_are_round_values_and_contain_the_curves() {
    let plot = plot(LUXCORE, PlotUnit::Candela, 800);
    let values: Vec<f64> = plot.rings.iter().map(|r| r.value).collect();
    assert_eq!(values, [500.0, 1000.0, 1500.0, 2000.0, 2500.0, 3000.0, 3500.0]);
    let max = plot.curves.iter().map(|c| c.max_value()).fold(0.0, f64::max);
    assert!(
        max <= plot.outer_value && max > 0.8 * plot.outer_value,
        "{max} vs {}",
        plot.outer_value
    );

    // cd/klm of a relative file: per 1000 lm of rated lamp flux (13000 lm).
    let klm = plot_unit_caption(LUXCORE);
    assert!((klm.0 - 1000.0 / 13000.0).abs() < 1e-12);
    assert!(klm.1.contains("rated lamp flux (13000 lm)"), "{}", klm.1);
    // cd/klm of an absolute file: per 1000 lm of the integrated luminaire flux, and it says so.
    let p = photometry(LDT_C90);
    let abs = plot_unit_caption(LDT_C90);
    assert!((abs.0 - 1000.0 / p.flux_lm()).abs() < 1e-12);
    assert!(abs.1.contains("integrated luminaire flux"), "{}", abs.1);
}

fn plot_unit_caption(file: &str) -> (f64, String) {
    let plot = plot(file, PlotUnit::CandelaPerKilolumen, 800);
    (plot.cd_to_unit, plot.caption.join("\n"))
}

#[test]
fn write_errors_name_the_file() {
    let p = photometry(LUXCORE);
    let opts = PlotOptions::default();
    let bad_ext = Path::new("plot.jpeg");
    let e = write_plot(&p, &opts, bad_ext).unwrap_err();
    assert!(
        matches!(e, PlotError::UnsupportedFormat { .. }) && e.to_string().contains("plot.jpeg"),
        "{e}"
    );
    let unwritable = Path::new("/nonexistent-lumiview-dir/plot.png");
    let e = write_plot(&p, &opts, unwritable).unwrap_err();
    assert!(e.to_string().contains("/nonexistent-lumiview-dir/plot.png"), "{e}");
    let e = PolarPlot::new(&p, &PlotOptions { size_px: 10, ..opts }).unwrap_err();
    assert!(matches!(e, PlotError::Size { size: 10 }), "{e}");
}

#[test]
fn writes_svg_and_png_files() {
    let p = photometry(LDT_C90);
    let dir = repo("target/plot-test-output");
    std::fs::create_dir_all(&dir).unwrap();
    let opts = PlotOptions {
        size_px: 400,
        ..PlotOptions::default()
    };
    write_plot(&p, &opts, &dir.join("ldt.svg")).unwrap();
    write_plot(&p, &opts, &dir.join("ldt.PNG")).unwrap();
    let svg = std::fs::read_to_string(dir.join("ldt.svg")).unwrap();
    balanced_tags(&svg);
    assert!(svg.contains("Dummy LDT file"), "title from the EULUMDAT luminaire name");
    let png = Pixmap::load_png(dir.join("ldt.PNG")).unwrap();
    assert_eq!(png.width(), 400);
}
