/*
 * probebake trace: rays against the scene, on the device and on the CPU.
 *
 * pb_trace runs the GLSL kernel (shaders/comp/trace.comp); pb_trace_cpu runs
 * the same watertight intersection through the same BVH on the host, and
 * pb_trace_brute tests every triangle (the reference of the reference).
 * Closest-hit results agree to float rounding: same triangle, or the same
 * distance when two triangles tie.
 */
#ifndef PROBEBAKE_TRACE_H
#define PROBEBAKE_TRACE_H

#include "probebake/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A ray in the scene's local frame. Hits count for tmin < t < tmax.
 * `direction` need not be unit length: t is in units of its length. */
typedef struct pb_ray {
    float origin[3];
    float tmin;
    float direction[3];
    float tmax;
} pb_ray;

#define PB_NO_HIT 0xffffffffu

/* Closest hit: scene triangle index (PB_NO_HIT on a miss), distance t, and
 * barycentrics (u, v): point = (1-u-v) v0 + u v1 + v v2. backface is 1 when
 * the ray meets the triangle's back side (glTF front = counter-clockwise). */
typedef struct pb_hit {
    float t;
    uint32_t triangle;
    float u, v;
    uint32_t backface;
} pb_hit;

typedef enum pb_trace_mode {
    PB_TRACE_CLOSEST = 0,     /* nearest hit */
    PB_TRACE_ANY = 1          /* shadow rays: stop at the first hit found (any triangle) */
} pb_trace_mode;

typedef struct pb_trace_stats {
    double kernel_ms;         /* sum of GPU timestamp intervals of the trace dispatches (0 if unsupported) */
    double wall_ms;           /* host wall time of pb_trace, transfers included */
    uint32_t submits;         /* bounded submissions used */
} pb_trace_stats;

typedef struct pb_scene pb_scene;
typedef struct pb_bvh pb_bvh;
typedef struct pb_context pb_context;

/* The scene and its BVH in device memory. */
typedef struct pb_gpu_scene pb_gpu_scene;

/* Uploads the BVH, triangles and the alpha-mask data (materials, texture
 * texels) of `scene`. Both must describe the same scene; neither is kept.
 *  Returns PB_ERROR_TOO_LARGE (refused before allocating) when an array
 *  exceeds the device's maxMemoryAllocationSize or the total exceeds its
 *  device-local memory; PB_ERROR_OUT_OF_DEVICE_MEMORY when allocation fails. */
pb_result pb_gpu_scene_create(pb_context *ctx, const pb_scene *scene, const pb_bvh *bvh,
                              pb_gpu_scene **out, pb_error *err);
void pb_gpu_scene_destroy(pb_gpu_scene *gs);

/* Bytes of device memory used by the uploaded scene, and the part of it that
 * traversal reads for every ray (nodes + triangle positions + flags). */
uint64_t pb_gpu_scene_bytes(const pb_gpu_scene *gs, uint64_t *traversal_bytes);

/* Traces `count` rays on the device in submissions of at most
 * rays_per_submit rays. hits: `count` entries, caller-owned.
 * stats: may be NULL. */
pb_result pb_trace(pb_context *ctx, pb_gpu_scene *gs, const pb_ray *rays, uint32_t count,
                   pb_trace_mode mode, pb_hit *hits, pb_trace_stats *stats, pb_error *err);

/* CPU reference: same intersection, same BVH, `threads` host threads (0: all). */
void pb_trace_cpu(const pb_scene *scene, const pb_bvh *bvh, const pb_ray *rays, uint32_t count,
                  pb_trace_mode mode, pb_hit *hits, uint32_t threads);

/* Brute force: every triangle for every ray. */
void pb_trace_brute(const pb_scene *scene, const pb_ray *rays, uint32_t count,
                    pb_trace_mode mode, pb_hit *hits, uint32_t threads);

/* Robust origin for a ray leaving a surface (Wächter & Binder 2019, "A fast
 * and robust method for avoiding self-intersection"): moves `p` off the plane
 * of geometric normal `n` (unit, pointing to the side the ray leaves to) by a
 * few float ulps of p, or by a fixed tiny amount near the origin. */
void pb_offset_ray_origin(const float p[3], const float n[3], float out[3]);

/* The same on the device (shaders/include/ray_offset.glsl through
 * ray_offset.comp), for `count` points: points, normals and origins hold
 * 3 floats per point. Bit-identical to pb_offset_ray_origin. */
pb_result pb_offset_ray_origins_gpu(pb_context *ctx, const float *points, const float *normals, uint32_t count,
                                    float *origins, pb_error *err);


/* A regular probe grid: probe (i,j,k) sits at origin + (i,j,k) * spacing. */
typedef struct pb_probe_grid {
    float origin[3];
    float spacing[3];
    uint32_t counts[3];
} pb_probe_grid;

/* Grid of about `target_probes` probes (at least 1 per axis) at cell centres
 * of the box [lo, hi], with equal spacing on every axis. */
void pb_probe_grid_fit(const float lo[3], const float hi[3], uint32_t target_probes, pb_probe_grid *grid);

uint32_t pb_probe_grid_count(const pb_probe_grid *grid);

/* Probe-style rays: for probes [first, first+count) of the grid, `per_probe`
 * directions on a spherical Fibonacci set turned by a random rotation drawn
 * from (seed, probe index) alone, so any subset of probes gets the same rays
 * as the whole; each probe's rays come in a spatially coherent order (Morton
 * order of their octahedral coordinates). out: count*per_probe rays (tmin 0,
 * tmax +inf). Returns PB_ERROR_OUT_OF_HOST_MEMORY if scratch cannot be had. */
pb_result pb_probe_rays(const pb_probe_grid *grid, uint32_t first, uint32_t count, uint32_t per_probe, uint32_t seed,
                        pb_ray *out);

/* The unrotated spherical-Fibonacci set of n directions in its coherent
 * (Morton) order, 4 floats per direction (w = 0). */
pb_result pb_sf_directions(uint32_t n, float *out4);

/* Uniformly random rotation (row-major 3x3) keyed on (seed, probe, pass). */
void pb_random_rotation(uint32_t seed, uint32_t probe, uint32_t pass, float m[9]);

/* 32-bit hash (PCG output permutation) and a uniform float in [0,1) from a
 * key tuple. Every random number in probebake comes from these. */
uint32_t pb_hash32(uint32_t x);
float pb_random01(uint32_t seed, uint32_t a, uint32_t b, uint32_t c);

#ifdef __cplusplus
}
#endif
#endif
