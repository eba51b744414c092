/* The GLFW host's test checks: the illuminance probe (shader against lumi_instance_illuminance), the
 * luminaire-pixel check (composited pixel against predictions from lumi_luminaire_sample and from a
 * ray cast into the room), and the screenshot. Each prints one line and returns whether it passed. */
#ifndef CHECKS_H
#define CHECKS_H

#include <stdbool.h>

#include "gl_interop.h"
#include "lumiview.h"
#include "lv_math.h"
#include "scene.h"

/* The view the last frame was drawn with. */
typedef struct frame_view {
    float view[16], projection[16];
    lv_vec3 eye;
    int width, height; /* framebuffer, pixels */
    float exposure;           /* the room's tone-mapping exposure, m²/cd */
    float luminaire_exposure; /* lumiview's layer (the luminaires' own luminance), m²/cd */
    bool half_float;   /* the colour target is RGBA16F (luminance above 65504 cd/m² overflows) */
} frame_view;

/* Tolerances. */
#define PROBE_TOLERANCE 0.01
#define PIXEL_TOLERANCE (2.0 / 255.0)

/* E at world point p on an upward surface from the room's GLSL (scene_probe) against the library's
 * lumi_instance_illuminance; passes within PROBE_TOLERANCE (relative). */
bool check_probe(const scene *s, const lumi_context *ctx, lumi_instance inst, lv_vec3 p);

/* Pixel (x, y), counted from the top-left like the screenshot, of the back buffer after compositing.
 * Predicts the luminaire's value tonemap(L(C, γ) · luminaire_exposure), (C, γ) the direction from its
 * photometric centre to the eye (lumi_luminaire_sample), and the room's value along the pixel's ray
 * (ray cast into the boxes; E from lumi_instance_illuminance plus the uniform indirect term;
 * tonemap(ρ E / π · exposure)). Whichever is nearer (lumiview's depth at the pixel against the room
 * hit's GL window depth) is expected; passes when every channel is within PIXEL_TOLERANCE of it, and
 * — when the room is expected in front of the luminaire — the two predictions differ by more than
 * 2 · PIXEL_TOLERANCE, so that the check can tell them apart. Also checks that lumiview's image
 * registers with the host's projection: its alpha is > 0 where the host's matrices project two points
 * of the opening (catches a flipped origin). */
bool check_luminaire_pixel(const scene *s, const lumi_context *ctx, lumi_luminaire lum, lumi_instance inst,
                           const gl_imported *color, const gl_imported *depth, const frame_view *v, long x,
                           long y);

/* The near-field luminaire's pixel: where the host's matrices project its frame's origin (`nf_model`'s
 * translation, on the bundled scan's opaque centre tile). It must be lumiview's (its depth nearer
 * than the room's along the pixel's ray; choose a view where it is). With the proxy
 * (`proxy_expected`): lumiview's luminance there is the scan's ground truth LV_SCAN_CENTRE_CD_M2 within
 * NEARFIELD_TOLERANCE, and the composited pixel shows tonemap(L_truth · luminaire_exposure) within
 * PIXEL_TOLERANCE. Without: lumiview drew something there (no ground truth: the cameras are sampled
 * along the view direction), and the composite shows tonemap of lumiview's own value. */
#define NEARFIELD_TOLERANCE 0.02
bool check_nearfield_pixel(const scene *s, const gl_imported *color, const gl_imported *depth, const frame_view *v,
                           const float nf_model[16], bool proxy_expected, const char *mode_name);

/* Reads the back buffer (bottom-up) and writes it top-down as an RGB PNG. */
bool write_screenshot(const char *path, int width, int height);

#endif /* CHECKS_H */
