//! Scenes: a glTF 2.0 scene loaded into a context, the one `lumi_render` draws lit by the context's
//! instances, its lighting settings, and the illuminance at host-given points computed by
//! the CPU reference path tracer (`scene::Tracer`).
//!
//! Promises:
//! - A scene is loaded once: its triangles and materials (`scene::load`) and its ray-query
//!   hierarchy (`scene::bvh::Bvh`), built at load and shared by every `lumi_scene_illuminance`.
//!   Coordinates are glTF's (metres, +Y up); an instance's model matrix maps the luminaire frame
//!   (nadir −Z, C0 +X) into them, e.g. `scene::placement(x, y, z, yaw)`.
//! - At most one scene is drawn (`lumi_context_set_scene`); it is uploaded when set, and
//!   destroying it stops drawing it.
//! - `lumi_scene_illuminance` lights the scene with every instance of the context at the time of
//!   the call, as the GPU pass does: a photometric file by its web, a near-field scan by its far
//!   field (`nearfield::farfield`, estimated from its images on first use). Out-parameters are
//!   written only on success; every argument is checked before any work.

use std::ffi::c_char;
use std::sync::Arc;

use glam::DVec3;

use super::context::{lumi_context, with_context, ContextInner};
use super::handle;
use super::{lumi_status, path_arg, write_out, FfiError};
use super::{LUMI_STATUS_INVALID_ARGUMENT, LUMI_STATUS_IO, LUMI_STATUS_OUT_OF_MEMORY, LUMI_STATUS_PARSE};
use crate::gpu::scene::SceneSettings;
use crate::gpu::{Arg, GpuError, LogLevel};
use crate::scene::bvh::Bvh;
use crate::scene::{Scene, SceneError, SceneLuminaire, SurfacePoint, TraceOptions, Tracer};

/// Handle of a scene, owned by its context (0 is never a valid handle).
pub type lumi_scene = u64;

/// `lumi_illuminance_options.light`: direct light only (straight from the luminaires, with
/// shadows).
pub const LUMI_ILLUMINANCE_DIRECT: u32 = 0;
/// `lumi_illuminance_options.light`: direct light plus inter-reflection, every bounce (the default).
pub const LUMI_ILLUMINANCE_TOTAL: u32 = 1;

/// Most points one `lumi_scene_illuminance` call takes.
pub const LUMI_ILLUMINANCE_MAX_POINTS: u32 = 1048576;
/// Most paths per point, direct estimates per point, and area samples per estimate one
/// `lumi_scene_illuminance` call takes.
pub const LUMI_ILLUMINANCE_MAX_SAMPLES: u32 = 65536;

/// Default indirect paths per point (`lumi_illuminance_options_default`); why this many:
/// docs/scene-lighting.md, "C API".
const DEFAULT_PATHS_PER_POINT: u32 = 512;

/// How the scene `lumi_render` draws is lit (the GPU pass). Start from
/// `lumi_scene_settings_default()`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_scene_settings {
    /// Visibility from shadow maps; false lets every luminaire reach every point facing it.
    pub shadows: bool,
    /// The illuminance below which a luminaire's light is left out, lux (finite, > 0): its
    /// influence radius is where I_max / r² falls to it.
    pub lux_floor_lx: f32,
    /// Most bytes of the shadow-map atlas (> 0; 4 bytes a texel). Cube faces shrink by powers of
    /// two until every luminaire's six fit; below 16 px a render fails naming this field.
    pub shadow_budget_bytes: u64,
    /// Largest cube-map face, pixels (16…8192).
    pub max_face_px: u32,
    /// Inter-reflection from virtual point lights: photons shot from the luminaires on the CPU
    /// (made again when the scene or an instance changes), every reflection gathered per pixel,
    /// all bounces, without visibility between the reflection and the pixel
    /// (docs/scene-lighting.md, "Inter-reflection").
    pub indirect: bool,
    /// Photons shot from all instances together, 1…65,536 (each leaves one virtual point light per
    /// reflection; a frame's cost grows with their number).
    pub bounce_photons: u32,
    /// Distance below which a virtual point light's 1/r² is held, metres (finite, ≥ 0).
    pub vpl_clamp_m: f32,
    /// Most instances whose shadow maps are rendered again in one `lumi_render` after they moved
    /// (≥ 1); the others keep their old maps until a later frame's turn (lowest first). A new
    /// scene, shadow layout or atlas renders every instance at once.
    pub shadow_updates_per_frame: u32,
}

/// How `lumi_scene_illuminance` estimates. Start from `lumi_illuminance_options_default()`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_illuminance_options {
    /// `LUMI_ILLUMINANCE_TOTAL` (direct plus every bounce of inter-reflection) or
    /// `LUMI_ILLUMINANCE_DIRECT`.
    pub light: u32,
    /// Indirect paths per point with `LUMI_ILLUMINANCE_TOTAL`, 1…`LUMI_ILLUMINANCE_MAX_SAMPLES`
    /// (ignored with `LUMI_ILLUMINANCE_DIRECT`). The indirect part's standard error falls as
    /// 1/√paths.
    pub paths_per_point: u32,
    /// Independent estimates of the direct term per point, 1…`LUMI_ILLUMINANCE_MAX_SAMPLES` (their
    /// spread gives the direct term's standard error; a scene lit only by point sources uses one,
    /// exact).
    pub direct_estimates: u32,
    /// Points drawn on each luminaire's luminous opening per direct estimate,
    /// 1…`LUMI_ILLUMINANCE_MAX_SAMPLES`, rounded up to a square; ignored for point openings.
    pub area_samples: u32,
    /// Seed of the random numbers: the same seed, scene, instances and points give the same
    /// numbers, whatever the number of threads.
    pub seed: u64,
}

/// The state behind a `lumi_scene` handle.
#[derive(Debug)]
pub struct SceneEntry {
    /// The scene (world-space triangles and materials).
    pub scene: Arc<Scene>,
    /// Its ray-query hierarchy, built once at load.
    pub bvh: Arc<Bvh>,
}

/// The GPU pass's defaults: shadows on, lux floor 0.1 lx, shadow budget 64 MiB, faces up to 512 px,
/// inter-reflection on from 256 photons with a 0.25 m clamp, shadows of up to 32 moved instances
/// rendered per frame.
#[no_mangle]
pub extern "C" fn lumi_scene_settings_default() -> lumi_scene_settings {
    let d = SceneSettings::default();
    lumi_scene_settings {
        shadows: d.shadows,
        lux_floor_lx: d.lux_floor_lx,
        shadow_budget_bytes: d.shadow_budget_bytes,
        max_face_px: d.max_face_px,
        indirect: d.indirect,
        bounce_photons: d.bounce_photons,
        vpl_clamp_m: d.vpl_clamp_m,
        shadow_updates_per_frame: d.shadow_updates_per_frame,
    }
}

/// The defaults: `LUMI_ILLUMINANCE_TOTAL`, 512 paths per point, 4 direct estimates of 64 area
/// samples each, seed 1 (in the sample office: about 1 % standard error on the work plane; cost
/// measured in docs/scene-lighting.md, "C API").
#[no_mangle]
pub extern "C" fn lumi_illuminance_options_default() -> lumi_illuminance_options {
    let d = TraceOptions::default();
    lumi_illuminance_options {
        light: LUMI_ILLUMINANCE_TOTAL,
        paths_per_point: DEFAULT_PATHS_PER_POINT,
        direct_estimates: d.direct_estimates as u32,
        area_samples: d.area_samples as u32,
        seed: d.seed,
    }
}

/// The scene behind handle `s` of this context.
fn scene_of(c: &ContextInner, s: lumi_scene) -> Result<&SceneEntry, FfiError> {
    handle::decode(c.tag, handle::Kind::Scene, s, "scene")?;
    c.scenes.get(&s).ok_or_else(|| gone(s))
}

/// A scene handle of this context that names no live scene.
fn gone(s: lumi_scene) -> FfiError {
    FfiError::invalid("scene", format!("no scene with handle {s:#x} (destroyed?)"))
}

/// A scene-loading error: the file unreadable (`IO`, or `OUT_OF_MEMORY` for a buffer that cannot be
/// allocated) or malformed (`PARSE`); the text names the file.
fn load_error(e: SceneError) -> FfiError {
    let status = match &e {
        SceneError::Io { source, .. } if source.kind() == std::io::ErrorKind::OutOfMemory => LUMI_STATUS_OUT_OF_MEMORY,
        SceneError::Io { .. } => LUMI_STATUS_IO,
        SceneError::Format { .. } => LUMI_STATUS_PARSE,
        SceneError::InvalidArgument { .. } => LUMI_STATUS_INVALID_ARGUMENT,
    };
    FfiError::new(status, e.to_string())
}

/// A scene-pass error, naming `lumi_scene_settings`' fields and the scene as the C API spells them.
fn pass_error(e: GpuError) -> FfiError {
    match e {
        GpuError::InvalidArgument { arg, message } => {
            let field = match arg {
                Arg::LuxFloor => "settings.lux_floor_lx",
                Arg::BudgetBytes => "settings.shadow_budget_bytes",
                Arg::FacePx => "settings.max_face_px",
                Arg::BouncePhotons => "settings.bounce_photons",
                Arg::VplClamp => "settings.vpl_clamp_m",
                Arg::ShadowUpdates => "settings.shadow_updates_per_frame",
                Arg::Scene => "scene",
                other => other.name(),
            };
            FfiError::invalid(field, message)
        }
        other => other.into(),
    }
}

/// Loads a glTF 2.0 scene (`.glb`, or `.gltf` with its buffers and PNG textures beside it or
/// embedded) for drawing (`lumi_context_set_scene`) and for illuminance (`lumi_scene_illuminance`).
/// Coordinates are glTF's: metres, +Y up; surfaces are Lambertian with the materials' base colour
/// (docs/scene-lighting.md). The ray-query hierarchy is built here, once. A file that loads but is
/// doubtful (a primitive without a material, lines or points, a JPEG texture) succeeds and sends one
/// warning per finding, naming the file, to the log callback.
///
/// - `path`: NUL-terminated UTF-8 path, borrowed for the call.
/// - `out`: receives the handle (owned by the context: free it with `lumi_scene_destroy` or by
///   destroying the context); written only on success.
///
/// Errors: `LUMI_STATUS_NULL_POINTER` (`path`, `out`), `LUMI_STATUS_INVALID_ARGUMENT` (`path` empty
/// or not UTF-8), `LUMI_STATUS_IO` (the file, or a buffer or image it names, cannot be read, is not
/// a regular file or is over 1 GiB), `LUMI_STATUS_PARSE` (not glTF 2.0, a truncated GLB, an index or
/// accessor out of range, non-finite positions, more than 8 million triangles, no triangles,
/// unsupported features; the text names the file and the glTF object), `LUMI_STATUS_OUT_OF_MEMORY`.
///
/// Threading: one thread at a time per context; the load holds the context's lock.
///
/// # Safety
/// `ctx` is a live context; `path` a NUL-terminated string; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_scene_load(
    ctx: *mut lumi_context,
    path: *const c_char,
    out: *mut lumi_scene,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_scene_load", ctx, |c| {
            let path = path_arg(path, "path")?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let scene = crate::scene::load(&path).map_err(load_error)?;
            for w in scene.warnings() {
                c.renderer.ctx.log(LogLevel::Warning, w);
            }
            let bvh = Arc::new(Bvh::build(&scene));
            let h = handle::encode(c.tag, handle::Kind::Scene, c.next_scene);
            c.next_scene += 1;
            c.scenes.insert(
                h,
                SceneEntry {
                    scene: Arc::new(scene),
                    bvh,
                },
            );
            write_out(out, h);
            Ok(())
        })
    }
}

/// Frees a scene. If it is the scene `lumi_render` draws, the context draws none from then on.
/// Handle 0 is ignored; a stale, foreign or wrong-kind handle is an error (nothing changes).
///
/// Threading: one thread at a time per context.
///
/// # Safety
/// `ctx` is a live context.
#[no_mangle]
pub unsafe extern "C" fn lumi_scene_destroy(ctx: *mut lumi_context, scene: lumi_scene) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_scene_destroy", ctx, |c| {
            if scene == 0 {
                return Ok(());
            }
            handle::decode(c.tag, handle::Kind::Scene, scene, "scene")?;
            c.scenes.remove(&scene).ok_or_else(|| gone(scene))?;
            if c.active_scene == Some(scene) {
                c.renderer.clear_scene();
                c.active_scene = None;
            }
            Ok(())
        })
    }
}

/// Chooses the scene `lumi_render` draws: from the next render on, every frame draws `scene` from
/// the camera, lit by every instance of the context (scans by their far field; direct light with
/// shadow maps, luminance L = ρ·E/π in cd/m²), before the luminaires' own appearance, in the same depth test.
/// `scene` 0 draws none. The scene is uploaded to the GPU here (setting the scene already drawn
/// does nothing); on an error the context draws what it drew before.
///
/// Errors: `LUMI_STATUS_INVALID_ARGUMENT` (a stale, foreign or wrong-kind handle; a scene whose
/// vertices exceed the device's largest buffer, naming `scene`), `LUMI_STATUS_GPU`,
/// `LUMI_STATUS_OUT_OF_MEMORY` (the upload).
///
/// Threading: one thread at a time per context.
///
/// # Safety
/// `ctx` is a live context.
#[no_mangle]
pub unsafe extern "C" fn lumi_context_set_scene(ctx: *mut lumi_context, scene: lumi_scene) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_context_set_scene", ctx, |c| {
            if scene == 0 {
                c.renderer.clear_scene();
                c.active_scene = None;
                return Ok(());
            }
            let entry = scene_of(c, scene)?;
            let (s, bvh) = (entry.scene.clone(), entry.bvh.clone());
            if c.active_scene == Some(scene) {
                return Ok(());
            }
            c.renderer.set_scene_shared(s, Some(bvh)).map_err(pass_error)?;
            c.active_scene = Some(scene);
            Ok(())
        })
    }
}

/// Sets how the drawn scene is lit (`lumi_scene_settings`; kept by the context, also while no scene
/// is set). On an error nothing changes.
///
/// - `settings`: required; read during the call only.
///
/// Errors: `LUMI_STATUS_NULL_POINTER` (`settings`), `LUMI_STATUS_INVALID_ARGUMENT` naming the
/// field (`settings.lux_floor_lx` not finite or not > 0, `settings.shadow_budget_bytes` 0,
/// `settings.max_face_px` outside 16…8192, `settings.bounce_photons` outside 1…65,536,
/// `settings.vpl_clamp_m` not finite or negative, `settings.shadow_updates_per_frame` 0).
///
/// Threading: one thread at a time per context.
///
/// # Safety
/// `ctx` is a live context; `settings` NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn lumi_context_set_scene_settings(
    ctx: *mut lumi_context,
    settings: *const lumi_scene_settings,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_context_set_scene_settings", ctx, |c| {
            let Some(s) = settings.as_ref() else {
                return Err(FfiError::null("settings"));
            };
            c.renderer
                .set_scene_settings(SceneSettings {
                    lux_floor_lx: s.lux_floor_lx,
                    shadows: s.shadows,
                    shadow_budget_bytes: s.shadow_budget_bytes,
                    max_face_px: s.max_face_px,
                    indirect: s.indirect,
                    bounce_photons: s.bounce_photons,
                    vpl_clamp_m: s.vpl_clamp_m,
                    shadow_updates_per_frame: s.shadow_updates_per_frame,
                    deferred_max_pixels: SceneSettings::default().deferred_max_pixels,
                })
                .map_err(pass_error)
        })
    }
}

/// The options from C (NULL: the defaults), checked.
fn trace_options(o: Option<&lumi_illuminance_options>) -> Result<TraceOptions, FfiError> {
    let o = o.copied().unwrap_or_else(|| lumi_illuminance_options_default());
    let count = |v: u32, field: &str| -> Result<usize, FfiError> {
        if v == 0 || v > LUMI_ILLUMINANCE_MAX_SAMPLES {
            return Err(FfiError::invalid(
                field,
                format!("{v} is outside 1…{LUMI_ILLUMINANCE_MAX_SAMPLES}"),
            ));
        }
        Ok(v as usize)
    };
    let paths_per_point = match o.light {
        LUMI_ILLUMINANCE_DIRECT => 0,
        LUMI_ILLUMINANCE_TOTAL => count(o.paths_per_point, "opts.paths_per_point")?,
        v => {
            return Err(FfiError::invalid(
                "opts.light",
                format!("unknown value {v} (LUMI_ILLUMINANCE_DIRECT 0, LUMI_ILLUMINANCE_TOTAL 1)"),
            ))
        }
    };
    Ok(TraceOptions {
        paths_per_point,
        direct_estimates: count(o.direct_estimates, "opts.direct_estimates")?,
        area_samples: count(o.area_samples, "opts.area_samples")?,
        seed: o.seed,
        ..TraceOptions::default()
    })
}

/// Reads `count` points and normals (3 floats each), checked: finite, normals non-zero.
///
/// # Safety
/// `points_m` and `normals` are non-NULL and point to `3 × count` readable floats each.
unsafe fn surface_points(
    points_m: *const f32,
    normals: *const f32,
    count: usize,
) -> Result<Vec<SurfacePoint>, FfiError> {
    // SAFETY: per the caller's contract; count ≤ LUMI_ILLUMINANCE_MAX_POINTS, so 3 × count fits.
    let (p, n) = unsafe {
        (
            std::slice::from_raw_parts(points_m, 3 * count),
            std::slice::from_raw_parts(normals, 3 * count),
        )
    };
    let mut out = Vec::with_capacity(count);
    for (i, (p, n)) in p.chunks_exact(3).zip(n.chunks_exact(3)).enumerate() {
        let (p, n) = (
            DVec3::new(p[0].into(), p[1].into(), p[2].into()),
            DVec3::new(n[0].into(), n[1].into(), n[2].into()),
        );
        if !p.is_finite() {
            return Err(FfiError::invalid("points_m", format!("point {i} ({p}) is not finite")));
        }
        if !n.is_finite() || n == DVec3::ZERO {
            return Err(FfiError::invalid(
                "normals",
                format!("normal {i} ({n}) must be finite and non-zero"),
            ));
        }
        out.push(SurfacePoint {
            position_m: p,
            normal: n.normalize(),
        });
    }
    Ok(out)
}

/// Illuminance in lux at host-given points of a scene, on the side each normal faces, from every
/// instance of the context placed by its model matrix (a near-field scan lights by the far field
/// estimated from its images, as the drawn scene does; docs/scene-lighting.md), with visibility
/// (the scene's surfaces cast shadows; luminaires and the points themselves do not), computed by
/// the CPU reference path tracer (docs/scene-lighting.md, "C API"): the direct term from shadow
/// rays to points on each luminous opening, and with `LUMI_ILLUMINANCE_TOTAL` inter-reflection
/// between the scene's Lambertian surfaces by path tracing (every bounce: Russian roulette, capped
/// at 64). With no instance every point gets 0 lx. The scene need not be the one `lumi_render`
/// draws.
///
/// - `points_m`: `3 × count` floats, x, y, z of each point in scene metres (glTF axes, +Y up).
/// - `normals`: `3 × count` floats, the normal of each point's receiving side (any non-zero
///   length; normalised), e.g. (0, 1, 0) for a work plane or a floor.
/// - `count`: 1…`LUMI_ILLUMINANCE_MAX_POINTS`.
/// - `opts`: NULL for `lumi_illuminance_options_default()`.
/// - `out_lx`: `count` doubles, the illuminance of each point, lux.
/// - `out_std_error_lx`: NULL, or `count` doubles, each estimate's standard error, lux (0 where
///   the estimate is exact: direct light from point sources only).
///
/// Both outputs are written only on success. Cost: per point and instance, about
/// `direct_estimates × area_samples` shadow rays, plus one closest-hit and one shadow ray per
/// bounce of each of `paths_per_point` paths, on every core (measured in docs/scene-lighting.md);
/// the call holds the context's lock until it is done.
///
/// Errors: `LUMI_STATUS_NULL_POINTER` (`points_m`, `normals`, `out_lx`),
/// `LUMI_STATUS_INVALID_ARGUMENT` naming the argument: `count` 0 or above the cap; `opts.light`
/// unknown; `opts.paths_per_point` (with `LUMI_ILLUMINANCE_TOTAL`), `opts.direct_estimates`,
/// `opts.area_samples` 0 or above `LUMI_ILLUMINANCE_MAX_SAMPLES`; a stale, foreign or wrong-kind
/// `scene`; a point that is not finite (`points_m`), a normal that is not finite or zero
/// (`normals`); an instance whose model matrix scales, shears or mirrors (`instance`, naming its
/// handle: the tracer needs a rotation and a translation).
///
/// Threading: one thread at a time per context.
///
/// # Safety
/// `ctx` is a live context; `points_m` and `normals` NULL or `3 × count` readable floats each;
/// `opts` NULL or valid; `out_lx` NULL or `count` writable doubles; `out_std_error_lx` NULL or
/// `count` writable doubles.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn lumi_scene_illuminance(
    ctx: *const lumi_context,
    scene: lumi_scene,
    points_m: *const f32,
    normals: *const f32,
    count: usize,
    opts: *const lumi_illuminance_options,
    out_lx: *mut f64,
    out_std_error_lx: *mut f64,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_scene_illuminance", ctx, |c| {
            if points_m.is_null() {
                return Err(FfiError::null("points_m"));
            }
            if normals.is_null() {
                return Err(FfiError::null("normals"));
            }
            if out_lx.is_null() {
                return Err(FfiError::null("out_lx"));
            }
            if count == 0 || count > LUMI_ILLUMINANCE_MAX_POINTS as usize {
                return Err(FfiError::invalid(
                    "count",
                    format!("{count} is outside 1…{LUMI_ILLUMINANCE_MAX_POINTS}"),
                ));
            }
            let opts = trace_options(opts.as_ref())?;
            let entry = scene_of(c, scene)?;
            let points = surface_points(points_m, normals, count)?;
            let mut luminaires = Vec::new();
            for (id, lum, model) in c.renderer.instances() {
                let l = SceneLuminaire {
                    photometry: c.renderer.light_of(lum)?,
                    scene_from_luminaire: model.as_dmat4(),
                };
                if let Err(why) = l.check_placement() {
                    let h = handle::encode(c.tag, handle::Kind::Instance, id.0);
                    return Err(FfiError::invalid("instance", format!("instance {h:#x}: {why}")));
                }
                luminaires.push(l);
            }
            let tracer = Tracer::with_bvh(&entry.scene, entry.bvh.clone(), &luminaires)
                .map_err(|e| FfiError::invalid("scene", e))?;
            let result = tracer
                .illuminance(&points, &opts)
                .map_err(|e| FfiError::invalid("points_m", e))?;
            let direct_only = opts.paths_per_point == 0;
            for (i, r) in result.iter().enumerate() {
                out_lx.add(i).write(r.total_lx);
                if !out_std_error_lx.is_null() {
                    let se = if direct_only { r.direct_se_lx } else { r.total_se_lx };
                    out_std_error_lx.add(i).write(se);
                }
            }
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_from_c_are_checked_and_named() {
        let d = trace_options(None).unwrap();
        assert_eq!(d.paths_per_point, DEFAULT_PATHS_PER_POINT as usize);
        assert_eq!(
            (d.direct_estimates, d.area_samples, d.seed),
            (4, 64, TraceOptions::default().seed)
        );
        let mut o = lumi_illuminance_options_default();
        o.light = LUMI_ILLUMINANCE_DIRECT;
        o.paths_per_point = 0; // ignored for direct light
        assert_eq!(trace_options(Some(&o)).unwrap().paths_per_point, 0);
        let bad = |f: &dyn Fn(&mut lumi_illuminance_options), field: &str| {
            let mut o = lumi_illuminance_options_default();
            f(&mut o);
            let e = trace_options(Some(&o)).unwrap_err();
            assert_eq!(e.status, LUMI_STATUS_INVALID_ARGUMENT);
            assert!(e.message.contains(&format!("'{field}'")), "{}", e.message);
        };
        bad(&|o| o.light = 2, "opts.light");
        bad(&|o| o.paths_per_point = 0, "opts.paths_per_point");
        bad(
            &|o| o.paths_per_point = LUMI_ILLUMINANCE_MAX_SAMPLES + 1,
            "opts.paths_per_point",
        );
        bad(&|o| o.direct_estimates = 0, "opts.direct_estimates");
        bad(&|o| o.area_samples = u32::MAX, "opts.area_samples");
    }

    #[test]
    fn points_are_checked_and_normals_normalised() {
        let p = [0.0f32, 1.0, 2.0, 3.0, 4.0, 5.0];
        let n = [0.0f32, 2.0, 0.0, 0.0, 0.0, -0.5];
        // SAFETY: 6 floats each, count 2.
        let s = unsafe { surface_points(p.as_ptr(), n.as_ptr(), 2) }.unwrap();
        assert_eq!(s[1].position_m, DVec3::new(3.0, 4.0, 5.0));
        assert_eq!((s[0].normal, s[1].normal), (DVec3::Y, DVec3::NEG_Z));
        let mut q = p;
        q[4] = f32::NAN;
        // SAFETY: as above.
        let e = unsafe { surface_points(q.as_ptr(), n.as_ptr(), 2) }.unwrap_err();
        assert!(
            e.message.contains("'points_m'") && e.message.contains("point 1"),
            "{}",
            e.message
        );
        let z = [0.0f32; 6];
        // SAFETY: as above.
        let e = unsafe { surface_points(p.as_ptr(), z.as_ptr(), 2) }.unwrap_err();
        assert!(
            e.message.contains("'normals'") && e.message.contains("normal 0"),
            "{}",
            e.message
        );
    }
}
