/* The GLFW host's own objects and the composite pass; see host_objects.h. */
#include "host_objects.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- GLSL ---------------------------------------------------------------------------------- */

static const char *const GLSL_VERSION = "#version 450 core\n";

/* Reinhard, x / (1 + x) written as 1 − 1/(1 + x) so that an infinite luminance (RGBA16F overflow)
 * gives 1 rather than NaN. */
static const char *const GLSL_TONEMAP =
    "vec3 tonemap(vec3 luminance, float exposure) {\n"
    "    vec3 x = max(luminance * exposure, vec3(0.0));\n"
    "    return vec3(1.0) - vec3(1.0) / (vec3(1.0) + x);\n"
    "}\n";

/* The host's objects: each vertex carries its face's luminance (cd/m², from the library's
 * illuminance), tone-mapped like lumiview's image. */
static const char *const OBJECT_VS =
    "layout(location = 0) in vec3 aPos;\n"
    "layout(location = 1) in vec3 aLuminance;\n"
    "uniform mat4 uViewProj;\n"
    "flat out vec3 vLuminance;\n"
    "void main() {\n"
    "    vLuminance = aLuminance;\n"
    "    gl_Position = uViewProj * vec4(aPos, 1.0);\n"
    "}\n";

static const char *const OBJECT_FS =
    "flat in vec3 vLuminance;\n"
    "uniform float uExposure;\n"
    "layout(location = 0) out vec4 oColor;\n"
    "void main() {\n"
    "    oColor = vec4(tonemap(vLuminance, uExposure), 1.0);\n"
    "}\n";

/* A triangle covering the viewport, from gl_VertexID alone. */
static const char *const FULLSCREEN_VS =
    "void main() {\n"
    "    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n"
    "    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);\n"
    "}\n";

static const char *const COMPOSITE_FS =
    "layout(binding = 1) uniform sampler2D uColor;   // lumiview colour, linear cd/m^2, premultiplied\n"
    "layout(binding = 2) uniform sampler2D uDepth;   // lumiview R32F, GL window depth\n"
    "uniform float uExposure;\n"
    "layout(location = 0) out vec4 oColor;\n"
    "void main() {\n"
    "    ivec2 p = ivec2(gl_FragCoord.xy);           // memory row 0 = bottom row (LUMI_ORIGIN_BOTTOM_LEFT)\n"
    "    vec4 c = texelFetch(uColor, p, 0);\n"
    "    if (c.a <= 0.0) discard;\n"
    "    gl_FragDepth = texelFetch(uDepth, p, 0).r;\n"
    "    oColor = vec4(tonemap(c.rgb, uExposure), 1.0);\n"
    "}\n";

static GLuint compile(GLenum type, const char *const *parts, GLsizei count, const char *name) {
    GLuint sh = glCreateShader(type);
    if (!sh) {
        fprintf(stderr, "glfw_host: glCreateShader failed for %s\n", name);
        return 0;
    }
    glShaderSource(sh, count, parts, NULL);
    glCompileShader(sh);
    GLint ok = GL_FALSE;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096];
        GLsizei n = 0;
        glGetShaderInfoLog(sh, (GLsizei)sizeof log, &n, log);
        fprintf(stderr, "glfw_host: compiling %s failed:\n%.*s\n", name, (int)n, log);
        glDeleteShader(sh);
        return 0;
    }
    return sh;
}

static GLuint link(GLuint vs, GLuint fs, const char *name) {
    GLuint p = 0;
    if (vs && fs) {
        p = glCreateProgram();
        glAttachShader(p, vs);
        glAttachShader(p, fs);
        glLinkProgram(p);
        GLint ok = GL_FALSE;
        glGetProgramiv(p, GL_LINK_STATUS, &ok);
        if (!ok) {
            char log[4096];
            GLsizei n = 0;
            glGetProgramInfoLog(p, (GLsizei)sizeof log, &n, log);
            fprintf(stderr, "glfw_host: linking %s failed:\n%.*s\n", name, (int)n, log);
            glDeleteProgram(p);
            p = 0;
        }
    }
    if (vs) glDeleteShader(vs);
    if (fs) glDeleteShader(fs);
    return p;
}

static GLuint make_program(const char *vs_body, const char *fs_body, const char *name) {
    const char *vs_parts[] = {GLSL_VERSION, vs_body};
    const char *fs_parts[] = {GLSL_VERSION, GLSL_TONEMAP, fs_body};
    GLuint vs = compile(GL_VERTEX_SHADER, vs_parts, 2, name);
    GLuint fs = compile(GL_FRAGMENT_SHADER, fs_parts, 3, name);
    return link(vs, fs, name);
}

/* Uniform location that must exist (an optimised-away uniform is a bug here). */
static bool uniform(GLuint program, const char *name, GLint *loc) {
    *loc = glGetUniformLocation(program, name);
    if (*loc < 0) {
        fprintf(stderr, "glfw_host: uniform %s not found\n", name);
        return false;
    }
    return true;
}

/* ---- Geometry ------------------------------------------------------------------------------ */

static void add_box(host_objects *h, lv_vec3 mn, lv_vec3 mx, double r, double g, double b, const char *name) {
    if (h->box_count >= HOST_MAX_BOXES) return;
    host_box *bx = &h->boxes[h->box_count++];
    memset(bx, 0, sizeof *bx);
    bx->min = mn;
    bx->max = mx;
    bx->albedo[0] = r;
    bx->albedo[1] = g;
    bx->albedo[2] = b;
    bx->name = name;
}

static double axis_of(lv_vec3 v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

static lv_vec3 with_axis(lv_vec3 v, int a, double x) {
    if (a == 0) v.x = x;
    else if (a == 1) v.y = x;
    else v.z = x;
    return v;
}

/* A box of the stand, given in the stand's own horizontal axes: `along` the direction the panel
 * faces (f = (sin yaw, 0, cos yaw)), `side` across it, from the luminaire's centre; y absolute. With
 * yaw a multiple of 90° the world box is exactly axis-aligned. */
static void add_stand_box(host_objects *h, double along0, double along1, double side_half, double y0, double y1,
                          const char *name) {
    double yaw = NEARFIELD_YAW_DEG * LV_PI_DEG;
    lv_vec3 f = lv_vec3_make(sin(yaw), 0, cos(yaw)), s = lv_vec3_make(cos(yaw), 0, -sin(yaw));
    lv_vec3 c = lv_vec3_make(NEARFIELD_X, 0, NEARFIELD_Z);
    lv_vec3 mn = lv_vec3_make(INFINITY, y0, INFINITY), mx = lv_vec3_make(-INFINITY, y1, -INFINITY);
    for (int i = 0; i < 4; i++) {
        lv_vec3 p = lv_vec3_add(c, lv_vec3_add(lv_vec3_scale(f, i & 1 ? along1 : along0),
                                               lv_vec3_scale(s, i & 2 ? side_half : -side_half)));
        mn.x = fmin(mn.x, p.x);
        mn.z = fmin(mn.z, p.z);
        mx.x = fmax(mx.x, p.x);
        mx.z = fmax(mx.z, p.z);
    }
    /* Round away the 1e-17 that sin/cos leave at multiples of 90°. */
    mn.x = round(mn.x * 1e6) / 1e6;
    mn.z = round(mn.z * 1e6) / 1e6;
    mx.x = round(mx.x * 1e6) / 1e6;
    mx.z = round(mx.z * 1e6) / 1e6;
    add_box(h, mn, mx, 0.25, 0.25, 0.27, name);
}

static void build_boxes(host_objects *h, bool occluder, bool nearfield_stand) {
    if (occluder)
        add_box(h, lv_vec3_make(OCCLUDER_MIN_X, 0.0, OCCLUDER_MIN_Z),
                lv_vec3_make(OCCLUDER_MAX_X, OCCLUDER_HEIGHT_M, OCCLUDER_MAX_Z), 0.55, 0.42, 0.30, "host column");
    if (nearfield_stand) {
        /* Behind the panel (its back plane lies 50 mm behind the front tiles, and it spans ±0.1 m
         * around its centre): a mounting plate 60–75 mm behind the tiles, a pole from the base to the
         * plate, and a base on the floor. */
        add_stand_box(h, -0.075, -0.06, 0.11, NEARFIELD_Y - 0.11, NEARFIELD_Y + 0.11, "stand plate");
        add_stand_box(h, -0.105, -0.075, 0.015, 0.02, NEARFIELD_Y, "stand pole");
        add_stand_box(h, -0.15, 0.06, 0.15, 0.0, 0.02, "stand base");
    }
}

/* 6 floats per vertex: position, luminance; 36 vertices per box, face by face in host_box order. */
static size_t box_vertices(const host_box *b, float *out) {
    size_t n = 0;
    for (int a = 0; a < 3; a++) {
        for (int side = 0; side < 2; side++) {
            double plane = side ? axis_of(b->max, a) : axis_of(b->min, a);
            int u = (a + 1) % 3, v = (a + 2) % 3;
            lv_vec3 q[4];
            for (int k = 0; k < 4; k++) {
                lv_vec3 p = with_axis(lv_vec3_make(0, 0, 0), a, plane);
                p = with_axis(p, u, (k == 1 || k == 2) ? axis_of(b->max, u) : axis_of(b->min, u));
                p = with_axis(p, v, (k >= 2) ? axis_of(b->max, v) : axis_of(b->min, v));
                q[k] = p;
            }
            const double *lum = b->face_luminance[a * 2 + side];
            static const int idx[6] = {0, 1, 2, 0, 2, 3};
            for (int k = 0; k < 6; k++) {
                float *o = out + n * 6;
                o[0] = (float)q[idx[k]].x;
                o[1] = (float)q[idx[k]].y;
                o[2] = (float)q[idx[k]].z;
                o[3] = (float)lum[0];
                o[4] = (float)lum[1];
                o[5] = (float)lum[2];
                n++;
            }
        }
    }
    return n;
}

/* Writes every box's vertices into the vertex buffer. */
static bool upload(host_objects *h) {
    if (h->box_count == 0) return true;
    size_t max_vertices = (size_t)h->box_count * 36;
    float *v = malloc(max_vertices * 6 * sizeof(float));
    if (!v) {
        fprintf(stderr, "glfw_host: out of memory\n");
        return false;
    }
    size_t n = 0;
    for (int i = 0; i < h->box_count; i++) n += box_vertices(&h->boxes[i], v + n * 6);
    glNamedBufferSubData(h->vbo, 0, (GLsizeiptr)(n * 6 * sizeof(float)), v);
    free(v);
    return lv_gl_ok("uploading the host's objects");
}

/* ---- Public -------------------------------------------------------------------------------- */

void host_nearfield_model(float m[16]) {
    double yaw = NEARFIELD_YAW_DEG * LV_PI_DEG, fx = sin(yaw), fz = cos(yaw); /* nadir → world (fx, 0, fz) */
    memset(m, 0, 16 * sizeof(float));
    m[1] = 1.0f;         /* frame +X → world up */
    m[4] = (float)fz;    /* frame +Y → world (fz, 0, −fx) = (−Z) × (+X), right-handed */
    m[6] = (float)-fx;
    m[8] = (float)-fx;   /* frame +Z → world −f: the nadir faces f */
    m[10] = (float)-fz;
    m[12] = (float)NEARFIELD_X;
    m[13] = (float)NEARFIELD_Y;
    m[14] = (float)NEARFIELD_Z;
    m[15] = 1.0f;
}

bool host_objects_create(host_objects *h, bool occluder, bool nearfield_stand) {
    memset(h, 0, sizeof *h);
    build_boxes(h, occluder, nearfield_stand);
    h->vertex_count = (GLsizei)(h->box_count * 36);
    glCreateVertexArrays(1, &h->empty_vao);
    if (h->box_count > 0) {
        glCreateBuffers(1, &h->vbo);
        glNamedBufferStorage(h->vbo, (GLsizeiptr)((size_t)h->vertex_count * 6 * sizeof(float)), NULL,
                             GL_DYNAMIC_STORAGE_BIT);
        glCreateVertexArrays(1, &h->vao);
        glVertexArrayVertexBuffer(h->vao, 0, h->vbo, 0, 6 * sizeof(float));
        for (GLuint a = 0; a < 2; a++) {
            glEnableVertexArrayAttrib(h->vao, a);
            glVertexArrayAttribFormat(h->vao, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
            glVertexArrayAttribBinding(h->vao, a, 0);
        }
    }
    h->object_program = make_program(OBJECT_VS, OBJECT_FS, "host object shader");
    h->composite_program = make_program(FULLSCREEN_VS, COMPOSITE_FS, "composite shader");
    if (!h->object_program || !h->composite_program) return false;
    if (!uniform(h->object_program, "uViewProj", &h->object_view_proj) ||
        !uniform(h->object_program, "uExposure", &h->object_exposure) ||
        !uniform(h->composite_program, "uExposure", &h->composite_exposure))
        return false;
    return lv_gl_ok("creating the host's objects");
}

void host_objects_destroy(host_objects *h) {
    if (h->object_program) glDeleteProgram(h->object_program);
    if (h->composite_program) glDeleteProgram(h->composite_program);
    if (h->vao) glDeleteVertexArrays(1, &h->vao);
    if (h->empty_vao) glDeleteVertexArrays(1, &h->empty_vao);
    if (h->vbo) glDeleteBuffers(1, &h->vbo);
    memset(h, 0, sizeof *h);
}

bool host_objects_light(host_objects *h, const room *r, const lumi_context *ctx, bool total) {
    if (h->box_count == 0) return true;
    size_t count = (size_t)h->box_count * 6;
    float points[HOST_MAX_BOXES * 6][3], normals[HOST_MAX_BOXES * 6][3];
    double lx[HOST_MAX_BOXES * 6];
    for (int i = 0; i < h->box_count; i++) {
        const host_box *b = &h->boxes[i];
        lv_vec3 centre = lv_vec3_scale(lv_vec3_add(b->min, b->max), 0.5);
        for (int face = 0; face < 6; face++) {
            int a = face / 2;
            double sign = face % 2 ? 1.0 : -1.0;
            lv_vec3 n = with_axis(lv_vec3_make(0, 0, 0), a, sign);
            lv_vec3 p = with_axis(centre, a, (face % 2 ? axis_of(b->max, a) : axis_of(b->min, a)) + sign * 1e-3);
            float *pp = points[i * 6 + face], *nn = normals[i * 6 + face];
            pp[0] = (float)p.x;
            pp[1] = (float)p.y;
            pp[2] = (float)p.z;
            nn[0] = (float)n.x;
            nn[1] = (float)n.y;
            nn[2] = (float)n.z;
        }
    }
    if (!room_illuminance(r, ctx, &points[0][0], &normals[0][0], count,
                          total ? LUMI_ILLUMINANCE_TOTAL : LUMI_ILLUMINANCE_DIRECT, 0, lx, NULL))
        return false;
    for (int i = 0; i < h->box_count; i++) {
        host_box *b = &h->boxes[i];
        for (int face = 0; face < 6; face++) {
            b->face_lx[face] = lx[i * 6 + face];
            for (int c = 0; c < 3; c++) b->face_luminance[face][c] = b->albedo[c] * b->face_lx[face] / LV_PI;
        }
    }
    h->lit_total = total;
    return upload(h);
}

void host_objects_draw(const host_objects *h, const float view[16], const float projection[16], float exposure) {
    if (h->box_count == 0) return;
    float vp[16];
    lv_mat4_mul(vp, projection, view);
    glProgramUniformMatrix4fv(h->object_program, h->object_view_proj, 1, GL_FALSE, vp);
    glProgramUniform1f(h->object_program, h->object_exposure, exposure);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glUseProgram(h->object_program);
    glBindVertexArray(h->vao);
    glDrawArrays(GL_TRIANGLES, 0, h->vertex_count);
}

void host_composite(const host_objects *h, GLuint color, GLuint depth, float exposure) {
    glProgramUniform1f(h->composite_program, h->composite_exposure, exposure);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glUseProgram(h->composite_program);
    glBindTextureUnit(1, color);
    glBindTextureUnit(2, depth);
    glBindVertexArray(h->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
}

/* Slab test: the entry face (t > 0) of an outward box. */
static bool ray_box(lv_vec3 o, lv_vec3 d, const host_box *b, double *t_hit, int *face) {
    double tmin = -INFINITY, tmax = INFINITY;
    int amin = -1, smin = 0;
    for (int a = 0; a < 3; a++) {
        double oa = axis_of(o, a), da = axis_of(d, a), lo = axis_of(b->min, a), hi = axis_of(b->max, a);
        if (fabs(da) < 1e-15) {
            if (oa < lo || oa > hi) return false;
            continue;
        }
        double t1 = (lo - oa) / da, t2 = (hi - oa) / da;
        double tn = da > 0 ? t1 : t2, tf = da > 0 ? t2 : t1;
        if (tn > tmin) {
            tmin = tn;
            amin = a;
            smin = da > 0 ? 0 : 1; /* entering through the min face when travelling +, else the max face */
        }
        if (tf < tmax) tmax = tf;
    }
    if (tmin > tmax || tmin <= 0 || amin < 0) return false;
    *t_hit = tmin;
    *face = amin * 2 + smin;
    return true;
}

bool host_ray_hit(const host_objects *h, lv_vec3 origin, lv_vec3 dir, double *t, int *face, const host_box **box) {
    bool hit = false;
    double best = INFINITY;
    for (int i = 0; i < h->box_count; i++) {
        double th;
        int f;
        if (ray_box(origin, dir, &h->boxes[i], &th, &f) && th < best) {
            best = th;
            *t = th;
            *face = f;
            *box = &h->boxes[i];
            hit = true;
        }
    }
    return hit;
}
