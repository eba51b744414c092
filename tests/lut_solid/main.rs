//! Host-lighting look-up tables and the photometric solid: values against the web, encodings
//! within their stated error, files read back with the exr/png/gltf crates, mesh topology, and
//! the `lumiview lut` / `lumiview solid` commands.
//!
//! One test binary (`lut_solid`, CPU only), its parts by concept:
//! - `common.rs`: what every part uses: the fixtures, opening one, a temporary path, running `lumiview`;
//! - `tables.rs`: look-up tables against the web, their encodings within the stated error, bad arguments;
//! - `table_files.rs`: tables as EXR and PNG read back with their metadata, and `lumiview lut`;
//! - `solid.rs`: the photometric solid: closed, outward, the right radii, glTF and OBJ, `lumiview solid`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;
mod solid;
mod table_files;
mod tables;
