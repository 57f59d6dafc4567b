/* Emitter triangles sampled by solid angle (Arvo 1995, "Stratified sampling
 * of spherical triangles"): seen from a point x, every direction toward the
 * triangle is equally likely, density 1 / (its solid angle). Area sampling's
 * density d^2 / (cos_e area) swings over a triangle close to x, and the light
 * it brings swings with it; this one's does not. Triangles of small solid
 * angle (far away or edge-on) keep area sampling: there both are alike, and
 * the differences of nearly equal unit vectors below lose their digits. The
 * CPU reference of shaders/include/spherical_triangle.glsl, same arithmetic
 * in the same order (docs/bake.md, "Emitters by solid angle"). */
#ifndef PB_SPHERICAL_TRIANGLE_H
#define PB_SPHERICAL_TRIANGLE_H

#include "probebake/base.h"

#include <stdint.h>

/* Solid angles (sr) between which a triangle is sampled by solid angle. */
#define PB_SPH_MIN_SOLID_ANGLE 1e-2f
#define PB_SPH_MAX_SOLID_ANGLE 6.2f

/* atan2(y, x) for y >= 0, in [0, pi], to float's rounding (6e-8 relative),
 * by the same polynomial as the kernels' (GLSL's atan may be 4096 ulp off). */
float pb_atan_nonneg(float y, float x);

/* sin h and cos h for h in [0, pi] (clamped into it), to float's rounding
 * (1e-7 relative), by the same polynomials as the kernels': GLSL allows sin
 * and cos an absolute error of 2^-11, and drivers differ. */
void pb_sincos_0_pi(float h, float *s, float *c);

/* The solid angle of triangle (v0, v1, v2) seen from x (Van Oosterom and
 * Strackee's formula: any size, either orientation). */
float pb_spherical_triangle_area(const float x[3], const float v0[3], const float v1[3], const float v2[3]);

/* 1 when a triangle of that solid angle is sampled by solid angle. */
int pb_spherical_triangle_sampled(float area);

/* A unit direction from x toward the triangle, uniform over its solid angle
 * `area` (pb_spherical_triangle_area) for u1, u2 uniform in [0, 1). */
void pb_spherical_triangle_sample(const float x[3], const float v0[3], const float v1[3], const float v2[3],
                                  float area, float u1, float u2, float w[3]);

/* The same on the device (shaders/comp/spherical_triangle.comp), for the
 * tests: per entry 20 floats in (x, v0, v1, v2 as xyz + 1 unused each, then
 * u1, u2, 2 unused), 4 out (the direction, zero where the solid angle is
 * outside the sampled range, then the solid angle). */
typedef struct pb_context pb_context;
pb_result pb_spherical_triangle_gpu(pb_context *ctx, const float *inputs, uint32_t count, float *out, pb_error *err);

#endif
