//! [`Pack`]: a `.lvpack` file opened for random access.
//!
//! Opening reads and checks the header, the directory and every small section (metadata, cameras,
//! image table, tile tables) with their checksums, and cross-checks them, so every tile-table entry
//! is known to point into the pool. Pages are read with positioned reads when first needed, checked
//! against their CRC32, and kept in a bounded cache. Nothing here trusts a size declared in the file
//! before checking it against the file's length.
//!
//! - `open.rs`: opening ([`Pack::open`]: header, directory, small sections and their cross-checks)
//!   and [`Pack::verify`] (every page, every tile, the padding);
//! - `pages.rs`: where the bytes come from (a file with positioned reads, or memory) and the
//!   bounded cache of verified pages ([`Pack::page_bytes`]).
//!
//! This file holds [`Pack`] itself: its accessors, and sampling and decoding tiles and images.

mod open;
mod pages;

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{ImageSource, LuminanceImage, RayImageSet, Scan};

pub use self::open::VerifyReport;
pub use self::pages::PageBytes;

use self::pages::{Backing, PageCache};
use super::format::{self, page_name, ImageEntry, PackMetadata, PoolLayout, SectionInfo};
use super::tiles::{self, decode_tile, decode_value, EMPTY_TILE};

/// How [`Pack::open_with`] opens a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OpenOptions {
    /// Verify every page's checksum (and that padding is zero) while opening, instead of each page
    /// when it is first read.
    pub verify_pages: bool,
    /// Bytes of pages kept in memory after reading (least recently used ones are dropped first;
    /// the page in use is always kept). Default 1 GiB.
    pub cache_bytes: u64,
}

impl Default for OpenOptions {
    fn default() -> Self {
        Self {
            verify_pages: false,
            cache_bytes: 1 << 30,
        }
    }
}

/// A `.lvpack` file opened for random access. `Send + Sync`: sample and decode from many threads.
pub struct Pack {
    path: PathBuf,
    backing: Backing,
    file_len: u64,
    dir_offset: u64,
    sections: Vec<SectionInfo>,
    proxy: Option<super::PackProxy>,
    pages: Vec<SectionInfo>,
    metadata: PackMetadata,
    layout: PoolLayout,
    set: RayImageSet,
    images: Vec<ImageEntry>,
    tables: Vec<u32>,
    cache: Mutex<PageCache>,
    cache_budget: u64,
}

impl std::fmt::Debug for Pack {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pack")
            .field("path", &self.path)
            .field("images", &self.images.len())
            .field("layout", &self.layout)
            .finish_non_exhaustive()
    }
}

impl Pack {
    /// Opens `path`: checks header, directory and the small sections (page checksums are checked
    /// when each page is first read).
    ///
    /// Errors: I/O; [`NearfieldError::Format`] for a file that is not a pack or is truncated;
    /// [`NearfieldError::Unsupported`] for another format version; [`NearfieldError::Corrupt`]
    /// naming the section (`header`, `directory`, `metadata`, `cameras`, `images`, `tile-tables`,
    /// `page.N`) whose checksum or content is wrong.
    pub fn open(path: &Path) -> Result<Pack> {
        Self::open_with(path, &OpenOptions::default())
    }

    /// [`Pack::open`] with options (eager page verification, cache size).
    pub fn open_with(path: &Path, opts: &OpenOptions) -> Result<Pack> {
        let (file, len) =
            crate::files::open_regular(path, u64::MAX, "a .lvpack").map_err(|e| NearfieldError::io(path, e))?;
        Self::load(path.to_path_buf(), Backing::File(file), len, opts)
    }

    /// Opens a pack held in memory (tests, fuzzing); errors name the file `<memory>`.
    pub fn from_bytes(bytes: Vec<u8>, opts: &OpenOptions) -> Result<Pack> {
        let len = bytes.len() as u64;
        Self::load(PathBuf::from("<memory>"), Backing::Memory(bytes), len, opts)
    }

    fn corrupt(&self, section: &str, message: String) -> NearfieldError {
        NearfieldError::Corrupt {
            path: self.path.clone(),
            section: section.into(),
            message,
        }
    }

    /// The file's path (`<memory>` for [`Pack::from_bytes`]).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// File length in bytes.
    pub fn file_len(&self) -> u64 {
        self.file_len
    }

    /// The JSON metadata.
    pub fn metadata(&self) -> &PackMetadata {
        &self.metadata
    }

    /// Tile size, slot size and page geometry of the pool.
    pub fn layout(&self) -> &PoolLayout {
        &self.layout
    }

    /// Cameras, capture sphere and intrinsics.
    pub fn rayset(&self) -> &RayImageSet {
        &self.set
    }

    /// Number of images (= cameras).
    pub fn image_count(&self) -> usize {
        self.images.len()
    }

    /// Per-image records (size, tile box, table offset, tile count, maximum).
    pub fn images(&self) -> &[ImageEntry] {
        &self.images
    }

    /// All tile tables back to back (`u32` global slot per tile, [`EMPTY_TILE`] when not stored);
    /// image `i`'s table is `images()[i].table_offset ..+ bbox.w · bbox.h`. This is what a GPU binds
    /// next to the pages, in windows of [`PoolLayout::table_window`] entries that no image's table
    /// crosses.
    pub fn tile_tables(&self) -> &[u32] {
        &self.tables
    }

    /// Image `image`'s tile table (row-major over its tile box), or `None` for a bad index.
    pub fn tile_table(&self, image: usize) -> Option<&[u32]> {
        let e = self.images.get(image)?;
        let start = e.table_offset as usize;
        self.tables.get(start..start + e.bbox.area() as usize)
    }

    /// The section directory (names, offsets, lengths, CRC32s).
    pub fn sections(&self) -> &[SectionInfo] {
        &self.sections
    }

    /// The proxy mesh stored with the scan (version-2 packs), if any.
    pub fn proxy(&self) -> Option<&super::PackProxy> {
        self.proxy.as_ref()
    }

    /// Number of pool pages.
    pub fn page_count(&self) -> usize {
        self.pages.len()
    }

    /// Where page `index` lies in the file (offset a multiple of 4096, so it can be memory-mapped
    /// and uploaded as is).
    pub fn page_section(&self, index: usize) -> Option<&SectionInfo> {
        self.pages.get(index)
    }

    /// Page and byte offset within the page of global slot `slot`, or `None` beyond the pool.
    pub fn slot_location(&self, slot: u32) -> Option<(usize, usize)> {
        if slot == EMPTY_TILE || u64::from(slot) >= self.layout.slots_total {
            return None;
        }
        let s = self.layout.slots_per_page;
        Some((
            (slot / s) as usize,
            (slot % s) as usize * self.layout.entry_bytes as usize,
        ))
    }

    fn entry(&self, image: usize) -> Result<&ImageEntry> {
        self.images.get(image).ok_or_else(|| {
            NearfieldError::invalid("image index", format!("{image} is outside 0…{}", self.images.len()))
        })
    }

    /// The slot bytes of global slot `g`: from its start to at most two slots on (or the page end),
    /// plus the page name for errors.
    fn slot<'p>(&self, page: &'p PageBytes, g: u32) -> Result<&'p [u8]> {
        let (p, off) = self
            .slot_location(g)
            .ok_or_else(|| self.corrupt(format::TILE_TABLES, format!("slot {g} is beyond the pool")))?;
        let e = self.layout.entry_bytes as usize;
        page.get(off..(off + 2 * e).min(page.len()))
            .ok_or_else(|| self.corrupt(&page_name(p), format!("slot {g} lies beyond the page's end")))
    }

    /// Calls `f` with the bytes of global slot `g` (from its start to at most two slots on, or the
    /// end of its page: an f32 tile takes two). Reads (and verifies) the slot's page on first use.
    ///
    /// Errors: a slot beyond the pool or its page, I/O, or a corrupt page.
    pub fn with_slot<R>(&self, g: u32, f: impl FnOnce(&[u8]) -> R) -> Result<R> {
        let (p, _) = self
            .slot_location(g)
            .ok_or_else(|| self.corrupt(format::TILE_TABLES, format!("slot {g} is beyond the pool")))?;
        let page = self.page_bytes(p)?;
        Ok(f(self.slot(&page, g)?))
    }

    /// Decodes the tile at global slot `g` into `out` (`tile_size²` luminances, cd/m², row-major)
    /// and says how it is stored.
    ///
    /// Errors: as [`Pack::with_slot`], or a malformed tile.
    pub fn decode_slot(&self, g: u32, out: &mut [f32]) -> Result<tiles::TileMode> {
        let e = self.layout.entry_bytes as usize;
        self.with_slot(g, |slot| decode_tile(slot, e, out))?.map_err(|m| {
            let p = self.slot_location(g).map_or(0, |(p, _)| p);
            self.corrupt(&page_name(p), format!("slot {g}: {m}"))
        })
    }

    /// The stored luminance (cd/m²) of pixel (`col`, `row`) of image `image`; 0 where no tile is
    /// stored. Reads (and verifies) the tile's page on first use.
    ///
    /// Errors: an index outside the image count or the image ([`NearfieldError::InvalidArgument`]),
    /// I/O, or a corrupt page.
    pub fn sample(&self, image: usize, col: u32, row: u32) -> Result<f32> {
        let e = self.entry(image)?;
        if col >= e.width || row >= e.height {
            return Err(NearfieldError::invalid(
                "pixel",
                format!("({col}, {row}) is outside image {image}'s {}×{}", e.width, e.height),
            ));
        }
        let t = self.layout.tile_size;
        let (tx, ty) = (col / t, row / t);
        let b = e.bbox;
        if tx < b.x0 || ty < b.y0 || tx - b.x0 >= b.w || ty - b.y0 >= b.h {
            return Ok(0.0);
        }
        let at = e.table_offset as usize + (ty - b.y0) as usize * b.w as usize + (tx - b.x0) as usize;
        let g = self.tables.get(at).copied().unwrap_or(EMPTY_TILE);
        let Some((p, _)) = self.slot_location(g) else {
            return Ok(0.0);
        };
        let page = self.page_bytes(p)?;
        let slot = self.slot(&page, g)?;
        let index = ((row % t) * t + col % t) as usize;
        decode_value(slot, self.layout.entry_bytes as usize, (t * t) as usize, index)
            .map_err(|m| self.corrupt(&page_name(p), format!("slot {g}: {m}")))
    }

    /// Decodes image `image` into a dense luminance image (cd/m²; zeros where no tile is stored).
    /// Allocates `width · height` floats as the cameras section states (each ≤ 65,536).
    pub fn decode_image(&self, image: usize) -> Result<LuminanceImage> {
        let e = *self.entry(image)?;
        let mut img = LuminanceImage::zeros(e.width, e.height);
        let t = self.layout.tile_size as usize;
        let (w, h) = (e.width as usize, e.height as usize);
        let b = e.bbox;
        let table = self.tile_table(image).unwrap_or(&[]);
        let mut tile = vec![0.0f32; t * t];
        let mut current: Option<(usize, PageBytes)> = None;
        for by in 0..b.h as usize {
            for bx in 0..b.w as usize {
                let g = table.get(by * b.w as usize + bx).copied().unwrap_or(EMPTY_TILE);
                let Some((p, _)) = self.slot_location(g) else {
                    continue;
                };
                let page = match &current {
                    Some((cp, page)) if *cp == p => page.clone(),
                    _ => {
                        let page = self.page_bytes(p)?;
                        current = Some((p, page.clone()));
                        page
                    }
                };
                let slot = self.slot(&page, g)?;
                decode_tile(slot, self.layout.entry_bytes as usize, &mut tile)
                    .map_err(|m| self.corrupt(&page_name(p), format!("slot {g}: {m}")))?;
                let (tx, ty) = (b.x0 as usize + bx, b.y0 as usize + by);
                let (c0, c1) = (tx * t, ((tx + 1) * t).min(w));
                for rr in 0..t {
                    let r = ty * t + rr;
                    if r >= h || c0 >= c1 {
                        break;
                    }
                    img.data[r * w + c0..r * w + c1].copy_from_slice(&tile[rr * t..rr * t + (c1 - c0)]);
                }
            }
        }
        Ok(img)
    }

    /// The pack as a [`Scan`] whose images are decoded from it (e.g. to repack with other options).
    pub fn into_scan(self) -> Scan {
        Scan {
            set: self.set.clone(),
            source: Box::new(self),
        }
    }
}

impl ImageSource for Pack {
    fn image(&self, index: usize) -> Result<LuminanceImage> {
        self.decode_image(index)
    }
    fn input_files(&self) -> Vec<PathBuf> {
        vec![self.path.clone()]
    }
}
