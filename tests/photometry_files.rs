//! Real and hand-written photometric files: every file parses; intensities, flux, openings,
//! orientation and error messages are checked against values derived independently of the reader
//! (the files' own numbers, formulas, or the Python writers in scripts/).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use lumiview::photometry::ies::IesVersion;
use lumiview::photometry::luminaire::RawFile;
use lumiview::photometry::web::direction;
use lumiview::photometry::{load, load_from_text, FileFormat, LoadOptions, OpeningShape, Photometry, Symmetry};

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

fn open(rel: &str) -> Photometry {
    load(&data(rel), &LoadOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn open_with(rel: &str, opts: LoadOptions) -> Photometry {
    load(&data(rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn assert_close(got: f64, want: f64, rel_tol: f64, what: &str) {
    let tol = rel_tol * want.abs().max(1e-9);
    assert!((got - want).abs() <= tol, "{what}: got {got}, want {want} (±{tol})");
}

fn files_under(dir: &str, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(data(dir))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)))
        .collect();
    v.sort();
    v
}

#[test]
fn every_bundled_file_parses() {
    let mut n = 0;
    for (dir, ext) in [
        ("photometric-viewer/ies95", "ies"),
        ("photometric-viewer/ldt", "ldt"),
        ("misc", "ies"),
        ("pairs", "ies"),
        ("pairs", "ldt"),
        ("fixtures", "ies"),
    ] {
        for p in files_under(dir, ext) {
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            let r = load(&p, &LoadOptions::default());
            if name == "tilt_file_missing.ies" {
                assert!(r.is_err(), "{name} must fail");
                continue;
            }
            let ph = r.unwrap_or_else(|e| panic!("{e}"));
            assert!(ph.flux_lm() > 0.0 && ph.flux_lm().is_finite(), "{name}");
            n += 1;
        }
    }
    assert!(n >= 50, "only {n} files found");
}

/// The 19 photometric-viewer IES files share one rotationally symmetric candela table (37 values,
/// γ 0–90 in 2.5° steps); these are its first values as written in the files.
const PV_TABLE_HEAD: [f64; 6] = [2200.0, 2000.2, 1950.0, 1700.1, 1328.4, 1115.1];

#[test]
fn photometric_viewer_ies_intensities_and_multipliers() {
    for p in files_under("photometric-viewer/ies95", "ies") {
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let ph = load(&p, &LoadOptions::default()).unwrap();
        assert_eq!(ph.format, FileFormat::Ies(IesVersion::Lm63_1995), "{name}");
        assert_eq!(ph.symmetry, Symmetry::Rotational, "{name}");
        // Relative photometry: IES candela values are already cd for the rated lamps, so the
        // lamp flux does not scale them; only the multiplier does.
        let k = if name.contains("with_multiplier") { 1.5 } else { 1.0 };
        for (i, want) in PV_TABLE_HEAD.iter().enumerate() {
            for c in [0.0, 77.0, 181.0, 359.0] {
                assert_close(ph.intensity(c, 2.5 * i as f64), k * want, 1e-12, &name);
            }
        }
        assert_eq!(ph.intensity(0.0, 90.0), 0.0, "{name}");
        assert_eq!(ph.intensity(0.0, 120.0), 0.0, "{name}: zero above the measured range");
        assert_eq!(ph.lamp_flux_lm.is_some(), name.starts_with("relative"), "{name}");
        if name.starts_with("relative") {
            assert_eq!(ph.lamp_flux_lm, Some(500.0));
        }
    }
}

#[test]
fn photometric_viewer_ies_openings() {
    // (file, shape, length (X), width (Y), height) in metres. The files are LM-63-1995: their
    // shape codes follow the pre-2002 reading of docs/photometry.md (one negative horizontal
    // dimension: ellipse or ellipsoid; a zero length/width takes the round dimension beside it).
    let ft = 0.3048;
    let cases: [(&str, OpeningShape, f64, f64, f64); 19] = [
        ("absolute_photometry.ies", OpeningShape::Ellipse, 0.12, 0.12, 0.0),
        (
            "absolute_photometry_with_multiplier.ies",
            OpeningShape::Ellipse,
            0.12,
            0.12,
            0.0,
        ),
        (
            "ellipse_opening_along_length.ies",
            OpeningShape::VerticalCylinder,
            0.34,
            0.12,
            0.56,
        ),
        (
            "ellipse_opening_along_width.ies",
            OpeningShape::VerticalCylinder,
            0.34,
            0.12,
            0.56,
        ),
        (
            "ellipsoid_opening_along_length.ies",
            OpeningShape::Ellipsoid,
            0.34,
            0.12,
            0.56,
        ),
        (
            "ellipsoid_opening_along_width.ies",
            OpeningShape::Ellipsoid,
            0.34,
            0.12,
            0.56,
        ),
        (
            "horizontal_cylinder_opening_along_length.ies",
            OpeningShape::HorizontalCylinderAlongLength,
            0.12,
            0.34,
            0.34,
        ),
        (
            "horizontal_cylinder_opening_along_width.ies",
            OpeningShape::HorizontalCylinderAlongWidth,
            0.34,
            0.12,
            0.34,
        ),
        ("imperial_units.ies", OpeningShape::Box, 0.34 * ft, 0.12 * ft, 0.56 * ft),
        ("label_lines.ies", OpeningShape::Box, 0.34 * ft, 0.12 * ft, 0.56 * ft),
        ("metric_units.ies", OpeningShape::Box, 0.34, 0.12, 0.56),
        ("point_opening.ies", OpeningShape::Point, 0.0, 0.0, 0.0),
        ("rectangular_opening.ies", OpeningShape::Rectangle, 0.34, 0.12, 0.0),
        (
            "rectangular_opening_with_height.ies",
            OpeningShape::Box,
            0.34,
            0.12,
            0.56,
        ),
        ("relative_photometry.ies", OpeningShape::Ellipse, 0.12, 0.12, 0.0),
        (
            "relative_photometry_with_multiplier.ies",
            OpeningShape::Ellipse,
            0.12,
            0.12,
            0.0,
        ),
        ("round_opening.ies", OpeningShape::Ellipse, 0.12, 0.12, 0.0),
        (
            "round_opening_with_height.ies",
            OpeningShape::VerticalCylinder,
            0.12,
            0.12,
            0.34,
        ),
        ("sphere_opening.ies", OpeningShape::Ellipsoid, 0.12, 0.12, 0.12),
    ];
    for (file, shape, l, w, h) in cases {
        let ph = open(&format!("photometric-viewer/ies95/{file}"));
        let o = ph.opening;
        assert_eq!(o.shape, shape, "{file}");
        assert_close(o.size_x_m, l, 1e-12, file);
        assert_close(o.size_y_m, w, 1e-12, file);
        assert_close(o.height_m, h, 1e-12, file);
    }
    // Luminance = I / A_proj: a 0.34 m × 0.12 m flat rectangle seen from below and at 60°.
    let r = open("photometric-viewer/ies95/rectangular_opening.ies");
    assert_close(r.luminance(0.0, 0.0).unwrap(), 2200.0 / (0.34 * 0.12), 1e-12, "L(0,0)");
    let i60 = r.intensity(0.0, 60.0);
    assert_close(
        r.luminance(0.0, 60.0).unwrap(),
        i60 / (0.34 * 0.12 * 0.5),
        1e-9,
        "L(0,60)",
    );
    // A sphere shows π r² from every direction.
    let s = open("photometric-viewer/ies95/sphere_opening.ies");
    assert_close(
        s.luminance(123.0, 45.0).unwrap(),
        s.intensity(123.0, 45.0) / (PI * 0.06 * 0.06),
        1e-9,
        "sphere",
    );
    // A point has no luminance.
    assert!(open("photometric-viewer/ies95/point_opening.ies")
        .luminance(0.0, 0.0)
        .is_none());
}

#[test]
fn eulumdat_symmetry_3_is_stored_from_c270_through_c0_to_c90() {
    // Why C270 first: the EULUMDAT descriptions index the stored planes Mc1 = 3·Mc/4 + 1 …
    // Mc2 = Mc1 + Mc/2 (wrapping), i.e. C270 … C360=C0 … C90, and IES exports of the same
    // luminaires (bilateral about C90–C270, IES horizontal angles 90–270) agree only with that
    // reading. Reading the block as C90 … C270 mirrors the luminaire about the C90–C270 plane.
    let ph = open("photometric-viewer/ldt/symmetry_to_c90c270.ldt");
    assert_eq!(ph.symmetry, Symmetry::C90C270);
    let RawFile::Ldt(raw) = &ph.raw else { panic!() };
    assert_eq!(raw.mc, 36);
    let ng = raw.ng;
    let block = |k: usize| &raw.intensities[k * ng..(k + 1) * ng];
    // Absolute photometry with a 1000 lm luminaire flux and conversion factor 1: cd = cd/klm.
    for ig in [1usize, 10, 20] {
        let g = raw.gamma_deg[ig];
        assert_eq!(ph.intensity(270.0, g), block(0)[ig], "C270 is the first stored plane");
        assert_eq!(ph.intensity(0.0, g), block(9)[ig], "C0 is the tenth");
        assert_eq!(ph.intensity(90.0, g), block(18)[ig], "C90 is the last");
        // The mirror half: I(C) = I(180° − C).
        assert_eq!(ph.intensity(180.0, g), block(9)[ig]);
        assert_eq!(ph.intensity(120.0, g), ph.intensity(60.0, g));
        assert_eq!(ph.intensity(200.0, g), ph.intensity(340.0, g));
    }
}

#[test]
fn eulumdat_symmetries_expand_correctly() {
    let c0 = open("photometric-viewer/ldt/symmetry_to_c0c180.ldt");
    let q = open("photometric-viewer/ldt/symmetry_to_c0c90c180c270.ldt");
    let none = open("photometric-viewer/ldt/no_symmetry.ldt");
    let rot = open("photometric-viewer/ldt/symmetry_about_vertical_axis.ldt");
    for g in [0.0, 12.5, 47.5, 90.0] {
        for c in [10.0, 45.0, 80.0, 130.0] {
            assert_eq!(c0.intensity(c, g), c0.intensity(360.0 - c, g), "C0–C180 mirror");
            assert_eq!(q.intensity(c, g), q.intensity(180.0 - c, g), "quadrant about C90");
            assert_eq!(q.intensity(c, g), q.intensity(360.0 - c, g), "quadrant about C0");
            assert_eq!(rot.intensity(c, g), rot.intensity(0.0, g), "rotational");
        }
    }
    // The no-symmetry file stores 24 planes of 15°: every plane is its own.
    let RawFile::Ldt(raw) = &none.raw else { panic!() };
    assert_eq!(raw.mc, 24);
    for k in [0usize, 5, 13, 23] {
        let c = raw.c_deg[k];
        assert_eq!(
            none.intensity(c, raw.gamma_deg[4]),
            raw.intensities[k * raw.ng + 4],
            "plane C{c}"
        );
    }
    // The 345°–360° gap interpolates towards C0.
    let mid = none.intensity(352.5, 10.0);
    let (a, b) = (none.intensity(345.0, 10.0), none.intensity(0.0, 10.0));
    assert_close(mid, 0.5 * (a + b), 1e-12, "wrap");
}

#[test]
fn eulumdat_lamp_sets_and_relative_scaling() {
    // relative.ldt: 2 lamps with 500 lm *in total*: cd = cd/klm × 0.5 (not × 2 lamps).
    let rel = open("photometric-viewer/ldt/relative.ldt");
    // absolute.ldt: lamp count −2 marks absolute photometry (DIAL/Relux convention): the flux
    // field is the luminaire's 500 lm, intensities stay cd/klm of it, and there is no lamp flux.
    let abs = open("photometric-viewer/ldt/absolute.ldt");
    assert_eq!(rel.lamp_flux_lm, Some(500.0));
    assert_eq!(abs.lamp_flux_lm, None);
    assert_eq!(abs.declared_luminaire_flux_lm, Some(500.0));
    assert_close(rel.intensity(0.0, 0.0), 2200.0 * 0.5, 1e-12, "relative");
    assert_close(abs.intensity(0.0, 0.0), 2200.0 * 0.5, 1e-12, "absolute");
    // Lamp sets are alternatives: set 1 by default, set 2 (1200 lm) on request.
    let m1 = open("photometric-viewer/ldt/multiple_lamp_sets.ldt");
    let m2 = open_with(
        "photometric-viewer/ldt/multiple_lamp_sets.ldt",
        LoadOptions {
            lamp_set: 1,
            ..LoadOptions::default()
        },
    );
    assert_close(m1.intensity(0.0, 0.0), 2200.0 * 0.5, 1e-12, "set 1");
    assert_close(m2.intensity(0.0, 0.0), 2200.0 * 1.2, 1e-12, "set 2");
    let e = load(
        &data("photometric-viewer/ldt/multiple_lamp_sets.ldt"),
        &LoadOptions {
            lamp_set: 7,
            ..LoadOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("multiple_lamp_sets.ldt") && e.contains("3 lamp set"), "{e}");
}

#[test]
fn eulumdat_luminous_areas() {
    let o = |f: &str| open(&format!("photometric-viewer/ldt/{f}")).opening;
    let r = o("rectangular_luminaire_rectangular_luminous_opening.ldt");
    // EULUMDAT: length 50 mm along Y (C90–C270), width 40 mm along X (docs/adr/0002).
    assert_eq!((r.shape, r.size_x_m, r.size_y_m), (OpeningShape::Rectangle, 0.04, 0.05));
    let rh = o("rectangular_luminaire_rectangular_luminous_opening_with_heights.ldt");
    assert_eq!(rh.shape, OpeningShape::RectangleWithSides);
    assert_eq!(rh.side_heights_m, [0.011, 0.012, 0.013, 0.014]);
    // Seen from C0 at γ = 90°: only the C0 side face shows, spanning the length (0.05 m) × 0.011 m.
    assert_close(rh.projected_area(0.0, 90.0), 0.05 * 0.011, 1e-9, "C0 side");
    assert_close(rh.projected_area(270.0, 90.0), 0.04 * 0.014, 1e-9, "C270 side");
    let d = o("round_luminaire_round_luminous_opening.ldt");
    assert_eq!((d.shape, d.size_x_m, d.size_y_m), (OpeningShape::Ellipse, 0.05, 0.05));
    assert_close(d.projected_area(0.0, 0.0), PI * 0.025 * 0.025, 1e-12, "disc");
    let dh = o("rectangular_luminaire_round_luminous_opening_with_heights.ldt");
    assert_eq!(dh.shape, OpeningShape::DiscWithSides);
    assert!(open("photometric-viewer/ldt/absolute.ldt").opening.is_point());
    let size = open("photometric-viewer/ldt/rectangular_luminaire_rectangular_luminous_opening.ldt").luminaire_size_m;
    // Luminaire 120 mm long (Y) × 60 mm wide (X) × 30 mm high.
    assert_eq!(size, Some([0.06, 0.12, 0.03]));
}

#[test]
fn flux_agrees_with_declared_flux_where_the_file_is_consistent() {
    // BEGA 50804K3: absolute photometry; its [LAMP] label declares the luminaire's 4777 lm.
    let bega = open("misc/arnold-usd_bega_50804K3.ies");
    assert_close(bega.flux_lm(), 4777.0, 0.01, "BEGA integrated vs declared");
    // ASA 15M R2: 13000 lm lamp; integrated flux from an independent midpoint quadrature of the
    // bilinear table (Python, 720 × 720 cells): 9560.83 lm, i.e. LOR 73.5 %.
    let asa = open("misc/luxcore_ASA_15M_R2.ies");
    assert_close(asa.flux_lm(), 9560.83, 1e-4, "ASA integrated");
    assert_close(asa.integrated_lor().unwrap(), 0.7354, 1e-3, "ASA LOR");
    // Analytic Type B floodlight: I = 1000 cos²γ (1 + 0.5 x + 0.25 y) below the horizon integrates
    // to 2000π/3 lm (the odd terms cancel).
    for f in [
        "fixtures/type_b.ies",
        "fixtures/type_a.ies",
        "fixtures/type_b_lateral.ies",
    ] {
        assert_close(open(f).flux_lm(), 2000.0 * PI / 3.0, 0.005, f);
    }
    // Not consistent, and not checked: the photometric-viewer EULUMDAT files are dummies that reuse
    // one intensity table with an unrelated flux field and LORL 100 % (absolute.ldt: 452 lm from the
    // table against 500 lm declared).
    let dummy = open("photometric-viewer/ldt/absolute.ldt");
    assert!((dummy.flux_lm() / dummy.declared_luminaire_flux_lm.unwrap() - 1.0).abs() > 0.05);
}

/// Samples on a grid covering the sphere, including the seams C0/C360 and the poles.
fn sphere_samples() -> Vec<(f64, f64)> {
    let mut v = Vec::new();
    let mut c = 0.0;
    while c < 360.0 {
        let mut g = 0.0;
        while g <= 180.0 {
            v.push((c, g));
            g += 3.7;
        }
        v.push((c, 180.0));
        c += 7.3;
    }
    v
}

#[test]
fn ies_and_eulumdat_of_the_same_luminaire_agree() {
    for kind in ["full", "c0c180", "c90c270", "quadrant", "rotational"] {
        let ies = open(&format!("pairs/{kind}.ies"));
        let ldt = open(&format!("pairs/{kind}.ldt"));
        // The same 0.6 m (X) × 0.3 m (Y) opening: IES width 0.3 / length 0.6, EULUMDAT length 300
        // / width 600 mm (the formats put their length on different axes, docs/adr/0002).
        let (oi, ol) = (ies.opening, ldt.opening);
        assert_eq!((oi.size_x_m, oi.size_y_m), (0.6, 0.3), "{kind} IES opening");
        assert_eq!((ol.size_x_m, ol.size_y_m), (0.6, 0.3), "{kind} LDT opening");
        for (c, g) in sphere_samples() {
            let (a, b) = (ies.intensity(c, g), ldt.intensity(c, g));
            assert!(
                (a - b).abs() <= 1e-3 * a.abs().max(b.abs()) + 1e-6,
                "{kind} at C{c} γ{g}: IES {a} vs LDT {b}"
            );
        }
    }
    let ies = open("misc/luxcore_ASA_15M_R2.ies");
    let ldt = open("pairs/luxcore_ASA_15M_R2.ldt");
    for (c, g) in sphere_samples() {
        let (a, b) = (ies.intensity(c, g), ldt.intensity(c, g));
        assert!(
            (a - b).abs() <= 1e-3 * a.max(b) + 1e-3,
            "ASA at C{c} γ{g}: IES {a} vs LDT {b}"
        );
    }
}

#[test]
fn the_frame_is_c0_along_x_and_counter_clockwise() {
    // The pair distribution has its side lobe towards C30 (scripts/make-orientation-pairs.py):
    // a reader that runs C clockwise would put it at C330.
    let full = open("pairs/full.ies");
    assert!(full.intensity(30.0, 80.0) > 1.3 * full.intensity(330.0, 80.0));
    // The luminaire turned 90° counter-clockwise: its C0 plane now lies at C90.
    let rot = open("pairs/rotated90.ies");
    for (c, g) in sphere_samples() {
        let (a, b) = (full.intensity(c, g), rot.intensity(c + 90.0, g));
        assert!((a - b).abs() <= 1e-3 * a.max(b) + 1e-6, "C{c} γ{g}: {a} vs rotated {b}");
    }
    assert_close(rot.intensity(90.0, 45.0), full.intensity(0.0, 45.0), 1e-9, "C0 → C90");
}

#[test]
fn ies_90_270_is_mirrored_not_rotated() {
    // Stored planes C90: 100 60 5, C180: 100 90 40, C270: 100 60 5 (γ 0, 45, 90).
    let ph = open("fixtures/c90_270.ies");
    assert_eq!(ph.symmetry, Symmetry::C90C270);
    assert_eq!(ph.intensity(180.0, 45.0), 90.0);
    assert_eq!(ph.intensity(0.0, 45.0), 90.0, "C0 mirrors C180");
    assert_eq!(ph.intensity(90.0, 45.0), 60.0, "C90 stays where it was stored");
    assert_eq!(ph.intensity(45.0, 45.0), 75.0, "C45 mirrors C135");
    assert_eq!(ph.intensity(315.0, 90.0), ph.intensity(225.0, 90.0));
}

#[test]
fn uplight_90_to_180() {
    let ph = open("fixtures/uplight_90_180.ies");
    assert_eq!(ph.intensity(0.0, 45.0), 0.0, "nothing below the horizontal plane");
    assert_eq!(ph.intensity(10.0, 89.0), 0.0);
    assert_eq!(ph.intensity(0.0, 90.0), 50.0);
    assert_eq!(ph.intensity(200.0, 135.0), 300.0);
    assert_eq!(ph.intensity(0.0, 180.0), 400.0);
    assert_eq!(ph.web.flux_between(0.0, 90.0), 0.0);
}

#[test]
fn type_b_and_type_a_are_converted_not_reinterpreted() {
    // Derived by hand from LM-63-2002 §3, not from lumiview's formulas: in Types A and B,
    // H = V = 0 is photometric horizontal (lumiview: C0, γ 90°), V = −90° is nadir, and horizontal
    // angles run clockwise seen from above (H = +90° lies at C270).
    let a = open("fixtures/type_a_by_hand.ies");
    assert_close(a.intensity(0.0, 90.0), 1000.0, 1e-9, "A: photometric horizontal");
    assert_close(a.intensity(270.0, 90.0), 500.0, 1e-9, "A: H +90° is C270");
    assert_close(a.intensity(90.0, 90.0), 200.0, 1e-9, "A: H −90° is C90");
    assert_close(a.intensity(0.0, 0.0), 10.0, 1e-9, "A: V −90° is nadir");
    assert_close(a.intensity(123.0, 180.0), 10.0, 1e-9, "A: V +90° is zenith");
    let b = open("fixtures/type_b_by_hand.ies");
    assert_close(b.intensity(0.0, 90.0), 1000.0, 1e-9, "B: photometric horizontal");
    assert_close(b.intensity(330.0, 90.0), 700.0, 1e-9, "B: H +30° is C330");
    assert_close(b.intensity(30.0, 90.0), 300.0, 1e-9, "B: H −30° is C30");
    assert_close(b.intensity(0.0, 0.0), 10.0, 1e-9, "B: V −90° is nadir");
    assert_eq!(
        b.intensity(180.0, 90.0),
        0.0,
        "B: behind the floodlight is outside V −90…90"
    );
    // Analytic floodlights (scripts/make-typeab-fixtures.py) sample
    // I(d) = 1000·max(0, d.x)²·(1 + 0.5 d.z + 0.25 d.y) on their native grids; the web must
    // reproduce I at Type C angles.
    let want = |c: f64, g: f64, lateral: bool| {
        let d = direction(c, g);
        let ahead = d[0].max(0.0);
        1000.0 * ahead * ahead * (1.0 + 0.5 * d[2] + if lateral { 0.0 } else { 0.25 * d[1] })
    };
    for (file, lateral) in [
        ("fixtures/type_b.ies", false),
        ("fixtures/type_a.ies", false),
        ("fixtures/type_b_lateral.ies", true),
    ] {
        let ph = open(file);
        let mut worst: f64 = 0.0;
        for (c, g) in sphere_samples() {
            let w = want(c, g, lateral);
            let got = ph.intensity(c, g);
            if w > 100.0 {
                worst = worst.max((got - w).abs() / w);
            } else {
                assert!((got - w).abs() < 15.0, "{file} C{c} γ{g}: {got} vs {w}");
            }
        }
        assert!(worst < 0.02, "{file}: worst relative error {worst}");
    }
    // Read as Type C (the known bug), the same numbers would put the beam at nadir.
    let b = open("fixtures/type_b.ies");
    assert!(
        b.intensity(0.0, 80.0) > 5.0 * b.intensity(0.0, 10.0),
        "the beam is horizontal"
    );
    assert!(
        b.intensity(45.0, 80.0) > b.intensity(315.0, 80.0),
        "+Y side is brighter (1 + 0.25 y)"
    );
}

#[test]
fn lm63_1986_without_version_line() {
    let ph = open("fixtures/lm63_1986.ies");
    assert_eq!(ph.format, FileFormat::Ies(IesVersion::Lm63_1986));
    assert_eq!(ph.labels.iter().filter(|(k, _)| k.is_empty()).count(), 3);
    assert_eq!(ph.intensity(0.0, 45.0), 300.0);
    assert_eq!(ph.lamp_flux_lm, Some(1500.0));
    assert_eq!(ph.opening.shape, OpeningShape::Rectangle);
    assert_close(ph.opening.size_x_m, 0.5 * 0.3048, 1e-12, "feet");
}

#[test]
fn tilt_include_with_shared_lines_and_a_chosen_tilt() {
    let base = open("fixtures/tilt_include_shared.ies");
    let t = base.tilt.as_ref().unwrap();
    assert_eq!(t.lamp_to_luminaire_geometry, 2);
    assert_eq!(t.angles_deg, vec![0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0]);
    assert_eq!(t.factors, vec![1.0, 0.98, 0.95, 0.9, 0.84, 0.8, 0.78]);
    assert_eq!(base.intensity(0.0, 0.0), 500.0, "measured orientation: no factor");
    assert!(base.keywords_contain("TILT=NONE"));
    let at = |deg: f64| {
        open_with(
            "fixtures/tilt_include_shared.ies",
            LoadOptions {
                tilt_deg: Some(deg),
                ..LoadOptions::default()
            },
        )
    };
    assert_close(at(30.0).intensity(0.0, 0.0), 475.0, 1e-12, "30°");
    assert_close(at(37.5).intensity(0.0, 45.0), 400.0 * 0.925, 1e-12, "37.5°");
    let file = open_with(
        "fixtures/tilt_file.ies",
        LoadOptions {
            tilt_deg: Some(45.0),
            ..LoadOptions::default()
        },
    );
    assert_close(file.intensity(0.0, 0.0), 90.0, 1e-12, "TILT=<file> at 45°");
    let e = load(&data("fixtures/tilt_file_missing.ies"), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("tilt_file_missing.ies:3") && e.contains("no_such_tilt_file.dat"),
        "{e}"
    );
}

trait Keywords {
    fn keywords_contain(&self, text: &str) -> bool;
}

impl Keywords for Photometry {
    fn keywords_contain(&self, text: &str) -> bool {
        self.labels.iter().any(|(_, v)| v.contains(text))
    }
}

#[test]
fn commas_tabs_and_records_spanning_lines() {
    let ph = open("fixtures/commas_tabs.ies");
    // multiplier 2.0 × ballast factor 0.9 × ballast-lamp factor 1
    assert_close(ph.candela_scale, 1.8, 1e-12, "scale");
    assert_close(ph.intensity(0.0, 0.0), 180.0, 1e-12, "C0 γ0");
    assert_close(ph.intensity(90.0, 30.0), 171.0, 1e-12, "C90 γ30");
    assert_close(ph.intensity(180.0, 90.0), 25.2, 1e-12, "C180 γ90");
    assert_eq!(ph.intensity(270.0, 30.0), ph.intensity(90.0, 30.0));
}

#[test]
fn latin1_and_crlf() {
    let ph = open("fixtures/latin1.ies");
    let get = |k: &str| ph.labels.iter().find(|(key, _)| key == k).map(|(_, v)| v.clone());
    assert_eq!(get("MANUFAC").as_deref(), Some("Müller Leuchten GmbH"));
    assert_eq!(get("LUMINAIRE").as_deref(), Some("Strahler 30°"));
    assert_eq!(ph.intensity(0.0, 45.0), 40.0);
}

#[test]
fn lm63_2019_generation_type_is_not_a_factor() {
    let ph = open("fixtures/lm63_2019.ies");
    assert_eq!(ph.format, FileFormat::Ies(IesVersion::Lm63_2019));
    // multiplier 2 × ballast factor 0.9; the 1.10000 after it is the file generation type.
    assert_close(ph.intensity(0.0, 0.0), 180.0, 1e-12, "2019 scale");
    let RawFile::Ies(raw) = &ph.raw else { panic!() };
    assert_eq!(raw.file_generation_type(), Some(1.1));
    assert_eq!(
        lumiview::photometry::ies::file_generation_description(1.1),
        Some("test at an accredited lab")
    );
    assert_eq!(
        raw.keyword("LUMINAIRE"),
        Some("uses the 2019 fields\nand a MORE continuation")
    );
    assert_eq!(raw.keyword("_USERKEY"), Some("user keywords are kept"));
    // Before 2002 the same position is the ballast-lamp factor and is applied.
    let old = open("fixtures/factors_1995.ies");
    assert_close(old.intensity(0.0, 0.0), 100.0 * 2.0 * 0.9 * 0.95, 1e-12, "1995 scale");
    assert_eq!(old.lamp_flux_lm, Some(2000.0));
    // In LM-63-2002 it is "future use": never a factor (here 0, which a reader that multiplies
    // turns into an all-dark luminaire). The two-digit year `LM-63-02` is 2002.
    let fu = open("fixtures/future_use_2002.ies");
    assert_eq!(fu.format, FileFormat::Ies(IesVersion::Lm63_2002));
    assert_eq!(fu.intensity(0.0, 0.0), 100.0);
    assert!(
        fu.warnings.iter().any(|w| w.contains("future use")),
        "{:?}",
        fu.warnings
    );
}

#[test]
fn full_circle_with_and_without_the_360_entry() {
    let a = open("fixtures/full_with_360.ies");
    let b = open("fixtures/full_without_360.ies");
    for (c, g) in sphere_samples() {
        assert_eq!(a.intensity(c, g), b.intensity(c, g), "C{c} γ{g}");
    }
    assert_eq!(a.intensity(315.0, 90.0), 25.0, "between C270 (40) and C360 = C0 (10)");
}

fn ies_err(text: &str) -> String {
    load_from_text(text, "bad.ies", &LoadOptions::default())
        .unwrap_err()
        .to_string()
}

#[test]
fn bad_files_are_errors_that_name_file_line_and_field() {
    let good = std::fs::read_to_string(data("fixtures/factors_1995.ies")).unwrap();
    assert!(load_from_text(&good, "good.ies", &LoadOptions::default()).is_ok());
    // Truncated anywhere in the numbers: an error naming what was being read.
    let real = std::fs::read_to_string(data("misc/luxcore_ASA_15M_R2.ies")).unwrap();
    for cut in [real.len() / 3, real.len() / 2, real.len() - 10] {
        let e = ies_err(&real[..cut]);
        assert!(e.starts_with("bad.ies:") && e.contains("truncated"), "{e}");
    }
    let cases = [
        (good.replace("100 50 10", "100 NaN 10"), "candela values"),
        (
            good.replace("2 1000 2.0 3 1 1 2", "2 1000 2.0 3 1 7 2"),
            "unknown photometric type 7",
        ),
        (good.replace("2 1000 2.0 3 1 1 2", "2 1000 2.0 3 1 1 3"), "units type"),
        (
            good.replace("2 1000 2.0 3 1", "2 1000 2.0 3.5 1"),
            "number of vertical angles",
        ),
        (good.replace("0 45 90", "0 90 90"), "vertical angles"),
        (good.replace("TILT=NONE", "TILT="), "TILT"),
        (good.replace("TILT=NONE", "[TILT] NONE"), "TILT"),
        (good.replace("2 1000 2.0", "2 0 2.0"), "lumens per lamp"),
    ];
    for (text, want) in cases {
        let e = ies_err(&text);
        assert!(e.starts_with("bad.ies") && e.contains(want), "want `{want}` in: {e}");
    }
    // EULUMDAT: truncated, bad symmetry, letters in a number.
    let ldt = std::fs::read_to_string(data("photometric-viewer/ldt/symmetry_to_c0c180.ldt")).unwrap();
    let lerr = |t: &str| {
        load_from_text(t, "bad.ldt", &LoadOptions::default())
            .unwrap_err()
            .to_string()
    };
    let e = lerr(&ldt[..ldt.len() / 2]);
    assert!(
        e.starts_with("bad.ldt") && e.contains("luminous intensities") && e.contains("truncated"),
        "{e}"
    );
    let mut lines: Vec<&str> = ldt.lines().collect();
    lines[2] = "5";
    let e = lerr(&lines.join("\n"));
    assert!(e.contains("bad.ldt:3") && e.contains("symmetry"), "{e}");
    lines[2] = "2";
    lines[3] = "thirty-six";
    let e = lerr(&lines.join("\n"));
    assert!(e.contains("bad.ldt:4") && e.contains("thirty-six"), "{e}");
    // A missing file names the path.
    let e = load(Path::new("/no/such/file.ies"), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("/no/such/file.ies"), "{e}");
}

#[test]
fn implausible_arguments_and_sizes_are_errors() {
    let good = std::fs::read_to_string(data("fixtures/factors_1995.ies")).unwrap();
    let e = ies_err(&good.replace("1 2 0.2 0.2 0", "1 2 1e300 0.2 0"));
    assert!(e.contains("luminous opening width") && e.contains("plausible"), "{e}");
    let e = load(
        &data("fixtures/type_b.ies"),
        &LoadOptions {
            ab_step_deg: 1e-9,
            ..LoadOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("ab_step_deg"), "{e}");
    // A full-circle file that stops at 270° is read, with a warning about the interpolated gap.
    let planes = |angles: &[u32]| {
        let h: Vec<String> = angles.iter().map(|a| a.to_string()).collect();
        let v: Vec<&str> = angles.iter().map(|_| "5 5").collect();
        format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 {} 1 2 0 0 0\n1 1 10\n0 90\n{}\n{}\n",
            angles.len(),
            h.join(" "),
            v.join(" ")
        )
    };
    let partial = planes(&[0, 30, 60, 90, 120, 150, 180, 210, 240, 270]);
    let ph = load_from_text(&partial, "partial.ies", &LoadOptions::default()).unwrap();
    assert!(ph.warnings.iter().any(|w| w.contains("270")), "{:?}", ph.warnings);
    let whole = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 4 1 2 0 0 0\n1 1 10\n0 90\n0 90 180 300\n1 1 2 2 3 3 4 4\n";
    assert!(load_from_text(whole, "whole.ies", &LoadOptions::default())
        .unwrap()
        .warnings
        .is_empty());
}

#[test]
fn review_regressions() {
    // A negative value is read as 0 with a warning naming the file and its own line (line 11
    // here), not the table's first line.
    let neg = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 3 2 1 2 0 0 0\n1 1 10\n0 45 90\n0 180\n100 50\n10\n\n9 8\n-7\n";
    let p = load_from_text(neg, "neg.ies", &LoadOptions::default()).unwrap();
    let w = p.warnings.join("\n");
    assert!(
        w.contains("neg.ies: line 11:") && w.contains("negative candela") && w.contains("-7"),
        "{w}"
    );
    assert_eq!(p.intensity(180.0, 90.0), 0.0);
    // TILT=<device>: refused, not read forever.
    let dev = std::env::temp_dir().join("lumiview_tilt_dev.ies");
    std::fs::write(
        &dev,
        "IESNA:LM-63-2002\nTILT=/dev/zero\n1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1 1\n",
    )
    .unwrap();
    let e = load(&dev, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("/dev/zero") && e.contains("regular file"), "{e}");
    // A Type B table needs at least 2 × 2 angles.
    let e = ies_err("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 1 1 2 2 0 0 0\n1 1 10\n0\n0\n5\n");
    assert!(e.contains("at least 2"), "{e}");
    // An ellipsoid (pre-2002 code −w, l, −h) shows π·(l/2)·(w/2) from below.
    let el = open("photometric-viewer/ies95/ellipsoid_opening_along_length.ies");
    assert_close(
        el.luminance(0.0, 0.0).unwrap(),
        2200.0 / (PI * 0.17 * 0.06),
        1e-9,
        "ellipsoid",
    );
    // An absurd EULUMDAT luminous area is an error, like an absurd IES one.
    let ldt = std::fs::read_to_string(data(
        "photometric-viewer/ldt/rectangular_luminaire_rectangular_luminous_opening.ldt",
    ))
    .unwrap();
    let mut lines: Vec<&str> = ldt.lines().collect();
    lines[15] = "1e300";
    let e = load_from_text(&lines.join("\n"), "big.ldt", &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("big.ldt") && e.contains("plausible"), "{e}");
    // --tilt on a file without a TILT table applies nothing and says so.
    let ph = open_with(
        "misc/luxcore_ASA_15M_R2.ies",
        LoadOptions {
            tilt_deg: Some(45.0),
            ..LoadOptions::default()
        },
    );
    assert_eq!(ph.tilt_applied_deg, None);
}
