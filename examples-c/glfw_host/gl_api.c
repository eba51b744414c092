/* The host's GL loader; see gl_api.h. */
#include "gl_api.h"

#include <stdio.h>
#include <string.h>

#define LV_GL_DEFINE(ret, name, params) lv_pfn_##name lv_##name = NULL;
LV_GL_FUNCTIONS(LV_GL_DEFINE)
#undef LV_GL_DEFINE

static unsigned debug_errors;

bool lv_gl_has_extension(const char *name) {
    GLint n = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &n);
    for (GLint i = 0; i < n; i++) {
        const GLubyte *e = glGetStringi(GL_EXTENSIONS, (GLuint)i);
        if (e && strcmp((const char *)e, name) == 0) return true;
    }
    return false;
}

bool lv_gl_load(lv_gl_get_proc get_proc) {
    bool ok = true;
    /* Cast between function-pointer types: the GL ABI of each entry point is what gl.xml declares. */
#define LV_GL_LOAD(ret, name, params)                                      \
    lv_##name = (lv_pfn_##name)get_proc(#name);                            \
    if (!lv_##name) {                                                      \
        fprintf(stderr, "glfw_host: GL entry point %s not found\n", #name); \
        ok = false;                                                        \
    }
    LV_GL_FUNCTIONS(LV_GL_LOAD)
#undef LV_GL_LOAD
    if (!ok) return false;
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major < 4 || (major == 4 && minor < 5)) {
        fprintf(stderr, "glfw_host: OpenGL %d.%d; 4.5 is needed\n", major, minor);
        return false;
    }
    static const char *const needed[] = {"GL_EXT_memory_object", "GL_EXT_memory_object_fd"};
    for (size_t i = 0; i < sizeof needed / sizeof needed[0]; i++) {
        if (!lv_gl_has_extension(needed[i])) {
            fprintf(stderr, "glfw_host: the GL implementation (%s) lacks %s: it cannot import Vulkan memory\n",
                    (const char *)glGetString(GL_RENDERER), needed[i]);
            ok = false;
        }
    }
    return ok;
}

static void LV_GLAPIENTRY on_debug(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                                   const GLchar *message, const void *user) {
    (void)source;
    (void)length;
    (void)user;
    if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
    bool error = type == GL_DEBUG_TYPE_ERROR || severity == GL_DEBUG_SEVERITY_HIGH ||
                 severity == GL_DEBUG_SEVERITY_MEDIUM;
    if (error) debug_errors++;
    fprintf(stderr, "GL debug %s (type 0x%x, id %u): %s\n", error ? "error" : "message", type, id,
            message ? message : "");
}

void lv_gl_install_debug_output(void) {
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(on_debug, NULL);
}

unsigned lv_gl_debug_errors(void) { return debug_errors; }

bool lv_gl_ok(const char *what) {
    bool ok = true;
    for (int i = 0; i < 16; i++) {
        GLenum e = glGetError();
        if (e == GL_NO_ERROR) break;
        fprintf(stderr, "glfw_host: %s: GL error 0x%04x\n", what, e);
        ok = false;
    }
    return ok;
}
