//! The photometric web: absolute luminous intensity (cd) over the whole sphere of directions in
//! lumiview's luminaire frame (docs/conventions.md): γ from nadir (−Z), C counter-clockwise from
//! +X seen from above. Built from a file's native grid by symmetry expansion (Type C) or by
//! resampling (Types A and B); bilinear between grid nodes, zero outside the measured γ range.

use super::error::{parse_error, ParseError};

/// Tolerance for angle comparisons, degrees.
pub(crate) const ANGLE_EPS: f64 = 1e-6;

/// Angular distance from a Type A/B pole within which the rotation angle is meaningless, degrees.
const POLE_EPS_DEG: f64 = 1e-6;

/// The largest intensity in cd a web accepts. No luminaire comes near it (a searchlight reaches
/// about 1e9 cd); anything above is a wrong multiplier or a corrupt file, and the bound keeps flux
/// integrals, luminances (≤ 1e27 cd/m² over the smallest area divided by) and f32 textures finite.
pub const MAX_INTENSITY_CD: f64 = 1e15;

/// The photometric coordinate system a file was measured in (IES field "photometric type").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum PhotometricType {
    /// Type A (automotive): polar axis vertical; H = V = 0 is photometric horizontal (C0,
    /// γ 90°), V = −90° nadir, H clockwise from above. See [`type_a_direction`].
    A,
    /// Type B (floodlights): polar axis horizontal along Y; V rotates about it (−90° nadir, 0
    /// horizontal along C0), H is the lateral angle, clockwise from above. See
    /// [`type_b_direction`].
    B,
    /// Type C: polar axis vertical; C planes about it, γ from nadir. lumiview's own frame.
    C,
}

/// The symmetry a file declares through its stored angle range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Symmetry {
    /// Every plane stored.
    None,
    /// One plane stored: the same in every C plane.
    Rotational,
    /// Symmetric about the C0–C180 plane (the XZ plane): C0…C180 stored.
    C0C180,
    /// Symmetric about the C90–C270 plane (the YZ plane): C90…C270 (IES) or C270…C90 (EULUMDAT)
    /// stored.
    C90C270,
    /// Symmetric about both planes: C0…C90 stored.
    Quadrant,
    /// Type A/B: symmetric about the vertical plane through the photometric axis (H ≥ 0 stored).
    Lateral,
    /// Type A/B: symmetric about both reference planes (H ≥ 0 and V ≥ 0 stored).
    LateralAndVertical,
    /// Type A/B: symmetric about the horizontal reference plane only (V ≥ 0 stored).
    Vertical,
}

/// Absolute luminous intensity on a complete C 0–360° grid and the measured γ range.
#[derive(Debug, Clone, PartialEq)]
pub struct PhotometricWeb {
    /// C angles in degrees, strictly increasing, first 0, last 360 (a copy of C0).
    c_deg: Vec<f64>,
    /// γ angles in degrees, strictly increasing, within 0…180. Outside [first, last] I = 0.
    gamma_deg: Vec<f64>,
    /// Intensities in cd, `cd[ic * gamma_deg.len() + ig]`.
    cd: Vec<f64>,
}

/// Direction (unit vector, luminaire frame) of the Type C angles, degrees.
///
/// ```
/// use lumiview::photometry::web::{angles_of, direction};
/// let d = direction(90.0, 90.0); // C90, horizontal: +Y
/// assert!((d[1] - 1.0).abs() < 1e-12);
/// let (c, g) = angles_of([0.0, 0.0, -1.0]); // nadir
/// assert_eq!((c, g), (0.0, 0.0));
/// ```
pub fn direction(c_deg: f64, gamma_deg: f64) -> [f64; 3] {
    let (c, g) = (c_deg.to_radians(), gamma_deg.to_radians());
    [g.sin() * c.cos(), g.sin() * c.sin(), -g.cos()]
}

/// Type C angles (degrees; C in 0…360, γ in 0…180) of a direction in the luminaire frame.
pub fn angles_of(d: [f64; 3]) -> (f64, f64) {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if len.is_nan() || len <= 0.0 {
        return (0.0, 0.0);
    }
    let gamma = (-d[2] / len).clamp(-1.0, 1.0).acos().to_degrees();
    let mut c = d[1].atan2(d[0]).to_degrees();
    if c < 0.0 {
        c += 360.0;
    }
    if c >= 360.0 {
        c -= 360.0;
    }
    (c, gamma)
}

// Types A and B (LM-63-2002 §3): the luminaire is measured aimed along photometric horizontal,
// H = V = 0, which lumiview puts at C0, γ = 90° (+X); V = −90° is nadir (−Z); horizontal angles run
// clockwise seen from above (towards −Y), where Type C runs counter-clockwise.

/// Native Type A angles (H, V) in degrees of a direction. Type A: polar axis vertical (Z); H is the
/// rotation about it, clockwise from +X seen from above; V the elevation (latitude) from the
/// horizontal plane, −90° at nadir. Equivalent to Type C with γ = V + 90°, C = −H.
pub fn type_a_angles(d: [f64; 3]) -> (f64, f64) {
    let v = d[2].clamp(-1.0, 1.0).asin().to_degrees();
    let h = (-d[1]).atan2(d[0]).to_degrees();
    (h, v)
}

/// Native Type B angles (H, V) in degrees of a direction. Type B: polar axis horizontal along Y
/// (the luminaire's lateral axis); V is the rotation about it, from +X (V = 0) towards +Z (V = 90°,
/// nadir at −90°); H the latitude from the XZ plane, positive towards −Y (clockwise from above).
pub fn type_b_angles(d: [f64; 3]) -> (f64, f64) {
    let h = (-d[1]).clamp(-1.0, 1.0).asin().to_degrees();
    let v = d[2].atan2(d[0]).to_degrees();
    (h, v)
}

/// Direction of native Type A angles (degrees): `(cos V cos H, −cos V sin H, sin V)`.
pub fn type_a_direction(h_deg: f64, v_deg: f64) -> [f64; 3] {
    let (h, v) = (h_deg.to_radians(), v_deg.to_radians());
    [v.cos() * h.cos(), -v.cos() * h.sin(), v.sin()]
}

/// Direction of native Type B angles (degrees): `(cos H cos V, −sin H, cos H sin V)`.
pub fn type_b_direction(h_deg: f64, v_deg: f64) -> [f64; 3] {
    let (h, v) = (h_deg.to_radians(), v_deg.to_radians());
    [h.cos() * v.cos(), -h.sin(), h.cos() * v.sin()]
}

/// A file's table as stored: `values[ih * v.len() + iv]` for horizontal angle `h[ih]` and
/// vertical angle `v[iv]` (the order of IES and EULUMDAT files), already in cd.
#[derive(Debug, Clone)]
pub struct NativeGrid<'a> {
    /// File name, for errors.
    pub file: &'a str,
    /// Horizontal angles (C planes, or Type A/B horizontal angles), degrees.
    pub h: &'a [f64],
    /// Vertical angles (γ, or Type A/B vertical angles), degrees.
    pub v: &'a [f64],
    /// Intensities in cd.
    pub values: &'a [f64],
}

/// Puts a file's angle list in increasing order when it is not: a list written in decreasing
/// order, or distinct angles out of order, happen in real files. Returns the permutation applied
/// (`new[k] = old[perm[k]]`) so the caller can reorder the rows that go with the angles, or `None`
/// when the list was already increasing or holds a repeated angle (which stays an error).
pub(crate) fn order_angles(angles: &mut [f64]) -> Option<Vec<usize>> {
    if angles.windows(2).all(|w| w[1] > w[0]) || angles.iter().any(|a| !a.is_finite()) {
        return None;
    }
    let mut perm: Vec<usize> = (0..angles.len()).collect();
    perm.sort_by(|&a, &b| angles[a].total_cmp(&angles[b]));
    let sorted: Vec<f64> = perm.iter().map(|&i| angles[i]).collect();
    if sorted.windows(2).any(|w| w[1] <= w[0]) {
        return None;
    }
    angles.copy_from_slice(&sorted);
    Some(perm)
}

fn check_increasing(file: &str, what: &str, a: &[f64]) -> Result<(), ParseError> {
    for w in a.windows(2) {
        if w[1] <= w[0] {
            return Err(parse_error(
                file,
                None,
                what,
                format!("angles must increase strictly, found {} then {}", w[0], w[1]),
            ));
        }
    }
    Ok(())
}

fn check_values(g: &NativeGrid<'_>) -> Result<(), ParseError> {
    if g.values.len() != g.h.len() * g.v.len() {
        return Err(parse_error(
            g.file,
            None,
            "candela values",
            format!(
                "expected {} × {} = {} values, found {}",
                g.h.len(),
                g.v.len(),
                g.h.len() * g.v.len(),
                g.values.len()
            ),
        ));
    }
    for (i, &x) in g.values.iter().enumerate() {
        if !(x.is_finite() && (0.0..=MAX_INTENSITY_CD).contains(&x)) {
            let (ih, iv) = (i / g.v.len(), i % g.v.len());
            let shown = if x.abs() < 1e9 {
                format!("{x}")
            } else {
                format!("{x:e}")
            };
            return Err(parse_error(
                g.file,
                None,
                "candela values",
                format!(
                    "intensity at horizontal {}°, vertical {}° is {shown} cd: expected a finite value from 0 to \
                     {MAX_INTENSITY_CD:e} cd (wrong multiplier?)",
                    g.h[ih], g.v[iv]
                ),
            ));
        }
    }
    Ok(())
}

impl PhotometricWeb {
    /// Builds a web from a Type C table, expanding the symmetry its horizontal range declares:
    /// one angle (rotational), 0–90 (quadrant), 0–180 (about C0–C180), 90–270 (about C90–C270),
    /// 0–360 with or without the 360° entry, or any start at 0 with last angle above 180.
    pub fn from_type_c(g: &NativeGrid<'_>) -> Result<(Self, Symmetry), ParseError> {
        check_values(g)?;
        check_increasing(g.file, "vertical angles", g.v)?;
        check_increasing(g.file, "horizontal angles", g.h)?;
        if g.v.len() < 2 {
            return Err(parse_error(
                g.file,
                None,
                "vertical angles",
                "at least 2 vertical angles are needed",
            ));
        }
        let (v0, v1) = (g.v[0], g.v[g.v.len() - 1]);
        if v0 < -ANGLE_EPS || v1 > 180.0 + ANGLE_EPS {
            return Err(parse_error(
                g.file,
                None,
                "vertical angles",
                format!("Type C vertical angles must lie within 0…180°, found {v0}…{v1}"),
            ));
        }
        let nv = g.v.len();
        let plane = |ih: usize| &g.values[ih * nv..(ih + 1) * nv];
        let near = |a: f64, b: f64| (a - b).abs() < ANGLE_EPS;
        let (h0, h1) = (g.h[0], g.h[g.h.len() - 1]);
        // Planes of the expanded web: (angle, source plane index).
        let mut planes: Vec<(f64, usize)> = Vec::new();
        let symmetry;
        if g.h.len() == 1 {
            symmetry = Symmetry::Rotational;
            planes.push((0.0, 0));
            planes.push((360.0, 0));
        } else if near(h0, 0.0) && near(h1, 90.0) {
            symmetry = Symmetry::Quadrant;
            let n = g.h.len();
            for (i, &h) in g.h.iter().enumerate() {
                planes.push((h, i));
            }
            for i in (0..n - 1).rev() {
                planes.push((180.0 - g.h[i], i));
            }
            for i in 1..n {
                planes.push((180.0 + g.h[i], i));
            }
            for i in (0..n - 1).rev() {
                planes.push((360.0 - g.h[i], i));
            }
        } else if near(h0, 0.0) && near(h1, 180.0) {
            symmetry = Symmetry::C0C180;
            let n = g.h.len();
            for (i, &h) in g.h.iter().enumerate() {
                planes.push((h, i));
            }
            for i in (0..n - 1).rev() {
                planes.push((360.0 - g.h[i], i));
            }
        } else if near(h0, 90.0) && near(h1, 270.0) {
            // Symmetric about the C90–C270 plane: I(C) = I(180° − C). The stored planes stay where
            // they are (a common reader shifts them by −90°, rotating the luminaire).
            symmetry = Symmetry::C90C270;
            let n = g.h.len();
            // C in [0, 90): mirror of 180 − C in (90, 180].
            for i in (0..n).rev() {
                let c = 180.0 - g.h[i];
                if (-ANGLE_EPS..90.0 - ANGLE_EPS).contains(&c) {
                    planes.push((c.max(0.0), i));
                }
            }
            for (i, &h) in g.h.iter().enumerate() {
                planes.push((h, i));
            }
            // C in (270, 360]: mirror of 180 − C + 360 = 540 − C, from stored C in [180, 270).
            for i in (0..n).rev() {
                let c = 540.0 - g.h[i];
                if c > 270.0 + ANGLE_EPS && c <= 360.0 + ANGLE_EPS {
                    planes.push((c.min(360.0), i));
                }
            }
        } else if near(h0, 0.0) && h1 > 180.0 + ANGLE_EPS && h1 <= 360.0 + ANGLE_EPS {
            symmetry = Symmetry::None;
            for (i, &h) in g.h.iter().enumerate() {
                planes.push((h, i));
            }
            if !near(h1, 360.0) {
                planes.push((360.0, 0));
            }
        } else {
            return Err(parse_error(
                g.file,
                None,
                "horizontal angles",
                format!(
                    "unsupported Type C horizontal range {h0}…{h1}: expected a single angle, 0–90, \
                     0–180, 90–270 or 0–360"
                ),
            ));
        }

        let mut c_deg = Vec::with_capacity(planes.len() + 2);
        let mut cd = Vec::with_capacity((planes.len() + 2) * nv);
        for &(c, src) in &planes {
            if let Some(&last) = c_deg.last() {
                if c <= last + ANGLE_EPS {
                    continue; // the mirror plane coincides with a stored one
                }
            }
            c_deg.push(c);
            cd.extend_from_slice(plane(src));
        }
        // A symmetric range whose mirrored planes miss 0° or 360° (e.g. 90–270 with a stored angle
        // set not symmetric about 180°): interpolate the missing ends across the wrap.
        if c_deg[0] > ANGLE_EPS || c_deg[c_deg.len() - 1] < 360.0 - ANGLE_EPS {
            let first_c = c_deg[0];
            let last_c = c_deg[c_deg.len() - 1];
            let span = first_c + 360.0 - last_c;
            let t = if span > 0.0 { (360.0 - last_c) / span } else { 0.0 };
            let n = c_deg.len();
            let edge: Vec<f64> = (0..nv)
                .map(|iv| cd[(n - 1) * nv + iv] * (1.0 - t) + cd[iv] * t)
                .collect();
            if first_c > ANGLE_EPS {
                c_deg.insert(0, 0.0);
                let mut new = edge.clone();
                new.extend_from_slice(&cd);
                cd = new;
            }
            if c_deg[c_deg.len() - 1] < 360.0 - ANGLE_EPS {
                c_deg.push(360.0);
                cd.extend_from_slice(&edge);
            }
        }
        // Exact end points.
        c_deg[0] = 0.0;
        let last = c_deg.len() - 1;
        c_deg[last] = 360.0;
        let web = PhotometricWeb {
            c_deg,
            gamma_deg: g.v.to_vec(),
            cd,
        };
        Ok((web, symmetry))
    }

    /// Builds a web from a Type A or B table by resampling it onto a regular C × γ grid with
    /// `step_deg` spacing (bilinear in the native angles; zero outside the native ranges).
    pub fn from_type_ab(
        g: &NativeGrid<'_>,
        kind: PhotometricType,
        step_deg: f64,
    ) -> Result<(Self, Symmetry), ParseError> {
        check_values(g)?;
        check_increasing(g.file, "vertical angles", g.v)?;
        check_increasing(g.file, "horizontal angles", g.h)?;
        if g.h.len() < 2 || g.v.len() < 2 {
            return Err(parse_error(
                g.file,
                None,
                "angles",
                format!("Type {kind:?} needs at least 2 horizontal and 2 vertical angles"),
            ));
        }
        let (h0, h1) = (g.h[0], g.h[g.h.len() - 1]);
        let (v0, v1) = (g.v[0], g.v[g.v.len() - 1]);
        // The latitude angle is limited to ±90°, the rotation angle to ±180°.
        let (lat_name, lat, rot_name, rot) = match kind {
            PhotometricType::A => ("vertical", (v0, v1), "horizontal", (h0, h1)),
            PhotometricType::B => ("horizontal", (h0, h1), "vertical", (v0, v1)),
            PhotometricType::C => {
                return Err(parse_error(
                    g.file,
                    None,
                    "photometric type",
                    "internal: Type C passed to the A/B path",
                ))
            }
        };
        if lat.0 < -90.0 - ANGLE_EPS || lat.1 > 90.0 + ANGLE_EPS {
            return Err(parse_error(
                g.file,
                None,
                format!("{lat_name} angles"),
                format!(
                    "Type {kind:?} {lat_name} angles must lie within −90…90°, found {}…{}",
                    lat.0, lat.1
                ),
            ));
        }
        if rot.0 < -180.0 - ANGLE_EPS || rot.1 > 180.0 + ANGLE_EPS {
            return Err(parse_error(
                g.file,
                None,
                format!("{rot_name} angles"),
                format!(
                    "Type {kind:?} {rot_name} angles must lie within −180…180°, found {}…{}",
                    rot.0, rot.1
                ),
            ));
        }
        let h_sym = h0.abs() < ANGLE_EPS && g.h.len() > 1;
        let v_sym = v0.abs() < ANGLE_EPS && g.v.len() > 1;
        let symmetry = match (h_sym, v_sym) {
            (true, true) => Symmetry::LateralAndVertical,
            (true, false) => Symmetry::Lateral,
            (false, true) => Symmetry::Vertical,
            (false, false) => Symmetry::None,
        };
        let nc = (360.0 / step_deg).round().max(4.0) as usize;
        let ng = (180.0 / step_deg).round().max(2.0) as usize;
        let c_deg: Vec<f64> = (0..=nc).map(|i| 360.0 * i as f64 / nc as f64).collect();
        let gamma_deg: Vec<f64> = (0..=ng).map(|i| 180.0 * i as f64 / ng as f64).collect();
        let mut cd = Vec::with_capacity(c_deg.len() * gamma_deg.len());
        for &c in &c_deg {
            for &gm in &gamma_deg {
                let d = direction(c, gm);
                let (mut h, mut v) = match kind {
                    PhotometricType::A => type_a_angles(d),
                    _ => type_b_angles(d),
                };
                if h_sym {
                    h = h.abs();
                }
                if v_sym {
                    v = v.abs();
                }
                // At a pole of the native system (latitude ±90°) every rotation angle names the
                // same direction: take one the file has.
                match kind {
                    PhotometricType::A if v.abs() > 90.0 - POLE_EPS_DEG => h = h.clamp(h0, h1),
                    PhotometricType::B if h.abs() > 90.0 - POLE_EPS_DEG => v = v.clamp(v0, v1),
                    _ => {}
                }
                cd.push(bilinear_native(g, h, v));
            }
        }
        Ok((PhotometricWeb { c_deg, gamma_deg, cd }, symmetry))
    }

    /// Builds a web directly from a complete grid (C 0…360 with the 360° copy, γ increasing within
    /// 0…180). Used by tests and by generators of synthetic distributions.
    pub fn from_grid(c_deg: Vec<f64>, gamma_deg: Vec<f64>, cd: Vec<f64>) -> Result<Self, ParseError> {
        let g = NativeGrid {
            file: "<grid>",
            h: &c_deg,
            v: &gamma_deg,
            values: &cd,
        };
        check_values(&g)?;
        check_increasing("<grid>", "C angles", &c_deg)?;
        check_increasing("<grid>", "γ angles", &gamma_deg)?;
        if c_deg.len() < 2 || c_deg[0].abs() > ANGLE_EPS || (c_deg[c_deg.len() - 1] - 360.0).abs() > ANGLE_EPS {
            return Err(parse_error("<grid>", None, "C angles", "must run from 0 to 360"));
        }
        if gamma_deg.len() < 2 || gamma_deg[0] < -ANGLE_EPS || gamma_deg[gamma_deg.len() - 1] > 180.0 + ANGLE_EPS {
            return Err(parse_error("<grid>", None, "γ angles", "need at least 2 within 0…180"));
        }
        let ng = gamma_deg.len();
        let last = (c_deg.len() - 1) * ng;
        if (0..ng).any(|j| (cd[j] - cd[last + j]).abs() > 1e-9 * cd[j].abs().max(cd[last + j].abs())) {
            return Err(parse_error(
                "<grid>",
                None,
                "C360 plane",
                "must equal the C0 plane (the same direction)",
            ));
        }
        Ok(PhotometricWeb { c_deg, gamma_deg, cd })
    }

    /// C angles of the grid, degrees (0 … 360 inclusive).
    pub fn c_angles(&self) -> &[f64] {
        &self.c_deg
    }

    /// γ angles of the grid, degrees; intensity is zero outside [first, last].
    pub fn gamma_angles(&self) -> &[f64] {
        &self.gamma_deg
    }

    /// Grid intensities in cd, `[ic * gamma_angles().len() + ig]`.
    pub fn values(&self) -> &[f64] {
        &self.cd
    }

    /// The measured γ range in degrees.
    pub fn gamma_range(&self) -> (f64, f64) {
        (self.gamma_deg[0], self.gamma_deg[self.gamma_deg.len() - 1])
    }

    /// Scales every intensity (e.g. by a TILT factor).
    pub(crate) fn scale(&mut self, k: f64) {
        for v in &mut self.cd {
            *v *= k;
        }
    }

    /// Luminous intensity in cd towards Type C angles (degrees): bilinear in (C, γ), C wraps around,
    /// zero outside the measured γ range.
    pub fn sample(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        if !c_deg.is_finite() || !gamma_deg.is_finite() {
            return 0.0;
        }
        let (g0, g1) = self.gamma_range();
        if gamma_deg < g0 - ANGLE_EPS || gamma_deg > g1 + ANGLE_EPS {
            return 0.0;
        }
        let c = c_deg.rem_euclid(360.0);
        let (ic, tc) = locate(&self.c_deg, c);
        let (ig, tg) = locate(&self.gamma_deg, gamma_deg.clamp(g0, g1));
        let ng = self.gamma_deg.len();
        let at = |i: usize, j: usize| self.cd[i * ng + j];
        let ic1 = (ic + 1).min(self.c_deg.len() - 1);
        let ig1 = (ig + 1).min(ng - 1);
        let a = at(ic, ig) * (1.0 - tg) + at(ic, ig1) * tg;
        let b = at(ic1, ig) * (1.0 - tg) + at(ic1, ig1) * tg;
        a * (1.0 - tc) + b * tc
    }

    /// Luminous intensity in cd towards a direction of the luminaire frame (need not be unit).
    pub fn sample_dir(&self, d: [f64; 3]) -> f64 {
        let (c, g) = angles_of(d);
        self.sample(c, g)
    }

    /// The largest intensity in cd and the (C, γ) where it occurs (degrees).
    pub fn max_intensity(&self) -> (f64, f64, f64) {
        let ng = self.gamma_deg.len();
        let mut best = (0.0, 0.0, 0.0);
        for (i, &v) in self.cd.iter().enumerate() {
            if v > best.0 {
                best = (v, self.c_deg[i / ng], self.gamma_deg[i % ng]);
            }
        }
        best
    }

    /// Luminous flux in lm: the exact integral of the bilinear intensity over the sphere,
    /// Φ = ∫∫ I(C, γ) sin γ dγ dC (closed-form weights per grid cell).
    pub fn flux(&self) -> f64 {
        self.flux_between(0.0, 180.0)
    }

    /// Luminous flux in lm emitted into γ ∈ [from, to] (degrees), e.g. (0, 90) for the downward
    /// flux.
    pub fn flux_between(&self, from_deg: f64, to_deg: f64) -> f64 {
        let ng = self.gamma_deg.len();
        let mut total = 0.0;
        for ic in 0..self.c_deg.len() - 1 {
            let dc = (self.c_deg[ic + 1] - self.c_deg[ic]).to_radians();
            for ig in 0..ng - 1 {
                let (a, b) = (self.gamma_deg[ig], self.gamma_deg[ig + 1]);
                let (lo, hi) = (a.max(from_deg), b.min(to_deg));
                if hi <= lo {
                    continue;
                }
                // I linear in γ along each plane: I = Ia (b−γ)/h + Ib (γ−a)/h over [lo, hi].
                let h = (b - a).to_radians();
                if h <= 0.0 {
                    continue; // a gap too small for radians (subnormal): no solid angle
                }
                let (int_sin, int_lin) = cell_integrals(a, lo, hi);
                let wb = int_lin / h;
                let wa = int_sin - wb;
                let i_a = 0.5 * (self.cd[ic * ng + ig] + self.cd[(ic + 1) * ng + ig]);
                let i_b = 0.5 * (self.cd[ic * ng + ig + 1] + self.cd[(ic + 1) * ng + ig + 1]);
                total += dc * (i_a * wa + i_b * wb);
            }
        }
        total
    }
}

/// ∫ sin γ dγ and ∫ (γ − a) sin γ dγ (γ in radians) over [lo, hi], given in degrees with
/// a ≤ lo < hi ≤ 180, in a form without cancellation: with m = (lo + hi)/2 and d = (hi − lo)/2,
/// ∫ sin γ = 2 sin m sin d and ∫ (γ − lo) sin γ = 2 cos m (sin d − d cos d) + 2 d sin m sin d.
/// Differences are taken in degrees before converting, so a narrow cell keeps its width's digits.
/// The textbook antiderivative differences lose every digit for cells narrower than ~1e-6°, which
/// made the flux of a fine γ grid negative (or NaN for a subnormal step).
fn cell_integrals(a_deg: f64, lo_deg: f64, hi_deg: f64) -> (f64, f64) {
    let m = (0.5 * (lo_deg + hi_deg)).to_radians();
    let d = (0.5 * (hi_deg - lo_deg)).to_radians();
    let (sin_d, cos_d) = d.sin_cos();
    let (sin_m, cos_m) = m.sin_cos();
    // sin d − d cos d = d³/3 − d⁵/30 + d⁷/840 − d⁹/45360 + …, by its series where it cancels.
    let d2 = d * d;
    let s = if d < 0.05 {
        d * d2 * (1.0 / 3.0 - d2 * (1.0 / 30.0 - d2 * (1.0 / 840.0 - d2 / 45360.0)))
    } else {
        sin_d - d * cos_d
    };
    let int_sin = 2.0 * sin_m * sin_d;
    let from_lo = 2.0 * cos_m * s + 2.0 * d * sin_m * sin_d;
    (int_sin, (lo_deg - a_deg).to_radians() * int_sin + from_lo)
}

/// Index `i` and fraction `t` with `a[i] ≤ x ≤ a[i+1]` (clamped at the ends).
fn locate(a: &[f64], x: f64) -> (usize, f64) {
    let n = a.len();
    if n < 2 || x <= a[0] {
        return (0, 0.0);
    }
    if x >= a[n - 1] {
        return (n - 1, 0.0);
    }
    let i = a.partition_point(|&v| v <= x) - 1;
    let t = (x - a[i]) / (a[i + 1] - a[i]);
    (i, t)
}

/// Bilinear lookup in a native table; zero outside its ranges.
fn bilinear_native(g: &NativeGrid<'_>, h: f64, v: f64) -> f64 {
    let inside = |a: &[f64], x: f64| x >= a[0] - ANGLE_EPS && x <= a[a.len() - 1] + ANGLE_EPS;
    if !inside(g.h, h) || !inside(g.v, v) {
        return 0.0;
    }
    let nv = g.v.len();
    let (ih, th) = locate(g.h, h.clamp(g.h[0], g.h[g.h.len() - 1]));
    let (iv, tv) = locate(g.v, v.clamp(g.v[0], g.v[nv - 1]));
    let ih1 = (ih + 1).min(g.h.len() - 1);
    let iv1 = (iv + 1).min(nv - 1);
    let at = |i: usize, j: usize| g.values[i * nv + j];
    let a = at(ih, iv) * (1.0 - tv) + at(ih, iv1) * tv;
    let b = at(ih1, iv) * (1.0 - tv) + at(ih1, iv1) * tv;
    a * (1.0 - th) + b * th
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn grid<'a>(h: &'a [f64], v: &'a [f64], values: &'a [f64]) -> NativeGrid<'a> {
        NativeGrid {
            file: "t",
            h,
            v,
            values,
        }
    }

    #[test]
    fn isotropic_flux_is_4pi() {
        let v: Vec<f64> = (0..=18).map(|i| i as f64 * 10.0).collect();
        let vals = vec![100.0; v.len()];
        let (w, s) = PhotometricWeb::from_type_c(&grid(&[0.0], &v, &vals)).unwrap();
        assert_eq!(s, Symmetry::Rotational);
        assert!((w.flux() - 400.0 * PI).abs() < 1e-9, "{}", w.flux());
        assert!((w.flux_between(0.0, 90.0) - 200.0 * PI).abs() < 1e-9);
    }

    #[test]
    fn lambertian_flux_is_pi_i0() {
        // I = I0 cos γ in the lower hemisphere, sampled every 5°: the bilinear integral is close
        // to π I0 (linear interpolation of a concave function underestimates slightly).
        let v: Vec<f64> = (0..=18).map(|i| i as f64 * 5.0).collect();
        let vals: Vec<f64> = v.iter().map(|g| 1000.0 * g.to_radians().cos()).collect();
        let (w, _) = PhotometricWeb::from_type_c(&grid(&[0.0], &v, &vals)).unwrap();
        let rel = (w.flux() - 1000.0 * PI) / (1000.0 * PI);
        assert!(rel.abs() < 2e-3, "{rel}");
    }

    #[test]
    fn zero_outside_measured_gamma() {
        let v = [0.0, 45.0, 90.0];
        let vals = [10.0, 10.0, 10.0];
        let (w, _) = PhotometricWeb::from_type_c(&grid(&[0.0], &v, &vals)).unwrap();
        assert_eq!(w.sample(0.0, 90.0), 10.0);
        assert_eq!(w.sample(0.0, 90.5), 0.0);
        assert_eq!(w.sample(123.0, 180.0), 0.0);
    }

    #[test]
    fn flux_of_a_fine_gamma_step_is_exact_and_never_negative() {
        // All light in one cell 1e-9° wide at γ = 60°: the old antiderivative difference gave a
        // flux of random sign here, and NaN for a subnormal step.
        let v = [60.0, 60.0 + 1e-9];
        let (w, _) = PhotometricWeb::from_type_c(&grid(&[0.0], &v, &[0.0, 1000.0])).unwrap();
        let h = (v[1] - v[0]).to_radians(); // 1e-9° as stored next to 60
        let exact = 2.0 * PI * 1000.0 * (h / 2.0) * 60f64.to_radians().sin();
        assert!(
            w.flux() >= 0.0 && ((w.flux() - exact) / exact).abs() < 1e-6,
            "{} vs {exact}",
            w.flux()
        );
        let v = [0.0, 5e-324, 90.0];
        let (w, _) = PhotometricWeb::from_type_c(&grid(&[0.0], &v, &[1.0, 1.0, 1.0])).unwrap();
        assert!(
            w.flux().is_finite() && (w.flux() - 2.0 * PI).abs() < 1e-9,
            "{}",
            w.flux()
        );
    }

    #[test]
    fn absurd_intensity_is_an_error() {
        let v = [0.0, 90.0];
        let e = PhotometricWeb::from_type_c(&grid(&[0.0], &v, &[1.0, 1e300])).unwrap_err();
        assert!(e.message.contains("wrong multiplier"), "{e}");
        let (w, _) = PhotometricWeb::from_type_c(&grid(&[0.0], &v, &[1.0, MAX_INTENSITY_CD])).unwrap();
        assert!(w.flux().is_finite());
    }

    #[test]
    fn type_b_axes() {
        let d = type_b_direction(0.0, 0.0);
        assert!((d[0] - 1.0).abs() < 1e-12, "photometric horizontal is C0");
        let d = type_b_direction(0.0, -90.0);
        assert!((d[2] + 1.0).abs() < 1e-12, "V = −90° is nadir");
        let d = type_b_direction(90.0, 0.0);
        assert!((d[1] + 1.0).abs() < 1e-12, "H runs clockwise from above: +90° is C270");
        let d = type_a_direction(90.0, 0.0);
        assert!((d[1] + 1.0).abs() < 1e-12);
        let d = type_a_direction(0.0, -90.0);
        assert!((d[2] + 1.0).abs() < 1e-12);
        let (h, v) = type_b_angles(type_b_direction(30.0, -50.0));
        assert!((h - 30.0).abs() < 1e-9 && (v + 50.0).abs() < 1e-9);
        let (h, v) = type_a_angles(type_a_direction(-70.0, 20.0));
        assert!((h + 70.0).abs() < 1e-9 && (v - 20.0).abs() < 1e-9);
    }
}
