/* The room lumiview draws for the GLFW host; see room.h. */
#include "room.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "lv_lumi.h"

const double ROOM_FLOOR_RGB[3] = {0.25, 0.19, 0.14};

static const room_placement PENDANTS[ROOM_PENDANT_COUNT] = {
    {-2.0, ROOM_PENDANT_Y_M, -1.0, 0.0}, {0.0, ROOM_PENDANT_Y_M, -1.0, 0.0}, {2.0, ROOM_PENDANT_Y_M, -1.0, 0.0},
    {-2.0, ROOM_PENDANT_Y_M, 1.0, 0.0},  {0.0, ROOM_PENDANT_Y_M, 1.0, 0.0},  {2.0, ROOM_PENDANT_Y_M, 1.0, 0.0},
};

double room_reflectance_y(const double rgb[3]) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

void room_placement_model(room_placement p, float m[16]) {
    /* R_y(yaw) · B. B's columns: X → (1, 0, 0), Y → (0, 0, −1), Z → (0, 1, 0). R_y turns (x, z) by yaw
     * counter-clockwise seen from above (+Y): (1, 0, 0) → (cos, 0, −sin), (0, 0, −1) → (−sin, 0, −cos). */
    double c = cos(p.yaw_deg * LV_PI_DEG), s = sin(p.yaw_deg * LV_PI_DEG);
    memset(m, 0, 16 * sizeof(float));
    m[0] = (float)c; /* frame +X (C0) → (cos, 0, −sin) */
    m[2] = (float)-s;
    m[4] = (float)-s; /* frame +Y (C90) → (−sin, 0, −cos) */
    m[6] = (float)-c;
    m[9] = 1.0f; /* frame +Z (zenith) → +Y; the nadir points down */
    m[12] = (float)p.x_m;
    m[13] = (float)p.y_m;
    m[14] = (float)p.z_m;
    m[15] = 1.0f;
}

bool room_apply_settings(const room *r, lumi_context *ctx) {
    lumi_scene_settings s = lumi_scene_settings_default();
    s.shadows = r->shadows;
    s.indirect = r->indirect;
    s.bounce_photons = r->bounce_photons;
    return lv_lumi_ok(lumi_context_set_scene_settings(ctx, &s), "lumi_context_set_scene_settings");
}

bool room_create(room *r, lumi_context *ctx, const char *scene_path, const char *file, bool shadows, bool indirect,
                 uint32_t bounce_photons) {
    memset(r, 0, sizeof *r);
    r->shadows = shadows;
    r->indirect = indirect;
    r->bounce_photons = bounce_photons;
    if (!lv_lumi_ok(lumi_scene_load(ctx, scene_path, &r->scene), "lumi_scene_load")) return false;
    if (!lv_lumi_ok(lumi_luminaire_load(ctx, file, &r->lum), "lumi_luminaire_load") ||
        !lv_lumi_ok(lumi_luminaire_get_info(ctx, r->lum, &r->info), "lumi_luminaire_get_info"))
        return false;
    if (r->info.kind != LUMI_LUMINAIRE_FARFIELD) {
        fprintf(stderr, "glfw_host: --file %s is a near-field scan; the pendants need photometry (IES or EULUMDAT)\n",
                file);
        return false;
    }
    for (int i = 0; i < ROOM_PENDANT_COUNT; i++) {
        r->placements[i] = PENDANTS[i];
        room_placement_model(PENDANTS[i], r->models[i]);
        if (!lv_lumi_ok(lumi_instance_create(ctx, r->lum, r->models[i], &r->pendants[i]), "lumi_instance_create"))
            return false;
    }
    if (!room_apply_settings(r, ctx) || !lv_lumi_ok(lumi_context_set_scene(ctx, r->scene), "lumi_context_set_scene"))
        return false;
    printf("room %s: %d pendants of %s (%.1f lm, max %.1f cd, opening %.3f x %.3f x %.3f m) at y = %.2f m, "
           "x = -2, 0, 2 m, z = -1, 1 m, nadir down, C0 along +X; shadows %s, indirect %s (%u photons)\n",
           scene_path, ROOM_PENDANT_COUNT, file, r->info.flux_lm, r->info.max_intensity_cd, r->info.opening_size_m[0],
           r->info.opening_size_m[1], r->info.opening_size_m[2], ROOM_PENDANT_Y_M, shadows ? "on" : "off",
           indirect ? "on" : "off", bounce_photons);
    return true;
}

bool room_destroy(room *r, lumi_context *ctx) {
    bool ok = true;
    if (r->scene) {
        ok = lv_lumi_ok(lumi_context_set_scene(ctx, 0), "lumi_context_set_scene (clear)") && ok;
        ok = lv_lumi_ok(lumi_scene_destroy(ctx, r->scene), "lumi_scene_destroy") && ok;
    }
    for (int i = 0; i < ROOM_PENDANT_COUNT; i++)
        if (r->pendants[i]) ok = lv_lumi_ok(lumi_instance_destroy(ctx, r->pendants[i]), "lumi_instance_destroy") && ok;
    if (r->lum) ok = lv_lumi_ok(lumi_luminaire_destroy(ctx, r->lum), "lumi_luminaire_destroy") && ok;
    memset(r, 0, sizeof *r);
    return ok;
}

bool room_illuminance(const room *r, const lumi_context *ctx, const float *points_m, const float *normals,
                      size_t count, uint32_t light, uint32_t paths, double *lx, double *std_error_lx) {
    lumi_illuminance_options o = lumi_illuminance_options_default();
    o.light = light;
    if (paths) o.paths_per_point = paths;
    return lv_lumi_ok(lumi_scene_illuminance(ctx, r->scene, points_m, normals, count, &o, lx, std_error_lx),
                      "lumi_scene_illuminance");
}

int room_pendant_at_pixel(const room *r, const float view_proj[16], int width, int height, double gx, double gy,
                          double max_px) {
    int best = -1;
    double best_d = max_px;
    for (int i = 0; i < ROOM_PENDANT_COUNT; i++) {
        lv_vec3 ndc;
        lv_vec3 c = lv_vec3_make(r->models[i][12], r->models[i][13], r->models[i][14]);
        double clip[4], p4[4] = {c.x, c.y, c.z, 1.0};
        lv_mat4_transform4(view_proj, p4, clip);
        if (!(clip[3] > 0.0) || !lv_mat4_transform_point(view_proj, c, &ndc)) continue; /* behind the eye */
        double px = (ndc.x * 0.5 + 0.5) * width - 0.5, py = (ndc.y * 0.5 + 0.5) * height - 0.5;
        double d = hypot(px - gx, py - gy);
        if (d <= best_d) {
            best_d = d;
            best = i;
        }
    }
    return best;
}
