//! A TM-25 ray file in memory: the header plus the file's raw `f32` records (not a `Vec` of structs);
//! each [`Ray`] is converted on the fly (metres, unit direction, fluxes).

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::header::{SpectralKind, Tm25Header};
use super::spectral::{photopic_efficiency, LuminousSource, K_M};

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
pub(super) struct Columns {
    pub(super) items: usize,
    pub(super) radiant: Option<usize>,
    pub(super) wavelength: Option<usize>,
    pub(super) luminous: Option<usize>,
    pub(super) spectrum_index: Option<usize>,
    pub(super) additional: usize,
}

impl Columns {
    pub(super) fn of(h: &Tm25Header) -> Self {
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
    pub(super) path: PathBuf,
    pub(super) header: Tm25Header,
    pub(super) columns: Columns,
    pub(super) data: Vec<f32>,
    pub(super) luminous: LuminousSource,
    pub(super) warnings: Vec<String>,
}

impl RayFile {
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
