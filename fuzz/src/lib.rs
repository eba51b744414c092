//! The property both fuzz targets check: arbitrary bytes either fail to load with an error, or
//! load into a photometry whose every derived quantity is finite and non-negative.

use lumiview::photometry::{load_from_text, text::decode, LoadOptions, Photometry};

/// Angles (C, γ) in degrees to sample: grid-ish, off-grid, out of range and non-finite.
const ANGLES: [(f64, f64); 14] = [
    (0.0, 0.0),
    (0.0, 90.0),
    (45.0, 37.5),
    (90.0, 180.0),
    (179.9, 89.9),
    (270.0, 120.0),
    (359.999_999, 45.0),
    (360.0, 45.0),
    (-30.0, 60.0),
    (725.0, 10.0),
    (12.0, -5.0),
    (12.0, 200.0),
    (1e300, 1e300),
    (-1e300, 5.0),
];

const NON_FINITE: [f64; 3] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];

fn finite_non_negative(what: &str, v: f64) {
    assert!(v.is_finite() && v >= 0.0, "{what} = {v}");
}

/// Decodes `data`, loads it under `name` (the extension picks the reader) and, when it loads,
/// checks the property. Panics (a fuzzer finding) when the property fails.
pub fn check(data: &[u8], name: &str) {
    let text = decode(data.to_vec());
    let Ok(p) = load_from_text(&text, name, &LoadOptions::default()) else {
        return;
    };
    check_photometry(&p);
    // A file with a TILT table: apply it at a few lamp tilts (inside, between and beyond its angles).
    if let Some(t) = &p.tilt {
        let first = t.angles_deg.first().copied().unwrap_or(0.0);
        for tilt in [first - 10.0, first + 7.5, 90.0] {
            let opts = LoadOptions {
                tilt_deg: Some(tilt),
                ..LoadOptions::default()
            };
            if let Ok(q) = load_from_text(&text, name, &opts) {
                check_photometry(&q);
            }
        }
    }
}

/// Asserts that everything derived from a loaded photometry is finite and ≥ 0.
pub fn check_photometry(p: &Photometry) {
    let web = &p.web;
    for &(c, g) in &ANGLES {
        finite_non_negative("sample", web.sample(c, g));
        if let Some(l) = p.luminance(c, g) {
            finite_non_negative("luminance", l);
        }
        // NaN is tolerated here (∞ × 0 from absurd opening sizes): `luminance` reads it as no area.
        let a = p.opening.projected_area(c, g);
        assert!(a >= 0.0 || a.is_nan(), "projected area = {a}");
    }
    for &x in &NON_FINITE {
        for (c, g) in [(x, 45.0), (45.0, x), (x, x)] {
            finite_non_negative("sample at a non-finite angle", web.sample(c, g));
            if let Some(l) = p.luminance(c, g) {
                finite_non_negative("luminance at a non-finite angle", l);
            }
        }
        finite_non_negative("sample_dir", web.sample_dir([x, 0.0, -1.0]));
    }
    finite_non_negative("sample_dir", web.sample_dir([0.3, -0.2, -1.0]));
    finite_non_negative("flux", web.flux());
    finite_non_negative("flux_lm", p.flux_lm());
    finite_non_negative("downward flux", web.flux_between(0.0, 90.0));
    let (max, c, g) = web.max_intensity();
    finite_non_negative("max intensity", max);
    assert!(c.is_finite() && g.is_finite(), "max intensity at ({c}, {g})");
    if let Some(lor) = p.integrated_lor() {
        finite_non_negative("integrated LOR", lor);
    }
    for v in web.values() {
        finite_non_negative("grid value", *v);
    }
    if let Some(t) = &p.tilt {
        for a in [-90.0, 0.0, 12.5, 45.0, 90.0, 180.0] {
            finite_non_negative("TILT factor", t.factor_at(a));
        }
    }
}
