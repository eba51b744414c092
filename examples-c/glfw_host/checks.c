/* The GLFW host's checks; see checks.h. */
#include "checks.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "lv_lumi.h"
#include "lv_png.h"
#include "lv_scan.h"

bool check_probe(const scene *s, const lumi_context *ctx, lumi_instance inst, lv_vec3 p) {
    double e_shader = 0.0, e_lib = 0.0;
    if (!scene_probe(s, p, &e_shader)) return false;
    float point[3] = {(float)p.x, (float)p.y, (float)p.z}, up[3] = {0.0f, 1.0f, 0.0f};
    if (!lv_lumi_ok(lumi_instance_illuminance(ctx, inst, point, up, &e_lib), "lumi_instance_illuminance"))
        return false;
    double ratio = e_lib > 0.0 ? e_shader / e_lib : NAN;
    bool ok;
    if (e_lib > 1e-6) {
        ok = fabs(ratio - 1.0) <= PROBE_TOLERANCE;
    } else {
        ok = fabs(e_shader) <= 1e-6; /* both dark: nothing to compare */
    }
    char ratio_text[32];
    if (e_lib > 1e-6)
        snprintf(ratio_text, sizeof ratio_text, "%.6f", ratio);
    else
        snprintf(ratio_text, sizeof ratio_text, "n/a (no light)");
    printf("probe %g %g %g: E_shader = %.6g lux, E_library = %.6g lux (lumi_instance_illuminance), ratio %s -> %s\n",
           p.x, p.y, p.z, e_shader, e_lib, ratio_text, ok ? "PASS" : "FAIL");
    if (!ok)
        fprintf(stderr, "glfw_host: probe at (%g, %g, %g): the shader's illuminance differs from the library's by "
                        "more than %.0f %%\n", p.x, p.y, p.z, PROBE_TOLERANCE * 100);
    return ok;
}

static double max_channel_diff(const double a[3], const double b[3]) {
    double m = 0.0;
    for (int k = 0; k < 3; k++) m = fmax(m, fabs(a[k] - b[k]));
    return m;
}

/* lumiview's image must register with the host's projection: two points on the opening's long axis
 * (±35 % of its length from the photometric centre, on its centre line, so inside any opening
 * shape) are projected with the host's matrices and lumiview's alpha there must be > 0. A vertically
 * flipped image (wrong origin) or another projection puts the footprint elsewhere, unless the
 * opening happens to project symmetrically about the pixel row of its centre. */
static bool check_footprint(const scene *s, const gl_imported *color, const float view_proj[16], int width,
                            int height) {
    double l = s->opening_m[0], w = s->opening_m[1];
    if (!(l > 0.0) && !(w > 0.0)) {
        printf("footprint: point opening, nothing to register -> SKIP\n");
        return true;
    }
    float clip_from_lum[16];
    lv_mat4_mul(clip_from_lum, view_proj, s->model);
    bool ok = true;
    int px[2][2];
    float alpha[2];
    for (int k = 0; k < 2; k++) {
        double f = k ? 0.35 : -0.35;
        lv_vec3 p = l >= w ? lv_vec3_make(f * l, 0, 0) : lv_vec3_make(0, f * w, 0), ndc;
        if (!lv_mat4_transform_point(clip_from_lum, p, &ndc)) return false;
        px[k][0] = (int)floor((ndc.x * 0.5 + 0.5) * width);
        px[k][1] = (int)floor((ndc.y * 0.5 + 0.5) * height); /* GL row, from the bottom */
        alpha[k] = 0.0f;
        if (px[k][0] < 0 || px[k][0] >= width || px[k][1] < 0 || px[k][1] >= height) {
            ok = false;
            continue;
        }
        float texel[4] = {0, 0, 0, 0};
        glGetTextureSubImage(color->texture, 0, px[k][0], px[k][1], 0, 1, 1, 1, GL_RGBA, GL_FLOAT,
                             (GLsizei)sizeof texel, texel);
        alpha[k] = texel[3];
        if (!(texel[3] > 0.0f)) ok = false;
    }
    if (!lv_gl_ok("reading the footprint")) return false;
    printf("footprint: opening points at pixels %d,%d and %d,%d (from the top-left): lumiview alpha %g, %g -> %s\n",
           px[0][0], height - 1 - px[0][1], px[1][0], height - 1 - px[1][1], (double)alpha[0], (double)alpha[1],
           ok ? "PASS" : "FAIL");
    if (!ok)
        fprintf(stderr, "glfw_host: lumiview's image does not cover the opening where the host's camera projects "
                        "it (flipped origin or another projection?)\n");
    return ok;
}

bool check_luminaire_pixel(const scene *s, const lumi_context *ctx, lumi_luminaire lum, lumi_instance inst,
                           const gl_imported *color, const gl_imported *depth, const frame_view *v, long x,
                           long y) {
    if (x >= v->width || y >= v->height) {
        fprintf(stderr, "glfw_host: --check-luminaire-pixel %ld,%ld is outside the %dx%d framebuffer\n", x, y,
                v->width, v->height);
        return false;
    }
    GLint gx = (GLint)x, gy = (GLint)(v->height - 1 - y); /* GL rows count from the bottom */

    /* What the screen shows. */
    unsigned char px[4] = {0, 0, 0, 0};
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(gx, gy, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, px);
    /* What lumiview rendered there, read through the imported textures. */
    float lib[4] = {0, 0, 0, 0}, lib_depth = 1.0f;
    glGetTextureSubImage(color->texture, 0, gx, gy, 0, 1, 1, 1, GL_RGBA, GL_FLOAT, (GLsizei)sizeof lib, lib);
    glGetTextureSubImage(depth->texture, 0, gx, gy, 0, 1, 1, 1, GL_RED, GL_FLOAT, (GLsizei)sizeof lib_depth,
                         &lib_depth);
    if (!lv_gl_ok("reading the checked pixel")) return false;
    if (!(lib[3] > 0.0f)) {
        fprintf(stderr, "glfw_host: pixel %ld,%ld is not on the luminaire's opening in lumiview's image (alpha %g): "
                        "choose a view where it is (README: the test view)\n", x, y, lib[3]);
        return false;
    }
    double shown[3] = {px[0] / 255.0, px[1] / 255.0, px[2] / 255.0};

    /* Prediction 1: the luminaire, seen from the eye: L(C, γ) for the direction centre → eye. */
    lv_vec3 to_eye = lv_vec3_sub(v->eye, s->luminaire_pos);
    lv_vec3 d = lv_vec3_make(s->world_to_lum[0] * to_eye.x + s->world_to_lum[3] * to_eye.y + s->world_to_lum[6] * to_eye.z,
                             s->world_to_lum[1] * to_eye.x + s->world_to_lum[4] * to_eye.y + s->world_to_lum[7] * to_eye.z,
                             s->world_to_lum[2] * to_eye.x + s->world_to_lum[5] * to_eye.y + s->world_to_lum[8] * to_eye.z);
    double c_deg, g_deg, l_pred = 0.0;
    lv_angles_of(d, &c_deg, &g_deg);
    if (!lv_lumi_ok(lumi_luminaire_sample(ctx, lum, c_deg, g_deg, NULL, &l_pred), "lumi_luminaire_sample"))
        return false;
    double t_lum = lv_tonemap(l_pred, v->luminaire_exposure);
    double pred_lum[3] = {t_lum, t_lum, t_lum};

    /* Prediction 2: the room along the pixel's ray. */
    float vp[16], inv[16];
    lv_mat4_mul(vp, v->projection, v->view);
    if (!lv_mat4_invert(inv, vp)) {
        fprintf(stderr, "glfw_host: singular view-projection matrix\n");
        return false;
    }
    double nx = (gx + 0.5) / v->width * 2.0 - 1.0, ny = (gy + 0.5) / v->height * 2.0 - 1.0;
    lv_vec3 a, b;
    if (!lv_mat4_transform_point(inv, lv_vec3_make(nx, ny, -1.0), &a) ||
        !lv_mat4_transform_point(inv, lv_vec3_make(nx, ny, 1.0), &b)) {
        fprintf(stderr, "glfw_host: cannot unproject pixel %ld,%ld\n", x, y);
        return false;
    }
    lv_vec3 dir = lv_vec3_normalize(lv_vec3_sub(b, a));
    double t = 0.0;
    lv_vec3 normal = lv_vec3_make(0, 1, 0);
    const scene_box *box = NULL;
    if (!scene_ray_hit(s, v->eye, dir, &t, &normal, &box)) {
        fprintf(stderr, "glfw_host: the ray through pixel %ld,%ld leaves the room (is the camera inside?)\n", x, y);
        return false;
    }
    lv_vec3 hit = lv_vec3_add(v->eye, lv_vec3_scale(dir, t));
    float hp[3] = {(float)hit.x, (float)hit.y, (float)hit.z}, hn[3] = {(float)normal.x, (float)normal.y, (float)normal.z};
    double e_direct = 0.0;
    if (!lv_lumi_ok(lumi_instance_illuminance(ctx, inst, hp, hn, &e_direct), "lumi_instance_illuminance"))
        return false;
    double e = e_direct + s->indirect_lux, pred_room[3];
    for (int k = 0; k < 3; k++) pred_room[k] = lv_tonemap(box->albedo[k] * e / LV_PI, v->exposure);
    double clip[4], hp4[4] = {hit.x, hit.y, hit.z, 1.0};
    lv_mat4_transform4(vp, hp4, clip);
    double room_depth = 0.5 * clip[2] / clip[3] + 0.5;

    /* Which one the composite must show: the nearer. */
    bool expect_room = room_depth < lib_depth;
    const double *expected = expect_room ? pred_room : pred_lum;
    double diff = max_channel_diff(shown, expected);
    bool distinguishable = max_channel_diff(pred_lum, pred_room) > 2.0 * PIXEL_TOLERANCE;
    bool ok = diff <= PIXEL_TOLERANCE + 1e-9 && (!expect_room || distinguishable);

    printf("check-luminaire-pixel %ld,%ld: composited = (%.4f, %.4f, %.4f) [%u %u %u]; luminaire predicted = %.4f "
           "[%u] (L(C %.2f°, γ %.2f°) = %.6g cd/m², lumiview's pixel %.6g cd/m², exposure %g); %s predicted = "
           "(%.4f, %.4f, %.4f) [%u %u %u] (%.3f m away, E = %.4g lux); depth luminaire %.6f, %s %.6f; expected: %s, "
           "off by %.4f (tolerance %.4f) -> %s\n",
           x, y, shown[0], shown[1], shown[2], px[0], px[1], px[2], t_lum, lv_to_u8(t_lum), c_deg, g_deg, l_pred,
           (double)lib[0], v->luminaire_exposure, box->name, pred_room[0], pred_room[1], pred_room[2], lv_to_u8(pred_room[0]),
           lv_to_u8(pred_room[1]), lv_to_u8(pred_room[2]), t, e, (double)lib_depth, box->name, room_depth,
           expect_room ? (box->name) : "luminaire", diff, PIXEL_TOLERANCE, ok ? "PASS" : "FAIL");
    bool footprint_ok = check_footprint(s, color, vp, v->width, v->height);
    if (v->half_float && l_pred > 65504.0)
        fprintf(stderr, "glfw_host: note: L = %.6g cd/m² exceeds RGBA16F's largest value (65504); use "
                        "--color-format rgba32f\n", l_pred);
    if (!ok && expect_room && !distinguishable)
        fprintf(stderr, "glfw_host: the %s's shade and the luminaire's predicted value are too close at exposures %g "
                        "(room) and %g (luminaire) to tell them apart; choose another exposure\n", box->name,
                v->exposure, v->luminaire_exposure);
    else if (!ok)
        fprintf(stderr, "glfw_host: pixel %ld,%ld shows (%u %u %u), expected the %s's (%u %u %u) within %.0f/255\n", x,
                y, px[0], px[1], px[2], expect_room ? box->name : "luminaire", lv_to_u8(expected[0]),
                lv_to_u8(expected[1]), lv_to_u8(expected[2]), PIXEL_TOLERANCE * 255.0);
    return ok && footprint_ok;
}

bool check_nearfield_pixel(const scene *s, const gl_imported *color, const gl_imported *depth, const frame_view *v,
                           const float nf_model[16], bool proxy_expected, const char *mode_name) {
    float vp[16], inv[16];
    lv_mat4_mul(vp, v->projection, v->view);
    lv_vec3 centre = lv_vec3_make(nf_model[12], nf_model[13], nf_model[14]), ndc;
    if (!lv_mat4_transform_point(vp, centre, &ndc) || fabs(ndc.x) >= 1.0 || fabs(ndc.y) >= 1.0 || fabs(ndc.z) >= 1.0) {
        fprintf(stderr, "glfw_host: the near-field luminaire's centre is outside the view; choose --camera/--target "
                        "that see it (README)\n");
        return false;
    }
    GLint gx = (GLint)floor((ndc.x * 0.5 + 0.5) * v->width), gy = (GLint)floor((ndc.y * 0.5 + 0.5) * v->height);
    long x = gx, y = v->height - 1 - gy; /* from the top-left, like the screenshot */
    unsigned char px[4] = {0, 0, 0, 0};
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(gx, gy, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, px);
    float lib[4] = {0, 0, 0, 0}, lib_depth = 1.0f;
    glGetTextureSubImage(color->texture, 0, gx, gy, 0, 1, 1, 1, GL_RGBA, GL_FLOAT, (GLsizei)sizeof lib, lib);
    glGetTextureSubImage(depth->texture, 0, gx, gy, 0, 1, 1, 1, GL_RED, GL_FLOAT, (GLsizei)sizeof lib_depth,
                         &lib_depth);
    if (!lv_gl_ok("reading the near-field pixel")) return false;

    /* The room along the pixel's ray must be behind lumiview's image there. */
    if (!lv_mat4_invert(inv, vp)) {
        fprintf(stderr, "glfw_host: singular view-projection matrix\n");
        return false;
    }
    double nx = (gx + 0.5) / v->width * 2.0 - 1.0, ny = (gy + 0.5) / v->height * 2.0 - 1.0;
    lv_vec3 a, b, normal;
    if (!lv_mat4_transform_point(inv, lv_vec3_make(nx, ny, -1.0), &a) ||
        !lv_mat4_transform_point(inv, lv_vec3_make(nx, ny, 1.0), &b)) {
        fprintf(stderr, "glfw_host: cannot unproject pixel %ld,%ld\n", x, y);
        return false;
    }
    lv_vec3 dir = lv_vec3_normalize(lv_vec3_sub(b, a));
    double t = 0.0, room_depth = 1.0;
    const scene_box *box = NULL;
    if (scene_ray_hit(s, v->eye, dir, &t, &normal, &box)) {
        lv_vec3 hit = lv_vec3_add(v->eye, lv_vec3_scale(dir, t));
        double clip[4], hp4[4] = {hit.x, hit.y, hit.z, 1.0};
        lv_mat4_transform4(vp, hp4, clip);
        room_depth = 0.5 * clip[2] / clip[3] + 0.5;
    }
    if (!(lib[3] > 0.0f) || !(lib_depth < room_depth)) {
        fprintf(stderr, "glfw_host: at pixel %ld,%ld (the near-field luminaire's centre) lumiview drew %s (alpha %g, "
                        "depth %g; the %s is at depth %g): choose a view where the luminaire is visible\n",
                x, y, lib[3] > 0.0f ? "something behind the room" : "nothing", (double)lib[3], (double)lib_depth,
                box ? box->name : "room", room_depth);
        return false;
    }
    double shown = px[0] / 255.0, l_img = lib[0];
    double l_pred = proxy_expected ? LV_SCAN_CENTRE_CD_M2 : l_img;
    double t_pred = lv_tonemap(l_pred, v->luminaire_exposure);
    double rel = (l_img - LV_SCAN_CENTRE_CD_M2) / LV_SCAN_CENTRE_CD_M2;
    bool ok = fabs(shown - t_pred) <= PIXEL_TOLERANCE + 1e-9 && fabs(px[1] / 255.0 - t_pred) <= PIXEL_TOLERANCE + 1e-9 &&
              fabs(px[2] / 255.0 - t_pred) <= PIXEL_TOLERANCE + 1e-9;
    if (proxy_expected && !(fabs(rel) <= NEARFIELD_TOLERANCE)) ok = false;
    if (proxy_expected)
        printf("check-nearfield-pixel %ld,%ld (%s, proxy on): lumiview L = %.6g cd/m² (scan's centre tile %.0f, %+.3f "
               "%%), composited = [%u %u %u], predicted %.4f [%u] (exposure %g); depth %.6f in front of the %s (%.6f) "
               "-> %s\n",
               x, y, mode_name, l_img, LV_SCAN_CENTRE_CD_M2, rel * 100.0, px[0], px[1], px[2], t_pred, lv_to_u8(t_pred),
               v->luminaire_exposure, (double)lib_depth, box ? box->name : "room", room_depth, ok ? "PASS" : "FAIL");
    else
        printf("check-nearfield-pixel %ld,%ld (%s, proxy off): lumiview L = %.6g cd/m² (no ground truth without the "
               "proxy), composited = [%u %u %u], tonemap of lumiview's value %.4f [%u]; stand-in depth %.6f in front "
               "of the %s (%.6f) -> %s\n",
               x, y, mode_name, l_img, px[0], px[1], px[2], t_pred, lv_to_u8(t_pred), (double)lib_depth,
               box ? box->name : "room", room_depth, ok ? "PASS" : "FAIL");
    if (!ok)
        fprintf(stderr, "glfw_host: the near-field pixel %ld,%ld shows [%u %u %u] with lumiview L = %.6g cd/m²; expected "
                        "[%u] %s\n", x, y, px[0], px[1], px[2], l_img, lv_to_u8(t_pred),
                proxy_expected ? "from the scan's 3000 cd/m² (within 2 % and 2/255)" : "(within 2/255)");
    return ok;
}

bool write_screenshot(const char *path, int width, int height) {
    size_t row = (size_t)width * 4;
    unsigned char *rgba = malloc(row * (size_t)height);
    unsigned char *rgb = malloc((size_t)width * 3 * (size_t)height);
    if (!rgba || !rgb) {
        free(rgba);
        free(rgb);
        fprintf(stderr, "glfw_host: out of memory for the screenshot\n");
        return false;
    }
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    bool ok = lv_gl_ok("reading the screenshot");
    if (ok) {
        for (int y = 0; y < height; y++) {
            const unsigned char *src = rgba + (size_t)(height - 1 - y) * row; /* GL row 0 is the bottom */
            unsigned char *dst = rgb + (size_t)y * width * 3;
            for (int x = 0; x < width; x++) {
                dst[x * 3 + 0] = src[x * 4 + 0];
                dst[x * 3 + 1] = src[x * 4 + 1];
                dst[x * 3 + 2] = src[x * 4 + 2];
            }
        }
        ok = lv_png_write(path, rgb, (uint32_t)width, (uint32_t)height, 3, (size_t)width * 3);
    }
    free(rgba);
    free(rgb);
    return ok;
}
