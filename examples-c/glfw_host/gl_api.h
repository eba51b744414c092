/* The OpenGL 4.5 core subset the GLFW host uses, plus GL_EXT_memory_object, GL_EXT_memory_object_fd
 * and GL_EXT_external_objects' UUID queries, declared here and loaded through glfwGetProcAddress.
 *
 * Why not the system headers: Debian 12's <GL/glcorearb.h> lacks the GL_EXT_memory_object(_fd)
 * declarations, and no loader library is assumed. This header declares exactly what the host calls:
 * the types and tokens (values from the Khronos registry, gl.xml) and one function pointer per entry
 * point. Each `glFoo` below is a macro for the pointer `lv_glFoo`, so the names cannot clash with
 * libGL's own exported symbols. Include it instead of any GL header. */
#ifndef GL_API_H
#define GL_API_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#define LV_GLAPIENTRY __stdcall
#else
#define LV_GLAPIENTRY
#endif

typedef unsigned int GLenum;
typedef unsigned char GLboolean;
typedef unsigned int GLbitfield;
typedef int GLint;
typedef unsigned int GLuint;
typedef int GLsizei;
typedef float GLfloat;
typedef double GLdouble;
typedef char GLchar;
typedef unsigned char GLubyte;
typedef uint64_t GLuint64;
typedef ptrdiff_t GLsizeiptr;
typedef ptrdiff_t GLintptr;
typedef void(LV_GLAPIENTRY *GLDEBUGPROC)(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                                         const GLchar *message, const void *user);

/* Core tokens. */
#define GL_FALSE 0
#define GL_TRUE 1
#define GL_NO_ERROR 0
#define GL_TRIANGLES 0x0004
#define GL_LESS 0x0201
#define GL_BACK 0x0405
#define GL_DEPTH_TEST 0x0B71
#define GL_CULL_FACE 0x0B44
#define GL_PACK_ALIGNMENT 0x0D05
#define GL_UNPACK_ALIGNMENT 0x0CF5
#define GL_TEXTURE_2D 0x0DE1
#define GL_UNSIGNED_BYTE 0x1401
#define GL_FLOAT 0x1406
#define GL_DEPTH 0x1801
#define GL_RED 0x1903
#define GL_RGBA 0x1908
#define GL_VENDOR 0x1F00
#define GL_RENDERER 0x1F01
#define GL_VERSION 0x1F02
#define GL_NEAREST 0x2600
#define GL_LINEAR 0x2601
#define GL_TEXTURE_MAG_FILTER 0x2800
#define GL_TEXTURE_MIN_FILTER 0x2801
#define GL_TEXTURE_WRAP_S 0x2802
#define GL_TEXTURE_WRAP_T 0x2803
#define GL_REPEAT 0x2901
#define GL_CLAMP_TO_EDGE 0x812F
#define GL_DEPTH_BUFFER_BIT 0x00000100
#define GL_COLOR_BUFFER_BIT 0x00004000
#define GL_DYNAMIC_STORAGE_BIT 0x0100
#define GL_MAJOR_VERSION 0x821B
#define GL_MINOR_VERSION 0x821C
#define GL_NUM_EXTENSIONS 0x821D
#define GL_EXTENSIONS 0x1F03
#define GL_R32F 0x822E
#define GL_RGBA16F 0x881A
#define GL_RGBA32F 0x8814
#define GL_FRAGMENT_SHADER 0x8B30
#define GL_VERTEX_SHADER 0x8B31
#define GL_COMPILE_STATUS 0x8B81
#define GL_LINK_STATUS 0x8B82
#define GL_INFO_LOG_LENGTH 0x8B84
#define GL_FRAMEBUFFER 0x8D40
#define GL_FRAMEBUFFER_COMPLETE 0x8CD5
#define GL_COLOR_ATTACHMENT0 0x8CE0
#define GL_FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE 0x8216
#define GL_DEBUG_OUTPUT_SYNCHRONOUS 0x8242
#define GL_DEBUG_OUTPUT 0x92E0
#define GL_DEBUG_TYPE_ERROR 0x824C
#define GL_DEBUG_SEVERITY_HIGH 0x9146
#define GL_DEBUG_SEVERITY_MEDIUM 0x9147
#define GL_DEBUG_SEVERITY_LOW 0x9148
#define GL_DEBUG_SEVERITY_NOTIFICATION 0x826B
#define GL_DONT_CARE 0x1100

/* GL_EXT_memory_object, GL_EXT_memory_object_fd, GL_EXT_external_objects (UUIDs). */
#define GL_TEXTURE_TILING_EXT 0x9580
#define GL_DEDICATED_MEMORY_OBJECT_EXT 0x9581
#define GL_OPTIMAL_TILING_EXT 0x9584
#define GL_NUM_DEVICE_UUIDS_EXT 0x9596
#define GL_DEVICE_UUID_EXT 0x9597
#define GL_DRIVER_UUID_EXT 0x9598
#define GL_UUID_SIZE_EXT 16
#define GL_HANDLE_TYPE_OPAQUE_FD_EXT 0x9586

/* X(return type, name, parameter list): every entry point the host calls. */
#define LV_GL_FUNCTIONS(X)                                                                                    \
    X(GLenum, glGetError, (void))                                                                            \
    X(const GLubyte *, glGetString, (GLenum name))                                                           \
    X(const GLubyte *, glGetStringi, (GLenum name, GLuint index))                                            \
    X(void, glGetIntegerv, (GLenum pname, GLint * data))                                                     \
    X(void, glEnable, (GLenum cap))                                                                          \
    X(void, glDepthFunc, (GLenum func))                                                                      \
    X(void, glDepthMask, (GLboolean flag))                                                                   \
    X(void, glClearColor, (GLfloat r, GLfloat g, GLfloat b, GLfloat a))                                      \
    X(void, glClearDepth, (GLdouble depth))                                                                  \
    X(void, glClear, (GLbitfield mask))                                                                      \
    X(void, glViewport, (GLint x, GLint y, GLsizei width, GLsizei height))                                   \
    X(void, glFinish, (void))                                                                                \
    X(void, glReadBuffer, (GLenum src))                                                                      \
    X(void, glReadPixels, (GLint x, GLint y, GLsizei w, GLsizei h, GLenum format, GLenum type, void *data))  \
    X(void, glPixelStorei, (GLenum pname, GLint param))                                                      \
    X(void, glDebugMessageCallback, (GLDEBUGPROC callback, const void *user))                                \
    X(void, glGetFramebufferAttachmentParameteriv, (GLenum target, GLenum attachment, GLenum pname, GLint *p)) \
    X(GLuint, glCreateShader, (GLenum type))                                                                 \
    X(void, glShaderSource, (GLuint shader, GLsizei count, const GLchar *const *string, const GLint *length)) \
    X(void, glCompileShader, (GLuint shader))                                                                \
    X(void, glGetShaderiv, (GLuint shader, GLenum pname, GLint * params))                                    \
    X(void, glGetShaderInfoLog, (GLuint shader, GLsizei size, GLsizei * length, GLchar * log))               \
    X(void, glDeleteShader, (GLuint shader))                                                                 \
    X(GLuint, glCreateProgram, (void))                                                                       \
    X(void, glAttachShader, (GLuint program, GLuint shader))                                                 \
    X(void, glLinkProgram, (GLuint program))                                                                 \
    X(void, glGetProgramiv, (GLuint program, GLenum pname, GLint * params))                                  \
    X(void, glGetProgramInfoLog, (GLuint program, GLsizei size, GLsizei * length, GLchar * log))             \
    X(void, glDeleteProgram, (GLuint program))                                                               \
    X(void, glUseProgram, (GLuint program))                                                                  \
    X(GLint, glGetUniformLocation, (GLuint program, const GLchar *name))                                     \
    X(void, glProgramUniform1f, (GLuint program, GLint location, GLfloat v0))                                \
    X(void, glProgramUniformMatrix4fv,                                                                       \
      (GLuint program, GLint location, GLsizei count, GLboolean transpose, const GLfloat *value))            \
    X(void, glCreateBuffers, (GLsizei n, GLuint * buffers))                                                  \
    X(void, glNamedBufferStorage, (GLuint buffer, GLsizeiptr size, const void *data, GLbitfield flags))      \
    X(void, glNamedBufferSubData, (GLuint buffer, GLintptr offset, GLsizeiptr size, const void *data))       \
    X(void, glDeleteBuffers, (GLsizei n, const GLuint *buffers))                                             \
    X(void, glCreateVertexArrays, (GLsizei n, GLuint * arrays))                                              \
    X(void, glDeleteVertexArrays, (GLsizei n, const GLuint *arrays))                                         \
    X(void, glVertexArrayVertexBuffer,                                                                       \
      (GLuint vao, GLuint binding, GLuint buffer, GLintptr offset, GLsizei stride))                          \
    X(void, glVertexArrayAttribFormat,                                                                       \
      (GLuint vao, GLuint attrib, GLint size, GLenum type, GLboolean normalized, GLuint offset))             \
    X(void, glVertexArrayAttribBinding, (GLuint vao, GLuint attrib, GLuint binding))                         \
    X(void, glEnableVertexArrayAttrib, (GLuint vao, GLuint index))                                           \
    X(void, glBindVertexArray, (GLuint array))                                                               \
    X(void, glDrawArrays, (GLenum mode, GLint first, GLsizei count))                                         \
    X(void, glCreateTextures, (GLenum target, GLsizei n, GLuint * textures))                                 \
    X(void, glDeleteTextures, (GLsizei n, const GLuint *textures))                                           \
    X(void, glGetTextureSubImage,                                                                            \
      (GLuint texture, GLint level, GLint x, GLint y, GLint z, GLsizei w, GLsizei h, GLsizei d,              \
       GLenum format, GLenum type, GLsizei size, void *pixels))                                              \
    X(void, glTextureParameteri, (GLuint texture, GLenum pname, GLint param))                                \
    X(void, glBindTextureUnit, (GLuint unit, GLuint texture))                                                \
    X(void, glBindFramebuffer, (GLenum target, GLuint framebuffer))                                          \
    X(void, glGetUnsignedBytevEXT, (GLenum pname, GLubyte * data))                                           \
    X(void, glGetUnsignedBytei_vEXT, (GLenum target, GLuint index, GLubyte * data))                          \
    X(void, glCreateMemoryObjectsEXT, (GLsizei n, GLuint * memory_objects))                                  \
    X(void, glDeleteMemoryObjectsEXT, (GLsizei n, const GLuint *memory_objects))                             \
    X(GLboolean, glIsMemoryObjectEXT, (GLuint memory_object))                                                \
    X(void, glMemoryObjectParameterivEXT, (GLuint memory_object, GLenum pname, const GLint *params))         \
    X(void, glImportMemoryFdEXT, (GLuint memory, GLuint64 size, GLenum handle_type, GLint fd))               \
    X(void, glTextureStorageMem2DEXT,                                                                        \
      (GLuint texture, GLsizei levels, GLenum format, GLsizei w, GLsizei h, GLuint memory, GLuint64 offset))

#define LV_GL_DECLARE(ret, name, params)                     \
    typedef ret(LV_GLAPIENTRY *lv_pfn_##name) params;        \
    extern lv_pfn_##name lv_##name;
LV_GL_FUNCTIONS(LV_GL_DECLARE)
#undef LV_GL_DECLARE

#define glGetError lv_glGetError
#define glGetString lv_glGetString
#define glGetStringi lv_glGetStringi
#define glGetIntegerv lv_glGetIntegerv
#define glEnable lv_glEnable
#define glDepthFunc lv_glDepthFunc
#define glDepthMask lv_glDepthMask
#define glClearColor lv_glClearColor
#define glClearDepth lv_glClearDepth
#define glClear lv_glClear
#define glViewport lv_glViewport
#define glFinish lv_glFinish
#define glReadBuffer lv_glReadBuffer
#define glReadPixels lv_glReadPixels
#define glPixelStorei lv_glPixelStorei
#define glDebugMessageCallback lv_glDebugMessageCallback
#define glGetFramebufferAttachmentParameteriv lv_glGetFramebufferAttachmentParameteriv
#define glCreateShader lv_glCreateShader
#define glShaderSource lv_glShaderSource
#define glCompileShader lv_glCompileShader
#define glGetShaderiv lv_glGetShaderiv
#define glGetShaderInfoLog lv_glGetShaderInfoLog
#define glDeleteShader lv_glDeleteShader
#define glCreateProgram lv_glCreateProgram
#define glAttachShader lv_glAttachShader
#define glLinkProgram lv_glLinkProgram
#define glGetProgramiv lv_glGetProgramiv
#define glGetProgramInfoLog lv_glGetProgramInfoLog
#define glDeleteProgram lv_glDeleteProgram
#define glUseProgram lv_glUseProgram
#define glGetUniformLocation lv_glGetUniformLocation
#define glProgramUniform1f lv_glProgramUniform1f
#define glProgramUniformMatrix4fv lv_glProgramUniformMatrix4fv
#define glCreateBuffers lv_glCreateBuffers
#define glNamedBufferStorage lv_glNamedBufferStorage
#define glNamedBufferSubData lv_glNamedBufferSubData
#define glDeleteBuffers lv_glDeleteBuffers
#define glCreateVertexArrays lv_glCreateVertexArrays
#define glDeleteVertexArrays lv_glDeleteVertexArrays
#define glVertexArrayVertexBuffer lv_glVertexArrayVertexBuffer
#define glVertexArrayAttribFormat lv_glVertexArrayAttribFormat
#define glVertexArrayAttribBinding lv_glVertexArrayAttribBinding
#define glEnableVertexArrayAttrib lv_glEnableVertexArrayAttrib
#define glBindVertexArray lv_glBindVertexArray
#define glDrawArrays lv_glDrawArrays
#define glCreateTextures lv_glCreateTextures
#define glDeleteTextures lv_glDeleteTextures
#define glGetTextureSubImage lv_glGetTextureSubImage
#define glTextureParameteri lv_glTextureParameteri
#define glBindTextureUnit lv_glBindTextureUnit
#define glBindFramebuffer lv_glBindFramebuffer
#define glGetUnsignedBytevEXT lv_glGetUnsignedBytevEXT
#define glGetUnsignedBytei_vEXT lv_glGetUnsignedBytei_vEXT
#define glCreateMemoryObjectsEXT lv_glCreateMemoryObjectsEXT
#define glDeleteMemoryObjectsEXT lv_glDeleteMemoryObjectsEXT
#define glIsMemoryObjectEXT lv_glIsMemoryObjectEXT
#define glMemoryObjectParameterivEXT lv_glMemoryObjectParameterivEXT
#define glImportMemoryFdEXT lv_glImportMemoryFdEXT
#define glTextureStorageMem2DEXT lv_glTextureStorageMem2DEXT

/* A function returning an entry point by name (glfwGetProcAddress). */
typedef void (*lv_gl_proc)(void);
typedef lv_gl_proc (*lv_gl_get_proc)(const char *name);

/* Loads every entry point above with the current context. Checks first that the context is
 * OpenGL ≥ 4.5 and has GL_EXT_memory_object and GL_EXT_memory_object_fd (a GLX implementation
 * returns non-NULL pointers even for functions it lacks, so the extension strings decide). Prints
 * what is missing and returns false on failure. */
bool lv_gl_load(lv_gl_get_proc get_proc);

/* Whether the context lists the extension (after lv_gl_load). */
bool lv_gl_has_extension(const char *name);

/* Installs a debug-output callback (GL 4.3 core) that prints errors and warnings and counts
 * messages of type ERROR or severity HIGH/MEDIUM. */
void lv_gl_install_debug_output(void);
/* Messages counted by the debug callback. */
unsigned lv_gl_debug_errors(void);

/* Prints "<what>: GL error 0x…" for every pending glGetError and returns false if there was one. */
bool lv_gl_ok(const char *what);

#endif /* GL_API_H */
