/* The KTX 2.0 container around a Basis Universal image (ktx2_read.h). */
#include "scene/ktx2_read.h"

#include "io/ktx2_layout.h"
#include "scene/basis_etc1s.h"
#include "scene/basis_uastc.h"

#include <stdlib.h>
#include <string.h>
#include <zstd.h>
#include <zstd_errors.h>

enum {
    SCHEME_NONE = 0, SCHEME_BASISLZ = 1, SCHEME_ZSTD = 2, /* supercompressionScheme */
    MODEL_ETC1S = 163,                /* the descriptor's colorModel */
    MODEL_UASTC = 166,
    UASTC_RGBA = 3, UASTC_RRRG = 5,   /* UASTC channel ids with alpha */
    SGD_HEADER = 20, IMAGE_DESC = 20, /* BasisLZ global data */
    P_FRAME = 2,                      /* an image desc's flag: a video frame predicted from the one before */
    MAX_SIDE = 1 << 28,
};

static uint32_t u16(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8;
}
static uint32_t u32(const uint8_t *p)
{
    return u16(p) | u16(p + 2) << 16;
}
static uint64_t u64(const uint8_t *p)
{
    return (uint64_t)u32(p) | (uint64_t)u32(p + 4) << 32;
}
/* whether [offset, offset + length) lies inside size bytes */
static int inside(uint64_t offset, uint64_t length, uint64_t size)
{
    return offset <= size && length <= size - offset;
}

int pb_ktx2_is(const uint8_t *bytes, size_t size)
{
    return size >= sizeof pb_ktx2_identifier && memcmp(bytes, pb_ktx2_identifier, sizeof pb_ktx2_identifier) == 0;
}

/* What decoding needs of the container besides the info. */
typedef struct container {
    pb_ktx2_info info;
    uint32_t images;             /* in the file: layers x faces x levels */
    uint32_t scheme;             /* supercompression */
    uint64_t level_off, level_len; /* the base level's bytes */
    uint64_t level_raw_len;      /* ... and their length uncompressed */
    uint64_t sgd_off, sgd_len;   /* supercompression global data */
} container;

static int parse(const uint8_t *p, size_t size, container *c, const char **why)
{
    memset(c, 0, sizeof *c);
    if (!pb_ktx2_is(p, size) || size < PB_KTX2_LEVELS_AT) {
        *why = "not a KTX2 file, or its header is cut short";
        return -1;
    }
    uint32_t vk_format = u32(p + 12), width = u32(p + 20), height = u32(p + 24), depth = u32(p + 28);
    uint32_t layers = u32(p + 32), faces = u32(p + 36), levels = u32(p + 40), scheme = u32(p + 44);
    uint32_t dfd_off = u32(p + 48), dfd_len = u32(p + 52);
    c->sgd_off = u64(p + 64);
    c->sgd_len = u64(p + 72);
    if (width == 0 || height == 0 || depth > 1) {
        *why = "not a 2D texture";
        return -1;
    }
    if (width > MAX_SIDE || height > MAX_SIDE) {
        *why = "wider or taller than 2^28 texels";
        return -1;
    }
    if (faces != 1 && faces != 6) {
        *why = "a face count other than 1 or 6";
        return -1;
    }
    if (levels > 32 || layers > 65536) {
        *why = "more than 32 levels or 65,536 layers";
        return -1;
    }
    if (!inside(PB_KTX2_LEVELS_AT, (uint64_t)PB_KTX2_LEVEL_BYTES * (levels ? levels : 1), size)) {
        *why = "its level index is cut short";
        return -1;
    }
    c->level_off = u64(p + PB_KTX2_LEVELS_AT);
    c->level_len = u64(p + PB_KTX2_LEVELS_AT + 8);
    c->level_raw_len = u64(p + PB_KTX2_LEVELS_AT + 16);
    c->scheme = scheme;
    if (!inside(c->level_off, c->level_len, size)) {
        *why = "its base level lies outside the file";
        return -1;
    }
    c->images = (layers ? layers : 1) * faces * (levels ? levels : 1);

    /* the data format descriptor: its total size, then one basic block */
    if (!inside(dfd_off, dfd_len, size) || dfd_len < 4 + 24) {
        *why = "no data format descriptor";
        return -1;
    }
    const uint8_t *block = p + dfd_off + 4;
    uint32_t block_size = u32(block + 4) >> 16, model = u32(block + 8) & 0xff;
    if ((u32(block) & 0x1ffffu) != 0 || block_size < 24 || block_size > dfd_len - 4 || (block_size - 24) % 16) {
        *why = "a data format descriptor that is not a basic one";
        return -1;
    }
    uint32_t samples = (block_size - 24) / 16; /* ETC1S: 2 with an alpha slice */
    c->info.width = width;
    c->info.height = height;
    if (vk_format == 0 && scheme == SCHEME_BASISLZ && model == MODEL_ETC1S) {
        c->info.codec = PB_KTX2_ETC1S;
        if (samples < 1 || samples > 2) {
            *why = "an ETC1S descriptor with other than 1 or 2 samples";
            return -1;
        }
        c->info.has_alpha = samples == 2;
    } else if (vk_format == 0 && model == MODEL_UASTC) {
        c->info.codec = PB_KTX2_UASTC;
        if (scheme != SCHEME_NONE && scheme != SCHEME_ZSTD) {
            *why = "UASTC under a supercompression other than none or Zstandard";
            return -1;
        }
        uint32_t channel = samples ? (u32(block + 24) >> 24) & 0xf : 0;
        c->info.has_alpha = channel == UASTC_RGBA || channel == UASTC_RRRG;
    } else
        c->info.codec = PB_KTX2_OTHER;
    return 0;
}

int pb_ktx2_peek(const uint8_t *bytes, size_t size, pb_ktx2_info *info, const char **why)
{
    container c;
    if (parse(bytes, size, &c, why))
        return -1;
    *info = c.info;
    return 0;
}

static int decode_etc1s(const uint8_t *p, size_t size, const container *c, uint8_t *rgba, const char **why)
{
    /* the global data: codebook sizes, one image desc per image, then the
     * endpoint codebook, the selector codebook and the slices' codes */
    if (!inside(c->sgd_off, c->sgd_len, size) || c->sgd_len < SGD_HEADER) {
        *why = "no BasisLZ global data";
        return -1;
    }
    const uint8_t *g = p + c->sgd_off;
    uint32_t endpoint_count = u16(g), selector_count = u16(g + 2);
    uint64_t e_len = u32(g + 4), s_len = u32(g + 8), t_len = u32(g + 12), x_len = u32(g + 16);
    uint64_t descs = SGD_HEADER, books = descs + (uint64_t)IMAGE_DESC * c->images;
    if (!inside(books, e_len + s_len + t_len + x_len, c->sgd_len)) {
        *why = "BasisLZ global data cut short";
        return -1;
    }
    const uint8_t *d = g + descs; /* the base level's first image */
    uint32_t flags = u32(d), rgb_off = u32(d + 4), rgb_len = u32(d + 8), a_off = u32(d + 12), a_len = u32(d + 16);
    if (flags & P_FRAME) {
        *why = "a video frame predicted from another";
        return -1;
    }
    if (!inside(rgb_off, rgb_len, c->level_len) || !inside(a_off, a_len, c->level_len) ||
        (c->info.has_alpha && a_len == 0)) {
        *why = "an ETC1S slice outside its level";
        return -1;
    }
    pb_etc1s_codebooks cb;
    if (pb_etc1s_codebooks_read(&cb, g + books, e_len, endpoint_count, g + books + e_len, s_len, selector_count,
                                g + books + e_len + s_len, t_len, why))
        return -1;
    const uint8_t *level = p + c->level_off;
    int r = pb_etc1s_slice_decode(&cb, level + rgb_off, rgb_len, c->info.width, c->info.height, PB_ETC1S_RGB, rgba,
                                  why);
    if (r == 0 && c->info.has_alpha)
        r = pb_etc1s_slice_decode(&cb, level + a_off, a_len, c->info.width, c->info.height, PB_ETC1S_ALPHA, rgba,
                                  why);
    else if (r == 0)
        for (size_t i = 0, n = (size_t)c->info.width * c->info.height; i < n; ++i)
            rgba[4 * i + 3] = 255;
    pb_etc1s_codebooks_free(&cb);
    return r;
}

/* The first n bytes a Zstandard frame of whole bytes decompresses to, into
 * out: 0, or -1 where the frame is corrupt or ends sooner. Streamed, so only
 * the bytes asked for are written whatever size the frame claims. */
static int zstd_prefix(const uint8_t *in, size_t in_len, uint64_t whole, uint8_t *out, size_t n, const char **why)
{
    ZSTD_DCtx *z = ZSTD_createDCtx();
    if (!z) {
        *why = "out of memory";
        return -1;
    }
    /* no window wider than the level's bytes: a frame claiming one is not
     * the level's, and must not make the decoder allocate it */
    int window_log = 10;
    while (window_log < 27 && ((uint64_t)1 << window_log) < whole)
        ++window_log;
    ZSTD_DCtx_setParameter(z, ZSTD_d_windowLogMax, window_log);
    ZSTD_inBuffer src = {in, in_len, 0};
    ZSTD_outBuffer dst = {out, n, 0};
    size_t r = 1;
    while (dst.pos < n && r != 0) {
        size_t before_in = src.pos, before_out = dst.pos;
        r = ZSTD_decompressStream(z, &dst, &src);
        if (ZSTD_isError(r) || (src.pos == before_in && dst.pos == before_out))
            break; /* an error, or no progress: the input ends inside the frame */
    }
    ZSTD_freeDCtx(z);
    if (dst.pos < n) {
        *why = ZSTD_isError(r) && ZSTD_getErrorCode(r) == ZSTD_error_memory_allocation
                   ? "out of memory"
                   : "its Zstandard-compressed level is corrupt or cut short";
        return -1;
    }
    return 0;
}

/* UASTC: the base level's first image is its first ceil(w/4) x ceil(h/4)
 * blocks, stored as they are or in one Zstandard frame. */
static int decode_uastc(const uint8_t *p, const container *c, uint8_t *rgba, const char **why)
{
    uint64_t need = 16 * (((uint64_t)c->info.width + 3) / 4) * (((uint64_t)c->info.height + 3) / 4);
    const uint8_t *level = p + c->level_off;
    if (c->scheme == SCHEME_NONE)
        return pb_uastc_image_decode(level, (size_t)c->level_len, c->info.width, c->info.height, rgba, why);
    if (c->level_raw_len < need) {
        *why = "its base level uncompressed is smaller than its blocks";
        return -1;
    }
    uint8_t *blocks = malloc((size_t)need);
    if (!blocks) {
        *why = "out of memory";
        return -1;
    }
    int r = zstd_prefix(level, (size_t)c->level_len, c->level_raw_len, blocks, (size_t)need, why);
    if (r == 0)
        r = pb_uastc_image_decode(blocks, (size_t)need, c->info.width, c->info.height, rgba, why);
    free(blocks);
    return r;
}

int pb_ktx2_decode(const uint8_t *bytes, size_t size, uint8_t *rgba, const char **why)
{
    container c;
    if (parse(bytes, size, &c, why))
        return -1;
    switch (c.info.codec) {
    case PB_KTX2_ETC1S:
        return decode_etc1s(bytes, size, &c, rgba, why);
    case PB_KTX2_UASTC:
        return decode_uastc(bytes, &c, rgba, why);
    default:
        *why = "neither ETC1S nor UASTC, the formats KHR_texture_basisu allows";
        return -1;
    }
}
