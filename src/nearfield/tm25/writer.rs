//! Writing a TM-25-13 file ([`encode`]) from a header and raw records, for tests and tools.

use super::header::Tm25Header;
use super::{COLUMN_LABEL_BYTES, FIXED_BYTES, HEADER_BYTES};
use crate::nearfield::error::{NearfieldError, Result};

/// Encodes a TM-25-13 file from a header and raw records (`items_per_ray` f32 per ray, file units).
/// The ray count written is `records.len() / items_per_ray`; counts and the text size come from the
/// header's vectors; `ray_data_offset` is ignored. Used by tests and tools that write ray files.
pub fn encode(header: &Tm25Header, records: &[f32]) -> Result<Vec<u8>> {
    let items = header.items_per_ray();
    if header.flags.stokes || header.flags.tristimulus {
        return Err(NearfieldError::invalid(
            "TM-25 flags",
            "Stokes and tristimulus columns have no agreed layout and are not written",
        ));
    }
    if !records.len().is_multiple_of(items) {
        return Err(NearfieldError::invalid(
            "TM-25 records",
            format!("{} values are not whole rays of {items} items", records.len()),
        ));
    }
    let too_many =
        |what: &str, n: usize| NearfieldError::invalid(what, format!("{n} does not fit the header's 32-bit field"));
    let n_tables = i32::try_from(header.spectral_tables.len())
        .map_err(|_| too_many("spectral tables", header.spectral_tables.len()))?;
    let n_add = i32::try_from(header.additional_columns.len())
        .map_err(|_| too_many("additional columns", header.additional_columns.len()))?;
    let text_units = header.additional_text.chars().count();
    let text_bytes = (4 * text_units).div_ceil(32) * 32;
    let text_bytes_i32 = i32::try_from(text_bytes).map_err(|_| too_many("additional text", text_bytes))?;
    let nan = |v: Option<f64>| v.map_or(f32::NAN, |v| v as f32);
    let mut out = Vec::with_capacity(FIXED_BYTES as usize + 4 * records.len());
    out.extend_from_slice(b"TM25");
    out.extend_from_slice(&header.version.to_le_bytes());
    out.extend_from_slice(&header.creation_method.as_i32().to_le_bytes());
    out.extend_from_slice(&nan(header.luminous_flux_lm).to_le_bytes());
    out.extend_from_slice(&nan(header.radiant_flux_w).to_le_bytes());
    out.extend_from_slice(&((records.len() / items) as u64).to_le_bytes());
    let mut date = header.date.as_bytes().to_vec();
    date.resize(28, 0);
    out.extend_from_slice(&date);
    out.extend_from_slice(&header.ray_start_position.to_le_bytes());
    out.extend_from_slice(&header.spectral.as_i32().to_le_bytes());
    for v in [
        header.single_wavelength_nm,
        header.min_wavelength_nm,
        header.max_wavelength_nm,
    ] {
        out.extend_from_slice(&nan(v).to_le_bytes());
    }
    out.extend_from_slice(&n_tables.to_le_bytes());
    out.extend_from_slice(&n_add.to_le_bytes());
    out.extend_from_slice(&text_bytes_i32.to_le_bytes());
    out.resize(HEADER_BYTES as usize, 0);
    for (_, on) in header.flags.entries() {
        out.extend_from_slice(&i32::from(on).to_le_bytes());
    }
    for (_, text) in header.description.entries() {
        encode_utf32(text, 4000, &mut out);
    }
    let start = out.len();
    for t in &header.spectral_tables {
        let n = i32::try_from(t.wavelengths_nm.len().min(t.weights.len()))
            .map_err(|_| too_many("spectral table points", t.wavelengths_nm.len()))?;
        out.extend_from_slice(&n.to_le_bytes());
        for (l, w) in t.wavelengths_nm.iter().zip(&t.weights) {
            out.extend_from_slice(&(*l as f32).to_le_bytes());
            out.extend_from_slice(&(*w as f32).to_le_bytes());
        }
    }
    let block = out.len() - start;
    out.resize(start + block.div_ceil(32) * 32, 0);
    for c in &header.additional_columns {
        encode_utf32(c, COLUMN_LABEL_BYTES as usize, &mut out);
    }
    encode_utf32(&header.additional_text, text_bytes, &mut out);
    for v in records {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

fn encode_utf32(s: &str, bytes: usize, out: &mut Vec<u8>) {
    let start = out.len();
    for ch in s.chars().take(bytes / 4) {
        out.extend_from_slice(&(ch as u32).to_le_bytes());
    }
    out.resize(start + bytes, 0);
}

/// One ray at (1, 2, 3) mm along (0, 0, 2) followed by `extra` columns, encoded: the unit tests' file.
#[cfg(test)]
pub(super) fn one_ray(h: &Tm25Header, extra: &[f32]) -> Vec<u8> {
    let mut r = vec![1.0, 2.0, 3.0, 0.0, 0.0, 2.0];
    r.extend_from_slice(extra);
    encode(h, &r).unwrap()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::super::header::{Description, SpectralKind, Tm25Flags};
    use super::super::rays::RayFile;
    use super::super::spectral::{LuminousSource, SpectralTable};
    use super::*;

    #[test]
    fn round_trip_with_tables_labels_and_text() {
        let h = Tm25Header {
            flags: Tm25Flags {
                radiant_flux: true,
                ..Tm25Flags::default()
            },
            spectral: SpectralKind::Table,
            spectral_tables: vec![SpectralTable {
                wavelengths_nm: vec![550.0, 560.0, 570.0],
                weights: vec![1.0, 2.0, 1.0],
            }],
            additional_columns: vec!["phase".into()],
            additional_text: "hello ✓".into(),
            description: Description {
                manufacturer: "Ünïcode AG".into(),
                ..Description::default()
            },
            ..Tm25Header::default()
        };
        let bytes = one_ray(&h, &[0.5, 7.0]);
        // 36288 + (4 + 24 → 32) + 512 + 32 + 4·8
        assert_eq!(bytes.len(), 36288 + 32 + 512 + 32 + 32);
        let f = RayFile::from_bytes(&bytes, "t.tm25ray").unwrap();
        assert_eq!(f.header().description.manufacturer, "Ünïcode AG");
        assert_eq!(f.header().additional_columns, vec!["phase".to_string()]);
        assert_eq!(f.header().additional_text, "hello ✓");
        assert_eq!(f.additional(0, 0), Some(7.0));
        let r = f.ray(0).unwrap();
        assert!((r.position_m - DVec3::new(1e-3, 2e-3, 3e-3)).length() < 1e-12);
        assert_eq!(r.direction, DVec3::Z);
        let k = f.header().spectral_tables[0].luminous_efficacy().unwrap();
        assert!(k > 650.0 && k < 683.0, "{k}");
        assert_eq!(f.luminous_source(), &LuminousSource::SpectralTable { lm_per_w: k });
        assert!((r.luminous_lm.unwrap() - 0.5 * k).abs() < 1e-9);
        assert!(f.warnings().iter().any(|w| w.contains("unit length")));
    }
}
