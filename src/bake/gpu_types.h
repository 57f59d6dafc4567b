/* C mirrors of the GLSL structs in shaders/include/scene.glsl and the push
 * constant blocks of the kernels in shaders/comp, field for field. The asserts catch
 * any drift in size or offset at compile time. */
#ifndef PB_GPU_TYPES_H
#define PB_GPU_TYPES_H

#include "probebake/bvh.h"
#include "probebake/trace.h"

#include <assert.h>
#include <stddef.h>
#include <stdint.h>

#define PB_FLAG_ALPHA_MASK 0x80000000u
/* gpu_scene_refs.flags: vertex colours follow the texture coordinates in
 * tri_uv (12 floats per triangle after the 6 n of the UVs) */
#define PB_SCENE_VERTEX_COLORS 1u
/* ... and vertex normals after them (3 packed words per triangle,
 * shading_normals.h); without it the kernels shade with the face normal */
#define PB_SCENE_SHADING_NORMALS 2u
/* ... a material is thin glass (pb_material.transmission > 0): its triangles
 * are opaque to the traversal, and the ray's owner decides (glass_step) */
#define PB_SCENE_TRANSMISSION 4u
/* ... a material has a normal map (pb_material.normal_texture): the
 * kernels bend its shading normals (normal_map.glsl) */
#define PB_SCENE_NORMAL_MAPS 8u
/* ... and the file's tangents after the normals (4 words per triangle,
 * pb_tangents_pack) */
#define PB_SCENE_TANGENTS 16u

typedef struct gpu_material {
    float base_alpha;
    float cutoff;
    int32_t texture;
    uint32_t mode;
} gpu_material;
_Static_assert(sizeof(gpu_material) == 16, "gpu_material layout");

typedef struct gpu_texture {
    uint32_t offset;
    uint32_t width, height;
    uint32_t wrap; /* wrap_s | wrap_t << 8 */
} gpu_texture;
_Static_assert(sizeof(gpu_texture) == 16, "gpu_texture layout");

_Static_assert(sizeof(pb_bvh4_node) == 48, "Node4 layout");
_Static_assert(offsetof(pb_bvh4_node, codes_lo) == 15 && offsetof(pb_bvh4_node, qbox) == 16 &&
                   offsetof(pb_bvh4_node, inner) == 40 && offsetof(pb_bvh4_node, leaf) == 44,
               "Node4 layout");

/* Leaf-ordered triangle record (Tri in scene.glsl), read as 64-bit words. */
typedef struct gpu_tri {
    float v[9];
    uint32_t flags; /* material index | PB_FLAG_ALPHA_MASK */
} gpu_tri;
_Static_assert(sizeof(gpu_tri) == 40, "Tri layout");

typedef struct gpu_scene_refs {
    uint64_t nodes, tris, tri_uv, materials, textures, texels;
    uint32_t triangle_count, flags; /* PB_SCENE_* */
} gpu_scene_refs;
_Static_assert(sizeof(gpu_scene_refs) == 56, "SceneRefs layout");

/* Ray and Hit of trace.comp are pb_ray and pb_hit. */
_Static_assert(sizeof(pb_ray) == 32 && offsetof(pb_ray, direction) == 16, "Ray layout");
_Static_assert(sizeof(pb_hit) == 20 && offsetof(pb_hit, backface) == 16, "Hit layout");

typedef struct trace_push {
    gpu_scene_refs scene;
    uint64_t rays, hits;
    uint32_t count, spread; /* spread: the workgroup stride (pb_dispatch_spread) */
} trace_push;
_Static_assert(sizeof(trace_push) == 80, "trace.comp push constants");

typedef struct ray_offset_push {
    uint64_t points, normals, origins;
    uint32_t count, pad;
} ray_offset_push;
_Static_assert(sizeof(ray_offset_push) == 32, "ray_offset.comp push constants");

typedef struct dilate_push {
    uint64_t sh, state_in, state_out, table; /* SH in place, states ping-pong (dilate.comp) */
    uint64_t neighbours; /* sparse: 26 probe indices per probe (dilate.h); 0: a grid */
    uint64_t unused;
    uint32_t counts[4];                                     /* grid x, y, z; probes */
} dilate_push;
_Static_assert(sizeof(dilate_push) == 64 && offsetof(dilate_push, counts) == 48, "dilate.comp push constants");

#endif
