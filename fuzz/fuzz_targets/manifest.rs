//! Arbitrary bytes parsed as a scan manifest (`cargo fuzz run manifest`), with no image file
//! present: parsing and assembling a scan never panic. Cameras that parse are finite and valid;
//! assembling a scan whose image files do not exist fails with an error (also with
//! `skip_bad`, which drops every image).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lumiview::nearfield::manifest::{assemble_scan, parse_manifest, ImportOptions};
use lumiview::nearfield::RayImageSet;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("/nonexistent-lumiview-fuzz/scan/manifest.json");
    let Ok(m) = parse_manifest(data, path) else {
        return;
    };
    assert!(!m.entries.is_empty());
    let cameras: Vec<_> = m
        .entries
        .iter()
        .filter_map(|e| e.camera.as_ref().ok().cloned())
        .collect();
    for c in &cameras {
        assert!(c.validate().is_ok(), "a parsed camera is valid: {c:?}");
    }
    if !cameras.is_empty() {
        let set = RayImageSet {
            sphere: m.sphere,
            intrinsics: m.intrinsics,
            cameras,
        };
        assert!(set.validate().is_ok());
        let _ = set.coincident_groups(1e-6);
    }
    // Only when no named file exists (a name such as /dev/stdin must not be opened here).
    if m.entries.iter().all(|e| std::fs::symlink_metadata(&e.file).is_err()) {
        for skip_bad in [false, true] {
            let opts = ImportOptions {
                skip_bad,
                verify_pixels: false,
            };
            // A `Manifest` holds errors and is not `Clone`: parse it again.
            if let Ok(again) = parse_manifest(data, path) {
                assert!(assemble_scan(vec![again], &opts).is_err());
            }
        }
    }
});
