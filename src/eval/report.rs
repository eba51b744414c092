//! What the harness reports: the results of one mode ([`ModeReport`]) and of one luminaire
//! ([`LuminaireReport`]), the table `lumiview eval` prints with each luminaire's verdict
//! ([`format_table`]), and a view written as render | reference | error ([`write_triptych`]).

use std::path::Path;

use super::metrics::SetMetrics;
use super::verdict::{reconstructed_verdict, verdict, NO_THRESHOLD};

/// Results of one mode on one luminaire.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModeReport {
    /// The mode's label.
    pub mode: String,
    /// Views outside the capture sphere.
    pub outside: SetMetrics,
    /// Views inside it.
    pub inside: SetMetrics,
    /// Held-out capture cameras.
    pub held_out: SetMetrics,
    /// Median relative intensity error over the direction grid.
    pub intensity_median: f64,
    /// Largest relative intensity error.
    pub intensity_max: f64,
    /// Relative flux error against the same quadrature of the ray-caster's orthographic intensities.
    pub flux_error: f64,
    /// Largest excess change per sweep step (render change − reference change), as a fraction.
    pub jump: f64,
    /// The least and the most light the mode draws in a sweep frame, as fractions of the
    /// reference's, over the pixels the jump sums (Σ R_k / Σ T_k; NaN for a dark sweep): a mode that
    /// draws under 1 % of it in every frame has no jump to compare (docs/quality-metrics.md,
    /// change 9).
    pub sweep_light: (f64, f64),
    /// Index of the worst outside view (by log RMSE or, lacking it, silhouette).
    pub worst_view: Option<usize>,
}

/// Results on one luminaire.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LuminaireReport {
    /// The luminaire.
    pub name: String,
    /// Capture cameras (after holding out 10 %).
    pub cameras: usize,
    /// Capture image side (px).
    pub capture_px: u32,
    /// Capture pitch at the centre (mm).
    pub pitch_mm: f64,
    /// View pitch at the luminaire's centre (mm): the capture pitch, or finer where the capture cap
    /// leaves the smallest feature under 6 pixels.
    pub view_pitch_mm: f64,
    /// Notes (relaxed rules, moved eyes).
    pub notes: Vec<String>,
    /// The reference quadrature's own flux error against the closed form (point sampling + directions).
    pub quadrature_flux_error: f64,
    /// Per mode.
    pub modes: Vec<ModeReport>,
}

fn fmt_opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("n/a".into(), |x| format!("{:.*}", digits, x * scale))
}

/// The reports as a text table (one row per luminaire and mode).
pub fn format_table(reports: &[LuminaireReport]) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<11} {:<20} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>7} {:>7}\n",
        "luminaire",
        "mode",
        "logRMSE",
        "med%",
        "p95%",
        "sil px",
        "in lRMSE",
        "in med%",
        "dbl%",
        "held lR",
        "I med%",
        "I max%",
        "flux%",
        "jump%",
        "swp lt%"
    ));
    for rep in reports {
        for m in &rep.modes {
            s.push_str(&format!(
                "{:<11} {:<20} {:>8} {:>8} {:>8} {:>8.2} {:>8} {:>8} {:>8} {:>8} {:>8.3} {:>8.3} {:>8.3} {:>7.3} {:>7.1}\n",
                rep.name,
                m.mode,
                fmt_opt(m.outside.log_rmse, 1.0, 4),
                fmt_opt(m.outside.median_rel, 100.0, 3),
                fmt_opt(m.outside.p95_rel, 100.0, 2),
                m.outside.silhouette_px,
                fmt_opt(m.inside.log_rmse, 1.0, 4),
                fmt_opt(m.inside.median_rel, 100.0, 3),
                fmt_opt(m.inside.doubled, 100.0, 2),
                fmt_opt(m.held_out.log_rmse, 1.0, 4),
                m.intensity_median * 100.0,
                m.intensity_max * 100.0,
                m.flux_error * 100.0,
                m.jump * 100.0,
                m.sweep_light.1 * 100.0,
            ));
        }
        s.push_str(&format!(
            "{:<11} ({} cameras, {}² px, {:.3} mm pitch, views {:.3} mm; views measured outside/inside/held-out {}; quadrature flux error {:.3} %{})\n",
            "",
            rep.cameras,
            rep.capture_px,
            rep.pitch_mm,
            rep.view_pitch_mm,
            rep.modes.first().map_or(String::from("-"), |m| {
                let f = |s: &SetMetrics| format!("{}/{}", s.views, s.views + s.unmeasured);
                format!("{} {} {}", f(&m.outside), f(&m.inside), f(&m.held_out))
            }),
            rep.quadrature_flux_error * 100.0,
            if rep.notes.is_empty() {
                String::new()
            } else {
                format!("; {}", rep.notes.join("; "))
            }
        ));
        if let Some(v) = verdict(rep) {
            let mut line = if v.failures.is_empty() {
                "contract met by continuous+proxy".to_string()
            } else {
                format!("contract NOT met: {}", v.failures.join("; "))
            };
            if !v.ties.is_empty() {
                line.push_str(&format!("; ties with nearest within 2⁻¹¹: {}", v.ties.join(", ")));
            }
            if !v.not_compared.is_empty() {
                line.push_str(&format!("; not compared: {}", v.not_compared.join(", ")));
            }
            s.push_str(&format!("{:<11} {line}\n", ""));
        } else if rep.name == NO_THRESHOLD {
            s.push_str(&format!("{:<11} no threshold (reported only)\n", ""));
        }
        if let Some(v) = reconstructed_verdict(rep) {
            let line = if v.failures.is_empty() {
                "contract met by continuous+rec-proxy".to_string()
            } else {
                format!("contract NOT met by continuous+rec-proxy: {}", v.failures.join("; "))
            };
            s.push_str(&format!("{:<11} {line}\n", ""));
        }
        if let Some(line) = reconstructed_against_true(rep) {
            s.push_str(&format!("{:<11} {line}\n", ""));
        }
    }
    s
}

/// Each figure of `continuous+rec-proxy` over the same figure of `continuous+proxy` (issue 17 asks
/// for ≤ 1.5), where both were measured.
fn reconstructed_against_true(rep: &LuminaireReport) -> Option<String> {
    let find = |label: &str| rep.modes.iter().find(|m| m.mode == label);
    let (t, r) = (find("continuous+proxy")?, find("continuous+rec-proxy")?);
    let figures: [(&str, Option<f64>, Option<f64>); 7] = [
        ("logRMSE", t.outside.log_rmse, r.outside.log_rmse),
        ("med%", t.outside.median_rel, r.outside.median_rel),
        ("in lRMSE", t.inside.log_rmse, r.inside.log_rmse),
        ("dbl%", t.inside.doubled, r.inside.doubled),
        ("I med%", Some(t.intensity_median), Some(r.intensity_median)),
        ("flux%", Some(t.flux_error), Some(r.flux_error)),
        ("jump%", Some(t.jump), Some(r.jump)),
    ];
    let parts: Vec<String> = figures
        .iter()
        .map(|&(name, t, r)| match (t, r) {
            (Some(t), Some(r)) if t > 0.0 => format!("{name} ×{:.2}", r / t),
            (Some(_), Some(0.0)) => format!("{name} = (both 0)"),
            (Some(_), Some(_)) => format!("{name} ×∞ (true proxy 0)"),
            _ => format!("{name} n/a"),
        })
        .collect();
    Some(format!("reconstructed / true proxy: {}", parts.join(", ")))
}

/// Writes render | reference | relative error (red = render too bright, blue = too dark, full at
/// ±10 %) side by side as an 8-bit PNG; luminance is shown on a log scale over 4 decades below the
/// reference maximum.
pub fn write_triptych(path: &Path, render: &[f32], reference: &[f32], w: usize, h: usize) -> std::io::Result<()> {
    let lmax = reference.iter().cloned().fold(0.0f32, f32::max).max(1e-30);
    let tone = |v: f32| -> u8 {
        if v <= 0.0 {
            return 0;
        }
        let t = ((v / lmax).log10() + 4.0) / 4.0;
        (t.clamp(0.0, 1.0) * 255.0) as u8
    };
    let mut rgb = vec![0u8; 3 * w * 3 * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (a, b) = (render[i], reference[i]);
            let row = y * 3 * w;
            let ta = tone(a);
            let tb = tone(b);
            rgb[3 * (row + x)..3 * (row + x) + 3].copy_from_slice(&[ta, ta, ta]);
            rgb[3 * (row + w + x)..3 * (row + w + x) + 3].copy_from_slice(&[tb, tb, tb]);
            let e = if b > 1e-3 * lmax { (a - b) / b } else { 0.0 };
            let m = ((e.abs() / 0.1).min(1.0) * 255.0) as u8;
            let px = if e > 0.0 { [m, 0, 0] } else { [0, 0, m] };
            rgb[3 * (row + 2 * w + x)..3 * (row + 2 * w + x) + 3].copy_from_slice(&px);
        }
    }
    let f = std::fs::File::create(path)?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(f), 3 * w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header().map_err(std::io::Error::other)?;
    wr.write_image_data(&rgb).map_err(std::io::Error::other)?;
    Ok(())
}
