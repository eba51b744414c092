//! Look-up tables as files: EXR and PNG read back with the exr and png crates, texels and metadata
//! intact, and the `lumiview lut` command with its errors.

use std::collections::HashMap;
use std::io::Cursor;

use exr::prelude::{ReadChannels, ReadLayers};

use lumiview::photometry::lut::{EncodedLut, Lut, LutEncoding, LutTexels};

use crate::common::{lumiview, open, tmp, ASA, BEGA};

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
