//! The ray-file convergence harness (docs/quality-metrics.md, "Ray files"): rays forward-traced
//! from a synthetic luminaire ([`emit_rays`]) at several counts N, each turned into a virtual scan
//! by the kernel density estimate ([`raykde::estimate`]), packed with its bounding proxy and
//! rendered on the GPU (continuous selection, proxy) from views outside and inside the estimate's
//! capture sphere and orthographically (flux), then compared with two references:
//!
//! - the **kernel-matched truth**: the same estimator with the N-ray estimate's kernels frozen
//!   ([`raykde::estimate_frozen`]), applied to `truth_factor` × N rays of the same luminaire (at most
//!   `truth_max_rays`), rendered the same way: the estimate's statistical error;
//! - the **raw truth**: the exact ray-caster ([`render_pinhole`], [`synth::render_ortho`]): the statistical
//!   error and the kernels' blur together.
//!
//! [`run`] measures one luminaire at every N; [`format_table`] prints the rows as
//! `lumiview eval-rays` shows them, with the contract's verdict ([`verdicts`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;

use super::metrics::{aggregate, compare_view_with_margin, SetMetrics, ViewMetrics};
use super::rays::{add_bound_estimate, proxy_reach};
use super::{fibonacci, framed_view, ortho_intensity, reference_ortho_intensity, render_view, write_triptych};
use super::{EvalError, View};
use crate::gpu::{RenderTarget, Renderer};
use crate::nearfield::pack::{PackOptions, PackProxy};
use crate::nearfield::proxy::triangles_of;
use crate::nearfield::raykde::{self, KdeOptions, KdeScan, RayBatch};
use crate::nearfield::synth::emit::emit_rays;
use crate::nearfield::synth::{self, render_pinhole, Luminaire};
use crate::nearfield::tm25::RayFile;
use crate::nearfield::NearfieldError;

/// The contract's targets at 10⁶ rays against the kernel-matched truth.
pub const TARGET_LOG_RMSE: f64 = 0.02;
/// Median relative error target at 10⁶ rays.
pub const TARGET_MEDIAN: f64 = 0.03;
/// Flux error target at 10⁶ rays.
pub const TARGET_FLUX: f64 = 0.01;
/// Each reported kernel width at least this much finer at 10⁷ rays than at 10⁵.
pub const TARGET_SHRINK: f64 = 1.5;

/// What the harness does.
#[derive(Debug, Clone, PartialEq)]
pub struct RayConvConfig {
    /// Ray counts N.
    pub rays: Vec<u64>,
    /// Rays of the kernel-matched truth per estimated ray.
    pub truth_factor: f64,
    /// Most rays of a kernel-matched truth.
    pub truth_max_rays: u64,
    /// Rays forward-traced at a time for the truth (memory: about 100 bytes each).
    pub batch_rays: u64,
    /// Eye distances outside the capture sphere, in capture radii.
    pub outside_radii: Vec<f64>,
    /// Eye distances inside it, in capture radii (moved out to clear the luminaire).
    pub inside_radii: Vec<f64>,
    /// View directions (γ, C) in degrees (photometric: γ 0 straight down).
    pub directions_deg: Vec<(f64, f64)>,
    /// View pixels across the luminaire's bounding sphere (capped at `max_view_px`).
    pub view_px: u32,
    /// Largest view side (px).
    pub max_view_px: u32,
    /// Fibonacci directions of the flux quadrature (the whole sphere).
    pub flux_directions: usize,
    /// Side of the orthographic views of the estimates (px; the ray-caster's are 4× finer, at least
    /// 512 px, so that small bright features are resolved).
    pub ortho_px: u32,
    /// Seed of the forward tracer (the truth uses others).
    pub seed: u64,
    /// Where the packs are written (overwritten on every run).
    pub work_dir: PathBuf,
    /// Where each row's first outside view is written as PNGs (estimate | reference | error,
    /// against each truth), if anywhere.
    pub images_dir: Option<PathBuf>,
}

impl Default for RayConvConfig {
    fn default() -> Self {
        Self {
            rays: vec![10_000, 100_000, 1_000_000, 10_000_000],
            truth_factor: 20.0,
            truth_max_rays: 20_000_000,
            batch_rays: 4_000_000,
            outside_radii: vec![1.4, 2.5, 5.0],
            inside_radii: vec![0.3, 0.6],
            directions_deg: vec![(0.0, 10.0), (30.0, 100.0), (55.0, 200.0)],
            view_px: 200,
            max_view_px: 256,
            flux_directions: 96,
            ortho_px: 128,
            seed: 1,
            work_dir: std::env::temp_dir().join("lumiview-eval-rays"),
            images_dir: None,
        }
    }
}

/// Errors of a set of views against one reference.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Against {
    /// Views outside the capture sphere.
    pub outside: SetMetrics,
    /// Views inside it.
    pub inside: SetMetrics,
    /// |Φ − Φ_ref| / Φ_ref from the orthographic quadrature of both.
    pub flux_error: f64,
}

/// One luminaire at one ray count.
#[derive(Debug, Clone, PartialEq)]
pub struct RayConvRow {
    /// The luminaire.
    pub luminaire: String,
    /// Rays estimated.
    pub rays: u64,
    /// Rays of the kernel-matched truth.
    pub truth_rays: u64,
    /// What the estimate chose.
    pub report: raykde::KdeReport,
    /// Against the kernel-matched truth.
    pub kernel: Against,
    /// Against the exact ray-caster.
    pub raw: Against,
    /// The kernel-matched truth against the exact ray-caster (the kernels' own blur).
    pub blur: Against,
    /// Seconds: forward tracing N rays, estimating them, the truth.
    pub seconds: (f64, f64, f64),
}

/// The views of one luminaire, fixed for every N (so the raw references are cast once).
struct Views {
    outside: Vec<View>,
    inside: Vec<View>,
    /// (direction, ray-caster's orthographic intensity) for the flux quadrature.
    flux: Vec<(DVec3, f64)>,
    centre: DVec3,
    rb: f64,
}

fn direction(gamma_deg: f64, c_deg: f64) -> DVec3 {
    let (g, c) = (gamma_deg.to_radians(), c_deg.to_radians());
    DVec3::new(g.sin() * c.cos(), g.sin() * c.sin(), -g.cos())
}

fn views(lum: &dyn Luminaire, radius_m: f64, cfg: &RayConvConfig) -> Views {
    let b = lum.bounds();
    let centre = b.centre();
    let rb = b.centre().length() + b.radius();
    let target = lum.feature_centre();
    let pitch = 2.0 * rb / f64::from(cfg.view_px.max(8));
    let mut outside = Vec::new();
    let mut inside = Vec::new();
    for &(g, c) in &cfg.directions_deg {
        let w = direction(g, c);
        for &k in &cfg.outside_radii {
            outside.push(framed_view(
                centre + w * k * radius_m,
                target,
                rb,
                pitch,
                cfg.max_view_px,
            ));
        }
        for &k in &cfg.inside_radii {
            let d = (k * radius_m).max(rb + 0.05).min(0.95 * radius_m);
            inside.push(framed_view(centre + w * d, target, rb, pitch, cfg.max_view_px));
        }
    }
    Views {
        outside,
        inside,
        flux: Vec::new(),
        centre,
        rb,
    }
}

/// Casts the raw references: luminance under 10⁻⁷ of the luminaire's largest counts as dark.
fn cast(lum: &dyn Luminaire, views: &[View]) -> Result<Vec<Vec<f32>>, EvalError> {
    let dark = (1e-7 * lum.max_luminance()) as f32;
    views
        .iter()
        .map(|v| {
            let mut img = render_pinhole(lum, &v.camera, &v.intrinsics, 1)?.data;
            for x in &mut img {
                if *x < dark {
                    *x = 0.0;
                }
            }
            Ok(img)
        })
        .collect()
}

/// A luminaire's views with the ray-caster's images outside and inside and its flux (lm).
type Prepared = (Views, Vec<Vec<f32>>, Vec<Vec<f32>>, f64);

/// Renders of one estimate: the views, and the orthographic flux.
struct Rendered {
    outside: Vec<Vec<f32>>,
    inside: Vec<Vec<f32>>,
    flux_lm: f64,
}

fn render_estimate(
    r: &mut Renderer,
    e: &KdeScan,
    path: &Path,
    v: &Views,
    cfg: &RayConvConfig,
) -> Result<Rendered, EvalError> {
    let proxy = PackProxy {
        triangles: triangles_of(&e.proxy),
        bound: true,
        source: "the hull of the ray origins, grown by two spatial kernels".into(),
    };
    let opts = PackOptions {
        proxy: Some(proxy),
        source: "lumiview eval-rays".into(),
        ..PackOptions::default()
    };
    let id = add_bound_estimate(r, e, path, &opts, 4 << 30)?;
    let result = (|| {
        let mut targets: Vec<RenderTarget> = Vec::new();
        let mut set = |views: &[View]| -> Result<Vec<Vec<f32>>, EvalError> {
            views
                .iter()
                .map(|view| Ok(render_view(r, &mut targets, view)?))
                .collect()
        };
        let outside = set(&v.outside)?;
        let inside = set(&v.inside)?;
        // The estimate's light reaches past the luminaire's bounds by its kernels, as far as the
        // proxy (the origins' hull grown by two spatial kernels): the frame holds all of it.
        let reach = proxy_reach(e, v.centre, v.rb);
        let mut flux = 0.0;
        for (w, _) in &v.flux {
            flux += ortho_intensity(r, &mut targets, *w, v.centre, reach, cfg.ortho_px)?;
        }
        flux *= 4.0 * std::f64::consts::PI / cfg.flux_directions.max(1) as f64;
        Ok(Rendered {
            outside,
            inside,
            flux_lm: flux,
        })
    })();
    r.remove_luminaire(id)?;
    result
}

fn against(a: &Rendered, reference_out: &[Vec<f32>], reference_in: &[Vec<f32>], flux: f64, v: &Views) -> Against {
    let metrics = |imgs: &[Vec<f32>], refs: &[Vec<f32>], views: &[View]| -> SetMetrics {
        let m: Vec<ViewMetrics> = imgs
            .iter()
            .zip(refs)
            .zip(views)
            .map(|((img, t), view)| {
                let k = &view.intrinsics;
                compare_view_with_margin(img, t, k.width as usize, k.height as usize, view.margin_px)
            })
            .collect();
        let mut set = aggregate(&m);
        if set.log_rmse.is_none() {
            // No view with interior pixels (features smaller than their 5 × 5 test): the error over
            // all lit pixels of the views with light, for [`log_rmse_or_all_lit`].
            let lit: Vec<f64> = m.iter().filter_map(|v| v.all_lit_log_rmse).collect();
            set.all_lit_log_rmse = (!lit.is_empty()).then(|| lit.iter().sum::<f64>() / lit.len() as f64);
        }
        set
    };
    Against {
        outside: metrics(&a.outside, reference_out, &v.outside),
        inside: metrics(&a.inside, reference_in, &v.inside),
        flux_error: if flux > 0.0 {
            (a.flux_lm - flux).abs() / flux
        } else {
            f64::NAN
        },
    }
}

/// Measures one synthetic luminaire at every configured ray count. `row` receives each row as it
/// is finished (a full run takes a while); `progress` a line of what is happening.
///
/// # Errors
/// From the forward tracer, the estimate, the pack writer and the GPU; an unknown luminaire.
pub fn run(
    r: &mut Renderer,
    name: &str,
    cfg: &RayConvConfig,
    progress: &(dyn Fn(&str) + Sync),
    row: &mut dyn FnMut(&RayConvRow),
) -> Result<Vec<RayConvRow>, EvalError> {
    let lum: Arc<dyn Luminaire> = Arc::from(synth::luminaire(name)?);
    std::fs::create_dir_all(&cfg.work_dir).map_err(|e| NearfieldError::io(&cfg.work_dir, e))?;
    let mut prepared: Option<Prepared> = None;
    let mut rows = Vec::new();
    for &n in &cfg.rays {
        let t0 = Instant::now();
        progress(&format!("{name}, {n} rays: forward-tracing"));
        let file = {
            let rays = emit_rays(lum.as_ref(), n, cfg.seed, &|_| {})?;
            let bytes = rays.to_tm25("lumiview eval-rays")?;
            drop(rays);
            RayFile::from_bytes(&bytes, format!("{name}-{n}.tm25ray"))?
        };
        let t1 = Instant::now();
        progress(&format!("{name}, {n} rays: estimating"));
        let opts = KdeOptions {
            keep_kernel_levels: true,
            ..KdeOptions::default()
        };
        let est = raykde::estimate(&file, &opts, &|_, _| {})?;
        drop(file);
        let t2 = Instant::now();
        // The views follow the first estimate's capture radius (the same for every N: it comes from
        // the origins' extent).
        let prepared = match prepared.take() {
            Some(p) => prepared.insert(p),
            None => {
                let mut v = views(lum.as_ref(), est.report.radius_m, cfg);
                progress(&format!(
                    "{name}: ray-casting {} views and {} orthographic references",
                    v.outside.len() + v.inside.len(),
                    cfg.flux_directions
                ));
                let out = cast(lum.as_ref(), &v.outside)?;
                let ins = cast(lum.as_ref(), &v.inside)?;
                v.flux = fibonacci(cfg.flux_directions)
                    .into_iter()
                    .map(|w| {
                        Ok((
                            w,
                            reference_ortho_intensity(lum.as_ref(), w, v.centre, v.rb, (4 * cfg.ortho_px).max(512))?,
                        ))
                    })
                    .collect::<Result<_, EvalError>>()?;
                let flux = v.flux.iter().map(|(_, i)| i).sum::<f64>() * 4.0 * std::f64::consts::PI
                    / cfg.flux_directions.max(1) as f64;
                prepared.insert((v, out, ins, flux))
            }
        };
        let (v, raw_out, raw_in, raw_flux) = &*prepared;
        // The kernel-matched truth, in batches of fresh rays (seeds apart from the estimate's).
        let truth_rays = ((cfg.truth_factor * n as f64).round() as u64).clamp(1, cfg.truth_max_rays.max(1));
        let batch = cfg.batch_rays.clamp(1, truth_rays);
        let batches = truth_rays.div_ceil(batch);
        let mut k = 0u64;
        let mut next = || -> Result<Option<RayBatch>, NearfieldError> {
            if k == batches {
                return Ok(None);
            }
            k += 1;
            progress(&format!(
                "{name}, {n} rays: kernel-matched truth, batch {k}/{batches} of {batch} rays"
            ));
            let rays = emit_rays(lum.as_ref(), batch, cfg.seed.wrapping_add(1000 * k + 7), &|_| {})?;
            let share = 1.0 / batches as f64;
            Ok(Some(
                rays.origins
                    .iter()
                    .zip(&rays.directions)
                    .zip(&rays.flux_lm)
                    .map(|((p, d), f)| (*p, *d, f * share))
                    .collect(),
            ))
        };
        let truth = raykde::estimate_frozen(&est, &mut next, &|_, _| {})?;
        let t3 = Instant::now();
        progress(&format!("{name}, {n} rays: rendering"));
        let stem = format!("{name}-{n}");
        let a = render_estimate(r, &est, &cfg.work_dir.join(format!("{stem}-estimate.lvpack")), v, cfg)?;
        let t = render_estimate(r, &truth, &cfg.work_dir.join(format!("{stem}-truth.lvpack")), v, cfg)?;
        if let Some(dir) = &cfg.images_dir {
            std::fs::create_dir_all(dir).map_err(|e| NearfieldError::io(dir, e))?;
            if let Some(view) = v.outside.first() {
                let (w, h) = (view.intrinsics.width as usize, view.intrinsics.height as usize);
                for (tag, reference) in [("kernel", &t.outside[0]), ("raw", &raw_out[0])] {
                    let f = dir.join(format!("{stem}-{tag}.png"));
                    write_triptych(&f, &a.outside[0], reference, w, h).map_err(|e| NearfieldError::io(&f, e))?;
                }
            }
        }
        let out = RayConvRow {
            luminaire: name.into(),
            rays: n,
            truth_rays: batch * batches,
            kernel: against(&a, &t.outside, &t.inside, t.flux_lm, v),
            raw: against(&a, raw_out, raw_in, *raw_flux, v),
            blur: against(&t, raw_out, raw_in, *raw_flux, v),
            report: est.report.clone(),
            seconds: (
                (t1 - t0).as_secs_f64(),
                (t2 - t1).as_secs_f64(),
                (t3 - t2).as_secs_f64(),
            ),
        };
        row(&out);
        rows.push(out);
    }
    Ok(rows)
}

fn opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or_else(|| "n/a".into(), |x| format!("{:.*}", digits, x * scale))
}

/// The rows as a table: kernels, then the errors against each reference (log-luminance RMSE and
/// median relative error outside | inside, flux error).
pub fn format_table(rows: &[RayConvRow]) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<10} {:>9} {:>9} {:>7} {:>8} {:>6} | {:^29} | {:^29} | {:^29}\n",
        "luminaire",
        "rays",
        "truth",
        "I-kern",
        "σ",
        "cams",
        "vs kernel-matched truth",
        "vs raw truth",
        "kernel blur (truth vs raw)"
    ));
    s.push_str(&format!(
        "{:<10} {:>9} {:>9} {:>7} {:>8} {:>6} | {:>13} {:>8} {:>6} | {:>13} {:>8} {:>6} | {:>13} {:>8} {:>6}\n",
        "",
        "",
        "",
        "°",
        "mm",
        "",
        "logRMSE o/i",
        "med %",
        "flux %",
        "logRMSE o/i",
        "med %",
        "flux %",
        "logRMSE o/i",
        "med %",
        "flux %"
    ));
    for r in rows {
        let cols = |a: &Against| {
            let med = match (a.outside.median_rel, a.inside.median_rel) {
                (Some(o), Some(i)) => Some(o.max(i)),
                (o, i) => o.or(i),
            };
            let lr = |m: &SetMetrics| match (m.log_rmse, m.all_lit_log_rmse) {
                (Some(x), _) => opt(Some(x), 1.0, 3),
                (None, Some(x)) => format!("{}*", opt(Some(x), 1.0, 3)),
                _ => opt(None, 1.0, 3),
            };
            format!(
                "{:>6}/{:<6} {:>8} {:>6}",
                lr(&a.outside),
                lr(&a.inside),
                opt(med, 100.0, 1),
                opt(Some(a.flux_error), 100.0, 2)
            )
        };
        s.push_str(&format!(
            "{:<10} {:>9} {:>9} {:>7.2} {:>8.3} {:>6} | {} | {} | {}\n",
            r.luminaire,
            r.rays,
            r.truth_rays,
            r.report.angular_kernel_deg.median,
            r.report.spatial_kernel_m.median * 1e3,
            r.report.cameras,
            cols(&r.kernel),
            cols(&r.raw),
            cols(&r.blur)
        ));
    }
    s.push_str(
        "I-kern: median intensity kernel half-width; σ: median spatial kernel; logRMSE: log10-luminance RMSE over\n\
         interior pixels, views outside / inside the capture sphere; med: median relative error (the worse of\n\
         outside and inside); flux: from orthographic renders over the sphere. *: over all lit pixels (features\n\
         too small for interior pixels, whose 5 × 5 neighbourhood must be smooth).\n",
    );
    for v in verdicts(rows) {
        s.push_str(&v);
        s.push('\n');
    }
    s
}

/// The log-luminance RMSE over interior pixels, or over all lit ones where a view set has no
/// interior pixels (features smaller than the interior test's 5 × 5 neighbourhood: the raw truth
/// of small dots).
pub fn log_rmse_or_all_lit(m: &SetMetrics) -> Option<f64> {
    m.log_rmse.or(m.all_lit_log_rmse)
}

/// The contract's checks on the rows (docs/quality-metrics.md, "Ray files"), one line each, each
/// starting with `PASS` or `FAIL`: the targets at 10⁶ rays against the kernel-matched truth, the
/// kernels' shrinking from 10⁵ to 10⁷ rays, and the raw error falling with N.
pub fn verdicts(rows: &[RayConvRow]) -> Vec<String> {
    let mut out = Vec::new();
    let mut names: Vec<&str> = rows.iter().map(|r| r.luminaire.as_str()).collect();
    names.dedup();
    let mark = |ok: bool| if ok { "PASS" } else { "FAIL" };
    for name in names {
        let mine: Vec<&RayConvRow> = rows.iter().filter(|r| r.luminaire == name).collect();
        if let Some(r) = mine.iter().find(|r| r.rays == 1_000_000) {
            let k = &r.kernel;
            let worst = |f: &dyn Fn(&SetMetrics) -> Option<f64>| {
                [f(&k.outside), f(&k.inside)]
                    .into_iter()
                    .flatten()
                    .fold(None, |a: Option<f64>, b| Some(a.map_or(b, |a| a.max(b))))
            };
            let lr = worst(&|m| m.log_rmse);
            let med = worst(&|m| m.median_rel);
            let ok = lr.is_some_and(|x| x < TARGET_LOG_RMSE)
                && med.is_some_and(|x| x < TARGET_MEDIAN)
                && k.flux_error < TARGET_FLUX;
            out.push(format!(
                "{} {name} at 10⁶ rays vs kernel-matched truth: log RMSE {} (< {TARGET_LOG_RMSE}), median {} % \
                 (< {} %), flux {:.2} % (< {} %)",
                mark(ok),
                opt(lr, 1.0, 4),
                opt(med, 100.0, 2),
                TARGET_MEDIAN * 100.0,
                k.flux_error * 100.0,
                TARGET_FLUX * 100.0
            ));
        }
        let at = |n: u64| mine.iter().find(|r| r.rays == n);
        if let (Some(a), Some(b)) = (at(100_000), at(10_000_000)) {
            let ratio = |x: f64, y: f64| if y > 0.0 { x / y } else { f64::INFINITY };
            let ri = ratio(a.report.angular_kernel_deg.median, b.report.angular_kernel_deg.median);
            let rf = ratio(
                a.report.footprint_kernel_deg.median,
                b.report.footprint_kernel_deg.median,
            );
            let rs = ratio(a.report.spatial_kernel_m.median, b.report.spatial_kernel_m.median);
            let ok = ri >= TARGET_SHRINK && rf >= TARGET_SHRINK && rs >= TARGET_SHRINK;
            out.push(format!(
                "{} {name} kernels from 10⁵ to 10⁷ rays: intensity {ri:.2}×, footprint {rf:.2}×, spatial {rs:.2}× finer \
                 (≥ {TARGET_SHRINK}×)",
                mark(ok)
            ));
        }
        if mine.len() >= 2 {
            let lr = |r: &RayConvRow| {
                let v: Vec<f64> = [&r.raw.outside, &r.raw.inside]
                    .into_iter()
                    .filter_map(log_rmse_or_all_lit)
                    .collect();
                (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
            };
            let seq: Vec<Option<f64>> = mine.iter().map(|r| lr(r)).collect();
            let falls = seq.windows(2).all(|w| match (w[0], w[1]) {
                (Some(a), Some(b)) => b <= a * 1.05,
                _ => false,
            }) && seq.first().copied().flatten() > seq.last().copied().flatten();
            out.push(format!(
                "{} {name} error against the raw truth falls with N: log RMSE {}",
                mark(falls),
                seq.iter().map(|x| opt(*x, 1.0, 3)).collect::<Vec<_>>().join(" → ")
            ));
        }
    }
    out
}
