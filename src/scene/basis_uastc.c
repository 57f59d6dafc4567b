/* UASTC blocks to RGBA8 (basis_uastc.h). Section names below are the UASTC
 * specification's; "KDFS" is the Khronos Data Format Specification's ASTC
 * chapter. */
#include "scene/basis_uastc.h"

#include "common/common.h"

#include <stdatomic.h>
#include <string.h>

enum { MODES = 19, SOLID = 8, RESERVED = 19 };

/* "List of UASTC Modes": per mode its prefix code (LSB first), weight bits,
 * endpoint BISE range, subsets, weight planes, endpoint components (2 LA,
 * 3 RGB, 4 RGBA), which transcode hints precede the endpoints, and which
 * partition table its pattern index reads. */
enum { NO_PATTERN, PATTERNS2, PATTERNS3, PATTERNS2_BC7_3 };
typedef struct uastc_mode {
    uint8_t code, code_bits;
    uint8_t weight_bits, endpoint_range, subsets, planes, comps;
    uint8_t bc1_hint1, etc1_bias, etc2_hints, compsel_bits, patterns;
} uastc_mode;

static const uastc_mode modes[MODES + 1] = {
    /*        code  len  w  range sub pl comp h1 bias etc2 sel pattern */
    [0] = {0x01, 4, 4, 19, 1, 1, 3, 1, 1, 0, 0, NO_PATTERN},
    [1] = {0x35, 6, 2, 20, 1, 1, 3, 1, 1, 0, 0, NO_PATTERN},
    [2] = {0x1D, 5, 3, 8, 2, 1, 3, 1, 1, 0, 0, PATTERNS2},
    [3] = {0x03, 5, 2, 7, 3, 1, 3, 1, 1, 0, 0, PATTERNS3},
    [4] = {0x13, 5, 2, 12, 2, 1, 3, 1, 1, 0, 0, PATTERNS2},
    [5] = {0x0B, 5, 3, 20, 1, 1, 3, 1, 1, 0, 0, NO_PATTERN},
    [6] = {0x1B, 5, 2, 18, 1, 2, 3, 1, 1, 0, 2, NO_PATTERN},
    [7] = {0x07, 5, 2, 12, 2, 1, 3, 1, 1, 0, 0, PATTERNS2_BC7_3},
    [8] = {0x17, 5, 0, 0, 0, 0, 4, 0, 0, 0, 0, NO_PATTERN}, /* solid colour */
    [9] = {0x0F, 5, 2, 8, 2, 1, 4, 1, 1, 1, 0, PATTERNS2},
    [10] = {0x02, 3, 4, 13, 1, 1, 4, 0, 0, 1, 0, NO_PATTERN},
    [11] = {0x00, 2, 2, 13, 1, 2, 4, 0, 0, 1, 2, NO_PATTERN},
    [12] = {0x06, 3, 3, 19, 1, 1, 4, 0, 0, 1, 0, NO_PATTERN},
    [13] = {0x1F, 5, 1, 20, 1, 2, 4, 1, 1, 1, 2, NO_PATTERN},
    [14] = {0x0D, 5, 2, 20, 1, 1, 4, 1, 1, 1, 0, NO_PATTERN},
    [15] = {0x05, 7, 4, 20, 1, 1, 2, 1, 1, 1, 0, NO_PATTERN},
    [16] = {0x15, 6, 2, 20, 2, 1, 2, 1, 1, 1, 0, PATTERNS2},
    [17] = {0x25, 6, 2, 20, 1, 2, 2, 1, 1, 1, 0, NO_PATTERN}, /* its second plane is alpha's */
    [18] = {0x09, 4, 5, 11, 1, 1, 3, 1, 1, 0, 0, NO_PATTERN},
    [RESERVED] = {0x45, 7, 0, 0, 0, 0, 0, 0, 0, 0, 0, NO_PATTERN},
};

/* The partition patterns UASTC shares with BC7, as the specification prints
 * them: each texel's subset, row by row. */
static const char patterns2[30][17] = {
    "0011001100110011", "0001000100010001", "1000100010001000", "0001001100110111", "1111111011101100",
    "0011011101111111", "1110110010000000", "1111111011001000", "0000000000010011", "1100100000000000",
    "0000000101111111", "1111111111101000", "1110100000000000", "1111111100000000", "0000111111111111",
    "1111111111110000", "1000111011111111", "1111111101110001", "0111001100010000", "0011000100000000",
    "0000100011001110", "1111111101110011", "1000110011001110", "0011000100010000", "1111011101110011",
    "0110011001100110", "1111000000001111", "1010101010101010", "1111000011110000", "1001001101101100",
};
static const char patterns3[11][17] = {
    "0000000011221122", "1111111100002222", "1111000000002222", "1111222200000000",
    "1120112011201120", "0112011201120112", "0211021102110211", "2000200021112111",
    "2012201220122012", "1111000022221111", "0022001100110022",
};
/* mode 7's: two ASTC subsets that BC7 draws with three */
static const char patterns2_bc7_3[19][17] = {
    "0000111100000000", "0010001000100010", "1100110010000000", "0000000100110011", "1111111100001111",
    "0100010001000100", "0001001111111111", "0111001100110011", "1100000000111100", "0111011100000000",
    "0000000011101110", "1100000000001100", "0111001100000000", "0000000111111111", "1111111111110110",
    "1100110011001000", "1111111110001000", "0011011011001000", "1111011100000000",
};

/* "UASTC/ASTC BISE Ranges Table": plain bits, and a trit or a quint above them */
typedef struct bise_range {
    uint8_t bits, trit, quint;
} bise_range;
static const bise_range ranges[21] = {
    {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {0, 0, 1}, {1, 1, 0}, {3, 0, 0}, {1, 0, 1}, {2, 1, 0}, {4, 0, 0}, {2, 0, 1}, {3, 1, 0},
    {5, 0, 0}, {3, 0, 1}, {4, 1, 0}, {6, 0, 0}, {4, 0, 1}, {5, 1, 0}, {7, 0, 0}, {5, 0, 1}, {6, 1, 0}, {8, 0, 0},
};

/* The block's 128 bits, least significant first. */
typedef struct block_bits {
    uint64_t lo, hi;
} block_bits;

static block_bits load_bits(const uint8_t *b)
{
    block_bits v = {0, 0};
    for (int i = 7; i >= 0; --i) {
        v.lo = v.lo << 8 | b[i];
        v.hi = v.hi << 8 | b[8 + i];
    }
    return v;
}

/* bits [at, at + n) of the block; n <= 8, at + n <= 128 */
static uint32_t bits_at(const block_bits *b, uint32_t at, uint32_t n)
{
    uint64_t v = at >= 64 ? b->hi >> (at - 64) : at ? b->lo >> at | b->hi << (64 - at) : b->lo;
    return (uint32_t)v & ((1u << n) - 1);
}

/* KDFS "Color endpoint unquantization": a BISE integer of the range to
 * 0-255. Binary ranges replicate their bits; trit and quint ranges scale
 * the trit or quint and mix in the bits (the B and C of the KDFS table). */
static uint32_t unquantize_endpoint(uint32_t v, bise_range r)
{
    if (!r.trit && !r.quint) {
        uint32_t out = 0;
        for (int shift = 8 - r.bits; shift > -r.bits; shift -= r.bits)
            out |= shift >= 0 ? v << shift : v >> -shift;
        return out & 0xff;
    }
    uint32_t d = v >> r.bits, m = v & ((1u << r.bits) - 1);
    uint32_t a = (m & 1) ? 0x1ff : 0, hi = m >> 1; /* hi: the bits above the lowest, "b", "cb", ... */
    uint32_t b = 0, c = 0;
    if (r.trit) {
        switch (r.bits) {
        case 1: c = 204; break;
        case 2: c = 93, b = hi * 0x116; break;                          /* b000b0bb0 */
        case 3: c = 44, b = (hi >> 1) * 0x10a + (hi & 1) * 0x85; break; /* cb000cbcb */
        case 4: c = 22, b = hi << 6 | hi; break;                        /* dcb000dcb */
        case 5: c = 11, b = hi << 5 | hi >> 2; break;                   /* edcb000ed */
        case 6: c = 5, b = hi << 4 | hi >> 4; break;                    /* fedcb000f */
        }
    } else {
        switch (r.bits) {
        case 1: c = 113; break;
        case 2: c = 54, b = hi * 0x10c; break;                 /* b0000bb00 */
        case 3: c = 26, b = hi << 7 | hi << 1 | hi >> 1; break; /* cb0000cbc */
        case 4: c = 13, b = hi << 6 | hi >> 1; break;           /* dcb0000dc */
        case 5: c = 6, b = hi << 5 | hi >> 3; break;            /* edcb0000e */
        }
    }
    uint32_t t = (d * c + b) ^ a;
    return (a & 0x80) | t >> 2;
}

/* KDFS "Weight unquantization" for plain-bit weights: replicated to 6 bits,
 * then the upper half moved up by one so that the range is 0-64. */
static uint32_t unquantize_weight(uint32_t v, uint32_t bits)
{
    uint32_t out = 0;
    for (int shift = 6 - (int)bits; shift > -(int)bits; shift -= (int)bits)
        out |= shift >= 0 ? v << shift : v >> -shift;
    out &= 63;
    return out + (out > 32);
}

/* KDFS "Weight application", decode mode RGBA8 and no sRGB: endpoints
 * widened to 16 bits by replication, mixed in 1/64ths, the top byte kept. */
static uint8_t interpolate(uint32_t lo, uint32_t hi, uint32_t w)
{
    lo |= lo << 8;
    hi |= hi << 8;
    return (uint8_t)(((lo * (64 - w) + hi * w + 32) >> 6) >> 8);
}

static int mode_of(const uint8_t *block)
{
    for (int m = 0; m <= RESERVED; ++m)
        if ((block[0] & ((1u << modes[m].code_bits) - 1)) == modes[m].code)
            return m;
    return RESERVED; /* unreachable: the codes are complete */
}

/* "ETQ": n values' trits (in groups of 5 in 8 bits) or quints (groups of 3
 * in 7 bits), a short last group in the fewest bits its values need, each
 * group's code t0 + 3 t1 + 9 t2 ... A code past its group's range is not an
 * error: every digit is taken modulo 3 or 5, as Binomial's transcoder reads
 * it (20,000 random blocks decode as it decodes them). */
static void read_trits_quints(const block_bits *block, uint32_t *at, uint32_t n, int trit, uint32_t *out)
{
    static const uint8_t trit_bits[6] = {0, 2, 4, 5, 7, 8}, quint_bits[4] = {0, 3, 5, 7};
    uint32_t per = trit ? 5 : 3, base = trit ? 3 : 5;
    for (uint32_t first = 0; first < n; first += per) {
        uint32_t count = n - first < per ? n - first : per;
        uint32_t bits = trit ? trit_bits[count] : quint_bits[count];
        uint32_t code = bits_at(block, *at, bits);
        *at += bits;
        for (uint32_t i = 0; i < count; ++i, code /= base)
            out[first + i] = code % base;
    }
}

int pb_uastc_block_decode(const uint8_t block[16], uint8_t rgba[64])
{
    int m = mode_of(block);
    if (m == RESERVED)
        return -1;
    const uastc_mode *mode = &modes[m];
    block_bits b = load_bits(block);
    if (m == SOLID) {
        for (uint32_t c = 0; c < 4; ++c)
            rgba[c] = (uint8_t)bits_at(&b, 5 + 8 * c, 8);
        for (uint32_t i = 1; i < 16; ++i)
            memcpy(rgba + 4 * i, rgba, 4);
        return 0;
    }

    /* the transcode hints: BC1 (one or two bits), ETC1 flip, differential
     * and two intensity tables (8 bits), ETC1 bias, ETC2 alpha table */
    uint32_t at = mode->code_bits + 1 + mode->bc1_hint1 + 8 + 5u * mode->etc1_bias + 8u * mode->etc2_hints;

    /* the partition pattern: each texel's subset, and each subset's first
     * texel (its "anchor", whose weight is stored without its top bit) */
    uint8_t subset[16] = {0}, anchor[3] = {0};
    if (mode->patterns != NO_PATTERN) {
        uint32_t count = mode->patterns == PATTERNS2 ? 30 : mode->patterns == PATTERNS3 ? 11 : 19;
        uint32_t pat = bits_at(&b, at, mode->patterns == PATTERNS3 ? 4 : 5);
        at += mode->patterns == PATTERNS3 ? 4 : 5;
        if (pat >= count)
            return -1;
        const char *p = mode->patterns == PATTERNS2 ? patterns2[pat]
                        : mode->patterns == PATTERNS3 ? patterns3[pat] : patterns2_bc7_3[pat];
        for (int i = 15; i >= 0; --i) {
            subset[i] = (uint8_t)(p[i] - '0');
            anchor[subset[i]] = (uint8_t)i;
        }
    }
    /* ASTC's colour component selector: which channel the second plane
     * weighs (mode 17, luminance-alpha, always alpha) */
    uint32_t ccs = 3;
    if (mode->compsel_bits) {
        ccs = bits_at(&b, at, 2);
        at += 2;
    }

    /* endpoints: trits or quints first, then each value's bits */
    bise_range r = ranges[mode->endpoint_range];
    uint32_t n = 2u * mode->comps * mode->subsets, e[18] = {0};
    if (r.trit || r.quint)
        read_trits_quints(&b, &at, n, r.trit, e);
    for (uint32_t i = 0; i < n; ++i) {
        e[i] = e[i] << r.bits | bits_at(&b, at, r.bits);
        at += r.bits;
        e[i] = unquantize_endpoint(e[i], r);
    }

    /* weights in raster order (two per texel with two planes), the anchors'
     * one bit shorter */
    uint32_t w[32];
    for (uint32_t i = 0, k = 0; i < 16; ++i)
        for (uint32_t p = 0; p < mode->planes; ++p, ++k) {
            uint32_t bits = mode->weight_bits - (anchor[subset[i]] == i);
            w[k] = unquantize_weight(bits_at(&b, at, bits), mode->weight_bits);
            at += bits;
        }

    for (uint32_t i = 0; i < 16; ++i) {
        const uint32_t *ep = e + 2u * mode->comps * subset[i];
        uint8_t *out = rgba + 4 * i;
        for (uint32_t c = 0; c < 4; ++c) {
            /* the endpoint pair of channel c: luminance feeds R, G and B */
            uint32_t pair = mode->comps == 2 ? (c < 3 ? 0 : 1) : c;
            uint32_t wt = mode->planes == 2 && c == ccs ? w[2 * i + 1] : w[mode->planes * i];
            out[c] = pair < mode->comps ? interpolate(ep[2 * pair], ep[2 * pair + 1], wt) : 255;
        }
    }
    return 0;
}

/* A range of block rows decoded by one of the host's threads. */
typedef struct image_job {
    const uint8_t *blocks;
    uint64_t blocks_x;
    uint32_t width, height;
    uint8_t *rgba;
    atomic_int invalid; /* a block of some row was invalid */
} image_job;

static void decode_rows(void *user, uint64_t begin, uint64_t end)
{
    image_job *job = user;
    for (uint64_t by = begin; by < end; ++by)
        for (uint64_t bx = 0; bx < job->blocks_x; ++bx) {
            uint8_t texels[64];
            if (pb_uastc_block_decode(job->blocks + 16 * (by * job->blocks_x + bx), texels)) {
                atomic_store(&job->invalid, 1);
                return;
            }
            for (uint32_t y = 0; y < 4 && by * 4 + y < job->height; ++y)
                for (uint32_t x = 0; x < 4 && bx * 4 + x < job->width; ++x)
                    memcpy(job->rgba + 4 * ((by * 4 + y) * job->width + bx * 4 + x), texels + 4 * (4 * y + x), 4);
        }
}

int pb_uastc_image_decode(const uint8_t *blocks, size_t size, uint32_t width, uint32_t height, uint8_t *rgba,
                          const char **why)
{
    uint64_t bw = ((uint64_t)width + 3) / 4, bh = ((uint64_t)height + 3) / 4;
    if (size / 16 < bw * bh) {
        *why = "fewer UASTC blocks than its size needs";
        return -1;
    }
    /* blocks are independent: rows of them on all host cores, in groups of
     * at least 4,096 blocks so that a small image stays on one */
    image_job job = {blocks, bw, width, height, rgba, 0};
    uint64_t grain = bw ? (4096 + bw - 1) / bw : 1;
    pb_parallel_for(bh, grain, 0, decode_rows, &job);
    if (atomic_load(&job.invalid)) {
        *why = "an invalid UASTC block";
        return -1;
    }
    return 0;
}
