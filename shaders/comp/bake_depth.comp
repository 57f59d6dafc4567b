#version 460
// bake_depth: one invocation per (probe, octahedral texel). Mean distance and
// mean squared distance of this pass's rays around the texel's direction,
// weighted by max(0, cos)^lobe_power (a cosine-power lobe: the filter DDGI
// uses for visibility), misses at max_distance. Output: 2 floats per texel
// at reduced[32 * probe_count + 2 * (n*n * probe_in_submission + texel)].
// CPU reference: pb_bake_depth_cpu (src/bake/bake_cpu.c).
#extension GL_GOOGLE_include_directive : require

#include "bake.glsl"
#include "octahedral.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    uint64_t params;
} pc;

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    uint texels = P.octmap_res * P.octmap_res;
    uint i = gl_GlobalInvocationID.x;
    if (i >= P.probe_count * texels)
        return;
    uint local = i / texels, texel = i % texels;
    uint probe = P.first_probe + local;
    vec3 td = oct_texel_direction(texel % P.octmap_res, texel / P.octmap_res, P.octmap_res);
    Vec4Buf rays = Vec4Buf(P.rays);
    float wsum = 0.0, m1 = 0.0, m2 = 0.0;
    for (uint r = 0u; r < P.rays_per_probe; ++r) {
        vec3 d = probe_ray_direction(P, probe, r);
        float c = td.x * d.x + td.y * d.y + td.z * d.z;
        if (c <= 0.0)
            continue;
        float w = pow(c, P.lobe_power);
        float dist = min(abs(rays.v[local * P.rays_per_probe + r].w), P.max_distance);
        wsum += w;
        m1 += w * dist;
        m2 += w * dist * dist;
    }
    FloatRW out_ = FloatRW(P.reduced);
    uint base = 32u * P.probe_count + 2u * i;
    out_.v[base] = wsum > 0.0 ? m1 / wsum : P.max_distance;
    out_.v[base + 1u] = wsum > 0.0 ? m2 / wsum : P.max_distance * P.max_distance;
}
