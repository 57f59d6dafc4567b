/* Light cells on the device, kept by the GPU scene across bakes. They depend
 * on the scene and the seed only (light_cells.c), yet every bake learned
 * them again: ~225 ms of host shadow rays on The Crypt, five times in a
 * three-level sparse bake. */
#ifndef PB_LIGHT_CELLS_GPU_H
#define PB_LIGHT_CELLS_GPU_H

#include "bake/gpu_scene.h"
#include "bake/light_cells.h"
#include "probebake/bake.h"

typedef struct pb_light_cells_gpu {
    uint32_t seed;                /* what they were learned with */
    pb_light_cells host;          /* table NULL: emitters are drawn by power */
    pb_buffer table, slots, clusters, members, cluster_of; /* light_cells.glsl's arrays, leaf order */
} pb_light_cells_gpu;

/* The light cells of (gs's scene, seed), learned and uploaded on first use
 * and kept in gs (pb_gpu_scene_destroy frees them); *out is gs's. `learned`
 * (may be NULL) says whether this call learned them. */
pb_result pb_light_cells_gpu_get(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, uint32_t seed,
                                 const pb_bake_emitters *emitters, const pb_light_cells_gpu **out, int *learned,
                                 pb_error *err);
void pb_light_cells_gpu_free(pb_context *ctx, pb_light_cells_gpu *g);

#endif
