/* The GLFW host's room: geometry (axis-aligned boxes in a Y-up world, metres), the GLSL that lights it
 * from the luminaire's look-up table (E = I cos i / r², docs/lut-and-solid.md §3), the composite
 * pass that merges lumiview's luminaire image by depth, and the 1×1 illuminance probe. */
#ifndef SCENE_H
#define SCENE_H

#include <stdbool.h>

#include "gl_api.h"
#include "lumiview.h"
#include "lv_math.h"

/* Room extent: x and z in [−ROOM_HALF_M, ROOM_HALF_M], y (up) in [0, ROOM_HEIGHT_M]. */
#define ROOM_HALF_M 3.0
#define ROOM_HEIGHT_M 3.0
/* The luminaire's photometric centre, world (hanging 0.5 m below the ceiling). */
#define LUMINAIRE_X 0.0
#define LUMINAIRE_Y 2.5
#define LUMINAIRE_Z 0.0
/* The near-field luminaire (the examples' bundled scan, lv_scan.h): its frame's origin (the centre of
 * its front tiles) stands at (NEARFIELD_X, NEARFIELD_Y, NEARFIELD_Z) on a pole, its panel upright
 * (frame +X = world up) and its nadir (frame −Z) facing the horizontal direction of yaw
 * NEARFIELD_YAW_DEG (from world +Z towards +X): towards the west-south-west of the room, where the
 * default orbit camera moves. It is drawn, not a light: the room is lit by the far-field luminaire. */
#define NEARFIELD_X (-0.6)
#define NEARFIELD_Y 1.45
#define NEARFIELD_Z (-0.2)
#define NEARFIELD_YAW_DEG (-72.0)
/* Diffuse reflectance of the room's surfaces. */
#define ROOM_REFLECTANCE 0.5
#define SCENE_MAX_BOXES 16

typedef struct scene_box {
    lv_vec3 min, max;
    float albedo[3];
    const char *name;
    bool inward; /* the room: seen from inside, normals point in */
} scene_box;

typedef struct scene {
    scene_box boxes[SCENE_MAX_BOXES];
    int box_count;
    GLuint vao, vbo, empty_vao;
    GLsizei vertex_count;
    GLuint room_program, composite_program, probe_program;
    GLuint lut_texture, probe_texture, probe_fbo;
    /* Uniform locations. */
    GLint room_view_proj, room_exposure, room_indirect;
    GLint composite_exposure;
    GLint probe_point;
    /* Lighting inputs, world. */
    float model[16];           /* luminaire frame → world */
    float world_to_lum[9];     /* inverse of the model's 3×3, column-major */
    lv_vec3 luminaire_pos;     /* photometric centre */
    double indirect_lux;       /* uniform inter-reflected illuminance (0 when off) */
    double opening_m[3];       /* the luminous opening's length (X), width (Y), height (Z) */
} scene;

/* The model matrix putting the luminaire at (LUMINAIRE_X, LUMINAIRE_Y, LUMINAIRE_Z) with its nadir
 * (−Z of the luminaire frame) pointing down (world −Y) and C0 (+X) along world +X; hence C90 (+Y)
 * along world −Z. Column-major. */
void scene_luminaire_model(float model[16]);

/* The near-field luminaire's model matrix (see NEARFIELD_*). Column-major. */
void scene_nearfield_model(float model[16]);

/* Builds the room (with the cabinet when `occluder`, the near-field luminaire's stand when
 * `nearfield_stand`), compiles the shaders and uploads the 2D
 * look-up table (`lut`: `lut_w` × `lut_h` absolute cd, row 0 = γ 0°). `indirect` adds a uniform
 * inter-reflected illuminance from the integrating-sphere formula E = Φ ρ / (A (1 − ρ)). Prints why
 * and returns false on failure (call scene_destroy either way). */
bool scene_create(scene *s, const float model[16], const lumi_luminaire_info *info, const float *lut,
                  uint32_t lut_w, uint32_t lut_h, bool occluder, bool indirect, bool nearfield_stand);
void scene_destroy(scene *s);

/* Draws the lit room into the bound framebuffer (depth test on, LESS). */
void scene_draw_room(const scene *s, const float view[16], const float projection[16], float exposure);

/* Composites lumiview's images: samples `color` (linear cd/m², premultiplied) and `depth` (R32F GL
 * window depth) at gl_FragCoord, discards empty pixels, writes gl_FragDepth = depth and the
 * tone-mapped colour; the depth test against the room decides. */
void scene_composite(const scene *s, GLuint color, GLuint depth, float exposure);

/* Direct illuminance (lux) at world point p on an upward-facing surface (normal +Y), evaluated by the
 * same GLSL function that lights the room, in a 1×1 R32F pass; restores the default framebuffer. */
bool scene_probe(const scene *s, lv_vec3 p, double *lux);

/* The nearest surface of the room along the ray origin + t·dir (t > 0): distance, surface normal
 * (facing the ray origin's side) and box. False when nothing is hit. */
bool scene_ray_hit(const scene *s, lv_vec3 origin, lv_vec3 dir, double *t, lv_vec3 *normal, const scene_box **box);

#endif /* SCENE_H */
