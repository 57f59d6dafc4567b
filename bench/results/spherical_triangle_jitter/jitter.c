/* How far a Vulkan device's own rounding of sqrt and division may move the
 * solid-angle sampler's directions (tests/test_bake.c,
 * spherical_triangle_kernel_matches_cpu): the host's sampler
 * (src/bake/spherical_triangle.c, same arithmetic) with every square root and
 * division result moved at random by up to J ulp, on the test's 65,536
 * triangles, against the formulas in double precision
 * (tests/spherical_triangle_exact.h); the worst angle per kind of shape.
 * Build from the repository root:
 *   cc -O2 -ffp-contract=off -DPB_SOURCE_DIR=\".\" -Isrc -Iinclude bench/results/spherical_triangle_jitter/jitter.c \
 *      src/bake/spherical_triangle.c -lm -o /tmp/jitter && /tmp/jitter
 * Two random draws (seed 7, 8); out.txt has the output. (ROBUST 1: the two
 * projections divided by the squared length, robust to a unit vector's
 * length: better on near-hemispheres under jitter, not elsewhere; not kept.) */
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include "../../../tests/test_util.h"
#include "bake/spherical_triangle.h"
static int J = 0; static uint32_t seed = 7;
static float jit(float v) { if (!J) return v; seed = seed * 1664525u + 1013904223u; int d = (int)(seed >> 28) % (2*J+1) - J; while (d > 0) { v = nextafterf(v, INFINITY); d--; } while (d < 0) { v = nextafterf(v, -INFINITY); d++; } return v; }
static float dot3(const float a[3], const float b[3]) { return a[0]*b[0]+a[1]*b[1]+a[2]*b[2]; }
static void cross3(const float a[3], const float b[3], float c[3]) { c[0] = a[1]*b[2]-a[2]*b[1]; c[1] = a[2]*b[0]-a[0]*b[2]; c[2] = a[0]*b[1]-a[1]*b[0]; }
static float len3(const float a[3]) { return jit(sqrtf(dot3(a, a))); }
static float dv(float a, float b) { return jit(a / b); }
static int ROBUST = 0;
static void toward(const float x[3], const float v[3], float d[3]) { for (int k = 0; k < 3; ++k) d[k] = v[k] - x[k]; float l = len3(d); for (int k = 0; k < 3; ++k) d[k] = dv(d[k], l); }
void sample(const float x[3], const float v0[3], const float v1[3], const float v2[3], float area, float u1, float u2, float w[3]) {
    float A[3], B[3], C[3], P[3], bP[3], cm[3], cp[3];
    toward(x, v0, A), toward(x, v1, B), toward(x, v2, C);
    float ca = ROBUST ? dv(dot3(C, A), dot3(A, A)) : dot3(C, A);
    for (int k = 0; k < 3; ++k) P[k] = C[k] - ca * A[k];
    float pl = len3(P);
    for (int k = 0; k < 3; ++k) P[k] = dv(P[k], pl);
    cross3(B, P, bP);
    float k = fabsf(dot3(A, bP)), bp = dot3(B, P);
    float h = 0.5f * u1 * area, sh, ch; pb_sincos_0_pi(h, &sh, &ch);
    float den = k * ch - bp * sh;
    for (int j = 0; j < 3; ++j) cm[j] = C[j] - A[j], cp[j] = C[j] + A[j];
    float tau_c = dv(len3(cm), len3(cp));
    float tau = dv((1.f + dot3(A, B)) * sh, den);
    if (!(den > 0.f && tau < tau_c)) tau = tau_c;
    float t2 = tau * tau, Cs[3], d[3];
    for (int j = 0; j < 3; ++j) { Cs[j] = dv((1.f - t2) * A[j] + (2.f * tau) * P[j], 1.f + t2); d[j] = Cs[j] - B[j]; }
    float e = u2 * 0.5f * dot3(d, d);
    float z = 1.f - e;
    float bp2[3], cb = ROBUST ? dv(dot3(Cs, B), dot3(B, B)) : dot3(Cs, B);
    for (int j = 0; j < 3; ++j) bp2[j] = Cs[j] - cb * B[j];
    float bl = len3(bp2);
    if (!(bl > 0.f)) { w[0] = B[0], w[1] = B[1], w[2] = B[2]; return; }
    float r = dv(sqrtf(fmaxf(0.f, e * (2.f - e))), bl);
    for (int j = 0; j < 3; ++j) w[j] = z * B[j] + r * bp2[j];
    float wl = len3(w);
    for (int j = 0; j < 3; ++j) w[j] = dv(w[j], wl); }
#include "../../../tests/spherical_triangle_exact.h"
int main(void) {
  uint32_t n = 1u << 16; test_rng r = {17}; float *in = calloc((size_t)n * 20, 4);
  for (uint32_t i = 0; i < n; ++i) {
        float *e = in + 20 * (size_t)i;
        for (int k = 0; k < 3; ++k) e[k] = (float)(rng_uniform(&r) * 4 - 2);
        float d0[3], d1[3], d2[3];
        rng_direction(&r, d0), rng_direction(&r, d1), rng_direction(&r, d2);
        double spread = pow(10.0, -2.5 * rng_uniform(&r));
        for (int k = 0; k < 3; ++k) { d1[k] = (float)(d0[k] + spread * d1[k]); d2[k] = (float)(d0[k] + spread * (i % 4 == 0 ? 0.01 : 1.0) * d2[k]); }
        for (int k = 0; k < 3; ++k) { float l0 = (float)(0.1 + 3 * rng_uniform(&r)), l1 = (float)(0.1 + 3 * rng_uniform(&r));
            e[4 + k] = e[k] + l0 * d0[k]; e[8 + k] = e[k] + l1 * d1[k]; e[12 + k] = e[k] + l0 * d2[k]; }
        if (i % 16 == 1) { float h = (float)pow(10.0, -1.0 - 3.0 * rng_uniform(&r)); float big[9] = {-4, -3, 0, 4, -3, 0, 0, 5, 0};
            for (int k = 0; k < 9; ++k) e[4 + 4 * (k / 3) + k % 3] = big[k] + e[k % 3]; e[2] += h; }
        e[16] = (float)rng_uniform(&r), e[17] = (float)rng_uniform(&r);
  }
  for (uint32_t s0 = 7; s0 <= 8; ++s0) for (ROBUST = 0; ROBUST < 2; ++ROBUST) for (J = 0; J <= 3; J += 1) {
    seed = s0;
    double worst[3] = {0};
    for (uint32_t i = 0; i < n; ++i) { float *e = in + 20 * (size_t)i; int c = i % 16 == 1 ? 0 : i % 4 == 0 ? 1 : 2;
      float a = pb_spherical_triangle_area(e, e+4, e+8, e+12);
      if (!pb_spherical_triangle_sampled(a)) continue;
      float w[3]; sample(e, e+4, e+8, e+12, a, e[16], e[17], w);
      double p[12], wd[3]; for (int k = 0; k < 12; ++k) p[k] = e[4 * (k / 3) + k % 3];
      exact_triangle_sample(p, p + 3, p + 6, p + 9, a, e[16], e[17], wd);
      double ang = exact_angle(w, wd); if (ang > worst[c]) worst[c] = ang; }
    printf("seed %u robust %d jitter %d ulp: near-hemisphere %.3g sliver %.3g other %.3g\n", s0, ROBUST, J, worst[0], worst[1], worst[2]);
  }
}
