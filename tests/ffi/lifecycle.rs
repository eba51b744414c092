//! Versions and the ABI, NULL arguments and an ABI mismatch without a device (use after a failed
//! create, destroy(NULL), a UUID nobody has), and the lifecycle of every object with its errors up to
//! a render through the C API whose centre pixel is the library's own L(C, γ).

use std::ffi::CString;
use std::ptr;

use glam::Vec3;
use lumiview::ffi::context::*;
use lumiview::ffi::instance::*;
use lumiview::ffi::luminaire::*;
use lumiview::ffi::lut::*;
use lumiview::ffi::render::*;
use lumiview::ffi::target::*;
use lumiview::ffi::*;

use crate::common::{context, cpath, last_error};
use crate::gpu_common::{self, gl_perspective, look_at, GPU_LOCK};

#[test]
fn version_and_abi() {
    assert_eq!(lumi_abi_version(), LUMI_ABI_VERSION);
    assert_eq!(lumi_version(), 1 << 8); // 0.1.0
}

#[test]
fn null_arguments_and_abi_mismatch_without_a_device() {
    // SAFETY: every call passes NULL where the contract allows it and checks the status.
    unsafe {
        assert_eq!(
            lumi_context_create(ptr::null(), ptr::null_mut()),
            LUMI_STATUS_NULL_POINTER
        );
        assert!(last_error().contains("'out'"), "{}", last_error());
        let mut desc = lumi_context_desc_default();
        desc.abi_version = 999;
        let sentinel = 0x1234usize as *mut lumi_context;
        let mut ctx = sentinel;
        assert_eq!(lumi_context_create(&desc, &mut ctx), LUMI_STATUS_ABI_MISMATCH);
        assert_eq!(ctx, sentinel, "out-pointer untouched on error");
        assert!(last_error().contains("999"));
        lumi_context_destroy(ptr::null_mut());
        // Calls on a NULL context fail cleanly (use after a failed create).
        let mut lum: lumi_luminaire = 77;
        assert_eq!(
            lumi_luminaire_load(ptr::null_mut(), cpath("misc/luxcore_ASA_15M_R2.ies").as_ptr(), &mut lum),
            LUMI_STATUS_NULL_POINTER
        );
        assert_eq!(lum, 77);
        assert_eq!(
            lumi_render(ptr::null_mut(), 1, ptr::null(), ptr::null()),
            LUMI_STATUS_NULL_POINTER
        );
        // A UUID nobody has.
        let mut desc = lumi_context_desc_default();
        desc.has_device_uuid = true;
        desc.device_uuid = [0xAB; 16];
        let mut ctx = sentinel;
        let s = lumi_context_create(&desc, &mut ctx);
        assert!(s == LUMI_STATUS_NO_DEVICE, "status {s}: {}", last_error());
        assert_eq!(ctx, sentinel);
    }
}

#[test]
fn lifecycle_errors_and_a_render_through_the_c_api() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals.
    unsafe {
        let mut caps: lumi_device_caps = std::mem::zeroed();
        assert_eq!(lumi_context_caps(ctx, &mut caps), LUMI_STATUS_OK);
        assert!(caps.external_memory);
        assert_eq!(lumi_context_caps(ctx, ptr::null_mut()), LUMI_STATUS_NULL_POINTER);
        // Naming the same device by its UUID opens it.
        let mut by_uuid = lumi_context_desc_default();
        by_uuid.has_device_uuid = true;
        by_uuid.device_uuid = caps.device_uuid;
        let mut ctx2: *mut lumi_context = ptr::null_mut();
        assert_eq!(
            lumi_context_create(&by_uuid, &mut ctx2),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let mut caps2: lumi_device_caps = std::mem::zeroed();
        assert_eq!(lumi_context_caps(ctx2, &mut caps2), LUMI_STATUS_OK);
        assert_eq!(caps2.device_uuid, caps.device_uuid);
        lumi_context_destroy(ctx2);

        // Loading: missing file, malformed file, good file.
        let mut lum: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("does-not-exist.ies").as_ptr(), &mut lum),
            LUMI_STATUS_IO
        );
        assert!(last_error().contains("does-not-exist.ies"));
        assert_eq!(lum, 0);
        assert_eq!(
            lumi_luminaire_load(ctx, ptr::null(), &mut lum),
            LUMI_STATUS_NULL_POINTER
        );
        let bad = std::env::temp_dir().join(format!("lumiview-ffi-bad-{}.ies", std::process::id()));
        std::fs::write(&bad, "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3\n").unwrap();
        let cbad = CString::new(bad.to_str().unwrap()).unwrap();
        assert_eq!(lumi_luminaire_load(ctx, cbad.as_ptr(), &mut lum), LUMI_STATUS_PARSE);
        assert!(last_error().contains("lumiview-ffi-bad"), "{}", last_error());
        std::fs::remove_file(&bad).ok();
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("misc/luxcore_ASA_15M_R2.ies").as_ptr(), &mut lum),
            LUMI_STATUS_OK
        );
        assert_ne!(lum, 0);

        let mut info: lumi_luminaire_info = std::mem::zeroed();
        assert_eq!(lumi_luminaire_get_info(ctx, lum, &mut info), LUMI_STATUS_OK);
        assert_eq!(info.opening_shape, LUMI_OPENING_RECTANGLE);
        assert!((info.flux_lm - 9560.8).abs() < 1.0, "{}", info.flux_lm);
        let mut info2: lumi_luminaire_info = std::mem::zeroed();
        info2.flux_lm = -1.0;
        assert_eq!(
            lumi_luminaire_get_info(ctx, lum + 1000, &mut info2),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(info2.flux_lm, -1.0, "untouched");

        // LUT: size query, too small, full, bad enum.
        let desc = lumi_lut_desc_default();
        let mut need = 0usize;
        assert_eq!(
            lumi_luminaire_lut(ctx, lum, &desc, ptr::null_mut(), 0, &mut need, ptr::null_mut()),
            LUMI_STATUS_OK
        );
        assert_eq!(need, 360 * 181 * 4);
        let mut buf = vec![0u8; need];
        let mut got = 0usize;
        assert_eq!(
            lumi_luminaire_lut(ctx, lum, &desc, buf.as_mut_ptr(), 10, &mut got, ptr::null_mut()),
            LUMI_STATUS_BUFFER_TOO_SMALL
        );
        assert_eq!(got, need);
        let mut max_cd = 0.0;
        assert_eq!(
            lumi_luminaire_lut(ctx, lum, &desc, buf.as_mut_ptr(), buf.len(), &mut got, &mut max_cd),
            LUMI_STATUS_OK
        );
        let first = f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]);
        let mut cd = 0.0;
        assert_eq!(
            lumi_luminaire_sample(ctx, lum, 0.0, 0.0, &mut cd, ptr::null_mut()),
            LUMI_STATUS_OK
        );
        assert!((first as f64 - cd).abs() < 1e-3 * cd.max(1.0));
        let mut bad_desc = desc;
        bad_desc.encoding = 7;
        assert_eq!(
            lumi_luminaire_lut(
                ctx,
                lum,
                &bad_desc,
                buf.as_mut_ptr(),
                buf.len(),
                &mut got,
                ptr::null_mut()
            ),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("desc.encoding"));
        assert_eq!(
            lumi_luminaire_sample(ctx, lum, 0.0, 200.0, &mut cd, ptr::null_mut()),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(
            lumi_luminaire_sample(ctx, lum, f64::NAN, 0.0, &mut cd, ptr::null_mut()),
            LUMI_STATUS_INVALID_ARGUMENT
        );

        // Instances: NaN matrix, stale luminaire, good.
        let id = glam::Mat4::IDENTITY.to_cols_array();
        let mut nan = id;
        nan[5] = f32::NAN;
        let mut inst: lumi_instance = 5;
        assert_eq!(
            lumi_instance_create(ctx, lum, nan.as_ptr(), &mut inst),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(
            lumi_instance_create(ctx, 9999, id.as_ptr(), &mut inst),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(
            lumi_instance_create(ctx, lum, ptr::null(), &mut inst),
            LUMI_STATUS_NULL_POINTER
        );
        assert_eq!(inst, 5);
        assert_eq!(lumi_instance_create(ctx, lum, id.as_ptr(), &mut inst), LUMI_STATUS_OK);
        let mut lux = 0.0;
        let point = [0.0f32, 0.0, -2.0];
        let up = [0.0f32, 0.0, 1.0];
        assert_eq!(
            lumi_instance_illuminance(ctx, inst, point.as_ptr(), up.as_ptr(), &mut lux),
            LUMI_STATUS_OK
        );
        assert!(
            (lux - cd / 4.0).abs() < 1e-6 * cd,
            "E = I/r² straight below: {lux} vs {}",
            cd / 4.0
        );

        // Targets: bad formats, zero size, good.
        let mut tdesc = lumi_target_desc_default();
        tdesc.width = 65;
        tdesc.height = 65;
        let mut target: lumi_target = 3;
        let mut bad_t = tdesc;
        bad_t.color_format = 42;
        assert_eq!(
            lumi_target_create(ctx, &bad_t, &mut target),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("color_format"));
        bad_t = tdesc;
        bad_t.depth_format = 9;
        assert_eq!(
            lumi_target_create(ctx, &bad_t, &mut target),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        bad_t = tdesc;
        bad_t.width = 0;
        assert_eq!(
            lumi_target_create(ctx, &bad_t, &mut target),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(target, 3);
        if !caps.external_semaphore {
            // lavapipe: no exported semaphores, a clear UNSUPPORTED (the CPU-wait contract applies).
            let mut sem = tdesc;
            sem.semaphores = true;
            assert_eq!(lumi_target_create(ctx, &sem, &mut target), LUMI_STATUS_UNSUPPORTED);
            assert!(last_error().contains("external_semaphore"), "{}", last_error());
        }
        tdesc.color_format = LUMI_COLOR_RGBA32F;
        assert_eq!(lumi_target_create(ctx, &tdesc, &mut target), LUMI_STATUS_OK);
        let (mut fa, mut fb) = (-3, -3);
        assert_eq!(
            lumi_target_export_semaphores(ctx, target, &mut fa, &mut fb),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!((fa, fb), (-3, -3));

        // Read-back before a render is an error.
        let mut px = vec![0u8; 65 * 65 * 16];
        let mut written = 0usize;
        assert_eq!(
            lumi_target_read_pixels(
                ctx,
                target,
                LUMI_ATTACHMENT_COLOR,
                px.as_mut_ptr(),
                px.len(),
                &mut written
            ),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        // ... but a size query (NULL buffer) is not.
        let mut size = 0usize;
        assert_eq!(
            lumi_target_read_pixels(ctx, target, LUMI_ATTACHMENT_COLOR, ptr::null_mut(), 0, &mut size),
            LUMI_STATUS_OK
        );
        assert_eq!(size, px.len());
        assert_eq!(
            lumi_target_read_pixels(ctx, target, LUMI_ATTACHMENT_COLOR, ptr::null_mut(), 0, ptr::null_mut()),
            LUMI_STATUS_NULL_POINTER
        );

        // Render: bad camera enums, NaN matrix, then a good frame.
        let eye = Vec3::new(0.0, 0.0, -3.0);
        let mut cam = lumi_camera_default();
        cam.view = look_at(eye, Vec3::ZERO, Vec3::Y).to_cols_array();
        cam.projection = gl_perspective(20f32.to_radians(), 1.0, 0.1, 20.0).to_cols_array();
        cam.origin = LUMI_ORIGIN_TOP_LEFT;
        let mut bad_cam = cam;
        bad_cam.depth_range = 5;
        assert_eq!(
            lumi_render(ctx, target, &bad_cam, ptr::null()),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        bad_cam = cam;
        bad_cam.view[0] = f32::INFINITY;
        assert_eq!(
            lumi_render(ctx, target, &bad_cam, ptr::null()),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        let mut opts = lumi_render_options_default();
        opts.overlays = 0x80;
        assert_eq!(lumi_render(ctx, target, &cam, &opts), LUMI_STATUS_INVALID_ARGUMENT);
        opts = lumi_render_options_default();
        opts.exposure = -1.0;
        assert_eq!(lumi_render(ctx, target, &cam, &opts), LUMI_STATUS_INVALID_ARGUMENT);
        assert_eq!(
            lumi_render(ctx, target + 100, &cam, ptr::null()),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(
            lumi_render(ctx, target, &cam, ptr::null()),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );

        assert_eq!(
            lumi_target_read_pixels(ctx, target, LUMI_ATTACHMENT_COLOR, px.as_mut_ptr(), 10, &mut written),
            LUMI_STATUS_BUFFER_TOO_SMALL
        );
        assert_eq!(written, px.len());
        assert_eq!(
            lumi_target_read_pixels(ctx, target, 3, px.as_mut_ptr(), px.len(), &mut written),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(
            lumi_target_read_pixels(
                ctx,
                target,
                LUMI_ATTACHMENT_COLOR,
                px.as_mut_ptr(),
                px.len(),
                &mut written
            ),
            LUMI_STATUS_OK
        );
        let centre = (32 * 65 + 32) * 16;
        let l = f32::from_le_bytes([px[centre], px[centre + 1], px[centre + 2], px[centre + 3]]) as f64;
        let mut want = 0.0;
        assert_eq!(
            lumi_luminaire_sample(ctx, lum, 0.0, 0.0, ptr::null_mut(), &mut want),
            LUMI_STATUS_OK
        );
        assert!((l / want - 1.0).abs() < 0.005, "centre {l} cd/m² vs L(0, 0) = {want}");

        // Export: each call a new fd; bad attachment leaves the out-struct alone.
        let mut e1: lumi_export = std::mem::zeroed();
        let mut e2: lumi_export = std::mem::zeroed();
        assert_eq!(
            lumi_target_export(ctx, target, LUMI_ATTACHMENT_COLOR, &mut e1),
            LUMI_STATUS_OK
        );
        assert_eq!(
            lumi_target_export(ctx, target, LUMI_ATTACHMENT_DEPTH, &mut e2),
            LUMI_STATUS_OK
        );
        assert!(e1.fd >= 0 && e2.fd >= 0 && e1.fd != e2.fd);
        assert_eq!(e1.gl_internal_format, 0x8814);
        assert_eq!(e2.gl_internal_format, 0x822E);
        assert_eq!(e1.device_uuid, caps.device_uuid);
        libc_close(e1.fd);
        libc_close(e2.fd);
        let mut e3: lumi_export = std::mem::zeroed();
        e3.fd = -7;
        assert_eq!(
            lumi_target_export(ctx, target, 2, &mut e3),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert_eq!(e3.fd, -7);

        // Destroy: stale handles are errors, 0 is ignored.
        assert_eq!(lumi_instance_destroy(ctx, 0), LUMI_STATUS_OK);
        assert_eq!(lumi_instance_destroy(ctx, inst), LUMI_STATUS_OK);
        assert_eq!(lumi_instance_destroy(ctx, inst), LUMI_STATUS_INVALID_ARGUMENT);
        assert_eq!(lumi_target_destroy(ctx, target), LUMI_STATUS_OK);
        assert_eq!(lumi_target_destroy(ctx, target), LUMI_STATUS_INVALID_ARGUMENT);
        assert_eq!(lumi_luminaire_destroy(ctx, lum), LUMI_STATUS_OK);
        assert_eq!(lumi_luminaire_destroy(ctx, lum), LUMI_STATUS_INVALID_ARGUMENT);
        lumi_context_destroy(ctx);
    }
    gpu_common::assert_no_validation_messages();
}

/// Closes an fd (std owns the only safe wrapper).
fn libc_close(fd: i32) {
    use std::os::fd::FromRawFd;
    // SAFETY: an fd we own, closed once.
    drop(unsafe { std::os::fd::OwnedFd::from_raw_fd(fd) });
}
