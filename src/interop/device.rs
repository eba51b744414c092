//! Opening the wgpu device on Vulkan with the external-memory extensions, on the physical device
//! the host names (by UUID) if it names one, and reporting what the device can do.

use std::ffi::CStr;

use ash::vk;
use wgpu::hal::api::Vulkan;

use super::InteropError;

/// What the opened device can do and who it is (for the host's UUID check).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceCaps {
    /// `VkPhysicalDeviceIDProperties::deviceUUID` (compare with `GL_DEVICE_UUID_EXT`).
    pub device_uuid: [u8; 16],
    /// `VkPhysicalDeviceIDProperties::driverUUID` (compare with `GL_DRIVER_UUID_EXT`).
    pub driver_uuid: [u8; 16],
    /// The adapter's name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub adapter_name: String,
    /// The driver's name and version as wgpu reports it.
    pub driver: String,
    /// `VK_KHR_external_memory_fd` is enabled: targets can be exported as opaque fds.
    pub external_memory: bool,
    /// `VK_KHR_external_semaphore_fd` is enabled.
    pub external_semaphore: bool,
    /// The queue family the renderer submits on (needed for ownership transfers).
    pub queue_family: u32,
    /// True for a software rasteriser (lavapipe).
    pub is_cpu: bool,
}

/// A wgpu device opened for lumiview.
#[derive(Debug)]
pub struct OpenedDevice {
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Capabilities and identity.
    pub caps: DeviceCaps,
}

/// Device and driver UUIDs of an adapter, read with `vkGetPhysicalDeviceProperties2`.
fn adapter_uuids(adapter: &wgpu::Adapter) -> Option<([u8; 16], [u8; 16])> {
    // SAFETY: the hal adapter is only borrowed for the duration of this call; we make no Vulkan call
    // that outlives it and only query properties of its physical device with its own instance.
    unsafe {
        let hal = adapter.as_hal::<Vulkan>()?;
        let instance = hal.shared_instance().raw_instance();
        let mut id = vk::PhysicalDeviceIDProperties::default();
        let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut id);
        instance.get_physical_device_properties2(hal.raw_physical_device(), &mut props);
        Some((id.device_uuid, id.driver_uuid))
    }
}

/// Whether the adapter has a device extension.
fn adapter_has_extension(adapter: &wgpu::Adapter, name: &CStr) -> bool {
    // SAFETY: borrowing the hal adapter to read its cached extension list; no Vulkan call is made.
    unsafe {
        adapter
            .as_hal::<Vulkan>()
            .is_some_and(|hal| hal.physical_device_capabilities().supports_extension(name))
    }
}

/// Enumerates the Vulkan adapters with their device UUIDs.
pub fn list_adapters(instance: &wgpu::Instance) -> Vec<(wgpu::Adapter, [u8; 16])> {
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN))
        .into_iter()
        .filter_map(|a| adapter_uuids(&a).map(|(dev, _)| (a, dev)))
        .collect()
}

/// Storage buffers per shader stage the passes need.
pub const NEEDED_STORAGE_BUFFERS: u32 = 16;

/// Opens a device: the adapter whose device UUID equals `preferred_uuid` (an error if none does),
/// else the first discrete GPU, integrated GPU, other, then CPU adapter. Requests
/// `VULKAN_EXTERNAL_MEMORY_FD` when the adapter has it and adds `VK_KHR_external_semaphore_fd`
/// where the driver has it.
pub fn open_device(instance: &wgpu::Instance, preferred_uuid: Option<[u8; 16]>) -> Result<OpenedDevice, InteropError> {
    let adapters = list_adapters(instance);
    if adapters.is_empty() {
        return Err(InteropError::NoAdapter(
            "no Vulkan adapter found (is a Vulkan driver installed? CI uses Mesa lavapipe: mesa-vulkan-drivers)".into(),
        ));
    }
    let adapter = match preferred_uuid {
        Some(uuid) => adapters
            .into_iter()
            .find(|(_, u)| *u == uuid)
            .map(|(a, _)| a)
            .ok_or_else(|| {
                InteropError::NoAdapter(format!(
                    "no Vulkan adapter has the requested device UUID {}",
                    hex(&uuid)
                ))
            })?,
        None => {
            let rank = |t: wgpu::DeviceType| match t {
                wgpu::DeviceType::DiscreteGpu => 0,
                wgpu::DeviceType::IntegratedGpu => 1,
                wgpu::DeviceType::VirtualGpu => 2,
                wgpu::DeviceType::Other => 3,
                wgpu::DeviceType::Cpu => 4,
            };
            let mut v = adapters;
            v.sort_by_key(|(a, _)| rank(a.get_info().device_type));
            v.into_iter()
                .next()
                .map(|(a, _)| a)
                .ok_or_else(|| InteropError::NoAdapter("no adapter".into()))?
        }
    };
    let (device_uuid, driver_uuid) =
        adapter_uuids(&adapter).ok_or_else(|| InteropError::NoAdapter("adapter is not a Vulkan adapter".into()))?;
    let info = adapter.get_info();
    let mut features = wgpu::Features::empty();
    let external_memory = adapter.features().contains(wgpu::Features::VULKAN_EXTERNAL_MEMORY_FD);
    if external_memory {
        features |= wgpu::Features::VULKAN_EXTERNAL_MEMORY_FD;
    }
    let external_semaphore = adapter_has_extension(&adapter, ash::khr::external_semaphore_fd::NAME);
    let mut limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
    // The near-field pass binds 16 storage buffers in its fragment stage (draw and luminaire records,
    // cameras, selection tables and proxy BVH, chunk map, counter, 8 pool pages of ≤ 128 MiB); lavapipe
    // allows 32, real GPUs more.
    let have = adapter.limits();
    if have.max_storage_buffers_per_shader_stage < NEEDED_STORAGE_BUFFERS {
        return Err(InteropError::Unsupported(format!(
            "the adapter allows {} storage buffers per shader stage; lumiview needs {NEEDED_STORAGE_BUFFERS}",
            have.max_storage_buffers_per_shader_stage
        )));
    }
    limits.max_storage_buffers_per_shader_stage = NEEDED_STORAGE_BUFFERS;
    limits.max_storage_buffer_binding_size = have.max_storage_buffer_binding_size.min(128 << 20);
    let desc = wgpu::DeviceDescriptor {
        label: Some("lumiview"),
        required_features: features,
        required_limits: limits.clone(),
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::MemoryUsage,
        trace: wgpu::Trace::Off,
    };
    // SAFETY: `open_with_callback` requires that the callback only adds extensions the device
    // supports (we add external_semaphore_fd only when the adapter lists it) and removes nothing;
    // the hal device it returns is handed straight to `create_device_from_hal` on the same adapter.
    let (device, queue, queue_family) = unsafe {
        let hal = adapter
            .as_hal::<Vulkan>()
            .ok_or_else(|| InteropError::NoAdapter("adapter is not a Vulkan adapter".into()))?;
        let callback: Box<wgpu::hal::vulkan::CreateDeviceCallback> = Box::new(move |args| {
            if external_semaphore {
                args.extensions.push(ash::khr::external_semaphore_fd::NAME);
                if !args.extensions.contains(&ash::khr::external_semaphore::NAME) {
                    args.extensions.push(ash::khr::external_semaphore::NAME);
                }
            }
        });
        let open = hal
            .open_with_callback(features, &limits, &desc.memory_hints, Some(callback))
            .map_err(|e| InteropError::Vulkan(format!("opening the Vulkan device failed: {e}")))?;
        let family = open.device.queue_family_index();
        drop(hal);
        let (device, queue) = adapter
            .create_device_from_hal::<Vulkan>(open, &desc)
            .map_err(|e| InteropError::Vulkan(format!("wgpu rejected the Vulkan device: {e}")))?;
        (device, queue, family)
    };
    let caps = DeviceCaps {
        device_uuid,
        driver_uuid,
        adapter_name: info.name.clone(),
        driver: format!("{} {}", info.driver, info.driver_info).trim().to_string(),
        external_memory,
        external_semaphore,
        queue_family,
        is_cpu: info.device_type == wgpu::DeviceType::Cpu,
    };
    Ok(OpenedDevice {
        adapter,
        device,
        queue,
        caps,
    })
}

/// Lower-case hex of a UUID.
pub fn hex(uuid: &[u8; 16]) -> String {
    uuid.iter().map(|b| format!("{b:02x}")).collect()
}
