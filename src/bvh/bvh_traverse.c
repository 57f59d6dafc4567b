/* CPU reference traversal and brute force. The traversal is the GPU kernel's
 * loop in C (shaders/include/traverse.glsl): 4-wide quantized nodes, child
 * boxes sorted near to far, hit leaves tested in that order, the nearest hit
 * inner child next and the others a pending group, whose predecessor goes on
 * the stack (at most one entry per level). Written as a walker (bvh_walk.h)
 * so that a model can run rays side by side as SIMD lanes do. */
#include "bvh/alpha.h"
#include "bvh/bvh_walk.h"
#include "bvh/bvh_wide.h"
#include "bvh/intersect.h"
#include "common/common.h"
#include "probebake/bvh.h"
#include "probebake/trace.h"

#include <stdlib.h>
#include <string.h>

typedef struct trace_job {
    const pb_scene *scene;
    const pb_bvh *bvh;
    const pb_ray *rays;
    pb_hit *hits;
    pb_trace_mode mode;
} trace_job;

static void finish_hit(const pb_scene *s, const pb_ray *ray, uint32_t tri, float t, float u, float v, pb_hit *hit)
{
    hit->triangle = tri;
    hit->t = t;
    hit->u = u;
    hit->v = v;
    hit->backface = 0;
    if (tri != PB_NO_HIT) {
        const float *p = s->positions + 9 * (size_t)tri;
        hit->backface = pb_is_backface(p, p + 3, p + 6, ray->direction);
    } else {
        hit->t = ray->tmax;
        hit->u = hit->v = 0.f;
    }
}

/* Compare-exchange of child slots a and b by box distance; ties keep slot order. */
#define PB_SORT2(a, b)                                                                                              \
    do {                                                                                                           \
        if (d[b] < d[a]) {                                                                                         \
            float td = d[a]; uint32_t tc = ch[a], tn = cnt[a];                                                    \
            d[a] = d[b], ch[a] = ch[b], cnt[a] = cnt[b];                                                           \
            d[b] = td, ch[b] = tc, cnt[b] = tn;                                                                    \
        }                                                                                                          \
    } while (0)

/* A group of pending inner siblings: the first sibling's node index, how many
 * are pending (0-3) and their ranks among the node's inner children, nearest
 * first, 2 bits each. One stack entry per level instead of three: on llvmpipe
 * a push is a scalar store per SIMD lane, so one push site instead of three
 * is what pays (bench/RESULTS.md). */
#define PB_GROUP(first, count, ranks) ((first) << 8 | (count) << 6 | (ranks))
#define PB_GROUP_COUNT(g) (((g) >> 6) & 3)

void pb_bvh_walk_start(pb_bvh_walk *w, const pb_ray *ray)
{
    pb_ray_prepare(ray->origin, ray->direction, &w->r);
    w->tmin = ray->tmin, w->tmax = ray->tmax;
    w->best = PB_NO_HIT;
    w->u = w->v = 0.f;
    w->node = w->group = w->sp = 0; /* the root, no group pending */
    w->run = 0;
}

void pb_bvh_walk_step(pb_bvh_walk *w, const pb_bvh *bvh)
{
    const pb_bvh4_node *nd = &bvh->wide_nodes[w->node];
    float *d = w->d;
    uint32_t *ch = w->ch, *cnt = w->cnt;
    uint32_t used = pb_bvh4_slots(nd, ch, cnt);
    float scale[3] = {pb_bvh4_scale(nd->exponent[0]), pb_bvh4_scale(nd->exponent[1]), pb_bvh4_scale(nd->exponent[2])};
    pb_ray_node_boxes(&w->r, nd->origin, scale, nd->qbox, used, w->tmin, w->tmax, d);
    /* near to far: leaves are tested in that order, inner children pushed far first */
    PB_SORT2(0, 1);
    PB_SORT2(2, 3);
    PB_SORT2(0, 2);
    PB_SORT2(1, 3);
    PB_SORT2(1, 2);
    /* the hit leaves, near to far, as one run of triangles (one loop in the kernel) */
    w->run = 0;
    for (int s = 0; s < 4; ++s) {
        w->run += cnt[s] != 0 && d[s] < INFINITY && d[s] <= w->tmax ? cnt[s] : 0;
        w->e[s] = w->run;
    }
    w->first = pb_bvh4_first_inner(nd);
}

int pb_bvh_walk_test(pb_bvh_walk *w, const pb_scene *scene, const pb_bvh *bvh, uint32_t i)
{
    const uint32_t *ch = w->ch, *e = w->e;
    uint32_t k = i < e[0] ? ch[0] + i : i < e[1] ? ch[1] + (i - e[0]) : i < e[2] ? ch[2] + (i - e[1]) : ch[3] + (i - e[2]);
    const float *p = bvh->tri_positions + 9 * (size_t)k;
    float t, u, v;
    if (!pb_ray_triangle(&w->r, p, p + 3, p + 6, w->tmin, w->tmax, &t, &u, &v))
        return 0;
    if (!pb_alpha_opaque(scene, bvh->tri_order[k], u, v))
        return 0;
    w->tmax = t, w->best = k, w->u = u, w->v = v;
    return 1;
}

int pb_bvh_walk_next(pb_bvh_walk *w)
{
    /* the hit inner children, near to far, as ranks among the node's inner
     * children (consecutive from `first`): the nearest is next, the rest
     * become the pending group, and the group they replace is pushed */
    uint32_t n = 0, ranks = 0;
    for (int s = 0; s < 4; ++s) {
        if (w->cnt[s] != 0 || !(w->d[s] < INFINITY && w->d[s] <= w->tmax)) /* a miss or unused slot is +inf, tmax may be too */
            continue;
        ranks |= w->ch[s] << (2 * n++);
    }
    if (n != 0) {
        w->node = w->first + (ranks & 3);
        if (n > 1) {
            if (PB_GROUP_COUNT(w->group) != 0)
                w->stack[w->sp++] = w->group;
            w->group = PB_GROUP(w->first, n - 1, ranks >> 2);
        }
        return 1;
    }
    if (PB_GROUP_COUNT(w->group) == 0) {
        if (w->sp == 0)
            return 0;
        w->group = w->stack[--w->sp];
    }
    w->node = (w->group >> 8) + (w->group & 3);
    w->group = PB_GROUP(w->group >> 8, PB_GROUP_COUNT(w->group) - 1, (w->group & 63) >> 2);
    return 1;
}

static void trace_bvh_one(const trace_job *j, const pb_ray *ray, pb_hit *hit)
{
    const pb_bvh *bvh = j->bvh;
    if (bvh->triangle_count == 0) {
        finish_hit(j->scene, ray, PB_NO_HIT, 0.f, 0.f, 0.f, hit);
        return;
    }
    pb_bvh_walk w;
    pb_bvh_walk_start(&w, ray);
    do {
        pb_bvh_walk_step(&w, bvh);
        for (uint32_t i = 0; i < w.run; ++i)
            if (pb_bvh_walk_test(&w, j->scene, bvh, i) && j->mode == PB_TRACE_ANY)
                goto done;
    } while (pb_bvh_walk_next(&w));
done:
    finish_hit(j->scene, ray, w.best == PB_NO_HIT ? PB_NO_HIT : bvh->tri_order[w.best], w.tmax, w.u, w.v, hit);
}

static void trace_bvh_range(void *user, uint64_t b, uint64_t e)
{
    const trace_job *j = user;
    for (uint64_t i = b; i < e; ++i)
        trace_bvh_one(j, &j->rays[i], &j->hits[i]);
}

void pb_trace_cpu(const pb_scene *scene, const pb_bvh *bvh, const pb_ray *rays, uint32_t count, pb_trace_mode mode,
                  pb_hit *hits, uint32_t threads)
{
    trace_job j = {scene, bvh, rays, hits, mode};
    pb_parallel_for(count, 256, threads, trace_bvh_range, &j);
}

/* Brute force: every triangle against every ray, through pb_ray_triangle,
 * in index order (the lowest index wins a tie, as nothing else decides).
 * A block of triangles is first screened in the ray's sheared frame
 * (pb_ray_triangle's Ax, Ay, ...: the same float operations, so the same
 * bits): where all three vertices lie strictly on one side of the ray in x
 * or in y, the ray's point is outside the triangle, the edge functions'
 * exact signs are mixed and pb_ray_triangle would return 0, so it is not
 * called. The screen reads the triangles as nine arrays (vertex, axis),
 * which vectorize; without them (out of memory) every triangle is tested. */
typedef struct brute_job {
    trace_job t;
    const float *soa; /* 9 arrays of triangle_count floats: vertex v's axis a at (3 v + a) n, or NULL */
} brute_job;

#define BRUTE_BLOCK 256

static void brute_range(void *user, uint64_t b, uint64_t e)
{
    const brute_job *bj = user;
    const trace_job *j = &bj->t;
    const pb_scene *s = j->scene;
    const uint32_t n = s->triangle_count;
    uint8_t keep[BRUTE_BLOCK];
    for (uint64_t i = b; i < e; ++i) {
        const pb_ray *ray = &j->rays[i];
        pb_ray_pre r;
        pb_ray_prepare(ray->origin, ray->direction, &r);
        float tmax = ray->tmax, bu = 0.f, bv = 0.f;
        uint32_t best = PB_NO_HIT;
        const float *q[9] = {NULL};
        if (bj->soa)
            for (int v = 0; v < 3; ++v) {
                q[3 * v] = bj->soa + (size_t)(3 * v + r.kx) * n;
                q[3 * v + 1] = bj->soa + (size_t)(3 * v + r.ky) * n;
                q[3 * v + 2] = bj->soa + (size_t)(3 * v + r.kz) * n;
            }
        const float ox = r.org[r.kx], oy = r.org[r.ky], oz = r.org[r.kz], sx = r.sx, sy = r.sy;
        int done = 0;
        for (uint32_t k0 = 0; k0 < n && !done; k0 += BRUTE_BLOCK) {
            uint32_t m = n - k0 < BRUTE_BLOCK ? n - k0 : BRUTE_BLOCK;
            if (bj->soa) {
                const float *X0 = q[0] + k0, *Y0 = q[1] + k0, *Z0 = q[2] + k0, *X1 = q[3] + k0, *Y1 = q[4] + k0,
                            *Z1 = q[5] + k0, *X2 = q[6] + k0, *Y2 = q[7] + k0, *Z2 = q[8] + k0;
                for (uint32_t k = 0; k < m; ++k) {
                    float az = Z0[k] - oz, bz = Z1[k] - oz, cz = Z2[k] - oz;
                    float ax = (X0[k] - ox) - sx * az, bx = (X1[k] - ox) - sx * bz, cx = (X2[k] - ox) - sx * cz;
                    float ay = (Y0[k] - oy) - sy * az, by = (Y1[k] - oy) - sy * bz, cy = (Y2[k] - oy) - sy * cz;
                    int out = (ax < 0.f) & (bx < 0.f) & (cx < 0.f);
                    out |= (ax > 0.f) & (bx > 0.f) & (cx > 0.f);
                    out |= (ay < 0.f) & (by < 0.f) & (cy < 0.f);
                    out |= (ay > 0.f) & (by > 0.f) & (cy > 0.f);
                    keep[k] = (uint8_t)!out;
                }
            } else {
                memset(keep, 1, m);
            }
            for (uint32_t k = 0; k < m; ++k) {
                if (!keep[k])
                    continue;
                const float *p = s->positions + 9 * (size_t)(k0 + k);
                float t, u, v;
                if (!pb_ray_triangle(&r, p, p + 3, p + 6, ray->tmin, tmax, &t, &u, &v))
                    continue;
                if (!pb_alpha_opaque(s, k0 + k, u, v))
                    continue;
                tmax = t, best = k0 + k, bu = u, bv = v;
                if (j->mode == PB_TRACE_ANY) {
                    done = 1;
                    break;
                }
            }
        }
        finish_hit(s, ray, best, tmax, bu, bv, &j->hits[i]);
    }
}

void pb_trace_brute(const pb_scene *scene, const pb_ray *rays, uint32_t count, pb_trace_mode mode, pb_hit *hits,
                    uint32_t threads)
{
    size_t n = scene->triangle_count;
    float *soa = n ? malloc(9 * n * sizeof *soa) : NULL;
    for (size_t k = 0; soa && k < n; ++k)
        for (int c = 0; c < 9; ++c)
            soa[(size_t)c * n + k] = scene->positions[9 * k + (size_t)c];
    brute_job j = {{scene, NULL, rays, hits, mode}, soa};
    pb_parallel_for(count, 64, threads, brute_range, &j);
    free(soa);
}
