//! Vulkan external memory: the only module allowed to use `ash` or `wgpu::hal`.
//!
//! - [`device`]: opens the wgpu device on Vulkan with `VK_KHR_external_memory_fd` (and
//!   `VK_KHR_external_semaphore_fd` where the driver has it), on the physical device whose UUID the
//!   host names, and reports UUIDs and capabilities.
//! - [`image`]: exportable images (dedicated allocation, optimal tiling, opaque fd) wrapped as wgpu
//!   textures; fd export; queue-family release/acquire barriers around each frame.
//!
//! - [`semaphore`]: exportable binary semaphores for GPU-side synchronisation where the driver has
//!   `VK_KHR_external_semaphore_fd`.
//!
//! The synchronisation contract is written in docs/interop.md: without exported semaphores (Mesa
//! lavapipe) a render returns only after the GPU finished, and the host must finish its reads of a
//! target before the next render into it.

pub mod device;
pub mod image;
pub mod semaphore;

pub use device::{open_device, DeviceCaps, OpenedDevice};
pub use image::{ExportInfo, ExportableImage};
pub use semaphore::ExportableSemaphore;

/// An error of the Vulkan interop layer.
#[derive(Debug, thiserror::Error)]
pub enum InteropError {
    /// No suitable adapter.
    #[error("{0}")]
    NoAdapter(String),
    /// The driver lacks what is needed (an extension, an exportable format).
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A Vulkan call failed.
    #[error("Vulkan: {0}")]
    Vulkan(String),
    /// A Vulkan allocation failed for want of device or host memory.
    #[error("out of memory: {0}")]
    OutOfMemory(String),
}
