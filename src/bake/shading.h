/* Shading data on the device, as path.glsl reads it through BakeParams:
 * materials, punctual lights, the emitter alias table (leaf order) and the
 * environment table. Shared by the bake and the renderer. */
#ifndef PB_SHADING_H
#define PB_SHADING_H

#include "bake/bake_data.h"
#include "bake/gpu_scene.h"
#include "gpu/gpu.h"
#include "probebake/bake.h"

typedef struct pb_shading {
    pb_buffer materials, lights, emitters, emit_pdf, env, light_table;
    uint32_t light_count;
    uint32_t light_select;        /* 1: one light drawn per hit (more lights than max_lights_per_hit) */
    pb_light_table lights_drawn;  /* host copy when light_select */
    pb_bake_emitters emit;        /* host copy, scene triangle order (CPU references) */
    pb_env_table env_table;       /* host copy; count 0 and width 0: black */
} pb_shading;

/* environment NULL: the uniform sky (black: none). */
/* max_lights_per_hit 0: the default, 8. */
pb_result pb_shading_create(pb_context *ctx, const pb_scene *scene, const pb_gpu_scene *gs, const float sky[3],
                            const pb_environment *environment, uint32_t max_lights_per_hit, pb_shading *out,
                            pb_error *err);
/* Sets the shading fields of prm (scene refs excluded). */
void pb_shading_params(const pb_shading *s, gpu_bake_params *prm);
void pb_shading_destroy(pb_context *ctx, pb_shading *s);

/* The host tables alone (CPU references): emitters and environment. */
pb_result pb_shading_host(const pb_scene *scene, const float sky[3], const pb_environment *environment,
                          pb_bake_emitters *emit, pb_env_table *env, pb_error *err);

/* Whether hits draw one light: more than max_lights_per_hit (0: 8) lights. */
int pb_shading_draws_lights(const pb_scene *scene, uint32_t max_lights_per_hit);

#endif
