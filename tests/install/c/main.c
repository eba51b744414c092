/* C11 consumer of an installed lumiview through its C API alone, built with
 *
 *   cc -std=c11 main.c $(pkg-config --cflags --libs lumiview) -o c_consumer
 *
 *   c_consumer PHOTOMETRY_FILE      (an IES or EULUMDAT file with a luminous opening)
 *
 * The render check of tests/install/cpp/main.cpp: a context with the defaults; the file loads as a
 * far-field luminaire with flux > 0; one instance (identity model: luminaire frame = world, +Z up,
 * nadir −Z) seen from 2 m straight below (eye (0, 0, −2) looking up at the photometric centre) into
 * a 64 × 64 RGBA32F read-back target; the centre pixel's luminance (R, cd/m²) is finite, > 0 and
 * within 2 % of lumi_luminaire_sample(0, 0), the luminance of the opening seen from straight below
 * (γ 0 = nadir, docs/conventions.md). Also: a missing file is LUMI_STATUS_IO and the last-error text
 * names it. One line per check ending in PASS (or FAIL), exit status non-zero on any failure.
 *
 * No libm: the camera is built without sqrt/tan (its axes are unit vectors already, and the
 * projection takes the focal factor directly), so the pkg-config line alone links it. */
#include <lumiview.h>

#include <math.h> /* isfinite (a macro) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SIZE_PX 64u
#define EYE_DISTANCE_M 2.0
#define LUMINANCE_TOLERANCE 0.02
#define MISSING_FILE "/nonexistent/x.ies"

static int failures = 0;

static void report(const char *check, int ok, const char *detail) {
    printf("%s: %s: %s\n", check, detail, ok ? "PASS" : "FAIL");
    fflush(stdout);
    if (!ok) failures++;
}

/* Prints "<call> failed: <status>: <last error>" and returns 0 unless `status` is OK. */
static int ok_or_report(lumi_status status, const char *call) {
    if (status == LUMI_STATUS_OK) return 1;
    char text[1024];
    lumi_last_error(text, sizeof text);
    fprintf(stderr, "c consumer: %s failed: status %u: %s\n", call, (unsigned)status, text);
    failures++;
    return 0;
}

static double abs_d(double v) { return v < 0.0 ? -v : v; }

/* Right-handed look-at (world → eye, the eye looks down its −Z), like gluLookAt, column-major.
 * `f` is the unit view direction, `up` a unit vector perpendicular to it (no normalisation). */
static void look_at(float out[16], const double eye[3], const double f[3], const double up[3]) {
    double s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
    double u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
    memset(out, 0, 16 * sizeof(float));
    for (int i = 0; i < 3; i++) {
        out[i * 4 + 0] = (float)s[i];
        out[i * 4 + 1] = (float)u[i];
        out[i * 4 + 2] = (float)-f[i];
    }
    out[12] = (float)-(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    out[13] = (float)-(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    out[14] = (float)(f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2]);
    out[15] = 1.0f;
}

/* GL perspective projection (clip z in −w…w), like gluPerspective, from the focal factor
 * focal = 1 / tan(fovy / 2). */
static void perspective_gl(float out[16], double focal, double aspect, double near_m, double far_m) {
    memset(out, 0, 16 * sizeof(float));
    out[0] = (float)(focal / aspect);
    out[5] = (float)focal;
    out[10] = (float)((far_m + near_m) / (near_m - far_m));
    out[11] = -1.0f;
    out[14] = (float)(2.0 * far_m * near_m / (near_m - far_m));
}

/* The little-endian float at byte offset `at` (x86-64 and AArch64 hosts are little-endian). */
static float float_at(const uint8_t *bytes, size_t at) {
    float v;
    memcpy(&v, bytes + at, sizeof v);
    return v;
}

/* Renders into `target` and checks its centre pixel against lumi_luminaire_sample(0, 0). */
static void render_and_check(lumi_context *ctx, lumi_luminaire lum, lumi_target target, double smaller_m) {
    /* Eye 2 m below the photometric centre looking up (+Z); world +Z is up, so the image's up is +Y.
     * The half-height seen at the opening's distance is half its smaller side. */
    lumi_camera cam = lumi_camera_default(); /* GL depth range, bottom-left origin */
    const double eye[3] = {0.0, 0.0, -EYE_DISTANCE_M}, forward[3] = {0.0, 0.0, 1.0}, up[3] = {0.0, 1.0, 0.0};
    look_at(cam.view, eye, forward, up);
    perspective_gl(cam.projection, EYE_DISTANCE_M / (0.5 * smaller_m), 1.0, 0.05, 20.0);
    if (!ok_or_report(lumi_render(ctx, target, &cam, NULL), "lumi_render")) return;

    /* Size query: a NULL buffer; `need` receives the size. */
    size_t need = 0, written = 0;
    if (!ok_or_report(lumi_target_read_pixels(ctx, target, LUMI_ATTACHMENT_COLOR, NULL, 0, &need),
                      "lumi_target_read_pixels (size query)"))
        return;
    uint8_t *px = malloc(need);
    if (!px) {
        report("render", 0, "out of memory");
        return;
    }
    char detail[256];
    size_t expect_bytes = (size_t)SIZE_PX * SIZE_PX * 16;
    double expected = 0.0;
    if (!ok_or_report(lumi_target_read_pixels(ctx, target, LUMI_ATTACHMENT_COLOR, px, need, &written),
                      "lumi_target_read_pixels")) {
        /* reported */
    } else if (written != expect_bytes) {
        snprintf(detail, sizeof detail, "read %zu bytes, expected %zu", written, expect_bytes);
        report("render", 0, detail);
    } else if (ok_or_report(lumi_luminaire_sample(ctx, lum, 0.0, 0.0, NULL, &expected), "lumi_luminaire_sample")) {
        size_t centre = ((size_t)(SIZE_PX / 2) * SIZE_PX + SIZE_PX / 2) * 16;
        double rendered = float_at(px, centre), alpha = float_at(px, centre + 12);
        int ok = isfinite(rendered) && rendered > 0.0 && expected > 0.0 &&
                 abs_d(rendered - expected) <= LUMINANCE_TOLERANCE * expected;
        snprintf(detail, sizeof detail, "L %.6g cd/m2 vs sample(0, 0) %.6g cd/m2 (alpha %.3g)", rendered, expected,
                 alpha);
        report("render centre pixel", ok, detail);
    }
    free(px);
}

/* The render check; see the file comment. The field of view is chosen from the opening so that its
 * smaller side spans the image height (as the C++ consumer does): pixel (32, 32), half a pixel off
 * the image centre, lies well inside the opening. */
static void check_render(lumi_context *ctx, lumi_luminaire lum, const lumi_luminaire_info *info) {
    double x_m = info->opening_size_m[0], y_m = info->opening_size_m[1];
    double smaller_m = (x_m > 0.0 && y_m > 0.0) ? (x_m < y_m ? x_m : y_m) : (x_m > y_m ? x_m : y_m);
    if (!(smaller_m > 0.0)) {
        report("render", 0, "the file has no luminous opening seen from below (point source)");
        return;
    }
    const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    lumi_instance inst = 0;
    lumi_target target = 0;
    lumi_target_desc td = lumi_target_desc_default();
    td.width = SIZE_PX;
    td.height = SIZE_PX;
    td.color_format = LUMI_COLOR_RGBA32F;
    td.depth_format = LUMI_DEPTH_NONE;
    td.exportable = false;
    if (ok_or_report(lumi_instance_create(ctx, lum, identity, &inst), "lumi_instance_create") &&
        ok_or_report(lumi_target_create(ctx, &td, &target), "lumi_target_create"))
        render_and_check(ctx, lum, target, smaller_m);
    lumi_target_destroy(ctx, target); /* handle 0 is ignored */
    lumi_instance_destroy(ctx, inst);
}

static void check_missing_file(lumi_context *ctx) {
    lumi_luminaire lum = 0;
    lumi_status st = lumi_luminaire_load(ctx, MISSING_FILE, &lum);
    char text[1024] = "";
    lumi_last_error(text, sizeof text);
    int ok = st == LUMI_STATUS_IO && lum == 0 && strstr(text, MISSING_FILE) != NULL;
    char detail[1100];
    snprintf(detail, sizeof detail, "status %u (LUMI_STATUS_IO is %u): %s", (unsigned)st, (unsigned)LUMI_STATUS_IO,
             text);
    report("missing file", ok, detail);
    if (st == LUMI_STATUS_OK) lumi_luminaire_destroy(ctx, lum);
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: c_consumer PHOTOMETRY_FILE\n");
        return 2;
    }
    const char *path = argv[1];
    char detail[512];
    lumi_context *ctx = NULL;
    lumi_device_caps caps;
    lumi_luminaire lum = 0;
    lumi_luminaire_info info;

    uint32_t v = lumi_version();
    snprintf(detail, sizeof detail, "lumiview %u.%u.%u, ABI %u (header %u)", (unsigned)(v >> 16),
             (unsigned)((v >> 8) & 0xffu), (unsigned)(v & 0xffu), (unsigned)lumi_abi_version(),
             (unsigned)LUMI_ABI_VERSION);
    report("version", lumi_abi_version() == LUMI_ABI_VERSION, detail);

    lumi_context_desc cd = lumi_context_desc_default(); /* abi_version = LUMI_ABI_VERSION */
    if (ok_or_report(lumi_context_create(&cd, &ctx), "lumi_context_create") &&
        ok_or_report(lumi_context_caps(ctx, &caps), "lumi_context_caps")) {
        snprintf(detail, sizeof detail, "adapter '%s'%s", caps.adapter_name, caps.is_cpu ? " (software)" : "");
        report("context", 1, detail);

        if (ok_or_report(lumi_luminaire_load(ctx, path, &lum), "lumi_luminaire_load") &&
            ok_or_report(lumi_luminaire_get_info(ctx, lum, &info), "lumi_luminaire_get_info")) {
            snprintf(detail, sizeof detail, "%s: kind %u, flux %.6g lm, opening %.4g m x %.4g m", path,
                     (unsigned)info.kind, info.flux_lm, info.opening_size_m[0], info.opening_size_m[1]);
            int farfield = info.kind == LUMI_LUMINAIRE_FARFIELD && info.flux_lm > 0.0;
            report("load", farfield, detail);
            if (farfield) check_render(ctx, lum, &info);
        }
        lumi_luminaire_destroy(ctx, lum); /* handle 0 is ignored */
        check_missing_file(ctx);
    }
    lumi_context_destroy(ctx); /* NULL is ignored */

    if (failures != 0) {
        printf("c consumer: %d check(s) failed\n", failures);
        return 1;
    }
    printf("c consumer: all checks passed\n");
    return 0;
}
