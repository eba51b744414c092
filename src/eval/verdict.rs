//! The quality contract's verdict on one luminaire's report (docs/quality-metrics.md, "Thresholds"):
//! continuous + proxy under the thresholds, with enough measured views, drawing the sweep's
//! light, and not worse than `nearest` on any metric ([`verdict`]); ties within [`TIE_FLOOR`].

use super::config::EvalMode;
use super::evaluate::RECONSTRUCTED_LABEL;
use super::report::LuminaireReport;

/// Where continuous + proxy and `nearest` both sit at the storage's quantisation (fp16 tiles: 2⁻¹¹
/// relative), "not worse" allows this much (docs/quality-metrics.md, "Thresholds").
pub const TIE_FLOOR: f64 = 1.0 / 2048.0;

/// The luminaire the contract reports without thresholds.
pub const NO_THRESHOLD: &str = "reflector";

/// How a luminaire's report stands against the quality contract (docs/quality-metrics.md,
/// "Thresholds"): continuous + proxy under the thresholds, with two measured views per
/// unmeasured one in each set, drawing the sweep's light, and not worse than `nearest` on any metric.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Verdict {
    /// What fails, one line each (empty: the contract is met).
    pub failures: Vec<String>,
    /// Metrics where continuous + proxy is worse than `nearest` by no more than [`TIE_FLOOR`].
    pub ties: Vec<String>,
    /// Comparisons that do not apply (change 9: a `nearest` that draws none of the sweep's light).
    pub not_compared: Vec<String>,
}

/// The contract's verdict on `rep`; `None` where it does not apply: the report lacks `nearest` or
/// continuous + proxy, or the luminaire is [`NO_THRESHOLD`].
pub fn verdict(rep: &LuminaireReport) -> Option<Verdict> {
    let find = |label: &str| rep.modes.iter().find(|m| m.mode == label);
    let (c, n) = (
        find(EvalMode::CONTINUOUS_PROXY.label().as_str())?,
        find(EvalMode::NEAREST.label().as_str())?,
    );
    if rep.name == NO_THRESHOLD {
        return None;
    }
    let mut v = Verdict::default();
    let mut below = |what: String, value: Option<f64>, limit: f64| match value {
        Some(x) if x < limit => {}
        Some(x) => v.failures.push(format!("{what} {x:.4} ≥ {limit}")),
        None => v.failures.push(format!("{what} n/a")),
    };
    for (set, what) in [
        (&c.outside, "outside"),
        (&c.inside, "inside"),
        (&c.held_out, "held-out"),
    ] {
        below(format!("{what} log RMSE"), set.log_rmse, 0.01);
        below(format!("{what} median"), set.median_rel, 0.02);
    }
    below("flux error".into(), Some(c.flux_error), 0.01);
    below("jump".into(), Some(c.jump), 0.02);
    for (set, what) in [
        (&c.outside, "outside"),
        (&c.inside, "inside"),
        (&c.held_out, "held-out"),
    ] {
        if set.views == 0 || set.views < 2 * set.unmeasured {
            v.failures.push(format!(
                "{what}: {} views measured, {} unmeasured",
                set.views, set.unmeasured
            ));
        }
    }
    let (lo, hi) = c.sweep_light;
    if !lo.is_nan() && (lo < 0.9 || hi > 1.1) {
        v.failures.push(format!(
            "draws {:.1}–{:.1} % of the sweep's light",
            100.0 * lo,
            100.0 * hi
        ));
    }
    let mut not_worse = |what: &str, a: Option<f64>, b: Option<f64>| match (a, b) {
        (None, _) => v.failures.push(format!("{what} n/a")),
        // A nearest value of n/a (no interior left) counts as worse than any number.
        (Some(_), None) => {}
        (Some(a), Some(b)) if a <= b => {}
        (Some(a), Some(b)) if a <= b + TIE_FLOOR => v.ties.push(what.into()),
        (Some(a), Some(b)) => v.failures.push(format!("{what} {a:.6} worse than nearest's {b:.6}")),
    };
    not_worse("outside log RMSE", c.outside.log_rmse, n.outside.log_rmse);
    not_worse("outside median", c.outside.median_rel, n.outside.median_rel);
    not_worse("outside p95", c.outside.p95_rel, n.outside.p95_rel);
    not_worse("inside log RMSE", c.inside.log_rmse, n.inside.log_rmse);
    not_worse("inside median", c.inside.median_rel, n.inside.median_rel);
    not_worse("inside doubled", c.inside.doubled, n.inside.doubled);
    not_worse("held-out log RMSE", c.held_out.log_rmse, n.held_out.log_rmse);
    not_worse(
        "silhouette",
        Some(c.outside.silhouette_px),
        Some(n.outside.silhouette_px),
    );
    not_worse("intensity median", Some(c.intensity_median), Some(n.intensity_median));
    not_worse("intensity max", Some(c.intensity_max), Some(n.intensity_max));
    not_worse("flux", Some(c.flux_error), Some(n.flux_error));
    // Change 9: a nearest that draws under 1 % of the sweep's light in every frame drew none of it.
    if n.sweep_light.1.is_nan() || n.sweep_light.1 >= 0.01 {
        not_worse("jump", Some(c.jump), Some(n.jump));
    } else {
        v.not_compared.push(format!(
            "jump (nearest draws at most {:.4} % of the sweep's light)",
            100.0 * n.sweep_light.1
        ));
    }
    Some(v)
}

/// The contract's verdict on the reconstructed proxy's row (`continuous+rec-proxy`, issue 17): the
/// verdict of `rep` with that row in place of the true proxy's; `None` where either row is missing
/// or [`verdict`] does not apply.
pub fn reconstructed_verdict(rep: &LuminaireReport) -> Option<Verdict> {
    let label = EvalMode::CONTINUOUS_PROXY.label();
    let rec = rep.modes.iter().find(|m| m.mode == RECONSTRUCTED_LABEL)?.clone();
    rep.modes.iter().find(|m| m.mode == label)?;
    let mut as_true = rep.clone();
    for m in &mut as_true.modes {
        if m.mode == label {
            *m = super::report::ModeReport {
                mode: label.clone(),
                ..rec.clone()
            };
        }
    }
    verdict(&as_true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{ModeReport, SetMetrics};

    fn set(log_rmse: f64, median: f64) -> SetMetrics {
        SetMetrics {
            views: 4,
            unmeasured: 1,
            log_rmse: Some(log_rmse),
            median_rel: Some(median),
            p95_rel: Some(median),
            doubled: Some(0.0),
            ..SetMetrics::default()
        }
    }

    fn mode(label: &str, log_rmse: f64, median: f64, jump: f64, light: f64) -> ModeReport {
        ModeReport {
            mode: label.into(),
            outside: set(log_rmse, median),
            inside: set(log_rmse, median),
            held_out: set(log_rmse, median),
            intensity_median: median,
            intensity_max: median,
            flux_error: median,
            jump,
            sweep_light: (light, light),
            worst_view: None,
        }
    }

    fn report(name: &str, c: ModeReport, n: ModeReport) -> LuminaireReport {
        LuminaireReport {
            name: name.into(),
            modes: vec![n, c],
            ..LuminaireReport::default()
        }
    }

    #[test]
    fn the_verdict_holds_thresholds_ties_and_the_sweep_light_rule() {
        let good = || mode("continuous+proxy", 0.001, 0.001, 0.001, 1.0);
        // Better everywhere.
        let v = verdict(&report("disc", good(), mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert_eq!(v, Verdict::default());
        // Worse than nearest by less than 2⁻¹¹: a tie; by more: a failure.
        let v = verdict(&report("cos100", good(), mode("nearest", 1.0, 0.0008, 0.05, 1.0))).unwrap();
        assert!(v.failures.is_empty(), "{v:?}");
        assert!(v.ties.contains(&"outside median".to_string()), "{v:?}");
        let v = verdict(&report("cos100", good(), mode("nearest", 1.0, 0.0001, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("outside median")), "{v:?}");
        // A threshold: median 3 % fails even where nearest is worse.
        let bad = mode("continuous+proxy", 0.001, 0.03, 0.001, 1.0);
        let v = verdict(&report("rect", bad, mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("outside median")), "{v:?}");
        // Change 9: a jump over nearest's is compared while nearest draws the sweep's light …
        let jumpy = || mode("continuous+proxy", 0.001, 0.001, 0.005, 0.95);
        let v = verdict(&report("peak", jumpy(), mode("nearest", 1.0, 0.5, 0.0, 0.02))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("jump")), "{v:?}");
        // … and not where it draws none of it.
        let v = verdict(&report("peak", jumpy(), mode("nearest", 1.0, 0.5, 0.0, 1e-6))).unwrap();
        assert!(v.failures.is_empty() && v.not_compared.len() == 1, "{v:?}");
        // Continuous + proxy must draw the sweep's light itself.
        let dim = mode("continuous+proxy", 0.001, 0.001, 0.001, 0.5);
        let v = verdict(&report("disc", dim, mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.contains("sweep's light")), "{v:?}");
        // Too few measured views.
        let mut few = good();
        few.inside.unmeasured = 3;
        let v = verdict(&report("disc", few, mode("nearest", 1.0, 0.5, 0.05, 1.0))).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("inside:")), "{v:?}");
        // The reflector has no thresholds.
        assert!(verdict(&report("reflector", good(), mode("nearest", 1.0, 0.5, 0.05, 1.0))).is_none());
    }

    #[test]
    fn the_reconstructed_proxy_is_held_to_the_same_contract() {
        let nearest = || mode("nearest", 1.0, 0.5, 0.05, 1.0);
        let good = || mode("continuous+proxy", 0.001, 0.001, 0.001, 1.0);
        let mut rep = report("strips", good(), nearest());
        assert!(reconstructed_verdict(&rep).is_none(), "no reconstructed row");
        // A reconstructed proxy that loses light fails on its own figures, the true proxy's
        // verdict unchanged.
        rep.modes.push(mode(RECONSTRUCTED_LABEL, 0.001, 0.001, 0.001, 1.0));
        rep.modes[2].flux_error = 0.92;
        let v = reconstructed_verdict(&rep).unwrap();
        assert!(v.failures.iter().any(|f| f.starts_with("flux error")), "{v:?}");
        assert_eq!(verdict(&rep).unwrap(), Verdict::default());
        rep.modes[2].flux_error = 0.001;
        assert_eq!(reconstructed_verdict(&rep).unwrap(), Verdict::default());
    }
}
