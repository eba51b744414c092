//! [`write_pack`]: streams a scan into a `.lvpack` file.
//!
//! Images are requested from the scan's source and encoded in parallel (rayon) in chunks of a
//! bounded number of images; a writer thread places each chunk's tiles into pool pages in image
//! order and writes them as they come, so at most three chunks (one being encoded, one queued, one
//! being written) are held at a time. Tile tables go to a spill file next to the output and are
//! copied into the pack at the end; the per-image records (40 bytes each, like the cameras the
//! scan already holds) stay in memory. The pack is written under a unique temporary name beside it
//! ([`crate::files::TempOutput`]) and renamed when complete, so a failed, killed or concurrent run
//! never leaves a file that looks finished; an output that is one of the scan's input files is
//! refused.

use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::sync_channel;

use rayon::prelude::*;

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{Hemisphere, Scan};

use super::csr::csr_bytes_for;
use super::format::{
    self, align_up, page_name, CameraCounts, EncodingMeta, FootprintMeta, Header, ImageEntry, IntrinsicsMeta,
    PackMetadata, PagesMeta, PoolLayout, SectionInfo, SphereMeta, ThresholdKind, ThresholdMeta, TileCounts,
    SECTION_ALIGN,
};
use super::tiles::{self, EncodedImage, TileMode, EMPTY_TILE, MAX_RELATIVE_ERROR};
use super::{PackOptions, PackStats, Threshold};

/// Longest camera label stored (bytes).
const MAX_LABEL_BYTES: usize = 1 << 16;

/// Writes `scan` to `path` as a `.lvpack` file and returns what was written.
///
/// Images come from `scan.source` one by one (several at once from the rayon pool); memory use
/// depends on [`PackOptions::chunk_images`] and the image size, not on the number of images.
/// `progress(done, total)` is called after each image is written, from a writer thread. An
/// existing file at `path` is replaced only when the new pack is complete.
///
/// Errors: invalid options or scan, an image of the wrong size or with a negative or non-finite
/// value (named), an image source error, I/O errors on the output, or more than `u32::MAX − 1`
/// pool slots.
pub fn write_pack(
    scan: &Scan,
    path: &Path,
    opts: &PackOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<PackStats> {
    opts.validate()?;
    scan.set.validate()?;
    if let Some(c) = scan.set.cameras.iter().find(|c| c.label.len() > MAX_LABEL_BYTES) {
        return Err(NearfieldError::image(
            c.label.chars().take(64).collect::<String>(),
            format!("label longer than {MAX_LABEL_BYTES} bytes"),
        ));
    }
    let n = scan.set.cameras.len();
    let entry = tiles::entry_bytes(opts.tile_size);
    let slots_per_page = (opts.page_bytes / entry as u64).min(u64::from(u32::MAX));
    let chunk = match opts.chunk_images {
        0 => 4 * rayon::current_num_threads(),
        c => c,
    }
    .max(1);

    let name = path
        .file_name()
        .ok_or_else(|| NearfieldError::invalid("output", format!("{} has no file name", path.display())))?;
    // Never replace what is being read (a pack repacked onto itself, an image of the scan).
    crate::files::ensure_not_input(path, scan.source.input_files().iter().map(PathBuf::as_path))
        .map_err(|m| NearfieldError::invalid("output", m))?;
    let mut tables_name = name.to_os_string();
    tables_name.push(".tables");
    // Unique temporary files beside the output (two writers of one output never share one; a
    // killed writer's are removed by the next), removed on error, the pack renamed into place.
    let create = |target: &Path| {
        let (mut t, _stale) = crate::files::TempOutput::create(target).map_err(|e| NearfieldError::io(target, e))?;
        let file = t
            .take_file()
            .ok_or_else(|| NearfieldError::invalid("output", "temporary file not open"))?;
        Ok::<_, NearfieldError>((t, file))
    };
    let (pack_temp, file) = create(path)?;
    let (spill_temp, spill) = create(&path.with_file_name(tables_name))?;
    let partial = pack_temp.path().to_path_buf();
    let spill_path = spill_temp.path().to_path_buf();
    let mut pool = PoolWriter {
        out: BufWriter::with_capacity(4 << 20, file),
        path: partial.clone(),
        pos: 0,
        entry: entry as u64,
        slots_per_page,
        page: None,
        sections: Vec::new(),
        spill: Spill {
            out: BufWriter::with_capacity(1 << 20, spill),
            path: spill_path,
            crc: crc32fast::Hasher::new(),
            entries: 0,
        },
        images: Vec::with_capacity(n),
        table_window: opts.page_bytes / 4,
        global: Vec::new(),
        counts: Counts::default(),
    };
    pool.zeros(SECTION_ALIGN)?;

    let pending_bytes = AtomicU64::new(0);
    let peak_bytes = AtomicU64::new(0);
    let handed = AtomicUsize::new(0);
    let written = AtomicUsize::new(0);
    let peak_images = AtomicUsize::new(0);
    let threshold = opts.threshold;

    let (encode_result, pool) = std::thread::scope(|s| {
        let (tx, rx) = sync_channel::<Vec<EncodedImage>>(1);
        let (pending_bytes, written) = (&pending_bytes, &written);
        let writer = s.spawn(move || -> Result<PoolWriter> {
            for batch in rx {
                for img in batch {
                    let held = img.held_bytes() as u64;
                    pool.add(img)?;
                    pending_bytes.fetch_sub(held, Ordering::Relaxed);
                    let done = written.fetch_add(1, Ordering::Relaxed) + 1;
                    progress(done, n);
                }
            }
            Ok(pool)
        });
        let mut result = Ok(());
        for start in (0..n).step_by(chunk) {
            let end = (start + chunk).min(n);
            let batch: Result<Vec<EncodedImage>> = (start..end)
                .into_par_iter()
                .map(|i| {
                    let out = handed.fetch_add(1, Ordering::Relaxed) + 1;
                    peak_images.fetch_max(out.saturating_sub(written.load(Ordering::Relaxed)), Ordering::Relaxed);
                    let cam = &scan.set.cameras[i];
                    let k = scan.set.intrinsics_of(i);
                    let img = scan.source.image(i)?;
                    if img.width != k.width || img.height != k.height {
                        return Err(NearfieldError::image(
                            &cam.label,
                            format!(
                                "size {}×{} differs from the camera's {}×{}",
                                img.width, img.height, k.width, k.height
                            ),
                        ));
                    }
                    tiles::encode_image(&img, &cam.label, opts.tile_size, threshold, entry)
                })
                .collect();
            match batch {
                Ok(batch) => {
                    let held: u64 = batch.iter().map(|e| e.held_bytes() as u64).sum();
                    let now = pending_bytes.fetch_add(held, Ordering::Relaxed) + held;
                    peak_bytes.fetch_max(now, Ordering::Relaxed);
                    if tx.send(batch).is_err() {
                        break; // the writer stopped on an error; join() reports it
                    }
                }
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        drop(tx);
        let pool = writer.join().unwrap_or_else(|p| std::panic::resume_unwind(p));
        (result, pool)
    });
    let pool = pool?;
    encode_result?;
    let mut stats = pool.finish(scan, opts)?;
    drop(spill_temp);
    pack_temp.commit().map_err(|e| NearfieldError::io(path, e))?;
    stats.peak_pending_bytes = peak_bytes.load(Ordering::Relaxed);
    stats.peak_pending_images = peak_images.load(Ordering::Relaxed);
    Ok(stats)
}

/// Tile-table entries on their way to the spill file.
struct Spill {
    out: BufWriter<File>,
    path: PathBuf,
    crc: crc32fast::Hasher,
    entries: u64,
}

/// The page being filled.
struct OpenPage {
    index: usize,
    start: u64,
    used: u64,
    crc: crc32fast::Hasher,
}

#[derive(Debug, Default)]
struct Counts {
    tiles: u64,
    tiles_f32: u64,
    empty_images: u64,
    pixels: u64,
    pixels_kept: u64,
    csr_bytes: u64,
    lower: u64,
    upper: u64,
}

/// Places tiles in pages and writes them.
struct PoolWriter {
    out: BufWriter<File>,
    path: PathBuf,
    pos: u64,
    entry: u64,
    slots_per_page: u64,
    page: Option<OpenPage>,
    sections: Vec<SectionInfo>,
    spill: Spill,
    images: Vec<ImageEntry>,
    /// Tile-table window (entries).
    table_window: u64,
    /// Scratch: global slot of each of the current image's tiles.
    global: Vec<u32>,
    counts: Counts,
}

impl PoolWriter {
    fn write(&mut self, bytes: &[u8]) -> Result<()> {
        self.out
            .write_all(bytes)
            .map_err(|e| NearfieldError::io(&self.path, e))?;
        self.pos += bytes.len() as u64;
        Ok(())
    }

    fn zeros(&mut self, n: u64) -> Result<()> {
        const Z: [u8; 4096] = [0; 4096];
        let mut left = n;
        while left > 0 {
            let k = left.min(Z.len() as u64) as usize;
            self.write(&Z[..k])?;
            left -= k as u64;
        }
        Ok(())
    }

    fn align(&mut self) -> Result<()> {
        self.zeros(align_up(self.pos) - self.pos)
    }

    fn close_page(&mut self) {
        if let Some(p) = self.page.take() {
            self.sections.push(SectionInfo {
                name: page_name(p.index),
                offset: p.start,
                length: p.used * self.entry,
                crc32: p.crc.finalize(),
            });
        }
    }

    fn open_page(&mut self) -> Result<()> {
        let index = self.page.as_ref().map_or(self.sections.len(), |p| p.index + 1);
        self.close_page();
        self.align()?;
        self.page = Some(OpenPage {
            index,
            start: self.pos,
            used: 0,
            crc: crc32fast::Hasher::new(),
        });
        Ok(())
    }

    fn page_bytes(&mut self, bytes: &[u8]) -> Result<()> {
        self.write(bytes)?;
        if let Some(p) = self.page.as_mut() {
            p.crc.update(bytes);
        }
        Ok(())
    }

    /// Reserves `slots` consecutive slots in one page; returns the first one's global index.
    fn place(&mut self, slots: u64) -> Result<u32> {
        let s = self.slots_per_page;
        match self.page.as_ref().map(|p| p.used) {
            Some(used) if used + slots <= s => {}
            Some(used) if used < s => {
                // An f32 tile does not fit the page's last slot: leave it unused (zeros).
                let pad = vec![0u8; ((s - used) * self.entry) as usize];
                self.page_bytes(&pad)?;
                if let Some(p) = self.page.as_mut() {
                    p.used = s;
                }
                self.open_page()?;
            }
            _ => self.open_page()?,
        }
        let p = self
            .page
            .as_mut()
            .ok_or_else(|| NearfieldError::invalid("pack", "no open page"))?;
        let g = p.index as u64 * s + p.used;
        if g + slots >= u64::from(EMPTY_TILE) {
            return Err(NearfieldError::invalid(
                "pack",
                format!("more than {} pool slots: split the scan", EMPTY_TILE - 1),
            ));
        }
        p.used += slots;
        Ok(g as u32)
    }

    fn add(&mut self, img: EncodedImage) -> Result<()> {
        self.global.clear();
        let mut at = 0usize;
        for &mode in &img.modes {
            let slots = mode.slots() as u64;
            let g = self.place(slots)?;
            let len = (slots * self.entry) as usize;
            self.page_bytes(&img.bytes[at..at + len])?;
            at += len;
            self.global.push(g);
            if mode == TileMode::F32 {
                self.counts.tiles_f32 += 1;
            }
        }
        // Keep the table inside one window: pad with empty entries up to the next boundary.
        let len = img.table.len() as u64;
        let used = self.spill.entries % self.table_window;
        let pad = if used + len > self.table_window && len <= self.table_window {
            self.table_window - used
        } else {
            0
        };
        let mut buf = Vec::with_capacity((pad + len) as usize * 4);
        for _ in 0..pad {
            buf.extend_from_slice(&EMPTY_TILE.to_le_bytes());
        }
        let table_offset = self.spill.entries + pad;
        for &t in &img.table {
            let v = if t == EMPTY_TILE {
                EMPTY_TILE
            } else {
                self.global[t as usize]
            };
            buf.extend_from_slice(&v.to_le_bytes());
        }
        self.spill
            .out
            .write_all(&buf)
            .map_err(|e| NearfieldError::io(&self.spill.path, e))?;
        self.spill.crc.update(&buf);
        self.spill.entries += pad + len;
        let c = &mut self.counts;
        c.tiles += img.modes.len() as u64;
        c.empty_images += u64::from(img.modes.is_empty());
        c.pixels += u64::from(img.width) * u64::from(img.height);
        c.pixels_kept += img.pixels_kept;
        c.csr_bytes += csr_bytes_for(img.height, img.pixels_kept);
        self.images.push(ImageEntry {
            width: img.width,
            height: img.height,
            bbox: img.bbox,
            table_offset,
            tiles: img.modes.len() as u32,
            max_cd_m2: img.max,
        });
        Ok(())
    }

    fn section(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
        self.align()?;
        self.sections.push(SectionInfo {
            name: name.into(),
            offset: self.pos,
            length: bytes.len() as u64,
            crc32: crc32fast::hash(bytes),
        });
        self.write(bytes)
    }

    /// Writes the small sections, copies the tile tables in, writes the directory and the header
    /// (the caller renames the file into place).
    fn finish(mut self, scan: &Scan, opts: &PackOptions) -> Result<PackStats> {
        self.close_page();
        let pages: Vec<SectionInfo> = self.sections.clone();
        let pool_bytes: u64 = pages.iter().map(|p| p.length).sum();
        let slots_total = pool_bytes / self.entry;
        let layout = PoolLayout {
            tile_size: opts.tile_size,
            entry_bytes: self.entry as u32,
            slots_per_page: self.slots_per_page as u32,
            page_count: pages.len() as u32,
            slots_total,
            table_entries: self.spill.entries,
            table_window: self.table_window as u32,
        };
        for c in &scan.set.cameras {
            match c.hemisphere {
                Hemisphere::Lower => self.counts.lower += 1,
                Hemisphere::Upper => self.counts.upper += 1,
            }
        }
        let set = &scan.set;
        let k = &set.intrinsics;
        let c = &self.counts;
        let (kind, value) = match opts.threshold {
            Threshold::Absolute(v) => (ThresholdKind::Absolute, v),
            Threshold::RelativeToImageMax(v) => (ThresholdKind::Relative, v),
        };
        let meta = PackMetadata {
            format: "lvpack".into(),
            version: if opts.proxy.is_some() {
                format::VERSION
            } else {
                format::VERSION_1
            },
            created_by: format!("lumiview {}", env!("CARGO_PKG_VERSION")),
            source: opts.source.clone(),
            capture_sphere: SphereMeta {
                centre_m: set.sphere.centre_m.to_array(),
                radius_m: set.sphere.radius_m,
            },
            intrinsics: IntrinsicsMeta {
                width: k.width,
                height: k.height,
                principal_px: k.principal_px.to_array(),
                focal_px: k.focal_px.to_array(),
            },
            cameras: CameraCounts {
                total: set.cameras.len() as u64,
                lower: c.lower,
                upper: c.upper,
            },
            encoding: EncodingMeta {
                scheme: "f16-pow2-tile-scale/f32".into(),
                tile_size: opts.tile_size,
                entry_bytes: self.entry as u32,
                max_relative_error: MAX_RELATIVE_ERROR,
                threshold: ThresholdMeta { kind, value },
            },
            pages: PagesMeta {
                count: layout.page_count,
                slots_per_page: layout.slots_per_page,
                page_bytes_max: opts.page_bytes,
                slots_total,
            },
            tiles: TileCounts {
                kept: c.tiles,
                f32: c.tiles_f32,
                empty_images: c.empty_images,
            },
            footprint: FootprintMeta {
                pixels: c.pixels,
                pixels_kept: c.pixels_kept,
                dense_f16_bytes: 2 * c.pixels,
                csr_bytes: c.csr_bytes,
                pool_bytes,
                tile_table_bytes: 4 * self.spill.entries,
            },
            proxy: opts.proxy.as_ref().map(|p| format::ProxyMeta {
                triangles: (p.triangles.len() / 3) as u64,
                kind: if p.bound { "bound" } else { "surface" }.into(),
                source: p.source.clone(),
            }),
        };
        let json = serde_json::to_vec_pretty(&meta)
            .map_err(|e| NearfieldError::invalid("metadata", format!("cannot serialise: {e}")))?;
        self.section(format::METADATA, &json)?;
        self.section(format::CAMERAS, &format::encode_cameras(set))?;
        self.section(format::IMAGES, &format::encode_images(&layout, &self.images))?;
        if let Some(p) = &opts.proxy {
            if p.triangles.len() / 3 > format::MAX_PROXY_TRIANGLES as usize {
                return Err(NearfieldError::invalid(
                    "proxy",
                    format!(
                        "{} triangles exceed {}",
                        p.triangles.len() / 3,
                        format::MAX_PROXY_TRIANGLES
                    ),
                ));
            }
            self.section(format::PROXY, &format::encode_proxy(&p.triangles, p.bound))?;
        }

        // Tile tables: copy the spill file in.
        self.align()?;
        let spill_path = self.spill.path.clone();
        let spill_io = |e| NearfieldError::io(&spill_path, e);
        let expected_crc = self.spill.crc.clone().finalize();
        self.spill.out.flush().map_err(spill_io)?;
        let mut spill = self.spill.out.get_ref().try_clone().map_err(spill_io)?;
        spill.seek(SeekFrom::Start(0)).map_err(spill_io)?;
        let (start, len) = (self.pos, 4 * self.spill.entries);
        let mut crc = crc32fast::Hasher::new();
        let mut buf = vec![0u8; 1 << 20];
        let mut left = len;
        while left > 0 {
            let k = left.min(buf.len() as u64) as usize;
            spill.read_exact(&mut buf[..k]).map_err(spill_io)?;
            crc.update(&buf[..k]);
            self.write(&buf[..k])?;
            left -= k as u64;
        }
        let crc32 = crc.finalize();
        if crc32 != expected_crc {
            return Err(NearfieldError::format(
                &spill_path,
                "tile tables changed on disk while packing",
            ));
        }
        self.sections.push(SectionInfo {
            name: format::TILE_TABLES.into(),
            offset: start,
            length: len,
            crc32,
        });
        drop(spill);
        // The spill file is removed with its temporary name by the caller.

        // Directory, then the header at offset 0.
        let pad = self.pos.next_multiple_of(8) - self.pos;
        self.zeros(pad)?;
        let dir = format::encode_directory(&self.sections);
        let dir_offset = self.pos;
        self.write(&dir)?;
        let header = Header {
            version: if opts.proxy.is_some() {
                format::VERSION
            } else {
                format::VERSION_1
            },
            file_len: self.pos,
            dir_offset,
            dir_count: self.sections.len() as u32,
            dir_crc: crc32fast::hash(&dir),
        };
        let file_len = self.pos;
        let mut file = self
            .out
            .into_inner()
            .map_err(|e| NearfieldError::io(&self.path, e.into_error()))?;
        let io = |e| NearfieldError::io(&self.path, e);
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.write_all(&header.encode()).map_err(io)?;
        // No fsync: it would cost more than the packing of a small scan, and a pack cut short by a
        // crash is never mistaken for a good one (the header states the length, every section has a
        // checksum). A caller that needs durability syncs the file itself.
        drop(file);

        let c = &self.counts;
        Ok(PackStats {
            images: self.images.len(),
            empty_images: c.empty_images as usize,
            tiles_kept: c.tiles,
            tiles_f32: c.tiles_f32,
            pages: pages.len(),
            pool_bytes,
            tile_table_bytes: len,
            bytes: file_len,
            pixels: c.pixels,
            pixels_kept: c.pixels_kept,
            dense_f16_bytes: 2 * c.pixels,
            csr_bytes: c.csr_bytes,
            peak_pending_bytes: 0,
            peak_pending_images: 0,
        })
    }
}
