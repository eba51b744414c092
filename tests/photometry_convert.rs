//! `lumiview convert` round trips over every IES and EULUMDAT file in tests/data/: IES → LDT → IES
//! and LDT → IES → LDT keep the absolute intensities at every node of the original web within
//! 0.1 % of the peak, the dimensions and side heights on their axes, the housing; an LDT and the IES
//! made from it give the same luminance table within 0.5 %. Plus the CLI over a folder.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use lumiview::photometry::convert::{to_ies, to_ldt};
use lumiview::photometry::{load, load_from_text, FileFormat, LoadOptions, OpeningShape, Photometry};

fn data_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                // tests/data/fuzz/ holds hostile inputs (tests/hostile_inputs.rs), not luminaires.
                if p.file_name().is_some_and(|n| n == "fuzz") {
                    continue;
                }
                walk(&p, out);
            } else if p
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| e.eq_ignore_ascii_case("ies") || e.eq_ignore_ascii_case("ldt"))
            {
                out.push(p);
            }
        }
    }
    let mut v = Vec::new();
    walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data"), &mut v);
    v
}

/// Converts to the other format and back, through text, as a user's files would go.
fn round_trip(p: &Photometry) -> (Photometry, Photometry) {
    let (mid, back) = match p.format {
        FileFormat::Eulumdat => {
            let ies = to_ies(p).unwrap();
            let mid = load_from_text(&ies.text, "mid.ies", &LoadOptions::default()).unwrap();
            let ldt = to_ldt(&mid, "back.ldt").unwrap();
            (
                mid,
                load_from_text(&ldt.text, "back.ldt", &LoadOptions::default()).unwrap(),
            )
        }
        FileFormat::Ies(_) => {
            let ldt = to_ldt(p, "mid.ldt").unwrap();
            let mid = load_from_text(&ldt.text, "mid.ldt", &LoadOptions::default()).unwrap();
            let ies = to_ies(&mid).unwrap();
            (
                mid,
                load_from_text(&ies.text, "back.ies", &LoadOptions::default()).unwrap(),
            )
        }
    };
    (mid, back)
}

fn same_intensities(a: &Photometry, b: &Photometry, what: &str) {
    let peak = a.web.max_intensity().0;
    let tol = 1e-3 * peak;
    let ng = a.web.gamma_angles().len();
    for (i, &cd) in a.web.values().iter().enumerate() {
        let (c, g) = (a.web.c_angles()[i / ng], a.web.gamma_angles()[i % ng]);
        let v = b.intensity(c, g);
        assert!(
            (v - cd).abs() <= tol,
            "{what}: C{c} γ{g}: {v} cd vs {cd} cd (tolerance {tol} cd = 0.1 % of the peak)"
        );
    }
}

/// Shapes EULUMDAT can hold exactly.
fn ldt_representable(o: &lumiview::photometry::LuminousOpening) -> bool {
    let round = (o.size_x_m - o.size_y_m).abs() <= 1e-12;
    match o.shape {
        OpeningShape::Point
        | OpeningShape::Rectangle
        | OpeningShape::Box
        | OpeningShape::RectangleWithSides
        | OpeningShape::DiscWithSides => true,
        OpeningShape::Ellipse | OpeningShape::VerticalCylinder => round,
        _ => false,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 + 1e-6 * a.abs()
}

#[test]
fn every_file_round_trips() {
    let mut count = 0;
    for path in data_files() {
        let Ok(p) = load(&path, &LoadOptions::default()) else {
            continue; // the files that are errors on purpose (tests/photometry_files.rs)
        };
        count += 1;
        let name = path.display().to_string();
        let (mid, back) = round_trip(&p);
        same_intensities(&p, &mid, &format!("{name} → other format"));
        same_intensities(&p, &back, &format!("{name} → other format → back"));
        assert_eq!(back.symmetry, p.symmetry_written(), "{name}: symmetry");
        let (o, m, b) = (p.opening, mid.opening, back.opening);
        if ldt_representable(&o) || p.format == FileFormat::Eulumdat {
            for (q, which) in [(m, "converted"), (b, "back")] {
                assert!(
                    close(q.size_x_m, o.size_x_m) && close(q.size_y_m, o.size_y_m),
                    "{name}: {which} opening {} × {} m, original {} × {} m (X × Y)",
                    q.size_x_m,
                    q.size_y_m,
                    o.size_x_m,
                    o.size_y_m
                );
                assert!(
                    q.side_heights_m.iter().zip(o.side_heights_m).all(|(x, y)| close(*x, y))
                        || (matches!(o.shape, OpeningShape::Box | OpeningShape::VerticalCylinder)
                            && q.side_heights_m.iter().all(|h| close(*h, o.height_m))),
                    "{name}: {which} side heights {:?}, original {:?}",
                    q.side_heights_m,
                    o.side_heights_m
                );
            }
            assert_eq!(b.shape, o.shape, "{name}: shape after the round trip");
        } else {
            // EULUMDAT approximates the shape; the long axis stays the long axis.
            assert_eq!(
                b.size_x_m >= b.size_y_m,
                o.size_x_m >= o.size_y_m,
                "{name}: axes swapped ({:?} → {:?})",
                o,
                b
            );
        }
        match (p.luminaire_size_m, back.luminaire_size_m) {
            (Some(a), Some(z)) => assert!(
                a.iter().zip(z).all(|(x, y)| close(*x, y)),
                "{name}: housing {a:?} → {z:?}"
            ),
            (a, z) => assert_eq!(a, z, "{name}: housing"),
        }
    }
    assert!(count >= 60, "only {count} files loaded");
}

trait Written {
    fn symmetry_written(&self) -> lumiview::photometry::Symmetry;
}

impl Written for Photometry {
    /// Type A/B files are written as Type C with every plane.
    fn symmetry_written(&self) -> lumiview::photometry::Symmetry {
        use lumiview::photometry::{PhotometricType, Symmetry};
        if self.photometric_type == PhotometricType::C {
            self.symmetry
        } else {
            Symmetry::None
        }
    }
}

#[test]
fn an_ldt_and_its_ies_give_the_same_luminance() {
    let mut count = 0;
    for path in data_files() {
        let Ok(p) = load(&path, &LoadOptions::default()) else {
            continue;
        };
        if p.format != FileFormat::Eulumdat || p.opening.is_point() {
            continue;
        }
        count += 1;
        let ies = load_from_text(&to_ies(&p).unwrap().text, "x.ies", &LoadOptions::default()).unwrap();
        for g in [0.0, 30.0, 45.0, 60.0, 65.0, 70.0, 75.0, 80.0, 85.0] {
            for k in 0..24 {
                let c = f64::from(k) * 15.0;
                match (p.luminance(c, g), ies.luminance(c, g)) {
                    (Some(a), Some(b)) => assert!(
                        (a - b).abs() <= 5e-3 * a.abs().max(1e-9),
                        "{}: L(C{c}, γ{g}) {a} vs IES {b}",
                        path.display()
                    ),
                    (a, b) => assert_eq!(a.is_some(), b.is_some(), "{}: C{c} γ{g}", path.display()),
                }
            }
        }
    }
    assert!(count >= 10, "{count} EULUMDAT files with an opening");
}

#[test]
fn the_dimensions_move_with_their_axes() {
    // EULUMDAT luminous area 600 (length, Y) × 150 (width, X): the IES file says width 0.6,
    // length 0.15 (docs/adr/0002); the side heights and housing go into lumiview's keywords.
    let p = load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fixtures/side_lit.ldt"),
        &LoadOptions::default(),
    )
    .unwrap();
    let c = to_ies(&p).unwrap();
    let line10 = c
        .text
        .lines()
        .skip_while(|l| !l.starts_with("TILT="))
        .nth(1)
        .unwrap()
        .split_whitespace()
        .map(|t| t.parse::<f64>().unwrap())
        .collect::<Vec<_>>();
    assert_eq!(&line10[7..9], &[0.6, 0.15], "IES width, length");
    assert!(
        c.text.contains("[_LUMIVIEW_SIDE_HEIGHTS_M] 0.06 0.03 0 0.015"),
        "{}",
        c.text
    );
    assert!(c.lost.iter().any(|l| l.contains("unequal side heights")));
    // Another reader sees a box of the mean height; lumiview reads the four faces back.
    let back = load_from_text(&c.text, "s.ies", &LoadOptions::default()).unwrap();
    assert_eq!(back.opening.shape, OpeningShape::RectangleWithSides);
    assert_eq!(back.luminaire_size_m, Some([0.17, 0.62, 0.08]));
}

fn lumiview(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn cli_converts_a_folder_into_one_table_and_continues_past_a_bad_file() {
    let dir = std::env::temp_dir().join(format!("lumiview-convert-{}", std::process::id()));
    let src = dir.join("in");
    let out = dir.join("out");
    std::fs::create_dir_all(&src).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    std::fs::copy(root.join("pairs/full.ldt"), src.join("a.ldt")).unwrap();
    std::fs::copy(root.join("misc/luxcore_ASA_15M_R2.ies"), src.join("b.ies")).unwrap();
    std::fs::write(src.join("broken.ies"), "IESNA:LM-63-2002\nTILT=NONE\n1 2 3\n").unwrap();
    let o = lumiview(&["convert", src.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "a bad file makes the exit status non-zero");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines[0], "input,output,format,not_kept,error");
    assert_eq!(lines.len(), 4, "{stdout}");
    assert!(stderr.contains("broken.ies"), "{stderr}");
    assert!(out.join("a.ies").exists() && out.join("b.ldt").exists());
    let a = load(&src.join("a.ldt"), &LoadOptions::default()).unwrap();
    let b = load(&out.join("a.ies"), &LoadOptions::default()).unwrap();
    same_intensities(&a, &b, "CLI a.ldt → a.ies");
    // One file to one named file; the input itself is refused as output.
    let one = out.join("single.ldt");
    let o = lumiview(&[
        "convert",
        src.join("b.ies").to_str().unwrap(),
        "-o",
        one.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = lumiview(&["convert", one.to_str().unwrap(), "-o", one.to_str().unwrap()]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("the output is the input"));
    let o = lumiview(&[
        "convert",
        one.to_str().unwrap(),
        "-o",
        out.join("x.txt").to_str().unwrap(),
    ]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains(".ies or .ldt"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_written_fields_read_by_hand() {
    // IES symmetric about C90–C270, stored C90, C180, C270 with 10, 20, 30 cd: mirrored, C0 holds
    // C180's 20 cd. EULUMDAT Isym 3 stores C270, C0, C90 in that order (lines 28 ff.), in cd/klm of
    // the luminaire's own flux (absolute photometry: a negative lamp count).
    let ies = "IESNA:LM-63-2002\n[TEST] t\nTILT=NONE\n1 -1 1 2 3 1 2 0.2 0.6 0\n1 1 10\n0 90\n90 180 270\n10 10\n20 20\n30 30\n";
    let p = load_from_text(ies, "sym.ies", &LoadOptions::default()).unwrap();
    let c = to_ldt(&p, "sym.ldt").unwrap();
    let l: Vec<&str> = c.text.split("\r\n").collect();
    assert_eq!(
        (l[2], l[3], l[4], l[5], l[6]),
        ("3", "4", "90", "2", "90"),
        "Isym, Mc, Dc, Ng, Dg"
    );
    // Lines 16–17: luminous area length (Y) = the IES width 0.2 m, width (X) = the IES length 0.6 m.
    assert_eq!((l[15], l[16]), ("200", "600"));
    assert_eq!(l[25], "1", "one lamp set");
    assert!(
        l[26].starts_with('-'),
        "absolute photometry: negative lamp count, {}",
        l[26]
    );
    let flux: f64 = l[28].parse().unwrap();
    assert!((flux - p.flux_lm()).abs() < 1e-3 * flux);
    let (c0, ng) = (42, 2);
    assert_eq!(&l[c0..c0 + 4], &["0", "90", "180", "270"], "C angles");
    assert_eq!(&l[c0 + 4..c0 + 4 + ng], &["0", "90"], "γ angles");
    let cd = |k: usize| l[c0 + 6 + k].parse::<f64>().unwrap() * flux / 1000.0;
    for (block, want) in [(0, 30.0), (1, 20.0), (2, 10.0)] {
        assert!(
            (cd(block * ng) - want).abs() < 1e-4,
            "stored block {block}: {} cd, want {want}",
            cd(block * ng)
        );
    }
    assert_eq!(l.len(), c0 + 6 + 3 * ng + 1, "three stored planes and a final line end");
    // And back to IES: horizontal angles 90, 180, 270 with their values; width 0.2, length 0.6.
    let back = to_ies(&load_from_text(&c.text, "sym.ldt", &LoadOptions::default()).unwrap()).unwrap();
    let t: Vec<&str> = back.text.split("\r\n").collect();
    let tilt = t.iter().position(|x| *x == "TILT=NONE").unwrap();
    let line10: Vec<&str> = t[tilt + 1].split(' ').collect();
    assert_eq!((line10[3], line10[4], line10[7], line10[8]), ("2", "3", "0.2", "0.6"));
    assert_eq!(t[tilt + 4], "90 180 270");
    // Through cd/klm at seven significant digits and back: the same candela to 10⁻⁶.
    for (row, want) in t[tilt + 5..tilt + 8].iter().zip([10.0, 20.0, 30.0]) {
        for v in row.split(' ') {
            let v: f64 = v.parse().unwrap();
            assert!((v / want - 1.0).abs() < 1e-6, "{row}: want {want}");
        }
    }
}
