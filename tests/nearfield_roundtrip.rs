//! The whole near-field data path end to end: a synthetic scan (rigo layout, pole cameras included)
//! is written as a manifest + `.pf` images, imported, packed into a `.lvpack`, unpacked, and every
//! pixel of every camera is compared with the synthetic render within the pack's stated relative
//! quantisation bound — for the Lambertian disc and for the 10⁶ cd/m² peak beside 1 cd/m².

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use lumiview::nearfield::layout::Layout;
use lumiview::nearfield::manifest::{load_scan, write_scan, ImportOptions};
use lumiview::nearfield::pack::{write_pack, Pack, PackOptions, MAX_RELATIVE_ERROR};
use lumiview::nearfield::synth::{synth_scan, SynthOptions};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lumiview-roundtrip-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn round_trip(luminaire: &str) {
    let opts = SynthOptions {
        luminaire: luminaire.into(),
        layout: Layout::Rigo {
            per_hemisphere: 120,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        size: (96, 80),
        ..SynthOptions::default()
    };
    let truth = synth_scan(&opts).unwrap();
    let dir = tmp(luminaire);
    let manifest = write_scan(&dir, &truth, &|_, _| {}).unwrap();
    let imported = load_scan(&[manifest], &ImportOptions::default()).unwrap();
    assert_eq!(
        imported.set.cameras.len(),
        truth.set.cameras.len(),
        "no camera dropped (pole cameras included)"
    );
    let pack_path = dir.join("scan.lvpack");
    write_pack(&imported, &pack_path, &PackOptions::default(), &|_, _| {}).unwrap();
    let pack = Pack::open(&pack_path).unwrap();
    let mut nonzero = 0usize;
    let mut max_value = 0f32;
    let mut worst = 0f64;
    for i in 0..truth.set.cameras.len() {
        let want = truth.source.image(i).unwrap();
        let got = pack.decode_image(i).unwrap();
        assert_eq!((got.width, got.height), (want.width, want.height));
        for (k, (&v, &d)) in want.data.iter().zip(&got.data).enumerate() {
            if v == 0.0 {
                assert_eq!(d, 0.0, "{luminaire} camera {i} pixel {k}: zero became {d}");
                continue;
            }
            nonzero += 1;
            max_value = max_value.max(v);
            let rel = (f64::from(d) - f64::from(v)).abs() / f64::from(v);
            worst = worst.max(rel);
            assert!(
                rel <= MAX_RELATIVE_ERROR,
                "{luminaire} camera {i} pixel {k}: {v} cd/m² came back as {d} ({rel:e})"
            );
        }
    }
    assert!(
        nonzero > 1000,
        "{luminaire}: the scan sees the luminaire ({nonzero} lit pixels)"
    );
    eprintln!("{luminaire}: {nonzero} lit pixels, max {max_value} cd/m², worst relative error {worst:e} (bound {MAX_RELATIVE_ERROR:e})");
    if luminaire == "peak" {
        assert!(
            max_value >= 1e6 * 0.99,
            "the peak's 10⁶ cd/m² is in the scan ({max_value})"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn disc_scan_survives_manifest_import_and_pack() {
    round_trip("disc");
}

#[test]
fn peak_scan_survives_manifest_import_and_pack() {
    round_trip("peak");
}
