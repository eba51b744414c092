/* The GLFW host's room, lighting, composite and probe passes; see scene.h. */
#include "scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- GLSL ---------------------------------------------------------------------------------- */

static const char *const GLSL_VERSION = "#version 450 core\n";

/* The lighting function, shared by the room and the probe (docs/lut-and-solid.md §1.1 and §3). */
static const char *const GLSL_LIGHTING =
    "const float PI = 3.14159265358979;\n"
    "uniform sampler2D uLut;     // W x H R32F, absolute cd; LINEAR, REPEAT on s, CLAMP_TO_EDGE on t\n"
    "uniform vec2 uLutSize;      // (W, H)\n"
    "uniform mat3 uWorldToLum;   // inverse of the model matrix's 3x3\n"
    "uniform vec3 uLumPos;       // photometric centre, world\n"
    "// I in cd towards the unit luminaire-frame direction d. Texel i at C = 360 i / W (u = C/360 +\n"
    "// 0.5/W), row j at gamma = 180 j / (H - 1) (v = gamma/180 (H-1)/H + 0.5/H): node-aligned.\n"
    "float intensityCd(vec3 d) {\n"
    "    float gamma = acos(clamp(-d.z, -1.0, 1.0));\n"
    "    float c = (d.x == 0.0 && d.y == 0.0) ? 0.0 : atan(d.y, d.x);\n"
    "    vec2 uv = vec2(c * 0.15915494 + 0.5 / uLutSize.x,\n"
    "                   gamma * 0.31830989 * (uLutSize.y - 1.0) / uLutSize.y + 0.5 / uLutSize.y);\n"
    "    return textureLod(uLut, uv, 0.0).r;\n"
    "}\n"
    "// Illuminance in lux at world point p with unit normal n: E = I cos i / r^2.\n"
    "float illuminance(vec3 p, vec3 n) {\n"
    "    vec3 v = p - uLumPos;\n"
    "    float r2 = max(dot(v, v), 1e-8);\n"
    "    vec3 d = normalize(uWorldToLum * v);\n"
    "    float cosI = max(dot(n, -v) * inversesqrt(r2), 0.0);\n"
    "    return intensityCd(d) * cosI / r2;\n"
    "}\n";

/* Reinhard, x / (1 + x) written as 1 − 1/(1 + x) so that an infinite luminance (RGBA16F overflow)
 * gives 1 rather than NaN. */
static const char *const GLSL_TONEMAP =
    "vec3 tonemap(vec3 luminance, float exposure) {\n"
    "    vec3 x = max(luminance * exposure, vec3(0.0));\n"
    "    return vec3(1.0) - vec3(1.0) / (vec3(1.0) + x);\n"
    "}\n";

static const char *const ROOM_VS =
    "layout(location = 0) in vec3 aPos;\n"
    "layout(location = 1) in vec3 aNormal;\n"
    "layout(location = 2) in vec3 aAlbedo;\n"
    "uniform mat4 uViewProj;\n"
    "out vec3 vPos;\n"
    "out vec3 vNormal;\n"
    "out vec3 vAlbedo;\n"
    "void main() {\n"
    "    vPos = aPos;\n"
    "    vNormal = aNormal;\n"
    "    vAlbedo = aAlbedo;\n"
    "    gl_Position = uViewProj * vec4(aPos, 1.0);\n"
    "}\n";

static const char *const ROOM_FS =
    "in vec3 vPos;\n"
    "in vec3 vNormal;\n"
    "in vec3 vAlbedo;\n"
    "uniform float uExposure;\n"
    "uniform float uIndirect;    // uniform inter-reflected illuminance, lux\n"
    "layout(location = 0) out vec4 oColor;\n"
    "void main() {\n"
    "    float e = illuminance(vPos, normalize(vNormal)) + uIndirect;\n"
    "    vec3 luminance = vAlbedo * e / PI;          // Lambertian: L = rho E / pi\n"
    "    oColor = vec4(tonemap(luminance, uExposure), 1.0);\n"
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

static const char *const PROBE_FS =
    "uniform vec3 uProbe;\n"
    "layout(location = 0) out float oLux;\n"
    "void main() {\n"
    "    oLux = illuminance(uProbe, vec3(0.0, 1.0, 0.0));\n"
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

static GLuint make_program(const char *vs_body, const char *fs_body, bool lighting, const char *name) {
    const char *vs_parts[] = {GLSL_VERSION, vs_body};
    const char *fs_lit[] = {GLSL_VERSION, GLSL_LIGHTING, GLSL_TONEMAP, fs_body};
    const char *fs_plain[] = {GLSL_VERSION, GLSL_TONEMAP, fs_body};
    GLuint vs = compile(GL_VERTEX_SHADER, vs_parts, 2, name);
    GLuint fs = lighting ? compile(GL_FRAGMENT_SHADER, fs_lit, 4, name) : compile(GL_FRAGMENT_SHADER, fs_plain, 3, name);
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

/* Sets the lighting uniforms of a program that includes GLSL_LIGHTING. */
static bool set_lighting_uniforms(const scene *s, GLuint program, uint32_t lut_w, uint32_t lut_h) {
    GLint lut, size, w2l, pos;
    if (!uniform(program, "uLut", &lut) || !uniform(program, "uLutSize", &size) ||
        !uniform(program, "uWorldToLum", &w2l) || !uniform(program, "uLumPos", &pos))
        return false;
    glProgramUniform1i(program, lut, 0);
    glProgramUniform2f(program, size, (float)lut_w, (float)lut_h);
    glProgramUniformMatrix3fv(program, w2l, 1, GL_FALSE, s->world_to_lum);
    glProgramUniform3f(program, pos, (float)s->luminaire_pos.x, (float)s->luminaire_pos.y,
                       (float)s->luminaire_pos.z);
    return true;
}

/* ---- Geometry ------------------------------------------------------------------------------ */

static void add_box(scene *s, lv_vec3 mn, lv_vec3 mx, float r, float g, float b, const char *name, bool inward) {
    if (s->box_count >= SCENE_MAX_BOXES) return;
    scene_box *bx = &s->boxes[s->box_count++];
    bx->min = mn;
    bx->max = mx;
    bx->albedo[0] = r;
    bx->albedo[1] = g;
    bx->albedo[2] = b;
    bx->name = name;
    bx->inward = inward;
}

/* A box given in the luminaire frame, placed in the world with the model matrix (the host's model
 * only permutes axes and translates, so the world box stays axis-aligned). */
static void add_luminaire_box(scene *s, lv_vec3 lmin, lv_vec3 lmax, float albedo, const char *name) {
    lv_vec3 mn = lv_vec3_make(INFINITY, INFINITY, INFINITY), mx = lv_vec3_make(-INFINITY, -INFINITY, -INFINITY);
    for (int i = 0; i < 8; i++) {
        lv_vec3 c = lv_vec3_make(i & 1 ? lmax.x : lmin.x, i & 2 ? lmax.y : lmin.y, i & 4 ? lmax.z : lmin.z), w;
        lv_mat4_transform_point(s->model, c, &w);
        mn = lv_vec3_make(fmin(mn.x, w.x), fmin(mn.y, w.y), fmin(mn.z, w.z));
        mx = lv_vec3_make(fmax(mx.x, w.x), fmax(mx.y, w.y), fmax(mx.z, w.z));
    }
    add_box(s, mn, mx, albedo, albedo, albedo, name, false);
}

static double axis_of(lv_vec3 v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

static lv_vec3 with_axis(lv_vec3 v, int a, double x) {
    if (a == 0) v.x = x;
    else if (a == 1) v.y = x;
    else v.z = x;
    return v;
}

/* 9 floats per vertex: position, normal, albedo; 36 vertices per box. */
static size_t box_vertices(const scene_box *b, float *out) {
    size_t n = 0;
    for (int a = 0; a < 3; a++) {
        for (int side = 0; side < 2; side++) {
            double sign = side ? 1.0 : -1.0;
            double plane = side ? axis_of(b->max, a) : axis_of(b->min, a);
            int u = (a + 1) % 3, v = (a + 2) % 3;
            lv_vec3 q[4];
            for (int k = 0; k < 4; k++) {
                lv_vec3 p = with_axis(lv_vec3_make(0, 0, 0), a, plane);
                p = with_axis(p, u, (k == 1 || k == 2) ? axis_of(b->max, u) : axis_of(b->min, u));
                p = with_axis(p, v, (k >= 2) ? axis_of(b->max, v) : axis_of(b->min, v));
                q[k] = p;
            }
            lv_vec3 nrm = with_axis(lv_vec3_make(0, 0, 0), a, b->inward ? -sign : sign);
            static const int idx[6] = {0, 1, 2, 0, 2, 3};
            for (int k = 0; k < 6; k++) {
                float *o = out + n * 9;
                o[0] = (float)q[idx[k]].x;
                o[1] = (float)q[idx[k]].y;
                o[2] = (float)q[idx[k]].z;
                o[3] = (float)nrm.x;
                o[4] = (float)nrm.y;
                o[5] = (float)nrm.z;
                o[6] = b->albedo[0];
                o[7] = b->albedo[1];
                o[8] = b->albedo[2];
                n++;
            }
        }
    }
    return n;
}

static void build_boxes(scene *s, const lumi_luminaire_info *info, bool occluder, bool nearfield_stand) {
    const double h = ROOM_HALF_M, ceiling = ROOM_HEIGHT_M;
    const float rho = (float)ROOM_REFLECTANCE;
    add_box(s, lv_vec3_make(-h, 0, -h), lv_vec3_make(h, ceiling, h), rho, rho, rho, "room", true);
    /* A table beside the luminaire: top 1.2 × 0.8 m at 0.75 m, four legs. */
    double tx = -1.4, tz = -0.9;
    add_box(s, lv_vec3_make(tx - 0.6, 0.71, tz - 0.4), lv_vec3_make(tx + 0.6, 0.75, tz + 0.4), 0.45f, 0.36f, 0.28f,
            "table", false);
    for (int i = 0; i < 4; i++) {
        double lx = tx + (i & 1 ? 0.52 : -0.52), lz = tz + (i & 2 ? 0.32 : -0.32);
        add_box(s, lv_vec3_make(lx - 0.03, 0, lz - 0.03), lv_vec3_make(lx + 0.03, 0.71, lz + 0.03), 0.3f, 0.3f,
                0.3f, "table leg", false);
    }
    /* The occluder: a tall cabinet on the line of sight of the test view (README: camera
     * 2.2,1.4,2.2 looking at the luminaire). */
    if (occluder)
        add_box(s, lv_vec3_make(0.8, 0, 0.8), lv_vec3_make(1.4, 2.2, 1.4), 0.55f, 0.42f, 0.30f, "cabinet", false);
    /* The near-field luminaire's stand: a pole behind its panel (whose back plane is 50 mm behind the
     * front tiles, and which spans ±0.1 m around its centre) from the floor to its centre, on a base. */
    if (nearfield_stand) {
        double yaw = NEARFIELD_YAW_DEG * LV_PI_DEG;
        double px = NEARFIELD_X - 0.09 * sin(yaw), pz = NEARFIELD_Z - 0.09 * cos(yaw);
        add_box(s, lv_vec3_make(px - 0.015, 0.02, pz - 0.015), lv_vec3_make(px + 0.015, NEARFIELD_Y, pz + 0.015),
                0.25f, 0.25f, 0.27f, "stand", false);
        add_box(s, lv_vec3_make(px - 0.15, 0, pz - 0.15), lv_vec3_make(px + 0.15, 0.02, pz + 0.15), 0.25f, 0.25f,
                0.27f, "stand base", false);
    }
    /* The luminaire's housing just above its opening (z = 0 in its frame), and two suspension rods. */
    double l = info->opening_size_m[0], w = info->opening_size_m[1], hh = 0.05;
    if (info->housing_size_m[0] > 0 && info->housing_size_m[1] > 0 && info->housing_size_m[2] > 0) {
        l = fmax(l, info->housing_size_m[0]);
        w = fmax(w, info->housing_size_m[1]);
        hh = info->housing_size_m[2];
    }
    if (l < 0.02) l = 0.02;
    if (w < 0.02) w = 0.02;
    double z0 = fmax(info->opening_size_m[2] * 0.5, 0.0) + 0.003;
    add_luminaire_box(s, lv_vec3_make(-l / 2, -w / 2, z0), lv_vec3_make(l / 2, w / 2, z0 + hh), 0.2f, "housing");
    double top = z0 + hh, to_ceiling = ceiling - LUMINAIRE_Y;
    if (to_ceiling > top) {
        for (int i = 0; i < 2; i++) {
            double y = (i ? 1 : -1) * (w / 2 > 0.1 ? w / 2 - 0.05 : 0.0);
            add_luminaire_box(s, lv_vec3_make(-0.005, y - 0.005, top), lv_vec3_make(0.005, y + 0.005, to_ceiling),
                              0.2f, "suspension");
        }
    }
}

/* ---- Public -------------------------------------------------------------------------------- */

void scene_luminaire_model(float m[16]) {
    memset(m, 0, 16 * sizeof(float));
    m[0] = 1.0f;  /* luminaire +X (C0)    → world +X */
    m[6] = -1.0f; /* luminaire +Y (C90)   → world −Z */
    m[9] = 1.0f;  /* luminaire +Z (zenith) → world +Y; nadir → world −Y */
    m[12] = (float)LUMINAIRE_X;
    m[13] = (float)LUMINAIRE_Y;
    m[14] = (float)LUMINAIRE_Z;
    m[15] = 1.0f;
}

void scene_nearfield_model(float m[16]) {
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

bool scene_create(scene *s, const float model[16], const lumi_luminaire_info *info, const float *lut,
                  uint32_t lut_w, uint32_t lut_h, bool occluder, bool indirect, bool nearfield_stand) {
    memset(s, 0, sizeof *s);
    memcpy(s->model, model, sizeof s->model);
    float inv[16];
    if (!lv_mat4_invert(inv, model)) {
        fprintf(stderr, "glfw_host: the luminaire's model matrix is singular\n");
        return false;
    }
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) s->world_to_lum[c * 3 + r] = inv[c * 4 + r];
    s->luminaire_pos = lv_vec3_make(model[12], model[13], model[14]);
    for (int i = 0; i < 3; i++) s->opening_m[i] = info->opening_size_m[i];
    double area = 2.0 * (2 * ROOM_HALF_M) * (2 * ROOM_HALF_M) + 4.0 * (2 * ROOM_HALF_M) * ROOM_HEIGHT_M;
    s->indirect_lux = indirect ? info->flux_lm * ROOM_REFLECTANCE / (area * (1.0 - ROOM_REFLECTANCE)) : 0.0;

    build_boxes(s, info, occluder, nearfield_stand);
    size_t max_vertices = (size_t)s->box_count * 36;
    float *v = malloc(max_vertices * 9 * sizeof(float));
    if (!v) {
        fprintf(stderr, "glfw_host: out of memory\n");
        return false;
    }
    size_t n = 0;
    for (int i = 0; i < s->box_count; i++) n += box_vertices(&s->boxes[i], v + n * 9);
    s->vertex_count = (GLsizei)n;
    glCreateBuffers(1, &s->vbo);
    glNamedBufferStorage(s->vbo, (GLsizeiptr)(n * 9 * sizeof(float)), v, 0);
    free(v);
    glCreateVertexArrays(1, &s->vao);
    glVertexArrayVertexBuffer(s->vao, 0, s->vbo, 0, 9 * sizeof(float));
    for (GLuint a = 0; a < 3; a++) {
        glEnableVertexArrayAttrib(s->vao, a);
        glVertexArrayAttribFormat(s->vao, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
        glVertexArrayAttribBinding(s->vao, a, 0);
    }
    glCreateVertexArrays(1, &s->empty_vao);

    /* The look-up table: LINEAR, REPEAT in C, CLAMP_TO_EDGE in γ, one level (docs/lut-and-solid.md). */
    glCreateTextures(GL_TEXTURE_2D, 1, &s->lut_texture);
    glTextureStorage2D(s->lut_texture, 1, GL_R32F, (GLsizei)lut_w, (GLsizei)lut_h);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(s->lut_texture, 0, 0, 0, (GLsizei)lut_w, (GLsizei)lut_h, GL_RED, GL_FLOAT, lut);
    glTextureParameteri(s->lut_texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(s->lut_texture, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(s->lut_texture, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(s->lut_texture, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

    /* The probe target: 1×1 R32F. */
    glCreateTextures(GL_TEXTURE_2D, 1, &s->probe_texture);
    glTextureStorage2D(s->probe_texture, 1, GL_R32F, 1, 1);
    glCreateFramebuffers(1, &s->probe_fbo);
    glNamedFramebufferTexture(s->probe_fbo, GL_COLOR_ATTACHMENT0, s->probe_texture, 0);
    if (glCheckNamedFramebufferStatus(s->probe_fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        fprintf(stderr, "glfw_host: the 1x1 R32F probe framebuffer is incomplete\n");
        return false;
    }

    s->room_program = make_program(ROOM_VS, ROOM_FS, true, "room shader");
    s->composite_program = make_program(FULLSCREEN_VS, COMPOSITE_FS, false, "composite shader");
    s->probe_program = make_program(FULLSCREEN_VS, PROBE_FS, true, "probe shader");
    if (!s->room_program || !s->composite_program || !s->probe_program) return false;
    if (!set_lighting_uniforms(s, s->room_program, lut_w, lut_h) ||
        !set_lighting_uniforms(s, s->probe_program, lut_w, lut_h) ||
        !uniform(s->room_program, "uViewProj", &s->room_view_proj) ||
        !uniform(s->room_program, "uExposure", &s->room_exposure) ||
        !uniform(s->room_program, "uIndirect", &s->room_indirect) ||
        !uniform(s->composite_program, "uExposure", &s->composite_exposure) ||
        !uniform(s->probe_program, "uProbe", &s->probe_point))
        return false;
    glProgramUniform1f(s->room_program, s->room_indirect, (float)s->indirect_lux);
    return lv_gl_ok("creating the scene");
}

void scene_destroy(scene *s) {
    if (s->room_program) glDeleteProgram(s->room_program);
    if (s->composite_program) glDeleteProgram(s->composite_program);
    if (s->probe_program) glDeleteProgram(s->probe_program);
    if (s->probe_fbo) glDeleteFramebuffers(1, &s->probe_fbo);
    if (s->probe_texture) glDeleteTextures(1, &s->probe_texture);
    if (s->lut_texture) glDeleteTextures(1, &s->lut_texture);
    if (s->vao) glDeleteVertexArrays(1, &s->vao);
    if (s->empty_vao) glDeleteVertexArrays(1, &s->empty_vao);
    if (s->vbo) glDeleteBuffers(1, &s->vbo);
    memset(s, 0, sizeof *s);
}

void scene_draw_room(const scene *s, const float view[16], const float projection[16], float exposure) {
    float vp[16];
    lv_mat4_mul(vp, projection, view);
    glProgramUniformMatrix4fv(s->room_program, s->room_view_proj, 1, GL_FALSE, vp);
    glProgramUniform1f(s->room_program, s->room_exposure, exposure);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glUseProgram(s->room_program);
    glBindTextureUnit(0, s->lut_texture);
    glBindVertexArray(s->vao);
    glDrawArrays(GL_TRIANGLES, 0, s->vertex_count);
}

void scene_composite(const scene *s, GLuint color, GLuint depth, float exposure) {
    glProgramUniform1f(s->composite_program, s->composite_exposure, exposure);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glUseProgram(s->composite_program);
    glBindTextureUnit(1, color);
    glBindTextureUnit(2, depth);
    glBindVertexArray(s->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
}

bool scene_probe(const scene *s, lv_vec3 p, double *lux) {
    glProgramUniform3f(s->probe_program, s->probe_point, (float)p.x, (float)p.y, (float)p.z);
    glBindFramebuffer(GL_FRAMEBUFFER, s->probe_fbo);
    glViewport(0, 0, 1, 1);
    glDisable(GL_DEPTH_TEST);
    glUseProgram(s->probe_program);
    glBindTextureUnit(0, s->lut_texture);
    glBindVertexArray(s->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    float value = -1.0f;
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, 1, 1, GL_RED, GL_FLOAT, &value);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!lv_gl_ok("probe pass")) return false;
    *lux = value;
    return true;
}

/* Slab test. Outward boxes: the entry face (t > 0); inward ones (the room): the exit face. */
static bool ray_box(lv_vec3 o, lv_vec3 d, const scene_box *b, double *t_hit, lv_vec3 *normal) {
    double tmin = -INFINITY, tmax = INFINITY;
    int amin = -1, amax = -1;
    double smin = 0, smax = 0;
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
            smin = da > 0 ? -1.0 : 1.0;
        }
        if (tf < tmax) {
            tmax = tf;
            amax = a;
            smax = da > 0 ? 1.0 : -1.0;
        }
    }
    if (tmin > tmax) return false;
    if (b->inward) {
        if (tmax <= 0 || amax < 0) return false;
        *t_hit = tmax;
        *normal = with_axis(lv_vec3_make(0, 0, 0), amax, -smax);
    } else {
        if (tmin <= 0 || amin < 0) return false;
        *t_hit = tmin;
        *normal = with_axis(lv_vec3_make(0, 0, 0), amin, smin);
    }
    return true;
}

bool scene_ray_hit(const scene *s, lv_vec3 origin, lv_vec3 dir, double *t, lv_vec3 *normal, const scene_box **box) {
    bool hit = false;
    double best = INFINITY;
    for (int i = 0; i < s->box_count; i++) {
        double th;
        lv_vec3 n;
        if (ray_box(origin, dir, &s->boxes[i], &th, &n) && th < best) {
            best = th;
            *t = th;
            *normal = n;
            *box = &s->boxes[i];
            hit = true;
        }
    }
    return hit;
}
