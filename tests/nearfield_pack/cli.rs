//! The `lumiview info` and `lumiview pack` commands: info and verify as JSON and text, repacking,
//! packing synthetic scans, manifests and ray files, and errors that name what is wrong.

use std::path::Path;
use std::process::Command;

use lumiview::nearfield::pack::{Pack, PackOptions};

use crate::common::{disc_image, pack, scan, tmp};

fn lumiview() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
}

#[test]
fn cli_info_and_repack() {
    let (path, stats) = pack(
        &scan((0..5).map(|i| disc_image(40, 30, i)).collect()),
        "cli.lvpack",
        &PackOptions::default(),
    );
    let out = lumiview()
        .args(["info", path.to_str().unwrap(), "--json", "--verify"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cameras"]["total"], 5);
    assert_eq!(v["tiles"]["kept"], stats.tiles_kept);
    assert_eq!(v["verify"]["ok"], true);
    assert!(v["footprint"]["ratio_to_csr"].as_f64().unwrap() > 0.0);
    assert!(v["sections"]
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s["name"] == "tile-tables"));
    let out = lumiview().args(["info", path.to_str().unwrap()]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("cameras") && text.contains("CSR"),
        "{text}"
    );

    // Repack with another tile size.
    let dst = tmp("cli-repack.lvpack");
    let out = lumiview()
        .args([
            "pack",
            path.to_str().unwrap(),
            "-o",
            dst.to_str().unwrap(),
            "--tile",
            "16",
            "--threshold",
            "0",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(Pack::open(&dst).unwrap().layout().tile_size, 16);

    // A corrupted page fails --verify with the section named.
    let mut bytes = std::fs::read(&path).unwrap();
    let off = Pack::open(&path).unwrap().page_section(0).unwrap().offset as usize;
    bytes[off + 9] ^= 4;
    let bad = tmp("cli-bad.lvpack");
    std::fs::write(&bad, &bytes).unwrap();
    let out = lumiview()
        .args(["info", bad.to_str().unwrap(), "--verify"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("page.0"));
}

#[test]
fn cli_packs_synthetic_scans_manifests_and_ray_files() {
    // --synth: the synthetic goniophotometer, streamed.
    let synth = tmp("cli-synth.lvpack");
    let out = lumiview()
        .args([
            "pack",
            "--synth",
            "disc",
            "--layout",
            "fibonacci:12",
            "--size",
            "64x48",
            "--quiet",
            "--json",
            "-o",
        ])
        .arg(&synth)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["images"], 12);
    assert!(v["tiles_kept"].as_u64().unwrap() > 0);
    let p = Pack::open(&synth).unwrap();
    assert_eq!((p.rayset().intrinsics.width, p.rayset().intrinsics.height), (64, 48));
    assert!(p.metadata().source.contains("disc"), "{}", p.metadata().source);

    // A scan manifest (written from the pack just made), packed again: the same pixels.
    let dir = tmp("cli-manifest");
    let _ = std::fs::remove_dir_all(&dir);
    let manifest =
        lumiview::nearfield::manifest::write_scan(&dir, &Pack::open(&synth).unwrap().into_scan(), &|_, _| {}).unwrap();
    let from_manifest = tmp("cli-manifest.lvpack");
    let out = lumiview()
        .arg("pack")
        .arg(&manifest)
        .arg("-o")
        .arg(&from_manifest)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let q = Pack::open(&from_manifest).unwrap();
    assert_eq!(q.rayset().cameras.len(), 12);
    for i in 0..12 {
        assert_eq!(q.decode_image(i).unwrap(), p.decode_image(i).unwrap(), "image {i}");
    }

    // A TM-25 ray file: its kernel estimate, stored with the hull of its ray origins (version 2).
    let rays = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/raysets/Cyl10k.1.tm25ray");
    let from_rays = tmp("cli-rays.lvpack");
    let out = lumiview()
        .arg("pack")
        .arg(&rays)
        .args(["--quiet", "-o"])
        .arg(&from_rays)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r = Pack::open(&from_rays).unwrap();
    assert!(r.image_count() >= 12);
    assert!(r.metadata().footprint.pixels_kept > 0);
    assert!(r.proxy().is_some_and(|p| p.bound && !p.triangles.is_empty()));
    // Repacking keeps the proxy; a camera layout for a ray file is refused (rays2scan sets it).
    let again = tmp("cli-rays-again.lvpack");
    let out = lumiview()
        .arg("pack")
        .arg(&from_rays)
        .args(["--quiet", "-o"])
        .arg(&again)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(Pack::open(&again).unwrap().proxy(), r.proxy());
    let out = lumiview()
        .arg("pack")
        .arg(&rays)
        .args(["--layout", "fibonacci:20", "-o"])
        .arg(tmp("x.lvpack"))
        .output()
        .unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--layout"));

    // Errors name what is wrong.
    for args in [
        vec!["pack", "-o", "x.lvpack"],
        vec![
            "pack",
            "--synth",
            "disc",
            "--tile",
            "0",
            "--layout",
            "fibonacci:2",
            "--size",
            "8x8",
            "-o",
            "x.lvpack",
        ],
        vec!["pack", "--synth", "disc", "--threshold", "rel:5", "-o", "x.lvpack"],
        vec!["pack", "--synth", "disc", "--page-mib", "129", "-o", "x.lvpack"],
        vec![
            "info",
            "--verify",
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/misc/luxcore_ASA_15M_R2.ies"),
        ],
    ] {
        let out = lumiview()
            .args(&args)
            .current_dir(env!("CARGO_TARGET_TMPDIR"))
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("error"), "{args:?}: {err}");
    }
}
