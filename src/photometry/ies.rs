//! IES LM-63 reader: 1986 (no version line), 1991 (`IESNA91`), 1995, 2002 and 2019.
//!
//! The header is read line by line (keywords, `[MORE]` continuations, free label lines), the TILT
//! line is matched only at the start of a line, and everything after it is one stream of numbers
//! separated by spaces, tabs, commas or line ends, consumed by count (records may span or share
//! lines).

use super::error::{parse_error, ParseError, PhotometryError};
use super::text::{Lines, Tokens};

/// The LM-63 edition a file follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
pub enum IesVersion {
    /// LM-63-1986: no version line.
    Lm63_1986,
    /// LM-63-1991: `IESNA91`.
    Lm63_1991,
    /// LM-63-1995: `IESNA:LM-63-1995`.
    Lm63_1995,
    /// LM-63-2002: `IESNA:LM-63-2002`.
    Lm63_2002,
    /// LM-63-2019: `IES:LM-63-2019`.
    Lm63_2019,
}

impl IesVersion {
    /// The edition's name as people write it.
    pub fn name(self) -> &'static str {
        match self {
            IesVersion::Lm63_1986 => "LM-63-1986",
            IesVersion::Lm63_1991 => "LM-63-1991",
            IesVersion::Lm63_1995 => "LM-63-1995",
            IesVersion::Lm63_2002 => "LM-63-2002",
            IesVersion::Lm63_2019 => "LM-63-2019",
        }
    }
}

/// Where a TILT table came from.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub enum TiltSource {
    /// `TILT=INCLUDE`: in the file itself.
    Include,
    /// `TILT=<file>`: a separate file (the name as written).
    File(String),
}

/// Lamp output factors against lamp tilt angle (IES TILT data).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TiltTable {
    /// Where it came from.
    pub source: TiltSource,
    /// Lamp-to-luminaire geometry code (1: vertical base-up or base-down, 2: horizontal, tilt in
    /// the C0 plane, 3: horizontal, tilt in the C90 plane).
    pub lamp_to_luminaire_geometry: u8,
    /// Tilt angles, degrees, increasing.
    pub angles_deg: Vec<f64>,
    /// Multiplying factors at those angles.
    pub factors: Vec<f64>,
}

impl TiltTable {
    /// The multiplying factor at a tilt angle (degrees): linear between entries, the end value
    /// beyond them (a lamp tilted past the table keeps the last measured factor).
    pub fn factor_at(&self, angle_deg: f64) -> f64 {
        let a = &self.angles_deg;
        let f = &self.factors;
        if a.is_empty() {
            return 1.0;
        }
        if angle_deg <= a[0] {
            return f[0];
        }
        if angle_deg >= a[a.len() - 1] {
            return f[f.len() - 1];
        }
        let i = a.partition_point(|&x| x <= angle_deg) - 1;
        let t = (angle_deg - a[i]) / (a[i + 1] - a[i]);
        f[i] * (1.0 - t) + f[i + 1] * t
    }
}

/// An IES file as written (values not yet scaled).
#[derive(Debug, Clone, PartialEq)]
pub struct IesFile {
    /// Edition.
    pub version: IesVersion,
    /// Keyword lines (`[KEY] value`), in order; `[MORE]` lines are joined to the keyword before
    /// them with a newline. User keywords (`[_…]`) are kept as written.
    pub keywords: Vec<(String, String)>,
    /// Free label lines (1986/1991 files, or stray lines before TILT).
    pub labels: Vec<String>,
    /// TILT data, when the file has any.
    pub tilt: Option<TiltTable>,
    /// Number of lamps.
    pub lamp_count: f64,
    /// Rated lumens per lamp; −1 for absolute photometry.
    pub lumens_per_lamp: f64,
    /// Candela multiplier.
    pub multiplier: f64,
    /// Photometric type code (1 = C, 2 = B, 3 = A).
    pub photometric_type: u8,
    /// Units of the luminous dimensions (1 = feet, 2 = metres).
    pub units: u8,
    /// Luminous width (along C90), length (along C0), height, in the file's units.
    pub width: f64,
    /// See `width`.
    pub length: f64,
    /// See `width`.
    pub height: f64,
    /// Ballast factor.
    pub ballast_factor: f64,
    /// 1986–1995: ballast-lamp photometric factor; 2002: "future use"; 2019: the file generation
    /// type.
    pub line11_second: f64,
    /// Input watts.
    pub input_watts: f64,
    /// Vertical angles, degrees.
    pub vertical_deg: Vec<f64>,
    /// Horizontal angles, degrees.
    pub horizontal_deg: Vec<f64>,
    /// Candela values as written, `[ih * vertical.len() + iv]`.
    pub candela: Vec<f64>,
    /// Things read that a user should know about (non-standard but readable).
    pub warnings: Vec<String>,
}

impl IesFile {
    /// True for absolute photometry (lumens per lamp = −1).
    pub fn is_absolute(&self) -> bool {
        self.lumens_per_lamp < 0.0
    }

    /// The factor applied to every candela value: multiplier × ballast factor × (1986–1995 only)
    /// ballast-lamp photometric factor. LM-63-2002 renamed that field "future use" and LM-63-2019
    /// made it the file generation type: neither is a factor.
    pub fn candela_scale(&self) -> f64 {
        let blp = if self.version >= IesVersion::Lm63_2002 {
            1.0
        } else {
            self.line11_second
        };
        self.multiplier * self.ballast_factor * blp
    }

    /// LM-63-2019 file generation type, when the file is 2019.
    pub fn file_generation_type(&self) -> Option<f64> {
        (self.version >= IesVersion::Lm63_2019).then_some(self.line11_second)
    }

    /// The value of a keyword (first occurrence), without brackets, e.g. `"MANUFAC"`.
    pub fn keyword(&self, key: &str) -> Option<&str> {
        self.keywords
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    }
}

/// Describes an LM-63-2019 file generation type code.
pub fn file_generation_description(code: f64) -> Option<&'static str> {
    const TABLE: [(f64, &str); 10] = [
        (1.00001, "undefined"),
        (1.00010, "computer simulation"),
        (1.00000, "test at an unaccredited lab"),
        (1.00100, "test at an unaccredited lab, lumen scaled"),
        (1.01000, "test at an unaccredited lab, interpolated angle set"),
        (
            1.01100,
            "test at an unaccredited lab, interpolated angle set, lumen scaled",
        ),
        (1.10000, "test at an accredited lab"),
        (1.10100, "test at an accredited lab, lumen scaled"),
        (1.11000, "test at an accredited lab, interpolated angle set"),
        (
            1.11100,
            "test at an accredited lab, interpolated angle set, lumen scaled",
        ),
    ];
    TABLE.iter().find(|(c, _)| (c - code).abs() < 2e-6).map(|(_, d)| *d)
}

fn detect_version(first: &str) -> Option<IesVersion> {
    let t = first.trim().to_ascii_uppercase();
    if t.starts_with("IESNA91") {
        return Some(IesVersion::Lm63_1991);
    }
    let rest = t
        .strip_prefix("IESNA:LM-63-")
        .or_else(|| t.strip_prefix("IES:LM-63-"))
        .or_else(|| t.strip_prefix("IESNA: LM-63-"))?;
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    let year = match (digits.len(), digits.parse::<u32>().unwrap_or(0)) {
        // Two-digit years (`IESNA:LM-63-95`, `-02`) occur in real files.
        (2, y) if y >= 80 => 1900 + y,
        (2, y) => 2000 + y,
        (_, y) => y,
    };
    Some(match year {
        0..=1990 => IesVersion::Lm63_1986,
        1991..=1994 => IesVersion::Lm63_1991,
        1995..=2001 => IesVersion::Lm63_1995,
        2002..=2018 => IesVersion::Lm63_2002,
        _ => IesVersion::Lm63_2019,
    })
}

/// The TILT value when `line` is the TILT line (`TILT=`, matched at the start of the line only).
fn tilt_value(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let head = t.get(..4)?;
    if !head.eq_ignore_ascii_case("TILT") {
        return None;
    }
    let rest = t[4..].trim_start();
    rest.strip_prefix('=').map(str::trim)
}

/// Reads the four TILT fields from a token stream.
fn read_tilt(tokens: &mut Tokens<'_>, file: &str, source: TiltSource) -> Result<TiltTable, ParseError> {
    let geometry = tokens.count("TILT lamp-to-luminaire geometry", 1, 3)? as u8;
    let n = tokens.count("TILT number of angle/factor pairs", 0, 100_000)? as usize;
    let angles = tokens.numbers(n, "TILT angles")?;
    let factors = tokens.numbers(n, "TILT multiplying factors")?;
    for w in angles.windows(2) {
        if w[1] <= w[0] {
            return Err(parse_error(
                file,
                None,
                "TILT angles",
                format!("angles must increase, found {} then {}", w[0], w[1]),
            ));
        }
    }
    if let Some(f) = factors.iter().find(|f| **f < 0.0) {
        return Err(parse_error(
            file,
            None,
            "TILT multiplying factors",
            format!("found negative factor {f}"),
        ));
    }
    Ok(TiltTable {
        source,
        lamp_to_luminaire_geometry: geometry,
        angles_deg: angles,
        factors,
    })
}

/// Parses IES LM-63 text. `file` names the file in errors; `load_tilt` reads a `TILT=<file>`
/// reference (relative to the IES file) and returns its text.
pub fn parse(
    text: &str,
    file: &str,
    load_tilt: &dyn Fn(&str) -> Result<String, PhotometryError>,
) -> Result<IesFile, PhotometryError> {
    if text
        .trim_matches(|c: char| c.is_whitespace() || c == '\u{1a}')
        .is_empty()
    {
        return Err(parse_error(file, Some(1), "header", "the file is empty").into());
    }
    let mut warnings = Vec::new();
    // Lines are read one at a time (a file of millions of lines costs no line table).
    let mut ls = Lines::new(text);
    let version = match ls.clone().next().and_then(detect_version) {
        Some(v) => {
            ls.next();
            v
        }
        None => IesVersion::Lm63_1986,
    };
    let mut keywords: Vec<(String, String)> = Vec::new();
    let mut labels = Vec::new();
    let mut tilt_line = None;
    while let Some(line) = ls.next() {
        let i = ls.count - 1;
        if let Some(v) = tilt_value(line) {
            tilt_line = Some((i, v));
            break;
        }
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        if let Some(rest) = t.strip_prefix('[') {
            if let Some(end) = rest.find(']') {
                let key = rest[..end].trim().to_string();
                let value = rest[end + 1..].trim().to_string();
                if key.eq_ignore_ascii_case("MORE") {
                    match keywords.last_mut() {
                        Some((_, v)) => {
                            v.push('\n');
                            v.push_str(&value);
                        }
                        None => {
                            warnings.push(format!("line {}: [MORE] without a keyword before it", i + 1));
                            keywords.push((key, value));
                        }
                    }
                } else {
                    keywords.push((key, value));
                }
                continue;
            }
        }
        if version >= IesVersion::Lm63_1995 {
            warnings.push(format!("line {}: not a keyword line; kept as a label", i + 1));
        }
        labels.push(t.to_string());
    }
    let Some((tilt_idx, tilt_text)) = tilt_line else {
        return Err(parse_error(
            file,
            Some(ls.count),
            "TILT",
            "no line starting with `TILT=` found (truncated or not an IES file?)",
        )
        .into());
    };
    let mut tokens = Tokens::new(file, ls.rest(), tilt_idx + 2, true);
    let tilt = if tilt_text.eq_ignore_ascii_case("NONE") {
        None
    } else if tilt_text.eq_ignore_ascii_case("INCLUDE") {
        Some(read_tilt(&mut tokens, file, TiltSource::Include)?)
    } else if tilt_text.is_empty() {
        return Err(parse_error(
            file,
            Some(tilt_idx + 1),
            "TILT",
            "expected NONE, INCLUDE or a file name after `TILT=`",
        )
        .into());
    } else {
        let tilt_src = load_tilt(tilt_text).map_err(|e| {
            parse_error(
                file,
                Some(tilt_idx + 1),
                "TILT",
                format!("the TILT file `{tilt_text}` named here cannot be read: {e}"),
            )
        })?;
        let tilt_file_label = format!("{file} (TILT file {tilt_text})");
        // The named file may be anything: errors say what was expected, never what is there.
        let mut tt = Tokens::new(&tilt_file_label, &tilt_src, 1, true).without_quotes();
        Some(read_tilt(
            &mut tt,
            &tilt_file_label,
            TiltSource::File(tilt_text.to_string()),
        )?)
    };

    let lamp_line = tokens.line();
    let lamp_count = tokens.number("number of lamps")?;
    if lamp_count < 0.0 || lamp_count.fract() != 0.0 {
        return Err(parse_error(
            file,
            Some(lamp_line),
            "number of lamps",
            format!("expected a whole number ≥ 0, found {lamp_count}"),
        )
        .into());
    }
    let lumens_line = tokens.line();
    let lumens_per_lamp = tokens.number("lumens per lamp")?;
    if !(lumens_per_lamp > 0.0 || lumens_per_lamp == -1.0) {
        return Err(parse_error(
            file,
            Some(lumens_line),
            "lumens per lamp",
            format!("expected −1 (absolute photometry) or a positive lamp flux, found {lumens_per_lamp}"),
        )
        .into());
    }
    let mult_line = tokens.line();
    let multiplier = tokens.number("candela multiplier")?;
    if multiplier <= 0.0 {
        return Err(parse_error(
            file,
            Some(mult_line),
            "candela multiplier",
            format!("expected a positive factor, found {multiplier}"),
        )
        .into());
    }
    let counts_line = tokens.line();
    let n_vert = tokens.count("number of vertical angles", 1, 100_000)? as usize;
    let n_horiz = tokens.count("number of horizontal angles", 1, 100_000)? as usize;
    if n_vert.saturating_mul(n_horiz) > super::luminaire::MAX_TABLE_VALUES {
        return Err(parse_error(
            file,
            Some(counts_line),
            "number of vertical angles",
            format!(
                "{n_vert} vertical × {n_horiz} horizontal angles is more than the {} candela values lumiview reads",
                super::luminaire::MAX_TABLE_VALUES
            ),
        )
        .into());
    }
    let type_line = tokens.line();
    let ptype = tokens.number("photometric type")?;
    let photometric_type = match ptype {
        1.0 => 1,
        2.0 => 2,
        3.0 => 3,
        other => {
            return Err(parse_error(
                file,
                Some(type_line),
                "photometric type",
                format!("unknown photometric type {other} (expected 1 = C, 2 = B, 3 = A)"),
            )
            .into())
        }
    };
    let units_line = tokens.line();
    let units = tokens.number("units type")?;
    let units = match units {
        1.0 => 1,
        2.0 => 2,
        other => {
            return Err(parse_error(
                file,
                Some(units_line),
                "units type",
                format!("expected 1 (feet) or 2 (metres), found {other}"),
            )
            .into())
        }
    };
    let width = tokens.number("luminous opening width")?;
    let length = tokens.number("luminous opening length")?;
    let height = tokens.number("luminous opening height")?;
    let bf_line = tokens.line();
    let ballast_factor = tokens.number("ballast factor")?;
    if ballast_factor <= 0.0 {
        return Err(parse_error(
            file,
            Some(bf_line),
            "ballast factor",
            format!("expected a positive factor, found {ballast_factor}"),
        )
        .into());
    }
    let second_name = if version >= IesVersion::Lm63_2019 {
        "file generation type"
    } else if version >= IesVersion::Lm63_2002 {
        "future use field"
    } else {
        "ballast-lamp photometric factor"
    };
    let second_line = tokens.line();
    let line11_second = tokens.number(second_name)?;
    if version >= IesVersion::Lm63_2019 {
        if file_generation_description(line11_second).is_none() {
            warnings.push(format!(
                "line {second_line}: unrecognised LM-63-2019 file generation type {line11_second}"
            ));
        }
    } else if version >= IesVersion::Lm63_2002 {
        if line11_second != 1.0 {
            warnings.push(format!(
                "line {second_line}: the LM-63-2002 \"future use\" field holds {line11_second}; not applied \
                 (it was the ballast-lamp photometric factor before 2002)"
            ));
        }
    } else if line11_second <= 0.0 {
        return Err(parse_error(
            file,
            Some(second_line),
            second_name,
            format!("expected a positive factor, found {line11_second}"),
        )
        .into());
    }
    let input_watts = tokens.number("input watts")?;
    let vertical_deg = tokens.numbers(n_vert, "vertical angles")?;
    let horizontal_deg = tokens.numbers(n_horiz, "horizontal angles")?;
    let total = n_vert.saturating_mul(n_horiz);
    let mut candela = Vec::with_capacity(total.min(tokens.upper_bound()));
    // Negative values: count, smallest, its index and line.
    let mut negative: Option<(usize, f64, usize, usize)> = None;
    for _ in 0..total {
        let line = tokens.line();
        let v = tokens.number("candela values")?;
        if v < 0.0 {
            let (n, least, at, at_line) = negative.unwrap_or((0, 0.0, candela.len(), line));
            negative = Some(if v < least {
                (n + 1, v, candela.len(), line)
            } else {
                (n + 1, least, at, at_line)
            });
        }
        candela.push(v);
    }
    let mut vertical_deg = vertical_deg;
    let mut horizontal_deg = horizontal_deg;
    if let Some((n, least, at, at_line)) = negative {
        // Negative candela come from background subtraction in real measurements: read as no
        // light, and say so.
        warnings.push(format!(
            "line {at_line}: {n} negative candela value(s) read as 0 (the smallest, {least}, at horizontal {}°, \
             vertical {}°)",
            horizontal_deg[at / n_vert],
            vertical_deg[at % n_vert]
        ));
        for v in &mut candela {
            *v = v.max(0.0);
        }
    }
    if let Some(perm) = super::web::order_angles(&mut vertical_deg) {
        warnings.push("vertical angles are not in increasing order: read in increasing order".into());
        for row in candela.chunks_exact_mut(n_vert) {
            let old = row.to_vec();
            for (k, &i) in perm.iter().enumerate() {
                row[k] = old[i];
            }
        }
    }
    if let Some(perm) = super::web::order_angles(&mut horizontal_deg) {
        warnings.push("horizontal angles are not in increasing order: read in increasing order".into());
        let old = candela.clone();
        for (k, &i) in perm.iter().enumerate() {
            candela[k * n_vert..(k + 1) * n_vert].copy_from_slice(&old[i * n_vert..(i + 1) * n_vert]);
        }
    }
    if tokens.has_more() {
        let line = tokens.line();
        warnings.push(format!(
            "line {line}: {} values after the candela table ignored (only the first luminaire data set is read)",
            tokens.count_rest()
        ));
    }
    Ok(IesFile {
        version,
        keywords,
        labels,
        tilt,
        lamp_count,
        lumens_per_lamp,
        multiplier,
        photometric_type,
        units,
        width,
        length,
        height,
        ballast_factor,
        line11_second,
        input_watts,
        vertical_deg,
        horizontal_deg,
        candela,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_tilt(name: &str) -> Result<String, PhotometryError> {
        Err(PhotometryError::Io {
            path: name.into(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no"),
        })
    }

    const MINIMAL: &str = "IESNA:LM-63-2002\n[TEST] x\n[LUMINAIRE] says TILT=INCLUDE here\nTILT=NONE\n\
        1 1000 2 3 1 1 2 0.5 0.6 0\n1 1 10\n0 45 90\n0\n100 50 0\n";

    #[test]
    fn keyword_containing_tilt_does_not_derail() {
        let f = parse(MINIMAL, "m.ies", &no_tilt).unwrap();
        assert_eq!(f.version, IesVersion::Lm63_2002);
        assert!(f.tilt.is_none());
        assert_eq!(f.keyword("LUMINAIRE"), Some("says TILT=INCLUDE here"));
        assert_eq!(f.candela, vec![100.0, 50.0, 0.0]);
        assert_eq!(f.candela_scale(), 2.0);
    }

    #[test]
    fn tilt_include_sharing_lines() {
        let t = "IESNA:LM-63-1995\nTILT=INCLUDE\n1 3 0 45 90 1.0 0.9\n0.8 1 1000 1 2 1 1 2 0 0 0 1 1 10 0 90 0 5 6\n";
        let f = parse(t, "t.ies", &no_tilt).unwrap();
        let tilt = f.tilt.as_ref().unwrap();
        assert_eq!(tilt.angles_deg, vec![0.0, 45.0, 90.0]);
        assert_eq!(tilt.factors, vec![1.0, 0.9, 0.8]);
        assert!((tilt.factor_at(22.5) - 0.95).abs() < 1e-12);
        assert_eq!(f.candela, vec![5.0, 6.0]);
    }

    #[test]
    fn truncated_file_names_the_field() {
        let cut = &MINIMAL[..MINIMAL.len() - 4];
        let e = parse(cut, "cut.ies", &no_tilt).unwrap_err().to_string();
        assert!(
            e.contains("cut.ies") && e.contains("candela values") && e.contains("truncated"),
            "{e}"
        );
    }

    #[test]
    fn unknown_photometric_type_is_an_error() {
        let t = MINIMAL.replace("1 1000 2 3 1 1 2", "1 1000 2 3 1 4 2");
        let e = parse(&t, "p.ies", &no_tilt).unwrap_err().to_string();
        assert!(e.contains("unknown photometric type 4"), "{e}");
    }

    #[test]
    fn huge_table_in_a_short_file_is_an_error_not_an_allocation() {
        // 100000 × 100000 candela values declared (80 GB as f64), both angle lists present.
        let angles = |n: usize| {
            (0..n)
                .map(|i| format!("{}", i as f64 * 1e-3))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let t = format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 100000 100000 1 2 0 0 0\n1 1 10\n{}\n{}\n0 0\n",
            angles(100_000),
            angles(100_000)
        );
        let e = parse(&t, "big.ies", &no_tilt).unwrap_err().to_string();
        assert!(e.contains("more than the 2000000 candela values"), "{e}");
        // Within the limit: the declared table is not allocated before the values are there.
        let t = format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 1000 1000 1 2 0 0 0\n1 1 10\n{}\n{}\n0 0\n",
            angles(1000),
            angles(1000)
        );
        let e = parse(&t, "big.ies", &no_tilt).unwrap_err().to_string();
        assert!(e.contains("candela values") && e.contains("truncated"), "{e}");
    }

    #[test]
    fn missing_tilt_line_is_an_error() {
        let e = parse("IESNA91\n[TEST] x\n", "n.ies", &no_tilt).unwrap_err().to_string();
        assert!(e.contains("TILT"), "{e}");
    }
}
