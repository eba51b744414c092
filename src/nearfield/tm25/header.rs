//! The TM-25 header model: everything in a file before the ray records (the 256-byte header, the
//! known-data flags, the description block, the spectral tables, the column labels and the additional
//! text), and the ray record layout that follows from it.

use super::spectral::SpectralTable;
use super::FIXED_BYTES;

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
    pub(super) fn from_i32(v: i32) -> Self {
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
    pub(super) fn from_i32(v: i32) -> Option<Self> {
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

    pub(super) fn fields_mut(&mut self) -> [&mut String; 9] {
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
