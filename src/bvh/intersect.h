/* Ray/box and ray/triangle tests shared by the CPU traversal and brute force.
 * shaders/include/intersect.glsl is the same arithmetic, operation for
 * operation (the GLSL marks it `precise` so no FMA contraction changes it;
 * the C side is built with -ffp-contract=off).
 *
 * Triangle test: watertight (Woop, Benthin & Wald, JCGT 2013). The ray is
 * sheared so it runs along +Z; the 2D edge function of a shared edge depends
 * only on its two sheared vertices, so both triangles see it with opposite
 * signs and no ray slips between neighbours. An edge function of exactly 0
 * counts as inside for both (a hit on the edge, never a gap).
 *
 * Edge functions must have the exact sign: plain float products round a
 * sliver's edge functions to 0 or to the wrong sign and report phantom hits
 * far from the ray (seen on The Crypt). So each a*b - c*d is an adaptive
 * predicate: the float result when its magnitude exceeds its rounding-error
 * bound (then its sign is certain), else the exact value rounded once
 * (exact_diff.h, integer arithmetic: no double, no 64-bit integer on the
 * device). Both paths give the exact sign, so shared edges stay consistent.
 *
 * Box test: the four child boxes of a 4-wide node in the node's frame, with
 * slabs widened by a bound on every rounding (pb_ray_node_boxes), so rounding
 * never culls a box the ray touches.
 *
 * No hit value depends on a division: a Vulkan device may divide with 2.5 ulp
 * of error, and drivers differ (an H100's 1/det moved u and v by an ulp, so
 * the alpha-blend hash of them cut different rays than the CPU did). The
 * shear constants and 1/det come from pb_rcp, integer bit operations and
 * correctly rounded products and sums only, which every device computes as
 * this C does. Only the box test's 1/dir is a division (pb_rcp there cost
 * lavapipe 4 %): a box test just culls, so it need only be conservative on
 * every device, not identical. */
#ifndef PB_INTERSECT_H
#define PB_INTERSECT_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bvh/exact_diff.h"

typedef struct pb_ray_pre {
    float org[3];
    float idir[3];     /* 1/dir with zeros replaced by a signed tiny value */
    int kx, ky, kz;    /* axis permutation: kz = largest |dir| component */
    float sx, sy, sz;  /* shear constants */
} pb_ray_pre;

/* Slab widening of pb_ray_node_boxes, 2^-19 = 32u (u = 2^-24): the
 * roundings it bounds add up to under 10u (see there). */
#define PB_SLAB_MARGIN 0x1p-19f

/* 1/b the same on every device: an integer first guess (5 % off) and three
 * Newton steps y += y(1 - by), each operation correctly rounded in IEEE and
 * in Vulkan alike. Error < 1.49u over every float mantissa (test_bvh checks
 * all 2^24 in [0.5, 2)); |b| outside [2^-100, 2^100] is scaled by 2^64 into
 * it first (exact). A result below float range (|b| > 2^126) may flush to 0
 * on a GPU. */
static inline float pb_rcp(float b)
{
    float m = fabsf(b), scale = 1.f;
    if (m == 0.f)
        return signbit(b) ? -INFINITY : INFINITY;
    if (!(m == m))
        return b;
    if (m < 0x1p-100f)
        m *= 0x1p64f, scale = 0x1p64f;
    else if (m > 0x1p100f) {
        if (m == INFINITY)
            return b < 0.f ? -0.f : 0.f;
        m *= 0x1p-64f, scale = 0x1p-64f;
    }
    uint32_t bits;
    memcpy(&bits, &m, 4);
    bits = 0x7EF311C3u - bits;
    float y;
    memcpy(&y, &bits, 4);
    for (int i = 0; i < 3; ++i) {
        float e = 1.f - m * y;
        y = y + y * e;
    }
    y *= scale;
    return b < 0.f ? -y : y;
}

static inline void pb_ray_prepare(const float org[3], const float dir[3], pb_ray_pre *r)
{
    float ax = fabsf(dir[0]), ay = fabsf(dir[1]), az = fabsf(dir[2]);
    int kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (dir[kz] < 0.f) {
        int t = kx;
        kx = ky;
        ky = t;
    }
    r->kx = kx, r->ky = ky, r->kz = kz;
    r->sz = pb_rcp(dir[kz]);
    r->sx = dir[kx] * r->sz;
    r->sy = dir[ky] * r->sz;
    for (int k = 0; k < 3; ++k) {
        float d = dir[k];
        if (fabsf(d) < 1e-30f)
            d = d < 0.f ? -1e-30f : 1e-30f; /* as the GLSL: -0 becomes +1e-30 */
        r->idir[k] = 1.0f / d;
        r->org[k] = org[k];
    }
}

/* a*b - c*d with the exact sign. |float - exact| <= (2u + u^2)(|ab| + |cd|),
 * u = 2^-24; 2.5e-7 (about 4.2u) also covers rounding of the bound itself. */
#define PB_EDGE_ERROR_BOUND 2.5e-7f

static inline float pb_edge_function(float a, float b, float c, float d)
{
    float p = a * b, q = c * d;
    float r = p - q;
    if (fabsf(r) > PB_EDGE_ERROR_BOUND * (fabsf(p) + fabsf(q)))
        return r;
    return pb_exact_diff(a, b, c, d);
}

/* Entry distances of a 4-wide node's child boxes, clipped to [tmin, tmax],
 * +inf for a missed box or an unused slot (i >= used). Bound q of axis k
 * decodes to origin + q * scale (pb_bvh4_child_box), so its slab distance is
 * q * B + A with B = scale * idir and A = (origin - org) * idir, both per
 * node: one fma per bound where the decoded box took a subtraction and a
 * product, and the near and far bounds are picked once per axis by the sign
 * of idir where each box took a min and a max (as Embree's nodes do). On
 * lavapipe: 1.04-1.10x the trace kernel's probe rays, 0.94-0.96x the bake's
 * GPU time (bench/RESULTS.md, "Box tests in the node's frame").
 *
 * That form cancels where a ray passes close to a box far from its node's
 * origin, so its error is not relative to the distance: each axis widens
 * near and far by E = PB_SLAB_MARGIN (|A| + (|origin| + 256 scale) |idir|).
 * What E bounds, with u = 2^-24 and t the true distance to the decoded
 * bound: A's two roundings (2u |A|), B's and the product's (2u q|B|; an fma
 * split in two on some device), the fma's own (u |t|), A - E's (u |A|),
 * 1/dir as a Vulkan division (5u |t|, and it differs per axis), and the
 * decode's rounding of the bound itself (u (|origin| + 255 scale) |idir|,
 * which the exact q * scale + origin does not carry). |t| <= |A| + 255 |B|,
 * so under 10u times E's bracket. Conservative, not identical: devices may
 * fuse differently, and 1/dir differs already; hits do not depend on it.
 * Here the host multiplies, then adds (the split fma above): x86-64's
 * baseline has no fma instruction, so fmaf was a call into libm per bound,
 * and the walker traced The Crypt's probe rays at 1.00 Mrays/s a thread
 * against 1.77 now, the same hits. */
static inline void pb_ray_node_boxes_widened(const pb_ray_pre *r, const float origin[3], const float scale[3],
                                             const uint8_t q[3][2][4], uint32_t used, float tmin, float tmax,
                                             float margin, float d[4])
{
    float an[3], af[3], b[3];
    int flip[3];
    for (int k = 0; k < 3; ++k) {
        float a = (origin[k] - r->org[k]) * r->idir[k];
        float e = margin * (fabsf(a) + (fabsf(origin[k]) + 256.f * scale[k]) * fabsf(r->idir[k]));
        an[k] = a - e;
        af[k] = a + e;
        b[k] = scale[k] * r->idir[k];
        flip[k] = r->idir[k] < 0.f; /* the hi bound is the near one */
    }
    for (uint32_t i = 0; i < 4; ++i) {
        float t0 = tmin, t1 = tmax;
        for (int k = 0; k < 3; ++k) {
            float tn = (float)q[k][flip[k]][i] * b[k] + an[k];
            float tf = (float)q[k][!flip[k]][i] * b[k] + af[k];
            t0 = tn > t0 ? tn : t0;
            t1 = tf < t1 ? tf : t1;
        }
        d[i] = i < used && t0 <= t1 ? t0 : INFINITY;
    }
}

/* The traversals' form; test_bvh also runs the one above with no margin, to
 * show its rays need it. */
static inline void pb_ray_node_boxes(const pb_ray_pre *r, const float origin[3], const float scale[3],
                                     const uint8_t q[3][2][4], uint32_t used, float tmin, float tmax, float d[4])
{
    pb_ray_node_boxes_widened(r, origin, scale, q, used, tmin, tmax, PB_SLAB_MARGIN, d);
}

/* Watertight test of triangle (v0, v1, v2). On a hit with tmin < t < tmax
 * returns 1 and writes t and the barycentrics of v1 (u) and v2 (v). */
static inline int pb_ray_triangle(const pb_ray_pre *r, const float *v0, const float *v1, const float *v2, float tmin,
                                  float tmax, float *t_out, float *u_out, float *v_out)
{
    const int kx = r->kx, ky = r->ky, kz = r->kz;
    float A[3], B[3], C[3];
    for (int k = 0; k < 3; ++k) {
        A[k] = v0[k] - r->org[k];
        B[k] = v1[k] - r->org[k];
        C[k] = v2[k] - r->org[k];
    }
    float Ax = A[kx] - r->sx * A[kz], Ay = A[ky] - r->sy * A[kz];
    float Bx = B[kx] - r->sx * B[kz], By = B[ky] - r->sy * B[kz];
    float Cx = C[kx] - r->sx * C[kz], Cy = C[ky] - r->sy * C[kz];
    float U = pb_edge_function(Cx, By, Cy, Bx);
    float V = pb_edge_function(Ax, Cy, Ay, Cx);
    float W = pb_edge_function(Bx, Ay, By, Ax);
    if ((U < 0.f || V < 0.f || W < 0.f) && (U > 0.f || V > 0.f || W > 0.f))
        return 0;
    float det = U + V + W;
    if (det == 0.f)
        return 0;
    float Az = r->sz * A[kz], Bz = r->sz * B[kz], Cz = r->sz * C[kz];
    float T = U * Az + V * Bz + W * Cz;
    /* compare t = T/det against the interval without dividing: flip signs so det > 0 */
    if (det < 0.f) {
        T = -T;
        det = -det;
        U = -U;
        V = -V;
        W = -W;
    }
    if (!(T > tmin * det) || !(T < tmax * det))
        return 0;
    float inv = pb_rcp(det);
    *t_out = T * inv;
    *u_out = V * inv;
    *v_out = W * inv;
    return 1;
}

/* 1 when the ray direction leaves the triangle's front (CCW) side. */
static inline uint32_t pb_is_backface(const float *v0, const float *v1, const float *v2, const float dir[3])
{
    float e1[3] = {v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]};
    float e2[3] = {v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]};
    float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    return n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2] > 0.f;
}

#endif
