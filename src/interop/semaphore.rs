//! Exportable binary semaphores (`VK_KHR_external_semaphore_fd`, opaque fd) for GPU-side
//! synchronisation with the host, where the driver has them (real GPUs; not Mesa lavapipe).
//!
//! Per target two semaphores: `render_done` (lumiview signals it with each frame's submission; the
//! host waits on it before reading) and `host_done` (the host signals it after its reads; lumiview's
//! next frame waits on it before writing). With them `lumi_render` does not wait on the CPU.

use std::os::fd::{FromRawFd, OwnedFd};

use ash::vk;
use wgpu::hal::api::Vulkan;

use super::InteropError;

/// A binary semaphore created exportable as an opaque fd on wgpu's device.
#[derive(Debug)]
pub struct ExportableSemaphore {
    device: wgpu::Device,
    raw: vk::Semaphore,
}

impl ExportableSemaphore {
    /// Creates the semaphore; `Unsupported` when the device cannot export semaphores as opaque fds.
    pub fn new(adapter: &wgpu::Adapter, device: &wgpu::Device) -> Result<Self, InteropError> {
        // SAFETY: queries and object creation on wgpu's own Vulkan device, borrowed through as_hal
        // for this block; the semaphore is destroyed in Drop while `self.device` keeps the device alive.
        unsafe {
            let hal_adapter = adapter
                .as_hal::<Vulkan>()
                .ok_or_else(|| InteropError::Vulkan("not a Vulkan adapter".into()))?;
            let instance = hal_adapter.shared_instance().raw_instance();
            let info = vk::PhysicalDeviceExternalSemaphoreInfo::default()
                .handle_type(vk::ExternalSemaphoreHandleTypeFlags::OPAQUE_FD);
            let mut props = vk::ExternalSemaphoreProperties::default();
            instance.get_physical_device_external_semaphore_properties(
                hal_adapter.raw_physical_device(),
                &info,
                &mut props,
            );
            if !props
                .external_semaphore_features
                .contains(vk::ExternalSemaphoreFeatureFlags::EXPORTABLE)
            {
                return Err(InteropError::Unsupported(
                    "the driver cannot export semaphores as opaque fds (VK_KHR_external_semaphore_fd)".into(),
                ));
            }
            drop(hal_adapter);
            let hal_device = device
                .as_hal::<Vulkan>()
                .ok_or_else(|| InteropError::Vulkan("not a Vulkan device".into()))?;
            if !hal_device
                .enabled_device_extensions()
                .contains(&ash::khr::external_semaphore_fd::NAME)
            {
                return Err(InteropError::Unsupported(
                    "VK_KHR_external_semaphore_fd is not enabled on this device".into(),
                ));
            }
            let mut export =
                vk::ExportSemaphoreCreateInfo::default().handle_types(vk::ExternalSemaphoreHandleTypeFlags::OPAQUE_FD);
            let raw = hal_device
                .raw_device()
                .create_semaphore(&vk::SemaphoreCreateInfo::default().push_next(&mut export), None)
                .map_err(|e| InteropError::Vulkan(format!("vkCreateSemaphore: {e}")))?;
            Ok(ExportableSemaphore {
                device: device.clone(),
                raw,
            })
        }
    }

    /// Exports a new opaque fd of the semaphore (owned by the caller; a successful import takes it).
    pub fn export_fd(&self) -> Result<OwnedFd, InteropError> {
        // SAFETY: the semaphore was created exportable as OPAQUE_FD on this device; the returned fd is
        // new and owned by us until wrapped.
        unsafe {
            let hal_device = self
                .device
                .as_hal::<Vulkan>()
                .ok_or_else(|| InteropError::Vulkan("not a Vulkan device".into()))?;
            let loader = ash::khr::external_semaphore_fd::Device::new(
                hal_device.shared_instance().raw_instance(),
                hal_device.raw_device(),
            );
            let info = vk::SemaphoreGetFdInfoKHR::default()
                .semaphore(self.raw)
                .handle_type(vk::ExternalSemaphoreHandleTypeFlags::OPAQUE_FD);
            let fd = loader
                .get_semaphore_fd(&info)
                .map_err(|e| InteropError::Vulkan(format!("vkGetSemaphoreFdKHR: {e}")))?;
            if fd < 0 {
                return Err(InteropError::Vulkan(format!("vkGetSemaphoreFdKHR returned fd {fd}")));
            }
            Ok(OwnedFd::from_raw_fd(fd))
        }
    }

    /// The next `queue.submit` signals this semaphore when its work completes.
    pub fn signal_on_next_submit(&self, queue: &wgpu::Queue) {
        // SAFETY: the semaphore lives as long as self, which outlives the submission (Drop waits idle).
        unsafe {
            if let Some(q) = queue.as_hal::<Vulkan>() {
                q.add_signal_semaphore(self.raw, None);
            }
        }
    }

    /// The next `queue.submit` waits for this semaphore before any of its commands run.
    pub fn wait_on_next_submit(&self, queue: &wgpu::Queue) {
        // SAFETY: as above; the host promised to signal it once per frame (docs/interop.md).
        unsafe {
            if let Some(q) = queue.as_hal::<Vulkan>() {
                // Every command waits (ALL_COMMANDS), and the acquire barrier's first scope is
                // ALL_COMMANDS too, so the two form one dependency chain.
                q.add_wait_semaphore(self.raw, None, vk::PipelineStageFlags::ALL_COMMANDS);
            }
        }
    }
}

impl Drop for ExportableSemaphore {
    fn drop(&mut self) {
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        // SAFETY: the device is idle, so no pending submission uses the semaphore; destroyed once.
        unsafe {
            if let Some(d) = self.device.as_hal::<Vulkan>() {
                d.raw_device().destroy_semaphore(self.raw, None);
            }
        }
    }
}
