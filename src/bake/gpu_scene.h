/* The uploaded scene (leaf order) and the kernels that read it. */
#ifndef PB_GPU_SCENE_H
#define PB_GPU_SCENE_H

#include "bake/gpu_types.h"
#include "gpu/gpu.h"

struct pb_gpu_scene {
    pb_context *ctx;          /* the context it lives on (not owned) */
    const pb_bvh *bvh;        /* the host BVH it was made from (not owned; outlives it, as documented:
                                 destroy in reverse order); host stages trace with it (path guiding) */
    pb_buffer nodes, tris, tri_uv, materials, textures, texels;
    uint32_t *tri_order;      /* leaf -> scene triangle, host copy */
    uint32_t triangle_count;
    uint32_t stack_size;      /* traversal stack entries (PB_BVH_STACK_SIZE) */
    gpu_scene_refs refs;
    pb_pipeline trace_closest, trace_any;
    uint64_t bytes, traversal_bytes;
    /* ray/hit buffers, grown on demand and reused */
    pb_buffer rays, hits;
    uint32_t ray_capacity;
    /* nodes and triangles as RGBA32UI texel views, set 0 of the scene kernels
     * (scene.glsl); texel_loads: the kernels read through them (specialisation
     * constant 1), else through the addresses in refs */
    VkBufferView node_view, tri_view;
    VkDescriptorPool set_pool;
    VkDescriptorSet set;
    uint32_t texel_loads;
    struct pb_light_cells_gpu *light_cells; /* the bakes' light cells, learned once per seed (light_cells_gpu.h) */
    struct pb_guide_cache *guide_cache;     /* path guiding's guide, learned once per key (guide_cache.h); owned,
                                               but pb_bake_devices points it at a shared one for a bake */
    const pb_scene *hashed_scene;           /* scene_hash is its pb_scene_hash (a bake's, kept: a sparse bake's
                                               levels hash once); NULL before the first bake */
    uint64_t scene_hash;
};

/* Frees the scene's device objects on `ctx`. */
void pb_gpu_scene_destroy_ctx(pb_context *ctx, pb_gpu_scene *gs);

#endif
