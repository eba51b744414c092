//! The wgpu renderer (safe wgpu only; Vulkan specifics live in `interop`).
//!
//! - [`context`]: device on Vulkan, error handling, device loss, logging.
//! - [`target`]: render targets (colour + depth outputs), export, read-back.
//! - [`camera`]: the host's matrices and conventions.
//! - [`farfield`]: the far-field appearance pass and overlays.
//! - [`nearfield`]: the near-field appearance pass (scans), with [`residency`] of their tiles; the
//!   CPU geometry it draws and culls with is `nearfield::select` (`lit_bound`, `view`).
//! - [`shaders`]: the WGSL each pass compiles (generated constants, `shaders/common/`, the pass)
//!   and the CPU tests (naga) that hold the shader contract.
//! - [`slots`]: per-draw records at dynamic offsets.
//! - [`renderer`]: luminaires, instances and frames: what the C API drives.

pub mod camera;
pub mod context;
pub mod farfield;
pub mod nearfield;
pub mod renderer;
pub mod residency;
pub mod shaders;
pub mod slots;
pub mod target;

pub use camera::{DepthRange, HostCamera, Origin};
pub use context::{ContextDesc, GpuContext, LogLevel, LogSink};
pub use farfield::{OutputMode, Overlays, RenderOptions};
pub use renderer::{InstanceId, LuminaireId, Renderer};
pub use target::{Attachment, ColorFormat, DepthFormat, RenderTarget, TargetDesc};

use crate::interop::InteropError;
use crate::photometry::PhotometryError;

/// An error of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// A bad argument, named.
    #[error("invalid argument '{name}': {message}")]
    InvalidArgument {
        /// The argument.
        name: String,
        /// Why.
        message: String,
    },
    /// The device or driver lacks something (external memory, an exportable format).
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// wgpu reported a validation error.
    #[error("GPU validation error: {0}")]
    Validation(String),
    /// Out of GPU memory.
    #[error("out of GPU memory: {0}")]
    OutOfMemory(String),
    /// The device was lost.
    #[error("GPU device lost: {0}")]
    DeviceLost(String),
    /// Device creation or Vulkan interop failed.
    #[error(transparent)]
    Interop(#[from] InteropError),
    /// Loading photometry failed.
    #[error(transparent)]
    Photometry(#[from] PhotometryError),
    /// A near-field scan was bad or could not be read.
    #[error(transparent)]
    Nearfield(#[from] crate::nearfield::NearfieldError),
}

impl GpuError {
    /// An invalid-argument error.
    pub fn invalid(name: impl Into<String>, message: impl Into<String>) -> Self {
        GpuError::InvalidArgument {
            name: name.into(),
            message: message.into(),
        }
    }
}
