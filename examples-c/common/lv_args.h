/* Command-line value parsing for the examples: strict (the whole string must parse, numbers must be
 * finite), so a typo is an error rather than a silent 0. */
#ifndef LV_ARGS_H
#define LV_ARGS_H

#include <stdbool.h>

#include "lv_math.h"

/* A finite double. */
bool lv_parse_double(const char *s, double *out);
/* A decimal integer in [min, max]. */
bool lv_parse_int(const char *s, long min, long max, long *out);
/* "x,y,z" of finite doubles. */
bool lv_parse_vec3(const char *s, lv_vec3 *out);
/* "x,y" of non-negative integers. */
bool lv_parse_xy(const char *s, long *x, long *y);
/* "WxH" of integers in 1…16384. */
bool lv_parse_size(const char *s, long *w, long *h);

#endif /* LV_ARGS_H */
