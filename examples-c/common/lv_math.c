/* Vector and matrix helpers; see lv_math.h. */
#include "lv_math.h"

#include <math.h>
#include <string.h>

lv_vec3 lv_vec3_make(double x, double y, double z) {
    lv_vec3 v = {x, y, z};
    return v;
}

lv_vec3 lv_vec3_add(lv_vec3 a, lv_vec3 b) { return lv_vec3_make(a.x + b.x, a.y + b.y, a.z + b.z); }

lv_vec3 lv_vec3_sub(lv_vec3 a, lv_vec3 b) { return lv_vec3_make(a.x - b.x, a.y - b.y, a.z - b.z); }

lv_vec3 lv_vec3_scale(lv_vec3 a, double s) { return lv_vec3_make(a.x * s, a.y * s, a.z * s); }

double lv_vec3_dot(lv_vec3 a, lv_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

lv_vec3 lv_vec3_cross(lv_vec3 a, lv_vec3 b) {
    return lv_vec3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

double lv_vec3_length(lv_vec3 a) { return sqrt(lv_vec3_dot(a, a)); }

lv_vec3 lv_vec3_normalize(lv_vec3 a) {
    double l = lv_vec3_length(a);
    return l > 0.0 ? lv_vec3_scale(a, 1.0 / l) : a;
}

lv_vec3 lv_direction_cg(double c_deg, double gamma_deg) {
    double c = c_deg * LV_PI / 180.0, g = gamma_deg * LV_PI / 180.0;
    return lv_vec3_make(sin(g) * cos(c), sin(g) * sin(c), -cos(g));
}

void lv_angles_of(lv_vec3 d, double *c_deg, double *gamma_deg) {
    lv_vec3 u = lv_vec3_normalize(d);
    double cz = -u.z;
    if (cz > 1.0) cz = 1.0;
    if (cz < -1.0) cz = -1.0;
    *gamma_deg = acos(cz) * 180.0 / LV_PI;
    double c = (u.x == 0.0 && u.y == 0.0) ? 0.0 : atan2(u.y, u.x) * 180.0 / LV_PI;
    if (c < 0.0) c += 360.0;
    if (c >= 360.0) c -= 360.0;
    *c_deg = c;
}

void lv_mat4_identity(float m[16]) {
    memset(m, 0, 16 * sizeof(float));
    m[0] = m[5] = m[10] = m[15] = 1.0f;
}

void lv_mat4_mul(float out[16], const float a[16], const float b[16]) {
    float r[16];
    for (int c = 0; c < 4; c++) {
        for (int row = 0; row < 4; row++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++) s += (double)a[k * 4 + row] * (double)b[c * 4 + k];
            r[c * 4 + row] = (float)s;
        }
    }
    memcpy(out, r, sizeof r);
}

bool lv_mat4_look_at(float out[16], lv_vec3 eye, lv_vec3 target, lv_vec3 up) {
    lv_vec3 f = lv_vec3_sub(target, eye);
    if (lv_vec3_length(f) <= 0.0) return false;
    f = lv_vec3_normalize(f);
    lv_vec3 s = lv_vec3_cross(f, lv_vec3_normalize(up));
    if (lv_vec3_length(s) < 1e-9) return false;
    s = lv_vec3_normalize(s);
    lv_vec3 u = lv_vec3_cross(s, f);
    lv_mat4_identity(out);
    out[0] = (float)s.x;
    out[4] = (float)s.y;
    out[8] = (float)s.z;
    out[1] = (float)u.x;
    out[5] = (float)u.y;
    out[9] = (float)u.z;
    out[2] = (float)-f.x;
    out[6] = (float)-f.y;
    out[10] = (float)-f.z;
    out[12] = (float)-lv_vec3_dot(s, eye);
    out[13] = (float)-lv_vec3_dot(u, eye);
    out[14] = (float)lv_vec3_dot(f, eye);
    return true;
}

void lv_mat4_perspective_gl(float out[16], double fovy_deg, double aspect, double near_m, double far_m) {
    double f = 1.0 / tan(fovy_deg * LV_PI / 360.0);
    memset(out, 0, 16 * sizeof(float));
    out[0] = (float)(f / aspect);
    out[5] = (float)f;
    out[10] = (float)((far_m + near_m) / (near_m - far_m));
    out[11] = -1.0f;
    out[14] = (float)(2.0 * far_m * near_m / (near_m - far_m));
}

bool lv_mat4_invert(float out[16], const float m[16]) {
    /* Gauss-Jordan elimination with partial pivoting, in double precision. */
    double a[4][8];
    for (int r = 0; r < 4; r++) {
        for (int c = 0; c < 4; c++) {
            a[r][c] = m[c * 4 + r];
            a[r][c + 4] = (r == c) ? 1.0 : 0.0;
        }
    }
    for (int col = 0; col < 4; col++) {
        int piv = col;
        for (int r = col + 1; r < 4; r++)
            if (fabs(a[r][col]) > fabs(a[piv][col])) piv = r;
        if (fabs(a[piv][col]) < 1e-30) return false;
        if (piv != col) {
            for (int k = 0; k < 8; k++) {
                double t = a[col][k];
                a[col][k] = a[piv][k];
                a[piv][k] = t;
            }
        }
        double inv = 1.0 / a[col][col];
        for (int k = 0; k < 8; k++) a[col][k] *= inv;
        for (int r = 0; r < 4; r++) {
            if (r == col) continue;
            double f = a[r][col];
            for (int k = 0; k < 8; k++) a[r][k] -= f * a[col][k];
        }
    }
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) out[c * 4 + r] = (float)a[r][c + 4];
    return true;
}

void lv_mat4_transform4(const float m[16], const double p[4], double out[4]) {
    for (int r = 0; r < 4; r++) {
        out[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r] * p[3];
    }
}

bool lv_mat4_transform_point(const float m[16], lv_vec3 p, lv_vec3 *out) {
    double in[4] = {p.x, p.y, p.z, 1.0}, o[4];
    lv_mat4_transform4(m, in, o);
    if (o[3] == 0.0) return false;
    *out = lv_vec3_make(o[0] / o[3], o[1] / o[3], o[2] / o[3]);
    return true;
}

lv_vec3 lv_mat4_transform_dir(const float m[16], lv_vec3 v) {
    return lv_vec3_make(m[0] * v.x + m[4] * v.y + m[8] * v.z, m[1] * v.x + m[5] * v.y + m[9] * v.z,
                        m[2] * v.x + m[6] * v.y + m[10] * v.z);
}
