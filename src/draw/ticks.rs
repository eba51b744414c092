//! Ticks of axes, rings and scale bars: round 1-2-5 steps (1, 2, 5 × 10ⁿ), the tick values over a
//! range, and their labels. One home for every picture's ticks: the polar diagram's rings, the
//! isolux diagram's axes in metres, the coverage picture's colour bar in degrees and the
//! logarithmic scale bar under a render.
//!
//! Each step finder keeps the arithmetic its picture has always used, so no picture changes: the
//! steps of [`step_at_least`] and [`step_and_count`] are m · 10^⌊log₁₀ x⌋ with the power from
//! `powf`, those of [`step_for_span`] are m × 10ⁿ computed exactly (a division for n < 0), those of
//! [`log_ticks`] m · 10ⁿ with the power from `powi`. They can differ in the last bit for some
//! exponents (5 · 10⁻⁶, say).

/// The smallest 1-2-5 × 10ⁿ step ≥ `x` (within 10⁻¹² relative); 1 for a non-finite or
/// non-positive `x`.
pub fn step_at_least(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * p >= x * (1.0 - 1e-12) {
            return m * p;
        }
    }
    10.0 * p
}

/// The smallest 1-2-5 step that reaches `max` in at most `max_count` steps, and how many steps
/// that takes (at least 1): the rings of a polar diagram. `None` for a non-finite or
/// non-positive `max` (or no step allowed).
pub fn step_and_count(max: f64, max_count: usize) -> Option<(f64, usize)> {
    if !(max.is_finite() && max > 0.0) || max_count == 0 {
        return None;
    }
    let magnitude = 10f64.powf((max / max_count as f64).log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0, 20.0, 50.0] {
        let step = m * magnitude;
        let count = (max / step - 1e-9).ceil().max(1.0) as usize;
        if count <= max_count {
            return Some((step, count));
        }
    }
    Some((100.0 * magnitude, 1))
}

/// The smallest 1-2-5 step that divides `span` into at most `max_intervals` intervals, each step
/// m × 10ⁿ computed exactly (1 for a non-finite or non-positive span): the axes of the isolux
/// diagram.
pub fn step_for_span(span: f64, max_intervals: f64) -> f64 {
    if !(span.is_finite() && span > 0.0) {
        return 1.0;
    }
    let mut exponent = (span / max_intervals).log10().floor() as i32;
    loop {
        for m in [1.0, 2.0, 5.0] {
            let step = if exponent >= 0 {
                m * 10f64.powi(exponent)
            } else {
                m / 10f64.powi(-exponent)
            };
            if span / step <= max_intervals + 1e-9 {
                return step;
            }
        }
        exponent += 1;
    }
}

/// The ticks k · `step` within ±`half_width`, ascending, 0 among them.
pub fn symmetric_ticks(half_width: f64, step: f64) -> Vec<f64> {
    let k = (half_width / step + 1e-9).floor() as i64;
    (-k..=k).map(|i| i as f64 * step).collect()
}

/// The 1-2-5 values within [`lo`, `hi`] (> 0) for a logarithmic axis, thinned to the decades
/// (1 × 10ⁿ) when there are more than `max_ticks`.
pub fn log_ticks(lo: f64, hi: f64, max_ticks: usize) -> Vec<f64> {
    let mut v = Vec::new();
    let mut e = lo.log10().floor() as i32;
    while 10f64.powi(e) <= hi * 1.000001 && v.len() < 1000 {
        for m in [1.0, 2.0, 5.0] {
            let t = m * 10f64.powi(e);
            if t >= lo * 0.999999 && t <= hi * 1.000001 {
                v.push(t);
            }
        }
        e += 1;
    }
    if v.len() > max_ticks {
        v.retain(|t| {
            let m = t / 10f64.powi(t.log10().floor() as i32);
            (m - 1.0).abs() < 1e-6
        });
    }
    v
}

/// The decimals a tick label needs at a 1-2-5 `step`: none from 1 up, else as many as the step
/// has (0.5 → 1, 0.05 → 2).
pub fn decimals_for_step(step: f64) -> usize {
    if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    }
}

/// A tick label with as many decimals as the step needs ([`decimals_for_step`]).
pub fn label_at_step(v: f64, step: f64) -> String {
    let decimals = decimals_for_step(step);
    format!("{v:.decimals$}")
}

/// A tick label of a length axis: at most three decimals, trailing zeros dropped, a typographic
/// minus (−2, 0.5, 12.25).
pub fn label_trimmed(v: f64) -> String {
    trim_number(format!("{v:.3}")).replace('-', "\u{2212}")
}

/// A tick label of a logarithmic scale, short: 1, 20, 500, 5k, 2M, 1e9 …
pub fn label_short(v: f64) -> String {
    if v >= 1e9 {
        let e = v.log10().floor();
        let m = (v / 10f64.powf(e)).round();
        return format!("{m}e{e}");
    }
    let (d, suffix) = if v >= 1e6 {
        (v / 1e6, "M")
    } else if v >= 1e3 {
        (v / 1e3, "k")
    } else {
        (v, "")
    };
    if d >= 1.0 || d == 0.0 {
        format!("{}{suffix}", (d * 1000.0).round() / 1000.0)
    } else {
        let digits = (-d.log10()).ceil() as usize;
        format!("{d:.digits$}{suffix}")
    }
}

/// Drops trailing zeros (and a trailing point) of a formatted decimal; `-0` becomes `0`.
pub fn trim_number(s: String) -> String {
    if !s.contains('.') {
        return s;
    }
    let t = s.trim_end_matches('0').trim_end_matches('.');
    if t == "-0" {
        "0".to_string()
    } else {
        t.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_at_least() {
        assert_eq!(step_at_least(0.3), 0.5);
        assert_eq!(step_at_least(1.0), 1.0);
        assert_eq!(step_at_least(12.0), 20.0);
        assert_eq!(label_at_step(0.25, 0.05), "0.25");
    }

    #[test]
    fn ring_steps_follow_1_2_5() {
        assert_eq!(step_and_count(6019.0, 7), Some((1000.0, 7)));
        assert_eq!(step_and_count(2866.0, 7), Some((500.0, 6)));
        assert_eq!(step_and_count(463.0, 7), Some((100.0, 5)));
        assert_eq!(step_and_count(1000.0, 7), Some((200.0, 5)));
        assert_eq!(step_and_count(0.0, 7), None);
        let (s, n) = step_and_count(0.37, 7).unwrap_or_default();
        assert!((s - 0.1).abs() < 1e-12 && n == 4);
    }

    #[test]
    fn span_steps_follow_1_2_5() {
        assert_eq!(step_for_span(6.0, 10.0), 1.0);
        assert_eq!(step_for_span(10.0, 10.0), 1.0);
        assert_eq!(step_for_span(10.2, 10.0), 2.0);
        assert_eq!(step_for_span(30.0, 10.0), 5.0);
        assert_eq!(step_for_span(0.6, 10.0), 0.1);
        assert_eq!(symmetric_ticks(3.0, 1.0), [-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0]);
        assert_eq!(symmetric_ticks(10.2, 2.0).len(), 11);
    }

    #[test]
    fn log_ticks_are_1_2_5_and_thin_to_decades() {
        assert_eq!(log_ticks(1.0, 100.0, 20), vec![1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]);
        assert_eq!(log_ticks(1.0, 100.0, 4), vec![1.0, 10.0, 100.0]);
        assert_eq!(label_short(5000.0), "5k");
        assert_eq!(label_short(0.02), "0.02");
        assert_eq!(label_short(2e6), "2M");
        assert_eq!(label_short(5e15), "5e15");
    }

    #[test]
    fn decimals_follow_the_step() {
        // Every 1-2-5 step below 1 the ring and colour-bar finders make: m · 10⁻ᵏ needs k decimals.
        for k in 1..=15 {
            let p = 10f64.powf(-f64::from(k));
            for (m, extra) in [(1.0, 0), (2.0, 0), (5.0, 0), (10.0, 1), (20.0, 1), (50.0, 1)] {
                let step = m * p;
                if step < 1.0 {
                    assert_eq!(decimals_for_step(step), k as usize - extra, "{step:e}");
                }
            }
        }
        assert_eq!(decimals_for_step(1.0), 0);
        assert_eq!(label_at_step(1500.0, 500.0), "1500");
        assert_eq!(label_at_step(0.3, 0.1), "0.3");
    }

    #[test]
    fn trimmed_labels() {
        assert_eq!(label_trimmed(-2.0), "\u{2212}2");
        assert_eq!(label_trimmed(0.5), "0.5");
        assert_eq!(label_trimmed(-0.0001), "0");
        assert_eq!(trim_number("12.500".to_string()), "12.5");
        assert_eq!(trim_number("120".to_string()), "120");
    }
}
