//! The `lumiview` command line: output forms the issue fixes (JSON shapes, defaults) and errors
//! that name the file or argument.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::{Command, Output};

fn lumiview(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = lumiview(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

const ASA: &str = "tests/data/misc/luxcore_ASA_15M_R2.ies";

#[test]
fn info_json_has_the_summary_fields() {
    let v = json(&["info", ASA, "--json"]);
    assert_eq!(v["format"], "IES LM-63-2002");
    assert_eq!(v["photometric_type"], "C");
    assert_eq!(v["symmetry"], "C0C180");
    assert_eq!(v["grid"]["native_horizontal"], 73);
    assert_eq!(v["grid"]["native_vertical"], 37);
    assert_eq!(v["lamp_flux_lm"], 13000.0);
    assert_eq!(v["multiplier"], 1.0);
    let flux = v["integrated_flux_lm"].as_f64().unwrap();
    assert!((flux - 9560.83).abs() < 1.0, "{flux}");
    assert!(v["max_intensity_cd"].as_f64().unwrap() > 5000.0);
    assert_eq!(v["opening"]["shape"], "Rectangle");
    assert!((v["opening"]["size_x_m"].as_f64().unwrap() - 1.24 * 0.3048).abs() < 1e-9);
    assert!(v["labels"].as_array().unwrap().iter().any(|l| l["key"] == "MANUFAC"));
    // The text form carries the same facts.
    let text = String::from_utf8(lumiview(&["info", ASA]).stdout).unwrap();
    for want in [
        "IES LM-63-2002",
        "C0C180",
        "13000.0 lm",
        "integrated flux",
        "Rectangle",
        "American Electric",
    ] {
        assert!(text.contains(want), "missing `{want}` in:\n{text}");
    }
}

#[test]
fn sample_json_form() {
    let v = json(&[
        "sample", ASA, "--at", "0,0", "--at", "90,62.5", "--at", "0,120", "--json",
    ]);
    assert_eq!(v["unit"], "cd");
    let s = v["samples"].as_array().unwrap();
    assert_eq!(s.len(), 3);
    assert_eq!(s[1]["c"], 90.0);
    assert_eq!(s[1]["gamma"], 62.5);
    assert!(s[0]["cd"].as_f64().unwrap() > 0.0);
    assert_eq!(s[2]["cd"], 0.0, "nothing above the measured 0–90° range");
    assert_eq!(v.as_object().unwrap().len(), 2);
}

#[test]
fn luminance_json_defaults_to_the_glare_grid() {
    let v = json(&["luminance", ASA, "--json"]);
    assert_eq!(v["unit"], "cd/m2");
    let c: Vec<f64> = v["c"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let g: Vec<f64> = v["gamma"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(c.len(), 24);
    assert_eq!((c[0], c[23]), (0.0, 345.0));
    assert_eq!(g, vec![65.0, 70.0, 75.0, 80.0, 85.0]);
    let table = v["table"].as_array().unwrap();
    assert_eq!(table.len(), 5);
    assert_eq!(table[0].as_array().unwrap().len(), 24);
    // table[i][j] is for gamma[i], c[j]: a flat 0.378 m square seen at γ = 70°, C = 90°.
    let s = json(&["sample", ASA, "--at", "90,70", "--json"]);
    let i = s["samples"][0]["cd"].as_f64().unwrap();
    let a = (1.24f64 * 0.3048).powi(2) * 70f64.to_radians().cos();
    let l = table[1][6].as_f64().unwrap();
    assert!((l - i / a).abs() < 1e-6 * l, "{l} vs {}", i / a);
}

#[test]
fn errors_name_the_file_or_argument_and_fail() {
    let out = lumiview(&["info", "tests/data/nope.ies"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("tests/data/nope.ies"));
    let out = lumiview(&["sample", ASA, "--at", "10"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--at `10`"));
    let out = lumiview(&["sample", ASA, "--at", "10,200"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("GAMMA"));
    let out = lumiview(&["luminance", "tests/data/photometric-viewer/ies95/point_opening.ies"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("point"));
    let out = lumiview(&["luminance", ASA, "--c", "0:345:0.01", "--gamma", "0:180:0.01"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("at most 1000000"));
    let out = lumiview(&["luminance", ASA, "--c", "0:10"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--c `0:10`"));
}

// ---- Issue 15: the first hour with the CLI. Each test failed before its fix. ----

fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn eulumdat_labels_are_separated_from_their_values() {
    // "luminaire number" is 16 characters: it ran into its value ("luminaire numberPAIR-1").
    let out = lumiview(&["info", "tests/data/pairs/full.ldt"]);
    let text = String::from_utf8(out.stdout).unwrap();
    let line = text.lines().find(|l| l.contains("luminaire number")).unwrap();
    assert!(line.contains("luminaire number PAIR-1"), "{line}");
}

#[test]
fn options_that_do_not_apply_are_errors_naming_them() {
    // --tilt on a TILT=NONE file was silently ignored.
    let out = lumiview(&["info", ASA, "--tilt", "30"]);
    assert!(!out.status.success());
    let e = stderr_of(&out);
    assert!(
        e.contains("--tilt") && e.contains("TILT=NONE") && e.contains(ASA),
        "{e}"
    );
    // On an EULUMDAT file too.
    let out = lumiview(&["sample", "tests/data/pairs/full.ldt", "--at", "0,0", "--tilt", "10"]);
    assert!(!out.status.success() && stderr_of(&out).contains("--tilt"));
    // --lamp-set on an IES file.
    let out = lumiview(&["info", ASA, "--lamp-set", "2"]);
    assert!(!out.status.success() && stderr_of(&out).contains("--lamp-set"));
    // --housing on an IES file (checked before the GPU starts).
    let out = lumiview(&["render", ASA, "--housing", "-o", "/tmp/lumiview-housing.png"]);
    assert!(!out.status.success());
    let e = stderr_of(&out);
    assert!(e.contains("--housing") && e.contains("IES files have none"), "{e}");
    // PNG-only options on an EXR.
    let out = lumiview(&["render", ASA, "--legend", "-o", "/tmp/lumiview-legend.exr"]);
    assert!(!out.status.success() && stderr_of(&out).contains("--legend applies to .png"));
    // A bad exposure names itself.
    let out = lumiview(&["render", ASA, "--exposure", "-1", "-o", "/tmp/lumiview-e.png"]);
    assert!(!out.status.success() && stderr_of(&out).contains("--exposure"));
}

#[test]
fn implausible_files_are_flagged_in_info() {
    // LORL 5999 %: `warnings: []` before.
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pairs/full.ldt")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut bad = lines.clone();
    bad[22] = "5999"; // line 23: light output ratio LORL, %
    let path = std::env::temp_dir().join(format!("lumiview-lor-{}.ldt", std::process::id()));
    std::fs::write(&path, bad.join("\r\n")).unwrap();
    let v = json(&["info", path.to_str().unwrap(), "--json"]);
    let w = v["warnings"].as_array().unwrap();
    assert!(w.iter().any(|w| w.as_str().unwrap().contains("5999.0 %")), "{w:?}");
    assert!(w
        .iter()
        .all(|w| w.as_str().unwrap().starts_with(path.to_str().unwrap())));
    let _ = std::fs::remove_file(&path);
}

#[test]
fn cameras_of_a_ray_file_are_its_virtual_scans() {
    // It said "manifest JSON: expected value at line 1 column 1".
    let out = lumiview(&["cameras", "tests/data/raysets/Cyl10k.1.tm25ray", "--json"]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    assert!(stderr_of(&out).contains("TM-25 ray file"));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["cameras"].as_u64().unwrap() > 0);
    let out = lumiview(&["cameras", ASA]);
    assert!(!out.status.success() && stderr_of(&out).contains("not a near-field scan"));
}

#[test]
fn a_folder_gives_one_table_and_continues_past_a_bad_file() {
    let dir = std::env::temp_dir().join(format!("lumiview-folder-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::copy(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/",
            "tests/data/misc/luxcore_ASA_15M_R2.ies"
        ),
        dir.join("a.ies"),
    )
    .unwrap();
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pairs/full.ldt"),
        dir.join("sub/b.LDT"),
    )
    .unwrap();
    std::fs::write(dir.join("c.ies"), "not photometry").unwrap();
    std::fs::write(dir.join("notes.txt"), "ignored").unwrap();
    let out = lumiview(&["info", dir.to_str().unwrap()]);
    assert!(!out.status.success(), "the bad file makes the exit status non-zero");
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert!(rows[0].starts_with("file,format,luminaire,"), "{text}");
    assert_eq!(rows.len(), 4, "{text}");
    assert!(rows
        .iter()
        .any(|r| r.contains("c.ies") && r.ends_with(|c: char| c != ',')));
    assert!(stderr_of(&lumiview(&["info", dir.to_str().unwrap()])).contains("c.ies"));
    // JSON lines, one per file.
    let out = lumiview(&["info", dir.to_str().unwrap(), "--json"]);
    let objects: Vec<serde_json::Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(objects.len(), 3);
    assert!(objects.iter().any(|o| o["error"].is_string()));
    // luminance over the folder: file,c_deg,gamma_deg,luminance_cd_m2.
    let out = lumiview(&["luminance", dir.to_str().unwrap(), "--c", "0:90:90", "--gamma", "0:0:1"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.starts_with("file,c_deg,gamma_deg,luminance_cd_m2,error\n"),
        "{text}"
    );
    assert_eq!(text.lines().count(), 1 + 2 * 2 + 1, "{text}");
    assert!(text.lines().any(|l| l.contains("c.ies") && !l.ends_with(',')), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_demo_shows_its_build() {
    // The README's demo printed nothing for 11 minutes while it built.
    let demo = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/demo")).unwrap();
    for line in demo
        .lines()
        .filter(|l| l.trim_start().starts_with("cargo build") || l.contains("cmake --build"))
    {
        assert!(!line.contains("--quiet") && !line.contains("/dev/null"), "{line}");
    }
}

#[test]
fn synth_forward_traces_a_ray_file_that_reads_back() {
    let dir = std::env::temp_dir().join(format!("lumiview-synth-rays-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("disc.tm25ray");
    let p = path.to_str().unwrap();
    let out = lumiview(&["synth", "disc", "--rays", "2e3", "--seed", "4", "-o", p]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("2000 rays"));
    let v = json(&["info", p, "--json"]);
    let text = v.to_string();
    assert!(text.contains("2000"), "{text}");
    // A ray file needs an output, of the right kind; a count is a number.
    for (args, want) in [
        (vec!["synth", "disc", "--rays", "2e3"], "-o FILE.tm25ray"),
        (vec!["synth", "disc", "--rays", "2e3", "-o", "x.png"], "x.png"),
        (vec!["synth", "disc", "--rays", "many", "-o", p], "--rays 'many'"),
    ] {
        let out = lumiview(&args);
        assert!(
            !out.status.success() && stderr_of(&out).contains(want),
            "{args:?}: {}",
            stderr_of(&out)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A point source (no opening) of 1000 cd in every direction, written to a temporary file.
fn isotropic_point_source(name: &str) -> std::path::PathBuf {
    let p = std::env::temp_dir().join(format!("lumiview-cli-{}-{name}.ies", std::process::id()));
    std::fs::write(
        &p,
        "IESNA:LM-63-2002\n[TEST] isotropic point\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 90 180\n0\n1000 1000 1000\n",
    )
    .unwrap();
    p
}

#[test]
fn scene_grid_is_the_inverse_square_law_where_nothing_is_in_the_way() {
    // One 1000 cd point source 1.75 m above a work plane at 1.2 m in the sample office, over the
    // free middle of the room: E = I cos³γ / h², written here, independent of the tracer.
    let ies = isotropic_point_source("grid");
    let csv = std::env::temp_dir().join(format!("lumiview-cli-{}-grid.csv", std::process::id()));
    let lum = format!("{}@0.1,2.95,-0.2,30", ies.display());
    let out = lumiview(&[
        "scene",
        "assets/scenes/office.glb",
        "--luminaire",
        &lum,
        "--grid",
        "1.2",
        "--grid-rect",
        "-1,-1,1,1",
        "--spacing",
        "0.25",
        "--direct-only",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x_m,y_m,z_m,E_lx"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 64, "8 × 8 cells of 0.25 m");
    let mut e_all = Vec::new();
    for r in &rows {
        let (dx, dz, h) = (r[0] - 0.1, r[2] + 0.2, 2.95 - r[1]);
        let d2 = dx * dx + dz * dz + h * h;
        let cos = h / d2.sqrt();
        let want = 1000.0 * cos * cos * cos / (h * h);
        assert!((r[3] - want).abs() <= 0.001 + 1e-6 * want, "{r:?}: want {want}");
        e_all.push(r[3]);
    }
    // The printed figures are the grid's.
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let (min, max) = e_all.iter().fold((f64::MAX, 0.0f64), |(a, b), &e| (a.min(e), b.max(e)));
    let avg = e_all.iter().sum::<f64>() / e_all.len() as f64;
    assert!(stdout.contains("8 × 8 points"), "{stdout}");
    assert!(stdout.contains(&format!("U0 = Emin/Ē {:.3}", min / avg)), "{stdout}");
    // Three significant digits, as a lighting report gives them.
    let three = |v: f64| {
        let decimals = (2 - v.log10().floor() as i32).clamp(0, 6) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    assert!(stdout.contains(&format!("Emax {} lx", three(max))), "{stdout}");
    assert!(stdout.contains(&format!("Ē {} lx", three(avg))), "{stdout}");
    assert!(
        stdout.contains("direct light with visibility (no inter-reflection)"),
        "{stdout}"
    );
    let _ = std::fs::remove_file(&csv);
    let _ = std::fs::remove_file(&ies);
}

#[test]
fn scene_grid_png_with_inter_reflection_is_brighter_and_shadowed_under_the_cabinet() {
    let ies = isotropic_point_source("png");
    let png = std::env::temp_dir().join(format!("lumiview-cli-{}-grid.png", std::process::id()));
    let lum = format!("{}@0,2.5,0", ies.display());
    let run = |extra: &[&str]| {
        let mut args = vec![
            "scene",
            "assets/scenes/office.glb",
            "--luminaire",
            &lum,
            "--grid",
            "0.75",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", png.to_str().unwrap()]);
        let out = lumiview(&args);
        assert!(out.status.success(), "{}", stderr_of(&out));
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let avg = |s: &str| -> f64 {
        let t = s.split("Ē ").nth(1).unwrap();
        t.split(' ').next().unwrap().parse().unwrap()
    };
    let direct = run(&["--direct-only", "--spacing", "0.5"]);
    let total = run(&["--paths", "64", "--spacing", "0.5"]);
    // Walls (0.5), ceiling (0.7) and floor reflect: the room's inter-reflection adds a large part.
    assert!(avg(&total) > 1.3 * avg(&direct), "{direct}\n{total}");
    // Inside the closed cabinet nothing arrives: Emin is 0.
    assert!(total.contains("Emin 0 lx"), "{total}");
    assert!(total.contains("64 paths per point"), "{total}");
    let pm = tiny_skia::Pixmap::load_png(&png).unwrap();
    assert_eq!(pm.width(), 900);
    let _ = std::fs::remove_file(&png);
    let _ = std::fs::remove_file(&ies);
}

#[test]
fn scene_options_that_do_not_apply_and_bad_placements_are_named() {
    let ies = ASA;
    let lum = format!("{ies}@0,2.9,0");
    let cases: [(&[&str], &str); 6] = [
        (&["--grid", "0.75", "-o", "/tmp/x.exr"], "must end in .csv or .png"),
        (&["-o", "/tmp/x.csv"], "a view must end in .png or .exr"),
        (
            &["--grid", "0.75", "--camera", "1,1,1", "-o", "/tmp/x.csv"],
            "--camera applies to a rendered view",
        ),
        (
            &["--spacing", "0.2", "-o", "/tmp/x.png"],
            "--spacing applies to the illuminance grid",
        ),
        (
            &["--grid", "0.75", "--grid-rect", "1,1,0,0", "-o", "/tmp/x.csv"],
            "--grid-rect '1,1,0,0'",
        ),
        (&["--grid", "0.75", "--spacing", "0", "-o", "/tmp/x.csv"], "--spacing"),
    ];
    for (extra, want) in cases {
        let mut args = vec!["scene", "assets/scenes/office.glb", "--luminaire", &lum];
        args.extend_from_slice(extra);
        let out = lumiview(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = stderr_of(&out);
        assert!(err.contains(want), "{args:?}: `{want}` not in {err}");
    }
    for (lum, want) in [
        (ies.to_string(), "no '@'"),
        (format!("{ies}@0,2.9"), "luminaire"),
        ("tests/data/fuzz/no-rays.tm25ray@0,2,0".to_string(), "no-rays.tm25ray"),
        ("missing.ies@0,2,0".to_string(), "missing.ies"),
    ] {
        let out = lumiview(&[
            "scene",
            "assets/scenes/office.glb",
            "--luminaire",
            &lum,
            "--grid",
            "1",
            "-o",
            "/tmp/x.csv",
        ]);
        assert!(!out.status.success(), "{lum}");
        let err = stderr_of(&out);
        assert!(err.contains(want), "{lum}: `{want}` not in {err}");
    }
    let out = lumiview(&[
        "scene",
        "missing.glb",
        "--luminaire",
        &lum,
        "--grid",
        "1",
        "-o",
        "/tmp/x.csv",
    ]);
    assert!(stderr_of(&out).contains("missing.glb"), "{}", stderr_of(&out));
}

/// A near-field scan lights a scene and converts to IES by its far field, estimated from its
/// images: the synthetic Lambertian disc (r = 0.1 m, 10,000 cd/m², facing down; Φ = π²·L·r² =
/// 986.96 lm) packed small; `convert` writes IES whose flux and nadir intensity are the disc's
/// (within 2 %), and `scene --grid` over the office puts E = L·π·r² / (r² + h²) under it (within
/// 3 %), both independent of the estimator.
#[test]
fn a_scan_converts_to_ies_and_lights_a_scene_by_its_far_field() {
    let dir = std::env::temp_dir().join(format!("lumiview-cli-scan-light-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pack = dir.join("disc.lvpack");
    let p = pack.to_str().unwrap();
    let out = lumiview(&[
        "pack",
        "--synth",
        "disc",
        "--layout",
        "fibonacci:600",
        "--size",
        "32x32",
        "--no-proxy",
        "-o",
        p,
    ]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let ies = dir.join("disc.ies");
    let out = lumiview(&["convert", p, "-o", ies.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    assert!(stderr_of(&out).contains("far field of the scan"), "{}", stderr_of(&out));
    let v = json(&["info", ies.to_str().unwrap(), "--json"]);
    let flux = v["integrated_flux_lm"].as_f64().unwrap_or_else(|| panic!("{v}"));
    let truth = std::f64::consts::PI.powi(2) * 10_000.0 * 0.01;
    assert!((flux / truth - 1.0).abs() < 0.02, "{flux} lm vs {truth}");
    let i0 = json(&["sample", ies.to_str().unwrap(), "--at", "0,0", "--json"])["samples"][0]["cd"]
        .as_f64()
        .unwrap();
    assert!((i0 / (truth / std::f64::consts::PI) - 1.0).abs() < 0.02, "I(0) {i0}");

    let csv = dir.join("grid.csv");
    let lum = format!("{p}@0,1.75,0");
    let out = lumiview(&[
        "scene",
        "assets/scenes/office.glb",
        "--luminaire",
        &lum,
        "--grid",
        "0.75",
        "--grid-rect",
        "-0.05,-0.05,0.05,0.05",
        "--spacing",
        "0.1",
        "--direct-only",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let text = std::fs::read_to_string(&csv).unwrap();
    let row: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let analytic = 10_000.0 * std::f64::consts::PI * 0.01 / 1.01;
    assert!((row[3] / analytic - 1.0).abs() < 0.03, "{row:?} vs {analytic} lx");
    let _ = std::fs::remove_dir_all(&dir);
}
