//! GPU tests of the scene lighting pass (issue 20, direct light) on Vulkan (lavapipe in CI), each
//! against an independent reference, never against the pass's own output: the illuminance a pixel
//! shows (E = π·L/ρ_Y, the luminance of its RGB) at points found by casting the pixel's camera ray
//! through the CPU hierarchy (`scene::bvh`), against I(C, γ)·cos³γ/h² written here, and against the
//! CPU reference path tracer's direct term (`scene::reference`) in the sample office; the penumbra
//! of a 1.2 m linear luminaire against the reference's. Measured figures are printed
//! (`--nocapture`) and quoted in docs/scene-lighting.md.
//! In CI (CI=true) a missing adapter fails; locally the tests print why they skip.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod scene_common;

mod gpu_common;

use std::sync::Arc;

use scene_common::{floor, office, photometry_text, scene_of};

use glam::{DMat4, DVec3, Vec3};
use gpu_common::GPU_LOCK;
use lumiview::gpu::scene::SceneSettings;
use lumiview::gpu::{HostCamera, RenderOptions, RenderTarget, Renderer, TargetDesc};
use lumiview::photometry::Photometry;
use lumiview::scene::bvh::Bvh;
use lumiview::scene::model::luminance_y;
use lumiview::scene::sample::OFFICE_LUMINAIRES;
use lumiview::scene::{placement, Scene, SceneLuminaire, SurfacePoint, TraceOptions, Tracer};

/// A synthetic point luminaire with no symmetry: five C planes (0–360°), γ 0–90°.
const ASYMMETRIC_IES: &str = "IESNA:LM-63-2002\n[TEST] asymmetric point source\nTILT=NONE\n\
1 -1 1 5 5 1 2 0 0 0\n1 1 10\n0 22.5 45 67.5 90\n0 90 180 270 360\n\
1000 900 700 400 100\n1000 760 600 300 50\n1000 500 350 150 20\n1000 650 500 250 40\n1000 900 700 400 100\n";

/// A linear luminaire: opening 1.2 m along X (IES length) × 0.1 m along Y (width), I = 1000 cd ·
/// cos γ below.
const LINEAR_IES: &str = "IESNA:LM-63-2002\n[TEST] linear 1.2 m\nTILT=NONE\n\
1 -1 1 5 1 1 2 0.1 1.2 0\n1 1 30\n0 22.5 45 67.5 90\n0\n1000 923.8795 707.1068 382.6834 0\n";

/// The half-plane x ≥ 0 at height `h` (over |z| ≤ 5 m, x ≤ 5 m).
fn plate(h: f64) -> Vec<[DVec3; 3]> {
    let c = |x: f64, z: f64| DVec3::new(x, h, z);
    vec![
        [c(0.0, -5.0), c(0.0, 5.0), c(5.0, 5.0)],
        [c(0.0, -5.0), c(5.0, 5.0), c(5.0, -5.0)],
    ]
}

/// What a pixel's camera ray hits: the point, the normal turned towards the camera, ρ_Y, the
/// triangle; `None` for the background or a textured surface.
#[derive(Debug, Clone, Copy)]
struct Probe {
    px: (u32, u32),
    point: SurfacePoint,
    rho_y: f64,
    triangle: usize,
}

/// A renderer whose scene pass draws direct light only (most tests here measure the direct term).
fn renderer() -> Option<Renderer> {
    let mut r = gpu_common::renderer()?;
    r.set_scene_settings(SceneSettings {
        indirect: false,
        ..SceneSettings::default()
    })
    .unwrap();
    Some(r)
}

/// The camera ray through the centre of pixel (i, j) (row 0 at the top), world space.
fn pixel_ray(cam: &HostCamera, w: u32, h: u32, i: u32, j: u32) -> (DVec3, DVec3) {
    let inv: DMat4 = cam.clip_from_world().as_dmat4().inverse();
    let x = (f64::from(i) + 0.5) / f64::from(w) * 2.0 - 1.0;
    let y = 1.0 - (f64::from(j) + 0.5) / f64::from(h) * 2.0;
    let p0 = inv.project_point3(DVec3::new(x, y, 0.0));
    let p1 = inv.project_point3(DVec3::new(x, y, 1.0));
    (p0, (p1 - p0).normalize())
}

fn probe(scene: &Scene, bvh: &Bvh, cam: &HostCamera, w: u32, h: u32, i: u32, j: u32) -> Option<Probe> {
    let (o, d) = pixel_ray(cam, w, h, i, j);
    let hit = bvh.closest_hit(o, d, 1e3)?;
    let tri = scene.triangles()[hit.triangle];
    let material = &scene.materials()[scene.material_of()[hit.triangle] as usize];
    if material.base_color_texture.is_some() {
        return None;
    }
    let mut n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
    if n.dot(d) > 0.0 {
        n = -n;
    }
    Some(Probe {
        px: (i, j),
        point: SurfacePoint {
            position_m: o + d * hit.t,
            normal: n,
        },
        rho_y: luminance_y(material.base_color_factor),
        triangle: hit.triangle,
    })
}

/// Probe pixels on a grid (`border` px in from the edges, every `step` px), kept where the pixel
/// and its four neighbours see one flat surface and no luminaire's opening (the far-field pass
/// draws it there, over the lit room).
fn clear_probes(
    scene: &Scene,
    bvh: &Bvh,
    cam: &HostCamera,
    (w, h): (u32, u32),
    mats: &[DMat4],
    border: u32,
    step: usize,
) -> Vec<Probe> {
    let mut probes = Vec::new();
    for j in (border..h - border).step_by(step) {
        for i in (border..w - border).step_by(step) {
            let Some(p) = probe(scene, bvh, cam, w, h, i, j) else {
                continue;
            };
            let (o, d) = pixel_ray(cam, w, h, i, j);
            if mats.iter().any(|m| hits_opening(m, o, d, 0.05)) {
                continue;
            }
            let same = [(i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)].iter().all(|&(a, b)| {
                probe(scene, bvh, cam, w, h, a, b).is_some_and(|q| {
                    q.point.normal.dot(p.point.normal) > 0.9999
                        && (q.point.position_m - p.point.position_m).dot(p.point.normal).abs() < 1e-3
                })
            });
            if same {
                probes.push(p);
            }
        }
    }
    probes
}

/// Renders `scene` lit by `lights` (photometry, placement matrix) and returns the luminance
/// (cd/m², Y of the linear RGB) per pixel, row 0 at the top.
fn render_luminance(
    r: &mut Renderer,
    scene: &Scene,
    lights: &[(Arc<Photometry>, DMat4)],
    cam: &HostCamera,
    w: u32,
    h: u32,
) -> Vec<f64> {
    r.set_scene(scene).unwrap();
    let mut ids = Vec::new();
    let mut lums: Vec<(usize, lumiview::gpu::LuminaireId)> = Vec::new();
    for (p, m) in lights {
        let key = Arc::as_ptr(p) as usize;
        let lum = match lums.iter().find(|(k, _)| *k == key) {
            Some((_, id)) => *id,
            None => {
                let id = r.add_photometry(p.clone()).unwrap();
                lums.push((key, id));
                id
            }
        };
        ids.push(r.add_instance(lum, m.as_mat4()).unwrap());
    }
    let mut t = RenderTarget::new(&r.ctx, &TargetDesc::luminance(w, h)).unwrap();
    r.render(&mut t, cam, &RenderOptions::default()).unwrap();
    let px = t.read(&r.ctx, lumiview::gpu::Attachment::Color).unwrap();
    for id in ids {
        r.remove_instance(id).unwrap();
    }
    px.chunks_exact(16)
        .map(|c| {
            let f = |k: usize| f64::from(f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]]));
            0.2126 * f(0) + 0.7152 * f(1) + 0.0722 * f(2)
        })
        .collect()
}

/// A GL-convention perspective camera at `eye` looking at `at`, +Y up, top-left origin.
fn perspective(eye: Vec3, at: Vec3, fov_deg: f32, aspect: f32) -> HostCamera {
    HostCamera {
        view: gpu_common::look_at(eye, at, Vec3::Y),
        projection: gpu_common::gl_perspective(fov_deg.to_radians(), aspect, 0.05, 50.0),
        depth_range: lumiview::gpu::DepthRange::NegOneToOne,
        reversed_z: false,
        origin: lumiview::gpu::Origin::TopLeft,
    }
}

/// E = I(C, γ) cos³γ / h² for a luminaire `h` m above the receiver at scene offset (dx, dz), C0
/// along +X turned by `yaw_deg` about +Y (C0 = (cos ψ, 0, −sin ψ), C90 = (−sin ψ, 0, −cos ψ)).
fn point_reference_lx(p: &Photometry, h: f64, yaw_deg: f64, dx: f64, dz: f64) -> f64 {
    let psi = yaw_deg.to_radians();
    let (c0, c90) = ((psi.cos(), -psi.sin()), (-psi.sin(), -psi.cos()));
    let (along0, along90) = (dx * c0.0 + dz * c0.1, dx * c90.0 + dz * c90.1);
    let mut c = along90.atan2(along0).to_degrees();
    if c < 0.0 {
        c += 360.0;
    }
    let gamma = (dx.hypot(dz) / h).atan();
    p.intensity(c, gamma.to_degrees()) * gamma.cos().powi(3) / (h * h)
}

#[test]
fn a_luminaire_over_an_open_plane_gives_i_cos3_over_h2() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let rho = 0.5;
    let scene = scene_of(vec![(floor(20.0), rho)]);
    let bvh = Bvh::build(&scene);
    let p = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let (h, yaw) = (2.5, 30.0);
    let (w, hgt) = (96u32, 64u32);
    let cam = perspective(
        Vec3::new(0.5, 1.6, 4.5),
        Vec3::new(-0.3, 0.0, -0.5),
        70.0,
        w as f32 / hgt as f32,
    );
    let lum = render_luminance(
        &mut r,
        &scene,
        &[(p.clone(), placement(0.0, h, 0.0, yaw))],
        &cam,
        w,
        hgt,
    );
    let mut worst: f64 = 0.0;
    let mut probes = 0;
    for j in (2..hgt).step_by(6) {
        for i in (2..w).step_by(9) {
            let Some(pr) = probe(&scene, &bvh, &cam, w, hgt, i, j) else {
                continue;
            };
            let x = pr.point.position_m;
            let want = point_reference_lx(&p, h, yaw, x.x, x.z);
            if want < 1.0 {
                continue;
            }
            let got = std::f64::consts::PI * lum[(j * w + i) as usize] / pr.rho_y;
            let rel = (got - want).abs() / want;
            worst = worst.max(rel);
            probes += 1;
            assert!(rel < 0.005, "pixel ({i}, {j}) at {x}: {got} lx vs {want} lx");
        }
    }
    eprintln!("open plane, asymmetric point source at {h} m, yaw {yaw}°: {probes} probe pixels, worst {worst:.1e}");
    assert!(probes >= 20, "{probes} probes");
    gpu_common::assert_no_validation_messages();
}

/// A low box on the floor shadows the strip just behind it: the blocker lies within a few per cent
/// of the receiver's distance to the luminaire (found in review: the blocker search looked no
/// nearer than a quarter of the way and drew that strip lit). Visibility from the CPU BVH.
#[test]
fn a_low_box_shadows_the_floor_right_behind_it() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let rho = 0.5;
    let low_box = lumiview::scene::sample::box_triangles(DVec3::new(0.9, 0.0, -1.0), DVec3::new(1.0, 0.1, 1.0), false);
    let scene = scene_of(vec![(floor(20.0), rho), (low_box, rho)]);
    let bvh = Bvh::build(&scene);
    let p = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let (h, yaw) = (2.5, 0.0);
    let light = DVec3::new(0.0, h, 0.0);
    let (w, hgt) = (96u32, 64u32);
    // From beyond the box, looking down at the 4 cm strip its top edge shadows (x 1.0 … 1.042 m).
    let cam = perspective(
        Vec3::new(1.5, 0.6, 0.0),
        Vec3::new(1.03, 0.0, 0.0),
        12.0,
        w as f32 / hgt as f32,
    );
    let lum = render_luminance(
        &mut r,
        &scene,
        &[(p.clone(), placement(0.0, h, 0.0, yaw))],
        &cam,
        w,
        hgt,
    );
    let (mut shadowed, mut lit, mut worst_lit) = (0, 0, 0.0f64);
    for j in 0..hgt {
        for i in 0..w {
            let Some(pr) = probe(&scene, &bvh, &cam, w, hgt, i, j) else {
                continue;
            };
            let x = pr.point.position_m;
            if pr.point.normal.y < 0.99 || x.y.abs() > 1e-9 || x.z.abs() > 0.5 {
                continue;
            }
            let to = light - x;
            let full = point_reference_lx(&p, h, yaw, x.x, x.z);
            let got = std::f64::consts::PI * lum[(j * w + i) as usize] / pr.rho_y;
            // Keep clear of the shadow's edge by a pixel's footprint (about 2 mm here).
            let near_edge = |q: DVec3| bvh.occluded(q + DVec3::Y * 1e-6, light - q, 1.0);
            let hidden = near_edge(x);
            let firm = [-0.004, 0.004].iter().all(|dx| near_edge(x + DVec3::X * *dx) == hidden);
            if !firm {
                continue;
            }
            if hidden {
                shadowed += 1;
                assert!(
                    got < 0.01 * full,
                    "pixel ({i}, {j}) at {x} behind the box: {got} lx of {full} unshadowed"
                );
            } else if to.length() > 0.0 {
                lit += 1;
                worst_lit = worst_lit.max((got - full).abs() / full);
                assert!(
                    (got - full).abs() < 0.005 * full,
                    "pixel ({i}, {j}) at {x} in the open: {got} lx vs {full} lx"
                );
            }
        }
    }
    eprintln!("low box: {shadowed} floor probes in its shadow (all dark), {lit} lit (worst {worst_lit:.1e})");
    assert!(shadowed >= 20 && lit >= 20, "{shadowed} shadowed, {lit} lit probes");
    gpu_common::assert_no_validation_messages();
}

#[test]
fn two_hundred_fifty_six_luminaires_light_the_plane_within_their_influence() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let rho = 0.6;
    let scene = scene_of(vec![(floor(25.0), rho)]);
    let bvh = Bvh::build(&scene);
    let p = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    // 16 × 16 luminaires 2 m apart at 2.5 m, yaws varied; a lux floor of 20 lx: each reaches
    // √(1000 / 20) ≈ 7.1 m, so the tiles' lists and the per-fragment test leave most out.
    let floor_lx: f64 = 20.0;
    r.set_scene_settings(SceneSettings {
        lux_floor_lx: floor_lx as f32,
        indirect: false,
        ..Default::default()
    })
    .unwrap();
    let mut placed = Vec::new();
    for i in 0..16 {
        for k in 0..16 {
            let (x, z, yaw) = (
                -15.0 + 2.0 * f64::from(i),
                -15.0 + 2.0 * f64::from(k),
                f64::from(i * 16 + k) * 37.0,
            );
            placed.push((x, z, yaw));
        }
    }
    let lights: Vec<(Arc<Photometry>, DMat4)> = placed
        .iter()
        .map(|&(x, z, yaw)| (p.clone(), placement(x, 2.5, z, yaw)))
        .collect();
    let (w, hgt) = (128u32, 72u32);
    let cam = perspective(
        Vec3::new(0.0, 9.0, 14.0),
        Vec3::new(0.0, 0.0, 0.0),
        70.0,
        w as f32 / hgt as f32,
    );
    let lum = render_luminance(&mut r, &scene, &lights, &cam, w, hgt);
    let (mut probes, mut worst_above, mut worst_below) = (0, 0.0f64, 0.0f64);
    for j in (4..hgt).step_by(8) {
        for i in (4..w).step_by(12) {
            let Some(pr) = probe(&scene, &bvh, &cam, w, hgt, i, j) else {
                continue;
            };
            let x = pr.point.position_m;
            let each: Vec<f64> = placed
                .iter()
                .map(|&(lx, lz, yaw)| point_reference_lx(&p, 2.5, yaw, x.x - lx, x.z - lz))
                .collect();
            let all: f64 = each.iter().sum();
            let got = std::f64::consts::PI * lum[(j * w + i) as usize] / pr.rho_y;
            // What the cut-off may leave out: the luminaires beyond their influence radius, each
            // under the floor there.
            let radius = (1000.0 / floor_lx).sqrt();
            let beyond: f64 = placed
                .iter()
                .zip(&each)
                .filter(|((lx, lz, _), _)| (x - DVec3::new(*lx, 2.5, *lz)).length() > radius)
                .map(|(_, e)| *e)
                .sum();
            // 0.5 %, the open plane's limit: lavapipe lands within 1e-6 of the in-reach sum, an H100
            // (f32 transcendentals, 256 terms) 0.10 % below it.
            assert!(
                got <= all * 1.005 && got >= (all - beyond) * 0.995,
                "pixel ({i}, {j}) at {x}: {got} lx; all luminaires {all} lx, those in reach {}",
                all - beyond
            );
            worst_above = worst_above.max(got / (all - beyond) - 1.0);
            worst_below = worst_below.max(all - got);
            probes += 1;
        }
    }
    eprintln!(
        "256 luminaires, lux floor {floor_lx} lx: {probes} probes within [in-reach sum, full sum]: at most {:.1} lx below \
         the full sum (left out by the cut-off), {:.1e} above the in-reach sum",
        worst_below,
        worst_above
    );
    assert!(probes >= 20);
    gpu_common::assert_no_validation_messages();
}

#[test]
fn the_luminaires_appearance_composites_over_the_lit_room_with_depth() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let scene = scene_of(vec![(floor(20.0), 0.4)]);
    let bvh = Bvh::build(&scene);
    let p = gpu_common::bega();
    // The opening's long side (0.6 m) along the view, so that it covers pixels seen from 18° below.
    let yaw = if p.opening.size_x_m > p.opening.size_y_m {
        90.0
    } else {
        0.0
    };
    let m = placement(0.0, 2.5, 0.0, yaw);
    r.set_scene(&scene).unwrap();
    let lum = r.add_photometry(p.clone()).unwrap();
    r.add_instance(lum, m.as_mat4()).unwrap();
    let (w, hgt) = (192u32, 128u32);
    let cam = perspective(
        Vec3::new(0.0, 1.5, 3.0),
        Vec3::new(0.0, 1.2, 0.0),
        60.0,
        w as f32 / hgt as f32,
    );
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            depth: lumiview::gpu::DepthFormat::R32Float,
            ..TargetDesc::luminance(w, hgt)
        },
    )
    .unwrap();
    r.render(&mut t, &cam, &RenderOptions::default()).unwrap();
    let color = t.read(&r.ctx, lumiview::gpu::Attachment::Color).unwrap();
    let depth = t.read(&r.ctx, lumiview::gpu::Attachment::Depth).unwrap();
    let f = |b: &[u8], k: usize| f64::from(f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]));
    let window_depth = |x: DVec3| {
        let c = cam.projection.as_dmat4() * cam.view.as_dmat4() * x.extend(1.0);
        0.5 * c.z / c.w + 0.5
    };
    // The opening's centre: the far-field luminance towards the eye, in front of the floor.
    let clip = cam.clip_from_world().as_dmat4() * DVec3::new(0.0, 2.5, 0.0).extend(1.0);
    let (i, j) = (
        ((clip.x / clip.w * 0.5 + 0.5) * f64::from(w)) as usize,
        ((0.5 - clip.y / clip.w * 0.5) * f64::from(hgt)) as usize,
    );
    let k = j * w as usize + i;
    let to_eye = m
        .inverse()
        .transform_vector3(DVec3::new(0.0, 1.5, 3.0) - DVec3::new(0.0, 2.5, 0.0));
    let (c, g) = lumiview::photometry::web::angles_of(to_eye.to_array());
    let want = p.luminance(c, g).unwrap();
    let got = f(&color, 4 * k);
    assert!((got / want - 1.0).abs() < 0.01, "opening: {got} cd/m² vs {want}");
    let (o, d) = pixel_ray(&cam, w, hgt, i as u32, j as u32);
    let t_open = (2.5 - o.y) / d.y;
    let dz = (f(&depth, k) - window_depth(o + d * t_open)).abs();
    assert!(dz < 1e-4, "opening depth off by {dz}");
    // Floor pixels: the lit floor's depth, and its luminance near ρ·I cos³γ/(π h²) (the 0.6 m
    // opening's near field shifts it by a few per cent at 2.5 m; the plane test above is exact).
    let mut floor_px = 0;
    for j in (hgt / 2..hgt).step_by(10) {
        for i in (0..w).step_by(14) {
            let Some(pr) = probe(&scene, &bvh, &cam, w, hgt, i, j) else {
                continue;
            };
            let k = (j * w + i) as usize;
            let x = pr.point.position_m;
            let dz = (f(&depth, k) - window_depth(x)).abs();
            assert!(dz < 1e-4, "floor pixel ({i}, {j}): depth off by {dz}");
            let want = 0.4 / std::f64::consts::PI * point_reference_lx(&p, 2.5, yaw, x.x, x.z);
            let got = f(&color, 4 * k);
            assert!(
                got > 0.0 && (got - want).abs() <= 0.05 * want,
                "floor pixel ({i}, {j}): {got} vs ~{want}"
            );
            floor_px += 1;
        }
    }
    eprintln!(
        "composite: the opening's pixel {got:.0} cd/m² vs L = {want:.0}; {floor_px} floor pixels' depths within 1e-4"
    );
    assert!(floor_px >= 10);
    gpu_common::assert_no_validation_messages();
}

/// The linear luminaire's visible share along the floor line z = 0 under the plate, as the GPU
/// shows it (E with the plate / E without) and as the reference computes it, at the floor points
/// the pixels of an orthographic top view between plate and floor see.
#[test]
fn a_linear_luminaire_casts_the_references_penumbra() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let (h, h_plate) = (2.5, 1.0);
    let linear = photometry_text(LINEAR_IES, "linear.ies");
    let open = scene_of(vec![(floor(10.0), 0.5)]);
    let shaded = scene_of(vec![(floor(10.0), 0.5), (plate(h_plate), 0.5)]);
    let (w, hgt) = (400u32, 4u32);
    // Looking down from 0.5 m (below the plate, which lies behind the camera), 5 mm pixels.
    let cam = HostCamera::from_ortho(DVec3::Y, DVec3::new(0.0, 0.3, 0.0), 0.005, w, hgt, 0.35);
    let lights = [(linear.clone(), placement(0.0, h, 0.0, 0.0))];
    let e0 = render_luminance(&mut r, &open, &lights, &cam, w, hgt);
    let e1 = render_luminance(&mut r, &shaded, &lights, &cam, w, hgt);
    let bvh = Bvh::build(&open);
    let row = hgt / 2;
    let mut xs = Vec::new();
    let mut gpu = Vec::new();
    for i in 0..w {
        let pr = probe(&open, &bvh, &cam, w, hgt, i, row).unwrap();
        xs.push(pr.point.position_m);
        let k = (row * w + i) as usize;
        gpu.push(e1[k] / e0[k]);
    }
    let lum = SceneLuminaire {
        photometry: linear.clone(),
        scene_from_luminaire: lights[0].1,
    };
    let points: Vec<SurfacePoint> = xs
        .iter()
        .map(|&p| SurfacePoint {
            position_m: p,
            normal: DVec3::Y,
        })
        .collect();
    let opts = TraceOptions {
        paths_per_point: 0,
        direct_estimates: 4,
        area_samples: 1024,
        seed: 7,
        ..TraceOptions::default()
    };
    let r0 = lumiview::scene::illuminance(&open, std::slice::from_ref(&lum), &points, &opts).unwrap();
    let r1 = lumiview::scene::illuminance(&shaded, std::slice::from_ref(&lum), &points, &opts).unwrap();
    let reference: Vec<f64> = r0.iter().zip(&r1).map(|(a, b)| b.direct_lx / a.direct_lx).collect();
    let x: Vec<f64> = xs.iter().map(|p| p.x).collect();
    let width = |f: &[f64], tol: f64| -> (f64, f64) {
        // x grows or falls along the row: take the extremes of each set.
        let lit: Vec<f64> = x
            .iter()
            .zip(f)
            .filter(|(_, v)| **v >= 1.0 - tol)
            .map(|(x, _)| *x)
            .collect();
        let dark: Vec<f64> = x.iter().zip(f).filter(|(_, v)| **v <= tol).map(|(x, _)| *x).collect();
        (
            lit.iter().copied().fold(f64::MIN, f64::max),
            dark.iter().copied().fold(f64::MAX, f64::min),
        )
    };
    let (g_lit, g_dark) = width(&gpu, 1e-4);
    let (r_lit, r_dark) = width(&reference, 1e-9);
    let (gw, rw) = (g_dark - g_lit, r_dark - r_lit);
    let mean_abs = gpu.iter().zip(&reference).map(|(a, b)| (a - b).abs()).sum::<f64>() / gpu.len() as f64;
    eprintln!(
        "penumbra of a 1.2 m linear luminaire at {h} m under an edge at {h_plate} m: GPU lit to x = {g_lit:.3}, dark from \
         {g_dark:.3}: width {gw:.3} m; reference {r_lit:.3} … {r_dark:.3}: {rw:.3} m ({:+.1} %); visible share mean \
         |GPU − reference| {mean_abs:.3}",
        100.0 * (gw / rw - 1.0)
    );
    assert!(
        (gw / rw - 1.0).abs() < 0.2,
        "penumbra width {gw} vs the reference's {rw}"
    );
    for (k, (&g, &rf)) in gpu.iter().zip(&reference).enumerate() {
        if rf >= 1.0 - 1e-9 || rf <= 1e-9 {
            // Fully lit or fully dark in the reference, away from the penumbra's ends by 2 cm.
            let near_end = (x[k] - r_lit).abs() < 0.02 || (x[k] - r_dark).abs() < 0.02;
            if !near_end {
                assert!((g - rf).abs() < 0.01, "x = {}: GPU share {g} vs {rf}", x[k]);
            }
        }
    }
    gpu_common::assert_no_validation_messages();
}

/// Points of the opening of the office's linear luminaire (luminaire frame), for classifying
/// probes: 48 × 4 over its 1.2 × 0.1 m.
fn opening_points() -> Vec<DVec3> {
    let mut v = Vec::new();
    for i in 0..48 {
        for j in 0..4 {
            v.push(DVec3::new(
                -0.6 + 1.2 * (f64::from(i) + 0.5) / 48.0,
                -0.05 + 0.1 * (f64::from(j) + 0.5) / 4.0,
                0.0,
            ));
        }
    }
    v
}

/// Whether the ray o + t d meets the linear luminaire's opening (1.2 × 0.1 m in its frame's z = 0
/// plane) grown by `margin_m`.
fn hits_opening(scene_from_luminaire: &DMat4, o: DVec3, d: DVec3, margin_m: f64) -> bool {
    let inv = scene_from_luminaire.inverse();
    let (o, d) = (inv.transform_point3(o), inv.transform_vector3(d));
    if d.z.abs() < 1e-12 {
        return false;
    }
    let t = -o.z / d.z;
    let p = o + t * d;
    t > 0.0 && p.x.abs() <= 0.6 + margin_m && p.y.abs() <= 0.05 + margin_m
}

/// Whether each luminaire is fully seen (1), fully hidden (0) or partly seen (between) from x,
/// by shadow rays to its opening's points; luminaires behind the receiving side count as hidden.
fn seen_shares(bvh: &Bvh, x: DVec3, n: DVec3, lights: &[DMat4]) -> Vec<f64> {
    let pts = opening_points();
    lights
        .iter()
        .map(|m| {
            let mut seen = 0;
            for p in &pts {
                let s = m.transform_point3(*p);
                let d = s - x;
                if d.dot(n) <= 0.0 {
                    continue;
                }
                let len = d.length();
                if !bvh.occluded(x + n * 1e-7, d / len, len) {
                    seen += 1;
                }
            }
            f64::from(seen) / pts.len() as f64
        })
        .collect()
}

#[test]
fn the_office_under_its_documented_layout_matches_the_references_direct_term() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let scene = office();
    let bvh = Bvh::build(&scene);
    let linear = photometry_text(LINEAR_IES, "linear.ies");
    let mats: Vec<DMat4> = OFFICE_LUMINAIRES.iter().map(|p| p.matrix()).collect();
    let lights: Vec<(Arc<Photometry>, DMat4)> = mats.iter().map(|m| (linear.clone(), *m)).collect();
    let (w, hgt) = (160u32, 112u32);
    let cam = perspective(
        Vec3::new(2.8, 1.7, 1.8),
        Vec3::new(-1.0, 0.5, -0.9),
        75.0,
        w as f32 / hgt as f32,
    );
    let lum = render_luminance(&mut r, &scene, &lights, &cam, w, hgt);
    let probes = clear_probes(&scene, &bvh, &cam, (w, hgt), &mats, 3, 5);
    let tracer = Tracer::new(
        &scene,
        &lights
            .iter()
            .map(|(p, m)| SceneLuminaire {
                photometry: p.clone(),
                scene_from_luminaire: *m,
            })
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let opts = TraceOptions {
        paths_per_point: 0,
        direct_estimates: 4,
        area_samples: 256,
        seed: 3,
        ..TraceOptions::default()
    };
    let points: Vec<SurfacePoint> = probes.iter().map(|p| p.point).collect();
    let reference = tracer.illuminance(&points, &opts).unwrap();
    // Classify: every luminaire fully seen or fully hidden at the point and 3 cm around it (in
    // its plane), or some luminaire partly seen (penumbra).
    let (mut all_lit, mut some_hidden, mut all_hidden, mut penumbra) = (0, 0, 0, 0);
    let mut worst_clear: f64 = 0.0;
    let mut pen_err = Vec::new();
    let mut max_se: f64 = 0.0;
    let mut failures = Vec::new();
    for (p, rf) in probes.iter().zip(&reference) {
        let x = p.point.position_m;
        let n = p.point.normal;
        let (t1, t2) = {
            let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Z };
            let t1 = n.cross(a).normalize();
            (t1, n.cross(t1))
        };
        let shares = seen_shares(&bvh, x, n, &mats);
        let clear = shares.iter().all(|s| *s == 0.0 || *s == 1.0)
            && [t1, -t1, t2, -t2]
                .iter()
                .all(|t| seen_shares(&bvh, x + 0.03 * *t, n, &mats) == shares);
        let got = std::f64::consts::PI * lum[(p.px.1 * w + p.px.0) as usize] / p.rho_y;
        let want = rf.direct_lx;
        if clear {
            let seen = shares.iter().filter(|s| **s == 1.0).count();
            match seen {
                6 => all_lit += 1,
                0 => all_hidden += 1,
                _ => some_hidden += 1,
            }
            max_se = max_se.max(rf.direct_se_lx / want.max(1e-9));
            let err = (got - want).abs();
            let rel = err / want.max(1e-9);
            if want > 0.0 {
                worst_clear = worst_clear.max(rel);
            }
            assert!(
                err <= 0.03 * want + 1e-3,
                "pixel {:?} at {x:.3} (normal {n}, triangle {}, material {}), luminaires seen {shares:?}: GPU {got} lx vs \
                 reference {want} lx",
                p.px,
                p.triangle,
                scene.material_of()[p.triangle]
            );
            if err > 0.01 * want + 1e-3 {
                failures.push(format!(
                    "pixel {:?} at {x:.3} (normal {n}, triangle {}), luminaires seen {shares:?}: GPU {got:.2} lx vs \
                     reference {want:.2} lx",
                    p.px, p.triangle
                ));
            }
        } else {
            penumbra += 1;
            pen_err.push((got - want) / want.max(1.0));
        }
    }
    let clear = all_lit + some_hidden + all_hidden;
    pen_err.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    let median_pen = pen_err.get(pen_err.len() / 2).copied().unwrap_or(0.0);
    let worst_pen = pen_err.last().copied().unwrap_or(0.0);
    let p75_pen = pen_err.get(pen_err.len() * 3 / 4).copied().unwrap_or(0.0);
    eprintln!(
        "office, 6 × linear 1.2 m luminaires: {} probes; fully lit or shadowed {clear} (all six seen {all_lit}, some hidden \
         {some_hidden}, all hidden {all_hidden}): worst {:.2} % (reference standard error ≤ {:.2} %); penumbra {penumbra}: \
         median |error| {:.1} %, 75th percentile {:.1} %, worst {:.1} %",
        probes.len(),
        100.0 * worst_clear,
        100.0 * max_se,
        100.0 * median_pen.abs(),
        100.0 * p75_pen.abs(),
        100.0 * worst_pen.abs()
    );
    // Known: a receiver in a crevice (the 10 cm gap between the cabinet's back and the wall) can
    // read the cabinet just beyond a blocker-search point as a blocker (docs/scene-lighting.md):
    // at most 1 % of the clear probes may be off by 1–3 %, and they are printed.
    eprintln!(
        "{} of {clear} clear probes off by more than 1 %:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(
        failures.len() * 100 <= clear,
        "{} of {clear} clear probes off by more than 1 %",
        failures.len()
    );
    // Penumbra probes (a luminaire partly hidden): measured median |error| 0.4 %, 75th percentile
    // 2.2 %, worst 72 % (where the blocker depth of PCSS is a mean over blockers at different
    // depths); held at twice the measured median and 75th percentile.
    assert!(
        median_pen.abs() <= 0.008 && p75_pen.abs() <= 0.045,
        "penumbra: median |error| {median_pen}, 75th percentile {p75_pen}"
    );
    assert!(clear + penumbra >= 50 && clear >= 30 && penumbra >= 5, "probe counts");
    assert!(all_lit > 0 && some_hidden > 0, "both kinds of clear probes");
    gpu_common::assert_no_validation_messages();
}

/// The office lit by `lights` with inter-reflection, seen from a corner: at clear probe pixels
/// (one flat surface around them, no luminaire in front) the GPU's illuminance π·L/ρ_Y against the
/// reference's direct term plus the CPU gather of the same VPLs (the implementation), and against
/// the reference path tracer's total (the method, visibility of the bounce left out). Returns the
/// relative errors (implementation, method) per probe.
fn office_with_bounce(r: &mut Renderer, lights: &[(Arc<Photometry>, DMat4)]) -> (Vec<f64>, Vec<f64>) {
    let scene = office();
    let bvh = Bvh::build(&scene);
    let settings = SceneSettings::default();
    r.set_scene_settings(settings).unwrap();
    let (w, hgt) = (96u32, 64u32);
    let cam = perspective(
        Vec3::new(2.8, 1.7, 1.8),
        Vec3::new(-1.0, 0.5, -0.9),
        75.0,
        w as f32 / hgt as f32,
    );
    let lum = render_luminance(r, &scene, lights, &cam, w, hgt);
    let mats: Vec<DMat4> = lights.iter().map(|l| l.1).collect();
    let probes = clear_probes(&scene, &bvh, &cam, (w, hgt), &mats, 2, 3);
    let lums: Vec<SceneLuminaire> = lights
        .iter()
        .map(|(p, m)| SceneLuminaire {
            photometry: p.clone(),
            scene_from_luminaire: *m,
        })
        .collect();
    let tracer = Tracer::new(&scene, &lums).unwrap();
    let points: Vec<SurfacePoint> = probes.iter().map(|p| p.point).collect();
    let reference = tracer
        .illuminance(
            &points,
            &TraceOptions {
                paths_per_point: 1024,
                area_samples: 256,
                seed: 5,
                ..TraceOptions::default()
            },
        )
        .unwrap();
    let vpls = lumiview::scene::vpl::VplSet::generate(
        &scene,
        &bvh,
        &lums,
        &lumiview::scene::vpl::VplOptions {
            photons: settings.bounce_photons as usize,
            clamp_m: f64::from(settings.vpl_clamp_m),
            ..Default::default()
        },
    )
    .unwrap();
    let (mut implementation, mut method) = (Vec::new(), Vec::new());
    for (p, rf) in probes.iter().zip(&reference) {
        let got = std::f64::consts::PI * lum[(p.px.1 * w + p.px.0) as usize] / p.rho_y;
        let mirror = rf.direct_lx + vpls.illuminance_lx(p.point.position_m, p.point.normal);
        implementation.push(got / mirror - 1.0);
        method.push(got / rf.total_lx - 1.0);
    }
    (implementation, method)
}

/// (median, 95th percentile) of |e|.
fn abs_quantiles(e: &[f64]) -> (f64, f64) {
    let mut a: Vec<f64> = e.iter().map(|x| x.abs()).collect();
    a.sort_by(f64::total_cmp);
    (a[a.len() / 2], a[a.len() * 95 / 100])
}

#[test]
fn the_office_with_inter_reflection_gathers_its_virtual_point_lights() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let linear = photometry_text(LINEAR_IES, "linear.ies");
    let lights: Vec<(Arc<Photometry>, DMat4)> =
        OFFICE_LUMINAIRES.iter().map(|p| (linear.clone(), p.matrix())).collect();
    let (implementation, method) = office_with_bounce(&mut r, &lights);
    let (im, ip) = abs_quantiles(&implementation);
    let (mm, mp) = abs_quantiles(&method);
    println!(
        "office, linear layout: {} probes; GPU vs direct + CPU gather: median {im:.4}, p95 {ip:.4}; vs the path \
         tracer's total: median {mm:.4}, p95 {mp:.4}",
        implementation.len()
    );
    // The implementation: the shader gathers what scene::vpl describes (measured 0.11 % / 1.0 %;
    // the p95 holds the direct term's own penumbra differences).
    assert!(implementation.len() > 300);
    assert!(im < 0.005 && ip < 0.02, "GPU vs CPU gather: median {im}, p95 {ip}");
    // The method on every visible surface, where the bounce's missing visibility shows (under the
    // desks, in corners): measured 3.7 % / 22.6 %; held loosely against regressions.
    assert!(mm < 0.06 && mp < 0.3, "GPU vs path tracer: median {mm}, p95 {mp}");
    // Without inter-reflection the same frame misses the bounce everywhere.
    r.set_scene_settings(SceneSettings {
        indirect: false,
        ..SceneSettings::default()
    })
    .unwrap();
}

#[test]
fn moved_luminaires_update_their_shadows_within_the_per_frame_budget() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let settings = SceneSettings {
        indirect: false,
        shadow_updates_per_frame: 2,
        ..SceneSettings::default()
    };
    r.set_scene_settings(settings).unwrap();
    let scene = office();
    let p = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let (w, hgt) = (64u32, 48u32);
    let cam = perspective(
        Vec3::new(2.8, 1.7, 1.8),
        Vec3::new(-1.0, 0.5, -0.9),
        75.0,
        w as f32 / hgt as f32,
    );
    let before: Vec<DMat4> = OFFICE_LUMINAIRES.iter().map(|q| q.matrix()).collect();
    let after: Vec<DMat4> = before
        .iter()
        .enumerate()
        .map(|(i, m)| {
            if i == 0 {
                *m
            } else {
                DMat4::from_translation(DVec3::new(0.3, -0.4, 0.2)) * *m
            }
        })
        .collect();
    let read = |r: &mut Renderer, t: &mut RenderTarget| -> Vec<f32> {
        r.render(t, &cam, &RenderOptions::default()).unwrap();
        t.read(&r.ctx, lumiview::gpu::Attachment::Color)
            .unwrap()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    };
    r.set_scene(&scene).unwrap();
    let lum = r.add_photometry(p.clone()).unwrap();
    let ids: Vec<_> = before
        .iter()
        .map(|m| r.add_instance(lum, m.as_mat4()).unwrap())
        .collect();
    let mut t = RenderTarget::new(&r.ctx, &TargetDesc::luminance(w, hgt)).unwrap();
    read(&mut r, &mut t);
    let s0 = r.scene_stats();
    assert_eq!(
        (s0.shadow_lights_rendered, s0.shadows_pending),
        (6, 0),
        "a new atlas renders all: {s0:?}"
    );
    read(&mut r, &mut t);
    assert_eq!(
        r.scene_stats().shadow_lights_rendered,
        6,
        "nothing moved, nothing rendered"
    );
    for (id, m) in ids.iter().zip(&after) {
        r.set_transform(*id, m.as_mat4()).unwrap();
    }
    // Five moved, two a frame: 2, 2, 1.
    let mut pending = Vec::new();
    let mut last = Vec::new();
    for _ in 0..4 {
        last = read(&mut r, &mut t);
        let s = r.scene_stats();
        pending.push((s.shadow_lights_rendered - 6, s.shadows_pending));
    }
    assert_eq!(pending, vec![(2, 3), (4, 1), (5, 0), (5, 0)]);
    // The frame after the last update is the frame a fresh renderer draws.
    let mut fresh = renderer().unwrap();
    fresh.set_scene_settings(settings).unwrap();
    fresh.set_scene(&scene).unwrap();
    let lum2 = fresh.add_photometry(p.clone()).unwrap();
    for m in &after {
        fresh.add_instance(lum2, m.as_mat4()).unwrap();
    }
    let mut t2 = RenderTarget::new(&fresh.ctx, &TargetDesc::luminance(w, hgt)).unwrap();
    let want = read(&mut fresh, &mut t2);
    let worst = last
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert_eq!(
        worst, 0.0,
        "incremental shadow maps differ from fresh ones by up to {worst}"
    );
}

#[test]
fn textured_surfaces_reflect_their_texels() {
    // The office's rug (white × a 2 × 2 sRGB checker, nearest, repeating every 0.4 m) under a
    // point luminaire, seen from above: each rug pixel's luminance is ρ_Y(texel)·E/π with ρ from
    // the CPU's texture sampling at the pixel ray's hit and E the exact direct term.
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let scene = office();
    let bvh = Bvh::build(&scene);
    let p = photometry_text(ASYMMETRIC_IES, "asymmetric.ies");
    let lights = vec![(p.clone(), placement(0.0, 2.8, -1.0, 0.0))];
    let (w, hgt) = (96u32, 64u32);
    let cam = perspective(
        Vec3::new(0.0, 2.2, -0.2),
        Vec3::new(0.0, 0.0, -1.0),
        60.0,
        w as f32 / hgt as f32,
    );
    let lum = render_luminance(&mut r, &scene, &lights, &cam, w, hgt);
    let tracer = Tracer::new(
        &scene,
        &[SceneLuminaire {
            photometry: p,
            scene_from_luminaire: lights[0].1,
        }],
    )
    .unwrap();
    let (mut n, mut worst, mut dark, mut light) = (0, 0.0f64, 0, 0);
    for j in 0..hgt {
        for i in 0..w {
            let (o, d) = pixel_ray(&cam, w, hgt, i, j);
            let Some(hit) = bvh.closest_hit(o, d, 1e3) else {
                continue;
            };
            let m = &scene.materials()[scene.material_of()[hit.triangle] as usize];
            if m.base_color_texture.is_none() {
                continue;
            }
            // Away from the checker's edges (texel size 0.2 m): the pixel's footprint is ~1 cm.
            let x = o + d * hit.t;
            let edge = |v: f64| {
                let f = (v / 0.2).rem_euclid(1.0);
                f.min(1.0 - f) * 0.2
            };
            if edge(x.x + 1.0) < 0.02 || edge(x.z + 1.7) < 0.02 {
                continue;
            }
            let rho = scene.reflectance_y(hit.triangle, hit.b1, hit.b2);
            let e = tracer
                .illuminance(
                    &[SurfacePoint {
                        position_m: x,
                        normal: DVec3::Y,
                    }],
                    &TraceOptions {
                        paths_per_point: 0,
                        direct_estimates: 1,
                        ..TraceOptions::default()
                    },
                )
                .unwrap()[0]
                .direct_lx;
            let want = rho * e / std::f64::consts::PI;
            let got = lum[(j * w + i) as usize];
            worst = worst.max((got / want - 1.0).abs());
            n += 1;
            if rho < 0.2 {
                dark += 1;
            } else {
                light += 1;
            }
        }
    }
    println!("rug: {n} pixels ({dark} on dark squares, {light} on light), worst relative error {worst:.2e}");
    assert!(dark > 50 && light > 50, "{dark} dark, {light} light rug pixels");
    assert!(worst < 0.01, "worst {worst}");
}

/// The compute lighting (each pixel's surface from a G-buffer pass, lit once in a compute pass,
/// composited with its depth) and the per-fragment lighting (`SceneSettings::deferred_max_pixels`
/// = 0) give one frame: the office under the linear layout with shadows and inter-reflection,
/// forward and reversed depth, luminance with the R32F depth output and tone-mapped RGBA8. The
/// independent references are the tests above, which run the compute lighting.
#[test]
fn the_compute_lighting_gives_the_per_fragment_lightings_frame() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let scene = office();
    r.set_scene(&scene).unwrap();
    let linear = photometry_text(LINEAR_IES, "linear.ies");
    let lum = r.add_photometry(linear).unwrap();
    for q in OFFICE_LUMINAIRES.iter() {
        r.add_instance(lum, q.matrix().as_mat4()).unwrap();
    }
    // The BEGA luminaire's own appearance composites over both.
    let bega = r.add_photometry(gpu_common::bega()).unwrap();
    r.add_instance(bega, placement(0.5, 2.4, -0.5, 0.0).as_mat4()).unwrap();
    let (w, hgt) = (120u32, 80u32);
    let (eye, at) = (Vec3::new(2.8, 1.7, 1.8), Vec3::new(-1.0, 0.5, -0.9));
    let forward = perspective(eye, at, 75.0, w as f32 / hgt as f32);
    let (near, far) = (0.05f32, 50.0f32);
    let t = 1.0 / (75f32.to_radians() / 2.0).tan();
    let reversed = HostCamera {
        projection: glam::Mat4::from_cols(
            glam::Vec4::new(t * hgt as f32 / w as f32, 0.0, 0.0, 0.0),
            glam::Vec4::new(0.0, t, 0.0, 0.0),
            glam::Vec4::new(0.0, 0.0, near / (far - near), -1.0),
            glam::Vec4::new(0.0, 0.0, far * near / (far - near), 0.0),
        ),
        depth_range: lumiview::gpu::DepthRange::ZeroToOne,
        reversed_z: true,
        ..forward
    };
    let luminance = TargetDesc {
        depth: lumiview::gpu::DepthFormat::R32Float,
        ..TargetDesc::luminance(w, hgt)
    };
    let display = TargetDesc {
        color: lumiview::gpu::ColorFormat::Rgba8Srgb,
        ..TargetDesc::luminance(w, hgt)
    };
    let tone = RenderOptions {
        output: lumiview::gpu::OutputMode::ToneMapped,
        exposure: 0.02,
        ..RenderOptions::default()
    };
    let cases = [
        (
            "forward depth, luminance",
            &forward,
            luminance,
            RenderOptions::default(),
        ),
        (
            "reversed depth, luminance",
            &reversed,
            luminance,
            RenderOptions::default(),
        ),
        ("forward depth, tone mapped", &forward, display, tone),
    ];
    for (name, cam, desc, options) in cases {
        let mut frames = Vec::new();
        for deferred_max_pixels in [0, u64::MAX] {
            r.set_scene_settings(SceneSettings {
                deferred_max_pixels,
                ..SceneSettings::default()
            })
            .unwrap();
            let mut t = RenderTarget::new(&r.ctx, &desc).unwrap();
            r.render(&mut t, cam, &options).unwrap();
            let color = t.read(&r.ctx, lumiview::gpu::Attachment::Color).unwrap();
            let depth = if desc.depth == lumiview::gpu::DepthFormat::R32Float {
                t.read(&r.ctx, lumiview::gpu::Attachment::Depth).unwrap()
            } else {
                Vec::new()
            };
            frames.push((color, depth));
        }
        let ((fc, fd), (cc, cd)) = (&frames[0], &frames[1]);
        assert_eq!(fd, cd, "{name}: depth outputs differ");
        let (mut n, mut off) = (0usize, Vec::new());
        if desc.color == lumiview::gpu::ColorFormat::Rgba8Srgb {
            for (k, (a, b)) in fc.chunks_exact(4).zip(cc.chunks_exact(4)).enumerate() {
                n += usize::from(a[3] > 0);
                let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
                if d > 1 {
                    off.push((k, f64::from(d)));
                }
            }
        } else {
            let f = |c: &[u8], k: usize| f32::from_le_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]]);
            for k in 0..(w * hgt) as usize {
                if f(fc, 4 * k + 3) != f(cc, 4 * k + 3) {
                    off.push((k, f64::INFINITY));
                    continue;
                }
                n += usize::from(f(fc, 4 * k + 3) > 0.0);
                let d = (0..3)
                    .map(|c| {
                        let (a, b) = (f64::from(f(fc, 4 * k + c)), f64::from(f(cc, 4 * k + c)));
                        (a - b).abs() / a.abs().max(b.abs()).max(1e-3)
                    })
                    .fold(0.0, f64::max);
                if d > 1e-4 {
                    off.push((k, d));
                }
            }
        }
        println!(
            "{name}: {n} pixels drawn; {} differ (relative > 1e-4, or > 1 level in RGBA8){}",
            off.len(),
            off.iter()
                .map(|(k, d)| format!(" ({}, {}): {d:.2e}", *k as u32 % w, *k as u32 / w))
                .take(5)
                .collect::<String>()
        );
        assert!(n > (w * hgt / 2) as usize, "{name}: {n} pixels drawn");
        // A pixel on a shadow's or an edge's boundary may tip either way in f32.
        assert!(off.len() * 1000 <= n, "{name}: {} of {n} pixels differ", off.len());
    }
    gpu_common::assert_no_validation_messages();
}
