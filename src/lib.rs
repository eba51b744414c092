//! lumiview: near-field luminaire appearance for lighting tools.
//!
//! Modules (one-way dependencies, see `docs/architecture.md`):
//! - [`photometry`]: IES / EULUMDAT far-field photometry (pure CPU).
//! - [`nearfield`]: near-field scans (pure CPU).
//! - [`files`]: reading files with limits, writing outputs through temporary files (pure CPU).
//! - [`memory`]: freed memory handed back to the system between a long computation's stages.
//! - [`scene`]: scene lighting's CPU layer: glTF scenes, luminaire placement, ray queries and the
//!   reference path tracer (pure CPU).
//! - [`source`]: any luminaire file: its kind and the one dispatch to its reader (pure CPU).
//! - [`draw`]: text with the bundled font and the GLB container, for plots, pictures and meshes
//!   (pure CPU, a leaf).
//! - [`gpu`]: wgpu renderer.
//! - [`eval`]: the near-field quality harness (synthetic scans against the exact ray-caster).
//! - [`interop`]: Vulkan external memory (the only ash / wgpu-hal code).
//! - [`ffi`]: the C ABI (the only `extern "C"` code).
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used))]

pub mod draw;
pub mod eval;
pub mod ffi;
pub mod files;
pub mod gpu;
pub mod interop;
pub mod memory;
pub mod nearfield;
pub mod photometry;
pub mod scene;
pub mod source;
