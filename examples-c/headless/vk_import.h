/* The headless example's own Vulkan device (the "Vulkan host"): imports an image lumiview exported
 * as an opaque fd and copies it to host memory. Independent of lumiview's device, as a real Vulkan
 * host application would be. */
#ifndef VK_IMPORT_H
#define VK_IMPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <vulkan/vulkan.h>

#include "lumiview.h"

typedef struct vk_host {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice physical;
    VkDevice device;
    uint32_t queue_family;
    VkQueue queue;
    VkCommandPool pool;
    VkPhysicalDeviceMemoryProperties memory;
    char device_name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE];
    uint8_t device_uuid[VK_UUID_SIZE];
    uint8_t driver_uuid[VK_UUID_SIZE];
} vk_host;

/* Creates an instance (Vulkan 1.1; with `validation`, VK_LAYER_KHRONOS_validation and a messenger
 * that counts errors), picks the physical device whose deviceUUID and driverUUID equal the given
 * ones (VkPhysicalDeviceIDProperties) and creates a device with VK_KHR_external_memory_fd and one
 * queue. On failure prints why, destroys what it made and returns false. */
bool vk_host_create(vk_host *host, const uint8_t device_uuid[16], const uint8_t driver_uuid[16],
                    bool validation);

/* Imports `exp` (taking ownership of exp->fd: it is consumed on success and closed on failure),
 * acquires the image from VK_QUEUE_FAMILY_EXTERNAL (from exp->vk_layout to TRANSFER_SRC_OPTIMAL),
 * copies it into a host-visible buffer, releases it back to VK_QUEUE_FAMILY_EXTERNAL in
 * exp->vk_layout, waits, and copies the tightly packed rows (memory row 0 first) into `out`, which
 * must hold exactly width × height × texel size bytes. Frees the import before returning. */
bool vk_host_read_export(vk_host *host, const lumi_export *exp, void *out, size_t out_len);

/* Validation-layer errors and warnings seen so far (0 without validation). */
unsigned vk_host_validation_errors(void);

/* Destroys everything `vk_host_create` made; a zeroed host is fine. */
void vk_host_destroy(vk_host *host);

/* Bytes per texel of the formats lumiview exports, 0 for any other. */
uint32_t vk_format_texel_size(int32_t vk_format);

#endif /* VK_IMPORT_H */
