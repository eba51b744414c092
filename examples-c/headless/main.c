/* lumiview headless example: render a luminaire's appearance, export the image as an opaque fd,
 * import it into this program's own Vulkan device, and check what came through.
 *
 *   headless [FILE] [--out DIR] [--exposure E] [--validation] [--no-nearfield] [--scene GLTF]
 *
 * For three views from below the luminaire (perspective cameras 3 m from its photometric centre,
 * looking at it; GL depth range, top-left origin) it checks, and exits non-zero if any fails:
 *   1. the imported colour and depth images equal lumi_target_read_pixels byte for byte;
 *   2. the luminance at the centre pixel (whose centre is exactly the image centre, on the
 *      photometric centre) equals the library's own L(C, γ) (lumi_luminaire_sample) within 0.5 %;
 *   3. the depth there equals GL's window depth of the photometric centre within 1e-5;
 *   4. a corner pixel is empty (alpha 0), and two points of the opening projected with the camera's
 *      matrices land on lumiview's image (it registers with the camera, top-left origin).
 * and writes a tone-mapped PNG of each view into DIR.
 *
 * Then the same for a near-field luminaire loaded through the same call: the bundled synthetic
 * `two-planes` scan (generated on first run with the lumiview CLI, cached under target/, with its
 * proxy mesh; lv_scan.h), placed 10 m away. Three views from in front of it (1.5 m, fov 12°) check the
 * import byte for byte, the centre pixel's luminance against the scan's ground truth (the opaque
 * centre tile, 3,000 cd/m², within 1 %), a neighbouring tile's (1,200 cd/m²), the proxy's depth and an
 * empty corner; then each selection mode (LUMI_SELECTION_*) with the proxy, and the bounding mode
 * without it (drawn, stand-in depth through the capture centre).
 *
 * With --scene, last: a glTF scene (metres, +Y up, open floor around x = z = 0, such as
 * assets/scenes/office.glb) with the luminaire hung 2.95 m above that floor point, nadir down. It
 * prints lumi_scene_illuminance (direct, and total with inter-reflection) at three points, and
 * checks that the direct illuminance below the luminaire is I(0, 0)/h² within 3 % (the point
 * formula: what an opening up to 0.6 m adds at 2.95 m is less), that the total is at least the direct
 * light everywhere, and that a render with the scene set draws something lit straight below the
 * camera. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "lumiview.h"
#include "lv_args.h"
#include "lv_lumi.h"
#include "lv_math.h"
#include "lv_png.h"
#include "lv_scan.h"
#include "vk_import.h"

#ifndef LUMIVIEW_REPO_ROOT
#define LUMIVIEW_REPO_ROOT "."
#endif

#define DEFAULT_FILE LUMIVIEW_REPO_ROOT "/tests/data/misc/arnold-usd_bega_50804K3.ies"
/* Odd, so that pixel (128, 128) has its centre exactly at the image centre. */
#define SIZE 257u
#define DISTANCE_M 3.0
#define FOVY_DEG 20.0
#define LUMINANCE_TOLERANCE 0.005
#define DEPTH_TOLERANCE 1e-5

typedef struct view {
    double c_deg, gamma_deg;
} view;

static const view VIEWS[] = {{30.0, 40.0}, {0.0, 0.0}, {90.0, 80.0}};

/* The near-field luminaire: its frame is the world translated by NF_OFFSET (out of the far-field
 * views, which see ±0.5 m around the origin). Its views: 1.5 m from its centre, fov 12° (±0.16 m). */
#define NF_OFFSET_X 10.0
#define NF_DISTANCE_M 1.5
#define NF_FOVY_DEG 12.0
#define NF_TOLERANCE 0.01
/* A point on the front tile i = 3, j = 2 (odd: 1,200 cd/m²), beside the centre tile. */
#define NF_TILE_X_M 0.04
#define NF_TILE_CD_M2 1200.0
/* PNG exposure of the near-field views (m²/cd): 3,000 cd/m² at 0.55. */
#define NF_PNG_EXPOSURE 4e-4

static const view NF_VIEWS[] = {{0.0, 0.0}, {30.0, 40.0}, {200.0, 60.0}};

/* The scene step: the luminaire's photometric centre this high above the floor point (0, 0, 0). */
#define SCENE_HEIGHT_M 2.95
#define SCENE_TOLERANCE 0.03

typedef struct options {
    const char *file;
    const char *out_dir;
    double exposure;
    bool validation;
    bool nearfield;
    const char *scene; /* NULL: no scene step */
} options;

static void usage(FILE *f) {
    fprintf(f,
            "usage: headless [FILE] [--out DIR] [--exposure E] [--validation] [--no-nearfield] [--scene GLTF]\n"
            "  FILE            IES or EULUMDAT file (default %s)\n"
            "  --out DIR       where the PNGs go (default: the current directory)\n"
            "  --exposure E    tone-mapping exposure for the far-field PNGs in m^2/cd (default 1e-4)\n"
            "  --validation    Vulkan validation on lumiview's device and on ours; any message fails\n"
            "  --no-nearfield  skip the near-field luminaire (the bundled two-planes scan)\n"
            "  --scene GLTF    also light a glTF scene (metres, +Y up, open floor around x = z = 0, e.g.\n"
            "                  assets/scenes/office.glb) and print lumi_scene_illuminance in it\n",
            DEFAULT_FILE);
}

/* Returns 0 to go on, 1 after --help, 2 on a usage error. */
static int parse_args(int argc, char **argv, options *o) {
    o->file = DEFAULT_FILE;
    o->out_dir = ".";
    o->exposure = 1e-4;
    o->validation = false;
    o->nearfield = true;
    o->scene = NULL;
    bool have_file = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 1;
        } else if (strcmp(a, "--out") == 0 && next) {
            o->out_dir = next;
            i++;
        } else if (strcmp(a, "--exposure") == 0 && next) {
            if (!lv_parse_double(next, &o->exposure) || o->exposure <= 0.0) {
                fprintf(stderr, "headless: --exposure wants a number > 0, got '%s'\n", next);
                return 2;
            }
            i++;
        } else if (strcmp(a, "--validation") == 0) {
            o->validation = true;
        } else if (strcmp(a, "--no-nearfield") == 0) {
            o->nearfield = false;
        } else if (strcmp(a, "--scene") == 0 && next) {
            o->scene = next;
            i++;
        } else if (a[0] != '-' && !have_file) {
            o->file = a;
            have_file = true;
        } else {
            fprintf(stderr, "headless: unexpected argument '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    return 0;
}

/* Creates `dir` if it does not exist (one level). */
static bool ensure_dir(const char *dir) {
    struct stat st;
    if (stat(dir, &st) == 0) {
        if (S_ISDIR(st.st_mode)) return true;
        fprintf(stderr, "headless: %s exists and is not a directory\n", dir);
        return false;
    }
    if (mkdir(dir, 0777) != 0) {
        fprintf(stderr, "headless: cannot create %s: %s\n", dir, strerror(errno));
        return false;
    }
    return true;
}

/* Camera `distance` m from `centre` along (C, γ) of the luminaire frame (= world axes here), looking
 * at it. */
static bool make_camera_at(const view *v, lv_vec3 centre, double distance, double fovy_deg, lumi_camera *cam,
                           float clip_from_world[16]) {
    lv_vec3 dir = lv_direction_cg(v->c_deg, v->gamma_deg);
    lv_vec3 eye = lv_vec3_add(centre, lv_vec3_scale(dir, distance));
    lv_vec3 up = fabs(dir.z) > 0.99 ? lv_vec3_make(0, 1, 0) : lv_vec3_make(0, 0, 1);
    *cam = lumi_camera_default();
    if (!lv_mat4_look_at(cam->view, eye, centre, up)) {
        fprintf(stderr, "headless: degenerate camera for C %g, γ %g\n", v->c_deg, v->gamma_deg);
        return false;
    }
    lv_mat4_perspective_gl(cam->projection, fovy_deg, 1.0, 0.1, 10.0);
    cam->depth_range = LUMI_DEPTH_RANGE_NEG_ONE_TO_ONE;
    cam->reversed_z = false;
    cam->origin = LUMI_ORIGIN_TOP_LEFT;
    lv_mat4_mul(clip_from_world, cam->projection, cam->view);
    return true;
}

/* Camera 3 m from the origin along (C, γ) of the luminaire frame (= world here), looking at it. */
static bool make_camera(const view *v, lumi_camera *cam, float clip_from_world[16]) {
    return make_camera_at(v, lv_vec3_make(0, 0, 0), DISTANCE_M, FOVY_DEG, cam, clip_from_world);
}

/* Exports one attachment and reads it through the Vulkan host into `out`. */
static bool import_attachment(lumi_context *ctx, lumi_target target, uint32_t which, vk_host *vk, void *out,
                              size_t len) {
    lumi_export e;
    if (!lv_lumi_ok(lumi_target_export(ctx, target, which, &e), "lumi_target_export")) return false;
    if (e.width != SIZE || e.height != SIZE) {
        fprintf(stderr, "headless: exported image is %ux%u, expected %ux%u\n", e.width, e.height, SIZE, SIZE);
        if (e.fd >= 0) close(e.fd);
        return false;
    }
    if (memcmp(e.device_uuid, vk->device_uuid, 16) != 0 || memcmp(e.driver_uuid, vk->driver_uuid, 16) != 0) {
        fprintf(stderr, "headless: the export's device/driver UUIDs differ from the Vulkan host's device\n");
        if (e.fd >= 0) close(e.fd);
        return false;
    }
    return vk_host_read_export(vk, &e, out, len); /* consumes e.fd */
}

/* Reads one attachment with lumi_target_read_pixels and compares it with the import, exactly. */
static bool compare_with_read_back(lumi_context *ctx, lumi_target target, uint32_t which, const uint8_t *imported,
                                   uint8_t *scratch, size_t len, uint32_t texel, const char *name) {
    size_t written = 0;
    if (!lv_lumi_ok(lumi_target_read_pixels(ctx, target, which, scratch, len, &written), "lumi_target_read_pixels"))
        return false;
    if (written != len) {
        fprintf(stderr, "headless: read-back of %s gave %zu bytes, expected %zu\n", name, written, len);
        return false;
    }
    if (memcmp(imported, scratch, len) != 0) {
        size_t i = 0;
        while (i < len && imported[i] == scratch[i]) i++;
        size_t px = i / texel;
        fprintf(stderr, "headless: imported %s differs from lumi_target_read_pixels at byte %zu (pixel %zu, %zu)\n",
                name, i, px % SIZE, px / SIZE);
        return false;
    }
    return true;
}

/* Renders one frame and reads colour and depth through the Vulkan host, checking them against
 * lumi_target_read_pixels byte for byte. */
static bool render_and_import(lumi_context *ctx, lumi_target target, const lumi_camera *cam, vk_host *vk,
                              float *color, float *depth, uint8_t *scratch) {
    lumi_render_options ro = lumi_render_options_default();
    ro.output = LUMI_OUTPUT_LUMINANCE;
    if (!lv_lumi_ok(lumi_render(ctx, target, cam, &ro), "lumi_render")) return false;
    size_t color_len = (size_t)SIZE * SIZE * 16, depth_len = (size_t)SIZE * SIZE * 4;
    if (!import_attachment(ctx, target, LUMI_ATTACHMENT_COLOR, vk, color, color_len) ||
        !import_attachment(ctx, target, LUMI_ATTACHMENT_DEPTH, vk, depth, depth_len))
        return false;
    return compare_with_read_back(ctx, target, LUMI_ATTACHMENT_COLOR, (const uint8_t *)color, scratch, color_len,
                                  16, "colour") &&
           compare_with_read_back(ctx, target, LUMI_ATTACHMENT_DEPTH, (const uint8_t *)depth, scratch, depth_len, 4,
                                  "depth");
}

static bool write_png(const char *path, const float *rgba, double exposure) {
    uint8_t *rgb = malloc((size_t)SIZE * SIZE * 3);
    if (!rgb) {
        fprintf(stderr, "headless: out of memory\n");
        return false;
    }
    for (size_t i = 0; i < (size_t)SIZE * SIZE; i++)
        for (int k = 0; k < 3; k++) rgb[i * 3 + k] = lv_to_u8(lv_tonemap(rgba[i * 4 + k], exposure));
    bool ok = lv_png_write(path, rgb, SIZE, SIZE, 3, (size_t)SIZE * 3); /* memory row 0 = top row */
    free(rgb);
    return ok;
}

/* lumiview's image registers with the camera: at two points of the opening (±35 % along its longer
 * axis from the photometric centre, on its centre line), projected with the camera's matrices and the
 * top-left origin, the alpha must be > 0. Returns the number of points checked (0 for a point
 * opening) or −1 on failure. */
static int check_footprint(const lumi_luminaire_info *info, const float clip_from_world[16], const float *color) {
    double l = info->opening_size_m[0], w = info->opening_size_m[1];
    if (!(l > 0.0) && !(w > 0.0)) return 0;
    for (int k = 0; k < 2; k++) {
        double f = k ? 0.35 : -0.35;
        lv_vec3 p = l >= w ? lv_vec3_make(f * l, 0, 0) : lv_vec3_make(0, f * w, 0), ndc;
        if (!lv_mat4_transform_point(clip_from_world, p, &ndc)) return -1;
        long x = (long)floor((ndc.x * 0.5 + 0.5) * SIZE);
        long y = (long)floor((0.5 - ndc.y * 0.5) * SIZE); /* LUMI_ORIGIN_TOP_LEFT: row 0 is the top */
        if (x < 0 || y < 0 || x >= (long)SIZE || y >= (long)SIZE || !(color[((size_t)y * SIZE + (size_t)x) * 4 + 3] > 0.0f)) {
            fprintf(stderr, "headless: the opening point (%g, %g, 0) projects to pixel %ld,%ld, where lumiview's image is "
                            "empty: the image does not register with the camera (flipped origin?)\n", p.x, p.y, x, y);
            return -1;
        }
    }
    return 2;
}

/* Renders, imports and checks one view. */
static bool run_view(lumi_context *ctx, lumi_luminaire lum, const lumi_luminaire_info *info, lumi_target target,
                     vk_host *vk, const options *o, int index, float *color, float *depth, uint8_t *scratch) {
    const view *v = &VIEWS[index];
    lumi_camera cam;
    float clip_from_world[16];
    if (!make_camera(v, &cam, clip_from_world)) return false;
    if (!render_and_import(ctx, target, &cam, vk, color, depth, scratch)) return false;

    bool ok = true;
    size_t centre = (size_t)(SIZE / 2) * SIZE + SIZE / 2;
    double l_img = color[centre * 4], alpha = color[centre * 4 + 3];
    double l_lib = 0.0;
    if (!lv_lumi_ok(lumi_luminaire_sample(ctx, lum, v->c_deg, v->gamma_deg, NULL, &l_lib), "lumi_luminaire_sample"))
        return false;
    double rel = l_lib > 0.0 ? (l_img - l_lib) / l_lib : INFINITY;
    if (!(l_lib > 0.0) || !(fabs(rel) <= LUMINANCE_TOLERANCE) || alpha != 1.0) {
        fprintf(stderr,
                "headless: view %d (C %g°, γ %g°): centre pixel L = %.6g cd/m² (alpha %g), library L(C, γ) = "
                "%.6g cd/m²: off by more than %.1f %%\n",
                index + 1, v->c_deg, v->gamma_deg, l_img, alpha, l_lib, LUMINANCE_TOLERANCE * 100);
        ok = false;
    }
    /* GL window depth of the photometric centre: (z_ndc + 1) / 2. */
    double origin[4] = {0, 0, 0, 1}, clip[4];
    lv_mat4_transform4(clip_from_world, origin, clip);
    double depth_pred = 0.5 * clip[2] / clip[3] + 0.5, depth_img = depth[centre];
    if (!(fabs(depth_img - depth_pred) <= DEPTH_TOLERANCE)) {
        fprintf(stderr, "headless: view %d: centre depth %.7f, GL window depth of the centre %.7f\n", index + 1,
                depth_img, depth_pred);
        ok = false;
    }
    if (color[3] != 0.0f || depth[0] != 1.0f) {
        fprintf(stderr, "headless: view %d: corner pixel not empty (alpha %g, depth %g)\n", index + 1, color[3],
                depth[0]);
        ok = false;
    }
    int footprint = check_footprint(info, clip_from_world, color);
    if (footprint < 0) ok = false;
    char path[4096];
    int n = snprintf(path, sizeof path, "%s/headless-view%d-c%g-g%g.png", o->out_dir, index + 1, v->c_deg,
                     v->gamma_deg);
    if (n < 0 || (size_t)n >= sizeof path) {
        fprintf(stderr, "headless: output path too long\n");
        return false;
    }
    if (!write_png(path, color, o->exposure)) ok = false;
    printf("view %d (C %5.1f°, γ %4.1f°): centre L = %.6g cd/m², library L(C, γ) = %.6g cd/m² (%+.4f %%); "
           "depth %.6f (predicted %.6f); footprint %d/2; import == read-back (%ux%u RGBA32F + R32F); %s -> %s\n",
           index + 1, v->c_deg, v->gamma_deg, l_img, l_lib, rel * 100.0, depth_img, depth_pred,
           footprint < 0 ? 0 : footprint, SIZE, SIZE, ok ? "ok" : "FAILED", path);
    return ok;
}

/* The pixel (top-left origin) where a world point projects, or false when outside the image. */
static bool pixel_of(const float clip_from_world[16], lv_vec3 p, long *x, long *y) {
    lv_vec3 ndc;
    if (!lv_mat4_transform_point(clip_from_world, p, &ndc)) return false;
    *x = (long)floor((ndc.x * 0.5 + 0.5) * SIZE);
    *y = (long)floor((0.5 - ndc.y * 0.5) * SIZE);
    return *x >= 0 && *y >= 0 && *x < (long)SIZE && *y < (long)SIZE;
}

/* GL window depth of a world point: (z_ndc + 1) / 2. */
static double window_depth(const float clip_from_world[16], lv_vec3 p) {
    double h[4] = {p.x, p.y, p.z, 1.0}, clip[4];
    lv_mat4_transform4(clip_from_world, h, clip);
    return 0.5 * clip[2] / clip[3] + 0.5;
}

static double rel_err(double got, double want) { return want != 0.0 ? (got - want) / want : INFINITY; }

/* One near-field view: renders it in `mode` (proxy on or off), imports it and checks the centre (the
 * scan's ground truth, or with the proxy off that something is drawn at the stand-in depth), the
 * neighbouring tile with the proxy, and an empty corner. `png` NULL writes no image. */
static bool run_nearfield_view(lumi_context *ctx, lumi_instance inst, lumi_target target, vk_host *vk,
                               const options *o, int index, uint32_t mode, bool use_proxy, float *color,
                               float *depth, uint8_t *scratch, bool write_image) {
    const view *v = &NF_VIEWS[index];
    lv_vec3 centre = lv_vec3_make(NF_OFFSET_X, 0, 0);
    lumi_camera cam;
    float clip_from_world[16];
    if (!make_camera_at(v, centre, NF_DISTANCE_M, NF_FOVY_DEG, &cam, clip_from_world)) return false;
    if (!lv_lumi_ok(lumi_instance_set_nearfield(ctx, inst, mode, use_proxy), "lumi_instance_set_nearfield"))
        return false;
    if (!render_and_import(ctx, target, &cam, vk, color, depth, scratch)) return false;

    bool ok = true;
    size_t c = (size_t)(SIZE / 2) * SIZE + SIZE / 2;
    double l = color[c * 4], alpha = color[c * 4 + 3], d = depth[c];
    double d_pred = window_depth(clip_from_world, centre), rel = rel_err(l, LV_SCAN_CENTRE_CD_M2);
    long tx = -1, ty = -1;
    double l_tile = NAN, rel_tile = NAN;
    if (use_proxy) {
        if (!(fabs(rel) <= NF_TOLERANCE) || alpha != 1.0) {
            fprintf(stderr, "headless: near-field view %d (%s, proxy): centre L = %.6g cd/m² (alpha %g), the scan's "
                            "centre tile is %.0f cd/m²: off by more than %.0f %%\n",
                    index + 1, lv_selection_name(mode), l, alpha, LV_SCAN_CENTRE_CD_M2, NF_TOLERANCE * 100);
            ok = false;
        }
        if (!pixel_of(clip_from_world, lv_vec3_make(NF_OFFSET_X + NF_TILE_X_M, 0, 0), &tx, &ty)) {
            fprintf(stderr, "headless: near-field view %d: the neighbouring tile projects outside the image\n",
                    index + 1);
            ok = false;
        } else {
            l_tile = color[((size_t)ty * SIZE + (size_t)tx) * 4];
            rel_tile = rel_err(l_tile, NF_TILE_CD_M2);
            if (!(fabs(rel_tile) <= NF_TOLERANCE)) {
                fprintf(stderr, "headless: near-field view %d (%s, proxy): pixel %ld,%ld on tile (3, 2) shows L = %.6g "
                                "cd/m², the scan's tile is %.0f cd/m² (flipped or misregistered image?)\n",
                        index + 1, lv_selection_name(mode), tx, ty, l_tile, NF_TILE_CD_M2);
                ok = false;
            }
        }
    } else if (!(l > 0.0) || alpha != 1.0) {
        fprintf(stderr, "headless: near-field view %d (%s, no proxy): nothing drawn at the centre (L %g, alpha %g)\n",
                index + 1, lv_selection_name(mode), l, alpha);
        ok = false;
    }
    /* With the proxy: the centre tile's surface (z = 0 through the centre); without: the stand-in plane
     * through the capture centre facing the eye. Both pass through the centre. */
    if (!(fabs(d - d_pred) <= DEPTH_TOLERANCE)) {
        fprintf(stderr, "headless: near-field view %d (%s, proxy %s): centre depth %.7f, GL window depth of the "
                        "centre %.7f\n", index + 1, lv_selection_name(mode), use_proxy ? "on" : "off", d, d_pred);
        ok = false;
    }
    if (color[3] != 0.0f || depth[0] != 1.0f) {
        fprintf(stderr, "headless: near-field view %d: corner pixel not empty (alpha %g, depth %g)\n", index + 1,
                color[3], depth[0]);
        ok = false;
    }
    char path[4096] = "";
    if (write_image) {
        int n = snprintf(path, sizeof path, "%s/headless-nearfield-view%d-c%g-g%g.png", o->out_dir, index + 1,
                         v->c_deg, v->gamma_deg);
        if (n < 0 || (size_t)n >= sizeof path) {
            fprintf(stderr, "headless: output path too long\n");
            return false;
        }
        if (!write_png(path, color, NF_PNG_EXPOSURE)) ok = false;
    }
    if (use_proxy)
        printf("nearfield view %d (C %5.1f°, γ %4.1f°) %-10s proxy on : centre L = %.6g cd/m² (scan %.0f, %+.4f %%), "
               "tile (3, 2) at %ld,%ld L = %.6g (scan %.0f, %+.4f %%); depth %.6f (predicted %.6f); import == "
               "read-back; %s%s%s\n",
               index + 1, v->c_deg, v->gamma_deg, lv_selection_name(mode), l, LV_SCAN_CENTRE_CD_M2, rel * 100.0, tx,
               ty, l_tile, NF_TILE_CD_M2, rel_tile * 100.0, d, d_pred, ok ? "ok" : "FAILED", path[0] ? " -> " : "",
               path);
    else
        printf("nearfield view %d (C %5.1f°, γ %4.1f°) %-10s proxy off: centre L = %.6g cd/m² (drawn; no ground truth "
               "without the proxy: the cameras are sampled along the view direction), stand-in depth %.6f "
               "(predicted %.6f); import == read-back; %s\n",
               index + 1, v->c_deg, v->gamma_deg, lv_selection_name(mode), l, d, d_pred, ok ? "ok" : "FAILED");
    return ok;
}

/* Loads the bundled scan with its proxy, places it and runs the near-field views and mode checks.
 * Returns the number of failures. */
static int run_nearfield(lumi_context *ctx, const lv_scan_files *files, lumi_target target, vk_host *vk,
                         const options *o, float *color, float *depth, uint8_t *scratch) {
    lumi_luminaire lum = 0;
    lumi_instance inst = 0;
    int failed = 0;
    lumi_luminaire_desc d = lumi_luminaire_desc_default();
    d.proxy_path = files->proxy;
    if (!lv_lumi_ok(lumi_luminaire_load_ex(ctx, files->pack, &d, &lum), "lumi_luminaire_load_ex")) return 1;
    lumi_luminaire_info info;
    if (!lv_lumi_ok(lumi_luminaire_get_info(ctx, lum, &info), "lumi_luminaire_get_info")) {
        failed++;
        goto done;
    }
    printf("near-field luminaire %s: kind %s, %u cameras, capture sphere r = %.3f m, content r = %.3f m, proxy %s, "
           "%.1f MiB on the GPU (budget %.0f MiB)\n",
           files->pack, info.kind == LUMI_LUMINAIRE_NEARFIELD ? "LUMI_LUMINAIRE_NEARFIELD" : "far-field?",
           info.camera_count, info.capture_radius_m, info.content_radius_m, info.has_proxy ? files->proxy : "none",
           info.gpu_bytes / 1048576.0, info.budget_bytes / 1048576.0);
    if (info.kind != LUMI_LUMINAIRE_NEARFIELD || !info.has_proxy || info.camera_count == 0) {
        fprintf(stderr, "headless: lumi_luminaire_get_info does not describe the scan as a near-field luminaire with "
                        "a proxy\n");
        failed++;
        goto done;
    }
    /* The far-field calls answer for a scan from the far field estimated from its images (what lights
       a scene): a finite, positive intensity below it. */
    double cd = -1.0;
    if (!lv_lumi_ok(lumi_luminaire_sample(ctx, lum, 0.0, 0.0, &cd, NULL), "lumi_luminaire_sample (near-field)") ||
        !(cd > 0.0 && cd < 1e9)) {
        fprintf(stderr, "headless: lumi_luminaire_sample on a near-field luminaire gave no far-field intensity (%g cd)\n",
                cd);
        failed++;
    } else {
        printf("near-field luminaire: far field estimated from its images, I(C 0, γ 0) = %.2f cd\n", cd);
    }
    float model[16];
    lv_mat4_identity(model);
    model[12] = (float)NF_OFFSET_X;
    if (!lv_lumi_ok(lumi_instance_create(ctx, lum, model, &inst), "lumi_instance_create")) {
        failed++;
        goto done;
    }
    int n = (int)(sizeof NF_VIEWS / sizeof NF_VIEWS[0]);
    for (int i = 0; i < n; i++)
        if (!run_nearfield_view(ctx, inst, target, vk, o, i, LUMI_SELECTION_CONTINUOUS, true, color, depth, scratch,
                                true))
            failed++;
    /* The modes, from view 2 (off-axis). */
    const uint32_t modes[] = {LUMI_SELECTION_NEAREST, LUMI_SELECTION_IDW4};
    for (size_t m = 0; m < sizeof modes / sizeof modes[0]; m++)
        if (!run_nearfield_view(ctx, inst, target, vk, o, 1, modes[m], true, color, depth, scratch, false)) failed++;
    if (!run_nearfield_view(ctx, inst, target, vk, o, 1, LUMI_SELECTION_CONTINUOUS, false, color, depth, scratch,
                            false))
        failed++;
    if (failed == 0) printf("headless: near-field: all %d views and 3 mode checks passed\n", n);

done:
    if (inst && !lv_lumi_ok(lumi_instance_destroy(ctx, inst), "lumi_instance_destroy")) failed++;
    if (lum && !lv_lumi_ok(lumi_luminaire_destroy(ctx, lum), "lumi_luminaire_destroy")) failed++;
    return failed;
}

/* The scene step (see the top of the file): the far-field instance `inst` is hung in the scene for
 * it and put back at the origin afterwards. Returns the number of failures. */
static int run_scene(lumi_context *ctx, lumi_luminaire lum, lumi_instance inst, lumi_target target,
                     const char *path, float *color) {
    lumi_scene scene = 0;
    int failed = 0;
    if (!lv_lumi_ok(lumi_scene_load(ctx, path, &scene), "lumi_scene_load")) return 1;
    /* Luminaire frame → scene: X → +X, Y → −Z, Z → +Y (nadir down), centre SCENE_HEIGHT_M up. */
    const float hung[16] = {1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, (float)SCENE_HEIGHT_M, 0, 1};
    float identity[16];
    lv_mat4_identity(identity);
    if (!lv_lumi_ok(lumi_instance_set_transform(ctx, inst, hung), "lumi_instance_set_transform")) {
        failed++;
        goto done;
    }
    /* The floor below the luminaire, the floor 1.2 m beside it, a work plane point above that. */
    const float points[3][3] = {{0, 0, 0}, {0, 0, 1.2f}, {0, 0.8f, 1.2f}};
    const float normals[3][3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    double direct[3], total[3], total_se[3];
    lumi_illuminance_options opts = lumi_illuminance_options_default();
    opts.light = LUMI_ILLUMINANCE_DIRECT;
    if (!lv_lumi_ok(lumi_scene_illuminance(ctx, scene, &points[0][0], &normals[0][0], 3, &opts, direct, NULL),
                    "lumi_scene_illuminance") ||
        !lv_lumi_ok(lumi_scene_illuminance(ctx, scene, &points[0][0], &normals[0][0], 3, NULL, total, total_se),
                    "lumi_scene_illuminance")) {
        failed++;
        goto done;
    }
    double cd = 0.0;
    if (!lv_lumi_ok(lumi_luminaire_sample(ctx, lum, 0.0, 0.0, &cd, NULL), "lumi_luminaire_sample")) {
        failed++;
        goto done;
    }
    double point_formula = cd / (SCENE_HEIGHT_M * SCENE_HEIGHT_M), rel = rel_err(direct[0], point_formula);
    for (int k = 0; k < 3; k++) {
        printf("scene %s: (%g, %g, %g) m, normal +Y: direct %.2f lx, total %.2f ± %.2f lx\n", path, points[k][0],
               points[k][1], points[k][2], direct[k], total[k], total_se[k]);
        if (!(total[k] >= direct[k])) {
            fprintf(stderr, "headless: scene point %d: total %.6g lx below the direct %.6g lx\n", k, total[k],
                    direct[k]);
            failed++;
        }
    }
    printf("scene: below the luminaire %.2f lx, I(0, 0)/h² = %.2f lx (%+.2f %%)\n", direct[0], point_formula,
           rel * 100.0);
    if (!(fabs(rel) <= SCENE_TOLERANCE)) {
        fprintf(stderr, "headless: scene: the direct illuminance below the luminaire is off I(0, 0)/h² by more than "
                        "%.0f %%\n", SCENE_TOLERANCE * 100);
        failed++;
    }
    /* Drawn: looking straight down from 2 m at the floor point (0, 0, 1.2). */
    lumi_camera cam = lumi_camera_default();
    if (!lv_mat4_look_at(cam.view, lv_vec3_make(0, 2.0, 1.2), lv_vec3_make(0, 0, 1.2), lv_vec3_make(0, 0, -1))) {
        failed++;
        goto done;
    }
    lv_mat4_perspective_gl(cam.projection, 40.0, 1.0, 0.1, 10.0);
    cam.origin = LUMI_ORIGIN_TOP_LEFT;
    size_t written = 0, c = (size_t)(SIZE / 2) * SIZE + SIZE / 2;
    if (!lv_lumi_ok(lumi_context_set_scene(ctx, scene), "lumi_context_set_scene") ||
        !lv_lumi_ok(lumi_render(ctx, target, &cam, NULL), "lumi_render") ||
        !lv_lumi_ok(lumi_target_read_pixels(ctx, target, LUMI_ATTACHMENT_COLOR, (uint8_t *)color,
                                            (size_t)SIZE * SIZE * 16, &written),
                    "lumi_target_read_pixels")) {
        failed++;
        goto done;
    }
    printf("scene drawn: the floor straight below the camera shows RGB (%.3f, %.3f, %.3f) cd/m², alpha %g\n",
           color[c * 4], color[c * 4 + 1], color[c * 4 + 2], color[c * 4 + 3]);
    if (color[c * 4 + 3] != 1.0f || !(color[c * 4 + 1] > 0.0f)) {
        fprintf(stderr, "headless: scene: nothing lit drawn where the floor is\n");
        failed++;
    }
    if (failed == 0) printf("headless: scene: all checks passed\n");

done:
    if (!lv_lumi_ok(lumi_context_set_scene(ctx, 0), "lumi_context_set_scene")) failed++;
    if (!lv_lumi_ok(lumi_instance_set_transform(ctx, inst, identity), "lumi_instance_set_transform")) failed++;
    if (!lv_lumi_ok(lumi_scene_destroy(ctx, scene), "lumi_scene_destroy")) failed++;
    return failed;
}

int main(int argc, char **argv) {
    setvbuf(stdout, NULL, _IOLBF, 0); /* keep stdout and stderr in order in logs */
    options o;
    int pa = parse_args(argc, argv, &o);
    if (pa != 0) return pa == 1 ? 0 : 2;
    if (!ensure_dir(o.out_dir)) return 1;
    /* The near-field scan first: generating it runs the lumiview CLI, before any Vulkan device exists. */
    lv_scan_files scan;
    if (o.nearfield && !lv_scan_ensure(LUMIVIEW_REPO_ROOT, &scan)) return 1;

    int rc = 1;
    lumi_context *ctx = NULL;
    lumi_luminaire lum = 0;
    lumi_instance inst = 0;
    lumi_target target = 0;
    vk_host vk;
    memset(&vk, 0, sizeof vk);
    float *color = malloc((size_t)SIZE * SIZE * 16);
    float *depth = malloc((size_t)SIZE * SIZE * 4);
    uint8_t *scratch = malloc((size_t)SIZE * SIZE * 16);
    if (!color || !depth || !scratch) {
        fprintf(stderr, "headless: out of memory\n");
        goto done;
    }

    printf("lumiview %u.%u.%u (ABI %u)\n", lumi_version() >> 16, (lumi_version() >> 8) & 0xFF,
           lumi_version() & 0xFF, lumi_abi_version());
    lumi_context_desc desc = lumi_context_desc_default();
    desc.validation = o.validation;
    desc.log = lv_log_stderr;
    if (!lv_lumi_ok(lumi_context_create(&desc, &ctx), "lumi_context_create")) goto done;
    lumi_device_caps caps;
    if (!lv_lumi_ok(lumi_context_caps(ctx, &caps), "lumi_context_caps")) goto done;
    char dev_uuid[37], drv_uuid[37];
    lv_uuid_format(caps.device_uuid, dev_uuid);
    lv_uuid_format(caps.driver_uuid, drv_uuid);
    printf("lumiview device: %s (%s), deviceUUID %s, driverUUID %s\n", caps.adapter_name,
           caps.is_cpu ? "software" : "hardware", dev_uuid, drv_uuid);
    if (!caps.external_memory) {
        fprintf(stderr, "headless: the device cannot export memory (VK_KHR_external_memory_fd missing)\n");
        goto done;
    }
    if (!vk_host_create(&vk, caps.device_uuid, caps.driver_uuid, o.validation)) goto done;
    printf("vulkan host: %s, queue family %u\n", vk.device_name, vk.queue_family);

    if (!lv_lumi_ok(lumi_luminaire_load(ctx, o.file, &lum), "lumi_luminaire_load")) goto done;
    lumi_luminaire_info info;
    if (!lv_lumi_ok(lumi_luminaire_get_info(ctx, lum, &info), "lumi_luminaire_get_info")) goto done;
    printf("luminaire %s: %.1f lm, max %.1f cd at C %.1f°, γ %.1f°, opening %.3f x %.3f x %.3f m\n", o.file,
           info.flux_lm, info.max_intensity_cd, info.max_c_deg, info.max_gamma_deg, info.opening_size_m[0],
           info.opening_size_m[1], info.opening_size_m[2]);
    float model[16];
    lv_mat4_identity(model); /* the luminaire frame is the world frame */
    if (!lv_lumi_ok(lumi_instance_create(ctx, lum, model, &inst), "lumi_instance_create")) goto done;
    lumi_target_desc td = lumi_target_desc_default();
    td.width = SIZE;
    td.height = SIZE;
    td.color_format = LUMI_COLOR_RGBA32F;
    td.depth_format = LUMI_DEPTH_R32F;
    td.exportable = true;
    if (!lv_lumi_ok(lumi_target_create(ctx, &td, &target), "lumi_target_create")) goto done;

    int failed = 0;
    for (int i = 0; i < (int)(sizeof VIEWS / sizeof VIEWS[0]); i++)
        if (!run_view(ctx, lum, &info, target, &vk, &o, i, color, depth, scratch)) failed++;
    if (failed == 0) printf("headless: all %d views passed\n", (int)(sizeof VIEWS / sizeof VIEWS[0]));
    if (o.nearfield) failed += run_nearfield(ctx, &scan, target, &vk, &o, color, depth, scratch);
    if (o.scene) failed += run_scene(ctx, lum, inst, target, o.scene, color);
    if (o.validation && (lv_log_errors() || lv_log_warnings() || vk_host_validation_errors())) {
        fprintf(stderr, "headless: validation reported %u lumiview errors, %u warnings, %u Vulkan-host messages\n",
                lv_log_errors(), lv_log_warnings(), vk_host_validation_errors());
        failed++;
    }
    if (failed == 0) {
        printf("headless: all checks passed\n");
        rc = 0;
    } else {
        fprintf(stderr, "headless: FAILED (%d problem%s)\n", failed, failed == 1 ? "" : "s");
    }

done:
    if (ctx) {
        if (target && !lv_lumi_ok(lumi_target_destroy(ctx, target), "lumi_target_destroy")) rc = 1;
        if (inst && !lv_lumi_ok(lumi_instance_destroy(ctx, inst), "lumi_instance_destroy")) rc = 1;
        if (lum && !lv_lumi_ok(lumi_luminaire_destroy(ctx, lum), "lumi_luminaire_destroy")) rc = 1;
        lumi_context_destroy(ctx);
    }
    vk_host_destroy(&vk);
    free(color);
    free(depth);
    free(scratch);
    return rc;
}
