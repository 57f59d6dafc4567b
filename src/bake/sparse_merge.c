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

pb_result pb_sparse_merge(const pb_volume *const *parts, const char *const *names, uint32_t N, pb_volume *out,
                          pb_error *err)
{
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
    pb_sparse_brick *all = malloc((size_t)(bricks ? bricks : 1) * sizeof *all);
    uint32_t *from_part = malloc((size_t)(bricks ? bricks : 1) * sizeof *from_part);
    uint32_t *from_brick = malloc((size_t)(bricks ? bricks : 1) * sizeof *from_brick);
    pb_sparse_layout *sp = calloc(1, sizeof *sp);
    if (!all || !from_part || !from_brick || !sp) {
        free(all), free(from_part), free(from_brick), free(sp);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory merging %llu bricks",
                       (unsigned long long)bricks);
    }
    uint32_t B = 0;
    for (uint32_t level = 0; level < L; ++level)
        for (uint32_t k = 0; k < N; ++k)
            for (uint32_t b = 0; b < parts[k]->sparse->brick_count; ++b)
                if (parts[k]->sparse->bricks[b].level == level) {
                    all[B] = parts[k]->sparse->bricks[b];
                    from_part[B] = k, from_brick[B] = b;
                    B++;
                }
    uint32_t P = 0;
    pb_result r = pb_sparse_layout_build(L, l0->cells, all, B, sp, &P, NULL, err);
    free(all);
    if (r != PB_OK) {
        free(from_part), free(from_brick), free(sp);
        return r;
    }
    /* the header of part 0, the probes of every part */
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
    for (uint32_t k = 0; k < N; ++k)
        pb_shard_account(out, parts[k]);
    uint8_t *filled = calloc(P ? P : 1, 1);
    uint32_t *src_part = malloc((size_t)(P ? P : 1) * sizeof *src_part);
    if (!filled || !src_part)
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory merging %u probes", P);
    if (r == PB_OK)
        r = pb_volume_alloc(out, err);
    uint64_t halves = pb_volume_tile_halves(out->octmap_res);
    for (uint32_t m = 0; r == PB_OK && m < B; ++m) {
        const pb_volume *v = parts[from_part[m]];
        for (uint32_t i = 0; r == PB_OK && i < PB_SPARSE_BRICK_PROBES; ++i) {
            uint32_t q = sp->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)m + i];
            uint32_t p = v->sparse->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)from_brick[m] + i];
            if (filled[q]) {
                /* a probe bricks share, maybe of two parts: one bake on one
                 * kind of device gives it one record; across different devices
                 * (transcendentals round differently) the lower part's stays */
                if (!strcmp(v->device, parts[src_part[q]]->device) && !same_probe(out, q, v, p, halves)) {
                    const pb_sparse_brick *br = &sp->bricks[m];
                    uint32_t step = pb_sparse_step(L, br->level);
                    r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                                "%s: its probe at finest lattice point (%u, %u, %u) differs from %s's: not parts of "
                                "one bake (another build or driver?)", names[from_part[m]],
                                (3 * br->coord[0] + (i & 3u)) * step, (3 * br->coord[1] + ((i >> 2) & 3u)) * step,
                                (3 * br->coord[2] + (i >> 4)) * step, names[src_part[q]]);
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
            filled[q] = 1, src_part[q] = from_part[m];
        }
    }
    free(filled), free(src_part), free(from_part), free(from_brick);
    if (r != PB_OK) {
        pb_sparse_layout_free(sp);
        free(sp);
        pb_volume_free(out);
        return r;
    }
    out->sparse = sp;
    /* the stages that need neighbours across parts: as the one-process bake */
    pb_volume_dilate(out, PB_DILATION_ROUNDS);
    if ((r = pb_sparse_stitch(out, err)) != PB_OK || (r = pb_sparse_drop_invalid(out, err)) != PB_OK)
        pb_volume_free(out);
    return r;
}
