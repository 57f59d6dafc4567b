// Scene data as the kernels see it: every array is a buffer reference (a
// device address in push constants), so no binding range limits its size.
// Mirrors src/bake/gpu_scene.h (C structs with _Static_assert on layout).
#ifndef PB_SCENE_GLSL
#define PB_SCENE_GLSL

#include "address.glsl"
#include "octahedral.glsl"

#define PB_NO_HIT 0xffffffffu
#define PB_FLAG_ALPHA_MASK 0x80000000u
#define PB_SCENE_VERTEX_COLORS 1u
#define PB_SCENE_SHADING_NORMALS 2u
#define PB_SCENE_TRANSMISSION 4u
#define PB_SCENE_NORMAL_MAPS 8u
#define PB_SCENE_TANGENTS 16u
#define PB_INF uintBitsToFloat(0x7f800000u)

// 4-wide quantized BVH node (include/probebake/bvh.h), decoded: child i's
// box on axis a is origin[a] + q[a][i] * scale[a], q from qlo / qhi.
struct Node4 {
    vec3 origin;
    vec3 scale;
    vec4 qlo[3];
    vec4 qhi[3];
    uvec4 child;  // a leaf's first triangle, an inner child's rank among the inner children
    uvec4 count;  // a leaf's triangles; 0 for an inner or unused slot
    uint first;   // the first inner child's node index
    uint used;    // used slots (they come first)
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

// How the traversal reads nodes and triangles (specialisation constant 1 of
// every kernel that includes this file; 0 is traverse.glsl's STACK_SIZE):
// through buffer references, or (1) as 16-byte texels of two storage texel
// buffers, set 0 bindings 0 and 1, over the same bytes. llvmpipe on AVX2
// lowers a divergent buffer load to one masked scalar load per lane and
// 32/64-bit component, but an image load to one unmasked load per lane and
// texel: 1.18-1.37x the trace rate there (bench/RESULTS.md). The host picks
// per device (PB_SCENE_LOADS_*); both give the same words, so the same hits.
layout(constant_id = 1) const uint PB_SCENE_TEXELS = 0u;
layout(set = 0, binding = 0, rgba32ui) uniform readonly restrict uimageBuffer pb_node_texels;
layout(set = 0, binding = 1, rgba32ui) uniform readonly restrict uimageBuffer pb_tri_texels;

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

vec4 unpack_bytes(uint w)
{
    return vec4((uvec4(w) >> uvec4(0u, 8u, 16u, 24u)) & 0xffu);
}

// A node's six 64-bit words (include/probebake/bvh.h): origin.xy |
// origin.z, scale exponents, slot codes 0-7 | q[0] | q[1] | q[2] | first
// inner child, slot codes 8-15; first leaf triangle, slot codes 16-19.
// Each slot code (5 bits) is 0 for an empty slot, 31 for an inner child,
// else a leaf's triangle count; a node's inner children, and its leaves'
// triangles, are consecutive in slot order, so an inner child is named by
// its rank and a leaf by its first triangle. As C's pb_bvh4_slots.
Node4 load_node4(pb_addr base, uint index)
{
    uvec2 wd[6];
    if (PB_SCENE_TEXELS != 0u) {
        int b = 3 * int(index);
        for (int i = 0; i < 3; ++i) {
            uvec4 x = imageLoad(pb_node_texels, b + i);
            wd[2 * i] = x.xy;
            wd[2 * i + 1] = x.zw;
        }
    } else {
        Words64 w = Words64(base);
        for (uint i = 0u; i < 6u; ++i)
            wd[i] = PB_WORD(w, 6u * index + i);
    }
    Node4 n;
    n.origin = vec3(uintBitsToFloat(wd[0]), uintBitsToFloat(wd[1].x));
    n.scale = uintBitsToFloat(((uvec3(wd[1].y) >> uvec3(0u, 8u, 16u)) & 0xffu) << 23u);
    for (uint a = 0u; a < 3u; ++a) {
        n.qlo[a] = unpack_bytes(wd[2u + a].x);
        n.qhi[a] = unpack_bytes(wd[2u + a].y);
    }
    uint codes = wd[1].y >> 24u | (wd[5].x >> 24u) << 8u | (wd[5].y >> 28u) << 16u;
    uint rank = 0u, leaf = wd[5].y & 0xfffffffu;
    n.first = wd[5].x & 0xffffffu;
    n.used = 0u;
    for (int i = 0; i < 4; ++i) {
        uint c = (codes >> (5u * uint(i))) & 31u;
        n.count[i] = c == 31u ? 0u : c;
        n.child[i] = c == 31u ? rank : leaf;
        rank += c == 31u ? 1u : 0u;
        leaf += n.count[i];
        n.used += c != 0u ? 1u : 0u;
    }
    return n;
}

// Leaf-ordered triangle record: 10 words, v0 v1 v2 (9 floats) then flags.
struct Tri {
    vec3 v0, v1, v2;
    uint flags;
};

// As texels, record `index` starts at texel 2.5 * index: the three texels
// from texel (5 * index) / 2 hold it, from their first 64-bit word (even
// index) or their second (odd). The host pads the array by one texel.
Tri load_tri(pb_addr base, uint index)
{
    uvec2 wd[5];
    if (PB_SCENE_TEXELS != 0u) {
        int b = int((5u * index) >> 1u);
        uvec4 x = imageLoad(pb_tri_texels, b), y = imageLoad(pb_tri_texels, b + 1), z = imageLoad(pb_tri_texels, b + 2);
        bool odd = (index & 1u) != 0u;
        wd[0] = odd ? x.zw : x.xy;
        wd[1] = odd ? y.xy : x.zw;
        wd[2] = odd ? y.zw : y.xy;
        wd[3] = odd ? z.xy : y.zw;
        wd[4] = odd ? z.zw : z.xy;
    } else {
        Words64 w = Words64(base);
        for (uint i = 0u; i < 5u; ++i)
            wd[i] = PB_WORD(w, 5u * index + i);
    }
    vec2 a = unpack_float2(wd[0]);   // v0.x v0.y
    vec2 c = unpack_float2(wd[1]);   // v0.z v1.x
    vec2 d = unpack_float2(wd[2]);   // v1.y v1.z
    vec2 e = unpack_float2(wd[3]);   // v2.x v2.y
    uvec2 f = wd[4];                 // v2.z, flags
    Tri t;
    t.v0 = vec3(a, c.x);
    t.v1 = vec3(c.y, d);
    t.v2 = vec3(e, uintBitsToFloat(f.x));
    t.flags = f.y;
    return t;
}

// Addresses of the uploaded scene, in leaf order (see bvh.h).
struct SceneRefs {
    pb_addr nodes;     // Node4[] (48 bytes each)
    pb_addr tris;      // 10 words per triangle: 9 position floats, flags (material | PB_FLAG_ALPHA_MASK)
    pb_addr tri_uv;    // float[6] per triangle; then, with PB_SCENE_VERTEX_COLORS, float[12] per triangle (RGBA per corner);
                       // then, with PB_SCENE_SHADING_NORMALS, uint[3] per triangle (vertex normals, 16-bit octahedral);
                       // then, with PB_SCENE_TANGENTS, uint[4] per triangle (the file's tangents: normal_map.glsl)
    pb_addr materials; // Material[]
    pb_addr textures;  // Texture[]
    pb_addr texels;    // RGBA8 words
    uint triangle_count;
    uint flags;        // PB_SCENE_*
};

// A triangle's texture coordinates, corner by corner.
struct TriUV {
    vec2 c0, c1, c2;
};

TriUV load_tri_uv(SceneRefs s, uint tri)
{
    FloatBuf uv = FloatBuf(s.tri_uv);
    uint b = 6u * tri;
    return TriUV(vec2(uv.v[b], uv.v[b + 1u]), vec2(uv.v[b + 2u], uv.v[b + 3u]), vec2(uv.v[b + 4u], uv.v[b + 5u]));
}

vec2 interpolate_uv(TriUV c, float u, float v)
{
    precise float w0 = 1.0 - u - v;
    precise float ts = w0 * c.c0.x + u * c.c1.x + v * c.c2.x;
    precise float tt = w0 * c.c0.y + u * c.c1.y + v * c.c2.y;
    return vec2(ts, tt);
}

// Texture coordinates of leaf-ordered triangle `tri` at barycentrics (u, v),
// in the CPU reference's order (bake_cpu.c, alpha.h), unfused. Shading and
// the alpha test call it only where a texture reads them: on lavapipe each of
// these six loads is a branch per SIMD lane, skipped when no lane needs it.
vec2 surface_uv(SceneRefs s, uint tri, float u, float v)
{
    return interpolate_uv(load_tri_uv(s, tri), u, v);
}

// Vertex colour (glTF COLOR_0) of leaf-ordered triangle `tri` at (u, v):
// linear RGBA, white when the scene has none (src/scene/vertex_color.h is
// the CPU reference, same arithmetic in the same order).
vec4 vertex_color(SceneRefs s, uint tri, float u, float v)
{
    if ((s.flags & PB_SCENE_VERTEX_COLORS) == 0u)
        return vec4(1.0);
    FloatBuf c = FloatBuf(s.tri_uv);
    uint b = 6u * s.triangle_count + 12u * tri;
    precise float w0 = 1.0 - u - v;
    precise vec4 r = w0 * vec4(c.v[b], c.v[b + 1u], c.v[b + 2u], c.v[b + 3u]) +
                     u * vec4(c.v[b + 4u], c.v[b + 5u], c.v[b + 6u], c.v[b + 7u]) +
                     v * vec4(c.v[b + 8u], c.v[b + 9u], c.v[b + 10u], c.v[b + 11u]);
    return r;
}

// Shading normal of leaf-ordered triangle `tri` at (u, v): its vertex
// normals (packed as two snorm16 octahedral coordinates) interpolated and
// normalized, turned to the side of ng (the geometric normal, facing the
// ray's origin); ng where they cancel. pb_shading_normal_cpu
// (src/bake/shading_normals.c) is the CPU reference, same arithmetic.
vec3 shading_normal(SceneRefs s, uint tri, float u, float v, vec3 ng)
{
    UintBuf w = UintBuf(s.tri_uv);
    uint b = ((s.flags & PB_SCENE_VERTEX_COLORS) != 0u ? 18u : 6u) * s.triangle_count + 3u * tri;
    vec3 n0 = oct_decode(unpackSnorm2x16(w.v[b]));
    vec3 n1 = oct_decode(unpackSnorm2x16(w.v[b + 1u]));
    vec3 n2 = oct_decode(unpackSnorm2x16(w.v[b + 2u]));
    precise float w0 = 1.0 - u - v;
    precise vec3 n = w0 * n0 + u * n1 + v * n2;
    float l = length(n);
    if (!(l > 1e-6))
        return ng;
    return (dot(n, ng) < 0.0 ? -n : n) / l;
}

#endif
