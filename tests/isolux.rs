//! `lumiview isolux` and `photometry::isolux`: illuminance on the floor against an independent
//! evaluation of E = I(C, γ)·cos³γ / H² (C = atan2(y, x), tan γ = r / H, written here from
//! `Photometry::intensity` alone), an analytic point source, the floor frame (x along C0, y along
//! C90, C counter-clockwise), the PNG, SVG and CSV the command writes, and errors naming the
//! argument or file.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use lumiview::photometry::isolux::{illuminance_lx, IsoluxGrid, IsoluxOptions};
use lumiview::photometry::plot::{IsoluxPlot, IsoluxPlotOptions};
use lumiview::photometry::{load, load_from_text, LoadOptions, Photometry};
use tiny_skia::Pixmap;

const BEGA: &str = "tests/data/misc/arnold-usd_bega_50804K3.ies";
const LDT_C0: &str = "tests/data/photometric-viewer/ldt/symmetry_to_c0c180.ldt";
/// No symmetry at all: I(C 315°) ≠ I(C 45°), so a clockwise C would show.
const LDT_NONE: &str = "tests/data/photometric-viewer/ldt/no_symmetry.ldt";

/// An isotropic 1000 cd downlight: γ 0–90°, one C plane (rotational symmetry).
const ISOTROPIC_IES: &str = "IESNA:LM-63-2002\n[TEST] isotropic point source\nTILT=NONE\n\
1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 45 90\n0\n1000 1000 1000\n";

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn photometry(path: &str) -> Photometry {
    load(&repo(path), &LoadOptions::default()).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn out_dir(test: &str) -> PathBuf {
    let dir = repo("target/isolux-test-output").join(test);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn lumiview(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

fn ok(args: &[&str]) -> String {
    let out = lumiview(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The reference: E = I(C, γ) · cos³γ / H², from the file's intensity at angles computed here.
fn reference_lx(p: &Photometry, h: f64, x: f64, y: f64) -> f64 {
    let gamma = (x.hypot(y) / h).atan();
    let c = y.atan2(x).to_degrees().rem_euclid(360.0);
    p.intensity(c, gamma.to_degrees()) * gamma.cos().powi(3) / (h * h)
}

fn assert_close(what: &str, got: f64, want: f64, rel: f64) {
    assert!(
        (got - want).abs() <= rel * want.abs(),
        "{what}: {got} lx, expected {want} lx (±{:.2} %)",
        rel * 100.0
    );
}

/// Ten floor points, metres: the nadir, the four axes and five off-axis points in every quadrant.
const POINTS_M: [(f64, f64); 10] = [
    (0.0, 0.0),
    (1.0, 0.0),
    (-1.5, 0.0),
    (0.0, 2.0),
    (0.0, -0.75),
    (1.25, 1.75),
    (-2.0, 1.0),
    (-0.5, -2.5),
    (3.0, -3.0),
    (2.25, 0.5),
];

fn check_grid_values(file: &str, h: f64) {
    let p = photometry(file);
    let opts = IsoluxOptions {
        height_m: h,
        extent_m: Some(4.0),
        step_m: Some(0.25),
    };
    let grid = IsoluxGrid::new(&p, &opts).unwrap();
    assert_eq!(grid.points_per_side(), 33);
    let index = |v: f64| {
        let i = (v / grid.step_m).round() as i64 + grid.half_points as i64;
        usize::try_from(i).unwrap()
    };
    for (x, y) in POINTS_M {
        let (ix, iy) = (index(x), index(y));
        assert_eq!((grid.coordinate_m(ix), grid.coordinate_m(iy)), (x, y));
        let want = reference_lx(&p, h, x, y);
        assert!(want > 0.05, "{file} ({x}, {y}): {want} lx is too dark to test anything");
        assert_close(
            &format!("{file} grid ({x}, {y})"),
            grid.at(ix, iy).unwrap(),
            want,
            0.005,
        );
        assert_close(
            &format!("{file} illuminance_lx ({x}, {y})"),
            illuminance_lx(&p, h, x, y),
            want,
            0.005,
        );
    }
}

#[test]
fn grid_values_equal_i_cos3_over_h2_for_real_files() {
    check_grid_values(BEGA, 3.0);
    check_grid_values(LDT_C0, 2.5);
    check_grid_values(LDT_NONE, 2.5);
}

/// Parses CSV text into (x, y, E) rows after checking the header.
fn csv_rows(text: &str) -> Vec<(f64, f64, f64)> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x_m,y_m,E_lx"), "CSV header");
    lines
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            assert_eq!(f.len(), 3, "{l}");
            (f[0], f[1], f[2])
        })
        .collect()
}

#[test]
fn csv_from_the_cli_equals_the_formula() {
    let dir = out_dir("csv");
    for (file, h) in [(BEGA, "3"), (LDT_NONE, "2.5")] {
        let p = photometry(file);
        let h_m: f64 = h.parse().unwrap();
        let csv = dir.join(format!(
            "{}.csv",
            Path::new(file).file_stem().unwrap().to_string_lossy()
        ));
        let csv_arg = csv.to_str().unwrap();
        let summary = ok(&[
            "isolux", file, "--height", h, "--extent", "4", "--step", "0.5", "-o", csv_arg,
        ]);
        assert!(summary.contains("17 × 17 points"), "{summary}");
        let rows = csv_rows(&std::fs::read_to_string(&csv).unwrap());
        assert_eq!(rows.len(), 17 * 17);
        // One row per grid point, y ascending, x ascending within a row.
        assert_eq!((rows[0].0, rows[0].1), (-4.0, -4.0));
        assert_eq!((rows[1].0, rows[1].1), (-3.5, -4.0));
        assert_eq!((rows[17].0, rows[17].1), (-4.0, -3.5));
        // Ten rows spread over the grid, most of them off the C0/C90 axes.
        for k in 0..10 {
            let (x, y, e) = rows[7 + 31 * k];
            assert_close(&format!("{file} CSV ({x}, {y})"), e, reference_lx(&p, h_m, x, y), 0.005);
        }
        let nadir = rows.iter().find(|r| r.0 == 0.0 && r.1 == 0.0).unwrap();
        assert_close("nadir", nadir.2, p.intensity(0.0, 0.0) / (h_m * h_m), 0.005);
    }
}

#[test]
fn isotropic_point_source_is_analytic() {
    let p = load_from_text(ISOTROPIC_IES, "isotropic.ies", &LoadOptions::default()).unwrap();
    let h = 2.0;
    let below = 1000.0 / (h * h);
    let at_r_h = 1000.0 * 45f64.to_radians().cos().powi(3) / (h * h);
    let grid = IsoluxGrid::new(
        &p,
        &IsoluxOptions {
            height_m: h,
            extent_m: Some(4.0),
            step_m: Some(0.5),
        },
    )
    .unwrap();
    let k = grid.half_points;
    assert!((grid.at(k, k).unwrap() - below).abs() < 1e-9);
    for (ix, iy) in [(k + 4, k), (k - 4, k), (k, k + 4), (k, k - 4)] {
        assert!((grid.at(ix, iy).unwrap() - at_r_h).abs() < 1e-9, "({ix}, {iy})");
    }
    let diagonal = h / 2f64.sqrt();
    assert!((illuminance_lx(&p, h, diagonal, -diagonal) - at_r_h).abs() < 1e-9);
    let max = grid.max();
    assert_eq!((max.x_m, max.y_m), (0.0, 0.0));
    assert!((max.e_lx - 250.0).abs() < 1e-9);

    // The same through the CLI.
    let dir = out_dir("isotropic");
    let ies = dir.join("isotropic.ies");
    std::fs::write(&ies, ISOTROPIC_IES).unwrap();
    let csv = dir.join("isotropic.csv");
    let summary = ok(&[
        "isolux",
        ies.to_str().unwrap(),
        "--height",
        "2",
        "--extent",
        "4",
        "--step",
        "0.5",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(summary.contains("max. E 250.0000 lx at (0, 0) m"), "{summary}");
    assert!(
        summary.contains("isolux lines at 5, 10, 20, 50, 100, 200 lx"),
        "{summary}"
    );
    let rows = csv_rows(&std::fs::read_to_string(&csv).unwrap());
    let at = |x: f64, y: f64| rows.iter().find(|r| r.0 == x && r.1 == y).unwrap().2;
    assert_close("CSV below", at(0.0, 0.0), below, 1e-5);
    assert_close("CSV r = h on x", at(2.0, 0.0), at_r_h, 1e-5);
    assert_close("CSV r = h on −y", at(0.0, -2.0), at_r_h, 1e-5);
}

/// Light only towards C90: it must land on +y, nothing on −y (C270), +x (C0) or −x (C180).
#[test]
fn floor_frame_puts_c90_on_plus_y() {
    let ies = "IESNA:LM-63-2002\n[TEST] light towards C90 only\nTILT=NONE\n\
1 -1 1 3 9 1 2 0 0 0\n1 1 10\n0 45 90\n0 45 90 135 180 225 270 315 360\n\
0 0 0\n0 0 0\n0 1000 1000\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n";
    let p = load_from_text(ies, "c90.ies", &LoadOptions::default()).unwrap();
    let h = 2.0;
    let lit = 1000.0 * 45f64.to_radians().cos().powi(3) / (h * h);
    assert!((illuminance_lx(&p, h, 0.0, h) - lit).abs() < 1e-9);
    for (x, y) in [(0.0, -h), (h, 0.0), (-h, 0.0)] {
        assert_eq!(illuminance_lx(&p, h, x, y), 0.0, "({x}, {y})");
    }
    // Counter-clockwise: C 45° (x > 0, y > 0) is lit by interpolation towards C90, C 315° not.
    assert!(illuminance_lx(&p, h, 1.0, 1.5) > 0.0);
    assert_eq!(illuminance_lx(&p, h, 1.0, -1.5), 0.0);
    let grid = IsoluxGrid::new(
        &p,
        &IsoluxOptions {
            height_m: h,
            extent_m: Some(4.0),
            step_m: Some(0.1),
        },
    )
    .unwrap();
    let max = grid.max();
    assert!(
        max.y_m > 0.5 && max.x_m.abs() < 1e-9,
        "max at ({}, {})",
        max.x_m,
        max.y_m
    );
    // Every isolux line lies on the +y side.
    for c in grid.contours(&grid.levels()) {
        for line in &c.lines {
            assert!(
                line.points.iter().all(|q| q[1] >= -1e-9),
                "{} lx line below y = 0",
                c.level_lx
            );
        }
    }
}

/// Darker than every fill colour and the grid lines in all channels: a line's ink (an
/// anti-aliased 1 px line half over a pixel still passes).
fn is_dark(p: [u8; 4]) -> bool {
    p[0] < 160 && p[1] < 160 && p[2] < 160
}

fn pixel(pm: &Pixmap, x: f64, y: f64) -> [u8; 4] {
    let c = pm.pixel(x.round() as u32, y.round() as u32).unwrap().demultiply();
    [c.red(), c.green(), c.blue(), c.alpha()]
}

fn dark_near(pm: &Pixmap, at: [f64; 2], r: i32) -> bool {
    (-r..=r).any(|dy| (-r..=r).any(|dx| is_dark(pixel(pm, at[0] + f64::from(dx), at[1] + f64::from(dy)))))
}

#[test]
fn png_has_the_width_asked_for_and_draws_the_lines_where_they_are() {
    let dir = out_dir("png");
    let png = dir.join("bega.png");
    let summary = ok(&[
        "isolux",
        BEGA,
        "--height",
        "3",
        "--size",
        "640",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(
        summary.contains("isolux lines at 5, 10, 20, 50, 100, 200 lx"),
        "{summary}"
    );
    assert!(summary.contains("max. E"), "{summary}");
    let pm = Pixmap::load_png(&png).unwrap();
    assert_eq!(pm.width(), 640);
    assert!(pm.height() > 640);

    // The same diagram from the library, for where things are.
    let p = photometry(BEGA);
    let grid = IsoluxGrid::new(
        &p,
        &IsoluxOptions {
            height_m: 3.0,
            extent_m: None,
            step_m: None,
        },
    )
    .unwrap();
    let plot = IsoluxPlot::new(
        &p,
        &grid,
        &IsoluxPlotOptions {
            size_px: 640,
            fill: true,
        },
    )
    .unwrap();
    assert_eq!((plot.width, plot.height), (pm.width(), pm.height()));
    assert_eq!(plot.levels_lx, [5.0, 10.0, 20.0, 50.0, 100.0, 200.0]);
    // Every level is labelled.
    for level in &plot.levels_lx {
        assert!(
            plot.labels.iter().any(|l| l.level_lx == *level),
            "no label on {level} lx"
        );
    }
    // Along every line, the image is dark where the line is (labels may cover a few points).
    for c in &plot.contours {
        let pts: Vec<[f64; 2]> = c.lines.iter().flat_map(|l| l.points.iter().copied()).collect();
        let samples: Vec<[f64; 2]> = pts.iter().step_by((pts.len() / 40).max(1)).copied().collect();
        let hits = samples
            .iter()
            .filter(|q| dark_near(&pm, plot.to_canvas(q[0], q[1]), 2))
            .count();
        assert!(
            hits * 10 >= samples.len() * 8,
            "{} lx: only {hits} of {} points of the line are drawn",
            c.level_lx,
            samples.len()
        );
    }
    // Between the lines: the fill. Halfway between the nadir and the 200 lx line along −y lies
    // the top band (orange-red), and beyond the 5 lx line the floor stays white.
    let top_band = [-0.25, -0.6];
    assert!(illuminance_lx(&p, 3.0, top_band[0], top_band[1]) > 200.0);
    let q = plot.to_canvas(top_band[0], top_band[1]);
    let inside = pixel(&pm, q[0], q[1]);
    assert!(
        inside[0] > 150 && inside[1] < 140 && inside[2] < 90,
        "top band: {inside:?}"
    );
    let far = plot.to_canvas(-0.8 * plot.half_width_m, -0.8 * plot.half_width_m);
    assert_eq!(pixel(&pm, far[0], far[1]), [255, 255, 255, 255]);

    // Without the fill the same point is white (the background), the lines still drawn.
    let bare = dir.join("bega-no-fill.png");
    ok(&[
        "isolux",
        BEGA,
        "--height",
        "3",
        "--size",
        "640",
        "--no-fill",
        "-o",
        bare.to_str().unwrap(),
    ]);
    let bare_pm = Pixmap::load_png(&bare).unwrap();
    assert_eq!(pixel(&bare_pm, q[0], q[1]), [255, 255, 255, 255]);
}

#[test]
fn svg_has_units_labels_and_title() {
    let dir = out_dir("svg");
    let svg_path = dir.join("bega.svg");
    ok(&["isolux", BEGA, "--height", "3", "-o", svg_path.to_str().unwrap()]);
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
    assert!(svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<g id=").count(), svg.matches("</g>").count());
    assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
    for needle in [
        "E in lx",
        "Isolux lines in lx: 5, 10, 20, 50, 100, 200",
        "x in m, towards C0",
        "y in m, towards C90",
        "mounting height 3 m",
        "50804K3",
        "Max. E ",
        "data:image/png;base64,",
    ] {
        assert!(svg.contains(needle), "missing `{needle}`");
    }
    // The values on the lines (in the label layer).
    let labels = &svg[svg.find("<g id=\"isolux-labels\">").unwrap()..];
    let labels = &labels[..labels.find("</g>").unwrap()];
    for level in ["5", "10", "20", "50", "100", "200"] {
        assert!(labels.contains(&format!(">{level}</text>")), "no label {level}");
    }
    // Tick labels in metres on both axes, with a typographic minus.
    for tick in [">0</text>", ">2</text>", ">\u{2212}2</text>"] {
        assert!(svg.contains(tick), "missing tick {tick}");
    }
}

fn fails_with(args: &[&str], needles: &[&str]) {
    let out = lumiview(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    for n in needles {
        assert!(err.contains(n), "{args:?}: `{n}` missing from: {err}");
    }
}

#[test]
fn errors_name_the_argument_or_file() {
    let dir = out_dir("errors");
    let png = dir.join("e.png");
    let png = png.to_str().unwrap();
    for bad in ["0", "-1", "nan", "inf", "-0"] {
        fails_with(&["isolux", BEGA, "--height", bad, "-o", png], &["--height"]);
    }
    fails_with(&["isolux", BEGA, "--height", "abc", "-o", png], &["--height"]);
    fails_with(&["isolux", BEGA, "-o", png], &["--height"]);
    fails_with(
        &["isolux", BEGA, "--height", "3", "--extent", "-2", "-o", png],
        &["--extent"],
    );
    fails_with(
        &["isolux", BEGA, "--height", "3", "--step", "0", "-o", png],
        &["--step"],
    );
    fails_with(
        &[
            "isolux", BEGA, "--height", "3", "--extent", "2", "--step", "3", "-o", png,
        ],
        &["--step", "--extent"],
    );
    fails_with(
        &[
            "isolux", BEGA, "--height", "3", "--extent", "100", "--step", "0.001", "-o", png,
        ],
        &["--step", "points per side"],
    );
    fails_with(
        &["isolux", BEGA, "--height", "3", "--size", "10", "-o", png],
        &["--size"],
    );
    fails_with(
        &["isolux", BEGA, "--height", "3", "-o", "out/isolux.jpg"],
        &["out/isolux.jpg"],
    );
    fails_with(&["isolux", BEGA, "--height", "3", "-o", "isolux"], &["isolux", ".csv"]);
    fails_with(
        &["isolux", "tests/data/no-such-file.ies", "--height", "3", "-o", png],
        &["tests/data/no-such-file.ies"],
    );
    fails_with(
        &[
            "isolux",
            BEGA,
            "--height",
            "3",
            "-o",
            "/nonexistent-lumiview-dir/isolux.csv",
        ],
        &["/nonexistent-lumiview-dir/isolux.csv"],
    );
    fails_with(
        &[
            "isolux",
            BEGA,
            "--height",
            "3",
            "-o",
            "/nonexistent-lumiview-dir/isolux.png",
        ],
        &["/nonexistent-lumiview-dir/isolux.png"],
    );
    fails_with(
        &["isolux", BEGA, "--height", "3", "--lamp-set", "2", "-o", png],
        &["--lamp-set"],
    );
    // Nothing was written by the failed runs.
    assert!(!Path::new(png).exists());
}

/// An uplight sends nothing to the floor: the CSV is all zeros, the diagram is an error saying so.
#[test]
fn uplight_has_no_isolux_lines() {
    let ies = "IESNA:LM-63-2002\n[TEST] uplight\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1 10\n90 135 180\n0\n0 500 1000\n";
    let dir = out_dir("uplight");
    let file = dir.join("uplight.ies");
    std::fs::write(&file, ies).unwrap();
    let csv = dir.join("uplight.csv");
    let summary = ok(&[
        "isolux",
        file.to_str().unwrap(),
        "--height",
        "2",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(summary.contains("no light reaches the floor"), "{summary}");
    let rows = csv_rows(&std::fs::read_to_string(&csv).unwrap());
    assert!(rows.iter().all(|r| r.2 == 0.0));
    let png = dir.join("uplight.png");
    fails_with(
        &[
            "isolux",
            file.to_str().unwrap(),
            "--height",
            "2",
            "-o",
            png.to_str().unwrap(),
        ],
        &["uplight.ies", "no light reaches the floor"],
    );
}
