//! Host-lighting look-up tables of a far-field luminaire: the table kinds and encodings, their
//! description, and `lumi_luminaire_lut` (docs/lut-and-solid.md has the texel mapping).

use super::context::with_context;
use super::luminaire::{lumi_luminaire, photometry_of};
use super::{lumi_status, write_out, FfiError, LUMI_STATUS_BUFFER_TOO_SMALL};
use crate::photometry::lut::{Lut, LutEncoding, LutTexels};

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
    /// Texels along C (2D) or cos γ (1D), 2…8192.
    pub width: u32,
    /// Texels along γ (2D; ignored for 1D), 2…8192.
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

/// Writes a host-lighting look-up table into `buffer` (row-major, row 0 = γ 0° for 2D; texel i of
/// a 1D table at cos γ = 1 − 2i/(N−1)), in the encoding asked for (f32/f16 little-endian, or 8-bit
/// gamma 2.2). `max_intensity_cd` (may be NULL) receives the maximum used for normalising.
/// With `buffer` NULL only `required_bytes` is written (a size query). If `buffer_len` is too small:
/// `LUMI_STATUS_BUFFER_TOO_SMALL`, and `required_bytes` still says the size. A near-field scan
/// (`LUMI_LUMINAIRE_NEARFIELD`) gives the table of its far field, estimated from its images on
/// the first call that needs it (docs/scene-lighting.md, "Scans as light sources").
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
