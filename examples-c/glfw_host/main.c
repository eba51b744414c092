/* lumiview GLFW host: an OpenGL 4.5 application that imports lumiview's images once through
 * GL_EXT_memory_object_fd and, every frame, has lumiview draw a lit room with the host's camera — a
 * glTF scene (lumi_scene_load, default the shipped office) lit by six pendants of a photometric file
 * with shadows and inter-reflection, the pendants' own appearance, and a near-field luminaire (a
 * scan, by default the bundled synthetic two-planes scan, generated on first run, lv_scan.h) on a
 * stand — then draws its own objects in GL (the stand) and composites lumiview's image with them by
 * depth. See examples-c/README.md for the flags and what each check proves.
 *
 * Interactive: drag to orbit, scroll to zoom, +/- exposure, L shadows on/off, I indirect light on/off,
 * S solid overlay, H housing overlay, 1/2/3 near-field selection nearest/idw4/continuous, P near-field
 * proxy on/off (printed and shown in the title), Esc quits. Test mode (any of --frames, --screenshot,
 * --probe, --check-luminaire-pixel, --check-nearfield-pixel): runs N frames (default 1), runs the checks
 * on the last one and exits non-zero if one fails. */
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
#include "host_objects.h"
#include "lumiview.h"
#include "lv_args.h"
#include "lv_lumi.h"
#include "lv_math.h"
#include "lv_scan.h"
#include "room.h"

#ifndef LUMIVIEW_REPO_ROOT
#define LUMIVIEW_REPO_ROOT "."
#endif
#define DEFAULT_FILE LUMIVIEW_REPO_ROOT "/tests/data/misc/arnold-usd_bega_50804K3.ies"
#define DEFAULT_SCENE LUMIVIEW_REPO_ROOT "/assets/scenes/office.glb"
#define MAX_PROBES 16
#define FOVY_DEG 60.0
#define NEAR_M 0.05
#define FAR_M 50.0
/* Degrees the camera orbits per frame in a --frames run (ending at the given view). */
#define ORBIT_STEP_DEG 0.6
/* The default view: from the office's south-west corner across the room towards the cabinet in the
 * north-east corner, the near-field luminaire on its stand by the east wall. */
#define DEFAULT_EYE lv_vec3_make(-2.85, 1.65, 1.9)
#define DEFAULT_TARGET lv_vec3_make(0.8, 1.15, -0.9)
#define DEFAULT_EXPOSURE 0.016

typedef struct options {
    const char *file, *scene;
    const char *scan;  /* NULL: the bundled scan; "none": no near-field luminaire */
    const char *proxy; /* NULL: the bundled scan's proxy (or none for another scan); "none": no proxy */
    uint32_t nf_mode;
    bool nf_proxy, check_nearfield;
    const char *screenshot;
    const char *press; /* keys pressed by the test, one per frame from the first (NULL: none) */
    long frames; /* 0: interactive */
    int probe_count;
    lv_vec3 probes[MAX_PROBES];
    double probe_rgb[MAX_PROBES][3];
    double next_probe_rgb[3];
    bool has_camera, has_target, occluder, shadows, indirect, check_pixel, validation, test_uuid_mismatch;
    long bounce_photons;
    lv_vec3 camera, target;
    long check_x, check_y;
    double exposure;
    long width, height;
    bool color32;
    uint32_t overlays;
} options;

/* Mutable state the GLFW callbacks touch. */
typedef struct app {
    double yaw_deg, pitch_deg, distance;
    lv_vec3 target;
    double exposure;
    uint32_t overlays;
    uint32_t nf_mode;
    bool nf_proxy, nf_dirty;
    bool shadows, indirect, lighting_dirty;
    bool dragging;
    double last_x, last_y;
} app;

static void usage(FILE *f) {
    fprintf(f,
            "usage: glfw_host [options]\n"
            "  --scene PATH                 the room: a glTF scene in metres, +Y up (default %s)\n"
            "  --file PATH                  IES or EULUMDAT file of the six pendants (default %s)\n"
            "  --shadows on|off             shadow maps in lumiview's room (default on; key L)\n"
            "  --indirect on|off            inter-reflection in lumiview's room (default on; key I)\n"
            "  --bounce-photons N           photons for the inter-reflection, 1..65536 (default: the library's, 256)\n"
            "  --scan PATH|none             near-field scan: .lvpack, JSON manifest or TM-25 ray file (default: the\n"
            "                               bundled two-planes scan, generated on first run); none: no near-field luminaire\n"
            "  --scan-proxy PATH|none       its proxy glTF (default: the bundled scan's; none for another scan)\n"
            "  --nearfield-mode nearest|idw4|continuous  near-field camera selection at start (default continuous; keys 1/2/3)\n"
            "  --nearfield-proxy on|off     use the proxy at start (default on; key P)\n"
            "  --check-nearfield-pixel      the near-field luminaire's centre pixel vs its scan's ground truth\n"
            "  --frames N                   run N frames, the camera orbiting %.1f° per frame (clockwise seen from above)\n"
            "                               and arriving at the given view on the last, then exit\n"
            "  --screenshot PATH            write the last frame as PNG\n"
            "  --press KEYS                 press these keys, one per frame from the first (of L I S H P 1 2 3 + -;\n"
            "                               tests the key paths: a state printed, then the checks on the last frame)\n"
            "  --probe X,Y,Z                illuminance at a point on an upward-facing surface the view sees: the\n"
            "                               rendered pixel vs lumi_scene_illuminance (repeatable)\n"
            "  --probe-reflectance R,G,B    linear RGB base colour of the surface of the probes that follow\n"
            "                               (default the office floor, 0.25,0.19,0.14)\n"
            "  --check-luminaire-pixel X,Y  pixel (from the top-left) on a pendant's photometric centre vs prediction\n"
            "  --camera X,Y,Z --target X,Y,Z  fix the view (world metres, Y up)\n"
            "  --occluder on|off            a column the host draws on the test view's line of sight (default off)\n"
            "  --exposure E                 tone-mapping exposure, m^2/cd (default %g)\n"
            "  --size WxH                   framebuffer size (default 801x601)\n"
            "  --color-format rgba16f|rgba32f  lumiview's colour target (default rgba16f)\n"
            "  --overlays none|solid|housing|both  lumiview's overlays at start (keys S and H toggle them)\n"
            "  --validation                 Vulkan validation in lumiview; any message fails\n"
            "  --test-uuid-mismatch         test the refusal: pretend GL's device UUID differs (exits 1)\n",
            DEFAULT_SCENE, DEFAULT_FILE, ORBIT_STEP_DEG, DEFAULT_EXPOSURE);
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

/* "r,g,b" in 0…1 with a luminance-weighted reflectance above 0. */
static bool parse_reflectance(const char *s, double rgb[3]) {
    lv_vec3 v;
    if (!lv_parse_vec3(s, &v)) return false;
    rgb[0] = v.x;
    rgb[1] = v.y;
    rgb[2] = v.z;
    for (int k = 0; k < 3; k++)
        if (!(rgb[k] >= 0.0 && rgb[k] <= 1.0)) return false;
    return room_reflectance_y(rgb) > 0.0;
}

/* 0: go on; 1: --help printed; 2: usage error. */
static int parse_args(int argc, char **argv, options *o) {
    memset(o, 0, sizeof *o);
    o->file = DEFAULT_FILE;
    o->scene = DEFAULT_SCENE;
    o->nf_mode = LUMI_SELECTION_CONTINUOUS;
    o->nf_proxy = true;
    o->shadows = true;
    o->indirect = true;
    o->bounce_photons = (long)lumi_scene_settings_default().bounce_photons;
    o->exposure = DEFAULT_EXPOSURE;
    o->width = 801;
    o->height = 601;
    for (int k = 0; k < 3; k++) o->next_probe_rgb[k] = ROOM_FLOOR_RGB[k];
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
        } else if (strcmp(a, "--scene") == 0) {
            o->scene = v;
        } else if (strcmp(a, "--shadows") == 0) {
            bad = !parse_on_off(v, &o->shadows);
        } else if (strcmp(a, "--indirect") == 0) {
            bad = !parse_on_off(v, &o->indirect);
        } else if (strcmp(a, "--bounce-photons") == 0) {
            bad = !lv_parse_int(v, 1, 65536, &o->bounce_photons);
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
        } else if (strcmp(a, "--press") == 0) {
            o->press = v;
            bad = strspn(v, "LISHP123+-") != strlen(v);
            test_mode = true;
        } else if (strcmp(a, "--probe") == 0) {
            bad = o->probe_count >= MAX_PROBES || !lv_parse_vec3(v, &o->probes[o->probe_count]);
            if (!bad) memcpy(o->probe_rgb[o->probe_count], o->next_probe_rgb, sizeof o->next_probe_rgb);
            o->probe_count++;
            test_mode = true;
        } else if (strcmp(a, "--probe-reflectance") == 0) {
            bad = !parse_reflectance(v, o->next_probe_rgb);
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
        } else if (strcmp(a, "--exposure") == 0) {
            bad = !lv_parse_double(v, &o->exposure) || !(o->exposure > 0.0);
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
    if (o->press && (long)strlen(o->press) > o->frames) {
        fprintf(stderr, "glfw_host: --press %s needs --frames %zu or more (one key per frame)\n", o->press,
                strlen(o->press));
        return 2;
    }
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

/* Whether a point is inside the office, ROOM_MARGIN_M from its surfaces. */
#define ROOM_MARGIN_M 0.05
static bool in_room(lv_vec3 p) {
    return p.x >= ROOM_MIN_X + ROOM_MARGIN_M && p.x <= ROOM_MAX_X - ROOM_MARGIN_M && p.z >= ROOM_MIN_Z + ROOM_MARGIN_M &&
           p.z <= ROOM_MAX_Z - ROOM_MARGIN_M && p.y >= ROOM_MARGIN_M && p.y <= ROOM_HEIGHT_M - ROOM_MARGIN_M;
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
    case GLFW_KEY_KP_ADD: a->exposure *= 1.25; break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT: a->exposure /= 1.25; break;
    case GLFW_KEY_L:
        if (action == GLFW_PRESS) {
            a->shadows = !a->shadows;
            a->lighting_dirty = true;
        }
        break;
    case GLFW_KEY_I:
        if (action == GLFW_PRESS) {
            a->indirect = !a->indirect;
            a->lighting_dirty = true;
        }
        break;
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

/* The GLFW key of a --press character. */
static int press_key(char c) {
    switch (c) {
    case 'L': return GLFW_KEY_L;
    case 'I': return GLFW_KEY_I;
    case 'S': return GLFW_KEY_S;
    case 'H': return GLFW_KEY_H;
    case 'P': return GLFW_KEY_P;
    case '1': return GLFW_KEY_1;
    case '2': return GLFW_KEY_2;
    case '3': return GLFW_KEY_3;
    case '+': return GLFW_KEY_EQUAL;
    default: return GLFW_KEY_MINUS;
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
    lumi_luminaire nf_lum = 0;
    lumi_instance nf_inst = 0;
    lumi_target target = 0;
    room rm;
    memset(&rm, 0, sizeof rm);
    float nf_model[16];
    host_nearfield_model(nf_model);
    bool nf_has_proxy = false;
    host_objects ho;
    memset(&ho, 0, sizeof ho);
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

    /* lumiview's room: the scene, the pendants, the lighting switches. */
    if (!room_create(&rm, ctx, o.scene, o.file, o.shadows, o.indirect, (uint32_t)o.bounce_photons)) goto done;
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
               "(%.2f, %.2f, %.2f) on the host's stand, facing yaw %.0f°; selection %s, proxy %s (keys 1/2/3, P)\n",
               scan_path, ni.camera_count, ni.capture_radius_m, ni.has_proxy ? proxy_path : "none",
               ni.gpu_bytes / 1048576.0, NEARFIELD_X, NEARFIELD_Y, NEARFIELD_Z, NEARFIELD_YAW_DEG,
               lv_selection_name(o.nf_mode), o.nf_proxy ? (ni.has_proxy ? "on" : "on (but none loaded)") : "off");
    }
    /* The host's own objects, lit from the library's illuminance in the room. */
    if (!host_objects_create(&ho, o.occluder, nearfield) || !host_objects_light(&ho, &rm, ctx, o.indirect)) goto done;
    printf("host objects: %d box(es) drawn in GL%s%s, lit per face by lumi_scene_illuminance (%s)\n", ho.box_count,
           nearfield ? " (the near-field stand)" : "", o.occluder ? " (the test column)" : "",
           o.indirect ? "total" : "direct");

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
    a.overlays = o.overlays;
    a.nf_mode = o.nf_mode;
    a.nf_proxy = o.nf_proxy;
    a.shadows = o.shadows;
    a.indirect = o.indirect;
    a.target = o.has_target ? o.target : DEFAULT_TARGET;
    lv_vec3 eye0 = o.has_camera ? o.camera : DEFAULT_EYE;
    if (!in_room(eye0) || !in_room(a.target)) {
        fprintf(stderr, "glfw_host: --camera and --target must be inside the room (%.2f < x < %.2f, %.2f < y < %.2f, "
                        "%.2f < z < %.2f)\n", ROOM_MIN_X + ROOM_MARGIN_M, ROOM_MAX_X - ROOM_MARGIN_M, ROOM_MARGIN_M,
                ROOM_HEIGHT_M - ROOM_MARGIN_M, ROOM_MIN_Z + ROOM_MARGIN_M, ROOM_MAX_Z - ROOM_MARGIN_M);
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
        /* A --frames run orbits clockwise (seen from above) and arrives at the given view on its last frame. */
        fv.eye = orbit_eye(&a, o.frames > 1 ? (double)(o.frames - 1 - frame) * ORBIT_STEP_DEG : 0.0);
        fv.width = fb_w;
        fv.height = fb_h;
        fv.exposure = (float)a.exposure;
        fv.half_float = !o.color32;
        if (!lv_mat4_look_at(fv.view, fv.eye, a.target, lv_vec3_make(0, 1, 0))) {
            fprintf(stderr, "glfw_host: degenerate camera (looking straight up or down?)\n");
            failed = true;
            break;
        }
        lv_mat4_perspective_gl(fv.projection, FOVY_DEG, (double)fb_w / fb_h, NEAR_M, FAR_M);

        if (o.press && frame < (long)strlen(o.press)) {
            printf("frame %ld: key %c\n", frame, o.press[frame]);
            on_key(win, press_key(o.press[frame]), 0, GLFW_PRESS, 0);
            fv.exposure = (float)a.exposure;
        }
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
        if (a.lighting_dirty) {
            a.lighting_dirty = false;
            bool relight = rm.indirect != a.indirect;
            rm.shadows = a.shadows;
            rm.indirect = a.indirect;
            if (!room_apply_settings(&rm, ctx) || (relight && !host_objects_light(&ho, &rm, ctx, a.indirect))) {
                failed = true;
                break;
            }
            printf("room: shadows %s, indirect %s\n", a.shadows ? "on" : "off", a.indirect ? "on" : "off");
        }
        /* 1. lumiview renders the lit room and the luminaires with the host's camera (returns after the
         *    GPU is done). */
        lumi_camera cam = lumi_camera_default();
        memcpy(cam.view, fv.view, sizeof cam.view);
        memcpy(cam.projection, fv.projection, sizeof cam.projection);
        cam.depth_range = LUMI_DEPTH_RANGE_NEG_ONE_TO_ONE;
        cam.reversed_z = false;
        cam.origin = LUMI_ORIGIN_BOTTOM_LEFT; /* memory row 0 = bottom row, like GL textures */
        lumi_render_options ro = lumi_render_options_default();
        ro.output = LUMI_OUTPUT_LUMINANCE;
        ro.exposure = fv.exposure;
        ro.overlays = a.overlays;
        if (!lv_lumi_ok(lumi_render(ctx, target, &cam, &ro), "lumi_render")) {
            failed = true;
            break;
        }
        /* 2. The host's own objects, then lumiview's image composited by depth. */
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glViewport(0, 0, fb_w, fb_h);
        glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
        glClearDepth(1.0);
        glDepthMask(GL_TRUE);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        host_objects_draw(&ho, fv.view, fv.projection, fv.exposure);
        host_composite(&ho, color.texture, depth.texture, fv.exposure);
        if (!lv_gl_ok("drawing a frame")) {
            failed = true;
            break;
        }
        /* 3. On the last frame of a test run: the checks and the screenshot (back buffer). */
        if (last) {
            if (o.check_pixel &&
                !check_luminaire_pixel(&rm, &ho, ctx, &color, &depth, &fv, o.check_x, o.check_y))
                failed = true;
            if (o.check_nearfield &&
                !check_nearfield_pixel(&ho, &color, &depth, &fv, nf_model, a.nf_proxy && nf_has_proxy,
                                       lv_selection_name(a.nf_mode)))
                failed = true;
            if (o.screenshot && !write_screenshot(o.screenshot, fb_w, fb_h)) failed = true;
            for (int i = 0; i < o.probe_count; i++)
                if (!check_probe(&rm, ctx, &color, &depth, &fv, o.probes[i], o.probe_rgb[i], a.indirect)) failed = true;
        }
        /* 4. The sync contract: GL's reads of the imported images finish before the next lumi_render. */
        glFinish();
        glfwSwapBuffers(win);
        glfwPollEvents();
        if (!o.frames) {
            char title[224];
            snprintf(title, sizeof title, "lumiview GLFW host - exposure %.3g m2/cd (+/-) - shadows %s (L), indirect %s (I)%s%s%s%s%s",
                     a.exposure, a.shadows ? "on" : "off", a.indirect ? "on" : "off",
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
    if (gl_loaded) {
        glFinish(); /* GL is done with the imported images before lumiview frees its side */
        gl_imported_free(&color);
        gl_imported_free(&depth);
        host_objects_destroy(&ho);
        if (!lv_gl_ok("releasing GL objects")) rc = 1;
    }
    if (ctx) {
        if (target && !lv_lumi_ok(lumi_target_destroy(ctx, target), "lumi_target_destroy")) rc = 1;
        if (!room_destroy(&rm, ctx)) rc = 1;
        if (nf_inst && !lv_lumi_ok(lumi_instance_destroy(ctx, nf_inst), "lumi_instance_destroy (scan)")) rc = 1;
        if (nf_lum && !lv_lumi_ok(lumi_luminaire_destroy(ctx, nf_lum), "lumi_luminaire_destroy (scan)")) rc = 1;
        lumi_context_destroy(ctx);
    }
    if (win) glfwDestroyWindow(win);
    if (glfw_up) glfwTerminate();
    return rc;
}
