/* C reference of shaders/include/probe_sample_core.glsl, step for step (the
 * same float operations in the same order, so results agree to rounding of
 * sqrt and the fused multiply-adds a driver may form). */
#include "common/common.h"
#include "probebake/sample.h"
#include "probebake/sh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Everything but the SH and depth arrays: the checks, the frame, the
 * relocated positions with their flags and the sparse layout. */
static pb_result sample_volume_frame(const pb_volume *v, const double frame_origin[3], float normal_bias,
                                     float view_bias, pb_sample_volume *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (v->flags & PB_VOLUME_SHARD)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "the volume is part %u of %u of a sharded bake: probebake merge joins the parts first",
                       v->shard.index, v->shard.count);
    int sparse = (v->flags & PB_VOLUME_SPARSE) && v->sparse;
    if (!(v->flags & PB_VOLUME_GRID) && !sparse)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "the volume is a point set: run-time sampling interpolates in a grid");
    uint32_t P = v->probe_count;
    out->probes = malloc((size_t)P * 4 * sizeof(float));
    if (!out->probes)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u probes", P);
    for (int k = 0; k < 3; ++k) {
        out->origin[k] = (float)(v->origin[k] - frame_origin[k]);
        out->spacing[k] = (float)v->spacing[k];
        out->counts[k] = (int32_t)(sparse ? v->sparse->cells[k] : v->counts[k]);
    }
    if (sparse && pb_sparse_layout_words(v->sparse, &out->sparse_words, &out->sparse_word_count) != PB_OK) {
        pb_sample_volume_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse layout");
    }
    out->levels = sparse ? v->sparse->levels : 0;
    out->octmap_res = (int32_t)v->octmap_res;
    out->normal_bias = normal_bias > 0.f ? normal_bias : PB_SAMPLE_NORMAL_BIAS;
    out->view_bias = view_bias > 0.f ? view_bias : PB_SAMPLE_VIEW_BIAS;
    out->depth_unit = v->depth_unit > 0.f ? v->depth_unit : 1.f;
    out->probe_count = P;
    for (uint32_t p = 0; p < P; ++p) {
        double pos[3];
        pb_volume_probe_position(v, p, pos);
        for (int k = 0; k < 3; ++k)
            out->probes[4 * (size_t)p + k] = (float)(pos[k] - frame_origin[k]);
        memcpy(&out->probes[4 * (size_t)p + 3], &v->probe_flags[p], 4);
    }
    return PB_OK;
}

pb_result pb_sample_volume_build(const pb_volume *v, const double frame_origin[3], float normal_bias,
                                 float view_bias, pb_sample_volume *out, pb_error *err)
{
    pb_result r = sample_volume_frame(v, frame_origin, normal_bias, view_bias, out, err);
    if (r != PB_OK)
        return r;
    uint32_t P = v->probe_count, side = v->octmap_res + 2;
    out->sh = malloc((size_t)P * 27 * sizeof(float));
    out->depth = malloc((size_t)P * side * side * sizeof(uint32_t));
    if (!out->sh || !out->depth) {
        pb_sample_volume_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u probes", P);
    }
    memcpy(out->sh, v->sh, (size_t)P * 27 * sizeof(float));
    for (uint64_t t = 0; t < (uint64_t)P * side * side; ++t)
        out->depth[t] = (uint32_t)v->depth[2 * t] | (uint32_t)v->depth[2 * t + 1] << 16;
    return PB_OK;
}

pb_result pb_sample_volume_adopt(pb_volume *v, const double frame_origin[3], float normal_bias, float view_bias,
                                 pb_sample_volume *out, pb_error *err)
{
    pb_result r = sample_volume_frame(v, frame_origin, normal_bias, view_bias, out, err);
    if (r != PB_OK)
        return r;
    /* a texel's two halves, mean first, are the sampler's word with the mean
     * in its low half: the same bytes where the low half comes first */
    uint64_t texels = (uint64_t)v->probe_count * (v->octmap_res + 2) * (v->octmap_res + 2);
    unsigned char *bytes = (unsigned char *)v->depth;
#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
    for (uint64_t t = 0; t < texels; ++t) {
        uint16_t h[2];
        memcpy(h, bytes + 4 * t, 4);
        uint32_t w = (uint32_t)h[0] | (uint32_t)h[1] << 16;
        memcpy(bytes + 4 * t, &w, 4);
    }
#else
    (void)texels;
#endif
    out->sh = v->sh, out->depth = (uint32_t *)(void *)bytes;
    v->sh = NULL, v->depth = NULL;
    return PB_OK;
}

void pb_sample_volume_free(pb_sample_volume *s)
{
    free(s->probes), free(s->sh), free(s->depth), free(s->sparse_words);
    memset(s, 0, sizeof *s);
}

/* x clamped to [lo, hi]; NaN gives lo (the GLSL leaves NaN to the driver;
 * here a NaN from a damaged file must not reach an int conversion) */
static float clampf(float x, float lo, float hi)
{
    return x >= lo ? (x > hi ? hi : x) : lo;
}

static void oct_encode(const float d[3], float uv[2])
{
    float l1 = fabsf(d[0]) + fabsf(d[1]) + fabsf(d[2]);
    float u = d[0] / l1, v = d[1] / l1;
    if (d[2] < 0.f) {
        float su = u >= 0.f ? 1.f : -1.f, sv = v >= 0.f ? 1.f : -1.f;
        float fu = (1.f - fabsf(v)) * su, fv = (1.f - fabsf(u)) * sv;
        u = fu, v = fv;
    }
    uv[0] = u, uv[1] = v;
}

static void depth_at(const pb_sample_volume *s, int probe, int x, int y, float m[2])
{
    int side = s->octmap_res + 2;
    uint32_t t = s->depth[(size_t)side * side * probe + (size_t)side * y + x];
    m[0] = pb_half_to_float((uint16_t)(t & 0xffffu));
    m[1] = pb_half_to_float((uint16_t)(t >> 16));
}

static void depth_moments(const pb_sample_volume *s, int probe, const float dir[3], float m[2])
{
    int n = s->octmap_res;
    float uv[2], f[2], t[2];
    int b[2];
    oct_encode(dir, uv);
    for (int k = 0; k < 2; ++k) {
        f[k] = (uv[k] * 0.5f + 0.5f) * (float)n + 0.5f;
        float i0 = clampf(floorf(f[k]), 0.f, (float)n);
        t[k] = clampf(f[k] - i0, 0.f, 1.f);
        b[k] = (int)i0;
    }
    float m00[2], m10[2], m01[2], m11[2];
    depth_at(s, probe, b[0], b[1], m00);
    depth_at(s, probe, b[0] + 1, b[1], m10);
    depth_at(s, probe, b[0], b[1] + 1, m01);
    depth_at(s, probe, b[0] + 1, b[1] + 1, m11);
    for (int k = 0; k < 2; ++k) {
        /* GLSL mix(x, y, a) = x (1 - a) + y a */
        float a = m00[k] * (1.f - t[0]) + m10[k] * t[0], c = m01[k] * (1.f - t[0]) + m11[k] * t[0];
        m[k] = a * (1.f - t[1]) + c * t[1];
    }
}

static float chebyshev(const float m[2], float r)
{
    if (r <= m[0])
        return 1.f;
    float var = fabsf(m[1] - m[0] * m[0]);
    float d = r - m[0];
    float c = var / (var + d * d);
    return c * c * c;
}

float pb_sample_visibility_cpu(const pb_sample_volume *s, int probe, const float q[3], const float n[3],
                               float detail[3])
{
    const float *pp = s->probes + 4 * (size_t)probe;
    float from[3] = {q[0] - pp[0], q[1] - pp[1], q[2] - pp[2]};
    float r = sqrtf(from[0] * from[0] + from[1] * from[1] + from[2] * from[2]);
    float dir[3] = {r > 0.f ? from[0] / r : n[0], r > 0.f ? from[1] / r : n[1], r > 0.f ? from[2] / r : n[2]};
    float m[2];
    depth_moments(s, probe, dir, m);
    float ru = r / s->depth_unit; /* the moments are in depth units */
    if (detail)
        detail[0] = m[0], detail[1] = m[1], detail[2] = ru;
    return chebyshev(m, ru);
}

/* The grid a cage is taken from: the whole grid, or one 4 x 4 x 4 brick. */
typedef struct cage_grid {
    float origin[3], spacing[3];
    int counts[3];
    int brick; /* -1: a grid volume */
    float normal_bias, view_bias; /* x the cage's smallest spacing */
} cage_grid;

static int cage_probe(const pb_sample_volume *s, const cage_grid *g, const int ijk[3])
{
    int local = ijk[0] + g->counts[0] * (ijk[1] + g->counts[1] * ijk[2]);
    if (g->brick < 0)
        return local;
    return (int)s->sparse_words[s->sparse_words[3] + PB_SPARSE_BRICK_PROBES * (uint32_t)g->brick + (uint32_t)local];
}

/* rgb: the irradiance; probes/weights (may be NULL): the eight cage probes
 * and the normalised weight each got in it. */
static void sample_cage(const pb_sample_volume *s, const cage_grid *g, const float p[3], const float n[3],
                        const float view[3], float rgb[3], int probes[8], float weights[8])
{
    float smin = 1e30f;
    for (int k = 0; k < 3; ++k)
        if (g->counts[k] > 1)
            smin = fminf(smin, g->spacing[k]);
    if (smin >= 1e30f)
        smin = 0.f;
    float biased[3], rel[3], alpha[3];
    int base[3];
    for (int k = 0; k < 3; ++k) {
        biased[k] = p[k] + (n[k] * g->normal_bias + view[k] * g->view_bias) * smin;
        rel[k] = g->counts[k] > 1 ? (biased[k] - g->origin[k]) / g->spacing[k] : 0.f;
        int hi = g->counts[k] - 2 > 0 ? g->counts[k] - 2 : 0;
        base[k] = (int)clampf(floorf(rel[k]), 0.f, (float)hi); /* in float: rel may be huge or NaN */
        alpha[k] = clampf(rel[k] - (float)base[k], 0.f, 1.f);
    }
    float sum[3] = {0, 0, 0}, sum_tri[3] = {0, 0, 0}, wsum = 0.f, wsum_tri = 0.f, wi[8] = {0}, wti[8];
    int pi[8];
    for (int i = 0; i < 8; ++i) {
        int off[3] = {i & 1, (i >> 1) & 1, (i >> 2) & 1}, ijk[3];
        float wt = 1.f;
        for (int k = 0; k < 3; ++k) {
            ijk[k] = base[k] + off[k] < g->counts[k] - 1 ? base[k] + off[k] : g->counts[k] - 1;
            wt *= off[k] ? alpha[k] : 1.f - alpha[k];
        }
        int probe = cage_probe(s, g, ijk);
        pi[i] = probe, wti[i] = wt;
        float e[3];
        pb_sh_eval(s->sh + 27 * (size_t)probe, n, e);
        for (int k = 0; k < 3; ++k)
            sum_tri[k] += wt * e[k];
        wsum_tri += wt;
        uint32_t flags;
        memcpy(&flags, &s->probes[4 * (size_t)probe + 3], 4);
        if (!(flags & PB_PROBE_VALID))
            continue;
        const float *pp = s->probes + 4 * (size_t)probe;
        float to[3] = {pp[0] - p[0], pp[1] - p[1], pp[2] - p[2]};
        float dl = sqrtf(to[0] * to[0] + to[1] * to[1] + to[2] * to[2]);
        float wb = (dl > 0.f ? (to[0] / dl * n[0] + to[1] / dl * n[1] + to[2] / dl * n[2]) : 1.f) * 0.5f + 0.5f;
        float w = wb * wb + 0.2f;
        w *= pb_sample_visibility_cpu(s, probe, biased, n, NULL);
        w = fmaxf(w, 1e-6f);
        if (w < 0.2f)
            w *= w * w * 25.f;
        w *= wt;
        wi[i] = w;
        for (int k = 0; k < 3; ++k)
            sum[k] += w * e[k];
        wsum += w;
    }
    for (int i = 0; probes && i < 8; ++i) {
        probes[i] = pi[i];
        weights[i] = wsum > 0.f ? wi[i] / wsum : (wsum_tri > 0.f ? wti[i] / wsum_tri : 0.f);
    }
    for (int k = 0; k < 3; ++k) {
        float e = wsum > 0.f ? sum[k] / wsum : (wsum_tri > 0.f ? sum_tri[k] / wsum_tri : 0.f);
        rgb[k] = fmaxf(e, 0.f);
    }
}

/* pb_sample_sparse_brick of probe_sample_core.glsl: the brick serving p. */
static int sparse_brick_at(const pb_sample_volume *s, const float u[3], uint32_t *cell)
{
    const uint32_t *w = s->sparse_words;
    float f[3];
    int ci[3];
    for (int k = 0; k < 3; ++k) {
        float c = clampf(floorf(u[k]), 0.f, (float)s->counts[k] - 1.f);
        f[k] = clampf(u[k] - c, 0.f, 1.f);
        ci[k] = (int)c;
    }
    *cell = (uint32_t)(ci[0] + s->counts[0] * (ci[1] + s->counts[1] * ci[2]));
    uint32_t e = w[w[0] + *cell];
    uint32_t d = e >> PB_SPARSE_DEPTH_SHIFT, b = e & PB_SPARSE_EMPTY;
    if (d != 0) {
        int m = d == 1 ? 3 : 9, q[3];
        for (int k = 0; k < 3; ++k) {
            int t = (int)floorf(f[k] * (float)m);
            q[k] = t < 0 ? 0 : (t > m - 1 ? m - 1 : t);
        }
        b = w[w[1] + b + (uint32_t)(q[0] + m * (q[1] + m * q[2]))];
    }
    return b == PB_SPARSE_EMPTY ? -1 : (int)b;
}

int pb_sample_brick_cpu(const pb_sample_volume *s, const float p[3], const float n[3], const float view[3],
                        uint32_t *cell)
{
    *cell = 0;
    if (s->levels == 0)
        return -1;
    int span = s->levels == 1 ? 3 : (s->levels == 2 ? 9 : 27);
    /* the brick is looked up where its cage is interpolated, at the biased
     * point: looked up at p, a point near a brick face would be served by a
     * cage it lies outside of (clamped), a seam across level boundaries */
    float fmin = fminf(s->spacing[0], fminf(s->spacing[1], s->spacing[2])), u[3];
    for (int k = 0; k < 3; ++k) {
        float size = s->spacing[k] * (float)span;
        float pb = p[k] + (n[k] * s->normal_bias + view[k] * s->view_bias) * fmin;
        u[k] = (pb - s->origin[k]) / size;
    }
    return sparse_brick_at(s, u, cell);
}

void pb_sample_cage_cpu(const pb_sample_volume *s, const float p[3], const float n[3], const float view[3],
                        float rgb[3], int probes[8], float weights[8])
{
    cage_grid g = {{s->origin[0], s->origin[1], s->origin[2]},
                   {s->spacing[0], s->spacing[1], s->spacing[2]},
                   {s->counts[0], s->counts[1], s->counts[2]},
                   -1,
                   s->normal_bias,
                   s->view_bias};
    if (probes)
        for (int i = 0; i < 8; ++i)
            probes[i] = -1, weights[i] = 0.f;
    if (s->levels == 0) {
        sample_cage(s, &g, p, n, view, rgb, probes, weights);
        return;
    }
    uint32_t cell;
    int b = pb_sample_brick_cpu(s, p, n, view, &cell), levels = (int)s->levels;
    if (b < 0) {
        rgb[0] = rgb[1] = rgb[2] = 0.f;
        return;
    }
    const uint32_t *br = s->sparse_words + s->sparse_words[2] + 4 * (size_t)b;
    int up = levels - 1 - (int)br[3], step = up == 0 ? 1 : (up == 1 ? 3 : 9);
    for (int k = 0; k < 3; ++k) {
        g.origin[k] = s->origin[k] + (float)(3 * step * (int)br[k]) * s->spacing[k];
        g.spacing[k] = s->spacing[k] * (float)step;
        g.counts[k] = 4;
    }
    g.brick = b;
    /* the bias stays a fraction of the finest spacing: scaled by a coarse
     * brick's it would carry the point through walls (leaks) */
    g.normal_bias = s->normal_bias / (float)step;
    g.view_bias = s->view_bias / (float)step;
    sample_cage(s, &g, p, n, view, rgb, probes, weights);
}

void pb_sample_cpu(const pb_sample_volume *s, const float p[3], const float n[3], const float view[3], float rgb[3])
{
    pb_sample_cage_cpu(s, p, n, view, rgb, NULL, NULL);
}
