/* lumiview API helpers; see lv_lumi.h. */
#include "lv_lumi.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>

const char *lv_status_name(lumi_status status) {
    switch (status) {
    case LUMI_STATUS_OK: return "LUMI_STATUS_OK";
    case LUMI_STATUS_INVALID_ARGUMENT: return "LUMI_STATUS_INVALID_ARGUMENT";
    case LUMI_STATUS_NULL_POINTER: return "LUMI_STATUS_NULL_POINTER";
    case LUMI_STATUS_UNSUPPORTED: return "LUMI_STATUS_UNSUPPORTED";
    case LUMI_STATUS_IO: return "LUMI_STATUS_IO";
    case LUMI_STATUS_PARSE: return "LUMI_STATUS_PARSE";
    case LUMI_STATUS_GPU: return "LUMI_STATUS_GPU";
    case LUMI_STATUS_DEVICE_LOST: return "LUMI_STATUS_DEVICE_LOST";
    case LUMI_STATUS_OUT_OF_MEMORY: return "LUMI_STATUS_OUT_OF_MEMORY";
    case LUMI_STATUS_BUFFER_TOO_SMALL: return "LUMI_STATUS_BUFFER_TOO_SMALL";
    case LUMI_STATUS_PANIC: return "LUMI_STATUS_PANIC";
    case LUMI_STATUS_POISONED: return "LUMI_STATUS_POISONED";
    case LUMI_STATUS_ABI_MISMATCH: return "LUMI_STATUS_ABI_MISMATCH";
    case LUMI_STATUS_NO_DEVICE: return "LUMI_STATUS_NO_DEVICE";
    default: return "unknown status";
    }
}

bool lv_lumi_ok(lumi_status status, const char *call) {
    if (status == LUMI_STATUS_OK) return true;
    char text[1024];
    size_t n = lumi_last_error(text, sizeof text);
    fprintf(stderr, "%s failed: %s (%u): %s%s\n", call, lv_status_name(status), (unsigned)status,
            n ? text : "(no error text)", n >= sizeof text ? " [truncated]" : "");
    return false;
}

static atomic_uint log_errors;
static atomic_uint log_warnings;

void lv_log_stderr(void *user, uint32_t level, const char *message) {
    (void)user;
    static const char *names[3] = {"error", "warning", "info"};
    if (level == 0) atomic_fetch_add(&log_errors, 1u);
    if (level == 1) atomic_fetch_add(&log_warnings, 1u);
    fprintf(stderr, "lumiview %s: %s\n", level < 3 ? names[level] : "log", message ? message : "");
}

unsigned lv_log_errors(void) { return atomic_load(&log_errors); }

unsigned lv_log_warnings(void) { return atomic_load(&log_warnings); }

double lv_tonemap(double luminance, double exposure) {
    double x = luminance * exposure;
    if (!(x > 0.0)) return 0.0; /* also NaN */
    if (isinf(x)) return 1.0;
    return x / (1.0 + x);
}

uint8_t lv_to_u8(double v) {
    if (!(v > 0.0)) return 0;
    if (v >= 1.0) return 255;
    return (uint8_t)lround(v * 255.0);
}

void lv_uuid_format(const uint8_t uuid[16], char out[37]) {
    static const char hex[] = "0123456789abcdef";
    int o = 0;
    for (int i = 0; i < 16; i++) {
        if (i == 4 || i == 6 || i == 8 || i == 10) out[o++] = '-';
        out[o++] = hex[uuid[i] >> 4];
        out[o++] = hex[uuid[i] & 15];
    }
    out[o] = '\0';
}
