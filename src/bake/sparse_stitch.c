/* Stitching a sparse volume's level seams (sparse_stitch.h). */
#include "bake/sparse_stitch.h"
#include "bake/sparse_miss.h"
#include "common/common.h"
#include "probebake/sample.h"
#include "probebake/sh.h"
#include "probebake/sparse.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* What brick o's own sampler holds at finest-lattice point k3, as SH: its
 * trilinear weights there, visibility of `where` (the probe's relocated
 * position; frame: the volume's origin). Where every cage probe sees the point this is the
 * plain trilinear SH, and the interpolant is continuous across the level
 * face; a probe behind a wall (valid, but dark outside a room) is not
 * averaged in, as the sampler would not. Returns 0 (sh untouched) where no
 * probe of the cage sees the point. */
static int brick_visible_trilinear(const pb_volume *v, const pb_sample_volume *sv, uint32_t o, const uint32_t k3[3],
                                   const float where[3], float sh[27])
{
    const pb_sparse_layout *sp = v->sparse;
    const pb_sparse_brick *b = &sp->bricks[o];
    const uint32_t *probes = sp->brick_probes + PB_SPARSE_BRICK_PROBES * (size_t)o;
    uint32_t step = pb_sparse_step(sp->levels, b->level);
    int base[3];
    float a[3], q[3];
    for (int k = 0; k < 3; ++k) {
        double rel = (double)k3[k] / step - 3.0 * b->coord[k]; /* in [0, 3] */
        int i = (int)floor(rel);
        base[k] = i < 0 ? 0 : (i > 2 ? 2 : i);
        a[k] = (float)(rel - base[k]);
        q[k] = where[k];
    }
    static const float up[3] = {0.f, 1.f, 0.f}; /* only used where q is a probe's own position */
    float acc[27] = {0}, wsum = 0.f;
    for (int c = 0; c < 8; ++c) {
        int qi[3];
        float w = 1.f;
        for (int k = 0; k < 3; ++k) {
            int off = (c >> k) & 1;
            qi[k] = base[k] + off;
            w *= off ? a[k] : 1.f - a[k];
        }
        uint32_t p = probes[qi[0] + 4 * (qi[1] + 4 * qi[2])];
        if (w <= 0.f || !(v->probe_flags[p] & PB_PROBE_VALID))
            continue;
        w *= pb_sample_visibility_cpu(sv, (int)p, q, up, NULL);
        const float *src = v->sh + 27 * (size_t)p;
        for (int i = 0; i < 27; ++i)
            acc[i] += w * src[i];
        wsum += w;
    }
    if (!(wsum > 1e-6f))
        return 0;
    for (int i = 0; i < 27; ++i)
        sh[i] = acc[i] / wsum;
    return 1;
}

/* Whether the coarser level's value `coarse` misses probe p's baked SH by
 * more than the layout accepts (the probe test's measure, sparse_miss.h).
 * There the coarse level is wrong, and a stitched probe would carry its
 * error into the finer brick, whose cells nearly all touch a face (26 of 27). */
static int coarse_misses(const pb_volume *v, uint32_t p, const float coarse[27], float tol)
{
    if (!(tol > 0.f))
        return 0; /* not recorded: stitch everywhere (the first sparse files) */
    float pred[6], baked[6];
    for (int a = 0; a < 6; ++a) {
        float e[3], c[3];
        pb_sh_eval(coarse, pb_sparse_miss_axes[a], c);
        pb_sh_eval(v->sh + 27 * (size_t)p, pb_sparse_miss_axes[a], e);
        pred[a] = pb_luminance(c);
        baked[a] = pb_luminance(e);
    }
    return pb_sparse_misses(pred, baked, v->probe_std_error ? v->probe_std_error[p] : 0.f, tol);
}

/* The centre u (in coarsest bricks) of cell c (0-7) of the eight cells of
 * spacing `step` around finest-lattice point k3; 0 where it lies outside
 * the layout. span: finest steps per coarsest brick. */
static int cell_around(const pb_sparse_layout *sp, const uint32_t k3[3], uint32_t c, uint32_t step, uint32_t span,
                       float u[3])
{
    int outside = 0;
    for (int k = 0; k < 3; ++k) {
        double at = (double)k3[k] + (((c >> k) & 1u) ? 0.5 : -0.5) * step;
        outside |= at < 0.0 || at > (double)sp->cells[k] * span;
        u[k] = (float)(at / span);
    }
    return !outside;
}

/* The coarsest brick of a level below `level` that serves a cell of this
 * level around finest-lattice point k3 and does not have that point (k3 is
 * a hanging probe of it), coarse levels first; PB_SPARSE_EMPTY if none.
 * at[3]: the centre of that cell, in coarsest cells. */
static uint32_t hanging_on(const pb_sparse_layout *sp, uint32_t level, uint32_t span, const uint32_t k3[3],
                           float at[3])
{
    uint32_t L = sp->levels, step = pb_sparse_step(L, level), coarse = PB_SPARSE_EMPTY;
    for (uint32_t c = 0; c < 8; ++c) { /* the eight cells of this level around the probe */
        float u[3];
        if (!cell_around(sp, k3, c, step, span, u))
            continue;
        uint32_t nbk = pb_sparse_find(sp, u);
        if (nbk == PB_SPARSE_EMPTY)
            continue;
        const pb_sparse_brick *o = &sp->bricks[nbk];
        uint32_t ostep = pb_sparse_step(L, o->level);
        if (o->level < level && (k3[0] % ostep || k3[1] % ostep || k3[2] % ostep) &&
            (coarse == PB_SPARSE_EMPTY || o->level < sp->bricks[coarse].level)) {
            coarse = nbk;
            memcpy(at, u, sizeof u);
        }
    }
    return coarse;
}

pb_result pb_sparse_seam_misses(const pb_volume *v, uint32_t level, pb_sparse_brick **cells, uint32_t *count,
                                pb_error *err)
{
    const pb_sparse_layout *sp = v->sparse;
    *cells = NULL;
    *count = 0;
    if (!sp || level == 0 || level >= sp->levels)
        return PB_OK;
    pb_sample_volume sv;
    pb_result r = pb_sample_volume_build(v, v->origin, 0.f, 0.f, &sv, err);
    if (r != PB_OK)
        return r;
    /* span: finest steps per coarsest brick; below: level-`level` bricks per coarsest brick, per axis */
    uint32_t L = sp->levels, span = 3 * pb_sparse_step(L, 0), step = pb_sparse_step(L, level), below = span / (3 * step);
    uint32_t cap = 0;
    /* the seam test's own threshold where recorded, else the refinement's */
    float tol = v->settings.seam_error > 0.f ? v->settings.seam_error : v->settings.refine_error;
    for (uint32_t b = 0; r == PB_OK && b < sp->brick_count; ++b) {
        const pb_sparse_brick *br = &sp->bricks[b];
        if (br->level != level)
            continue;
        for (uint32_t i = 0; r == PB_OK && i < PB_SPARSE_BRICK_PROBES; ++i) {
            uint32_t off[3] = {i & 3u, (i >> 2) & 3u, i >> 4}, k3[3];
            if (off[0] % 3 && off[1] % 3 && off[2] % 3)
                continue; /* inside the brick */
            uint32_t p = sp->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)b + i];
            if (!(v->probe_flags[p] & PB_PROBE_VALID))
                continue; /* no bake to test against */
            for (int k = 0; k < 3; ++k)
                k3[k] = (3 * br->coord[k] + off[k]) * step;
            float where[3];
            for (int k = 0; k < 3; ++k)
                where[k] = v->base[3 * (size_t)p + k] + v->offset[3 * (size_t)p + k];
            /* each cell of the coarser level around the probe, in its coarsest brick (refinement never
             * leaves one: parts place as the whole), that does not have the probe's lattice point */
            for (uint32_t c = 0; r == PB_OK && c < 8; ++c) {
                float u[3];
                if (!cell_around(sp, k3, c, step, span, u))
                    continue;
                pb_sparse_brick cell = {level, {0, 0, 0}};
                int same_root = 1;
                for (int k = 0; k < 3; ++k) {
                    cell.coord[k] = (uint32_t)floorf(u[k] * (float)below);
                    same_root &= cell.coord[k] / below == br->coord[k] / below;
                }
                uint32_t coarse = same_root ? pb_sparse_find(sp, u) : PB_SPARSE_EMPTY;
                if (coarse == PB_SPARSE_EMPTY || sp->bricks[coarse].level + 1 != level)
                    continue;
                uint32_t ostep = pb_sparse_step(L, level - 1);
                if (!(k3[0] % ostep || k3[1] % ostep || k3[2] % ostep))
                    continue; /* the coarser brick has this point: not hanging there */
                int seen = 0;
                for (uint32_t e = *count; e-- > 0 && !seen;)
                    seen = !memcmp((*cells)[e].coord, cell.coord, sizeof cell.coord);
                float sh[27];
                if (seen || !brick_visible_trilinear(v, &sv, coarse, k3, where, sh) ||
                    !coarse_misses(v, p, sh, tol))
                    continue;
                if (*count == cap) {
                    uint32_t nc = cap ? 2 * cap : 64;
                    pb_sparse_brick *g = realloc(*cells, (size_t)nc * sizeof *g);
                    if (!g) {
                        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the seam test");
                        break;
                    }
                    *cells = g, cap = nc;
                }
                (*cells)[(*count)++] = cell;
            }
        }
    }
    pb_sample_volume_free(&sv);
    if (r != PB_OK) {
        free(*cells);
        *cells = NULL, *count = 0;
    }
    return r;
}

pb_result pb_sparse_stitch(pb_volume *v, pb_error *err)
{
    const pb_sparse_layout *sp = v->sparse;
    if (!sp)
        return PB_OK;
    /* the frame: the volume's origin (lattice point 0); read for depth moments
     * only, v->sh holds the stitched SH as it goes */
    pb_sample_volume sv;
    pb_result r = pb_sample_volume_build(v, v->origin, 0.f, 0.f, &sv, err);
    if (r != PB_OK)
        return r;
    uint32_t L = sp->levels, span = 1;
    for (uint32_t l = 0; l < L; ++l)
        span *= 3; /* finest steps per cell */
    for (uint32_t level = 1; level < L; ++level)
        for (uint32_t b = 0; b < sp->brick_count; ++b) {
            const pb_sparse_brick *br = &sp->bricks[b];
            if (br->level != level)
                continue;
            uint32_t step = pb_sparse_step(L, level);
            for (uint32_t i = 0; i < PB_SPARSE_BRICK_PROBES; ++i) {
                uint32_t off[3] = {i & 3u, (i >> 2) & 3u, i >> 4}, k3[3];
                if (off[0] % 3 && off[1] % 3 && off[2] % 3)
                    continue; /* inside the brick */
                for (int k = 0; k < 3; ++k)
                    k3[k] = (3 * br->coord[k] + off[k]) * step;
                float u[3];
                uint32_t coarse = hanging_on(sp, level, span, k3, u);
                if (coarse == PB_SPARSE_EMPTY)
                    continue;
                /* visibility of where the probe is (relocated out of walls), not of its lattice point */
                uint32_t p = sp->brick_probes[PB_SPARSE_BRICK_PROBES * (size_t)b + i];
                float where[3];
                for (int k = 0; k < 3; ++k)
                    where[k] = v->base[3 * (size_t)p + k] + v->offset[3 * (size_t)p + k];
                /* a dilated probe always takes it; a baked one unless the coarser level misses it; the
                 * empty probe of a compacted volume (neither) never: every dropped slot names it */
                uint32_t f = v->probe_flags[p];
                float sh[27];
                if ((f & (PB_PROBE_VALID | PB_PROBE_DILATED)) && brick_visible_trilinear(v, &sv, coarse, k3, where, sh) &&
                    (!(f & PB_PROBE_VALID) || !coarse_misses(v, p, sh, v->settings.refine_error)))
                    memcpy(v->sh + 27 * (size_t)p, sh, sizeof sh);
            }
        }
    pb_sample_volume_free(&sv);
    return PB_OK;
}
