//! The `.lvpack` store: a scan's luminance images cut into small tiles, only tiles with signal
//! kept, in a tile pool split into pages of at most 128 MiB, with a per-image tile table over the
//! image's bounding box (O(1) random access: pixel → tile → pool slot).
//!
//! - [`write_pack`] streams a [`Scan`](crate::nearfield::Scan) into a file: images are encoded in
//!   parallel in bounded chunks and written in image order as pages fill, so memory does not grow
//!   with the number of images.
//! - [`Pack`] opens a file, checks the header, directory and every small section eagerly, and each
//!   page's checksum when the page is first read; it samples pixels, decodes whole images, hands out
//!   page bytes for the GPU and gives the [`RayImageSet`](crate::nearfield::RayImageSet) back.
//! - [`tiles`] holds the tile encoding (fp16 × per-tile power-of-two scale, exact f32 for tiles of
//!   extreme dynamic range; every nonzero value within [`MAX_RELATIVE_ERROR`] = 2^-11), [`csr`] the
//!   reference CSR layout the footprint is compared against, [`format`](mod@format) the byte layout.
//!
//! The byte-exact layout is in docs/formats.md (section `lvpack`).

pub mod csr;
pub mod format;
mod reader;
pub mod tiles;
mod writer;

pub use csr::{csr_bytes, csr_bytes_for, CsrImage};
pub use format::{ImageEntry, PackMetadata, PoolLayout, SectionInfo, MAX_PAGE_BYTES};
pub use reader::{OpenOptions, Pack, PageBytes, VerifyReport};
pub use tiles::{TileBox, TileMode, EMPTY_TILE, MAX_RELATIVE_ERROR};
pub use writer::write_pack;

/// The file-name extension of a pack (a file named so is read as a pack or refused, never as
/// anything else).
pub const EXTENSION: &str = "lvpack";

use super::error::{NearfieldError, Result};

/// Which tiles are kept: a tile is kept when any of its values is above the threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Threshold {
    /// An absolute luminance (cd/m²). `Absolute(0.0)` (the default) keeps every tile with a nonzero
    /// pixel: the pack is lossless about which pixels are zero.
    Absolute(f32),
    /// A fraction of each image's maximum luminance (e.g. `1e-4`).
    RelativeToImageMax(f32),
}

impl Default for Threshold {
    fn default() -> Self {
        Threshold::Absolute(0.0)
    }
}

impl Threshold {
    /// Checks that the value is finite and ≥ 0 (a relative one also ≤ 1).
    pub fn validate(&self) -> Result<()> {
        let (v, max) = match *self {
            Threshold::Absolute(v) => (v, f32::MAX),
            Threshold::RelativeToImageMax(v) => (v, 1.0),
        };
        if !(v.is_finite() && (0.0..=max).contains(&v)) {
            return Err(NearfieldError::invalid(
                "threshold",
                format!("{v} must be finite, ≥ 0 (and ≤ 1 when relative)"),
            ));
        }
        Ok(())
    }

    /// Parses `0.5` / `abs:0.5` (cd/m²) or `rel:1e-4` (fraction of each image's maximum).
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim();
        let bad = || {
            NearfieldError::invalid(
                "threshold",
                format!("`{text}`: expected a luminance in cd/m² (`0.5`, `abs:0.5`) or `rel:FRACTION` (`rel:1e-4`)"),
            )
        };
        let (rel, num) = if let Some(r) = t.strip_prefix("rel:") {
            (true, r)
        } else {
            (false, t.strip_prefix("abs:").unwrap_or(t))
        };
        let v: f32 = num.trim().parse().map_err(|_| bad())?;
        let th = if rel {
            Threshold::RelativeToImageMax(v)
        } else {
            Threshold::Absolute(v)
        };
        th.validate()?;
        Ok(th)
    }
}

/// How [`write_pack`] stores a scan.
#[derive(Debug, Clone, PartialEq)]
pub struct PackOptions {
    /// Tile edge in pixels, 1…64 (default 8).
    pub tile_size: u32,
    /// Which tiles are kept (default: every tile with a nonzero pixel).
    pub threshold: Threshold,
    /// Largest page in bytes, at most [`MAX_PAGE_BYTES`] (128 MiB, the default) and at least two
    /// slots; smaller values exist for tests.
    pub page_bytes: u64,
    /// Images encoded together in one parallel chunk (0: four per worker thread). Memory grows
    /// with this, never with the number of images.
    pub chunk_images: usize,
    /// A description of the input, stored in the metadata (e.g. the manifest path).
    pub source: String,
    /// A proxy mesh to store with the scan (makes a version-2 pack).
    pub proxy: Option<PackProxy>,
}

/// A proxy mesh stored in a pack: the surface (or a bound of the surfaces) where the images'
/// luminance appears, used for parallax-correct rendering unless the user gives another.
#[derive(Debug, Clone, PartialEq)]
pub struct PackProxy {
    /// Triangle vertices, three per triangle (m, luminaire frame).
    pub triangles: Vec<[f32; 3]>,
    /// True when the mesh encloses the light rather than being its surface (a ray file's grown
    /// hull): the renderer then samples the images plainly, darkness included.
    pub bound: bool,
    /// Where the mesh came from.
    pub source: String,
}

impl Default for PackOptions {
    fn default() -> Self {
        Self {
            tile_size: 8,
            threshold: Threshold::default(),
            page_bytes: MAX_PAGE_BYTES,
            chunk_images: 0,
            source: String::new(),
            proxy: None,
        }
    }
}

impl PackOptions {
    /// Checks tile size, threshold and page size.
    pub fn validate(&self) -> Result<()> {
        if !(tiles::MIN_TILE_SIZE..=tiles::MAX_TILE_SIZE).contains(&self.tile_size) {
            return Err(NearfieldError::invalid(
                "tile size",
                format!(
                    "{} px is outside {}…{}",
                    self.tile_size,
                    tiles::MIN_TILE_SIZE,
                    tiles::MAX_TILE_SIZE
                ),
            ));
        }
        self.threshold.validate()?;
        let min = 2 * tiles::entry_bytes(self.tile_size) as u64;
        if !(min..=MAX_PAGE_BYTES).contains(&self.page_bytes) {
            return Err(NearfieldError::invalid(
                "page size",
                format!(
                    "{} bytes is outside {min}…{MAX_PAGE_BYTES} (two {}-px tile slots … 128 MiB)",
                    self.page_bytes, self.tile_size
                ),
            ));
        }
        Ok(())
    }
}

/// What [`write_pack`] wrote.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PackStats {
    /// Images packed.
    pub images: usize,
    /// Images without any kept tile.
    pub empty_images: usize,
    /// Tiles kept.
    pub tiles_kept: u64,
    /// Of those, tiles stored as exact f32 (dynamic range beyond fp16 within the tile).
    pub tiles_f32: u64,
    /// Pool pages.
    pub pages: usize,
    /// Bytes of all pool pages.
    pub pool_bytes: u64,
    /// Bytes of all tile tables.
    pub tile_table_bytes: u64,
    /// Bytes of the whole file.
    pub bytes: u64,
    /// Pixels of all images.
    pub pixels: u64,
    /// Pixels above the threshold (the nonzero pixels at threshold 0).
    pub pixels_kept: u64,
    /// Dense fp16 size of all images (2 bytes per pixel).
    pub dense_f16_bytes: u64,
    /// CSR size of the same pixels (see [`csr_bytes_for`]).
    pub csr_bytes: u64,
    /// Most bytes of encoded images waiting to be written at any time (bounded by the chunk size,
    /// independent of the number of images).
    pub peak_pending_bytes: u64,
    /// Most images handed out by the source but not yet written at any time.
    pub peak_pending_images: usize,
}

impl PackStats {
    /// File size over the dense fp16 size.
    pub fn ratio_to_dense_f16(&self) -> f64 {
        ratio(self.bytes, self.dense_f16_bytes)
    }
    /// File size over the CSR size.
    pub fn ratio_to_csr(&self) -> f64 {
        ratio(self.bytes, self.csr_bytes)
    }
}

/// `a / b`, or NaN when `b` is 0.
pub(crate) fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 {
        f64::NAN
    } else {
        a as f64 / b as f64
    }
}
