/* The sparse bake (docs/sparse.md): bricks placed by the error that
 * interpolation makes, level by level.
 *
 *   1. coarsest bricks over the whole extent; bake their probes;
 *   2. per level, each cell of a brick with a surface near its corners gets
 *      one probe baked inside (a point of the next level's lattice, so it
 *      is reused if the cell is refined); where the level's own sampler
 *      mispredicts that probe, the cell becomes a brick of the next level;
 *   3. bricks with every probe inside geometry are dropped;
 *   4. probes on a finer brick's faces that a coarser neighbour does not
 *      have take that neighbour's trilinear SH (no jump across the face).
 *
 * Every probe is keyed by its index on the finest lattice and baked once
 * (pb_bake over points, so relocation, validity and convergence are the
 * grid bake's), whatever brick or level asks for it first.
 *
 * With --indirect volume each bounce is such a placement of its own (bounce
 * k's probes reflect bounce k - 1's sparse volume at their rays' first hits,
 * pb_bake_bounce), and the last bounce's layout is the volume's. */
#include "bake/gpu_scene.h"
#include "bake/indirect_volume.h"
#include "bake/settings.h"
#include "bake/shard.h"
#include "bake/sparse_miss.h"
#include "bake/sparse_compact.h"
#include "bake/sparse_stitch.h"
#include "bake/sparse_surface_tests.h"
#include "bake/timings.h"
#include "common/common.h"
#include "common/key_map.h"
#include "probebake/bake.h"
#include "probebake/sh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Baked probes by finest-lattice key. */
typedef struct probe_store {
    uint32_t count, cap, halves;
    uint32_t *keys;     /* 3 per probe */
    float *offset;      /* 3 per probe */
    uint32_t *flags, *paths;
    float *sh, *std_error;
    uint16_t *depth;
    pb_key_map index;
} probe_store;

typedef struct sparse_job {
    pb_context *ctx;
    const pb_scene *scene;
    pb_gpu_scene *gs;
    pb_bake_desc d;
    float refine_error;                 /* recorded in the volume (parts must agree) */
    uint32_t refine_test;               /* 1 + pb_refine_test, recorded too */
    uint32_t test_pass_scale;           /* the surface test's, recorded too (0 for the probe test) */
    uint32_t seam_rounds;               /* the seam test's, recorded too */
    float seam_error;                   /* its threshold, recorded too (0 with no seam test) */
    int one_bounce;                     /* --indirect volume: every bake is pb_bake_bounce over `feedback` */
    const pb_sample_volume *feedback;   /* the previous bounce's volume (NULL on the first) */
    uint32_t levels, cells[3];
    double F[3];                /* finest spacing per axis */
    uint64_t X, Y;              /* finest lattice points per axis (x, y), for keys */
    probe_store ps;
    pb_sparse_brick *bricks;
    uint32_t brick_count, brick_cap;
    pb_volume first;            /* the first bake's header: settings, device, depth unit (no probes) */
    pb_volume_timings timings;
    uint64_t rays, traversals, relocation_rays;
    uint32_t passes_max;
    pb_sparse_stats stats;
} sparse_job;

static uint32_t pow3u(uint32_t e)
{
    uint32_t p = 1;
    while (e--)
        p *= 3;
    return p;
}

static uint64_t lattice_key(const sparse_job *j, const uint32_t k[3])
{
    return k[0] + j->X * (k[1] + j->Y * (uint64_t)k[2]);
}

static uint32_t store_find(const sparse_job *j, const uint32_t k[3])
{
    return pb_key_map_get(&j->ps.index, lattice_key(j, k));
}

static int store_reserve(probe_store *s, uint32_t more)
{
    if (s->count + more <= s->cap)
        return 1;
    uint32_t cap = s->cap ? s->cap : 1024;
    while (cap < s->count + more)
        cap *= 2;
#define GROW(field, per)                                                                                              \
    do {                                                                                                           \
        void *p_ = realloc(s->field, (size_t)cap * (per) * sizeof *s->field);                                      \
        if (!p_)                                                                                                   \
            return 0;                                                                                              \
        s->field = p_;                                                                                             \
    } while (0)
    GROW(keys, 3);
    GROW(offset, 3);
    GROW(flags, 1);
    GROW(paths, 1);
    GROW(sh, 27);
    GROW(std_error, 1);
    GROW(depth, s->halves);
#undef GROW
    s->cap = cap;
    return 1;
}

static void store_free(probe_store *s)
{
    free(s->keys), free(s->offset), free(s->flags), free(s->paths), free(s->sh), free(s->std_error), free(s->depth);
    pb_key_map_free(&s->index);
}

/* Random-number id of a lattice point (pb_points.ids): a mix of its key. */
static uint32_t key_id(uint64_t key)
{
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdull;
    key ^= key >> 33;
    return (uint32_t)key;
}

/* Adds what one bake of the job spent to the job's totals; the first bake's
 * header is the volume's. kept: the bake's probes are the volume's (a test
 * bake's passes are not the volume's). */
static pb_result account(sparse_job *j, const pb_volume *v, int kept, pb_error *err)
{
    j->rays += v->rays_traced;
    j->traversals += v->traversals;
    j->relocation_rays += v->relocation_rays;
    if (kept && v->settings.passes > j->passes_max)
        j->passes_max = v->settings.passes;
    pb_volume_timings_add(&j->timings, &v->timings);
    if (j->stats.bakes == 1) { /* the header every part shares; the arrays stay v's */
        j->first = *v;
        j->first.base = j->first.offset = j->first.sh = j->first.probe_std_error = NULL;
        j->first.probe_flags = j->first.probe_paths = NULL;
        j->first.depth = NULL;
        j->first.sparse = NULL;
    } else if (v->depth_unit != j->first.depth_unit) {
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse bake: depth units differ between levels (%g, %g)",
                       (double)j->first.depth_unit, (double)v->depth_unit);
    }
    return PB_OK;
}

/* Bakes free points (not lattice points, not kept in the store): the
 * refinement's surface tests. */
static pb_result bake_free(sparse_job *j, const pb_points *pts, uint32_t pass_scale, pb_volume *v, pb_error *err)
{
    pb_bake_desc d = j->d;
    d.points = pts;
    d.passes = pb_bake_passes(&d) * pass_scale; /* the default resolved first: 0 x scale would be the default */
    pb_result r = j->one_bounce ? pb_bake_bounce(j->ctx, j->scene, j->gs, &d, j->feedback, v, err)
                                : pb_bake(j->ctx, j->scene, j->gs, &d, v, err);
    j->stats.bakes++;
    return r == PB_OK ? account(j, v, 0, err) : r;
}

/* Bakes the lattice points `keys` (3 per point) not baked yet, as probes of
 * `level` (relocation bound: 45 % of that level's spacing). */
static pb_result bake_points(sparse_job *j, const uint32_t *keys, uint32_t count, uint32_t level, pb_error *err)
{
    uint32_t *todo = malloc(((size_t)count + 1) * 3 * sizeof *todo);
    pb_key_map seen;
    if (!todo || !pb_key_map_init(&seen, count)) {
        free(todo);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u sparse probes", count);
    }
    uint32_t n = 0;
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t *k = keys + 3 * (size_t)i;
        uint64_t key = lattice_key(j, k);
        if (store_find(j, k) != PB_KEY_MAP_MISSING || pb_key_map_get(&seen, key) != PB_KEY_MAP_MISSING)
            continue;
        if (!pb_key_map_put(&seen, key, n)) {
            pb_key_map_free(&seen);
            free(todo);
            return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u sparse probes", count);
        }
        memcpy(todo + 3 * (size_t)n++, k, 3 * sizeof *k);
    }
    pb_key_map_free(&seen);
    if (n == 0) {
        free(todo);
        return PB_OK;
    }
    pb_points pts = {n, malloc((size_t)n * 3 * sizeof(double)), malloc((size_t)n * sizeof(uint32_t)), 0.0};
    pb_result r = PB_OK;
    if (!pts.positions || !pts.ids || !store_reserve(&j->ps, n))
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u sparse probes", n);
    uint32_t step = pb_sparse_step(j->levels, level);
    pts.spacing = fmin(j->F[0], fmin(j->F[1], j->F[2])) * step;
    for (uint32_t i = 0; r == PB_OK && i < n; ++i) {
        for (int k = 0; k < 3; ++k)
            pts.positions[3 * (size_t)i + k] = j->scene->origin[k] + ((double)j->d.grid.origin[k] +
                                                                      (double)todo[3 * (size_t)i + k] * j->F[k]);
        pts.ids[i] = key_id(lattice_key(j, todo + 3 * (size_t)i));
    }
    pb_volume v;
    memset(&v, 0, sizeof v);
    if (r == PB_OK) {
        pb_bake_desc d = j->d;
        d.points = &pts;
        r = j->one_bounce ? pb_bake_bounce(j->ctx, j->scene, j->gs, &d, j->feedback, &v, err)
                          : pb_bake(j->ctx, j->scene, j->gs, &d, &v, err);
        j->stats.bakes++;
    }
    if (r == PB_OK)
        r = account(j, &v, 1, err);
    if (r == PB_OK) {
        probe_store *s = &j->ps;
        for (uint32_t i = 0; i < n && r == PB_OK; ++i) {
            uint32_t at = s->count++;
            memcpy(s->keys + 3 * (size_t)at, todo + 3 * (size_t)i, 3 * sizeof(uint32_t));
            memcpy(s->offset + 3 * (size_t)at, v.offset + 3 * (size_t)i, 3 * sizeof(float));
            s->flags[at] = v.probe_flags[i];
            s->paths[at] = v.probe_paths[i];
            s->std_error[at] = v.probe_std_error[i];
            memcpy(s->sh + 27 * (size_t)at, v.sh + 27 * (size_t)i, 27 * sizeof(float));
            memcpy(s->depth + (size_t)s->halves * at, v.depth + (size_t)s->halves * i, s->halves * sizeof(uint16_t));
            if (!pb_key_map_put(&s->index, lattice_key(j, todo + 3 * (size_t)i), at))
                r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse probes");
        }
        j->stats.probes[level] += n;
    }
    pb_volume_free(&v);
    free(todo), free(pts.positions), free(pts.ids);
    return r;
}

/* The finest-lattice keys of brick b's 64 probes. */
static void brick_keys(const sparse_job *j, const pb_sparse_brick *b, uint32_t keys[64 * 3])
{
    uint32_t step = pb_sparse_step(j->levels, b->level);
    for (uint32_t i = 0; i < PB_SPARSE_BRICK_PROBES; ++i) {
        uint32_t off[3] = {i & 3u, (i >> 2) & 3u, i >> 4};
        for (int k = 0; k < 3; ++k)
            keys[3 * i + k] = (3 * b->coord[k] + off[k]) * step;
    }
}

/* Bakes the probes of `count` candidate bricks, then keeps those with a
 * valid probe (appended to j->bricks). */
static pb_result add_bricks(sparse_job *j, const pb_sparse_brick *cand, uint32_t count, uint32_t level, pb_error *err)
{
    if (count == 0)
        return PB_OK;
    uint32_t *keys = malloc((size_t)count * 64 * 3 * sizeof *keys);
    if (!keys)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u bricks", count);
    for (uint32_t b = 0; b < count; ++b)
        brick_keys(j, &cand[b], keys + (size_t)b * 64 * 3);
    pb_result r = bake_points(j, keys, count * 64, level, err);
    if (r == PB_OK && j->brick_count + count > j->brick_cap) {
        uint32_t cap = j->brick_cap ? j->brick_cap : 64;
        while (cap < j->brick_count + count)
            cap *= 2;
        pb_sparse_brick *nb = realloc(j->bricks, (size_t)cap * sizeof *nb);
        if (!nb)
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u bricks", cap);
        else
            j->bricks = nb, j->brick_cap = cap;
    }
    for (uint32_t b = 0; r == PB_OK && b < count; ++b) {
        int valid = 0;
        for (uint32_t i = 0; i < 64 && !valid; ++i)
            valid = (j->ps.flags[store_find(j, keys + ((size_t)b * 64 + i) * 3)] & PB_PROBE_VALID) != 0;
        if (valid) {
            j->bricks[j->brick_count++] = cand[b];
            j->stats.bricks[level]++;
        } else {
            j->stats.dropped[level]++;
        }
    }
    free(keys);
    return r;
}

/* The sparse volume of the current bricks (probes in layout order). */
static pb_result assemble(sparse_job *j, pb_volume *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (j->brick_count == 0)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "%s: every probe of the sparse bake is inside geometry: nothing to sample",
                       j->scene->path[0] ? j->scene->path : "scene");
    pb_sparse_layout *sp = calloc(1, sizeof *sp);
    uint32_t P = 0, *keys = NULL;
    pb_result r = sp ? pb_sparse_layout_build(j->levels, j->cells, j->bricks, j->brick_count, sp, &P, &keys, err)
                     : pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    if (r != PB_OK) {
        free(sp);
        return r;
    }
    *out = j->first;
    out->flags = (j->first.flags & ~(PB_VOLUME_GRID | PB_VOLUME_SHARD)) | PB_VOLUME_SPARSE;
    out->probe_count = P;
    out->counts[0] = P, out->counts[1] = out->counts[2] = 1;
    for (int k = 0; k < 3; ++k) {
        out->origin[k] = j->scene->origin[k] + (double)j->d.grid.origin[k];
        out->spacing[k] = j->F[k];
    }
    out->settings.passes = j->passes_max;
    out->settings.refine_error = j->refine_error;
    out->settings.refine_test = j->refine_test;
    out->settings.test_pass_scale = j->test_pass_scale;
    out->settings.seam_rounds = j->seam_rounds;
    out->settings.seam_error = j->seam_error;
    out->timings = j->timings;
    out->rays_traced = j->rays;
    out->traversals = j->traversals;
    out->relocation_rays = j->relocation_rays;
    r = pb_volume_alloc(out, err);
    if (r != PB_OK) {
        pb_sparse_layout_free(sp);
        free(sp), free(keys);
        return r;
    }
    out->sparse = sp;
    uint32_t halves = j->ps.halves;
    for (uint32_t p = 0; p < P; ++p) {
        uint32_t s = store_find(j, keys + 3 * (size_t)p);
        for (int k = 0; k < 3; ++k) {
            out->base[3 * (size_t)p + k] = (float)((double)keys[3 * (size_t)p + k] * j->F[k]);
            out->offset[3 * (size_t)p + k] = j->ps.offset[3 * (size_t)s + k];
        }
        out->probe_flags[p] = j->ps.flags[s];
        out->probe_paths[p] = j->ps.paths[s];
        out->probe_std_error[p] = j->ps.std_error[s];
        memcpy(out->sh + 27 * (size_t)p, j->ps.sh + 27 * (size_t)s, 27 * sizeof(float));
        memcpy(out->depth + (size_t)halves * p, j->ps.depth + (size_t)halves * s, halves * sizeof(uint16_t));
    }
    free(keys);
    return PB_OK;
}

/* Nearest surface seen by probe s, metres: the smallest mean depth of its tile. */
static float nearest_surface(const sparse_job *j, uint32_t s)
{
    const uint16_t *t = j->ps.depth + (size_t)j->ps.halves * s;
    float m = INFINITY;
    for (uint32_t i = 0; i < j->ps.halves; i += 2)
        m = fminf(m, pb_half_to_float(t[i]));
    return m * j->first.depth_unit;
}

static float irradiance_lum(const float sh[27], const float n[3])
{
    float e[3];
    pb_sh_eval(sh, n, e);
    return pb_luminance(e);
}

/* The probe test: one probe baked inside each cell (a point of the next
 * level's lattice, kept if the cell is refined); the cell is refined where
 * the level's sampler mispredicts it along any axis, or where it is
 * invalid (geometry crosses the cell). */
static pb_result test_by_probe(sparse_job *j, const pb_sparse_desc *sd, const pb_sample_volume *sv,
                               const pb_sparse_brick *cells, uint32_t count, uint8_t *refine, pb_error *err)
{
    uint32_t fine_step = pb_sparse_step(j->levels, cells[0].level);
    uint32_t *keys = malloc(((size_t)count + 1) * 3 * sizeof *keys);
    if (!keys)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse refinement");
    for (uint32_t t = 0; t < count; ++t)
        for (int k = 0; k < 3; ++k)
            keys[3 * (size_t)t + k] = (3 * cells[t].coord[k] + 1) * fine_step;
    pb_result r = bake_points(j, keys, count, cells[0].level, err);
    for (uint32_t t = 0; r == PB_OK && t < count; ++t) {
        uint32_t s = store_find(j, keys + 3 * (size_t)t);
        if (!(j->ps.flags[s] & PB_PROBE_VALID)) {
            refine[t] = 1; /* geometry crosses the cell: a valid corner, an invalid probe inside */
            continue;
        }
        float p[3];
        for (int k = 0; k < 3; ++k)
            p[k] = (float)((double)j->d.grid.origin[k] + (double)keys[3 * (size_t)t + k] * j->F[k]) +
                   j->ps.offset[3 * (size_t)s + k];
        float pred[6], baked[6];
        for (int a = 0; a < 6; ++a) {
            const float *n = pb_sparse_miss_axes[a];
            float rgb[3];
            pb_sample_cpu(sv, p, n, n, rgb);
            pred[a] = pb_luminance(rgb);
            baked[a] = irradiance_lum(j->ps.sh + 27 * (size_t)s, n);
        }
        refine[t] = pb_sparse_misses(pred, baked, j->ps.std_error[s], sd->refine_error);
    }
    free(keys);
    return r;
}

/* Where the surface tests of the cells of level-`level` bricks lie: a test
 * point every 3 finest spacings at most, per normal axis (a 9-cell is tested
 * on its 27 sub-cells); below the lattice origin the bounds reach down by
 * up to a finest spacing (the grid is centred in them). */
static pb_cell_test_desc cell_test_desc(const sparse_job *j, uint32_t level)
{
    uint32_t step = pb_sparse_step(j->levels, level);
    pb_cell_test_desc td = {.sub = step >= 9 ? step / 3 : 1};
    if (td.sub > PB_CELL_TESTS_SUB_MAX)
        td.sub = PB_CELL_TESTS_SUB_MAX;
    for (int k = 0; k < 3; ++k)
        td.origin[k] = j->d.grid.origin[k], td.size[k] = j->F[k] * step, td.margin[k] = j->F[k];
    return td;
}

/* The surface test (sparse_surface_tests.h): probes baked at points on the
 * surfaces inside each cell, where a renderer samples (biased off the
 * surface as the sampler biases, seen along the normal); the cell is
 * refined where the level's sampler mispredicts the irradiance there. The
 * test probes are thrown away. A cell no surface crosses is not refined. */
static pb_result test_by_surface(sparse_job *j, const pb_sparse_desc *sd, const pb_sample_volume *sv,
                                 const pb_sparse_brick *cells, uint32_t count, uint8_t *refine, pb_error *err)
{
    float finest = (float)fmin(j->F[0], fmin(j->F[1], j->F[2]));
    pb_cell_test_desc td = cell_test_desc(j, cells[0].level - 1);
    uint32_t *coords = malloc(((size_t)count + 1) * 3 * sizeof *coords);
    if (!coords)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse refinement");
    for (uint32_t t = 0; t < count; ++t)
        memcpy(coords + 3 * (size_t)t, cells[t].coord, 3 * sizeof *coords);
    pb_cell_tests ct;
    pb_result r = pb_cell_surface_tests(j->scene, j->gs->bvh, &td, coords, count, &ct, err);
    free(coords);
    /* a cell no surface crosses gets no test: counted as skipped, not tested */
    uint32_t with = 0;
    for (uint32_t i = 0; r == PB_OK && i < ct.count; ++i)
        with += i == 0 || ct.cell[i] != ct.cell[i - 1];
    j->stats.tested[cells[0].level - 1] -= count - with;
    j->stats.skipped[cells[0].level - 1] += count - with;
    if (r != PB_OK || ct.count == 0)
        return r;
    j->stats.test_probes[cells[0].level - 1] += ct.count;
    float bias = (sv->normal_bias + sv->view_bias) * finest;
    pb_points pts = {ct.count, malloc((size_t)ct.count * 3 * sizeof(double)), malloc((size_t)ct.count * sizeof(uint32_t)),
                     0.0};
    pb_volume v;
    memset(&v, 0, sizeof v);
    if (!pts.positions || !pts.ids) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u surface tests", ct.count);
    } else {
        for (uint32_t i = 0; i < ct.count; ++i) {
            for (int k = 0; k < 3; ++k)
                pts.positions[3 * (size_t)i + k] =
                    j->scene->origin[k] + (double)(ct.x[3 * (size_t)i + k] + bias * ct.n[3 * (size_t)i + k]);
            /* keyed by cell, sub-cell and normal axis, apart from the lattice points' ids */
            const pb_sparse_brick *c = &cells[ct.cell[i]];
            uint64_t key = c->coord[0] + ((uint64_t)c->coord[1] << 21) + ((uint64_t)c->coord[2] << 42);
            pts.ids[i] = key_id(~(key * 512u + ct.slot[i]));
        }
        r = bake_free(j, &pts, sd->test_pass_scale, &v, err);
    }
    /* mispredicted by more than the refine error of the larger of the two
     * values (so in [0, 1]: a dark wall predicted bright counts as much as a
     * bright one predicted dark), and by 3 standard errors. Not judged: where
     * both are below 1 % of the mean of the tests in the same coarsest brick,
     * and where the lookup (at the biased point) reads another coarsest
     * brick, whose cage refining this cell would not change. So every
     * decision rests on the cell's own coarsest brick, and a part of a
     * sharded bake, which holds only some, decides as the whole does (the
     * tests come grouped by coarsest brick: the bricks they refine are
     * sorted so, sort_bricks). */
    float *baked = r == PB_OK ? malloc((size_t)ct.count * 3 * sizeof *baked) : NULL;
    if (r == PB_OK && !baked)
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u surface tests", ct.count);
    for (uint32_t i = 0; r == PB_OK && i < ct.count; ++i) {
        float rgb[3];
        const float *x = ct.x + 3 * (size_t)i, *n = ct.n + 3 * (size_t)i;
        baked[3 * i] = irradiance_lum(v.sh + 27 * (size_t)i, n);
        uint32_t read_from;
        int own = pb_sample_brick_cpu(sv, x, n, n, &read_from) >= 0 &&
                  read_from == pb_sparse_coarsest_cell(j->cells, &cells[ct.cell[i]]);
        if (own)
            pb_sample_cpu(sv, x, n, n, rgb);
        baked[3 * i + 1] = own ? pb_luminance(rgb) : -1.f; /* -1: another coarsest brick's lookup */
    }
    for (uint32_t i = 0, end; r == PB_OK && i < ct.count; i = end) {
        uint64_t cell = pb_sparse_coarsest_cell(j->cells, &cells[ct.cell[i]]);
        double sum = 0.0;
        for (end = i; end < ct.count && pb_sparse_coarsest_cell(j->cells, &cells[ct.cell[end]]) == cell; ++end)
            sum += baked[3 * end];
        for (uint32_t t = i; t < end; ++t)
            baked[3 * t + 2] = (float)(sum / (end - i));
    }
    for (uint32_t i = 0; r == PB_OK && i < ct.count; ++i) {
        if (!(v.probe_flags[i] & PB_PROBE_VALID))
            continue; /* the biased point is inside geometry: no renderer samples there */
        float e = baked[3 * i], p = baked[3 * i + 1], mean = baked[3 * i + 2];
        if (p < 0.f)
            continue; /* its lookup reads another coarsest brick */
        float big = fmaxf(e, p);
        if (!(big > 0.01f * mean))
            continue;
        float rel = fabsf(e - p) / big;
        float noise = v.probe_std_error[i] > 0.f ? 3.f * v.probe_std_error[i] : 0.f;
        if (rel > fmaxf(sd->refine_error, noise))
            refine[ct.cell[i]] = 1;
    }
    free(baked);
    pb_volume_free(&v);
    free(pts.positions), free(pts.ids);
    pb_cell_tests_free(&ct);
    return r;
}

/* Whether the cell of a level-`level` brick at next-level coordinates c is
 * worth a finer brick: inside the bounds (the coarsest bricks overshoot
 * them: a cell wholly beyond is not the user's volume; the bounds reach up to
 * one finest spacing past the last lattice point, so a cell starting at the
 * last point still holds surfaces), with a valid corner (else solid: nothing
 * to light) and a surface within two cells of a corner probe or a corner
 * inside geometry. 0 worth it, 1 beyond, 2 not near or solid. */
static int cell_unworthy(const sparse_job *j, uint32_t level, const uint32_t c[3])
{
    uint32_t step = pb_sparse_step(j->levels, level);
    double s_l = fmax(j->F[0], fmax(j->F[1], j->F[2])) * step;
    for (int k = 0; k < 3; ++k)
        if (c[k] * step > j->d.grid.counts[k] - 1)
            return 1;
    int near = 0, open = 0;
    for (uint32_t i = 0; i < 8; ++i) {
        uint32_t k3[3];
        for (int k = 0; k < 3; ++k)
            k3[k] = (c[k] + ((i >> k) & 1u)) * step;
        uint32_t s = store_find(j, k3);
        int valid = (j->ps.flags[s] & PB_PROBE_VALID) != 0;
        open |= valid;
        near |= !valid || nearest_surface(j, s) < 2.0 * s_l;
    }
    return near && open ? 0 : 2;
}

/* The seam test (docs/sparse.md, placement step 3): a level's new bricks'
 * hanging probes test the coarser cells beside them; a cell whose value
 * misses one there is refined too, and the test runs again on the bricks
 * that adds, until none is missed (at most j->seam_rounds rounds). */
static pb_result refine_seams(sparse_job *j, uint32_t level, pb_error *err)
{
    pb_key_map tried;
    if (!pb_key_map_init(&tried, 1024))
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the seam test");
    uint32_t step = pb_sparse_step(j->levels, level), below = pb_sparse_step(j->levels, 0) / step * 3;
    pb_result r = PB_OK;
    for (uint32_t round = 0; r == PB_OK && round < j->seam_rounds; ++round) {
        pb_volume cur;
        if ((r = assemble(j, &cur, err)) != PB_OK)
            break;
        pb_sparse_brick *cells = NULL;
        uint32_t n = 0, kept = 0;
        r = pb_sparse_seam_misses(&cur, level + 1, &cells, &n, err);
        for (uint32_t i = 0; r == PB_OK && i < n; ++i) {
            float u[3];
            uint32_t k3[3];
            for (int k = 0; k < 3; ++k) {
                u[k] = ((float)cells[i].coord[k] + 0.5f) / (float)below;
                k3[k] = cells[i].coord[k] * step;
            }
            uint32_t at = pb_sparse_find(cur.sparse, u);
            if (at == PB_SPARSE_EMPTY || cur.sparse->bricks[at].level != level)
                continue; /* already finer (or no brick there) */
            uint64_t key = lattice_key(j, k3);
            if (pb_key_map_get(&tried, key) != PB_KEY_MAP_MISSING || cell_unworthy(j, level, cells[i].coord))
                continue;
            if (!pb_key_map_put(&tried, key, 1u)) {
                r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the seam test");
                break;
            }
            cells[kept++] = cells[i];
        }
        pb_volume_free(&cur);
        /* only cells a surface crosses: no pixel samples the others (as for the surface test) */
        uint32_t *coords = r == PB_OK && kept ? malloc((size_t)kept * 3 * sizeof *coords) : NULL;
        if (r == PB_OK && kept && !coords)
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the seam test");
        if (coords) {
            for (uint32_t i = 0; i < kept; ++i)
                memcpy(coords + 3 * (size_t)i, cells[i].coord, 3 * sizeof *coords);
            pb_cell_test_desc td = cell_test_desc(j, level);
            pb_cell_tests ct;
            r = pb_cell_surface_tests(j->scene, j->gs->bvh, &td, coords, kept, &ct, err);
            uint32_t m = 0;
            for (uint32_t i = 0; r == PB_OK && i < ct.count; ++i)
                if (i == 0 || ct.cell[i] != ct.cell[i - 1])
                    cells[m++] = cells[ct.cell[i]];
            if (r == PB_OK) {
                kept = m;
                pb_cell_tests_free(&ct);
            }
            free(coords);
        }
        j->stats.refined[level] += kept;
        j->stats.seam_refined[level] += kept;
        if (r == PB_OK)
            r = add_bricks(j, cells, kept, level + 1, err);
        free(cells);
        if (kept == 0)
            break;
    }
    pb_key_map_free(&tried);
    return r;
}

/* Bricks level by level, each level's by coarsest brick (stable): the order
 * the parts of a sharded bake merge in, now that the seam test adds bricks
 * to a level in rounds. */
static int brick_order(const void *a, const void *b)
{
    const uint64_t *x = a, *y = b;
    return x[0] < y[0] ? -1 : x[0] > y[0] ? 1 : (x[1] > y[1]) - (x[1] < y[1]);
}

static pb_result sort_bricks(sparse_job *j, pb_error *err)
{
    uint64_t *order = malloc(((size_t)j->brick_count + 1) * 2 * sizeof *order);
    pb_sparse_brick *sorted = malloc(((size_t)j->brick_count + 1) * sizeof *sorted);
    if (!order || !sorted) {
        free(order), free(sorted);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u bricks", j->brick_count);
    }
    uint64_t C = (uint64_t)j->cells[0] * j->cells[1] * j->cells[2];
    for (uint32_t b = 0; b < j->brick_count; ++b) {
        order[2 * b] = j->bricks[b].level * C + pb_sparse_coarsest_cell(j->cells, &j->bricks[b]);
        order[2 * b + 1] = b;
    }
    qsort(order, j->brick_count, 2 * sizeof *order, brick_order);
    for (uint32_t b = 0; b < j->brick_count; ++b)
        sorted[b] = j->bricks[order[2 * b + 1]];
    memcpy(j->bricks, sorted, (size_t)j->brick_count * sizeof *sorted);
    free(order), free(sorted);
    return PB_OK;
}

/* Refines the bricks of `level` into the next: the cells worth testing,
 * the test, new bricks; then the seam test. */
static pb_result refine_level(sparse_job *j, const pb_sparse_desc *sd, uint32_t level, pb_error *err)
{
    pb_volume cur;
    pb_result r = assemble(j, &cur, err);
    if (r != PB_OK)
        return r;
    pb_sample_volume sv;
    r = pb_sample_volume_build(&cur, j->scene->origin, 0.f, 0.f, &sv, err);
    pb_volume_free(&cur);
    if (r != PB_OK)
        return r;
    uint32_t nb = j->brick_count, tests = 0;
    pb_sparse_brick *test_cell = malloc(((size_t)nb * 27 + 1) * sizeof *test_cell);
    uint8_t *refine = calloc((size_t)nb * 27 + 1, 1);
    if (!test_cell || !refine) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse refinement");
        goto done;
    }
    for (uint32_t b = 0; b < nb; ++b) {
        const pb_sparse_brick *br = &j->bricks[b];
        if (br->level != level)
            continue;
        for (uint32_t c = 0; c < 27; ++c) {
            uint32_t cc[3] = {c % 3, (c / 3) % 3, c / 9}, coord[3];
            for (int k = 0; k < 3; ++k)
                coord[k] = 3 * br->coord[k] + cc[k];
            int why = cell_unworthy(j, level, coord);
            if (why) {
                (why == 1 ? j->stats.beyond : j->stats.skipped)[level]++;
                continue;
            }
            memcpy(test_cell[tests].coord, coord, sizeof coord);
            test_cell[tests].level = level + 1;
            tests++;
        }
    }
    j->stats.tested[level] += tests;
    if (tests)
        r = sd->test == PB_REFINE_TEST_PROBE ? test_by_probe(j, sd, &sv, test_cell, tests, refine, err)
                                             : test_by_surface(j, sd, &sv, test_cell, tests, refine, err);
    uint32_t nc = 0;
    for (uint32_t t = 0; r == PB_OK && t < tests; ++t)
        if (refine[t]) {
            test_cell[nc++] = test_cell[t];
            j->stats.refined[level]++;
        }
    if (r == PB_OK)
        r = add_bricks(j, test_cell, nc, level + 1, err);
    if (r == PB_OK && nc && j->seam_rounds)
        r = refine_seams(j, level, err);
    if (r == PB_OK)
        r = sort_bricks(j, err);
done:
    pb_sample_volume_free(&sv);
    free(test_cell), free(refine);
    return r;
}

/* One placement: coarsest bricks, refinement level by level, assembly,
 * dilation, stitching. */
static pb_result place(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc,
                       const pb_sparse_desc *sd_in, int one_bounce, const pb_sample_volume *feedback, pb_volume *out,
                       pb_sparse_stats *stats, pb_error *err)
{
    const pb_sparse_desc sd = *sd_in;
    sparse_job j;
    memset(&j, 0, sizeof j);
    j.ctx = ctx, j.scene = scene, j.gs = gs, j.d = *desc, j.levels = sd.levels;
    j.one_bounce = one_bounce, j.feedback = feedback, j.refine_error = sd.refine_error;
    j.refine_test = 1u + sd.test;
    j.test_pass_scale = sd.test == PB_REFINE_TEST_SURFACE ? sd.test_pass_scale : 0u;
    j.seam_rounds = sd.seam_rounds;
    j.seam_error = sd.seam_rounds ? sd.seam_error : 0.f;
    j.d.shard_index = j.d.shard_count = 0; /* a part is a range of coarsest bricks, its bakes whole */
    uint32_t span = pow3u(sd.levels);
    for (int k = 0; k < 3; ++k) {
        if (desc->grid.counts[k] == 0 || !(desc->grid.spacing[k] > 0.f) || !isfinite(desc->grid.spacing[k]))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse bake: grid spacing and counts must be positive");
        j.F[k] = desc->grid.spacing[k];
        j.cells[k] = (desc->grid.counts[k] - 1 + span - 1) / span;
        j.cells[k] = j.cells[k] ? j.cells[k] : 1;
        if ((uint64_t)j.cells[k] * span >= (1u << 20))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse bake: %u finest probes on axis %d is too many",
                           desc->grid.counts[k], k);
    }
    j.X = (uint64_t)j.cells[0] * span + 1, j.Y = (uint64_t)j.cells[1] * span + 1;
    uint32_t n = desc->octmap_res ? desc->octmap_res : 16;
    j.ps.halves = (uint32_t)pb_volume_tile_halves(n);
    pb_sparse_brick *cand = NULL;
    pb_result r = pb_key_map_init(&j.ps.index, 4096) ? PB_OK
                                                      : pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    /* level 0: every cell (a part: its range of cells; refinement stays
     * inside a coarsest brick, so parts place as the whole does) */
    uint64_t C = (uint64_t)j.cells[0] * j.cells[1] * j.cells[2];
    if (r == PB_OK && C > (1u << 22))
        r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse bake: %llu coarsest bricks is too many (raise the spacing)",
                    (unsigned long long)C);
    uint32_t first = 0, count = (uint32_t)C;
    if (r == PB_OK && desc->shard_count) {
        if (desc->shard_index >= desc->shard_count || desc->shard_count > C)
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                        "--shard %u/%u: a sparse bake splits by coarsest brick, and this one has %llu: at most %llu "
                        "parts, index below the count", desc->shard_index, desc->shard_count, (unsigned long long)C,
                        (unsigned long long)C);
        else
            pb_shard_range((uint32_t)C, desc->shard_index, desc->shard_count, &first, &count);
    }
    if (r == PB_OK && !(cand = malloc((size_t)count * sizeof *cand)))
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %llu bricks", (unsigned long long)C);
    if (r == PB_OK) {
        for (uint64_t i = 0; i < count; ++i) {
            uint64_t c = first + i;
            cand[i] = (pb_sparse_brick){0, {(uint32_t)(c % j.cells[0]), (uint32_t)((c / j.cells[0]) % j.cells[1]),
                                            (uint32_t)(c / ((uint64_t)j.cells[0] * j.cells[1]))}};
        }
        r = add_bricks(&j, cand, count, 0, err);
    }
    free(cand);
    for (uint32_t level = 0; r == PB_OK && level + 1 < j.levels; ++level)
        r = refine_level(&j, &sd, level, err);
    if (r == PB_OK && desc->shard_count && j.brick_count == 0)
        r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                    "%s: part %u/%u of the sparse bake has no brick outside geometry: bake it in fewer parts",
                    scene->path[0] ? scene->path : "scene", desc->shard_index, desc->shard_count);
    if (r == PB_OK)
        r = assemble(&j, out, err);
    if (r == PB_OK && desc->shard_count) { /* merge dilates and stitches the whole (sparse_merge.c) */
        out->flags |= PB_VOLUME_SHARD;
        out->shard = (pb_volume_shard){desc->shard_index, desc->shard_count, first, (uint32_t)C, 1};
        if (stats)
            *stats = j.stats;
        store_free(&j.ps);
        free(j.bricks);
        return PB_OK;
    }
    /* invalid probes (in rock, inside kept bricks) take their neighbours'
     * light on the device, as a grid's do; then the level seams are stitched */
    if (r == PB_OK && (r = pb_volume_dilate_gpu(ctx, out, PB_DILATION_ROUNDS, err)) != PB_OK)
        pb_volume_free(out);
    if (r == PB_OK && (r = pb_sparse_stitch(out, err)) != PB_OK)
        pb_volume_free(out);
    if (stats)
        *stats = j.stats;
    store_free(&j.ps);
    free(j.bricks);
    return r;
}

/* One bounce of --indirect volume: a placement of its own; the stats of
 * the last, the bakes and test probes of all. */
typedef struct sparse_bounce {
    pb_context *ctx;
    const pb_scene *scene;
    pb_gpu_scene *gs;
    const pb_sparse_desc *sd;
    uint32_t bakes, test_probes[3];
    pb_sparse_stats last;
} sparse_bounce;

static pb_result sparse_bounce_bake(void *user, const pb_bake_desc *d, const pb_sample_volume *previous,
                                    pb_volume *out, pb_error *err)
{
    sparse_bounce *b = user;
    pb_result r = place(b->ctx, b->scene, b->gs, d, b->sd, 1, previous, out, &b->last, err);
    b->bakes += r == PB_OK ? b->last.bakes : 0;
    for (int l = 0; r == PB_OK && l < 3; ++l)
        b->test_probes[l] += b->last.test_probes[l];
    return r;
}

/* Step 7: the probes in rock, read by dilation and stitching, are dropped
 * (sparse_compact.c); a part keeps them for the merge to dilate. */
static pb_result drop_invalid(pb_volume *out, pb_error *err)
{
    pb_result r = pb_sparse_drop_invalid(out, err);
    if (r != PB_OK)
        pb_volume_free(out);
    return r;
}

pb_result pb_bake_sparse(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc,
                         const pb_sparse_desc *sd_in, pb_volume *out, pb_sparse_stats *stats, pb_error *err)
{
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    /* every setting checked before any work (settings.c: the command line
     * runs the same checks before it loads the scene) */
    pb_sparse_desc sd;
    pb_result checked = pb_bake_settings(desc, sd_in, &sd, err);
    if (checked != PB_OK)
        return checked;
    if (!desc->indirect_volume || desc->bounces == 0) {
        pb_bake_desc d = *desc;
        d.indirect_volume = 0;
        pb_result r = place(ctx, scene, gs, &d, &sd, 0, NULL, out, stats, err);
        return r == PB_OK && !desc->shard_count ? drop_invalid(out, err) : r;
    }
    /* --indirect volume: bounce k places and bakes its own layout (the
     * last bounce's is the volume's), its probe rays' first hits reflecting
     * bounce k - 1's sparse volume */
    sparse_bounce sb = {.ctx = ctx, .scene = scene, .gs = gs, .sd = &sd};
    pb_result r = pb_indirect_volume_bounces(scene, desc, sparse_bounce_bake, &sb, out, err);
    if (r == PB_OK) /* the bounces sampled their volumes whole; the file drops what no lookup weighs */
        r = drop_invalid(out, err);
    if (r == PB_OK && stats) {
        *stats = sb.last;
        stats->bakes = sb.bakes;
        memcpy(stats->test_probes, sb.test_probes, sizeof sb.test_probes);
    }
    return r;
}
