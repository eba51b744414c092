//! Reading a TM-25 file ([`RayFile::read`], [`RayFile::from_bytes`]): the blocks in file order, every
//! field and size checked (an error names the file, the offset and what is wrong), then every ray
//! validated; non-fatal findings become the file's warnings.

use std::io::BufReader;
use std::path::Path;

use super::header::{CreationMethod, Description, SpectralKind, Tm25Flags, Tm25Header};
use super::input::{decode_utf32, known, le_f32, le_i32, Input, Src};
use super::rays::{Columns, RayFile};
use super::spectral::{LuminousSource, SpectralTable};
use super::{COLUMN_LABEL_BYTES, DESCRIPTION_BYTES, FLAGS_BYTES, HEADER_BYTES};
use crate::nearfield::error::{NearfieldError, Result};

const FLAG_NAMES: [&str; 8] = [
    "position",
    "direction",
    "radiant flux",
    "wavelength",
    "luminous flux",
    "Stokes",
    "tristimulus",
    "spectrum index",
];

impl RayFile {
    /// Reads a TM-25 file. Sizes are checked against the file size before anything is allocated.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        // A FIFO or device is refused before it is opened (opening a FIFO blocks).
        let (file, len) =
            crate::files::open_regular(path, u64::MAX, "a TM-25 ray file").map_err(|e| NearfieldError::io(path, e))?;
        let input = Input {
            src: Src::File(BufReader::with_capacity(1 << 16, file)),
            len,
            pos: 0,
            path,
        };
        Self::parse(input)
    }

    /// Reads a TM-25 file from memory; `name` names it in errors.
    pub fn from_bytes(bytes: &[u8], name: impl AsRef<Path>) -> Result<Self> {
        let input = Input {
            src: Src::Bytes(bytes),
            len: bytes.len() as u64,
            pos: 0,
            path: name.as_ref(),
        };
        Self::parse(input)
    }

    fn parse(mut inp: Input<'_>) -> Result<Self> {
        let path = inp.path.to_path_buf();
        let fmt = |m: String| NearfieldError::format(&path, m);
        let unsupported = |m: String| NearfieldError::Unsupported {
            path: path.clone(),
            message: m,
        };
        let mut warnings = Vec::new();
        if inp.len < 4 {
            return Err(fmt(format!(
                "not a TM-25 ray file: {} bytes, shorter than the \"TM25\" magic",
                inp.len
            )));
        }
        let magic = inp.take(4, "file type")?;
        if magic != b"TM25" {
            return Err(fmt(format!(
                "not a TM-25 ray file: the first 4 bytes are {:?}, expected \"TM25\"",
                String::from_utf8_lossy(&magic)
            )));
        }
        let mut h = vec![0u8; 4];
        h.extend(inp.take(HEADER_BYTES - 4, "file header (256 bytes)")?);

        let version = le_i32(&h, 4);
        if version != 2013 {
            if !(2013..=2100).contains(&version) {
                return Err(fmt(format!(
                    "version (offset 4) is {version}: this reader knows TM-25-13 (2013) and later revisions"
                )));
            }
            warnings.push(format!(
                "version {version}: read with the TM-25-13 layout (later revisions keep it compatible)"
            ));
        }
        let creation_method = CreationMethod::from_i32(le_i32(&h, 8));
        if let CreationMethod::Other(v) = creation_method {
            warnings.push(format!(
                "creation method (offset 8) is {v}; 0 (simulated) or 1 (measured) expected"
            ));
        }
        let flux_field = |at: usize, name: &str, unit: &str| -> Result<Option<f64>> {
            let v = le_f32(&h, at);
            if v.is_nan() {
                return Ok(None);
            }
            if !v.is_finite() || v < 0.0 {
                return Err(fmt(format!(
                    "{name} (offset {at}) is {v} {unit}: it must be ≥ 0, or NaN for unknown"
                )));
            }
            Ok(Some(v as f64))
        };
        let luminous_flux_lm = flux_field(12, "total luminous flux", "lm")?;
        let radiant_flux_w = flux_field(16, "total radiant flux", "W")?;
        let ray_count = u64::from_le_bytes([h[20], h[21], h[22], h[23], h[24], h[25], h[26], h[27]]);
        let date = String::from_utf8_lossy(&h[28..56])
            .trim_end_matches('\0')
            .split('\0')
            .next()
            .unwrap_or_default()
            .trim()
            .to_string();
        let ray_start_position = le_i32(&h, 56);
        let spectral_id = le_i32(&h, 60);
        let spectral = SpectralKind::from_i32(spectral_id).ok_or_else(|| {
            fmt(format!(
                "spectral data identifier (offset 60) is {spectral_id}: it must be 0…4"
            ))
        })?;
        let single_wavelength_nm = known(le_f32(&h, 64));
        let min_wavelength_nm = known(le_f32(&h, 68));
        let max_wavelength_nm = known(le_f32(&h, 72));
        if spectral == SpectralKind::SingleWavelength && !single_wavelength_nm.is_some_and(|l| l.is_finite() && l > 0.0)
        {
            return Err(fmt(format!(
                "spectral data identifier 1 (single wavelength) but the wavelength (offset 64) is {}",
                le_f32(&h, 64)
            )));
        }
        let n_tables = le_i32(&h, 76);
        let n_additional = le_i32(&h, 80);
        let text_bytes = le_i32(&h, 84);
        if n_tables < 0 || n_additional < 0 || text_bytes < 0 {
            return Err(fmt(format!(
                "negative count in the header: spectral tables {n_tables} (offset 76), additional items \
                 {n_additional} (offset 80), additional text bytes {text_bytes} (offset 84)"
            )));
        }
        if matches!(spectral, SpectralKind::Table | SpectralKind::PerRayTableIndex) && n_tables == 0 {
            return Err(fmt(format!(
                "spectral data identifier {spectral_id} ({}) needs spectral tables, but the count (offset 76) is 0",
                spectral.name()
            )));
        }
        if n_tables > 0 && !matches!(spectral, SpectralKind::Table | SpectralKind::PerRayTableIndex) {
            warnings.push(format!(
                "{n_tables} spectral table(s) with spectral data identifier {spectral_id}: tables read but unused"
            ));
        }
        if spectral == SpectralKind::Table && n_tables > 1 {
            warnings.push(format!(
                "spectral data identifier 3 with {n_tables} tables: the first describes every ray"
            ));
        }
        if text_bytes % 4 != 0 {
            return Err(fmt(format!(
                "additional text size (offset 84) is {text_bytes} bytes: not whole UTF-32 units"
            )));
        }
        if text_bytes % 32 != 0 {
            warnings.push(format!(
                "additional text size {text_bytes} is not a multiple of 32 bytes as TM-25-13 asks"
            ));
        }
        if h[88..256].iter().any(|b| *b != 0) {
            warnings.push("reserved header bytes 88–255 are not zero (ignored)".into());
        }

        let fb = inp.take(FLAGS_BYTES, "known-data flags block")?;
        let mut f = [false; 8];
        for (i, name) in FLAG_NAMES.iter().enumerate() {
            let v = le_i32(&fb, 4 * i);
            if v != 0 && v != 1 {
                return Err(fmt(format!(
                    "{name} flag (offset {}) is {v}: flags must be 0 or 1",
                    HEADER_BYTES + 4 * i as u64
                )));
            }
            f[i] = v == 1;
        }
        if !f[0] || !f[1] {
            return Err(fmt(
                "position and direction flags (offsets 256, 260) must be 1: every ray has x, y, z, kx, ky, kz".into(),
            ));
        }
        let flags = Tm25Flags {
            radiant_flux: f[2],
            wavelength: f[3],
            luminous_flux: f[4],
            stokes: f[5],
            tristimulus: f[6],
            spectrum_index: f[7],
        };
        if flags.stokes {
            return Err(unsupported(
                "the Stokes flag (offset 276) is set: Stokes columns are not supported, because implementations \
                 disagree on their layout (3 columns S1–S3, or 6 with the polarisation ellipse axis), so the ray \
                 records cannot be split reliably"
                    .into(),
            ));
        }
        if flags.tristimulus {
            return Err(unsupported(
                "the tristimulus flag (offset 280) is set: tristimulus X/Z columns are not supported, because \
                 implementations disagree on the column layout around them, so the ray records cannot be split reliably"
                    .into(),
            ));
        }
        if !flags.radiant_flux && !flags.luminous_flux {
            return Err(fmt(
                "neither the radiant flux flag (offset 264) nor the luminous flux flag (offset 272) is set: rays carry no flux".into(),
            ));
        }
        if spectral == SpectralKind::PerRayWavelength && !flags.wavelength {
            return Err(fmt(
                "spectral data identifier 2 (wavelength per ray) but the wavelength flag (offset 268) is 0".into(),
            ));
        }
        if flags.wavelength && spectral != SpectralKind::PerRayWavelength {
            warnings.push(format!(
                "wavelength column present with spectral data identifier {spectral_id} (2 expected)"
            ));
        }
        if flags.spectrum_index != (spectral == SpectralKind::PerRayTableIndex) {
            return Err(fmt(format!(
                "spectrum index flag (offset 284) is {} but the spectral data identifier is {spectral_id}: the \
                 flag is set exactly when the identifier is 4",
                u8::from(flags.spectrum_index)
            )));
        }

        let db = inp.take(DESCRIPTION_BYTES, "description block")?;
        let mut description = Description::default();
        for (i, field) in description.fields_mut().into_iter().enumerate() {
            let chunk = &db[i * 4000..(i + 1) * 4000];
            *field = decode_utf32(chunk, &format!("description field {}", i + 1), &mut warnings);
        }

        // Spectral tables: i32 N + N pairs each; the whole block padded to 32 bytes.
        let mut spectral_tables = Vec::new();
        let mut block = 0u64;
        for t in 1..=n_tables {
            let nb = inp.take(4, &format!("spectral table {t} (point count)"))?;
            let n = le_i32(&nb, 0);
            if n <= 0 {
                return Err(fmt(format!(
                    "spectral table {t} (offset {}) declares {n} points: it must be > 0",
                    inp.pos - 4
                )));
            }
            let bytes = 8 * n as u64;
            let pairs = inp.take(bytes, &format!("spectral table {t} ({n} points)"))?;
            let mut table = SpectralTable::default();
            for (j, p) in pairs.chunks_exact(8).enumerate() {
                let (l, w) = (le_f32(p, 0), le_f32(p, 4));
                if !(l.is_finite() && l > 0.0 && w.is_finite() && w >= 0.0) {
                    return Err(fmt(format!(
                        "spectral table {t}, point {j}: wavelength {l} nm and weight {w} must be finite, λ > 0 and weight ≥ 0"
                    )));
                }
                table.wavelengths_nm.push(l as f64);
                table.weights.push(w as f64);
            }
            spectral_tables.push(table);
            block += 4 + bytes;
        }
        let pad = (32 - block % 32) % 32;
        if n_tables > 0 && pad > 0 {
            inp.take(pad, "padding after the spectral tables")?;
        }

        let mut additional_columns = Vec::new();
        inp.ensure(
            (n_additional as u64) * COLUMN_LABEL_BYTES,
            &format!("additional column labels ({n_additional} × 512 bytes)"),
        )?;
        for c in 1..=n_additional {
            let b = inp.take(COLUMN_LABEL_BYTES, "additional column label")?;
            let name = decode_utf32(&b, &format!("additional column label {c}"), &mut warnings);
            additional_columns.push(if name.is_empty() {
                format!("additional {c}")
            } else {
                name
            });
        }
        let text = inp.take(text_bytes as u64, "additional text block")?;
        let additional_text = decode_utf32(&text, "additional text", &mut warnings);

        let ray_data_offset = inp.pos;
        let header = Tm25Header {
            version,
            creation_method,
            luminous_flux_lm,
            radiant_flux_w,
            ray_count,
            date,
            ray_start_position,
            spectral,
            single_wavelength_nm,
            min_wavelength_nm,
            max_wavelength_nm,
            flags,
            description,
            spectral_tables,
            additional_columns,
            additional_text,
            additional_text_bytes: text_bytes as u64,
            ray_data_offset,
        };
        let columns = Columns::of(&header);
        let record = 4 * columns.items as u64;
        if !(0..=7).contains(&ray_start_position) {
            if ray_start_position as u64 == ray_data_offset {
                warnings.push(format!(
                    "ray start position (offset 56) is {ray_start_position}, which equals the computed ray data \
                     offset: read as an offset by its writer (TM-25-13 defines a code 0…7 there)"
                ));
            } else {
                warnings.push(format!(
                    "ray start position (offset 56) is {ray_start_position}: neither a start-position code (0…7) \
                     nor the computed ray data offset {ray_data_offset}; the computed offset is used"
                ));
            }
        }
        let needed = ray_count.checked_mul(record);
        let remaining = inp.remaining();
        match needed {
            Some(n) if n == remaining => {}
            Some(n) if n > remaining => {
                return Err(fmt(format!(
                    "the header declares {ray_count} rays × {record} bytes = {n} bytes of ray data from offset \
                     {ray_data_offset}, but only {remaining} bytes follow (file size {}, expected {}): the file is \
                     truncated or the ray count is wrong",
                    inp.len,
                    ray_data_offset.saturating_add(n)
                )))
            }
            Some(n) => {
                return Err(fmt(format!(
                    "{} bytes follow the last of {ray_count} rays ({record} bytes each from offset {ray_data_offset}; \
                     expected file size {}, actual {}): the ray count, flags or block sizes do not match the data",
                    remaining - n,
                    ray_data_offset + n,
                    inp.len
                )))
            }
            None => {
                return Err(fmt(format!(
                    "the header declares {ray_count} rays of {record} bytes: far more than the file's {} bytes",
                    inp.len
                )))
            }
        }
        let count = usize::try_from(ray_count)
            .ok()
            .and_then(|c| c.checked_mul(columns.items))
            .ok_or_else(|| fmt(format!("{ray_count} rays do not fit in memory on this platform")))?;
        let data = inp.take_f32s(count, "ray data")?;

        let mut file = Self {
            luminous: LuminousSource::Unavailable,
            path,
            header,
            columns,
            data,
            warnings,
        };
        file.validate_rays()?;
        file.luminous = file.choose_luminous_source();
        file.compare_header_flux();
        Ok(file)
    }

    /// Warns where the header's total fluxes differ from the sums of the ray columns by more than 1 %.
    fn compare_header_flux(&mut self) {
        let c = self.columns;
        let sum = |j: usize| -> f64 { self.data.chunks_exact(c.items).map(|r| r[j] as f64).sum() };
        let checks = [
            (c.luminous, self.header.luminous_flux_lm, "luminous", "lm"),
            (c.radiant, self.header.radiant_flux_w, "radiant", "W"),
        ];
        for (col, head, name, unit) in checks {
            if let (Some(j), Some(h)) = (col, head) {
                let s = sum(j);
                if (s - h).abs() > 0.01 * h.abs().max(s.abs()) {
                    self.warnings.push(format!(
                        "the rays' {name} fluxes sum to {s:.6} {unit}, the header states {h} {unit} (lumiview takes the header's \
                         total as the source's flux unless told otherwise: docs/formats.md)"
                    ));
                }
            }
        }
    }

    /// Checks every ray: finite position and direction, non-zero direction, finite non-negative
    /// fluxes, positive wavelengths, spectrum indices within the tables.
    fn validate_rays(&mut self) -> Result<()> {
        let c = self.columns;
        let n_tables = self.header.spectral_tables.len();
        let mut not_unit = 0u64;
        let mut first_not_unit = None;
        let err = |i: usize, m: String| NearfieldError::format(&self.path, format!("ray {i}: {m}"));
        for (i, r) in self.data.chunks_exact(c.items.max(1)).enumerate() {
            let (p, k) = (&r[0..3], &r[3..6]);
            if p.iter().any(|v| !v.is_finite()) {
                return Err(err(
                    i,
                    format!("position ({}, {}, {}) mm is not finite", p[0], p[1], p[2]),
                ));
            }
            if k.iter().any(|v| !v.is_finite()) {
                return Err(err(
                    i,
                    format!("direction ({}, {}, {}) is not finite", k[0], k[1], k[2]),
                ));
            }
            let n2 = k.iter().map(|v| (*v as f64) * (*v as f64)).sum::<f64>();
            if n2 < 1e-12 {
                return Err(err(
                    i,
                    format!("direction ({}, {}, {}) has (almost) zero length", k[0], k[1], k[2]),
                ));
            }
            if (n2.sqrt() - 1.0).abs() > 1e-3 {
                not_unit += 1;
                first_not_unit.get_or_insert(i);
            }
            for (col, name, unit) in [(c.radiant, "radiant flux", "W"), (c.luminous, "luminous flux", "lm")] {
                if let Some(j) = col {
                    let v = r[j];
                    if !v.is_finite() || v < 0.0 {
                        return Err(err(i, format!("{name} {v} {unit} must be finite and ≥ 0")));
                    }
                }
            }
            if let Some(j) = c.wavelength {
                let v = r[j];
                if !v.is_finite() || v <= 0.0 {
                    return Err(err(i, format!("wavelength {v} nm must be finite and > 0")));
                }
            }
            if let Some(j) = c.spectrum_index {
                let v = r[j];
                if !(v.fract() == 0.0 && v >= 1.0 && (v as f64) <= n_tables as f64) {
                    return Err(err(i, format!("spectrum index {v} is not a table number 1…{n_tables}")));
                }
            }
        }
        if let Some(i) = first_not_unit {
            self.warnings.push(format!(
                "{not_unit} direction(s) differ from unit length by more than 10⁻³ (first: ray {i}); normalised on use"
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::header::Tm25Header;
    use super::super::writer::one_ray;
    use super::*;

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let good = one_ray(&Tm25Header::default(), &[1.0]);
        for n in [0, 3, 4, 100, 256, 288, 36287, 36288, good.len() - 1] {
            assert!(RayFile::from_bytes(&good[..n], "t").is_err(), "{n}");
        }
        let mut huge = good.clone();
        huge[20..28].copy_from_slice(&u64::MAX.to_le_bytes());
        let e = RayFile::from_bytes(&huge, "t").unwrap_err().to_string();
        assert!(e.contains("rays"), "{e}");
        let mut neg = good.clone();
        neg[76..80].copy_from_slice(&(-1i32).to_le_bytes());
        assert!(RayFile::from_bytes(&neg, "t").is_err());
        let mut table = good.clone();
        table[76..80].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(RayFile::from_bytes(&table, "t").is_err());
    }
}
