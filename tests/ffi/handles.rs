//! Handles never cross contexts, kinds or lifetimes: a foreign, wrong-kind or stale handle is an
//! error naming the argument for every function that takes one, and the other context is unchanged.

use std::ptr;

use lumiview::ffi::context::*;
use lumiview::ffi::instance::*;
use lumiview::ffi::luminaire::*;
use lumiview::ffi::lut::*;
use lumiview::ffi::render::*;
use lumiview::ffi::scene::*;
use lumiview::ffi::target::*;
use lumiview::ffi::*;

use crate::common::{context, cpath, last_error};
use crate::gpu_common::GPU_LOCK;

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
        let office = std::ffi::CString::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/office.glb")).unwrap();
        let (mut scene_a, mut scene_b) = (0, 0);
        assert_eq!(lumi_scene_load(a, office.as_ptr(), &mut scene_a), LUMI_STATUS_OK);
        assert_eq!(lumi_scene_load(b, office.as_ptr(), &mut scene_b), LUMI_STATUS_OK);
        assert_ne!(scene_a, scene_b);
        assert_eq!(lumi_context_set_scene(b, scene_b), LUMI_STATUS_OK);

        // Every function that takes a handle, called on context `a` with `handle`: its status, and
        // whether its out-parameter was left alone.
        let calls = |lum: lumi_luminaire,
                     inst: lumi_instance,
                     tgt: lumi_target,
                     scene: lumi_scene|
         -> Vec<(&str, lumi_status, bool)> {
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
            let (mut lux, up) = ([-7.0], [0.0f32, 1.0, 0.0]);
            v.push((
                "lumi_scene_illuminance",
                lumi_scene_illuminance(
                    a,
                    scene,
                    p.as_ptr(),
                    up.as_ptr(),
                    1,
                    ptr::null(),
                    lux.as_mut_ptr(),
                    ptr::null_mut(),
                ),
                lux[0] == -7.0,
            ));
            v.push(("lumi_context_set_scene", lumi_context_set_scene(a, scene), true));
            v.push(("lumi_scene_destroy", lumi_scene_destroy(a, scene), true));
            v.push(("lumi_instance_destroy", lumi_instance_destroy(a, inst), true));
            v.push(("lumi_target_destroy", lumi_target_destroy(a, tgt), true));
            v.push(("lumi_luminaire_destroy", lumi_luminaire_destroy(a, lum), true));
            v
        };
        let check = |what: &str, lum, inst, tgt, scene, want: &str| {
            for (name, status, untouched) in calls(lum, inst, tgt, scene) {
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
        check("foreign", lum_b, inst_b, tgt_b, scene_b, "belongs to another context");
        // Handles of the wrong kind.
        check("wrong kind", inst_a, tgt_a, scene_a, lum_a, "handle, not a");
        // Made-up values.
        check("made up", 5, 6, 7, 8, "not a lumiview handle");

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
        let (mut lux, wall, towards) = ([0.0], [0.0f32, 0.5, -1.5], [0.0f32, 0.0, 1.0]);
        assert_eq!(
            lumi_scene_illuminance(
                b,
                scene_b,
                wall.as_ptr(),
                towards.as_ptr(),
                1,
                ptr::null(),
                lux.as_mut_ptr(),
                ptr::null_mut()
            ),
            LUMI_STATUS_OK,
            "{}",
            last_error()
        );
        assert!(lux[0] > 0.0, "b's instance lights b's scene");
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
        assert_eq!(lumi_scene_destroy(a, scene_a), LUMI_STATUS_OK);
        let mut again = 0;
        assert_eq!(lumi_luminaire_load(a, file.as_ptr(), &mut again), LUMI_STATUS_OK);
        assert_ne!(again, lum_a);
        let mut again = 0;
        assert_eq!(lumi_scene_load(a, office.as_ptr(), &mut again), LUMI_STATUS_OK);
        assert_ne!(again, scene_a);
        check("stale", lum_a, inst_a, tgt_a, scene_a, "(destroyed");
        lumi_context_destroy(a);
        lumi_context_destroy(b);
    }
}
