/* Small vector and matrix helpers for the lumiview C examples.
 *
 * Matrices are column-major float[16] like GL, glm and lumiview's C API: element (row r, column c)
 * is m[c * 4 + r]. Angles in degrees at the interface, as in lumiview.
 *
 * The luminaire frame (docs/conventions.md): nadir (γ = 0) along −Z, C0 along +X, C90 along +Y;
 * the direction of (C, γ) is d = (sin γ cos C, sin γ sin C, −cos γ). */
#ifndef LV_MATH_H
#define LV_MATH_H

#include <stdbool.h>

#define LV_PI 3.14159265358979323846
/* Radians per degree. */
#define LV_PI_DEG (LV_PI / 180.0)

typedef struct lv_vec3 {
    double x, y, z;
} lv_vec3;

lv_vec3 lv_vec3_make(double x, double y, double z);
lv_vec3 lv_vec3_add(lv_vec3 a, lv_vec3 b);
lv_vec3 lv_vec3_sub(lv_vec3 a, lv_vec3 b);
lv_vec3 lv_vec3_scale(lv_vec3 a, double s);
double lv_vec3_dot(lv_vec3 a, lv_vec3 b);
lv_vec3 lv_vec3_cross(lv_vec3 a, lv_vec3 b);
double lv_vec3_length(lv_vec3 a);
/* a / |a|; the zero vector stays zero. */
lv_vec3 lv_vec3_normalize(lv_vec3 a);

/* Unit direction of (C, γ) in degrees in the luminaire frame. */
lv_vec3 lv_direction_cg(double c_deg, double gamma_deg);
/* (C, γ) in degrees of a direction in the luminaire frame: C in [0, 360), γ in [0, 180]. C is 0 on
 * the poles, where it is undefined. */
void lv_angles_of(lv_vec3 d, double *c_deg, double *gamma_deg);

void lv_mat4_identity(float m[16]);
/* out = a · b (out may alias a or b). */
void lv_mat4_mul(float out[16], const float a[16], const float b[16]);
/* Right-handed look-at (world → eye, the eye looks down −Z), like gluLookAt. Returns false when the
 * eye equals the target or `up` is parallel to the view direction. */
bool lv_mat4_look_at(float out[16], lv_vec3 eye, lv_vec3 target, lv_vec3 up);
/* GL perspective projection (clip z in −w…w), like gluPerspective; fovy in degrees. */
void lv_mat4_perspective_gl(float out[16], double fovy_deg, double aspect, double near_m, double far_m);
/* General inverse; returns false for a singular matrix (out untouched). */
bool lv_mat4_invert(float out[16], const float m[16]);
/* m · (p, 1), divided by w; returns false when w is 0. */
bool lv_mat4_transform_point(const float m[16], lv_vec3 p, lv_vec3 *out);
/* m · (p, 1) as a homogeneous 4-vector. */
void lv_mat4_transform4(const float m[16], const double p[4], double out[4]);
/* The upper-left 3×3 times v (a direction). */
lv_vec3 lv_mat4_transform_dir(const float m[16], lv_vec3 v);

#endif /* LV_MATH_H */
