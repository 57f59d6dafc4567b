/* Display and comparison of rendered images: exposure, ACES tone curve,
 * sRGB, error heat maps and metrics, PNG (over zlib) and PFM files. */
#include "common/common.h"
#include "common/srgb.h"
#include "probebake/files.h"
#include "probebake/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

float pb_tonemap_aces(float x)
{
    /* Narkowicz's fit of the ACES reference rendering transform */
    x = x > 0.f ? x : 0.f;
    float y = (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f);
    return y < 1.f ? y : 1.f;
}

float pb_srgb_encode(float l)
{
    return pb_linear_to_srgb(l);
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

float pb_auto_exposure(const float *rgba, uint32_t width, uint32_t height)
{
    double sum = 0;
    uint64_t n = 0, pixels = (uint64_t)width * height;
    int all = 0;
    for (int pass = 0; pass < 2 && n == 0; ++pass)
        for (uint64_t i = 0; i < pixels; ++i)
            if (pass == 1 || rgba[4 * i + 3] > 0.f) {
                float l = pb_luminance(rgba + 4 * i);
                sum += log(1e-4 + (l > 0.f ? l : 0.f)); /* negative (SH ringing) or NaN counts as black */
                ++n, all = pass;
            }
    double avg = n ? exp(sum / n) : 0.18;
    double ev = log2(0.18 / avg);
    /* A mostly black image (metal surfaces in a diffuse bake, unlit rooms) has a
     * log-average near the floor, and would be pushed until its lit parts clip:
     * cap the exposure where the 99th-percentile luminance reaches 4 (ACES 0.91). */
    float *l = n ? malloc(n * sizeof *l) : NULL;
    if (l) {
        uint64_t k = 0;
        for (uint64_t i = 0; i < pixels; ++i)
            if (all || rgba[4 * i + 3] > 0.f) {
                float v = pb_luminance(rgba + 4 * i);
                l[k++] = v > 0.f ? v : 0.f; /* NaN too */
            }
        qsort(l, n, sizeof *l, compare_floats);
        float top = l[(n - 1) * 99 / 100];
        if (top > 0.f && ev > log2(4.0 / top))
            ev = log2(4.0 / top);
        free(l);
    }
    return (float)ev;
}

void pb_tonemap_image(const float *rgba, uint32_t width, uint32_t height, float exposure_ev, unsigned char *rgb8)
{
    float scale = exp2f(exposure_ev);
    for (uint64_t i = 0; i < (uint64_t)width * height; ++i)
        for (int c = 0; c < 3; ++c) {
            float v = pb_srgb_encode(pb_tonemap_aces(rgba[4 * i + c] * scale));
            rgb8[3 * i + c] = (unsigned char)(v * 255.f + 0.5f);
        }
}

void pb_error_heatmap(const float *a, const float *b, uint32_t width, uint32_t height, float max_error,
                      unsigned char *rgb8)
{
    /* black -> blue -> green -> yellow -> red */
    static const float ramp[5][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
    for (uint64_t i = 0; i < (uint64_t)width * height; ++i) {
        float la = pb_luminance(a + 4 * i), lb = pb_luminance(b + 4 * i);
        float e = fabsf(la - lb) / fmaxf(lb, 1e-3f) / max_error;
        e = e < 0.f ? 0.f : (e > 1.f ? 1.f : e);
        float x = e * 4.f;
        int k = (int)x < 4 ? (int)x : 3;
        float t = x - (float)k;
        for (int c = 0; c < 3; ++c)
            rgb8[3 * i + c] = (unsigned char)(255.f * (ramp[k][c] * (1.f - t) + ramp[k + 1][c] * t) + 0.5f);
    }
}

double pb_image_relative_rmse(const float *a, const float *b, uint32_t width, uint32_t height)
{
    double se = 0, sum = 0;
    uint64_t n = 0;
    for (uint64_t i = 0; i < (uint64_t)width * height; ++i) {
        if (!(b[4 * i + 3] > 0.f))
            continue;
        double d = (double)pb_luminance(a + 4 * i) - pb_luminance(b + 4 * i);
        se += d * d;
        sum += pb_luminance(b + 4 * i);
        ++n;
    }
    return n && sum > 0 ? sqrt(se / n) / (sum / n) : 0.0;
}

/* PNG, 8-bit RGB, written here over zlib: each row takes the filter whose
 * bytes, read as signed, sum smallest in magnitude (PNG's usual heuristic),
 * and the rows are deflated at zlib's default level. zlib reports a failed
 * allocation (Z_MEM_ERROR); stb_image_write, used before, asserted and
 * aborted (tests/test_out_of_memory.sh). */
static void put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24), p[1] = (unsigned char)(v >> 16), p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

/* A chunk whose `n` data bytes already stand at at + 8: length, type, CRC. */
static unsigned char *png_chunk(unsigned char *at, const char type[4], uint32_t n)
{
    put_be32(at, n);
    memcpy(at + 4, type, 4);
    put_be32(at + 8 + n, (uint32_t)crc32(crc32(0L, Z_NULL, 0), at + 4, 4 + n));
    return at + 12 + n;
}

static unsigned char paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return (unsigned char)(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

/* Row y filtered five ways into five rows of `stride` bytes; the type with
 * the smallest sum of |signed byte| is returned. */
static int png_filter(const unsigned char *cur, const unsigned char *up, size_t stride, unsigned char *five)
{
    long best = -1;
    int best_type = 0;
    for (int f = 0; f < 5; ++f) {
        unsigned char *o = five + (size_t)f * stride;
        long sum = 0;
        for (size_t i = 0; i < stride; ++i) {
            int a = i >= 3 ? cur[i - 3] : 0, b = up ? up[i] : 0, c = up && i >= 3 ? up[i - 3] : 0;
            int pred = f == 0 ? 0 : f == 1 ? a : f == 2 ? b : f == 3 ? (a + b) / 2 : paeth(a, b, c);
            o[i] = (unsigned char)(cur[i] - pred);
            sum += o[i] < 128 ? o[i] : 256 - o[i];
        }
        if (best < 0 || sum < best)
            best = sum, best_type = f;
    }
    return best_type;
}

pb_result pb_write_png(const char *path, const unsigned char *rgb8, uint32_t width, uint32_t height, pb_error *err)
{
    size_t stride = 3 * (size_t)width, row = stride + 1, raw_n = row * height;
    uLong bound = compressBound((uLong)raw_n);
    unsigned char *raw = malloc(raw_n), *five = malloc(5 * stride);
    unsigned char *b = malloc(8 + 25 + 12 + (size_t)bound + 12);
    pb_result r = PB_OK;
    if (!raw || !five || !b) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for the image", path);
        goto done;
    }
    for (uint32_t y = 0; y < height; ++y) {
        const unsigned char *cur = rgb8 + stride * y, *up = y ? cur - stride : NULL;
        int f = png_filter(cur, up, stride, five);
        raw[row * y] = (unsigned char)f;
        memcpy(raw + row * y + 1, five + (size_t)f * stride, stride);
    }
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    memcpy(b, signature, 8);
    unsigned char *at = b + 8;
    put_be32(at + 8, width), put_be32(at + 12, height);
    at[16] = 8, at[17] = 2, at[18] = 0, at[19] = 0, at[20] = 0; /* 8 bits, RGB, deflate, adaptive, no interlace */
    at = png_chunk(at, "IHDR", 13);
    uLongf zn = bound;
    int z = compress2(at + 8, &zn, raw, (uLong)raw_n, Z_DEFAULT_COMPRESSION);
    if (z != Z_OK) {
        r = pb_fail(err, z == Z_MEM_ERROR ? PB_ERROR_OUT_OF_HOST_MEMORY : PB_ERROR_IO, "%s: cannot compress the image (%s)",
                    path, z == Z_MEM_ERROR ? "out of host memory" : "zlib error");
        goto done;
    }
    at = png_chunk(at, "IDAT", (uint32_t)zn);
    at = png_chunk(at, "IEND", 0);
    r = pb_output_write(path, b, (uint64_t)(at - b), NULL, NULL, err);
done:
    free(raw), free(five), free(b);
    return r;
}

pb_result pb_write_pfm(const char *path, const float *rgba, uint32_t width, uint32_t height, pb_error *err)
{
    char head[64];
    int hl = snprintf(head, sizeof head, "PF\n%u %u\n-1.0\n", width, height);
    size_t size = (size_t)hl + (size_t)width * height * 12;
    unsigned char *b = malloc(size);
    if (!b)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for the image", path);
    memcpy(b, head, (size_t)hl);
    for (uint32_t y = 0; y < height; ++y) { /* PFM rows go bottom to top */
        const float *src = rgba + 4 * (size_t)width * (height - 1 - y);
        for (uint32_t x = 0; x < width; ++x)
            memcpy(b + hl + 12 * ((size_t)width * y + x), src + 4 * x, 12);
    }
    pb_result r = pb_output_write(path, b, size, NULL, NULL, err);
    free(b);
    return r;
}

/* The PFM reader for what pb_write_pfm writes (and any colour PFM): "PF",
 * width, height, a scale whose sign is the byte order, then rows bottom to
 * top. Alpha 1 everywhere (a PFM has none); the caller sets coverage. */
pb_result pb_read_pfm(const char *path, float **rgba, uint32_t *width, uint32_t *height, pb_error *err)
{
    *rgba = NULL;
    *width = *height = 0;
    unsigned char *b = NULL;
    uint64_t size = 0;
    pb_result r = pb_input_read(path, (uint64_t)1 << 32, &b, &size, err);
    if (r != PB_OK)
        return r;
    /* header: three whitespace-separated tokens after "PF" and one whitespace byte */
    char magic[3] = {0};
    unsigned w = 0, h = 0;
    double scale = 0;
    int used = 0;
    if (sscanf((const char *)b, "%2s %u %u %lf%n", magic, &w, &h, &scale, &used) != 4 || strcmp(magic, "PF") ||
        used <= 0 || (uint64_t)used >= size || !(b[used] == '\n' || b[used] == ' ' || b[used] == '\r')) {
        free(b);
        return pb_fail(err, PB_ERROR_IO, "%s: not a colour PFM image (expected \"PF\", width, height, scale)", path);
    }
    uint64_t need = (uint64_t)used + 1 + (uint64_t)w * h * 12;
    if (w == 0 || h == 0 || w > 65536 || h > 65536 || scale == 0.0 || !isfinite(scale) || size < need) {
        free(b);
        return pb_fail(err, PB_ERROR_IO, "%s: PFM of %ux%u needs %llu bytes, has %llu (or a bad size or scale)", path,
                       w, h, (unsigned long long)need, (unsigned long long)size);
    }
    float *img = malloc((size_t)w * h * 16);
    if (!img) {
        free(b);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for a %ux%u image", path, w, h);
    }
    const unsigned char *px = b + used + 1;
    const uint16_t probe = 1;
    int host_little = *(const unsigned char *)&probe == 1, file_little = scale < 0.0;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            float *dst = img + 4 * ((size_t)w * (h - 1 - y) + x);
            for (int c = 0; c < 3; ++c) {
                unsigned char q[4];
                memcpy(q, px + 12 * ((size_t)w * y + x) + 4 * c, 4);
                if (host_little != file_little) {
                    unsigned char t = q[0];
                    q[0] = q[3], q[3] = t, t = q[1], q[1] = q[2], q[2] = t;
                }
                memcpy(&dst[c], q, 4);
            }
            dst[3] = 1.f;
            if (!isfinite(dst[0]) || !isfinite(dst[1]) || !isfinite(dst[2])) {
                free(img), free(b);
                return pb_fail(err, PB_ERROR_IO, "%s: pixel (%u, %u) is not finite", path, x, h - 1 - y);
            }
        }
    free(b);
    *rgba = img, *width = w, *height = h;
    return PB_OK;
}
