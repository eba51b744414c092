//! One luminaire evaluated ([`evaluate`]): its scan loaded onto the GPU with its proxy, the views and
//! the orthographic directions ray-cast for their references, then each configured mode rendered and
//! compared: views outside and inside the capture sphere and from held-out cameras, intensity and
//! flux, and the continuity sweep.

use glam::{DVec2, DVec3, Mat4};

use super::config::EvalConfig;
use super::metrics::{self, aggregate, compare_view_with_margin, ViewMetrics};
use super::prepare::{prepare, Prepared};
use super::render::{ortho_intensity, reference_ortho_intensity, render_view};
use super::report::{write_triptych, LuminaireReport, ModeReport};
use super::views::{direction, fibonacci, margin_px, View};
use super::EvalError;
use crate::gpu::nearfield::NearfieldOptions;
use crate::gpu::Renderer;
use crate::nearfield::proxy::triangles_of;
use crate::nearfield::synth::render_pinhole;
use crate::nearfield::Intrinsics;

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
    let (modes, quad, mut notes) = result?;
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

type Loaded = (Vec<ModeReport>, f64, Vec<String>);

fn evaluate_loaded(
    r: &mut Renderer,
    inst: crate::gpu::InstanceId,
    p: &Prepared,
    cfg: &EvalConfig,
    progress: &dyn Fn(&str),
) -> Result<Loaded, EvalError> {
    let lum = p.lum.as_ref();
    let centre = lum.bounds().centre();
    // Views look at the finest feature (the centre where it has none off the centre).
    let target = lum.feature_centre();
    let mut notes = Vec::new();
    let mut targets = Vec::new();
    // Views and their references.
    let mut outside = Vec::new();
    let mut inside = Vec::new();
    for &(g, c) in &cfg.directions_deg {
        let w = direction(g, c);
        for &d in &cfg.outside_m {
            outside.push(p.view(centre + w * d, target, cfg.max_view_px));
        }
        for &d in &cfg.inside_m {
            let min = p.rb + 0.05;
            let d2 = if d < min {
                notes.push(format!("inside eye at {d} m moved out to {min:.3} m"));
                min
            } else {
                d
            };
            inside.push(p.view(centre + w * d2, target, cfg.max_view_px));
        }
    }
    notes.dedup();
    let n_held = cfg.held_out_views.min(p.held_out.len());
    let held: Vec<View> = (0..n_held)
        .map(|i| {
            let (c, k) = &p.held_out[i * p.held_out.len() / n_held.max(1)];
            // From the removed camera's pose at the views' pitch where that is finer than the
            // captures' (a feature the captures resolve with few pixels has no interior at their
            // pitch), cropped about the principal point like the other views.
            let s = (p.pitch_m / p.view_pitch(c.position_m, target)).max(1.0);
            let side = |n: u32| ((f64::from(n) * s).ceil() as u32).clamp(8, cfg.max_view_px.max(8));
            let (w, h) = if s > 1.0 {
                (side(k.width), side(k.height))
            } else {
                (k.width, k.height)
            };
            // The crop is centred on the feature's pixel, kept inside the image.
            let full = DVec2::new(f64::from(k.width), f64::from(k.height)) * s;
            let crop = DVec2::new(f64::from(w), f64::from(h));
            let rel = target - c.position_m;
            let z = rel.dot(c.forward).max(1e-9);
            let at = k.principal_px * s + k.focal_px * s * DVec2::new(rel.dot(c.right), rel.dot(c.down)) / z;
            let shift = (at - 0.5 * crop).clamp(DVec2::ZERO, (full - crop).max(DVec2::ZERO));
            View {
                camera: c.clone(),
                intrinsics: Intrinsics {
                    width: w,
                    height: h,
                    principal_px: k.principal_px * s - shift,
                    focal_px: k.focal_px * s,
                },
                margin_px: margin_px(s),
            }
        })
        // Held-out cameras that see nothing (the dark hemisphere) measure nothing.
        .filter(|v| v.camera.forward.z > 0.05)
        .collect();
    progress(&format!(
        "{}: ray-casting {} reference views",
        lum.name(),
        outside.len() + inside.len() + held.len()
    ));
    // Luminance under 10⁻⁷ of the luminaire's largest is dark (change 8): cos¹⁰⁰ seen from γ 55°
    // is 10⁻²⁴ of its peak, which f32 still holds but nobody sees.
    let dark = (1e-7 * lum.max_luminance()) as f32;
    let reference = |v: &View| -> Result<Vec<f32>, EvalError> {
        let mut img = render_pinhole(lum, &v.camera, &v.intrinsics, 1)?.data;
        for x in &mut img {
            if *x < dark {
                *x = 0.0;
            }
        }
        Ok(img)
    };
    let refs_out: Vec<Vec<f32>> = outside.iter().map(reference).collect::<Result<_, _>>()?;
    let refs_in: Vec<Vec<f32>> = inside.iter().map(reference).collect::<Result<_, _>>()?;
    let refs_held: Vec<Vec<f32>> = held.iter().map(reference).collect::<Result<_, _>>()?;
    // Intensity and flux directions.
    let grid: Vec<DVec3> = [0.0, 45.0, 90.0]
        .iter()
        .flat_map(|c| [0.0, 10.0, 25.0, 40.0, 55.0, 70.0, 80.0].map(|g| direction(g, *c)))
        .collect();
    let fib = fibonacci(cfg.flux_directions);
    let i_max = grid.iter().map(|w| lum.intensity_cd(*w)).fold(0.0, f64::max);
    // The intensity directions (closed form above 1 % of the maximum) and the flux directions (lower
    // hemisphere), each with the ray-caster's Σ T·p² over the same orthographic pixels as the render.
    progress(&format!("{}: ray-casting the orthographic references", lum.name()));
    let grid: Vec<(DVec3, f64)> = grid
        .into_iter()
        .filter(|w| lum.intensity_cd(*w) > 1e-2 * i_max)
        .map(|w| Ok((w, reference_ortho_intensity(lum, w, centre, p.rb, cfg.ortho_px)?)))
        .collect::<Result<_, EvalError>>()?;
    let fib: Vec<(DVec3, f64)> = fib
        .into_iter()
        .filter(|w| w.z < 0.0)
        .map(|w| Ok((w, reference_ortho_intensity(lum, w, centre, p.rb, cfg.ortho_px)?)))
        .collect::<Result<_, EvalError>>()?;
    let quad_weight = 4.0 * std::f64::consts::PI / cfg.flux_directions as f64;
    let phi_t: f64 = fib.iter().map(|(_, i)| i).sum::<f64>() * quad_weight;
    let quad = (phi_t - lum.flux_lm()).abs() / lum.flux_lm();
    // Sweep.
    let spacing = (4.0 * std::f64::consts::PI / (2.0 * p.per_hemisphere as f64))
        .sqrt()
        .to_degrees();
    let steps = ((cfg.sweep_spacings * spacing / cfg.sweep_step_deg).ceil() as usize).max(2);
    let sweep: Vec<View> = (0..=steps)
        .map(|k| {
            let w = direction(40.0, 10.0 + k as f64 * cfg.sweep_step_deg);
            p.view(centre + w * 2.0, target, cfg.max_sweep_px)
        })
        .collect();
    progress(&format!("{}: ray-casting {} sweep references", lum.name(), sweep.len()));
    let refs_sweep: Vec<Vec<f32>> = sweep.iter().map(reference).collect::<Result<_, _>>()?;
    let mut reports = Vec::new();
    for mode in &cfg.modes {
        progress(&format!("{}: rendering {}", lum.name(), mode.label()));
        r.set_nearfield_settings(inst, mode.settings())?;
        let mut set = |views: &[View], refs: &[Vec<f32>]| -> Result<Vec<ViewMetrics>, EvalError> {
            let mut out = Vec::new();
            for (v, t) in views.iter().zip(refs) {
                let img = render_view(r, &mut targets, v)?;
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
        };
        let m_out = set(&outside, &refs_out)?;
        let m_in = set(&inside, &refs_in)?;
        let m_held = set(&held, &refs_held)?;
        let worst_view = m_out
            .iter()
            .enumerate()
            .max_by(|a, b| {
                let key = |m: &ViewMetrics| m.log_rmse.unwrap_or(f64::INFINITY);
                key(a.1).total_cmp(&key(b.1))
            })
            .map(|(i, _)| i);
        if let Some(dir) = &cfg.images_dir {
            let worst_in = m_in
                .iter()
                .enumerate()
                .max_by(|a, b| {
                    let key = |m: &ViewMetrics| m.log_rmse.unwrap_or(f64::INFINITY);
                    key(a.1).total_cmp(&key(b.1))
                })
                .map(|(i, _)| i);
            for (tag, views, refs, which) in [
                ("outside", &outside, &refs_out, worst_view),
                ("inside", &inside, &refs_in, worst_in),
            ] {
                if let Some(i) = which {
                    let img = render_view(r, &mut targets, &views[i])?;
                    let k = &views[i].intrinsics;
                    let f = dir.join(format!(
                        "{}-{}-{tag}-worst.png",
                        lum.name(),
                        mode.label().replace('+', "-")
                    ));
                    std::fs::create_dir_all(dir)
                        .and_then(|_| write_triptych(&f, &img, &refs[i], k.width as usize, k.height as usize))
                        .map_err(|e| crate::nearfield::NearfieldError::io(&f, e))?;
                }
            }
        }
        // Intensity.
        let mut errs = Vec::new();
        for (w, i_t) in &grid {
            let i_hat = ortho_intensity(r, &mut targets, *w, centre, p.rb, cfg.ortho_px)?;
            errs.push((i_hat - i_t).abs() / i_t);
        }
        errs.sort_by(|a, b| a.total_cmp(b));
        let mut phi_hat = 0.0;
        for (w, _) in &fib {
            phi_hat += ortho_intensity(r, &mut targets, *w, centre, p.rb, cfg.ortho_px)?;
        }
        phi_hat *= quad_weight;
        // Sweep.
        let mut prev: Option<Vec<f32>> = None;
        let mut jump: f64 = 0.0;
        let mut sweep_light = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, v) in sweep.iter().enumerate() {
            let img = render_view(r, &mut targets, v)?;
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
        reports.push(ModeReport {
            mode: mode.label().into(),
            outside: aggregate(&m_out),
            inside: aggregate(&m_in),
            held_out: aggregate(&m_held),
            intensity_median: errs.get(errs.len().saturating_sub(1) / 2).copied().unwrap_or(f64::NAN),
            intensity_max: errs.last().copied().unwrap_or(f64::NAN),
            flux_error: (phi_hat - phi_t).abs() / phi_t,
            jump,
            sweep_light,
            worst_view,
        });
    }
    Ok((reports, quad, notes))
}
