/* The bake's bounce rays without the bake (bounce_rays.h). */
#include "bounce_rays.h"
#include "bake/path_cpu.h"
#include "probebake/octahedral.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct keyed_ray {
    uint64_t key;
    pb_ray ray;
} keyed_ray;

static int cmp_keyed(const void *a, const void *b)
{
    uint64_t x = ((const keyed_ray *)a)->key, y = ((const keyed_ray *)b)->key;
    return x < y ? -1 : x > y;
}

static uint32_t spread5(uint32_t v) /* 5 bits to every third bit */
{
    uint32_t r = 0;
    for (int b = 0; b < 5; ++b)
        r |= ((v >> b) & 1u) << (3 * b);
    return r;
}

uint32_t bench_bounce_rays(const pb_scene *s, pb_ray *rays, const pb_hit *hits, uint32_t n, int sorted)
{
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const pb_hit *h = &hits[i];
        if (h->triangle == PB_NO_HIT || h->backface)
            continue;
        const float *p = s->positions + 9 * (size_t)h->triangle;
        float e1[3], e2[3], x[3], ng[3];
        for (int k = 0; k < 3; ++k)
            e1[k] = p[3 + k] - p[k], e2[k] = p[6 + k] - p[k];
        ng[0] = e1[1] * e2[2] - e1[2] * e2[1];
        ng[1] = e1[2] * e2[0] - e1[0] * e2[2];
        ng[2] = e1[0] * e2[1] - e1[1] * e2[0];
        float len = sqrtf(ng[0] * ng[0] + ng[1] * ng[1] + ng[2] * ng[2]);
        if (!(len > 0.f))
            continue;
        float facing = ng[0] * rays[i].direction[0] + ng[1] * rays[i].direction[1] + ng[2] * rays[i].direction[2];
        for (int k = 0; k < 3; ++k) {
            ng[k] /= facing > 0.f ? -len : len;
            x[k] = p[k] + h->u * e1[k] + h->v * e2[k];
        }
        pb_ray out;
        pb_offset_ray_origin(x, ng, out.origin);
        pb_cosine_direction_cpu(ng, pb_random01(7, i, 0, 0), pb_random01(7, i, 1, 0), out.direction);
        out.tmin = 0.f;
        out.tmax = INFINITY;
        rays[m++] = out;
    }
    if (!sorted || !m)
        return m;
    keyed_ray *kr = malloc((size_t)m * sizeof *kr);
    if (!kr) {
        fprintf(stderr, "bench: out of host memory sorting %u bounce rays\n", m);
        exit(1);
    }
    for (uint32_t i = 0; i < m; ++i) {
        const float *o = rays[i].origin;
        float uv[2];
        pb_oct_encode(rays[i].direction, uv);
        uint32_t bx = (uint32_t)fminf(7.f, (uv[0] * 0.5f + 0.5f) * 8.f), by = (uint32_t)fminf(7.f, (uv[1] * 0.5f + 0.5f) * 8.f);
        uint32_t cell = 0;
        for (int k = 0; k < 3; ++k) {
            float ext = s->bounds_max[k] - s->bounds_min[k];
            float f = ext > 0.f ? (o[k] - s->bounds_min[k]) / ext : 0.f;
            uint32_t c = (uint32_t)fminf(31.f, fmaxf(0.f, f * 32.f));
            cell |= spread5(c) << k;
        }
        /* bin: 6 bits, cell: 15 bits, i < 2^28 (trace_bench's limit): ties keep order */
        kr[i].key = ((uint64_t)(by * 8 + bx) << 58) | ((uint64_t)cell << 40) | i;
        kr[i].ray = rays[i];
    }
    qsort(kr, m, sizeof *kr, cmp_keyed);
    for (uint32_t i = 0; i < m; ++i)
        rays[i] = kr[i].ray;
    free(kr);
    return m;
}
