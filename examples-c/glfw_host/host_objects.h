/* What the GLFW host draws itself, in GL, next to lumiview's image: a few objects of its own
 * (axis-aligned boxes in scene metres, +Y up: the near-field luminaire's stand, and the test's
 * column), flat-shaded per face from the library's illuminance (lumi_scene_illuminance at each face's
 * centre, L = ρ E / π per channel), and the composite pass that merges lumiview's colour and depth
 * with them by the ordinary depth test. lumiview knows nothing of these objects: they cast no shadow
 * in its room and it draws the room behind them; the depth test decides per pixel. */
#ifndef HOST_OBJECTS_H
#define HOST_OBJECTS_H

#include <stdbool.h>

#include "gl_api.h"
#include "lumiview.h"
#include "lv_math.h"
#include "room.h"

/* The near-field luminaire (the examples' bundled scan, lv_scan.h): its frame's origin (the centre of
 * its front tiles) is held at (NEARFIELD_X, NEARFIELD_Y, NEARFIELD_Z) by the host's stand, in the
 * office's free south-east corner (x 2.3…3, z 0.4…2: east of the second desk), its panel upright
 * (frame +X = world up) and its nadir (frame −Z) facing the horizontal direction of yaw
 * NEARFIELD_YAW_DEG (from world +Z towards +X; a multiple of 90° so that the stand's boxes are
 * axis-aligned): −X, across the room towards the default view. It is drawn by lumiview, not a light. */
#define NEARFIELD_X 0.3
#define NEARFIELD_Y 1.35
#define NEARFIELD_Z (-1.8)
#define NEARFIELD_YAW_DEG 0.0

/* The test's column (--occluder on): a 0.3 × 1.9 × 0.3 m box the host draws on the floor, on the line
 * of sight from the test view's eye (2.2, 1.3, 1.8) to the pendant at (0, 2.4, 1) (README). */
#define OCCLUDER_MIN_X 1.17
#define OCCLUDER_MAX_X 1.47
#define OCCLUDER_MIN_Z 1.33
#define OCCLUDER_MAX_Z 1.63
#define OCCLUDER_HEIGHT_M 1.9

#define HOST_MAX_BOXES 8

typedef struct host_box {
    lv_vec3 min, max;
    double albedo[3]; /* linear RGB reflectance */
    const char *name;
    double face_lx[6];                /* illuminance at each face's centre: −X, +X, −Y, +Y, −Z, +Z */
    double face_luminance[6][3];      /* ρ E / π per channel, cd/m² */
} host_box;

typedef struct host_objects {
    host_box boxes[HOST_MAX_BOXES];
    int box_count;
    GLuint vao, vbo, empty_vao;
    GLsizei vertex_count;
    GLuint object_program, composite_program;
    GLint object_view_proj, object_exposure, composite_exposure;
    bool lit_total; /* the faces' illuminance includes inter-reflection (else direct only) */
} host_objects;

/* The near-field luminaire's model matrix (see NEARFIELD_*). Column-major. */
void host_nearfield_model(float model[16]);

/* Builds the boxes (the column when `occluder`, the stand when `nearfield_stand`), their vertex buffer
 * and the shaders. Prints why and returns false on failure (call host_objects_destroy either way). */
bool host_objects_create(host_objects *h, bool occluder, bool nearfield_stand);
void host_objects_destroy(host_objects *h);

/* Lights the boxes' faces from the room: lumi_scene_illuminance at each face's centre (1 mm out along
 * its normal), direct only or total (`total`), and uploads the face luminances. */
bool host_objects_light(host_objects *h, const room *r, const lumi_context *ctx, bool total);

/* Draws the host's objects into the bound framebuffer (depth test LESS), tone-mapped with `exposure`. */
void host_objects_draw(const host_objects *h, const float view[16], const float projection[16], float exposure);

/* Composites lumiview's images: samples `color` (linear cd/m², premultiplied) and `depth` (R32F GL
 * window depth) at gl_FragCoord, discards empty pixels, writes gl_FragDepth = depth and the
 * tone-mapped colour; the depth test against the host's objects decides. */
void host_composite(const host_objects *h, GLuint color, GLuint depth, float exposure);

/* The nearest host box along the ray origin + t·dir (t > 0): distance, the face's index (as in
 * host_box.face_lx) and the box. False when none is hit. */
bool host_ray_hit(const host_objects *h, lv_vec3 origin, lv_vec3 dir, double *t, int *face, const host_box **box);

#endif /* HOST_OBJECTS_H */
