/* The headless example's Vulkan host: import of lumiview's exported images; see vk_import.h.
 *
 * Spec references (Vulkan 1.3): §11.2.5 "External Memory Handle Types" (opaque fd import must use the
 * same allocationSize and memoryTypeIndex as the exporting allocation, on a device with the same
 * deviceUUID/driverUUID), §7.7.4 "Queue Family Ownership Transfer" (the acquire's oldLayout/newLayout
 * must match the release's), VkMemoryDedicatedAllocateInfo for dedicated exports. */
#include "vk_import.h"

#include "lumiview_vulkan.h"

#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static atomic_uint validation_messages;

static const char *vk_result_name(VkResult r) {
    switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_INVALID_EXTERNAL_HANDLE: return "VK_ERROR_INVALID_EXTERNAL_HANDLE";
    default: return "VkResult";
    }
}

/* Prints "<what>: <VkResult>" and returns false unless r is VK_SUCCESS. */
static bool vk_ok(VkResult r, const char *what) {
    if (r == VK_SUCCESS) return true;
    fprintf(stderr, "vulkan host: %s failed: %s (%d)\n", what, vk_result_name(r), (int)r);
    return false;
}

static VKAPI_ATTR VkBool32 VKAPI_CALL on_validation(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT types,
                                                    const VkDebugUtilsMessengerCallbackDataEXT *data,
                                                    void *user) {
    (void)types;
    (void)user;
    atomic_fetch_add(&validation_messages, 1u);
    fprintf(stderr, "vulkan host validation %s: %s\n",
            severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "error" : "warning",
            data && data->pMessage ? data->pMessage : "");
    return VK_FALSE;
}

unsigned vk_host_validation_errors(void) { return atomic_load(&validation_messages); }

uint32_t vk_format_texel_size(int32_t vk_format) {
    switch (vk_format) {
    case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
    case VK_FORMAT_R16G16B16A16_SFLOAT: return 8;
    case VK_FORMAT_R32_SFLOAT: return 4;
    case VK_FORMAT_D32_SFLOAT: return 4;
    case VK_FORMAT_R8G8B8A8_SRGB: return 4;
    case VK_FORMAT_R8G8B8A8_UNORM: return 4;
    default: return 0;
    }
}

static bool has_layer(const char *name) {
    uint32_t n = 0;
    if (vkEnumerateInstanceLayerProperties(&n, NULL) != VK_SUCCESS || n == 0) return false;
    VkLayerProperties props[64];
    if (n > 64) n = 64;
    VkResult r = vkEnumerateInstanceLayerProperties(&n, props);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE) return false;
    for (uint32_t i = 0; i < n; i++)
        if (strcmp(props[i].layerName, name) == 0) return true;
    return false;
}

static bool has_device_extension(VkPhysicalDevice pd, const char *name) {
    uint32_t n = 0;
    if (vkEnumerateDeviceExtensionProperties(pd, NULL, &n, NULL) != VK_SUCCESS) return false;
    VkExtensionProperties props[512];
    if (n > 512) n = 512;
    VkResult r = vkEnumerateDeviceExtensionProperties(pd, NULL, &n, props);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE) return false;
    for (uint32_t i = 0; i < n; i++)
        if (strcmp(props[i].extensionName, name) == 0) return true;
    return false;
}

static bool create_instance(vk_host *h, bool validation) {
    uint32_t version = VK_API_VERSION_1_0;
    if (!vk_ok(vkEnumerateInstanceVersion(&version), "vkEnumerateInstanceVersion")) return false;
    if (version < VK_API_VERSION_1_1) {
        fprintf(stderr, "vulkan host: the Vulkan loader supports only %u.%u; external memory needs 1.1\n",
                VK_API_VERSION_MAJOR(version), VK_API_VERSION_MINOR(version));
        return false;
    }
    const char *layer = "VK_LAYER_KHRONOS_validation";
    const char *ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    if (validation && !has_layer(layer)) {
        fprintf(stderr, "vulkan host: validation requested but %s is not installed "
                        "(Debian: vulkan-validationlayers)\n", layer);
        return false;
    }
    VkApplicationInfo app = {
        .sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
        .pApplicationName = "lumiview headless example",
        .apiVersion = VK_API_VERSION_1_1,
    };
    VkInstanceCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
        .pApplicationInfo = &app,
        .enabledLayerCount = validation ? 1u : 0u,
        .ppEnabledLayerNames = validation ? &layer : NULL,
        .enabledExtensionCount = validation ? 1u : 0u,
        .ppEnabledExtensionNames = validation ? &ext : NULL,
    };
    if (!vk_ok(vkCreateInstance(&info, NULL, &h->instance), "vkCreateInstance")) return false;
    if (validation) {
        PFN_vkCreateDebugUtilsMessengerEXT create =
            (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(h->instance, "vkCreateDebugUtilsMessengerEXT");
        if (!create) {
            fprintf(stderr, "vulkan host: vkCreateDebugUtilsMessengerEXT not found\n");
            return false;
        }
        VkDebugUtilsMessengerCreateInfoEXT m = {
            .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
            .messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
            .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
            .pfnUserCallback = on_validation,
        };
        if (!vk_ok(create(h->instance, &m, NULL, &h->messenger), "vkCreateDebugUtilsMessengerEXT")) return false;
    }
    return true;
}

static bool pick_device(vk_host *h, const uint8_t device_uuid[16], const uint8_t driver_uuid[16]) {
    uint32_t n = 0;
    if (!vk_ok(vkEnumeratePhysicalDevices(h->instance, &n, NULL), "vkEnumeratePhysicalDevices")) return false;
    VkPhysicalDevice devs[16];
    if (n > 16) n = 16;
    VkResult r = vkEnumeratePhysicalDevices(h->instance, &n, devs);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE) return vk_ok(r, "vkEnumeratePhysicalDevices");
    for (uint32_t i = 0; i < n; i++) {
        VkPhysicalDeviceIDProperties id = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES};
        VkPhysicalDeviceProperties2 p = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &id};
        vkGetPhysicalDeviceProperties2(devs[i], &p);
        if (memcmp(id.deviceUUID, device_uuid, 16) != 0) continue;
        if (memcmp(id.driverUUID, driver_uuid, 16) != 0) {
            fprintf(stderr, "vulkan host: %s has the exporter's deviceUUID but another driverUUID: "
                            "its memory cannot be imported\n", p.properties.deviceName);
            return false;
        }
        h->physical = devs[i];
        memcpy(h->device_uuid, id.deviceUUID, VK_UUID_SIZE);
        memcpy(h->driver_uuid, id.driverUUID, VK_UUID_SIZE);
        snprintf(h->device_name, sizeof h->device_name, "%s", p.properties.deviceName);
        return true;
    }
    fprintf(stderr, "vulkan host: none of the %u Vulkan devices has the exporter's deviceUUID\n", n);
    return false;
}

static bool create_device(vk_host *h) {
    if (!has_device_extension(h->physical, VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME)) {
        fprintf(stderr, "vulkan host: %s lacks %s\n", h->device_name, VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME);
        return false;
    }
    uint32_t nf = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(h->physical, &nf, NULL);
    VkQueueFamilyProperties fams[32];
    if (nf > 32) nf = 32;
    vkGetPhysicalDeviceQueueFamilyProperties(h->physical, &nf, fams);
    uint32_t family = UINT32_MAX;
    /* Every graphics or compute family supports transfers (Vulkan §5.1). */
    for (uint32_t i = 0; i < nf && family == UINT32_MAX; i++)
        if (fams[i].queueCount > 0 &&
            (fams[i].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT | VK_QUEUE_TRANSFER_BIT)))
            family = i;
    if (family == UINT32_MAX) {
        fprintf(stderr, "vulkan host: %s has no queue family that can copy\n", h->device_name);
        return false;
    }
    float priority = 1.0f;
    VkDeviceQueueCreateInfo q = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
        .queueFamilyIndex = family,
        .queueCount = 1,
        .pQueuePriorities = &priority,
    };
    const char *ext = VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME;
    VkDeviceCreateInfo info = {
        .sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
        .queueCreateInfoCount = 1,
        .pQueueCreateInfos = &q,
        .enabledExtensionCount = 1,
        .ppEnabledExtensionNames = &ext,
    };
    if (!vk_ok(vkCreateDevice(h->physical, &info, NULL, &h->device), "vkCreateDevice")) return false;
    h->queue_family = family;
    vkGetDeviceQueue(h->device, family, 0, &h->queue);
    VkCommandPoolCreateInfo pool = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
        .flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT,
        .queueFamilyIndex = family,
    };
    if (!vk_ok(vkCreateCommandPool(h->device, &pool, NULL, &h->pool), "vkCreateCommandPool")) return false;
    vkGetPhysicalDeviceMemoryProperties(h->physical, &h->memory);
    return true;
}

bool vk_host_create(vk_host *host, const uint8_t device_uuid[16], const uint8_t driver_uuid[16],
                    bool validation) {
    memset(host, 0, sizeof *host);
    if (create_instance(host, validation) && pick_device(host, device_uuid, driver_uuid) && create_device(host))
        return true;
    vk_host_destroy(host);
    return false;
}

void vk_host_destroy(vk_host *host) {
    if (host->device) {
        vkDeviceWaitIdle(host->device);
        if (host->pool) vkDestroyCommandPool(host->device, host->pool, NULL);
        vkDestroyDevice(host->device, NULL);
    }
    if (host->messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy =
            (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(host->instance, "vkDestroyDebugUtilsMessengerEXT");
        if (destroy) destroy(host->instance, host->messenger, NULL);
    }
    if (host->instance) vkDestroyInstance(host->instance, NULL);
    memset(host, 0, sizeof *host);
}

/* The first memory type in `bits` that has all of `flags`, or UINT32_MAX. */
static uint32_t find_memory_type(const vk_host *h, uint32_t bits, VkMemoryPropertyFlags flags) {
    for (uint32_t i = 0; i < h->memory.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (h->memory.memoryTypes[i].propertyFlags & flags) == flags) return i;
    return UINT32_MAX;
}

/* Everything one import creates; released by import_free. */
typedef struct import {
    VkImage image;
    VkDeviceMemory image_memory;
    VkBuffer buffer;
    VkDeviceMemory buffer_memory;
    VkCommandBuffer cmd;
    VkFence fence;
} import;

static void import_free(vk_host *h, import *im) {
    if (im->fence) vkDestroyFence(h->device, im->fence, NULL);
    if (im->cmd) vkFreeCommandBuffers(h->device, h->pool, 1, &im->cmd);
    if (im->buffer) vkDestroyBuffer(h->device, im->buffer, NULL);
    if (im->buffer_memory) vkFreeMemory(h->device, im->buffer_memory, NULL);
    if (im->image) vkDestroyImage(h->device, im->image, NULL);
    if (im->image_memory) vkFreeMemory(h->device, im->image_memory, NULL);
    memset(im, 0, sizeof *im);
}

/* Creates the image and imports the fd into its memory (lumiview_vulkan.h). Consumes `fd` in every
 * case. */
static bool import_image(vk_host *h, const lumi_export *e, import *im) {
    VkResult r = lumi_vk_import(h->physical, h->device, e, &im->image, &im->image_memory);
    if (r == VK_ERROR_FORMAT_NOT_SUPPORTED)
        fprintf(stderr, "vulkan host: format %d with usage 0x%x cannot be imported from an opaque fd here\n",
                (int)e->vk_format, (unsigned)e->vk_usage);
    return vk_ok(r, "lumi_vk_import (opaque-fd image import)");
}

static bool create_readback_buffer(vk_host *h, VkDeviceSize size, import *im) {
    VkBufferCreateInfo bci = {
        .sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
        .size = size,
        .usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT,
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
    };
    if (!vk_ok(vkCreateBuffer(h->device, &bci, NULL, &im->buffer), "vkCreateBuffer")) return false;
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(h->device, im->buffer, &req);
    uint32_t type = find_memory_type(h, req.memoryTypeBits,
                                     VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    if (type == UINT32_MAX) {
        fprintf(stderr, "vulkan host: no host-visible coherent memory type for the read-back buffer\n");
        return false;
    }
    VkMemoryAllocateInfo mai = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
        .allocationSize = req.size,
        .memoryTypeIndex = type,
    };
    if (!vk_ok(vkAllocateMemory(h->device, &mai, NULL, &im->buffer_memory), "vkAllocateMemory (read-back)"))
        return false;
    return vk_ok(vkBindBufferMemory(h->device, im->buffer, im->buffer_memory, 0), "vkBindBufferMemory");
}

/* Records: acquire from VK_QUEUE_FAMILY_EXTERNAL, copy to the buffer, release back, make the buffer
 * visible to the host. */
static bool record_copy(vk_host *h, const lumi_export *e, VkImageAspectFlags aspect, import *im) {
    VkCommandBufferAllocateInfo cai = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = h->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 1,
    };
    if (!vk_ok(vkAllocateCommandBuffers(h->device, &cai, &im->cmd), "vkAllocateCommandBuffers")) return false;
    VkCommandBufferBeginInfo begin = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    if (!vk_ok(vkBeginCommandBuffer(im->cmd, &begin), "vkBeginCommandBuffer")) return false;
    /* Acquire: the other half of lumiview's release (same layouts, queue families swapped). */
    lumi_vk_cmd_acquire(im->cmd, e, im->image, h->queue_family, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
    VkBufferImageCopy copy = {
        .bufferOffset = 0,
        .bufferRowLength = 0, /* tightly packed */
        .bufferImageHeight = 0,
        .imageSubresource = {aspect, 0, 0, 1},
        .imageOffset = {0, 0, 0},
        .imageExtent = {e->width, e->height, 1},
    };
    vkCmdCopyImageToBuffer(im->cmd, im->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, im->buffer, 1, &copy);
    /* Release back to the exporter in the layout its next acquire expects (reads: no access). */
    lumi_vk_cmd_release(im->cmd, e, im->image, h->queue_family, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, 0);
    VkBufferMemoryBarrier to_host = {
        .sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER,
        .srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT,
        .dstAccessMask = VK_ACCESS_HOST_READ_BIT,
        .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .buffer = im->buffer,
        .offset = 0,
        .size = VK_WHOLE_SIZE,
    };
    vkCmdPipelineBarrier(im->cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, NULL, 1,
                         &to_host, 0, NULL);
    return vk_ok(vkEndCommandBuffer(im->cmd), "vkEndCommandBuffer");
}

bool vk_host_read_export(vk_host *host, const lumi_export *exp, void *out, size_t out_len) {
    import im;
    memset(&im, 0, sizeof im);
    uint32_t texel = vk_format_texel_size(exp->vk_format);
    size_t need = (size_t)exp->width * exp->height * texel;
    bool bad = false;
    if (texel == 0) {
        fprintf(stderr, "vulkan host: unexpected exported VkFormat %d\n", (int)exp->vk_format);
        bad = true;
    } else if (out_len != need) {
        fprintf(stderr, "vulkan host: output buffer has %zu bytes, the image %zu\n", out_len, need);
        bad = true;
    } else if (exp->vk_tiling != VK_IMAGE_TILING_OPTIMAL) {
        fprintf(stderr, "vulkan host: unexpected tiling %d (lumiview exports OPTIMAL)\n", (int)exp->vk_tiling);
        bad = true;
    }
    if (bad) {
        if (exp->fd >= 0) close(exp->fd);
        return false;
    }
    VkImageAspectFlags aspect = lumi_vk_aspect(exp);
    bool ok = import_image(host, exp, &im) && create_readback_buffer(host, need, &im) &&
              record_copy(host, exp, aspect, &im);
    if (ok) {
        VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        ok = vk_ok(vkCreateFence(host->device, &fci, NULL, &im.fence), "vkCreateFence");
    }
    if (ok) {
        VkSubmitInfo submit = {
            .sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
            .commandBufferCount = 1,
            .pCommandBuffers = &im.cmd,
        };
        ok = vk_ok(vkQueueSubmit(host->queue, 1, &submit, im.fence), "vkQueueSubmit") &&
             vk_ok(vkWaitForFences(host->device, 1, &im.fence, VK_TRUE, 30ull * 1000 * 1000 * 1000),
                   "vkWaitForFences (30 s)");
    }
    if (ok) {
        void *mapped = NULL;
        ok = vk_ok(vkMapMemory(host->device, im.buffer_memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
        if (ok) {
            memcpy(out, mapped, need);
            vkUnmapMemory(host->device, im.buffer_memory);
        }
    }
    import_free(host, &im);
    return ok;
}
