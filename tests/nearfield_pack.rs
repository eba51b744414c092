//! The `.lvpack` store: round trips within the quantisation bound (also for a 10⁶ cd/m² peak beside
//! 1 cd/m² and for values over 10⁻⁶…10⁹), empty and all-signal images, a corrupted byte in every
//! section found and named, truncation, page limits, CSR, memory independent of the image count,
//! and the `lumiview pack` / `lumiview info` commands.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use glam::{DVec2, DVec3};
use proptest::prelude::*;

use lumiview::nearfield::error::Result;
use lumiview::nearfield::layout::{cameras, Layout};
use lumiview::nearfield::pack::tiles::{self, decode_tile, encode_tile, entry_bytes, TileMode};
use lumiview::nearfield::pack::{
    csr_bytes, write_pack, CsrImage, OpenOptions, Pack, PackOptions, PackStats, Threshold, EMPTY_TILE,
    MAX_RELATIVE_ERROR,
};
use lumiview::nearfield::rayset::MemorySource;
use lumiview::nearfield::{CaptureSphere, ImageSource, Intrinsics, LuminanceImage, NearfieldError, RayImageSet, Scan};

fn tmp(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("nearfield_pack");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn intrinsics(w: u32, h: u32) -> Intrinsics {
    Intrinsics {
        width: w,
        height: h,
        principal_px: DVec2::new(w as f64 / 2.0, h as f64 / 2.0),
        focal_px: DVec2::splat(w as f64),
    }
}

fn rayset(n: usize, w: u32, h: u32) -> RayImageSet {
    let sphere = CaptureSphere {
        centre_m: DVec3::ZERO,
        radius_m: 1.117,
    };
    RayImageSet {
        sphere,
        intrinsics: intrinsics(w, h),
        cameras: cameras(&sphere, &Layout::Fibonacci { count: n }, 1).unwrap(),
    }
}

fn scan(images: Vec<LuminanceImage>) -> Scan {
    let (w, h) = (images[0].width, images[0].height);
    Scan {
        set: rayset(images.len(), w, h),
        source: Box::new(MemorySource { images }),
    }
}

fn pack(scan: &Scan, name: &str, opts: &PackOptions) -> (PathBuf, PackStats) {
    let path = tmp(name);
    let stats = write_pack(scan, &path, opts, &|_, _| {}).unwrap();
    (path, stats)
}

fn within(v: f32, d: f32) -> bool {
    if v == 0.0 {
        d == 0.0
    } else {
        (f64::from(d) - f64::from(v)).abs() <= f64::from(v) * MAX_RELATIVE_ERROR
    }
}

fn assert_image_within(orig: &LuminanceImage, got: &LuminanceImage, what: &str) {
    assert_eq!((orig.width, orig.height), (got.width, got.height), "{what}");
    for (i, (&v, &d)) in orig.data.iter().zip(&got.data).enumerate() {
        assert!(within(v, d), "{what}: pixel {i}: {v} decoded as {d}");
    }
}

/// A deterministic generator for test images.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Log-uniform in 1e-6…1e9, zero with probability `zeros`.
    fn luminance(&mut self, zeros: f64) -> f32 {
        if self.next() < zeros {
            0.0
        } else {
            10f64.powf(-6.0 + 15.0 * self.next()) as f32
        }
    }
}

/// A disc of signal (log-uniform values) on black, plus a 10⁶ peak beside 1 cd/m².
fn disc_image(w: u32, h: u32, seed: u64) -> LuminanceImage {
    let mut rng = Rng(seed);
    let mut img = LuminanceImage::zeros(w, h);
    let (cx, cy, r) = (w as f64 * 0.45, h as f64 * 0.55, w.min(h) as f64 * 0.3);
    for y in 0..h {
        for x in 0..w {
            let d = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
            if d < r {
                img.data[(y * w + x) as usize] = rng.luminance(0.1);
            }
        }
    }
    img.data[(2 * w + 2) as usize] = 1.0e6;
    img.data[(2 * w + 3) as usize] = 1.0;
    img
}

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
fn pages_respect_the_limit_and_f32_tiles_never_straddle() {
    // Every tile of these images needs exact f32 (1e-6 beside 1e9); mix in fp16 tiles so pages
    // fill unevenly and the writer has to skip a page's last slot.
    let mut images = Vec::new();
    for k in 0..5 {
        let mut img = LuminanceImage::zeros(24, 16);
        for (i, v) in img.data.iter_mut().enumerate() {
            let tile = (i % 24) / 8 + 3 * ((i / 24) / 8);
            *v = if (tile + k) % 2 == 0 {
                if i % 2 == 0 {
                    1e9
                } else {
                    1e-6
                }
            } else {
                1.0 + i as f32
            };
        }
        images.push(img);
    }
    let s = scan(images.clone());
    let e = entry_bytes(8) as u64;
    let opts = PackOptions {
        page_bytes: 3 * e + 7,
        ..PackOptions::default()
    };
    let (path, stats) = pack(&s, "pages.lvpack", &opts);
    assert!(stats.tiles_f32 > 0 && stats.tiles_f32 < stats.tiles_kept);
    let p = Pack::open(&path).unwrap();
    assert_eq!(p.layout().slots_per_page, 3);
    assert!(p.page_count() > 5, "{} pages", p.page_count());
    for i in 0..p.page_count() {
        let sec = p.page_section(i).unwrap();
        assert!(sec.length <= opts.page_bytes && sec.length <= 3 * e, "{sec:?}");
        assert_eq!(sec.offset % 4096, 0, "{sec:?}");
        assert_eq!(p.page_bytes(i).unwrap().len() as u64, sec.length);
    }
    for (i, img) in images.iter().enumerate() {
        assert_image_within(img, &p.decode_image(i).unwrap(), &format!("image {i}"));
    }
    // Every f32 tile's two slots lie in one page.
    for &g in p.tile_tables().iter().filter(|&&g| g != EMPTY_TILE) {
        let (page, off) = p.slot_location(g).unwrap();
        let bytes = p.page_bytes(page).unwrap();
        let mut out = vec![0.0f32; 64];
        let mode = decode_tile(&bytes[off..], e as usize, &mut out).unwrap();
        assert!(off as u64 + mode.slots() as u64 * e <= bytes.len() as u64);
    }
    // The default is 128 MiB, the most allowed.
    assert_eq!(PackOptions::default().page_bytes, 128 << 20);
    let too_big = PackOptions {
        page_bytes: (128 << 20) + 1,
        ..PackOptions::default()
    };
    assert!(write_pack(&s, &tmp("too_big.lvpack"), &too_big, &|_, _| {}).is_err());
    // A tiny cache (re-reads pages) gives the same answers.
    let small = Pack::open_with(
        &path,
        &OpenOptions {
            cache_bytes: 0,
            ..OpenOptions::default()
        },
    )
    .unwrap();
    assert_eq!(small.decode_image(3).unwrap(), p.decode_image(3).unwrap());
}

#[test]
fn tile_tables_never_cross_a_window() {
    let e = entry_bytes(8) as u64;
    // Page limit of two slots: windows of 66 table entries; 10×4-tile tables must not cross one.
    let full = |w: u32, h: u32, base: f32| {
        let mut img = LuminanceImage::zeros(w, h);
        img.data.iter_mut().enumerate().for_each(|(i, v)| *v = base + i as f32);
        img
    };
    let images: Vec<_> = (0..5).map(|i| full(80, 32, 1.0 + i as f32)).collect();
    let opts = PackOptions {
        page_bytes: 2 * e,
        ..PackOptions::default()
    };
    let (path, _) = pack(&scan(images.clone()), "windows.lvpack", &opts);
    let p = Pack::open(&path).unwrap();
    let window = u64::from(p.layout().table_window);
    assert_eq!(window, 2 * e / 4);
    for (i, img) in images.iter().enumerate() {
        let entry = p.images()[i];
        assert_eq!(entry.bbox.area(), 40);
        assert!(
            entry.table_offset % window + 40 <= window,
            "image {i} at {}",
            entry.table_offset
        );
        assert_image_within(img, &p.decode_image(i).unwrap(), &format!("image {i}"));
    }
    assert!(p.layout().table_entries > 5 * 40, "padding was needed");
    // A table longer than a window may cross boundaries.
    let (path, _) = pack(
        &scan(vec![full(96, 72, 3.0), full(96, 72, 4.0)]),
        "long-table.lvpack",
        &opts,
    );
    let p = Pack::open(&path).unwrap();
    assert_eq!(p.images()[1].table_offset, 108);
    assert_image_within(&full(96, 72, 4.0), &p.decode_image(1).unwrap(), "long table");
}

/// Offsets of a byte inside each section plus header and directory, with the name to expect.
fn corruption_sites(bytes: &[u8]) -> Vec<(String, usize)> {
    let p = Pack::from_bytes(bytes.to_vec(), &OpenOptions::default()).unwrap();
    let mut sites = vec![("header".to_string(), 20usize)];
    for s in p.sections() {
        assert!(s.length > 0, "{s:?}");
        sites.push((s.name.clone(), (s.offset + s.length / 2) as usize));
        sites.push((s.name.clone(), (s.offset + s.length - 1) as usize));
    }
    let dir = p
        .sections()
        .iter()
        .map(|s| s.offset + s.length)
        .max()
        .unwrap()
        .next_multiple_of(8);
    sites.push(("directory".to_string(), dir as usize + 3));
    sites
}

#[test]
fn a_corrupted_byte_in_every_section_is_found_and_named() {
    let mut images: Vec<_> = (0..4).map(|i| disc_image(40, 32, i)).collect();
    images.push(LuminanceImage::zeros(40, 32));
    let opts = PackOptions {
        page_bytes: 40 * entry_bytes(8) as u64,
        ..PackOptions::default()
    };
    let (path, _) = pack(&scan(images), "corrupt.lvpack", &opts);
    let bytes = std::fs::read(&path).unwrap();
    let sites = corruption_sites(&bytes);
    let names: Vec<&str> = sites.iter().map(|(n, _)| n.as_str()).collect();
    for want in [
        "header",
        "directory",
        "metadata",
        "cameras",
        "images",
        "tile-tables",
        "page.0",
        "page.1",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    for (name, at) in sites {
        let mut bad = bytes.clone();
        bad[at] ^= 0x10;
        // Small sections fail at open; pages on first access, or at open with eager verification.
        let eager = Pack::from_bytes(
            bad.clone(),
            &OpenOptions {
                verify_pages: true,
                ..OpenOptions::default()
            },
        );
        let lazy = Pack::from_bytes(bad.clone(), &OpenOptions::default());
        let err = match (eager, lazy) {
            (Err(e), Ok(p)) => {
                assert!(name.starts_with("page."), "{name} was not checked at open");
                let page: usize = name["page.".len()..].parse().unwrap();
                let e2 = p.page_bytes(page).unwrap_err();
                assert_eq!(e.to_string(), e2.to_string());
                assert!(p.verify().is_err());
                e
            }
            (Err(e), Err(_)) => e,
            (Ok(_), _) => panic!("byte {at} in {name} went unnoticed"),
        };
        match &err {
            NearfieldError::Corrupt { section, .. } => assert_eq!(section, &name, "byte {at}: {err}"),
            _ => panic!("byte {at} in {name}: not a Corrupt error: {err}"),
        }
        assert!(err.to_string().contains(&format!("'{name}'")), "{err}");
    }
    // And through the file API: open names the section, the page errors on first use.
    let mut bad = bytes.clone();
    let p = Pack::open(&path).unwrap();
    let page0 = p.page_section(0).unwrap().offset as usize;
    bad[page0 + 5] ^= 1;
    let path2 = tmp("corrupt-page.lvpack");
    std::fs::write(&path2, &bad).unwrap();
    let p2 = Pack::open(&path2).unwrap();
    let err = (0..5).map(|i| p2.decode_image(i)).find_map(|r| r.err()).unwrap();
    assert!(
        matches!(&err, NearfieldError::Corrupt { section, .. } if section == "page.0"),
        "{err}"
    );
}

#[test]
fn every_single_byte_change_anywhere_is_detected_by_verify() {
    let (path, _) = pack(
        &scan(vec![disc_image(12, 10, 3), disc_image(12, 10, 4)]),
        "every.lvpack",
        &PackOptions::default(),
    );
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.len() > 4 * 4096);
    for at in 0..bytes.len() {
        let mut bad = bytes.clone();
        bad[at] ^= 0x01;
        let res = Pack::from_bytes(bad, &OpenOptions::default()).and_then(|p| p.verify());
        assert!(res.is_err(), "a change at byte {at} went unnoticed");
    }
}

#[test]
fn truncated_and_foreign_files_are_errors() {
    let (path, _) = pack(
        &scan(vec![disc_image(20, 20, 8)]),
        "trunc.lvpack",
        &PackOptions::default(),
    );
    let bytes = std::fs::read(&path).unwrap();
    for cut in (0..bytes.len()).step_by(97).chain([bytes.len() - 1, 63, 64, 65]) {
        let err = Pack::from_bytes(bytes[..cut].to_vec(), &OpenOptions::default()).unwrap_err();
        if cut >= 64 {
            assert!(err.to_string().contains("truncated"), "cut at {cut}: {err}");
        }
    }
    let mut extended = bytes.clone();
    extended.push(0);
    assert!(Pack::from_bytes(extended, &OpenOptions::default()).is_err());
    assert!(matches!(
        Pack::from_bytes(b"LVPACK but not really".to_vec(), &OpenOptions::default()),
        Err(NearfieldError::Format { .. })
    ));
    // A later version is reported as such.
    let mut v3 = bytes.clone();
    v3[8] = 3;
    let crc = crc32fast::hash(&v3[..60]);
    v3[60..64].copy_from_slice(&crc.to_le_bytes());
    assert!(matches!(
        Pack::from_bytes(v3, &OpenOptions::default()),
        Err(NearfieldError::Unsupported { .. })
    ));
    // A version-1 file relabelled 2 fails on its metadata's version, naming the section.
    let mut v2 = bytes.clone();
    v2[8] = 2;
    let crc = crc32fast::hash(&v2[..60]);
    v2[60..64].copy_from_slice(&crc.to_le_bytes());
    assert!(matches!(
        Pack::from_bytes(v2, &OpenOptions::default()),
        Err(NearfieldError::Corrupt { .. })
    ));
    assert!(matches!(
        Pack::open(&tmp("does-not-exist.lvpack")),
        Err(NearfieldError::Io { .. })
    ));
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

/// A source that counts how many images were handed out but not yet written (via progress).
struct Counting {
    inner: MemorySource,
    handed: AtomicUsize,
    written: Arc<AtomicUsize>,
    peak: AtomicUsize,
}

impl ImageSource for Counting {
    fn image(&self, index: usize) -> Result<LuminanceImage> {
        let h = self.handed.fetch_add(1, Ordering::SeqCst) + 1;
        self.peak
            .fetch_max(h - self.written.load(Ordering::SeqCst), Ordering::SeqCst);
        self.inner.image(index % self.inner.images.len())
    }
}

fn counted_pack(n: usize, chunk: usize) -> (usize, PackStats) {
    let written = Arc::new(AtomicUsize::new(0));
    let src = Counting {
        inner: MemorySource {
            images: (0..3).map(|i| disc_image(48, 40, i)).collect(),
        },
        handed: AtomicUsize::new(0),
        written: written.clone(),
        peak: AtomicUsize::new(0),
    };
    let s = Scan {
        set: rayset(n, 48, 40),
        source: Box::new(src),
    };
    let opts = PackOptions {
        chunk_images: chunk,
        ..PackOptions::default()
    };
    let w = written.clone();
    let progress = move |done: usize, total: usize| {
        assert_eq!(total, n);
        w.store(done, Ordering::SeqCst);
    };
    let stats = write_pack(&s, &tmp(&format!("count{n}.lvpack")), &opts, &progress).unwrap();
    assert_eq!(written.load(Ordering::SeqCst), n);
    (stats.peak_pending_images, stats)
}

#[test]
fn memory_is_independent_of_the_image_count() {
    let chunk = 4;
    let (peak_n, small) = counted_pack(60, chunk);
    let (peak_4n, large) = counted_pack(240, chunk);
    // At most one chunk being encoded, one queued and one being written are held at once.
    for (peak, stats) in [(peak_n, &small), (peak_4n, &large)] {
        assert!(peak <= 3 * chunk, "{peak} images held at once");
        let per_image = stats.pool_bytes / stats.images as u64 * 4 + 4096;
        assert!(stats.peak_pending_bytes <= 3 * chunk as u64 * per_image, "{stats:?}");
    }
    assert_eq!(large.tiles_kept, 4 * small.tiles_kept);
}

#[test]
fn bad_input_is_an_error_and_leaves_no_file() {
    let mut img = disc_image(16, 16, 1);
    img.data[17] = f32::NAN;
    let s = scan(vec![disc_image(16, 16, 0), img]);
    let path = tmp("nan.lvpack");
    let _ = std::fs::remove_file(&path);
    let err = write_pack(&s, &path, &PackOptions::default(), &|_, _| {}).unwrap_err();
    assert!(
        err.to_string().contains("cam 1") && err.to_string().contains("col 1, row 1"),
        "{err}"
    );
    assert!(!path.exists() && !tmp("nan.lvpack.partial").exists() && !tmp("nan.lvpack.tables.partial").exists());
    // Wrong size.
    let s = Scan {
        set: rayset(2, 16, 16),
        source: Box::new(MemorySource {
            images: vec![disc_image(16, 16, 0), disc_image(16, 15, 0)],
        }),
    };
    assert!(write_pack(&s, &path, &PackOptions::default(), &|_, _| {}).is_err());
    // Bad options.
    for opts in [
        PackOptions {
            tile_size: 0,
            ..PackOptions::default()
        },
        PackOptions {
            tile_size: 65,
            ..PackOptions::default()
        },
        PackOptions {
            page_bytes: 100,
            ..PackOptions::default()
        },
        PackOptions {
            threshold: Threshold::Absolute(f32::NAN),
            ..PackOptions::default()
        },
    ] {
        assert!(write_pack(&s, &path, &opts, &|_, _| {}).is_err(), "{opts:?}");
    }
    assert!(!path.exists());
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

fn lumiview() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lumiview"))
}

#[test]
fn cli_info_and_repack() {
    let (path, stats) = pack(
        &scan((0..5).map(|i| disc_image(40, 30, i)).collect()),
        "cli.lvpack",
        &PackOptions::default(),
    );
    let out = lumiview()
        .args(["info", path.to_str().unwrap(), "--json", "--verify"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cameras"]["total"], 5);
    assert_eq!(v["tiles"]["kept"], stats.tiles_kept);
    assert_eq!(v["verify"]["ok"], true);
    assert!(v["footprint"]["ratio_to_csr"].as_f64().unwrap() > 0.0);
    assert!(v["sections"]
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s["name"] == "tile-tables"));
    let out = lumiview().args(["info", path.to_str().unwrap()]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("cameras") && text.contains("CSR"),
        "{text}"
    );

    // Repack with another tile size.
    let dst = tmp("cli-repack.lvpack");
    let out = lumiview()
        .args([
            "pack",
            path.to_str().unwrap(),
            "-o",
            dst.to_str().unwrap(),
            "--tile",
            "16",
            "--threshold",
            "0",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(Pack::open(&dst).unwrap().layout().tile_size, 16);

    // A corrupted page fails --verify with the section named.
    let mut bytes = std::fs::read(&path).unwrap();
    let off = Pack::open(&path).unwrap().page_section(0).unwrap().offset as usize;
    bytes[off + 9] ^= 4;
    let bad = tmp("cli-bad.lvpack");
    std::fs::write(&bad, &bytes).unwrap();
    let out = lumiview()
        .args(["info", bad.to_str().unwrap(), "--verify"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("page.0"));
}

#[test]
fn cli_packs_synthetic_scans_manifests_and_ray_files() {
    // --synth: the synthetic goniophotometer, streamed.
    let synth = tmp("cli-synth.lvpack");
    let out = lumiview()
        .args([
            "pack",
            "--synth",
            "disc",
            "--layout",
            "fibonacci:12",
            "--size",
            "64x48",
            "--quiet",
            "--json",
            "-o",
        ])
        .arg(&synth)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["images"], 12);
    assert!(v["tiles_kept"].as_u64().unwrap() > 0);
    let p = Pack::open(&synth).unwrap();
    assert_eq!((p.rayset().intrinsics.width, p.rayset().intrinsics.height), (64, 48));
    assert!(p.metadata().source.contains("disc"), "{}", p.metadata().source);

    // A scan manifest (written from the pack just made), packed again: the same pixels.
    let dir = tmp("cli-manifest");
    let _ = std::fs::remove_dir_all(&dir);
    let manifest =
        lumiview::nearfield::manifest::write_scan(&dir, &Pack::open(&synth).unwrap().into_scan(), &|_, _| {}).unwrap();
    let from_manifest = tmp("cli-manifest.lvpack");
    let out = lumiview()
        .arg("pack")
        .arg(&manifest)
        .arg("-o")
        .arg(&from_manifest)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let q = Pack::open(&from_manifest).unwrap();
    assert_eq!(q.rayset().cameras.len(), 12);
    for i in 0..12 {
        assert_eq!(q.decode_image(i).unwrap(), p.decode_image(i).unwrap(), "image {i}");
    }

    // A TM-25 ray file: its kernel estimate, stored with the hull of its ray origins (version 2).
    let rays = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/raysets/Cyl10k.1.tm25ray");
    let from_rays = tmp("cli-rays.lvpack");
    let out = lumiview()
        .arg("pack")
        .arg(&rays)
        .args(["--quiet", "-o"])
        .arg(&from_rays)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r = Pack::open(&from_rays).unwrap();
    assert!(r.image_count() >= 12);
    assert!(r.metadata().footprint.pixels_kept > 0);
    assert!(r.proxy().is_some_and(|p| p.bound && !p.triangles.is_empty()));
    // Repacking keeps the proxy; a camera layout for a ray file is refused (rays2scan sets it).
    let again = tmp("cli-rays-again.lvpack");
    let out = lumiview()
        .arg("pack")
        .arg(&from_rays)
        .args(["--quiet", "-o"])
        .arg(&again)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(Pack::open(&again).unwrap().proxy(), r.proxy());
    let out = lumiview()
        .arg("pack")
        .arg(&rays)
        .args(["--layout", "fibonacci:20", "-o"])
        .arg(tmp("x.lvpack"))
        .output()
        .unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--layout"));

    // Errors name what is wrong.
    for args in [
        vec!["pack", "-o", "x.lvpack"],
        vec![
            "pack",
            "--synth",
            "disc",
            "--tile",
            "0",
            "--layout",
            "fibonacci:2",
            "--size",
            "8x8",
            "-o",
            "x.lvpack",
        ],
        vec!["pack", "--synth", "disc", "--threshold", "rel:5", "-o", "x.lvpack"],
        vec!["pack", "--synth", "disc", "--page-mib", "129", "-o", "x.lvpack"],
        vec![
            "info",
            "--verify",
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/misc/luxcore_ASA_15M_R2.ies"),
        ],
    ] {
        let out = lumiview()
            .args(&args)
            .current_dir(env!("CARGO_TARGET_TMPDIR"))
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("error"), "{args:?}: {err}");
    }
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
