//! Spectral data and luminous flux: the CIE 1924 photopic V(λ), spectral tables and their luminous
//! efficacy, and the rule that gives each ray its luminous flux ([`LuminousSource`]), chosen once per
//! file.

use super::header::SpectralKind;
use super::rays::RayFile;

/// Maximum luminous efficacy of radiation for photopic vision (lm/W).
pub const K_M: f64 = 683.0;

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

impl RayFile {
    pub(super) fn choose_luminous_source(&self) -> LuminousSource {
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
}

#[cfg(test)]
mod tests {
    use super::super::header::{SpectralKind, Tm25Flags, Tm25Header};
    use super::super::writer::one_ray;
    use super::*;

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
}
