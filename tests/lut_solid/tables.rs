//! Look-up tables: 2-D texels equal to the web at the documented angles and through the shader's
//! mapping, 1-D tables the true C average, normalisation, the f16 and u8 encodings within their
//! stated error, and bad arguments as errors.

use lumiview::photometry::lut::{
    self, c_mean, decode_u8, u_1d, uv_2d, EncodedLut, Lut, LutEncoding, LutKind, LutTexels, F16_MAX_REL_ERROR,
    F16_MAX_SUBNORMAL_ERROR, U8_MAX_ABS_ERROR,
};
use lumiview::photometry::web::direction;
use lumiview::photometry::{PhotometricWeb, PhotometryError};

use crate::common::{fixtures, open, ASA, BEGA};

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Brute-force mean over the C circle: many evenly spaced planes (a prime count, so no alignment
/// with the file's planes).
fn brute_c_mean(web: &PhotometricWeb, gamma_deg: f64) -> f64 {
    let m = 10_007;
    (0..m)
        .map(|k| web.sample(360.0 * (k as f64 + 0.5) / m as f64, gamma_deg))
        .sum::<f64>()
        / m as f64
}

#[test]
fn lut_2d_texels_equal_web_at_documented_angles() {
    for f in fixtures() {
        let p = open(&f);
        for (w, h) in [(37, 19), (360, 181), (1, 2), (64, 33)] {
            let t = Lut::new_2d(&p.web, w, h, false).unwrap();
            assert_eq!((t.width(), t.height(), t.kind()), (w, h, LutKind::Table2d));
            assert_eq!(t.values().len(), w * h);
            for j in 0..h {
                for i in 0..w {
                    let c = 360.0 * i as f64 / w as f64;
                    let g = 180.0 * j as f64 / (h - 1) as f64;
                    let expect = p.web.sample(c, g);
                    let got = t.values()[j * w + i];
                    assert!(
                        (got - expect).abs() <= 1e-12 * expect.max(1.0),
                        "{f} {w}x{h} ({i},{j}): {got} vs {expect}"
                    );
                    assert_eq!(t.texel(i, j), Some(got));
                }
            }
            assert_eq!(t.texel(w, 0), None);
        }
    }
}

#[test]
fn lut_2d_shader_mapping_reproduces_the_web() {
    // The documented (u, v) with emulated bilinear REPEAT/CLAMP filtering, at random directions,
    // against the web; away from the γ cut-off of the measured range where the web jumps to 0.
    for f in [ASA, BEGA, "tests/data/photometric-viewer/ldt/no_symmetry.ldt"] {
        let p = open(f);
        let (max, _, _) = p.web.max_intensity();
        let (_, g1) = p.web.gamma_range();
        let t = Lut::new_2d(&p.web, 720, 361, false).unwrap();
        let mut rng = Lcg(7);
        for _ in 0..20_000 {
            let c = 360.0 * rng.next();
            let g = (2.0 * rng.next() - 1.0).acos().to_degrees();
            if (g - g1).abs() < 1.0 {
                continue;
            }
            let d = direction(c, g);
            let got = t.sample_dir(d);
            let expect = p.web.sample(c, g);
            assert!((got - expect).abs() <= 0.01 * max, "{f} C {c} γ {g}: {got} vs {expect}");
        }
        // At texel centres the shader path returns the texel itself.
        for (i, j) in [(0, 5), (100, 200), (719, 360), (359, 1)] {
            let (c, g) = lut::texel_angles_2d(i, j, 720, 361);
            let [u, v] = uv_2d(direction(c, g), 720, 361);
            assert!((t.sample_uv(u, v) - t.texel(i, j).unwrap()).abs() < 1e-6 * max);
        }
    }
}

#[test]
fn lut_1d_is_the_true_c_average() {
    for f in fixtures() {
        let p = open(&f);
        let (max, _, _) = p.web.max_intensity();
        let n = 257;
        let t = Lut::new_1d(&p.web, n, false).unwrap();
        assert_eq!((t.width(), t.height(), t.kind()), (n, 1, LutKind::Table1d));
        for i in 0..n {
            let cos_g = 1.0 - 2.0 * i as f64 / (n - 1) as f64;
            let g = cos_g.clamp(-1.0, 1.0).acos().to_degrees();
            let brute = brute_c_mean(&p.web, g);
            let got = t.values()[i];
            assert!(
                (got - brute).abs() <= 1e-4 * max,
                "{f} texel {i} (γ {g}): {got} vs brute {brute}"
            );
            assert!((got - c_mean(&p.web, g)).abs() <= 1e-12 * max);
        }
        // Nadir and zenith are texel centres 0 and N − 1; the shader coordinate needs no acos.
        assert!((u_1d([0.0, 0.0, -1.0], n) - 0.5 / n as f64).abs() < 1e-15);
        assert!((u_1d([0.0, 0.0, 1.0], n) - (n as f64 - 0.5) / n as f64).abs() < 1e-15);
        assert!((t.sample_dir([0.0, 0.0, -1.0]) - t.values()[0]).abs() < 1e-9 * max);
    }
}

#[test]
fn lut_1d_differs_from_a_few_planes_for_asymmetric_files() {
    // The C-average is not the mean of C0/C90/C180/C270 for a C0–C180-symmetric street light.
    let p = open(ASA);
    let g = 60.0;
    let four = [0.0, 90.0, 180.0, 270.0]
        .iter()
        .map(|&c| p.web.sample(c, g))
        .sum::<f64>()
        / 4.0;
    let mean = c_mean(&p.web, g);
    assert!((mean - brute_c_mean(&p.web, g)).abs() < 1e-4 * mean);
    assert!((mean - four).abs() > 1e-3 * mean, "{mean} vs {four}");
}

#[test]
fn normalised_tables_peak_at_one_and_keep_the_maximum() {
    for f in fixtures() {
        let p = open(&f);
        for kind in [LutKind::Table2d, LutKind::Table1d] {
            let make = |norm| match kind {
                LutKind::Table2d => Lut::new_2d(&p.web, 90, 46, norm).unwrap(),
                LutKind::Table1d => Lut::new_1d(&p.web, 128, norm).unwrap(),
            };
            let (abs, rel) = (make(false), make(true));
            assert!(rel.normalized() && !abs.normalized());
            let peak = rel.values().iter().copied().fold(0.0, f64::max);
            assert_eq!(peak, 1.0, "{f} {kind:?}");
            assert_eq!(rel.max_cd(), abs.max_cd());
            assert_eq!(abs.max_cd(), abs.values().iter().copied().fold(0.0, f64::max));
            assert!(abs.max_cd() <= p.web.max_intensity().0 * (1.0 + 1e-12));
            for (a, r) in abs.values().iter().zip(rel.values()) {
                assert!((r * rel.max_cd() - a).abs() <= 1e-12 * abs.max_cd());
            }
        }
        // The 2D table holds the web's peak when the grid passes through it (1° grid, integer-degree peaks).
        let t = Lut::new_2d(&p.web, 360, 181, false).unwrap();
        let (peak, c, g) = p.web.max_intensity();
        if c.fract() == 0.0 && g.fract() == 0.0 {
            assert!(
                (t.max_cd() - peak).abs() <= 1e-12 * peak,
                "{f}: {} vs {peak}",
                t.max_cd()
            );
        }
    }
}

fn check_f16(enc: &EncodedLut, src: &Lut) {
    assert_eq!(enc.encoding(), LutEncoding::F16);
    for (d, x) in enc.decode().iter().zip(src.values()) {
        let bound = (F16_MAX_REL_ERROR * x.abs()).max(F16_MAX_SUBNORMAL_ERROR);
        assert!((d - x).abs() <= bound, "{d} vs {x}");
    }
}

#[test]
fn f16_decodes_within_its_error() {
    for f in fixtures() {
        let p = open(&f);
        for norm in [true, false] {
            let t = Lut::new_2d(&p.web, 72, 37, norm).unwrap();
            check_f16(&t.encode(LutEncoding::F16).unwrap(), &t);
            let t = Lut::new_1d(&p.web, 200, norm).unwrap();
            let e = t.encode(LutEncoding::F16).unwrap();
            check_f16(&e, &t);
            assert_eq!(e.normalized(), norm);
        }
    }
    // Absolute tables above 65504 cd cannot be half floats: an error, not infinity.
    let web = PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 90.0], vec![1e5, 0.0, 1e5, 0.0]).unwrap();
    let t = Lut::new_2d(&web, 4, 4, false).unwrap();
    assert!(matches!(
        t.encode(LutEncoding::F16),
        Err(PhotometryError::InvalidArgument { .. })
    ));
}

#[test]
fn u8_decodes_within_its_error() {
    for f in fixtures() {
        let p = open(&f);
        for norm in [true, false] {
            let t = Lut::new_2d(&p.web, 72, 37, norm).unwrap();
            let e = t.encode(LutEncoding::U8).unwrap();
            assert!(e.normalized(), "8-bit tables are always normalised");
            assert_eq!(e.max_cd(), t.max_cd());
            let abs: Vec<f64> = if norm {
                t.values().iter().map(|v| v * t.max_cd()).collect()
            } else {
                t.values().to_vec()
            };
            let LutTexels::U8(bytes) = e.texels() else {
                panic!("not u8")
            };
            for ((d, x), &b) in e.decode_cd().iter().zip(&abs).zip(bytes) {
                assert!((d - x).abs() <= U8_MAX_ABS_ERROR * t.max_cd(), "{f}: {d} vs {x}");
                // The packing itself: byte = round(255·(I/Imax)^(1/2.2)).
                assert_eq!(b, (255.0 * (x / t.max_cd()).powf(1.0 / 2.2)).round() as u8);
                assert_eq!(*d, decode_u8(b, t.max_cd()));
            }
            assert!(bytes.contains(&255));
        }
    }
}

#[test]
fn bad_arguments_are_errors_not_panics() {
    let p = open(BEGA);
    let bad = |r: Result<Lut, PhotometryError>| matches!(r, Err(PhotometryError::InvalidArgument { .. }));
    assert!(bad(Lut::new_2d(&p.web, 0, 10, false)));
    assert!(bad(Lut::new_2d(&p.web, 10, 0, false)));
    assert!(bad(Lut::new_2d(&p.web, 10, 1, false)));
    assert!(bad(Lut::new_2d(&p.web, 16385, 2, false)));
    assert!(bad(Lut::new_2d(&p.web, 2, 16385, false)));
    assert!(bad(Lut::new_2d(&p.web, 16384, 16384, false)));
    assert!(bad(Lut::new_2d(&p.web, usize::MAX, usize::MAX, false)));
    assert!(bad(Lut::new_1d(&p.web, 0, false)));
    assert!(bad(Lut::new_1d(&p.web, 1, false)));
    assert!(bad(Lut::new_1d(&p.web, 16385, true)));
    let zero = PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 180.0], vec![0.0; 4]).unwrap();
    assert!(bad(Lut::new_1d(&zero, 16, true)));
    let t = Lut::new_1d(&zero, 16, false).unwrap();
    assert!(t.encode(LutEncoding::U8).is_err());
    assert_eq!(t.encode(LutEncoding::F32).unwrap().decode(), vec![0.0; 16]);
    // Wrong container for the encoding.
    let t = Lut::new_1d(&p.web, 16, true).unwrap();
    assert!(t.encode(LutEncoding::U8).unwrap().to_exr().is_err());
    assert!(t.encode(LutEncoding::F32).unwrap().to_png().is_err());
}
