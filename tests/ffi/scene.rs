//! Scenes through the C API: the shipped office loads and hostile files are errors naming them;
//! `lumi_scene_illuminance` against E = I(C, γ)·cos³γ/h² written here (C and γ from the placement
//! convention) and against the Rust reference tracer run directly; shadows, inter-reflection,
//! the defaults' convergence; every bad argument; near-field instances add no light;
//! `lumi_render` draws the scene set on the context lit (the floor's pixel against the C API's own
//! illuminance), and not once it is destroyed or cleared.

use std::ffi::CString;
use std::ptr;

use glam::{DVec3, Vec3};
use lumiview::ffi::context::*;
use lumiview::ffi::instance::*;
use lumiview::ffi::luminaire::*;
use lumiview::ffi::render::*;
use lumiview::ffi::scene::*;
use lumiview::ffi::target::*;
use lumiview::ffi::*;
use lumiview::scene::model::luminance_y;
use lumiview::scene::sample::OFFICE_LUMINAIRES;
use lumiview::scene::{placement, SceneLuminaire, SurfacePoint, TraceOptions, Tracer};

use crate::common::{context, cpath, cstr, last_error, temp_dir};
use crate::gpu_common::{self, gl_perspective, look_at, GPU_LOCK};

/// A point luminaire with no symmetry: five C planes (0–360°), γ 0–90°, opening 0 × 0 × 0.
const ASYMMETRIC_IES: &str = "IESNA:LM-63-2002\n[TEST] asymmetric point source\nTILT=NONE\n\
1 -1 1 5 5 1 2 0 0 0\n1 1 10\n0 22.5 45 67.5 90\n0 90 180 270 360\n\
1000 900 700 400 100\n1000 760 600 300 50\n1000 500 350 150 20\n1000 650 500 250 40\n1000 900 700 400 100\n";

/// Where the test luminaire hangs: over desk 1 (top 0.72–0.75 m over x −2.3…−0.7, z −0.4…0.4).
const LUM_AT: (f64, f64, f64, f64) = (-1.5, 2.95, 0.0, 30.0);

/// Floor points with nothing between them and `LUM_AT` (off the rug, the desks, the chairs), and
/// the one under desk 1.
const OPEN_FLOOR: [[f32; 3]; 3] = [[0.0, 0.0, 1.2], [-2.6, 0.0, 1.6], [0.5, 0.0, -0.1]];
const UNDER_DESK: [f32; 3] = [-1.5, 0.0, 0.0];

fn office() -> CString {
    CString::new(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes/office.glb")
            .to_str()
            .unwrap(),
    )
    .unwrap()
}

/// The model matrix of `LUM_AT` as the C API gets it (f32, column-major).
fn model() -> [f32; 16] {
    let (x, y, z, yaw) = LUM_AT;
    placement(x, y, z, yaw).as_mat4().to_cols_array()
}

/// Calls `lumi_scene_illuminance` on `points` (normals +Y), returning the status, the values and
/// the standard errors.
///
/// # Safety
/// `ctx` is a live context.
unsafe fn illuminance(
    ctx: *mut lumi_context,
    scene: lumi_scene,
    points: &[[f32; 3]],
    opts: Option<&lumi_illuminance_options>,
) -> (lumi_status, Vec<f64>, Vec<f64>) {
    let normals = vec![[0.0f32, 1.0, 0.0]; points.len()];
    let (mut lx, mut se) = (vec![-1.0; points.len()], vec![-1.0; points.len()]);
    // SAFETY: buffers of `points.len()` entries; `ctx` per the caller.
    let s = unsafe {
        lumi_scene_illuminance(
            ctx,
            scene,
            points.as_ptr().cast(),
            normals.as_ptr().cast(),
            points.len(),
            opts.map_or(ptr::null(), |o| o as *const _),
            lx.as_mut_ptr(),
            se.as_mut_ptr(),
        )
    };
    (s, lx, se)
}

fn direct_only() -> lumi_illuminance_options {
    let mut o = lumi_illuminance_options_default();
    o.light = LUMI_ILLUMINANCE_DIRECT;
    o
}

/// A file in a private folder holding `text`, as a C path.
fn temp_file(dir: &std::path::Path, name: &str, bytes: &[u8]) -> CString {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    cstr(&p)
}

/// The shipped office loads; a missing file, a directory, a truncated GLB and a text file are
/// errors naming the file, with the out-parameter untouched; NULLs and empty paths are named;
/// destroy takes 0 and refuses a stale handle.
#[test]
fn scenes_load_and_hostile_files_are_errors_naming_them() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    let dir = temp_dir("scene-load");
    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals.
    unsafe {
        let mut scene: lumi_scene = 0;
        assert_eq!(
            lumi_scene_load(ctx, office().as_ptr(), &mut scene),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert_ne!(scene, 0);
        let glb = std::fs::read(env!("CARGO_MANIFEST_DIR").to_string() + "/assets/scenes/office.glb").unwrap();
        let cases: Vec<(CString, lumi_status, &str)> = vec![
            (cpath("does-not-exist.glb"), LUMI_STATUS_IO, "does-not-exist.glb"),
            (cstr(&dir), LUMI_STATUS_IO, "lumiview-ffi-scene-load"),
            (
                temp_file(&dir, "truncated.glb", &glb[..glb.len() / 2]),
                LUMI_STATUS_PARSE,
                "truncated.glb",
            ),
            (
                temp_file(&dir, "header-only.glb", &glb[..12]),
                LUMI_STATUS_PARSE,
                "header-only.glb",
            ),
            (
                temp_file(&dir, "notes.gltf", b"not a scene\n"),
                LUMI_STATUS_PARSE,
                "notes.gltf",
            ),
        ];
        for (path, want, name) in &cases {
            let mut out: lumi_scene = 77;
            assert_eq!(
                lumi_scene_load(ctx, path.as_ptr(), &mut out),
                *want,
                "{name}: {}",
                last_error()
            );
            let e = last_error();
            assert!(e.starts_with("lumi_scene_load: ") && e.contains(name), "{e}");
            assert_eq!(out, 77, "{name}: out untouched");
        }
        let mut out: lumi_scene = 77;
        assert_eq!(lumi_scene_load(ctx, ptr::null(), &mut out), LUMI_STATUS_NULL_POINTER);
        assert!(last_error().contains("'path'"), "{}", last_error());
        let empty = CString::new("").unwrap();
        assert_eq!(
            lumi_scene_load(ctx, empty.as_ptr(), &mut out),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(
            lumi_scene_load(ctx, office().as_ptr(), ptr::null_mut()),
            LUMI_STATUS_NULL_POINTER
        );
        assert!(last_error().contains("'out'"), "{}", last_error());
        assert_eq!(out, 77);
        assert_eq!(
            lumi_scene_load(ptr::null_mut(), office().as_ptr(), &mut out),
            LUMI_STATUS_NULL_POINTER
        );

        // A second load is another scene; destroy takes 0, then refuses the stale handle.
        let mut again: lumi_scene = 0;
        assert_eq!(lumi_scene_load(ctx, office().as_ptr(), &mut again), LUMI_STATUS_OK);
        assert_ne!(again, scene);
        assert_eq!(lumi_scene_destroy(ctx, 0), LUMI_STATUS_OK);
        assert_eq!(lumi_scene_destroy(ctx, scene), LUMI_STATUS_OK);
        assert_eq!(lumi_scene_destroy(ctx, scene), LUMI_STATUS_INVALID_ARGUMENT);
        assert!(last_error().contains("(destroyed?)"), "{}", last_error());
        let (s, lx, _) = illuminance(ctx, scene, &OPEN_FLOOR, None);
        assert_eq!(s, LUMI_STATUS_INVALID_ARGUMENT);
        assert!(lx.iter().all(|&v| v == -1.0));
        // The other scene is untouched; the context frees it.
        let (s, lx, _) = illuminance(ctx, again, &OPEN_FLOOR, Some(&direct_only()));
        assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
        assert_eq!(lx, vec![0.0; 3], "no instances: no light");
        lumi_context_destroy(ctx);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// One point luminaire over the office floor: the direct term at open floor points is
/// E = I(C, γ)·cos³γ/h² with C and γ derived here from the placement convention and I from
/// `lumi_luminaire_sample`, exact (standard error 0); the point under the desk gets no direct light
/// and less in total; total ≥ direct, and inter-reflection adds light. An area luminaire (the
/// BEGA's 0.6 m opening) gives exactly the numbers of the Rust tracer run on the same scene,
/// matrix and points, direct and total, values and standard errors.
#[test]
fn scene_illuminance_is_the_analytic_direct_term_and_the_reference_tracers() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    let dir = temp_dir("scene-illuminance");
    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals.
    unsafe {
        let mut scene: lumi_scene = 0;
        assert_eq!(lumi_scene_load(ctx, office().as_ptr(), &mut scene), LUMI_STATUS_OK);
        let ies = temp_file(&dir, "asymmetric.ies", ASYMMETRIC_IES.as_bytes());
        let mut lum: lumi_luminaire = 0;
        assert_eq!(lumi_luminaire_load(ctx, ies.as_ptr(), &mut lum), LUMI_STATUS_OK);
        let m = model();
        let mut inst: lumi_instance = 0;
        assert_eq!(lumi_instance_create(ctx, lum, m.as_ptr(), &mut inst), LUMI_STATUS_OK);

        let mut points = OPEN_FLOOR.to_vec();
        points.push(UNDER_DESK);
        let (s, direct, se) = illuminance(ctx, scene, &points, Some(&direct_only()));
        assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
        // The centre as the C API has it (f32), the rest of the convention from the placement: at
        // yaw ψ the luminaire's X is scene (cos ψ, 0, −sin ψ), its Y scene (−sin ψ, 0, −cos ψ), nadir −Y.
        let centre = DVec3::new(m[12].into(), m[13].into(), m[14].into());
        let yaw = LUM_AT.3.to_radians();
        let (ax, ay) = (
            DVec3::new(yaw.cos(), 0.0, -yaw.sin()),
            DVec3::new(-yaw.sin(), 0.0, -yaw.cos()),
        );
        for (k, p) in OPEN_FLOOR.iter().enumerate() {
            let d = DVec3::new(p[0].into(), p[1].into(), p[2].into()) - centre;
            let h = -d.y;
            let gamma = (h / d.length()).acos().to_degrees();
            let c = d.dot(ay).atan2(d.dot(ax)).to_degrees().rem_euclid(360.0);
            let mut cd = 0.0;
            assert_eq!(
                lumi_luminaire_sample(ctx, lum, c, gamma, &mut cd, ptr::null_mut()),
                LUMI_STATUS_OK
            );
            let want = cd * (gamma.to_radians().cos()).powi(3) / (h * h);
            println!(
                "open floor {p:?}: C {c:.2}°, γ {gamma:.2}°, E {:.6} lx, I cos³γ/h² {want:.6} lx",
                direct[k]
            );
            assert!(want > 10.0, "a meaningful point: {want}");
            assert!((direct[k] / want - 1.0).abs() < 1e-5, "{p:?}: {} vs {want}", direct[k]);
            assert_eq!(se[k], 0.0, "a point source's direct term is exact");
        }
        assert_eq!(direct[3], 0.0, "under the desk: no direct light");

        // Total: inter-reflection adds light everywhere, and reaches under the desk.
        let (s, total, total_se) = illuminance(ctx, scene, &points, None);
        assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
        for k in 0..points.len() {
            println!(
                "{:?}: total {:.3} ± {:.3} lx, direct {:.3} lx",
                points[k], total[k], total_se[k], direct[k]
            );
            assert!(total[k] > direct[k] && total_se[k] > 0.0, "{:?}", points[k]);
        }
        assert!(total[3] < 0.5 * total[0], "under the desk is darker: {total:?}");

        // The BEGA (area source) against the Rust tracer: the same numbers, bit for bit.
        assert_eq!(lumi_instance_destroy(ctx, inst), LUMI_STATUS_OK);
        let mut bega: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("misc/arnold-usd_bega_50804K3.ies").as_ptr(), &mut bega),
            LUMI_STATUS_OK
        );
        assert_eq!(lumi_instance_create(ctx, bega, m.as_ptr(), &mut inst), LUMI_STATUS_OK);
        let rust_scene = lumiview::scene::load(std::path::Path::new(
            &(env!("CARGO_MANIFEST_DIR").to_string() + "/assets/scenes/office.glb"),
        ))
        .unwrap();
        let lums = [SceneLuminaire {
            photometry: gpu_common::bega(),
            scene_from_luminaire: glam::Mat4::from_cols_array(&m).as_dmat4(),
        }];
        let tracer = Tracer::new(&rust_scene, &lums).unwrap();
        let sp: Vec<SurfacePoint> = points
            .iter()
            .map(|p| SurfacePoint {
                position_m: Vec3::from_array(*p).as_dvec3(),
                normal: DVec3::Y,
            })
            .collect();
        for (opts, paths) in [(direct_only(), 0), (lumi_illuminance_options_default(), 512)] {
            let (s, lx, se) = illuminance(ctx, scene, &points, Some(&opts));
            assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
            let want = tracer
                .illuminance(
                    &sp,
                    &TraceOptions {
                        paths_per_point: paths,
                        ..TraceOptions::default()
                    },
                )
                .unwrap();
            for k in 0..points.len() {
                let w = &want[k];
                let w_se = if paths == 0 { w.direct_se_lx } else { w.total_se_lx };
                assert_eq!((lx[k], se[k]), (w.total_lx, w_se), "{:?}, {paths} paths", points[k]);
            }
            assert!(lx[0] > 0.0 && se[0] > 0.0, "{lx:?} {se:?}");
        }
        // The standard errors are optional.
        let normals = vec![[0.0f32, 1.0, 0.0]; points.len()];
        let mut lx = vec![0.0; points.len()];
        assert_eq!(
            lumi_scene_illuminance(
                ctx,
                scene,
                points.as_ptr().cast(),
                normals.as_ptr().cast(),
                points.len(),
                ptr::null(),
                lx.as_mut_ptr(),
                ptr::null_mut()
            ),
            LUMI_STATUS_OK
        );
        assert!(lx[0] > 0.0);
        lumi_context_destroy(ctx);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The defaults converge in the office as documented: six ASA luminaires (`OFFICE_LUMINAIRES`),
/// 100 points of the work plane at 0.8 m, median standard error ≤ 1 % of the total (measured and
/// timed in docs/scene-lighting.md, "C API").
#[test]
fn the_defaults_converge_on_the_office_work_plane() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals.
    unsafe {
        let mut scene: lumi_scene = 0;
        assert_eq!(lumi_scene_load(ctx, office().as_ptr(), &mut scene), LUMI_STATUS_OK);
        let mut lum: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("misc/luxcore_ASA_15M_R2.ies").as_ptr(), &mut lum),
            LUMI_STATUS_OK
        );
        for p in OFFICE_LUMINAIRES {
            let m = p.matrix().as_mat4().to_cols_array();
            let mut inst: lumi_instance = 0;
            assert_eq!(lumi_instance_create(ctx, lum, m.as_ptr(), &mut inst), LUMI_STATUS_OK);
        }
        let mut points = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                points.push([-2.7 + 0.6 * i as f32, 0.8, -1.8 + 0.4 * j as f32]);
            }
        }
        // The standard error relative to the total: median, 90th percentile, worst (lit points).
        let spread = |lx: &[f64], se: &[f64]| {
            let mut rel: Vec<f64> = lx
                .iter()
                .zip(se)
                .filter(|(e, _)| **e > 1.0)
                .map(|(e, s)| s / e)
                .collect();
            rel.sort_by(f64::total_cmp);
            (
                rel.len(),
                rel[rel.len() / 2],
                rel[rel.len() * 9 / 10],
                rel[rel.len() - 1],
            )
        };
        // The cost of other path counts, for docs/scene-lighting.md (the defaults are 512).
        for paths in [0, 128, 256, 1024] {
            let mut o = lumi_illuminance_options_default();
            if paths == 0 {
                o.light = LUMI_ILLUMINANCE_DIRECT;
            } else {
                o.paths_per_point = paths;
            }
            let t = std::time::Instant::now();
            let (s, lx, se) = illuminance(ctx, scene, &points, Some(&o));
            let elapsed = t.elapsed();
            assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
            let (_, median, p90, worst) = spread(&lx, &se);
            println!(
                "{paths} paths: {elapsed:?} per 100 points; standard error median {:.2} %, 90th percentile {:.2} %, \
                 worst {:.2} %",
                median * 100.0,
                p90 * 100.0,
                worst * 100.0
            );
        }
        let t = std::time::Instant::now();
        let (s, lx, se) = illuminance(ctx, scene, &points, None);
        let elapsed = t.elapsed();
        assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
        let (lit, median, p90, worst) = spread(&lx, &se);
        let mean = lx.iter().sum::<f64>() / lx.len() as f64;
        println!(
            "defaults, 100 work-plane points, 6 ASA luminaires: {elapsed:?}; {lit} lit, mean {mean:.1} lx; \
             standard error median {:.2} %, 90th percentile {:.2} %, worst {:.2} %",
            median * 100.0,
            p90 * 100.0,
            worst * 100.0
        );
        assert!(lit >= 95, "nearly every point is lit: {lit}");
        assert!(median <= 0.01, "median standard error {median}");
        lumi_context_destroy(ctx);
    }
}

/// Every bad argument is refused with the argument named and the outputs untouched; an instance
/// that scales is named by its handle.
#[test]
fn scene_illuminance_refuses_bad_arguments() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals (the NULLs
    // are what is being tested).
    unsafe {
        let mut scene: lumi_scene = 0;
        assert_eq!(lumi_scene_load(ctx, office().as_ptr(), &mut scene), LUMI_STATUS_OK);
        let mut lum: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("misc/luxcore_ASA_15M_R2.ies").as_ptr(), &mut lum),
            LUMI_STATUS_OK
        );
        let mut inst: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, lum, model().as_ptr(), &mut inst),
            LUMI_STATUS_OK
        );
        let p = [0.0f32, 0.0, 1.2, 0.5, 0.0, -0.1];
        let n = [0.0f32, 1.0, 0.0, 0.0, 1.0, 0.0];
        let call = |scene: lumi_scene,
                    p: *const f32,
                    n: *const f32,
                    count: usize,
                    o: *const lumi_illuminance_options,
                    lx: bool,
                    want: lumi_status,
                    arg: &str| {
            let (mut out, mut se) = ([-1.0; 2], [-1.0; 2]);
            let lx_ptr = if lx { out.as_mut_ptr() } else { ptr::null_mut() };
            let s = lumi_scene_illuminance(ctx, scene, p, n, count, o, lx_ptr, se.as_mut_ptr());
            let e = last_error();
            assert_eq!(s, want, "{arg}: {e}");
            assert!(
                e.starts_with("lumi_scene_illuminance: ") && e.contains(&format!("'{arg}'")),
                "{arg}: {e}"
            );
            assert_eq!((out, se), ([-1.0; 2], [-1.0; 2]), "{arg}: outputs untouched");
            e
        };
        let d = lumi_illuminance_options_default();
        let null = ptr::null();
        call(
            scene,
            null,
            n.as_ptr(),
            2,
            &d,
            true,
            LUMI_STATUS_NULL_POINTER,
            "points_m",
        );
        call(
            scene,
            p.as_ptr(),
            null,
            2,
            &d,
            true,
            LUMI_STATUS_NULL_POINTER,
            "normals",
        );
        call(
            scene,
            p.as_ptr(),
            n.as_ptr(),
            2,
            &d,
            false,
            LUMI_STATUS_NULL_POINTER,
            "out_lx",
        );
        let bad = LUMI_STATUS_INVALID_ARGUMENT;
        call(scene, p.as_ptr(), n.as_ptr(), 0, &d, true, bad, "count");
        let too_many = LUMI_ILLUMINANCE_MAX_POINTS as usize + 1;
        let e = call(scene, p.as_ptr(), n.as_ptr(), too_many, &d, true, bad, "count");
        assert!(e.contains("1048577"), "{e}");
        let with = |f: &dyn Fn(&mut lumi_illuminance_options)| {
            let mut o = d;
            f(&mut o);
            o
        };
        let o = with(&|o| o.light = 9);
        call(scene, p.as_ptr(), n.as_ptr(), 2, &o, true, bad, "opts.light");
        let o = with(&|o| o.paths_per_point = 0);
        call(scene, p.as_ptr(), n.as_ptr(), 2, &o, true, bad, "opts.paths_per_point");
        let o = with(&|o| o.direct_estimates = LUMI_ILLUMINANCE_MAX_SAMPLES + 1);
        call(scene, p.as_ptr(), n.as_ptr(), 2, &o, true, bad, "opts.direct_estimates");
        let o = with(&|o| o.area_samples = 0);
        call(scene, p.as_ptr(), n.as_ptr(), 2, &o, true, bad, "opts.area_samples");
        for h in [0, lum, inst, scene + 1] {
            call(h, p.as_ptr(), n.as_ptr(), 2, &d, true, bad, "scene");
        }
        let mut nan = p;
        nan[4] = f32::NAN;
        let e = call(scene, nan.as_ptr(), n.as_ptr(), 2, &d, true, bad, "points_m");
        assert!(e.contains("point 1"), "{e}");
        let mut zero = n;
        zero[1] = 0.0;
        let e = call(scene, p.as_ptr(), zero.as_ptr(), 2, &d, true, bad, "normals");
        assert!(e.contains("normal 0"), "{e}");
        let mut inf = n;
        inf[5] = f32::INFINITY;
        call(scene, p.as_ptr(), inf.as_ptr(), 2, &d, true, bad, "normals");

        // A model matrix that scales (accepted for drawing) is refused by the tracer, naming it.
        let scaled = (glam::Mat4::from_cols_array(&model()) * glam::Mat4::from_scale(Vec3::splat(2.0))).to_cols_array();
        let mut big: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, lum, scaled.as_ptr(), &mut big),
            LUMI_STATUS_OK
        );
        let e = call(scene, p.as_ptr(), n.as_ptr(), 2, &d, true, bad, "instance");
        assert!(
            e.contains(&format!("{big:#x}")) && e.contains("scales or shears"),
            "{e}"
        );
        let mut mirrored = model();
        mirrored[0] = -mirrored[0];
        mirrored[1] = -mirrored[1];
        mirrored[2] = -mirrored[2];
        assert_eq!(lumi_instance_set_transform(ctx, big, mirrored.as_ptr()), LUMI_STATUS_OK);
        let e = call(scene, p.as_ptr(), n.as_ptr(), 2, &d, true, bad, "instance");
        assert!(e.contains("mirrors"), "{e}");
        assert_eq!(lumi_instance_destroy(ctx, big), LUMI_STATUS_OK);
        let (s, lx, _) = illuminance(ctx, scene, &[[0.0, 0.0, 1.2]], Some(&direct_only()));
        assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
        assert!(lx[0] > 0.0);
        lumi_context_destroy(ctx);
    }
}

/// A near-field scan placed in the scene lights it by the far field estimated from its images,
/// in `lumi_scene_illuminance` and in the drawn scene alike: the synthetic Lambertian disc
/// (r = 0.1 m, 10,000 cd/m²) 1 m over an open floor point, facing down, gives the analytic
/// E = L·π·r² / (r² + h²) = 311.0 lx there (within 3 %: the estimator's kernel), and the drawn
/// floor pixel is within 1 % of the C API's direct term.
#[test]
fn nearfield_instances_light_by_their_far_field() {
    use lumiview::nearfield::layout::Layout;
    use lumiview::nearfield::pack::{write_pack, PackOptions};
    use lumiview::nearfield::synth::{self, SynthOptions};
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    let dir = temp_dir("scene-nearfield");
    let opts = SynthOptions {
        luminaire: "disc".into(),
        layout: Layout::Fibonacci { count: 600 },
        size: (32, 32),
        supersample: 2,
        ..SynthOptions::default()
    };
    let pack = dir.join("disc.lvpack");
    write_pack(
        &synth::synth_scan(&opts).unwrap(),
        &pack,
        &PackOptions::default(),
        &|_, _| {},
    )
    .unwrap();
    const SIZE: usize = 33;
    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals.
    unsafe {
        let mut scene: lumi_scene = 0;
        assert_eq!(lumi_scene_load(ctx, office().as_ptr(), &mut scene), LUMI_STATUS_OK);
        let mut scan: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cstr(&pack).as_ptr(), &mut scan),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let floor = OPEN_FLOOR[0];
        let over = placement(floor[0].into(), 1.0, floor[2].into(), 0.0)
            .as_mat4()
            .to_cols_array();
        let mut near: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, scan, over.as_ptr(), &mut near),
            LUMI_STATUS_OK
        );
        let (s, e, _) = illuminance(ctx, scene, &[floor], Some(&direct_only()));
        assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
        let analytic = 10_000.0 * std::f64::consts::PI * 0.01 / 1.01;
        println!("under the scanned disc: {:.2} lx, analytic {analytic:.2} lx", e[0]);
        assert!((e[0] / analytic - 1.0).abs() < 0.03, "{} vs {analytic}", e[0]);

        // Drawn: the floor point seen obliquely (the scan itself is off the line of sight).
        let mut set = lumi_scene_settings_default();
        set.indirect = false;
        assert_eq!(lumi_context_set_scene_settings(ctx, &set), LUMI_STATUS_OK);
        assert_eq!(lumi_context_set_scene(ctx, scene), LUMI_STATUS_OK, "{}", last_error());
        let mut td = lumi_target_desc_default();
        td.width = SIZE as u32;
        td.height = SIZE as u32;
        td.exportable = false;
        let mut target: lumi_target = 0;
        assert_eq!(lumi_target_create(ctx, &td, &mut target), LUMI_STATUS_OK);
        let at = Vec3::from_array(floor);
        let mut cam = lumi_camera_default();
        cam.view = look_at(at + Vec3::new(1.0, 1.5, 0.0), at, Vec3::Y).to_cols_array();
        cam.projection = gl_perspective(20f32.to_radians(), 1.0, 0.1, 10.0).to_cols_array();
        assert_eq!(
            lumi_render(ctx, target, &cam, ptr::null()),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let c = SIZE / 2;
        let px = rgba(ctx, target, SIZE, c, c);
        let l = luminance_y([px[0].into(), px[1].into(), px[2].into()]);
        let e_pixel = std::f64::consts::PI * l / luminance_y([0.25, 0.19, 0.14]);
        println!("drawn floor pixel: E = πL/ρ {e_pixel:.2} lx");
        assert!((e_pixel / e[0] - 1.0).abs() < 0.01, "{e_pixel} vs {}", e[0]);
        lumi_context_destroy(ctx);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Reads pixel (x, y) of an RGBA32F target: (R, G, B, A).
///
/// # Safety
/// `ctx` is live and `target` one of its `size` × `size` RGBA32F targets.
unsafe fn rgba(ctx: *mut lumi_context, target: lumi_target, size: usize, x: usize, y: usize) -> [f32; 4] {
    let mut px = vec![0u8; size * size * 16];
    let mut written = 0;
    // SAFETY: a buffer of the stated length; ctx and target per the caller.
    let s = unsafe {
        lumi_target_read_pixels(
            ctx,
            target,
            LUMI_ATTACHMENT_COLOR,
            px.as_mut_ptr(),
            px.len(),
            &mut written,
        )
    };
    assert_eq!(s, LUMI_STATUS_OK, "{}", last_error());
    let f: &[f32] = bytemuck::cast_slice(&px);
    let i = (y * size + x) * 4;
    [f[i], f[i + 1], f[i + 2], f[i + 3]]
}

/// `lumi_context_set_scene` makes `lumi_render` draw the office lit: the floor pixel straight below
/// the camera shows E = π·L/ρ_Y within 1 % of `lumi_scene_illuminance`'s direct term there; the
/// settings are checked field by field; destroying the drawn scene (or setting 0) draws none.
#[test]
fn the_scene_set_on_the_context_is_drawn_lit() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    const SIZE: usize = 33;
    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals.
    unsafe {
        let mut scene: lumi_scene = 0;
        assert_eq!(lumi_scene_load(ctx, office().as_ptr(), &mut scene), LUMI_STATUS_OK);
        let mut lum: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("misc/luxcore_ASA_15M_R2.ies").as_ptr(), &mut lum),
            LUMI_STATUS_OK
        );
        let mut inst: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, lum, model().as_ptr(), &mut inst),
            LUMI_STATUS_OK
        );
        let mut td = lumi_target_desc_default();
        td.width = SIZE as u32;
        td.height = SIZE as u32;
        td.exportable = false;
        let mut target: lumi_target = 0;
        assert_eq!(lumi_target_create(ctx, &td, &mut target), LUMI_STATUS_OK);
        // Looking straight down at the open floor point (0, 0, 1.2) from 2 m: the centre pixel.
        let floor = OPEN_FLOOR[0];
        let at = Vec3::from_array(floor);
        let mut cam = lumi_camera_default();
        cam.view = look_at(at + Vec3::Y * 2.0, at, Vec3::NEG_Z).to_cols_array();
        cam.projection = gl_perspective(40f32.to_radians(), 1.0, 0.1, 10.0).to_cols_array();
        let c = SIZE / 2;

        // Settings: each bad field named, nothing changed; the defaults and shadows off are fine.
        let mut set = lumi_scene_settings_default();
        assert!(set.shadows && set.lux_floor_lx == 0.1 && set.max_face_px == 512);
        assert!(set.indirect && set.bounce_photons == 256 && set.vpl_clamp_m == 0.25);
        assert_eq!(
            lumi_context_set_scene_settings(ctx, ptr::null()),
            LUMI_STATUS_NULL_POINTER
        );
        type Spoil<'a> = &'a dyn Fn(&mut lumi_scene_settings);
        let cases: [(Spoil, &str); 8] = [
            (&|s| s.lux_floor_lx = f32::NAN, "settings.lux_floor_lx"),
            (&|s| s.lux_floor_lx = 0.0, "settings.lux_floor_lx"),
            (&|s| s.shadow_budget_bytes = 0, "settings.shadow_budget_bytes"),
            (&|s| s.max_face_px = 8, "settings.max_face_px"),
            (&|s| s.bounce_photons = 0, "settings.bounce_photons"),
            (&|s| s.bounce_photons = 1 << 17, "settings.bounce_photons"),
            (&|s| s.vpl_clamp_m = f32::NAN, "settings.vpl_clamp_m"),
            (&|s| s.shadow_updates_per_frame = 0, "settings.shadow_updates_per_frame"),
        ];
        for (f, field) in cases {
            let mut bad = lumi_scene_settings_default();
            f(&mut bad);
            assert_eq!(lumi_context_set_scene_settings(ctx, &bad), LUMI_STATUS_INVALID_ARGUMENT);
            assert!(last_error().contains(&format!("'{field}'")), "{}", last_error());
        }
        set.shadows = false;
        assert_eq!(lumi_context_set_scene_settings(ctx, &set), LUMI_STATUS_OK);
        set.shadows = true;
        // Direct light first: the pixel against the C API's direct term.
        set.indirect = false;
        assert_eq!(lumi_context_set_scene_settings(ctx, &set), LUMI_STATUS_OK);

        // Without a scene: nothing where the floor is.
        assert_eq!(
            lumi_render(ctx, target, &cam, ptr::null()),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert_eq!(rgba(ctx, target, SIZE, c, c)[3], 0.0);
        // With it: the lit floor, E = π L / ρ_Y against the C API's direct term.
        for h in [lum, inst, target, scene + 1] {
            assert_eq!(lumi_context_set_scene(ctx, h), LUMI_STATUS_INVALID_ARGUMENT);
            assert!(last_error().contains("'scene'"), "{}", last_error());
        }
        assert_eq!(lumi_context_set_scene(ctx, scene), LUMI_STATUS_OK, "{}", last_error());
        assert_eq!(lumi_context_set_scene(ctx, scene), LUMI_STATUS_OK, "setting it again");
        assert_eq!(
            lumi_render(ctx, target, &cam, ptr::null()),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let px = rgba(ctx, target, SIZE, c, c);
        let l = luminance_y([px[0].into(), px[1].into(), px[2].into()]);
        let rho = luminance_y([0.25, 0.19, 0.14]);
        let e_pixel = std::f64::consts::PI * l / rho;
        let (s, e, _) = illuminance(ctx, scene, &[floor], Some(&direct_only()));
        assert_eq!(s, LUMI_STATUS_OK);
        println!(
            "floor pixel: L {l:.4} cd/m², E = πL/ρ {e_pixel:.3} lx; lumi_scene_illuminance direct {:.3} lx",
            e[0]
        );
        assert_eq!(px[3], 1.0);
        assert!((e_pixel / e[0] - 1.0).abs() < 0.01, "{e_pixel} vs {}", e[0]);
        // With inter-reflection (the default), against the C API's total with every bounce: the
        // GPU's virtual point lights at one open floor point (docs/scene-lighting.md measures the
        // method on the work plane).
        set.indirect = true;
        assert_eq!(lumi_context_set_scene_settings(ctx, &set), LUMI_STATUS_OK);
        assert_eq!(lumi_render(ctx, target, &cam, ptr::null()), LUMI_STATUS_OK);
        let px = rgba(ctx, target, SIZE, c, c);
        let e_total_pixel = std::f64::consts::PI * luminance_y([px[0].into(), px[1].into(), px[2].into()]) / rho;
        let (s, total, _) = illuminance(ctx, scene, &[floor], None);
        assert_eq!(s, LUMI_STATUS_OK);
        println!(
            "with inter-reflection: E = πL/ρ {e_total_pixel:.3} lx; lumi_scene_illuminance total {:.3} lx",
            total[0]
        );
        assert!(total[0] > e[0] && e_total_pixel > e_pixel);
        assert!(
            (e_total_pixel / total[0] - 1.0).abs() < 0.1,
            "{e_total_pixel} vs {}",
            total[0]
        );
        // A scaled instance cannot send photons: with inter-reflection on, lumi_render names it by
        // its handle; with it off, the instance is drawn.
        let mut scaled = model();
        for v in scaled.iter_mut().take(12) {
            *v *= 2.0;
        }
        let mut big: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, lum, scaled.as_ptr(), &mut big),
            LUMI_STATUS_OK
        );
        assert_eq!(
            lumi_render(ctx, target, &cam, ptr::null()),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        let err = last_error();
        assert!(
            err.contains("'instance'") && err.contains(&format!("{big:#x}")) && err.contains("scales or shears"),
            "{err}"
        );
        set.indirect = false;
        assert_eq!(lumi_context_set_scene_settings(ctx, &set), LUMI_STATUS_OK);
        assert_eq!(
            lumi_render(ctx, target, &cam, ptr::null()),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert_eq!(lumi_instance_destroy(ctx, big), LUMI_STATUS_OK);
        set.indirect = true;
        assert_eq!(lumi_context_set_scene_settings(ctx, &set), LUMI_STATUS_OK);

        // Destroying the drawn scene stops drawing it; so does setting 0.
        let mut other: lumi_scene = 0;
        assert_eq!(lumi_scene_load(ctx, office().as_ptr(), &mut other), LUMI_STATUS_OK);
        assert_eq!(lumi_scene_destroy(ctx, scene), LUMI_STATUS_OK);
        assert_eq!(
            lumi_render(ctx, target, &cam, ptr::null()),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert_eq!(
            rgba(ctx, target, SIZE, c, c),
            [0.0; 4],
            "the destroyed scene is not drawn"
        );
        assert_eq!(lumi_context_set_scene(ctx, scene), LUMI_STATUS_INVALID_ARGUMENT);
        assert_eq!(lumi_context_set_scene(ctx, other), LUMI_STATUS_OK);
        assert_eq!(lumi_render(ctx, target, &cam, ptr::null()), LUMI_STATUS_OK);
        assert_eq!(rgba(ctx, target, SIZE, c, c), px, "the other office, drawn the same");
        assert_eq!(lumi_context_set_scene(ctx, 0), LUMI_STATUS_OK);
        assert_eq!(lumi_render(ctx, target, &cam, ptr::null()), LUMI_STATUS_OK);
        assert_eq!(rgba(ctx, target, SIZE, c, c)[3], 0.0, "scene 0: none drawn");
        lumi_context_destroy(ctx);
    }
    gpu_common::assert_no_validation_messages();
}
