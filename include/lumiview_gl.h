/* lumiview_gl.h: header-only helpers for an OpenGL host that imports lumiview's exported images
 * through GL_EXT_memory_object_fd (static inline functions over lumiview.h; they add no ABI).
 *
 * Include it AFTER the host's GL declarations (its loader: glad, libepoxy, GLEW, or
 * <GL/glcorearb.h> + <GL/glext.h> with prototypes): it calls the OpenGL 4.5 direct-state-access
 * entry points and those of GL_EXT_memory_object, GL_EXT_memory_object_fd and
 * GL_EXT_semaphore(_fd) by their usual names, and defines the tokens below only where the host's
 * headers did not (values from the Khronos registry, gl.xml).
 *
 * Per export (once, or again after the target is recreated), on the thread with the GL context:
 *     lumi_export e;  lumi_target_export(ctx, target, LUMI_ATTACHMENT_COLOR, &e);
 *     GLuint memory, texture;
 *     if (lumi_gl_import(&e, &memory, &texture) != GL_NO_ERROR) ...   // takes e.fd
 * Per frame: `lumi_render` (it returns once the GPU is done), draw with `texture`, and finish the
 * reads before the next `lumi_render` into the same target (`lumi_gl_finish_reads()`, i.e.
 * glFinish, or the semaphore path: `lumi_gl_import_semaphore`, `lumi_gl_wait_render` and
 * `lumi_gl_signal_host_done`). Free with `lumi_gl_release_import`.
 *
 * The import functions take ownership of `e->fd` although `e` is const: afterwards the caller's
 * copy of the number is stale (with lumiview.hpp, pass `exported_image::release()`'s struct). */
#ifndef LUMIVIEW_GL_H
#define LUMIVIEW_GL_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>
#include <unistd.h>

#include "lumiview.h"

#ifndef GL_NO_ERROR
#error "lumiview_gl.h: include the host's OpenGL declarations (loader or GL headers) first"
#endif

/* Tokens (gl.xml), defined only where the host's headers lack them. */
#ifndef GL_INVALID_OPERATION
#define GL_INVALID_OPERATION 0x0502
#endif
#ifndef GL_HANDLE_TYPE_OPAQUE_FD_EXT
#define GL_HANDLE_TYPE_OPAQUE_FD_EXT 0x9586
#endif
#ifndef GL_DEDICATED_MEMORY_OBJECT_EXT
#define GL_DEDICATED_MEMORY_OBJECT_EXT 0x9581
#endif
#ifndef GL_TEXTURE_TILING_EXT
#define GL_TEXTURE_TILING_EXT 0x9580
#endif
#ifndef GL_OPTIMAL_TILING_EXT
#define GL_OPTIMAL_TILING_EXT 0x9584
#endif
#ifndef GL_LAYOUT_SHADER_READ_ONLY_EXT
#define GL_LAYOUT_SHADER_READ_ONLY_EXT 0x9591
#endif
#ifndef GL_NUM_DEVICE_UUIDS_EXT
#define GL_NUM_DEVICE_UUIDS_EXT 0x9596
#endif
#ifndef GL_DEVICE_UUID_EXT
#define GL_DEVICE_UUID_EXT 0x9597
#endif
#ifndef GL_DRIVER_UUID_EXT
#define GL_DRIVER_UUID_EXT 0x9598
#endif
#ifndef GL_UUID_SIZE_EXT
#define GL_UUID_SIZE_EXT 16
#endif

/* True when the current GL context runs on the device and driver that exported: `device_uuid` is one
 * of its GL_DEVICE_UUID_EXT (GL_NUM_DEVICE_UUIDS_EXT of them, at most 8 looked at) and `driver_uuid`
 * its GL_DRIVER_UUID_EXT. Pass `lumi_device_caps` or `lumi_export` UUIDs. Memory from any other
 * device or driver cannot be imported. */
static inline bool lumi_gl_same_device(const uint8_t device_uuid[16], const uint8_t driver_uuid[16]) {
    GLubyte uuid[GL_UUID_SIZE_EXT];
    GLint n = 0;
    glGetIntegerv(GL_NUM_DEVICE_UUIDS_EXT, &n);
    if (n <= 0) {
        /* No GL_EXT_memory_object (the query raised GL_INVALID_ENUM): its entry points may be NULL. */
        for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; i++) {
        }
        return false;
    }
    bool device_ok = false;
    for (GLint i = 0; i < n && i < 8; i++) {
        memset(uuid, 0, sizeof uuid);
        glGetUnsignedBytei_vEXT(GL_DEVICE_UUID_EXT, (GLuint)i, uuid);
        if (memcmp(uuid, device_uuid, 16) == 0) device_ok = true;
    }
    memset(uuid, 0, sizeof uuid);
    glGetUnsignedBytevEXT(GL_DRIVER_UUID_EXT, uuid);
    return device_ok && memcmp(uuid, driver_uuid, 16) == 0;
}

/* Deletes what `lumi_gl_import` made (0 names are skipped; GL closes the fd) and zeroes them. */
static inline void lumi_gl_release_import(GLuint *memory, GLuint *texture) {
    if (*texture) glDeleteTextures(1, texture);
    if (*memory) glDeleteMemoryObjectsEXT(1, memory);
    *texture = 0;
    *memory = 0;
}

/* Imports one export as an immutable GL_TEXTURE_2D: checks the UUIDs (`lumi_gl_same_device`),
 * creates a memory object (GL_DEDICATED_MEMORY_OBJECT_EXT as `e->dedicated` says), imports the fd
 * (glImportMemoryFdEXT, GL_HANDLE_TYPE_OPAQUE_FD_EXT, `e->allocation_size`), and creates a texture
 * with GL_TEXTURE_TILING_EXT = `e->gl_tiling` and glTextureStorageMem2DEXT(1 level,
 * `e->gl_internal_format`, `e->width` × `e->height`, offset 0), filtered GL_NEAREST and
 * GL_CLAMP_TO_EDGE. Takes ownership of `e->fd`: GL owns it after a successful import; it is closed
 * here on every failure before that. Returns GL_NO_ERROR, the first GL error raised, or
 * GL_INVALID_OPERATION when the UUIDs differ or the export is empty; on failure nothing is left
 * and both names are 0. Texel (0, 0) is memory row 0: the image row `lumi_camera.origin` names. */
static inline GLenum lumi_gl_import(const lumi_export *e, GLuint *memory, GLuint *texture) {
    int fd = e->fd;
    GLenum err = GL_NO_ERROR;
    GLint dedicated = e->dedicated ? GL_TRUE : GL_FALSE;
    *memory = 0;
    *texture = 0;
    for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; i++) {
        /* earlier errors are not ours */
    }
    if (fd < 0 || !lumi_gl_same_device(e->device_uuid, e->driver_uuid) || e->width == 0 || e->height == 0 ||
        e->allocation_size == 0) {
        err = GL_INVALID_OPERATION;
        goto fail;
    }
    glCreateMemoryObjectsEXT(1, memory);
    glMemoryObjectParameterivEXT(*memory, GL_DEDICATED_MEMORY_OBJECT_EXT, &dedicated);
    if ((err = glGetError()) != GL_NO_ERROR) goto fail;
    glImportMemoryFdEXT(*memory, e->allocation_size, GL_HANDLE_TYPE_OPAQUE_FD_EXT, fd);
    if ((err = glGetError()) != GL_NO_ERROR) goto fail;
    fd = -1; /* owned by GL now */
    glCreateTextures(GL_TEXTURE_2D, 1, texture);
    glTextureParameteri(*texture, GL_TEXTURE_TILING_EXT, (GLint)e->gl_tiling);
    glTextureStorageMem2DEXT(*texture, 1, e->gl_internal_format, (GLsizei)e->width, (GLsizei)e->height, *memory, 0);
    glTextureParameteri(*texture, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(*texture, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(*texture, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(*texture, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    if ((err = glGetError()) != GL_NO_ERROR) goto fail;
    return GL_NO_ERROR;
fail:
    if (fd >= 0) close(fd);
    lumi_gl_release_import(memory, texture);
    return err;
}

/* Without semaphores: waits until GL has finished every command so far, so the next `lumi_render`
 * into the imported target may overwrite what the host read (glFinish; a glFenceSync +
 * glClientWaitSync on the last command that reads the texture does the same with less stall). */
static inline void lumi_gl_finish_reads(void) { glFinish(); }

#ifdef GL_EXT_semaphore_fd
/* The semaphore path (`lumi_target_desc.semaphores`, needs GL_EXT_semaphore_fd): imports one fd
 * from `lumi_target_export_semaphores` into a new semaphore object (GL owns the fd on success; it
 * is closed here on failure). Returns GL_NO_ERROR or the GL error. */
static inline GLenum lumi_gl_import_semaphore(int32_t fd, GLuint *semaphore) {
    for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; i++) {
    }
    glGenSemaphoresEXT(1, semaphore);
    glImportSemaphoreFdEXT(*semaphore, GL_HANDLE_TYPE_OPAQUE_FD_EXT, fd);
    GLenum err = glGetError();
    if (err != GL_NO_ERROR) {
        glDeleteSemaphoresEXT(1, semaphore);
        *semaphore = 0;
        close(fd);
    }
    return err;
}

/* Each frame before reading the target's textures (all of them in one call: colour and depth; at
 * most 4): the GPU wait on `render_done`, source layout GL_LAYOUT_SHADER_READ_ONLY_EXT (the layout
 * lumiview released the images in). */
static inline void lumi_gl_wait_render(GLuint render_done, GLuint count, const GLuint *textures) {
    GLenum layouts[4] = {GL_LAYOUT_SHADER_READ_ONLY_EXT, GL_LAYOUT_SHADER_READ_ONLY_EXT,
                         GL_LAYOUT_SHADER_READ_ONLY_EXT, GL_LAYOUT_SHADER_READ_ONLY_EXT};
    glWaitSemaphoreEXT(render_done, 0, NULL, count < 4 ? count : 4, textures, layouts);
}

/* Each frame after the last command that reads the textures, exactly once and naming all of them
 * (at most 4): signal `host_done`, destination layout GL_LAYOUT_SHADER_READ_ONLY_EXT (which
 * lumiview's next frame acquires), and flush so the signal reaches the GPU. */
static inline void lumi_gl_signal_host_done(GLuint host_done, GLuint count, const GLuint *textures) {
    GLenum layouts[4] = {GL_LAYOUT_SHADER_READ_ONLY_EXT, GL_LAYOUT_SHADER_READ_ONLY_EXT,
                         GL_LAYOUT_SHADER_READ_ONLY_EXT, GL_LAYOUT_SHADER_READ_ONLY_EXT};
    glSignalSemaphoreEXT(host_done, 0, NULL, count < 4 ? count : 4, textures, layouts);
    glFlush();
}
#endif /* GL_EXT_semaphore_fd */

#endif /* LUMIVIEW_GL_H */
