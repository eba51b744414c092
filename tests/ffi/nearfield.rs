//! Near-field scans (`.lvpack`, manifest, TM-25) loaded through the C API, rendered in every
//! selection mode against the synthetic goniophotometer's ray-cast truth, with their camera layout
//! and cache.

use std::path::{Path, PathBuf};
use std::ptr;

use glam::Vec3;
use lumiview::ffi::context::*;
use lumiview::ffi::instance::*;
use lumiview::ffi::luminaire::*;
use lumiview::ffi::lut::*;
use lumiview::ffi::render::*;
use lumiview::ffi::target::*;
use lumiview::ffi::*;

use crate::common::{context, cpath, cstr, last_error, temp_dir};
use crate::gpu_common::{self, gl_perspective, look_at, GPU_LOCK};

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
        // "infinite-depth billboard", shaders/nearfield/pass.wgsl): with cameras ~10° apart, as here, the
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

        // Far-field calls on a scan answer from the far field estimated from its images: the
        // disc's I(γ) = L·πr²·cos γ = 314.16 cd · cos γ (the estimator's kernel rounds the cosine
        // by about σ²), the table and the inverse-square illuminance from the same web.
        let i0 = 10_000.0 * std::f64::consts::PI * 0.01;
        let (mut cd, mut l) = (-1.0, -1.0);
        assert_eq!(
            lumi_luminaire_sample(ctx, lum, 0.0, 0.0, &mut cd, &mut l),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert!((cd / i0 - 1.0).abs() < 0.03, "I(0) {cd} vs {i0}");
        // The opening is the measured extent (a 0.2 m square for a 0.2 m disc): L = I / A.
        assert!(l > 0.0 && (l / (cd / 0.04) - 1.0).abs() < 0.1, "L {l}");
        let mut cd60 = -1.0;
        assert_eq!(
            lumi_luminaire_sample(ctx, lum, 90.0, 60.0, &mut cd60, ptr::null_mut()),
            LUMI_STATUS_OK
        );
        assert!((cd60 / (0.5 * i0) - 1.0).abs() < 0.03, "I(60°) {cd60} vs {}", 0.5 * i0);
        let ldesc = lumi_lut_desc_default();
        let mut need = 0usize;
        assert_eq!(
            lumi_luminaire_lut(ctx, lum, &ldesc, ptr::null_mut(), 0, &mut need, ptr::null_mut()),
            LUMI_STATUS_OK
        );
        assert!(need > 0);
        let (p, n) = ([0.0f32, 0.0, -2.0], [0.0f32, 0.0, 1.0]);
        let mut lux = -1.0;
        assert_eq!(
            lumi_instance_illuminance(ctx, inst, p.as_ptr(), n.as_ptr(), &mut lux),
            LUMI_STATUS_OK
        );
        assert!((lux - cd / 4.0).abs() < 1e-9 * cd, "{lux} vs I(0)/4 = {}", cd / 4.0);

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
