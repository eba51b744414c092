//! The near-field appearance pass: a scanned luminaire (`.lvpack`) drawn from the host's camera with
//! the luminance its capture cameras measured (shaders/nearfield/pass.wgsl says what each fragment does).
//!
//! A [`NearfieldLuminaire`] holds on the GPU: the camera records, the selection tables
//! ([`crate::nearfield::select::Selection`]), a chunk map and a pool of residency chunks ([`super::residency`]) within a
//! budget, plus its bounding box and optional proxy mesh. When the whole pack fits the budget it is
//! uploaded once; otherwise each frame first makes resident every chunk of every camera the frame can
//! select (found on the CPU from the view, conservatively), so a frame never reads a tile that is not
//! there; a view that needs more than the budget is an error, never a partial image.
//!
//! - `luminaire.rs`: [`NearfieldLuminaire`], a pack's GPU state, and making a view's chunks resident;
//! - `upload.rs`: [`NearfieldPass::upload`], a pack onto the GPU (records, tables, pool);
//! - `pass.rs`: [`NearfieldPass`]: pipelines, a frame's draws (`prepare`), and drawing them;
//! - `records.rs`: the GPU-side layout: storage blocks, pool layout, vertex layouts, buffers.

use crate::nearfield::select::{SelectionMode, SelectionOptions};

/// Pool pages a luminaire can bind (the shader declares this many).
pub const MAX_POOL_PAGES: usize = 8;

/// Largest pool page (lavapipe's storage-binding limit; also kind to real GPUs).
pub const MAX_PAGE_BYTES: u64 = 128 << 20;

/// Default GPU budget of one near-field luminaire (bytes).
pub const DEFAULT_BUDGET_BYTES: u64 = 512 << 20;

/// How a scan becomes a GPU luminaire.
#[derive(Debug, Clone, PartialEq)]
pub struct NearfieldOptions {
    /// GPU bytes this luminaire may hold: camera records, selection tables, chunk map and tile pool
    /// together. The pool gets what the rest leaves, at most [`MAX_POOL_PAGES`] × 128 MiB.
    pub budget_bytes: u64,
    /// Radius (m) of the ball around the capture centre that holds everything the cameras saw;
    /// `None` derives it from the cameras' tile bounding boxes (see
    /// [`crate::nearfield::select::view::content_radius_m`]).
    pub content_radius_m: Option<f64>,
    /// Selection-table options.
    pub selection: SelectionOptions,
    /// Without a proxy, draw the bounding polygon of the pixels that can be lit ([`crate::nearfield::select::lit_bound`])
    /// instead of the content ball's box where it applies. The image is the same either way (the
    /// tests compare them); only the work differs.
    pub bounding_polygon: bool,
    /// The proxy encloses the light rather than being its surface (a ray file's grown hull,
    /// `PackProxy::bound`): images are then sampled plainly, dark texels included. Otherwise, in
    /// proxy mode, the bilinear weights are renormalised over the texels that hold light, so a
    /// surface's edge is not darkened by the darkness beyond it in the capture.
    pub proxy_is_bound: bool,
}

impl Default for NearfieldOptions {
    fn default() -> Self {
        NearfieldOptions {
            budget_bytes: DEFAULT_BUDGET_BYTES,
            content_radius_m: None,
            selection: SelectionOptions::default(),
            bounding_polygon: true,
            proxy_is_bound: false,
        }
    }
}

/// Per-instance settings of a near-field luminaire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NearfieldSettings {
    /// Camera selection.
    pub mode: SelectionMode,
    /// Use the proxy mesh (when the luminaire has one) for parallax-correct reprojection.
    pub proxy: bool,
}

impl Default for NearfieldSettings {
    fn default() -> Self {
        NearfieldSettings {
            mode: SelectionMode::Continuous,
            proxy: true,
        }
    }
}

mod luminaire;
mod pass;
mod records;
mod upload;

pub use luminaire::{NearfieldLuminaire, ResidencyReport};
#[cfg(test)]
pub(crate) use pass::pipeline_constant_names;
pub use pass::{NearfieldFrame, NearfieldPass};
#[cfg(test)]
pub(crate) use records::{DrawUniform, LumUniform};
