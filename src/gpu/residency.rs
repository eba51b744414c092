//! Residency of a `.lvpack`'s tiles on the GPU within a memory budget (CPU bookkeeping; no wgpu).
//!
//! The pack's tile tables and tile slots are cut into **chunks** of [`CHUNK_BYTES`]:
//! - table chunk `t` holds table entries `[t·E, (t+1)·E)`, E = `CHUNK_BYTES / 4`;
//! - slot chunk `s` holds pool slots `[s·S, (s+1)·S)` plus one spare slot (a copy of the next
//!   chunk's first slot, so an f32 tile's second half is always in the same chunk), with
//!   S = ⌊CHUNK_BYTES / entry_bytes⌋ − 1.
//!
//! A chunk id is its index in the chunk map: table chunks first, then slot chunks. The GPU pool holds
//! `capacity` chunks; the chunk map says where each pack chunk lives (or [`EMPTY`]). Each camera needs
//! a contiguous range of table chunks and one of slot chunks (images are packed one after another).
//! Before a frame, [`Residency::make_resident`] brings in every chunk of every camera the frame can
//! select, evicting the least recently used chunks that the frame does not need; when the frame needs
//! more than the pool holds it is an error, never a partial frame.

use std::collections::BTreeSet;

use crate::nearfield::pack::{Pack, EMPTY_TILE};

/// Bytes of one residency chunk (64 KiB: fine enough that a view of a few hundred cameras needs a
/// small part of a large scan).
pub const CHUNK_BYTES: u64 = 64 << 10;

/// Chunk-map value of a chunk that is not resident.
pub const EMPTY: u32 = u32::MAX;

/// How a pack is cut into chunks, and which chunks each camera needs.
#[derive(Debug, Clone)]
pub struct ChunkLayout {
    /// Table entries per table chunk.
    pub entries_per_chunk: u32,
    /// Slots per slot chunk (without the spare).
    pub slots_per_chunk: u32,
    /// Bytes of one slot.
    pub entry_bytes: u32,
    /// Number of table chunks (slot chunk `s` has id `table_chunks + s`).
    pub table_chunks: u32,
    /// Number of slot chunks.
    pub slot_chunks: u32,
    /// Per camera: inclusive ranges of chunk ids (table, slots); `None` for a camera without tiles.
    pub camera_chunks: Vec<Option<([u32; 2], [u32; 2])>>,
}

impl ChunkLayout {
    /// Cuts `pack` into chunks.
    pub fn new(pack: &Pack) -> Result<Self, String> {
        let layout = pack.layout();
        let entry_bytes = layout.entry_bytes;
        let per = (CHUNK_BYTES / u64::from(entry_bytes)).saturating_sub(1);
        if per == 0 || 2 * u64::from(entry_bytes) > CHUNK_BYTES {
            return Err(format!(
                "pool slots of {entry_bytes} bytes do not fit a {CHUNK_BYTES}-byte residency chunk twice"
            ));
        }
        let slots_per_chunk = per as u32;
        let entries_per_chunk = (CHUNK_BYTES / 4) as u32;
        let table_chunks = layout.table_entries.div_ceil(u64::from(entries_per_chunk));
        let slot_chunks = layout.slots_total.div_ceil(per);
        if table_chunks + slot_chunks >= u64::from(EMPTY) || layout.table_entries >= u64::from(u32::MAX) {
            return Err("the pack is too large for 32-bit chunk and table addressing".into());
        }
        let table_chunks = table_chunks as u32;
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
            let s0 = table_chunks + lo / slots_per_chunk;
            let s1 = table_chunks + hi / slots_per_chunk;
            camera_chunks.push(Some(([t0, t1], [s0, s1])));
        }
        Ok(ChunkLayout {
            entries_per_chunk,
            slots_per_chunk,
            entry_bytes,
            table_chunks,
            slot_chunks: slot_chunks as u32,
            camera_chunks,
        })
    }

    /// Number of chunk ids.
    pub fn chunk_count(&self) -> u32 {
        self.table_chunks + self.slot_chunks
    }

    /// Every chunk the cameras need (sorted, unique).
    pub fn chunks_of(&self, cameras: impl IntoIterator<Item = u32>) -> Vec<u32> {
        let mut set = BTreeSet::new();
        for c in cameras {
            if let Some(Some((t, s))) = self.camera_chunks.get(c as usize) {
                set.extend(t[0]..=t[1]);
                set.extend(s[0]..=s[1]);
            }
        }
        set.into_iter().collect()
    }

    /// Every chunk any camera needs.
    pub fn all_needed(&self) -> Vec<u32> {
        self.chunks_of(0..self.camera_chunks.len() as u32)
    }

    /// The bytes of chunk `id` as the GPU holds them (`CHUNK_BYTES` or fewer).
    pub fn chunk_bytes(&self, pack: &Pack, id: u32) -> crate::nearfield::error::Result<Vec<u8>> {
        if id < self.table_chunks {
            let tables = pack.tile_tables();
            let a = id as usize * self.entries_per_chunk as usize;
            let b = (a + self.entries_per_chunk as usize).min(tables.len());
            return Ok(bytemuck::cast_slice(&tables[a.min(b)..b]).to_vec());
        }
        let s = id - self.table_chunks;
        let layout = pack.layout();
        let first = u64::from(s) * u64::from(self.slots_per_chunk);
        let end = (first + u64::from(self.slots_per_chunk) + 1).min(layout.slots_total);
        let e = self.entry_bytes as usize;
        let mut out = vec![0u8; (end - first) as usize * e];
        let mut g = first;
        while g < end {
            let Some((page, off)) = pack.slot_location(g as u32) else {
                break;
            };
            // Slots run on within a page until its end.
            let in_page = u64::from(layout.slots_per_page) - (g % u64::from(layout.slots_per_page));
            let n = in_page.min(end - g) as usize;
            let bytes = pack.page_bytes(page)?;
            let dst = (g - first) as usize * e;
            let avail = bytes.len().saturating_sub(off).min(n * e);
            out[dst..dst + avail].copy_from_slice(&bytes[off..off + avail]);
            g += n as u64;
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
