//! Portable float maps: `Pf` (grey) and `PF` (colour), either byte order, rows flipped so row 0 is the
//! top.

use std::path::Path;

use super::{check_size, fmt_err, MAX_DIMENSION, REC709_LUMA};
use crate::nearfield::error::Result;
use crate::nearfield::rayset::LuminanceImage;

/// The header of a PFM file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PfmHeader {
    pub(super) colour: bool,
    pub(super) width: u32,
    pub(super) height: u32,
    little_endian: bool,
    data_offset: usize,
}

impl PfmHeader {
    fn pixel_bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 4 * if self.colour { 3 } else { 1 }
    }
}

/// Parses a PFM header from the first bytes of a file and checks the file length.
pub(super) fn parse_pfm_header(head: &[u8], file_len: u64, path: &Path) -> Result<PfmHeader> {
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

#[cfg(test)]
mod tests {
    use super::*;

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
