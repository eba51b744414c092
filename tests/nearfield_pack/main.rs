//! The `.lvpack` store: round trips within the quantisation bound (also for a 10⁶ cd/m² peak beside
//! 1 cd/m² and for values over 10⁻⁶…10⁹), empty and all-signal images, a corrupted byte in every
//! section found and named, truncation, page limits, CSR, memory independent of the image count,
//! and the `lumiview pack` / `lumiview info` commands.
//!
//! One test binary (`nearfield_pack`, CPU only), its parts by concept:
//! - `common.rs`: what every part uses: scans of generated images, packing one, the quantisation bound;
//! - `round_trip.rs`: images, metadata and cameras come back (peaks, empty and full images, a repack);
//! - `encoding.rs`: tiles (sizes, thresholds, the quantisation bound over all values) and CSR;
//! - `writer.rs`: what the writer lays out and holds: pages, table windows, memory, bad input;
//! - `integrity.rs`: corruption found and named, truncated and foreign files;
//! - `cli.rs`: the `lumiview pack` and `lumiview info` commands.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod cli;
mod common;
mod encoding;
mod integrity;
mod round_trip;
mod writer;
