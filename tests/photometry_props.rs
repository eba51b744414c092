//! Property tests of the photometric web and the file readers, through the public API:
//! symmetry expansion against explicitly mirrored tables, bilinear interpolation (nodes, cells,
//! the C wrap, periodicity, the measured γ range, flux), and reader invariance under the many
//! ways one table can be written (delimiters, line breaks, number spellings, decimal commas).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;

use lumiview::photometry::web::NativeGrid;
use lumiview::photometry::{load_from_text, LoadOptions, PhotometricWeb, Photometry, Symmetry};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// Table generators
// ---------------------------------------------------------------------------------------------

/// Strictly increasing angles from `from` to exactly `to`, spaced by the relative `steps`.
fn spread(from: f64, to: f64, steps: &[f64]) -> Vec<f64> {
    let total: f64 = steps.iter().sum();
    let mut out = vec![from];
    let mut acc = 0.0;
    for (i, s) in steps.iter().enumerate() {
        acc += s;
        out.push(if i + 1 == steps.len() {
            to
        } else {
            from + (to - from) * acc / total
        });
    }
    out
}

/// γ angles: 2 to 8, strictly increasing within 0…180 (start and end random, often 0 / 90 / 180).
fn gammas() -> impl Strategy<Value = Vec<f64>> {
    let start = prop_oneof![Just(0.0), 0.0..60.0f64];
    let end = prop_oneof![Just(90.0), Just(180.0), 100.0..180.0f64];
    (start, end, prop::collection::vec(1.0..10.0f64, 1..8)).prop_map(|(s, e, steps)| spread(s, e, &steps))
}

/// Intensities (cd), with zeros mixed in; cycled to fill a table.
fn intensities() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(prop_oneof![1 => Just(0.0), 4 => 0.0..1000.0f64], 64)
}

/// A table of `nh × nv` values taken cyclically from `pool`.
fn fill(pool: &[f64], nh: usize, nv: usize) -> Vec<f64> {
    (0..nh * nv).map(|i| pool[i % pool.len()]).collect()
}

fn web_c(h: &[f64], v: &[f64], values: &[f64]) -> (PhotometricWeb, Symmetry) {
    PhotometricWeb::from_type_c(&NativeGrid {
        file: "prop",
        h,
        v,
        values,
    })
    .unwrap()
}

/// Builds an explicit full-circle table (no 360° entry) from planes given as (C, source plane),
/// C anywhere in 0…360. A missing C0 plane is interpolated across the wrap from its neighbours.
fn explicit(planes: &[(f64, usize)], nv: usize, values: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut p: Vec<(f64, Vec<f64>)> = planes
        .iter()
        .map(|&(c, i)| (c.rem_euclid(360.0), values[i * nv..(i + 1) * nv].to_vec()))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p.dedup_by(|b, a| (b.0 - a.0).abs() < 1e-9);
    if p[0].0 > 1e-9 {
        let (first, last) = (&p[0], &p[p.len() - 1]);
        let t = (360.0 - last.0) / (first.0 + 360.0 - last.0);
        let c0: Vec<f64> = (0..nv).map(|k| last.1[k] * (1.0 - t) + first.1[k] * t).collect();
        p.insert(0, (0.0, c0));
    }
    let h = p.iter().map(|x| x.0).collect();
    let vals = p.iter().flat_map(|x| x.1.iter().copied()).collect();
    (h, vals)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

/// Sample points: random (C, γ) well beyond one turn and beyond the γ range.
fn points() -> impl Strategy<Value = Vec<(f64, f64)>> {
    prop::collection::vec((-720.0..720.0f64, -10.0..190.0f64), 24)
}

fn assert_same_everywhere(a: &PhotometricWeb, b: &PhotometricWeb, pts: &[(f64, f64)]) -> Result<(), TestCaseError> {
    let nodes = b
        .c_angles()
        .iter()
        .flat_map(|&c| b.gamma_angles().iter().map(move |&g| (c, g)));
    for (c, g) in pts.iter().copied().chain(nodes) {
        let (x, y) = (a.sample(c, g), b.sample(c, g));
        prop_assert!(close(x, y), "at C {c}, γ {g}: {x} vs {y}");
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Symmetry expansion
// ---------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// 0–90 stored: the same as the table mirrored explicitly into all four quadrants, and
    /// I(C) = I(−C) = I(180° − C).
    #[test]
    fn quadrant_equals_mirrored_table(
        steps in prop::collection::vec(1.0..10.0f64, 1..6), v in gammas(), pool in intensities(), pts in points(),
    ) {
        let h = spread(0.0, 90.0, &steps);
        let vals = fill(&pool, h.len(), v.len());
        let (sym, s) = web_c(&h, &v, &vals);
        prop_assert_eq!(s, Symmetry::Quadrant);
        let planes: Vec<(f64, usize)> = h
            .iter()
            .enumerate()
            .flat_map(|(i, &c)| [(c, i), (180.0 - c, i), (180.0 + c, i), (360.0 - c, i)])
            .collect();
        let (fh, fv) = explicit(&planes, v.len(), &vals);
        let (full, s) = web_c(&fh, &v, &fv);
        prop_assert_eq!(s, Symmetry::None);
        assert_same_everywhere(&sym, &full, &pts)?;
        for &(c, g) in &pts {
            let x = sym.sample(c, g);
            prop_assert!(close(x, sym.sample(-c, g)) && close(x, sym.sample(180.0 - c, g)), "C {c}, γ {g}");
        }
        prop_assert!(close(sym.flux(), full.flux()));
    }

    /// 0–180 stored: the same as the table mirrored about the C0–C180 plane, I(C) = I(360° − C).
    #[test]
    fn c0_c180_equals_mirrored_table(
        steps in prop::collection::vec(1.0..10.0f64, 1..7), v in gammas(), pool in intensities(), pts in points(),
    ) {
        let h = spread(0.0, 180.0, &steps);
        let vals = fill(&pool, h.len(), v.len());
        let (sym, s) = web_c(&h, &v, &vals);
        prop_assert_eq!(s, Symmetry::C0C180);
        let planes: Vec<(f64, usize)> = h.iter().enumerate().flat_map(|(i, &c)| [(c, i), (360.0 - c, i)]).collect();
        let (fh, fv) = explicit(&planes, v.len(), &vals);
        let (full, _) = web_c(&fh, &v, &fv);
        assert_same_everywhere(&sym, &full, &pts)?;
        for &(c, g) in &pts {
            prop_assert!(close(sym.sample(c, g), sym.sample(360.0 - c, g)), "C {c}, γ {g}");
        }
        prop_assert!(close(sym.flux(), full.flux()));
    }

    /// 90–270 stored: the same as the table mirrored about the C90–C270 plane,
    /// I(C) = I(180° − C), whether or not C180 (whose mirror is C0) is among the stored planes.
    #[test]
    fn c90_c270_equals_mirrored_table(
        steps in prop::collection::vec(1.0..10.0f64, 1..7),
        with_c180 in any::<bool>(),
        v in gammas(),
        pool in intensities(),
        pts in points(),
    ) {
        let mut h = spread(90.0, 270.0, &steps);
        if with_c180 && !h.iter().any(|&c| (c - 180.0).abs() < 0.5) {
            h.push(180.0);
            h.sort_by(f64::total_cmp);
        }
        let vals = fill(&pool, h.len(), v.len());
        let (sym, s) = web_c(&h, &v, &vals);
        prop_assert_eq!(s, Symmetry::C90C270);
        let planes: Vec<(f64, usize)> = h.iter().enumerate().flat_map(|(i, &c)| [(c, i), (180.0 - c, i)]).collect();
        let (fh, fv) = explicit(&planes, v.len(), &vals);
        let (full, _) = web_c(&fh, &v, &fv);
        assert_same_everywhere(&sym, &full, &pts)?;
        for &(c, g) in &pts {
            prop_assert!(close(sym.sample(c, g), sym.sample(180.0 - c, g)), "C {c}, γ {g}");
        }
        prop_assert!(close(sym.flux(), full.flux()));
    }

    /// One stored plane (at any C): the same in every direction as a full table of copies.
    #[test]
    fn rotational_equals_copied_planes(
        at in 0.0..360.0f64, copies in 2usize..7, v in gammas(), pool in intensities(), pts in points(),
    ) {
        let vals = fill(&pool, 1, v.len());
        let (sym, s) = web_c(&[at], &v, &vals);
        prop_assert_eq!(s, Symmetry::Rotational);
        let fh: Vec<f64> = (0..copies).map(|i| 360.0 * i as f64 / copies as f64).collect();
        let fv: Vec<f64> = (0..copies).flat_map(|_| vals.iter().copied()).collect();
        let (full, _) = web_c(&fh, &v, &fv);
        assert_same_everywhere(&sym, &full, &pts)?;
        for &(c, g) in &pts {
            prop_assert!(close(sym.sample(c, g), sym.sample(0.0, g)), "C {c}, γ {g}");
        }
    }

    /// 0–360: a table without the 360° entry equals the same table with C360 = C0 appended.
    #[test]
    fn full_circle_with_and_without_360(
        last in 181.0..359.0f64,
        steps in prop::collection::vec(1.0..10.0f64, 1..8),
        v in gammas(),
        pool in intensities(),
        pts in points(),
    ) {
        let h = spread(0.0, last, &steps);
        let vals = fill(&pool, h.len(), v.len());
        let (open, s) = web_c(&h, &v, &vals);
        prop_assert_eq!(s, Symmetry::None);
        let mut h360 = h.clone();
        h360.push(360.0);
        let mut vals360 = vals.clone();
        vals360.extend_from_slice(&vals[..v.len()]);
        let (closed, s) = web_c(&h360, &v, &vals360);
        prop_assert_eq!(s, Symmetry::None);
        prop_assert_eq!(open.c_angles(), closed.c_angles());
        assert_same_everywhere(&open, &closed, &pts)?;
        prop_assert!(close(open.flux(), closed.flux()));
    }
}

// ---------------------------------------------------------------------------------------------
// Interpolation
// ---------------------------------------------------------------------------------------------

/// A random full-circle web (0–360 without the 360° entry, expanded by `from_type_c`).
fn full_web() -> impl Strategy<Value = PhotometricWeb> {
    (
        181.0..359.0f64,
        prop::collection::vec(1.0..10.0f64, 1..8),
        gammas(),
        intensities(),
    )
        .prop_map(|(last, steps, v, pool)| {
            let h = spread(0.0, last, &steps);
            let vals = fill(&pool, h.len(), v.len());
            web_c(&h, &v, &vals).0
        })
}

/// Index of the grid cell holding `x` in increasing `a` (the last cell for the end point).
fn cell(a: &[f64], x: f64) -> usize {
    a.partition_point(|&v| v <= x).clamp(1, a.len() - 1) - 1
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// At every grid node `sample` returns the node's value.
    #[test]
    fn nodes_return_node_values(web in full_web()) {
        let (cs, gs, vals) = (web.c_angles(), web.gamma_angles(), web.values());
        for (i, &c) in cs.iter().enumerate() {
            for (j, &g) in gs.iter().enumerate() {
                let want = vals[i * gs.len() + j];
                prop_assert!(close(web.sample(c, g), want), "node C {c}, γ {g}: {} vs {want}", web.sample(c, g));
            }
        }
    }

    /// Inside a cell the value lies between the smallest and largest of its four corners.
    #[test]
    fn cells_stay_within_their_corners(web in full_web(), fr in prop::collection::vec((0.0..1.0f64, 0.0..1.0f64), 16)) {
        let (cs, gs, vals) = (web.c_angles(), web.gamma_angles(), web.values());
        let (g0, g1) = web.gamma_range();
        for (fc, fg) in fr {
            let (c, g) = (fc * 360.0, g0 + fg * (g1 - g0));
            let (i, j) = (cell(cs, c), cell(gs, g));
            let ng = gs.len();
            let corners = [vals[i * ng + j], vals[i * ng + j + 1], vals[(i + 1) * ng + j], vals[(i + 1) * ng + j + 1]];
            let lo = corners.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = corners.iter().copied().fold(0.0, f64::max);
            let s = web.sample(c, g);
            prop_assert!(s >= lo - 1e-9 * hi && s <= hi * (1.0 + 1e-12), "C {c}, γ {g}: {s} outside {lo}…{hi}");
        }
    }

    /// Continuous across the C wrap: C = 360 − ε, C = ε and C = 0 agree to within the slope × ε.
    #[test]
    fn continuous_across_the_wrap(web in full_web(), fg in prop::collection::vec(0.0..1.0f64, 8)) {
        let (g0, g1) = web.gamma_range();
        let max = web.max_intensity().0;
        let eps = 1e-9;
        for f in fg {
            let g = g0 + f * (g1 - g0);
            let at0 = web.sample(0.0, g);
            for c in [360.0 - eps, eps, 360.0, -eps] {
                let x = web.sample(c, g);
                prop_assert!((x - at0).abs() <= 1e-6 * max + 1e-12, "γ {g}: C {c} gives {x}, C 0 gives {at0}");
            }
        }
    }

    /// Periodic in C: sample(C) = sample(C + 360) = sample(C − 360).
    #[test]
    fn periodic_in_c(web in full_web(), pts in points()) {
        let max = web.max_intensity().0;
        for (c, g) in pts {
            let x = web.sample(c, g);
            for y in [web.sample(c + 360.0, g), web.sample(c - 360.0, g)] {
                prop_assert!((x - y).abs() <= 1e-9 * (1.0 + max), "C {c}, γ {g}: {x} vs {y}");
            }
        }
    }

    /// Zero outside the measured γ range (beyond the angle tolerance), and never negative or NaN,
    /// including at non-finite angles.
    #[test]
    fn zero_outside_the_measured_gamma_range(web in full_web(), c in -720.0..720.0f64, d in 1e-5..90.0f64) {
        let (g0, g1) = web.gamma_range();
        prop_assert_eq!(web.sample(c, g0 - d), 0.0);
        prop_assert_eq!(web.sample(c, g1 + d), 0.0);
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            prop_assert_eq!(web.sample(x, g0), 0.0);
            prop_assert_eq!(web.sample(c, x), 0.0);
        }
        let s = web.sample(c, 0.5 * (g0 + g1));
        prop_assert!(s.is_finite() && s >= 0.0);
    }

    /// A constant intensity I over γ ∈ [a, b] carries exactly I · 2π (cos a − cos b), whatever the
    /// grid: expanded from any symmetric range, or given whole to `from_grid`.
    #[test]
    fn flux_of_a_constant_intensity(
        i in 0.1..1e4f64,
        kind in 0usize..5,
        steps in prop::collection::vec(1.0..10.0f64, 1..7),
        v in gammas(),
    ) {
        let h = match kind {
            0 => vec![33.0],
            1 => spread(0.0, 90.0, &steps),
            2 => spread(0.0, 180.0, &steps),
            3 => spread(90.0, 270.0, &steps),
            _ => spread(0.0, 300.0, &steps),
        };
        let vals = vec![i; h.len() * v.len()];
        let (web, _) = web_c(&h, &v, &vals);
        let (a, b) = (v[0].to_radians(), v[v.len() - 1].to_radians());
        let want = i * 2.0 * PI * (a.cos() - b.cos());
        prop_assert!(close(web.flux(), want), "{} vs {want}", web.flux());
        let mut c = spread(0.0, 360.0, &steps);
        c.dedup();
        let grid = PhotometricWeb::from_grid(c.clone(), v.clone(), vec![i; c.len() * v.len()]).unwrap();
        prop_assert!(close(grid.flux(), want), "{} vs {want}", grid.flux());
        // The downward part of it: γ ∈ [a, b] ∩ [0, 90].
        let (da, db) = (a, b.min(PI / 2.0));
        let down = if db > da { i * 2.0 * PI * (da.cos() - db.cos()) } else { 0.0 };
        prop_assert!(close(web.flux_between(0.0, 90.0), down), "{} vs {down}", web.flux_between(0.0, 90.0));
    }
}

/// Solid angle of the γ band [a, b] (degrees) over the whole C circle, without cancellation.
fn band(a: f64, b: f64) -> f64 {
    4.0 * PI * (0.5 * (a + b)).to_radians().sin() * (0.5 * (b - a)).to_radians().sin()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Flux is additive over γ and bounded by the smallest and largest intensity times the solid
    /// angle of the measured band.
    #[test]
    fn flux_is_additive_and_bounded(web in full_web(), split in 0.0..180.0f64) {
        let (g0, g1) = web.gamma_range();
        let (lo, hi) = (web.flux_between(0.0, split), web.flux_between(split, 180.0));
        prop_assert!(lo >= 0.0 && hi >= 0.0, "{lo}, {hi}");
        prop_assert!(close(lo + hi, web.flux()), "{} + {} vs {}", lo, hi, web.flux());
        let min = web.values().iter().copied().fold(f64::INFINITY, f64::min);
        let max = web.max_intensity().0;
        let omega = band(g0, g1);
        prop_assert!(web.flux() >= min * omega * (1.0 - 1e-9) && web.flux() <= max * omega * (1.0 + 1e-9));
    }

    /// Cells down to 1e-12° wide, anywhere in γ: the flux stays within min·Ω … max·Ω (in
    /// particular finite and ≥ 0); the textbook integral loses every digit there.
    #[test]
    fn flux_of_fine_gamma_cells(g in 0.0..179.0f64, exp in -12.0..-1.0f64, a in 0.0..1000.0f64, b in 0.0..1000.0f64) {
        let v = [g, g + 10f64.powf(exp)];
        prop_assume!(v[1] > v[0]);
        let (web, _) = web_c(&[0.0], &v, &[a, b]);
        let omega = band(v[0], v[1]);
        let f = web.flux();
        prop_assert!(f >= a.min(b) * omega * (1.0 - 1e-6) && f <= a.max(b) * omega * (1.0 + 1e-6), "{f} vs Ω {omega}");
    }
}

// ---------------------------------------------------------------------------------------------
// Readers: one table, many spellings
// ---------------------------------------------------------------------------------------------

/// Random choices consumed in order (cycled): how each number is spelled and what follows it.
#[derive(Debug, Clone)]
struct Spelling {
    picks: Vec<u8>,
    next: usize,
}

impl Spelling {
    fn pick(&mut self, n: u8) -> u8 {
        let p = self.picks[self.next % self.picks.len()] % n;
        self.next += 1;
        p
    }
}

fn spellings() -> impl Strategy<Value = Spelling> {
    prop::collection::vec(any::<u8>(), 1..256).prop_map(|picks| Spelling { picks, next: 0 })
}

/// One way of writing `x` that parses back to exactly `x`.
fn spell(x: f64, s: &mut Spelling, decimal_comma: bool) -> String {
    let mut t = match s.pick(4) {
        0 => format!("{x}"),
        1 => format!("{x:e}"),
        2 => format!("{x:E}"),
        _ if x.fract() == 0.0 && x.abs() < 1e15 => format!("{x:.1}"),
        _ => format!("{x}"),
    };
    if x >= 0.0 && s.pick(4) == 0 {
        t.insert(0, '+');
    }
    if decimal_comma && s.pick(2) == 0 {
        t = t.replace('.', ",");
    }
    t
}

/// IES: the data after TILT as records of numbers.
#[derive(Debug, Clone)]
struct IesTable {
    tilt: Option<(f64, Vec<f64>, Vec<f64>)>,
    line10: [f64; 10],
    line11: [f64; 3],
    v: Vec<f64>,
    h: Vec<f64>,
    cd: Vec<f64>,
}

impl IesTable {
    fn records(&self) -> Vec<Vec<f64>> {
        let mut r = Vec::new();
        if let Some((geometry, angles, factors)) = &self.tilt {
            r.push(vec![*geometry]);
            r.push(vec![angles.len() as f64]);
            r.push(angles.clone());
            r.push(factors.clone());
        }
        r.push(self.line10.to_vec());
        r.push(self.line11.to_vec());
        r.push(self.v.clone());
        r.push(self.h.clone());
        r.extend(self.cd.chunks(self.v.len()).map(<[f64]>::to_vec));
        r
    }

    fn header(&self) -> &'static str {
        "IESNA:LM-63-2002\n[TEST] property test\n[MANUFAC] lumiview, Inc.\n[MORE] second line\n"
    }

    fn tilt_line(&self) -> &'static str {
        if self.tilt.is_some() {
            "TILT=INCLUDE"
        } else {
            "TILT=NONE"
        }
    }

    /// One record a line, single spaces, LF.
    fn canonical(&self) -> String {
        let mut t = format!("{}{}\n", self.header(), self.tilt_line());
        for r in self.records() {
            let line: Vec<String> = r.iter().map(|x| format!("{x}")).collect();
            t.push_str(&line.join(" "));
            t.push('\n');
        }
        t
    }

    /// Random delimiters (spaces, tabs, commas, line ends; records split or shared), random number
    /// spellings and the given line terminator.
    fn scrambled(&self, s: &mut Spelling, eol: &str) -> String {
        const SEPS: [&str; 10] = [" ", "  ", "\t", ",", ", ", " ,", "\n", ",\n", " \n\t", "\n\n"];
        let mut t = format!("{}{}\n", self.header(), self.tilt_line());
        for x in self.records().concat() {
            t.push_str(&spell(x, s, false));
            t.push_str(SEPS[s.pick(SEPS.len() as u8) as usize]);
        }
        t.replace('\n', eol)
    }
}

fn ies_tables() -> impl Strategy<Value = IesTable> {
    let tilt = prop::option::of((1u8..4, prop::collection::vec(1.0..20.0f64, 1..6), 0.0..2.0f64));
    (
        tilt,
        (
            0u8..4,
            100.0..1e5f64,
            0.01..100.0f64,
            1u8..3,
            -1.0..1.0f64,
            -1.0..1.0f64,
            -1.0..1.0f64,
        ),
        (0.1..2.0f64, 0.1..2.0f64, 0.0..500.0f64),
        (0usize..5, prop::collection::vec(1.0..10.0f64, 1..6)),
        gammas(),
        intensities(),
    )
        .prop_map(
            |(tilt, (lamps, lumens, mult, units, w, l, ht), (bf, blp, watts), (kind, steps), v, pool)| {
                let h = match kind {
                    0 => vec![0.0],
                    1 => spread(0.0, 90.0, &steps),
                    2 => spread(0.0, 180.0, &steps),
                    3 => spread(90.0, 270.0, &steps),
                    _ => spread(0.0, 360.0, &steps),
                };
                let tilt = tilt.map(|(g, steps, f)| {
                    let angles = spread(0.0, 90.0, &steps);
                    let factors = angles.iter().map(|a| f * (1.0 - a / 180.0)).collect();
                    (f64::from(g), angles, factors)
                });
                let lumens = if lamps == 0 { -1.0 } else { lumens };
                IesTable {
                    tilt,
                    line10: [
                        f64::from(lamps.max(1)),
                        lumens,
                        mult,
                        v.len() as f64,
                        h.len() as f64,
                        1.0,
                        f64::from(units),
                        w,
                        l,
                        ht,
                    ],
                    line11: [bf, blp, watts],
                    cd: fill(&pool, h.len(), v.len()),
                    v,
                    h,
                }
            },
        )
}

fn load(text: &str, name: &str) -> Photometry {
    load_from_text(text, name, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}\n---\n{text}"))
}

/// EULUMDAT: the fields written one a line, then the angle and intensity tables.
#[derive(Debug, Clone)]
struct LdtTable {
    isym: u8,
    mc: usize,
    gamma: Vec<f64>,
    header_numbers: [f64; 12],
    sets: Vec<[f64; 3]>,
    direct_ratios: [f64; 10],
    intensities: Vec<f64>,
}

impl LdtTable {
    fn c_angles(&self) -> Vec<f64> {
        (0..self.mc).map(|i| 360.0 * i as f64 / self.mc as f64).collect()
    }

    /// The canonical text with `s` = `None`: one value a line, decimal points.
    fn write(&self, mut s: Option<&mut Spelling>, eol: &str) -> String {
        fn num(x: f64, s: &mut Option<&mut Spelling>) -> String {
            match s.as_deref_mut() {
                Some(sp) => spell(x, sp, true),
                None => format!("{x}"),
            }
        }
        let s = &mut s;
        let n = &self.header_numbers;
        let mut lines: Vec<String> = vec![
            "lumiview property test".into(),
            num(1.0, s),
            num(f64::from(self.isym), s),
            num(self.mc as f64, s),
            num(360.0 / self.mc as f64, s),
            num(self.gamma.len() as f64, s),
            num(self.gamma[1] - self.gamma[0], s),
            "REPORT-1".into(),
            "Luminaire".into(),
            "L-1".into(),
            "prop.ldt".into(),
            "2024-01-01 nobody".into(),
        ];
        lines.extend(n.iter().map(|&x| num(x, s)));
        lines.push(num(0.0, s)); // measurement tilt
        lines.push(num(self.sets.len() as f64, s));
        for set in &self.sets {
            lines.push(num(set[0], s));
            lines.push("LED".into());
            lines.push(num(set[1], s));
            lines.push("3000 K".into());
            lines.push("80".into());
            lines.push(num(set[2], s));
        }
        let mut t = lines.join("\n");
        t.push('\n');
        // The numeric tables: one value a line in the canonical form, any whitespace otherwise.
        let tables: Vec<f64> = self
            .direct_ratios
            .iter()
            .chain(&self.c_angles())
            .chain(&self.gamma)
            .chain(&self.intensities)
            .copied()
            .collect();
        const SEPS: [&str; 5] = ["\n", " ", "\t", "  \n", "\n\n"];
        for x in tables {
            let sep = match s.as_deref_mut() {
                Some(sp) => SEPS[sp.pick(SEPS.len() as u8) as usize],
                None => "\n",
            };
            t.push_str(&num(x, s));
            t.push_str(sep);
        }
        t.replace('\n', eol)
    }
}

fn ldt_tables() -> impl Strategy<Value = LdtTable> {
    (
        0u8..5,
        1usize..4,
        gammas(),
        prop::collection::vec(0.0..2000.0f64, 12),
        prop::collection::vec((prop_oneof![Just(-1.0), 1.0..4.0f64], 0.0..1e5f64, 0.0..500.0f64), 1..3),
        prop::collection::vec(0.0..1.0f64, 10),
        intensities(),
    )
        .prop_map(|(isym, k, gamma, mut head, sets, dr, pool)| {
            let mc = match isym {
                0 | 1 => k * 6,
                _ => k * 4,
            };
            let planes = match isym {
                0 => mc,
                1 => 1,
                2 | 3 => mc / 2 + 1,
                _ => mc / 4 + 1,
            };
            head[11] = head[11].max(1.0); // conversion factor: 0 would be read as 1
            LdtTable {
                isym,
                mc,
                header_numbers: head.try_into().unwrap(),
                sets: sets.into_iter().map(|(c, f, w)| [c.round(), f, w]).collect(),
                direct_ratios: dr.try_into().unwrap(),
                intensities: fill(&pool, planes, gamma.len()),
                gamma,
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// An IES table reads to exactly its values, and every scrambled spelling of it reads to the
    /// same file and the same photometry as the canonical text.
    #[test]
    fn ies_reads_the_same_however_written(table in ies_tables(), mut s in spellings(), eol in 0usize..3) {
        let canonical = table.canonical();
        let p = load(&canonical, "prop.ies");
        let lumiview::photometry::luminaire::RawFile::Ies(f) = &p.raw else {
            panic!("not read as IES");
        };
        prop_assert_eq!(&f.vertical_deg, &table.v);
        prop_assert_eq!(&f.horizontal_deg, &table.h);
        prop_assert_eq!(&f.candela, &table.cd);
        prop_assert_eq!(f.multiplier, table.line10[2]);
        prop_assert_eq!([f.width, f.length, f.height], [table.line10[7], table.line10[8], table.line10[9]]);
        prop_assert_eq!(f.input_watts, table.line11[2]);
        prop_assert_eq!(f.tilt.as_ref().map(|t| t.factors.clone()), table.tilt.as_ref().map(|t| t.2.clone()));
        let scrambled = table.scrambled(&mut s, ["\n", "\r\n", "\r"][eol]);
        let q = load(&scrambled, "prop.ies");
        // Warnings cite line numbers, which the scrambled layout moves; everything else must match.
        let without_warnings = |mut ph: lumiview::photometry::Photometry| {
            ph.warnings.clear();
            if let lumiview::photometry::luminaire::RawFile::Ies(f) = &mut ph.raw {
                f.warnings.clear();
            }
            ph
        };
        prop_assert_eq!(p.warnings.len(), q.warnings.len());
        prop_assert_eq!(without_warnings(p), without_warnings(q), "scrambled text:\n{:?}", scrambled);
    }

    /// A EULUMDAT table reads to exactly its values, and the same table written with decimal
    /// commas or points, other whitespace in the tables and CRLF reads to the same photometry.
    #[test]
    fn ldt_reads_the_same_however_written(table in ldt_tables(), mut s in spellings(), crlf in any::<bool>()) {
        let canonical = table.write(None, "\n");
        let p = load(&canonical, "prop.ldt");
        let lumiview::photometry::luminaire::RawFile::Ldt(f) = &p.raw else {
            panic!("not read as EULUMDAT");
        };
        prop_assert_eq!(&f.gamma_deg, &table.gamma);
        prop_assert_eq!(&f.c_deg, &table.c_angles());
        prop_assert_eq!(&f.intensities, &table.intensities);
        prop_assert_eq!(f.direct_ratios, table.direct_ratios);
        prop_assert_eq!(f.lamp_sets.len(), table.sets.len());
        prop_assert_eq!(f.lamp_sets[0].flux_lm, table.sets[0][1]);
        prop_assert_eq!(f.conversion_factor, table.header_numbers[11]);
        let scrambled = table.write(Some(&mut s), if crlf { "\r\n" } else { "\n" });
        let q = load(&scrambled, "prop.ldt");
        prop_assert_eq!(&p, &q, "scrambled text:\n{:?}", scrambled);
    }
}
