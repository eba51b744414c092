//! IES TM-25-13 ray files: reader (and a writer for tests and tools).
//!
//! Layout (little-endian; see docs/formats.md, section "IES TM-25 ray files"):
//!
//! | offset | size | field (TM-25-13 clause) |
//! |---|---|---|
//! | 0 | 4 | `"TM25"` (4.7.1.1) |
//! | 4 | i32 | version, 2013 (4.7.1.2) |
//! | 8 | i32 | creation method: 0 simulated, 1 measured (4.7.1.3) |
//! | 12 | f32 | total luminous flux, lm; NaN = unknown (4.7.1.4) |
//! | 16 | f32 | total radiant flux, W; NaN = unknown (4.7.1.5) |
//! | 20 | u64 | number of rays (4.7.1.6) |
//! | 28 | char\[28\] | creation date and time, NUL-padded (4.7.1.7) |
//! | 56 | i32 | ray start position: a *code* (0 = unknown), not a byte offset (4.7.1.8) |
//! | 60 | i32 | spectral data identifier 0…4 (4.7.1.9) |
//! | 64/68/72 | f32 | single / minimum / maximum wavelength, nm (4.7.1.10–12) |
//! | 76 | i32 | number of spectral tables (4.7.1.13) |
//! | 80 | i32 | number of additional ray data items (4.7.1.14) |
//! | 84 | i32 | size of the additional text block, bytes (4.7.1.15) |
//! | 88 | 168 | reserved |
//! | 256 | 8 × i32 | known-data flags: position, direction, radiant flux, wavelength, luminous flux, Stokes, tristimulus, spectrum index (4.7.2) |
//! | 288 | 9 × 4000 | description: 9 UTF-32 fields of 1000 units (4.7.3) |
//! | 36288 | … | spectral tables: per table i32 N + N × (λ, weight) f32; the whole block zero-padded to a multiple of 32 bytes (4.7.4) |
//! | … | 512 each | additional column labels, UTF-32 (4.7.5) |
//! | … | size | additional text, UTF-32 (4.7.6) |
//! | … | rays × items × 4 | ray records: x, y, z (mm), kx, ky, kz, then the flagged columns in flag order, then the additional columns |
//!
//! The ray data offset is computed from this layout, and the file size must equal
//! `offset + rays × items × 4` exactly: a mismatch is an error that states both sizes. Every size is
//! checked against the file size before anything is allocated.
//!
//! Rays are kept as the file's `f32` records (28 bytes per ray for 7 columns), not as a `Vec` of
//! structs; [`RayFile::rays`] yields [`Ray`]s (metres, unit directions, fluxes) on the fly.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::error::{NearfieldError, Result};

/// Size of the file header block (4.7.1).
pub const HEADER_BYTES: u64 = 256;
/// Size of the known-data flags block (4.7.2).
pub const FLAGS_BYTES: u64 = 32;
/// Size of the description block (4.7.3): 9 fields × 1000 UTF-32 code units.
pub const DESCRIPTION_BYTES: u64 = 36_000;
/// Offset of the spectral tables block, the first variable-size part.
pub const FIXED_BYTES: u64 = HEADER_BYTES + FLAGS_BYTES + DESCRIPTION_BYTES;
/// Size of one additional-column label (4.7.5): 128 UTF-32 code units.
pub const COLUMN_LABEL_BYTES: u64 = 512;
/// Maximum luminous efficacy of radiation for photopic vision (lm/W).
pub const K_M: f64 = 683.0;

/// How the ray data were created (4.7.1.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CreationMethod {
    /// 0: by simulation.
    Simulated,
    /// 1: by measurement (e.g. a near-field goniophotometer).
    Measured,
    /// Any other value (kept, with a warning).
    Other(i32),
}

impl CreationMethod {
    fn from_i32(v: i32) -> Self {
        match v {
            0 => Self::Simulated,
            1 => Self::Measured,
            o => Self::Other(o),
        }
    }
    /// The stored integer.
    pub fn as_i32(self) -> i32 {
        match self {
            Self::Simulated => 0,
            Self::Measured => 1,
            Self::Other(v) => v,
        }
    }
    /// A short name ("simulated", "measured", "other (N)").
    pub fn name(self) -> String {
        match self {
            Self::Simulated => "simulated".into(),
            Self::Measured => "measured".into(),
            Self::Other(v) => format!("other ({v})"),
        }
    }
}

/// The spectral data identifier (4.7.1.9). Checked against the three real files: the LED file with
/// one spectral table and no wavelength column has 3, the 500 nm point source has 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpectralKind {
    /// 0: no spectral information.
    None = 0,
    /// 1: every ray has the header's single wavelength.
    SingleWavelength = 1,
    /// 2: a wavelength column per ray.
    PerRayWavelength = 2,
    /// 3: one spectral table describes every ray.
    Table = 3,
    /// 4: a spectrum-index column per ray selects one of several tables (1-based).
    PerRayTableIndex = 4,
}

impl SpectralKind {
    fn from_i32(v: i32) -> Option<Self> {
        Some(match v {
            0 => Self::None,
            1 => Self::SingleWavelength,
            2 => Self::PerRayWavelength,
            3 => Self::Table,
            4 => Self::PerRayTableIndex,
            _ => return None,
        })
    }
    /// The stored integer.
    pub fn as_i32(self) -> i32 {
        self as i32
    }
    /// A short description.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::SingleWavelength => "single wavelength",
            Self::PerRayWavelength => "wavelength per ray",
            Self::Table => "one spectral table for all rays",
            Self::PerRayTableIndex => "spectral table index per ray",
        }
    }
}

/// The known-data flags (4.7.2). Position and direction are always present (their flags must be 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Tm25Flags {
    /// A radiant flux column (W).
    pub radiant_flux: bool,
    /// A wavelength column (nm).
    pub wavelength: bool,
    /// A luminous flux column (lm; tristimulus Y).
    pub luminous_flux: bool,
    /// Stokes columns (rejected as unsupported: their column count differs between implementations).
    pub stokes: bool,
    /// Tristimulus X and Z columns (rejected as unsupported, see [`Tm25Flags::stokes`]).
    pub tristimulus: bool,
    /// A spectrum-index column (1-based index into the spectral tables).
    pub spectrum_index: bool,
}

impl Tm25Flags {
    /// The eight stored flags in file order, with their names.
    pub fn entries(&self) -> [(&'static str, bool); 8] {
        [
            ("position", true),
            ("direction", true),
            ("radiant flux", self.radiant_flux),
            ("wavelength", self.wavelength),
            ("luminous flux", self.luminous_flux),
            ("Stokes", self.stokes),
            ("tristimulus", self.tristimulus),
            ("spectrum index", self.spectrum_index),
        ]
    }
}

/// The description block (4.7.3): nine free-text fields.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Description {
    /// 4.7.3.1 Name of the light source.
    pub light_source_name: String,
    /// 4.7.3.2 Manufacturer of the light source.
    pub manufacturer: String,
    /// 4.7.3.3 Creator of the optical light source model.
    pub model_creator: String,
    /// 4.7.3.4 Creator of the ray file.
    pub ray_file_creator: String,
    /// 4.7.3.5 Measurement equipment or simulation software used.
    pub equipment: String,
    /// 4.7.3.6 Camera information.
    pub camera: String,
    /// 4.7.3.7 Light source operation (drive current, temperature, ...).
    pub operation: String,
    /// 4.7.3.8 Additional information.
    pub additional_info: String,
    /// 4.7.3.9 Data reference (to the source geometry).
    pub data_reference: String,
}

impl Description {
    /// The nine fields in file order with their names (as used by `lumiview info`).
    pub fn entries(&self) -> [(&'static str, &str); 9] {
        [
            ("light source name", &self.light_source_name),
            ("manufacturer", &self.manufacturer),
            ("model creator", &self.model_creator),
            ("ray file creator", &self.ray_file_creator),
            ("equipment / software", &self.equipment),
            ("camera", &self.camera),
            ("operation", &self.operation),
            ("additional information", &self.additional_info),
            ("data reference", &self.data_reference),
        ]
    }

    fn fields_mut(&mut self) -> [&mut String; 9] {
        [
            &mut self.light_source_name,
            &mut self.manufacturer,
            &mut self.model_creator,
            &mut self.ray_file_creator,
            &mut self.equipment,
            &mut self.camera,
            &mut self.operation,
            &mut self.additional_info,
            &mut self.data_reference,
        ]
    }
}

/// One spectral table (4.7.4): relative spectral weights at wavelengths.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpectralTable {
    /// Wavelengths (nm), > 0.
    pub wavelengths_nm: Vec<f64>,
    /// Relative weights, ≥ 0 (any scale).
    pub weights: Vec<f64>,
}

impl SpectralTable {
    /// Luminous efficacy of radiation of this spectrum, `683 · ∫V(λ)S(λ)dλ / ∫S(λ)dλ` in lm/W
    /// (trapezoids over the table's points; a one-point table is a line). `None` when the spectrum
    /// has no power.
    pub fn luminous_efficacy(&self) -> Option<f64> {
        let mut pts: Vec<(f64, f64)> = self
            .wavelengths_nm
            .iter()
            .copied()
            .zip(self.weights.iter().copied())
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        if pts.len() == 1 {
            return (pts[0].1 > 0.0).then(|| K_M * photopic_efficiency(pts[0].0));
        }
        let (mut num, mut den) = (0.0, 0.0);
        for w in pts.windows(2) {
            let ((l0, s0), (l1, s1)) = (w[0], w[1]);
            let dl = l1 - l0;
            num += 0.5 * dl * (s0 * photopic_efficiency(l0) + s1 * photopic_efficiency(l1));
            den += 0.5 * dl * (s0 + s1);
        }
        (den > 0.0 && num.is_finite()).then(|| K_M * num / den)
    }

    /// Wavelength of the largest weight (nm).
    pub fn peak_nm(&self) -> Option<f64> {
        self.wavelengths_nm
            .iter()
            .zip(&self.weights)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(l, _)| *l)
    }
}

/// Everything in a TM-25 file before the ray records.
#[derive(Debug, Clone, PartialEq)]
pub struct Tm25Header {
    /// File version (2013 for TM-25-13).
    pub version: i32,
    /// Simulated or measured.
    pub creation_method: CreationMethod,
    /// Total luminous flux (lm); `None` where the file stores NaN (unknown).
    pub luminous_flux_lm: Option<f64>,
    /// Total radiant flux (W); `None` where the file stores NaN (unknown).
    pub radiant_flux_w: Option<f64>,
    /// Number of rays.
    pub ray_count: u64,
    /// Creation date and time as written (ISO 8601 nominally), NULs removed.
    pub date: String,
    /// Ray start position code (4.7.1.8; 0 = unknown; the reference implementation accepts 0…7). It
    /// is not a byte offset: the ray data offset is [`Tm25Header::ray_data_offset`].
    pub ray_start_position: i32,
    /// The spectral data identifier.
    pub spectral: SpectralKind,
    /// Single wavelength (nm) for [`SpectralKind::SingleWavelength`]; `None` where NaN.
    pub single_wavelength_nm: Option<f64>,
    /// Minimum wavelength (nm); `None` where NaN.
    pub min_wavelength_nm: Option<f64>,
    /// Maximum wavelength (nm); `None` where NaN.
    pub max_wavelength_nm: Option<f64>,
    /// Which optional columns each ray has.
    pub flags: Tm25Flags,
    /// The nine description strings.
    pub description: Description,
    /// Spectral tables (their count is the header's 4.7.1.13).
    pub spectral_tables: Vec<SpectralTable>,
    /// Labels of the additional columns (their count is the header's 4.7.1.14).
    pub additional_columns: Vec<String>,
    /// The additional text block.
    pub additional_text: String,
    /// Size of the additional text block as declared in the header (bytes).
    pub additional_text_bytes: u64,
    /// Byte offset of the first ray record (computed from the layout when reading).
    pub ray_data_offset: u64,
}

impl Tm25Header {
    /// Number of `f32` items per ray: 6 + flagged columns + additional columns.
    pub fn items_per_ray(&self) -> usize {
        let f = &self.flags;
        6 + usize::from(f.radiant_flux)
            + usize::from(f.wavelength)
            + usize::from(f.luminous_flux)
            + if f.stokes { 6 } else { 0 }
            + if f.tristimulus { 2 } else { 0 }
            + usize::from(f.spectrum_index)
            + self.additional_columns.len()
    }

    /// Column names of a ray record, in order.
    pub fn column_names(&self) -> Vec<String> {
        let mut v: Vec<String> = ["x", "y", "z", "kx", "ky", "kz"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let f = &self.flags;
        if f.radiant_flux {
            v.push("radiant flux".into());
        }
        if f.wavelength {
            v.push("wavelength".into());
        }
        if f.luminous_flux {
            v.push("luminous flux".into());
        }
        if f.spectrum_index {
            v.push("spectrum index".into());
        }
        v.extend(self.additional_columns.iter().cloned());
        v
    }
}

/// Where a ray's luminous flux comes from. Chosen once per file, in this order: the file's
/// luminous flux column; else (radiant flux only) the header ratio Φv/Φe when both header fluxes are
/// known and positive; else the spectral information (683 lm/W × V(λ) of the single wavelength, of
/// each ray's wavelength, or the luminous efficacy of the spectral table(s)); else none.
#[derive(Debug, Clone, PartialEq)]
pub enum LuminousSource {
    /// The luminous flux column of the file.
    Column,
    /// Radiant flux × the header's luminous / radiant flux.
    HeaderRatio {
        /// Φv / Φe from the header (lm/W).
        lm_per_w: f64,
    },
    /// Radiant flux × 683 lm/W × V(λ) of the header's single wavelength.
    SingleWavelength {
        /// The wavelength (nm).
        nm: f64,
        /// 683 · V(λ) (lm/W).
        lm_per_w: f64,
    },
    /// Radiant flux × 683 lm/W × V(λ) of each ray's wavelength column.
    PerRayWavelength,
    /// Radiant flux × the luminous efficacy of the file's spectral table.
    SpectralTable {
        /// 683 ∫VS / ∫S (lm/W).
        lm_per_w: f64,
    },
    /// Radiant flux × the luminous efficacy of the table each ray's index selects.
    PerRayTable {
        /// Efficacy per table, in table order (lm/W).
        lm_per_w: Vec<f64>,
    },
    /// Radiant flux only, and nothing says how to weigh it: no luminous flux.
    Unavailable,
}

impl LuminousSource {
    /// A one-line description of the rule.
    pub fn describe(&self) -> String {
        match self {
            Self::Column => "luminous flux column of the file".into(),
            Self::HeaderRatio { lm_per_w } => {
                format!("radiant flux × header Φv/Φe = {lm_per_w:.3} lm/W")
            }
            Self::SingleWavelength { nm, lm_per_w } => {
                format!("radiant flux × 683 lm/W × V({nm} nm) = {lm_per_w:.3} lm/W")
            }
            Self::PerRayWavelength => "radiant flux × 683 lm/W × V(λ) of each ray's wavelength".into(),
            Self::SpectralTable { lm_per_w } => {
                format!("radiant flux × luminous efficacy of the spectral table = {lm_per_w:.3} lm/W")
            }
            Self::PerRayTable { .. } => "radiant flux × luminous efficacy of each ray's spectral table".into(),
            Self::Unavailable => "none (radiant flux only, no spectral information)".into(),
        }
    }
    /// A short machine name (`column`, `header-ratio`, `single-wavelength`, ...).
    pub fn key(&self) -> &'static str {
        match self {
            Self::Column => "column",
            Self::HeaderRatio { .. } => "header-ratio",
            Self::SingleWavelength { .. } => "single-wavelength",
            Self::PerRayWavelength => "per-ray-wavelength",
            Self::SpectralTable { .. } => "spectral-table",
            Self::PerRayTable { .. } => "per-ray-table",
            Self::Unavailable => "unavailable",
        }
    }
}

/// One ray, converted: metres, unit direction, fluxes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point in metres (the file's millimetres × 10⁻³).
    pub position_m: DVec3,
    /// Unit direction (the file's direction normalised).
    pub direction: DVec3,
    /// Luminous flux (lm): the file's column or derived by [`RayFile::luminous_source`].
    pub luminous_lm: Option<f64>,
    /// Radiant flux (W) when the file has a radiant flux column.
    pub radiant_w: Option<f64>,
    /// Wavelength (nm): the ray's column, else the header's single wavelength.
    pub wavelength_nm: Option<f64>,
    /// 1-based spectral table index when the file has a spectrum-index column.
    pub spectrum_index: Option<usize>,
}

/// Column positions inside a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Columns {
    items: usize,
    radiant: Option<usize>,
    wavelength: Option<usize>,
    luminous: Option<usize>,
    spectrum_index: Option<usize>,
    additional: usize,
}

impl Columns {
    fn of(h: &Tm25Header) -> Self {
        let mut next = 6;
        let mut col = |present: bool| {
            present.then(|| {
                next += 1;
                next - 1
            })
        };
        let radiant = col(h.flags.radiant_flux);
        let wavelength = col(h.flags.wavelength);
        let luminous = col(h.flags.luminous_flux);
        let spectrum_index = col(h.flags.spectrum_index);
        Self {
            items: h.items_per_ray(),
            radiant,
            wavelength,
            luminous,
            spectrum_index,
            additional: next,
        }
    }
}

/// A TM-25 ray file in memory: header plus the raw `f32` records.
#[derive(Debug, Clone)]
pub struct RayFile {
    path: PathBuf,
    header: Tm25Header,
    columns: Columns,
    data: Vec<f32>,
    luminous: LuminousSource,
    warnings: Vec<String>,
}

/// Summary statistics of a ray file (`lumiview info`).
#[derive(Debug, Clone, PartialEq)]
pub struct RayStats {
    /// Number of rays.
    pub count: u64,
    /// Σ luminous flux of the rays (lm), when available.
    pub luminous_sum_lm: Option<f64>,
    /// Σ radiant flux column (W), when present.
    pub radiant_sum_w: Option<f64>,
    /// Smallest and largest per-ray flux of the weight used below.
    pub flux_range: (f64, f64),
    /// Which flux the direction statistics weigh by: "luminous", "radiant" or "count".
    pub weight: &'static str,
    /// Bounding box of the start points (m).
    pub bbox_min_m: DVec3,
    /// Bounding box of the start points (m).
    pub bbox_max_m: DVec3,
    /// Largest distance of a start point from the origin (m).
    pub max_radius_m: f64,
    /// Flux-weighted mean of the unit directions (its length: 1 = collimated, 0 = symmetric).
    pub mean_direction: DVec3,
    /// Share of the weight travelling upwards (kz > 0).
    pub upward_fraction: f64,
    /// Share of the weight per 10° band of the angle from +Z (index 0: 0–10°, ..., 17: 170–180°).
    pub polar_histogram: [f64; 18],
    /// Largest angle between a ray and the mean direction (degrees); 180 when the mean is zero.
    pub max_angle_from_mean_deg: f64,
    /// Largest |‖k‖ − 1| of the stored directions (they are normalised on use).
    pub max_direction_norm_error: f64,
    /// Smallest and largest wavelength of the rays (nm), when known.
    pub wavelength_range_nm: Option<(f64, f64)>,
}

/// Photopic luminous efficiency V(λ), CIE 1924 (2° observer), linearly interpolated in the CIE 5 nm
/// table; 0 outside 360–830 nm and for non-finite input.
pub fn photopic_efficiency(nm: f64) -> f64 {
    if !nm.is_finite() || !(360.0..=830.0).contains(&nm) {
        return 0.0;
    }
    let x = (nm - 360.0) / 5.0;
    let i = (x.floor() as usize).min(V_1924_5NM.len() - 2);
    let t = x - i as f64;
    V_1924_5NM[i] * (1.0 - t) + V_1924_5NM[i + 1] * t
}

/// CIE 1924 photopic V(λ), 360–830 nm in 5 nm steps (CIE 018:2019 / CVRL values).
#[rustfmt::skip]
const V_1924_5NM: [f64; 95] = [
    3.917e-6, 6.965e-6, 1.239e-5, 2.202e-5, 3.9e-5, 6.4e-5, 1.2e-4, 2.17e-4, 3.96e-4, 6.4e-4, // 360–405 nm
    1.21e-3, 2.18e-3, 4.0e-3, 7.3e-3, 1.16e-2, 1.684e-2, 2.3e-2, 2.98e-2, 3.8e-2, 4.8e-2, // 410–455 nm
    6.0e-2, 7.39e-2, 9.098e-2, 1.126e-1, 1.3902e-1, 1.693e-1, 2.0802e-1, 2.586e-1, 3.23e-1, 4.073e-1, // 460–505 nm
    5.03e-1, 6.082e-1, 7.1e-1, 7.932e-1, 8.62e-1, 9.148501e-1, 9.54e-1, 9.803e-1, 9.949501e-1, 1.0, // 510–555 nm
    9.95e-1, 9.786e-1, 9.52e-1, 9.154e-1, 8.7e-1, 8.163e-1, 7.57e-1, 6.949e-1, 6.31e-1, 5.668e-1, // 560–605 nm
    5.03e-1, 4.412e-1, 3.81e-1, 3.21e-1, 2.65e-1, 2.17e-1, 1.75e-1, 1.382e-1, 1.07e-1, 8.16e-2, // 610–655 nm
    6.1e-2, 4.458e-2, 3.2e-2, 2.32e-2, 1.7e-2, 1.192e-2, 8.21e-3, 5.723e-3, 4.102e-3, 2.929e-3, // 660–705 nm
    2.091e-3, 1.484e-3, 1.047e-3, 7.4e-4, 5.2e-4, 3.611e-4, 2.492e-4, 1.719e-4, 1.2e-4, 8.48e-5, // 710–755 nm
    6.0e-5, 4.24e-5, 3.0e-5, 2.12e-5, 1.499e-5, 1.06e-5, 7.4657e-6, 5.2578e-6, 3.7029e-6, 2.6078e-6, // 760–805 nm
    1.8366e-6, 1.2934e-6, 9.1093e-7, 6.4153e-7, 4.5181e-7, // 810–830 nm
];

/// Bytes from a slice or a file, read front to back, every length checked against the file size
/// before it is read or allocated.
struct Input<'a> {
    src: Src<'a>,
    len: u64,
    pos: u64,
    path: &'a Path,
}

enum Src<'a> {
    Bytes(&'a [u8]),
    File(BufReader<File>),
}

impl Input<'_> {
    fn remaining(&self) -> u64 {
        self.len.saturating_sub(self.pos)
    }

    fn ensure(&self, n: u64, what: &str) -> Result<()> {
        if n > self.remaining() {
            return Err(NearfieldError::format(
                self.path,
                format!(
                    "truncated in the {what}: it needs {n} bytes at offset {}, but the file ends after {} more \
                     (file size {} bytes)",
                    self.pos,
                    self.remaining(),
                    self.len
                ),
            ));
        }
        Ok(())
    }

    fn take(&mut self, n: u64, what: &str) -> Result<Vec<u8>> {
        self.ensure(n, what)?;
        let out = match &mut self.src {
            Src::Bytes(b) => {
                // In range: pos + n ≤ len = b.len().
                let (s, e) = (self.pos as usize, (self.pos + n) as usize);
                b.get(s..e).map(<[u8]>::to_vec).unwrap_or_default()
            }
            Src::File(r) => {
                let mut v = vec![0u8; n as usize];
                r.read_exact(&mut v).map_err(|e| NearfieldError::io(self.path, e))?;
                v
            }
        };
        self.pos += n;
        Ok(out)
    }

    /// `count` little-endian f32 (the caller has checked that they fit).
    fn take_f32s(&mut self, count: usize, what: &str) -> Result<Vec<f32>> {
        let bytes = (count as u64).saturating_mul(4);
        self.ensure(bytes, what)?;
        // As large as the file (gigabytes for 10⁸ rays): a failed allocation is an error, not an abort.
        let mut out =
            crate::files::try_vec(count, &format!("the {what}")).map_err(|e| NearfieldError::io(self.path, e))?;
        let conv = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        match &mut self.src {
            Src::Bytes(b) => {
                let (s, e) = (self.pos as usize, (self.pos + bytes) as usize);
                out.extend(b.get(s..e).unwrap_or_default().chunks_exact(4).map(conv));
            }
            Src::File(r) => {
                const CHUNK: usize = 1 << 20;
                let mut buf = vec![0u8; CHUNK];
                let mut left = bytes as usize;
                while left > 0 {
                    let n = left.min(CHUNK);
                    let chunk = &mut buf[..n];
                    r.read_exact(chunk).map_err(|e| NearfieldError::io(self.path, e))?;
                    out.extend(chunk.chunks_exact(4).map(conv));
                    left -= n;
                }
            }
        }
        self.pos += bytes;
        Ok(out)
    }
}

fn le_i32(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
fn le_f32(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// A NaN-for-unknown float as an option.
fn known(v: f32) -> Option<f64> {
    (!v.is_nan()).then_some(v as f64)
}

/// UTF-32LE up to the first NUL; invalid code points become U+FFFD (and a warning).
fn decode_utf32(bytes: &[u8], what: &str, warnings: &mut Vec<String>) -> String {
    let mut s = String::new();
    let mut bad = 0usize;
    for c in bytes.chunks_exact(4) {
        let u = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        if u == 0 {
            break;
        }
        match char::from_u32(u) {
            Some(ch) => s.push(ch),
            None => {
                bad += 1;
                s.push(char::REPLACEMENT_CHARACTER);
            }
        }
    }
    if bad > 0 {
        warnings.push(format!("{what}: {bad} invalid UTF-32 code unit(s) replaced by U+FFFD"));
    }
    s
}

fn encode_utf32(s: &str, bytes: usize, out: &mut Vec<u8>) {
    let start = out.len();
    for ch in s.chars().take(bytes / 4) {
        out.extend_from_slice(&(ch as u32).to_le_bytes());
    }
    out.resize(start + bytes, 0);
}

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
                        "the rays' {name} fluxes sum to {s:.6} {unit}, the header states {h} {unit}; ray values are used as they are"
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

    fn choose_luminous_source(&self) -> LuminousSource {
        let h = &self.header;
        if h.flags.luminous_flux {
            return LuminousSource::Column;
        }
        if let (Some(v), Some(e)) = (h.luminous_flux_lm, h.radiant_flux_w) {
            if v > 0.0 && e > 0.0 {
                return LuminousSource::HeaderRatio { lm_per_w: v / e };
            }
        }
        match h.spectral {
            SpectralKind::SingleWavelength => match h.single_wavelength_nm {
                Some(nm) => LuminousSource::SingleWavelength {
                    nm,
                    lm_per_w: K_M * photopic_efficiency(nm),
                },
                None => LuminousSource::Unavailable,
            },
            SpectralKind::PerRayWavelength => LuminousSource::PerRayWavelength,
            SpectralKind::Table => match h.spectral_tables.first().and_then(SpectralTable::luminous_efficacy) {
                Some(k) => LuminousSource::SpectralTable { lm_per_w: k },
                None => LuminousSource::Unavailable,
            },
            SpectralKind::PerRayTableIndex => LuminousSource::PerRayTable {
                lm_per_w: h
                    .spectral_tables
                    .iter()
                    .map(|t| t.luminous_efficacy().unwrap_or(0.0))
                    .collect(),
            },
            SpectralKind::None => LuminousSource::Unavailable,
        }
    }

    /// The file (or name) it was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }
    /// The header, description, flags and tables.
    pub fn header(&self) -> &Tm25Header {
        &self.header
    }
    /// Non-fatal findings (unusual header values, non-unit directions, ...).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
    /// How [`Ray::luminous_lm`] is obtained.
    pub fn luminous_source(&self) -> &LuminousSource {
        &self.luminous
    }
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.data.len() / self.columns.items.max(1)
    }
    /// Whether the file has no rays.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The raw `f32` record of ray `index` (file units and column order, see [`Tm25Header::column_names`]).
    pub fn record(&self, index: usize) -> Option<&[f32]> {
        let n = self.columns.items;
        self.data
            .get(index.checked_mul(n)?..index.checked_add(1)?.checked_mul(n)?)
    }
    /// Additional column `column` (0-based among the additional columns) of ray `index`.
    pub fn additional(&self, index: usize, column: usize) -> Option<f32> {
        if column >= self.header.additional_columns.len() {
            return None;
        }
        self.record(index)?.get(self.columns.additional + column).copied()
    }

    /// Ray `index`, converted (metres, unit direction, fluxes).
    pub fn ray(&self, index: usize) -> Option<Ray> {
        let r = self.record(index)?;
        let c = &self.columns;
        let get = |j: Option<usize>| j.and_then(|j| r.get(j)).map(|v| *v as f64);
        let position_m = DVec3::new(r[0] as f64, r[1] as f64, r[2] as f64) * 1e-3;
        let direction = DVec3::new(r[3] as f64, r[4] as f64, r[5] as f64).normalize_or_zero();
        let radiant_w = get(c.radiant);
        let spectrum_index = get(c.spectrum_index).map(|v| v as usize);
        let wavelength_nm = get(c.wavelength).or(match self.header.spectral {
            SpectralKind::SingleWavelength => self.header.single_wavelength_nm,
            _ => None,
        });
        let luminous_lm = match &self.luminous {
            LuminousSource::Column => get(c.luminous),
            LuminousSource::HeaderRatio { lm_per_w }
            | LuminousSource::SingleWavelength { lm_per_w, .. }
            | LuminousSource::SpectralTable { lm_per_w } => radiant_w.map(|w| w * lm_per_w),
            LuminousSource::PerRayWavelength => radiant_w
                .zip(wavelength_nm)
                .map(|(w, l)| w * K_M * photopic_efficiency(l)),
            LuminousSource::PerRayTable { lm_per_w } => radiant_w
                .zip(spectrum_index)
                .map(|(w, t)| w * t.checked_sub(1).and_then(|t| lm_per_w.get(t)).copied().unwrap_or(0.0)),
            LuminousSource::Unavailable => None,
        };
        Some(Ray {
            position_m,
            direction,
            luminous_lm,
            radiant_w,
            wavelength_nm,
            spectrum_index,
        })
    }

    /// All rays in file order.
    pub fn rays(&self) -> Rays<'_> {
        Rays {
            file: self,
            next: 0,
            end: self.len(),
        }
    }

    /// Sums, bounding box and direction distribution (one pass over the rays).
    pub fn stats(&self) -> RayStats {
        let has_lum = !matches!(self.luminous, LuminousSource::Unavailable);
        let has_rad = self.columns.radiant.is_some();
        let weight = if has_lum {
            "luminous"
        } else if has_rad {
            "radiant"
        } else {
            "count"
        };
        let (mut lum, mut rad, mut total) = (0.0, 0.0, 0.0);
        let mut flux_range = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut max_radius_m = 0.0f64;
        let mut mean = DVec3::ZERO;
        let mut up = 0.0;
        let mut hist = [0.0; 18];
        let mut max_norm_err = 0.0f64;
        let mut wl: Option<(f64, f64)> = None;
        for (i, r) in self.rays().enumerate() {
            let w = if has_lum {
                r.luminous_lm.unwrap_or(0.0)
            } else {
                r.radiant_w.unwrap_or(1.0)
            };
            lum += r.luminous_lm.unwrap_or(0.0);
            rad += r.radiant_w.unwrap_or(0.0);
            total += w;
            flux_range = (flux_range.0.min(w), flux_range.1.max(w));
            lo = lo.min(r.position_m);
            hi = hi.max(r.position_m);
            max_radius_m = max_radius_m.max(r.position_m.length());
            mean += w * r.direction;
            if r.direction.z > 0.0 {
                up += w;
            }
            let theta = r.direction.z.clamp(-1.0, 1.0).acos().to_degrees();
            hist[((theta / 10.0) as usize).min(17)] += w;
            if let Some(rec) = self.record(i) {
                let n = rec[3..6].iter().map(|v| (*v as f64).powi(2)).sum::<f64>().sqrt();
                max_norm_err = max_norm_err.max((n - 1.0).abs());
            }
            if let Some(l) = r.wavelength_nm {
                wl = Some(wl.map_or((l, l), |(a, b)| (a.min(l), b.max(l))));
            }
        }
        let n = self.len();
        if total > 0.0 {
            mean /= total;
            up /= total;
            for h in &mut hist {
                *h /= total;
            }
        }
        let m = mean.normalize_or_zero();
        let max_angle_from_mean_deg = if m == DVec3::ZERO {
            180.0
        } else {
            self.rays()
                .map(|r| r.direction.dot(m).clamp(-1.0, 1.0).acos().to_degrees())
                .fold(0.0, f64::max)
        };
        if n == 0 {
            lo = DVec3::ZERO;
            hi = DVec3::ZERO;
            flux_range = (0.0, 0.0);
        }
        RayStats {
            count: n as u64,
            luminous_sum_lm: has_lum.then_some(lum),
            radiant_sum_w: has_rad.then_some(rad),
            flux_range,
            weight,
            bbox_min_m: lo,
            bbox_max_m: hi,
            max_radius_m,
            mean_direction: mean,
            upward_fraction: up,
            polar_histogram: hist,
            max_angle_from_mean_deg,
            max_direction_norm_error: max_norm_err,
            wavelength_range_nm: wl,
        }
    }
}

/// Iterator over the rays of a [`RayFile`].
#[derive(Debug, Clone)]
pub struct Rays<'a> {
    file: &'a RayFile,
    next: usize,
    end: usize,
}

impl Iterator for Rays<'_> {
    type Item = Ray;
    fn next(&mut self) -> Option<Ray> {
        if self.next >= self.end {
            return None;
        }
        self.next += 1;
        self.file.ray(self.next - 1)
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.end - self.next;
        (n, Some(n))
    }
}

impl ExactSizeIterator for Rays<'_> {}

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

impl Default for Tm25Header {
    /// A simulated TM-25-13 file with a luminous flux column and nothing else.
    fn default() -> Self {
        Self {
            version: 2013,
            creation_method: CreationMethod::Simulated,
            luminous_flux_lm: None,
            radiant_flux_w: None,
            ray_count: 0,
            date: String::new(),
            ray_start_position: 0,
            spectral: SpectralKind::None,
            single_wavelength_nm: None,
            min_wavelength_nm: None,
            max_wavelength_nm: None,
            flags: Tm25Flags {
                luminous_flux: true,
                ..Tm25Flags::default()
            },
            description: Description::default(),
            spectral_tables: Vec::new(),
            additional_columns: Vec::new(),
            additional_text: String::new(),
            additional_text_bytes: 0,
            ray_data_offset: FIXED_BYTES,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_ray(h: &Tm25Header, extra: &[f32]) -> Vec<u8> {
        let mut r = vec![1.0, 2.0, 3.0, 0.0, 0.0, 2.0];
        r.extend_from_slice(extra);
        encode(h, &r).unwrap()
    }

    #[test]
    fn v_lambda_known_values() {
        assert_eq!(photopic_efficiency(555.0), 1.0);
        assert!((photopic_efficiency(500.0) - 0.323).abs() < 1e-12);
        assert!((photopic_efficiency(502.5) - 0.5 * (0.323 + 0.4073)).abs() < 1e-12);
        assert_eq!(photopic_efficiency(300.0), 0.0);
        assert_eq!(photopic_efficiency(f64::NAN), 0.0);
        assert!((photopic_efficiency(830.0) - 4.5181e-7).abs() < 1e-15);
    }

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

    #[test]
    fn header_ratio_wins_over_spectrum() {
        let h = Tm25Header {
            flags: Tm25Flags {
                radiant_flux: true,
                ..Tm25Flags::default()
            },
            luminous_flux_lm: Some(300.0),
            radiant_flux_w: Some(1.5),
            spectral: SpectralKind::SingleWavelength,
            single_wavelength_nm: Some(500.0),
            ..Tm25Header::default()
        };
        let f = RayFile::from_bytes(&one_ray(&h, &[2.0]), "t").unwrap();
        assert_eq!(f.luminous_source(), &LuminousSource::HeaderRatio { lm_per_w: 200.0 });
        assert!((f.ray(0).unwrap().luminous_lm.unwrap() - 400.0).abs() < 1e-9);
        let h = Tm25Header {
            luminous_flux_lm: None,
            ..h
        };
        let f = RayFile::from_bytes(&one_ray(&h, &[2.0]), "t").unwrap();
        let want = 2.0 * 683.0 * 0.323;
        assert!((f.ray(0).unwrap().luminous_lm.unwrap() - want).abs() < 1e-9);
        assert_eq!(f.ray(0).unwrap().wavelength_nm, Some(500.0));
    }

    #[test]
    fn per_ray_wavelength_and_table_index() {
        let h = Tm25Header {
            flags: Tm25Flags {
                radiant_flux: true,
                wavelength: true,
                ..Tm25Flags::default()
            },
            spectral: SpectralKind::PerRayWavelength,
            ..Tm25Header::default()
        };
        let f = RayFile::from_bytes(&one_ray(&h, &[1.0, 555.0]), "t").unwrap();
        assert!((f.ray(0).unwrap().luminous_lm.unwrap() - 683.0).abs() < 1e-9);
        let h = Tm25Header {
            flags: Tm25Flags {
                radiant_flux: true,
                spectrum_index: true,
                ..Tm25Flags::default()
            },
            spectral: SpectralKind::PerRayTableIndex,
            spectral_tables: vec![
                SpectralTable {
                    wavelengths_nm: vec![555.0],
                    weights: vec![1.0],
                },
                SpectralTable {
                    wavelengths_nm: vec![500.0],
                    weights: vec![1.0],
                },
            ],
            ..Tm25Header::default()
        };
        let f = RayFile::from_bytes(&one_ray(&h, &[1.0, 2.0]), "t").unwrap();
        assert_eq!(f.ray(0).unwrap().spectrum_index, Some(2));
        assert!((f.ray(0).unwrap().luminous_lm.unwrap() - 683.0 * 0.323).abs() < 1e-6);
        let e = RayFile::from_bytes(&one_ray(&h, &[1.0, 3.0]), "t").unwrap_err();
        assert!(e.to_string().contains("ray 0: spectrum index 3"), "{e}");
    }

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
