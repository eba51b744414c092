//! Exportable images: a `VkImage` with a dedicated, exportable allocation (opaque fd), created with
//! ash on wgpu's own `VkDevice` and wrapped as a `wgpu::Texture`; fd export; and the queue-family
//! release/acquire barriers around each frame.

use std::os::fd::{FromRawFd, OwnedFd};

use ash::vk;
use wgpu::hal::api::Vulkan;

use super::InteropError;

/// Where the image is left for the host after each frame (release to `VK_QUEUE_FAMILY_EXTERNAL`).
/// GL hosts name the matching `GL_LAYOUT_SHADER_READ_ONLY_EXT` when they use semaphores.
pub const RELEASE_LAYOUT: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

/// What a host needs to import an exported image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExportInfo {
    /// Size of the allocation in bytes (`VkMemoryRequirements::size`; GL `glImportMemoryFdEXT` size).
    pub allocation_size: u64,
    /// The `VkFormat` of the image.
    pub vk_format: i32,
    /// `VK_IMAGE_TILING_OPTIMAL` (0) — hosts must import with optimal tiling too.
    pub vk_tiling: i32,
    /// The allocation is dedicated to this image (GL: `GL_DEDICATED_MEMORY_OBJECT_EXT` = true).
    pub dedicated: bool,
    /// The `VkImageLayout` the image is in when a render returns.
    pub vk_layout: i32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `VkImageUsageFlags` the image was created with (a Vulkan host must import with the same).
    pub vk_usage: u32,
    /// `memoryTypeIndex` of the exported allocation: a Vulkan host importing the fd must allocate
    /// with the same index (same physical device, hence the same memory types).
    pub memory_type_index: u32,
}

/// An exportable image wrapped as a wgpu texture. The memory lives until the wgpu texture is dropped
/// (wgpu calls our drop callback, which destroys the image and frees the memory); hosts that imported
/// an fd keep their own reference to the memory.
#[derive(Debug)]
pub struct ExportableImage {
    /// The wgpu texture over the image.
    pub texture: wgpu::Texture,
    image: vk::Image,
    memory: vk::DeviceMemory,
    aspect: vk::ImageAspectFlags,
    attachment_layout: vk::ImageLayout,
    /// Import information for hosts.
    pub info: ExportInfo,
    /// Whether the image has been released to the external queue family at least once (the next
    /// frame must acquire it back first).
    released: bool,
}

/// Whether `format` can be created as an exportable optimal-tiling image with `usage`.
fn exportable(
    adapter: &wgpu::Adapter,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
) -> Result<(bool, bool), InteropError> {
    // SAFETY: borrowing the hal adapter to query format properties of its physical device with its
    // own instance; all structures live on this stack frame for the call.
    unsafe {
        let hal = adapter
            .as_hal::<Vulkan>()
            .ok_or_else(|| InteropError::Vulkan("not a Vulkan adapter".into()))?;
        let instance = hal.shared_instance().raw_instance();
        let mut ext_info = vk::PhysicalDeviceExternalImageFormatInfo::default()
            .handle_type(vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD);
        let info = vk::PhysicalDeviceImageFormatInfo2::default()
            .format(format)
            .ty(vk::ImageType::TYPE_2D)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .push_next(&mut ext_info);
        let mut ext_props = vk::ExternalImageFormatProperties::default();
        let mut props = vk::ImageFormatProperties2::default().push_next(&mut ext_props);
        match instance.get_physical_device_image_format_properties2(hal.raw_physical_device(), &info, &mut props) {
            Ok(()) => {
                let f = ext_props.external_memory_properties.external_memory_features;
                Ok((
                    f.contains(vk::ExternalMemoryFeatureFlags::EXPORTABLE),
                    f.contains(vk::ExternalMemoryFeatureFlags::DEDICATED_ONLY),
                ))
            }
            Err(vk::Result::ERROR_FORMAT_NOT_SUPPORTED) => Ok((false, false)),
            Err(e) => Err(InteropError::Vulkan(format!(
                "vkGetPhysicalDeviceImageFormatProperties2: {e}"
            ))),
        }
    }
}

impl ExportableImage {
    /// Creates an exportable `width × height` image of `format` usable as a render attachment, a copy
    /// source and a sampled texture, and wraps it as a wgpu texture.
    pub fn new(
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        label: &str,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
    ) -> Result<Self, InteropError> {
        let is_depth = format.is_depth_stencil_format();
        let (aspect, attach_usage, attachment_layout, hal_attach) = if is_depth {
            (
                vk::ImageAspectFlags::DEPTH,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                wgpu::TextureUses::DEPTH_STENCIL_WRITE | wgpu::TextureUses::DEPTH_STENCIL_READ,
            )
        } else {
            (
                vk::ImageAspectFlags::COLOR,
                vk::ImageUsageFlags::COLOR_ATTACHMENT,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                wgpu::TextureUses::COLOR_TARGET,
            )
        };
        let vk_usage = attach_usage
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::SAMPLED;
        // SAFETY: borrowing the hal adapter only to translate a format; no handle escapes.
        let vk_format = unsafe {
            adapter
                .as_hal::<Vulkan>()
                .ok_or_else(|| InteropError::Vulkan("not a Vulkan adapter".into()))?
                .texture_format_as_raw(format)
        };
        let (can_export, _dedicated_only) = exportable(adapter, vk_format, vk_usage)?;
        if !can_export {
            return Err(InteropError::Unsupported(format!(
                "the driver cannot export {format:?} ({vk_format:?}) images as opaque fds"
            )));
        }
        // SAFETY: we create the image and memory on wgpu's own VkDevice (borrowed through as_hal for
        // this block), bind them once, and hand ownership to wgpu-hal through texture_from_raw with a
        // drop callback that destroys both exactly once, when wgpu drops the texture. On every early
        // error return the objects created so far are destroyed here.
        unsafe {
            let hal_device = device
                .as_hal::<Vulkan>()
                .ok_or_else(|| InteropError::Vulkan("not a Vulkan device".into()))?;
            let raw = hal_device.raw_device().clone();
            let instance = hal_device.shared_instance().raw_instance();
            let phys = hal_device.raw_physical_device();
            let mut ext =
                vk::ExternalMemoryImageCreateInfo::default().handle_types(vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD);
            let create = vk::ImageCreateInfo::default()
                .image_type(vk::ImageType::TYPE_2D)
                .format(vk_format)
                .extent(vk::Extent3D {
                    width,
                    height,
                    depth: 1,
                })
                .mip_levels(1)
                .array_layers(1)
                .samples(vk::SampleCountFlags::TYPE_1)
                .tiling(vk::ImageTiling::OPTIMAL)
                .usage(vk_usage)
                .sharing_mode(vk::SharingMode::EXCLUSIVE)
                .initial_layout(vk::ImageLayout::UNDEFINED)
                .push_next(&mut ext);
            let image = raw
                .create_image(&create, None)
                .map_err(|e| InteropError::Vulkan(format!("vkCreateImage: {e}")))?;
            let req = raw.get_image_memory_requirements(image);
            let mem_props = instance.get_physical_device_memory_properties(phys);
            let type_index = (0..mem_props.memory_type_count).find(|&i| {
                req.memory_type_bits & (1 << i) != 0
                    && mem_props.memory_types[i as usize]
                        .property_flags
                        .contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
            });
            let Some(type_index) = type_index else {
                raw.destroy_image(image, None);
                return Err(InteropError::Vulkan(
                    "no device-local memory type fits the image".into(),
                ));
            };
            let mut export =
                vk::ExportMemoryAllocateInfo::default().handle_types(vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD);
            let mut dedicated = vk::MemoryDedicatedAllocateInfo::default().image(image);
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(type_index)
                .push_next(&mut export)
                .push_next(&mut dedicated);
            let memory = match raw.allocate_memory(&alloc, None) {
                Ok(m) => m,
                Err(e) => {
                    raw.destroy_image(image, None);
                    let what = format!("vkAllocateMemory ({} bytes): {e}", req.size);
                    return Err(match e {
                        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                            InteropError::OutOfMemory(what)
                        }
                        _ => InteropError::Vulkan(what),
                    });
                }
            };
            if let Err(e) = raw.bind_image_memory(image, memory, 0) {
                raw.destroy_image(image, None);
                raw.free_memory(memory, None);
                return Err(InteropError::Vulkan(format!("vkBindImageMemory: {e}")));
            }
            let size = wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            };
            let hal_desc = wgpu::hal::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: hal_attach
                    | wgpu::TextureUses::COPY_SRC
                    | wgpu::TextureUses::COPY_DST
                    | wgpu::TextureUses::RESOURCE,
                memory_flags: wgpu::hal::MemoryFlags::empty(),
                view_formats: vec![],
            };
            let drop_device = raw.clone();
            let callback: wgpu::hal::DropCallback = Box::new(move || {
                drop_device.destroy_image(image, None);
                drop_device.free_memory(memory, None);
            });
            let hal_texture = hal_device.texture_from_raw(
                image,
                &hal_desc,
                Some(callback),
                wgpu::hal::vulkan::TextureMemory::External,
            );
            drop(hal_device);
            let usage = if is_depth {
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::TEXTURE_BINDING
            } else {
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST
                    | wgpu::TextureUsages::TEXTURE_BINDING
            };
            let texture = device.create_texture_from_hal::<Vulkan>(
                hal_texture,
                &wgpu::TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                },
                wgpu::TextureUses::UNINITIALIZED,
            );
            Ok(Self {
                texture,
                image,
                memory,
                aspect,
                attachment_layout,
                info: ExportInfo {
                    allocation_size: req.size,
                    vk_format: vk_format.as_raw(),
                    vk_tiling: vk::ImageTiling::OPTIMAL.as_raw(),
                    dedicated: true,
                    vk_layout: RELEASE_LAYOUT.as_raw(),
                    width,
                    height,
                    vk_usage: vk_usage.as_raw(),
                    memory_type_index: type_index,
                },
                released: false,
            })
        }
    }

    /// Exports the image's memory as a new opaque fd, owned by the caller (a successful GL or Vulkan
    /// import takes ownership of it; otherwise the caller closes it).
    pub fn export_fd(&self, device: &wgpu::Device) -> Result<OwnedFd, InteropError> {
        // SAFETY: `self.memory` is alive while `self.texture` is (its drop callback frees it), and it
        // was allocated with OPAQUE_FD export info on this device. vkGetMemoryFdKHR returns a new fd
        // that we own and wrap immediately.
        unsafe {
            let hal_device = device
                .as_hal::<Vulkan>()
                .ok_or_else(|| InteropError::Vulkan("not a Vulkan device".into()))?;
            if !hal_device
                .enabled_device_extensions()
                .contains(&ash::khr::external_memory_fd::NAME)
            {
                return Err(InteropError::Unsupported(
                    "VK_KHR_external_memory_fd is not enabled on this device".into(),
                ));
            }
            let loader = ash::khr::external_memory_fd::Device::new(
                hal_device.shared_instance().raw_instance(),
                hal_device.raw_device(),
            );
            let info = vk::MemoryGetFdInfoKHR::default()
                .memory(self.memory)
                .handle_type(vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD);
            let fd = loader
                .get_memory_fd(&info)
                .map_err(|e| InteropError::Vulkan(format!("vkGetMemoryFdKHR: {e}")))?;
            if fd < 0 {
                return Err(InteropError::Vulkan(format!("vkGetMemoryFdKHR returned fd {fd}")));
            }
            Ok(OwnedFd::from_raw_fd(fd))
        }
    }

    /// Records, into its own command encoder, the acquire from `VK_QUEUE_FAMILY_EXTERNAL` (from
    /// [`RELEASE_LAYOUT`] to the attachment layout wgpu's tracker believes the image is in).
    /// Returns `None` before the first release (nothing to acquire).
    pub fn encode_acquire(&self, device: &wgpu::Device, queue_family: u32) -> Option<wgpu::CommandBuffer> {
        if !self.released {
            return None;
        }
        Some(self.encode_barrier(
            device,
            queue_family,
            Transfer {
                src_family: vk::QUEUE_FAMILY_EXTERNAL,
                dst_family: queue_family,
                old_layout: RELEASE_LAYOUT,
                new_layout: self.attachment_layout,
                src_access: vk::AccessFlags::empty(),
                dst_access: self.attachment_access(),
                // ALL_COMMANDS, not TOP_OF_PIPE (no stage in a first scope): with semaphores this
                // chains to the wait on `host_done` (at ALL_COMMANDS), so the layout transition
                // happens after the host's release.
                src_stage: vk::PipelineStageFlags::ALL_COMMANDS,
                dst_stage: self.attachment_stage(),
            },
        ))
    }

    /// Notes that the release recorded by [`ExportableImage::encode_release`] was submitted: the
    /// image now belongs to the host, and the next frame acquires it first.
    pub fn mark_released(&mut self) {
        self.released = true;
    }

    /// Records the release to `VK_QUEUE_FAMILY_EXTERNAL` (attachment layout → [`RELEASE_LAYOUT`]).
    /// Call only when wgpu's last use of the texture in this submission left it in its attachment
    /// state; call [`ExportableImage::mark_released`] after submitting it.
    pub fn encode_release(&self, device: &wgpu::Device, queue_family: u32) -> wgpu::CommandBuffer {
        self.encode_barrier(
            device,
            queue_family,
            Transfer {
                src_family: queue_family,
                dst_family: vk::QUEUE_FAMILY_EXTERNAL,
                old_layout: self.attachment_layout,
                new_layout: RELEASE_LAYOUT,
                src_access: self.attachment_access(),
                dst_access: vk::AccessFlags::empty(),
                src_stage: self.attachment_stage(),
                dst_stage: vk::PipelineStageFlags::BOTTOM_OF_PIPE,
            },
        )
    }

    fn attachment_access(&self) -> vk::AccessFlags {
        if self.aspect == vk::ImageAspectFlags::DEPTH {
            vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ
        } else {
            vk::AccessFlags::COLOR_ATTACHMENT_WRITE | vk::AccessFlags::COLOR_ATTACHMENT_READ
        }
    }

    fn attachment_stage(&self) -> vk::PipelineStageFlags {
        if self.aspect == vk::ImageAspectFlags::DEPTH {
            vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS
        } else {
            vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
        }
    }

    fn encode_barrier(&self, device: &wgpu::Device, _queue_family: u32, t: Transfer) -> wgpu::CommandBuffer {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("lumiview queue-family transfer"),
        });
        let image = self.image;
        let aspect = self.aspect;
        // SAFETY: the raw barrier is recorded into an encoder that holds no wgpu commands (wgpu 30
        // forbids mixing them), on the image we created, with layouts matching what wgpu's tracker
        // and the previous release left; the command buffer is submitted in order with the frame's.
        unsafe {
            let Some(raw) = device.as_hal::<Vulkan>().map(|d| d.raw_device().clone()) else {
                return encoder.finish();
            };
            encoder.as_hal_mut::<Vulkan, _, _>(|hal_encoder| {
                let Some(hal_encoder) = hal_encoder else { return };
                let cb = hal_encoder.raw_handle();
                let barrier = vk::ImageMemoryBarrier::default()
                    .src_access_mask(t.src_access)
                    .dst_access_mask(t.dst_access)
                    .old_layout(t.old_layout)
                    .new_layout(t.new_layout)
                    .src_queue_family_index(t.src_family)
                    .dst_queue_family_index(t.dst_family)
                    .image(image)
                    .subresource_range(vk::ImageSubresourceRange {
                        aspect_mask: aspect,
                        base_mip_level: 0,
                        level_count: 1,
                        base_array_layer: 0,
                        layer_count: 1,
                    });
                raw.cmd_pipeline_barrier(
                    cb,
                    t.src_stage,
                    t.dst_stage,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[],
                    &[barrier],
                );
            });
        }
        encoder.finish()
    }
}

struct Transfer {
    src_family: u32,
    dst_family: u32,
    old_layout: vk::ImageLayout,
    new_layout: vk::ImageLayout,
    src_access: vk::AccessFlags,
    dst_access: vk::AccessFlags,
    src_stage: vk::PipelineStageFlags,
    dst_stage: vk::PipelineStageFlags,
}
