/* Strict command-line value parsing; see lv_args.h. */
#include "lv_args.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

/* Parses a finite double at *s and advances *s past it. */
static bool take_double(const char **s, double *out) {
    char *end = NULL;
    errno = 0;
    double v = strtod(*s, &end);
    if (end == *s || errno == ERANGE || !isfinite(v)) return false;
    *s = end;
    *out = v;
    return true;
}

static bool take_long(const char **s, long *out) {
    char *end = NULL;
    errno = 0;
    long v = strtol(*s, &end, 10);
    if (end == *s || errno == ERANGE) return false;
    *s = end;
    *out = v;
    return true;
}

bool lv_parse_double(const char *s, double *out) {
    double v;
    if (!s || !take_double(&s, &v) || *s != '\0') return false;
    *out = v;
    return true;
}

bool lv_parse_int(const char *s, long min, long max, long *out) {
    long v;
    if (!s || !take_long(&s, &v) || *s != '\0' || v < min || v > max) return false;
    *out = v;
    return true;
}

bool lv_parse_vec3(const char *s, lv_vec3 *out) {
    double v[3];
    if (!s) return false;
    for (int i = 0; i < 3; i++) {
        if (!take_double(&s, &v[i])) return false;
        if (i < 2 && *s++ != ',') return false;
    }
    if (*s != '\0') return false;
    *out = lv_vec3_make(v[0], v[1], v[2]);
    return true;
}

bool lv_parse_xy(const char *s, long *x, long *y) {
    long a, b;
    if (!s || !take_long(&s, &a) || *s++ != ',' || !take_long(&s, &b) || *s != '\0' || a < 0 || b < 0)
        return false;
    *x = a;
    *y = b;
    return true;
}

bool lv_parse_size(const char *s, long *w, long *h) {
    long a, b;
    if (!s || !take_long(&s, &a) || (*s != 'x' && *s != 'X')) return false;
    s++;
    if (!take_long(&s, &b) || *s != '\0' || a < 1 || b < 1 || a > 16384 || b > 16384) return false;
    *w = a;
    *h = b;
    return true;
}
