/*
 * probebake sample: the run-time half. Irradiance at a shading point from a
 * baked grid volume: the 8-probe cage, trilinear weights, a smooth backface
 * term, Chebyshev visibility from the depth moments, normal and view bias,
 * tiny-weight crushing, renormalisation and SH evaluation (docs/sampling.md).
 *
 * The GLSL is shaders/include/probe_sample_core.glsl (Vulkan wrapper
 * probe_sample.glsl, WebGL2 runtime/probe_sample.glsl); pb_sample_cpu is its
 * C reference, operation for operation.
 */
#ifndef PROBEBAKE_SAMPLE_H
#define PROBEBAKE_SAMPLE_H

#include "probebake/base.h"
#include "probebake/volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Defaults: biases as fractions of the smallest grid spacing. */
#define PB_SAMPLE_NORMAL_BIAS 0.1f
#define PB_SAMPLE_VIEW_BIAS 0.1f

/* A grid volume laid out as the shaders read it, in a chosen frame (the
 * renderer's: scene-local coordinates). */
typedef struct pb_sample_volume {
    float origin[3];            /* probe (0,0,0) before relocation, in the frame */
    float spacing[3];
    int32_t counts[3];
    int32_t octmap_res;
    float normal_bias, view_bias;
    float depth_unit;           /* metres per stored depth unit (the volume's) */
    uint32_t probe_count;
    uint32_t levels;            /* 0: a grid; 1-3: sparse (origin: lattice origin, spacing: the finest level's,
                                   counts: coarsest cells per axis) */
    uint32_t *sparse_words;     /* sparse: the layout tables as the shaders read them (pb_sparse_word) */
    uint32_t sparse_word_count;
    float *probes;              /* 4 per probe: relocated position in the frame, w = PB_PROBE_* flags (uint bits) */
    float *sh;                  /* 27 per probe: irradiance SH, coefficient major, RGB */
    uint32_t *depth;            /* (n+2)^2 per probe: halves (mean, mean squared) in depth units, as in the file */
} pb_sample_volume;

/* Lays out volume v (a grid or sparse) for sampling in the frame whose
 * origin is frame_origin (original coordinates). Biases <= 0 take the
 * defaults. Returns PB_ERROR_INVALID_ARGUMENT for a point-set volume (no
 * grid to interpolate in) and PB_ERROR_OUT_OF_HOST_MEMORY. */
pb_result pb_sample_volume_build(const pb_volume *v, const double frame_origin[3], float normal_bias,
                                 float view_bias, pb_sample_volume *out, pb_error *err);
/* pb_sample_volume_build that takes v's SH and depth arrays instead of
 * copying them (v->sh and v->depth are NULL after it succeeds; on failure v
 * is as it was): the same sampler, without a second copy of a large volume
 * (a million probes at 16x16: 1.4 GB). */
pb_result pb_sample_volume_adopt(pb_volume *v, const double frame_origin[3], float normal_bias, float view_bias,
                                 pb_sample_volume *out, pb_error *err);
void pb_sample_volume_free(pb_sample_volume *s);

/* Irradiance at p (frame coordinates) with unit normal n, seen from unit
 * direction view (from p towards the viewer). Sparse volumes: from the
 * finest brick whose cell covers p; black where there is none. */
void pb_sample_cpu(const pb_sample_volume *s, const float p[3], const float n[3], const float view[3], float rgb[3]);
/* pb_sample_cpu, also naming the eight probes of the cage it used and the
 * normalised weight each got (probes -1 and weights 0 where no brick serves
 * p): what tests check "no probe inside geometry is sampled" with. */
void pb_sample_cage_cpu(const pb_sample_volume *s, const float p[3], const float n[3], const float view[3],
                        float rgb[3], int probes[8], float weights[8]);
/* The brick of a sparse volume that pb_sample_cpu reads at p, or -1 where
 * none covers the biased point (and for a grid); *cell: the coarsest cell,
 * x fastest, the biased point falls in (clamped to the layout). */
int pb_sample_brick_cpu(const pb_sample_volume *s, const float p[3], const float n[3], const float view[3],
                        uint32_t *cell);

/* The Chebyshev visibility weight pb_sample_cpu gives probe `probe` for the
 * (already biased) point q, in [0, 1]: the part of the weight that the depth
 * moments decide. Scale-invariant: a scene and its copy scaled by s give the
 * same weight at corresponding points, to float16 rounding.
 *  detail: NULL, or receives (mean, mean square, distance of q) in depth units. */
float pb_sample_visibility_cpu(const pb_sample_volume *s, int probe, const float q[3], const float n[3],
                               float detail[3]);

typedef struct pb_context pb_context;

/* The shader on the device for `count` queries (4 floats each for p, n,
 * view; rgb out 4 floats each): the test of the GLSL against pb_sample_cpu. */
pb_result pb_sample_gpu(pb_context *ctx, const pb_sample_volume *s, const float *p4, const float *n4,
                        const float *view4, uint32_t count, float *rgb4, pb_error *err);

#ifdef __cplusplus
}
#endif
#endif
