//! Opening a [`Pack`] (`Pack::load`, behind [`Pack::open`] and [`Pack::from_bytes`]): the header,
//! the directory and every small section read, checksummed and cross-checked, so every tile-table
//! entry is known to point into the pool; and [`Pack::verify`], which reads and checks everything
//! else (every page, every tile the tables point at, the padding between sections).

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use super::pages::{Backing, PageBytes, PageCache};
use super::{OpenOptions, Pack};
use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::pack::format::{
    self, decode_cameras, decode_directory, decode_header, decode_images, page_name, HeaderError, PackMetadata,
    SectionInfo, DIR_ENTRY_BYTES, HEADER_BYTES, MAX_PAGE_BYTES, PAGE_PREFIX, SECTION_ALIGN,
};
use crate::nearfield::pack::tiles::{self, decode_tile, EMPTY_TILE, MAX_TILE_SIZE, MIN_TILE_SIZE};
use crate::nearfield::pack::PackProxy;

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

impl Pack {
    pub(super) fn load(path: PathBuf, backing: Backing, file_len: u64, opts: &OpenOptions) -> Result<Pack> {
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
                Some(PackProxy {
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
}
