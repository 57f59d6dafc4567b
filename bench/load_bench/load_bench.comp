#version 460
// load_bench: one way of reading 16-byte words (LOAD_KIND, -D at build time),
// in a dependent random walk over 64-byte records (4 words per step, as a
// BVH node), so each step's loads are divergent across lanes. Every kind
// reads the same bytes; the host checks that their sums agree.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_EXT_samplerless_texture_functions : require
#if LOAD_KIND == 2
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif

layout(local_size_x = 64) in;
layout(push_constant) uniform Push {
    uvec2 data;   // device address of the records
    uvec2 sums;   // device address of one uint per invocation
    uint records; // power of two
    uint steps;
} pc;

layout(set = 0, binding = 0) readonly buffer Words { uvec4 w[]; } ssbo;
// texture buffers without a sampler (a samplerBuffer makes glslang emit a
// sampled-image type that spirv-val warns about)
layout(set = 0, binding = 1) uniform utextureBuffer texel4;
layout(set = 0, binding = 2) uniform utextureBuffer texel1;
layout(set = 0, binding = 3, rgba32ui) uniform readonly restrict uimageBuffer image4;
// a uniform buffer holds 64 KiB (4,096 words) at most on lavapipe
// (maxUniformBufferRange): the host binds the first 64 KiB of the records
layout(set = 0, binding = 4, std140) uniform Uniforms { uvec4 w[4096]; } ubo;
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Ref4 { uvec4 v; };
#if LOAD_KIND == 2
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Ref64 { u64vec2 v; };
#endif
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer Sums { uint v[]; };

uvec4 word(uint i)
{
#if LOAD_KIND == 0 // storage buffer descriptor
    return ssbo.w[i];
#elif LOAD_KIND == 1 // buffer reference, 32-bit components (the portable kernels)
    uvec2 a = pc.data;
    uint lo = a.x + 16u * i;
    return Ref4(uvec2(lo, a.y + (lo < a.x ? 1u : 0u))).v;
#elif LOAD_KIND == 2 // buffer reference, 64-bit components (the native64 kernels)
    u64vec2 v = Ref64(packUint2x32(pc.data) + 16ul * uint64_t(i)).v;
    return uvec4(unpackUint2x32(v.x), unpackUint2x32(v.y));
#elif LOAD_KIND == 3 // uniform texel buffer, rgba32ui
    return texelFetch(texel4, int(i));
#elif LOAD_KIND == 4 // uniform texel buffer, r32ui, four fetches
    int j = 4 * int(i);
    return uvec4(texelFetch(texel1, j).x, texelFetch(texel1, j + 1).x, texelFetch(texel1, j + 2).x,
                 texelFetch(texel1, j + 3).x);
#elif LOAD_KIND == 5 // storage texel buffer, rgba32ui (the kernels' texel loads)
    return imageLoad(image4, int(i));
#else // uniform buffer: llvmpipe loads each lane's word unmasked, inline, no call
    return ubo.w[i];
#endif
}

uint hash(uint x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    return x ^ (x >> 16);
}

void main()
{
    uint rec = hash(gl_GlobalInvocationID.x) & (pc.records - 1u), sum = 0u;
    for (uint s = 0u; s < pc.steps; ++s) {
        uint b = 4u * rec;
        uvec4 v = word(b) ^ word(b + 1u) ^ word(b + 2u) ^ word(b + 3u);
        sum += v.x + v.w;
        rec = (v.x ^ v.y ^ v.z ^ v.w ^ s) & (pc.records - 1u);
    }
    Sums(pc.sums).v[gl_GlobalInvocationID.x] = sum;
}
