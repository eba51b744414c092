//! TechnoTeam `.pf` (luminance) and `.pcf` (colour) files: the `Key=Value` header, the pixels (the
//! file's last bytes), and the `.pf` writer.

use std::io::Write;
use std::path::Path;

use super::{
    check_size, fmt_err, MAX_DIMENSION, PF_MAX_HEADER, PF_TYPE_COLOUR, PF_TYPE_LUMINANCE, PF_TYPE_RAW, REC709_LUMA,
};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::LuminanceImage;

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
}
