/* Emitter triangles sampled by solid angle (spherical_triangle.h). */
#include "bake/spherical_triangle.h"
#include "common/vec3.h"

#include <math.h>

/* normalize(v - x) */
static void toward(const float x[3], const float v[3], float d[3])
{
    for (int k = 0; k < 3; ++k)
        d[k] = v[k] - x[k];
    float l = pb_length3(d);
    for (int k = 0; k < 3; ++k)
        d[k] /= l;
}

float pb_atan_nonneg(float y, float x)
{
    float ax = fabsf(x), hi = fmaxf(ax, y), lo = fminf(ax, y);
    if (!(hi > 0.f))
        return 0.f;
    int shift = lo > 0.41421356f * hi;
    float a = shift ? (lo - hi) / (lo + hi) : lo / hi, base = shift ? 0.78539816f : 0.f;
    float w = a * a;
    float p = (((-6.092343107e-02f * w + 1.060001552e-01f) * w - 1.424448639e-01f) * w + 1.999853104e-01f) * w -
              3.333331645e-01f;
    float r = base + (a + a * w * p);
    if (y > ax)
        r = 1.5707963f - r;
    return x < 0.f ? 3.1415927f - r : r;
}

void pb_sincos_0_pi(float h, float *s, float *c)
{
    h = fminf(fmaxf(h, 0.f), 3.14159274f);
    /* r = h - q pi/2 in [-pi/4, pi/4]: h - q (pi/2's float) is exact (Sterbenz),
     * then q times its low part; sin and cos of h from r's by the quadrant */
    int q = h > 2.35619449f ? 2 : h > 0.785398163f;
    float r = (h - (float)q * 1.57079637f) - (float)q * -4.37113883e-8f;
    float w = r * r;
    float ps = (-1.953543542e-04f * w + 8.332310244e-03f) * w - 1.666665673e-01f;
    float pc = (2.444946222e-05f * w - 1.388745848e-03f) * w + 4.166664928e-02f;
    float sr = r + r * w * ps, cr = (1.f - 0.5f * w) + w * w * pc;
    *s = q == 0 ? sr : q == 1 ? cr : -sr;
    *c = q == 0 ? cr : q == 1 ? -sr : -cr;
}

float pb_spherical_triangle_area(const float x[3], const float v0[3], const float v1[3], const float v2[3])
{
    float p0[3], p1[3], p2[3], e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) {
        p0[k] = v0[k] - x[k], p1[k] = v1[k] - x[k], p2[k] = v2[k] - x[k];
        e1[k] = v1[k] - v0[k], e2[k] = v2[k] - v0[k];
    }
    float l0 = pb_length3(p0), l1 = pb_length3(p1), l2 = pb_length3(p2);
    pb_cross3(e1, e2, n);
    float num = fabsf(pb_dot3(p0, n));
    float den = l0 * l1 * l2 + pb_dot3(p0, p1) * l2 + pb_dot3(p1, p2) * l0 + pb_dot3(p2, p0) * l1;
    return 2.f * pb_atan_nonneg(num, den);
}

int pb_spherical_triangle_sampled(float area)
{
    return area >= PB_SPH_MIN_SOLID_ANGLE && area <= PB_SPH_MAX_SOLID_ANGLE;
}

void pb_spherical_triangle_sample(const float x[3], const float v0[3], const float v1[3], const float v2[3],
                                  float area, float u1, float u2, float w[3])
{
    float A[3], B[3], C[3], P[3], bP[3], cm[3], cp[3];
    toward(x, v0, A), toward(x, v1, B), toward(x, v2, C);
    /* first step: C' on the arc from A toward C, by tau = tan(angle(A, C') / 2) */
    float ca = pb_dot3(C, A);
    for (int k = 0; k < 3; ++k)
        P[k] = C[k] - ca * A[k];
    float pl = pb_length3(P);
    for (int k = 0; k < 3; ++k)
        P[k] /= pl;
    pb_cross3(B, P, bP);
    float k = fabsf(pb_dot3(A, bP)), bp = pb_dot3(B, P);
    float h = 0.5f * u1 * area;
    float sh, ch;
    pb_sincos_0_pi(h, &sh, &ch);
    float den = k * ch - bp * sh;
    for (int j = 0; j < 3; ++j)
        cm[j] = C[j] - A[j], cp[j] = C[j] + A[j];
    float tau_c = pb_length3(cm) / pb_length3(cp); /* C' = C at u1 = 1 */
    float tau = (1.f + pb_dot3(A, B)) * sh / den;
    if (!(den > 0.f && tau < tau_c))
        tau = tau_c;
    float t2 = tau * tau, Cs[3], d[3];
    for (int j = 0; j < 3; ++j) {
        Cs[j] = ((1.f - t2) * A[j] + (2.f * tau) * P[j]) / (1.f + t2);
        d[j] = Cs[j] - B[j];
    }
    /* second step: 1 - cos(B, C') = |C' - B|^2 / 2 keeps its digits when C' is near B */
    float e = u2 * 0.5f * pb_dot3(d, d);
    float z = 1.f - e;
    float bp2[3], cb = pb_dot3(Cs, B);
    for (int j = 0; j < 3; ++j)
        bp2[j] = Cs[j] - cb * B[j];
    float bl = pb_length3(bp2);
    if (!(bl > 0.f)) {
        w[0] = B[0], w[1] = B[1], w[2] = B[2];
        return;
    }
    float r = sqrtf(fmaxf(0.f, e * (2.f - e))) / bl;
    for (int j = 0; j < 3; ++j)
        w[j] = z * B[j] + r * bp2[j];
    float wl = pb_length3(w);
    for (int j = 0; j < 3; ++j)
        w[j] /= wl;
}
