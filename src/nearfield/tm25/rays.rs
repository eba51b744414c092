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

/// What a ray file's flux values mean in absolute terms.
///
/// TM-25 gives the set's total flux in the header (Φv in lm, Φe in W) beside each ray's flux. The
/// tools that write ray sets treat the rays' values as relative weights and the header's total as
/// the source's flux (LightTools' and OpticStudio's ray-file headers carry "the total flux of this
/// source", which the reference TM-25 tools map to and from the TM-25 header); a ray set resampled
/// or cut keeps its header total in step. Files in the wild differ: the measured OSRAM LED's rays
/// sum to its header's 337 lm, a LightTools cylinder's 10,000 rays of ~1 lm each sit under a
/// header of 1 lm, and a point source written by the TM-25 tools carries rays of 0.1–1 W under a
/// header of 1 W.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RayFlux {
    /// The header's total, where it states one and the rays' sum differs from it by more than
    /// 1 %: the rays are scaled to it, with a warning naming both. Otherwise the rays' values.
    #[default]
    Header,
    /// The rays' own values, whatever the header says.
    Rays,
}

/// The factor that brings a ray set's fluxes to its header's total ([`RayFile::header_scale`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeaderScale {
    /// Multiply every ray's flux by this.
    pub factor: f64,
    /// The rays' sum, in `unit`.
    pub rays_sum: f64,
    /// The header's total, in `unit`.
    pub header_total: f64,
    /// "lm" (the header's Φv against the rays' luminous fluxes) or "W" (Φe against the radiant).
    pub unit: &'static str,
}

impl HeaderScale {
    /// A sentence for a warning: what the file holds and what was done.
    pub fn describe(&self, path: &Path) -> String {
        format!(
            "{}: the rays' fluxes sum to {:.6} {u}, the header states {} {u}: the rays are scaled by {:.6e} to the \
             header's total (TM-25 ray fluxes are relative where the header gives the total: docs/formats.md, \
             \"Absolute flux\"; `rays2scan --ray-flux rays` keeps the rays' values)",
            path.display(),
            self.rays_sum,
            self.header_total,
            self.factor,
            u = self.unit
        )
    }
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

    /// The factor that brings the rays' luminous fluxes to the total the header states, where it
    /// states one (Φv > 0 compared with the rays' luminous fluxes; else Φe > 0 with their radiant
    /// column) and the rays' sum differs from it by more than 1 %. `None` otherwise: no total in
    /// the header, no ray with flux, or sums within 1 % (the rays' values then stand).
    pub fn header_scale(&self) -> Option<HeaderScale> {
        let ok = |v: Option<f64>| v.filter(|x| x.is_finite() && *x > 0.0);
        let (sum, header, unit) = if let Some(h) = ok(self.header.luminous_flux_lm) {
            let s: f64 = (0..self.len())
                .filter_map(|i| self.ray(i)?.luminous_lm)
                .filter(|f| f.is_finite() && *f > 0.0)
                .sum();
            (s, h, "lm")
        } else if let (Some(h), Some(_)) = (ok(self.header.radiant_flux_w), self.columns.radiant) {
            let s: f64 = (0..self.len())
                .filter_map(|i| self.ray(i)?.radiant_w)
                .filter(|f| f.is_finite() && *f > 0.0)
                .sum();
            (s, h, "W")
        } else {
            return None;
        };
        if sum <= 0.0 || sum.is_nan() || (sum - header).abs() <= 0.01 * header.max(sum) {
            return None;
        }
        Some(HeaderScale {
            factor: header / sum,
            rays_sum: sum,
            header_total: header,
            unit,
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
