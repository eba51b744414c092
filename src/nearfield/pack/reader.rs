//! [`Pack`]: a `.lvpack` file opened for random access.
//!
//! Opening reads and checks the header, the directory and every small section (metadata, cameras,
//! image table, tile tables) with their checksums, and cross-checks them, so every tile-table entry
//! is known to point into the pool. Pages are read with positioned reads when first needed, checked
//! against their CRC32, and kept in a bounded cache. Nothing here trusts a size declared in the file
//! before checking it against the file's length.

use std::fs::File;
use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{ImageSource, LuminanceImage, RayImageSet, Scan};

use super::format::{
    self, decode_cameras, decode_directory, decode_header, decode_images, page_name, HeaderError, ImageEntry,
    PackMetadata, PoolLayout, SectionInfo, DIR_ENTRY_BYTES, HEADER_BYTES, MAX_PAGE_BYTES, PAGE_PREFIX, SECTION_ALIGN,
};
use super::tiles::{self, decode_tile, decode_value, EMPTY_TILE, MAX_TILE_SIZE, MIN_TILE_SIZE};

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

/// The verified bytes of one pool page (shared; cheap to clone).
#[derive(Clone)]
pub struct PageBytes(Arc<Vec<u8>>);

impl Deref for PageBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        &self.0
    }
}

impl AsRef<[u8]> for PageBytes {
    fn as_ref(&self) -> &[u8] {
        &self.0
    }
}

impl std::fmt::Debug for PageBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PageBytes({} bytes)", self.0.len())
    }
}

/// What [`Pack::verify`] checked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VerifyReport {
    /// Pages whose checksums matched.
    pub pages: usize,
    /// Bytes read: pages and padding.
    pub bytes: u64,
    /// Tiles decoded, every value finite and ≥ 0 cd/m².
    pub tiles: u64,
}

/// Where the bytes come from.
enum Backing {
    File(File),
    Memory(Vec<u8>),
}

impl Backing {
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        match self {
            Backing::Memory(m) => {
                let src = usize::try_from(offset)
                    .ok()
                    .and_then(|o| m.get(o..o.checked_add(buf.len())?))
                    .ok_or_else(|| std::io::Error::from(std::io::ErrorKind::UnexpectedEof))?;
                buf.copy_from_slice(src);
                Ok(())
            }
            Backing::File(f) => read_exact_at(f, buf, offset),
        }
    }
}

#[cfg(unix)]
fn read_exact_at(f: &File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(f, buf, offset)
}

#[cfg(windows)]
fn read_exact_at(f: &File, mut buf: &mut [u8], mut offset: u64) -> std::io::Result<()> {
    use std::os::windows::fs::FileExt;
    while !buf.is_empty() {
        match f.seek_read(buf, offset)? {
            0 => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            n => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
        }
    }
    Ok(())
}

#[cfg(not(any(unix, windows)))]
fn read_exact_at(_: &File, _: &mut [u8], _: u64) -> std::io::Result<()> {
    Err(std::io::Error::new(
        std::io::ErrorKind::Unsupported,
        "positioned reads are not available",
    ))
}

/// Pages read so far.
struct PageCache {
    pages: Vec<Option<(PageBytes, u64)>>,
    /// Pages found damaged (the error's message): a damaged page is read and checked once, then
    /// every later use fails at once (a render asks for its tiles thousands of times).
    bad: Vec<Option<String>>,
    bytes: u64,
    tick: u64,
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

    fn load(path: PathBuf, backing: Backing, file_len: u64, opts: &OpenOptions) -> Result<Pack> {
        let corrupt = |section: &str, message: String| NearfieldError::Corrupt {
            path: path.clone(),
            section: section.into(),
            message,
        };
        let read = |offset: u64, len: u64| -> Result<Vec<u8>> {
            // Callers have checked offset + len ≤ file_len, so this allocation is bounded by the file.
            let mut buf = vec![0u8; len as usize];
            backing
                .read_exact_at(&mut buf, offset)
                .map_err(|e| NearfieldError::io(&path, e))?;
            Ok(buf)
        };
        let head = read(0, file_len.min(HEADER_BYTES as u64))?;
        let header = decode_header(&head).map_err(|e| match e {
            HeaderError::NotPack(m) => NearfieldError::format(&path, m),
            HeaderError::Checksum => corrupt("header", "checksum mismatch".into()),
            HeaderError::Version(v) => NearfieldError::Unsupported {
                path: path.clone(),
                message: format!(
                    ".lvpack version {v}; this lumiview reads versions {} and {}",
                    format::VERSION_1,
                    format::VERSION
                ),
            },
            HeaderError::Field(m) => corrupt("header", m),
        })?;
        if header.file_len != file_len {
            return Err(NearfieldError::format(
                &path,
                if file_len < header.file_len {
                    format!(
                        "truncated: the header says {} bytes, the file has {file_len}",
                        header.file_len
                    )
                } else {
                    format!("{file_len} bytes, more than the {} the header states", header.file_len)
                },
            ));
        }
        let dir_len = u64::from(header.dir_count) * DIR_ENTRY_BYTES as u64;
        if header.dir_offset < HEADER_BYTES as u64 || header.dir_offset.checked_add(dir_len) != Some(file_len) {
            return Err(corrupt(
                "header",
                format!(
                    "directory at {} with {} entries does not end the {file_len}-byte file",
                    header.dir_offset, header.dir_count
                ),
            ));
        }
        let dir = read(header.dir_offset, dir_len)?;
        if crc32fast::hash(&dir) != header.dir_crc {
            return Err(corrupt("directory", "checksum mismatch".into()));
        }
        let sections = decode_directory(&dir).map_err(|m| corrupt("directory", m))?;

        // Places: aligned, inside [4096, directory), no overlaps; names known and unique.
        let mut by_offset: Vec<&SectionInfo> = sections.iter().collect();
        by_offset.sort_by_key(|s| s.offset);
        let mut end = HEADER_BYTES as u64;
        for s in &by_offset {
            let s_end = s.offset.checked_add(s.length);
            if s.offset % SECTION_ALIGN != 0 || s.offset < end || s_end.is_none_or(|e| e > header.dir_offset) {
                return Err(corrupt(
                    "directory",
                    format!(
                        "section '{}' at {} (+{}) is misaligned, overlaps another or runs past the directory",
                        s.name, s.offset, s.length
                    ),
                ));
            }
            end = s_end.unwrap_or(end);
        }
        let find = |name: &str| -> Result<&SectionInfo> {
            let mut it = sections.iter().filter(|s| s.name == name);
            match (it.next(), it.next()) {
                (Some(s), None) => Ok(s),
                (None, _) => Err(corrupt("directory", format!("no '{name}' section"))),
                _ => Err(corrupt("directory", format!("more than one '{name}' section"))),
            }
        };
        let small: &[&str] = if header.version == format::VERSION_1 {
            &[format::METADATA, format::CAMERAS, format::IMAGES, format::TILE_TABLES]
        } else {
            &[
                format::METADATA,
                format::CAMERAS,
                format::IMAGES,
                format::TILE_TABLES,
                format::PROXY,
            ]
        };
        let page_count = sections.iter().filter(|s| s.name.starts_with(PAGE_PREFIX)).count();
        if let Some(s) = sections.iter().find(|s| {
            !small.contains(&s.name.as_str())
                && s.name
                    .strip_prefix(PAGE_PREFIX)
                    .and_then(|i| i.parse::<usize>().ok())
                    .is_none_or(|i| i >= page_count || page_name(i) != s.name)
        }) {
            return Err(corrupt("directory", format!("unexpected section '{}'", s.name)));
        }
        let pages = (0..page_count)
            .map(|i| find(&page_name(i)).cloned())
            .collect::<Result<Vec<_>>>()?;
        let mut bodies = Vec::with_capacity(3);
        for name in [format::METADATA, format::CAMERAS, format::IMAGES] {
            let s = find(name)?;
            let body = read(s.offset, s.length)?;
            let crc = crc32fast::hash(&body);
            if crc != s.crc32 {
                return Err(corrupt(
                    name,
                    format!("checksum mismatch (stored {:08x}, computed {crc:08x})", s.crc32),
                ));
            }
            bodies.push(body);
        }
        let [meta_b, cam_b, img_b]: [Vec<u8>; 3] = bodies
            .try_into()
            .map_err(|_| corrupt("directory", "missing small sections".into()))?;
        // The tile tables (a few % of the pool, hundreds of MiB for a full scan) are read in chunks
        // straight into their u32 form.
        let ts = find(format::TILE_TABLES)?;
        if ts.length % 4 != 0 {
            return Err(corrupt(
                format::TILE_TABLES,
                format!("{} bytes is not a whole number of u32 entries", ts.length),
            ));
        }
        // Hundreds of MiB for a full scan: a failed allocation is an error, not an abort.
        let mut tables: Vec<u32> = crate::files::try_vec((ts.length / 4) as usize, "the tile tables")
            .map_err(|e| NearfieldError::io(&path, e))?;
        let mut crc = crc32fast::Hasher::new();
        let mut at = 0u64;
        while at < ts.length {
            let chunk = read(ts.offset + at, (ts.length - at).min(8 << 20))?;
            crc.update(&chunk);
            tables.extend(
                chunk
                    .chunks_exact(4)
                    .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            );
            at += chunk.len() as u64;
        }
        let crc = crc.finalize();
        if crc != ts.crc32 {
            return Err(corrupt(
                format::TILE_TABLES,
                format!("checksum mismatch (stored {:08x}, computed {crc:08x})", ts.crc32),
            ));
        }

        let metadata: PackMetadata =
            serde_json::from_slice(&meta_b).map_err(|e| corrupt(format::METADATA, format!("invalid JSON: {e}")))?;
        if metadata.format != "lvpack" || metadata.version != header.version {
            return Err(corrupt(
                format::METADATA,
                format!(
                    "format '{}' version {} is not lvpack {}",
                    metadata.format, metadata.version, header.version
                ),
            ));
        }
        let set = decode_cameras(&cam_b).map_err(|m| corrupt(format::CAMERAS, m))?;
        set.validate().map_err(|e| corrupt(format::CAMERAS, e.to_string()))?;
        let (layout, images) = decode_images(&img_b).map_err(|m| corrupt(format::IMAGES, m))?;
        let bad_images = |m: String| corrupt(format::IMAGES, m);
        let t = layout.tile_size;
        if !(MIN_TILE_SIZE..=MAX_TILE_SIZE).contains(&t)
            || layout.entry_bytes as usize != tiles::entry_bytes(t)
            || layout.slots_per_page < 2
            || u64::from(layout.slots_per_page) * u64::from(layout.entry_bytes) > MAX_PAGE_BYTES
        {
            return Err(bad_images(format!(
                "pool layout (tile {t} px, {} bytes per slot, {} slots per page) is not valid",
                layout.entry_bytes, layout.slots_per_page
            )));
        }
        if layout.page_count as usize != pages.len() || images.len() != set.cameras.len() {
            return Err(bad_images(format!(
                "{} pages and {} images, but the directory has {} pages and the cameras section {} cameras",
                layout.page_count,
                images.len(),
                pages.len(),
                set.cameras.len()
            )));
        }
        let (e, s) = (u64::from(layout.entry_bytes), u64::from(layout.slots_per_page));
        let mut slots = 0u64;
        for (i, p) in pages.iter().enumerate() {
            let last = i + 1 == pages.len();
            if p.length % e != 0 || p.length == 0 || p.length > s * e || (!last && p.length != s * e) {
                return Err(corrupt(
                    &p.name,
                    format!("{} bytes is not a whole page of {e}-byte slots", p.length),
                ));
            }
            slots += p.length / e;
        }
        if slots != layout.slots_total {
            return Err(bad_images(format!(
                "{} slots stated, the pages hold {slots}",
                layout.slots_total
            )));
        }
        if layout.table_entries != tables.len() as u64 {
            return Err(bad_images(format!(
                "{} tile-table entries stated, the section has {}",
                layout.table_entries,
                tables.len()
            )));
        }
        if let Some((k, g)) = tables
            .iter()
            .enumerate()
            .find(|(_, &g)| g != EMPTY_TILE && u64::from(g) >= layout.slots_total)
        {
            return Err(corrupt(
                format::TILE_TABLES,
                format!("entry {k} points at slot {g}, beyond the pool's {}", layout.slots_total),
            ));
        }
        let window = u64::from(layout.table_window);
        if window == 0 || window > MAX_PAGE_BYTES / 4 {
            return Err(bad_images(format!("tile-table window of {window} entries")));
        }
        for (i, im) in images.iter().enumerate() {
            let k = set.intrinsics_of(i);
            let area = im.bbox.area();
            if area <= window && im.table_offset % window + area > window {
                return Err(bad_images(format!(
                    "image {i}: tile table at {} crosses a {window}-entry window",
                    im.table_offset
                )));
            }
            let (tx, ty) = (k.width.div_ceil(t), k.height.div_ceil(t));
            let b = im.bbox;
            let inside = u64::from(b.x0) + u64::from(b.w) <= u64::from(tx)
                && u64::from(b.y0) + u64::from(b.h) <= u64::from(ty)
                && (b.w == 0) == (b.h == 0);
            let range = im
                .table_offset
                .checked_add(b.area())
                .filter(|&end| end <= layout.table_entries)
                .map(|end| im.table_offset as usize..end as usize);
            let range = match (im.width == k.width && im.height == k.height && inside, range) {
                (true, Some(r)) => r,
                _ => {
                    return Err(bad_images(format!(
                    "image {i}: size {}×{}, tile box {:?} or table at {} do not fit the camera's {}×{} / the tables",
                    im.width, im.height, b, im.table_offset, k.width, k.height
                )))
                }
            };
            let kept = tables[range].iter().filter(|&&g| g != EMPTY_TILE).count();
            if kept != im.tiles as usize {
                return Err(bad_images(format!(
                    "image {i}: {} tiles stated, its table lists {kept}",
                    im.tiles
                )));
            }
        }
        let m = &metadata;
        if m.encoding.tile_size != t
            || m.encoding.entry_bytes != layout.entry_bytes
            || m.pages.count != layout.page_count
            || m.pages.slots_per_page != layout.slots_per_page
            || m.pages.slots_total != layout.slots_total
            || m.cameras.total != set.cameras.len() as u64
        {
            return Err(corrupt(
                format::METADATA,
                "tile size, page or camera counts disagree with the binary sections".into(),
            ));
        }
        // The proxy (version 2, optional): checked whole at open, like the other small sections.
        let proxy = match sections.iter().find(|s| s.name == format::PROXY) {
            None => {
                if metadata.proxy.is_some() {
                    return Err(corrupt(
                        format::METADATA,
                        "names a proxy but there is no proxy section".into(),
                    ));
                }
                None
            }
            Some(s) => {
                if s.length > format::PROXY_HEADER_BYTES as u64 + 36 * format::MAX_PROXY_TRIANGLES {
                    return Err(corrupt(
                        format::PROXY,
                        format!("{} bytes is beyond the limit", s.length),
                    ));
                }
                let body = read(s.offset, s.length)?;
                let crc = crc32fast::hash(&body);
                if crc != s.crc32 {
                    return Err(corrupt(
                        format::PROXY,
                        format!("checksum mismatch (stored {:08x}, computed {crc:08x})", s.crc32),
                    ));
                }
                let (triangles, bound) = format::decode_proxy(&body).map_err(|m| corrupt(format::PROXY, m))?;
                let meta = metadata
                    .proxy
                    .as_ref()
                    .ok_or_else(|| corrupt(format::METADATA, "no proxy entry for the proxy section".into()))?;
                let kind_ok = matches!(meta.kind.as_str(), "bound" | "surface");
                if !kind_ok || meta.triangles != (triangles.len() / 3) as u64 || (meta.kind == "bound") != bound {
                    return Err(corrupt(
                        format::METADATA,
                        "the proxy entry disagrees with the proxy section".into(),
                    ));
                }
                Some(super::PackProxy {
                    triangles,
                    bound,
                    source: meta.source.clone(),
                })
            }
        };
        let pack = Pack {
            path,
            backing,
            file_len,
            dir_offset: header.dir_offset,
            cache: Mutex::new(PageCache {
                pages: vec![None; pages.len()],
                bad: vec![None; pages.len()],
                bytes: 0,
                tick: 0,
            }),
            cache_budget: opts.cache_bytes,
            sections,
            pages,
            metadata,
            layout,
            set,
            images,
            tables,
            proxy,
        };
        if opts.verify_pages {
            pack.verify()?;
        }
        Ok(pack)
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

    /// The verified bytes of page `index` (read and checked against its CRC32 the first time, then
    /// cached within [`OpenOptions::cache_bytes`]).
    pub fn page_bytes(&self, index: usize) -> Result<PageBytes> {
        let sec = self
            .pages
            .get(index)
            .ok_or_else(|| NearfieldError::invalid("page", format!("{index} is outside 0…{}", self.pages.len())))?;
        {
            let mut c = self.cache.lock().unwrap_or_else(PoisonError::into_inner);
            c.tick += 1;
            let tick = c.tick;
            if let Some(Some((p, used))) = c.pages.get_mut(index) {
                *used = tick;
                return Ok(p.clone());
            }
            if let Some(Some(m)) = c.bad.get(index) {
                return Err(self.corrupt(&sec.name, m.clone()));
            }
        }
        // Read outside the lock so other threads keep sampling cached pages.
        let mut buf = vec![0u8; sec.length as usize];
        self.backing
            .read_exact_at(&mut buf, sec.offset)
            .map_err(|e| NearfieldError::io(&self.path, e))?;
        let crc = crc32fast::hash(&buf);
        if crc != sec.crc32 {
            let m = format!("checksum mismatch (stored {:08x}, computed {crc:08x})", sec.crc32);
            if let Some(slot) = self
                .cache
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .bad
                .get_mut(index)
            {
                *slot = Some(m.clone());
            }
            return Err(self.corrupt(&sec.name, m));
        }
        let page = PageBytes(Arc::new(buf));
        let mut c = self.cache.lock().unwrap_or_else(PoisonError::into_inner);
        c.tick += 1;
        let tick = c.tick;
        if let Some(slot) = c.pages.get_mut(index) {
            if slot.is_none() {
                *slot = Some((page.clone(), tick));
                c.bytes += sec.length;
            }
        }
        while c.bytes > self.cache_budget {
            let victim = c
                .pages
                .iter()
                .enumerate()
                .filter(|(i, p)| *i != index && p.is_some())
                .min_by_key(|(_, p)| p.as_ref().map_or(u64::MAX, |(_, t)| *t))
                .map(|(i, _)| i);
            match victim {
                Some(v) => {
                    if let Some((p, _)) = c.pages[v].take() {
                        c.bytes -= p.len() as u64;
                    }
                }
                None => break,
            }
        }
        Ok(page)
    }

    /// Reads every page and checks its CRC32, checks that all bytes between sections are zero, so
    /// any changed byte of the file is found, and decodes every tile the tile tables point at,
    /// checking that each value is a finite luminance ≥ 0 (a pack written with valid checksums
    /// around NaN, infinite or negative values is refused too). Errors name the page (and slot) or
    /// `padding`.
    pub fn verify(&self) -> Result<VerifyReport> {
        let mut bytes = 0u64;
        // Every slot a table points at, in pool order: each page is read once, checked, and its
        // tiles decoded from the same bytes.
        let mut slots: Vec<u32> = self.tables.iter().copied().filter(|&g| g != EMPTY_TILE).collect();
        slots.sort_unstable();
        slots.dedup();
        let mut next = slots.iter().peekable();
        let mut tiles = 0u64;
        let mut values = vec![0f32; (self.layout.tile_size * self.layout.tile_size) as usize];
        let e = self.layout.entry_bytes as usize;
        for (i, p) in self.pages.iter().enumerate() {
            let mut buf =
                crate::files::try_vec(p.length as usize, &p.name).map_err(|e| NearfieldError::io(&self.path, e))?;
            buf.resize(p.length as usize, 0);
            self.backing
                .read_exact_at(&mut buf, p.offset)
                .map_err(|e| NearfieldError::io(&self.path, e))?;
            let crc = crc32fast::hash(&buf);
            if crc != p.crc32 {
                return Err(self.corrupt(
                    &p.name,
                    format!("checksum mismatch (stored {:08x}, computed {crc:08x})", p.crc32),
                ));
            }
            bytes += p.length;
            let page = PageBytes(Arc::new(buf));
            while let Some(&&g) = next.peek() {
                match self.slot_location(g) {
                    Some((pg, _)) if pg == i => {}
                    Some((pg, _)) if pg > i => break,
                    _ => return Err(self.corrupt(format::TILE_TABLES, format!("slot {g} is beyond the pool"))),
                }
                next.next();
                decode_tile(self.slot(&page, g)?, e, &mut values)
                    .map_err(|m| self.corrupt(&p.name, format!("slot {g}: {m}")))?;
                tiles += 1;
            }
        }
        if let Some(&g) = next.next() {
            return Err(self.corrupt(format::TILE_TABLES, format!("slot {g} is beyond the pool")));
        }
        let mut buf = vec![0u8; 8 << 20];
        let mut spans: Vec<(u64, u64)> = self.sections.iter().map(|s| (s.offset, s.offset + s.length)).collect();
        spans.sort_unstable();
        let mut gaps = Vec::new();
        let mut end = HEADER_BYTES as u64;
        for (a, b) in spans {
            gaps.push((end, a));
            end = b;
        }
        gaps.push((end, self.dir_offset));
        for (a, b) in gaps {
            let mut at = a;
            while at < b {
                let k = (b - at).min(buf.len() as u64) as usize;
                self.backing
                    .read_exact_at(&mut buf[..k], at)
                    .map_err(|e| NearfieldError::io(&self.path, e))?;
                if let Some(j) = buf[..k].iter().position(|&x| x != 0) {
                    return Err(self.corrupt(
                        "padding",
                        format!("byte {} between sections is not zero", at + j as u64),
                    ));
                }
                at += k as u64;
                bytes += k as u64;
            }
        }
        Ok(VerifyReport {
            pages: self.pages.len(),
            bytes,
            tiles,
        })
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
