/* Merging the parts of a sparse bake (sparse_merge.h). Checks first, then
 * the whole is assembled; a part that disagrees with another on a shared
 * probe is named, and nothing is returned. */
#include "bake/sparse_merge.h"
#include "bake/shard.h"
#include "bake/sparse_compact.h"
#include "bake/sparse_stitch.h"
#include "common/common.h"
#include "probebake/bake.h"
#include "probebake/sparse.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Every probe's record in part a at index p equals part b's at q. */
static int same_probe(const pb_volume *a, uint32_t p, const pb_volume *b, uint32_t q, uint64_t halves)
{
    return !memcmp(a->base + 3 * (size_t)p, b->base + 3 * (size_t)q, 12) &&
           !memcmp(a->offset + 3 * (size_t)p, b->offset + 3 * (size_t)q, 12) &&
           a->probe_flags[p] == b->probe_flags[q] && a->probe_paths[p] == b->probe_paths[q] &&
           !memcmp(&a->probe_std_error[p], &b->probe_std_error[q], 4) &&
           !memcmp(a->sh + 27 * (size_t)p, b->sh + 27 * (size_t)q, 108) &&
           !memcmp(a->depth + halves * p, b->depth + halves * q, 2 * halves);
}

/* Where the whole volume's bricks and probes come from, between begin and
 * end: each merged brick's part and its index there, each probe's filler. */
/* What begin saw of a part: add refuses a part read again that differs. */
typedef struct part_seen {
    char device[256];     /* the device it names */
    char name[512];       /* its file, for messages */
    uint32_t bricks, probes;
    uint64_t scene_hash;
    uint64_t layout_hash; /* its bricks and their probe indices (layout_hash) */
} part_seen;

struct pb_sparse_merging {
    uint32_t N, B;
    uint32_t *from_part, *from_brick; /* per merged brick */
    uint8_t *filled;                  /* per probe of the whole */
    uint32_t *src_part;               /* per probe: the part that filled it */
    part_seen *part;                  /* per part */
    uint32_t next;                    /* the part add expects next */
};

/* FNV-1a over a part's bricks and brick probe indices: a part read again
 * for its probes must have the layout begin read. */
static uint64_t layout_hash(const pb_sparse_layout *l)
{
    uint64_t h = 1469598103934665603ull;
    const unsigned char *b = (const unsigned char *)l->bricks, *p = (const unsigned char *)l->brick_probes;
    for (size_t i = 0; i < (size_t)l->brick_count * sizeof *l->bricks; ++i)
        h = (h ^ b[i]) * 1099511628211ull;
    for (size_t i = 0; i < (size_t)l->brick_count * PB_SPARSE_BRICK_PROBES * sizeof *l->brick_probes; ++i)
        h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

void pb_sparse_merging_free(pb_sparse_merging *m)
{
    if (!m)
        return;
    free(m->from_part), free(m->from_brick), free(m->filled), free(m->src_part);
    free(m->part);
    free(m);
}

pb_result pb_sparse_merge_begin(const pb_volume *const *parts, const char *const *names, uint32_t N, pb_volume *out,
                                pb_sparse_merging **merging, pb_error *err)
{
    *merging = NULL;
    const pb_volume *p0 = parts[0];
    const pb_sparse_layout *l0 = p0->sparse;
    uint32_t L = l0->levels;
    uint64_t C = (uint64_t)l0->cells[0] * l0->cells[1] * l0->cells[2];
    uint64_t bricks = 0;
    for (uint32_t k = 0; k < N; ++k) {
        const pb_sparse_layout *l = parts[k]->sparse;
        if (l->levels != L || memcmp(l->cells, l0->cells, sizeof l->cells) || parts[k]->shard.total != C)
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                           "%s: not a part of the same bake as %s: its sparse lattice (levels or cells) differs",
                           names[k], names[0]);
        uint32_t first, n;
        pb_shard_range((uint32_t)C, k, N, &first, &n);
        for (uint32_t b = 0; b < l->brick_count; ++b) {
            uint64_t c = pb_sparse_coarsest_cell(l0->cells, &l->bricks[b]);
            if (c < first || c >= (uint64_t)first + n)
                return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                               "%s: part %u/%u holds a brick of coarsest brick %llu, outside its range %u..%u",
                               names[k], k, N, (unsigned long long)c, first, first + n - 1);
        }
        bricks += l->brick_count;
    }
    if (bricks > (1u << 22))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%llu bricks in the parts: too many",
                       (unsigned long long)bricks);
    /* bricks level by level, parts in order; where each came from */
    size_t nb = bricks ? (size_t)bricks : 1;
    pb_sparse_brick *all = malloc(nb * sizeof *all);
    pb_sparse_layout *sp = calloc(1, sizeof *sp);
    pb_sparse_merging *m = calloc(1, sizeof *m);
    if (m) {
        m->from_part = malloc(nb * sizeof *m->from_part);
        m->from_brick = malloc(nb * sizeof *m->from_brick);
        m->part = calloc(N, sizeof *m->part);
    }
    if (!all || !sp || !m || !m->from_part || !m->from_brick || !m->part) {
        free(all), free(sp), pb_sparse_merging_free(m);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory merging %llu bricks",
                       (unsigned long long)bricks);
    }
    m->N = N;
    for (uint32_t k = 0; k < N; ++k) {
        part_seen *ps = &m->part[k];
        snprintf(ps->device, sizeof ps->device, "%s", parts[k]->device);
        snprintf(ps->name, sizeof ps->name, "%s", names[k]);
        ps->bricks = parts[k]->sparse->brick_count, ps->probes = parts[k]->probe_count;
        ps->scene_hash = parts[k]->settings.scene_hash;
        ps->layout_hash = layout_hash(parts[k]->sparse);
    }
    uint32_t B = 0;
    for (uint32_t level = 0; level < L; ++level)
        for (uint32_t k = 0; k < N; ++k)
            for (uint32_t b = 0; b < parts[k]->sparse->brick_count; ++b)
                if (parts[k]->sparse->bricks[b].level == level) {
                    all[B] = parts[k]->sparse->bricks[b];
                    m->from_part[B] = k, m->from_brick[B] = b;
                    B++;
                }
    m->B = B;
    uint32_t P = 0;
    pb_result r = pb_sparse_layout_build(L, l0->cells, all, B, sp, &P, NULL, err);
    free(all);
    if (r != PB_OK) {
        free(sp), pb_sparse_merging_free(m);
        return r;
    }
    /* the header of part 0; the probes come with each part */
    out->flags = p0->flags & ~PB_VOLUME_SHARD;
    out->probe_count = P;
    out->counts[0] = P, out->counts[1] = out->counts[2] = 1;
    out->octmap_res = p0->octmap_res;
    memcpy(out->origin, p0->origin, sizeof out->origin);
    memcpy(out->spacing, p0->spacing, sizeof out->spacing);
    out->settings = p0->settings;
    out->settings.passes = 0;
    out->depth_unit = p0->depth_unit;
    snprintf(out->device, sizeof out->device, "%s", p0->device);
    out->sparse = sp;
    m->filled = calloc(P ? P : 1, 1);
    m->src_part = malloc((size_t)(P ? P : 1) * sizeof *m->src_part);
    if (!m->filled || !m->src_part)
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory merging %u probes", P);
    if (r == PB_OK)
        r = pb_volume_alloc(out, err);
    if (r != PB_OK) {
        pb_sparse_merging_free(m);
        pb_volume_free(out);
        return r;
    }
    *merging = m;
    return PB_OK;
}

pb_result pb_sparse_merge_add(pb_sparse_merging *m, pb_volume *out, const pb_volume *v, pb_error *err)
{
    uint32_t k = m->next;
    if (k >= m->N)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "all %u parts are merged already", m->N);
    /* the part read again must be the one begin saw (its bricks' probes are
     * looked up by begin's brick indices) */
    const part_seen *seen = &m->part[k];
    if (!v->sparse || v->sparse->brick_count != seen->bricks || v->probe_count != seen->probes ||
        v->shard.index != k || v->settings.scene_hash != seen->scene_hash || strcmp(v->device, seen->device) ||
        layout_hash(v->sparse) != seen->layout_hash)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: changed while it was merged (its bricks, probes, part "
                       "index, scene or device)", seen->name);
    uint64_t halves = pb_volume_tile_halves(out->octmap_res);
    const pb_sparse_layout *sp = out->sparse;
    uint32_t L = sp->levels;
    for (uint32_t b = 0; b < m->B; ++b) {
        if (m->from_part[b] != k)
            continue;
        uint32_t own = m->from_brick[b];
        for (uint32_t i = 0; i < PB_SPARSE_BRICK_PROBES; ++i) {
            uint32_t q = sp->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)b + i];
            uint32_t p = v->sparse->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)own + i];
            if (m->filled[q]) {
                /* a probe bricks share, maybe of two parts: one bake on one
                 * kind of device gives it one record; across different devices
                 * (transcendentals round differently) the lower part's stays */
                if (!strcmp(v->device, m->part[m->src_part[q]].device) && !same_probe(out, q, v, p, halves)) {
                    const pb_sparse_brick *br = &sp->bricks[b];
                    uint32_t step = pb_sparse_step(L, br->level);
                    return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                                   "%s: its probe at finest lattice point (%u, %u, %u) differs from %s's: not parts of "
                                   "one bake (another build or driver?)", seen->name,
                                   (3 * br->coord[0] + (i & 3u)) * step, (3 * br->coord[1] + ((i >> 2) & 3u)) * step,
                                   (3 * br->coord[2] + (i >> 4)) * step, m->part[m->src_part[q]].name);
                }
                continue;
            }
            memcpy(out->base + 3 * (size_t)q, v->base + 3 * (size_t)p, 12);
            memcpy(out->offset + 3 * (size_t)q, v->offset + 3 * (size_t)p, 12);
            out->probe_flags[q] = v->probe_flags[p];
            out->probe_paths[q] = v->probe_paths[p];
            out->probe_std_error[q] = v->probe_std_error[p];
            memcpy(out->sh + 27 * (size_t)q, v->sh + 27 * (size_t)p, 108);
            memcpy(out->depth + halves * q, v->depth + halves * p, 2 * halves);
            m->filled[q] = 1, m->src_part[q] = k;
        }
    }
    pb_shard_account(out, v);
    m->next++;
    return PB_OK;
}

pb_result pb_sparse_merge_end(pb_sparse_merging *m, pb_volume *out, pb_error *err)
{
    uint32_t added = m->next, N = m->N;
    pb_sparse_merging_free(m);
    if (added != N)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u of %u parts merged", added, N);
    /* the stages that need neighbours across parts: as the one-process bake */
    pb_volume_dilate(out, PB_DILATION_ROUNDS);
    pb_result r = pb_sparse_stitch(out, err);
    if (r == PB_OK)
        r = pb_sparse_drop_invalid(out, err);
    return r;
}

pb_result pb_sparse_merge(const pb_volume *const *parts, const char *const *names, uint32_t N, pb_volume *out,
                          pb_error *err)
{
    pb_sparse_merging *m;
    pb_result r = pb_sparse_merge_begin(parts, names, N, out, &m, err);
    for (uint32_t k = 0; k < N && r == PB_OK; ++k)
        r = pb_sparse_merge_add(m, out, parts[k], err);
    if (r == PB_OK)
        r = pb_sparse_merge_end(m, out, err);
    else
        pb_sparse_merging_free(m);
    if (r != PB_OK)
        pb_volume_free(out);
    return r;
}
