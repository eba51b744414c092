//! Any luminaire file lumiview reads: which kind it is (from its first bytes) and opening it as
//! what lumiview draws. This is the one dispatch from a path to a reader: the C API
//! (`lumi_luminaire_load`) and the CLI's commands (`render`, `info`, `pack`, `cameras`) tell files
//! apart with [`detect`], and `lumi_luminaire_load` and the CLI's scan loading open them with
//! [`open`]. Adding a format means a [`SourceKind`], its detection (a scan's magic in
//! `nearfield::scanfile::kind_of`, or the photometric reader `photometry::load`) and its branch in
//! [`open`]; the compiler then points at each `match` on the kind that must say what to do with it.
//!
//! Pure CPU.

use std::path::{Path, PathBuf};

use crate::nearfield::pack::Pack;
use crate::nearfield::scanfile::{self, ScanFileKind};
use crate::nearfield::NearfieldError;
use crate::photometry::{self, LoadOptions, Photometry, PhotometryError};

/// What kind of luminaire file a path holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SourceKind {
    /// Far-field photometry: IES LM-63 or EULUMDAT (anything that is not a scan file; its reader
    /// reports a file that is neither).
    Photometry,
    /// A `.lvpack` tiled near-field store (magic `LVPACK`).
    Pack,
    /// A JSON scan manifest (first non-blank character `{`).
    Manifest,
    /// An IES TM-25 ray file (magic `TM25`).
    RayFile,
}

impl SourceKind {
    /// A near-field scan (drawn by the near-field pass), not photometry.
    pub fn is_scan(self) -> bool {
        self.scan_kind().is_some()
    }

    /// The scan-file kind, `None` for photometry.
    pub fn scan_kind(self) -> Option<ScanFileKind> {
        match self {
            SourceKind::Photometry => None,
            SourceKind::Pack => Some(ScanFileKind::Pack),
            SourceKind::Manifest => Some(ScanFileKind::Manifest),
            SourceKind::RayFile => Some(ScanFileKind::RayFile),
        }
    }
}

/// Reads the first bytes of `path` and says which kind of luminaire file it is.
///
/// Errors ([`scanfile::detect`]): a path that cannot be read or is not a regular file, or a file
/// named `.lvpack` without the pack's magic, each naming the file (such a file is never handed to
/// another reader).
pub fn detect(path: &Path) -> Result<SourceKind, NearfieldError> {
    Ok(match scanfile::detect(path)? {
        None => SourceKind::Photometry,
        Some(ScanFileKind::Pack) => SourceKind::Pack,
        Some(ScanFileKind::Manifest) => SourceKind::Manifest,
        Some(ScanFileKind::RayFile) => SourceKind::RayFile,
    })
}

/// How to open a luminaire file.
#[derive(Debug, Clone, Default)]
pub struct SourceOptions {
    /// For photometry: lamp tilt, lamp set, the checks of the reader.
    pub photometry: LoadOptions,
    /// For a manifest or ray file: the folder of the packed cache (`None`: the default,
    /// [`scanfile::open_scan`]).
    pub cache_dir: Option<PathBuf>,
}

/// A luminaire file, opened (returned once per load and moved on at once: the size of its
/// variants does not matter).
#[derive(Debug)]
#[allow(clippy::large_enum_variant)]
pub enum Source {
    /// Far-field photometry (its plausibility warnings, each naming the file, in
    /// [`Photometry::warnings`]).
    Photometry(Photometry),
    /// A near-field scan as a pack: a `.lvpack` opened as it is, or a manifest or ray file packed
    /// into the cache (`cached`: where) on first open.
    Scan {
        /// The pack.
        pack: Pack,
        /// The cached pack's path, for a manifest or a ray file.
        cached: Option<PathBuf>,
    },
}

/// An error opening a luminaire file; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// Reading photometry failed.
    #[error(transparent)]
    Photometry(#[from] PhotometryError),
    /// Reading or packing a scan failed.
    #[error(transparent)]
    Nearfield(#[from] NearfieldError),
}

/// Opens `path`, whose kind is `kind` (from [`detect`]), with the reader of that kind. The
/// warnings of packing a scan (an estimate's or an import's findings; none for a pack found in the
/// cache) are appended to `warnings`; photometry keeps its own in [`Photometry::warnings`].
pub fn open(
    path: &Path,
    kind: SourceKind,
    opts: &SourceOptions,
    warnings: &mut Vec<String>,
) -> Result<Source, SourceError> {
    match kind.scan_kind() {
        None => Ok(Source::Photometry(photometry::load(path, &opts.photometry)?)),
        Some(scan) => {
            let (pack, cached) =
                scanfile::open_scan_of_kind_with_warnings(path, scan, opts.cache_dir.as_deref(), warnings)?;
            Ok(Source::Scan { pack, cached })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_map_to_scan_kinds() {
        assert!(!SourceKind::Photometry.is_scan());
        for k in [SourceKind::Pack, SourceKind::Manifest, SourceKind::RayFile] {
            assert!(k.is_scan(), "{k:?}");
        }
        assert_eq!(SourceKind::RayFile.scan_kind(), Some(ScanFileKind::RayFile));
    }

    #[test]
    fn detect_and_open_name_the_file() {
        let dir = std::env::temp_dir().join(format!("lumiview-source-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ies = dir.join("a.ies");
        std::fs::write(
            &ies,
            "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1 1 10\n0 90 180\n0\n100 80 0\n",
        )
        .unwrap();
        assert_eq!(detect(&ies).unwrap(), SourceKind::Photometry);
        match open(&ies, SourceKind::Photometry, &SourceOptions::default(), &mut Vec::new()).unwrap() {
            Source::Photometry(p) => assert!(p.source.contains("a.ies"), "{}", p.source),
            other => panic!("{other:?}"),
        }
        let bad = dir.join("b.lvpack");
        std::fs::write(&bad, b"").unwrap();
        let e = detect(&bad).unwrap_err().to_string();
        assert!(e.contains("b.lvpack"), "{e}");
        let ray = dir.join("c.tm25ray");
        std::fs::write(&ray, b"TM25 truncated").unwrap();
        assert_eq!(detect(&ray).unwrap(), SourceKind::RayFile);
        let e = open(&ray, SourceKind::RayFile, &SourceOptions::default(), &mut Vec::new())
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.tm25ray"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
