//! Load warnings (a file that parses but is implausible, a scan with a finding, a scene with a
//! doubtful primitive) reach the host's log callback through the C API.

use std::ffi::{c_char, CStr};
use std::ptr;

use lumiview::ffi::context::*;
use lumiview::ffi::luminaire::*;
use lumiview::ffi::scene::*;
use lumiview::ffi::*;

use crate::common::{cpath, cstr, last_error, temp_dir};
use crate::gpu_common::{self, GPU_LOCK};

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

        // A scene whose one triangle has no material: glTF's default (white), with a warning.
        let scene_path = dir.join("no-material.glb");
        std::fs::write(&scene_path, triangle_without_material()).unwrap();
        let mut scene: lumi_scene = 0;
        assert_eq!(
            lumi_scene_load(ctx, cstr(&scene_path).as_ptr(), &mut scene),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        let w = warnings("no-material.glb");
        assert!(w.iter().any(|m| m.contains("no material")), "{w:?}");
        lumi_context_destroy(ctx);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// A GLB of one triangle whose primitive names no material.
fn triangle_without_material() -> Vec<u8> {
    use lumiview::draw::glb::{Buffer, ARRAY_BUFFER};
    let mut buf = Buffer::new();
    let pos: Vec<u8> = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let view = buf.push_view(&pos, ARRAY_BUFFER);
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": view, "componentType": 5126, "count": 3, "type": "VEC3",
            "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]}],
        "bufferViews": buf.views(),
        "buffers": [{"byteLength": buf.len()}],
    });
    buf.into_glb(&doc).unwrap()
}
