// Scene data as the kernels see it: every array is a buffer reference (a
// device address in push constants), so no binding range limits its size.
// Mirrors src/bake/gpu_scene.h (C structs with _Static_assert on layout).
#ifndef PB_SCENE_GLSL
#define PB_SCENE_GLSL

#include "address.glsl"

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

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer FloatBuf { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer UintBuf { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer MaterialBuf { Material m[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer TextureBuf { Texture t[]; };

// Nodes and triangles are read as 64-bit words: half as many load
// instructions as 32-bit components. On GPUs this is the same bytes in wider
// transactions; on lavapipe, which gathers every load component separately,
// a 64-bit component is one gather where a uvec2 is two (7 % faster on The
// Crypt). So kernels are built twice (CMakeLists.txt): PB_NATIVE64 for
// devices with shaderInt64 and shaderFloat64, and a portable variant.
#ifdef PB_NATIVE64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer Words64 { uint64_t v[]; };
#define PB_WORD(w, i) unpack32((w).v[i])
#else
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer Words64 { uvec2 v[]; };
#define PB_WORD(w, i) ((w).v[i])
#endif

vec2 unpack_float2(uvec2 w)
{
    return uintBitsToFloat(w);
}

Node load_node(pb_addr base, uint index)
{
    Words64 w = Words64(base);
    uint b = 8u * index;
    vec2 x0 = unpack_float2(PB_WORD(w, b + 0u)), x1 = unpack_float2(PB_WORD(w, b + 1u));
    vec2 y0 = unpack_float2(PB_WORD(w, b + 2u)), y1 = unpack_float2(PB_WORD(w, b + 3u));
    vec2 z0 = unpack_float2(PB_WORD(w, b + 4u)), z1 = unpack_float2(PB_WORD(w, b + 5u));
    uvec2 ch = PB_WORD(w, b + 6u), ct = PB_WORD(w, b + 7u);
    Node n;
    n.x = vec4(x0, x1);
    n.y = vec4(y0, y1);
    n.z = vec4(z0, z1);
    n.c = ivec4(ch, ct);
    return n;
}

// Leaf-ordered triangle record: 10 words, v0 v1 v2 (9 floats) then flags.
struct Tri {
    vec3 v0, v1, v2;
    uint flags;
};

Tri load_tri(pb_addr base, uint index)
{
    Words64 w = Words64(base);
    uint b = 5u * index;
    vec2 a = unpack_float2(PB_WORD(w, b + 0u));   // v0.x v0.y
    vec2 c = unpack_float2(PB_WORD(w, b + 1u));   // v0.z v1.x
    vec2 d = unpack_float2(PB_WORD(w, b + 2u));   // v1.y v1.z
    vec2 e = unpack_float2(PB_WORD(w, b + 3u));   // v2.x v2.y
    uvec2 f = PB_WORD(w, b + 4u);      // v2.z, flags
    Tri t;
    t.v0 = vec3(a, c.x);
    t.v1 = vec3(c.y, d);
    t.v2 = vec3(e, uintBitsToFloat(f.x));
    t.flags = f.y;
    return t;
}

// Addresses of the uploaded scene, in leaf order (see bvh.h).
struct SceneRefs {
    pb_addr nodes;     // Node[]
    pb_addr tris;      // 10 words per triangle: 9 position floats, flags (material | PB_FLAG_ALPHA_MASK)
    pb_addr tri_uv;    // float[6] per triangle
    pb_addr materials; // Material[]
    pb_addr textures;  // Texture[]
    pb_addr texels;    // RGBA8 words
    uint triangle_count;
    uint pad;
};

#endif
