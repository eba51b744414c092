/* GL import of lumiview's exports; see gl_interop.h. Spec: EXT_external_objects and
 * EXT_external_objects_fd (the GL_EXT_memory_object(_fd) entry points). */
#include "gl_interop.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "lv_lumi.h"

bool gl_query_uuids(gl_uuids *u) {
    memset(u, 0, sizeof *u);
    GLint n = 0;
    glGetIntegerv(GL_NUM_DEVICE_UUIDS_EXT, &n);
    if (n < 1) {
        fprintf(stderr, "glfw_host: GL_NUM_DEVICE_UUIDS_EXT is %d\n", n);
        return false;
    }
    if (n > GL_INTEROP_MAX_DEVICES) n = GL_INTEROP_MAX_DEVICES;
    for (GLint i = 0; i < n; i++) glGetUnsignedBytei_vEXT(GL_DEVICE_UUID_EXT, (GLuint)i, u->devices[i]);
    glGetUnsignedBytevEXT(GL_DRIVER_UUID_EXT, u->driver);
    u->device_count = n;
    return lv_gl_ok("querying GL_DEVICE_UUID_EXT / GL_DRIVER_UUID_EXT");
}

bool gl_uuids_match(const gl_uuids *u, const uint8_t device[16], const uint8_t driver[16], const char *who) {
    bool device_ok = false;
    for (int i = 0; i < u->device_count; i++)
        if (memcmp(u->devices[i], device, 16) == 0) device_ok = true;
    bool driver_ok = memcmp(u->driver, driver, 16) == 0;
    if (device_ok && driver_ok) return true;
    char a[37], b[37], c[37], d[37];
    lv_uuid_format(device, a);
    lv_uuid_format(u->devices[0], b);
    lv_uuid_format(driver, c);
    lv_uuid_format(u->driver, d);
    fprintf(stderr,
            "glfw_host: refusing to import: %s is not on this GL context's %s (the UUIDs differ), so its memory "
            "cannot be imported\n"
            "  lumiview deviceUUID %s, GL_DEVICE_UUID_EXT %s%s\n"
            "  lumiview driverUUID %s, GL_DRIVER_UUID_EXT %s\n",
            who, device_ok ? "driver" : "device", a, b, u->device_count > 1 ? " (first of several)" : "", c, d);
    return false;
}

bool gl_import(const lumi_export *e, const gl_uuids *u, gl_imported *out) {
    memset(out, 0, sizeof *out);
    int fd = e->fd;
    const char *what = e->gl_internal_format == GL_R32F ? "the depth image" : "the colour image";
    if (!gl_uuids_match(u, e->device_uuid, e->driver_uuid, what)) goto fail;
    if (e->gl_tiling != GL_OPTIMAL_TILING_EXT) {
        fprintf(stderr, "glfw_host: %s has GL tiling 0x%x, expected GL_OPTIMAL_TILING_EXT\n", what, e->gl_tiling);
        goto fail;
    }
    if (e->width == 0 || e->height == 0 || e->allocation_size == 0) {
        fprintf(stderr, "glfw_host: %s: empty export (%ux%u, %llu bytes)\n", what, e->width, e->height,
                (unsigned long long)e->allocation_size);
        goto fail;
    }
    lv_gl_ok("before the import"); /* clear stale errors so the checks below are ours */
    glCreateMemoryObjectsEXT(1, &out->memory);
    GLint dedicated = e->dedicated ? GL_TRUE : GL_FALSE;
    glMemoryObjectParameterivEXT(out->memory, GL_DEDICATED_MEMORY_OBJECT_EXT, &dedicated);
    if (!lv_gl_ok("glCreateMemoryObjectsEXT / glMemoryObjectParameterivEXT")) goto fail;
    glImportMemoryFdEXT(out->memory, e->allocation_size, GL_HANDLE_TYPE_OPAQUE_FD_EXT, fd);
    if (!lv_gl_ok("glImportMemoryFdEXT") || !glIsMemoryObjectEXT(out->memory)) goto fail;
    fd = -1; /* owned by GL now */
    glCreateTextures(GL_TEXTURE_2D, 1, &out->texture);
    glTextureParameteri(out->texture, GL_TEXTURE_TILING_EXT, (GLint)e->gl_tiling);
    glTextureStorageMem2DEXT(out->texture, 1, e->gl_internal_format, (GLsizei)e->width, (GLsizei)e->height,
                             out->memory, 0);
    glTextureParameteri(out->texture, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(out->texture, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(out->texture, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(out->texture, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    if (!lv_gl_ok("glTextureStorageMem2DEXT")) goto fail;
    out->width = e->width;
    out->height = e->height;
    return true;
fail:
    if (fd >= 0) close(fd);
    gl_imported_free(out);
    return false;
}

void gl_imported_free(gl_imported *im) {
    if (im->texture) glDeleteTextures(1, &im->texture);
    if (im->memory) glDeleteMemoryObjectsEXT(1, &im->memory);
    memset(im, 0, sizeof *im);
}
