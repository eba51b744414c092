//! Instances: a luminaire placed with a model matrix, its near-field settings (selection mode,
//! proxy use), and the CPU illuminance a host's lighting should reproduce.

use super::context::{with_context, ContextInner};
use super::handle;
use super::luminaire::{lumi_instance, lumi_luminaire, luminaire_id, luminaire_of};
use super::{lumi_status, mat_arg, write_out, FfiError};
use crate::gpu::nearfield::NearfieldSettings;
use crate::gpu::renderer::Luminaire;
use crate::gpu::InstanceId;
use crate::nearfield::select::SelectionMode;

/// Near-field camera selection (values fixed): the single nearest capture camera per pixel (the
/// reference viewer's choice; features jump where the choice changes).
pub const LUMI_SELECTION_NEAREST: u32 = 0;
/// Near-field camera selection: the four nearest capture cameras blended by inverse angular
/// distance.
pub const LUMI_SELECTION_IDW4: u32 = 1;
/// Near-field camera selection: barycentric weights over the spherical Delaunay triangle of capture
/// cameras around the view direction (continuous; the default).
pub const LUMI_SELECTION_CONTINUOUS: u32 = 2;

/// A selection mode from C (`LUMI_SELECTION_*`); an unknown value is an error.
struct SelectionArg(SelectionMode);

impl TryFrom<u32> for SelectionArg {
    type Error = FfiError;
    fn try_from(v: u32) -> Result<Self, FfiError> {
        SelectionMode::from_index(v).map(SelectionArg).ok_or_else(|| {
            FfiError::invalid(
                "selection_mode",
                format!("unknown value {v} (LUMI_SELECTION_NEAREST 0, _IDW4 1, _CONTINUOUS 2)"),
            )
        })
    }
}

// The C constants are literals (cbindgen copies them into the header); they are the modes' indices.
const _: () = assert!(
    LUMI_SELECTION_NEAREST == SelectionMode::Nearest.index()
        && LUMI_SELECTION_IDW4 == SelectionMode::Idw4.index()
        && LUMI_SELECTION_CONTINUOUS == SelectionMode::Continuous.index()
);

/// The renderer's id of instance handle `instance` of this context, which must still exist.
fn instance_id(c: &ContextInner, instance: lumi_instance) -> Result<InstanceId, FfiError> {
    let id = handle::decode(c.tag, handle::Kind::Instance, instance, "instance").map(InstanceId)?;
    if !c.renderer.has_instance(id) {
        return Err(FfiError::invalid(
            "instance",
            format!("no instance with handle {instance:#x} (destroyed, or its luminaire was)"),
        ));
    }
    Ok(id)
}

/// The luminaire an instance draws, and the instance's handle checked.
fn instance_luminaire(c: &ContextInner, instance: lumi_instance) -> Result<(lumi_luminaire, &Luminaire), FfiError> {
    let (lum, _) = c.renderer.instance(instance_id(c, instance)?).map_err(|_| {
        FfiError::invalid(
            "instance",
            format!("no instance with handle {instance:#x} (destroyed, or its luminaire was)"),
        )
    })?;
    let lum = handle::encode(c.tag, handle::Kind::Luminaire, lum.0);
    Ok((lum, luminaire_of(c, lum)?))
}

/// Creates an instance of a luminaire with a model matrix (luminaire frame → world, column-major
/// `float[16]`, metres). `out` is written only on success.
///
/// # Safety
/// `ctx` is a live context; `model` points to 16 floats; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_instance_create(
    ctx: *mut crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
    model: *const f32,
    out: *mut lumi_instance,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_instance_create", ctx, |c| {
            let m = mat_arg(model, "model")?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            luminaire_of(c, luminaire)?;
            let lum = luminaire_id(c, luminaire, "luminaire")?;
            let id = c.renderer.add_instance(lum, m)?;
            write_out(out, handle::encode(c.tag, handle::Kind::Instance, id.0));
            Ok(())
        })
    }
}

/// Sets an instance's model matrix (column-major `float[16]`).
///
/// # Safety
/// `ctx` is a live context; `model` points to 16 floats.
#[no_mangle]
pub unsafe extern "C" fn lumi_instance_set_transform(
    ctx: *mut crate::ffi::context::lumi_context,
    instance: lumi_instance,
    model: *const f32,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_instance_set_transform", ctx, |c| {
            let m = mat_arg(model, "model")?;
            Ok(c.renderer.set_transform(instance_id(c, instance)?, m)?)
        })
    }
}

/// Frees an instance. Handle 0 is ignored; a stale handle is an error.
///
/// # Safety
/// `ctx` is a live context.
#[no_mangle]
pub unsafe extern "C" fn lumi_instance_destroy(
    ctx: *mut crate::ffi::context::lumi_context,
    instance: lumi_instance,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_instance_destroy", ctx, |c| {
            if instance == 0 {
                return Ok(());
            }
            Ok(c.renderer.remove_instance(instance_id(c, instance)?)?)
        })
    }
}

/// Illuminance (lux) at a world point with unit surface normal from one instance: E = I cos i / r²
/// (far field), the value a host's lighting shader should reproduce from the look-up tables. An
/// instance of a near-field scan uses the scan's far field (as `lumi_luminaire_lut` does).
///
/// # Safety
/// `ctx` is a live context; `point` and `normal` point to 3 floats; `lux` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_instance_illuminance(
    ctx: *const crate::ffi::context::lumi_context,
    instance: lumi_instance,
    point: *const f32,
    normal: *const f32,
    lux: *mut f64,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_instance_illuminance", ctx, |c| {
            if point.is_null() {
                return Err(FfiError::null("point"));
            }
            if normal.is_null() {
                return Err(FfiError::null("normal"));
            }
            if lux.is_null() {
                return Err(FfiError::null("lux"));
            }
            let p = glam::Vec3::new(*point, *point.add(1), *point.add(2));
            let n = glam::Vec3::new(*normal, *normal.add(1), *normal.add(2));
            let e = c.renderer.illuminance(instance_id(c, instance)?, p, n)?;
            write_out(lux, e);
            Ok(())
        })
    }
}

/// Sets how an instance of a near-field luminaire draws: which capture cameras a pixel takes its
/// luminance from, and whether it reprojects through the luminaire's proxy mesh. New instances use
/// `LUMI_SELECTION_CONTINUOUS` with the proxy on.
///
/// - `selection_mode`: `LUMI_SELECTION_NEAREST`, `LUMI_SELECTION_IDW4` or
///   `LUMI_SELECTION_CONTINUOUS`.
/// - `use_proxy`: use the proxy mesh when the luminaire has one (`lumi_luminaire_info.has_proxy`);
///   without one (or with false) the view ray is reprojected through the capture sphere and depth is
///   a stand-in (docs/ffi-conventions.md, "Near-field scans").
///
/// Takes effect from the next `lumi_render`. Errors: `LUMI_STATUS_INVALID_ARGUMENT` for an unknown
/// `selection_mode` (nothing changes), a stale instance, or an instance of a far-field luminaire.
///
/// Threading: one thread at a time per context.
///
/// # Safety
/// `ctx` is a live context.
#[no_mangle]
pub unsafe extern "C" fn lumi_instance_set_nearfield(
    ctx: *mut crate::ffi::context::lumi_context,
    instance: lumi_instance,
    selection_mode: u32,
    use_proxy: bool,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_instance_set_nearfield", ctx, |c| {
            let SelectionArg(mode) = SelectionArg::try_from(selection_mode)?;
            if let (lum, Luminaire::Farfield(_)) = instance_luminaire(c, instance)? {
                return Err(FfiError::invalid(
                    "instance",
                    format!(
                        "instance {instance:#x} draws far-field luminaire {lum:#x} (LUMI_LUMINAIRE_FARFIELD); near-field \
                         settings apply to LUMI_LUMINAIRE_NEARFIELD luminaires"
                    ),
                ));
            }
            let id = instance_id(c, instance)?;
            Ok(c.renderer
                .set_nearfield_settings(id, NearfieldSettings { mode, proxy: use_proxy })?)
        })
    }
}
