/* lumiview GLFW host: an OpenGL 4.5 application that imports lumiview's images once through
 * GL_EXT_memory_object_fd and, every frame, renders the luminaires' appearance with lumiview (the
 * host's camera), draws a room lit by the far-field luminaire's photometry from its look-up table,
 * and composites the two by depth. Besides the far-field luminaire hangs a near-field one: a scan
 * (by default the bundled synthetic two-planes scan, generated on first run, lv_scan.h) on a stand,
 * loaded through the same lumi_luminaire_load_ex call. See examples-c/README.md for the flags and
 * what each check proves.
 *
 * Interactive: drag to orbit, scroll to zoom, +/- exposure, [/] the luminaires' own exposure, S solid
 * overlay, H housing overlay,
 * 1/2/3 near-field selection nearest/idw4/continuous, P near-field proxy on/off (printed and shown in
 * the title), Esc quits. Test mode (any of --frames, --screenshot, --probe, --check-luminaire-pixel,
 * --check-nearfield-pixel): runs N frames (default 1), runs the checks on the last one and exits
 * non-zero if one fails. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gl_api.h" /* before GLFW: GLFW_INCLUDE_NONE keeps GLFW from pulling in system GL headers */
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "checks.h"
#include "gl_interop.h"
#include "lumiview.h"
#include "lv_args.h"
#include "lv_lumi.h"
#include "lv_math.h"
#include "lv_scan.h"
#include "scene.h"

#ifndef LUMIVIEW_REPO_ROOT
#define LUMIVIEW_REPO_ROOT "."
#endif
#define DEFAULT_FILE LUMIVIEW_REPO_ROOT "/tests/data/misc/arnold-usd_bega_50804K3.ies"
#define MAX_PROBES 8
#define FOVY_DEG 60.0
#define NEAR_M 0.05
#define FAR_M 50.0
/* Degrees the camera orbits per frame in a --frames run. */
#define ORBIT_STEP_DEG 0.6
/* The 2D look-up table: 0.5° in C and γ, so the web's nodes (any multiple of 0.5°) are texels. */
#define LUT_W 720u
#define LUT_H 361u

typedef struct options {
    const char *file;
    const char *scan;  /* NULL: the bundled scan; "none": no near-field luminaire */
    const char *proxy; /* NULL: the bundled scan's proxy (or none for another scan); "none": no proxy */
    uint32_t nf_mode;
    bool nf_proxy, check_nearfield;
    const char *screenshot;
    long frames; /* 0: interactive */
    int probe_count;
    lv_vec3 probes[MAX_PROBES];
    bool has_camera, has_target, occluder, indirect, check_pixel, validation, test_uuid_mismatch;
    lv_vec3 camera, target;
    long check_x, check_y;
    double exposure, luminaire_exposure;
    long width, height;
    bool color32;
    uint32_t overlays;
} options;

/* Mutable state the GLFW callbacks touch. */
typedef struct app {
    double yaw_deg, pitch_deg, distance;
    lv_vec3 target;
    double exposure, luminaire_exposure;
    uint32_t overlays;
    uint32_t nf_mode;
    bool nf_proxy, nf_dirty;
    bool dragging;
    double last_x, last_y;
} app;

static void usage(FILE *f) {
    fprintf(f,
            "usage: glfw_host [options]\n"
            "  --file PATH                  IES or EULUMDAT file (default %s)\n"
            "  --scan PATH|none             near-field scan: .lvpack, JSON manifest or TM-25 ray file (default: the\n"
            "                               bundled two-planes scan, generated on first run); none: no near-field luminaire\n"
            "  --scan-proxy PATH|none       its proxy glTF (default: the bundled scan's; none for another scan)\n"
            "  --nearfield-mode nearest|idw4|continuous  near-field camera selection at start (default continuous; keys 1/2/3)\n"
            "  --nearfield-proxy on|off     use the proxy at start (default on; key P)\n"
            "  --check-nearfield-pixel      the near-field luminaire's centre pixel vs its scan's ground truth\n"
            "  --frames N                   run N frames, the camera orbiting %.1f° per frame (clockwise seen from above), then exit\n"
            "  --screenshot PATH            write the last frame as PNG\n"
            "  --probe X,Y,Z                floor illuminance at a world point: shader vs library (repeatable)\n"
            "  --check-luminaire-pixel X,Y  composited pixel (from the top-left) vs prediction\n"
            "  --camera X,Y,Z --target X,Y,Z  fix the view (world metres, Y up)\n"
            "  --occluder on|off            the cabinet between the test view and the luminaire (default on)\n"
            "  --indirect on|off            uniform inter-reflected illuminance (default on)\n"
            "  --exposure E                 tone-mapping exposure, m^2/cd (default 0.02)\n"
            "  --luminaire-exposure E       exposure of lumiview's layer, the luminaires' own luminance (default: --exposure;\n"
            "                               lower shows the pattern of a source far brighter than the room; keys [ and ])\n"
            "  --size WxH                   framebuffer size (default 801x601)\n"
            "  --color-format rgba16f|rgba32f  lumiview's colour target (default rgba16f)\n"
            "  --overlays none|solid|housing|both  lumiview's overlays at start (keys S and H toggle them)\n"
            "  --validation                 Vulkan validation in lumiview; any message fails\n"
            "  --test-uuid-mismatch         test the refusal: pretend GL's device UUID differs (exits 1)\n",
            DEFAULT_FILE, ORBIT_STEP_DEG);
}

static bool parse_on_off(const char *s, bool *out) {
    if (s && strcmp(s, "on") == 0) {
        *out = true;
        return true;
    }
    if (s && strcmp(s, "off") == 0) {
        *out = false;
        return true;
    }
    return false;
}

/* 0: go on; 1: --help printed; 2: usage error. */
static int parse_args(int argc, char **argv, options *o) {
    memset(o, 0, sizeof *o);
    o->file = DEFAULT_FILE;
    o->nf_mode = LUMI_SELECTION_CONTINUOUS;
    o->nf_proxy = true;
    o->occluder = true;
    o->indirect = true;
    o->exposure = 0.02;
    o->width = 801;
    o->height = 601;
    bool test_mode = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        bool bad = false;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 1;
        } else if (strcmp(a, "--validation") == 0) {
            o->validation = true;
            continue;
        } else if (strcmp(a, "--test-uuid-mismatch") == 0) {
            o->test_uuid_mismatch = true;
            continue;
        } else if (strcmp(a, "--check-nearfield-pixel") == 0) {
            o->check_nearfield = true;
            test_mode = true;
            continue;
        } else if (!v) {
            fprintf(stderr, "glfw_host: %s needs a value (or is unknown)\n", a);
            usage(stderr);
            return 2;
        } else if (strcmp(a, "--file") == 0) {
            o->file = v;
        } else if (strcmp(a, "--scan") == 0) {
            o->scan = v;
        } else if (strcmp(a, "--scan-proxy") == 0) {
            o->proxy = v;
        } else if (strcmp(a, "--nearfield-mode") == 0) {
            bad = !lv_parse_selection(v, &o->nf_mode);
        } else if (strcmp(a, "--nearfield-proxy") == 0) {
            bad = !parse_on_off(v, &o->nf_proxy);
        } else if (strcmp(a, "--frames") == 0) {
            bad = !lv_parse_int(v, 1, 1000000, &o->frames);
            test_mode = true;
        } else if (strcmp(a, "--screenshot") == 0) {
            o->screenshot = v;
            test_mode = true;
        } else if (strcmp(a, "--probe") == 0) {
            bad = o->probe_count >= MAX_PROBES || !lv_parse_vec3(v, &o->probes[o->probe_count]);
            o->probe_count++;
            test_mode = true;
        } else if (strcmp(a, "--check-luminaire-pixel") == 0) {
            bad = !lv_parse_xy(v, &o->check_x, &o->check_y);
            o->check_pixel = true;
            test_mode = true;
        } else if (strcmp(a, "--camera") == 0) {
            bad = !lv_parse_vec3(v, &o->camera);
            o->has_camera = true;
        } else if (strcmp(a, "--target") == 0) {
            bad = !lv_parse_vec3(v, &o->target);
            o->has_target = true;
        } else if (strcmp(a, "--occluder") == 0) {
            bad = !parse_on_off(v, &o->occluder);
        } else if (strcmp(a, "--indirect") == 0) {
            bad = !parse_on_off(v, &o->indirect);
        } else if (strcmp(a, "--exposure") == 0) {
            bad = !lv_parse_double(v, &o->exposure) || !(o->exposure > 0.0);
        } else if (strcmp(a, "--luminaire-exposure") == 0) {
            bad = !lv_parse_double(v, &o->luminaire_exposure) || !(o->luminaire_exposure > 0.0);
        } else if (strcmp(a, "--size") == 0) {
            bad = !lv_parse_size(v, &o->width, &o->height);
        } else if (strcmp(a, "--overlays") == 0) {
            o->overlays = 0;
            if (strcmp(v, "solid") == 0) o->overlays = LUMI_OVERLAY_SOLID;
            else if (strcmp(v, "housing") == 0) o->overlays = LUMI_OVERLAY_HOUSING;
            else if (strcmp(v, "both") == 0) o->overlays = LUMI_OVERLAY_SOLID | LUMI_OVERLAY_HOUSING;
            else bad = strcmp(v, "none") != 0;
        } else if (strcmp(a, "--color-format") == 0) {
            bad = strcmp(v, "rgba16f") != 0 && strcmp(v, "rgba32f") != 0;
            o->color32 = strcmp(v, "rgba32f") == 0;
        } else {
            fprintf(stderr, "glfw_host: unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        }
        if (bad) {
            fprintf(stderr, "glfw_host: bad value for %s: '%s'\n", a, v);
            return 2;
        }
        i++;
    }
    if (test_mode && o->frames == 0) o->frames = 1;
    if (o->check_nearfield && o->scan && strcmp(o->scan, "none") == 0) {
        fprintf(stderr, "glfw_host: --check-nearfield-pixel needs the near-field luminaire (not --scan none)\n");
        return 2;
    }
    if (o->check_nearfield && o->scan) {
        fprintf(stderr, "glfw_host: --check-nearfield-pixel knows the ground truth of the bundled scan only\n");
        return 2;
    }
    return 0;
}

/* Whether a point is inside the room, ROOM_MARGIN_M from its surfaces. */
#define ROOM_MARGIN_M 0.05
static bool in_room(lv_vec3 p) {
    double h = ROOM_HALF_M - ROOM_MARGIN_M;
    return fabs(p.x) <= h && fabs(p.z) <= h && p.y >= ROOM_MARGIN_M && p.y <= ROOM_HEIGHT_M - ROOM_MARGIN_M;
}

/* The orbit camera's eye, pulled in along its ray from the target so that it stays in the room. */
static lv_vec3 orbit_eye(const app *a, double yaw_offset_deg) {
    double y = (a->yaw_deg + yaw_offset_deg) * LV_PI_DEG, p = a->pitch_deg * LV_PI_DEG;
    lv_vec3 dir = lv_vec3_make(cos(p) * sin(y), sin(p), cos(p) * cos(y));
    double dist = a->distance;
    while (dist > 0.05 && !in_room(lv_vec3_add(a->target, lv_vec3_scale(dir, dist)))) dist *= 0.98;
    return lv_vec3_add(a->target, lv_vec3_scale(dir, dist));
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods) {
    (void)scancode;
    (void)mods;
    app *a = glfwGetWindowUserPointer(w);
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    switch (key) {
    case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
        a->exposure *= 1.25;
        a->luminaire_exposure *= 1.25;
        break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
        a->exposure /= 1.25;
        a->luminaire_exposure /= 1.25;
        break;
    case GLFW_KEY_RIGHT_BRACKET: a->luminaire_exposure *= 1.25; break;
    case GLFW_KEY_LEFT_BRACKET: a->luminaire_exposure /= 1.25; break;
    case GLFW_KEY_S:
        if (action == GLFW_PRESS) a->overlays ^= LUMI_OVERLAY_SOLID;
        break;
    case GLFW_KEY_H:
        if (action == GLFW_PRESS) a->overlays ^= LUMI_OVERLAY_HOUSING;
        break;
    case GLFW_KEY_1:
    case GLFW_KEY_2:
    case GLFW_KEY_3:
        if (action == GLFW_PRESS) {
            a->nf_mode = key == GLFW_KEY_1 ? LUMI_SELECTION_NEAREST
                         : key == GLFW_KEY_2 ? LUMI_SELECTION_IDW4 : LUMI_SELECTION_CONTINUOUS;
            a->nf_dirty = true;
        }
        break;
    case GLFW_KEY_P:
        if (action == GLFW_PRESS) {
            a->nf_proxy = !a->nf_proxy;
            a->nf_dirty = true;
        }
        break;
    default: break;
    }
}

static void on_button(GLFWwindow *w, int button, int action, int mods) {
    (void)mods;
    app *a = glfwGetWindowUserPointer(w);
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    a->dragging = action == GLFW_PRESS;
    glfwGetCursorPos(w, &a->last_x, &a->last_y);
}

static void on_cursor(GLFWwindow *w, double x, double y) {
    app *a = glfwGetWindowUserPointer(w);
    if (!a->dragging) return;
    a->yaw_deg -= (x - a->last_x) * 0.3;
    a->pitch_deg += (y - a->last_y) * 0.3;
    if (a->pitch_deg > 89.0) a->pitch_deg = 89.0;
    if (a->pitch_deg < -89.0) a->pitch_deg = -89.0;
    a->last_x = x;
    a->last_y = y;
}

static void on_scroll(GLFWwindow *w, double dx, double dy) {
    (void)dx;
    app *a = glfwGetWindowUserPointer(w);
    a->distance *= pow(0.9, dy);
    if (a->distance < 0.3) a->distance = 0.3;
    if (a->distance > 8.0) a->distance = 8.0;
}

static void on_glfw_error(int code, const char *message) {
    fprintf(stderr, "glfw_host: GLFW error 0x%x: %s\n", code, message ? message : "");
}

/* Fetches the 2D look-up table: LUT_W × LUT_H, f32, absolute cd. Caller frees. */
static float *fetch_lut(lumi_context *ctx, lumi_luminaire lum) {
    lumi_lut_desc d = lumi_lut_desc_default();
    d.kind = LUMI_LUT_2D;
    d.width = LUT_W;
    d.height = LUT_H;
    d.normalize = false;
    d.encoding = LUMI_LUT_F32;
    size_t need = 0;
    if (!lv_lumi_ok(lumi_luminaire_lut(ctx, lum, &d, NULL, 0, &need, NULL), "lumi_luminaire_lut (size)"))
        return NULL;
    if (need != (size_t)LUT_W * LUT_H * sizeof(float)) {
        fprintf(stderr, "glfw_host: the look-up table needs %zu bytes, expected %zu\n", need,
                (size_t)LUT_W * LUT_H * sizeof(float));
        return NULL;
    }
    float *lut = malloc(need);
    if (!lut) {
        fprintf(stderr, "glfw_host: out of memory\n");
        return NULL;
    }
    size_t written = 0;
    double max_cd = 0.0;
    if (!lv_lumi_ok(lumi_luminaire_lut(ctx, lum, &d, (uint8_t *)lut, need, &written, &max_cd), "lumi_luminaire_lut")) {
        free(lut);
        return NULL;
    }
    return lut;
}

/* Exports one attachment and imports it into GL (the export's fd is consumed either way). */
static bool import_attachment(lumi_context *ctx, lumi_target target, uint32_t which, gl_imported *out) {
    lumi_export e;
    if (!lv_lumi_ok(lumi_target_export(ctx, target, which, &e), "lumi_target_export")) return false;
    return gl_import(&e, out);
}

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(int argc, char **argv) {
    setvbuf(stdout, NULL, _IOLBF, 0); /* keep stdout and stderr in order in logs */
    options o;
    int pa = parse_args(argc, argv, &o);
    if (pa) return pa == 1 ? 0 : 2;
    /* The near-field scan first: generating it runs the lumiview CLI, before any window or device. */
    bool nearfield = !(o.scan && strcmp(o.scan, "none") == 0);
    lv_scan_files scan_files;
    memset(&scan_files, 0, sizeof scan_files);
    if (nearfield && !o.scan && !lv_scan_ensure(LUMIVIEW_REPO_ROOT, &scan_files)) return 1;
    const char *scan_path = o.scan ? o.scan : scan_files.pack;
    const char *proxy_path = o.proxy ? (strcmp(o.proxy, "none") == 0 ? NULL : o.proxy)
                                     : (o.scan ? NULL : scan_files.proxy);

    int rc = 1;
    GLFWwindow *win = NULL;
    lumi_context *ctx = NULL;
    lumi_luminaire lum = 0, nf_lum = 0;
    lumi_instance inst = 0, nf_inst = 0;
    lumi_target target = 0;
    float *lut = NULL;
    float nf_model[16];
    scene_nearfield_model(nf_model);
    bool nf_has_proxy = false;
    scene sc;
    memset(&sc, 0, sizeof sc);
    gl_imported color, depth;
    memset(&color, 0, sizeof color);
    memset(&depth, 0, sizeof depth);
    bool glfw_up = false, gl_loaded = false;

    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
        fprintf(stderr, "glfw_host: glfwInit failed (no display? run under xvfb-run)\n");
        return 1;
    }
    glfw_up = true;
    glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, GLFW_TRUE);
    glfwWindowHint(GLFW_DEPTH_BITS, 24);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE); /* the target is imported once, at this size */
    win = glfwCreateWindow((int)o.width, (int)o.height, "lumiview GLFW host", NULL, NULL);
    if (!win) {
        fprintf(stderr, "glfw_host: cannot create a %ldx%ld window with an OpenGL 4.5 core context\n", o.width,
                o.height);
        goto done;
    }
    glfwMakeContextCurrent(win);
    glfwSwapInterval(o.frames ? 0 : 1);
    if (!lv_gl_load(glfwGetProcAddress)) goto done;
    gl_loaded = true;
    lv_gl_install_debug_output();
    printf("GL: %s, %s\n", (const char *)glGetString(GL_RENDERER), (const char *)glGetString(GL_VERSION));
    int fb_w = 0, fb_h = 0;
    glfwGetFramebufferSize(win, &fb_w, &fb_h);
    GLint depth_bits = 0;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glGetFramebufferAttachmentParameteriv(GL_FRAMEBUFFER, GL_DEPTH, GL_FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE, &depth_bits);
    if (fb_w <= 0 || fb_h <= 0 || depth_bits < 16) {
        fprintf(stderr, "glfw_host: framebuffer %dx%d with %d depth bits; need a depth buffer\n", fb_w, fb_h,
                depth_bits);
        goto done;
    }

    /* lumiview on the GL context's device. */
    gl_uuids uuids;
    if (!gl_query_uuids(&uuids)) goto done;
    lumi_context_desc desc = lumi_context_desc_default();
    desc.has_device_uuid = true;
    memcpy(desc.device_uuid, uuids.devices[0], 16);
    desc.validation = o.validation;
    desc.log = lv_log_stderr;
    if (!lv_lumi_ok(lumi_context_create(&desc, &ctx), "lumi_context_create")) goto done;
    if (o.test_uuid_mismatch) uuids.devices[0][15] ^= 0xFF; /* as if GL ran on another device */
    lumi_device_caps caps;
    if (!lv_lumi_ok(lumi_context_caps(ctx, &caps), "lumi_context_caps")) goto done;
    if (!caps.external_memory) {
        fprintf(stderr, "glfw_host: lumiview's device (%s) cannot export memory\n", caps.adapter_name);
        goto done;
    }
    if (!gl_uuids_match(&uuids, caps.device_uuid, caps.driver_uuid, "lumiview's Vulkan device")) goto done;
    char uuid_text[37];
    lv_uuid_format(caps.device_uuid, uuid_text);
    printf("lumiview device: %s (deviceUUID %s matches GL)\n", caps.adapter_name, uuid_text);

    if (!lv_lumi_ok(lumi_luminaire_load(ctx, o.file, &lum), "lumi_luminaire_load")) goto done;
    lumi_luminaire_info info;
    if (!lv_lumi_ok(lumi_luminaire_get_info(ctx, lum, &info), "lumi_luminaire_get_info")) goto done;
    float model[16];
    scene_luminaire_model(model);
    if (!lv_lumi_ok(lumi_instance_create(ctx, lum, model, &inst), "lumi_instance_create")) goto done;
    printf("luminaire %s: %.1f lm, max %.1f cd, opening %.3f x %.3f x %.3f m, at (%.2f, %.2f, %.2f) nadir down\n",
           o.file, info.flux_lm, info.max_intensity_cd, info.opening_size_m[0], info.opening_size_m[1],
           info.opening_size_m[2], LUMINAIRE_X, LUMINAIRE_Y, LUMINAIRE_Z);
    lut = fetch_lut(ctx, lum);
    if (!lut) goto done;
    if (nearfield) {
        lumi_luminaire_desc nd = lumi_luminaire_desc_default();
        nd.proxy_path = proxy_path;
        if (!lv_lumi_ok(lumi_luminaire_load_ex(ctx, scan_path, &nd, &nf_lum), "lumi_luminaire_load_ex (scan)"))
            goto done;
        lumi_luminaire_info ni;
        if (!lv_lumi_ok(lumi_luminaire_get_info(ctx, nf_lum, &ni), "lumi_luminaire_get_info (scan)")) goto done;
        if (ni.kind != LUMI_LUMINAIRE_NEARFIELD) {
            fprintf(stderr, "glfw_host: --scan %s is not a near-field scan (a photometric file?)\n", scan_path);
            goto done;
        }
        nf_has_proxy = ni.has_proxy;
        if (!lv_lumi_ok(lumi_instance_create(ctx, nf_lum, nf_model, &nf_inst), "lumi_instance_create (scan)") ||
            !lv_lumi_ok(lumi_instance_set_nearfield(ctx, nf_inst, o.nf_mode, o.nf_proxy), "lumi_instance_set_nearfield"))
            goto done;
        printf("near-field luminaire %s: %u cameras, capture sphere r = %.3f m, proxy %s, %.1f MiB on the GPU; at "
               "(%.2f, %.2f, %.2f) on a stand, facing yaw %.0f°; selection %s, proxy %s (keys 1/2/3, P)\n",
               scan_path, ni.camera_count, ni.capture_radius_m, ni.has_proxy ? proxy_path : "none",
               ni.gpu_bytes / 1048576.0, NEARFIELD_X, NEARFIELD_Y, NEARFIELD_Z, NEARFIELD_YAW_DEG,
               lv_selection_name(o.nf_mode), o.nf_proxy ? (ni.has_proxy ? "on" : "on (but none loaded)") : "off");
    }
    if (!scene_create(&sc, model, &info, lut, LUT_W, LUT_H, o.occluder, o.indirect, nearfield)) goto done;
    free(lut);
    lut = NULL;

    lumi_target_desc td = lumi_target_desc_default();
    td.width = (uint32_t)fb_w;
    td.height = (uint32_t)fb_h;
    td.color_format = o.color32 ? LUMI_COLOR_RGBA32F : LUMI_COLOR_RGBA16F;
    td.depth_format = LUMI_DEPTH_R32F;
    td.exportable = true;
    if (!lv_lumi_ok(lumi_target_create(ctx, &td, &target), "lumi_target_create")) goto done;
    /* Imported once; every frame renders into the same memory. */
    if (!import_attachment(ctx, target, LUMI_ATTACHMENT_COLOR, &color) ||
        !import_attachment(ctx, target, LUMI_ATTACHMENT_DEPTH, &depth))
        goto done;
    printf("imported colour (%s) and depth (R32F) %dx%d through GL_EXT_memory_object_fd\n",
           o.color32 ? "RGBA32F" : "RGBA16F", fb_w, fb_h);

    app a;
    memset(&a, 0, sizeof a);
    a.exposure = o.exposure;
    a.luminaire_exposure = o.luminaire_exposure > 0.0 ? o.luminaire_exposure : o.exposure;
    a.overlays = o.overlays;
    a.nf_mode = o.nf_mode;
    a.nf_proxy = o.nf_proxy;
    a.target = o.has_target ? o.target : lv_vec3_make(0.0, 1.3, 0.0);
    lv_vec3 eye0 = o.has_camera ? o.camera : lv_vec3_make(-1.9, 1.6, 2.1);
    if (!in_room(eye0) || !in_room(a.target)) {
        fprintf(stderr, "glfw_host: --camera and --target must be inside the room (|x|, |z| < %.2f, %.2f < y < %.2f)\n",
                ROOM_HALF_M - ROOM_MARGIN_M, ROOM_MARGIN_M, ROOM_HEIGHT_M - ROOM_MARGIN_M);
        goto done;
    }
    lv_vec3 off = lv_vec3_sub(eye0, a.target);
    a.distance = lv_vec3_length(off);
    if (a.distance < 1e-6) {
        fprintf(stderr, "glfw_host: --camera and --target coincide\n");
        goto done;
    }
    a.pitch_deg = asin(off.y / a.distance) / LV_PI_DEG;
    a.yaw_deg = atan2(off.x, off.z) / LV_PI_DEG;
    glfwSetWindowUserPointer(win, &a);
    glfwSetKeyCallback(win, on_key);
    glfwSetMouseButtonCallback(win, on_button);
    glfwSetCursorPosCallback(win, on_cursor);
    glfwSetScrollCallback(win, on_scroll);

    bool failed = false;
    double t0 = now_s();
    long frame = 0;
    for (;; frame++) {
        if (o.frames ? frame >= o.frames : glfwWindowShouldClose(win)) break;
        bool last = o.frames && frame == o.frames - 1;
        frame_view fv;
        memset(&fv, 0, sizeof fv);
        fv.eye = orbit_eye(&a, o.frames > 1 ? -frame * ORBIT_STEP_DEG : 0.0);
        fv.width = fb_w;
        fv.height = fb_h;
        fv.exposure = (float)a.exposure;
        fv.luminaire_exposure = (float)a.luminaire_exposure;
        fv.half_float = !o.color32;
        if (!lv_mat4_look_at(fv.view, fv.eye, a.target, lv_vec3_make(0, 1, 0))) {
            fprintf(stderr, "glfw_host: degenerate camera (looking straight up or down?)\n");
            failed = true;
            break;
        }
        lv_mat4_perspective_gl(fv.projection, FOVY_DEG, (double)fb_w / fb_h, NEAR_M, FAR_M);

        if (a.nf_dirty) {
            a.nf_dirty = false;
            if (nf_inst) {
                if (!lv_lumi_ok(lumi_instance_set_nearfield(ctx, nf_inst, a.nf_mode, a.nf_proxy),
                                "lumi_instance_set_nearfield")) {
                    failed = true;
                    break;
                }
                printf("near-field: selection %s, proxy %s\n", lv_selection_name(a.nf_mode),
                       a.nf_proxy ? (nf_has_proxy ? "on" : "on (none loaded)") : "off");
            }
        }
        /* 1. lumiview renders the luminaires with the host's camera (returns after the GPU is done). */
        lumi_camera cam = lumi_camera_default();
        memcpy(cam.view, fv.view, sizeof cam.view);
        memcpy(cam.projection, fv.projection, sizeof cam.projection);
        cam.depth_range = LUMI_DEPTH_RANGE_NEG_ONE_TO_ONE;
        cam.reversed_z = false;
        cam.origin = LUMI_ORIGIN_BOTTOM_LEFT; /* memory row 0 = bottom row, like GL textures */
        lumi_render_options ro = lumi_render_options_default();
        ro.output = LUMI_OUTPUT_LUMINANCE;
        ro.exposure = fv.luminaire_exposure;
        ro.overlays = a.overlays;
        if (!lv_lumi_ok(lumi_render(ctx, target, &cam, &ro), "lumi_render")) {
            failed = true;
            break;
        }
        /* 2. The room, then the luminaire composited by depth. */
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glViewport(0, 0, fb_w, fb_h);
        glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
        glClearDepth(1.0);
        glDepthMask(GL_TRUE);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        scene_draw_room(&sc, fv.view, fv.projection, fv.exposure);
        scene_composite(&sc, color.texture, depth.texture, fv.luminaire_exposure);
        if (!lv_gl_ok("drawing a frame")) {
            failed = true;
            break;
        }
        /* 3. On the last frame of a test run: the checks and the screenshot (back buffer). */
        if (last) {
            if (o.check_pixel &&
                !check_luminaire_pixel(&sc, ctx, lum, inst, &color, &depth, &fv, o.check_x, o.check_y))
                failed = true;
            if (o.check_nearfield &&
                !check_nearfield_pixel(&sc, &color, &depth, &fv, nf_model, a.nf_proxy && nf_has_proxy,
                                       lv_selection_name(a.nf_mode)))
                failed = true;
            if (o.screenshot && !write_screenshot(o.screenshot, fb_w, fb_h)) failed = true;
            for (int i = 0; i < o.probe_count; i++)
                if (!check_probe(&sc, ctx, inst, o.probes[i])) failed = true;
        }
        /* 4. The sync contract: GL's reads of the imported images finish before the next lumi_render. */
        glFinish();
        glfwSwapBuffers(win);
        glfwPollEvents();
        if (!o.frames) {
            char title[224];
            snprintf(title, sizeof title, "lumiview GLFW host - exposure %.3g m2/cd, luminaires %.3g (+/-, [/])%s%s%s%s%s",
                     a.exposure, a.luminaire_exposure,
                     a.overlays & LUMI_OVERLAY_SOLID ? " [solid]" : "", a.overlays & LUMI_OVERLAY_HOUSING ? " [housing]" : "",
                     nf_inst ? " - near-field: " : "", nf_inst ? lv_selection_name(a.nf_mode) : "",
                     nf_inst ? (a.nf_proxy && nf_has_proxy ? " + proxy (1/2/3, P)" : ", no proxy (1/2/3, P)") : "");
            glfwSetWindowTitle(win, title);
        }
    }
    double elapsed = now_s() - t0;
    if (frame > 0)
        printf("frames: %ld through one import in %.2f s (%.1f ms per frame, %dx%d)\n", frame, elapsed,
               1000.0 * elapsed / frame, fb_w, fb_h);
    if (o.screenshot && !failed) printf("screenshot: %s\n", o.screenshot);
    if (lv_gl_debug_errors()) {
        fprintf(stderr, "glfw_host: the GL debug output reported %u error(s)\n", lv_gl_debug_errors());
        failed = true;
    }
    if (o.validation && (lv_log_errors() || lv_log_warnings())) {
        fprintf(stderr, "glfw_host: lumiview logged %u error(s) and %u warning(s) with validation on\n",
                lv_log_errors(), lv_log_warnings());
        failed = true;
    }
    rc = failed ? 1 : 0;
    if (o.frames) printf("glfw_host: %s\n", failed ? "FAILED" : "all checks passed");

done:
    free(lut);
    if (gl_loaded) {
        glFinish(); /* GL is done with the imported images before lumiview frees its side */
        gl_imported_free(&color);
        gl_imported_free(&depth);
        scene_destroy(&sc);
        if (!lv_gl_ok("releasing GL objects")) rc = 1;
    }
    if (ctx) {
        if (target && !lv_lumi_ok(lumi_target_destroy(ctx, target), "lumi_target_destroy")) rc = 1;
        if (inst && !lv_lumi_ok(lumi_instance_destroy(ctx, inst), "lumi_instance_destroy")) rc = 1;
        if (lum && !lv_lumi_ok(lumi_luminaire_destroy(ctx, lum), "lumi_luminaire_destroy")) rc = 1;
        if (nf_inst && !lv_lumi_ok(lumi_instance_destroy(ctx, nf_inst), "lumi_instance_destroy (scan)")) rc = 1;
        if (nf_lum && !lv_lumi_ok(lumi_luminaire_destroy(ctx, nf_lum), "lumi_luminaire_destroy (scan)")) rc = 1;
        lumi_context_destroy(ctx);
    }
    if (win) glfwDestroyWindow(win);
    if (glfw_up) glfwTerminate();
    return rc;
}
