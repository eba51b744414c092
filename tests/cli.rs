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
