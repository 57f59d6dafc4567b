/* A fair image metric for probe-lit renders (issue 14): the error over the
 * non-emissive surfaces, where probes are what lights the picture, with
 * the pixels an emitter rules left out (render.h). */
#include "common/common.h"
#include "probebake/render.h"
#include "probebake/sample.h"
#include "probebake/sparse.h"
#include "probebake/trace.h"
#include "render/render_types.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The kernel's pixel-centre rays (1 spp) of d's camera. */
static void pixel_rays(const pb_render_desc *d, pb_ray *rays)
{
    float fwd[3], right[3], up[3];
    pb_render_camera_basis(&d->camera, d->width, d->height, fwd, right, up);
    for (uint32_t py = 0; py < d->height; ++py)
        for (uint32_t px = 0; px < d->width; ++px) { /* the kernel's pixel centre (1 spp) */
            float sx = ((float)px + 0.5f) / (float)d->width * 2.f - 1.f;
            float sy = 1.f - ((float)py + 0.5f) / (float)d->height * 2.f;
            pb_ray *r = &rays[(uint64_t)py * d->width + px];
            memcpy(r->origin, d->camera.eye, 12);
            for (int k = 0; k < 3; ++k)
                r->direction[k] = fwd[k] + sx * right[k] + sy * up[k];
            r->tmin = 0.f, r->tmax = INFINITY;
        }
}

void pb_render_pixel_classes(const pb_scene *s, const pb_bvh *bvh, const pb_render_desc *d, uint8_t *cls)
{
    uint64_t n = (uint64_t)d->width * d->height;
    pb_ray *rays = malloc(n * sizeof *rays);
    pb_hit *hits = malloc(n * sizeof *hits);
    if (!rays || !hits) {
        memset(cls, PB_PIXEL_NONE, n);
        free(rays), free(hits);
        return;
    }
    pixel_rays(d, rays);
    pb_trace_cpu(s, bvh, rays, (uint32_t)n, PB_TRACE_CLOSEST, hits, 0);
    for (uint64_t i = 0; i < n; ++i) {
        cls[i] = PB_PIXEL_NONE;
        if (hits[i].triangle == PB_NO_HIT)
            continue;
        const pb_material *m = &s->materials[s->material[hits[i].triangle]];
        if (hits[i].backface && !m->double_sided)
            continue;
        cls[i] = m->emissive[0] > 0.f || m->emissive[1] > 0.f || m->emissive[2] > 0.f ? PB_PIXEL_EMITTER
                                                                                     : PB_PIXEL_SURFACE;
    }
    free(rays), free(hits);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void pb_image_surface_metrics(const float *a, const float *b, const uint8_t *cls, uint32_t w, uint32_t h,
                              pb_image_metrics *out)
{
    pb_image_surface_metrics_where(a, b, cls, NULL, 0, w, h, out);
}

void pb_image_surface_metrics_where(const float *a, const float *b, const uint8_t *cls, const uint8_t *mask,
                                    uint8_t want, uint32_t w, uint32_t h, pb_image_metrics *out)
{
    memset(out, 0, sizeof *out);
    uint64_t n = (uint64_t)w * h;
    uint8_t *use = calloc(n, 1);
    double *rel = malloc(n * sizeof *rel);
    if (!use || !rel) {
        free(use), free(rel);
        return;
    }
    double se = 0, sum = 0;
    uint64_t count = 0;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            uint64_t i = (uint64_t)y * w + x;
            if (cls[i] != PB_PIXEL_SURFACE || (mask && mask[i] != want))
                continue;
            int near_emitter = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int64_t xx = (int64_t)x + dx, yy = (int64_t)y + dy;
                    if (xx >= 0 && yy >= 0 && xx < w && yy < h && cls[(uint64_t)yy * w + (uint64_t)xx] == PB_PIXEL_EMITTER)
                        near_emitter = 1;
                }
            if (near_emitter)
                continue;
            use[i] = 1;
            double d = (double)pb_luminance(a + 4 * i) - pb_luminance(b + 4 * i);
            se += d * d, sum += pb_luminance(b + 4 * i), ++count;
        }
    if (count && sum > 0) {
        double mean = sum / count, floor_ = 0.01 * mean;
        uint64_t k = 0;
        for (uint64_t i = 0; i < n; ++i)
            if (use[i]) {
                double lb = pb_luminance(b + 4 * i);
                rel[k++] = fabs((double)pb_luminance(a + 4 * i) - lb) / fmax(lb, floor_);
            }
        qsort(rel, k, sizeof *rel, cmp_double);
        out->relative_rmse = sqrt(se / count) / mean;
        out->p95_relative = rel[(uint64_t)((k - 1) * 0.95 + 0.5)];
        out->pixels = count;
    }
    free(use), free(rel);
}

/* The level of the brick serving frame point q, or -1 (none). */
static int level_at(const pb_sample_volume *sv, const pb_sparse_layout *l, const double q[3])
{
    double span = sv->levels == 1 ? 3.0 : (sv->levels == 2 ? 9.0 : 27.0);
    float u[3];
    for (int k = 0; k < 3; ++k)
        u[k] = (float)((q[k] - sv->origin[k]) / (sv->spacing[k] * span));
    uint32_t b = pb_sparse_find(l, u);
    return b == PB_SPARSE_EMPTY ? -1 : (int)l->bricks[b].level;
}

void pb_render_seam_pixels(const pb_scene *s, const pb_bvh *bvh, const pb_render_desc *d, const pb_sample_volume *sv,
                           const pb_sparse_layout *l, const uint8_t *cls, uint8_t *seam, uint8_t *level)
{
    uint64_t n = (uint64_t)d->width * d->height;
    memset(seam, PB_SEAM_NONE, n);
    if (level)
        memset(level, PB_LEVEL_NONE, n);
    pb_ray *rays = malloc(n * sizeof *rays);
    pb_hit *hits = malloc(n * sizeof *hits);
    if (!rays || !hits || !sv->levels) {
        free(rays), free(hits);
        return;
    }
    pixel_rays(d, rays);
    pb_trace_cpu(s, bvh, rays, (uint32_t)n, PB_TRACE_CLOSEST, hits, 0);
    double finest = fmin(sv->spacing[0], fmin(sv->spacing[1], sv->spacing[2]));
    for (uint64_t i = 0; i < n; ++i) {
        if (cls[i] != PB_PIXEL_SURFACE || hits[i].triangle == PB_NO_HIT)
            continue;
        const float *v0 = s->positions + 9 * (size_t)hits[i].triangle, *v1 = v0 + 3, *v2 = v0 + 6;
        double e1[3], e2[3], ng[3], dir[3], len = 0, dl = 0;
        for (int k = 0; k < 3; ++k)
            e1[k] = (double)v1[k] - v0[k], e2[k] = (double)v2[k] - v0[k], dir[k] = rays[i].direction[k];
        ng[0] = e1[1] * e2[2] - e1[2] * e2[1], ng[1] = e1[2] * e2[0] - e1[0] * e2[2], ng[2] = e1[0] * e2[1] - e1[1] * e2[0];
        for (int k = 0; k < 3; ++k)
            len += ng[k] * ng[k], dl += dir[k] * dir[k];
        len = sqrt(len), dl = sqrt(dl);
        double facing = ng[0] * dir[0] + ng[1] * dir[1] + ng[2] * dir[2] > 0 ? -1.0 : 1.0;
        double q[3]; /* the biased point the sampler looks its brick up at (pb_sample_sparse) */
        for (int k = 0; k < 3; ++k) {
            double x = rays[i].origin[k] + (double)hits[i].t * dir[k];
            q[k] = x + (facing * ng[k] / len * sv->normal_bias - dir[k] / dl * sv->view_bias) * finest;
        }
        int here = level_at(sv, l, q);
        if (here < 0) {
            seam[i] = PB_SEAM_UNSERVED;
            continue;
        }
        if (level)
            level[i] = (uint8_t)here;
        for (int k = 0; k < 3 && seam[i] == PB_SEAM_NONE; ++k)
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                double p2[3] = {q[0], q[1], q[2]};
                p2[k] += sgn * 0.5 * finest;
                int there = level_at(sv, l, p2);
                if (there >= 0 && there != here)
                    seam[i] = PB_SEAM_LEVELS;
            }
    }
    free(rays), free(hits);
}
