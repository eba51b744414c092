//! The `.lvpack` byte layout: header, section directory, and the binary and JSON sections
//! (docs/formats.md, section `lvpack`). Everything is little-endian.
//!
//! ```text
//! [0, 64)        header (magic "LVPACK\r\n", version, file length, directory place and CRC, header CRC)
//! [64, 4096)     zero
//! page.0 …       pool pages, each at a multiple of 4096, zero padding between sections
//! metadata       JSON
//! cameras        sphere, shared intrinsics, one 168-byte record per camera, label bytes
//! images         pool layout, one 40-byte record per image
//! tile-tables    u32 per table entry
//! directory      48 bytes per section; the file ends with it
//! ```

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::nearfield::rayset::{Camera, CaptureSphere, Hemisphere, ImageMeta, Intrinsics, RayImageSet};

use super::tiles::TileBox;

/// The first 8 bytes of every `.lvpack` file.
pub const MAGIC: [u8; 8] = *b"LVPACK\r\n";
/// The format version this code writes and reads.
pub const VERSION: u32 = 2;

/// The first format version (no `proxy` section); still read and still written for packs without a
/// proxy, byte for byte as before.
pub const VERSION_1: u32 = 1;

/// Name of the optional proxy-mesh section (version 2).
pub const PROXY: &str = "proxy";

/// Magic of the proxy section.
pub const PROXY_MAGIC: [u8; 4] = *b"LVPX";

/// Bytes of the proxy section's fixed header: magic, flags, triangle count.
pub const PROXY_HEADER_BYTES: usize = 16;

/// Most proxy triangles a pack holds (2²⁴: 604 MB of f32).
pub const MAX_PROXY_TRIANGLES: u64 = 1 << 24;
/// Bytes of the header.
pub const HEADER_BYTES: usize = 64;
/// Bytes of one directory entry.
pub const DIR_ENTRY_BYTES: usize = 48;
/// Longest section name (bytes, ASCII).
pub const MAX_NAME_BYTES: usize = 24;
/// Every section starts at a multiple of this (so pages can be memory-mapped).
pub const SECTION_ALIGN: u64 = 4096;
/// Largest pool page (lavapipe's `maxStorageBufferRange`).
pub const MAX_PAGE_BYTES: u64 = 128 << 20;
/// Name of the JSON metadata section.
pub const METADATA: &str = "metadata";
/// Name of the cameras section.
pub const CAMERAS: &str = "cameras";
/// Name of the image-table section.
pub const IMAGES: &str = "images";
/// Name of the tile-table section.
pub const TILE_TABLES: &str = "tile-tables";
/// Prefix of pool page sections (`page.0`, `page.1`, …).
pub const PAGE_PREFIX: &str = "page.";
/// Bytes of the cameras section's fixed header.
pub const CAMERAS_HEADER_BYTES: usize = 88;
/// Bytes of one camera record.
pub const CAMERA_RECORD_BYTES: usize = 168;
/// Bytes of the images section's fixed header.
pub const IMAGES_HEADER_BYTES: usize = 48;
/// Bytes of one image record.
pub const IMAGE_RECORD_BYTES: usize = 40;

/// `x` rounded up to a multiple of [`SECTION_ALIGN`].
pub fn align_up(x: u64) -> u64 {
    x.div_ceil(SECTION_ALIGN) * SECTION_ALIGN
}

/// The name of pool page `index`.
pub fn page_name(index: usize) -> String {
    format!("{PAGE_PREFIX}{index}")
}

/// The fixed header at offset 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// Format version: [`VERSION_1`] or [`VERSION`].
    pub version: u32,
    /// Total file length in bytes (a shorter file is truncated).
    pub file_len: u64,
    /// Offset of the section directory.
    pub dir_offset: u64,
    /// Number of directory entries.
    pub dir_count: u32,
    /// CRC32 of the directory bytes.
    pub dir_crc: u32,
}

impl Header {
    /// The 64 header bytes: magic, version, header size, file length, directory offset, count,
    /// entry size and CRC, flags (0), reserved (0), then the CRC32 of bytes 0…59.
    pub fn encode(&self) -> [u8; HEADER_BYTES] {
        let mut b = [0u8; HEADER_BYTES];
        b[0..8].copy_from_slice(&MAGIC);
        b[8..12].copy_from_slice(&self.version.to_le_bytes());
        b[12..16].copy_from_slice(&(HEADER_BYTES as u32).to_le_bytes());
        b[16..24].copy_from_slice(&self.file_len.to_le_bytes());
        b[24..32].copy_from_slice(&self.dir_offset.to_le_bytes());
        b[32..36].copy_from_slice(&self.dir_count.to_le_bytes());
        b[36..40].copy_from_slice(&(DIR_ENTRY_BYTES as u32).to_le_bytes());
        b[40..44].copy_from_slice(&self.dir_crc.to_le_bytes());
        let crc = crc32fast::hash(&b[..60]);
        b[60..64].copy_from_slice(&crc.to_le_bytes());
        b
    }
}

/// What is wrong with a header, so the reader can pick the error kind.
#[derive(Debug, Clone, PartialEq)]
pub enum HeaderError {
    /// Not an `.lvpack` file at all (short or wrong magic).
    NotPack(String),
    /// The header checksum fails.
    Checksum,
    /// A version this code does not read.
    Version(u32),
    /// A field is malformed.
    Field(String),
}

/// Parses and checks the header (magic, checksum, version, sizes).
pub fn decode_header(b: &[u8]) -> Result<Header, HeaderError> {
    if b.len() < HEADER_BYTES {
        return Err(HeaderError::NotPack(format!(
            "{} bytes is shorter than the {HEADER_BYTES}-byte .lvpack header",
            b.len()
        )));
    }
    if b[..8] != MAGIC {
        return Err(HeaderError::NotPack(
            "no .lvpack magic \"LVPACK\\r\\n\" at offset 0".into(),
        ));
    }
    let mut r = Le::new(&b[..HEADER_BYTES]);
    r.skip(8);
    let (version, header_size) = (r.u32(), r.u32());
    let (file_len, dir_offset, dir_count, entry, dir_crc) = (r.u64(), r.u64(), r.u32(), r.u32(), r.u32());
    r.skip(16);
    let crc = r.u32();
    if crc32fast::hash(&b[..60]) != crc {
        return Err(HeaderError::Checksum);
    }
    if version != VERSION && version != VERSION_1 {
        return Err(HeaderError::Version(version));
    }
    if header_size as usize != HEADER_BYTES || entry as usize != DIR_ENTRY_BYTES {
        return Err(HeaderError::Field(format!(
            "header size {header_size} / directory entry size {entry} differ from version 1's {HEADER_BYTES} / {DIR_ENTRY_BYTES}"
        )));
    }
    Ok(Header {
        version,
        file_len,
        dir_offset,
        dir_count,
        dir_crc,
    })
}

/// One entry of the section directory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SectionInfo {
    /// Section name (`metadata`, `cameras`, `images`, `tile-tables`, `page.N`).
    pub name: String,
    /// Offset in the file (a multiple of 4096).
    pub offset: u64,
    /// Length in bytes.
    pub length: u64,
    /// CRC32 (IEEE, as `crc32fast`) of the section's bytes.
    pub crc32: u32,
}

/// Serialises directory entries: name (24 bytes, NUL-padded ASCII), u64 offset, u64 length,
/// u32 CRC32, u32 reserved (0).
pub fn encode_directory(sections: &[SectionInfo]) -> Vec<u8> {
    let mut out = Vec::with_capacity(sections.len() * DIR_ENTRY_BYTES);
    for s in sections {
        let mut name = [0u8; MAX_NAME_BYTES];
        let n = s.name.len().min(MAX_NAME_BYTES);
        name[..n].copy_from_slice(&s.name.as_bytes()[..n]);
        out.extend_from_slice(&name);
        out.extend_from_slice(&s.offset.to_le_bytes());
        out.extend_from_slice(&s.length.to_le_bytes());
        out.extend_from_slice(&s.crc32.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
    }
    out
}

/// Parses directory bytes (whose checksum was checked) into entries; names must be non-empty
/// printable ASCII followed only by NULs.
pub fn decode_directory(b: &[u8]) -> Result<Vec<SectionInfo>, String> {
    if !b.len().is_multiple_of(DIR_ENTRY_BYTES) {
        return Err(format!("{} bytes is not a whole number of entries", b.len()));
    }
    b.chunks_exact(DIR_ENTRY_BYTES)
        .enumerate()
        .map(|(i, e)| {
            let raw = &e[..MAX_NAME_BYTES];
            let n = raw.iter().position(|&c| c == 0).unwrap_or(MAX_NAME_BYTES);
            if n == 0 || !raw[..n].iter().all(|c| c.is_ascii_graphic()) || raw[n..].iter().any(|&c| c != 0) {
                return Err(format!("entry {i} has a malformed name"));
            }
            let mut r = Le::new(&e[MAX_NAME_BYTES..]);
            Ok(SectionInfo {
                name: String::from_utf8_lossy(&raw[..n]).into_owned(),
                offset: r.u64(),
                length: r.u64(),
                crc32: r.u32(),
            })
        })
        .collect()
}

/// Layout of the tile pool (binary, in the `images` section header).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoolLayout {
    /// Tile edge in pixels.
    pub tile_size: u32,
    /// Bytes of one pool slot (`4 + ⌈2·T²/4⌉·4`).
    pub entry_bytes: u32,
    /// Slots of every page but the last: global slot `g` lives in page `g / slots_per_page` at byte
    /// `(g % slots_per_page) · entry_bytes`.
    pub slots_per_page: u32,
    /// Number of pool pages.
    pub page_count: u32,
    /// Slots in all pages together.
    pub slots_total: u64,
    /// Entries of the `tile-tables` section.
    pub table_entries: u64,
    /// Tile tables come in windows of this many entries (`page size / 4`, 2^25 = 128 MiB at most):
    /// no image's table crosses a window boundary unless it is longer than a window (the gap before
    /// a boundary is filled with [`EMPTY_TILE`](super::EMPTY_TILE) entries), so a GPU binds the
    /// window `table_offset / table_window` alone.
    pub table_window: u32,
}

/// One image's record in the `images` section.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImageEntry {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bounding box of kept tiles (in tiles; 0 × 0 when the image has none).
    pub bbox: TileBox,
    /// First entry of its tile table in `tile-tables` (the table is `bbox.w · bbox.h` entries,
    /// row-major).
    pub table_offset: u64,
    /// Kept tiles.
    pub tiles: u32,
    /// Largest stored luminance (cd/m², as decoded).
    pub max_cd_m2: f32,
}

/// Serialises the `images` section: layout, `u64` image count, record size, table window, then the
/// records
/// (`u32` width, height, bbox x0, y0, w, h; `u64` table offset; `u32` tiles; `f32` max).
pub fn encode_images(layout: &PoolLayout, images: &[ImageEntry]) -> Vec<u8> {
    let mut out = Vec::with_capacity(IMAGES_HEADER_BYTES + images.len() * IMAGE_RECORD_BYTES);
    for v in [
        layout.tile_size,
        layout.entry_bytes,
        layout.slots_per_page,
        layout.page_count,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in [layout.slots_total, images.len() as u64, layout.table_entries] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&(IMAGE_RECORD_BYTES as u32).to_le_bytes());
    out.extend_from_slice(&layout.table_window.to_le_bytes());
    for e in images {
        for v in [e.width, e.height, e.bbox.x0, e.bbox.y0, e.bbox.w, e.bbox.h] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&e.table_offset.to_le_bytes());
        out.extend_from_slice(&e.tiles.to_le_bytes());
        out.extend_from_slice(&e.max_cd_m2.to_le_bytes());
    }
    out
}

/// Parses the `images` section (sizes only; the reader checks consistency).
pub fn decode_images(b: &[u8]) -> Result<(PoolLayout, Vec<ImageEntry>), String> {
    if b.len() < IMAGES_HEADER_BYTES {
        return Err(format!(
            "{} bytes is shorter than its {IMAGES_HEADER_BYTES}-byte header",
            b.len()
        ));
    }
    let mut r = Le::new(b);
    let (tile_size, entry_bytes, slots_per_page, page_count) = (r.u32(), r.u32(), r.u32(), r.u32());
    let (slots_total, count, table_entries) = (r.u64(), r.u64(), r.u64());
    let record = r.u32();
    let table_window = r.u32();
    if record as usize != IMAGE_RECORD_BYTES {
        return Err(format!(
            "record size {record} differs from version 1's {IMAGE_RECORD_BYTES}"
        ));
    }
    let body = (b.len() - IMAGES_HEADER_BYTES) as u64;
    if count.checked_mul(IMAGE_RECORD_BYTES as u64) != Some(body) {
        return Err(format!("{count} images do not fill its {body} record bytes"));
    }
    let images = (0..count)
        .map(|_| {
            let (width, height) = (r.u32(), r.u32());
            let bbox = TileBox {
                x0: r.u32(),
                y0: r.u32(),
                w: r.u32(),
                h: r.u32(),
            };
            ImageEntry {
                width,
                height,
                bbox,
                table_offset: r.u64(),
                tiles: r.u32(),
                max_cd_m2: f32::from_bits(r.u32()),
            }
        })
        .collect();
    Ok((
        PoolLayout {
            tile_size,
            entry_bytes,
            slots_per_page,
            page_count,
            slots_total,
            table_entries,
            table_window,
        },
        images,
    ))
}

fn put_f64s(out: &mut Vec<u8>, v: &[f64]) {
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

fn put_intrinsics(out: &mut Vec<u8>, k: &Intrinsics) {
    out.extend_from_slice(&k.width.to_le_bytes());
    out.extend_from_slice(&k.height.to_le_bytes());
    put_f64s(out, &[k.principal_px.x, k.principal_px.y, k.focal_px.x, k.focal_px.y]);
}

/// Serialises the `cameras` section: `u64` count, sphere centre (3 × f64) and radius, shared
/// intrinsics (`u32` width, height; `f64` cx, cy, fx, fy), `u32` record size, `u32` 0, then one
/// record per camera (position, right, down, forward as 3 × f64 each; `u8` hemisphere (0 lower,
/// 1 upper), `u8` flags (1 intrinsics override, 2 exposure, 4 overflow count), `u16` 0, `u32`
/// label length, override intrinsics, `f64` exposure s, `u64` overflow count, `u64` label offset),
/// then the UTF-8 labels back to back.
pub fn encode_cameras(set: &RayImageSet) -> Vec<u8> {
    let labels: usize = set.cameras.iter().map(|c| c.label.len()).sum();
    let mut out = Vec::with_capacity(CAMERAS_HEADER_BYTES + set.cameras.len() * CAMERA_RECORD_BYTES + labels);
    out.extend_from_slice(&(set.cameras.len() as u64).to_le_bytes());
    let c = set.sphere.centre_m;
    put_f64s(&mut out, &[c.x, c.y, c.z, set.sphere.radius_m]);
    put_intrinsics(&mut out, &set.intrinsics);
    out.extend_from_slice(&(CAMERA_RECORD_BYTES as u32).to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    let mut label_at = 0u64;
    for cam in &set.cameras {
        for v in [cam.position_m, cam.right, cam.down, cam.forward] {
            put_f64s(&mut out, &[v.x, v.y, v.z]);
        }
        out.push(match cam.hemisphere {
            Hemisphere::Lower => 0,
            Hemisphere::Upper => 1,
        });
        let flags = u8::from(cam.intrinsics.is_some())
            | u8::from(cam.meta.exposure_s.is_some()) << 1
            | u8::from(cam.meta.overflow_count.is_some()) << 2;
        out.push(flags);
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(&(cam.label.len() as u32).to_le_bytes());
        match &cam.intrinsics {
            Some(k) => put_intrinsics(&mut out, k),
            None => out.extend_from_slice(&[0u8; 40]),
        }
        put_f64s(&mut out, &[cam.meta.exposure_s.unwrap_or(0.0)]);
        out.extend_from_slice(&cam.meta.overflow_count.unwrap_or(0).to_le_bytes());
        out.extend_from_slice(&label_at.to_le_bytes());
        label_at += cam.label.len() as u64;
    }
    for cam in &set.cameras {
        out.extend_from_slice(cam.label.as_bytes());
    }
    out
}

fn get_intrinsics(r: &mut Le) -> Intrinsics {
    let (width, height) = (r.u32(), r.u32());
    let (cx, cy, fx, fy) = (r.f64(), r.f64(), r.f64(), r.f64());
    Intrinsics {
        width,
        height,
        principal_px: DVec2::new(cx, cy),
        focal_px: DVec2::new(fx, fy),
    }
}

/// Parses the `cameras` section (the reader validates the set).
pub fn decode_cameras(b: &[u8]) -> Result<RayImageSet, String> {
    if b.len() < CAMERAS_HEADER_BYTES {
        return Err(format!(
            "{} bytes is shorter than its {CAMERAS_HEADER_BYTES}-byte header",
            b.len()
        ));
    }
    let mut r = Le::new(b);
    let count = r.u64();
    let centre_m = DVec3::new(r.f64(), r.f64(), r.f64());
    let radius_m = r.f64();
    let intrinsics = get_intrinsics(&mut r);
    let record = r.u32();
    r.skip(4);
    if record as usize != CAMERA_RECORD_BYTES {
        return Err(format!(
            "record size {record} differs from version 1's {CAMERA_RECORD_BYTES}"
        ));
    }
    let records_end = count
        .checked_mul(CAMERA_RECORD_BYTES as u64)
        .and_then(|n| n.checked_add(CAMERAS_HEADER_BYTES as u64))
        .filter(|&end| end <= b.len() as u64)
        .ok_or_else(|| format!("{count} camera records do not fit its {} bytes", b.len()))?
        as usize;
    let labels = &b[records_end..];
    let mut cameras = Vec::with_capacity(count as usize);
    for i in 0..count as usize {
        let v3 = |r: &mut Le| DVec3::new(r.f64(), r.f64(), r.f64());
        let (position_m, right, down, forward) = (v3(&mut r), v3(&mut r), v3(&mut r), v3(&mut r));
        let hemisphere = match r.u8() {
            0 => Hemisphere::Lower,
            1 => Hemisphere::Upper,
            h => return Err(format!("camera {i}: hemisphere code {h} is neither 0 nor 1")),
        };
        let flags = r.u8();
        r.skip(2);
        let label_len = r.u32() as u64;
        let k = get_intrinsics(&mut r);
        let exposure = r.f64();
        let overflow = r.u64();
        let label_at = r.u64();
        if flags & !7 != 0 {
            return Err(format!("camera {i}: unknown flags {flags:#x}"));
        }
        let label = label_at
            .checked_add(label_len)
            .filter(|&end| end <= labels.len() as u64)
            .and_then(|end| std::str::from_utf8(&labels[label_at as usize..end as usize]).ok())
            .ok_or_else(|| format!("camera {i}: label bytes are out of range or not UTF-8"))?;
        cameras.push(Camera {
            position_m,
            right,
            down,
            forward,
            intrinsics: (flags & 1 != 0).then_some(k),
            hemisphere,
            meta: ImageMeta {
                exposure_s: (flags & 2 != 0).then_some(exposure),
                overflow_count: (flags & 4 != 0).then_some(overflow),
            },
            label: label.to_string(),
        });
    }
    Ok(RayImageSet {
        sphere: CaptureSphere { centre_m, radius_m },
        intrinsics,
        cameras,
    })
}

/// The JSON `metadata` section: a description for people and tools. The binary sections are
/// authoritative for the layout; the reader checks that the copies here agree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PackMetadata {
    /// Always `"lvpack"`.
    pub format: String,
    /// Format version (1).
    pub version: u32,
    /// Writer, e.g. `lumiview 0.1.0`.
    pub created_by: String,
    /// Where the images came from (manifest path, ray file, synthetic options …).
    pub source: String,
    /// Capture sphere (m, luminaire frame).
    pub capture_sphere: SphereMeta,
    /// Intrinsics shared by the cameras without an override.
    pub intrinsics: IntrinsicsMeta,
    /// Camera counts.
    pub cameras: CameraCounts,
    /// Tile encoding.
    pub encoding: EncodingMeta,
    /// Pool pages.
    pub pages: PagesMeta,
    /// Kept tiles.
    pub tiles: TileCounts,
    /// Sizes for comparison, computed while packing.
    pub footprint: FootprintMeta,
    /// The proxy mesh stored with the scan (version 2; absent in version 1 packs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub proxy: Option<ProxyMeta>,
}

/// The proxy mesh in the metadata.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProxyMeta {
    /// Triangles in the `proxy` section.
    pub triangles: u64,
    /// `"surface"`: the mesh is the emitting surface (images sampled only where they hold light);
    /// `"bound"`: it encloses the light (images sampled plainly, darkness included).
    pub kind: String,
    /// Where the mesh came from.
    pub source: String,
}

/// Serialises the proxy section: magic `LVPX`, u32 flags (1 = the mesh bounds the light rather
/// than being its surface), u64 triangle count, then 9 f32 per triangle (m, luminaire frame).
pub fn encode_proxy(triangles: &[[f32; 3]], bound: bool) -> Vec<u8> {
    let mut out = Vec::with_capacity(PROXY_HEADER_BYTES + 12 * triangles.len());
    out.extend_from_slice(&PROXY_MAGIC);
    out.extend_from_slice(&u32::from(bound).to_le_bytes());
    out.extend_from_slice(&((triangles.len() / 3) as u64).to_le_bytes());
    for v in triangles.iter().take(triangles.len() / 3 * 3) {
        for c in v {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    out
}

/// Parses the proxy section into its vertices (three per triangle) and the bound flag.
pub fn decode_proxy(b: &[u8]) -> Result<(Vec<[f32; 3]>, bool), String> {
    if b.len() < PROXY_HEADER_BYTES || b[..4] != PROXY_MAGIC {
        return Err("no proxy header".into());
    }
    let mut r = Le::new(b);
    r.skip(4);
    let (flags, count) = (r.u32(), r.u64());
    if flags > 1 {
        return Err(format!("unknown flags {flags}"));
    }
    if count > MAX_PROXY_TRIANGLES || (b.len() - PROXY_HEADER_BYTES) as u64 != count * 36 {
        return Err(format!("{count} triangles do not fill {} bytes", b.len()));
    }
    let mut v = Vec::with_capacity(count as usize * 3);
    for _ in 0..count * 3 {
        let p = [r.f32(), r.f32(), r.f32()];
        if !p.iter().all(|c| c.is_finite()) {
            return Err("a vertex is not finite".into());
        }
        v.push(p);
    }
    Ok((v, flags == 1))
}

/// Capture sphere in the metadata.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SphereMeta {
    /// Centre (m).
    pub centre_m: [f64; 3],
    /// Radius (m).
    pub radius_m: f64,
}

/// Shared intrinsics in the metadata.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IntrinsicsMeta {
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
    /// Principal point (px).
    pub principal_px: [f64; 2],
    /// Focal length (px).
    pub focal_px: [f64; 2],
}

/// Camera counts in the metadata.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CameraCounts {
    /// All cameras (= images).
    pub total: u64,
    /// Lower-hemisphere cameras.
    pub lower: u64,
    /// Upper-hemisphere cameras.
    pub upper: u64,
}

/// The tile encoding in the metadata.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EncodingMeta {
    /// `"f16-pow2-tile-scale/f32"`: fp16 × per-tile power-of-two scale, exact f32 tiles as fallback.
    pub scheme: String,
    /// Tile edge (px).
    pub tile_size: u32,
    /// Bytes per pool slot.
    pub entry_bytes: u32,
    /// Largest relative error of a nonzero value (2^-11).
    pub max_relative_error: f64,
    /// Which tiles were kept.
    pub threshold: ThresholdMeta,
}

/// The threshold in the metadata.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ThresholdMeta {
    /// `"absolute"` (cd/m²) or `"relative"` (fraction of each image's maximum).
    pub kind: ThresholdKind,
    /// The value.
    pub value: f32,
}

/// A threshold kind (serialised as `"absolute"` / `"relative"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ThresholdKind {
    /// cd/m².
    Absolute,
    /// Fraction of the image's maximum.
    Relative,
}

/// Pages in the metadata.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PagesMeta {
    /// Number of pages.
    pub count: u32,
    /// Slots per full page.
    pub slots_per_page: u32,
    /// The page-size limit the pack was written with (bytes).
    pub page_bytes_max: u64,
    /// Slots in all pages.
    pub slots_total: u64,
}

/// Tile counts in the metadata.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct TileCounts {
    /// Kept tiles.
    pub kept: u64,
    /// Of those, tiles stored as exact f32 (dynamic range beyond fp16).
    pub f32: u64,
    /// Images without any kept tile.
    pub empty_images: u64,
}

/// Sizes in the metadata (so `lumiview info` does not re-read images).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FootprintMeta {
    /// Pixels of all images.
    pub pixels: u64,
    /// Pixels above the threshold (nonzero pixels at threshold 0).
    pub pixels_kept: u64,
    /// Dense fp16 size: 2 bytes per pixel.
    pub dense_f16_bytes: u64,
    /// CSR size of the same pixels (`4·(rows + 1) + 8·pixels_kept` summed over images).
    pub csr_bytes: u64,
    /// Bytes of all pool pages.
    pub pool_bytes: u64,
    /// Bytes of the tile tables.
    pub tile_table_bytes: u64,
}

/// A little-endian reader over a slice whose length the caller has checked; reads past the end
/// give zeros (never panic).
pub struct Le<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Le<'a> {
    /// A reader at offset 0.
    pub fn new(b: &'a [u8]) -> Self {
        Self { b, at: 0 }
    }
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(s) = self.b.get(self.at..self.at + N) {
            out.copy_from_slice(s);
        }
        self.at += N;
        out
    }
    /// Skips `n` bytes.
    pub fn skip(&mut self, n: usize) {
        self.at += n;
    }
    /// A byte.
    pub fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    /// A u32.
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    /// A u64.
    pub fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    /// An f64.
    pub fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
    /// An f32.
    pub fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take())
    }
}
