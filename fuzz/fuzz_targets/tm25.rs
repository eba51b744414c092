//! Arbitrary bytes through the IES TM-25 ray-file reader (`cargo fuzz run tm25`).
//!
//! Property: reading either fails with an error, or every ray has a finite position, a unit
//! direction and finite, non-negative fluxes, and the summary statistics are finite. A panic, an
//! abort or an allocation beyond the input's size is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lumiview::nearfield::tm25::RayFile;

fuzz_target!(|data: &[u8]| {
    let Ok(f) = RayFile::from_bytes(data, "fuzz.tm25ray") else {
        return;
    };
    assert_eq!(f.len() as u64, f.header().ray_count);
    for r in f.rays() {
        assert!(r.position_m.is_finite(), "position {:?}", r.position_m);
        assert!((r.direction.length() - 1.0).abs() < 1e-9, "direction {:?}", r.direction);
        for v in [r.luminous_lm, r.radiant_w].into_iter().flatten() {
            assert!(v.is_finite() && v >= 0.0, "flux {v}");
        }
    }
    let s = f.stats();
    assert!(s.bbox_min_m.is_finite() && s.bbox_max_m.is_finite() && s.mean_direction.is_finite());
    for t in &f.header().spectral_tables {
        if let Some(k) = t.luminous_efficacy() {
            assert!(k.is_finite() && k >= 0.0, "efficacy {k}");
        }
    }
});
