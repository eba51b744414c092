//! IES LM-63-2019 ↔ EULUMDAT conversion, written from lumiview's model of a file
//! ([`Photometry`]): the absolute web, its declared symmetry, the luminous opening and housing by
//! axis, lamp data and labels.
//!
//! What is kept:
//! - **Intensities**, absolute: every node of the web in the stored range of the declared symmetry,
//!   with seven significant digits (well inside 0.1 % of the peak). C planes stay where they are:
//!   no rotation.
//! - **Symmetry**: IES one angle / 0–90 / 0–180 / 90–270 / 0–360 ↔ EULUMDAT Isym 1 / 4 / 2 / 3 / 0.
//! - **Dimensions by axis** (docs/adr/0002): the IES length (X) is the EULUMDAT width, the IES width
//!   (Y) the EULUMDAT length. EULUMDAT side heights that IES cannot express (unequal, or a housing)
//!   go into two IES user keywords, `[_LUMIVIEW_SIDE_HEIGHTS_M]` and `[_LUMIVIEW_HOUSING_M]`, which
//!   lumiview reads back; other readers see the nearest standard opening.
//! - **Lamp data and labels** where the target has a field for them.
//!
//! What cannot be kept is listed in [`Converted::lost`], one line per item, for the caller to show.

use super::error::PhotometryError;
use super::ies::TiltSource;
use super::luminaire::{FileFormat, Photometry, RawFile};
use super::opening::{LuminousOpening, OpeningShape};
use super::web::{PhotometricType, Symmetry, ANGLE_EPS};

/// IES user keyword holding the four side heights in metres (faces seen from C0, C90, C180, C270).
pub const SIDE_HEIGHTS_KEYWORD: &str = "_LUMIVIEW_SIDE_HEIGHTS_M";

/// IES user keyword holding the housing's extents along X, Y and Z in metres.
pub const HOUSING_KEYWORD: &str = "_LUMIVIEW_HOUSING_M";

/// A converted file.
#[derive(Debug, Clone, PartialEq)]
pub struct Converted {
    /// The file's text (CRLF line ends, as both formats' producers write them).
    pub text: String,
    /// What the target format could not keep, one finding per line.
    pub lost: Vec<String>,
}

/// Rounds to `digits` significant digits (Rust's `Display` of the result never uses an exponent).
fn sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return 0.0;
    }
    let p = digits - 1 - v.abs().log10().floor() as i32;
    if p > 300 {
        return v;
    }
    let k = 10f64.powi(p);
    let r = (v * k).round() / k;
    if r.is_finite() {
        r
    } else {
        v
    }
}

/// A number as written: seven significant digits, no exponent, no trailing zeros.
fn num(v: f64) -> String {
    let r = sig(v, 7);
    if r == 0.0 {
        "0".to_string()
    } else {
        format!("{r}")
    }
}

/// The C angles the target stores for a symmetry, taken from the web's grid (degrees).
fn stored_c(p: &Photometry, sym: Symmetry) -> Vec<f64> {
    let all = p.web.c_angles();
    let within = |lo: f64, hi: f64| -> Vec<f64> {
        all.iter()
            .copied()
            .filter(|&c| c >= lo - ANGLE_EPS && c <= hi + ANGLE_EPS)
            .collect()
    };
    match sym {
        Symmetry::Rotational => vec![0.0],
        Symmetry::Quadrant => within(0.0, 90.0),
        Symmetry::C0C180 => within(0.0, 180.0),
        Symmetry::C90C270 => within(90.0, 270.0),
        _ => within(0.0, 360.0),
    }
}

/// The symmetry to write: the file's own for Type C files whose stored range the web's grid
/// contains; otherwise every plane.
fn target_symmetry(p: &Photometry, lost: &mut Vec<String>) -> Symmetry {
    if p.photometric_type != PhotometricType::C {
        lost.push(format!(
            "{:?} photometry is written as Type C (C 0–360°), resampled as lumiview reads it",
            p.photometric_type
        ));
        return Symmetry::None;
    }
    let sym = p.symmetry;
    let ok = match sym {
        Symmetry::Rotational => true,
        Symmetry::Quadrant => has(p, 0.0) && has(p, 90.0),
        Symmetry::C0C180 => has(p, 0.0) && has(p, 180.0),
        Symmetry::C90C270 => has(p, 90.0) && has(p, 270.0),
        Symmetry::None => true,
        _ => false,
    };
    if ok {
        sym
    } else {
        Symmetry::None
    }
}

fn has(p: &Photometry, c: f64) -> bool {
    p.web.c_angles().iter().any(|&x| (x - c).abs() < ANGLE_EPS)
}

/// Evenly spaced within 1e-6°: the step, else `None`.
fn even_step(a: &[f64]) -> Option<f64> {
    let step = a.get(1)? - a.first()?;
    a.windows(2)
        .all(|w| ((w[1] - w[0]) - step).abs() < 1e-6)
        .then_some(step)
}

/// The first non-empty value of a label, keyword or EULUMDAT header field.
fn label<'a>(p: &'a Photometry, keys: &[&str]) -> Option<&'a str> {
    keys.iter().find_map(|k| {
        p.labels
            .iter()
            .find(|(key, v)| key.eq_ignore_ascii_case(k) && !v.trim().is_empty())
            .map(|(_, v)| v.trim())
    })
}

/// One line of a text field: line breaks become " / ", CR/LF never leak into the file.
fn one_line(s: &str, max_chars: usize) -> String {
    let t: String = s.replace(['\r', '\n'], " / ");
    t.chars().take(max_chars).collect()
}

// ---------------------------------------------------------------------------------------------
// To IES LM-63-2019

/// The IES luminous dimensions (width, length, height) in metres for an opening, the side heights
/// keyword when IES cannot express them, and what was lost.
fn ies_dimensions(o: &LuminousOpening, lost: &mut Vec<String>) -> ([f64; 3], Option<[f64; 4]>) {
    let (x, y, h) = (o.size_x_m, o.size_y_m, o.height_m);
    let sides = o.side_heights_m;
    let equal = sides.iter().all(|s| (s - sides[0]).abs() < 1e-12);
    // One height for four faces: the one that keeps their total area (each face spans the other
    // axis: the C0/C180 faces Y, the C90/C270 faces X).
    let perimeter = 2.0 * (x + y);
    let mean = if perimeter > 0.0 {
        ((sides[0] + sides[2]) * y + (sides[1] + sides[3]) * x) / perimeter
    } else {
        sides.iter().sum::<f64>() / 4.0
    };
    match o.shape {
        OpeningShape::Point => ([0.0; 3], None),
        OpeningShape::Rectangle => ([y, x, 0.0], None),
        OpeningShape::Box => ([y, x, h], None),
        OpeningShape::Ellipse => ([-y, -x, 0.0], None),
        OpeningShape::VerticalCylinder => ([-y, -x, h], None),
        OpeningShape::Ellipsoid => ([-y, -x, -h], None),
        OpeningShape::HorizontalCylinderAlongLength => ([-y, x, -h], None),
        OpeningShape::HorizontalCylinderAlongWidth => ([y, -x, -h], None),
        OpeningShape::VerticalEllipseFacingC0 => ([-y, 0.0, -h], None),
        OpeningShape::VerticalEllipseFacingC90 => ([0.0, -x, -h], None),
        OpeningShape::RectangleWithSides | OpeningShape::DiscWithSides => {
            let round = o.shape == OpeningShape::DiscWithSides;
            let s = if round { -1.0 } else { 1.0 };
            if equal {
                ([s * y, s * x, sides[0]], None)
            } else {
                lost.push(format!(
                    "unequal side heights (C0 {} m, C90 {} m, C180 {} m, C270 {} m): IES has one height; written \
                     as {} m (the height of equal total side area), the four heights kept in \
                     [{SIDE_HEIGHTS_KEYWORD}] for lumiview",
                    sides[0],
                    sides[1],
                    sides[2],
                    sides[3],
                    num(mean)
                ));
                ([s * y, s * x, mean], Some(sides))
            }
        }
    }
}

/// Writes `p` as an IES LM-63-2019 file.
///
/// # Errors
/// None today; the `Result` leaves room for files a later version cannot express.
pub fn to_ies(p: &Photometry) -> Result<Converted, PhotometryError> {
    let mut lost = Vec::new();
    let sym = target_symmetry(p, &mut lost);
    let h = stored_c(p, sym);
    let v: Vec<f64> = p.web.gamma_angles().to_vec();
    let (g0, g1) = p.web.gamma_range();
    if !((g0.abs() < ANGLE_EPS || (g0 - 90.0).abs() < ANGLE_EPS)
        && ((g1 - 90.0).abs() < ANGLE_EPS || (g1 - 180.0).abs() < ANGLE_EPS))
    {
        lost.push(format!(
            "vertical angles {g0}–{g1}°: LM-63 expects 0 or 90 first and 90 or 180 last; written as measured"
        ));
    }
    let mut out: Vec<String> = vec!["IES:LM-63-2019".to_string()];
    let kw = |k: &str, v: &str| format!("[{k}] {}", one_line(v, 240));
    let src_name = std::path::Path::new(&p.source)
        .file_name()
        .map_or(p.source.clone(), |n| n.to_string_lossy().into_owned());
    let test = label(p, &["TEST", "report"]).unwrap_or("unknown");
    out.push(kw("TEST", test));
    out.push(kw("TESTLAB", label(p, &["TESTLAB", "company"]).unwrap_or("unknown")));
    out.push(kw(
        "ISSUEDATE",
        label(p, &["ISSUEDATE", "date/user"]).unwrap_or("unknown"),
    ));
    out.push(kw("MANUFAC", label(p, &["MANUFAC", "company"]).unwrap_or("unknown")));
    for (ies_key, keys) in [
        ("LUMCAT", &["LUMCAT", "luminaire number"][..]),
        ("LUMINAIRE", &["LUMINAIRE", "luminaire name"][..]),
        ("LAMPCAT", &["LAMPCAT"][..]),
        ("LAMP", &["LAMP", "lamp type"][..]),
        ("BALLAST", &["BALLAST"][..]),
        ("BALLASTCAT", &["BALLASTCAT"][..]),
        ("TESTDATE", &["TESTDATE"][..]),
        ("DISTRIBUTION", &["DISTRIBUTION"][..]),
        ("OTHER", &["OTHER"][..]),
        ("SEARCH", &["SEARCH"][..]),
    ] {
        if let Some(v) = label(p, keys) {
            out.push(kw(ies_key, v));
        }
    }
    if let RawFile::Ldt(f) = &p.raw {
        let set = f.lamp_sets.get(p.lamp_set_index);
        if let Some(s) = set {
            if !s.colour.trim().is_empty() {
                out.push(kw("_COLOUR", &s.colour));
            }
            if !s.cri.trim().is_empty() {
                out.push(kw("_CRI", &s.cri));
            }
        }
        if f.lamp_sets.len() > 1 {
            lost.push(format!(
                "{} EULUMDAT lamp sets: IES holds one; the set in use is written",
                f.lamp_sets.len()
            ));
        }
        if f.direct_ratios.iter().any(|r| *r != 0.0) {
            lost.push("EULUMDAT direct ratios (utilisation by room index) have no IES field".into());
        }
        if f.measurement_tilt_deg != 0.0 {
            lost.push(format!(
                "tilt of the luminaire during measurement ({}°) has no IES field",
                f.measurement_tilt_deg
            ));
        }
    }
    if let RawFile::Ies(f) = &p.raw {
        let written = [
            "TEST",
            "TESTLAB",
            "ISSUEDATE",
            "MANUFAC",
            "LUMCAT",
            "LUMINAIRE",
            "LAMPCAT",
            "LAMP",
            "BALLAST",
            "BALLASTCAT",
            "TESTDATE",
            "DISTRIBUTION",
            "OTHER",
            "SEARCH",
        ];
        let dropped: Vec<String> = f
            .keywords
            .iter()
            .filter(|(k, _)| !written.iter().any(|w| w.eq_ignore_ascii_case(k)))
            .map(|(k, _)| format!("[{k}]"))
            .collect();
        if !dropped.is_empty() {
            lost.push(format!("keywords not carried over: {}", dropped.join(", ")));
        }
        if !f.labels.is_empty() {
            lost.push(format!("{} free label line(s) of the 1986/1991 header", f.labels.len()));
        }
    }
    out.push(kw("FILEGENINFO", &format!("converted by lumiview from {src_name}")));
    let (dims, sides) = ies_dimensions(&p.opening, &mut lost);
    if let Some(s) = sides {
        out.push(format!(
            "[{SIDE_HEIGHTS_KEYWORD}] {} {} {} {}",
            num(s[0]),
            num(s[1]),
            num(s[2]),
            num(s[3])
        ));
    }
    if let Some([x, y, z]) = p.luminaire_size_m {
        out.push(format!("[{HOUSING_KEYWORD}] {} {} {}", num(x), num(y), num(z)));
        lost.push(format!(
            "luminaire (housing) size {x} × {y} × {z} m has no IES field: kept in [{HOUSING_KEYWORD}] for lumiview"
        ));
    }
    // TILT: a table not yet applied is kept; an applied tilt is already in the intensities.
    match (&p.tilt, p.tilt_applied_deg) {
        (Some(t), None) => {
            out.push("TILT=INCLUDE".to_string());
            out.push(format!("{}", t.lamp_to_luminaire_geometry));
            out.push(format!("{}", t.angles_deg.len()));
            out.push(t.angles_deg.iter().map(|a| num(*a)).collect::<Vec<_>>().join(" "));
            out.push(t.factors.iter().map(|a| num(*a)).collect::<Vec<_>>().join(" "));
            if matches!(t.source, TiltSource::File(_)) {
                lost.push("TILT=<file>: the tilt table is written into the file (TILT=INCLUDE)".into());
            }
        }
        (Some(_), Some(a)) => {
            out.push("TILT=NONE".to_string());
            lost.push(format!(
                "the TILT factor at {a}° is applied to the intensities; the tilt table is not written"
            ));
        }
        (None, _) => out.push("TILT=NONE".to_string()),
    }
    // Line 10 and 11. Values are absolute candela with multiplier 1; relative photometry keeps its
    // rated lamp flux as lamps × lumens per lamp.
    let (lamps, lumens) = match p.lamp_flux_lm {
        Some(f) if p.lamp_count > 0.0 => (p.lamp_count, f / p.lamp_count),
        Some(f) => (1.0, f),
        None => (p.lamp_count.abs().max(1.0), -1.0),
    };
    out.push(format!(
        "{} {} 1 {} {} 1 2 {} {} {}",
        num(lamps),
        num(lumens),
        v.len(),
        h.len(),
        num(dims[0]),
        num(dims[1]),
        num(dims[2])
    ));
    // Ballast factor 1 (already in the candela); file generation type 1.00001: undefined, since
    // lumiview cannot know how the source was made.
    out.push(format!("1 1.00001 {}", num(p.input_watts.unwrap_or(0.0))));
    for chunk in v.chunks(10) {
        out.push(chunk.iter().map(|a| num(*a)).collect::<Vec<_>>().join(" "));
    }
    for chunk in h.chunks(10) {
        out.push(chunk.iter().map(|a| num(*a)).collect::<Vec<_>>().join(" "));
    }
    for &c in &h {
        let row: Vec<String> = v.iter().map(|&g| num(p.web.sample(c, g))).collect();
        for chunk in row.chunks(10) {
            out.push(chunk.join(" "));
        }
    }
    Ok(Converted {
        text: out.join("\r\n") + "\r\n",
        lost,
    })
}

// ---------------------------------------------------------------------------------------------
// To EULUMDAT

/// EULUMDAT luminous area (length a1 along Y, width b1 along X, 0 = round) and side heights in
/// metres for an opening, and what was lost.
fn ldt_area(o: &LuminousOpening, lost: &mut Vec<String>) -> ([f64; 2], [f64; 4]) {
    let (x, y, h) = (o.size_x_m, o.size_y_m, o.height_m);
    let q = std::f64::consts::FRAC_PI_4;
    let round = (x - y).abs() <= 1e-9 * x.max(y);
    let equal_area = |what: &str| {
        let k = q.sqrt();
        format!(
            "{what} {x} × {y} m: EULUMDAT has rectangles and discs; written as the rectangle of equal area {} × {} m",
            num(x * k),
            num(y * k)
        )
    };
    match o.shape {
        OpeningShape::Point => ([0.0, 0.0], [0.0; 4]),
        OpeningShape::Rectangle => ([y, x], [0.0; 4]),
        OpeningShape::Box => ([y, x], [h; 4]),
        OpeningShape::RectangleWithSides => ([y, x], o.side_heights_m),
        OpeningShape::DiscWithSides => ([x, 0.0], o.side_heights_m),
        OpeningShape::Ellipse | OpeningShape::VerticalCylinder => {
            let sides = if o.shape == OpeningShape::VerticalCylinder {
                [h; 4]
            } else {
                [0.0; 4]
            };
            if round {
                ([x, 0.0], sides)
            } else {
                lost.push(equal_area("an elliptic opening"));
                let k = q.sqrt();
                ([y * k, x * k], sides)
            }
        }
        OpeningShape::Ellipsoid => {
            lost.push(format!(
                "an ellipsoid {x} × {y} × {h} m: written as a {} of the same extents with luminous sides {h} m high",
                if round { "disc" } else { "rectangle" }
            ));
            if round {
                ([x, 0.0], [h; 4])
            } else {
                ([y, x], [h; 4])
            }
        }
        OpeningShape::HorizontalCylinderAlongLength => {
            lost.push(format!(
                "a horizontal cylinder along X ({x} m, diameter {y} m): written as a {x} × {y} m rectangle, sides seen \
                 from C90/C270 {h} m, its round ends as C0/C180 sides of equal area"
            ));
            ([y, x], [h * q, h, h * q, h])
        }
        OpeningShape::HorizontalCylinderAlongWidth => {
            lost.push(format!(
                "a horizontal cylinder along Y ({y} m, diameter {x} m): written as a {x} × {y} m rectangle, sides seen \
                 from C0/C180 {h} m, its round ends as C90/C270 sides of equal area"
            ));
            ([y, x], [h, h * q, h, h * q])
        }
        OpeningShape::VerticalEllipseFacingC0 => {
            lost.push(format!(
                "a vertical ellipse facing C0 ({y} × {h} m): written as a 1 mm wide area with C0/C180 sides of equal \
                 area"
            ));
            ([y, 0.001], [h * q, 0.0, h * q, 0.0])
        }
        OpeningShape::VerticalEllipseFacingC90 => {
            lost.push(format!(
                "a vertical ellipse facing C90 ({x} × {h} m): written as a 1 mm long area with C90/C270 sides of equal \
                 area"
            ));
            ([0.001, x], [0.0, h * q, 0.0, h * q])
        }
    }
}

/// Writes `p` as an EULUMDAT file; `file_name` goes into its file-name field.
///
/// # Errors
/// [`PhotometryError::InvalidArgument`] naming the file when it emits no light (EULUMDAT stores
/// cd per 1000 lm of a positive flux).
pub fn to_ldt(p: &Photometry, file_name: &str) -> Result<Converted, PhotometryError> {
    let mut lost = Vec::new();
    let mut sym = target_symmetry(p, &mut lost);
    let flux = p.flux_lm();
    // The set's flux: the rated lamp flux, or for absolute photometry the luminaire's own flux
    // with a negative lamp count (the DIAL/Relux convention).
    let (count, set_flux) = match p.lamp_flux_lm {
        Some(f) => (p.lamp_count.max(1.0), f),
        None => (-(p.lamp_count.abs().max(1.0)), flux),
    };
    if !(set_flux > 0.0 && set_flux.is_finite()) {
        return Err(PhotometryError::InvalidArgument {
            name: "file",
            message: format!(
                "{}: no positive flux ({set_flux} lm) to express the intensities in cd/klm, as EULUMDAT needs",
                p.source
            ),
        });
    }
    if count.fract() != 0.0 {
        lost.push(format!(
            "{count} lamps: EULUMDAT counts whole lamps; written as {}",
            count.round()
        ));
    }
    let k = 1000.0 / set_flux;
    // Every plane of the full circle (the web's grid without 360), and the stored ones.
    let mut c_all: Vec<f64> = p.web.c_angles().to_vec();
    c_all.pop();
    let mc_ok = |m: usize| match sym {
        Symmetry::C0C180 => m.is_multiple_of(2) && c_all.get(m / 2).is_some_and(|c| (c - 180.0).abs() < ANGLE_EPS),
        Symmetry::C90C270 | Symmetry::Quadrant => {
            m.is_multiple_of(4)
                && c_all.get(m / 4).is_some_and(|c| (c - 90.0).abs() < ANGLE_EPS)
                && c_all.get(3 * m / 4).is_some_and(|c| (c - 270.0).abs() < ANGLE_EPS)
        }
        _ => true,
    };
    if sym != Symmetry::Rotational && !mc_ok(c_all.len()) {
        lost.push(format!(
            "the C planes are not laid out as EULUMDAT's symmetry {sym:?} needs (C90/C180/C270 at a quarter/half of \
             Mc): every plane is written (Isym 0)"
        ));
        sym = Symmetry::None;
    }
    let (isym, c_list, stored): (u8, Vec<f64>, Vec<f64>) = match sym {
        Symmetry::Rotational => (1, vec![0.0], vec![0.0]),
        Symmetry::C0C180 => (2, c_all.clone(), stored_c(p, sym)),
        Symmetry::C90C270 => {
            // Stored from C270 through C0 to C90.
            let m = c_all.len();
            let order: Vec<f64> = c_all[3 * m / 4..].iter().chain(&c_all[..=m / 4]).copied().collect();
            (3, c_all.clone(), order)
        }
        Symmetry::Quadrant => (4, c_all.clone(), stored_c(p, sym)),
        _ => (0, c_all.clone(), c_all.clone()),
    };
    let gammas: Vec<f64> = p.web.gamma_angles().to_vec();
    if gammas[0] > ANGLE_EPS {
        lost.push(format!(
            "γ starts at {}°: written as measured, though some EULUMDAT readers expect γ from 0°",
            gammas[0]
        ));
    }
    let dc = if c_list.len() > 1 {
        even_step(&c_list).unwrap_or_else(|| {
            lost.push("C planes are not evenly spaced: Dc written as 0, every angle listed".into());
            0.0
        })
    } else {
        0.0
    };
    let dg = even_step(&gammas).unwrap_or_else(|| {
        lost.push("γ angles are not evenly spaced: Dg written as 0, every angle listed".into());
        0.0
    });
    let ldt = match &p.raw {
        RawFile::Ldt(f) => Some(f.as_ref()),
        RawFile::Ies(_) => None,
    };
    let set = ldt.and_then(|f| f.lamp_sets.get(p.lamp_set_index));
    let mm = |m: f64| num(m * 1000.0);
    let mut l: Vec<String> = Vec::new();
    l.push(one_line(label(p, &["company", "MANUFAC"]).unwrap_or("lumiview"), 78));
    // Ityp: kept from an EULUMDAT source; otherwise 1 (point source, rotationally symmetric) or 3.
    let ityp = ldt.map_or(if isym == 1 { 1 } else { 3 }, |f| f.type_indicator);
    l.push(ityp.to_string());
    l.push(isym.to_string());
    l.push(c_list.len().to_string());
    l.push(num(dc));
    l.push(gammas.len().to_string());
    l.push(num(dg));
    l.push(one_line(label(p, &["report", "TEST"]).unwrap_or(""), 78));
    l.push(one_line(label(p, &["luminaire name", "LUMINAIRE"]).unwrap_or(""), 78));
    l.push(one_line(label(p, &["luminaire number", "LUMCAT"]).unwrap_or(""), 78));
    l.push(one_line(file_name, 78));
    l.push(one_line(
        label(p, &["date/user", "ISSUEDATE", "TESTDATE"]).unwrap_or(""),
        78,
    ));
    match p.luminaire_size_m {
        // Luminaire length along Y, width along X; a round EULUMDAT housing keeps its width 0.
        Some([x, y, z]) => {
            let round = ldt.is_some_and(|f| f.luminaire_mm[1] == 0.0);
            l.push(mm(y));
            l.push(if round { "0".to_string() } else { mm(x) });
            l.push(mm(z));
        }
        None => {
            l.extend(["0", "0", "0"].iter().map(|s| s.to_string()));
            if p.format != FileFormat::Eulumdat {
                lost.push("IES files give no luminaire (housing) size: written as 0".into());
            }
        }
    }
    let (area, heights) = ldt_area(&p.opening, &mut lost);
    l.push(mm(area[0]));
    l.push(mm(area[1]));
    l.extend(heights.iter().map(|h| mm(*h)));
    let down = p.web.flux_between(0.0, 90.0);
    let dff = if flux > 0.0 { 100.0 * down / flux } else { 0.0 };
    let lor = 100.0 * flux / set_flux;
    l.push(num(dff));
    l.push(num(lor));
    l.push("1".to_string()); // conversion factor
    l.push(num(ldt.map_or(0.0, |f| f.measurement_tilt_deg)));
    l.push("1".to_string()); // one lamp set
    l.push(num(count.round()));
    l.push(one_line(
        set.map(|s| s.lamp_type.as_str())
            .or_else(|| label(p, &["LAMP", "LAMPCAT"]))
            .unwrap_or(""),
        78,
    ));
    l.push(num(set_flux));
    l.push(one_line(
        set.map(|s| s.colour.as_str())
            .or_else(|| label(p, &["_COLOUR"]))
            .unwrap_or(""),
        78,
    ));
    l.push(one_line(
        set.map(|s| s.cri.as_str())
            .or_else(|| label(p, &["_CRI"]))
            .unwrap_or(""),
        78,
    ));
    l.push(num(p.input_watts.unwrap_or(0.0)));
    match ldt {
        Some(f) => l.extend(f.direct_ratios.iter().map(|r| num(*r))),
        None => {
            l.extend((0..10).map(|_| "0".to_string()));
            lost.push("direct ratios (utilisation by room index) are not computed: written as 0".into());
        }
    }
    if let Some(f) = ldt {
        if f.lamp_sets.len() > 1 {
            lost.push(format!(
                "{} lamp sets: the set in use is written, the others are not",
                f.lamp_sets.len()
            ));
        }
    }
    if let RawFile::Ies(f) = &p.raw {
        if f.tilt.is_some() && p.tilt_applied_deg.is_none() {
            lost.push("the IES TILT table has no EULUMDAT field: intensities are at the measured tilt".into());
        }
        let keep: Vec<&str> = [
            "TEST",
            "TESTLAB",
            "ISSUEDATE",
            "MANUFAC",
            "LUMCAT",
            "LUMINAIRE",
            "LAMP",
            "LAMPCAT",
        ]
        .to_vec();
        let dropped: Vec<String> = f
            .keywords
            .iter()
            .filter(|(k, _)| !keep.iter().any(|x| x.eq_ignore_ascii_case(k)) && !k.starts_with('_'))
            .map(|(k, _)| format!("[{k}]"))
            .collect();
        if !dropped.is_empty() {
            lost.push(format!(
                "IES keywords without an EULUMDAT field: {}",
                dropped.join(", ")
            ));
        }
    }
    if p.tilt_applied_deg.is_some() {
        lost.push("the TILT factor is applied to the intensities".into());
    }
    l.extend(c_list.iter().map(|c| num(*c)));
    l.extend(gammas.iter().map(|g| num(*g)));
    for &c in &stored {
        for &g in &gammas {
            l.push(num(p.web.sample(c, g) * k));
        }
    }
    Ok(Converted {
        text: l.join("\r\n") + "\r\n",
        lost,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seven_significant_digits_without_exponent() {
        assert_eq!(num(1234.56789), "1234.568");
        assert_eq!(num(0.000123456789), "0.0001234568");
        assert_eq!(num(0.0), "0");
        assert_eq!(num(1e12), "1000000000000");
        assert_eq!(num(2.5), "2.5");
    }
}
