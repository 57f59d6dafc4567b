#version 460
// bake_depth: mean distance and mean squared distance of this pass's rays
// around each octahedral texel's direction, weighted by max(0, cos)^power (a
// cosine-power lobe, the filter DDGI uses for visibility; rays below the
// cutoff weight are skipped), misses at max_distance. Workgroup (x, y) covers
// texels [64x, 64x + 64) of probe y: the probe's rays (direction, distance)
// are staged through shared memory 64 at a time, so each is loaded and
// rotated once per workgroup instead of once per texel; the sum still runs
// over rays in order, as in the CPU reference (pb_bake_depth_cpu).
// Output: 2 floats per texel at reduced[40 * probe_count + 2 * (n*n * probe_in_submission + texel)].
#extension GL_GOOGLE_include_directive : require

#include "bake.glsl"
#include "octahedral.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    pb_addr params;
} pc;

shared vec4 cached[64];

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    uint texels = P.octmap_res * P.octmap_res;
    uint local = gl_WorkGroupID.y, lane = gl_LocalInvocationID.x;
    uint texel = gl_WorkGroupID.x * 64u + lane;
    uint probe = probe_slot(P, local);
    bool in_tile = texel < texels;
    vec3 td = in_tile ? oct_texel_direction(texel % P.octmap_res, texel / P.octmap_res, P.octmap_res) : vec3(0, 0, 1);
    Vec4Buf rays = Vec4Buf(P.rays);
    float wsum = 0.0, m1 = 0.0, m2 = 0.0;
    for (uint base = 0u; base < P.rays_per_probe; base += 64u) {
        uint r = base + lane;
        if (r < P.rays_per_probe)
            cached[lane] = vec4(probe_ray_direction(P, probe, r),
                                min(abs(rays.v[local * P.rays_per_probe + r].w), P.max_distance));
        barrier();
        uint m = min(64u, P.rays_per_probe - base);
        for (uint j = 0u; j < m; ++j) {
            vec4 c4 = cached[j];
            precise float c = (td.x * c4.x + td.y * c4.y) + td.z * c4.z;
            if (c <= P.lobe_cutoff)
                continue; // weight below cutoff^power: negligible (pb_depth_lobe_cutoff)
            float w = pow(c, P.lobe_power);
            wsum += w;
            m1 += w * c4.w;
            m2 += w * c4.w * c4.w;
        }
        barrier();
    }
    if (!in_tile)
        return;
    FloatRW out_ = FloatRW(P.reduced);
    uint base_out = 40u * P.probe_count + 2u * (texels * local + texel);
    out_.v[base_out] = wsum > 0.0 ? m1 / wsum : P.max_distance;
    out_.v[base_out + 1u] = wsum > 0.0 ? m2 / wsum : P.max_distance * P.max_distance;
}
