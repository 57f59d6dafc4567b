/* The view `render` takes of a scene that has no camera and was given no
 * --eye (probebake/render.h, pb_camera_default). An object or a terrain is
 * best seen from in front of its bounds, above; a level or a room is not:
 * from outside only the backs of its single-sided walls show, and those
 * render black (every OpenArena map gave a black image). So each candidate
 * view is scored by a small grid of CPU rays: the view from outside stands
 * where it sees more fronts of surfaces than backs, else the view from
 * inside the bounds that sees the most of them. */
#include "common/vec3.h"
#include "probebake/render.h"
#include "render/render_types.h"
#include "probebake/trace.h"

#include <math.h>
#include <string.h>

enum {
    GRID_X = 8, GRID_Y = 6,   /* rays per candidate view */
    INSIDE_X = 5, INSIDE_Y = 3, INSIDE_Z = 5 /* eyes inside the bounds, at cell centres */
};

/* v scaled to unit length */
static void unit(float v[3])
{
    float l = pb_length3(v);
    for (int k = 0; k < 3; ++k)
        v[k] /= l;
}

/* What view v sees, over a GRID_X x GRID_Y grid of rays across its frustum:
 * *front the mean of min(t, reach) / reach over rays that meet a surface's
 * front (or a double-sided surface; near fronts count less than far ones,
 * so an eye against a wall loses to one that looks across a room), *back
 * the share of rays that meet the back of a single-sided surface (a wall
 * seen from behind, or an eye inside a solid), *seen the number of
 * different triangles whose fronts they meet. Misses count for none. */
static void view_score(const pb_scene *s, const pb_bvh *bvh, const pb_camera_view *v, uint32_t width, uint32_t height,
                       float reach, double *front, double *back, uint32_t *seen)
{
    float f[3], r[3], u[3]; /* the renderer's own basis: r and u span the image's half-width and half-height */
    pb_render_camera_basis(v, width, height, f, r, u);
    pb_ray rays[GRID_X * GRID_Y];
    pb_hit hits[GRID_X * GRID_Y];
    for (int j = 0; j < GRID_Y; ++j)
        for (int i = 0; i < GRID_X; ++i) {
            float sx = 2.f * (i + 0.5f) / GRID_X - 1.f, sy = 1.f - 2.f * (j + 0.5f) / GRID_Y;
            pb_ray *ray = &rays[j * GRID_X + i];
            for (int k = 0; k < 3; ++k) {
                ray->origin[k] = v->eye[k];
                ray->direction[k] = f[k] + sx * r[k] + sy * u[k];
            }
            unit(ray->direction);
            ray->tmin = 0.f;
            ray->tmax = INFINITY;
        }
    pb_trace_cpu(s, bvh, rays, GRID_X * GRID_Y, PB_TRACE_CLOSEST, hits, 1);
    double fsum = 0.0, bsum = 0.0;
    uint32_t fronts[GRID_X * GRID_Y], nf = 0;
    for (int n = 0; n < GRID_X * GRID_Y; ++n) {
        if (hits[n].triangle == PB_NO_HIT)
            continue;
        if (hits[n].backface && !s->materials[s->material[hits[n].triangle]].double_sided) {
            bsum += 1.0;
            continue;
        }
        fsum += fmin(hits[n].t, reach) / reach;
        uint32_t i = 0;
        while (i < nf && fronts[i] != hits[n].triangle)
            ++i;
        if (i == nf)
            fronts[nf++] = hits[n].triangle;
    }
    *seen = nf;
    *front = fsum / (GRID_X * GRID_Y);
    *back = bsum / (GRID_X * GRID_Y);
}

void pb_camera_default(const pb_scene *s, const pb_bvh *bvh, float yfov, uint32_t width, uint32_t height,
                       pb_camera_view *out)
{
    float c[3], ext = 0.f;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5f * (s->bounds_min[k] + s->bounds_max[k]);
        ext = fmaxf(ext, s->bounds_max[k] - s->bounds_min[k]);
    }
    if (!(ext > 0.f)) /* an empty scene, or a point: a view of the sky */
        ext = 1.f;
    /* from the front, above, looking at the centre */
    pb_camera_view outside = {{c[0], c[1] + 0.3f * ext, c[2] + 1.2f * ext}, {0, 0, 0}, {0, 1, 0}, yfov};
    for (int k = 0; k < 3; ++k)
        outside.forward[k] = c[k] - outside.eye[k];
    *out = outside;
    if (!bvh || s->triangle_count == 0)
        return;
    float reach = 0.25f * ext;
    double front, back;
    uint32_t seen;
    view_score(s, bvh, &outside, width, height, reach, &front, &back, &seen);
    if (front > 0.0 && front >= back)
        return; /* it sees the scene's surfaces from their front */
    /* from inside: eyes on a lattice of the bounds, each looking along the
     * four horizontal axes, a little down; the best sees the most fronts (far
     * ones first) less backs, times log2(1 + the triangles it sees): a view
     * of one large wall (a skybox's) shows less of a level than one across
     * its rooms */
    static const float look[4][3] = {{0, -0.2f, -1}, {1, -0.2f, 0}, {0, -0.2f, 1}, {-1, -0.2f, 0}};
    const int steps[3] = {INSIDE_X, INSIDE_Y, INSIDE_Z};
    double best = (front - back) * log2(1.0 + seen);
    for (int z = 0; z < INSIDE_Z; ++z)
        for (int y = 0; y < INSIDE_Y; ++y)
            for (int x = 0; x < INSIDE_X; ++x)
                for (int d = 0; d < 4; ++d) {
                    const int at[3] = {x, y, z};
                    pb_camera_view v = {{0, 0, 0}, {look[d][0], look[d][1], look[d][2]}, {0, 1, 0}, yfov};
                    for (int k = 0; k < 3; ++k)
                        v.eye[k] = s->bounds_min[k] + (s->bounds_max[k] - s->bounds_min[k]) * (at[k] + 0.5f) / steps[k];
                    view_score(s, bvh, &v, width, height, reach, &front, &back, &seen);
                    double score = (front - back) * log2(1.0 + seen);
                    if (score > best)
                        best = score, *out = v;
                }
}
