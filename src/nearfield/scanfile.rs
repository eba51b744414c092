//! Scan files as a host hands them over (the C API's `lumi_luminaire_load`, a viewer's "open"):
//! tell a `.lvpack` store, a JSON scan manifest or an IES TM-25 ray file from anything else by its
//! first bytes, and turn a manifest or a ray file into a `.lvpack` with default options, cached so
//! that the second load only opens it.
//!
//! - `.lvpack`: the magic `LVPACK` at offset 0; opened as it is.
//! - TM-25 ray file: the magic `TM25` at offset 0; turned into a virtual scan by the kernel density
//!   estimate of its light field ([`raykde::estimate`], cameras, images and kernels chosen from the
//!   data) and packed with the grown hull of its ray origins as the proxy, exactly what
//!   `lumiview pack RAYS.tm25ray -o OUT.lvpack` does.
//! - JSON scan manifest: the first character other than white space (and a UTF-8 byte-order mark)
//!   is `{`; imported with [`load_scan`] (no bad image skipped), exactly what
//!   `lumiview pack manifest.json -o OUT.lvpack` does.
//!
//! Anything else is not a scan ([`detect`] returns `None`): the caller tries photometry (IES,
//! EULUMDAT), which cannot start with `{`, `LVPACK` or `TM25`.
//!
//! **The cache.** A manifest or ray file is packed once into `DIR/<stem>-<key>.lvpack`, where DIR is
//! the caller's cache folder or [`default_cache_dir`] (`$LUMIVIEW_CACHE_DIR`, else
//! `$XDG_CACHE_HOME/lumiview/packs`, else `$HOME/.cache/lumiview/packs`, else
//! `<temp>/lumiview-cache/packs`), and `<key>` is a 64-bit FNV-1a hash (16 hex digits) of the
//! input's canonical path, length and modification time and of the pack format, the methods and the
//! option defaults used (a new estimator rule or default re-packs).
//! Editing the input gives a new key; images a manifest refers to are not part of the key (delete the
//! cached file to re-pack after changing only them). A cached file is verified page by page and
//! tile by tile each time it is opened ([`Pack::verify`]); one that does not open or verify is
//! packed again. Packs are written under a unique temporary name and renamed into place, so two
//! processes loading the same file at once never see a half-written pack. Nothing removes old cache
//! entries.

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::time::UNIX_EPOCH;

use super::error::{NearfieldError, Result};
use super::manifest::{load_scan, ImportOptions};
use super::pack::{write_pack, OpenOptions, Pack, PackOptions, PackProxy};
use super::proxy::triangles_of;
use super::raykde;
use super::tm25::RayFile;
use super::Scan;

/// What kind of scan file a path holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScanFileKind {
    /// A `.lvpack` tiled store (magic `LVPACK`).
    Pack,
    /// A JSON scan manifest (first non-blank character `{`).
    Manifest,
    /// An IES TM-25 ray file (magic `TM25`).
    RayFile,
}

/// Bytes read to tell the kinds apart (white space before a manifest's `{` included).
const SNIFF_BYTES: usize = 4096;

/// Cache format: part of every key, so a change of the methods below invalidates old entries (the
/// option defaults and the estimate's rules are keyed too, by [`defaults_key`]; this names what they
/// do not hold).
const CACHE_VERSION: &str =
    "lumiview scan cache 10: lvpack defaults, tm25 kernel estimate v5 (intensity widths capped at their median, \
     cameras dense to the emission's edge, rays scaled to the header's total, k_s = 4 sqrt N, the spatial kernel \
     spread back by B-spline subdivision, a source within a pixel spread at level 2) with its proxy (4 sigma past a fixed kernel), \
     manifest strict with a reconstructed proxy v5 (thin parts collapsed, free grazing plane, stray parts dropped, \
     flat parts on the plane the images agree on, outlines at the images' steps, occluded cameras left out, flat \
     parts simplified)";

/// The defaults a cached pack depends on, as text for its key: the ray-file estimate's rules and
/// options, the reconstruction's and the pack's options.
fn defaults_key() -> String {
    format!(
        "k_s = {} sqrt N, k_I = {} N^(2/3); {:?}; {:?}; {:?}",
        raykde::DEFAULT_B,
        raykde::DEFAULT_BI,
        raykde::KdeOptions::default(),
        crate::nearfield::reconstruct::ReconstructOptions::default(),
        PackOptions::default()
    )
}

/// Reads the first bytes of `path` and says which kind of scan file it is, or `None` for anything
/// else (photometry, garbage).
///
/// Errors: [`NearfieldError::Io`] naming the file when it cannot be opened or read, or is not a
/// regular file (a FIFO or device is refused before it is opened); [`NearfieldError::Format`] for
/// a file named `.lvpack` without the pack's magic (empty, half-written or damaged: it is never
/// handed to another reader).
pub fn detect(path: &Path) -> Result<Option<ScanFileKind>> {
    let (mut f, len) =
        crate::files::open_regular(path, u64::MAX, "a luminaire file").map_err(|e| NearfieldError::io(path, e))?;
    let mut buf = vec![0u8; SNIFF_BYTES];
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(NearfieldError::io(path, e)),
        }
    }
    let kind = kind_of(&buf[..n]);
    let named_pack = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(super::pack::EXTENSION));
    if kind.is_none() && named_pack {
        return Err(NearfieldError::format(
            path,
            if len == 0 {
                "the file is empty, not a .lvpack (a pack whose writing failed?)".to_string()
            } else if buf[..n].iter().all(|&b| b == 0) {
                "the header is zero, not a .lvpack's (a half-written or damaged pack?)".to_string()
            } else {
                "no LVPACK magic at the start: not a .lvpack".to_string()
            },
        ));
    }
    Ok(kind)
}

/// The kind of scan file whose first bytes are `head`.
pub fn kind_of(head: &[u8]) -> Option<ScanFileKind> {
    if head.starts_with(b"LVPACK") {
        return Some(ScanFileKind::Pack);
    }
    if head.starts_with(b"TM25") {
        return Some(ScanFileKind::RayFile);
    }
    let text = head.strip_prefix(b"\xEF\xBB\xBF".as_slice()).unwrap_or(head);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Some(ScanFileKind::Manifest),
        _ => None,
    }
}

/// The scan a manifest or ray file describes, with the defaults of this module, a description for
/// the pack's metadata, and the proxy to store with it (a ray file's: the grown hull of its ray
/// origins, which bounds the light). A ray file becomes a kernel density estimate of its light
/// field ([`raykde::estimate`], every choice from the data). (A `.lvpack` is already a scan: open
/// it with [`Pack::open`].)
///
/// Errors: those of [`load_scan`], [`RayFile::read`] and [`raykde::estimate`], each naming the
/// file; [`NearfieldError::InvalidArgument`] for [`ScanFileKind::Pack`].
pub fn scan_from_file(path: &Path, kind: ScanFileKind) -> Result<(Scan, String, Option<PackProxy>)> {
    scan_from_file_with_warnings(path, kind, &mut Vec::new())
}

/// [`scan_from_file`], appending what the caller should tell the user (a ray file's estimate:
/// under-sampled directions, a coarse layout, ignored rays) to `warnings`.
pub fn scan_from_file_with_warnings(
    path: &Path,
    kind: ScanFileKind,
    warnings: &mut Vec<String>,
) -> Result<(Scan, String, Option<PackProxy>)> {
    match kind {
        ScanFileKind::Pack => Err(NearfieldError::invalid(
            "kind",
            format!("{} is already a .lvpack; open it with Pack::open", path.display()),
        )),
        ScanFileKind::Manifest => {
            let opts = ImportOptions {
                skip_bad: false,
                verify_pixels: false,
            };
            let scan = load_scan(&[path.to_path_buf()], &opts)?;
            // No mesh comes with a manifest: the proxy is reconstructed from the images.
            let what = format!("scan manifest {}", path.display());
            let proxy = crate::nearfield::reconstruct::scan_proxy(&scan, &what, &|_, _, _| {}, warnings)?
                .map(|rec| rec.to_pack_proxy());
            Ok((scan, what, proxy))
        }
        ScanFileKind::RayFile => {
            let rays = RayFile::read(path)?;
            let est = raykde::estimate(&rays, &raykde::KdeOptions::default(), &|_, _| {})?;
            warnings.extend(est.report.warnings.iter().cloned());
            let r = &est.report;
            let desc = format!(
                "TM-25 ray file {} as a kernel estimate ({} rays; intensity kernel {:.2}° median, spatial σ \
                 {:.3} mm median; {} cameras of {}² px)",
                path.display(),
                r.rays,
                r.angular_kernel_deg.median,
                r.spatial_kernel_m.median * 1e3,
                r.cameras,
                r.image_px
            );
            let proxy = PackProxy {
                triangles: triangles_of(&est.proxy),
                bound: true,
                source: "the hull of the ray origins, grown by two spatial kernels".into(),
            };
            Ok((est.scan, desc, Some(proxy)))
        }
    }
}

/// The cache folder used when the caller names none: `$LUMIVIEW_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/lumiview/packs`, else `$HOME/.cache/lumiview/packs`, else
/// `<temp>/lumiview-cache/packs` (empty variables count as unset; relative ones are ignored as the
/// XDG rules say).
pub fn default_cache_dir() -> PathBuf {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    if let Some(d) = var("LUMIVIEW_CACHE_DIR") {
        return d;
    }
    if let Some(d) = var("XDG_CACHE_HOME").filter(|d| d.is_absolute()) {
        return d.join("lumiview").join("packs");
    }
    if let Some(d) = var("HOME").filter(|d| d.is_absolute()) {
        return d.join(".cache").join("lumiview").join("packs");
    }
    std::env::temp_dir().join("lumiview-cache").join("packs")
}

/// 64-bit FNV-1a (stable across Rust versions, unlike `DefaultHasher`).
fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for b in p.iter().chain(&[0xFFu8]) {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// Where the cached pack of `path` lives in `cache_dir` (see the module documentation for the key).
///
/// Errors: [`NearfieldError::Io`] naming the file when it cannot be resolved or its metadata read.
pub fn cache_path(path: &Path, cache_dir: &Path) -> Result<PathBuf> {
    let canonical = path.canonicalize().map_err(|e| NearfieldError::io(path, e))?;
    let meta = std::fs::metadata(&canonical).map_err(|e| NearfieldError::io(path, e))?;
    let mtime = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    let key = fnv1a(&[
        CACHE_VERSION.as_bytes(),
        defaults_key().as_bytes(),
        canonical.to_string_lossy().as_bytes(),
        &meta.len().to_le_bytes(),
        &mtime.to_le_bytes(),
    ]);
    let stem: String = canonical
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect();
    Ok(cache_dir.join(format!("{stem}-{key:016x}.lvpack")))
}

/// Opens a scan file of any kind as a pack: a `.lvpack` as it is, a manifest or ray file through
/// the cache in `cache_dir` (or [`default_cache_dir`]), packing it first when it is not there yet.
/// Returns the pack and, for a manifest or ray file, the cached file's path.
///
/// Errors: those of [`detect`], [`scan_from_file`], [`write_pack`] and [`Pack::open`], each naming
/// its file; [`NearfieldError::Format`] naming the file when it is not a scan file at all;
/// [`NearfieldError::Io`] naming the cache folder when it cannot be created.
pub fn open_scan(path: &Path, cache_dir: Option<&Path>) -> Result<(Pack, Option<PathBuf>)> {
    let kind = detect(path)?.ok_or_else(|| {
        NearfieldError::format(
            path,
            "not a scan file (neither a .lvpack, a JSON scan manifest nor a TM-25 ray file)",
        )
    })?;
    open_scan_of_kind(path, kind, cache_dir)
}

/// [`open_scan`] for a file whose kind is known (from [`detect`]).
pub fn open_scan_of_kind(path: &Path, kind: ScanFileKind, cache_dir: Option<&Path>) -> Result<(Pack, Option<PathBuf>)> {
    open_scan_of_kind_with_warnings(path, kind, cache_dir, &mut Vec::new())
}

/// [`open_scan_of_kind`], appending the warnings of a new estimate or import to `warnings` (a pack
/// found in the cache adds none: they were given when it was made).
pub fn open_scan_of_kind_with_warnings(
    path: &Path,
    kind: ScanFileKind,
    cache_dir: Option<&Path>,
    warnings: &mut Vec<String>,
) -> Result<(Pack, Option<PathBuf>)> {
    if kind == ScanFileKind::Pack {
        return Ok((Pack::open(path)?, None));
    }
    let dir = cache_dir.map_or_else(default_cache_dir, Path::to_path_buf);
    let cached = cache_path(path, &dir)?;
    if cached.is_file() {
        // Every page is checked: a damaged cache entry is packed again from its source instead of
        // failing every render that uses it.
        let verify = OpenOptions {
            verify_pages: true,
            ..OpenOptions::default()
        };
        match Pack::open_with(&cached, &verify) {
            Ok(p) => return Ok((p, Some(cached))),
            Err(e) => warnings.push(format!(
                "{}: the cached pack {} is damaged ({e}); packing it again",
                path.display(),
                cached.display()
            )),
        }
    }
    let (scan, source, proxy) = scan_from_file_with_warnings(path, kind, warnings)?;
    std::fs::create_dir_all(&dir).map_err(|e| NearfieldError::io(&dir, e))?;
    let opts = PackOptions {
        source,
        proxy,
        ..PackOptions::default()
    };
    // Written under a unique temporary name and renamed into place (two processes loading the same
    // file at once each write their own; a reader never sees a half-written pack).
    write_pack(&scan, &cached, &opts, &|_, _| {})?;
    Ok((Pack::open(&cached)?, Some(cached)))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn kinds_from_first_bytes() {
        assert_eq!(kind_of(b"LVPACK\0\x01"), Some(ScanFileKind::Pack));
        assert_eq!(kind_of(b"TM25...."), Some(ScanFileKind::RayFile));
        assert_eq!(kind_of(b"  \n\t{\"format\""), Some(ScanFileKind::Manifest));
        assert_eq!(kind_of(b"\xEF\xBB\xBF{}"), Some(ScanFileKind::Manifest));
        assert_eq!(kind_of(b"IESNA:LM-63-2002\n"), None);
        assert_eq!(kind_of(b"BEGA\n1\n"), None);
        assert_eq!(kind_of(b""), None);
        assert_eq!(kind_of(b"LVPAC"), None);
    }

    #[test]
    fn the_key_changes_with_the_file() {
        let d = std::env::temp_dir().join(format!("lumiview-scanfile-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let f = d.join("a b.json");
        std::fs::write(&f, "{}").unwrap();
        let a = cache_path(&f, Path::new("/cache")).unwrap();
        assert!(a.starts_with("/cache"));
        let name = a.file_name().unwrap().to_string_lossy().into_owned();
        assert!(name.starts_with("a_b-") && name.ends_with(".lvpack"), "{name}");
        std::fs::write(&f, "{ }").unwrap();
        let b = cache_path(&f, Path::new("/cache")).unwrap();
        assert_ne!(a, b, "a longer file is another key");
        assert!(cache_path(&d.join("missing.json"), Path::new("/cache")).is_err());
        let _ = std::fs::remove_dir_all(&d);
    }
}
