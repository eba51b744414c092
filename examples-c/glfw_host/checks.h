/* The GLFW host's test checks: the luminaire pixel (lumiview's luminance against
 * lumi_luminaire_sample, the composite against the host's own objects), the illuminance probes (the
 * rendered room's pixels against lumi_scene_illuminance), the near-field pixel, and the screenshot.
 * Each prints one line and returns whether it passed. */
#ifndef CHECKS_H
#define CHECKS_H

#include <stdbool.h>

#include "gl_interop.h"
#include "host_objects.h"
#include "lumiview.h"
#include "lv_math.h"
#include "room.h"

/* The view the last frame was drawn with. */
typedef struct frame_view {
    float view[16], projection[16];
    lv_vec3 eye;
    int width, height; /* framebuffer, pixels */
    float exposure;    /* tone-mapping exposure, m²/cd */
    bool half_float;   /* the colour target is RGBA16F (luminance above 65504 cd/m² overflows) */
} frame_view;

/* Tolerances. */
#define PIXEL_TOLERANCE (2.0 / 255.0)
/* lumiview's luminance at a pendant's photometric centre against lumi_luminaire_sample. */
#define LUMINAIRE_TOLERANCE 0.01
/* GL window depth: lumiview's against a point's own (f32 depth; 1e-5 is about 2 mm at 3 m). */
#define DEPTH_TOLERANCE 1e-5
/* The probes: E = π Y / ρ_Y of the rendered pixel against lumi_scene_illuminance. Direct light (the
 * scene pass's 16 fixed points per opening and cube shadow maps against the tracer's 4 × 64 random
 * points and shadow rays): 2 % (measured within 0.2 %, shadowed points included). With inter-reflection
 * the GPU gathers virtual point lights from 256 photons without visibility, the tracer follows every
 * bounce: measured −4.6…+1.4 % at nine open points of the office (floor and desk tops), so 10 %, about
 * twice that. Near furniture the missing visibility over-estimates (+11…+23 % measured 0.2–0.3 m
 * from a desk): total-light probes belong in the open. */
#define PROBE_DIRECT_TOLERANCE 0.02
#define PROBE_TOTAL_TOLERANCE 0.10
/* Paths per point of the reference's total (its standard error, printed, stays below a quarter of
 * the tolerance). */
#define PROBE_PATHS 8192u

/* The luminance of linear RGB (Rec. 709 weights, as lumiview's scene pass). */
double luminance_y(const float rgb[3]);

/* Pixel (x, y), counted from the top-left like the screenshot, on a pendant's photometric centre
 * (the test view puts one on the centre pixel). lumiview's luminance there (read through the imported
 * colour texture) must be L(C, γ) from lumi_luminaire_sample for the direction from that centre to the
 * eye within LUMINAIRE_TOLERANCE, and its depth the centre's GL window depth within DEPTH_TOLERANCE
 * (lumiview drew the luminaire over its room). Then the composite: the host's objects along the pixel's
 * ray (a ray cast into its boxes) against lumiview's depth: the nearer one must be on screen within
 * PIXEL_TOLERANCE — tonemap(L · exposure) for the luminaire, the host face's tone-mapped luminance for
 * a host object, and then the two must differ by more than 2 · PIXEL_TOLERANCE so that the check can
 * tell them apart. Also: two points of the opening (±35 % of its length) projected with the host's
 * matrices show lumiview's depth of the opening there (catches a flipped origin). */
bool check_luminaire_pixel(const room *r, const host_objects *h, const lumi_context *ctx, const gl_imported *color,
                           const gl_imported *depth, const frame_view *v, long x, long y);

/* A probe at world point p on an upward-facing surface with linear RGB reflectance `rgb`: the pixel
 * p projects to, its centre's ray meets the plane y = p.y at q; lumiview's depth there must be q's
 * (the view sees that surface, not something in front), and E = π Y / ρ_Y from lumiview's luminance
 * is compared with lumi_scene_illuminance at q, normal +Y: its direct term (`indirect` off,
 * PROBE_DIRECT_TOLERANCE) or its total (PROBE_TOTAL_TOLERANCE, PROBE_PATHS paths). */
bool check_probe(const room *r, const lumi_context *ctx, const gl_imported *color, const gl_imported *depth,
                 const frame_view *v, lv_vec3 p, const double rgb[3], bool indirect);

/* The near-field luminaire's pixel: where the host's matrices project its frame's origin (`nf_model`'s
 * translation, on the bundled scan's opaque centre tile). The host's stand must lie behind it on the
 * pixel's ray and lumiview's depth must be nearer (the composite lets lumiview win). With the proxy
 * (`proxy_expected`): lumiview's luminance is the scan's ground truth LV_SCAN_CENTRE_CD_M2 within
 * NEARFIELD_TOLERANCE, its depth the tiles' plane's within DEPTH_TOLERANCE, and the composited pixel
 * tonemap(L_truth · exposure) within PIXEL_TOLERANCE. Without: lumiview drew at the luminaire (depth
 * within ±0.15 m of its centre along the ray; no ground truth: the cameras are sampled along the view
 * direction) and the composite shows tonemap of lumiview's own value. */
#define NEARFIELD_TOLERANCE 0.02
bool check_nearfield_pixel(const host_objects *h, const gl_imported *color, const gl_imported *depth,
                           const frame_view *v, const float nf_model[16], bool proxy_expected, const char *mode_name);

/* Reads the back buffer (bottom-up) and writes it top-down as an RGB PNG. */
bool write_screenshot(const char *path, int width, int height);

#endif /* CHECKS_H */
