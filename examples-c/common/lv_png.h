/* A minimal PNG writer: 8-bit greyscale, RGB or RGBA, no compression (stored deflate blocks), so it
 * needs no zlib. CRC-32 and Adler-32 are computed here. */
#ifndef LV_PNG_H
#define LV_PNG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Writes `pixels` (`height` rows of `width` × `channels` bytes, `stride` bytes apart, the top row
 * first) as a PNG file. `channels` is 1 (grey), 3 (RGB) or 4 (RGBA). On failure prints a message
 * naming the file to stderr and returns false. */
bool lv_png_write(const char *path, const uint8_t *pixels, uint32_t width, uint32_t height,
                  uint32_t channels, size_t stride);

/* CRC-32 (ISO 3309, as PNG uses it) of `len` bytes continuing from `crc` (start with 0). */
uint32_t lv_crc32(uint32_t crc, const uint8_t *data, size_t len);

/* Adler-32 (RFC 1950) of `len` bytes continuing from `adler` (start with 1). */
uint32_t lv_adler32(uint32_t adler, const uint8_t *data, size_t len);

#endif /* LV_PNG_H */
