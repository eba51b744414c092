/* GL import of lumiview's exports through lumiview_gl.h; see gl_interop.h. Spec: EXT_external_objects and
 * EXT_external_objects_fd (the GL_EXT_memory_object(_fd) entry points). */
#include "gl_interop.h"

#include <stdio.h>
#include <string.h>

#include "lumiview_gl.h"
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

bool gl_import(const lumi_export *e, gl_imported *out) {
    memset(out, 0, sizeof *out);
    GLenum err = lumi_gl_import(e, &out->memory, &out->texture); /* consumes e->fd; checks the UUIDs */
    if (err != GL_NO_ERROR) {
        fprintf(stderr, "glfw_host: lumi_gl_import (%ux%u, GL format 0x%x) failed: GL error 0x%x%s\n", e->width,
                e->height, e->gl_internal_format, err, err == GL_INVALID_OPERATION ? " (another device?)" : "");
        return false;
    }
    out->width = e->width;
    out->height = e->height;
    return true;
}

void gl_imported_free(gl_imported *im) {
    lumi_gl_release_import(&im->memory, &im->texture);
    memset(im, 0, sizeof *im);
}
