//! The C ABI called from Rust: lifecycles, NULLs, bad enum values, stale handles, out-parameters
//! untouched on error, destroy(NULL), use after a failed create, buffer sizes, and a render through
//! the C API whose centre pixel is the library's own L(C, γ); near-field scans (`.lvpack`, manifest,
//! TM-25) loaded through the same call, rendered in every selection mode against the synthetic
//! goniophotometer's ray-cast truth.
//!
//! One test binary (`ffi`, a GPU test: it uses `tests/gpu_common`), its parts by concept:
//! - `common.rs`: what every part uses: the last error, a context (or a skip), C paths, temporary folders;
//! - `lifecycle.rs`: versions, NULLs and an ABI mismatch without a device, lifecycle errors, a render;
//! - `logging.rs`: load warnings reach the host's log callback;
//! - `nearfield.rs`: near-field scans loaded, rendered and queried through the C API;
//! - `scene.rs`: glTF scenes loaded, drawn and queried for illuminance through the C API;
//! - `handles.rs`: handles never cross contexts, kinds or lifetimes.

#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../gpu_common/mod.rs"]
mod gpu_common;

mod common;
mod handles;
mod lifecycle;
mod logging;
mod nearfield;
mod scene;
