//! Residency of a `.lvpack`'s tiles on the GPU within a memory budget (CPU bookkeeping; no wgpu).
//!
//! **GPU slots carry an apron.** The pool holds each tile as the pack stores it (a header, then fp16
//! values × the tile's scale or exact f32 values) followed by its **apron**: the 2T + 1 values just
//! right of and below the tile (the column x = T for rows 0…T, corner included, then the row y = T
//! for columns 0…T − 1), as exact f32, read from the neighbouring tiles (0 beyond the image or where
//! no tile is kept). A bilinear footprint (x0…x0 + 1, y0…y0 + 1) then lies in the slot of the tile
//! holding (x0, y0): the shader reads one table entry and one header per camera sample instead of
//! four of each. An fp16 slot is [`gpu_slot_words`] words (the pack's slot plus the apron); an f32
//! tile takes two consecutive slots, as in the pack, with its apron after its T² values.
//!
//! A footprint whose (x0, y0) lies in a tile the pack does not keep, while a neighbour right, below
//! or diagonally below is kept, still needs that neighbour's values: such a tile gets an
//! **apron-only slot** (zeros, then the apron) after the pack's slots, and the GPU's copy of the tile
//! table points at it. The shader clamps the tile to the camera's tile box, so a footprint just left
//! of or above the box uses the box's first tile (the texels outside it are dark).
//!
//! The tile tables and the slots are cut into **chunks** of [`CHUNK_BYTES`]:
//! - table chunk `t` holds table entries `[t·E, (t+1)·E)`, E = `CHUNK_BYTES / 4`;
//! - slot chunk `s` holds slots `[s·S, (s+1)·S)` plus one spare slot (a copy of the next chunk's
//!   first slot, so an f32 tile's second half is always in the same chunk), with
//!   S = ⌊CHUNK_BYTES / slot bytes⌋ − 1; slots number the pack's slots first, then the apron-only
//!   slots.
//!
//! A chunk id is its index in the chunk map: table chunks first, then slot chunks. The GPU pool holds
//! `capacity` chunks; the chunk map says where each pack chunk lives (or [`EMPTY`]). Each camera needs
//! a contiguous range of table chunks and one or two ranges of slot chunks (its kept tiles, and its
//! apron-only slots). Before a frame, [`Residency::make_resident`] brings in every chunk of every
//! camera the frame can select, evicting the least recently used chunks that the frame does not need;
//! when the frame needs more than the pool holds it is an error, never a partial frame.

use std::collections::{BTreeMap, BTreeSet};

use crate::nearfield::pack::{Pack, EMPTY_TILE};

/// Bytes of one residency chunk (64 KiB: fine enough that a view of a few hundred cameras needs a
/// small part of a large scan).
pub const CHUNK_BYTES: u64 = 64 << 10;

/// Chunk-map value of a chunk that is not resident.
pub const EMPTY: u32 = u32::MAX;

/// Words of one GPU pool slot for tiles of edge `tile` px whose pack slot is `entry_bytes`: the pack's
/// slot and the tile's apron of 2·tile + 1 f32 values.
pub fn gpu_slot_words(tile: u32, entry_bytes: u32) -> u32 {
    entry_bytes / 4 + 2 * tile + 1
}

/// Marks a slot that continues the f32 tile before it (in [`ChunkLayout`]'s slot owners).
const CONTINUATION: (u32, u32) = (u32::MAX, u32::MAX);

/// The chunks one camera needs (inclusive ranges of chunk ids).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CameraChunks {
    /// Its tile table.
    pub table: [u32; 2],
    /// Its kept tiles' slots.
    pub slots: [u32; 2],
    /// Its apron-only slots, if it has any.
    pub apron_only: Option<[u32; 2]>,
}

/// How a pack is cut into chunks, and which chunks each camera needs.
#[derive(Debug, Clone)]
pub struct ChunkLayout {
    /// Table entries per table chunk.
    pub entries_per_chunk: u32,
    /// Slots per slot chunk (without the spare).
    pub slots_per_chunk: u32,
    /// Bytes of one slot in the pack.
    pub entry_bytes: u32,
    /// Words of one slot on the GPU (the pack's slot plus the apron).
    pub slot_words: u32,
    /// Tile edge (px).
    pub tile: u32,
    /// Number of table chunks (slot chunk `s` has id `table_chunks + s`).
    pub table_chunks: u32,
    /// Number of slot chunks.
    pub slot_chunks: u32,
    /// Per camera: the chunks it needs; `None` for a camera without tiles.
    pub camera_chunks: Vec<Option<CameraChunks>>,
    /// Slots in the pack (apron-only slots are numbered from here).
    pack_slots: u64,
    /// Per slot (the pack's, then the apron-only ones): the camera and tile-table index (within the
    /// camera's table) of the tile starting there, or [`CONTINUATION`].
    owners: Vec<(u32, u32)>,
    /// Global tile-table index → apron-only slot, for the GPU's copy of the tables.
    apron_only: BTreeMap<u64, u32>,
}

impl ChunkLayout {
    /// Cuts `pack` into chunks.
    pub fn new(pack: &Pack) -> Result<Self, String> {
        let layout = pack.layout();
        let entry_bytes = layout.entry_bytes;
        let tile = layout.tile_size;
        let slot_words = gpu_slot_words(tile, entry_bytes);
        let slot_bytes = 4 * u64::from(slot_words);
        let per = (CHUNK_BYTES / slot_bytes).saturating_sub(1);
        if per == 0 || 2 * slot_bytes > CHUNK_BYTES {
            return Err(format!(
                "GPU slots of {slot_bytes} bytes do not fit a {CHUNK_BYTES}-byte residency chunk twice"
            ));
        }
        let pack_slots = layout.slots_total;
        let mut owners = vec![CONTINUATION; pack_slots as usize];
        let mut apron_only = BTreeMap::new();
        let mut extra_ranges = Vec::with_capacity(pack.image_count());
        for (i, e) in pack.images().iter().enumerate() {
            let table = pack.tile_table(i).unwrap_or(&[]);
            let (w, h) = (e.bbox.w as usize, e.bbox.h as usize);
            let kept = |x: usize, y: usize| x < w && y < h && table.get(y * w + x).is_some_and(|&g| g != EMPTY_TILE);
            let first = owners.len() as u64;
            for (k, &g) in table.iter().enumerate() {
                if g != EMPTY_TILE {
                    if let Some(o) = owners.get_mut(g as usize) {
                        *o = (i as u32, k as u32);
                    }
                    continue;
                }
                let (x, y) = (k % w.max(1), k / w.max(1));
                if kept(x + 1, y) || kept(x, y + 1) || kept(x + 1, y + 1) {
                    apron_only.insert(e.table_offset + k as u64, owners.len() as u32);
                    owners.push((i as u32, k as u32));
                }
            }
            let last = owners.len() as u64;
            extra_ranges.push((last > first).then_some([first, last - 1]));
        }
        let slots_total = owners.len() as u64;
        let slots_per_chunk = per as u32;
        let entries_per_chunk = (CHUNK_BYTES / 4) as u32;
        let table_chunks = layout.table_entries.div_ceil(u64::from(entries_per_chunk));
        let slot_chunks = slots_total.div_ceil(per);
        if table_chunks + slot_chunks >= u64::from(EMPTY)
            || layout.table_entries >= u64::from(u32::MAX)
            || slots_total >= u64::from(EMPTY_TILE)
        {
            return Err("the pack is too large for 32-bit chunk, slot and table addressing".into());
        }
        let table_chunks = table_chunks as u32;
        let slot_chunk = |g: u64| table_chunks + (g / per) as u32;
        let mut camera_chunks = Vec::with_capacity(pack.image_count());
        for (i, e) in pack.images().iter().enumerate() {
            let table = pack.tile_table(i).unwrap_or(&[]);
            let (mut lo, mut hi) = (u32::MAX, 0u32);
            for &g in table {
                if g != EMPTY_TILE {
                    lo = lo.min(g);
                    hi = hi.max(g);
                }
            }
            if lo == u32::MAX {
                camera_chunks.push(None);
                continue;
            }
            let t0 = (e.table_offset / u64::from(entries_per_chunk)) as u32;
            let t1 = ((e.table_offset + table.len() as u64 - 1) / u64::from(entries_per_chunk)) as u32;
            camera_chunks.push(Some(CameraChunks {
                table: [t0, t1],
                slots: [slot_chunk(u64::from(lo)), slot_chunk(u64::from(hi))],
                apron_only: extra_ranges[i].map(|[a, b]| [slot_chunk(a), slot_chunk(b)]),
            }));
        }
        Ok(ChunkLayout {
            entries_per_chunk,
            slots_per_chunk,
            entry_bytes,
            slot_words,
            tile,
            table_chunks,
            slot_chunks: slot_chunks as u32,
            camera_chunks,
            pack_slots,
            owners,
            apron_only,
        })
    }

    /// Number of chunk ids.
    pub fn chunk_count(&self) -> u32 {
        self.table_chunks + self.slot_chunks
    }

    /// Apron-only slots (tiles the pack does not keep whose right, lower or lower-right neighbour it
    /// keeps).
    pub fn apron_only_slots(&self) -> u64 {
        self.owners.len() as u64 - self.pack_slots
    }

    /// Every chunk the cameras need (sorted, unique).
    pub fn chunks_of(&self, cameras: impl IntoIterator<Item = u32>) -> Vec<u32> {
        let mut set = BTreeSet::new();
        for c in cameras {
            if let Some(Some(cc)) = self.camera_chunks.get(c as usize) {
                set.extend(cc.table[0]..=cc.table[1]);
                set.extend(cc.slots[0]..=cc.slots[1]);
                if let Some(a) = cc.apron_only {
                    set.extend(a[0]..=a[1]);
                }
            }
        }
        set.into_iter().collect()
    }

    /// Every chunk any camera needs.
    pub fn all_needed(&self) -> Vec<u32> {
        self.chunks_of(0..self.camera_chunks.len() as u32)
    }

    /// The bytes of chunk `id` as the GPU holds them (`CHUNK_BYTES` or fewer): a table chunk is the
    /// pack's entries with apron-only slots filled in; a slot chunk is its slots with their aprons.
    pub fn chunk_bytes(&self, pack: &Pack, id: u32) -> crate::nearfield::error::Result<Vec<u8>> {
        if id < self.table_chunks {
            let tables = pack.tile_tables();
            let a = id as usize * self.entries_per_chunk as usize;
            let b = (a + self.entries_per_chunk as usize).min(tables.len());
            let mut entries = tables[a.min(b)..b].to_vec();
            for (&k, &g) in self.apron_only.range(a as u64..b as u64) {
                entries[k as usize - a] = g;
            }
            return Ok(bytemuck::cast_slice(&entries).to_vec());
        }
        let s = id - self.table_chunks;
        let first = u64::from(s) * u64::from(self.slots_per_chunk);
        // Tiles start in the chunk's slots proper; the spare only receives an f32 tile's second half.
        let starts = (first + u64::from(self.slots_per_chunk)).min(self.owners.len() as u64);
        let end = (first + u64::from(self.slots_per_chunk) + 1).min(self.owners.len() as u64);
        let sw = self.slot_words as usize;
        let mut words = vec![0u32; end.saturating_sub(first) as usize * sw];
        let t = self.tile as usize;
        let values = t * t;
        let e = self.entry_bytes as usize;
        let mut tile = vec![0.0f32; values];
        for g in first..starts {
            let (cam, k) = self.owners[g as usize];
            if (cam, k) == CONTINUATION {
                continue;
            }
            let at = (g - first) as usize * sw;
            let apron_at = if g < self.pack_slots {
                // The pack's words as they are (header, then fp16 pairs or f32 values).
                let mode = pack.decode_slot(g as u32, &mut tile)?;
                let n = match mode {
                    crate::nearfield::pack::tiles::TileMode::F16Scaled => e / 4,
                    crate::nearfield::pack::tiles::TileMode::F32 => 1 + values,
                };
                pack.with_slot(g as u32, |slot| {
                    for (j, w) in words[at..].iter_mut().take(n.min(slot.len() / 4)).enumerate() {
                        *w = u32::from_le_bytes([slot[4 * j], slot[4 * j + 1], slot[4 * j + 2], slot[4 * j + 3]]);
                    }
                })?;
                at + n
            } else {
                // An apron-only slot: an fp16 tile of zeros with scale 1.
                words[at] = 1.0f32.to_bits();
                at + e / 4
            };
            let apron = self.apron(pack, cam as usize, k as usize)?;
            for (j, v) in apron.into_iter().enumerate() {
                if let Some(w) = words.get_mut(apron_at + j) {
                    *w = v.to_bits();
                }
            }
        }
        Ok(bytemuck::cast_slice(&words).to_vec())
    }

    /// The apron of tile `k` (index in its camera's table) of camera `cam`: the 2T + 1 stored values
    /// right of it (rows 0…T) and below it (columns 0…T − 1), read from the three neighbouring tiles;
    /// 0 beyond the image or where no tile is kept.
    fn apron(&self, pack: &Pack, cam: usize, k: usize) -> crate::nearfield::error::Result<Vec<f32>> {
        let e = &pack.images()[cam];
        let t = self.tile as usize;
        let (w, h) = (e.bbox.w as usize, e.bbox.h as usize);
        let (bx, by) = (k % w.max(1), k / w.max(1));
        let table = pack.tile_table(cam).unwrap_or(&[]);
        let mut tile = vec![0f32; t * t];
        let mut out = vec![0f32; 2 * t + 1];
        // (neighbour dx, dy) → which of its values land where in the apron.
        for (dx, dy) in [(1, 0), (1, 1), (0, 1)] {
            let (x, y) = (bx + dx, by + dy);
            let g = if x < w && y < h {
                table.get(y * w + x).copied()
            } else {
                None
            };
            let Some(g) = g.filter(|&g| g != EMPTY_TILE) else {
                continue;
            };
            pack.decode_slot(g, &mut tile)?;
            match (dx, dy) {
                // Its first column: the column right of the tile, rows 0…T − 1.
                (1, 0) => (0..t).for_each(|r| out[r] = tile[r * t]),
                // Its first value: the corner (T, T).
                (1, 1) => out[t] = tile[0],
                // Its first row: the row below the tile.
                _ => (0..t).for_each(|c| out[t + 1 + c] = tile[c]),
            }
        }
        // Beyond the image there is nothing (a ragged tile's padding included).
        let (x0, y0) = ((e.bbox.x0 as usize + bx) * t, (e.bbox.y0 as usize + by) * t);
        for (a, v) in out.iter_mut().enumerate() {
            let (x, y) = if a <= t { (t, a) } else { (a - t - 1, t) };
            if x0 + x >= e.width as usize || y0 + y >= e.height as usize {
                *v = 0.0;
            }
        }
        Ok(out)
    }
}

/// Which chunk sits in which GPU chunk, and when each was last used.
#[derive(Debug, Clone)]
pub struct Residency {
    /// Pack chunk → GPU chunk, or [`EMPTY`] (uploaded to the GPU as the chunk map).
    pub map: Vec<u32>,
    /// GPU chunk → pack chunk, or [`EMPTY`].
    owner: Vec<u32>,
    /// GPU chunk → frame stamp of its last use.
    stamp: Vec<u64>,
    frame: u64,
    /// Chunks uploaded since creation (for reports and tests).
    pub uploads: u64,
    /// Chunks evicted since creation.
    pub evictions: u64,
}

/// What a frame must upload: (GPU chunk, pack chunk) pairs.
pub type Uploads = Vec<(u32, u32)>;

impl Residency {
    /// An empty pool of `capacity` GPU chunks for `chunks` pack chunks.
    pub fn new(chunks: u32, capacity: u32) -> Self {
        Residency {
            map: vec![EMPTY; chunks as usize],
            owner: vec![EMPTY; capacity as usize],
            stamp: vec![0; capacity as usize],
            frame: 0,
            uploads: 0,
            evictions: 0,
        }
    }

    /// GPU chunks in the pool.
    pub fn capacity(&self) -> u32 {
        self.owner.len() as u32
    }

    /// GPU chunks holding a pack chunk.
    pub fn resident(&self) -> usize {
        self.owner.iter().filter(|o| **o != EMPTY).count()
    }

    /// Makes every chunk of `needed` resident (sorted, unique), evicting least recently used chunks
    /// that are not needed. Returns the uploads to perform; the map is updated as if they were done.
    ///
    /// Errors: `needed` holds more chunks than the pool (nothing changes then).
    pub fn make_resident(&mut self, needed: &[u32]) -> Result<Uploads, String> {
        if needed.len() > self.owner.len() {
            return Err(format!(
                "this view needs {} residency chunks ({} MiB) but the budget holds {} ({} MiB)",
                needed.len(),
                (needed.len() as u64 * CHUNK_BYTES) >> 20,
                self.owner.len(),
                (self.owner.len() as u64 * CHUNK_BYTES) >> 20
            ));
        }
        self.frame += 1;
        let now = self.frame;
        let mut missing = Vec::new();
        for &c in needed {
            match self.map.get(c as usize) {
                Some(&g) if g != EMPTY => self.stamp[g as usize] = now,
                Some(_) => missing.push(c),
                None => return Err(format!("chunk {c} is beyond the pack")),
            }
        }
        if missing.is_empty() {
            return Ok(Vec::new());
        }
        // Free GPU chunks first, then the least recently used ones not stamped this frame.
        let mut victims: Vec<u32> = (0..self.owner.len() as u32)
            .filter(|&g| self.owner[g as usize] == EMPTY || self.stamp[g as usize] != now)
            .collect();
        victims.sort_by_key(|&g| (self.owner[g as usize] != EMPTY, self.stamp[g as usize]));
        let mut out = Vec::with_capacity(missing.len());
        for (c, g) in missing.into_iter().zip(victims) {
            let old = self.owner[g as usize];
            if old != EMPTY {
                self.map[old as usize] = EMPTY;
                self.evictions += 1;
            }
            self.owner[g as usize] = c;
            self.stamp[g as usize] = now;
            self.map[c as usize] = g;
            self.uploads += 1;
            out.push((g, c));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    use crate::nearfield::layout::Layout;
    use crate::nearfield::pack::{write_pack, ImageEntry, PackOptions};
    use crate::nearfield::rayset::{MemorySource, Scan};
    use crate::nearfield::synth::{synth_scan, SynthOptions};

    /// The shader's `footprint()` (shaders/nearfield/sampling.wgsl), step by step, over the GPU chunks.
    fn footprint(cl: &ChunkLayout, chunks: &HashMap<u32, Vec<u32>>, e: &ImageEntry, x0: i32, y0: i32) -> [f32; 4] {
        let t = cl.tile as i32;
        let word = |chunk: u32, w: usize| chunks.get(&chunk).and_then(|c| c.get(w)).copied().unwrap_or(0);
        let tile_of = |x: i32| x.div_euclid(t);
        let b = e.bbox;
        let has_box = b.w > 0 && b.h > 0;
        let bx = (tile_of(x0) - b.x0 as i32).clamp(0, (b.w as i32 - 1).max(0));
        let by = (tile_of(y0) - b.y0 as i32).clamp(0, (b.h as i32 - 1).max(0));
        let (lx, ly) = (x0 - (b.x0 as i32 + bx) * t, y0 - (b.y0 as i32 + by) * t);
        let near = has_box && (-1..t).contains(&lx) && (-1..t).contains(&ly);
        let entry = e.table_offset as u32 + by as u32 * b.w + bx as u32;
        let slot = word(entry / cl.entries_per_chunk, (entry % cl.entries_per_chunk) as usize);
        if !near || slot == EMPTY_TILE {
            return [0.0; 4];
        }
        let per = cl.slots_per_chunk;
        let chunk = cl.table_chunks + slot / per;
        let base = ((slot % per) * cl.slot_words) as usize;
        let scale = f32::from_bits(word(chunk, base));
        let half = scale > 0.0;
        let apron = if half {
            (cl.slot_words - 2 * cl.tile - 1) as usize
        } else {
            1 + (cl.tile * cl.tile) as usize
        };
        let mut v = [0.0; 4];
        for (j, out) in v.iter_mut().enumerate() {
            let (dx, dy) = ((j & 1) as i32, (j >> 1) as i32);
            let (x, y) = (lx + dx, ly + dy);
            let (col, row) = (x0 + dx, y0 + dy);
            if x < 0 || y < 0 || col < 0 || row < 0 || col as u32 >= e.width || row as u32 >= e.height {
                continue;
            }
            let inner = x < t && y < t;
            let k = (y * t + x) as usize;
            let a = if x == t { y } else { t + 1 + x } as usize;
            let w = if !inner {
                apron + a
            } else if half {
                1 + k / 2
            } else {
                1 + k
            };
            let bits = word(chunk, base + w);
            *out = if inner && half {
                let h = half::f16::from_bits(if k % 2 == 1 { (bits >> 16) as u16 } else { bits as u16 });
                h.to_f32() * scale
            } else {
                f32::from_bits(bits)
            };
        }
        v
    }

    /// Every bilinear footprint of every camera, read the way the shader reads the GPU's chunks,
    /// equals the pack's own values: fp16 and f32 tiles, tiles at the image's ragged edge, footprints
    /// reaching across tiles, into tiles the pack does not keep, and off the tile box and the image.
    #[test]
    fn every_footprint_reads_the_packs_values() {
        let opts = SynthOptions {
            luminaire: "led-dots".into(),
            layout: Layout::Fibonacci { count: 6 },
            size: (70, 61),
            ..SynthOptions::default()
        };
        let scan = synth_scan(&opts).unwrap();
        let mut images: Vec<_> = (0..scan.set.cameras.len())
            .map(|i| scan.source.image(i).unwrap())
            .collect();
        // A dynamic range beyond fp16 in a few tiles: they are stored as exact f32.
        for img in &mut images {
            let w = img.width as usize;
            let lit: Vec<usize> = (0..img.data.len())
                .filter(|&i| img.data[i] > 0.0 && i % w % 8 < 7)
                .collect();
            for &i in lit.iter().step_by(3) {
                img.data[i] = 3e12;
                img.data[i + 1] = 1e-4;
            }
        }
        let scan = Scan {
            set: scan.set,
            source: Box::new(MemorySource { images }),
        };
        let dir = std::env::temp_dir().join(format!("lumiview-apron-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("apron.lvpack");
        write_pack(&scan, &path, &PackOptions::default(), &|_, _| {}).unwrap();
        let pack = Pack::open(&path).unwrap();
        assert!(pack.metadata().tiles.f32 > 0, "the scan should hold f32 tiles");
        let cl = ChunkLayout::new(&pack).unwrap();
        assert!(
            cl.apron_only_slots() > 0,
            "the dots' edges should need apron-only slots"
        );
        let chunks: HashMap<u32, Vec<u32>> = cl
            .all_needed()
            .into_iter()
            .map(|c| {
                let bytes = cl.chunk_bytes(&pack, c).unwrap();
                assert!(bytes.len() as u64 <= CHUNK_BYTES);
                (c, bytemuck::pod_collect_to_vec(&bytes))
            })
            .collect();
        let mut lit = 0;
        for (i, e) in pack.images().iter().enumerate() {
            let truth = |c: i32, r: i32| {
                if c < 0 || r < 0 || c as u32 >= e.width || r as u32 >= e.height {
                    0.0
                } else {
                    pack.sample(i, c as u32, r as u32).unwrap()
                }
            };
            for y0 in -3..e.height as i32 + 2 {
                for x0 in -3..e.width as i32 + 2 {
                    let want = [
                        truth(x0, y0),
                        truth(x0 + 1, y0),
                        truth(x0, y0 + 1),
                        truth(x0 + 1, y0 + 1),
                    ];
                    let got = footprint(&cl, &chunks, e, x0, y0);
                    assert_eq!(got, want, "camera {i}, footprint at ({x0}, {y0})");
                    lit += usize::from(want.iter().any(|v| *v > 0.0));
                }
            }
        }
        assert!(lit > 100, "too few lit footprints ({lit}) to mean anything");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn lru_keeps_needed_chunks_and_evicts_the_oldest() {
        let mut r = Residency::new(10, 3);
        let up = r.make_resident(&[0, 1, 2]).unwrap();
        assert_eq!(up.len(), 3);
        // Chunk 0 used again, then 3 arrives: the oldest unused (1 or 2, stamped earlier) goes.
        r.make_resident(&[0]).unwrap();
        r.make_resident(&[2]).unwrap();
        let up = r.make_resident(&[3]).unwrap();
        assert_eq!(up.len(), 1);
        assert_eq!(r.map[1], EMPTY, "chunk 1 was least recently used");
        assert_ne!(r.map[0], EMPTY);
        assert_ne!(r.map[2], EMPTY);
        assert_ne!(r.map[3], EMPTY);
        // A frame needing more than the pool is refused and changes nothing.
        let before = r.map.clone();
        assert!(r.make_resident(&[4, 5, 6, 7]).unwrap_err().contains("budget"));
        assert_eq!(r.map, before);
        // Never more resident than the capacity; the map and owners agree.
        for frame in 0..50u32 {
            let need: Vec<u32> = vec![frame % 10, (frame * 7 + 3) % 10];
            let mut need = need;
            need.sort();
            need.dedup();
            r.make_resident(&need).unwrap();
            assert!(r.resident() <= 3);
            for &c in &need {
                let g = r.map[c as usize];
                assert_ne!(g, EMPTY);
                assert_eq!(r.owner[g as usize], c);
            }
        }
    }
}
