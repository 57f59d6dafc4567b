// Scene data as the kernels see it: every array is a buffer reference (a
// device address in push constants), so no binding range limits its size.
// Mirrors src/bake/gpu_scene.h (C structs with _Static_assert on layout).
#ifndef PB_SCENE_GLSL
#define PB_SCENE_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#define PB_NO_HIT 0xffffffffu
#define PB_FLAG_ALPHA_MASK 0x80000000u
#define PB_INF uintBitsToFloat(0x7f800000u)

// Child-pair BVH node (include/probebake/bvh.h): x, y, z hold
// (c0.lo, c0.hi, c1.lo, c1.hi); c holds (child0, child1, count0, count1).
struct Node {
    vec4 x;
    vec4 y;
    vec4 z;
    ivec4 c;
};

struct Material { // alpha-test view of a material
    float base_alpha;
    float cutoff;
    int texture;
    uint mode;
};

struct Texture {
    uint offset;
    uint width;
    uint height;
    uint wrap; // wrap_s | wrap_t << 8
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer NodeBuf { Node n[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer FloatBuf { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer UintBuf { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer MaterialBuf { Material m[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer TextureBuf { Texture t[]; };

// Addresses of the uploaded scene, in leaf order (see bvh.h).
struct SceneRefs {
    uint64_t nodes;     // Node[]
    uint64_t tri_pos;   // float[9] per triangle
    uint64_t tri_flags; // material index | PB_FLAG_ALPHA_MASK
    uint64_t tri_uv;    // float[6] per triangle
    uint64_t materials; // Material[]
    uint64_t textures;  // Texture[]
    uint64_t texels;    // RGBA8 words
    uint triangle_count;
    uint pad;
};

#endif
