//! The per-view metrics of docs/quality-metrics.md, on luminance images (cd/m², row-major).

/// Luminance of "lit" pixels: above this fraction of the view's reference maximum.
pub const LIT_FRACTION: f32 = 1e-3;

/// Largest max/min ratio of a 5 × 5 reference neighbourhood for an interior pixel.
pub const INTERIOR_RATIO: f32 = 1.25;

/// Fewest interior pixels for the pixel metrics to be reported.
pub const MIN_INTERIOR: usize = 50;

/// Relative error above which an interior pixel counts towards the doubled-pattern score.
pub const DOUBLED_ERROR: f64 = 0.25;

/// Metrics of one view (render against reference).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ViewMetrics {
    /// Lit reference pixels.
    pub lit: usize,
    /// Interior pixels.
    pub interior: usize,
    /// Log-luminance RMSE over interior pixels (`None`: fewer than [`MIN_INTERIOR`]).
    pub log_rmse: Option<f64>,
    /// Median relative error over interior pixels.
    pub median_rel: Option<f64>,
    /// 95th-percentile relative error over interior pixels.
    pub p95_rel: Option<f64>,
    /// Log-luminance RMSE over all lit pixels.
    pub all_lit_log_rmse: Option<f64>,
    /// Silhouette displacement (px).
    pub silhouette_px: f64,
    /// Fraction of interior pixels with a relative error above [`DOUBLED_ERROR`].
    pub doubled: Option<f64>,
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    // Nearest rank.
    let n = sorted.len();
    let k = ((q * n as f64).ceil() as usize).clamp(1, n);
    sorted[k - 1]
}

/// Compares a render with its reference (both `w × h`, cd/m²). Non-finite render values count as 0.
/// Interior pixels are at least 2 px from a silhouette or step ([`compare_view_with_margin`]).
pub fn compare_view(render: &[f32], reference: &[f32], w: usize, h: usize) -> ViewMetrics {
    compare_view_with_margin(render, reference, w, h, 2)
}

/// [`compare_view`] with interior pixels also at least `margin_px` (≥ 2) from a step inside the
/// luminaire: a reference pixel with light whose 4-neighbour has light too (however little: a dim
/// background is still the surface) and differs from it by more than [`INTERIOR_RATIO`]. A view finer than the captures by a factor s takes 2·s (change 7 of
/// docs/quality-metrics.md): such a step is where the captures' pixels put it, known to within one of
/// them. Silhouettes (light next to none) keep the 2 px of the 5 × 5 test: the proxy places them at
/// the view's own pixels (the silhouette metric measures how well).
pub fn compare_view_with_margin(
    render: &[f32],
    reference: &[f32],
    w: usize,
    h: usize,
    margin_px: usize,
) -> ViewMetrics {
    let n = w * h;
    if render.len() < n || reference.len() < n || n == 0 {
        return ViewMetrics::default();
    }
    let lmax = reference[..n].iter().cloned().fold(0.0f32, f32::max);
    if lmax <= 0.0 {
        return ViewMetrics::default();
    }
    let thr = LIT_FRACTION * lmax;
    let floor = 1e-6 * f64::from(lmax);
    let r = |i: usize| -> f64 {
        let v = render[i];
        if v.is_finite() {
            f64::from(v)
        } else {
            0.0
        }
    };
    let lit_t: Vec<bool> = reference[..n].iter().map(|v| *v > thr).collect();
    let lit_r: Vec<bool> = (0..n).map(|i| r(i) > f64::from(thr)).collect();
    // Steps, counted in a summed-area table (row-major, (w + 1) × (h + 1)) for the margin test.
    let step = |i: usize, j: usize| -> bool {
        let (a, b) = (reference[i], reference[j]);
        b > 0.0 && a.max(b) > INTERIOR_RATIO * a.min(b)
    };
    let mut sat = vec![0u32; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = 0u32;
        for x in 0..w {
            let i = y * w + x;
            let s = reference[i] > 0.0
                && ((x > 0 && step(i, i - 1))
                    || (x + 1 < w && step(i, i + 1))
                    || (y > 0 && step(i, i - w))
                    || (y + 1 < h && step(i, i + w)));
            row += u32::from(s);
            sat[(y + 1) * (w + 1) + x + 1] = sat[y * (w + 1) + x + 1] + row;
        }
    }
    let m = margin_px.max(2);
    let steps_near = |x: usize, y: usize| -> bool {
        let (x0, y0) = (x.saturating_sub(m), y.saturating_sub(m));
        let (x1, y1) = ((x + m + 1).min(w), (y + m + 1).min(h));
        let at = |xx: usize, yy: usize| sat[yy * (w + 1) + xx];
        at(x1, y1) + at(x0, y0) > at(x0, y1) + at(x1, y0)
    };
    let mut rel = Vec::new();
    let mut log2 = 0.0;
    let mut all_log2 = 0.0;
    let mut lit = 0usize;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if !lit_t[i] {
                continue;
            }
            lit += 1;
            let t = f64::from(reference[i]);
            let lr = (r(i).max(floor) / t).log10();
            all_log2 += lr * lr;
            if x < 2 || y < 2 || x + 2 >= w || y + 2 >= h {
                continue;
            }
            let (mut lo, mut hi) = (f32::MAX, 0.0f32);
            for yy in y - 2..=y + 2 {
                for xx in x - 2..=x + 2 {
                    let v = reference[yy * w + xx];
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            if lo <= thr || hi > INTERIOR_RATIO * lo || (m > 2 && steps_near(x, y)) {
                continue;
            }
            rel.push((r(i) - t).abs() / t);
            log2 += lr * lr;
        }
    }
    let interior = rel.len();
    let mut out = ViewMetrics {
        lit,
        interior,
        all_lit_log_rmse: (lit > 0).then(|| (all_log2 / lit as f64).sqrt()),
        ..Default::default()
    };
    // Silhouette displacement: disagreement area over the reference perimeter.
    let mut xor = 0usize;
    let mut perimeter = 0usize;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if lit_t[i] != lit_r[i] {
                xor += 1;
            }
            if lit_t[i] {
                let edge = (x == 0 || !lit_t[i - 1])
                    || (x + 1 == w || !lit_t[i + 1])
                    || (y == 0 || !lit_t[i - w])
                    || (y + 1 == h || !lit_t[i + w]);
                if edge {
                    perimeter += 1;
                }
            }
        }
    }
    out.silhouette_px = if perimeter > 0 {
        xor as f64 / perimeter as f64
    } else {
        0.0
    };
    if interior >= MIN_INTERIOR {
        out.log_rmse = Some((log2 / interior as f64).sqrt());
        out.doubled = Some(rel.iter().filter(|e| **e > DOUBLED_ERROR).count() as f64 / interior as f64);
        rel.sort_by(|a, b| a.total_cmp(b));
        out.median_rel = Some(percentile(&rel, 0.5));
        out.p95_rel = Some(percentile(&rel, 0.95));
    }
    out
}

/// Relative L1 change between consecutive images, Σ|b − a| / Σ a, over the pixels where `mask` holds.
pub fn relative_change(a: &[f32], b: &[f32], mask: &[bool]) -> f64 {
    let (mut d, mut s) = (0.0f64, 0.0f64);
    for ((x, y), m) in a.iter().zip(b).zip(mask) {
        if *m {
            d += f64::from((y - x).abs());
            s += f64::from(*x);
        }
    }
    if s > 0.0 {
        d / s
    } else {
        0.0
    }
}

/// Aggregate of a set of views (docs/quality-metrics.md): mean log RMSE, median of medians, largest
/// p95, largest silhouette displacement, largest doubled-pattern score over the measured views;
/// `None` when no view could be measured. Views with a dark reference are left out; views without
/// enough interior pixels are counted as unmeasured.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SetMetrics {
    /// Views measured: a lit reference with at least [`MIN_INTERIOR`] interior pixels.
    pub views: usize,
    /// Views with a lit reference but too few interior pixels to measure.
    pub unmeasured: usize,
    /// Mean of the views' log RMSE.
    pub log_rmse: Option<f64>,
    /// Median of the views' median relative errors.
    pub median_rel: Option<f64>,
    /// Largest p95 relative error.
    pub p95_rel: Option<f64>,
    /// Mean all-lit log RMSE.
    pub all_lit_log_rmse: Option<f64>,
    /// Largest silhouette displacement (px).
    pub silhouette_px: f64,
    /// Largest doubled-pattern score.
    pub doubled: Option<f64>,
}

/// Aggregates view metrics.
pub fn aggregate(views: &[ViewMetrics]) -> SetMetrics {
    // A view whose reference is dark everywhere (e.g. cos¹⁰⁰ at γ 75°, 10⁻⁵⁴ of its peak) has nothing
    // to measure: it is left out, and `views` counts the views measured.
    let lit: Vec<ViewMetrics> = views.iter().filter(|m| m.lit > 0).copied().collect();
    // Views with lit pixels but fewer than MIN_INTERIOR interior ones (a smooth but steep gradient, or
    // features too thin at that angle) are counted as unmeasured; the pixel metrics aggregate the rest,
    // and are n/a only when no view could be measured.
    let unmeasured = lit.iter().filter(|m| m.log_rmse.is_none()).count();
    let silhouette_px = lit.iter().map(|m| m.silhouette_px).fold(0.0, f64::max);
    let measured: Vec<ViewMetrics> = lit.iter().filter(|m| m.log_rmse.is_some()).copied().collect();
    let views = &measured[..];
    let all = |f: &dyn Fn(&ViewMetrics) -> Option<f64>| -> Option<Vec<f64>> { views.iter().map(f).collect() };
    let mean = |v: Vec<f64>| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    let max = |v: Vec<f64>| v.into_iter().reduce(f64::max);
    SetMetrics {
        views: views.len(),
        log_rmse: all(&|m| m.log_rmse).and_then(mean),
        median_rel: all(&|m| m.median_rel).and_then(|mut v| {
            v.sort_by(|a, b| a.total_cmp(b));
            (!v.is_empty()).then(|| v[(v.len() - 1) / 2])
        }),
        p95_rel: all(&|m| m.p95_rel).and_then(max),
        all_lit_log_rmse: all(&|m| m.all_lit_log_rmse).and_then(mean),
        silhouette_px,
        unmeasured,
        doubled: all(&|m| m.doubled).and_then(max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(w: usize, h: usize, cx: f64, r: f64, l: f32) -> Vec<f32> {
        let mut v = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - h as f64 / 2.0);
                if dx * dx + dy * dy < r * r {
                    v[y * w + x] = l;
                }
            }
        }
        v
    }

    #[test]
    fn identical_images_score_zero_and_a_uniform_error_is_measured() {
        let t = disc(64, 64, 32.0, 20.0, 1000.0);
        let m = compare_view(&t, &t, 64, 64);
        assert!(m.interior > 500 && m.lit > m.interior);
        assert_eq!(m.log_rmse, Some(0.0));
        assert_eq!(m.median_rel, Some(0.0));
        assert_eq!(m.silhouette_px, 0.0);
        let r: Vec<f32> = t.iter().map(|v| v * 1.02).collect();
        let m = compare_view(&r, &t, 64, 64);
        assert!((m.median_rel.unwrap() - 0.02).abs() < 1e-6);
        assert!((m.log_rmse.unwrap() - 1.02f64.log10()).abs() < 1e-6);
        assert_eq!(m.doubled, Some(0.0));
    }

    #[test]
    fn a_shifted_silhouette_is_measured_in_pixels() {
        let t = disc(128, 128, 64.0, 30.0, 10.0);
        let r = disc(128, 128, 66.0, 30.0, 10.0);
        let m = compare_view(&r, &t, 128, 128);
        // A disc moved by 2 px: the symmetric difference is about 4r·2 px², the perimeter 2πr px.
        let expect = 4.0 * 30.0 * 2.0 / (2.0 * std::f64::consts::PI * 30.0);
        assert!((m.silhouette_px - expect).abs() < 0.35 * expect, "{}", m.silhouette_px);
        // Interior pixels are at least 2 px inside the reference edge, so a 2 px shift leaves them
        // lit: the interior metrics do not see it.
        assert_eq!(m.doubled, Some(0.0));
        // A 5 px shift uncovers a band of interior pixels: the doubled score sees it.
        let r = disc(128, 128, 69.0, 30.0, 10.0);
        let m = compare_view(&r, &t, 128, 128);
        assert!(m.doubled.unwrap() > 0.0);
    }

    #[test]
    fn a_wider_margin_keeps_pixels_further_from_steps() {
        // A bright disc (r = 20 px) on a dim lit background: a step inside the lit region.
        let mut t = disc(96, 96, 48.0, 20.0, 1000.0);
        for v in &mut t {
            *v = v.max(100.0);
        }
        let near = compare_view(&t, &t, 96, 96);
        let far = compare_view_with_margin(&t, &t, 96, 96, 6);
        assert!(far.interior < near.interior && far.interior > 0);
        // A render blurred across the step by 3 px: the 2 px margin sees the blur, 6 px does not.
        let mut r = t.clone();
        for y in 0..96 {
            for x in 0..96 {
                let d = ((x as f64 + 0.5 - 48.0).powi(2) + (y as f64 + 0.5 - 48.0).powi(2)).sqrt();
                if (d - 20.0).abs() < 3.0 {
                    r[y * 96 + x] = 550.0;
                }
            }
        }
        assert!(compare_view(&r, &t, 96, 96).doubled.unwrap() > 0.0);
        let m = compare_view_with_margin(&r, &t, 96, 96, 6);
        assert_eq!((m.doubled, m.log_rmse), (Some(0.0), Some(0.0)));
        // A silhouette (the background dark) keeps the 2 px margin: as many interior pixels as before.
        let d = disc(96, 96, 48.0, 20.0, 1000.0);
        assert_eq!(
            compare_view_with_margin(&d, &d, 96, 96, 6).interior,
            compare_view(&d, &d, 96, 96).interior
        );
    }

    #[test]
    fn tiny_features_report_no_pixel_metrics() {
        let mut t = vec![0.0f32; 32 * 32];
        t[16 * 32 + 16] = 5.0;
        let m = compare_view(&t, &t, 32, 32);
        assert_eq!(m.lit, 1);
        assert_eq!(m.interior, 0);
        assert!(m.log_rmse.is_none() && m.median_rel.is_none());
    }

    #[test]
    fn relative_change_and_aggregate() {
        let a = vec![1.0f32, 2.0, 3.0];
        let b = vec![1.0f32, 2.5, 3.0];
        assert!((relative_change(&a, &b, &[true; 3]) - 0.5 / 6.0).abs() < 1e-12);
        let v = [
            ViewMetrics {
                lit: 100,
                log_rmse: Some(0.01),
                median_rel: Some(0.02),
                p95_rel: Some(0.05),
                silhouette_px: 0.5,
                ..Default::default()
            },
            ViewMetrics {
                lit: 100,
                log_rmse: Some(0.03),
                median_rel: Some(0.01),
                p95_rel: Some(0.07),
                silhouette_px: 0.2,
                ..Default::default()
            },
        ];
        let s = aggregate(&v);
        assert!((s.log_rmse.unwrap() - 0.02).abs() < 1e-12);
        assert_eq!(s.p95_rel, Some(0.07));
        assert_eq!(s.silhouette_px, 0.5);
        assert_eq!(s.median_rel, Some(0.01));
        assert_eq!(s.views, 2);
        // A view with a dark reference is left out; one without interior pixels is counted as
        // unmeasured, and only a set with no measured view is n/a.
        let dark = ViewMetrics::default();
        assert_eq!(aggregate(&[v[0], v[1], dark]), s);
        let no_interior = ViewMetrics {
            lit: 3,
            silhouette_px: 0.9,
            ..Default::default()
        };
        let m = aggregate(&[v[0], v[1], no_interior]);
        assert_eq!((m.views, m.unmeasured, m.log_rmse), (2, 1, s.log_rmse));
        assert_eq!(m.silhouette_px, 0.9);
        assert_eq!(aggregate(&[no_interior]).log_rmse, None);
    }
}
