//! Luminance image files of measured near-field scans: TechnoTeam `.pf` (luminance) and `.pcf`
//! (colour), PFM (`Pf` greyscale / `PF` colour) and OpenEXR (a `Y` channel, or `R`, `G`, `B`), all read
//! into a [`LuminanceImage`] (cd/m², row 0 at the top); and a `.pf` writer.
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

use std::io::{Read, Write};
use std::path::Path;

use glam::{DMat3, DVec3};

use super::error::{NearfieldError, Result};
use super::rayset::LuminanceImage;

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

/// OpenEXR's magic number.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// The kind of a luminance image file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ImageFormat {
    /// TechnoTeam `.pf` (luminance) or `.pcf` (colour); the header's `Typ` tells which.
    TechnoTeam,
    /// Portable float map (`Pf` grey, `PF` colour).
    Pfm,
    /// OpenEXR.
    Exr,
}

impl ImageFormat {
    /// The format named by a file's extension (`.pf`, `.pcf`, `.pfm`, `.exr`, any case).
    pub fn from_extension(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "pf" | "pcf" => Some(Self::TechnoTeam),
            "pfm" => Some(Self::Pfm),
            "exr" => Some(Self::Exr),
            _ => None,
        }
    }

    /// The format recognised from the first bytes of a file, if any.
    pub fn sniff(head: &[u8]) -> Option<Self> {
        if head.starts_with(&EXR_MAGIC) {
            Some(Self::Exr)
        } else if head.len() >= 3
            && (head.starts_with(b"PF") || head.starts_with(b"Pf"))
            && head[2].is_ascii_whitespace()
        {
            Some(Self::Pfm)
        } else if head.starts_with(b"Typ=") || head.starts_with(b"|Typ=") {
            Some(Self::TechnoTeam)
        } else {
            None
        }
    }

    /// The format of a file: by content when recognised, else by extension (so a damaged file gets
    /// the error of the reader its name asks for).
    pub fn detect(path: &Path, head: &[u8]) -> Result<Self> {
        Self::sniff(head).or_else(|| Self::from_extension(path)).ok_or_else(|| {
            NearfieldError::format(
                path,
                "not a luminance image: expected a TechnoTeam .pf/.pcf (starts with `Typ=`), a PFM (`Pf`/`PF`) \
                 or an OpenEXR file",
            )
        })
    }

    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Self::TechnoTeam => "TechnoTeam .pf/.pcf",
            Self::Pfm => "PFM",
            Self::Exr => "OpenEXR",
        }
    }
}

/// What a file's header says, read without its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageHeader {
    /// The file's format.
    pub format: ImageFormat,
    /// Width (columns), pixels.
    pub width: u32,
    /// Height (rows), pixels.
    pub height: u32,
    /// Channels stored per pixel (1 luminance, 3 colour).
    pub channels: u8,
}

/// The header of a TechnoTeam `.pf` / `.pcf` file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PfHeader {
    /// `true` for `Pic98::TPlane<Pic98::TRGBFloatPixel>` (B, G, R per pixel), `false` for luminance.
    pub colour: bool,
    /// `Columns`.
    pub width: u32,
    /// `Lines`.
    pub height: u32,
    /// `FirstLine` (the sensor row of row 0) when present. Read for information only: the manifest's
    /// intrinsics describe the stored pixel grid.
    pub first_line: Option<i64>,
    /// `FirstColumn` when present (information only, as `first_line`).
    pub first_column: Option<i64>,
    /// Every `Key=Value` field in file order (a leading `|` removed, both sides trimmed).
    pub fields: Vec<(String, String)>,
    /// Bytes before the pixel region: the header lines and the line (or NUL) that ends them. The
    /// separator byte and the pixels follow; the pixels are the file's last bytes.
    pub header_len: usize,
}

impl PfHeader {
    /// Bytes of pixel data the header declares.
    pub fn pixel_bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 4 * if self.colour { 3 } else { 1 }
    }
}

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

/// Parses the header of a TechnoTeam `.pf` / `.pcf` file from its first bytes (`head`, at least the
/// whole header: up to [`PF_MAX_HEADER`] bytes) and checks that a file of `file_len` bytes holds the
/// pixels it declares.
pub fn parse_pf_header(head: &[u8], file_len: u64, path: &Path) -> Result<PfHeader> {
    let limit = head.len().min(PF_MAX_HEADER);
    let mut fields: Vec<(String, String)> = Vec::new();
    let mut pos = 0usize;
    let mut header_len = None;
    let mut line_no = 0usize;
    while pos < limit {
        // A NUL byte at the start of a line ends the header (writers that put no empty line).
        if head[pos] == 0 {
            header_len = Some(pos);
            break;
        }
        let rest = &head[pos..limit];
        let Some(nl) = rest.iter().position(|&b| b == b'\n' || b == 0) else {
            break;
        };
        line_no += 1;
        let mut line = &rest[..nl];
        if line.last() == Some(&b'\r') {
            line = &line[..line.len() - 1];
        }
        if rest[nl] == 0 {
            // A NUL inside a line: the header ends there (the NUL is the separator).
            if !line.is_empty() {
                parse_pf_field(line, line_no, &mut fields, path)?;
            }
            header_len = Some(pos + nl);
            break;
        }
        if line.is_empty() {
            header_len = Some(pos + nl + 1);
            break;
        }
        parse_pf_field(line, line_no, &mut fields, path)?;
        pos += nl + 1;
    }
    let Some(header_len) = header_len else {
        return Err(fmt_err(
            path,
            if head.len() < PF_MAX_HEADER {
                "truncated: the header has no end (an empty line or a NUL byte) before the end of the file".to_string()
            } else {
                format!("no end of header (an empty line or a NUL byte) within the first {PF_MAX_HEADER} bytes")
            },
        ));
    };
    let get = |key: &str| -> Result<Option<&str>> {
        let mut found = fields.iter().filter(|(k, _)| k == key);
        let first = found.next().map(|(_, v)| v.as_str());
        if let (Some(a), Some((_, b))) = (first, found.next()) {
            if a != b {
                return Err(fmt_err(
                    path,
                    format!("header field {key} appears twice with different values ({a}, {b})"),
                ));
            }
        }
        Ok(first)
    };
    let typ = get("Typ")?.ok_or_else(|| fmt_err(path, "header field Typ is missing"))?;
    let colour = match typ {
        PF_TYPE_LUMINANCE => false,
        PF_TYPE_COLOUR => true,
        PF_TYPE_RAW => {
            return Err(NearfieldError::Unsupported {
                path: path.to_path_buf(),
                message: format!(
                    "Typ={typ} is a camera raw image (.pus), not luminance; export a luminance image (.pf)"
                ),
            })
        }
        other => {
            let known = format!("{PF_TYPE_LUMINANCE} or {PF_TYPE_COLOUR}");
            let message = format!("header field Typ={other} is not a known image type (expected {known})");
            return Err(fmt_err(path, message));
        }
    };
    let dim = |key: &str| -> Result<u64> {
        let v = get(key)?.ok_or_else(|| fmt_err(path, format!("header field {key} is missing")))?;
        v.parse::<u64>()
            .ok()
            .filter(|n| (1..=u64::from(MAX_DIMENSION)).contains(n))
            .ok_or_else(|| {
                fmt_err(
                    path,
                    format!("header field {key}={v} is not a whole number in 1…{MAX_DIMENSION}"),
                )
            })
    };
    let (height, width) = (dim("Lines")?, dim("Columns")?);
    let (width, height) = check_size(path, width, height)?;
    let offset = |key: &str| -> Result<Option<i64>> {
        match get(key)? {
            None => Ok(None),
            Some(v) => v
                .parse::<i64>()
                .map(Some)
                .map_err(|_| fmt_err(path, format!("header field {key}={v} is not an integer"))),
        }
    };
    let header = PfHeader {
        colour,
        width,
        height,
        first_line: offset("FirstLine")?,
        first_column: offset("FirstColumn")?,
        header_len,
        fields,
    };
    let need = header.pixel_bytes();
    let have = file_len.saturating_sub(header_len as u64);
    if have < need {
        return Err(fmt_err(
            path,
            format!(
                "truncated: the header declares {} × {} {} pixels ({need} bytes) but only {have} bytes follow the \
                 header",
                header.width,
                header.height,
                if colour { "B,G,R f32" } else { "f32" },
            ),
        ));
    }
    Ok(header)
}

fn parse_pf_field(line: &[u8], line_no: usize, fields: &mut Vec<(String, String)>, path: &Path) -> Result<()> {
    let text = String::from_utf8_lossy(line);
    let Some((k, v)) = text.split_once('=') else {
        // Free text lines are tolerated, but not binary garbage where the header should be.
        if line.iter().any(|&b| b < 0x09 || (0x0e..0x20).contains(&b)) {
            return Err(fmt_err(
                path,
                format!("header line {line_no} holds control bytes: not a TechnoTeam image header"),
            ));
        }
        return Ok(());
    };
    let k = k.trim();
    let k = k.strip_prefix('|').unwrap_or(k).trim();
    fields.push((k.to_string(), v.trim().to_string()));
    Ok(())
}

/// Reads `n` little-endian `f32` from `bytes` (exactly `4 n` bytes).
fn f32s_le(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Decodes a TechnoTeam `.pf` (luminance) or `.pcf` (colour → luminance by [`REC709_LUMA`]) file.
pub fn parse_pf(bytes: &[u8], path: &Path) -> Result<LuminanceImage> {
    let h = parse_pf_header(bytes, bytes.len() as u64, path)?;
    // Checked against the file length above, so this fits in memory and in usize.
    let need = h.pixel_bytes() as usize;
    let pixels = &bytes[bytes.len() - need..];
    let data = if h.colour {
        let w = REC709_LUMA;
        f32s_le(pixels)
            .chunks_exact(3)
            .map(|bgr| (w[0] * f64::from(bgr[2]) + w[1] * f64::from(bgr[1]) + w[2] * f64::from(bgr[0])) as f32)
            .collect()
    } else {
        f32s_le(pixels)
    };
    Ok(LuminanceImage {
        width: h.width,
        height: h.height,
        data,
    })
}

/// The `.pf` header lumiview writes (CR LF lines, an empty line, then the NUL separator).
fn pf_header_text(width: u32, height: u32) -> String {
    format!("Typ={PF_TYPE_LUMINANCE}\r\nLines={height}\r\nColumns={width}\r\nFirstLine=0\r\nFirstColumn=0\r\n\r\n\0")
}

/// Encodes `image` as a TechnoTeam luminance `.pf` file: header `Typ=Pic98::TPlane<float>`, `Lines`,
/// `Columns`, `FirstLine=0`, `FirstColumn=0` (CR LF lines), an empty line, a NUL byte, then the pixels
/// as little-endian `f32`, top row first.
///
/// # Errors
/// [`NearfieldError::InvalidArgument`] when the size is outside 1…[`MAX_DIMENSION`] or the pixel count
/// does not match `width · height`.
pub fn encode_pf(image: &LuminanceImage) -> Result<Vec<u8>> {
    let max = MAX_DIMENSION;
    if image.width == 0 || image.height == 0 || image.width > max || image.height > max {
        return Err(NearfieldError::invalid(
            "image size",
            format!("{} × {} px is outside 1…{max}", image.width, image.height),
        ));
    }
    if image.data.len() != image.width as usize * image.height as usize {
        return Err(NearfieldError::invalid(
            "image data",
            format!("{} values for {} × {} px", image.data.len(), image.width, image.height),
        ));
    }
    let header = pf_header_text(image.width, image.height);
    let mut out = Vec::with_capacity(header.len() + image.data.len() * 4);
    out.extend_from_slice(header.as_bytes());
    for v in &image.data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

/// Writes `image` to `path` as a TechnoTeam luminance `.pf` file ([`encode_pf`]).
///
/// # Errors
/// Those of [`encode_pf`], and [`NearfieldError::Io`] naming `path`.
pub fn write_pf(path: &Path, image: &LuminanceImage) -> Result<()> {
    let bytes = encode_pf(image)?;
    let mut f = std::fs::File::create(path).map_err(|e| NearfieldError::io(path, e))?;
    f.write_all(&bytes).map_err(|e| NearfieldError::io(path, e))?;
    f.flush().map_err(|e| NearfieldError::io(path, e))
}

/// The header of a PFM file.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PfmHeader {
    colour: bool,
    width: u32,
    height: u32,
    little_endian: bool,
    data_offset: usize,
}

impl PfmHeader {
    fn pixel_bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 4 * if self.colour { 3 } else { 1 }
    }
}

/// Parses a PFM header from the first bytes of a file and checks the file length.
fn parse_pfm_header(head: &[u8], file_len: u64, path: &Path) -> Result<PfmHeader> {
    let mut pos = 0usize;
    // Reads the next whitespace-separated token (at most 64 bytes).
    let mut token = |what: &str| -> Result<(String, usize)> {
        while pos < head.len() && head[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < head.len() && !head[pos].is_ascii_whitespace() && pos - start < 64 {
            pos += 1;
        }
        if pos >= head.len() {
            return Err(fmt_err(path, format!("truncated PFM header: {what} is missing")));
        }
        if !head[pos].is_ascii_whitespace() {
            return Err(fmt_err(path, format!("PFM header: {what} is too long")));
        }
        Ok((String::from_utf8_lossy(&head[start..pos]).into_owned(), pos))
    };
    let (magic, _) = token("the magic `PF` / `Pf`")?;
    let colour = match magic.as_str() {
        "PF" => true,
        "Pf" => false,
        other => {
            return Err(fmt_err(
                path,
                format!("not a PFM file: starts with `{other}`, expected `PF` or `Pf`"),
            ))
        }
    };
    let mut dim = |what: &str| -> Result<u64> {
        let (t, _) = token(what)?;
        t.parse::<u64>()
            .ok()
            .filter(|n| (1..=u64::from(MAX_DIMENSION)).contains(n))
            .ok_or_else(|| {
                fmt_err(
                    path,
                    format!("PFM header: {what} `{t}` is not a whole number in 1…{MAX_DIMENSION}"),
                )
            })
    };
    let width = dim("width")?;
    let height = dim("height")?;
    let (scale, end) = token("scale")?;
    let scale: f64 = scale
        .parse()
        .ok()
        .filter(|s: &f64| s.is_finite() && *s != 0.0)
        .ok_or_else(|| {
            fmt_err(
                path,
                format!("PFM header: scale `{scale}` is not a finite non-zero number"),
            )
        })?;
    let (width, height) = check_size(path, width, height)?;
    let h = PfmHeader {
        colour,
        width,
        height,
        little_endian: scale < 0.0,
        // Exactly one whitespace byte after the scale.
        data_offset: end + 1,
    };
    let need = h.pixel_bytes();
    let have = file_len.saturating_sub(h.data_offset as u64);
    if have < need {
        return Err(fmt_err(
            path,
            format!(
                "truncated: the PFM header declares {} × {} {} pixels ({need} bytes) but only {have} bytes follow it",
                h.width,
                h.height,
                if colour { "RGB" } else { "grey" }
            ),
        ));
    }
    Ok(h)
}

/// Decodes a PFM file (`Pf` grey, or `PF` colour → luminance by [`REC709_LUMA`]); rows are flipped so
/// row 0 is the top (PFM stores the bottom row first).
pub fn parse_pfm(bytes: &[u8], path: &Path) -> Result<LuminanceImage> {
    let h = parse_pfm_header(bytes, bytes.len() as u64, path)?;
    let need = h.pixel_bytes() as usize;
    let pixels = &bytes[h.data_offset..h.data_offset + need];
    let read = |c: &[u8]| {
        let b = [c[0], c[1], c[2], c[3]];
        if h.little_endian {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let values: Vec<f32> = pixels.chunks_exact(4).map(read).collect();
    let lum: Vec<f32> = if h.colour {
        let w = REC709_LUMA;
        values
            .chunks_exact(3)
            .map(|rgb| (w[0] * f64::from(rgb[0]) + w[1] * f64::from(rgb[1]) + w[2] * f64::from(rgb[2])) as f32)
            .collect()
    } else {
        values
    };
    let width = h.width as usize;
    let mut data = Vec::with_capacity(lum.len());
    for row in lum.chunks_exact(width).rev() {
        data.extend_from_slice(row);
    }
    Ok(LuminanceImage {
        width: h.width,
        height: h.height,
        data,
    })
}

/// Luminance weights (R, G, B) of linear RGB with the given CIE xy chromaticities of the red, green
/// and blue primaries and the white point: the Y row of the RGB → XYZ matrix, normalised so that
/// white (1, 1, 1) has Y = 1. For Rec. 709 / sRGB primaries and D65 this is ≈ [`REC709_LUMA`].
///
/// Returns `None` for degenerate chromaticities (a y of 0, collinear primaries, non-finite or
/// negative weights).
pub fn luminance_weights(red: [f64; 2], green: [f64; 2], blue: [f64; 2], white: [f64; 2]) -> Option<[f64; 3]> {
    let xyz = |[x, y]: [f64; 2]| -> Option<DVec3> {
        (y.abs() > 1e-9 && x.is_finite() && y.is_finite()).then(|| DVec3::new(x / y, 1.0, (1.0 - x - y) / y))
    };
    let m = DMat3::from_cols(xyz(red)?, xyz(green)?, xyz(blue)?);
    if m.determinant().abs() < 1e-12 {
        return None;
    }
    let s = m.inverse() * xyz(white)?;
    let w = [s.x, s.y, s.z];
    w.iter().all(|v| v.is_finite() && *v >= 0.0).then_some(w)
}

/// The layer header of an OpenEXR file that this reader uses: the first non-deep one.
fn exr_header<'a>(meta: &'a exr::meta::MetaData, path: &Path) -> Result<&'a exr::meta::header::Header> {
    meta.headers
        .iter()
        .find(|h| !h.deep)
        .ok_or_else(|| fmt_err(path, "OpenEXR file has no flat (non-deep) layer"))
}

/// Which channels of an EXR layer make the luminance.
enum ExrChannels {
    /// A `Y` channel.
    Y,
    /// `R`, `G`, `B` with these weights.
    Rgb([f64; 3]),
}

fn exr_channels(header: &exr::meta::header::Header, path: &Path) -> Result<ExrChannels> {
    let names: Vec<String> = header.channels.list.iter().map(|c| c.name.to_string()).collect();
    if names.iter().any(|n| n == "Y") {
        return Ok(ExrChannels::Y);
    }
    if ["R", "G", "B"].iter().all(|c| names.iter().any(|n| n == c)) {
        let w = match &header.shared_attributes.chromaticities {
            None => REC709_LUMA,
            Some(c) => {
                let xy = |v: exr::math::Vec2<f32>| [f64::from(v.0), f64::from(v.1)];
                luminance_weights(xy(c.red), xy(c.green), xy(c.blue), xy(c.white)).ok_or_else(|| {
                    fmt_err(
                        path,
                        "OpenEXR chromaticities attribute is degenerate (no luminance weights)",
                    )
                })?
            }
        };
        return Ok(ExrChannels::Rgb(w));
    }
    Err(fmt_err(
        path,
        format!(
            "OpenEXR layer has channels [{}]: expected a `Y` channel or `R`, `G` and `B`",
            names.join(", ")
        ),
    ))
}

fn exr_size(header: &exr::meta::header::Header, path: &Path) -> Result<(u32, u32)> {
    check_size(path, header.layer_size.0 as u64, header.layer_size.1 as u64)
}

/// Decodes an OpenEXR file: the first non-deep layer at full resolution, its `Y` channel, or `R`, `G`,
/// `B` combined by the file's chromaticities ([`luminance_weights`]; Rec. 709 when absent). Values in
/// cd/m², row 0 at the top.
pub fn parse_exr(bytes: &[u8], path: &Path) -> Result<LuminanceImage> {
    use exr::prelude::*;
    let exr_err = |e: exr::error::Error| fmt_err(path, format!("OpenEXR: {e}"));
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false).map_err(exr_err)?;
    let header = exr_header(&meta, path)?;
    let (width, height) = exr_size(header, path)?;
    let which = exr_channels(header, path)?;
    // The decoder is third-party code fed with untrusted bytes: a panic in it becomes an error.
    let decoded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .non_parallel()
            .from_buffered(std::io::Cursor::new(bytes))
    }))
    .map_err(|_| fmt_err(path, "OpenEXR: the decoder failed on malformed data"))?
    .map_err(exr_err)?;
    let layer = &decoded.layer_data;
    let n = width as usize * height as usize;
    if layer.size.0 != width as usize || layer.size.1 != height as usize {
        return Err(fmt_err(
            path,
            format!(
                "OpenEXR: decoded layer is {} × {} px, its header says {width} × {height}",
                layer.size.0, layer.size.1
            ),
        ));
    }
    let channel = |name: &str| -> std::result::Result<Vec<f32>, NearfieldError> {
        let ch = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .ok_or_else(|| {
                fmt_err(
                    path,
                    format!("OpenEXR: channel {name} is missing from the decoded layer"),
                )
            })?;
        let v: Vec<f32> = match &ch.sample_data {
            FlatSamples::F16(v) => v.iter().map(|x| x.to_f32()).collect(),
            FlatSamples::F32(v) => v.clone(),
            FlatSamples::U32(v) => v.iter().map(|&x| x as f32).collect(),
        };
        if v.len() != n {
            return Err(fmt_err(
                path,
                format!(
                    "OpenEXR: channel {name} has {} samples for {width} × {height} px (subsampled channels are not \
                     supported)",
                    v.len()
                ),
            ));
        }
        Ok(v)
    };
    let data = match which {
        ExrChannels::Y => channel("Y")?,
        ExrChannels::Rgb(w) => {
            let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
            r.iter()
                .zip(&g)
                .zip(&b)
                .map(|((r, g), b)| (w[0] * f64::from(*r) + w[1] * f64::from(*g) + w[2] * f64::from(*b)) as f32)
                .collect()
        }
    };
    Ok(LuminanceImage { width, height, data })
}

/// Decodes the bytes of a luminance image file; `path` picks the format when the content does not
/// ([`ImageFormat::detect`]) and names the file in errors.
pub fn decode_image(bytes: &[u8], path: &Path) -> Result<LuminanceImage> {
    match ImageFormat::detect(path, bytes)? {
        ImageFormat::TechnoTeam => parse_pf(bytes, path),
        ImageFormat::Pfm => parse_pfm(bytes, path),
        ImageFormat::Exr => parse_exr(bytes, path),
    }
}

/// Reads a luminance image file (`.pf`, `.pcf`, `.pfm`, `.exr`).
///
/// # Errors
/// [`NearfieldError::Io`] when the file cannot be read; [`NearfieldError::Format`] (naming the file
/// and what is wrong: not a regular file, truncated, header field missing or bad, size too large,
/// unknown type) or
/// [`NearfieldError::Unsupported`] (camera raw `.pus` images) otherwise. Pixel values are not checked
/// here (see [`LuminanceImage::validate`]).
pub fn read_image(path: &Path) -> Result<LuminanceImage> {
    let io = |e| NearfieldError::io(path, e);
    let file = open_regular(path)?;
    let len = file.metadata().map_err(io)?.len();
    // Up to MAX_FILE_BYTES (3 GiB): a failed allocation is an error, not an abort.
    let mut bytes = crate::files::try_vec(len as usize, "reading it").map_err(io)?;
    file.take(MAX_FILE_BYTES).read_to_end(&mut bytes).map_err(io)?;
    decode_image(&bytes, path)
}

/// Largest image file read: the pixels of [`MAX_PIXELS`] colour pixels plus a header.
const MAX_FILE_BYTES: u64 = MAX_PIXELS * 12 + PF_MAX_HEADER as u64;

/// Opens a regular file of at most [`MAX_FILE_BYTES`] (not a device, FIFO or folder, which could
/// block or never end).
fn open_regular(path: &Path) -> Result<std::fs::File> {
    // A refusal (not a regular file, too large) is a format error; anything else an I/O error.
    crate::files::open_regular(path, MAX_FILE_BYTES, "a luminance image")
        .map(|(f, _)| f)
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::InvalidInput => fmt_err(path, e.to_string()),
            _ => NearfieldError::io(path, e),
        })
}

/// Reads only the header of a luminance image file: its format and size, and checks that the file is
/// long enough for the pixels it declares (`.pf`, `.pcf`, `.pfm`; OpenEXR headers are read and their
/// channels checked). Reads at most [`PF_MAX_HEADER`] bytes for `.pf` / PFM.
///
/// # Errors
/// As [`read_image`], for what the header shows.
pub fn read_image_header(path: &Path) -> Result<ImageHeader> {
    let io = |e| NearfieldError::io(path, e);
    let file = open_regular(path)?;
    let len = file.metadata().map_err(io)?.len();
    let mut head = Vec::with_capacity(PF_MAX_HEADER.min(len as usize));
    file.take(PF_MAX_HEADER as u64).read_to_end(&mut head).map_err(io)?;
    match ImageFormat::detect(path, &head)? {
        ImageFormat::TechnoTeam => {
            let h = parse_pf_header(&head, len, path)?;
            Ok(ImageHeader {
                format: ImageFormat::TechnoTeam,
                width: h.width,
                height: h.height,
                channels: if h.colour { 3 } else { 1 },
            })
        }
        ImageFormat::Pfm => {
            let h = parse_pfm_header(&head, len, path)?;
            Ok(ImageHeader {
                format: ImageFormat::Pfm,
                width: h.width,
                height: h.height,
                channels: if h.colour { 3 } else { 1 },
            })
        }
        ImageFormat::Exr => {
            let file = open_regular(path)?;
            let meta = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(file), false)
            }))
            .map_err(|_| fmt_err(path, "OpenEXR: the header reader failed on malformed data"))?
            .map_err(|e| fmt_err(path, format!("OpenEXR: {e}")))?;
            let header = exr_header(&meta, path)?;
            let (width, height) = exr_size(header, path)?;
            let channels = match exr_channels(header, path)? {
                ExrChannels::Y => 1,
                ExrChannels::Rgb(_) => 3,
            };
            Ok(ImageHeader {
                format: ImageFormat::Exr,
                width,
                height,
                channels,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("t.pf")
    }

    #[test]
    fn pf_round_trip_and_header_variants() {
        let img = LuminanceImage {
            width: 3,
            height: 2,
            data: vec![0.0, 1.0, 2.5, 1e6, 3.0, 0.25],
        };
        let bytes = encode_pf(&img).unwrap();
        assert_eq!(parse_pf(&bytes, p()).unwrap(), img);
        // No empty line, NUL right after the last field; LF line ends; `|` keys; extra fields.
        let mut b = b"|Typ=Pic98::TPlane<float>\nComment=hello world\nLines=2\nColumns=3\nFirstLine=1\n\0".to_vec();
        for v in &img.data {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let h = parse_pf_header(&b, b.len() as u64, p()).unwrap();
        assert_eq!((h.width, h.height, h.first_line, h.first_column), (3, 2, Some(1), None));
        assert_eq!(parse_pf(&b, p()).unwrap(), img);
    }

    #[test]
    fn pf_errors_name_the_field() {
        let e = parse_pf(b"Typ=Pic98::TPlane<float>\r\nLines=2\r\n\r\n\0", p())
            .unwrap_err()
            .to_string();
        assert!(e.contains("Columns is missing"), "{e}");
        let e = parse_pf(b"Typ=Pic98::TPlane<float>\r\nLines=0\r\nColumns=2\r\n\r\n\0", p())
            .unwrap_err()
            .to_string();
        assert!(e.contains("Lines=0"), "{e}");
        let e = parse_pf(b"Typ=Pic98::TPlane<float>\r\nLines=70000\r\nColumns=2\r\n\r\n\0", p())
            .unwrap_err()
            .to_string();
        assert!(e.contains("Lines=70000"), "{e}");
        let e = parse_pf(
            b"Typ=Pic98::TPlane<float>\r\nLines=65536\r\nColumns=65536\r\n\r\n\0",
            p(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("more than"), "{e}");
        let e = parse_pf(
            b"Typ=Pic98::TPlane<unsigned short>\r\nLines=1\r\nColumns=1\r\n\r\n\0\0\0",
            p(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("raw"), "{e}");
        let e = parse_pf(b"Typ=Pic98::TPlane<float>\r\nLines=1", p())
            .unwrap_err()
            .to_string();
        assert!(e.contains("truncated"), "{e}");
    }

    #[test]
    fn rec709_weights_from_chromaticities() {
        let w = luminance_weights([0.64, 0.33], [0.30, 0.60], [0.15, 0.06], [0.3127, 0.3290]).unwrap();
        for (a, b) in w.iter().zip(REC709_LUMA) {
            assert!((a - b).abs() < 2e-4, "{w:?}");
        }
        assert!(luminance_weights([0.3, 0.3], [0.3, 0.3], [0.15, 0.06], [0.3127, 0.3290]).is_none());
        assert!(luminance_weights([0.3, 0.0], [0.3, 0.6], [0.15, 0.06], [0.3127, 0.3290]).is_none());
    }

    #[test]
    fn pfm_grey_big_endian_flips_rows() {
        let mut b = b"Pf\n2 2\n1.0\n".to_vec();
        for v in [1.0f32, 2.0, 3.0, 4.0] {
            b.extend_from_slice(&v.to_be_bytes());
        }
        let img = parse_pfm(&b, Path::new("x.pfm")).unwrap();
        assert_eq!(img.data, vec![3.0, 4.0, 1.0, 2.0]);
    }
}
