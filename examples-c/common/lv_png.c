/* Minimal uncompressed PNG writer; see lv_png.h. Format: PNG (ISO/IEC 15948), zlib (RFC 1950) with
 * stored deflate blocks (RFC 1951 §3.2.4). */
#include "lv_png.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

uint32_t lv_crc32(uint32_t crc, const uint8_t *data, size_t len) {
    /* The table is rebuilt per call (2 k steps): no shared state, so any thread may call this. */
    uint32_t table[256];
    for (uint32_t n = 0; n < 256; n++) {
        uint32_t c = n;
        for (int k = 0; k < 8; k++) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        table[n] = c;
    }
    crc = ~crc;
    for (size_t i = 0; i < len; i++) crc = table[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
    return ~crc;
}

uint32_t lv_adler32(uint32_t adler, const uint8_t *data, size_t len) {
    uint32_t a = adler & 0xFFFFu, b = adler >> 16;
    for (size_t i = 0; i < len; i++) {
        a = (a + data[i]) % 65521u;
        b = (b + a) % 65521u;
    }
    return (b << 16) | a;
}

static void put_be32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

/* Writes one chunk: length, type, data, CRC over type and data. */
static bool write_chunk(FILE *f, const char type[4], const uint8_t *data, uint32_t len) {
    uint8_t head[8];
    put_be32(head, len);
    memcpy(head + 4, type, 4);
    uint32_t crc = lv_crc32(0, head + 4, 4);
    crc = lv_crc32(crc, data, len);
    uint8_t tail[4];
    put_be32(tail, crc);
    return fwrite(head, 1, 8, f) == 8 && (len == 0 || fwrite(data, 1, len, f) == len) &&
           fwrite(tail, 1, 4, f) == 4;
}

bool lv_png_write(const char *path, const uint8_t *pixels, uint32_t width, uint32_t height,
                  uint32_t channels, size_t stride) {
    static const uint8_t color_type[5] = {0, 0, 0, 2, 6};
    if (width == 0 || height == 0 || (channels != 1 && channels != 3 && channels != 4) ||
        stride < (size_t)width * channels) {
        fprintf(stderr, "png: %s: invalid image %ux%u with %u channels\n", path, width, height, channels);
        return false;
    }
    /* Filtered scanlines: a filter byte (0, none) then the row. */
    size_t row = (size_t)width * channels + 1;
    size_t raw_len = row * height;
    size_t blocks = raw_len / 65535 + 1;
    size_t z_len = 2 + raw_len + blocks * 5 + 4;
    if (z_len > 0x7FFFFFFFu) {
        fprintf(stderr, "png: %s: image too large for one IDAT chunk\n", path);
        return false;
    }
    uint8_t *raw = malloc(raw_len);
    uint8_t *z = malloc(z_len);
    if (!raw || !z) {
        free(raw);
        free(z);
        fprintf(stderr, "png: %s: out of memory\n", path);
        return false;
    }
    for (uint32_t y = 0; y < height; y++) {
        raw[y * row] = 0;
        memcpy(raw + y * row + 1, pixels + y * stride, row - 1);
    }
    /* zlib stream: CMF 0x78 (deflate, 32 KiB window), FLG 0x01 (check bits: 0x7801 % 31 == 0). */
    size_t o = 0;
    z[o++] = 0x78;
    z[o++] = 0x01;
    size_t pos = 0;
    do {
        size_t n = raw_len - pos > 65535 ? 65535 : raw_len - pos;
        bool final = pos + n == raw_len;
        z[o++] = final ? 1 : 0; /* BFINAL, BTYPE = 00 (stored) */
        z[o++] = (uint8_t)(n & 0xFF);
        z[o++] = (uint8_t)(n >> 8);
        z[o++] = (uint8_t)(~n & 0xFF);
        z[o++] = (uint8_t)((~n >> 8) & 0xFF);
        memcpy(z + o, raw + pos, n);
        o += n;
        pos += n;
    } while (pos < raw_len);
    put_be32(z + o, lv_adler32(1, raw, raw_len));
    o += 4;

    uint8_t ihdr[13];
    put_be32(ihdr, width);
    put_be32(ihdr + 4, height);
    ihdr[8] = 8;                     /* bit depth */
    ihdr[9] = color_type[channels];  /* 0 grey, 2 RGB, 6 RGBA */
    ihdr[10] = 0;                    /* deflate */
    ihdr[11] = 0;                    /* adaptive filtering */
    ihdr[12] = 0;                    /* no interlace */
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

    bool ok = false;
    FILE *f = fopen(path, "wb");
    if (!f) {
        fprintf(stderr, "png: cannot create %s: %s\n", path, strerror(errno));
    } else {
        ok = fwrite(signature, 1, 8, f) == 8 && write_chunk(f, "IHDR", ihdr, 13) &&
             write_chunk(f, "IDAT", z, (uint32_t)o) && write_chunk(f, "IEND", NULL, 0);
        if (fclose(f) != 0) ok = false;
        if (!ok) fprintf(stderr, "png: writing %s failed: %s\n", path, strerror(errno));
    }
    free(raw);
    free(z);
    return ok;
}
