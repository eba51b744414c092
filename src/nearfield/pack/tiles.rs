//! Tiles of the `.lvpack` pool: how one tile's luminances are quantised into a pool slot, how a
//! slot decodes, and how an image is cut into kept tiles over a bounding box.
//!
//! # Encoding
//!
//! A pool slot is `entry_bytes(T) = 4 + ⌈2·T²/4⌉·4` bytes: a 4-byte little-endian `f32` header, then
//! the tile's `T²` values row-major, then zero padding to a multiple of 4 bytes.
//!
//! - **fp16 tile** (header > 0): the header is the tile's scale `s = 2^k` and each value is an IEEE
//!   binary16 `h` with `L = f32(h) · s`. `k = ⌊log₂ max⌋ − 14`, so the tile maximum lands in
//!   `[2^14, 2^15)`, far from fp16's overflow at 65,504; every value down to `max · 2^-29` is a
//!   normal fp16 with round-to-nearest, so its relative error is ≤ 2^-11 ≈ 0.049 %.
//! - **f32 tile** (header = −1.0): a tile whose values do not all meet that bound as fp16 (a dynamic
//!   range above ~2^28 inside one tile, or values near the ends of the f32 range) is stored as
//!   exact `f32` values. It takes two consecutive slots of the same page (values start right after
//!   the header and run on into the second slot).
//!
//! The encoder checks every value of every fp16 tile against the bound and falls back to f32 when
//! one misses it, so the bound [`MAX_RELATIVE_ERROR`] holds for every nonzero value by construction:
//! zeros stay exactly zero, nonzero values never become zero. A GPU decodes a pixel with one `u32`
//! fetch of the header, one fetch of the word holding the fp16 (`unpack2x16float`) and one multiply.

use half::f16;
use half::slice::HalfFloatSliceExt;

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::LuminanceImage;

use super::Threshold;

/// Largest relative quantisation error of any nonzero stored value: 2^-11 ≈ 0.0488 % (fp16 with
/// round-to-nearest in its normal range; f32 tiles are exact).
pub const MAX_RELATIVE_ERROR: f64 = 1.0 / 2048.0;

/// Header value of a tile stored as exact f32 values over two slots.
pub const F32_TILE_MARKER: f32 = -1.0;

/// Smallest tile edge in pixels.
pub const MIN_TILE_SIZE: u32 = 1;

/// Largest tile edge in pixels (64 × 64 values; a slot of 8,196 bytes).
pub const MAX_TILE_SIZE: u32 = 64;

/// Tile-table value of a tile that is not stored (all its pixels are zero, or at or below the
/// threshold).
pub const EMPTY_TILE: u32 = u32::MAX;

/// fp16 scale exponent offset: the tile maximum is scaled into `[2^14, 2^15)`.
const F16_TOP_EXPONENT: i32 = 14;

/// Bytes of one pool slot for tiles of `tile` × `tile` pixels: a 4-byte header plus `tile²` fp16
/// values, padded to a multiple of 4 bytes (so a GPU reads it as `u32` words).
pub fn entry_bytes(tile: u32) -> usize {
    let values = tile as usize * tile as usize;
    4 + (2 * values).div_ceil(4) * 4
}

/// How a tile is stored in the pool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TileMode {
    /// fp16 values times a per-tile power-of-two scale; one slot.
    F16Scaled,
    /// Exact f32 values; two consecutive slots of one page.
    F32,
}

impl TileMode {
    /// Pool slots the tile occupies.
    pub fn slots(self) -> usize {
        match self {
            TileMode::F16Scaled => 1,
            TileMode::F32 => 2,
        }
    }
}

/// Power of two `2^k` as f32 for `k` in the normal range −126…127.
fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// Whether the decoded `d` is within [`MAX_RELATIVE_ERROR`] of `v` (exact arithmetic in f64), with
/// zero kept exactly.
#[cfg(test)]
fn within_bound(v: f32, d: f32) -> bool {
    if v == 0.0 {
        return d == 0.0;
    }
    d.is_finite() && d > 0.0 && (f64::from(d) - f64::from(v)).abs() <= f64::from(v) * MAX_RELATIVE_ERROR
}

/// Encodes one tile's values (row-major, `tile²` of them, zero outside the image; each finite and
/// ≥ 0) and appends one slot (fp16) or two slots (f32) of `entry_bytes` each to `out`. Returns the
/// mode used. Every nonzero value decodes within [`MAX_RELATIVE_ERROR`].
pub fn encode_tile(values: &[f32], entry_bytes: usize, out: &mut Vec<u8>) -> TileMode {
    encode_tile_with(values, entry_bytes, out, &mut TileScratch::default()).0
}

/// Buffers reused from tile to tile.
#[derive(Debug, Default)]
struct TileScratch {
    scaled: Vec<f32>,
    halves: Vec<f16>,
    back: Vec<f32>,
}

/// [`encode_tile`] with reusable buffers; also returns the largest decoded value. Branch-free loops
/// (they vectorise): the bound check `|d − v| ≤ v · 2^-11` in f64 also keeps zeros exact and fails
/// for a nonzero value that would decode to 0 or to a non-finite value.
fn encode_tile_with(values: &[f32], entry_bytes: usize, out: &mut Vec<u8>, s: &mut TileScratch) -> (TileMode, f32) {
    let n = values.len();
    let start = out.len();
    // Valid values are finite and ≥ 0 (−0 included): with the sign masked, their bits order like them.
    let max_bits = values
        .iter()
        .map(|v| (v.to_bits() & 0x7FFF_FFFF) as i32)
        .fold(0, i32::max);
    let max = f32::from_bits(max_bits as u32);
    // The scale must be a normal f32 and so must its inverse: max ≥ 2^-112, and max < 2^128.
    let max_exp = (max_bits >> 23) - 127;
    let k = max_exp - F16_TOP_EXPONENT;
    if max == 0.0 || (-126..=126).contains(&k) {
        let (scale, inv) = if max == 0.0 { (1.0, 1.0) } else { (pow2(k), pow2(-k)) };
        s.scaled.clear();
        s.scaled.extend(values.iter().map(|&v| v * inv));
        s.halves.clear();
        s.halves.resize(n, f16::ZERO);
        s.halves.convert_from_f32_slice(&s.scaled);
        s.back.clear();
        s.back.resize(n, 0.0);
        s.halves.convert_to_f32_slice(&mut s.back);
        let ok = values.iter().zip(&s.back).fold(true, |ok, (&v, &b)| {
            let (v, d) = (f64::from(v), f64::from(b * scale));
            ok & ((d - v).abs() <= v * MAX_RELATIVE_ERROR)
        });
        if ok {
            out.resize(start + entry_bytes, 0);
            out[start..start + 4].copy_from_slice(&scale.to_le_bytes());
            for (dst, h) in out[start + 4..start + 4 + 2 * n].chunks_exact_mut(2).zip(&s.halves) {
                dst.copy_from_slice(&h.to_bits().to_le_bytes());
            }
            // Rounding is monotone, so the largest decoded value is the decoded maximum.
            return (TileMode::F16Scaled, f16::from_f32(max * inv).to_f32() * scale);
        }
    }
    out.resize(start + 2 * entry_bytes, 0);
    out[start..start + 4].copy_from_slice(&F32_TILE_MARKER.to_le_bytes());
    for (dst, v) in out[start + 4..start + 4 + 4 * n].chunks_exact_mut(4).zip(values) {
        dst.copy_from_slice(&v.to_le_bytes());
    }
    (TileMode::F32, max)
}

/// Reads a little-endian u32 at `at` (the caller has checked the range).
fn word(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at + 4)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The mode and scale of the tile whose slot starts at `slot[0]`; `slot` runs to at most two slots
/// or the end of the page. Errors describe what is malformed.
fn tile_header(slot: &[u8], values: usize, entry_bytes: usize) -> std::result::Result<(TileMode, f32), String> {
    let header = f32::from_bits(word(slot, 0).ok_or("slot is cut short by the end of its page")?);
    if header == F32_TILE_MARKER {
        if slot.len() < 4 + 4 * values {
            return Err("an f32 tile's second slot lies beyond the end of its page".into());
        }
        Ok((TileMode::F32, 1.0))
    } else if header.is_finite() && header > 0.0 {
        if slot.len() < entry_bytes {
            return Err("slot is cut short by the end of its page".into());
        }
        Ok((TileMode::F16Scaled, header))
    } else if header == 0.0 {
        Err("the tile table points at an unused slot".into())
    } else {
        Err(format!(
            "tile header {header} is neither a positive scale nor the f32 marker"
        ))
    }
}

/// Decodes one value of a mode-known tile.
fn value_of(slot: &[u8], mode: TileMode, scale: f32, index: usize) -> f32 {
    match mode {
        TileMode::F16Scaled => {
            let at = 4 + 2 * index;
            let h = f16::from_bits(u16::from_le_bytes([slot[at], slot[at + 1]]));
            h.to_f32() * scale
        }
        TileMode::F32 => {
            let at = 4 + 4 * index;
            f32::from_le_bytes([slot[at], slot[at + 1], slot[at + 2], slot[at + 3]])
        }
    }
}

/// Decodes the tile whose slot starts at `slot[0]` into `out` (`tile²` values). `slot` runs to the
/// end of the page (or at least two slots). Returns the mode, or what is malformed (an unused slot,
/// a bad header, a value that is negative or not finite).
pub fn decode_tile(slot: &[u8], entry_bytes: usize, out: &mut [f32]) -> std::result::Result<TileMode, String> {
    let (mode, scale) = tile_header(slot, out.len(), entry_bytes)?;
    for (i, o) in out.iter_mut().enumerate() {
        let v = value_of(slot, mode, scale, i);
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!("tile value {i} decodes to {v}"));
        }
        *o = v;
    }
    Ok(mode)
}

/// Decodes value `index` (row-major within the tile, `< values`) of the tile at `slot[0]`.
pub fn decode_value(slot: &[u8], entry_bytes: usize, values: usize, index: usize) -> std::result::Result<f32, String> {
    if index >= values {
        return Err(format!("value {index} is outside the tile's {values}"));
    }
    let (mode, scale) = tile_header(slot, values, entry_bytes)?;
    let v = value_of(slot, mode, scale, index);
    if !(v.is_finite() && v >= 0.0) {
        return Err(format!("tile value {index} decodes to {v}"));
    }
    Ok(v)
}

/// A rectangle of tiles: `x0, y0` is its top-left tile, `w × h` its size in tiles (0 × 0 for an
/// image without kept tiles).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TileBox {
    /// First tile column.
    pub x0: u32,
    /// First tile row.
    pub y0: u32,
    /// Width in tiles.
    pub w: u32,
    /// Height in tiles.
    pub h: u32,
}

impl TileBox {
    /// Number of tile-table entries (`w · h`).
    pub fn area(&self) -> u64 {
        u64::from(self.w) * u64::from(self.h)
    }
}

/// One image cut into tiles, encoded, not yet placed in the pool.
#[derive(Debug, Clone, Default)]
pub struct EncodedImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bounding box of the kept tiles.
    pub bbox: TileBox,
    /// Tile table over the box, row-major: index into `modes` (the image's n-th kept tile) or
    /// [`EMPTY_TILE`].
    pub table: Vec<u32>,
    /// Mode of each kept tile, in table order.
    pub modes: Vec<TileMode>,
    /// Slot bytes of the kept tiles, concatenated in table order.
    pub bytes: Vec<u8>,
    /// Pixels above the threshold (the nonzero pixels at threshold 0).
    pub pixels_kept: u64,
    /// Largest decoded value (cd/m²).
    pub max: f32,
}

impl EncodedImage {
    /// Heap bytes held (tables and slots), for the writer's accounting.
    pub fn held_bytes(&self) -> usize {
        self.table.len() * 4 + self.modes.len() + self.bytes.len()
    }
}

/// Raises `row_max[tx]` to the largest value (as sign-masked bits) of each `t`-pixel segment of a
/// row whose values are finite and ≥ 0.
fn tile_row_max(row: &[f32], t: usize, row_max: &mut [i32]) {
    let bits = |v: &f32| (v.to_bits() & 0x7FFF_FFFF) as i32;
    for (m, seg) in row_max.iter_mut().zip(row.chunks(t)) {
        let mut chunks = seg.chunks_exact(8);
        let mut sm = (&mut chunks).fold(0i32, |a, c| c.iter().map(bits).fold(a, i32::max));
        sm = chunks.remainder().iter().map(bits).fold(sm, i32::max);
        *m = (*m).max(sm);
    }
}

/// Cuts `image` into `tile` × `tile` tiles, keeps those with a value above the threshold and encodes
/// them. `label` names the image in errors; values must be finite and ≥ 0 (−0 reads as 0).
pub fn encode_image(
    image: &LuminanceImage,
    label: &str,
    tile: u32,
    threshold: Threshold,
    entry_bytes: usize,
) -> Result<EncodedImage> {
    let (w, h) = (image.width as usize, image.height as usize);
    if image.data.len() != w * h {
        return Err(NearfieldError::image(
            label,
            "pixel count does not match width × height",
        ));
    }
    let t = tile as usize;
    let (tiles_x, tiles_y) = (w.div_ceil(t), h.div_ceil(t));
    let bad_pixel = |i: usize| {
        let v = image.data[i];
        NearfieldError::image(
            label,
            format!(
                "pixel (col {}, row {}) is {v}: luminance must be finite and ≥ 0",
                i % w.max(1),
                i / w.max(1)
            ),
        )
    };
    let thr = match threshold {
        Threshold::Absolute(a) => a,
        Threshold::RelativeToImageMax(r) => {
            // Invalid values are reported by pass 1; here they only make the threshold meaningless.
            let max_bits = image
                .data
                .iter()
                .map(|v| (v.to_bits() & 0x7FFF_FFFF) as i32)
                .fold(0, i32::max);
            r * f32::from_bits(max_bits as u32)
        }
    };
    // −0 and anything not ≥ 0 compare as 0 (options are validated; this keeps the bits ordered).
    let thr_bits = if thr > 0.0 { thr.to_bits() } else { 0 };
    // Pass 1: per tile, the largest value. Each row is checked in one branch-free pass (finite and
    // ≥ 0; −0 passes and counts as 0) and skipped when it is all zeros; then the per-tile maxima are
    // taken over the values' bits with the sign masked off (for finite values ≥ 0 the bits order
    // like the values, and as i32 they reduce with vector instructions).
    let mut keep = vec![false; tiles_x * tiles_y];
    let mut row_max = vec![0i32; tiles_x];
    for ty in 0..tiles_y {
        row_max.iter_mut().for_each(|m| *m = 0);
        for r in ty * t..((ty + 1) * t).min(h) {
            let row = &image.data[r * w..(r + 1) * w];
            if !row.iter().fold(true, |ok, &v| ok & (0.0..=f32::MAX).contains(&v)) {
                let j = row.iter().position(|v| !(v.is_finite() && *v >= 0.0)).unwrap_or(0);
                return Err(bad_pixel(r * w + j));
            }
            if row.iter().fold(0u32, |a, v| a | (v.to_bits() & 0x7FFF_FFFF)) == 0 {
                continue;
            }
            tile_row_max(row, t, &mut row_max);
        }
        for (k, m) in keep[ty * tiles_x..(ty + 1) * tiles_x].iter_mut().zip(&row_max) {
            *k = *m as u32 > thr_bits;
        }
    }
    // Bounding box of kept tiles.
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0usize, 0usize);
    for ty in 0..tiles_y {
        for tx in 0..tiles_x {
            if keep[ty * tiles_x + tx] {
                x0 = x0.min(tx);
                x1 = x1.max(tx + 1);
                y0 = y0.min(ty);
                y1 = y1.max(ty + 1);
            }
        }
    }
    let mut out = EncodedImage {
        width: image.width,
        height: image.height,
        ..EncodedImage::default()
    };
    if x0 == usize::MAX {
        return Ok(out);
    }
    out.bbox = TileBox {
        x0: x0 as u32,
        y0: y0 as u32,
        w: (x1 - x0) as u32,
        h: (y1 - y0) as u32,
    };
    out.table.reserve((x1 - x0) * (y1 - y0));
    let mut vals = vec![0.0f32; t * t];
    let mut scratch = TileScratch::default();
    out.bytes.reserve(entry_bytes * keep.iter().filter(|k| **k).count());
    for ty in y0..y1 {
        for tx in x0..x1 {
            if !keep[ty * tiles_x + tx] {
                out.table.push(EMPTY_TILE);
                continue;
            }
            vals.iter_mut().for_each(|v| *v = 0.0);
            for rr in 0..t {
                let r = ty * t + rr;
                if r >= h {
                    break;
                }
                let c0 = tx * t;
                let c1 = (c0 + t).min(w);
                let src = &image.data[r * w + c0..r * w + c1];
                for (d, &s) in vals[rr * t..rr * t + (c1 - c0)].iter_mut().zip(src) {
                    // −0 becomes +0; everything here was checked finite and ≥ 0 in pass 1.
                    *d = if s == 0.0 { 0.0 } else { s };
                }
            }
            out.pixels_kept += vals.iter().filter(|v| v.to_bits() > thr_bits).count() as u64;
            let (mode, max) = encode_tile_with(&vals, entry_bytes, &mut out.bytes, &mut scratch);
            out.max = out.max.max(max);
            out.table.push(out.modes.len() as u32);
            out.modes.push(mode);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(vals: &[f32]) -> (TileMode, Vec<f32>) {
        let e = entry_bytes(8);
        let mut out = Vec::new();
        let mode = encode_tile(vals, e, &mut out);
        assert_eq!(out.len(), mode.slots() * e);
        let mut dec = vec![0.0; vals.len()];
        assert_eq!(decode_tile(&out, e, &mut dec).unwrap(), mode);
        for (i, (&v, &d)) in vals.iter().zip(&dec).enumerate() {
            assert!(within_bound(v, d), "value {i}: {v} → {d}");
            assert_eq!(decode_value(&out, e, vals.len(), i).unwrap(), d);
        }
        (mode, dec)
    }

    #[test]
    fn slot_sizes() {
        assert_eq!(entry_bytes(8), 132);
        assert_eq!(entry_bytes(1), 8);
        assert_eq!(entry_bytes(3), 4 + 20);
        for t in MIN_TILE_SIZE..=MAX_TILE_SIZE {
            let e = entry_bytes(t);
            assert_eq!(e % 4, 0);
            assert!(2 * e >= 4 + 4 * (t * t) as usize, "an f32 tile fits two slots");
        }
    }

    #[test]
    fn peak_beside_one_stays_fp16() {
        let mut v = vec![0.0f32; 64];
        v[0] = 1.0e6;
        v[1] = 1.0;
        v[9] = 3.3e-2;
        let (mode, _) = round_trip(&v);
        assert_eq!(mode, TileMode::F16Scaled);
    }

    #[test]
    fn huge_range_falls_back_to_exact_f32() {
        let mut v = vec![0.0f32; 64];
        v[0] = 1.0e9;
        v[1] = 1.0e-6;
        let (mode, dec) = round_trip(&v);
        assert_eq!(mode, TileMode::F32);
        assert_eq!(dec, v);
        let extreme = [f32::MAX, f32::MIN_POSITIVE, 1e-45, 0.0];
        let mut v = vec![0.0f32; 64];
        v[..4].copy_from_slice(&extreme);
        round_trip(&v);
        for x in extreme {
            round_trip(&[x; 64]);
        }
    }

    #[test]
    fn malformed_slots_are_errors() {
        let e = entry_bytes(8);
        let mut out = Vec::new();
        encode_tile(&[1.0e-6, 1.0e9].repeat(32), e, &mut out);
        assert!(
            decode_tile(&out[..e], e, &mut [0.0; 64]).is_err(),
            "f32 tile cut at one slot"
        );
        let zero = vec![0u8; e];
        assert!(decode_tile(&zero, e, &mut [0.0; 64]).is_err());
        let mut nan = zero.clone();
        nan[..4].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(decode_value(&nan, e, 64, 0).is_err());
        let mut neg = Vec::new();
        encode_tile(&[1.0; 64], e, &mut neg);
        neg[5] = 0xBC; // sign bit of value 0
        assert!(decode_tile(&neg, e, &mut [0.0; 64]).is_err());
        assert!(decode_value(&neg, e, 64, 64).is_err());
        assert!(decode_value(&neg[..3], e, 64, 0).is_err());
    }

    #[test]
    fn image_tiles_and_bbox() {
        let mut img = LuminanceImage::zeros(20, 11);
        img.data[3 * 20 + 17] = 5.0; // tile (2, 0)
        img.data[10 * 20 + 9] = 2.0; // tile (1, 1)
        img.data[0] = -0.0;
        let e = encode_image(&img, "t", 8, Threshold::Absolute(0.0), entry_bytes(8)).unwrap();
        assert_eq!(
            e.bbox,
            TileBox {
                x0: 1,
                y0: 0,
                w: 2,
                h: 2
            }
        );
        assert_eq!(e.table, vec![EMPTY_TILE, 0, 1, EMPTY_TILE]);
        assert_eq!(e.pixels_kept, 2);
        assert_eq!(e.max, 5.0);
        let neg_zero = encode_image(&img, "t", 8, Threshold::Absolute(-0.0), entry_bytes(8)).unwrap();
        assert_eq!(neg_zero.table, e.table);
        let above = encode_image(&img, "t", 8, Threshold::Absolute(2.0), entry_bytes(8)).unwrap();
        assert_eq!(above.table, vec![0]);
        let rel = encode_image(&img, "t", 8, Threshold::RelativeToImageMax(0.5), entry_bytes(8)).unwrap();
        assert_eq!(rel.table, vec![0]);
        img.data[5] = f32::NAN;
        let err = encode_image(&img, "t", 8, Threshold::Absolute(0.0), entry_bytes(8)).unwrap_err();
        assert!(err.to_string().contains("col 5, row 0"), "{err}");
        img.data[5] = -1.0;
        assert!(encode_image(&img, "t", 8, Threshold::RelativeToImageMax(0.1), entry_bytes(8)).is_err());
    }
}
