//! IES TM-25-13 ray files: reader (and a writer for tests and tools).
//!
//! Layout (little-endian; see docs/formats.md, section "IES TM-25 ray files"):
//!
//! | offset | size | field (TM-25-13 clause) |
//! |---|---|---|
//! | 0 | 4 | `"TM25"` (4.7.1.1) |
//! | 4 | i32 | version, 2013 (4.7.1.2) |
//! | 8 | i32 | creation method: 0 simulated, 1 measured (4.7.1.3) |
//! | 12 | f32 | total luminous flux, lm; NaN = unknown (4.7.1.4) |
//! | 16 | f32 | total radiant flux, W; NaN = unknown (4.7.1.5) |
//! | 20 | u64 | number of rays (4.7.1.6) |
//! | 28 | char\[28\] | creation date and time, NUL-padded (4.7.1.7) |
//! | 56 | i32 | ray start position: a *code* (0 = unknown), not a byte offset (4.7.1.8) |
//! | 60 | i32 | spectral data identifier 0…4 (4.7.1.9) |
//! | 64/68/72 | f32 | single / minimum / maximum wavelength, nm (4.7.1.10–12) |
//! | 76 | i32 | number of spectral tables (4.7.1.13) |
//! | 80 | i32 | number of additional ray data items (4.7.1.14) |
//! | 84 | i32 | size of the additional text block, bytes (4.7.1.15) |
//! | 88 | 168 | reserved |
//! | 256 | 8 × i32 | known-data flags: position, direction, radiant flux, wavelength, luminous flux, Stokes, tristimulus, spectrum index (4.7.2) |
//! | 288 | 9 × 4000 | description: 9 UTF-32 fields of 1000 units (4.7.3) |
//! | 36288 | … | spectral tables: per table i32 N + N × (λ, weight) f32; the whole block zero-padded to a multiple of 32 bytes (4.7.4) |
//! | … | 512 each | additional column labels, UTF-32 (4.7.5) |
//! | … | size | additional text, UTF-32 (4.7.6) |
//! | … | rays × items × 4 | ray records: x, y, z (mm), kx, ky, kz, then the flagged columns in flag order, then the additional columns |
//!
//! The ray data offset is computed from this layout, and the file size must equal
//! `offset + rays × items × 4` exactly: a mismatch is an error that states both sizes. Every size is
//! checked against the file size before anything is allocated.
//!
//! Rays are kept as the file's `f32` records (28 bytes per ray for 7 columns), not as a `Vec` of
//! structs; [`RayFile::rays`] yields [`Ray`]s (metres, unit directions, fluxes) on the fly.
//!
//! - `header.rs`: the header model: [`Tm25Header`], [`Tm25Flags`], [`Description`],
//!   [`CreationMethod`], [`SpectralKind`];
//! - `spectral.rs`: V(λ) ([`photopic_efficiency`]), [`SpectralTable`] and the rule that gives each
//!   ray its luminous flux ([`LuminousSource`]);
//! - `input.rs`: bytes from a slice or a file, every length checked against the file size; UTF-32 text;
//! - `reader.rs`: [`RayFile::read`] and [`RayFile::from_bytes`]: the header blocks and every ray
//!   checked, errors naming the file;
//! - `rays.rs`: [`RayFile`] in memory: its records and the converted [`Ray`]s ([`Rays`]);
//! - `stats.rs`: [`RayStats`], the summary `lumiview info` prints;
//! - `writer.rs`: [`encode`], a TM-25-13 file from a header and records.

mod header;
mod input;
mod rays;
mod reader;
mod spectral;
mod stats;
mod writer;

pub use header::{CreationMethod, Description, SpectralKind, Tm25Flags, Tm25Header};
pub use rays::{HeaderScale, Ray, RayFile, RayFlux, Rays};
pub use spectral::{photopic_efficiency, LuminousSource, SpectralTable, K_M};
pub use stats::RayStats;
pub use writer::encode;

/// Size of the file header block (4.7.1).
pub const HEADER_BYTES: u64 = 256;
/// Size of the known-data flags block (4.7.2).
pub const FLAGS_BYTES: u64 = 32;
/// Size of the description block (4.7.3): 9 fields × 1000 UTF-32 code units.
pub const DESCRIPTION_BYTES: u64 = 36_000;
/// Offset of the spectral tables block, the first variable-size part.
pub const FIXED_BYTES: u64 = HEADER_BYTES + FLAGS_BYTES + DESCRIPTION_BYTES;
/// Size of one additional-column label (4.7.5): 128 UTF-32 code units.
pub const COLUMN_LABEL_BYTES: u64 = 512;
