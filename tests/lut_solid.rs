//! Host-lighting look-up tables and the photometric solid: values against the web, encodings
//! within their stated error, files read back with the exr/png/gltf crates, mesh topology, and
//! the `lumiview lut` / `lumiview solid` commands.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::process::Command;

use exr::prelude::{ReadChannels, ReadLayers};

use lumiview::photometry::lut::{
    self, c_mean, decode_u8, u_1d, uv_2d, EncodedLut, Lut, LutEncoding, LutKind, LutTexels, F16_MAX_REL_ERROR,
    F16_MAX_SUBNORMAL_ERROR, U8_MAX_ABS_ERROR,
};
use lumiview::photometry::solid::{to_gltf_axes, PhotometricSolid, SolidOptions};
use lumiview::photometry::web::direction;
use lumiview::photometry::{load, LoadOptions, PhotometricWeb, Photometry, PhotometryError};

const ASA: &str = "tests/data/misc/luxcore_ASA_15M_R2.ies";
const BEGA: &str = "tests/data/misc/arnold-usd_bega_50804K3.ies";

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn open(rel: &str) -> Photometry {
    load(&data(rel), &LoadOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Every fixture: the two real files and the photometric-viewer set.
fn fixtures() -> Vec<String> {
    let mut out = vec![ASA.to_string(), BEGA.to_string()];
    for dir in [
        "tests/data/photometric-viewer/ies95",
        "tests/data/photometric-viewer/ldt",
    ] {
        let mut names: Vec<String> = std::fs::read_dir(data(dir))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".ies") || n.ends_with(".ldt"))
            .collect();
        names.sort();
        out.extend(names.into_iter().map(|n| format!("{dir}/{n}")));
    }
    assert!(out.len() > 30, "fixtures missing: {out:?}");
    out
}

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("lut_solid_{name}"))
}

fn lumiview(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

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

// ---------------------------------------------------------------------------------------------
// Look-up tables
// ---------------------------------------------------------------------------------------------

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

type ExrSingleLayer = exr::prelude::Image<exr::prelude::Layer<exr::prelude::AnyChannels<exr::prelude::FlatSamples>>>;

fn exr_text(img: &ExrSingleLayer, key: &str) -> String {
    match img.layer_data.attributes.other.get(&exr::prelude::Text::from(key)) {
        Some(exr::prelude::AttributeValue::Text(t)) => t.to_string(),
        other => panic!("{key}: {other:?}"),
    }
}

fn read_exr_single(bytes: &[u8]) -> ExrSingleLayer {
    exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes.to_vec()))
        .unwrap()
}

fn check_exr(bytes: &[u8], enc: &EncodedLut) {
    let img = read_exr_single(bytes);
    let layer = &img.layer_data;
    assert_eq!((layer.size.0, layer.size.1), (enc.width(), enc.height()));
    assert_eq!(layer.channel_data.list.len(), 1);
    let ch = &layer.channel_data.list[0];
    assert_eq!(ch.name.to_string(), "Y");
    match (&ch.sample_data, enc.texels()) {
        (exr::prelude::FlatSamples::F32(a), LutTexels::F32(b)) => assert_eq!(a, b),
        (exr::prelude::FlatSamples::F16(a), LutTexels::F16(b)) => assert_eq!(a, b),
        (a, _) => panic!("unexpected sample type {a:?}"),
    }
    match layer.attributes.other.get(&exr::prelude::Text::from("lumiview.max_cd")) {
        Some(exr::prelude::AttributeValue::F64(m)) => assert_eq!(*m, enc.max_cd()),
        other => panic!("max_cd attribute: {other:?}"),
    }
    assert_eq!(exr_text(&img, "lumiview.normalized"), enc.normalized().to_string());
    assert_eq!(exr_text(&img, "lumiview.kind"), enc.kind().name());
    assert_eq!(exr_text(&img, "lumiview.encoding"), enc.encoding().name());
    assert_eq!(exr_text(&img, "lumiview.mapping"), enc.kind().mapping());
}

struct PngRead {
    size: (u32, u32),
    pixels: Vec<u8>,
    text: HashMap<String, String>,
}

fn read_png(bytes: &[u8]) -> PngRead {
    let mut reader = png::Decoder::new(Cursor::new(bytes.to_vec())).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buf.truncate(info.buffer_size());
    let text = reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.clone(), t.text.clone()))
        .collect();
    PngRead {
        size: (info.width, info.height),
        pixels: buf,
        text,
    }
}

fn check_png(bytes: &[u8], enc: &EncodedLut) {
    let png = read_png(bytes);
    assert_eq!(png.size, (enc.width() as u32, enc.height() as u32));
    let LutTexels::U8(b) = enc.texels() else {
        panic!("not u8")
    };
    assert_eq!(&png.pixels, b);
    let max: f64 = png.text["lumiview.max_cd"].parse().unwrap();
    assert_eq!(max, enc.max_cd());
    assert_eq!(png.text["lumiview.normalized"], "true");
    assert_eq!(png.text["lumiview.kind"], enc.kind().name());
    assert_eq!(png.text["lumiview.encoding"], "u8-gamma2.2");
    assert_eq!(png.text["lumiview.mapping"], enc.kind().mapping());
}

#[test]
fn exr_and_png_read_back_with_metadata() {
    for f in [ASA, BEGA, "tests/data/photometric-viewer/ldt/symmetry_to_c90c270.ldt"] {
        let p = open(f);
        for norm in [false, true] {
            for t in [
                Lut::new_2d(&p.web, 96, 49, norm).unwrap(),
                Lut::new_1d(&p.web, 300, norm).unwrap(),
            ] {
                for encoding in [LutEncoding::F32, LutEncoding::F16] {
                    let e = t.encode(encoding).unwrap();
                    check_exr(&e.to_exr().unwrap(), &e);
                }
                let e = t.encode(LutEncoding::U8).unwrap();
                check_png(&e.to_png().unwrap(), &e);
            }
        }
    }
}

#[test]
fn cli_lut_writes_exr_and_png_and_prints_metadata() {
    let p = open(ASA);
    let exr_path = tmp("asa_2d_f16.exr");
    let out = lumiview(&[
        "lut",
        ASA,
        "--kind",
        "2d",
        "--size",
        "64x33",
        "--encoding",
        "f16",
        "-o",
        exr_path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let want = Lut::new_2d(&p.web, 64, 33, false)
        .unwrap()
        .encode(LutEncoding::F16)
        .unwrap();
    assert!(stdout.contains(&format!("max_cd: {}", want.max_cd())), "{stdout}");
    assert!(stdout.contains("normalized: false"), "{stdout}");
    assert!(stdout.contains("mapping: 2d node-aligned"), "{stdout}");
    check_exr(&std::fs::read(&exr_path).unwrap(), &want);

    let png_path = tmp("asa_1d_u8.png");
    let out = lumiview(&[
        "lut",
        ASA,
        "--kind",
        "1d",
        "--size",
        "512",
        "--encoding",
        "u8",
        "-o",
        png_path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let want = Lut::new_1d(&p.web, 512, false)
        .unwrap()
        .encode(LutEncoding::U8)
        .unwrap();
    assert!(stdout.contains(&format!("max_cd: {}", want.max_cd())), "{stdout}");
    assert!(stdout.contains("normalized: true"), "{stdout}");
    check_png(&std::fs::read(&png_path).unwrap(), &want);

    let exr_path = tmp("bega_1d_f32_norm.exr");
    let out = lumiview(&[
        "lut",
        BEGA,
        "--kind",
        "1d",
        "--size",
        "100",
        "--normalize",
        "-o",
        exr_path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let want = Lut::new_1d(&open(BEGA).web, 100, true)
        .unwrap()
        .encode(LutEncoding::F32)
        .unwrap();
    check_exr(&std::fs::read(&exr_path).unwrap(), &want);
}

#[test]
fn cli_lut_rejects_bad_arguments() {
    let cases: &[(&[&str], &str)] = &[
        (&["--encoding", "u8", "-o", "x.exr"], "x.exr"),
        (&["--encoding", "f32", "-o", "x.png"], "x.png"),
        (&["--encoding", "f16", "-o", "x.tiff"], "x.tiff"),
        (&["--size", "0x10", "-o", "x.exr"], "width"),
        (&["--size", "20000x10", "-o", "x.exr"], "width"),
        (&["--size", "64", "-o", "x.exr"], "--size"),
        (&["--kind", "1d", "--size", "8x8", "-o", "x.exr"], "--size"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["lut", BEGA];
        args.extend_from_slice(extra);
        let out = lumiview(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let out = lumiview(&["lut", "tests/data/misc/no_such_file.ies", "-o", "x.exr"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no_such_file.ies"));
}

// ---------------------------------------------------------------------------------------------
// Photometric solid
// ---------------------------------------------------------------------------------------------

/// Every undirected edge in exactly two triangles, and each directed edge once (so the two
/// triangles sharing an edge are wound consistently).
fn check_closed(mesh: &PhotometricSolid) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in mesh.indices().chunks_exact(3) {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "topologically degenerate triangle {t:?}"
        );
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "directed edge {a}->{b} used {n} times");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} has no opposite");
    }
    let edges = directed.len() / 2;
    let (v, f) = (mesh.vertex_count(), mesh.triangle_count());
    assert_eq!(edges * 2, f * 3);
    assert_eq!(
        v as i64 - edges as i64 + f as i64,
        2,
        "Euler characteristic of a sphere"
    );
    assert!(mesh.indices().iter().all(|&i| (i as usize) < v));
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3).map(|k| f64::from(a[k]) * f64::from(b[k])).sum()
}

fn len(a: [f32; 3]) -> f64 {
    dot(a, a).sqrt()
}

#[test]
fn solid_is_closed_outward_and_has_the_right_radii() {
    for f in fixtures() {
        let p = open(&f);
        let (max, _, _) = p.web.max_intensity();
        for (nc, ng, scale) in [(72, 36, 1.0), (16, 7, 2.5), (3, 2, 0.1)] {
            let opts = SolidOptions {
                c_steps: nc,
                gamma_steps: ng,
                scale_m: scale,
            };
            let mesh = PhotometricSolid::new(&p.web, &opts).unwrap();
            assert_eq!(mesh.vertex_count(), 2 + nc * (ng - 1));
            assert_eq!(mesh.triangle_count(), 2 * nc * (ng - 1));
            assert_eq!(mesh.normals().len(), mesh.vertex_count());
            assert_eq!(mesh.max_cd(), max);
            check_closed(&mesh);
            for (k, (&pos, &n)) in mesh.positions().iter().zip(mesh.normals()).enumerate() {
                assert!((len(n) - 1.0).abs() < 1e-5, "{f}: normal {k} {n:?}");
                let (c, g) = mesh.vertex_angles(k).unwrap();
                let i_cd = if k == 0 || k == mesh.vertex_count() - 1 {
                    c_mean(&p.web, g)
                } else {
                    p.web.sample(c, g)
                };
                let r = len(pos);
                assert!(
                    (r - scale * i_cd / max).abs() <= 1e-6 * scale,
                    "{f}: vertex {k} r {r} vs {}",
                    scale * i_cd / max
                );
                if r > 1e-9 * scale {
                    // On its ray, and the normal points out.
                    let d = direction(c, g);
                    let along = (0..3).map(|q| f64::from(pos[q]) * d[q]).sum::<f64>();
                    assert!((along - r).abs() <= 1e-6 * scale);
                    assert!(
                        dot(n, pos) >= -1e-6 * r,
                        "{f}: vertex {k} normal {n:?} points in at {pos:?}"
                    );
                }
            }
            // Faces wound counter-clockwise seen from outside: face normal · centroid ≥ 0.
            let pp = mesh.positions();
            for t in mesh.indices().chunks_exact(3) {
                let [a, b, c] = [pp[t[0] as usize], pp[t[1] as usize], pp[t[2] as usize]].map(|v| v.map(f64::from));
                let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let fnrm = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                let cen = [
                    (a[0] + b[0] + c[0]) / 3.0,
                    (a[1] + b[1] + c[1]) / 3.0,
                    (a[2] + b[2] + c[2]) / 3.0,
                ];
                let s: f64 = (0..3).map(|q| fnrm[q] * cen[q]).sum();
                assert!(s >= -1e-9 * scale * scale * scale, "{f}: inward face {t:?}: {s}");
            }
        }
    }
}

#[test]
fn solid_of_a_sphere_is_outward_everywhere() {
    // Isotropic: every face and vertex normal points out strictly; the nadir pole is −Z.
    let web = PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 180.0], vec![50.0; 4]).unwrap();
    let mesh = PhotometricSolid::new(&web, &SolidOptions::default()).unwrap();
    check_closed(&mesh);
    for (&p, &n) in mesh.positions().iter().zip(mesh.normals()) {
        assert!(dot(n, p) / len(p) > 0.99);
    }
    assert_eq!(mesh.positions()[0], [0.0, 0.0, -1.0]);
    assert_eq!(*mesh.positions().last().unwrap(), [0.0, 0.0, 1.0]);
}

#[test]
fn solid_errors() {
    let zero = PhotometricWeb::from_grid(vec![0.0, 360.0], vec![0.0, 180.0], vec![0.0; 4]).unwrap();
    assert!(matches!(
        PhotometricSolid::new(&zero, &SolidOptions::default()),
        Err(PhotometryError::InvalidArgument { .. })
    ));
    let p = open(BEGA);
    for (c, g, s) in [
        (0, 10, 1.0),
        (2, 10, 1.0),
        (10, 0, 1.0),
        (10, 1, 1.0),
        (100_000, 10, 1.0),
        (10, 10, 0.0),
        (10, 10, f64::INFINITY),
        (10, 10, -2.0),
    ] {
        let opts = SolidOptions {
            c_steps: c,
            gamma_steps: g,
            scale_m: s,
        };
        assert!(
            matches!(
                PhotometricSolid::new(&p.web, &opts),
                Err(PhotometryError::InvalidArgument { .. })
            ),
            "{c} {g} {s}"
        );
    }
}

fn check_glb(bytes: &[u8], mesh: &PhotometricSolid) {
    let gltf = gltf::Gltf::from_slice(bytes).unwrap();
    assert_eq!(gltf.document.meshes().count(), 1);
    assert_eq!(gltf.document.nodes().count(), 1);
    assert_eq!(gltf.document.scenes().count(), 1);
    let m = gltf.document.meshes().next().unwrap();
    let prims: Vec<_> = m.primitives().collect();
    assert_eq!(prims.len(), 1);
    let prim = &prims[0];
    assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
    let pos_acc = prim.get(&gltf::Semantic::Positions).unwrap();
    let nrm_acc = prim.get(&gltf::Semantic::Normals).unwrap();
    let idx_acc = prim.indices().unwrap();
    assert_eq!(pos_acc.count(), mesh.vertex_count());
    assert_eq!(nrm_acc.count(), mesh.vertex_count());
    assert_eq!(idx_acc.count(), mesh.indices().len());
    assert_eq!(idx_acc.data_type(), gltf::accessor::DataType::U32);
    let blob = gltf.blob.as_deref();
    let reader = prim.reader(|b| if b.index() == 0 { blob } else { None });
    let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    let nrm: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
    let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
    assert_eq!(idx, mesh.indices());
    let want: Vec<[f32; 3]> = mesh.positions().iter().map(|&p| to_gltf_axes(p)).collect();
    assert_eq!(pos, want);
    let want_n: Vec<[f32; 3]> = mesh.normals().iter().map(|&n| to_gltf_axes(n)).collect();
    assert_eq!(nrm, want_n);
    // min/max of POSITION are exact.
    let b = prim.bounding_box();
    for k in 0..3 {
        assert_eq!(b.min[k], pos.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min));
        assert_eq!(b.max[k], pos.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max));
    }
    // Nadir down in Y-up glTF.
    assert!(pos[0][1] <= 0.0 && pos[0][0] == 0.0);
}

#[test]
fn glb_parses_with_the_gltf_crate() {
    for f in [ASA, BEGA, "tests/data/photometric-viewer/ldt/no_symmetry.ldt"] {
        let p = open(f);
        let mesh = PhotometricSolid::new(
            &p.web,
            &SolidOptions {
                c_steps: 48,
                gamma_steps: 24,
                scale_m: 3.0,
            },
        )
        .unwrap();
        let bytes = mesh.to_glb().unwrap();
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(bytes.len() % 4, 0);
        assert_eq!(
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            bytes.len()
        );
        check_glb(&bytes, &mesh);
    }
}

fn obj_counts(text: &str) -> (usize, usize, usize) {
    let count = |p: &str| text.lines().filter(|l| l.starts_with(p)).count();
    (count("v "), count("vn "), count("f "))
}

#[test]
fn obj_has_the_right_lines() {
    let p = open(BEGA);
    let mesh = PhotometricSolid::new(&p.web, &SolidOptions::default()).unwrap();
    let obj = mesh.to_obj();
    assert_eq!(
        obj_counts(&obj),
        (mesh.vertex_count(), mesh.vertex_count(), mesh.triangle_count())
    );
    // Faces are 1-based v//vn and match the index buffer.
    let first_face = obj.lines().find(|l| l.starts_with("f ")).unwrap();
    let t = &mesh.indices()[0..3];
    assert_eq!(
        first_face,
        format!("f {a}//{a} {b}//{b} {c}//{c}", a = t[0] + 1, b = t[1] + 1, c = t[2] + 1)
    );
    let first_v: Vec<f32> = obj.lines().find(|l| l.starts_with("v ")).unwrap()[2..]
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(first_v, mesh.positions()[0].to_vec());
}

#[test]
fn cli_solid_writes_obj_and_glb() {
    let p = open(ASA);
    let obj_path = tmp("asa.obj");
    let out = lumiview(&[
        "solid",
        ASA,
        "-o",
        obj_path.to_str().unwrap(),
        "--resolution",
        "36x18",
        "--scale",
        "2",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("614 vertices") && stdout.contains("1224 triangles"),
        "{stdout}"
    );
    let mesh = PhotometricSolid::new(
        &p.web,
        &SolidOptions {
            c_steps: 36,
            gamma_steps: 18,
            scale_m: 2.0,
        },
    )
    .unwrap();
    assert_eq!(mesh.vertex_count(), 614);
    let text = std::fs::read_to_string(&obj_path).unwrap();
    assert_eq!(obj_counts(&text), (614, 614, 1224));
    assert_eq!(text, mesh.to_obj());

    let glb_path = tmp("asa.glb");
    let out = lumiview(&[
        "solid",
        ASA,
        "-o",
        glb_path.to_str().unwrap(),
        "--resolution",
        "36x18",
        "--scale",
        "2",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    check_glb(&std::fs::read(&glb_path).unwrap(), &mesh);

    let glb_default = tmp("bega_default.glb");
    let out = lumiview(&["solid", BEGA, "-o", glb_default.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mesh = PhotometricSolid::new(&open(BEGA).web, &SolidOptions::default()).unwrap();
    check_glb(&std::fs::read(&glb_default).unwrap(), &mesh);
}

#[test]
fn cli_solid_rejects_bad_arguments() {
    let cases: &[(&[&str], &str)] = &[
        (&["-o", "x.stl"], "x.stl"),
        (&["-o", "x"], "unknown output extension"),
        (&["-o", "x.obj", "--resolution", "72"], "--resolution"),
        (&["-o", "x.obj", "--resolution", "2x10"], "c_steps"),
        (&["-o", "x.obj", "--scale", "0"], "scale"),
        (&["-o", "x.obj", "--scale", "nan"], "scale"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["solid", BEGA];
        args.extend_from_slice(extra);
        let out = lumiview(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let out = lumiview(&["solid", "tests/data/misc/missing.ldt", "-o", "x.glb"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.ldt"));
    let dir_out = tmp("no_such_dir/x.obj");
    let out = lumiview(&["solid", BEGA, "-o", dir_out.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("x.obj"));
}
