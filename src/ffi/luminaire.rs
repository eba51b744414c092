//! Luminaires and instances: load from a file, query, host-lighting look-up tables, instances with
//! model matrices, and the CPU illuminance a host's lighting should reproduce.

use std::ffi::c_char;

use super::context::{with_context, ContextInner};
use super::{lumi_status, mat_arg, path_arg, write_out, FfiError, LUMI_STATUS_BUFFER_TOO_SMALL};
use crate::gpu::{InstanceId, LuminaireId};
use crate::photometry::lut::{Lut, LutEncoding, LutTexels};
use crate::photometry::{LoadOptions, OpeningShape, Photometry};

/// Handle of a luminaire, owned by its context (0 is never a valid handle).
pub type lumi_luminaire = u64;
/// Handle of an instance, owned by its context (0 is never a valid handle).
pub type lumi_instance = u64;

/// Luminaire kind: far-field photometry (IES LM-63 or EULUMDAT).
pub const LUMI_LUMINAIRE_FARFIELD: u32 = 0;

/// Opening shapes reported by `lumi_luminaire_get_info` (values fixed).
pub const LUMI_OPENING_POINT: u32 = 0;
/// Flat rectangle length × width.
pub const LUMI_OPENING_RECTANGLE: u32 = 1;
/// Box with luminous sides.
pub const LUMI_OPENING_BOX: u32 = 2;
/// Flat ellipse / disc.
pub const LUMI_OPENING_ELLIPSE: u32 = 3;
/// Vertical cylinder.
pub const LUMI_OPENING_VERTICAL_CYLINDER: u32 = 4;
/// Ellipsoid / sphere.
pub const LUMI_OPENING_ELLIPSOID: u32 = 5;
/// Horizontal cylinder along the length (X).
pub const LUMI_OPENING_HORIZONTAL_CYLINDER_X: u32 = 6;
/// Horizontal cylinder along the width (Y).
pub const LUMI_OPENING_HORIZONTAL_CYLINDER_Y: u32 = 7;
/// Vertical ellipse facing C0.
pub const LUMI_OPENING_VERTICAL_ELLIPSE_C0: u32 = 8;
/// Vertical ellipse facing C90.
pub const LUMI_OPENING_VERTICAL_ELLIPSE_C90: u32 = 9;
/// EULUMDAT rectangle with side heights.
pub const LUMI_OPENING_RECTANGLE_WITH_SIDES: u32 = 10;
/// EULUMDAT disc with side heights.
pub const LUMI_OPENING_DISC_WITH_SIDES: u32 = 11;

/// Facts about a luminaire. Units: cd, lm, m.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_luminaire_info {
    /// `LUMI_LUMINAIRE_FARFIELD`.
    pub kind: u32,
    /// Largest intensity (cd) and its direction (C, γ in degrees, lumiview's Type C frame).
    pub max_intensity_cd: f64,
    /// C angle of the maximum, degrees.
    pub max_c_deg: f64,
    /// γ angle of the maximum, degrees.
    pub max_gamma_deg: f64,
    /// Luminous flux integrated from the intensity distribution (lm).
    pub flux_lm: f64,
    /// One of `LUMI_OPENING_*`.
    pub opening_shape: u32,
    /// Opening extents along X (length), Y (width), Z (height), metres.
    pub opening_size_m: [f64; 3],
    /// Housing size (length, width, height) in metres; all 0 when the file gives none.
    pub housing_size_m: [f64; 3],
}

/// Look-up table kinds (values fixed).
pub const LUMI_LUT_2D: u32 = 0;
/// 1D over cos γ (averaged over C).
pub const LUMI_LUT_1D: u32 = 1;
/// Texel encodings: 32-bit float.
pub const LUMI_LUT_F32: u32 = 0;
/// 16-bit half float.
pub const LUMI_LUT_F16: u32 = 1;
/// 8-bit with gamma 2.2 (always normalised).
pub const LUMI_LUT_U8: u32 = 2;

/// Which host-lighting look-up table to produce (docs/lut-and-solid.md has the texel mapping).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct lumi_lut_desc {
    /// `LUMI_LUT_2D` (C × γ) or `LUMI_LUT_1D` (over cos γ).
    pub kind: u32,
    /// Texels along C (2D) or cos γ (1D), ≥ 2.
    pub width: u32,
    /// Texels along γ (2D; ignored for 1D), ≥ 2.
    pub height: u32,
    /// Divide by the maximum intensity (values 0…1) instead of absolute cd.
    pub normalize: bool,
    /// `LUMI_LUT_F32`, `LUMI_LUT_F16` or `LUMI_LUT_U8` (U8 implies normalised).
    pub encoding: u32,
}

/// A default look-up table description: 2D, 360 × 181 (1° steps: texel i at C = 360 i / W,
/// row j at γ = 180 j / (H − 1)), absolute cd, f32.
#[no_mangle]
pub extern "C" fn lumi_lut_desc_default() -> lumi_lut_desc {
    lumi_lut_desc {
        kind: LUMI_LUT_2D,
        width: 360,
        height: 181,
        normalize: false,
        encoding: LUMI_LUT_F32,
    }
}

pub(crate) fn photometry_of(c: &ContextInner, lum: lumi_luminaire) -> Result<&Photometry, FfiError> {
    let l = c
        .renderer
        .luminaire(LuminaireId(lum))
        .map_err(|_| FfiError::invalid("luminaire", format!("no luminaire with handle {lum}")))?;
    l.photometry()
        .map(|p| p.as_ref())
        .ok_or_else(|| FfiError::invalid("luminaire", "not a far-field luminaire"))
}

fn shape_code(s: OpeningShape) -> u32 {
    match s {
        OpeningShape::Point => LUMI_OPENING_POINT,
        OpeningShape::Rectangle => LUMI_OPENING_RECTANGLE,
        OpeningShape::Box => LUMI_OPENING_BOX,
        OpeningShape::Ellipse => LUMI_OPENING_ELLIPSE,
        OpeningShape::VerticalCylinder => LUMI_OPENING_VERTICAL_CYLINDER,
        OpeningShape::Ellipsoid => LUMI_OPENING_ELLIPSOID,
        OpeningShape::HorizontalCylinderAlongLength => LUMI_OPENING_HORIZONTAL_CYLINDER_X,
        OpeningShape::HorizontalCylinderAlongWidth => LUMI_OPENING_HORIZONTAL_CYLINDER_Y,
        OpeningShape::VerticalEllipseFacingC0 => LUMI_OPENING_VERTICAL_ELLIPSE_C0,
        OpeningShape::VerticalEllipseFacingC90 => LUMI_OPENING_VERTICAL_ELLIPSE_C90,
        OpeningShape::RectangleWithSides => LUMI_OPENING_RECTANGLE_WITH_SIDES,
        OpeningShape::DiscWithSides => LUMI_OPENING_DISC_WITH_SIDES,
    }
}

/// Loads a luminaire from a file and uploads it. The format is detected: IES LM-63 (1986–2019) or
/// EULUMDAT (`.ldt`).
///
/// - `path`: NUL-terminated UTF-8 path.
/// - `out`: receives the handle (owned by the context; free with `lumi_luminaire_destroy` or by
///   destroying the context); written only on success.
///
/// Errors: `LUMI_STATUS_IO`, `LUMI_STATUS_PARSE` (the text names the file, line and field),
/// `LUMI_STATUS_NULL_POINTER`, `LUMI_STATUS_GPU`.
///
/// # Safety
/// `ctx` is a live context; `path` a NUL-terminated string; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_load(
    ctx: *mut crate::ffi::context::lumi_context,
    path: *const c_char,
    out: *mut lumi_luminaire,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_load", ctx, |c| {
            let path = path_arg(path, "path")?;
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let id = c.renderer.load_luminaire(&path, &LoadOptions::default())?;
            write_out(out, id.0);
            Ok(())
        })
    }
}

/// Frees a luminaire and all its instances. Handle 0 is ignored; a stale handle is an error.
///
/// # Safety
/// `ctx` is a live context.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_destroy(
    ctx: *mut crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_destroy", ctx, |c| {
            if luminaire == 0 {
                return Ok(());
            }
            c.renderer
                .remove_luminaire(LuminaireId(luminaire))
                .map_err(|_| FfiError::invalid("luminaire", format!("no luminaire with handle {luminaire}")))
        })
    }
}

/// Describes a luminaire.
///
/// # Safety
/// `ctx` is a live context; `out` writable (written only on success).
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_get_info(
    ctx: *const crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
    out: *mut lumi_luminaire_info,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_get_info", ctx, |c| {
            if out.is_null() {
                return Err(FfiError::null("out"));
            }
            let p = photometry_of(c, luminaire)?;
            let (max_cd, mc, mg) = p.web.max_intensity();
            let o = &p.opening;
            write_out(
                out,
                lumi_luminaire_info {
                    kind: LUMI_LUMINAIRE_FARFIELD,
                    max_intensity_cd: max_cd,
                    max_c_deg: mc,
                    max_gamma_deg: mg,
                    flux_lm: p.flux_lm(),
                    opening_shape: shape_code(o.shape),
                    opening_size_m: [o.length_m, o.width_m, o.height_m],
                    housing_size_m: p.luminaire_size_m.unwrap_or([0.0; 3]),
                },
            );
            Ok(())
        })
    }
}

/// Luminous intensity (cd) of a luminaire towards (C, γ) in degrees, and the luminance (cd/m²) of
/// its luminous opening seen from there (0 where the projected area is zero). Either out-pointer may
/// be NULL; both are written only on success.
///
/// # Safety
/// `ctx` is a live context; non-NULL out-pointers writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_sample(
    ctx: *const crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
    c_deg: f64,
    gamma_deg: f64,
    intensity_cd: *mut f64,
    luminance_cd_m2: *mut f64,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_sample", ctx, |c| {
            if !c_deg.is_finite() || !gamma_deg.is_finite() {
                return Err(FfiError::invalid("c_deg/gamma_deg", "must be finite"));
            }
            if !(0.0..=180.0).contains(&gamma_deg) {
                return Err(FfiError::invalid("gamma_deg", format!("{gamma_deg} is outside 0…180")));
            }
            let p = photometry_of(c, luminaire)?;
            let i = p.intensity(c_deg.rem_euclid(360.0), gamma_deg);
            let l = p.luminance(c_deg.rem_euclid(360.0), gamma_deg).unwrap_or(0.0);
            if !intensity_cd.is_null() {
                write_out(intensity_cd, i);
            }
            if !luminance_cd_m2.is_null() {
                write_out(luminance_cd_m2, l);
            }
            Ok(())
        })
    }
}

/// Writes a host-lighting look-up table into `buffer` (row-major, row 0 = γ 0° for 2D; texel i of
/// a 1D table at cos γ = 1 − 2i/(N−1)), in the encoding asked for (f32/f16 little-endian, or 8-bit
/// gamma 2.2). `max_intensity_cd` (may be NULL) receives the maximum used for normalising.
/// With `buffer` NULL only `required_bytes` is written (a size query). If `buffer_len` is too small:
/// `LUMI_STATUS_BUFFER_TOO_SMALL`, and `required_bytes` still says the size.
///
/// # Safety
/// `ctx` is a live context; `desc` valid; `buffer` NULL or `buffer_len` writable bytes;
/// `required_bytes` writable.
#[no_mangle]
pub unsafe extern "C" fn lumi_luminaire_lut(
    ctx: *const crate::ffi::context::lumi_context,
    luminaire: lumi_luminaire,
    desc: *const lumi_lut_desc,
    buffer: *mut u8,
    buffer_len: usize,
    required_bytes: *mut usize,
    max_intensity_cd: *mut f64,
) -> lumi_status {
    // SAFETY: forwarded contract.
    unsafe {
        with_context("lumi_luminaire_lut", ctx, |c| {
            let Some(d) = desc.as_ref() else {
                return Err(FfiError::null("desc"));
            };
            if required_bytes.is_null() {
                return Err(FfiError::null("required_bytes"));
            }
            let encoding = match d.encoding {
                LUMI_LUT_F32 => LutEncoding::F32,
                LUMI_LUT_F16 => LutEncoding::F16,
                LUMI_LUT_U8 => LutEncoding::U8,
                e => return Err(FfiError::invalid("desc.encoding", format!("unknown value {e}"))),
            };
            if d.width < 2 || d.width > 8192 || (d.kind == LUMI_LUT_2D && (d.height < 2 || d.height > 8192)) {
                return Err(FfiError::invalid("desc.width/height", "must be 2…8192"));
            }
            let p = photometry_of(c, luminaire)?;
            let normalize = d.normalize || encoding == LutEncoding::U8;
            let lut = match d.kind {
                LUMI_LUT_2D => Lut::new_2d(&p.web, d.width as usize, d.height as usize, normalize)?,
                LUMI_LUT_1D => Lut::new_1d(&p.web, d.width as usize, normalize)?,
                k => return Err(FfiError::invalid("desc.kind", format!("unknown value {k}"))),
            };
            let enc = lut.encode(encoding)?;
            let bytes: Vec<u8> = match enc.texels() {
                LutTexels::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                LutTexels::F16(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                LutTexels::U8(v) => v.clone(),
            };
            if buffer.is_null() {
                write_out(required_bytes, bytes.len());
                return Ok(());
            }
            if buffer_len < bytes.len() {
                write_out(required_bytes, bytes.len());
                return Err(FfiError::new(
                    LUMI_STATUS_BUFFER_TOO_SMALL,
                    format!("buffer_len {buffer_len} < {} bytes needed", bytes.len()),
                ));
            }
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), buffer, bytes.len());
            write_out(required_bytes, bytes.len());
            if !max_intensity_cd.is_null() {
                write_out(max_intensity_cd, lut.max_cd());
            }
            Ok(())
        })
    }
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
            let id = c
                .renderer
                .add_instance(LuminaireId(luminaire), m)
                .map_err(|e| match e {
                    crate::gpu::GpuError::InvalidArgument { name, message } => FfiError::invalid(&name, message),
                    other => other.into(),
                })?;
            write_out(out, id.0);
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
            Ok(c.renderer.set_transform(InstanceId(instance), m)?)
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
            Ok(c.renderer.remove_instance(InstanceId(instance))?)
        })
    }
}

/// Illuminance (lux) at a world point with unit surface normal from one instance: E = I cos i / r²
/// (far field), the value a host's lighting shader should reproduce from the look-up tables.
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
            let e = c.renderer.illuminance(InstanceId(instance), p, n)?;
            write_out(lux, e);
            Ok(())
        })
    }
}
