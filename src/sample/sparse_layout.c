/* The sparse layout's bricks, probes and lookup tables (probebake/sparse.h).
 * Building is host work done once per bake; the lookup (pb_sparse_find) is
 * the C reference of pb_sparse_brick_at in probe_sample_core.glsl. */
#include "common/common.h"
#include "common/key_map.h"
#include "probebake/sparse.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

uint32_t pb_sparse_step(uint32_t levels, uint32_t level)
{
    uint32_t s = 1;
    for (uint32_t l = level + 1; l < levels; ++l)
        s *= 3;
    return s;
}

static uint32_t pow3(uint32_t e)
{
    uint32_t p = 1;
    while (e--)
        p *= 3;
    return p;
}

uint64_t pb_sparse_coarsest_cell(const uint32_t cells[3], const pb_sparse_brick *br)
{
    uint32_t per = pow3(br->level), c[3];
    for (int k = 0; k < 3; ++k)
        c[k] = br->coord[k] / per;
    return c[0] + (uint64_t)cells[0] * (c[1] + (uint64_t)cells[1] * c[2]);
}

/* (level, brick coordinates) as one key: coordinates below 2^20 per axis */
static uint64_t brick_key(uint32_t level, const uint32_t c[3])
{
    return (uint64_t)level << 60 | (uint64_t)c[2] << 40 | (uint64_t)c[1] << 20 | c[0];
}

void pb_sparse_layout_free(pb_sparse_layout *l)
{
    free(l->bricks), free(l->brick_probes), free(l->indirection), free(l->chunks);
    memset(l, 0, sizeof *l);
}

static uint64_t cell_count(const uint32_t cells[3])
{
    return (uint64_t)cells[0] * cells[1] * cells[2];
}

pb_result pb_sparse_layout_build(uint32_t levels, const uint32_t cells[3], const pb_sparse_brick *bricks,
                                 uint32_t count, pb_sparse_layout *out, uint32_t *probe_count, uint32_t **keys_out,
                                 pb_error *err)
{
    memset(out, 0, sizeof *out);
    *probe_count = 0;
    if (keys_out)
        *keys_out = NULL;
    if (levels < 1 || levels > PB_SPARSE_MAX_LEVELS)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse layout: %u levels (1 to %u)", levels,
                       PB_SPARSE_MAX_LEVELS);
    uint64_t C = cell_count(cells);
    if (C == 0 || C > (1u << 24) || count == 0 || count > (1u << 22))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse layout: %llu cells, %u bricks",
                       (unsigned long long)C, count);
    for (int k = 0; k < 3; ++k)
        if ((uint64_t)cells[k] * pow3(levels) >= (1u << 20))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse layout: %u cells on axis %d is too many", cells[k],
                           k);
    out->levels = levels;
    memcpy(out->cells, cells, sizeof out->cells);
    out->brick_count = count;
    out->bricks = malloc((size_t)count * sizeof *out->bricks);
    out->brick_probes = malloc((size_t)count * PB_SPARSE_BRICK_PROBES * sizeof(uint32_t));
    out->indirection = malloc(C * sizeof(uint32_t));
    uint8_t *depth = calloc(C, 1);
    uint32_t *keys = malloc((size_t)count * PB_SPARSE_BRICK_PROBES * 3 * sizeof(uint32_t));
    pb_key_map bm = {0}, pm = {0};
    pb_result r = PB_OK;
    if (!out->bricks || !out->brick_probes || !out->indirection || !depth || !keys || !pb_key_map_init(&bm, count) ||
        !pb_key_map_init(&pm, (uint64_t)count * 27)) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u bricks", count);
        goto done;
    }
    memcpy(out->bricks, bricks, (size_t)count * sizeof *bricks);
    /* bricks by (level, coordinates); each cell's depth is its finest brick's level */
    for (uint32_t b = 0; b < count; ++b) {
        const pb_sparse_brick *br = &bricks[b];
        if (br->level >= levels) {
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse layout: brick %u has level %u of %u", b, br->level,
                        levels);
            goto done;
        }
        uint32_t per = pow3(br->level), cell[3];
        for (int k = 0; k < 3; ++k) {
            if (br->coord[k] >= cells[k] * per) {
                r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse layout: brick %u lies outside the cells", b);
                goto done;
            }
            cell[k] = br->coord[k] / per;
        }
        uint64_t key = brick_key(br->level, br->coord);
        if (pb_key_map_get(&bm, key) != PB_KEY_MAP_MISSING) {
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse layout: brick %u appears twice", b);
            goto done;
        }
        if (!pb_key_map_put(&bm, key, b)) {
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u bricks", count);
            goto done;
        }
        uint64_t c = cell[0] + (uint64_t)cells[0] * (cell[1] + (uint64_t)cells[1] * cell[2]);
        if (br->level > depth[c])
            depth[c] = (uint8_t)br->level;
    }
    /* probes: one per finest-lattice point, numbered in order of first use */
    uint64_t X = (uint64_t)cells[0] * pow3(levels) + 1, Y = (uint64_t)cells[1] * pow3(levels) + 1;
    uint32_t P = 0;
    for (uint32_t b = 0; b < count; ++b) {
        const pb_sparse_brick *br = &bricks[b];
        uint32_t step = pb_sparse_step(levels, br->level);
        for (uint32_t i = 0; i < PB_SPARSE_BRICK_PROBES; ++i) {
            uint32_t off[3] = {i & 3u, (i >> 2) & 3u, i >> 4}, key3[3];
            for (int k = 0; k < 3; ++k)
                key3[k] = (3 * br->coord[k] + off[k]) * step;
            uint64_t key = key3[0] + X * (key3[1] + Y * (uint64_t)key3[2]);
            uint32_t p = pb_key_map_get(&pm, key);
            if (p == PB_KEY_MAP_MISSING) {
                p = P++;
                if (!pb_key_map_put(&pm, key, p)) {
                    r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse probes");
                    goto done;
                }
                memcpy(keys + 3 * (size_t)p, key3, sizeof key3);
            }
            out->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)b + i] = p;
        }
    }
    /* indirection and chunks */
    uint64_t chunk_entries = 0;
    for (uint64_t c = 0; c < C; ++c)
        if (depth[c])
            chunk_entries += (uint64_t)pow3(3 * depth[c]);
    if (chunk_entries >= PB_SPARSE_EMPTY) {
        r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse layout: %llu chunk entries is too many",
                    (unsigned long long)chunk_entries);
        goto done;
    }
    out->chunk_count = (uint32_t)chunk_entries;
    out->chunks = malloc((chunk_entries ? chunk_entries : 1) * sizeof(uint32_t));
    if (!out->chunks) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %llu chunk entries",
                    (unsigned long long)chunk_entries);
        goto done;
    }
    uint32_t next = 0;
    for (uint32_t z = 0; z < cells[2]; ++z)
        for (uint32_t y = 0; y < cells[1]; ++y)
            for (uint32_t x = 0; x < cells[0]; ++x) {
                uint64_t c = x + (uint64_t)cells[0] * (y + (uint64_t)cells[1] * z);
                uint32_t cell[3] = {x, y, z}, d = depth[c];
                if (d == 0) {
                    uint32_t b = pb_key_map_get(&bm, brick_key(0, cell));
                    out->indirection[c] = b == PB_KEY_MAP_MISSING ? PB_SPARSE_EMPTY : b;
                    continue;
                }
                out->indirection[c] = d << PB_SPARSE_DEPTH_SHIFT | next;
                uint32_t n = pow3(d);
                for (uint32_t sz = 0; sz < n; ++sz)
                    for (uint32_t sy = 0; sy < n; ++sy)
                        for (uint32_t sx = 0; sx < n; ++sx) {
                            uint32_t s[3] = {sx, sy, sz}, found = PB_SPARSE_EMPTY;
                            for (int l = (int)d; l >= 0 && found == PB_SPARSE_EMPTY; --l) {
                                uint32_t per = pow3((uint32_t)l), sub = pow3(d - (uint32_t)l), bc[3];
                                for (int k = 0; k < 3; ++k)
                                    bc[k] = cell[k] * per + s[k] / sub;
                                uint32_t b = pb_key_map_get(&bm, brick_key((uint32_t)l, bc));
                                if (b != PB_KEY_MAP_MISSING)
                                    found = b;
                            }
                            out->chunks[next++] = found;
                        }
            }
    *probe_count = P;
    if (keys_out) {
        uint32_t *shrunk = realloc(keys, (size_t)P * 3 * sizeof(uint32_t));
        *keys_out = shrunk ? shrunk : keys;
        keys = NULL;
    }
done:
    free(depth), free(keys);
    pb_key_map_free(&bm), pb_key_map_free(&pm);
    if (r != PB_OK)
        pb_sparse_layout_free(out);
    return r;
}

pb_result pb_sparse_layout_copy(const pb_sparse_layout *src, pb_sparse_layout *dst, pb_error *err)
{
    memset(dst, 0, sizeof *dst);
    *dst = *src;
    size_t C = (size_t)cell_count(src->cells);
    dst->bricks = malloc((size_t)src->brick_count * sizeof *dst->bricks);
    dst->brick_probes = malloc((size_t)src->brick_count * PB_SPARSE_BRICK_PROBES * sizeof(uint32_t));
    dst->indirection = malloc(C * sizeof(uint32_t));
    dst->chunks = malloc((src->chunk_count ? src->chunk_count : 1) * sizeof(uint32_t));
    if (!dst->bricks || !dst->brick_probes || !dst->indirection || !dst->chunks) {
        pb_sparse_layout_free(dst);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse layout");
    }
    memcpy(dst->bricks, src->bricks, (size_t)src->brick_count * sizeof *dst->bricks);
    memcpy(dst->brick_probes, src->brick_probes, (size_t)src->brick_count * PB_SPARSE_BRICK_PROBES * sizeof(uint32_t));
    memcpy(dst->indirection, src->indirection, C * sizeof(uint32_t));
    memcpy(dst->chunks, src->chunks, (size_t)src->chunk_count * sizeof(uint32_t));
    return PB_OK;
}

pb_result pb_sparse_layout_validate(const pb_sparse_layout *l, uint32_t probe_count, pb_error *err)
{
    if (l->levels < 1 || l->levels > PB_SPARSE_MAX_LEVELS)
        return pb_fail(err, PB_ERROR_PARSE, "sparse layout with %u levels (1 to %u)", l->levels, PB_SPARSE_MAX_LEVELS);
    uint64_t C = cell_count(l->cells);
    if (C == 0 || C > (1u << 24))
        return pb_fail(err, PB_ERROR_PARSE, "sparse layout with %llu cells", (unsigned long long)C);
    for (int k = 0; k < 3; ++k)
        if ((uint64_t)l->cells[k] * pow3(l->levels) >= (1u << 20))
            return pb_fail(err, PB_ERROR_PARSE, "sparse layout with %u cells on axis %d", l->cells[k], k);
    for (uint32_t b = 0; b < l->brick_count; ++b) {
        const pb_sparse_brick *br = &l->bricks[b];
        if (br->level >= l->levels)
            return pb_fail(err, PB_ERROR_PARSE, "sparse brick %u has level %u of %u", b, br->level, l->levels);
        for (int k = 0; k < 3; ++k)
            if (br->coord[k] >= l->cells[k] * pow3(br->level))
                return pb_fail(err, PB_ERROR_PARSE, "sparse brick %u lies outside the cells", b);
        for (uint32_t i = 0; i < PB_SPARSE_BRICK_PROBES; ++i)
            if (l->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)b + i] >= probe_count)
                return pb_fail(err, PB_ERROR_PARSE, "sparse brick %u names probe %u of %u", b,
                               l->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)b + i], probe_count);
    }
    for (uint32_t z = 0; z < l->cells[2]; ++z)
        for (uint32_t y = 0; y < l->cells[1]; ++y)
            for (uint32_t x = 0; x < l->cells[0]; ++x) {
                uint64_t c = x + (uint64_t)l->cells[0] * (y + (uint64_t)l->cells[1] * z);
                uint32_t e = l->indirection[c], d = e >> PB_SPARSE_DEPTH_SHIFT, off = e & PB_SPARSE_EMPTY;
                uint32_t cell[3] = {x, y, z};
                if (d >= l->levels)
                    return pb_fail(err, PB_ERROR_PARSE, "sparse cell %llu has depth %u", (unsigned long long)c, d);
                uint32_t n = pow3(d);
                if (d > 0 && (uint64_t)off + (uint64_t)n * n * n > l->chunk_count)
                    return pb_fail(err, PB_ERROR_PARSE, "sparse cell %llu points past the chunks",
                                   (unsigned long long)c);
                for (uint32_t s = 0; s < n * n * n; ++s) {
                    uint32_t b = d ? l->chunks[off + s] : off;
                    if (b == PB_SPARSE_EMPTY)
                        continue;
                    if (b >= l->brick_count)
                        return pb_fail(err, PB_ERROR_PARSE, "sparse cell %llu names brick %u of %u",
                                       (unsigned long long)c, b, l->brick_count);
                    /* the brick must cover the sub-cell */
                    const pb_sparse_brick *br = &l->bricks[b];
                    if (br->level > d)
                        return pb_fail(err, PB_ERROR_PARSE, "sparse cell %llu names a brick finer than its depth",
                                       (unsigned long long)c);
                    uint32_t sub[3] = {s % n, (s / n) % n, s / (n * n)}, div = pow3(d - br->level);
                    for (int k = 0; k < 3; ++k)
                        if (br->coord[k] != cell[k] * pow3(br->level) + sub[k] / div)
                            return pb_fail(err, PB_ERROR_PARSE, "sparse cell %llu names brick %u elsewhere",
                                           (unsigned long long)c, b);
                }
            }
    return PB_OK;
}

void pb_sparse_probe_levels(const pb_sparse_layout *l, uint32_t P, uint8_t *finest, uint32_t *first)
{
    for (uint32_t p = 0; p < P; ++p) {
        if (finest)
            finest[p] = 0;
        if (first)
            first[p] = UINT32_MAX;
    }
    for (uint32_t b = 0; b < l->brick_count; ++b)
        for (uint32_t i = 0; i < PB_SPARSE_BRICK_PROBES; ++i) {
            uint32_t p = l->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)b + i];
            if (p >= P)
                continue;
            if (finest && l->bricks[b].level > finest[p])
                finest[p] = (uint8_t)l->bricks[b].level;
            if (first && first[p] == UINT32_MAX)
                first[p] = b;
        }
}

pb_result pb_sparse_layout_words(const pb_sparse_layout *sp, uint32_t **words, uint32_t *count)
{
    *words = NULL, *count = 0;
    uint64_t cells = cell_count(sp->cells);
    uint64_t at_ind = 4, at_chunks = at_ind + cells, at_bricks = at_chunks + sp->chunk_count;
    uint64_t at_probes = at_bricks + 4ull * sp->brick_count;
    uint64_t total = at_probes + (uint64_t)PB_SPARSE_BRICK_PROBES * sp->brick_count;
    if (total > UINT32_MAX)
        return PB_ERROR_OUT_OF_HOST_MEMORY;
    uint32_t *w = malloc((size_t)total * sizeof *w);
    if (!w)
        return PB_ERROR_OUT_OF_HOST_MEMORY;
    w[0] = (uint32_t)at_ind, w[1] = (uint32_t)at_chunks, w[2] = (uint32_t)at_bricks, w[3] = (uint32_t)at_probes;
    memcpy(w + at_ind, sp->indirection, (size_t)cells * 4);
    memcpy(w + at_chunks, sp->chunks, (size_t)sp->chunk_count * 4);
    for (uint32_t b = 0; b < sp->brick_count; ++b) {
        uint32_t *q = w + at_bricks + 4 * (size_t)b;
        q[0] = sp->bricks[b].coord[0], q[1] = sp->bricks[b].coord[1], q[2] = sp->bricks[b].coord[2];
        q[3] = sp->bricks[b].level;
    }
    memcpy(w + at_probes, sp->brick_probes, (size_t)PB_SPARSE_BRICK_PROBES * sp->brick_count * 4);
    *words = w;
    *count = (uint32_t)total;
    return PB_OK;
}

/* x clamped to [lo, hi]; NaN gives lo (the GLSL leaves NaN to the driver;
 * here a NaN from a damaged file must not reach an int conversion) */
static float clampf(float x, float lo, float hi)
{
    return x >= lo ? (x > hi ? hi : x) : lo;
}

uint32_t pb_sparse_find(const pb_sparse_layout *l, const float u[3])
{
    int cell[3];
    float f[3];
    for (int k = 0; k < 3; ++k) {
        float c = clampf(floorf(u[k]), 0.f, (float)l->cells[k] - 1.f);
        cell[k] = (int)c;
        f[k] = clampf(u[k] - c, 0.f, 1.f);
    }
    uint32_t e = l->indirection[cell[0] + l->cells[0] * (cell[1] + l->cells[1] * cell[2])];
    uint32_t d = e >> PB_SPARSE_DEPTH_SHIFT, off = e & PB_SPARSE_EMPTY;
    if (d == 0)
        return off;
    int n = d == 1 ? 3 : 9, s[3];
    for (int k = 0; k < 3; ++k) {
        int q = (int)floorf(f[k] * (float)n);
        s[k] = q < 0 ? 0 : (q > n - 1 ? n - 1 : q);
    }
    return l->chunks[off + (uint32_t)(s[0] + n * (s[1] + n * s[2]))];
}
