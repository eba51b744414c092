//! Benchmark of the scene lighting pass, run by `scripts/bench-scene` (which prints the table).
//!
//! ```text
//! bench_scene [--size 640x360 ...] [--runs 9]
//! ```
//!
//! Cases, each a frame of `Renderer::render` into an RGBA32F target (submission and wait included:
//! what a host pays per `lumi_render`), timed as the median of `--runs` after one warm-up, with
//! shadow maps and virtual point lights cached (nothing moves), and again with one luminaire moved
//! before every frame (shadows and VPLs made again):
//! - the office (`assets/scenes/office.glb`) with one BEGA luminaire: direct light without shadows,
//!   with shadows, with shadows and inter-reflection (the defaults: 256 photons);
//! - a generated hall (32 × 32 × 5 m, 16 pillars) with 16 and with 256 luminaires on a square grid
//!   at 4.5 m, shadows and inter-reflection (the defaults);
//! - the office with eight statues (`scene::sample::office_with_statues`, 292,238 triangles), one
//!   luminaire, shadows and inter-reflection from about 100 and about 400 virtual point lights (the
//!   paper's RSM sample counts).
//!
//! Each static frame is also timed lit per fragment as the triangles are drawn
//! (`SceneSettings::deferred_max_pixels` = 0, the path of frames too large for the compute
//! lighting's per-pixel buffers): `fragment_static_ms`.
//!
//! Two trivial passes of the same size (a full-screen triangle writing a constant; a compute pass
//! storing one), timed before, between and after the cases, are the baseline: ratios are what to
//! read on a software device, absolute times only on a real GPU. Prints one JSON object.

use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use glam::{DMat4, DVec3, Mat4, Vec3};
use serde_json::json;

#[path = "common/bench.rs"]
mod bench;
use bench::{median, median_ms, plain_target, Res, Trivial, TrivialCompute};

use lumiview::gpu::scene::SceneSettings;
use lumiview::gpu::{
    ColorFormat, ContextDesc, DepthFormat, DepthRange, HostCamera, InstanceId, Origin, RenderOptions, RenderTarget,
    Renderer, TargetDesc,
};
use lumiview::photometry::{LoadOptions, Photometry};
use lumiview::scene::sample::{box_triangles, office_with_statues};
use lumiview::scene::{placement, Material, Scene, SceneParts};

struct Args {
    sizes: Vec<(u32, u32)>,
    runs: usize,
}

fn parse_args() -> Res<Args> {
    let mut a = Args {
        sizes: Vec::new(),
        runs: 9,
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or_else(|| format!("{k} needs a value"));
        match k.as_str() {
            "--runs" => a.runs = v()?.parse::<usize>()?.max(5),
            "--size" => {
                let s = v()?;
                let (w, h) = s.split_once('x').ok_or_else(|| format!("--size {s}: expected WxH"))?;
                a.sizes.push((w.parse()?, h.parse()?));
            }
            _ => return Err(format!("unknown argument {k}").into()),
        }
    }
    if a.sizes.is_empty() {
        a.sizes.push((640, 360));
    }
    Ok(a)
}

/// A hall of 32 × 32 × 5 m (floor 0.2, walls 0.5, ceiling 0.7) with 16 pillars (0.4 m square,
/// 0.5) on an 8 m grid.
fn hall() -> Res<Scene> {
    let mut parts = SceneParts::default();
    let mut add = |tris: Vec<[DVec3; 3]>, m: u32| {
        parts.material_of.extend(std::iter::repeat_n(m, tris.len()));
        parts.triangles.extend(tris);
    };
    let room = box_triangles(DVec3::new(-16.0, 0.0, -16.0), DVec3::new(16.0, 5.0, 16.0), true);
    for t in room {
        let m = if t.iter().all(|v| v.y == 0.0) {
            0
        } else if t.iter().all(|v| v.y == 5.0) {
            2
        } else {
            1
        };
        add(vec![t], m);
    }
    for i in 0..4 {
        for k in 0..4 {
            let (x, z) = (-12.0 + 8.0 * f64::from(i), -12.0 + 8.0 * f64::from(k));
            add(
                box_triangles(
                    DVec3::new(x - 0.2, 0.0, z - 0.2),
                    DVec3::new(x + 0.2, 5.0, z + 0.2),
                    false,
                ),
                1,
            );
        }
    }
    parts.uvs = vec![[[0.0; 2]; 3]; parts.triangles.len()];
    parts.materials = vec![Material::grey(0.2), Material::grey(0.5), Material::grey(0.7)];
    Ok(Scene::new(parts)?)
}

fn camera(eye: Vec3, at: Vec3, w: u32, h: u32) -> HostCamera {
    let f = (at - eye).normalize();
    let s = f.cross(Vec3::Y).normalize();
    let u = s.cross(f);
    let view = Mat4::from_cols(
        glam::Vec4::new(s.x, u.x, -f.x, 0.0),
        glam::Vec4::new(s.y, u.y, -f.y, 0.0),
        glam::Vec4::new(s.z, u.z, -f.z, 0.0),
        glam::Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    );
    let (near, far) = (0.05f32, 100.0f32);
    let t = 1.0 / (60f32.to_radians() / 2.0).tan();
    let projection = Mat4::from_cols(
        glam::Vec4::new(t * h as f32 / w as f32, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, t, 0.0, 0.0),
        glam::Vec4::new(0.0, 0.0, far / (near - far), -1.0),
        glam::Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
    );
    HostCamera {
        view,
        projection,
        depth_range: DepthRange::ZeroToOne,
        reversed_z: false,
        origin: Origin::TopLeft,
    }
}

/// One case: a scene, luminaire placements, settings and a view.
struct Case {
    name: String,
    scene: Arc<Scene>,
    placements: Vec<DMat4>,
    settings: SceneSettings,
    eye: Vec3,
    at: Vec3,
}

/// Photons that leave about `vpls` virtual point lights for `placements` in `scene` (one trial).
fn photons_for(scene: &Scene, p: &Arc<Photometry>, placements: &[DMat4], vpls: usize) -> Res<u32> {
    use lumiview::scene::vpl::{VplOptions, VplSet};
    let bvh = lumiview::scene::bvh::Bvh::build(scene);
    let lums: Vec<_> = placements
        .iter()
        .map(|m| lumiview::scene::SceneLuminaire {
            photometry: p.clone(),
            scene_from_luminaire: *m,
        })
        .collect();
    let trial = VplSet::generate(
        scene,
        &bvh,
        &lums,
        &VplOptions {
            photons: 1000,
            ..VplOptions::default()
        },
    )?;
    let per_photon = trial.vpls.len().max(1) as f64 / 1000.0;
    Ok(((vpls as f64 / per_photon).round() as u32).max(1))
}

fn run(a: &Args) -> Res<serde_json::Value> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let bega = Arc::new(lumiview::photometry::load(
        &root.join("tests/data/misc/arnold-usd_bega_50804K3.ies"),
        &LoadOptions::default(),
    )?);
    let office = Arc::new(lumiview::scene::load(&root.join("assets/scenes/office.glb"))?);
    let statues_glb = office_with_statues().to_glb()?;
    let statues = Arc::new(lumiview::scene::load_from_slice(
        &statues_glb,
        std::path::Path::new("office_with_statues.glb"),
        None,
    )?);
    let hall = Arc::new(hall()?);
    let one = vec![placement(0.0, 2.4, 0.0, 0.0)];
    let grid = |n: usize| -> Vec<DMat4> {
        let step = 32.0 / n as f64;
        (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) as f64, (k / n) as f64);
                placement(-16.0 + step * (i + 0.5), 4.5, -16.0 + step * (j + 0.5), 0.0)
            })
            .collect()
    };
    let office_eye = (Vec3::new(-2.52, 1.65, 1.68), Vec3::new(1.32, 0.9, -0.8));
    let hall_eye = (Vec3::new(-15.0, 1.7, 15.0), Vec3::new(0.0, 1.5, 0.0));
    let d = SceneSettings::default();
    let mut cases = vec![
        Case {
            name: "office, 1 luminaire, direct light without shadows".into(),
            scene: office.clone(),
            placements: one.clone(),
            settings: SceneSettings {
                shadows: false,
                indirect: false,
                ..d
            },
            eye: office_eye.0,
            at: office_eye.1,
        },
        Case {
            name: "office, 1 luminaire, shadows".into(),
            scene: office.clone(),
            placements: one.clone(),
            settings: SceneSettings { indirect: false, ..d },
            eye: office_eye.0,
            at: office_eye.1,
        },
        Case {
            name: "office, 1 luminaire, shadows + inter-reflection".into(),
            scene: office.clone(),
            placements: one.clone(),
            settings: d,
            eye: office_eye.0,
            at: office_eye.1,
        },
        Case {
            name: "hall, 16 luminaires, shadows + inter-reflection".into(),
            scene: hall.clone(),
            placements: grid(4),
            settings: d,
            eye: hall_eye.0,
            at: hall_eye.1,
        },
        Case {
            name: "hall, 256 luminaires, shadows + inter-reflection".into(),
            scene: hall.clone(),
            placements: grid(16),
            settings: d,
            eye: hall_eye.0,
            at: hall_eye.1,
        },
    ];
    for target in [100usize, 400] {
        cases.push(Case {
            name: format!(
                "{} triangles, 1 luminaire, shadows + ~{target} VPLs",
                statues.triangles().len()
            ),
            scene: statues.clone(),
            placements: one.clone(),
            settings: SceneSettings {
                bounce_photons: photons_for(&statues, &bega, &one, target)?,
                ..d
            },
            eye: office_eye.0,
            at: office_eye.1,
        });
    }
    let mut r = Renderer::new(&ContextDesc::default())?;
    let lum = r.add_photometry(bega.clone())?;
    let trivial = Trivial::new(&r.ctx.device);
    let mut sizes = Vec::new();
    for &(w, h) in &a.sizes {
        eprintln!("{w}×{h}: trivial passes");
        let plain = plain_target(&r, w, h);
        let compute = TrivialCompute::new(&r.ctx.device, w, h);
        let mut trivial_r = median_ms(|| trivial.frame(&r, &plain), a.runs)?.1;
        let mut trivial_c = median_ms(|| compute.frame(&r), a.runs)?.1;
        let mut target = RenderTarget::new(
            &r.ctx,
            &TargetDesc {
                width: w,
                height: h,
                color: ColorFormat::Rgba32Float,
                depth: DepthFormat::None,
                exportable: false,
                semaphores: false,
            },
        )?;
        let mut rows = Vec::new();
        for c in &cases {
            eprintln!("{w}×{h}: {}", c.name);
            r.set_scene_shared(c.scene.clone(), None)?;
            r.set_scene_settings(c.settings)?;
            let ids: Vec<InstanceId> = c
                .placements
                .iter()
                .map(|m| r.add_instance(lum, m.as_mat4()))
                .collect::<Result<_, _>>()?;
            let cam = camera(c.eye, c.at, w, h);
            let opts = RenderOptions::default();
            let t_first = Instant::now();
            r.render(&mut target, &cam, &opts)?;
            let first_ms = t_first.elapsed().as_secs_f64() * 1e3;
            let (static_ms, _) = median_ms(
                || {
                    r.render(&mut target, &cam, &opts)?;
                    Ok(())
                },
                a.runs,
            )?;
            // The same frame lit per fragment as the triangles are drawn (the path of frames
            // larger than SceneSettings::deferred_max_pixels).
            r.set_scene_settings(SceneSettings {
                deferred_max_pixels: 0,
                ..c.settings
            })?;
            let (fragment_ms, _) = median_ms(
                || {
                    r.render(&mut target, &cam, &opts)?;
                    Ok(())
                },
                a.runs,
            )?;
            r.set_scene_settings(c.settings)?;
            // One luminaire moves 1 cm back and forth: its shadows and every VPL are made again.
            let mut k = 0u32;
            let base = c.placements[0].as_mat4();
            let (moved_ms, _) = median_ms(
                || {
                    k += 1;
                    let dx = if k.is_multiple_of(2) { 0.0 } else { 0.01 };
                    r.set_transform(ids[0], Mat4::from_translation(Vec3::new(dx, 0.0, 0.0)) * base)?;
                    r.render(&mut target, &cam, &opts)?;
                    Ok(())
                },
                a.runs.min(5),
            )?;
            let stats = r.scene_stats();
            // The CPU part of a change: tracing the photons (the BVH built beforehand, as the
            // pass keeps it).
            let vpl_generation_ms = if c.settings.indirect {
                let bvh = lumiview::scene::bvh::Bvh::build(&c.scene);
                let lums: Vec<_> = c
                    .placements
                    .iter()
                    .map(|m| lumiview::scene::SceneLuminaire {
                        photometry: bega.clone(),
                        scene_from_luminaire: *m,
                    })
                    .collect();
                let opts = lumiview::scene::vpl::VplOptions {
                    photons: c.settings.bounce_photons as usize,
                    clamp_m: f64::from(c.settings.vpl_clamp_m),
                    ..Default::default()
                };
                let table = Arc::new(lumiview::scene::vpl::EmissionTable::of(&bega));
                let tables = vec![table; lums.len()];
                median_ms(
                    || {
                        lumiview::scene::vpl::VplSet::generate_with(&c.scene, &bvh, &lums, &tables, &opts)?;
                        Ok(())
                    },
                    5,
                )?
                .0
            } else {
                0.0
            };
            for id in ids {
                r.remove_instance(id)?;
            }
            trivial_r.extend(median_ms(|| trivial.frame(&r, &plain), 3)?.1);
            trivial_c.extend(median_ms(|| compute.frame(&r), 3)?.1);
            rows.push(json!({
                "case": c.name,
                "triangles": c.scene.triangles().len(),
                "luminaires": stats.luminaires,
                "vpls": stats.vpls,
                "photons": c.settings.bounce_photons,
                "indirect": c.settings.indirect,
                "shadows": c.settings.shadows,
                "shadow_face_px": stats.shadow_face_px,
                "first_frame_ms": first_ms,
                "static_ms": static_ms,
                "fragment_static_ms": fragment_ms,
                "moved_ms": moved_ms,
                "vpl_generation_ms": vpl_generation_ms,
            }));
        }
        let (tr, tc) = (median(trivial_r), median(trivial_c));
        for row in &mut rows {
            let s = row["static_ms"].as_f64().unwrap_or(f64::NAN);
            let m = row["moved_ms"].as_f64().unwrap_or(f64::NAN);
            row["static_ratio_render"] = json!(s / tr);
            row["static_ratio_compute"] = json!(s / tc);
            row["moved_ratio_render"] = json!(m / tr);
        }
        r.clear_scene();
        sizes.push(json!({"width": w, "height": h, "trivial_ms": tr, "trivial_compute_ms": tc, "cases": rows}));
    }
    Ok(json!({
        "device": r.ctx.caps.adapter_name,
        "is_cpu": r.ctx.caps.is_cpu,
        "runs": a.runs,
        "sizes": sizes,
    }))
}

fn main() -> ExitCode {
    match parse_args().and_then(|a| run(&a)) {
        Ok(v) => {
            println!("{v}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("bench_scene: error: {e}");
            ExitCode::FAILURE
        }
    }
}
