/* ETC1S slices of a BasisLZ stream to RGBA8 (basis_etc1s.h). The order of
 * the file: prefix codes (section 6 of the .basis specification), the
 * endpoint codebook (7), the selector codebook (8), the slices' codes (9),
 * then each slice's blocks (10). */
#include "scene/basis_etc1s.h"

#include <stdlib.h>
#include <string.h>

/* ---- bits, least significant first ---------------------------------- */

typedef struct bit_reader {
    const uint8_t *p;
    size_t size, pos; /* pos in bits */
    int overrun;      /* a read went past the end: the stream is corrupt */
} bit_reader;

static uint32_t get_bits(bit_reader *b, unsigned n)
{
    uint32_t v = 0;
    for (unsigned i = 0; i < n; ++i, ++b->pos) {
        size_t byte = b->pos >> 3;
        if (byte >= b->size) {
            b->overrun = 1;
            continue;
        }
        v |= (uint32_t)((b->p[byte] >> (b->pos & 7)) & 1u) << i;
    }
    return v;
}

/* ---- canonical prefix codes, as Deflate's (RFC 1951, 3.2.2) ---------- */

enum { MAX_CODE_BITS = 16, MAX_SYMBOLS = 1 << 14 };

struct pb_etc1s_huffman {
    uint16_t count[MAX_CODE_BITS + 1]; /* codes of each length */
    uint16_t *symbol;                  /* symbols by code: by length, then by value */
    uint32_t used;                     /* symbols with a code; 0: the table is empty */
};

static void huffman_free(pb_etc1s_huffman *h)
{
    if (h)
        free(h->symbol);
    free(h);
}

/* The code from n symbols' lengths (0: no code). An over-subscribed set of
 * lengths is corrupt; an incomplete one is allowed, as the encoder makes one
 * for a single symbol, and a code it never sent simply fails to decode. */
static pb_etc1s_huffman *huffman_make(const uint8_t *length, uint32_t n, const char **why)
{
    pb_etc1s_huffman *h = calloc(1, sizeof *h);
    if (!h || !(h->symbol = malloc(sizeof *h->symbol * (n ? n : 1)))) {
        huffman_free(h);
        *why = "out of memory";
        return NULL;
    }
    for (uint32_t s = 0; s < n; ++s)
        h->count[length[s]]++;
    h->count[0] = 0;
    int32_t left = 1;
    uint16_t offset[MAX_CODE_BITS + 2] = {0};
    for (int len = 1; len <= MAX_CODE_BITS; ++len) {
        left = 2 * left - h->count[len];
        if (left < 0) {
            huffman_free(h);
            *why = "an over-subscribed prefix code";
            return NULL;
        }
        offset[len + 1] = (uint16_t)(offset[len] + h->count[len]);
    }
    for (uint32_t s = 0; s < n; ++s)
        if (length[s])
            h->symbol[offset[length[s]]++] = (uint16_t)s;
    h->used = offset[MAX_CODE_BITS + 1];
    return h;
}

/* One symbol, its code's first bit read first; -1 where no code matches. */
static int32_t huffman_decode(bit_reader *b, const pb_etc1s_huffman *h)
{
    int32_t code = 0, first = 0, index = 0;
    for (int len = 1; len <= MAX_CODE_BITS; ++len) {
        code |= (int32_t)get_bits(b, 1);
        int32_t count = h->count[len];
        if (code - first < count)
            return b->overrun ? -1 : h->symbol[index + code - first];
        index += count;
        first = (first + count) << 1;
        code <<= 1;
    }
    return -1;
}

/* A prefix code as BasisLZ sends it: its lengths, run-length coded with a
 * second, small prefix code whose own lengths come first (3 bits each, in
 * an order that puts the likely ones first). An empty table (no symbols)
 * is valid: the stream then never decodes from it. */
static pb_etc1s_huffman *huffman_read(bit_reader *b, const char **why)
{
    static const uint8_t order[21] = {17, 18, 19, 20, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15, 16};
    uint32_t total = get_bits(b, 14);
    if (total == 0)
        return huffman_make(NULL, 0, why);
    uint32_t n_lengths = get_bits(b, 5);
    if (n_lengths < 1 || n_lengths > 21) {
        *why = "a prefix code of more than 21 length codes";
        return NULL;
    }
    uint8_t length_code_lengths[21] = {0};
    for (uint32_t i = 0; i < n_lengths; ++i)
        length_code_lengths[order[i]] = (uint8_t)get_bits(b, 3);
    pb_etc1s_huffman *lengths_code = huffman_make(length_code_lengths, 21, why);
    uint8_t *length = calloc(total, 1);
    if (!lengths_code || !length) {
        huffman_free(lengths_code);
        free(length);
        if (lengths_code)
            *why = "out of memory";
        return NULL;
    }
    *why = NULL;
    for (uint32_t cur = 0; cur < total && !*why;) {
        int32_t c = huffman_decode(b, lengths_code);
        uint32_t run = 0;
        if (c < 0)
            *why = "an invalid prefix code length";
        else if (c <= 16)
            length[cur++] = (uint8_t)c;
        else if (c == 17 || c == 18) { /* runs of unused symbols */
            run = c == 17 ? get_bits(b, 3) + 3 : get_bits(b, 7) + 11;
            if (run > total - cur)
                *why = "a prefix code's lengths run past its symbols";
            else
                cur += run;
        } else { /* 19, 20: the previous length repeated */
            run = c == 19 ? get_bits(b, 2) + 3 : get_bits(b, 7) + 7;
            if (cur == 0 || length[cur - 1] == 0 || run > total - cur)
                *why = "a prefix code's repeated length has nothing to repeat";
            else
                for (; run; --run, ++cur)
                    length[cur] = length[cur - 1];
        }
    }
    pb_etc1s_huffman *h = NULL;
    if (!*why && b->overrun)
        *why = "truncated prefix code";
    if (!*why)
        h = huffman_make(length, total, why);
    huffman_free(lengths_code);
    free(length);
    return h;
}

/* ---- codebooks ------------------------------------------------------- */

static int read_endpoints(pb_etc1s_codebooks *cb, const uint8_t *p, size_t size, const char **why)
{
    bit_reader b = {p, size, 0, 0};
    pb_etc1s_huffman *color[3] = {NULL, NULL, NULL}, *inten = NULL;
    int ok = (color[0] = huffman_read(&b, why)) && (color[1] = huffman_read(&b, why)) &&
             (color[2] = huffman_read(&b, why)) && (inten = huffman_read(&b, why));
    if (ok) {
        int grey = (int)get_bits(&b, 1);
        /* each colour channel is a delta from the previous endpoint's, with
         * a code chosen by that previous value's third of the range */
        uint8_t prev[3] = {16, 16, 16}, prev_inten = 0;
        for (uint32_t i = 0; i < cb->endpoint_count && ok; ++i) {
            int32_t d = huffman_decode(&b, inten);
            ok = d >= 0;
            cb->endpoints[i].inten = prev_inten = (uint8_t)((d + prev_inten) & 7);
            for (int c = 0; c < (grey ? 1 : 3) && ok; ++c) {
                const pb_etc1s_huffman *h = prev[c] <= 9 ? color[0] : prev[c] <= 21 ? color[1] : color[2];
                d = huffman_decode(&b, h);
                ok = d >= 0;
                cb->endpoints[i].color5[c] = prev[c] = (uint8_t)((prev[c] + d) & 31);
            }
            if (grey)
                cb->endpoints[i].color5[1] = cb->endpoints[i].color5[2] = cb->endpoints[i].color5[0];
        }
        if (!ok || b.overrun) {
            ok = 0;
            *why = "corrupt endpoint codebook";
        }
    }
    for (int c = 0; c < 3; ++c)
        huffman_free(color[c]);
    huffman_free(inten);
    return ok ? 0 : -1;
}

static int read_selectors(pb_etc1s_codebooks *cb, const uint8_t *p, size_t size, const char **why)
{
    bit_reader b = {p, size, 0, 0};
    uint32_t global = get_bits(&b, 1), hybrid = get_bits(&b, 1), raw = get_bits(&b, 1);
    if (global || hybrid) {
        *why = "global selector codebooks (never written by Basis Universal)";
        return -1;
    }
    pb_etc1s_huffman *delta = NULL;
    if (!raw && !(delta = huffman_read(&b, why)))
        return -1;
    /* each selector's four row bytes, raw or as a XOR with the previous */
    uint8_t prev[4] = {0, 0, 0, 0};
    int ok = 1;
    for (uint32_t i = 0; i < cb->selector_count && ok; ++i) {
        uint32_t s = 0;
        for (int row = 0; row < 4; ++row) {
            int32_t v = raw || i == 0 ? (int32_t)get_bits(&b, 8) : huffman_decode(&b, delta);
            if (v < 0 || v > 255) {
                ok = 0;
                break;
            }
            prev[row] = raw || i == 0 ? (uint8_t)v : (uint8_t)(v ^ prev[row]);
            s |= (uint32_t)prev[row] << (8 * row);
        }
        cb->selectors[i] = s;
    }
    huffman_free(delta);
    if (!ok || b.overrun) {
        *why = "corrupt selector codebook";
        return -1;
    }
    return 0;
}

static int read_tables(pb_etc1s_codebooks *cb, const uint8_t *p, size_t size, const char **why)
{
    bit_reader b = {p, size, 0, 0};
    if (!(cb->endpoint_pred = huffman_read(&b, why)) || !(cb->delta_endpoint = huffman_read(&b, why)) ||
        !(cb->selector = huffman_read(&b, why)) || !(cb->selector_rle = huffman_read(&b, why)))
        return -1;
    cb->history_size = get_bits(&b, 13);
    if (b.overrun) {
        *why = "truncated slice tables";
        return -1;
    }
    if (cb->history_size > 64) {
        *why = "a selector history longer than 64";
        return -1;
    }
    return 0;
}

void pb_etc1s_codebooks_free(pb_etc1s_codebooks *cb)
{
    free(cb->endpoints);
    free(cb->selectors);
    huffman_free(cb->endpoint_pred);
    huffman_free(cb->delta_endpoint);
    huffman_free(cb->selector);
    huffman_free(cb->selector_rle);
    memset(cb, 0, sizeof *cb);
}

int pb_etc1s_codebooks_read(pb_etc1s_codebooks *cb, const uint8_t *endpoints, size_t endpoints_size,
                            uint32_t endpoint_count, const uint8_t *selectors, size_t selectors_size,
                            uint32_t selector_count, const uint8_t *tables, size_t tables_size, const char **why)
{
    memset(cb, 0, sizeof *cb);
    if (endpoint_count == 0 || selector_count == 0) {
        *why = "an empty endpoint or selector codebook";
        return -1;
    }
    cb->endpoint_count = endpoint_count;
    cb->selector_count = selector_count;
    cb->endpoints = calloc(endpoint_count, sizeof *cb->endpoints);
    cb->selectors = calloc(selector_count, sizeof *cb->selectors);
    if (!cb->endpoints || !cb->selectors) {
        pb_etc1s_codebooks_free(cb);
        *why = "out of memory";
        return -1;
    }
    if (read_endpoints(cb, endpoints, endpoints_size, why) || read_selectors(cb, selectors, selectors_size, why) ||
        read_tables(cb, tables, tables_size, why)) {
        pb_etc1s_codebooks_free(cb);
        return -1;
    }
    return 0;
}

/* ---- slices ---------------------------------------------------------- */

/* A run length sent in chunks of chunk_bits, each followed by a bit that
 * says whether another chunk follows (section 10.2). */
static uint32_t get_vlc(bit_reader *b, unsigned chunk_bits)
{
    uint32_t v = 0;
    for (unsigned shift = 0; shift < 32; shift += chunk_bits) {
        uint32_t s = get_bits(b, chunk_bits + 1);
        v |= (s & ((1u << chunk_bits) - 1)) << shift;
        if (!(s >> chunk_bits) || b->overrun)
            break;
    }
    return v;
}

/* ETC1's intensity modifiers (Khronos Data Format, ETC1), in the order of
 * BasisLZ's selectors: most negative first */
static const int16_t inten_table[8][4] = {{-8, -2, 2, 8},       {-17, -5, 5, 17},     {-29, -9, 9, 29},
                                          {-42, -13, 13, 42},   {-60, -18, 18, 60},   {-80, -24, 24, 80},
                                          {-106, -33, 33, 106}, {-183, -47, 47, 183}};

static uint8_t clamp255(int v)
{
    return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
}

static void write_block(const pb_etc1s_endpoint *e, uint32_t sel, uint32_t bx, uint32_t by, uint32_t width,
                        uint32_t height, int channels, uint8_t *rgba)
{
    uint8_t colour[4][3];
    for (int c = 0; c < 3; ++c) {
        int base = (e->color5[c] << 3) | (e->color5[c] >> 2);
        for (int s = 0; s < 4; ++s)
            colour[s][c] = clamp255(base + inten_table[e->inten][s]);
    }
    for (uint32_t y = 0; y < 4 && by * 4 + y < height; ++y)
        for (uint32_t x = 0; x < 4 && bx * 4 + x < width; ++x) {
            const uint8_t *c = colour[(sel >> (8 * y + 2 * x)) & 3];
            uint8_t *px = rgba + ((size_t)(by * 4 + y) * width + bx * 4 + x) * 4;
            if (channels == PB_ETC1S_ALPHA)
                px[3] = c[1];
            else
                px[0] = c[0], px[1] = c[1], px[2] = c[2];
        }
}

/* The selector history: recently used selector indices, a used one moved
 * halfway to the front (section 10.1's approximate move to front). */
typedef struct history {
    uint32_t value[64];
    uint32_t size, rover;
} history;

static void history_add(history *h, uint32_t v)
{
    h->value[h->rover++] = v;
    if (h->rover == h->size)
        h->rover = h->size / 2;
}

static void history_use(history *h, uint32_t i)
{
    uint32_t t = h->value[i / 2];
    h->value[i / 2] = h->value[i];
    h->value[i] = t;
}

int pb_etc1s_slice_decode(const pb_etc1s_codebooks *cb, const uint8_t *data, size_t size, uint32_t width,
                          uint32_t height, int channels, uint8_t *rgba, const char **why)
{
    enum { PRED_REPEAT = 256, PRED_MIN_REPEAT = 3, PRED_VLC_BITS = 4, RLE_MIN = 3, RLE_LONG = 63 };
    const uint32_t bw = (width + 3) / 4, bh = (height + 3) / 4;
    /* per column, two rows: the endpoint index used there, and the
     * prediction bits an even row leaves for the odd row below it */
    struct column {
        uint32_t endpoint;
        uint32_t pred;
    } *row[2];
    row[0] = calloc((size_t)bw * 2, sizeof *row[0]);
    if (!row[0]) {
        *why = "out of memory";
        return -1;
    }
    row[1] = row[0] + bw;
    const uint32_t history_first = cb->selector_count, rle_symbol = cb->selector_count + cb->history_size;
    history hist = {{0}, cb->history_size, cb->history_size / 2};
    bit_reader b = {data, size, 0, 0};
    uint32_t pred_bits = 0, prev_pred = 0, pred_repeat = 0, prev_endpoint = 0, rle = 0;
    *why = NULL;
    for (uint32_t by = 0; by < bh && !*why; ++by) {
        struct column *cur = row[by & 1], *up = row[(by & 1) ^ 1];
        for (uint32_t bx = 0; bx < bw && !*why; ++bx) {
            if ((bx & 1) == 0) {
                if ((by & 1) == 0) { /* one symbol predicts a 2 x 2 group, 2 bits a block */
                    if (pred_repeat) {
                        pred_repeat--;
                        pred_bits = prev_pred;
                    } else {
                        int32_t s = huffman_decode(&b, cb->endpoint_pred);
                        if (s < 0 || s > PRED_REPEAT) {
                            *why = "corrupt endpoint prediction";
                            break;
                        }
                        if (s == PRED_REPEAT) {
                            pred_repeat = get_vlc(&b, PRED_VLC_BITS) + PRED_MIN_REPEAT - 1;
                            pred_bits = prev_pred;
                        } else
                            pred_bits = prev_pred = (uint32_t)s;
                    }
                    up[bx].pred = pred_bits >> 4; /* the odd row's two blocks */
                } else
                    pred_bits = cur[bx].pred;
            }
            uint32_t pred = pred_bits & 3, endpoint = 0;
            pred_bits >>= 2;
            if (pred == 0) /* the previous block's */
                endpoint = prev_endpoint;
            else if (pred == 1) /* the block above's */
                endpoint = up[bx].endpoint;
            else if (pred == 2) { /* the block above-left's */
                if (bx == 0) {
                    *why = "an endpoint predicted from left of the image";
                    break;
                }
                endpoint = up[bx - 1].endpoint;
            } else {
                int32_t d = huffman_decode(&b, cb->delta_endpoint);
                if (d < 0 || (uint32_t)d >= cb->endpoint_count) {
                    *why = "corrupt endpoint index";
                    break;
                }
                endpoint = prev_endpoint + (uint32_t)d;
                if (endpoint >= cb->endpoint_count)
                    endpoint -= cb->endpoint_count;
            }
            cur[bx].endpoint = prev_endpoint = endpoint;

            int64_t sym;
            if (rle) {
                rle--;
                sym = history_first;
            } else {
                sym = huffman_decode(&b, cb->selector);
                if (sym == rle_symbol && cb->history_size) {
                    int32_t run = huffman_decode(&b, cb->selector_rle);
                    if (run < 0) {
                        *why = "corrupt selector run";
                        break;
                    }
                    rle = (run == RLE_LONG ? get_vlc(&b, 7) : (uint32_t)run) + RLE_MIN - 1;
                    sym = history_first;
                }
            }
            uint32_t selector;
            if (sym < 0 || sym >= (int64_t)rle_symbol) {
                *why = "corrupt selector index";
                break;
            } else if (sym >= history_first) {
                uint32_t i = (uint32_t)(sym - history_first);
                selector = hist.value[i];
                if (i)
                    history_use(&hist, i);
            } else {
                selector = (uint32_t)sym;
                if (hist.size)
                    history_add(&hist, selector);
            }
            if (selector >= cb->selector_count) {
                *why = "corrupt selector history";
                break;
            }
            write_block(&cb->endpoints[endpoint], cb->selectors[selector], bx, by, width, height, channels, rgba);
        }
        if (!*why && b.overrun)
            *why = "truncated slice";
    }
    free(row[0]);
    return *why ? -1 : 0;
}
