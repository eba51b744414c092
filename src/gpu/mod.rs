//! The wgpu renderer (safe wgpu only; Vulkan specifics live in `interop`).
//!
//! - [`context`]: device on Vulkan, error handling, device loss, logging.
//! - [`target`]: render targets (colour + depth outputs), export, read-back.
//! - [`camera`]: the host's matrices and conventions.
//! - [`frame`]: one frame: the validated view, the pass interface, recording every pass into the
//!   target.
//! - [`farfield`]: the far-field appearance pass and overlays.
//! - [`nearfield`]: the near-field appearance pass (scans), with [`residency`] of their tiles; the
//!   CPU geometry it draws and culls with is `nearfield::select` (`lit_bound`, `view`).
//! - [`scene`]: the scene lighting pass: a glTF scene lit by every instance, scans by their far
//!   field (direct light, cube shadow maps in an atlas, tiled light lists), in cd/m².
//! - [`shaders`]: the WGSL each pass compiles (generated constants, `shaders/common/`, the pass)
//!   and the CPU tests (naga) that hold the shader contract.
//! - [`slots`]: per-draw records at dynamic offsets.
//! - [`renderer`]: luminaires, instances and frames: what the C API drives.

pub mod camera;
pub mod context;
pub mod farfield;
pub mod frame;
pub mod nearfield;
pub mod renderer;
pub mod residency;
pub mod scene;
pub mod shaders;
pub mod slots;
pub mod target;

pub use camera::{DepthRange, HostCamera, Origin};
pub use context::{ContextDesc, GpuContext, LogLevel, LogSink};
pub use frame::{FrameView, OutputMode, Overlays, RenderOptions};
pub use renderer::{InstanceId, LuminaireId, Renderer};
pub use target::{Attachment, ColorFormat, DepthFormat, RenderTarget, TargetDesc};

use crate::interop::InteropError;
use crate::photometry::PhotometryError;

/// An error of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// A bad argument, named.
    #[error("invalid argument '{arg}': {message}")]
    InvalidArgument {
        /// The argument.
        arg: Arg,
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
    pub fn invalid(arg: Arg, message: impl Into<String>) -> Self {
        GpuError::InvalidArgument {
            arg,
            message: message.into(),
        }
    }
}

/// An argument the renderer checks, as its errors name it: a type, so a caller that renames
/// arguments for its users (the C API's `desc.budget_bytes`, `camera.view`) matches on it rather than
/// on text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Arg {
    /// The camera's view matrix (world → eye).
    View,
    /// The camera's projection matrix.
    Projection,
    /// An instance's model matrix (luminaire frame → world).
    Model,
    /// The render options' exposure (m²/cd).
    Exposure,
    /// The render options' photometric-solid radius (m).
    SolidRadius,
    /// The render options' output mode.
    Output,
    /// A render target.
    Target,
    /// A target's width and height (pixels).
    Size,
    /// A target's exported semaphores.
    Semaphores,
    /// Which output of a target.
    Attachment,
    /// A luminaire id.
    Luminaire,
    /// An instance id.
    Instance,
    /// An illuminance query's point and normal.
    PointNormal,
    /// An illuminance query's point (m).
    Point,
    /// A near-field luminaire's GPU budget (bytes).
    BudgetBytes,
    /// A near-field luminaire's content radius (m).
    ContentRadius,
    /// A near-field luminaire's proxy mesh.
    Proxy,
    /// A near-field scan.
    Scan,
    /// A near-field pack's layout.
    Pack,
    /// A scene to light.
    Scene,
    /// The scene pass's lux floor (lx).
    LuxFloor,
    /// The scene pass's largest shadow-map face (px).
    FacePx,
    /// Photons shot for the scene's inter-reflection.
    BouncePhotons,
    /// The distance a virtual point light's 1/r² is held at.
    VplClamp,
    /// Luminaires whose shadows are rendered again per frame.
    ShadowUpdates,
}

impl Arg {
    /// The argument's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Arg::View => "view",
            Arg::Projection => "projection",
            Arg::Model => "model",
            Arg::Exposure => "exposure",
            Arg::SolidRadius => "solid_radius_m",
            Arg::Output => "output",
            Arg::Target => "target",
            Arg::Size => "width/height",
            Arg::Semaphores => "semaphores",
            Arg::Attachment => "attachment",
            Arg::Luminaire => "luminaire",
            Arg::Instance => "instance",
            Arg::PointNormal => "point/normal",
            Arg::Point => "point",
            Arg::BudgetBytes => "budget_bytes",
            Arg::ContentRadius => "content_radius_m",
            Arg::Proxy => "proxy",
            Arg::Scan => "scan",
            Arg::Pack => "pack",
            Arg::Scene => "scene",
            Arg::LuxFloor => "lux_floor_lx",
            Arg::FacePx => "max_face_px",
            Arg::BouncePhotons => "bounce_photons",
            Arg::VplClamp => "vpl_clamp_m",
            Arg::ShadowUpdates => "shadow_updates_per_frame",
        }
    }
}

impl std::fmt::Display for Arg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
