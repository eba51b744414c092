//! EULUMDAT (`.ldt`) reader. One value per line, decimal commas allowed; intensities in cd per
//! 1000 lm of lamp flux (or absolute cd when the lamp count is negative).

use super::error::{parse_error, ParseError};
use super::text::{to_count, Lines, Tokens};

/// One lamp set. Several sets are alternative equipment, not additive.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LampSet {
    /// Number of lamps (negative: absolute photometry).
    pub count: f64,
    /// Lamp type text.
    pub lamp_type: String,
    /// Total luminous flux of the set, lm (not per lamp).
    pub flux_lm: f64,
    /// Colour temperature / colour text.
    pub colour: String,
    /// Colour rendering text.
    pub cri: String,
    /// Wattage including ballast, W.
    pub watts: f64,
}

/// An EULUMDAT file as written.
#[derive(Debug, Clone, PartialEq)]
pub struct LdtFile {
    /// Line 1: company identification / data bank / version.
    pub company: String,
    /// Line 2: type indicator Ityp (not used for geometry; tools disagree on it).
    pub type_indicator: i64,
    /// Line 3: symmetry indicator Isym (0–4).
    pub symmetry: u8,
    /// Line 4: number of C planes Mc over 360°.
    pub mc: usize,
    /// Line 5: distance between C planes Dc, degrees.
    pub dc: f64,
    /// Line 6: number of intensities per C plane Ng.
    pub ng: usize,
    /// Line 7: distance between γ angles Dg, degrees.
    pub dg: f64,
    /// Line 8: measurement report number.
    pub report: String,
    /// Line 9: luminaire name.
    pub luminaire_name: String,
    /// Line 10: luminaire number.
    pub luminaire_number: String,
    /// Line 11: file name.
    pub file_name: String,
    /// Line 12: date / user.
    pub date_user: String,
    /// Lines 13–15: luminaire length/diameter, width (0 = round), height, mm.
    pub luminaire_mm: [f64; 3],
    /// Lines 16–17: luminous area length/diameter and width (0 = round), mm.
    pub luminous_area_mm: [f64; 2],
    /// Lines 18–21: luminous area heights at C0, C90, C180, C270, mm.
    pub luminous_heights_mm: [f64; 4],
    /// Line 22: downward flux fraction, %.
    pub dff_percent: f64,
    /// Line 23: light output ratio of the luminaire, %.
    pub lor_percent: f64,
    /// Line 24: conversion factor for luminous intensities.
    pub conversion_factor: f64,
    /// Line 25: tilt of the luminaire during measurement, degrees.
    pub measurement_tilt_deg: f64,
    /// Lines 26–26f: lamp sets.
    pub lamp_sets: Vec<LampSet>,
    /// Line 27: direct ratios for room indices 0.6 … 5.
    pub direct_ratios: [f64; 10],
    /// Line 28: C angles (Mc values), degrees.
    pub c_deg: Vec<f64>,
    /// Line 29: γ angles (Ng values), degrees.
    pub gamma_deg: Vec<f64>,
    /// Intensities as stored, cd/klm (or cd), `[plane * ng + ig]` for the stored planes.
    pub intensities: Vec<f64>,
    /// Non-fatal findings.
    pub warnings: Vec<String>,
}

impl LdtFile {
    /// Indices into `c_deg` of the planes the file stores, in storage order.
    ///
    /// Isym 3 (symmetric about the C90–C270 plane) stores the planes from C270 through C0 to C90:
    /// that is the reading that independent readers and paired IES exports agree on (the other
    /// reading, C90…C270, mirrors the luminaire). Pinned by tests/photometry_files.rs.
    pub fn stored_planes(&self) -> Vec<usize> {
        let mc = self.mc;
        match self.symmetry {
            0 => (0..mc).collect(),
            1 => vec![0],
            2 => (0..=mc / 2).collect(),
            3 => (3 * mc / 4..mc).chain(0..=mc / 4).collect(),
            _ => (0..=mc / 4).collect(),
        }
    }
}

/// Parses EULUMDAT text; `file` names the file in errors.
pub fn parse(text: &str, file: &str) -> Result<LdtFile, ParseError> {
    // Lines are read one at a time (a file of millions of lines costs no line table).
    let mut ls = Lines::new(text);
    let mut warnings = Vec::new();
    let mut next_line = |field: &str| -> Result<(usize, String), ParseError> {
        match ls.next() {
            Some(l) => Ok((ls.count, l.trim().to_string())),
            None => Err(parse_error(file, Some(ls.count), field, "file ends here (truncated?)")),
        }
    };
    fn num(file: &str, (line, text): (usize, String), field: &str) -> Result<f64, ParseError> {
        let t = text.replace(',', ".");
        let tok = super::text::Token { text: &t, line };
        super::text::parse_number(file, tok, field, false)
    }
    let company = next_line("company identification")?.1;
    let ityp_l = next_line("type indicator Ityp")?;
    let ityp_line = ityp_l.0;
    let type_indicator = to_count(
        file,
        ityp_line,
        "type indicator Ityp",
        num(file, ityp_l, "type indicator Ityp")?,
        0,
        3,
    )?;
    let isym_l = next_line("symmetry indicator Isym")?;
    let isym_line = isym_l.0;
    let symmetry = to_count(
        file,
        isym_line,
        "symmetry indicator Isym",
        num(file, isym_l, "symmetry indicator Isym")?,
        0,
        4,
    )? as u8;
    let mc_l = next_line("number of C planes Mc")?;
    let mc_line = mc_l.0;
    let mc = to_count(
        file,
        mc_line,
        "number of C planes Mc",
        num(file, mc_l, "number of C planes Mc")?,
        1,
        100_000,
    )? as usize;
    let dc = num(file, next_line("C plane distance Dc")?, "C plane distance Dc")?;
    let ng_l = next_line("number of intensities per plane Ng")?;
    let ng_line = ng_l.0;
    let ng = to_count(
        file,
        ng_line,
        "number of intensities per plane Ng",
        num(file, ng_l, "Ng")?,
        2,
        100_000,
    )? as usize;
    let dg = num(file, next_line("γ distance Dg")?, "γ distance Dg")?;
    let report = next_line("measurement report number")?.1;
    let luminaire_name = next_line("luminaire name")?.1;
    let luminaire_number = next_line("luminaire number")?.1;
    let file_name = next_line("file name")?.1;
    let date_user = next_line("date/user")?.1;
    let mut dims = [0.0; 9];
    let names = [
        "luminaire length/diameter (mm)",
        "luminaire width (mm)",
        "luminaire height (mm)",
        "luminous area length/diameter (mm)",
        "luminous area width (mm)",
        "luminous area height C0 (mm)",
        "luminous area height C90 (mm)",
        "luminous area height C180 (mm)",
        "luminous area height C270 (mm)",
    ];
    for (d, name) in dims.iter_mut().zip(names) {
        let l = next_line(name)?;
        let line = l.0;
        *d = num(file, l, name)?;
        if *d < 0.0 {
            return Err(parse_error(
                file,
                Some(line),
                name,
                format!("expected a size ≥ 0, found {d}"),
            ));
        }
    }
    let dff_percent = num(
        file,
        next_line("downward flux fraction DFF")?,
        "downward flux fraction DFF",
    )?;
    let lor_percent = num(file, next_line("light output ratio LORL")?, "light output ratio LORL")?;
    let cf_l = next_line("conversion factor for luminous intensities")?;
    let cf_line = cf_l.0;
    let mut conversion_factor = num(file, cf_l, "conversion factor for luminous intensities")?;
    if conversion_factor < 0.0 {
        return Err(parse_error(
            file,
            Some(cf_line),
            "conversion factor",
            format!("expected a factor > 0, found {conversion_factor}"),
        ));
    }
    if conversion_factor == 0.0 {
        warnings.push(format!("line {cf_line}: conversion factor 0 read as 1"));
        conversion_factor = 1.0;
    }
    let measurement_tilt_deg = num(file, next_line("measurement tilt")?, "measurement tilt")?;
    let nsets_l = next_line("number of lamp sets")?;
    let nsets_line = nsets_l.0;
    let nsets = to_count(
        file,
        nsets_line,
        "number of lamp sets",
        num(file, nsets_l, "number of lamp sets")?,
        1,
        20,
    )? as usize;
    let mut lamp_sets = Vec::with_capacity(nsets);
    for k in 0..nsets {
        let count = num(
            file,
            next_line(&format!("lamp set {} number of lamps", k + 1))?,
            "number of lamps",
        )?;
        let lamp_type = next_line("lamp type")?.1;
        let fl = next_line("lamp set total luminous flux")?;
        let fl_line = fl.0;
        let flux_lm = num(file, fl, "lamp set total luminous flux (lm)")?;
        if flux_lm < 0.0 {
            return Err(parse_error(
                file,
                Some(fl_line),
                "lamp set total luminous flux",
                format!("expected ≥ 0 lm, found {flux_lm}"),
            ));
        }
        let colour = next_line("colour temperature")?.1;
        let cri = next_line("colour rendering")?.1;
        let watts = num(file, next_line("wattage")?, "wattage including ballast (W)")?;
        lamp_sets.push(LampSet {
            count,
            lamp_type,
            flux_lm,
            colour,
            cri,
            watts,
        });
    }
    let rest_start = ls.count;
    let mut tokens = Tokens::new(file, ls.rest(), rest_start + 1, false);
    let mut direct_ratios = [0.0; 10];
    for d in &mut direct_ratios {
        *d = tokens.number_comma_decimal("direct ratios")?;
    }
    let mut c_deg = Vec::with_capacity(mc);
    for _ in 0..mc {
        c_deg.push(tokens.number_comma_decimal("C angles")?);
    }
    let mut gamma_deg = Vec::with_capacity(ng);
    for _ in 0..ng {
        gamma_deg.push(tokens.number_comma_decimal("γ angles")?);
    }
    let needs_div = match symmetry {
        2 => 2,
        // C270 and C90 must be planes of the file for the C270…C90 storage of Isym 3.
        3 | 4 => 4,
        _ => 1,
    };
    if symmetry > 1 && !mc.is_multiple_of(needs_div) {
        return Err(parse_error(
            file,
            Some(mc_line),
            "number of C planes Mc",
            format!("symmetry {symmetry} needs Mc divisible by {needs_div}, found {mc}"),
        ));
    }
    let mut lf = LdtFile {
        company,
        type_indicator,
        symmetry,
        mc,
        dc,
        ng,
        dg,
        report,
        luminaire_name,
        luminaire_number,
        file_name,
        date_user,
        luminaire_mm: [dims[0], dims[1], dims[2]],
        luminous_area_mm: [dims[3], dims[4]],
        luminous_heights_mm: [dims[5], dims[6], dims[7], dims[8]],
        dff_percent,
        lor_percent,
        conversion_factor,
        measurement_tilt_deg,
        lamp_sets,
        direct_ratios,
        c_deg,
        gamma_deg,
        intensities: Vec::new(),
        warnings,
    };
    let planes = lf.stored_planes().len();
    // Mc and Ng come from the file: reserve no more than the numbers left (a huge table declared
    // in a short file fails with "truncated" instead of allocating gigabytes first).
    let table_len = planes.saturating_mul(ng);
    if mc.saturating_mul(ng) > super::luminaire::MAX_TABLE_VALUES {
        return Err(parse_error(
            file,
            Some(mc_line),
            "number of C planes Mc",
            format!(
                "{mc} C planes × {ng} γ angles is more than the {} intensity values lumiview reads",
                super::luminaire::MAX_TABLE_VALUES
            ),
        ));
    }
    let mut intensities = Vec::with_capacity(table_len.min(tokens.upper_bound()));
    let mut negative: Option<(usize, f64)> = None;
    let mut negative_count = 0usize;
    for _ in 0..table_len {
        let value_line = tokens.line();
        let v = tokens.number_comma_decimal("luminous intensities").map_err(|mut e| {
            e.message = format!(
                "{} (expected {planes} planes × {ng} values for symmetry {symmetry})",
                e.message
            );
            e
        })?;
        if v < 0.0 {
            negative_count += 1;
            negative = Some(match negative {
                None => (value_line, v),
                Some((first, least)) => (first, least.min(v)),
            });
        }
        intensities.push(v.max(0.0));
    }
    if let Some((line, least)) = negative {
        lf.warnings.push(format!(
            "{negative_count} negative intensities read as 0 (the first on line {line}; the smallest {least})"
        ));
    }
    if let Some(perm) = super::web::order_angles(&mut lf.gamma_deg) {
        lf.warnings
            .push("γ angles are not in increasing order: read in increasing order".to_string());
        for plane in intensities.chunks_exact_mut(ng) {
            let old = plane.to_vec();
            for (k, &i) in perm.iter().enumerate() {
                plane[k] = old[i];
            }
        }
    }
    if tokens.has_more() {
        let line = tokens.line();
        lf.warnings.push(format!(
            "line {line}: {} values after the intensity table ignored",
            tokens.count_rest()
        ));
    }
    lf.intensities = intensities;
    Ok(lf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_table_in_a_short_file_is_an_error_not_an_allocation() {
        // Mc = Ng = 100000 (80 GB of intensities as f64), both angle lists present.
        let mut t = String::from("X\n1\n0\n100000\n0\n100000\n1\nr\nn\nn\nf\nd\n");
        t.push_str("0\n0\n0\n0\n0\n0\n0\n0\n0\n100\n100\n1\n0\n1\n1\nt\n1000\n3000\n80\n10\n");
        for _ in 0..10 {
            t.push_str("0\n");
        }
        for k in 0..2 {
            for i in 0..100_000 {
                t.push_str(&format!("{}\n", i as f64 * 0.0018 * f64::from(2 - k)));
            }
        }
        t.push_str("0\n");
        let e = parse(&t, "big.ldt").unwrap_err();
        assert!(e.message.contains("more than the 2000000 intensity values"), "{e}");
        // Within the limit (Mc = 10): the declared table is not allocated before the values are there.
        let t = t.replacen("X\n1\n0\n100000\n", "X\n1\n0\n10\n", 1);
        let e = parse(&t, "big.ldt").unwrap_err();
        assert!(
            e.field == "luminous intensities" && e.message.contains("truncated"),
            "{e}"
        );
    }

    #[test]
    fn isym3_planes_start_at_c270() {
        let mut f = LdtFile {
            company: String::new(),
            type_indicator: 1,
            symmetry: 3,
            mc: 8,
            dc: 45.0,
            ng: 2,
            dg: 90.0,
            report: String::new(),
            luminaire_name: String::new(),
            luminaire_number: String::new(),
            file_name: String::new(),
            date_user: String::new(),
            luminaire_mm: [0.0; 3],
            luminous_area_mm: [0.0; 2],
            luminous_heights_mm: [0.0; 4],
            dff_percent: 100.0,
            lor_percent: 100.0,
            conversion_factor: 1.0,
            measurement_tilt_deg: 0.0,
            lamp_sets: vec![],
            direct_ratios: [0.0; 10],
            c_deg: (0..8).map(|i| i as f64 * 45.0).collect(),
            gamma_deg: vec![0.0, 90.0],
            intensities: vec![],
            warnings: vec![],
        };
        // C270, C315, C0, C45, C90.
        assert_eq!(f.stored_planes(), vec![6, 7, 0, 1, 2]);
        f.symmetry = 4;
        assert_eq!(f.stored_planes(), vec![0, 1, 2]);
    }
}
