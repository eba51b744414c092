/* Importing lumiview's exported images into OpenGL through GL_EXT_memory_object_fd, and the
 * device/driver UUID checks that must pass first (GL_EXT_external_objects). */
#ifndef GL_INTEROP_H
#define GL_INTEROP_H

#include <stdbool.h>
#include <stdint.h>

#include "gl_api.h"
#include "lumiview.h"

#define GL_INTEROP_MAX_DEVICES 4

typedef struct gl_uuids {
    uint8_t driver[GL_UUID_SIZE_EXT];
    uint8_t devices[GL_INTEROP_MAX_DEVICES][GL_UUID_SIZE_EXT];
    int device_count;
} gl_uuids;

/* Queries GL_DRIVER_UUID_EXT and every GL_DEVICE_UUID_EXT (indexed, GL_NUM_DEVICE_UUIDS_EXT of
 * them) of the current context. */
bool gl_query_uuids(gl_uuids *u);

/* True when `device` is one of the context's device UUIDs and `driver` its driver UUID; otherwise
 * prints both sides, naming `who`, and returns false: memory from another device or driver cannot be
 * imported. */
bool gl_uuids_match(const gl_uuids *u, const uint8_t device[16], const uint8_t driver[16], const char *who);

typedef struct gl_imported {
    GLuint memory;  /* the memory object (owns the imported fd) */
    GLuint texture; /* immutable 2D texture over it, NEAREST, CLAMP_TO_EDGE */
    uint32_t width, height;
} gl_imported;

/* Imports one export with lumi_gl_import (lumiview_gl.h): checks its UUIDs against the context's,
 * creates a memory object (dedicated as the export says), imports the fd, and creates a texture with
 * GL_TEXTURE_TILING_EXT and glTextureStorageMem2DEXT in the export's GL format and size. Takes
 * ownership of e->fd: GL owns it after a successful import; it is closed on every failure before
 * that. The host checks the UUIDs once beforehand with gl_uuids_match, for its message. */
bool gl_import(const lumi_export *e, gl_imported *out);

/* Deletes the texture and the memory object (GL then closes the fd). Zeroed input is fine. */
void gl_imported_free(gl_imported *im);

#endif /* GL_INTEROP_H */
