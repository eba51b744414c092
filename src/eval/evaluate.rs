//! One luminaire evaluated ([`evaluate`]): its scan loaded onto the GPU with its proxy, the views and
//! the orthographic directions ray-cast for their references, then each configured mode rendered and
//! compared: views outside and inside the capture sphere and from held-out cameras, intensity and
//! flux, and the continuity sweep.

use std::path::Path;

use glam::{DVec3, Mat4};

use super::config::{EvalConfig, EvalMode};
use super::metrics::{self, aggregate, compare_view_with_margin, ViewMetrics};
use super::prepare::{prepare, reconstructed_proxy, Prepared};
use super::references::{references, OrthoReferences, Referenced, References};
use super::render::{ortho_intensity, render_view};
use super::report::{write_triptych, LuminaireReport, ModeReport};
use super::views::View;
use super::EvalError;
use crate::gpu::nearfield::NearfieldOptions;
use crate::gpu::{InstanceId, RenderTarget, Renderer};
use crate::nearfield::proxy::triangles_of;

/// Evaluates one synthetic luminaire in every configured mode.
pub fn evaluate(
    r: &mut Renderer,
    name: &str,
    cfg: &EvalConfig,
    progress: &dyn Fn(&str),
) -> Result<LuminaireReport, EvalError> {
    let p = prepare(name, cfg, progress)?;
    let lum = p.lum.as_ref();
    let proxy = triangles_of(&lum.proxy());
    // Everything resident where it fits (the pool is capped at MAX_POOL_PAGES pages): the harness
    // measures the rendering, and the contract's finest scans (strips: 3,485 cameras of 2,354² px)
    // need more than the default budget for one view.
    let opts = NearfieldOptions {
        budget_bytes: 4 << 30,
        ..NearfieldOptions::default()
    };
    let id = r.add_pack(p.pack.clone(), Some(proxy), &opts)?;
    let inst = r.add_instance(id, Mat4::IDENTITY)?;
    let result = evaluate_loaded(r, inst, &p, cfg, progress);
    r.remove_luminaire(id)?;
    let Loaded {
        mut modes,
        quadrature_flux_error: quad,
        refs,
    } = result?;
    let mut notes = refs.notes.clone();
    if cfg.reconstructed_proxy {
        // The proxy a user gets without a mesh, rendered as the contract's mode renders the true one
        // (or, where none is kept, without a proxy: what the user then sees).
        let (tris, warnings) = reconstructed_proxy(&p, progress)?;
        notes.extend(warnings);
        if let (Some(dir), Some(t)) = (&cfg.images_dir, &tris) {
            crate::nearfield::proxy::mesh_of_triangles(name, "reconstructed", t)
                .write_glb(&dir.join(format!("{name}-rec-proxy.glb")))?;
        }
        let kept = tris.is_some();
        let rec_opts = NearfieldOptions {
            proxy_is_bound: crate::nearfield::reconstruct::PROXY_IS_BOUND,
            ..opts.clone()
        };
        let id = r.add_pack(p.pack.clone(), tris, &rec_opts)?;
        let inst = r.add_instance(id, Mat4::IDENTITY)?;
        let mut gpu = Rendering {
            r,
            inst,
            targets: Vec::new(),
        };
        let mode = if kept {
            EvalMode::CONTINUOUS_PROXY
        } else {
            EvalMode {
                proxy: false,
                ..EvalMode::CONTINUOUS_PROXY
            }
        };
        let result = evaluate_mode(&mut gpu, mode, RECONSTRUCTED_LABEL, &p, cfg, &refs, progress);
        drop(gpu);
        r.remove_luminaire(id)?;
        let report = result?;
        if !kept {
            notes.push(format!("{RECONSTRUCTED_LABEL}: no proxy kept, rendered without one"));
        }
        modes.push(report);
    }
    notes.extend(p.notes.iter().cloned());
    Ok(LuminaireReport {
        name: name.into(),
        cameras: p.pack.image_count(),
        capture_px: p.capture_px,
        pitch_mm: p.pitch_m * 1e3,
        view_pitch_mm: p.view_pitch_m * 1e3,
        notes,
        quadrature_flux_error: quad,
        modes,
    })
}

/// The label of continuous selection with the proxy reconstructed from the scan.
pub const RECONSTRUCTED_LABEL: &str = "continuous+rec-proxy";

/// What [`evaluate_loaded`] measured: every mode's report, the reference flux's own error, and the
/// references (their notes, and for a further mode).
struct Loaded {
    modes: Vec<ModeReport>,
    quadrature_flux_error: f64,
    refs: References,
}

/// Measures the luminaire `p`, loaded on the GPU as instance `inst` of `r`: its references first,
/// then every configured mode.
fn evaluate_loaded(
    r: &mut Renderer,
    inst: InstanceId,
    p: &Prepared,
    cfg: &EvalConfig,
    progress: &dyn Fn(&str),
) -> Result<Loaded, EvalError> {
    let refs = references(p, cfg, progress)?;
    let mut gpu = Rendering {
        r,
        inst,
        targets: Vec::new(),
    };
    let mut reports = Vec::new();
    for mode in &cfg.modes {
        reports.push(evaluate_mode(&mut gpu, *mode, &mode.label(), p, cfg, &refs, progress)?);
    }
    Ok(Loaded {
        modes: reports,
        quadrature_flux_error: refs.ortho.quadrature_flux_error,
        refs,
    })
}

/// The GPU side of an evaluation: the renderer, the luminaire's instance in it, and the render
/// targets, kept by size across views and modes.
struct Rendering<'a> {
    r: &'a mut Renderer,
    inst: InstanceId,
    targets: Vec<RenderTarget>,
}

impl Rendering<'_> {
    /// The luminance of `v` as rendered.
    fn render(&mut self, v: &View) -> Result<Vec<f32>, EvalError> {
        Ok(render_view(self.r, &mut self.targets, v)?)
    }

    /// Î(ω) along the unit direction `w` ([`ortho_intensity`]).
    fn ortho_intensity(&mut self, w: DVec3, centre: DVec3, rb: f64, px: u32) -> Result<f64, EvalError> {
        ortho_intensity(self.r, &mut self.targets, w, centre, rb, px)
    }
}

/// Renders every view and compares it with the reference: the views outside and inside the capture
/// sphere and from held-out cameras, intensity and flux, and the sweep; with `cfg.images_dir`, also
/// writes the worst outside and inside view.
fn evaluate_mode(
    gpu: &mut Rendering,
    mode: EvalMode,
    label: &str,
    p: &Prepared,
    cfg: &EvalConfig,
    refs: &References,
    progress: &dyn Fn(&str),
) -> Result<ModeReport, EvalError> {
    let lum = p.lum.as_ref();
    progress(&format!("{}: rendering {label}", lum.name()));
    gpu.r.set_nearfield_settings(gpu.inst, mode.settings())?;
    let m_out = measure(gpu, &refs.outside)?;
    let m_in = measure(gpu, &refs.inside)?;
    let m_held = measure(gpu, &refs.held)?;
    let worst_view = worst(&m_out);
    if let Some(dir) = &cfg.images_dir {
        let worst_in = worst(&m_in);
        for (tag, set, which) in [
            ("outside", &refs.outside, worst_view),
            ("inside", &refs.inside, worst_in),
        ] {
            if let Some(i) = which {
                let f = dir.join(format!("{}-{}-{tag}-worst.png", lum.name(), label.replace('+', "-")));
                write_view(gpu, set, i, dir, &f)?;
            }
        }
    }
    let errs = intensity_errors(gpu, &refs.ortho, refs.centre, p.rb, cfg.ortho_px)?;
    let phi_hat = flux(gpu, &refs.ortho, refs.centre, p.rb, cfg.ortho_px)?;
    let sweep = sweep(gpu, &refs.sweep)?;
    Ok(ModeReport {
        mode: label.to_string(),
        outside: aggregate(&m_out),
        inside: aggregate(&m_in),
        held_out: aggregate(&m_held),
        intensity_median: errs.get(errs.len().saturating_sub(1) / 2).copied().unwrap_or(f64::NAN),
        intensity_max: errs.last().copied().unwrap_or(f64::NAN),
        flux_error: (phi_hat - refs.ortho.phi_t).abs() / refs.ortho.phi_t,
        jump: sweep.jump,
        sweep_light: sweep.light,
        worst_view,
    })
}

/// Each view of `set` rendered and compared with its reference, in order.
fn measure(gpu: &mut Rendering, set: &Referenced) -> Result<Vec<ViewMetrics>, EvalError> {
    let mut out = Vec::new();
    for (v, t) in set.views.iter().zip(&set.refs) {
        let img = gpu.render(v)?;
        let k = &v.intrinsics;
        out.push(compare_view_with_margin(
            &img,
            t,
            k.width as usize,
            k.height as usize,
            v.margin_px,
        ));
    }
    Ok(out)
}

/// The index of the worst view: the largest log RMSE, a view without one counting as worst (the last
/// of equals).
fn worst(metrics: &[ViewMetrics]) -> Option<usize> {
    metrics
        .iter()
        .enumerate()
        .max_by(|a, b| {
            let key = |m: &ViewMetrics| m.log_rmse.unwrap_or(f64::INFINITY);
            key(a.1).total_cmp(&key(b.1))
        })
        .map(|(i, _)| i)
}

/// Renders view `i` of `set` again and writes it to `f` (in `dir`, made if missing) as render |
/// reference | error ([`write_triptych`]).
fn write_view(gpu: &mut Rendering, set: &Referenced, i: usize, dir: &Path, f: &Path) -> Result<(), EvalError> {
    let img = gpu.render(&set.views[i])?;
    let k = &set.views[i].intrinsics;
    std::fs::create_dir_all(dir)
        .and_then(|_| write_triptych(f, &img, &set.refs[i], k.width as usize, k.height as usize))
        .map_err(|e| crate::nearfield::NearfieldError::io(f, e))?;
    Ok(())
}

/// The relative intensity error |Î − I| / I in each intensity direction, ascending.
fn intensity_errors(
    gpu: &mut Rendering,
    ortho: &OrthoReferences,
    centre: DVec3,
    rb: f64,
    px: u32,
) -> Result<Vec<f64>, EvalError> {
    let mut errs = Vec::new();
    for (w, i_t) in &ortho.intensity {
        let i_hat = gpu.ortho_intensity(*w, centre, rb, px)?;
        errs.push((i_hat - i_t).abs() / i_t);
    }
    errs.sort_by(|a, b| a.total_cmp(b));
    Ok(errs)
}

/// The rendered flux (lm): the quadrature of Î over the flux directions.
fn flux(gpu: &mut Rendering, ortho: &OrthoReferences, centre: DVec3, rb: f64, px: u32) -> Result<f64, EvalError> {
    let mut phi_hat = 0.0;
    for (w, _) in &ortho.flux {
        phi_hat += gpu.ortho_intensity(*w, centre, rb, px)?;
    }
    phi_hat *= ortho.quad_weight;
    Ok(phi_hat)
}

/// A mode along the continuity sweep ([`ModeReport::jump`], [`ModeReport::sweep_light`]).
struct Sweep {
    /// Largest excess change per step.
    jump: f64,
    /// The least and the most light drawn in a frame, as fractions of the reference's (NaN: dark).
    light: (f64, f64),
}

/// Renders the sweep's frames in order and compares each step with the reference's.
fn sweep(gpu: &mut Rendering, set: &Referenced) -> Result<Sweep, EvalError> {
    let refs_sweep = &set.refs;
    let mut prev: Option<Vec<f32>> = None;
    let mut jump: f64 = 0.0;
    let mut sweep_light = (f64::INFINITY, f64::NEG_INFINITY);
    for (k, v) in set.views.iter().enumerate() {
        let img = gpu.render(v)?;
        if let Some(a) = &prev {
            let (t0, t1) = (&refs_sweep[k - 1], &refs_sweep[k]);
            let lmax = t0.iter().cloned().fold(0.0f32, f32::max);
            let mask: Vec<bool> = t0.iter().zip(t1).map(|(x, y)| x.max(*y) > 1e-3 * lmax).collect();
            let jr = metrics::relative_change(a, &img, &mask);
            let jt = metrics::relative_change(t0, t1, &mask);
            jump = jump.max(jr - jt);
            let sum = |img: &[f32]| -> f64 {
                img.iter()
                    .zip(&mask)
                    .filter(|(_, m)| **m)
                    .map(|(x, _)| f64::from(*x))
                    .sum()
            };
            // Both frames of the step (so the first and the last count too).
            for (frame, reference) in [(a.as_slice(), t0), (img.as_slice(), t1)] {
                let truth = sum(reference);
                if truth > 0.0 {
                    let f = sum(frame) / truth;
                    sweep_light = (sweep_light.0.min(f), sweep_light.1.max(f));
                }
            }
        }
        prev = Some(img);
    }
    if !sweep_light.0.is_finite() {
        sweep_light = (f64::NAN, f64::NAN);
    }
    Ok(Sweep {
        jump,
        light: sweep_light,
    })
}
