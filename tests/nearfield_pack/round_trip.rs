//! Round trips: images within the quantisation bound (a 10⁶ cd/m² peak beside 1 cd/m² in one tile),
//! metadata, cameras and per-camera overrides, empty and all-signal images, and a repack from a
//! pack shared across threads.

use std::sync::Arc;

use lumiview::nearfield::pack::{csr_bytes, OpenOptions, Pack, PackOptions, EMPTY_TILE, MAX_RELATIVE_ERROR};
use lumiview::nearfield::LuminanceImage;

use crate::common::{assert_image_within, disc_image, intrinsics, pack, scan, tmp, within, Rng};

#[test]
fn round_trip_within_the_bound() {
    let images: Vec<_> = (0..7).map(|i| disc_image(61, 45, i)).collect();
    let s = scan(images.clone());
    let (path, stats) = pack(&s, "round_trip.lvpack", &PackOptions::default());
    let p = Pack::open(&path).unwrap();
    assert_eq!(p.image_count(), 7);
    assert_eq!(stats.images, 7);
    assert!(
        stats.tiles_f32 > 0,
        "log-uniform 1e-6…1e9 values need exact tiles somewhere"
    );
    assert!(stats.tiles_kept > stats.tiles_f32);
    for (i, img) in images.iter().enumerate() {
        let got = p.decode_image(i).unwrap();
        assert_image_within(img, &got, &format!("image {i}"));
        for (row, col) in [(0, 0), (2, 2), (2, 3), (20, 30), (44, 60), (30, 7)] {
            assert_eq!(
                p.sample(i, col, row).unwrap(),
                got.get(col, row),
                "image {i} ({col}, {row})"
            );
        }
        let e = p.images()[i];
        assert_eq!(e.max_cd_m2, got.data.iter().fold(0.0f32, |a, &b| a.max(b)));
    }
    // The peak tile stays fp16 and exact to the bound.
    assert!(within(1.0e6, p.sample(0, 2, 2).unwrap()) && within(1.0, p.sample(0, 3, 2).unwrap()));
    // Out of range is an error, never a panic.
    assert!(p.sample(7, 0, 0).is_err() && p.sample(0, 61, 0).is_err() && p.sample(0, 0, 45).is_err());
    assert!(p.decode_image(99).is_err());
    // The ray-image set comes back exactly.
    assert_eq!(p.rayset(), &s.set);
    // Footprint statistics agree with the CSR encoder and the file.
    assert_eq!(stats.csr_bytes, images.iter().map(|i| csr_bytes(i) as u64).sum::<u64>());
    assert_eq!(stats.bytes, std::fs::metadata(&path).unwrap().len());
    assert_eq!(stats.dense_f16_bytes, 7 * 61 * 45 * 2);
    assert_eq!(p.metadata().footprint.csr_bytes, stats.csr_bytes);
    assert!(!tmp("round_trip.lvpack.partial").exists() && !tmp("round_trip.lvpack.tables.partial").exists());
}

#[test]
fn peak_beside_one_in_one_tile() {
    let mut img = LuminanceImage::zeros(8, 8);
    img.data[0] = 1.0e6;
    img.data[1] = 1.0;
    img.data[63] = 1.0e7;
    img.data[62] = 0.25;
    let (path, stats) = pack(&scan(vec![img.clone()]), "peak.lvpack", &PackOptions::default());
    assert_eq!((stats.tiles_kept, stats.tiles_f32), (1, 0), "one fp16 tile");
    let p = Pack::open(&path).unwrap();
    assert_image_within(&img, &p.decode_image(0).unwrap(), "peak");
}

#[test]
fn metadata_cameras_and_overrides_round_trip() {
    let mut s = scan(vec![
        disc_image(16, 16, 1),
        disc_image(16, 16, 2),
        LuminanceImage::zeros(24, 8),
    ]);
    s.set.cameras[1].meta.exposure_s = Some(0.125);
    s.set.cameras[1].meta.overflow_count = Some(17);
    s.set.cameras[1].label = "upper/IMG_0001.pf — ü".into();
    s.set.cameras[2].intrinsics = Some(intrinsics(24, 8));
    s.set.cameras[2].hemisphere = lumiview::nearfield::Hemisphere::Upper;
    let opts = PackOptions {
        source: "unit test".into(),
        ..PackOptions::default()
    };
    let (path, _) = pack(&s, "meta.lvpack", &opts);
    let p = Pack::open(&path).unwrap();
    assert_eq!(p.rayset(), &s.set);
    let m = p.metadata();
    assert_eq!(m.source, "unit test");
    let lower = s
        .set
        .cameras
        .iter()
        .filter(|c| c.hemisphere == lumiview::nearfield::Hemisphere::Lower)
        .count() as u64;
    assert_eq!((m.cameras.lower, m.cameras.upper), (lower, 3 - lower));
    assert_eq!(m.encoding.tile_size, 8);
    assert_eq!(p.decode_image(2).unwrap(), LuminanceImage::zeros(24, 8));
}

#[test]
fn empty_and_all_signal_images() {
    let empty = LuminanceImage::zeros(19, 13);
    let mut full = LuminanceImage::zeros(19, 13);
    let mut rng = Rng(9);
    full.data.iter_mut().for_each(|v| *v = 1.0 + rng.next() as f32 * 100.0);
    let (path, stats) = pack(
        &scan(vec![empty.clone(), full.clone(), empty.clone()]),
        "mixed.lvpack",
        &PackOptions::default(),
    );
    let p = Pack::open(&path).unwrap();
    assert_eq!(stats.empty_images, 2);
    assert_eq!(stats.tiles_kept, 3 * 2, "19×13 px is 3×2 tiles of 8, all kept");
    assert_eq!(stats.pixels_kept, 19 * 13);
    let e = p.images();
    assert_eq!((e[0].bbox.w, e[0].bbox.h, e[0].tiles), (0, 0, 0));
    assert_eq!((e[1].bbox.x0, e[1].bbox.y0, e[1].bbox.w, e[1].bbox.h), (0, 0, 3, 2));
    assert!(p.tile_table(1).unwrap().iter().all(|&g| g != EMPTY_TILE));
    assert_eq!(p.decode_image(0).unwrap(), empty);
    assert_eq!(p.sample(2, 18, 12).unwrap(), 0.0);
    assert_image_within(&full, &p.decode_image(1).unwrap(), "full");
    assert_eq!(p.sample(1, 18, 12).unwrap(), p.decode_image(1).unwrap().get(18, 12));

    // Only empty images: no pages at all, still a valid pack.
    let (path, stats) = pack(&scan(vec![empty.clone(); 4]), "empty.lvpack", &PackOptions::default());
    assert_eq!((stats.pages, stats.tiles_kept), (0, 0));
    let p = Pack::open_with(
        &path,
        &OpenOptions {
            verify_pages: true,
            ..OpenOptions::default()
        },
    )
    .unwrap();
    assert_eq!(p.page_count(), 0);
    assert_eq!(p.decode_image(3).unwrap(), empty);
}

#[test]
fn repack_from_a_pack_and_share_across_threads() {
    let images: Vec<_> = (0..6).map(|i| disc_image(30, 30, i + 20)).collect();
    let (path, _) = pack(&scan(images.clone()), "repack-src.lvpack", &PackOptions::default());
    let p = Arc::new(Pack::open(&path).unwrap());
    let handles: Vec<_> = (0..3)
        .map(|t| {
            let p = p.clone();
            std::thread::spawn(move || (0..6).map(|i| p.sample(i, 10 + t, 12).unwrap()).collect::<Vec<_>>())
        })
        .collect();
    for (t, h) in handles.into_iter().enumerate() {
        let got = h.join().unwrap();
        for (i, v) in got.into_iter().enumerate() {
            assert!(within(images[i].get(10 + t as u32, 12), v));
        }
    }
    let p = Arc::try_unwrap(p).unwrap();
    let opts = PackOptions {
        tile_size: 4,
        ..PackOptions::default()
    };
    let (path2, _) = pack(&p.into_scan(), "repack-dst.lvpack", &opts);
    let q = Pack::open(&path2).unwrap();
    assert_eq!(q.layout().tile_size, 4);
    for (i, img) in images.iter().enumerate() {
        let got = q.decode_image(i).unwrap();
        for (&v, &d) in img.data.iter().zip(&got.data) {
            let tol = f64::from(v) * 2.0 * MAX_RELATIVE_ERROR * 1.001;
            assert!((f64::from(d) - f64::from(v)).abs() <= tol, "{v} → {d}");
        }
    }
}
