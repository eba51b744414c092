//! What the writer lays out and holds: pages within their limit (f32 tiles never straddle one), tile
//! tables never crossing a window, memory independent of the image count, and bad input an error
//! that leaves no file.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use lumiview::nearfield::error::Result;
use lumiview::nearfield::pack::tiles::{decode_tile, entry_bytes};
use lumiview::nearfield::pack::{write_pack, OpenOptions, Pack, PackOptions, PackStats, Threshold, EMPTY_TILE};
use lumiview::nearfield::rayset::MemorySource;
use lumiview::nearfield::{ImageSource, LuminanceImage, Scan};

use crate::common::{assert_image_within, disc_image, pack, rayset, scan, tmp};

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
