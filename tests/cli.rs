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
