//! The C ABI called from Rust: lifecycles, NULLs, bad enum values, stale handles, out-parameters
//! untouched on error, destroy(NULL), use after a failed create, buffer sizes, and a render through
//! the C API whose centre pixel is the library's own L(C, γ); near-field scans (`.lvpack`, manifest,
//! TM-25) loaded through the same call, rendered in every selection mode against the synthetic
//! goniophotometer's ray-cast truth.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod gpu_common;

use std::ffi::{c_char, CStr, CString};
use std::path::{Path, PathBuf};
use std::ptr;

use glam::Vec3;
use gpu_common::{data, gl_perspective, look_at, GPU_LOCK};
use lumiview::ffi::context::*;
use lumiview::ffi::instance::*;
use lumiview::ffi::luminaire::*;
use lumiview::ffi::lut::*;
use lumiview::ffi::render::*;
use lumiview::ffi::target::*;
use lumiview::ffi::*;

fn last_error() -> String {
    let mut buf = vec![0 as c_char; 1024];
    // SAFETY: a valid buffer of its length.
    unsafe { lumi_last_error(buf.as_mut_ptr(), buf.len()) };
    // SAFETY: NUL-terminated by lumi_last_error.
    unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
}

/// A context, or None (printing why) when there is no Vulkan device outside CI.
fn context() -> Option<*mut lumi_context> {
    let mut ctx: *mut lumi_context = ptr::null_mut();
    let mut desc = lumi_context_desc_default();
    desc.validation = gpu_common::validation_on();
    gpu_common::install_logger();
    // SAFETY: valid descriptor and out-pointer.
    let s = unsafe { lumi_context_create(&desc, &mut ctx) };
    if s != LUMI_STATUS_OK {
        if std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0") {
            panic!("CI=true and lumi_context_create failed: {}", last_error());
        }
        eprintln!("SKIP: {}", last_error());
        return None;
    }
    Some(ctx)
}

fn cpath(rel: &str) -> CString {
    CString::new(data(rel).to_str().unwrap()).unwrap()
}

/// Collects the messages the library logs through the C callback.
unsafe extern "C" fn collect_log(user: *mut std::ffi::c_void, level: u32, message: *const c_char) {
    // SAFETY: `user` is the Mutex the test passed; `message` is a NUL-terminated string for the call.
    unsafe {
        let sink = &*(user as *const std::sync::Mutex<Vec<(u32, String)>>);
        let text = CStr::from_ptr(message).to_string_lossy().into_owned();
        sink.lock().unwrap_or_else(|e| e.into_inner()).push((level, text));
    }
}

/// A file that parses but is implausible, and a scan with a finding, load through the C API and
/// their warnings reach the host's log callback at level 1, naming the file (the standard: "a file
/// that parses but is implausible gets a warning"; before, the C API dropped them).
#[test]
fn load_warnings_reach_the_log_callback() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let sink: std::sync::Mutex<Vec<(u32, String)>> = std::sync::Mutex::new(Vec::new());
    let mut desc = lumi_context_desc_default();
    desc.validation = gpu_common::validation_on();
    desc.log = Some(collect_log);
    desc.log_user = &sink as *const _ as *mut std::ffi::c_void;
    let mut ctx: *mut lumi_context = ptr::null_mut();
    // SAFETY: valid descriptor and out-pointer; `sink` outlives the context (destroyed below).
    unsafe {
        if lumi_context_create(&desc, &mut ctx) != LUMI_STATUS_OK {
            assert!(
                !std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0"),
                "CI=true and lumi_context_create failed: {}",
                last_error()
            );
            return;
        }
        let warnings = |name: &str| -> Vec<String> {
            sink.lock()
                .unwrap()
                .iter()
                .filter(|(level, m)| *level == 1 && m.contains(name))
                .map(|(_, m)| m.clone())
                .collect()
        };
        let mut lum: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("fuzz/subnormal.ies").as_ptr(), &mut lum),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let w = warnings("subnormal.ies");
        assert!(w.iter().any(|m| m.contains("implausibly small")), "{w:?}");

        let dir = temp_dir("load-warnings");
        let ccache = cstr(&dir.join("cache"));
        let mut d = lumi_luminaire_desc_default();
        d.cache_dir = ccache.as_ptr();
        let mut rays: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpath("fuzz/outlier-ray.tm25ray").as_ptr(), &d, &mut rays),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let w = warnings("outlier-ray.tm25ray");
        assert!(w.iter().any(|m| m.contains("outlier")), "{w:?}");
        lumi_context_destroy(ctx);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

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

/// A private temporary folder for one test.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lumiview-ffi-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn cstr(p: &Path) -> CString {
    CString::new(p.to_str().unwrap()).unwrap()
}

/// The synthetic `disc` (radius 100 mm, Lambertian 10,000 cd/m², facing −Z), scanned small:
/// rigo with 200 cameras per hemisphere, 64 × 64 px. Returns the scan, its `.lvpack` and the proxy
/// `.glb` in `dir`.
fn small_disc_scan(dir: &Path) -> (lumiview::nearfield::Scan, PathBuf, PathBuf) {
    use lumiview::nearfield::layout::Layout;
    use lumiview::nearfield::pack::{write_pack, PackOptions};
    use lumiview::nearfield::synth::{self, SynthOptions};
    let opts = SynthOptions {
        luminaire: "disc".into(),
        layout: Layout::Rigo {
            per_hemisphere: 200,
            overlap_deg: 2.0,
            jitter_deg: 0.05,
        },
        size: (64, 64),
        ..SynthOptions::default()
    };
    let scan = synth::synth_scan(&opts).unwrap();
    let pack = dir.join("disc.lvpack");
    write_pack(&scan, &pack, &PackOptions::default(), &|_, _| {}).unwrap();
    let glb = dir.join("disc-proxy.glb");
    synth::luminaire("disc").unwrap().proxy().write_glb(&glb).unwrap();
    (scan, pack, glb)
}

/// Reads the red channel (luminance) and the depth of pixel (x, y) of an RGBA32F + R32F target.
///
/// # Safety
/// `ctx` is live and `target` one of its targets, `size` × `size`.
unsafe fn pixel(ctx: *mut lumi_context, target: lumi_target, size: usize, x: usize, y: usize) -> (f32, f32, f32) {
    let mut color = vec![0u8; size * size * 16];
    let mut depth = vec![0u8; size * size * 4];
    let mut written = 0usize;
    // SAFETY: buffers of the stated lengths; ctx and target per the caller.
    unsafe {
        assert_eq!(
            lumi_target_read_pixels(
                ctx,
                target,
                LUMI_ATTACHMENT_COLOR,
                color.as_mut_ptr(),
                color.len(),
                &mut written
            ),
            LUMI_STATUS_OK
        );
        assert_eq!(
            lumi_target_read_pixels(
                ctx,
                target,
                LUMI_ATTACHMENT_DEPTH,
                depth.as_mut_ptr(),
                depth.len(),
                &mut written
            ),
            LUMI_STATUS_OK
        );
    }
    let c: &[f32] = bytemuck::cast_slice(&color);
    let d: &[f32] = bytemuck::cast_slice(&depth);
    let i = y * size + x;
    (c[i * 4], c[i * 4 + 3], d[i])
}

#[test]
fn nearfield_scans_through_the_c_api() {
    use lumiview::nearfield::pack::Pack;
    use lumiview::nearfield::synth;

    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = context() else { return };
    let dir = temp_dir("nearfield");
    let (scan, pack_path, glb) = small_disc_scan(&dir);
    let cameras = Pack::open(&pack_path).unwrap().rayset().cameras.len() as u32;
    let disc = synth::luminaire("disc").unwrap();
    let cpack = cstr(&pack_path);
    let cglb = cstr(&glb);

    // The view: from below (nadir −Z), 2.5 m away, fov 8°, the disc's centre on the centre pixel of a
    // 65 × 65 target; GL depth range, top-left origin.
    const SIZE: usize = 65;
    let eye = Vec3::new(0.45, -0.3, -2.4);
    let view = look_at(eye, Vec3::ZERO, Vec3::Z);
    let proj = gl_perspective(8f32.to_radians(), 1.0, 0.1, 20.0);
    let mut cam = lumi_camera_default();
    cam.view = view.to_cols_array();
    cam.projection = proj.to_cols_array();
    cam.origin = LUMI_ORIGIN_TOP_LEFT;
    let clip = (proj * view) * glam::Vec4::new(0.0, 0.0, 0.0, 1.0);
    let centre_depth = 0.5 * clip.z / clip.w + 0.5;
    // The ray-cast truth along the centre pixel's ray: the disc's 10,000 cd/m².
    let truth = disc.radiance(eye.as_dvec3(), -eye.as_dvec3());
    assert!((truth - 10_000.0).abs() < 1e-9, "{truth}");

    // SAFETY: `ctx` is live until destroyed at the end; all pointers are valid locals.
    unsafe {
        // A .lvpack through the same call as photometric files.
        let mut lum: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpack.as_ptr(), &mut lum),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let mut info: lumi_luminaire_info = std::mem::zeroed();
        assert_eq!(lumi_luminaire_get_info(ctx, lum, &mut info), LUMI_STATUS_OK);
        assert_eq!(info.kind, LUMI_LUMINAIRE_NEARFIELD);
        assert_eq!(info.camera_count, cameras);
        assert!(cameras > 300, "{cameras}");
        // The camera layout: a size query, a short buffer, then positions and axes equal to the
        // synthetic scan's own cameras (the input, not our pack), in its order.
        let mut count = 0usize;
        assert_eq!(
            lumi_luminaire_cameras(ctx, lum, ptr::null_mut(), ptr::null_mut(), 0, &mut count),
            LUMI_STATUS_OK
        );
        assert_eq!(count, cameras as usize);
        let mut pos = vec![f64::NAN; 3 * count];
        let mut dirs = vec![f64::NAN; 3 * count];
        let mut short = 0usize;
        assert_eq!(
            lumi_luminaire_cameras(ctx, lum, pos.as_mut_ptr(), ptr::null_mut(), count - 1, &mut short),
            LUMI_STATUS_BUFFER_TOO_SMALL
        );
        assert_eq!(short, count);
        assert!(pos[0].is_nan(), "nothing written on BUFFER_TOO_SMALL");
        assert_eq!(
            lumi_luminaire_cameras(ctx, lum, pos.as_mut_ptr(), dirs.as_mut_ptr(), count, &mut count),
            LUMI_STATUS_OK
        );
        for (i, cam) in scan.set.cameras.iter().enumerate() {
            let p = glam::DVec3::from_slice(&pos[3 * i..3 * i + 3]);
            let f = glam::DVec3::from_slice(&dirs[3 * i..3 * i + 3]);
            assert!(
                (p - cam.position_m).length() < 1e-9,
                "camera {i}: {p} vs {}",
                cam.position_m
            );
            assert!((f - cam.forward).length() < 1e-9, "camera {i}: {f} vs {}", cam.forward);
            assert!(
                (p.length() - info.capture_radius_m).abs() < 1e-9,
                "camera {i} on the capture sphere"
            );
            assert!(f.dot(-p.normalize()) > 0.999, "camera {i} looks at the capture centre");
        }
        assert_eq!(
            lumi_luminaire_cameras(ctx, lum, pos.as_mut_ptr(), dirs.as_mut_ptr(), count, ptr::null_mut()),
            LUMI_STATUS_NULL_POINTER
        );
        assert!(!info.has_proxy);
        assert!(
            (info.capture_radius_m - 1.117).abs() < 1e-9,
            "{}",
            info.capture_radius_m
        );
        assert_eq!(info.capture_centre_m, [0.0; 3]);
        assert!(info.content_radius_m > 0.1 && info.content_radius_m < info.capture_radius_m);
        assert!(info.gpu_bytes > 0 && info.gpu_bytes <= info.budget_bytes);
        assert_eq!(info.budget_bytes, lumi_luminaire_desc_default().budget_bytes);
        assert_eq!((info.flux_lm, info.opening_shape), (0.0, LUMI_OPENING_POINT));

        let model = glam::Mat4::IDENTITY.to_cols_array();
        let mut inst: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, lum, model.as_ptr(), &mut inst),
            LUMI_STATUS_OK
        );
        let mut tdesc = lumi_target_desc_default();
        tdesc.width = SIZE as u32;
        tdesc.height = SIZE as u32;
        tdesc.color_format = LUMI_COLOR_RGBA32F;
        tdesc.depth_format = LUMI_DEPTH_R32F;
        let mut target: lumi_target = 0;
        assert_eq!(lumi_target_create(ctx, &tdesc, &mut target), LUMI_STATUS_OK);

        // Every selection mode, proxy on (the luminaire has none: the capture-sphere path) and off.
        // Without a proxy each selected camera is sampled along the view direction (the
        // "infinite-depth billboard", shaders/nearfield.wgsl): with cameras ~10° apart, as here, the
        // cameras other than the nearest look past a 100 mm disc, so only "something lit, never
        // brighter than the disc, at the stand-in depth" holds; exactness is the proxy's (below).
        let modes = [
            (LUMI_SELECTION_NEAREST, "nearest"),
            (LUMI_SELECTION_IDW4, "idw4"),
            (LUMI_SELECTION_CONTINUOUS, "continuous"),
        ];
        for (mode, name) in modes {
            for use_proxy in [true, false] {
                assert_eq!(
                    lumi_instance_set_nearfield(ctx, inst, mode, use_proxy),
                    LUMI_STATUS_OK,
                    "{}",
                    last_error()
                );
                assert_eq!(
                    lumi_render(ctx, target, &cam, ptr::null()),
                    LUMI_STATUS_OK,
                    "{}",
                    last_error()
                );
                let (l, a, d) = pixel(ctx, target, SIZE, SIZE / 2, SIZE / 2);
                eprintln!("{name}, no proxy (use_proxy {use_proxy}): centre L = {l} cd/m², depth {d}");
                assert!(
                    l > 0.0 && f64::from(l) <= truth * 1.001,
                    "{name}: centre {l} vs {truth}"
                );
                assert_eq!(a, 1.0);
                // The stand-in depth is the plane through the capture centre facing the eye: at the
                // centre pixel, the capture centre's own depth.
                assert!((d - centre_depth).abs() < 1e-4, "{name}: depth {d} vs {centre_depth}");
                let (_, corner_a, corner_d) = pixel(ctx, target, SIZE, 0, 0);
                assert_eq!((corner_a, corner_d), (0.0, 1.0), "{name}: the corner is empty");
            }
        }

        // Bad mode values change nothing; NULL context.
        for bad in [3u32, 42, u32::MAX] {
            assert_eq!(
                lumi_instance_set_nearfield(ctx, inst, bad, true),
                LUMI_STATUS_INVALID_ARGUMENT
            );
            assert!(last_error().contains("selection_mode"), "{}", last_error());
        }
        assert_eq!(
            lumi_instance_set_nearfield(ptr::null_mut(), inst, LUMI_SELECTION_NEAREST, true),
            LUMI_STATUS_NULL_POINTER
        );
        assert_eq!(
            lumi_instance_set_nearfield(ctx, inst + 1000, LUMI_SELECTION_NEAREST, true),
            LUMI_STATUS_INVALID_ARGUMENT
        );

        // Far-field calls on a near-field luminaire: clear INVALID_ARGUMENT, out-params untouched.
        let (mut cd, mut l) = (-1.0, -1.0);
        assert_eq!(
            lumi_luminaire_sample(ctx, lum, 0.0, 0.0, &mut cd, &mut l),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("near-field"), "{}", last_error());
        assert_eq!((cd, l), (-1.0, -1.0));
        let ldesc = lumi_lut_desc_default();
        let mut need = 7usize;
        assert_eq!(
            lumi_luminaire_lut(ctx, lum, &ldesc, ptr::null_mut(), 0, &mut need, ptr::null_mut()),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("near-field"), "{}", last_error());
        assert_eq!(need, 7);
        let (p, n) = ([0.0f32, 0.0, -2.0], [0.0f32, 0.0, 1.0]);
        let mut lux = -1.0;
        assert_eq!(
            lumi_instance_illuminance(ctx, inst, p.as_ptr(), n.as_ptr(), &mut lux),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("near-field"), "{}", last_error());
        assert_eq!(lux, -1.0);

        // Near-field settings on a far-field instance are refused.
        let mut far: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load(ctx, cpath("misc/luxcore_ASA_15M_R2.ies").as_ptr(), &mut far),
            LUMI_STATUS_OK
        );
        let far_model = glam::Mat4::from_translation(glam::Vec3::new(50.0, 0.0, 0.0)).to_cols_array();
        let mut far_inst: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, far, far_model.as_ptr(), &mut far_inst),
            LUMI_STATUS_OK
        );
        assert_eq!(
            lumi_instance_set_nearfield(ctx, far_inst, LUMI_SELECTION_NEAREST, true),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("far-field"), "{}", last_error());
        // ... and a proxy or content radius for a photometric file too.
        let mut d = lumi_luminaire_desc_default();
        d.proxy_path = cglb.as_ptr();
        let mut h: lumi_luminaire = 99;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpath("misc/luxcore_ASA_15M_R2.ies").as_ptr(), &d, &mut h),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("desc.proxy_path"), "{}", last_error());
        assert_eq!(h, 99);

        // The proxy, loaded from the synthetic .glb through the descriptor: exact reprojection and
        // depth from the proxy (the disc lies in z = 0 through the centre).
        let mut desc = lumi_luminaire_desc_default();
        desc.proxy_path = cglb.as_ptr();
        let mut lum2: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpack.as_ptr(), &desc, &mut lum2),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let mut info2: lumi_luminaire_info = std::mem::zeroed();
        assert_eq!(lumi_luminaire_get_info(ctx, lum2, &mut info2), LUMI_STATUS_OK);
        assert!(info2.has_proxy);
        assert_eq!(lumi_luminaire_destroy(ctx, lum), LUMI_STATUS_OK);
        let mut inst2: lumi_instance = 0;
        assert_eq!(
            lumi_instance_create(ctx, lum2, model.as_ptr(), &mut inst2),
            LUMI_STATUS_OK
        );
        for (mode, name) in modes {
            assert_eq!(lumi_instance_set_nearfield(ctx, inst2, mode, true), LUMI_STATUS_OK);
            assert_eq!(
                lumi_render(ctx, target, &cam, ptr::null()),
                LUMI_STATUS_OK,
                "{}",
                last_error()
            );
            // The centre and a point 60 mm out on the disc (inside its 100 mm radius).
            let (l, a, d) = pixel(ctx, target, SIZE, SIZE / 2, SIZE / 2);
            eprintln!("{name} + proxy: centre L = {l} cd/m², depth {d}");
            assert!((f64::from(l) / truth - 1.0).abs() < 0.005, "{name} + proxy: centre {l}");
            assert_eq!(a, 1.0);
            assert!(
                (d - centre_depth).abs() < 1e-5,
                "{name} + proxy: depth {d} vs {centre_depth}"
            );
            let q = (proj * view) * glam::Vec4::new(0.06, 0.0, 0.0, 1.0);
            let (qx, qy) = (q.x / q.w, q.y / q.w);
            let (px, py) = (
                ((qx * 0.5 + 0.5) * SIZE as f32) as usize,
                ((0.5 - qy * 0.5) * SIZE as f32) as usize,
            );
            let (l, _, _) = pixel(ctx, target, SIZE, px, py);
            assert!(
                (f64::from(l) / truth - 1.0).abs() < 0.005,
                "{name} + proxy: pixel {px},{py}: {l}"
            );
        }

        // Descriptor errors: name the field or the file; out untouched.
        let mut h: lumi_luminaire = 99;
        let mut d = lumi_luminaire_desc_default();
        d.budget_bytes = 0;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpack.as_ptr(), &d, &mut h),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("desc.budget_bytes"), "{}", last_error());
        d = lumi_luminaire_desc_default();
        d.content_radius_m = -0.5;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpack.as_ptr(), &d, &mut h),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("desc.content_radius_m"), "{}", last_error());
        d.content_radius_m = 5.0; // beyond the 1.117 m capture sphere
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpack.as_ptr(), &d, &mut h),
            LUMI_STATUS_INVALID_ARGUMENT
        );
        assert!(last_error().contains("desc.content_radius_m"), "{}", last_error());
        assert!(last_error().contains("disc.lvpack"), "{}", last_error());
        d = lumi_luminaire_desc_default();
        let missing = cstr(&dir.join("no-such-proxy.glb"));
        d.proxy_path = missing.as_ptr();
        assert_eq!(lumi_luminaire_load_ex(ctx, cpack.as_ptr(), &d, &mut h), LUMI_STATUS_IO);
        assert!(last_error().contains("no-such-proxy.glb"), "{}", last_error());
        d.proxy_path = cpack.as_ptr(); // not glTF
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpack.as_ptr(), &d, &mut h),
            LUMI_STATUS_PARSE
        );
        assert!(last_error().contains("disc.lvpack"), "{}", last_error());
        assert_eq!(h, 99);

        // NULL arguments.
        assert_eq!(
            lumi_luminaire_load_ex(ctx, ptr::null(), ptr::null(), &mut h),
            LUMI_STATUS_NULL_POINTER
        );
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpack.as_ptr(), ptr::null(), ptr::null_mut()),
            LUMI_STATUS_NULL_POINTER
        );
        assert_eq!(
            lumi_luminaire_load_ex(ptr::null_mut(), cpack.as_ptr(), ptr::null(), &mut h),
            LUMI_STATUS_NULL_POINTER
        );
        assert_eq!(h, 99);
        // desc NULL means the defaults.
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpack.as_ptr(), ptr::null(), &mut h),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert_eq!(lumi_luminaire_destroy(ctx, h), LUMI_STATUS_OK);

        // A truncated .lvpack: PARSE (or IO), naming the file.
        let bytes = std::fs::read(&pack_path).unwrap();
        for (name, len) in [("cut-half.lvpack", bytes.len() / 2), ("cut-head.lvpack", 40)] {
            let cut = dir.join(name);
            std::fs::write(&cut, &bytes[..len]).unwrap();
            let mut h: lumi_luminaire = 99;
            let s = lumi_luminaire_load(ctx, cstr(&cut).as_ptr(), &mut h);
            assert!(
                s == LUMI_STATUS_PARSE || s == LUMI_STATUS_IO,
                "{name}: status {s}: {}",
                last_error()
            );
            assert!(last_error().contains(name), "{}", last_error());
            assert_eq!(h, 99);
        }

        // A JSON scan manifest through the same call: packed once into the cache folder.
        let cache = dir.join("cache");
        let manifest = lumiview::nearfield::manifest::write_scan(&dir.join("scan"), &scan, &|_, _| {}).unwrap();
        let ccache = cstr(&cache);
        let mut d = lumi_luminaire_desc_default();
        d.cache_dir = ccache.as_ptr();
        let mut from_manifest: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cstr(&manifest).as_ptr(), &d, &mut from_manifest),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let mut mi: lumi_luminaire_info = std::mem::zeroed();
        assert_eq!(lumi_luminaire_get_info(ctx, from_manifest, &mut mi), LUMI_STATUS_OK);
        assert_eq!((mi.kind, mi.camera_count), (LUMI_LUMINAIRE_NEARFIELD, cameras));
        let cached: Vec<PathBuf> = std::fs::read_dir(&cache).unwrap().map(|e| e.unwrap().path()).collect();
        assert_eq!(cached.len(), 1, "{cached:?}");
        assert!(cached[0].to_str().unwrap().ends_with(".lvpack"));
        let stamp = std::fs::metadata(&cached[0]).unwrap().modified().unwrap();
        let mut again: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cstr(&manifest).as_ptr(), &d, &mut again),
            LUMI_STATUS_OK
        );
        assert_eq!(
            std::fs::read_dir(&cache).unwrap().count(),
            1,
            "reused, not packed again"
        );
        assert_eq!(std::fs::metadata(&cached[0]).unwrap().modified().unwrap(), stamp);
        // A bad manifest names its file.
        let bad = dir.join("bad-manifest.json");
        std::fs::write(&bad, "{ \"format\": 3 ").unwrap();
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cstr(&bad).as_ptr(), &d, &mut h),
            LUMI_STATUS_PARSE
        );
        assert!(last_error().contains("bad-manifest.json"), "{}", last_error());

        // A TM-25 ray file through the same call: its kernel estimate, cameras chosen from the
        // data, with the hull of its ray origins as the proxy.
        let mut from_rays: lumi_luminaire = 0;
        assert_eq!(
            lumi_luminaire_load_ex(ctx, cpath("raysets/Cyl10k.1.tm25ray").as_ptr(), &d, &mut from_rays),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let mut ri: lumi_luminaire_info = std::mem::zeroed();
        assert_eq!(lumi_luminaire_get_info(ctx, from_rays, &mut ri), LUMI_STATUS_OK);
        assert_eq!(ri.kind, LUMI_LUMINAIRE_NEARFIELD);
        assert!(ri.camera_count >= 12, "{}", ri.camera_count);
        assert!(ri.has_proxy, "the pack's own proxy is used");
        assert!((ri.capture_radius_m - 1.1).abs() < 1e-9);
        assert_eq!(std::fs::read_dir(&cache).unwrap().count(), 2);

        assert_eq!(lumi_target_destroy(ctx, target), LUMI_STATUS_OK);
        lumi_context_destroy(ctx);
    }
    let _ = std::fs::remove_dir_all(&dir);
    gpu_common::assert_no_validation_messages();
}

/// Issue 21: a handle of another context, of another kind or of a destroyed object is
/// `LUMI_STATUS_INVALID_ARGUMENT` naming the argument for every function that takes one, the
/// out-parameters stay untouched, and nothing done through one context changes the other.
#[test]
fn handles_never_cross_contexts_kinds_or_lifetimes() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(a) = context() else { return };
    let Some(b) = context() else { return };
    // SAFETY: both contexts live until destroyed at the end; all pointers are valid locals.
    unsafe {
        let file = cpath("misc/luxcore_ASA_15M_R2.ies");
        let (mut lum_a, mut lum_b) = (0, 0);
        assert_eq!(lumi_luminaire_load(a, file.as_ptr(), &mut lum_a), LUMI_STATUS_OK);
        assert_eq!(lumi_luminaire_load(b, file.as_ptr(), &mut lum_b), LUMI_STATUS_OK);
        // The first luminaire of each context: equal counters, different handles.
        assert_ne!(lum_a, lum_b);
        let model: [f32; 16] = glam::Mat4::IDENTITY.to_cols_array();
        let (mut inst_a, mut inst_b) = (0, 0);
        assert_eq!(
            lumi_instance_create(a, lum_a, model.as_ptr(), &mut inst_a),
            LUMI_STATUS_OK
        );
        assert_eq!(
            lumi_instance_create(b, lum_b, model.as_ptr(), &mut inst_b),
            LUMI_STATUS_OK
        );
        let mut tdesc = lumi_target_desc_default();
        tdesc.width = 16;
        tdesc.height = 16;
        tdesc.exportable = false;
        let (mut tgt_a, mut tgt_b) = (0, 0);
        assert_eq!(
            lumi_target_create(a, &tdesc, &mut tgt_a),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert_eq!(lumi_target_create(b, &tdesc, &mut tgt_b), LUMI_STATUS_OK);

        // Every function that takes a handle, called on context `a` with `handle`: its status, and
        // whether its out-parameter was left alone.
        let calls = |lum: lumi_luminaire, inst: lumi_instance, tgt: lumi_target| -> Vec<(&str, lumi_status, bool)> {
            let mut v = Vec::new();
            let mut info: lumi_luminaire_info = std::mem::zeroed();
            info.flux_lm = -7.0;
            v.push((
                "lumi_luminaire_get_info",
                lumi_luminaire_get_info(a, lum, &mut info),
                info.flux_lm == -7.0,
            ));
            let mut n_cams = 7usize;
            v.push((
                "lumi_luminaire_cameras",
                lumi_luminaire_cameras(a, lum, ptr::null_mut(), ptr::null_mut(), 0, &mut n_cams),
                n_cams == 7,
            ));
            let mut cd = -7.0;
            v.push((
                "lumi_luminaire_sample",
                lumi_luminaire_sample(a, lum, 0.0, 0.0, &mut cd, ptr::null_mut()),
                cd == -7.0,
            ));
            let desc = lumi_lut_desc_default();
            let mut need = 7usize;
            v.push((
                "lumi_luminaire_lut",
                lumi_luminaire_lut(a, lum, &desc, ptr::null_mut(), 0, &mut need, ptr::null_mut()),
                need == 7,
            ));
            let mut out_inst: lumi_instance = 7;
            v.push((
                "lumi_instance_create",
                lumi_instance_create(a, lum, model.as_ptr(), &mut out_inst),
                out_inst == 7,
            ));
            v.push((
                "lumi_instance_set_transform",
                lumi_instance_set_transform(a, inst, model.as_ptr()),
                true,
            ));
            let (p, n) = ([0.0f32, 0.0, -2.0], [0.0f32, 0.0, 1.0]);
            let mut lux = -7.0;
            v.push((
                "lumi_instance_illuminance",
                lumi_instance_illuminance(a, inst, p.as_ptr(), n.as_ptr(), &mut lux),
                lux == -7.0,
            ));
            v.push((
                "lumi_instance_set_nearfield",
                lumi_instance_set_nearfield(a, inst, LUMI_SELECTION_NEAREST, true),
                true,
            ));
            let cam = lumi_camera_default();
            v.push(("lumi_render", lumi_render(a, tgt, &cam, ptr::null()), true));
            let mut buf = vec![0u8; 16 * 16 * 16];
            let mut written = 7usize;
            v.push((
                "lumi_target_read_pixels",
                lumi_target_read_pixels(a, tgt, LUMI_ATTACHMENT_COLOR, buf.as_mut_ptr(), buf.len(), &mut written),
                written == 7,
            ));
            let mut export: lumi_export = std::mem::zeroed();
            export.allocation_size = 7;
            v.push((
                "lumi_target_export",
                lumi_target_export(a, tgt, LUMI_ATTACHMENT_COLOR, &mut export),
                export.allocation_size == 7,
            ));
            let (mut f1, mut f2) = (-7, -7);
            v.push((
                "lumi_target_export_semaphores",
                lumi_target_export_semaphores(a, tgt, &mut f1, &mut f2),
                f1 == -7 && f2 == -7,
            ));
            v.push(("lumi_instance_destroy", lumi_instance_destroy(a, inst), true));
            v.push(("lumi_target_destroy", lumi_target_destroy(a, tgt), true));
            v.push(("lumi_luminaire_destroy", lumi_luminaire_destroy(a, lum), true));
            v
        };
        let check = |what: &str, lum, inst, tgt, want: &str| {
            for (name, status, untouched) in calls(lum, inst, tgt) {
                assert_eq!(
                    status,
                    LUMI_STATUS_INVALID_ARGUMENT,
                    "{what}: {name} gave {status}: {}",
                    last_error()
                );
                let e = last_error();
                assert!(
                    e.contains("invalid argument '") && e.contains(want),
                    "{what}: {name}: {e}"
                );
                assert!(untouched, "{what}: {name} wrote its out-parameter");
            }
        };
        // Context b's handles on context a.
        check("foreign", lum_b, inst_b, tgt_b, "belongs to another context");
        // Handles of the wrong kind.
        check("wrong kind", inst_a, tgt_a, lum_a, "handle, not a");
        // Made-up values.
        check("made up", 5, 6, 7, "not a lumiview handle");

        // Nothing happened to b: its luminaire, instance and target all work.
        let mut info: lumi_luminaire_info = std::mem::zeroed();
        assert_eq!(lumi_luminaire_get_info(b, lum_b, &mut info), LUMI_STATUS_OK);
        let mut lux = 0.0;
        let (p, n) = ([0.0f32, 0.0, -2.0], [0.0f32, 0.0, 1.0]);
        assert_eq!(
            lumi_instance_illuminance(b, inst_b, p.as_ptr(), n.as_ptr(), &mut lux),
            LUMI_STATUS_OK
        );
        assert!(lux > 0.0);
        let cam = lumi_camera_default();
        assert_eq!(
            lumi_render(b, tgt_b, &cam, ptr::null()),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );

        // Stale handles: destroyed objects of a stay invalid, also after new ones are made.
        assert_eq!(lumi_instance_destroy(a, inst_a), LUMI_STATUS_OK);
        assert_eq!(lumi_target_destroy(a, tgt_a), LUMI_STATUS_OK);
        assert_eq!(lumi_luminaire_destroy(a, lum_a), LUMI_STATUS_OK);
        let mut again = 0;
        assert_eq!(lumi_luminaire_load(a, file.as_ptr(), &mut again), LUMI_STATUS_OK);
        assert_ne!(again, lum_a);
        check("stale", lum_a, inst_a, tgt_a, "(destroyed");
        lumi_context_destroy(a);
        lumi_context_destroy(b);
    }
}
