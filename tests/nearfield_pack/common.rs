//! What every part of the `.lvpack` tests uses: scans of generated images (a disc of log-uniform
//! values beside a 10⁶ cd/m² peak), packing one into the test's temporary folder, and the
//! quantisation bound a decoded value must meet.

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};

use lumiview::nearfield::layout::{cameras, Layout};
use lumiview::nearfield::pack::{write_pack, PackOptions, PackStats, MAX_RELATIVE_ERROR};
use lumiview::nearfield::rayset::MemorySource;
use lumiview::nearfield::{CaptureSphere, Intrinsics, LuminanceImage, RayImageSet, Scan};

pub(crate) fn tmp(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("nearfield_pack");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

pub(crate) fn intrinsics(w: u32, h: u32) -> Intrinsics {
    Intrinsics {
        width: w,
        height: h,
        principal_px: DVec2::new(w as f64 / 2.0, h as f64 / 2.0),
        focal_px: DVec2::splat(w as f64),
    }
}

pub(crate) fn rayset(n: usize, w: u32, h: u32) -> RayImageSet {
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

pub(crate) fn scan(images: Vec<LuminanceImage>) -> Scan {
    let (w, h) = (images[0].width, images[0].height);
    Scan {
        set: rayset(images.len(), w, h),
        source: Box::new(MemorySource { images }),
    }
}

pub(crate) fn pack(scan: &Scan, name: &str, opts: &PackOptions) -> (PathBuf, PackStats) {
    let path = tmp(name);
    let stats = write_pack(scan, &path, opts, &|_, _| {}).unwrap();
    (path, stats)
}

pub(crate) fn within(v: f32, d: f32) -> bool {
    if v == 0.0 {
        d == 0.0
    } else {
        (f64::from(d) - f64::from(v)).abs() <= f64::from(v) * MAX_RELATIVE_ERROR
    }
}

pub(crate) fn assert_image_within(orig: &LuminanceImage, got: &LuminanceImage, what: &str) {
    assert_eq!((orig.width, orig.height), (got.width, got.height), "{what}");
    for (i, (&v, &d)) in orig.data.iter().zip(&got.data).enumerate() {
        assert!(within(v, d), "{what}: pixel {i}: {v} decoded as {d}");
    }
}

/// A deterministic generator for test images.
pub(crate) struct Rng(pub(crate) u64);
impl Rng {
    pub(crate) fn next(&mut self) -> f64 {
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
pub(crate) fn disc_image(w: u32, h: u32, seed: u64) -> LuminanceImage {
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
