//! What every part of the look-up table and solid tests uses: the fixtures (the two real files and
//! the photometric-viewer set), opening one, a temporary path, and running the `lumiview` binary.

use std::path::{Path, PathBuf};
use std::process::Command;

use lumiview::photometry::{load, LoadOptions, Photometry};

pub(crate) const ASA: &str = "tests/data/misc/luxcore_ASA_15M_R2.ies";
pub(crate) const BEGA: &str = "tests/data/misc/arnold-usd_bega_50804K3.ies";

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub(crate) fn open(rel: &str) -> Photometry {
    load(&data(rel), &LoadOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Every fixture: the two real files and the photometric-viewer set.
pub(crate) fn fixtures() -> Vec<String> {
    let mut out = vec![ASA.to_string(), BEGA.to_string()];
    for dir in [
        "tests/data/photometric-viewer/ies95",
        "tests/data/photometric-viewer/ldt",
    ] {
        let mut names: Vec<String> = std::fs::read_dir(data(dir))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".ies") || n.ends_with(".ldt"))
            .collect();
        names.sort();
        out.extend(names.into_iter().map(|n| format!("{dir}/{n}")));
    }
    assert!(out.len() > 30, "fixtures missing: {out:?}");
    out
}

pub(crate) fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("lut_solid_{name}"))
}

pub(crate) fn lumiview(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}
