//! OpenEXR files (the first flat layer: its `Y` channel, or `R`, `G`, `B` weighted by the file's
//! chromaticities) and the luminance weights of linear RGB with given primaries.

use std::path::Path;

use glam::{DMat3, DVec3};

use super::{check_size, fmt_err, REC709_LUMA};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::LuminanceImage;

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
pub(super) fn exr_header<'a>(meta: &'a exr::meta::MetaData, path: &Path) -> Result<&'a exr::meta::header::Header> {
    meta.headers
        .iter()
        .find(|h| !h.deep)
        .ok_or_else(|| fmt_err(path, "OpenEXR file has no flat (non-deep) layer"))
}

/// Which channels of an EXR layer make the luminance.
pub(super) enum ExrChannels {
    /// A `Y` channel.
    Y,
    /// `R`, `G`, `B` with these weights.
    Rgb([f64; 3]),
}

pub(super) fn exr_channels(header: &exr::meta::header::Header, path: &Path) -> Result<ExrChannels> {
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

pub(super) fn exr_size(header: &exr::meta::header::Header, path: &Path) -> Result<(u32, u32)> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rec709_weights_from_chromaticities() {
        let w = luminance_weights([0.64, 0.33], [0.30, 0.60], [0.15, 0.06], [0.3127, 0.3290]).unwrap();
        for (a, b) in w.iter().zip(REC709_LUMA) {
            assert!((a - b).abs() < 2e-4, "{w:?}");
        }
        assert!(luminance_weights([0.3, 0.3], [0.3, 0.3], [0.15, 0.06], [0.3127, 0.3290]).is_none());
        assert!(luminance_weights([0.3, 0.0], [0.3, 0.6], [0.15, 0.06], [0.3127, 0.3290]).is_none());
    }
}
