/* CPU reference traversal and brute force. The traversal is the GPU kernel's
 * loop in C (shaders/comp/trace.comp): child-pair nodes, leaves tested as
 * soon as their box is hit, nearer inner child first, far child on a stack
 * that holds at most one entry per level. */
#include "bvh/alpha.h"
#include "bvh/intersect.h"
#include "common/common.h"
#include "probebake/bvh.h"
#include "probebake/trace.h"

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

static void trace_bvh_one(const trace_job *j, const pb_ray *ray, pb_hit *hit)
{
    const pb_bvh *bvh = j->bvh;
    pb_ray_pre r;
    pb_ray_prepare(ray->origin, ray->direction, &r);
    float tmin = ray->tmin, tmax = ray->tmax;
    uint32_t best = PB_NO_HIT;
    float bu = 0.f, bv = 0.f;
    uint32_t stack[PB_BVH_MAX_DEPTH + 1];
    uint32_t sp = 0, node = 0;
    if (bvh->triangle_count == 0) {
        finish_hit(j->scene, ray, PB_NO_HIT, 0.f, 0.f, 0.f, hit);
        return;
    }
    for (;;) {
        const pb_bvh_node *nd = &bvh->nodes[node];
        float d[2];
        for (int s = 0; s < 2; ++s) {
            d[s] = INFINITY;
            if (nd->child[s] == -1)
                continue;
            float lo[3] = {nd->lo_hi_x[2 * s], nd->lo_hi_y[2 * s], nd->lo_hi_z[2 * s]};
            float hi[3] = {nd->lo_hi_x[2 * s + 1], nd->lo_hi_y[2 * s + 1], nd->lo_hi_z[2 * s + 1]};
            d[s] = pb_ray_box(&r, lo, hi, tmin, tmax);
        }
        for (int s = 0; s < 2; ++s) {
            if (nd->count[s] == 0 || !(d[s] < INFINITY && d[s] <= tmax))
                continue;
            uint32_t first = (uint32_t)nd->child[s];
            for (uint32_t k = first; k < first + nd->count[s]; ++k) {
                const float *p = bvh->tri_positions + 9 * (size_t)k;
                float t, u, v;
                if (!pb_ray_triangle(&r, p, p + 3, p + 6, tmin, tmax, &t, &u, &v))
                    continue;
                uint32_t tri = bvh->tri_order[k];
                if (!pb_alpha_opaque(j->scene, tri, u, v))
                    continue;
                tmax = t, best = tri, bu = u, bv = v;
                if (j->mode == PB_TRACE_ANY)
                    goto done;
            }
            d[s] = INFINITY;
        }
        int go0 = nd->count[0] == 0 && d[0] < INFINITY && d[0] <= tmax; /* a miss is +inf, tmax may be too */
        int go1 = nd->count[1] == 0 && d[1] < INFINITY && d[1] <= tmax;
        if (go0 && go1) {
            int near = d[1] < d[0];
            stack[sp++] = (uint32_t)nd->child[1 - near];
            node = (uint32_t)nd->child[near];
        } else if (go0) {
            node = (uint32_t)nd->child[0];
        } else if (go1) {
            node = (uint32_t)nd->child[1];
        } else {
            if (sp == 0)
                break;
            node = stack[--sp];
        }
    }
done:
    finish_hit(j->scene, ray, best, tmax, bu, bv, hit);
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

static void brute_range(void *user, uint64_t b, uint64_t e)
{
    const trace_job *j = user;
    const pb_scene *s = j->scene;
    for (uint64_t i = b; i < e; ++i) {
        const pb_ray *ray = &j->rays[i];
        pb_ray_pre r;
        pb_ray_prepare(ray->origin, ray->direction, &r);
        float tmax = ray->tmax, bu = 0.f, bv = 0.f;
        uint32_t best = PB_NO_HIT;
        for (uint32_t k = 0; k < s->triangle_count; ++k) {
            const float *p = s->positions + 9 * (size_t)k;
            float t, u, v;
            if (!pb_ray_triangle(&r, p, p + 3, p + 6, ray->tmin, tmax, &t, &u, &v))
                continue;
            if (!pb_alpha_opaque(s, k, u, v))
                continue;
            tmax = t, best = k, bu = u, bv = v;
            if (j->mode == PB_TRACE_ANY)
                break;
        }
        finish_hit(s, ray, best, tmax, bu, bv, &j->hits[i]);
    }
}

void pb_trace_brute(const pb_scene *scene, const pb_ray *rays, uint32_t count, pb_trace_mode mode, pb_hit *hits,
                    uint32_t threads)
{
    trace_job j = {scene, NULL, rays, hits, mode};
    pb_parallel_for(count, 64, threads, brute_range, &j);
}
