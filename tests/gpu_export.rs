//! The export test: every colour and depth format of a target is exported as an opaque fd, imported
//! into a second Vulkan device created here with ash (the "Vulkan host"), copied out and compared
//! byte for byte with the library's own read-back — through several frames of one import.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod gpu_common;

use std::os::fd::IntoRawFd;

use ash::vk;
use glam::{Mat4, Vec3};
use gpu_common::{asa, gl_perspective, look_at, renderer, GPU_LOCK};
use lumiview::gpu::{
    Attachment, ColorFormat, DepthFormat, DepthRange, HostCamera, Origin, Overlays, RenderOptions, RenderTarget,
    TargetDesc,
};

/// A second Vulkan device on the physical device with a given UUID.
struct VulkanHost {
    _entry: ash::Entry,
    instance: ash::Instance,
    device: ash::Device,
    phys: vk::PhysicalDevice,
    queue: vk::Queue,
    family: u32,
    pool: vk::CommandPool,
}

impl VulkanHost {
    fn new(uuid: [u8; 16]) -> VulkanHost {
        // SAFETY: test code; every Vulkan object created here is destroyed in Drop, and all structures
        // passed to Vulkan live for the duration of each call.
        unsafe {
            let entry = ash::Entry::load().expect("libvulkan");
            let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_1);
            let instance = entry
                .create_instance(&vk::InstanceCreateInfo::default().application_info(&app), None)
                .unwrap();
            let phys = instance
                .enumerate_physical_devices()
                .unwrap()
                .into_iter()
                .find(|&p| {
                    let mut id = vk::PhysicalDeviceIDProperties::default();
                    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut id);
                    instance.get_physical_device_properties2(p, &mut props);
                    id.device_uuid == uuid
                })
                .expect("a physical device with the exporter's UUID");
            let family = instance
                .get_physical_device_queue_family_properties(phys)
                .iter()
                .position(|q| q.queue_flags.contains(vk::QueueFlags::GRAPHICS))
                .unwrap() as u32;
            let exts = [ash::khr::external_memory_fd::NAME.as_ptr()];
            let prio = [1.0];
            let qinfo = [vk::DeviceQueueCreateInfo::default()
                .queue_family_index(family)
                .queue_priorities(&prio)];
            let device = instance
                .create_device(
                    phys,
                    &vk::DeviceCreateInfo::default()
                        .queue_create_infos(&qinfo)
                        .enabled_extension_names(&exts),
                    None,
                )
                .unwrap();
            let queue = device.get_device_queue(family, 0);
            let pool = device
                .create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(family), None)
                .unwrap();
            VulkanHost {
                _entry: entry,
                instance,
                device,
                phys,
                queue,
                family,
                pool,
            }
        }
    }

    fn memory_type(&self, bits: u32, flags: vk::MemoryPropertyFlags) -> u32 {
        // SAFETY: a query on a live instance.
        let props = unsafe { self.instance.get_physical_device_memory_properties(self.phys) };
        (0..props.memory_type_count)
            .find(|&i| bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(flags))
            .expect("memory type")
    }

    /// Imports an exported image and returns an importer that can read it back repeatedly.
    fn import(&self, e: &lumiview::interop::ExportInfo, fd: i32) -> Imported {
        // SAFETY: test code; the fd comes from vkGetMemoryFdKHR of a dedicated OPAQUE_FD allocation of an
        // image with exactly these parameters; ownership of the fd passes to Vulkan on success.
        unsafe {
            let format = vk::Format::from_raw(e.vk_format);
            let mut ext =
                vk::ExternalMemoryImageCreateInfo::default().handle_types(vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD);
            let image = self
                .device
                .create_image(
                    &vk::ImageCreateInfo::default()
                        .image_type(vk::ImageType::TYPE_2D)
                        .format(format)
                        .extent(vk::Extent3D {
                            width: e.width,
                            height: e.height,
                            depth: 1,
                        })
                        .mip_levels(1)
                        .array_layers(1)
                        .samples(vk::SampleCountFlags::TYPE_1)
                        .tiling(vk::ImageTiling::from_raw(e.vk_tiling))
                        .usage(vk::ImageUsageFlags::from_raw(e.vk_usage))
                        .sharing_mode(vk::SharingMode::EXCLUSIVE)
                        .initial_layout(vk::ImageLayout::UNDEFINED)
                        .push_next(&mut ext),
                    None,
                )
                .unwrap();
            let req = self.device.get_image_memory_requirements(image);
            assert!(
                req.size <= e.allocation_size,
                "importer needs {} > exported {}",
                req.size,
                e.allocation_size
            );
            let mut import = vk::ImportMemoryFdInfoKHR::default()
                .handle_type(vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD)
                .fd(fd);
            let mut dedicated = vk::MemoryDedicatedAllocateInfo::default().image(image);
            let memory = self
                .device
                .allocate_memory(
                    &vk::MemoryAllocateInfo::default()
                        .allocation_size(e.allocation_size)
                        .memory_type_index({
                            assert!(
                                req.memory_type_bits & (1 << e.memory_type_index) != 0,
                                "exporter's memory type fits"
                            );
                            e.memory_type_index
                        })
                        .push_next(&mut import)
                        .push_next(&mut dedicated),
                    None,
                )
                .unwrap();
            self.device.bind_image_memory(image, memory, 0).unwrap();
            let is_depth = format == vk::Format::D32_SFLOAT;
            let bytes_per_pixel = match format {
                vk::Format::R16G16B16A16_SFLOAT => 8,
                vk::Format::R32G32B32A32_SFLOAT => 16,
                _ => 4,
            };
            let size = (e.width * e.height * bytes_per_pixel) as u64;
            let buffer = self
                .device
                .create_buffer(
                    &vk::BufferCreateInfo::default()
                        .size(size)
                        .usage(vk::BufferUsageFlags::TRANSFER_DST),
                    None,
                )
                .unwrap();
            let breq = self.device.get_buffer_memory_requirements(buffer);
            let bmem = self
                .device
                .allocate_memory(
                    &vk::MemoryAllocateInfo::default()
                        .allocation_size(breq.size)
                        .memory_type_index(self.memory_type(
                            breq.memory_type_bits,
                            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
                        )),
                    None,
                )
                .unwrap();
            self.device.bind_buffer_memory(buffer, bmem, 0).unwrap();
            Imported {
                image,
                memory,
                buffer,
                bmem,
                size,
                aspect: if is_depth {
                    vk::ImageAspectFlags::DEPTH
                } else {
                    vk::ImageAspectFlags::COLOR
                },
                width: e.width,
                height: e.height,
                release_layout: vk::ImageLayout::from_raw(e.vk_layout),
            }
        }
    }

    /// Acquires the image from the external queue family, copies it out, releases it back.
    fn read(&self, im: &Imported) -> Vec<u8> {
        // SAFETY: test code; the exporter finished rendering (lumi_render waits) and released the image
        // to VK_QUEUE_FAMILY_EXTERNAL in `release_layout`; we acquire, copy, release back, and wait.
        unsafe {
            let cb = self
                .device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(self.pool)
                        .command_buffer_count(1),
                )
                .unwrap()[0];
            self.device
                .begin_command_buffer(cb, &vk::CommandBufferBeginInfo::default())
                .unwrap();
            let range = vk::ImageSubresourceRange {
                aspect_mask: im.aspect,
                base_mip_level: 0,
                level_count: 1,
                base_array_layer: 0,
                layer_count: 1,
            };
            let acquire = vk::ImageMemoryBarrier::default()
                .old_layout(im.release_layout)
                .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                .src_queue_family_index(vk::QUEUE_FAMILY_EXTERNAL)
                .dst_queue_family_index(self.family)
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ)
                .image(im.image)
                .subresource_range(range);
            self.device.cmd_pipeline_barrier(
                cb,
                vk::PipelineStageFlags::TOP_OF_PIPE,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[acquire],
            );
            let region = vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: im.aspect,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D {
                    width: im.width,
                    height: im.height,
                    depth: 1,
                });
            self.device.cmd_copy_image_to_buffer(
                cb,
                im.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                im.buffer,
                &[region],
            );
            let release = vk::ImageMemoryBarrier::default()
                .old_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                .new_layout(im.release_layout)
                .src_queue_family_index(self.family)
                .dst_queue_family_index(vk::QUEUE_FAMILY_EXTERNAL)
                .src_access_mask(vk::AccessFlags::TRANSFER_READ)
                .image(im.image)
                .subresource_range(range);
            self.device.cmd_pipeline_barrier(
                cb,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[release],
            );
            self.device.end_command_buffer(cb).unwrap();
            let cbs = [cb];
            self.device
                .queue_submit(
                    self.queue,
                    &[vk::SubmitInfo::default().command_buffers(&cbs)],
                    vk::Fence::null(),
                )
                .unwrap();
            self.device.queue_wait_idle(self.queue).unwrap();
            self.device.free_command_buffers(self.pool, &cbs);
            let ptr = self
                .device
                .map_memory(im.bmem, 0, im.size, vk::MemoryMapFlags::empty())
                .unwrap();
            let out = std::slice::from_raw_parts(ptr.cast::<u8>(), im.size as usize).to_vec();
            self.device.unmap_memory(im.bmem);
            out
        }
    }

    fn free(&self, im: Imported) {
        // SAFETY: the queue is idle; the objects were created by this device.
        unsafe {
            self.device.destroy_buffer(im.buffer, None);
            self.device.free_memory(im.bmem, None);
            self.device.destroy_image(im.image, None);
            self.device.free_memory(im.memory, None);
        }
    }
}

impl Drop for VulkanHost {
    fn drop(&mut self) {
        // SAFETY: everything created from the device was freed; destroy in reverse order.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(self.pool, None);
            self.device.destroy_device(None);
            self.instance.destroy_instance(None);
        }
    }
}

struct Imported {
    image: vk::Image,
    memory: vk::DeviceMemory,
    buffer: vk::Buffer,
    bmem: vk::DeviceMemory,
    size: u64,
    aspect: vk::ImageAspectFlags,
    width: u32,
    height: u32,
    release_layout: vk::ImageLayout,
}

#[test]
fn every_format_imports_into_a_second_vulkan_device_exactly() {
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(mut r) = renderer() else { return };
    assert!(
        r.ctx.caps.external_memory,
        "the device must export memory (lavapipe does)"
    );
    let host = VulkanHost::new(r.ctx.caps.device_uuid);
    let lum = r.add_photometry(asa()).unwrap();
    r.add_instance(lum, Mat4::IDENTITY).unwrap();
    r.add_instance(lum, Mat4::from_translation(Vec3::new(0.5, 0.2, -0.3)))
        .unwrap();
    let opts = RenderOptions {
        overlays: Overlays {
            solid: true,
            housing: true,
        },
        ..RenderOptions::default()
    };
    let mut checked = 0;
    for color in [
        ColorFormat::Rgba16Float,
        ColorFormat::Rgba32Float,
        ColorFormat::Rgba8Srgb,
    ] {
        for depth in [DepthFormat::R32Float, DepthFormat::Depth32Float] {
            let desc = TargetDesc {
                width: 67,
                height: 45,
                color,
                depth,
                exportable: true,
                semaphores: false,
            };
            let mut t = RenderTarget::new(&r.ctx, &desc).unwrap();
            let opts = if color == ColorFormat::Rgba8Srgb {
                RenderOptions {
                    output: lumiview::gpu::OutputMode::ToneMapped,
                    exposure: 1e-4,
                    ..opts
                }
            } else {
                opts
            };
            r.render(&mut t, &camera(0), &opts).unwrap();
            let mut imports = Vec::new();
            for which in [Attachment::Color, Attachment::Depth] {
                let (fd, info) = t.export(&r.ctx, which).unwrap();
                // A new fd each call.
                let (fd2, _) = t.export(&r.ctx, which).unwrap();
                drop(fd2);
                imports.push((which, host.import(&info, fd.into_raw_fd())));
            }
            // Several frames through one import, with a moving camera.
            for frame in 0..3 {
                if frame > 0 {
                    r.render(&mut t, &camera(frame), &opts).unwrap();
                }
                for (which, im) in &imports {
                    let theirs = host.read(im);
                    let ours = t.read(&r.ctx, *which).unwrap();
                    assert_eq!(theirs.len(), ours.len());
                    let diff = theirs.iter().zip(&ours).filter(|(a, b)| a != b).count();
                    assert_eq!(
                        diff, 0,
                        "{color:?}/{depth:?} {which:?} frame {frame}: {diff} bytes differ"
                    );
                    let nonzero = ours.iter().filter(|b| **b != 0).count();
                    assert!(nonzero > 0, "{which:?} image is empty");
                    checked += 1;
                }
            }
            for (_, im) in imports {
                host.free(im);
            }
        }
    }
    assert_eq!(checked, 3 * 2 * 2 * 3);
    gpu_common::assert_no_validation_messages();
}

fn camera(frame: u32) -> HostCamera {
    let a = 0.3 * frame as f32;
    let eye = Vec3::new(1.5 * a.cos(), 1.5 * a.sin(), -2.0);
    HostCamera {
        view: look_at(eye, Vec3::ZERO, Vec3::Z),
        projection: gl_perspective(50f32.to_radians(), 67.0 / 45.0, 0.1, 10.0),
        depth_range: DepthRange::NegOneToOne,
        reversed_z: false,
        origin: Origin::TopLeft,
    }
}
