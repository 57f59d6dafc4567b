/* Light cells: emitter clusters, cells measured with shadow rays
 * (light_cells.h). */
#include "bake/light_cells.h"
#include "bake/alias.h"
#include "common/common.h"
#include "probebake/trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PB_LIGHT_PASS 0xC0000001u   /* the surface points' and shadow rays' pass number in the RNG key */
#define PB_LIGHT_CELL_POINTS_PER_CELL 160.0 /* surface points per cell on average (64: 1.4x the paths on The Crypt, 400: 1.7x) */
#define PB_LIGHT_TABLE_MAX (1u << 21) /* slots x clusters: 32 MiB of tables at most */
#define PB_LIGHT_RAYS_PER_BATCH (1u << 18)

typedef struct keyed {
    uint64_t key;
    uint32_t index;
} keyed;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->index > y->index) - (x->index < y->index);
}

/* Emitters sorted by the cell of a grid of edge h that holds their centroid;
 * returns the number of distinct cells (clusters). */
static uint32_t cluster_keys(const pb_scene *s, const float *centroid, uint32_t E, float h, keyed *k)
{
    for (uint32_t i = 0; i < E; ++i) {
        uint64_t c[3];
        for (int a = 0; a < 3; ++a) {
            float f = floorf((centroid[3 * i + a] - s->bounds_min[a]) / h);
            c[a] = f < 0.f ? 0u : (f > 2097151.f ? 2097151u : (uint64_t)f);
        }
        k[i].key = c[2] << 42 | c[1] << 21 | c[0];
        k[i].index = i;
    }
    qsort(k, E, sizeof *k, cmp_keyed);
    uint32_t n = E ? 1u : 0u;
    for (uint32_t i = 1; i < E; ++i)
        n += k[i].key != k[i - 1].key;
    return n;
}

/* A shadow ray of the measurement and what its light is worth if unblocked. */
typedef struct probe_ray {
    uint32_t slot, cluster;
    float weight;                 /* cos at the emitter / distance^2 (clamped) */
} probe_ray;

/* One batch's shadow rays, R per (cell slot, candidate cluster) pair in the
 * pairs' order: each ray depends only on its pair and index, so ranges of
 * rays are made on all host cores, the same rays in the same order. */
typedef struct ray_batch {
    const pb_scene *s;
    const pb_light_cells *out;
    const uint32_t *pair_slot, *pair_cluster; /* per pair */
    const uint32_t *slot_cell, *first, *order;
    const float *points;
    uint32_t seed, R;
    float min_d2;
    pb_ray *rays;
    probe_ray *meta;
} ray_batch;

static void make_shadow_rays(void *user, uint64_t begin, uint64_t end)
{
    const ray_batch *b = user;
    const pb_scene *s = b->s;
    const pb_light_cells *out = b->out;
    for (uint64_t nr = begin; nr < end; ++nr) {
        uint32_t pair = (uint32_t)(nr / b->R), ri = (uint32_t)(nr % b->R);
        uint32_t sl = b->pair_slot[pair], best = b->pair_cluster[pair];
        uint32_t c = b->slot_cell[sl], f = b->first[c], np = b->first[c + 1] - f;
        uint32_t cf = out->cluster_range[2 * best], cn = out->cluster_range[2 * best + 1];
        uint32_t state = pb_rng_seed_cpu(b->seed, c, PB_LIGHT_PASS + 1u, best * b->R + ri);
        float u0 = pb_rng_next_cpu(&state), u1 = pb_rng_next_cpu(&state);
        float u2 = pb_rng_next_cpu(&state), u3 = pb_rng_next_cpu(&state);
        uint32_t pi = (uint32_t)(u0 * (float)np) < np ? (uint32_t)(u0 * (float)np) : np - 1u;
        const float *x = b->points + 6 * (size_t)b->order[f + pi], *nx = x + 3;
        uint32_t tri = out->member_tri[cf + pb_alias_sample(out->member_keep + cf, out->member_alias + cf, cn, u1)];
        const float *v0 = s->positions + 9 * (size_t)tri, *v1 = v0 + 3, *v2 = v0 + 6;
        float su = sqrtf(u2), b1 = su * (1.f - u3), b2 = su * u3, e1[3], e2[3], to[3];
        for (int a = 0; a < 3; ++a) {
            e1[a] = v1[a] - v0[a], e2[a] = v2[a] - v0[a];
            to[a] = v0[a] + b1 * e1[a] + b2 * e2[a] - x[a];
        }
        float ne[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        float nl = sqrtf(ne[0] * ne[0] + ne[1] * ne[1] + ne[2] * ne[2]);
        float d2 = to[0] * to[0] + to[1] * to[1] + to[2] * to[2];
        float cos_e =
            nl > 0.f && d2 > 0.f ? -(ne[0] * to[0] + ne[1] * to[1] + ne[2] * to[2]) / (nl * sqrtf(d2)) : 0.f;
        if (s->materials[s->material[tri]].double_sided)
            cos_e = fabsf(cos_e);
        pb_ray *ray = &b->rays[nr];
        memcpy(ray->origin, x, sizeof ray->origin);
        memcpy(ray->direction, to, sizeof ray->direction);
        ray->tmin = 0.f;
        float cos_x = d2 > 0.f ? (nx[0] * to[0] + nx[1] * to[1] + nx[2] * to[2]) / sqrtf(d2) : 0.f;
        int lit = cos_e > 0.f && cos_x > 0.f;
        ray->tmax = lit ? 0.9999f : 0.f;
        b->meta[nr] = (probe_ray){sl, best, lit ? cos_x * cos_e / fmaxf(d2, b->min_d2) : 0.f};
    }
}

/* What the four steps of a build share; owned by it, freed together. */
typedef struct cells_build {
    const pb_bake_pass *pass;
    const pb_scene *s;
    pb_light_cells *out;
    pb_surface_sampler surface;
    uint32_t E, C;          /* emitters, clusters */
    double *p;              /* per emitter: its probability by power */
    float *centroid;        /* per emitter: 3 floats */
    keyed *k;               /* emitters in cluster order */
    double *share;          /* per cluster: its part of the power */
    float *cen;             /* per cluster: power-weighted centre, squared radius */
    float cell;             /* the cells' edge */
    float *points;          /* surface points: position, normal */
    uint32_t have, cells, slots;
    uint32_t *first;        /* per cell + 1: its first point in `order` */
    uint32_t *order;        /* points by cell */
    uint32_t *slot_cell;    /* per slot (cell with enough points): its cell */
    double *light;          /* per slot and cluster: measured unblocked light */
    pb_shadow_batch_fn trace; /* the shadow rays' tracer, NULL: pb_trace_cpu */
    void *trace_user;
} cells_build;

static void cells_build_free(cells_build *b)
{
    pb_surface_sampler_free(&b->surface);
    free(b->p), free(b->centroid), free(b->k), free(b->share), free(b->cen), free(b->points);
    free(b->first), free(b->order), free(b->slot_cell), free(b->light);
}

/* 1. Clusters: emitters grouped by a grid over their centroids, coarsened
 * until there are at most PB_LIGHT_CLUSTERS_MAX; each cluster's power,
 * power-weighted centre and radius, and an alias table by power within it.
 * Returns 0 when out of memory; b->C < 2 means one cluster (nothing to learn). */
static int make_clusters(cells_build *b)
{
    const pb_scene *s = b->s;
    const pb_bake_emitters *em = b->pass->emitters;
    pb_light_cells *out = b->out;
    uint32_t E = b->E;
    for (uint32_t i = 0; i < E; ++i) {
        const float *v = s->positions + 9 * (size_t)em->tri[i];
        b->p[i] = (double)em->pdf_area[em->tri[i]] * pb_triangle_area(v);
        for (int a = 0; a < 3; ++a)
            b->centroid[3 * i + a] = (v[a] + v[3 + a] + v[6 + a]) / 3.f;
    }
    pb_cell_grid_fit(s, b->surface.area_total, PB_LIGHT_CELL_POINTS_PER_CELL, PB_LIGHT_CELL_POINTS, &out->grid);
    b->cell = 1.f / out->grid.inv_cell;
    float h = 0.5f * b->cell;
    while ((b->C = cluster_keys(s, b->centroid, E, h, b->k)) > PB_LIGHT_CLUSTERS_MAX)
        h *= 1.5f;
    uint32_t C = b->C;
    if (C < 2)
        return 1;
    out->clusters = C;
    out->cluster_range = calloc(2 * (size_t)C, sizeof *out->cluster_range);
    b->share = calloc(C, sizeof *b->share);
    b->cen = calloc(4 * (size_t)C, sizeof *b->cen);
    if (!out->cluster_range || !b->share || !b->cen)
        return 0;
    const keyed *k = b->k;
    for (uint32_t i = 0, c = 0; i < E; ++i) {
        if (i && k[i].key != k[i - 1].key)
            ++c;
        uint32_t e = k[i].index;
        if (!out->cluster_range[2 * c + 1])
            out->cluster_range[2 * c] = i;
        out->cluster_range[2 * c + 1]++;
        out->member_tri[i] = em->tri[e];
        out->cluster_of[em->tri[e]] = c;
        b->share[c] += b->p[e];
    }
    for (uint32_t c = 0; c < C; ++c) {
        uint32_t f = out->cluster_range[2 * c], n = out->cluster_range[2 * c + 1];
        double w[3] = {0, 0, 0}, wsum = 0;
        for (uint32_t i = f; i < f + n; ++i) {
            double pi = b->p[k[i].index] > 0 ? b->p[k[i].index] : 1e-30; /* zero-power members: the plain mean */
            wsum += pi;
            for (int a = 0; a < 3; ++a)
                w[a] += pi * b->centroid[3 * k[i].index + a];
        }
        float *cc = b->cen + 4 * c;
        for (int a = 0; a < 3; ++a)
            cc[a] = (float)(w[a] / wsum);
        float r2 = 0.f;
        for (uint32_t i = f; i < f + n; ++i) {
            float d2 = 0.f;
            for (int a = 0; a < 3; ++a) {
                float d = b->centroid[3 * k[i].index + a] - cc[a];
                d2 += d * d;
            }
            r2 = fmaxf(r2, d2);
        }
        cc[3] = r2;
        /* within the cluster by power (alias indices local to it) */
        double *wm = malloc(n * sizeof *wm);
        if (!wm)
            return 0;
        for (uint32_t i = 0; i < n; ++i)
            wm[i] = b->p[k[f + i].index];
        int built = pb_alias_build(wm, n, out->member_keep + f, out->member_alias + f);
        free(wm);
        if (built < 0)
            return 0;
        if (!built)
            for (uint32_t i = 0; i < n; ++i) /* no power at all: never drawn (q = 0) */
                out->member_keep[f + i] = 1.f, out->member_alias[f + i] = i;
    }
    return 1;
}

/* 2. Surface points by area (keyed by the seed only), bucketed by cell; the
 * cells grow while their tables would pass PB_LIGHT_TABLE_MAX. Then the
 * slots: the cells with enough points to learn from. */
static int bucket_points(cells_build *b)
{
    const pb_scene *s = b->s;
    pb_light_cells *out = b->out;
    uint32_t N = PB_LIGHT_CELL_POINTS;
    b->points = malloc(6 * (size_t)N * sizeof *b->points);
    uint32_t *point_cell = malloc(N * sizeof *point_cell);
    b->order = malloc(N * sizeof *b->order);
    int ok = b->points && point_cell && b->order;
    for (uint32_t i = 0; ok && i < N; ++i) {
        uint32_t state = pb_rng_seed_cpu(b->pass->seed, i, PB_LIGHT_PASS, 0u);
        float *x = b->points + 6 * (size_t)b->have;
        b->have += pb_surface_point(s, &b->surface, &state, x, x + 3) != 0;
    }
    uint32_t learnable = 0;
    while (ok) {
        b->cells = pb_cell_grid_cells(&out->grid);
        free(b->first);
        if (!(b->first = calloc((size_t)b->cells + 1, sizeof *b->first))) {
            ok = 0;
            break;
        }
        for (uint32_t i = 0; i < b->have; ++i)
            b->first[(point_cell[i] = pb_cell_grid_index(&out->grid, b->points + 6 * (size_t)i)) + 1]++;
        learnable = 0;
        for (uint32_t c = 0; c < b->cells; ++c)
            learnable += b->first[c + 1] >= PB_LIGHT_CELL_MIN_POINTS;
        if ((uint64_t)learnable * b->C <= PB_LIGHT_TABLE_MAX)
            break;
        b->cell *= 1.5f;
        pb_cell_grid_set(s, b->cell, &out->grid);
    }
    uint32_t *fill = ok ? calloc(b->cells, sizeof *fill) : NULL;
    b->slot_cell = malloc((learnable ? learnable : 1) * sizeof *b->slot_cell);
    if (!fill || !b->slot_cell) {
        free(fill), free(point_cell);
        return 0;
    }
    for (uint32_t c = 0; c < b->cells; ++c) {
        if (b->first[c + 1] >= PB_LIGHT_CELL_MIN_POINTS)
            b->slot_cell[b->slots++] = c;
        b->first[c + 1] += b->first[c];
    }
    for (uint32_t i = 0; i < b->have; ++i)
        b->order[b->first[point_cell[i]] + fill[point_cell[i]]++] = i; /* point order within a cell */
    free(fill), free(point_cell);
    return 1;
}

/* 3. Per slot: the candidate clusters by power over distance squared from
 * the mean of its points, measured with shadow rays from its points, in
 * batches of slots (b->light). */
static pb_result measure_cells(cells_build *b, pb_error *err)
{
    const pb_scene *s = b->s;
    uint32_t C = b->C, K = C < PB_LIGHT_CELL_CANDIDATES ? C : PB_LIGHT_CELL_CANDIDATES, R = PB_LIGHT_CELL_RAYS;
    uint32_t batch_cells = PB_LIGHT_RAYS_PER_BATCH / (K * R) ? PB_LIGHT_RAYS_PER_BATCH / (K * R) : 1;
    size_t batch_rays = (size_t)batch_cells * K * R;
    b->light = calloc((size_t)(b->slots ? b->slots : 1) * C, sizeof *b->light);
    double *U = malloc(C * sizeof *U);
    pb_ray *rays = malloc(batch_rays * sizeof *rays);
    pb_hit *hits = malloc(batch_rays * sizeof *hits);
    probe_ray *meta = malloc(batch_rays * sizeof *meta);
    uint32_t *pair_slot = malloc((size_t)batch_cells * K * sizeof *pair_slot);
    uint32_t *pair_cluster = malloc((size_t)batch_cells * K * sizeof *pair_cluster);
    pb_result r = b->light && U && rays && hits && meta && pair_slot && pair_cluster
                      ? PB_OK
                      : pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for light cells (%u emitters)",
                                b->E);
    float near2 = 0.25f * b->cell * b->cell, min_d2 = 0.0625f * b->cell * b->cell;
    for (uint32_t s0 = 0; r == PB_OK && s0 < b->slots; s0 += batch_cells) {
        uint32_t s1 = s0 + batch_cells < b->slots ? s0 + batch_cells : b->slots, npairs = 0;
        for (uint32_t sl = s0; sl < s1; ++sl) {
            uint32_t c = b->slot_cell[sl], f = b->first[c], np = b->first[c + 1] - f;
            float m[3] = {0, 0, 0};
            for (uint32_t i = f; i < f + np; ++i)
                for (int a = 0; a < 3; ++a)
                    m[a] += b->points[6 * (size_t)b->order[i] + a] / (float)np;
            for (uint32_t cl = 0; cl < C; ++cl) {
                float d2 = 0.f;
                for (int a = 0; a < 3; ++a) {
                    float d = b->cen[4 * cl + a] - m[a];
                    d2 += d * d;
                }
                U[cl] = b->share[cl] / fmax(d2, near2 + b->cen[4 * cl + 3]);
            }
            for (uint32_t kk = 0; kk < K; ++kk) { /* the K largest, in order */
                uint32_t best = 0;
                for (uint32_t cl = 1; cl < C; ++cl)
                    best = U[cl] > U[best] ? cl : best;
                if (!(U[best] > 0.0))
                    break;
                U[best] = -1.0;
                pair_slot[npairs] = sl, pair_cluster[npairs++] = best;
            }
        }
        size_t nr = (size_t)npairs * R;
        ray_batch rb = {s, b->out, pair_slot, pair_cluster, b->slot_cell, b->first, b->order, b->points,
                        b->pass->seed, R, min_d2, rays, meta};
        pb_parallel_for(nr, 1024, 0, make_shadow_rays, &rb);
        if (b->trace)
            r = b->trace(b->trace_user, rays, (uint32_t)nr, hits, err);
        else
            pb_trace_cpu(s, b->pass->bvh, rays, (uint32_t)nr, PB_TRACE_ANY, hits, 0);
        for (size_t i = 0; r == PB_OK && i < nr; ++i) /* in ray order: sums independent of the threads */
            if (hits[i].triangle == PB_NO_HIT)
                b->light[(size_t)meta[i].slot * C + meta[i].cluster] += b->share[meta[i].cluster] * meta[i].weight / R;
    }
    free(U), free(rays), free(hits), free(meta), free(pair_slot), free(pair_cluster);
    return r;
}

/* 4. Per slot: q = a share + (1 - a) measured / total, as an alias table
 * with each cluster's ratio q / share. Slots that measured no light draw
 * by power (no table). */
static int make_tables(cells_build *b)
{
    pb_light_cells *out = b->out;
    uint32_t C = b->C;
    out->slot = malloc(b->cells * sizeof *out->slot);
    out->table = calloc((size_t)(b->slots ? b->slots : 1) * C * 4, sizeof *out->table);
    double *q = malloc(C * sizeof *q);
    float *keep = malloc(C * sizeof *keep);
    uint32_t *alias = malloc(C * sizeof *alias);
    int ok = out->slot && out->table && q && keep && alias;
    if (ok)
        memset(out->slot, 0xff, b->cells * sizeof *out->slot);
    for (uint32_t sl = 0; ok && sl < b->slots; ++sl) {
        const double *Lc = b->light + (size_t)sl * C;
        double total = 0;
        for (uint32_t cl = 0; cl < C; ++cl)
            total += Lc[cl];
        if (!(total > 0.0) || !isfinite(total))
            continue; /* no emitter measured unblocked: by power */
        for (uint32_t cl = 0; cl < C; ++cl)
            q[cl] = PB_LIGHT_CELL_POWER_SHARE * b->share[cl] + (1.0 - PB_LIGHT_CELL_POWER_SHARE) * Lc[cl] / total;
        int built = pb_alias_build(q, C, keep, alias);
        if (!(ok = built >= 0))
            break;
        if (!built)
            continue; /* q is a power share and a measured share: it sums to 1 */
        float *tb = out->table + 4 * (size_t)out->learned * C;
        for (uint32_t cl = 0; cl < C; ++cl) {
            tb[4 * cl] = keep[cl];
            memcpy(&tb[4 * cl + 1], &alias[cl], 4);
            tb[4 * cl + 2] = b->share[cl] > 0.0 ? (float)(q[cl] / b->share[cl]) : 1.f;
            tb[4 * cl + 3] = 0.f;
        }
        out->slot[b->slot_cell[sl]] = out->learned++;
    }
    free(q), free(keep), free(alias);
    return ok;
}

pb_result pb_light_cells_build(const pb_bake_pass *pass, pb_shadow_batch_fn trace, void *trace_user,
                               pb_light_cells *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    const pb_scene *s = pass->scene;
    const pb_bake_emitters *em = pass->emitters;
    if (!em || !em->count || !s->triangle_count)
        return PB_OK;
    uint32_t E = em->count, T = s->triangle_count;
    cells_build b = {0};
    b.pass = pass, b.s = s, b.out = out, b.E = E, b.trace = trace, b.trace_user = trace_user;
    b.p = malloc(E * sizeof *b.p);
    b.centroid = malloc(3 * (size_t)E * sizeof *b.centroid);
    b.k = malloc(E * sizeof *b.k);
    out->cluster_of = pb_calloc_large(T, sizeof *out->cluster_of); /* per triangle */
    out->member_tri = malloc(E * sizeof *out->member_tri);
    out->member_keep = malloc(E * sizeof *out->member_keep);
    out->member_alias = malloc(E * sizeof *out->member_alias);
    int ok = b.p && b.centroid && b.k && out->cluster_of && out->member_tri && out->member_keep &&
             out->member_alias && pb_surface_sampler_init(s, &b.surface);
    ok = ok && make_clusters(&b);
    pb_result r = ok ? PB_OK : PB_ERROR_OUT_OF_HOST_MEMORY;
    if (ok && b.C >= 2) { /* one cluster: every cell would draw by power */
        r = bucket_points(&b) ? measure_cells(&b, err) : PB_ERROR_OUT_OF_HOST_MEMORY;
        if (r == PB_OK && !make_tables(&b))
            r = PB_ERROR_OUT_OF_HOST_MEMORY;
    }
    cells_build_free(&b);
    if (r == PB_ERROR_OUT_OF_HOST_MEMORY)
        pb_fail(err, r, "out of host memory for light cells (%u emitters)", E);
    if (r != PB_OK || !out->learned)
        pb_light_cells_free(out);
    return r;
}

void pb_light_cells_free(pb_light_cells *lc)
{
    free(lc->slot), free(lc->cluster_range), free(lc->member_tri), free(lc->member_keep), free(lc->member_alias);
    free(lc->cluster_of), free(lc->table);
    memset(lc, 0, sizeof *lc);
}

int32_t pb_light_cells_slot(const pb_light_cells *lc, const float x[3])
{
    if (!lc || !lc->table)
        return -1;
    uint32_t sl = lc->slot[pb_cell_grid_index(&lc->grid, x)];
    return sl == ~0u ? -1 : (int32_t)sl;
}

uint32_t pb_light_cells_sample(const pb_light_cells *lc, int32_t slot, float u0, float u1, float *ratio)
{
    const float *tb = lc->table + 4 * (size_t)slot * lc->clusters;
    float xc = u0 * (float)lc->clusters;
    uint32_t i = (uint32_t)xc < lc->clusters - 1u ? (uint32_t)xc : lc->clusters - 1u, alias;
    memcpy(&alias, &tb[4 * i + 1], 4);
    uint32_t c = xc - (float)i < tb[4 * i] ? i : alias;
    *ratio = tb[4 * c + 2];
    const uint32_t *rg = lc->cluster_range + 2 * c;
    return lc->member_tri[rg[0] + pb_alias_sample(lc->member_keep + rg[0], lc->member_alias + rg[0], rg[1], u1)];
}

float pb_light_cells_ratio(const pb_light_cells *lc, int32_t slot, uint32_t tri)
{
    return slot < 0 ? 1.f : lc->table[4 * ((size_t)slot * lc->clusters + lc->cluster_of[tri]) + 2];
}
