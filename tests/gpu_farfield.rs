//! GPU tests of the far-field pass on Vulkan (lavapipe in CI): numeric luminance checks at predicted
//! pixels, depth in the host's convention, occlusion between instances, overlays, read-back formats.
//! In CI (CI=true) a missing adapter fails; locally the tests print why they skip.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod gpu_common;

use glam::{Mat4, Vec3};
use gpu_common::{asa, bega, renderer, GPU_LOCK};
use lumiview::gpu::farfield::{luminance_table, shader_luminance, tone_map};
use lumiview::gpu::{
    Attachment, ColorFormat, DepthFormat, DepthRange, HostCamera, Origin, OutputMode, Overlays, RenderOptions,
    RenderTarget, TargetDesc,
};

fn f32s(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// A camera at `eye` looking at the origin, GL conventions.
fn gl_camera(eye: Vec3, fov_deg: f32, aspect: f32) -> HostCamera {
    let up = if eye.normalize().abs_diff_eq(Vec3::Z, 1e-3) || eye.normalize().abs_diff_eq(-Vec3::Z, 1e-3) {
        Vec3::Y
    } else {
        Vec3::Z
    };
    HostCamera {
        view: gpu_common::look_at(eye, Vec3::ZERO, up),
        projection: gpu_common::gl_perspective(fov_deg.to_radians(), aspect, 0.1, 20.0),
        depth_range: DepthRange::NegOneToOne,
        reversed_z: false,
        origin: Origin::TopLeft,
    }
}

#[test]
fn centre_pixel_shows_l_of_the_view_direction() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let p = bega();
    let table = luminance_table(&p);
    let lum = r.add_photometry(p.clone()).unwrap();
    r.add_instance(lum, Mat4::IDENTITY).unwrap();
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            width: 65,
            height: 65,
            color: ColorFormat::Rgba32Float,
            depth: DepthFormat::R32Float,
            exportable: true,
            semaphores: false,
        },
    )
    .unwrap();
    // Seen from below at an angle (C 30°, γ 40°) from 3 m.
    for (c, g) in [(30.0f64, 40.0f64), (90.0, 10.0), (200.0, 60.0)] {
        let d = lumiview::photometry::web::direction(c, g);
        let eye = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * 3.0;
        let cam = gl_camera(eye, 20.0, 1.0);
        r.render(&mut t, &cam, &RenderOptions::default()).unwrap();
        let px = f32s(&t.read(&r.ctx, Attachment::Color).unwrap());
        // The opening's centre projects to the centre of pixel (32, 32) of the odd-sized image.
        let centre = (32 * 65 + 32) * 4;
        let expected = p.luminance(c, g).unwrap();
        let got = px[centre] as f64;
        assert!(
            (got / expected - 1.0).abs() < 0.005,
            "C {c} γ {g}: got {got} cd/m², expected {expected}"
        );
        assert!((shader_luminance(&table, d) / expected - 1.0).abs() < 1e-3);
        assert_eq!(px[centre + 3], 1.0, "coverage alpha");
        assert_eq!(px[3], 0.0, "background alpha");
        // Depth: GL window depth of the centre (the opening at the origin, 3 m away).
        let depth = f32s(&t.read(&r.ctx, Attachment::Depth).unwrap());
        let clip = cam.projection * cam.view * glam::Vec4::new(0.0, 0.0, 0.0, 1.0);
        let want = 0.5 * clip.z / clip.w + 0.5;
        assert!(
            (depth[32 * 65 + 32] - want).abs() < 1e-4,
            "depth {} vs {want}",
            depth[32 * 65 + 32]
        );
        assert_eq!(depth[0], 1.0, "background depth is the far plane");
    }
    gpu_common::assert_no_validation_messages();
}

#[test]
fn tone_mapped_rgba8_matches_reinhard() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let p = bega();
    let lum = r.add_photometry(p.clone()).unwrap();
    r.add_instance(lum, Mat4::IDENTITY).unwrap();
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            width: 32,
            height: 32,
            color: ColorFormat::Rgba8Srgb,
            depth: DepthFormat::None,
            exportable: false,
            semaphores: false,
        },
    )
    .unwrap();
    let cam = gl_camera(Vec3::new(0.0, 0.0, -2.0), 20.0, 1.0);
    let exposure = 2e-5;
    let opts = RenderOptions {
        output: OutputMode::ToneMapped,
        exposure,
        ..RenderOptions::default()
    };
    r.render(&mut t, &cam, &opts).unwrap();
    let px = t.read(&r.ctx, Attachment::Color).unwrap();
    let l = p.luminance(0.0, 0.0).unwrap();
    let v = tone_map(l, exposure as f64);
    let srgb = if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    let want = (srgb * 255.0).round() as i32;
    let got = px[(16 * 32 + 16) * 4] as i32;
    assert!((got - want).abs() <= 1, "got {got}, want {want} (L = {l} cd/m²)");
    // Luminance output into an 8-bit target is refused.
    assert!(r.render(&mut t, &cam, &RenderOptions::default()).is_err());
    gpu_common::assert_no_validation_messages();
}

#[test]
fn nearer_instance_occludes_and_bottom_left_origin_flips_rows() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let lum = r.add_photometry(asa()).unwrap();
    // Two instances on the view axis: the one 1 m nearer the eye must win the depth test.
    r.add_instance(lum, Mat4::IDENTITY).unwrap();
    let near = r
        .add_instance(
            lum,
            Mat4::from_translation(Vec3::new(0.0, 0.0, -1.0)) * Mat4::from_scale(Vec3::splat(0.5)),
        )
        .unwrap();
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            width: 49,
            height: 33,
            color: ColorFormat::Rgba16Float,
            depth: DepthFormat::Depth32Float,
            exportable: true,
            semaphores: false,
        },
    )
    .unwrap();
    let mut cam = gl_camera(Vec3::new(0.0, 0.0, -3.0), 30.0, 1.5);
    r.render(&mut t, &cam, &RenderOptions::default()).unwrap();
    let d = f32s(&t.read(&r.ctx, Attachment::Depth).unwrap());
    let clip = cam.projection * cam.view * glam::Vec4::new(0.0, 0.0, -1.0, 1.0);
    let want = 0.5 * clip.z / clip.w + 0.5;
    assert!(
        (d[16 * 49 + 24] - want).abs() < 1e-4,
        "nearer instance's depth {} vs {want}",
        d[16 * 49 + 24]
    );
    r.remove_instance(near).unwrap();
    assert!(r.set_transform(near, Mat4::IDENTITY).is_err(), "stale instance id");
    // Move the luminaire up in the image (world +Y is eye-space +y for this camera), both origins.
    r.set_transform(lumiview::gpu::InstanceId(1), Mat4::IDENTITY).ok();
    let shifted = Mat4::from_translation(Vec3::new(0.0, 0.25, 0.0));
    let ids: Vec<_> = (1..=2)
        .map(lumiview::gpu::InstanceId)
        .filter(|i| r.has_instance(*i))
        .collect();
    for id in &ids {
        r.set_transform(*id, shifted).unwrap();
    }
    let rows_with_signal = |t: &mut RenderTarget, r: &mut lumiview::gpu::Renderer| -> Vec<usize> {
        let px = t.read(&r.ctx, Attachment::Color).unwrap();
        (0..33)
            .filter(|row| (0..49).any(|c| px[(row * 49 + c) * 8 + 6] != 0 || px[(row * 49 + c) * 8 + 7] != 0))
            .collect()
    };
    r.render(&mut t, &cam, &RenderOptions::default()).unwrap();
    let top = rows_with_signal(&mut t, &mut r);
    // Clip +y is image up (docs/ffi-conventions.md, "The camera"): the luminaire moved to world +Y,
    // eye-space +y for this camera, lies in the upper half, the low memory rows with TopLeft.
    let centroid = top.iter().sum::<usize>() as f64 / top.len().max(1) as f64;
    assert!(
        centroid < 15.0,
        "rows {top:?}: the luminaire above the view axis is not in the upper half"
    );
    cam.origin = Origin::BottomLeft;
    r.render(&mut t, &cam, &RenderOptions::default()).unwrap();
    let bottom = rows_with_signal(&mut t, &mut r);
    assert!(!top.is_empty());
    let mirrored: Vec<usize> = top.iter().map(|row| 32 - row).rev().collect();
    assert_eq!(bottom, mirrored, "BottomLeft mirrors the rows");
    gpu_common::assert_no_validation_messages();
}

#[test]
fn overlays_draw_lines_outside_the_opening() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    let lum = r.add_photometry(bega()).unwrap();
    r.add_instance(lum, Mat4::IDENTITY).unwrap();
    let mut t = RenderTarget::new(
        &r.ctx,
        &TargetDesc {
            width: 64,
            height: 64,
            color: ColorFormat::Rgba8Srgb,
            depth: DepthFormat::None,
            exportable: false,
            semaphores: false,
        },
    )
    .unwrap();
    let cam = gl_camera(Vec3::new(2.0, 1.0, -0.5), 45.0, 1.0);
    let mut opts = RenderOptions {
        output: OutputMode::ToneMapped,
        exposure: 1e-4,
        ..RenderOptions::default()
    };
    r.render(&mut t, &cam, &opts).unwrap();
    let plain = t.read(&r.ctx, Attachment::Color).unwrap();
    opts.overlays = Overlays {
        solid: true,
        housing: false,
    };
    r.render(&mut t, &cam, &opts).unwrap();
    let with_solid = t.read(&r.ctx, Attachment::Color).unwrap();
    let orange = with_solid.chunks_exact(4).filter(|p| p[0] > 200 && p[2] < 120).count();
    assert!(orange > 50, "solid wireframe pixels: {orange}");
    assert_eq!(plain.chunks_exact(4).filter(|p| p[0] > 200 && p[2] < 120).count(), 0);
    gpu_common::assert_no_validation_messages();
}
