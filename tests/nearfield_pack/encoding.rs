//! The encodings: tile sizes and thresholds, the tile quantisation bound over 10⁻⁶…10⁹ cd/m² and over
//! every finite f32, and the CSR encoding with its footprint.

use proptest::prelude::*;

use lumiview::nearfield::pack::tiles::{self, decode_tile, encode_tile, entry_bytes, TileMode};
use lumiview::nearfield::pack::{csr_bytes, CsrImage, Pack, PackOptions, Threshold};
use lumiview::nearfield::LuminanceImage;

use crate::common::{assert_image_within, disc_image, pack, scan, within};

#[test]
fn tile_sizes_and_thresholds() {
    let img = disc_image(37, 29, 5);
    let s = scan(vec![img.clone(), img.clone()]);
    for tile in [1, 3, 5, 8, 16, 64] {
        let opts = PackOptions {
            tile_size: tile,
            ..PackOptions::default()
        };
        let (path, _) = pack(&s, &format!("tile{tile}.lvpack"), &opts);
        let p = Pack::open(&path).unwrap();
        assert_eq!(p.layout().tile_size, tile);
        assert_eq!(p.layout().entry_bytes as usize, entry_bytes(tile));
        assert_image_within(&img, &p.decode_image(1).unwrap(), &format!("tile {tile}"));
    }
    // A threshold drops tiles whose values are all at or below it and keeps the rest as they are.
    let mut img = LuminanceImage::zeros(16, 8);
    img.data[0] = 0.5; // tile 0: only ≤ 1
    img.data[8] = 0.5; // tile 1: 0.5 beside 3.0
    img.data[9] = 3.0;
    let s = scan(vec![img.clone()]);
    let opts = PackOptions {
        threshold: Threshold::Absolute(1.0),
        ..PackOptions::default()
    };
    let (path, stats) = pack(&s, "thr.lvpack", &opts);
    assert_eq!((stats.tiles_kept, stats.pixels_kept), (1, 1));
    let p = Pack::open(&path).unwrap();
    assert_eq!(p.sample(0, 0, 0).unwrap(), 0.0);
    assert!(within(0.5, p.sample(0, 8, 0).unwrap()) && within(3.0, p.sample(0, 9, 0).unwrap()));
    let rel = PackOptions {
        threshold: Threshold::RelativeToImageMax(0.5),
        ..PackOptions::default()
    };
    let (_, stats) = pack(&s, "thr-rel.lvpack", &rel);
    assert_eq!(stats.tiles_kept, 1);
    assert_eq!(
        Threshold::parse("rel:1e-4").unwrap(),
        Threshold::RelativeToImageMax(1e-4)
    );
    assert_eq!(Threshold::parse("abs:2").unwrap(), Threshold::Absolute(2.0));
    assert_eq!(Threshold::parse("0.5").unwrap(), Threshold::Absolute(0.5));
    for bad in ["", "x", "-1", "rel:2", "nan", "inf"] {
        assert!(Threshold::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn csr_round_trip_and_footprint() {
    for seed in 0..4 {
        let img = disc_image(50, 33, seed);
        let csr = CsrImage::encode(&img).unwrap();
        assert_eq!(csr.decode(), img);
        assert_eq!(csr.byte_len(), csr_bytes(&img));
        let back = CsrImage::from_bytes(&csr.to_bytes()).unwrap();
        assert_eq!(back, csr);
        for (i, &v) in img.data.iter().enumerate() {
            assert_eq!(csr.sample((i % 50) as u32, (i / 50) as u32), v);
        }
    }
    // A compact source: tiles beat CSR by far.
    let mut img = LuminanceImage::zeros(304, 255);
    for y in 100..150 {
        for x in 130..180 {
            img.data[y * 304 + x] = 1000.0 + x as f32;
        }
    }
    let (_, stats) = pack(
        &scan(vec![img.clone(); 20]),
        "footprint.lvpack",
        &PackOptions::default(),
    );
    assert!(stats.ratio_to_csr() < 0.5, "{stats:?}");
    assert!(stats.ratio_to_dense_f16() < 0.1, "{stats:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Any tile of values over 10⁻⁶…10⁹ cd/m² (with zeros) decodes with every nonzero value within
    /// 2^-11 relative and every zero exact.
    #[test]
    fn tile_quantisation_bound(
        vals in prop::collection::vec(prop_oneof![1 => Just(0.0f64), 4 => -6.0..9.0f64], 64),
        peak in prop::option::of(0usize..64),
    ) {
        let mut v: Vec<f32> = vals.iter().map(|&e| if e == 0.0 { 0.0 } else { 10f64.powf(e) as f32 }).collect();
        if let Some(i) = peak {
            v[i] = 1.0e6;
            v[(i + 1) % 64] = 1.0;
        }
        let e = entry_bytes(8);
        let mut out = Vec::new();
        let mode = encode_tile(&v, e, &mut out);
        prop_assert_eq!(out.len(), mode.slots() * e);
        let mut dec = vec![0.0f32; 64];
        prop_assert_eq!(decode_tile(&out, e, &mut dec).unwrap(), mode);
        for (&a, &b) in v.iter().zip(&dec) {
            prop_assert!(within(a, b), "{} → {}", a, b);
        }
        // fp16 unless the tile's dynamic range exceeds what normal fp16 holds (2^28 guaranteed).
        let nz: Vec<f32> = v.iter().copied().filter(|&x| x > 0.0).collect();
        if let (Some(lo), Some(hi)) = (nz.iter().copied().reduce(f32::min), nz.iter().copied().reduce(f32::max)) {
            if f64::from(hi) / f64::from(lo) < 2f64.powi(28) {
                prop_assert_eq!(mode, TileMode::F16Scaled);
            }
        }
    }

    /// Arbitrary finite non-negative f32 bit patterns (the whole range, subnormals included).
    #[test]
    fn tile_bound_over_all_f32(bits in prop::collection::vec(0u32..0x7F80_0000, 16)) {
        let v: Vec<f32> = bits.into_iter().map(f32::from_bits).collect();
        let e = tiles::entry_bytes(4);
        let mut out = Vec::new();
        encode_tile(&v, e, &mut out);
        let mut dec = vec![0.0f32; 16];
        decode_tile(&out, e, &mut dec).unwrap();
        for (&a, &b) in v.iter().zip(&dec) {
            prop_assert!(within(a, b), "{} → {}", a, b);
        }
    }
}
