//! The JSON scan manifest: how a measured near-field scan (a set of luminance image files and their
//! camera poses) is described, imported ([`load_scan`]) and exported ([`write_scan`]).
//!
//! A manifest names the capture sphere, the shared pinhole intrinsics, and per image its file and
//! its camera pose: photometric angles (`phi_deg` = C, `theta_deg` = γ from nadir; the camera sits at
//! `centre + radius · dir` looking at the centre, oriented by
//! [`look_at_basis`](super::rayset::look_at_basis)) or a full basis (`position_m`, `right`, `down`,
//! `forward`). The complete description with an example is in docs/formats.md ("Scan manifest").
//!
//! Several manifests (e.g. one per hemisphere) merge into one scan when they share the sphere and
//! the intrinsics. Images are read lazily by a [`FileSource`]; importing opens each file only to check
//! its header (existence, format, size, length). Every inconsistency is an error naming the image,
//! unless [`ImportOptions::skip_bad`] (CLI: `--skip-bad-images`) drops the image with a warning.
//!
//! - `schema.rs`: the JSON schema (serde) and the conversion of intrinsics to and from it;
//! - `parse.rs`: [`parse_manifest`] and [`read_manifest`]: a [`Manifest`] with a camera (or why
//!   not) per [`ManifestEntry`];
//! - `import.rs`: [`assemble_scan`], [`load_scan`]: manifests merged into a scan, every image checked,
//!   read lazily by a [`FileSource`];
//! - `export.rs`: [`write_scan`]: a scan's images as `.pf` files and the manifest describing them.

mod export;
mod import;
mod parse;
mod schema;

pub use export::write_scan;
pub use import::{assemble_scan, load_scan, load_scan_with_report, FileSource, ImportOptions, ImportReport};
pub use parse::{parse_manifest, read_manifest, Manifest, ManifestEntry};

/// The `format` value of a manifest.
pub const MANIFEST_FORMAT: &str = "lumiview-scan-manifest";

/// The manifest version this reader understands and the writer writes.
pub const MANIFEST_VERSION: u32 = 1;

/// Largest manifest file read, bytes (≈ 2,000 bytes per image for 10⁵ images would be 200 MB).
pub const MAX_MANIFEST_BYTES: u64 = 1 << 30;

/// Two cameras whose directions from the capture centre are within this angle (rad) sit at the same
/// place; with the same orientation too they are a duplicate pose.
pub const DUPLICATE_TOLERANCE_RAD: f64 = 1e-6;

/// Largest allowed difference between a camera's distance from the centre and the sphere radius, as
/// a fraction of the radius (1 %; a larger one usually means millimetres given as metres).
pub const POSITION_TOLERANCE: f64 = 0.01;
