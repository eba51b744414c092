//! Luminance image files of measured near-field scans: TechnoTeam `.pf` (luminance) and `.pcf`
//! (colour), PFM (`Pf` greyscale / `PF` colour) and OpenEXR (a `Y` channel, or `R`, `G`, `B`), all read
//! into a [`LuminanceImage`](super::LuminanceImage) (cd/m², row 0 at the top); and a `.pf` writer.
//!
//! Byte layouts are in docs/formats.md ("Luminance image files"). In short:
//!
//! - **`.pf` / `.pcf`** — an ASCII header of `Key=Value` lines (CR LF or LF; a key may carry a
//!   leading `|`) with at least `Typ`, `Lines` (rows) and `Columns`; the header ends at an empty line
//!   or at a NUL byte, whichever comes first; one separator byte (NUL) follows; then little-endian
//!   `f32` pixels row by row, top row first. `Typ=Pic98::TPlane<float>` is luminance in cd/m²;
//!   `Typ=Pic98::TPlane<Pic98::TRGBFloatPixel>` is colour, three `f32` per pixel in B, G, R order.
//!   Like other robust readers, the pixels are taken as the **last** `rows · cols · 4 · channels`
//!   bytes of the file, so extra header bytes do not shift them. The `Typ` field decides the kind,
//!   not the file extension.
//! - **PFM** — `PF` (RGB) or `Pf` (grey), width, height, scale, each separated by whitespace, one
//!   whitespace byte, then `f32` pixels; a negative scale means little-endian, positive big-endian;
//!   the magnitude is not applied (pixels are taken as cd/m²). Rows are stored bottom row first and
//!   are flipped so row 0 is the top.
//! - **OpenEXR** — the first non-deep layer at full resolution; its `Y` channel if present, else
//!   `R`, `G`, `B` combined by the luminance weights of the file's `chromaticities` attribute
//!   (Rec. 709 / sRGB primaries with a D65 white when the attribute is absent).
//!
//! Colour to luminance: colour images are assumed to hold **linear** RGB with Rec. 709 / sRGB
//! primaries and a D65 white, scaled so that the luminance in cd/m² is
//! `Y = 0.2126 R + 0.7152 G + 0.0722 B` ([`REC709_LUMA`]; the Y row of the Rec. 709 RGB → XYZ
//! matrix, so a grey pixel R = G = B = L has luminance L). A camera calibrated to other primaries
//! must be converted to luminance by its own software (e.g. exported as `.pf`).
//!
//! Every error names the file and what is wrong. Sizes are capped at [`MAX_DIMENSION`] per side and
//! [`MAX_PIXELS`] in all, and the byte count a header declares is checked against the file before
//! any pixel buffer is allocated.
//!
//! - `reader.rs`: [`read_image`], [`read_image_header`], [`decode_image`]: any supported file, its
//!   format detected ([`ImageFormat`]) by content, else by extension;
//! - `pf.rs`: TechnoTeam `.pf` / `.pcf` ([`parse_pf_header`], [`parse_pf`]) and the `.pf` writer
//!   ([`encode_pf`], [`write_pf`]);
//! - `pfm.rs`: PFM ([`parse_pfm`]);
//! - `openexr.rs`: OpenEXR ([`parse_exr`]) and the luminance weights of given primaries
//!   ([`luminance_weights`]).

use std::path::Path;

use super::error::{NearfieldError, Result};

mod openexr;
mod pf;
mod pfm;
mod reader;

pub use openexr::{luminance_weights, parse_exr};
pub use pf::{encode_pf, parse_pf, parse_pf_header, write_pf, PfHeader};
pub use pfm::parse_pfm;
pub use reader::{decode_image, read_image, read_image_header, ImageFormat, ImageHeader};

/// Largest accepted width or height of an image, pixels.
pub const MAX_DIMENSION: u32 = 65_536;

/// Largest accepted pixel count of one image (2²⁸ ≈ 268 M pixels, 1 GiB of `f32`).
pub const MAX_PIXELS: u64 = 1 << 28;

/// Largest `.pf` / `.pcf` header searched for its end, bytes.
pub const PF_MAX_HEADER: usize = 64 * 1024;

/// Luminance weights of linear Rec. 709 / sRGB (D65) R, G, B: `Y = 0.2126 R + 0.7152 G + 0.0722 B`.
pub const REC709_LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// `Typ` of a TechnoTeam luminance image.
pub const PF_TYPE_LUMINANCE: &str = "Pic98::TPlane<float>";

/// `Typ` of a TechnoTeam colour image (B, G, R `f32` per pixel).
pub const PF_TYPE_COLOUR: &str = "Pic98::TPlane<Pic98::TRGBFloatPixel>";

/// `Typ` of a TechnoTeam camera raw image (`.pus`, `u16`): not luminance, rejected.
pub const PF_TYPE_RAW: &str = "Pic98::TPlane<unsigned short>";

fn fmt_err(path: &Path, message: impl Into<String>) -> NearfieldError {
    NearfieldError::format(path, message)
}

/// Checks a declared size against [`MAX_DIMENSION`] and [`MAX_PIXELS`].
fn check_size(path: &Path, width: u64, height: u64) -> Result<(u32, u32)> {
    let max = u64::from(MAX_DIMENSION);
    if width == 0 || height == 0 || width > max || height > max {
        return Err(fmt_err(
            path,
            format!("image size {width} × {height} px is outside 1…{MAX_DIMENSION} per side"),
        ));
    }
    if width * height > MAX_PIXELS {
        return Err(fmt_err(
            path,
            format!(
                "image size {width} × {height} px has more than {MAX_PIXELS} pixels (the most this reader accepts)"
            ),
        ));
    }
    // Both ≤ 65536, so they fit.
    Ok((width as u32, height as u32))
}
