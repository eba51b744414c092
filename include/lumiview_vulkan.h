/* lumiview_vulkan.h: header-only helpers for a Vulkan host that imports lumiview's exported images
 * (static inline functions over lumiview.h and the Vulkan 1.1 API; they add no ABI).
 *
 * What the host needs: a Vulkan 1.1 instance and device on the exporting physical device
 * (`lumi_vk_find_physical_device`), with the device extension VK_KHR_external_memory_fd enabled
 * (`LUMI_VK_MEMORY_EXTENSION`; and VK_KHR_external_semaphore_fd, `LUMI_VK_SEMAPHORE_EXTENSION`, for
 * the semaphore path).
 *
 * The import functions take ownership of `e->fd` although `e` is const: afterwards the caller's
 * copy of the number is stale (with lumiview.hpp, pass `exported_image::release()`'s struct).
 *
 * Per export (once, or again after the target is recreated):
 *     lumi_export e;  lumi_target_export(ctx, target, LUMI_ATTACHMENT_COLOR, &e);
 *     lumi_vk_import(physical, device, &e, &image, &memory);      // takes e.fd
 * Per frame, after `lumi_render` returned (or after waiting on its `render_done` semaphore):
 *     lumi_vk_cmd_acquire(cmd, &e, image, my_family, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
 *                         VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
 *     ... the host's reads of `image` ...
 *     lumi_vk_cmd_release(cmd, &e, image, my_family, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
 *                         VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0);
 * and the host's reads must be finished (a fence, or `host_done` signalled) before the next
 * `lumi_render` into the same target.
 *
 * The barriers are the two halves of the queue-family ownership transfers documented in
 * docs/interop.md ("Importing into Vulkan"): lumiview releases each image to VK_QUEUE_FAMILY_EXTERNAL in
 * `e.vk_layout` (VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL); the host acquires it with the same
 * oldLayout, uses it, and releases it back in `e.vk_layout`, which lumiview's next frame acquires.
 *
 * Include after <vulkan/vulkan.h> is reachable (this header includes it). Thread safety: as the
 * Vulkan objects passed in (the command buffer externally synchronised, and so on). */
#ifndef LUMIVIEW_VULKAN_H
#define LUMIVIEW_VULKAN_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>
#include <unistd.h>

#include <vulkan/vulkan.h>

#include "lumiview.h"

/* The device extension the image import needs, and the one the semaphore path
 * (`lumi_target_desc.semaphores`) needs besides. */
#define LUMI_VK_MEMORY_EXTENSION VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME
#define LUMI_VK_SEMAPHORE_EXTENSION VK_KHR_EXTERNAL_SEMAPHORE_FD_EXTENSION_NAME

/* The image aspect of an export: depth for `LUMI_DEPTH_D32F` (VK_FORMAT_D32_SFLOAT), else colour. */
static inline VkImageAspectFlags lumi_vk_aspect(const lumi_export *e) {
    return e->vk_format == VK_FORMAT_D32_SFLOAT ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
}

/* True when `physical` is the device and driver that exported (deviceUUID and driverUUID of
 * VkPhysicalDeviceIDProperties equal `device_uuid` / `driver_uuid`, e.g. from `lumi_device_caps` or
 * `lumi_export`). Memory from any other device or driver cannot be imported. */
static inline bool lumi_vk_same_device(VkPhysicalDevice physical, const uint8_t device_uuid[16],
                                       const uint8_t driver_uuid[16]) {
    VkPhysicalDeviceIDProperties id;
    memset(&id, 0, sizeof id);
    id.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES;
    VkPhysicalDeviceProperties2 props;
    memset(&props, 0, sizeof props);
    props.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2;
    props.pNext = &id;
    vkGetPhysicalDeviceProperties2(physical, &props);
    return memcmp(id.deviceUUID, device_uuid, 16) == 0 && memcmp(id.driverUUID, driver_uuid, 16) == 0;
}

/* Finds the physical device of `instance` (Vulkan 1.1) that lumiview's context runs on (its
 * `lumi_device_caps` UUIDs). VK_SUCCESS and `*out` set, or VK_ERROR_INITIALIZATION_FAILED when no
 * device has both UUIDs (at most 16 devices are looked at). */
static inline VkResult lumi_vk_find_physical_device(VkInstance instance, const lumi_device_caps *caps,
                                                    VkPhysicalDevice *out) {
    VkPhysicalDevice devices[16];
    uint32_t n = 16;
    VkResult r = vkEnumeratePhysicalDevices(instance, &n, devices);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE) return r;
    for (uint32_t i = 0; i < n; i++) {
        if (lumi_vk_same_device(devices[i], caps->device_uuid, caps->driver_uuid)) {
            *out = devices[i];
            return VK_SUCCESS;
        }
    }
    return VK_ERROR_INITIALIZATION_FAILED;
}

/* Imports one export: checks the UUIDs and that the device can import the format and usage from
 * an opaque fd, creates a 2D image exactly as lumiview made it (format, extent, usage, tiling,
 * external-memory info), allocates the imported memory with the exporter's size and memory type
 * (dedicated when `e->dedicated`) and binds it. Takes ownership of `e->fd`: the driver owns it
 * after a successful import, and it is closed here on every failure. On failure nothing is left
 * behind and `*image`, `*memory` are VK_NULL_HANDLE. Returns VK_SUCCESS, the failing call's
 * result, VK_ERROR_INCOMPATIBLE_DRIVER (another device or driver), VK_ERROR_FORMAT_NOT_SUPPORTED
 * (not importable, or a dedicated-only import of a non-dedicated export) or
 * VK_ERROR_INVALID_EXTERNAL_HANDLE (no fd, an empty export, or a size or memory type that does not
 * fit the image). Free with
 * `lumi_vk_release_import`. Needs VK_KHR_external_memory_fd on `device`. */
static inline VkResult lumi_vk_import(VkPhysicalDevice physical, VkDevice device, const lumi_export *e,
                                      VkImage *image, VkDeviceMemory *memory) {
    int fd = e->fd;
    VkResult r = VK_SUCCESS;
    *image = VK_NULL_HANDLE;
    *memory = VK_NULL_HANDLE;
    if (fd < 0 || e->width == 0 || e->height == 0 || e->allocation_size == 0) {
        r = VK_ERROR_INVALID_EXTERNAL_HANDLE;
        goto fail;
    }
    if (!lumi_vk_same_device(physical, e->device_uuid, e->driver_uuid)) {
        r = VK_ERROR_INCOMPATIBLE_DRIVER;
        goto fail;
    }
    {
        VkPhysicalDeviceExternalImageFormatInfo ext_info;
        memset(&ext_info, 0, sizeof ext_info);
        ext_info.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_IMAGE_FORMAT_INFO;
        ext_info.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
        VkPhysicalDeviceImageFormatInfo2 fmt_info;
        memset(&fmt_info, 0, sizeof fmt_info);
        fmt_info.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_IMAGE_FORMAT_INFO_2;
        fmt_info.pNext = &ext_info;
        fmt_info.format = (VkFormat)e->vk_format;
        fmt_info.type = VK_IMAGE_TYPE_2D;
        fmt_info.tiling = (VkImageTiling)e->vk_tiling;
        fmt_info.usage = (VkImageUsageFlags)e->vk_usage;
        VkExternalImageFormatProperties ext_props;
        memset(&ext_props, 0, sizeof ext_props);
        ext_props.sType = VK_STRUCTURE_TYPE_EXTERNAL_IMAGE_FORMAT_PROPERTIES;
        VkImageFormatProperties2 fmt_props;
        memset(&fmt_props, 0, sizeof fmt_props);
        fmt_props.sType = VK_STRUCTURE_TYPE_IMAGE_FORMAT_PROPERTIES_2;
        fmt_props.pNext = &ext_props;
        r = vkGetPhysicalDeviceImageFormatProperties2(physical, &fmt_info, &fmt_props);
        if (r != VK_SUCCESS) goto fail;
        VkExternalMemoryFeatureFlags features = ext_props.externalMemoryProperties.externalMemoryFeatures;
        if (!(features & VK_EXTERNAL_MEMORY_FEATURE_IMPORTABLE_BIT) ||
            ((features & VK_EXTERNAL_MEMORY_FEATURE_DEDICATED_ONLY_BIT) && !e->dedicated)) {
            r = VK_ERROR_FORMAT_NOT_SUPPORTED;
            goto fail;
        }
    }
    {
        VkExternalMemoryImageCreateInfo ext_create;
        memset(&ext_create, 0, sizeof ext_create);
        ext_create.sType = VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_IMAGE_CREATE_INFO;
        ext_create.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
        VkImageCreateInfo ici;
        memset(&ici, 0, sizeof ici);
        ici.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
        ici.pNext = &ext_create;
        ici.imageType = VK_IMAGE_TYPE_2D;
        ici.format = (VkFormat)e->vk_format;
        ici.extent.width = e->width;
        ici.extent.height = e->height;
        ici.extent.depth = 1;
        ici.mipLevels = 1;
        ici.arrayLayers = 1;
        ici.samples = VK_SAMPLE_COUNT_1_BIT;
        ici.tiling = (VkImageTiling)e->vk_tiling;
        ici.usage = (VkImageUsageFlags)e->vk_usage;
        ici.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        r = vkCreateImage(device, &ici, NULL, image);
        if (r != VK_SUCCESS) goto fail;
    }
    {
        VkMemoryRequirements req;
        vkGetImageMemoryRequirements(device, *image, &req);
        /* An opaque-fd import uses the exporter's allocation size and memory type; a dedicated one
         * is exactly the image's size (VUID-VkMemoryDedicatedAllocateInfo-image-01433). */
        if (req.size > e->allocation_size || (e->dedicated && req.size != e->allocation_size) ||
            e->vk_memory_type_index >= 32 ||
            !(req.memoryTypeBits & (1u << e->vk_memory_type_index))) {
            r = VK_ERROR_INVALID_EXTERNAL_HANDLE;
            goto fail;
        }
        VkMemoryDedicatedAllocateInfo dedicated;
        memset(&dedicated, 0, sizeof dedicated);
        dedicated.sType = VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO;
        dedicated.image = *image;
        VkImportMemoryFdInfoKHR import_info;
        memset(&import_info, 0, sizeof import_info);
        import_info.sType = VK_STRUCTURE_TYPE_IMPORT_MEMORY_FD_INFO_KHR;
        import_info.pNext = e->dedicated ? &dedicated : NULL;
        import_info.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
        import_info.fd = fd;
        VkMemoryAllocateInfo mai;
        memset(&mai, 0, sizeof mai);
        mai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
        mai.pNext = &import_info;
        mai.allocationSize = e->allocation_size;
        mai.memoryTypeIndex = e->vk_memory_type_index;
        r = vkAllocateMemory(device, &mai, NULL, memory);
        if (r != VK_SUCCESS) goto fail;
        fd = -1; /* a successful import owns the fd */
        r = vkBindImageMemory(device, *image, *memory, 0);
        if (r != VK_SUCCESS) goto fail;
    }
    return VK_SUCCESS;
fail:
    if (fd >= 0) close(fd);
    if (*memory != VK_NULL_HANDLE) vkFreeMemory(device, *memory, NULL);
    if (*image != VK_NULL_HANDLE) vkDestroyImage(device, *image, NULL);
    *image = VK_NULL_HANDLE;
    *memory = VK_NULL_HANDLE;
    return r;
}

/* Destroys what `lumi_vk_import` made (VK_NULL_HANDLE members are skipped) and nulls them. The GPU
 * must be done with the image. */
static inline void lumi_vk_release_import(VkDevice device, VkImage *image, VkDeviceMemory *memory) {
    if (*image != VK_NULL_HANDLE) vkDestroyImage(device, *image, NULL);
    if (*memory != VK_NULL_HANDLE) vkFreeMemory(device, *memory, NULL);
    *image = VK_NULL_HANDLE;
    *memory = VK_NULL_HANDLE;
}

/* One queue-family ownership transfer of an imported image (the acquire and the release below). */
static inline void lumi_vk_transfer_(VkCommandBuffer cmd, const lumi_export *e, VkImage image, uint32_t src_family,
                                     uint32_t dst_family, VkImageLayout old_layout, VkImageLayout new_layout,
                                     VkPipelineStageFlags src_stage, VkAccessFlags src_access,
                                     VkPipelineStageFlags dst_stage, VkAccessFlags dst_access) {
    VkImageMemoryBarrier b;
    memset(&b, 0, sizeof b);
    b.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER;
    b.srcAccessMask = src_access;
    b.dstAccessMask = dst_access;
    b.oldLayout = old_layout;
    b.newLayout = new_layout;
    b.srcQueueFamilyIndex = src_family;
    b.dstQueueFamilyIndex = dst_family;
    b.image = image;
    b.subresourceRange.aspectMask = lumi_vk_aspect(e);
    b.subresourceRange.levelCount = 1;
    b.subresourceRange.layerCount = 1;
    vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, NULL, 0, NULL, 1, &b);
}

/* Records the acquire of an imported image from lumiview: a queue-family ownership transfer from
 * VK_QUEUE_FAMILY_EXTERNAL to `queue_family`, layout `e->vk_layout` → `new_layout`, with no source
 * access (lumiview's release made its writes available) and destination `dst_stage` / `dst_access`
 * (e.g. FRAGMENT_SHADER / SHADER_READ to sample it, TRANSFER / TRANSFER_READ to copy it). The
 * source stage is `dst_stage` too: with semaphores, wait on `render_done` at `dst_stage`
 * (VkSubmitInfo.pWaitDstStageMask) and the wait and this barrier form one dependency chain; without
 * them `lumi_render` has returned and the GPU finished the frame. */
static inline void lumi_vk_cmd_acquire(VkCommandBuffer cmd, const lumi_export *e, VkImage image, uint32_t queue_family,
                                       VkImageLayout new_layout, VkPipelineStageFlags dst_stage,
                                       VkAccessFlags dst_access) {
    lumi_vk_transfer_(cmd, e, image, VK_QUEUE_FAMILY_EXTERNAL, queue_family, (VkImageLayout)e->vk_layout, new_layout,
                      dst_stage, 0, dst_stage, dst_access);
}

/* Records the release of an imported image back to lumiview after the host's use: ownership from
 * `queue_family` to VK_QUEUE_FAMILY_EXTERNAL, layout `old_layout` (the one the host used it in) →
 * `e->vk_layout`, which lumiview's next frame acquires; source `src_stage` / `src_access` (the
 * host's last use; 0 access for reads, which need no availability operation), destination
 * BOTTOM_OF_PIPE with no access. Record it in every frame that recorded an acquire. */
static inline void lumi_vk_cmd_release(VkCommandBuffer cmd, const lumi_export *e, VkImage image, uint32_t queue_family,
                                       VkImageLayout old_layout, VkPipelineStageFlags src_stage,
                                       VkAccessFlags src_access) {
    lumi_vk_transfer_(cmd, e, image, queue_family, VK_QUEUE_FAMILY_EXTERNAL, old_layout, (VkImageLayout)e->vk_layout,
                      src_stage, src_access, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0);
}

/* Imports one of a target's semaphores (`lumi_target_export_semaphores`) into `device` (which has
 * VK_KHR_external_semaphore_fd enabled): a new binary semaphore with the fd imported permanently.
 * Takes ownership of `fd` (the driver owns it on success; closed here on failure). The host waits on
 * `render_done` before its reads (at the acquire's `dst_stage`) and signals `host_done` after them,
 * once per frame. */
static inline VkResult lumi_vk_import_semaphore(VkDevice device, int32_t fd, VkSemaphore *out) {
    *out = VK_NULL_HANDLE;
    PFN_vkImportSemaphoreFdKHR import_fd =
        (PFN_vkImportSemaphoreFdKHR)vkGetDeviceProcAddr(device, "vkImportSemaphoreFdKHR");
    VkResult r = VK_ERROR_EXTENSION_NOT_PRESENT;
    if (import_fd) {
        VkSemaphoreCreateInfo sci;
        memset(&sci, 0, sizeof sci);
        sci.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
        r = vkCreateSemaphore(device, &sci, NULL, out);
        if (r == VK_SUCCESS) {
            VkImportSemaphoreFdInfoKHR info;
            memset(&info, 0, sizeof info);
            info.sType = VK_STRUCTURE_TYPE_IMPORT_SEMAPHORE_FD_INFO_KHR;
            info.semaphore = *out;
            info.handleType = VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT;
            info.fd = fd;
            r = import_fd(device, &info);
            if (r == VK_SUCCESS) return VK_SUCCESS;
            vkDestroySemaphore(device, *out, NULL);
            *out = VK_NULL_HANDLE;
        }
    }
    if (fd >= 0) close(fd);
    return r;
}

#endif /* LUMIVIEW_VULKAN_H */
