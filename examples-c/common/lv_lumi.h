/* Helpers around lumiview's C API shared by the examples: status names and error reporting,
 * a thread-safe log callback, tone mapping and UUID formatting. */
#ifndef LV_LUMI_H
#define LV_LUMI_H

#include <stdbool.h>
#include <stdint.h>

#include "lumiview.h"

/* The name of a status (`LUMI_STATUS_OK` …), or "unknown status". */
const char *lv_status_name(lumi_status status);

/* Returns true for `LUMI_STATUS_OK`. Otherwise prints "<call> failed: <STATUS> (<n>): <last error
 * text>" to stderr and returns false. Call it right after the failing call, on the same thread. */
bool lv_lumi_ok(lumi_status status, const char *call);

/* A `lumi_log_fn` that prints "lumiview <level>: <message>" to stderr and counts errors and
 * warnings (thread-safe; `user` is unused). */
void lv_log_stderr(void *user, uint32_t level, const char *message);
/* Errors (level 0) and warnings (level 1) seen by `lv_log_stderr` so far. */
unsigned lv_log_errors(void);
unsigned lv_log_warnings(void);

/* Reinhard as lumiview defines it: x = L · exposure, display value x / (1 + x); infinite L gives 1,
 * negative or NaN L gives 0. */
double lv_tonemap(double luminance, double exposure);

/* A display value in 0…1 as an 8-bit code (rounded, clamped). */
uint8_t lv_to_u8(double v);

/* "xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx" (36 characters and a NUL). */
void lv_uuid_format(const uint8_t uuid[16], char out[37]);

#endif /* LV_LUMI_H */
