//! A photometric file read into lumiview's model: format facts, labels, the absolute
//! [`PhotometricWeb`], the luminous opening, declared and integrated flux.

use std::path::Path;

use super::error::{parse_error, PhotometryError};
use super::ies::{self, IesFile, IesVersion, TiltTable};
use super::ldt::{self, LdtFile};
use super::opening::{classify_ies, luminance, LuminousOpening, OpeningShape};
use super::text::{decode, Lines};
use super::web::{NativeGrid, PhotometricType, PhotometricWeb, Symmetry, ANGLE_EPS, MAX_INTENSITY_CD};

/// Metres per foot.
pub const METRES_PER_FOOT: f64 = 0.3048;

/// The file format a luminaire was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum FileFormat {
    /// IES LM-63, with its edition.
    Ies(IesVersion),
    /// EULUMDAT.
    Eulumdat,
}

impl FileFormat {
    /// Human-readable name, e.g. `IES LM-63-2002`.
    pub fn name(&self) -> String {
        match self {
            FileFormat::Ies(v) => format!("IES {}", v.name()),
            FileFormat::Eulumdat => "EULUMDAT".to_string(),
        }
    }
}

/// Choices made when loading.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadOptions {
    /// Lamp tilt angle in degrees at which to apply an IES TILT table; `None` keeps the measured
    /// orientation (no factor).
    pub tilt_deg: Option<f64>,
    /// EULUMDAT lamp set to use (0-based; sets are alternative equipment).
    pub lamp_set: usize,
    /// Grid step in degrees for resampling Type A and B files into the C × γ frame (0 = automatic:
    /// the file's finest step, between 0.25° and 1°).
    pub ab_step_deg: f64,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            tilt_deg: None,
            lamp_set: 0,
            ab_step_deg: 0.0,
        }
    }
}

/// The raw file behind a [`Photometry`].
#[derive(Debug, Clone, PartialEq)]
pub enum RawFile {
    /// An IES file.
    Ies(Box<IesFile>),
    /// An EULUMDAT file.
    Ldt(Box<LdtFile>),
}

/// A luminaire's far-field photometry in absolute units.
#[derive(Debug, Clone, PartialEq)]
pub struct Photometry {
    /// The file's name as given.
    pub source: String,
    /// Format and edition.
    pub format: FileFormat,
    /// Labels and keywords (key, value) in file order.
    pub labels: Vec<(String, String)>,
    /// The file's photometric type (converted to Type C in `web`).
    pub photometric_type: PhotometricType,
    /// The symmetry the file declares.
    pub symmetry: Symmetry,
    /// Native table size as stored: (horizontal angles / C planes, vertical angles).
    pub native_size: (usize, usize),
    /// Number of lamps as written (EULUMDAT: of the chosen set; negative means absolute).
    pub lamp_count: f64,
    /// The EULUMDAT lamp set in use (0-based, `LoadOptions::lamp_set`); 0 for IES files.
    pub lamp_set_index: usize,
    /// Total rated lamp flux in lm, `None` for absolute photometry.
    pub lamp_flux_lm: Option<f64>,
    /// The factor applied to stored values to get cd (IES: multiplier × ballast factor ×
    /// ballast-lamp factor; EULUMDAT: conversion factor × lamp flux / 1000).
    pub candela_scale: f64,
    /// The file's own multiplier field (IES candela multiplier, EULUMDAT conversion factor).
    pub multiplier: f64,
    /// Declared light output ratio (fraction), where the file states one.
    pub declared_lor: Option<f64>,
    /// Declared luminaire flux in lm (EULUMDAT: lamp flux × LORL), where derivable.
    pub declared_luminaire_flux_lm: Option<f64>,
    /// Input power in W, where given.
    pub input_watts: Option<f64>,
    /// The luminous opening in metres.
    pub opening: LuminousOpening,
    /// Luminaire housing extents along X, Y and Z in m, where the file gives them (EULUMDAT: X is
    /// its width, Y its length; docs/adr/0002).
    pub luminaire_size_m: Option<[f64; 3]>,
    /// TILT table, when the file has one.
    pub tilt: Option<TiltTable>,
    /// Tilt angle applied (degrees), when one was asked for.
    pub tilt_applied_deg: Option<f64>,
    /// Absolute intensity in cd over the sphere.
    pub web: PhotometricWeb,
    /// Non-fatal findings, each beginning with the file's name: what the reader had to guess,
    /// and files that parse but are implausible (`summary::plausibility_warnings`).
    pub warnings: Vec<String>,
    /// The file as read.
    pub raw: RawFile,
}

impl Photometry {
    /// Luminous flux in lm integrated from the web.
    pub fn flux_lm(&self) -> f64 {
        self.web.flux()
    }

    /// Integrated flux divided by the rated lamp flux (the light output ratio the data imply).
    pub fn integrated_lor(&self) -> Option<f64> {
        self.lamp_flux_lm.filter(|f| *f > 0.0).map(|f| self.flux_lm() / f)
    }

    /// Luminous intensity in cd towards (C, γ) in degrees.
    pub fn intensity(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        self.web.sample(c_deg, gamma_deg)
    }

    /// Luminance in cd/m² of the luminous opening seen from (C, γ) in degrees: I / A_proj.
    /// `None` where the projected area is zero.
    pub fn luminance(&self, c_deg: f64, gamma_deg: f64) -> Option<f64> {
        luminance(
            self.intensity(c_deg, gamma_deg),
            self.opening.projected_area(c_deg, gamma_deg),
        )
    }
}

/// Reads a photometric file (IES or EULUMDAT, detected from the extension, else the contents).
///
/// Errors: a path that is not a regular file or is longer than [`MAX_PHOTOMETRY_FILE_BYTES`]
/// (refused before reading), binary data (a NUL byte), and every parse error, each naming the file.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Photometry, PhotometryError> {
    let bytes =
        crate::files::read_regular(path, MAX_PHOTOMETRY_FILE_BYTES, "an IES or EULUMDAT file").map_err(|source| {
            PhotometryError::Io {
                path: path.to_path_buf(),
                source,
            }
        })?;
    if let Some(at) = bytes.iter().position(|&b| b == 0) {
        return Err(super::error::parse_error(
            &path.display().to_string(),
            None,
            "file",
            format!(
                "byte {at} is NUL: binary data, not an IES or EULUMDAT text file (a half-written or damaged file?)"
            ),
        )
        .into());
    }
    let name = path.display().to_string();
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let load_tilt = move |tilt_name: &str| -> Result<String, PhotometryError> {
        let p = dir.join(tilt_name);
        let io = |source| PhotometryError::Io {
            path: p.clone(),
            source,
        };
        // Only a regular file of plausible size: a device or FIFO named in a file must not hang
        // or exhaust memory.
        crate::files::read_regular(&p, MAX_TILT_FILE_BYTES, "a TILT file")
            .map(decode)
            .map_err(io)
    };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let text = decode(bytes);
    let is_ldt = match ext.as_str() {
        "ldt" => true,
        "ies" => false,
        _ => !looks_like_ies(&text),
    };
    if is_ldt {
        from_ldt(ldt::parse(&text, &name)?, &name, opts)
    } else {
        from_ies(ies::parse(&text, &name, &load_tilt)?, &name, opts)
    }
}

/// Reads photometric text already in memory; `name` is used in errors and decides the format by
/// its extension (`.ies` / `.ldt`) or, failing that, by the contents. `TILT=<file>` references
/// cannot be resolved from memory and are an error.
pub fn load_from_text(text: &str, name: &str, opts: &LoadOptions) -> Result<Photometry, PhotometryError> {
    let lower = name.to_ascii_lowercase();
    let is_ldt = if lower.ends_with(".ldt") {
        true
    } else if lower.ends_with(".ies") {
        false
    } else {
        !looks_like_ies(text)
    };
    if is_ldt {
        from_ldt(ldt::parse(text, name)?, name, opts)
    } else {
        let no_files = |t: &str| -> Result<String, PhotometryError> {
            Err(parse_error(
                name,
                None,
                "TILT",
                format!("TILT={t} names a file, which cannot be read for in-memory text"),
            )
            .into())
        };
        from_ies(ies::parse(text, name, &no_files)?, name, opts)
    }
}

fn looks_like_ies(text: &str) -> bool {
    // Only the first 200 lines, read one at a time (no line table for a file of short lines).
    let starts = |l: &str, word: &str| {
        l.trim_start()
            .get(..word.len())
            .is_some_and(|h| h.eq_ignore_ascii_case(word))
    };
    let mut ls = Lines::new(text).take(200);
    ls.next().is_some_and(|l| starts(l, "IES")) || Lines::new(text).take(200).any(|l| starts(l, "TILT"))
}

/// Largest TILT file read, bytes.
pub const MAX_TILT_FILE_BYTES: u64 = 1 << 20;

/// Largest IES or EULUMDAT file read (32 MiB; published files are well under 1 MiB, a 0.1° × 1°
/// full-sphere table about 5 MiB). Larger files are refused before reading.
pub const MAX_PHOTOMETRY_FILE_BYTES: u64 = 32 << 20;

/// Most intensity values in one table (C planes × γ angles): 2,000,000, e.g. 0.1° × 0.1° over a
/// hemisphere. A larger declared table is refused before anything is allocated.
pub const MAX_TABLE_VALUES: usize = 2_000_000;

/// Largest luminous-opening dimension accepted, metres.
pub const MAX_OPENING_M: f64 = 1000.0;

/// A warning when a Type C range that runs past 180° stops well short of 360°: the missing planes
/// are interpolated across the gap back to C0.
fn wrap_gap_warning(h: &[f64]) -> Option<String> {
    let (first, last) = (*h.first()?, *h.last()?);
    if first.abs() > ANGLE_EPS || last <= 180.0 + ANGLE_EPS || last >= 360.0 - ANGLE_EPS {
        return None;
    }
    let max_step = h.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    (360.0 - last > 1.5 * max_step).then(|| {
        format!(
            "horizontal angles stop at {last}°: the planes from {last}° to 360° are interpolated towards C0 \
             across a {}° gap",
            360.0 - last
        )
    })
}

/// Smallest resampling step accepted for Type A/B files, degrees (0.05° is a 7201 × 3601 grid).
pub const MIN_AB_STEP_DEG: f64 = 0.05;

fn ab_step(opts: &LoadOptions, h: &[f64], v: &[f64]) -> Result<f64, PhotometryError> {
    if opts.ab_step_deg != 0.0 {
        if !(MIN_AB_STEP_DEG..=15.0).contains(&opts.ab_step_deg) {
            return Err(PhotometryError::InvalidArgument {
                name: "ab_step_deg",
                message: format!(
                    "{} is outside {MIN_AB_STEP_DEG}…15° (0 chooses the step from the file)",
                    opts.ab_step_deg
                ),
            });
        }
        return Ok(opts.ab_step_deg);
    }
    let finest = h
        .windows(2)
        .chain(v.windows(2))
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    Ok(finest.clamp(0.25, 1.0))
}

/// Converts a parsed IES file into the model.
pub fn from_ies(f: IesFile, name: &str, opts: &LoadOptions) -> Result<Photometry, PhotometryError> {
    let scale = f.candela_scale();
    let values: Vec<f64> = f.candela.iter().map(|v| v * scale).collect();
    let grid = NativeGrid {
        file: name,
        h: &f.horizontal_deg,
        v: &f.vertical_deg,
        values: &values,
    };
    let ptype = match f.photometric_type {
        1 => PhotometricType::C,
        2 => PhotometricType::B,
        _ => PhotometricType::A,
    };
    let (mut web, symmetry) = match ptype {
        PhotometricType::C => PhotometricWeb::from_type_c(&grid)?,
        t => PhotometricWeb::from_type_ab(&grid, t, ab_step(opts, &f.horizontal_deg, &f.vertical_deg)?)?,
    };
    let mut warnings = f.warnings.clone();
    let tilt_applied_deg = apply_tilt(&mut web, f.tilt.as_ref(), opts, name)?;
    let unit = if f.units == 1 { METRES_PER_FOOT } else { 1.0 };
    for (dim, value) in [("width", f.width), ("length", f.length), ("height", f.height)] {
        if (value * unit).abs() > MAX_OPENING_M {
            return Err(parse_error(
                name,
                None,
                format!("luminous opening {dim}"),
                format!(
                    "{} m is not a plausible luminous opening (limit {MAX_OPENING_M} m)",
                    value * unit
                ),
            )
            .into());
        }
    }
    if ptype == PhotometricType::C {
        warnings.extend(wrap_gap_warning(&f.horizontal_deg));
    }
    let (opening, warn) = classify_ies(
        f.width * unit,
        f.length * unit,
        f.height * unit,
        f.version < IesVersion::Lm63_2002,
    );
    warnings.extend(warn);
    let (opening, luminaire_size_m) = lumiview_keywords(&f, opening, &mut warnings);
    let lamp_flux_lm = (!f.is_absolute()).then_some(f.lamp_count * f.lumens_per_lamp);
    let labels = f
        .labels
        .iter()
        .map(|l| (String::new(), l.clone()))
        .chain(f.keywords.iter().cloned())
        .collect();
    Ok(finish(Photometry {
        source: name.to_string(),
        format: FileFormat::Ies(f.version),
        labels,
        photometric_type: ptype,
        symmetry,
        native_size: (f.horizontal_deg.len(), f.vertical_deg.len()),
        lamp_count: f.lamp_count,
        lamp_set_index: 0,
        lamp_flux_lm,
        candela_scale: scale,
        multiplier: f.multiplier,
        declared_lor: None,
        declared_luminaire_flux_lm: None,
        input_watts: Some(f.input_watts),
        opening,
        luminaire_size_m,
        tilt: f.tilt.clone(),
        tilt_applied_deg,
        web,
        warnings,
        raw: RawFile::Ies(Box::new(f)),
    }))
}

/// Reads the two IES user keywords lumiview's converter writes for what LM-63 cannot hold
/// (`convert::SIDE_HEIGHTS_KEYWORD`: four side heights in metres, faces seen from C0, C90, C180,
/// C270; `convert::HOUSING_KEYWORD`: the housing's X, Y, Z extents in metres). Side heights apply
/// to a rectangular or round opening; anything unreadable is ignored with a warning.
fn lumiview_keywords(
    f: &IesFile,
    opening: LuminousOpening,
    warnings: &mut Vec<String>,
) -> (LuminousOpening, Option<[f64; 3]>) {
    fn numbers<const N: usize>(text: &str) -> Option<[f64; N]> {
        let v: Vec<f64> = text
            .split_whitespace()
            .take(N)
            .map(|t| {
                t.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && (0.0..=MAX_OPENING_M).contains(x))
            })
            .collect::<Option<Vec<_>>>()?;
        v.try_into().ok()
    }
    let mut opening = opening;
    if let Some(text) = f.keyword(super::convert::SIDE_HEIGHTS_KEYWORD) {
        let shape = match opening.shape {
            OpeningShape::Rectangle | OpeningShape::Box => Some(OpeningShape::RectangleWithSides),
            OpeningShape::Ellipse | OpeningShape::VerticalCylinder
                if (opening.size_x_m - opening.size_y_m).abs() <= 1e-9 * opening.size_x_m =>
            {
                Some(OpeningShape::DiscWithSides)
            }
            _ => None,
        };
        match (numbers::<4>(text), shape) {
            (Some(h), Some(shape)) => {
                opening.shape = shape;
                opening.side_heights_m = h;
                opening.height_m = h.iter().copied().fold(0.0, f64::max);
            }
            _ => warnings.push(format!(
                "[{}] `{text}` ignored: expected four heights in metres for a rectangular or round opening",
                super::convert::SIDE_HEIGHTS_KEYWORD
            )),
        }
    }
    let housing = f.keyword(super::convert::HOUSING_KEYWORD).and_then(|text| {
        let v = numbers::<3>(text);
        if v.is_none() {
            warnings.push(format!(
                "[{}] `{text}` ignored: expected X, Y, Z in metres",
                super::convert::HOUSING_KEYWORD
            ));
        }
        v.filter(|[x, y, _]| *x > 0.0 && *y > 0.0)
    });
    (opening, housing)
}

fn apply_tilt(
    web: &mut PhotometricWeb,
    tilt: Option<&TiltTable>,
    opts: &LoadOptions,
    name: &str,
) -> Result<Option<f64>, PhotometryError> {
    let Some(angle) = opts.tilt_deg else {
        return Ok(None);
    };
    if !angle.is_finite() {
        return Err(PhotometryError::InvalidArgument {
            name: "tilt_deg",
            message: format!("{angle} is not a finite angle (file {name})"),
        });
    }
    if let Some(t) = tilt {
        // The factors come from the file: one that would take the web past the intensity bound
        // (or to infinity) is an error, as the same intensities written directly would be.
        let k = t.factor_at(angle);
        let peak = web.max_intensity().0;
        if !(k.is_finite() && peak * k <= MAX_INTENSITY_CD) {
            return Err(parse_error(
                name,
                None,
                "TILT multiplying factors",
                format!("factor {k:e} at a tilt of {angle}° takes the peak {peak} cd beyond {MAX_INTENSITY_CD:e} cd"),
            )
            .into());
        }
        web.scale(k);
        return Ok(Some(angle));
    }
    // TILT=NONE: the lamp output does not depend on tilt, so nothing is applied.
    Ok(None)
}

/// Converts a parsed EULUMDAT file into the model.
pub fn from_ldt(f: LdtFile, name: &str, opts: &LoadOptions) -> Result<Photometry, PhotometryError> {
    let Some(set) = f.lamp_sets.get(opts.lamp_set) else {
        return Err(PhotometryError::InvalidArgument {
            name: "lamp_set",
            message: format!(
                "{name} has {} lamp set(s); set {} asked for",
                f.lamp_sets.len(),
                opts.lamp_set + 1
            ),
        });
    };
    // Absolute photometry (negative lamp count, the DIAL/Relux convention) keeps the intensities
    // in cd/klm and puts the *luminaire* flux in the flux field: the scale is the same, only the
    // meaning of the flux (no lamp flux, no LOR) changes.
    let absolute = set.count < 0.0;
    if set.flux_lm <= 0.0 {
        return Err(parse_error(
            name,
            None,
            format!("lamp set {} total luminous flux", opts.lamp_set + 1),
            format!(
                "{} lm: intensities are in cd/klm and need a positive flux to become candela",
                set.flux_lm
            ),
        )
        .into());
    }
    let scale = f.conversion_factor * set.flux_lm / 1000.0;
    let stored = f.stored_planes();
    let ng = f.ng;
    for w in f.c_deg.windows(2) {
        if w[1] <= w[0] {
            return Err(parse_error(
                name,
                None,
                "C angles",
                format!("angles must increase, found {} then {}", w[0], w[1]),
            )
            .into());
        }
    }
    if f.c_deg.first().is_some_and(|c| c.abs() > ANGLE_EPS) || f.c_deg.last().is_some_and(|c| *c >= 360.0 - ANGLE_EPS) {
        return Err(parse_error(name, None, "C angles", "expected C angles from 0 up to below 360°").into());
    }
    // Every C plane of the full circle, taken from the stored plane its symmetry maps it to.
    let source_angle = |c: f64| -> f64 {
        match f.symmetry {
            0 => c,
            1 => f.c_deg[0],
            2 => {
                if c <= 180.0 + ANGLE_EPS {
                    c
                } else {
                    360.0 - c
                }
            }
            3 => {
                if c > 90.0 + ANGLE_EPS && c < 270.0 - ANGLE_EPS {
                    (180.0 - c).rem_euclid(360.0)
                } else {
                    c
                }
            }
            _ => {
                // Symmetric about both planes: fold into C0…C90.
                let r = if c > 180.0 { 360.0 - c } else { c };
                if r > 90.0 {
                    180.0 - r
                } else {
                    r
                }
            }
        }
    };
    let (planes_h, values): (Vec<f64>, Vec<f64>) = if f.symmetry == 1 {
        (vec![0.0], f.intensities[..ng].iter().map(|v| v * scale).collect())
    } else {
        let mut vals = Vec::with_capacity(f.mc * ng);
        for &c in &f.c_deg {
            let src = source_angle(c);
            let k = stored
                .iter()
                .position(|&i| (f.c_deg[i] - src).abs() < 1e-3)
                .ok_or_else(|| {
                    parse_error(
                        name,
                        None,
                        "C angles",
                        format!(
                            "plane C{c} maps to C{src} under symmetry {}, which the file does not store",
                            f.symmetry
                        ),
                    )
                })?;
            vals.extend(f.intensities[k * ng..(k + 1) * ng].iter().map(|v| v * scale));
        }
        (f.c_deg.clone(), vals)
    };
    let grid = NativeGrid {
        file: name,
        h: &planes_h,
        v: &f.gamma_deg,
        values: &values,
    };
    if planes_h.len() > 1 && planes_h[planes_h.len() - 1] <= 180.0 + ANGLE_EPS {
        return Err(parse_error(name, None, "C angles", "a full set of C planes must extend beyond C180").into());
    }
    let (web, _) = PhotometricWeb::from_type_c(&grid)?;
    let symmetry = match f.symmetry {
        0 => Symmetry::None,
        1 => Symmetry::Rotational,
        2 => Symmetry::C0C180,
        3 => Symmetry::C90C270,
        _ => Symmetry::Quadrant,
    };
    let mut warnings = f.warnings.clone();
    let m = |mm: f64| mm / 1000.0;
    let sizes = f
        .luminaire_mm
        .iter()
        .chain(&f.luminous_area_mm)
        .chain(&f.luminous_heights_mm);
    if let Some(big) = sizes.copied().find(|mm| m(*mm) > MAX_OPENING_M) {
        return Err(parse_error(
            name,
            None,
            "luminaire / luminous area dimensions",
            format!("{big} mm is not a plausible size (limit {MAX_OPENING_M} m)"),
        )
        .into());
    }
    // EULUMDAT's length runs along C90–C270 (Y) and its width along C0–C180 (X); the C0 side
    // height is the face seen from C0, spanning the length (docs/adr/0002).
    let [la, ba] = f.luminous_area_mm;
    let heights = f.luminous_heights_mm.map(m);
    let has_sides = heights.iter().any(|h| *h > 0.0);
    let tallest = heights.iter().copied().fold(0.0, f64::max);
    let opening = if la == 0.0 && ba == 0.0 {
        if has_sides {
            warnings.push("luminous area has side heights but no length or width: read as a point".into());
        }
        LuminousOpening::point()
    } else {
        let (shape, x, y) = match (ba == 0.0, has_sides) {
            (true, true) => (OpeningShape::DiscWithSides, la, la),
            (true, false) => (OpeningShape::Ellipse, la, la),
            (false, true) => (OpeningShape::RectangleWithSides, ba, la),
            (false, false) => (OpeningShape::Rectangle, ba, la),
        };
        let mut o = LuminousOpening::new(shape, m(x), m(y), tallest);
        o.side_heights_m = heights;
        o
    };
    let [ll, lw, lh] = f.luminaire_mm;
    let luminaire_size_m = (ll > 0.0).then(|| [m(if lw > 0.0 { lw } else { ll }), m(ll), m(lh)]);
    let labels = vec![
        ("company".to_string(), f.company.clone()),
        ("luminaire name".to_string(), f.luminaire_name.clone()),
        ("luminaire number".to_string(), f.luminaire_number.clone()),
        ("report".to_string(), f.report.clone()),
        ("file name".to_string(), f.file_name.clone()),
        ("date/user".to_string(), f.date_user.clone()),
        ("lamp type".to_string(), set.lamp_type.clone()),
    ];
    let lor = f.lor_percent / 100.0;
    Ok(finish(Photometry {
        source: name.to_string(),
        format: FileFormat::Eulumdat,
        labels,
        photometric_type: PhotometricType::C,
        symmetry,
        native_size: (stored.len(), ng),
        lamp_count: set.count,
        lamp_set_index: opts.lamp_set,
        lamp_flux_lm: (!absolute).then_some(set.flux_lm),
        candela_scale: scale,
        multiplier: f.conversion_factor,
        declared_lor: Some(lor),
        declared_luminaire_flux_lm: Some(set.flux_lm * if absolute { 1.0 } else { lor }),
        input_watts: Some(set.watts),
        opening,
        luminaire_size_m,
        tilt: None,
        tilt_applied_deg: None,
        web,
        warnings,
        raw: RawFile::Ldt(Box::new(f)),
    }))
}

/// Names the file in every reader warning and adds the plausibility checks that need the whole
/// model (light output ratio, declared against integrated flux).
fn finish(mut p: Photometry) -> Photometry {
    let prefix = format!("{}: ", p.source);
    for w in &mut p.warnings {
        if !w.starts_with(&prefix) {
            *w = format!("{prefix}{w}");
        }
    }
    let extra = super::summary::plausibility_warnings(&p);
    p.warnings.extend(extra);
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_tilt_factor_is_an_error_not_an_infinite_web() {
        let t = "IESNA:LM-63-2002\nTILT=INCLUDE\n1 2 0 90 1 1e300\n1 1000 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n100 50\n";
        assert!(load_from_text(t, "t.ies", &LoadOptions::default()).is_ok());
        let opts = LoadOptions {
            tilt_deg: Some(45.0),
            ..LoadOptions::default()
        };
        let e = load_from_text(t, "t.ies", &opts).unwrap_err().to_string();
        assert!(e.contains("TILT multiplying factors"), "{e}");
        let sane = t.replace("1e300", "0.5");
        let p = load_from_text(&sane, "t.ies", &opts).unwrap();
        assert!((p.web.sample(0.0, 0.0) - 100.0 * 0.75).abs() < 1e-9);
    }
}
