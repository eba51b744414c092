//! What a photometric report states about a luminaire, computed from its absolute web: the peak at
//! the angle the file stores, beam and field angles per principal plane, zonal lumens, downward and
//! upward light output ratios, the CIE flux code, and warnings for files that parse but are
//! implausible.
//!
//! Definitions (docs/photometry.md, "Summary figures"):
//! - **Beam / field angle** (IES): in a plane through the nadir, the angle between the two
//!   directions on either side of the plane's maximum where the intensity has fallen to 50 % (beam)
//!   or 10 % (field) of that maximum. Along a C plane the bilinear web is piecewise linear in γ, so
//!   the crossings are found exactly between the γ nodes.
//! - **Zonal lumens**: the flux in γ bands, integrated exactly for the bilinear web
//!   ([`PhotometricWeb::flux_between`]).
//! - **CIE flux code** (CIE 52): N1, N2, N3 = the flux in the cones of solid angle π/2, π and 3π/2
//!   about the nadir (half angles 41.41°, 60°, 75.52°) as per cent of the downward flux; N4 = the
//!   downward share of the luminaire's flux (DLOR/LOR), N5 = LOR, in per cent, as manufacturers'
//!   data sheets print it (a fully downward luminaire with LOR 64 % reads "… 100 64"). For absolute
//!   photometry the luminaire's own flux stands in for the lamp flux (LOR = 100 %).

use super::luminaire::{Photometry, RawFile};
use super::web::{PhotometricType, PhotometricWeb, ANGLE_EPS};

/// Relative tolerance within which two intensities count as the same peak.
const PEAK_TIE: f64 = 1e-9;

/// Largest difference accepted between integrated and declared luminaire flux before a warning.
pub const FLUX_MISMATCH_WARN: f64 = 0.05;

/// The largest intensity and where the file stores it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Peak {
    /// Intensity, cd.
    pub cd: f64,
    /// C angle, degrees, within the C range the file stores.
    pub c_deg: f64,
    /// γ angle, degrees.
    pub gamma_deg: f64,
}

/// Beam and field angle in one principal plane (IES definition, see the module docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PlaneSpread {
    /// The plane, e.g. `C0–C180`.
    pub plane: String,
    /// C angle of the plane's half drawn with positive angles (0 or 90).
    pub c_deg: f64,
    /// The plane's maximum intensity, cd.
    pub max_cd: f64,
    /// Where that maximum lies, as a signed angle from the nadir, degrees: positive towards
    /// `c_deg`, negative towards `c_deg + 180`.
    pub max_at_deg: f64,
    /// Beam angle (50 %), degrees; `None` when the intensity never falls to 50 % on one side.
    pub beam_deg: Option<f64>,
    /// The two 50 % directions (signed angles from the nadir, degrees).
    pub beam_edges_deg: Option<[f64; 2]>,
    /// Field angle (10 %), degrees; `None` when the intensity never falls to 10 % on one side.
    pub field_deg: Option<f64>,
    /// The two 10 % directions (signed angles from the nadir, degrees).
    pub field_edges_deg: Option<[f64; 2]>,
}

/// Flux in one γ band.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Zone {
    /// Lower γ, degrees.
    pub from_deg: f64,
    /// Upper γ, degrees.
    pub to_deg: f64,
    /// Flux, lm.
    pub flux_lm: f64,
    /// Per cent of the rated lamp flux (`None` for absolute photometry).
    pub percent_lamp: Option<f64>,
    /// Per cent of the luminaire's integrated flux.
    pub percent_luminaire: f64,
}

/// The CIE flux code (CIE 52), unrounded values in per cent.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CieFluxCode {
    /// Flux within 41.41° of the nadir (solid angle π/2), % of the downward flux.
    pub n1: f64,
    /// Within 60° (π), % of the downward flux.
    pub n2: f64,
    /// Within 75.52° (3π/2), % of the downward flux.
    pub n3: f64,
    /// Downward share of the luminaire's flux (DLOR / LOR), %.
    pub n4: f64,
    /// Light output ratio, %.
    pub n5: f64,
    /// True when N5 refers to the luminaire's own flux (absolute photometry: LOR 100 %).
    pub per_luminaire_flux: bool,
}

impl CieFluxCode {
    /// The code as written in reports: five whole numbers, e.g. `44 75 94 100 100`.
    pub fn text(&self) -> String {
        format!(
            "{:.0} {:.0} {:.0} {:.0} {:.0}",
            self.n1, self.n2, self.n3, self.n4, self.n5
        )
    }
}

/// The summary figures of a luminaire.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// The peak, at the angle the file stores.
    pub peak: Peak,
    /// Beam and field angles in the C0–C180 and C90–C270 planes.
    pub spreads: Vec<PlaneSpread>,
    /// Flux in the bands 0–30, 30–40, 40–60, 60–90 and 90–180°.
    pub zones: Vec<Zone>,
    /// Flux in the cumulative zones 0–30, 0–40, 0–60, 0–90, 90–180 and 0–180°.
    pub cumulative_zones: Vec<Zone>,
    /// Integrated luminous flux, lm.
    pub flux_lm: f64,
    /// Downward flux (γ 0–90°), lm.
    pub downward_flux_lm: f64,
    /// Upward flux (γ 90–180°), lm.
    pub upward_flux_lm: f64,
    /// Downward flux fraction (downward / total), in 0…1.
    pub downward_fraction: f64,
    /// Downward light output ratio (downward flux / rated lamp flux); `None` for absolute
    /// photometry.
    pub dlor: Option<f64>,
    /// Upward light output ratio; `None` for absolute photometry.
    pub ulor: Option<f64>,
    /// The CIE flux code; `None` when there is no downward flux.
    pub cie_flux_code: Option<CieFluxCode>,
}

/// Half angle in degrees of the cone about the nadir with solid angle `k`·π/2 (k = 1, 2, 3).
pub fn cie_cone_deg(k: u32) -> f64 {
    (1.0 - f64::from(k) / 4.0).acos().to_degrees()
}

impl Photometry {
    /// The C angles (degrees) the file stores for a Type C file, in the luminaire frame; `None` for
    /// Type A and B files (their web is resampled, every C is computed).
    pub fn stored_c_angles(&self) -> Option<Vec<f64>> {
        if self.photometric_type != PhotometricType::C {
            return None;
        }
        Some(match &self.raw {
            RawFile::Ies(f) => f.horizontal_deg.iter().map(|c| c.rem_euclid(360.0)).collect(),
            RawFile::Ldt(f) => f.stored_planes().iter().map(|&i| f.c_deg[i]).collect(),
        })
    }

    /// The largest intensity and its direction, reported at a C angle the file stores (a file
    /// symmetric about C0–C180 that stores C0…C180 has its peak reported there, not at the mirror
    /// image). Ties go to the smallest stored C, then the smallest γ.
    pub fn peak(&self) -> Peak {
        let web = &self.web;
        let (max_cd, c_any, g_any) = web.max_intensity();
        let Some(stored) = self.stored_c_angles() else {
            return Peak {
                cd: max_cd,
                c_deg: c_any,
                gamma_deg: g_any,
            };
        };
        let mut best: Option<Peak> = None;
        let mut cs = stored;
        cs.sort_by(f64::total_cmp);
        for &c in &cs {
            for &g in web.gamma_angles() {
                let v = web.sample(c, g);
                let better = match best {
                    None => true,
                    Some(b) => v > b.cd * (1.0 + PEAK_TIE) + f64::MIN_POSITIVE,
                };
                if better {
                    best = Some(Peak {
                        cd: v,
                        c_deg: c,
                        gamma_deg: g,
                    });
                }
            }
        }
        match best {
            // The stored planes hold every value of the web (the rest are mirror copies); a
            // stored maximum below the web's would be a symmetry bug, so fall back to the web.
            Some(b) if b.cd >= max_cd * (1.0 - PEAK_TIE) => b,
            _ => Peak {
                cd: max_cd,
                c_deg: c_any,
                gamma_deg: g_any,
            },
        }
    }

    /// Beam and field angles, zonal lumens, light output ratios and the CIE flux code.
    pub fn summary(&self) -> Summary {
        let web = &self.web;
        let flux = web.flux();
        let down = web.flux_between(0.0, 90.0);
        let up = web.flux_between(90.0, 180.0);
        let lamp = self.lamp_flux_lm.filter(|f| *f > 0.0);
        let zone = |a: f64, b: f64| {
            let f = web.flux_between(a, b);
            Zone {
                from_deg: a,
                to_deg: b,
                flux_lm: f,
                percent_lamp: lamp.map(|l| 100.0 * f / l),
                percent_luminaire: if flux > 0.0 { 100.0 * f / flux } else { 0.0 },
            }
        };
        let zones = [(0.0, 30.0), (30.0, 40.0), (40.0, 60.0), (60.0, 90.0), (90.0, 180.0)]
            .iter()
            .map(|&(a, b)| zone(a, b))
            .collect();
        let cumulative_zones = [
            (0.0, 30.0),
            (0.0, 40.0),
            (0.0, 60.0),
            (0.0, 90.0),
            (90.0, 180.0),
            (0.0, 180.0),
        ]
        .iter()
        .map(|&(a, b)| zone(a, b))
        .collect();
        let cie_flux_code = (down > 0.0).then(|| {
            let basis = lamp.unwrap_or(flux);
            CieFluxCode {
                n1: 100.0 * web.flux_between(0.0, cie_cone_deg(1)) / down,
                n2: 100.0 * web.flux_between(0.0, cie_cone_deg(2)) / down,
                n3: 100.0 * web.flux_between(0.0, cie_cone_deg(3)) / down,
                n4: 100.0 * down / flux,
                n5: 100.0 * flux / basis,
                per_luminaire_flux: lamp.is_none(),
            }
        });
        Summary {
            peak: self.peak(),
            spreads: vec![plane_spread(web, 0.0), plane_spread(web, 90.0)],
            zones,
            cumulative_zones,
            flux_lm: flux,
            downward_flux_lm: down,
            upward_flux_lm: up,
            downward_fraction: if flux > 0.0 { down / flux } else { 0.0 },
            dlor: lamp.map(|l| down / l),
            ulor: lamp.map(|l| up / l),
            cie_flux_code,
        }
    }
}

/// Beam and field angle in the plane through C = `c_deg` and C = `c_deg` + 180.
///
/// The plane is a full circle of directions: signed angle s from the nadir, s ≥ 0 towards `c_deg`
/// (γ = s), s < 0 towards `c_deg` + 180 (γ = −s); s = ±180 is the zenith. From the plane's maximum
/// the walk goes both ways round the circle (through the zenith when it must: an uplight) to the
/// first direction below the threshold.
pub fn plane_spread(web: &PhotometricWeb, c_deg: f64) -> PlaneSpread {
    let (g0, g1) = web.gamma_range();
    // Samples at every γ node, plus a zero just outside the measured range, where the intensity
    // drops to zero; the plane is piecewise linear between them.
    let mut gammas: Vec<f64> = web.gamma_angles().to_vec();
    let just = 2.0 * ANGLE_EPS; // outside the measured range by more than `sample`'s tolerance
    if g1 < 180.0 - just {
        gammas.push(g1 + just);
    }
    if g0 > just {
        gammas.insert(0, g0 - just);
    }
    if gammas[0] > 0.0 {
        gammas.insert(0, 0.0);
    }
    if gammas[gammas.len() - 1] < 180.0 {
        gammas.push(180.0);
    }
    let c_back = c_deg + 180.0;
    // The circle from the zenith on the back half (s just above −180) through the nadir to the
    // zenith on the front half (s = 180); the zenith appears once.
    let mut pts: Vec<(f64, f64)> = Vec::with_capacity(2 * gammas.len());
    for &g in gammas.iter().rev() {
        if g > 0.0 && g < 180.0 {
            pts.push((-g, web.sample(c_back, g)));
        }
    }
    for &g in &gammas {
        pts.push((g, web.sample(c_deg, g)));
    }
    let n = pts.len();
    // The maximum; among equal values the one nearest the nadir.
    let mut imax = 0;
    for (i, &(s, v)) in pts.iter().enumerate() {
        let (sm, vm) = pts[imax];
        if v > vm * (1.0 + PEAK_TIE) + f64::MIN_POSITIVE || (v >= vm * (1.0 - PEAK_TIE) && s.abs() < sm.abs()) {
            imax = i;
        }
    }
    let max_cd = pts[imax].1;
    // Angle of point `i` unwrapped relative to the start, walking `dir` (±1) steps round the circle.
    let step_angle = |from: usize, dir: isize| -> f64 {
        let to = (from as isize + dir).rem_euclid(n as isize) as usize;
        let d = pts[to].0 - pts[from].0;
        // Crossing the zenith: from s = 180 to s just above −180 (or back) is a small step.
        if dir > 0 && d < 0.0 {
            d + 360.0
        } else if dir < 0 && d > 0.0 {
            d - 360.0
        } else {
            d
        }
    };
    let edge = |fraction: f64, dir: isize| -> Option<f64> {
        let thr = fraction * max_cd;
        let (mut i, mut angle) = (imax, pts[imax].0);
        for _ in 0..n {
            let j = (i as isize + dir).rem_euclid(n as isize) as usize;
            let step = step_angle(i, dir);
            if pts[j].1 < thr {
                let t = (pts[i].1 - thr) / (pts[i].1 - pts[j].1);
                return Some(angle + step * t);
            }
            angle += step;
            i = j;
            if (angle - pts[imax].0).abs() >= 360.0 {
                return None;
            }
        }
        None
    };
    let edges = |fraction: f64| -> Option<[f64; 2]> {
        if max_cd <= 0.0 {
            return None;
        }
        let right = edge(fraction, 1)?;
        let left = edge(fraction, -1)?;
        (right - left < 360.0).then_some([left, right])
    };
    let wrap = |a: f64| {
        let w = (a + 180.0).rem_euclid(360.0) - 180.0;
        if w <= -180.0 {
            180.0
        } else {
            w
        }
    };
    let beam = edges(0.5);
    let field = edges(0.1);
    let name = if c_deg == 0.0 { "C0–C180" } else { "C90–C270" };
    PlaneSpread {
        plane: name.to_string(),
        c_deg,
        max_cd,
        max_at_deg: pts[imax].0,
        beam_deg: beam.map(|[a, b]| b - a),
        beam_edges_deg: beam.map(|[a, b]| [wrap(a), wrap(b)]),
        field_deg: field.map(|[a, b]| b - a),
        field_edges_deg: field.map(|[a, b]| [wrap(a), wrap(b)]),
    }
}

/// Warnings for a file that parses but is implausible: a light output ratio above 100 %
/// (declared or integrated), a declared luminaire flux more than 5 % from the integrated one, no
/// light at all or a peak below [`MIN_PLAUSIBLE_PEAK_CD`]. Each names the file.
pub fn plausibility_warnings(p: &Photometry) -> Vec<String> {
    let mut w = Vec::new();
    let flux = p.flux_lm();
    let name = &p.source;
    if let Some(lor) = p.declared_lor.filter(|l| *l > 1.0 + 1e-9) {
        w.push(format!(
            "{name}: declared light output ratio {:.1} % is above 100 % (a luminaire cannot emit more than its lamps)",
            lor * 100.0
        ));
    }
    if let Some(lor) = p.integrated_lor().filter(|l| *l > 1.005) {
        w.push(format!(
            "{name}: the intensities integrate to {:.1} lm, {:.1} % of the rated lamp flux {:.1} lm (above 100 %: wrong \
             lamp flux or multiplier?)",
            flux,
            lor * 100.0,
            p.lamp_flux_lm.unwrap_or(0.0)
        ));
    }
    if let Some(declared) = p.declared_luminaire_flux_lm.filter(|f| *f > 0.0) {
        let rel = (flux - declared) / declared;
        if rel.abs() > FLUX_MISMATCH_WARN {
            w.push(format!(
                "{name}: the intensities integrate to {flux:.1} lm but the file declares {declared:.1} lm of luminaire \
                 flux ({:+.1} %)",
                rel * 100.0
            ));
        }
    }
    let peak_cd = p.web.max_intensity().0;
    // A peak of 5e-324 cd integrates to 0 lm: that file is implausible, not dark.
    if peak_cd <= 0.0 {
        w.push(format!("{name}: every intensity is zero: the file emits no light"));
    } else if peak_cd < MIN_PLAUSIBLE_PEAK_CD {
        w.push(format!(
            "{name}: the peak intensity {peak_cd:e} cd is implausibly small (below {MIN_PLAUSIBLE_PEAK_CD:e} cd: wrong \
             multiplier or units?); renders and tables will show no light"
        ));
    }
    w
}

/// Below this peak intensity a file is implausible (a millicandela indicator LED is 10⁻³ cd; the
/// renderer's 32-bit floats cannot hold luminances from much smaller values).
pub const MIN_PLAUSIBLE_PEAK_CD: f64 = 1e-6;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cie_cones() {
        assert!((cie_cone_deg(1) - 41.4096).abs() < 1e-4);
        assert!((cie_cone_deg(2) - 60.0).abs() < 1e-9);
        assert!((cie_cone_deg(3) - 75.5225).abs() < 1e-4);
    }

    #[test]
    fn spread_of_a_step_distribution() {
        // 100 cd up to γ 40°, 0 from 50°: the 50 % crossing lies halfway, at 45°.
        let g: Vec<f64> = (0..=18).map(|i| f64::from(i) * 10.0).collect();
        let v: Vec<f64> = g.iter().map(|&x| if x <= 40.0 { 100.0 } else { 0.0 }).collect();
        let cd: Vec<f64> = v.iter().chain(&v).copied().collect();
        let web = PhotometricWeb::from_grid(vec![0.0, 360.0], g, cd).unwrap();
        let s = plane_spread(&web, 0.0);
        assert!((s.beam_deg.unwrap() - 90.0).abs() < 1e-9, "{s:?}");
        assert!((s.field_deg.unwrap() - 98.0).abs() < 1e-9, "{s:?}");
        assert_eq!(s.max_at_deg, 0.0);
    }

    #[test]
    fn an_uplight_spreads_through_the_zenith() {
        // 100 cd within 40° of the zenith, 0 from 50°: the beam is 90° wide about s = ±180.
        let g: Vec<f64> = (0..=18).map(|i| f64::from(i) * 10.0).collect();
        let v: Vec<f64> = g.iter().map(|&x| if x >= 140.0 { 100.0 } else { 0.0 }).collect();
        let cd: Vec<f64> = v.iter().chain(&v).copied().collect();
        let web = PhotometricWeb::from_grid(vec![0.0, 360.0], g, cd).unwrap();
        let s = plane_spread(&web, 90.0);
        assert!((s.beam_deg.unwrap() - 90.0).abs() < 1e-9, "{s:?}");
        assert!((s.field_deg.unwrap() - 98.0).abs() < 1e-9, "{s:?}");
        let [a, b] = s.beam_edges_deg.unwrap();
        assert!(
            (a.abs() - 135.0).abs() < 1e-9 && (b.abs() - 135.0).abs() < 1e-9,
            "{a} {b}"
        );
    }
}
