/* The room lumiview draws for the GLFW host: a glTF scene loaded with lumi_scene_load (default the
 * shipped office, assets/scenes/office.glb) and set on the context, lit by pendants (instances of
 * the far-field file placed with the scene convention @X,Y,Z[,YAW], docs/scene-lighting.md), with
 * the shadow and inter-reflection switches of lumi_scene_settings, and the illuminance the library
 * computes in it (lumi_scene_illuminance). Scene coordinates: glTF's, metres, +Y up. */
#ifndef ROOM_H
#define ROOM_H

#include <stdbool.h>
#include <stddef.h>

#include "lumiview.h"
#include "lv_math.h"

/* The office's extent (src/scene/sample.rs): x −3…3, y 0…3, z −2…2 m. The orbit camera stays inside
 * it (the pendants and the camera's bounds are the office's, also with another --scene). */
#define ROOM_MIN_X (-3.0)
#define ROOM_MAX_X 3.0
#define ROOM_MIN_Z (-2.0)
#define ROOM_MAX_Z 2.0
#define ROOM_HEIGHT_M 3.0

/* The pendants: 2 × 3 at y = 2.4 m (0.6 m below the ceiling), x = −2, 0, 2 m, z = −1, 1 m, yaw 0
 * (C0 along +X, C90 along −Z): the layout of docs/scene-lighting.md's `lumiview scene` example. */
#define ROOM_PENDANT_COUNT 6
#define ROOM_PENDANT_Y_M 2.4

/* A placement @X,Y,Z,YAW: the photometric centre at (x, y, z), the nadir along −Y, C0 along +X turned
 * by yaw about +Y (counter-clockwise seen from above). */
typedef struct room_placement {
    double x_m, y_m, z_m, yaw_deg;
} room_placement;

/* The office's luminance-weighted reflectance of a linear RGB base colour: ρ_Y = 0.2126 R + 0.7152 G
 * + 0.0722 B (what lumiview's scene pass and lumi_scene_illuminance use for photometry). */
double room_reflectance_y(const double rgb[3]);

/* The office floor's base colour (src/scene/sample.rs): (0.25, 0.19, 0.14), ρ_Y 0.199. */
extern const double ROOM_FLOOR_RGB[3];

/* The model matrix (column-major) of a placement: luminaire frame → scene is T(x, y, z) · R_y(yaw) · B,
 * with B: X → +X, Y → −Z, Z → +Y (nadir down). A rotation and a translation, as lumi_scene_illuminance
 * requires. */
void room_placement_model(room_placement p, float model[16]);

typedef struct room {
    lumi_scene scene;
    lumi_luminaire lum; /* the pendants' photometry (--file) */
    lumi_luminaire_info info;
    room_placement placements[ROOM_PENDANT_COUNT];
    float models[ROOM_PENDANT_COUNT][16];
    lumi_instance pendants[ROOM_PENDANT_COUNT];
    bool shadows, indirect;
    uint32_t bounce_photons;
} room;

/* Loads the scene and the photometric file, creates the six pendants, sets the scene on the context
 * and its lighting (shadows, indirect light from `bounce_photons` photons, the library's other
 * defaults). Prints what it did, or why it failed (then call room_destroy anyway). */
bool room_create(room *r, lumi_context *ctx, const char *scene_path, const char *file, bool shadows, bool indirect,
                 uint32_t bounce_photons);

/* lumi_context_set_scene_settings with the room's switches (r->shadows, r->indirect). */
bool room_apply_settings(const room *r, lumi_context *ctx);

/* Frees the pendants, the photometry and the scene (clearing the drawn scene first). False when a
 * lumi_ call failed (printed). Zeroed input is fine. */
bool room_destroy(room *r, lumi_context *ctx);

/* lumi_scene_illuminance at `count` points (x, y, z each) with their normals: `light`
 * LUMI_ILLUMINANCE_DIRECT or _TOTAL with `paths` paths per point (0: the library's default), the
 * library's other defaults. `std_error_lx` may be NULL. */
bool room_illuminance(const room *r, const lumi_context *ctx, const float *points_m, const float *normals,
                      size_t count, uint32_t light, uint32_t paths, double *lx, double *std_error_lx);

/* The pendant whose photometric centre projects nearest to window pixel (gx, gy) (GL rows, from the
 * bottom) with the view-projection `view_proj`, within `max_px`; -1 when none. */
int room_pendant_at_pixel(const room *r, const float view_proj[16], int width, int height, double gx, double gy,
                          double max_px);

#endif /* ROOM_H */
