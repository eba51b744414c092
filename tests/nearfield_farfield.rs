//! The far field of a near-field scan (`nearfield::farfield`) against the synthetic luminaires' closed
//! forms: flux, and intensity over the directions holding ≥ 1 % of the peak, against the raw truth and
//! the truth convolved with the estimator's kernel. `cargo test --release --test nearfield_farfield
//! -- --nocapture` prints the table of docs/scene-lighting.md; `FF=CAMERAS,PX` sets the scans'
//! Fibonacci camera count and image size (default 1500, 48), `FFBW=DEG` the kernel's width.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use lumiview::nearfield::farfield::{FarField, FarFieldOptions};
use lumiview::nearfield::layout::Layout;
use lumiview::nearfield::raykde::bandwidth::fibonacci;
use lumiview::nearfield::synth::scan::{synth_scan, SynthOptions};
use lumiview::nearfield::synth::{luminaire, Luminaire};
use lumiview::photometry::web::angles_of;

fn percentile(mut v: Vec<f64>, p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

impl Row {
    /// The row of the docs' table.
    fn print(&self) {
        println!(
            "| {} | {:.2} | {:+.2} % | {:.2} % / {:.2} % | {:.2} % / {:.2} % |",
            self.name,
            self.sigma_deg,
            100.0 * self.flux_err,
            100.0 * self.median_kernel,
            100.0 * self.p95_kernel,
            100.0 * self.median_raw,
            100.0 * self.p95_raw
        );
    }
}

struct Row {
    name: String,
    sigma_deg: f64,
    flux_err: f64,
    median_kernel: f64,
    p95_kernel: f64,
    median_raw: f64,
    p95_raw: f64,
}

fn measure(name: &str, layout: Layout, px: u32) -> Row {
    let lum: Box<dyn Luminaire> = luminaire(name).unwrap();
    let s = synth_scan(&SynthOptions {
        luminaire: name.into(),
        layout,
        size: (px, px),
        supersample: 2,
        ..SynthOptions::default()
    })
    .unwrap();
    let opts = FarFieldOptions {
        bandwidth_deg: std::env::var("FFBW").ok().map(|v| v.parse().unwrap()),
        ..FarFieldOptions::default()
    };
    let ff = FarField::estimate(&s.set, s.source.as_ref(), &opts, &|_| {}).unwrap();
    // The truth on 40,000 directions, each worth 4π/40,000 sr, for the convolution.
    let fine = fibonacci(40_000);
    let truth: Vec<f64> = fine.iter().map(|d| lum.intensity_cd(*d)).collect();
    let w = 4.0 * std::f64::consts::PI / fine.len() as f64;
    let sigma = ff.bandwidth_deg.to_radians();
    let kappa = 1.0 / (sigma * sigma);
    let norm = kappa / (2.0 * std::f64::consts::PI * (1.0 - (-2.0 * kappa).exp()));
    let peak = truth.iter().copied().fold(0.0, f64::max);
    let (mut raw, mut kern) = (Vec::new(), Vec::new());
    for d in fibonacci(3000) {
        let t = lum.intensity_cd(d);
        let conv: f64 = fine
            .iter()
            .zip(&truth)
            .map(|(f, i)| {
                let c = d.dot(*f);
                if c < (4.0 * sigma).cos() {
                    0.0
                } else {
                    i * w * norm * (kappa * (c - 1.0)).exp()
                }
            })
            .sum();
        let (c, g) = angles_of(d.to_array());
        let got = ff.intensity(c, g);
        if t >= 0.01 * peak {
            raw.push((got / t - 1.0).abs());
        }
        if conv >= 0.01 * peak {
            kern.push((got / conv - 1.0).abs());
        }
    }
    Row {
        name: name.into(),
        sigma_deg: ff.bandwidth_deg,
        flux_err: ff.flux_lm / lum.flux_lm() - 1.0,
        median_kernel: percentile(kern.clone(), 0.5),
        p95_kernel: percentile(kern, 0.95),
        median_raw: percentile(raw.clone(), 0.5),
        p95_raw: percentile(raw, 0.95),
    }
}

/// The far field of the scans of six luminaires whose images resolve them (48 px over the
/// luminaire: 7 mm pixels) against their closed forms: flux within 1 %, intensity against the
/// kernel-matched truth within 1.5 % median and 7 % at the 95th percentile (measured: ≤ 0.66 % and
/// ≤ 6.5 %, docs/scene-lighting.md). Three with features near the pixel size (strips, LED dots, a
/// 5 mm peak) are printed, not held: their error is the images' sampling, not the estimator's (it
/// falls from 5.8 % to 2.1 % median for the LED dots at 96 px). Three of them again from a meridian
/// layout, as a goniophotometer's: the same limits but 10 % at the 95th percentile (measured ≤ 7.3 %:
/// the disc's grazing directions, where its rows are 6° apart).
#[test]
fn scans_far_fields_match_the_closed_forms() {
    let (cams, px): (usize, u32) = std::env::var("FF")
        .ok()
        .and_then(|v| {
            let mut it = v.split(',').map(|x| x.parse::<f64>().unwrap());
            Some((it.next()? as usize, it.next()? as u32))
        })
        .unwrap_or((1500, 48));
    let held = ["disc", "rect", "star-panel", "two-planes", "cos10", "cos100"];
    let shown = ["strips", "led-dots", "peak"];
    println!("{cams} Fibonacci cameras, {px} × {px} px, 2 × 2 rays a pixel");
    println!("| luminaire | σ (°) | flux error | median / p95 vs kernel-matched | median / p95 vs raw |");
    println!("|---|---|---|---|---|");
    let mut failures = Vec::new();
    for n in held.iter().chain(&shown) {
        let r = measure(n, Layout::Fibonacci { count: cams }, px);
        r.print();
        if held.contains(n) && (r.flux_err.abs() > 0.01 || r.median_kernel > 0.015 || r.p95_kernel > 0.07) {
            failures.push(r.name);
        }
    }
    // A meridian layout as the goniophotometer's (crowded poles, rows 6° apart): the quadrature
    // normalisation keeps the pole unbiased.
    println!("rigo, 750 cameras per hemisphere, {px} × {px} px");
    for n in ["disc", "two-planes", "cos10"] {
        let layout = Layout::Rigo {
            per_hemisphere: 750,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        };
        let r = measure(n, layout, px);
        r.print();
        if r.flux_err.abs() > 0.01 || r.median_kernel > 0.015 || r.p95_kernel > 0.1 {
            failures.push(r.name);
        }
    }
    assert!(failures.is_empty(), "outside the limits: {failures:?}");
}
