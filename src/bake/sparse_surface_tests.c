#include "bake/sparse_surface_tests.h"

#include "common/common.h"
#include "probebake/trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Closest point to p on triangle (a, b, c), by the Voronoi regions of its
 * vertices and edges (Ericson, Real-Time Collision Detection, 5.1.5). */
static void closest_on_triangle(const double p[3], const double a[3], const double b[3], const double c[3],
                                double q[3])
{
    double ab[3], ac[3], ap[3];
    for (int k = 0; k < 3; ++k)
        ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k];
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
    double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        memcpy(q, a, 3 * sizeof *q);
        return;
    }
    double bp[3], cp[3];
    for (int k = 0; k < 3; ++k)
        bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
    double d3 = DOT(ab, bp), d4 = DOT(ac, bp), d5 = DOT(ab, cp), d6 = DOT(ac, cp);
#undef DOT
    double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    double s = 0, t = 0; /* q = a + s ab + t ac */
    if (d3 >= 0 && d4 <= d3)
        s = 1;
    else if (d6 >= 0 && d5 <= d6)
        t = 1;
    else if (vc <= 0 && d1 >= 0 && d3 <= 0)
        s = d1 / (d1 - d3);
    else if (vb <= 0 && d2 >= 0 && d6 <= 0)
        t = d2 / (d2 - d6);
    else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        s = 1 - w, t = w;
    } else {
        double den = 1 / (va + vb + vc);
        s = vb * den, t = vc * den;
    }
    for (int k = 0; k < 3; ++k)
        q[k] = a[k] + s * ab[k] + t * ac[k];
}

static uint32_t normal_bucket(const double n[3])
{
    double a[3] = {fabs(n[0]), fabs(n[1]), fabs(n[2])};
    uint32_t k = a[0] >= a[1] && a[0] >= a[2] ? 0u : (a[1] >= a[2] ? 1u : 2u);
    return 2u * k + (n[k] < 0);
}

static int emissive(const pb_scene *s, uint32_t tri)
{
    const pb_material *m = &s->materials[s->material[tri]];
    return m->emissive[0] > 0.f || m->emissive[1] > 0.f || m->emissive[2] > 0.f;
}

typedef struct best_point {
    double d2;          /* squared distance to the sub-cell's centre; INFINITY: none */
    float x[3], n[3];
} best_point;

/* One cell being queried: its box (the first sub-cell of an axis reaches
 * down by the margin), sub-cells per axis and the best point per sub-cell
 * and normal axis (sub^3 * 6). */
typedef struct cell_query_box {
    double lo[3], hi[3];    /* the cell, margins included */
    double cut_lo[3];       /* the cell's corner without the margin: sub-cell i starts at cut_lo + i * sub_size */
    double sub_size[3];
    uint32_t sub;
    best_point *best;
} cell_query_box;

/* The point of triangle (a, b, c) nearest the centre of sub-cell box
 * [lo, hi], if it lies inside, into its slot. */
static void consider_sub(const pb_scene *s, uint32_t tri, const double a[3], const double b[3], const double c[3],
                         const double n_unit[3], const double lo[3], const double hi[3], best_point best[6])
{
    double centre[3], q[3], d2 = 0, facing = 0, n[3];
    for (int k = 0; k < 3; ++k)
        centre[k] = 0.5 * (lo[k] + hi[k]);
    closest_on_triangle(centre, a, b, c, q);
    for (int k = 0; k < 3; ++k) {
        if (q[k] < lo[k] || q[k] > hi[k])
            return;
        d2 += (q[k] - centre[k]) * (q[k] - centre[k]);
        facing += n_unit[k] * (centre[k] - q[k]);
    }
    /* a double-sided surface is lit on the side facing the centre; a one-sided one on its front */
    double side = s->materials[s->material[tri]].double_sided && facing < 0 ? -1.0 : 1.0;
    for (int k = 0; k < 3; ++k)
        n[k] = side * n_unit[k];
    best_point *e = &best[normal_bucket(n)];
    if (!(d2 < e->d2))
        return;
    e->d2 = d2;
    float qf[3] = {(float)q[0], (float)q[1], (float)q[2]};
    for (int k = 0; k < 3; ++k)
        e->n[k] = (float)n[k];
    pb_offset_ray_origin(qf, e->n, e->x);
}

/* Leaf triangle t against the cell's sub-cells its box overlaps. */
static void consider(const pb_scene *s, const pb_bvh *bvh, uint32_t t, const cell_query_box *cq)
{
    uint32_t tri = bvh->tri_order[t];
    if (emissive(s, tri))
        return;
    const float *v = bvh->tri_positions + 9 * (size_t)t;
    double a[3], b[3], c[3], n[3], e1[3], e2[3];
    uint32_t first[3], last[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = v[k], b[k] = v[3 + k], c[k] = v[6 + k];
        e1[k] = b[k] - a[k], e2[k] = c[k] - a[k];
        double tlo = fmax(fmin(a[k], fmin(b[k], c[k])), cq->lo[k]), thi = fmin(fmax(a[k], fmax(b[k], c[k])), cq->hi[k]);
        if (tlo > thi)
            return;
        double f = floor((tlo - cq->cut_lo[k]) / cq->sub_size[k]), l = floor((thi - cq->cut_lo[k]) / cq->sub_size[k]);
        first[k] = f < 0 ? 0u : (f >= cq->sub ? cq->sub - 1 : (uint32_t)f);
        last[k] = l < 0 ? 0u : (l >= cq->sub ? cq->sub - 1 : (uint32_t)l);
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nl > 0))
        return;
    for (int k = 0; k < 3; ++k)
        n[k] /= nl;
    for (uint32_t z = first[2]; z <= last[2]; ++z)
        for (uint32_t y = first[1]; y <= last[1]; ++y)
            for (uint32_t x = first[0]; x <= last[0]; ++x) {
                uint32_t i3[3] = {x, y, z};
                double lo[3], hi[3];
                for (int k = 0; k < 3; ++k) {
                    lo[k] = i3[k] == 0 ? cq->lo[k] : cq->cut_lo[k] + i3[k] * cq->sub_size[k];
                    hi[k] = i3[k] + 1 == cq->sub ? cq->hi[k] : cq->cut_lo[k] + (i3[k] + 1) * cq->sub_size[k];
                }
                consider_sub(s, tri, a, b, c, n, lo, hi, cq->best + 6 * (x + cq->sub * (y + cq->sub * z)));
            }
}

/* Every leaf triangle whose box overlaps the cell (the BVH's child-pair form). */
static void cell_query(const pb_scene *s, const pb_bvh *bvh, const cell_query_box *cq)
{
    uint32_t stack[2 * PB_BVH_MAX_DEPTH + 2], sp = 0;
    if (bvh->node_count == 0)
        return;
    stack[sp++] = 0;
    while (sp) {
        const pb_bvh_node *nd = &bvh->nodes[stack[--sp]];
        for (int slot = 0; slot < 2; ++slot) {
            if (nd->child[slot] < 0)
                continue;
            const float *bx[3] = {nd->lo_hi_x, nd->lo_hi_y, nd->lo_hi_z};
            int overlap = 1;
            for (int k = 0; k < 3; ++k)
                overlap &= bx[k][2 * slot] <= cq->hi[k] && bx[k][2 * slot + 1] >= cq->lo[k];
            if (!overlap)
                continue;
            if (nd->count[slot]) {
                for (uint32_t t = 0; t < nd->count[slot]; ++t)
                    consider(s, bvh, (uint32_t)nd->child[slot] + t, cq);
            } else {
                stack[sp++] = (uint32_t)nd->child[slot];
            }
        }
    }
}

pb_result pb_cell_surface_tests(const pb_scene *s, const pb_bvh *bvh, const pb_cell_test_desc *d, const uint32_t *cells,
                                uint32_t cell_count, pb_cell_tests *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (cell_count == 0)
        return PB_OK;
    if (d->sub < 1 || d->sub > PB_CELL_TESTS_SUB_MAX)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "surface tests: %u sub-cells per axis (1 to %u)", d->sub,
                       PB_CELL_TESTS_SUB_MAX);
    uint32_t slots = d->sub * d->sub * d->sub * 6;
    size_t most = (size_t)cell_count * slots;
    out->x = malloc(most * 3 * sizeof *out->x);
    out->n = malloc(most * 3 * sizeof *out->n);
    out->cell = malloc(most * sizeof *out->cell);
    out->slot = malloc(most * sizeof *out->slot);
    best_point *best = malloc(slots * sizeof *best);
    if (!out->x || !out->n || !out->cell || !out->slot || !best) {
        free(best);
        pb_cell_tests_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u refinement cells", cell_count);
    }
    for (uint32_t c = 0; c < cell_count; ++c) {
        cell_query_box cq = {.sub = d->sub, .best = best};
        for (int k = 0; k < 3; ++k) {
            uint32_t ck = cells[3 * (size_t)c + k];
            cq.cut_lo[k] = d->origin[k] + (double)ck * d->size[k];
            cq.lo[k] = cq.cut_lo[k] - (ck == 0 ? d->margin[k] : 0.0);
            cq.hi[k] = cq.cut_lo[k] + d->size[k];
            cq.sub_size[k] = d->size[k] / d->sub;
        }
        for (uint32_t b = 0; b < slots; ++b)
            best[b].d2 = INFINITY;
        cell_query(s, bvh, &cq);
        for (uint32_t b = 0; b < slots; ++b) {
            if (!isfinite(best[b].d2))
                continue;
            uint32_t t = out->count++;
            memcpy(out->x + 3 * (size_t)t, best[b].x, sizeof best[b].x);
            memcpy(out->n + 3 * (size_t)t, best[b].n, sizeof best[b].n);
            out->cell[t] = c;
            out->slot[t] = b;
        }
    }
    free(best);
    return PB_OK;
}

void pb_cell_tests_free(pb_cell_tests *t)
{
    free(t->x), free(t->n), free(t->cell), free(t->slot);
    memset(t, 0, sizeof *t);
}
