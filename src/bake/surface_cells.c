/* Surface points and the cell grid (surface_cells.h). */
#include "bake/surface_cells.h"
#include "bake/alias.h"
#include "bake/path_cpu.h"
#include "common/common.h"
#include "probebake/trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double pb_triangle_area(const float *v)
{
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k)
        e1[k] = (double)v[3 + k] - v[k], e2[k] = (double)v[6 + k] - v[k];
    double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2], cz = e1[0] * e2[1] - e1[1] * e2[0];
    return 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
}

void pb_cell_grid_fit(const pb_scene *s, double area_total, double per_cell, uint32_t points, pb_cell_grid *g)
{
    float ext = 0.f;
    for (int k = 0; k < 3; ++k)
        ext = fmaxf(ext, s->bounds_max[k] - s->bounds_min[k]);
    ext = fmaxf(ext, 1e-6f);
    float cell = points ? (float)sqrt(per_cell * area_total / points) : ext;
    pb_cell_grid_set(s, fminf(fmaxf(cell, ext / 64.f), ext / 2.f), g);
}

void pb_cell_grid_set(const pb_scene *s, float cell, pb_cell_grid *g)
{
    g->inv_cell = 1.f / cell;
    for (int k = 0; k < 3; ++k) {
        g->origin[k] = s->bounds_min[k];
        float n = ceilf((s->bounds_max[k] - s->bounds_min[k]) * g->inv_cell);
        g->dims[k] = n < 1.f ? 1u : (n > 64.f ? 64u : (uint32_t)n);
    }
}

uint32_t pb_cell_grid_cells(const pb_cell_grid *g)
{
    return g->dims[0] * g->dims[1] * g->dims[2];
}

uint32_t pb_cell_grid_index(const pb_cell_grid *g, const float x[3])
{
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
        float f = floorf((x[k] - g->origin[k]) * g->inv_cell);
        c[k] = f < 0.f ? 0u : (f >= (float)g->dims[k] ? g->dims[k] - 1u : (uint32_t)f);
    }
    return (c[2] * g->dims[1] + c[1]) * g->dims[0] + c[0];
}

typedef struct triangle_areas {
    const pb_scene *s;
    double *area;
} triangle_areas;

static void areas_range(void *user, uint64_t begin, uint64_t end)
{
    const triangle_areas *ta = user;
    for (uint64_t t = begin; t < end; ++t)
        ta->area[t] = pb_triangle_area(ta->s->positions + 9 * t);
}

int pb_surface_sampler_init(const pb_scene *s, pb_surface_sampler *out)
{
    memset(out, 0, sizeof *out);
    uint32_t n = s->triangle_count ? s->triangle_count : 1;
    double *area = pb_malloc_large(n * sizeof *area); /* per triangle: huge pages where large */
    out->keep = pb_malloc_large(n * sizeof *out->keep);
    out->alias = pb_malloc_large(n * sizeof *out->alias);
    if (!area || !out->keep || !out->alias) {
        free(area);
        pb_surface_sampler_free(out);
        return 0;
    }
    triangle_areas ta = {s, area};
    pb_parallel_for(s->triangle_count, 1u << 16, 0, areas_range, &ta);
    for (uint32_t t = 0; t < s->triangle_count; ++t) /* in order: the same total on any number of threads */
        out->area_total += area[t];
    int built = s->triangle_count ? pb_alias_build(area, s->triangle_count, out->keep, out->alias) : 0;
    free(area);
    if (built < 0) {
        pb_surface_sampler_free(out);
        return 0;
    }
    if (!built) { /* no area at all: a table that draws each triangle, none of which gives a point */
        out->area_total = 0.0;
        for (uint32_t t = 0; t < n; ++t)
            out->keep[t] = 1.f, out->alias[t] = t;
    }
    return 1;
}

void pb_surface_sampler_free(pb_surface_sampler *ss)
{
    free(ss->keep), free(ss->alias);
    memset(ss, 0, sizeof *ss);
}

int pb_surface_point(const pb_scene *s, const pb_surface_sampler *ss, uint32_t *state, float x[3], float n[3])
{
    float u0 = pb_rng_next_cpu(state), u1 = pb_rng_next_cpu(state), u2 = pb_rng_next_cpu(state);
    uint32_t tri = pb_alias_sample(ss->keep, ss->alias, s->triangle_count, u0);
    const float *v0 = s->positions + 9 * (size_t)tri, *v1 = v0 + 3, *v2 = v0 + 6;
    float su = sqrtf(u1), b1 = su * (1.f - u2), b2 = su * u2, e1[3], e2[3], p[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = v1[k] - v0[k], e2[k] = v2[k] - v0[k];
        p[k] = v0[k] + b1 * e1[k] + b2 * e2[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    float nl = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nl > 0.f))
        return 0;
    float flip = s->materials[s->material[tri]].double_sided && pb_rng_next_cpu(state) < 0.5f ? -1.f : 1.f;
    for (int k = 0; k < 3; ++k)
        n[k] *= flip / nl;
    pb_offset_ray_origin(p, n, x);
    return 1;
}
