//! Which faces a file's luminous dimensions describe (docs/adr/0002-luminous-dimensions-per-format.md):
//! IES LM-63 puts its length along X (the 0–180° plane) and its width along Y; EULUMDAT, as Relux
//! reads it, puts its length along Y (C90–C270), and its C0 side height is the face seen from C0,
//! spanning that length. Every file here is written by the test; the expected areas follow from
//! the file's numbers and that rule alone.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use lumiview::photometry::meshes::{housing_lines, opening_triangles};
use lumiview::photometry::{load_from_text, LoadOptions, OpeningShape, Photometry};

/// An EULUMDAT file, Isym 0, C 0–345° step 15 × γ 0–180° step 5, one lamp set of 1000 lm with
/// conversion factor 1 (so the stored cd/klm are cd), intensity `cd(C, γ)`.
fn ldt(
    length_mm: f64,
    width_mm: f64,
    heights_mm: [f64; 4],
    luminaire_mm: [f64; 3],
    cd: impl Fn(f64, f64) -> f64,
) -> String {
    let mut l: Vec<String> = vec![
        "lumiview orientation test".into(),
        "1".into(),
        "0".into(),
        "24".into(),
        "15".into(),
        "37".into(),
        "5".into(),
        "report".into(),
        "orientation".into(),
        "ORI-1".into(),
        "orientation.ldt".into(),
        "2026-11-25".into(),
    ];
    l.extend(luminaire_mm.iter().map(|v| v.to_string()));
    l.push(length_mm.to_string());
    l.push(width_mm.to_string());
    l.extend(heights_mm.iter().map(|v| v.to_string()));
    for v in ["100", "90", "1", "0", "1", "1", "LED", "1000", "3000K", "80", "10"] {
        l.push(v.into());
    }
    l.extend((0..10).map(|_| "0.5".to_string()));
    l.extend((0..24).map(|i| (i * 15).to_string()));
    l.extend((0..37).map(|i| (i * 5).to_string()));
    for i in 0..24 {
        for j in 0..37 {
            l.push(format!("{:.6}", cd(f64::from(i * 15), f64::from(j * 5))));
        }
    }
    l.join("\n") + "\n"
}

fn load(text: &str, name: &str) -> Photometry {
    load_from_text(text, name, &LoadOptions::default()).unwrap()
}

#[test]
fn relux_linear_luminaire_c0_gamma85() {
    // The linear luminaire of issue 15: luminous area 1208 × 105 mm, C0/C180 sides 51 mm, 63.5 cd
    // at C0 γ85. Relux prints 877 cd/m² there: A_proj = 1.208 · 0.105 · cos 85° + 1.208 · 0.051 ·
    // sin 85° = 0.0724 m² (the long face is seen from C0).
    let text = ldt(1208.0, 105.0, [51.0, 0.0, 51.0, 0.0], [1208.0, 105.0, 54.0], |_, g| {
        if g <= 90.0 {
            63.5
        } else {
            0.0
        }
    });
    let p = load(&text, "linear.ldt");
    assert_eq!(p.opening.shape, OpeningShape::RectangleWithSides);
    assert!((p.opening.size_y_m - 1.208).abs() < 1e-12, "length along Y");
    assert!((p.opening.size_x_m - 0.105).abs() < 1e-12, "width along X");
    let l = p.luminance(0.0, 85.0).unwrap();
    assert!((l - 877.0).abs() <= 9.0, "L(C0, γ85) = {l:.1} cd/m², Relux 877");
    // The reading that multiplies h_C0 by the width gave 3877 cd/m² (4.4× too bright).
    assert!(l < 1000.0);
}

#[test]
fn panel_with_low_sides_on_all_four_faces() {
    // The second luminaire of issue 15: 630 × 400 mm, 8 mm sides all round (was 7 % off).
    let text = ldt(630.0, 400.0, [8.0; 4], [630.0, 400.0, 50.0], |_, _| 100.0);
    let p = load(&text, "panel.ldt");
    let (c, s) = (85f64.to_radians().cos(), 85f64.to_radians().sin());
    let want_c0 = 100.0 / (0.63 * 0.4 * c + 0.63 * 0.008 * s);
    let want_c90 = 100.0 / (0.63 * 0.4 * c + 0.4 * 0.008 * s);
    let (l0, l90) = (p.luminance(0.0, 85.0).unwrap(), p.luminance(90.0, 85.0).unwrap());
    assert!((l0 / want_c0 - 1.0).abs() < 1e-9, "C0: {l0} vs {want_c0}");
    assert!((l90 / want_c90 - 1.0).abs() < 1e-9, "C90: {l90} vs {want_c90}");
}

/// The vertices of the far-field mesh's side faces (those above the bottom plane).
fn side_vertices(p: &Photometry) -> Vec<[f32; 3]> {
    opening_triangles(&p.opening)
        .positions
        .into_iter()
        .filter(|v| v[2] > 1e-6)
        .collect()
}

#[test]
fn each_eulumdat_side_height_is_the_face_seen_from_its_c_plane() {
    // Luminous area 1000 mm long (Y) × 200 mm wide (X); one side face 50 mm high at a time.
    let faces = ["C0", "C90", "C180", "C270"];
    for (k, face) in faces.iter().enumerate() {
        let mut h = [0.0; 4];
        h[k] = 50.0;
        let p = load(&ldt(1000.0, 200.0, h, [1000.0, 200.0, 60.0], |_, _| 100.0), "side.ldt");
        // Seen horizontally from C = 0, 90, 180, 270: only the face of its own plane shows; the
        // C0/C180 faces span the length (1.0 m), the C90/C270 faces the width (0.2 m).
        for j in 0..4 {
            let c = 90.0 * j as f64;
            let a = p.opening.projected_area(c, 90.0);
            let want = if j != k {
                0.0
            } else if k % 2 == 0 {
                1.0 * 0.05
            } else {
                0.2 * 0.05
            };
            assert!(
                (a - want).abs() < 1e-12,
                "{face} side seen from C{c}: A = {a}, want {want}"
            );
            assert_eq!(
                p.luminance(c, 90.0).is_some(),
                j == k,
                "{face} side, luminance from C{c}"
            );
        }
        // The far-field pass draws the same face: its vertices lie on the side facing that plane.
        let v = side_vertices(&p);
        assert!(!v.is_empty(), "{face}: no side face drawn");
        let on_face = |q: &[f32; 3]| match k {
            0 => (q[0] - 0.1).abs() < 1e-6 && q[1].abs() <= 0.5 + 1e-6,
            1 => (q[1] - 0.5).abs() < 1e-6 && q[0].abs() <= 0.1 + 1e-6,
            2 => (q[0] + 0.1).abs() < 1e-6 && q[1].abs() <= 0.5 + 1e-6,
            _ => (q[1] + 0.5).abs() < 1e-6 && q[0].abs() <= 0.1 + 1e-6,
        };
        assert!(v.iter().all(on_face), "{face}: side vertices {v:?}");
        let span = |axis: usize| {
            let (lo, hi) = v
                .iter()
                .fold((f32::MAX, f32::MIN), |(a, b), q| (a.min(q[axis]), b.max(q[axis])));
            hi - lo
        };
        let along = if k % 2 == 0 { span(1) } else { span(0) };
        let want = if k % 2 == 0 { 1.0 } else { 0.2 };
        assert!((along - want).abs() < 1e-5, "{face}: face spans {along} m, want {want}");
    }
}

#[test]
fn eulumdat_housing_lies_along_the_same_axes() {
    let p = load(
        &ldt(1000.0, 200.0, [0.0; 4], [1100.0, 250.0, 70.0], |_, _| 100.0),
        "housing.ldt",
    );
    assert_eq!(p.luminaire_size_m, Some([0.25, 1.1, 0.07]));
    let lines = housing_lines(p.luminaire_size_m.unwrap());
    let max = |axis: usize| lines.iter().map(|v| v[axis]).fold(f32::MIN, f32::max);
    assert!(
        (max(0) - 0.125).abs() < 1e-6 && (max(1) - 0.55).abs() < 1e-6,
        "{lines:?}"
    );
}

#[test]
fn ies_length_lies_along_x() {
    // LM-63: the length is measured along the 0–180° plane, the width along 90–270°. A box
    // 1.0 m long, 0.2 m wide, 0.05 m high: seen from C0 the end (width × height) shows.
    let ies = "IESNA:LM-63-2002\n[TEST] t\nTILT=NONE\n1 -1 1 3 1 1 2 0.2 1.0 0.05\n1 1 10\n0 90 180\n0\n100 100 100\n";
    let p = load(ies, "box.ies");
    assert_eq!(p.opening.shape, OpeningShape::Box);
    assert!((p.opening.size_x_m - 1.0).abs() < 1e-12 && (p.opening.size_y_m - 0.2).abs() < 1e-12);
    assert!((p.opening.projected_area(0.0, 90.0) - 0.2 * 0.05).abs() < 1e-12);
    assert!((p.opening.projected_area(90.0, 90.0) - 1.0 * 0.05).abs() < 1e-12);
}

#[test]
fn the_side_lit_fixture_reads_along_its_axes() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fixtures/side_lit.ldt");
    let p = lumiview::photometry::load(&path, &LoadOptions::default()).unwrap();
    assert_eq!(p.opening.shape, OpeningShape::RectangleWithSides);
    assert_eq!((p.opening.size_x_m, p.opening.size_y_m), (0.15, 0.6));
    assert_eq!(p.opening.side_heights_m, [0.06, 0.03, 0.0, 0.015]);
    assert_eq!(p.luminaire_size_m, Some([0.17, 0.62, 0.08]));
    // Brightest side towards C0, then C90, C270, C180.
    let i = |c: f64| p.intensity(c, 80.0);
    assert!(i(0.0) > i(90.0) && i(90.0) > i(270.0) && i(270.0) > i(180.0));
}
