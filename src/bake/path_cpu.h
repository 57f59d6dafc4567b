/* The path tracer's C reference (shaders/include/path.glsl), shared by the
 * bake's and the renderer's CPU references. */
#ifndef PB_PATH_CPU_H
#define PB_PATH_CPU_H

#include "bake/bake_data.h"
#include "probebake/bake.h"

typedef struct pb_path_ctx {
    const pb_bake_pass *p;         /* scene, BVH, environment, emitters (other fields unused here) */
    gpu_light *lights;
    gpu_shade_material *materials;
    int smooth;                    /* the scene's vertex normals shade (PB_SCENE_SHADING_NORMALS) */
    int glass;                     /* the scene has thin glass (PB_SCENE_TRANSMISSION) */
} pb_path_ctx;

/* PathResult of path.glsl */
typedef struct pb_path_result {
    float L[3], L_direct[3], L_seen[3];
    float first_t;                 /* negative on a back face, INFINITY on a miss */
    int shade;
    float x[3], n[3], albedo[3];   /* n: the shading normal, facing the ray's origin */
} pb_path_result;

/* The kernels' random numbers (rng.glsl) and cosine-weighted directions
 * (path.glsl), for other CPU stages that must draw alike. */
uint32_t pb_rng_seed_cpu(uint32_t seed, uint32_t probe, uint32_t pass, uint32_t ray);
float pb_rng_next_cpu(uint32_t *state);
void pb_cosine_direction_cpu(const float n[3], float u1, float u2, float out[3]);

int pb_path_ctx_init(pb_path_ctx *c, const pb_bake_pass *p);
void pb_path_ctx_free(pb_path_ctx *c);

/* Thread-safe; traversals are counted per thread for pb_bake_trace_cpu. */
pb_path_result pb_path_radiance_cpu(const pb_path_ctx *c, const float o[3], const float dir[3], uint32_t bounces,
                                    int see_direct, uint32_t *state);

#endif
