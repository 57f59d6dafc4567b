#version 460
// bake_depth: mean distance and mean squared distance of this pass's rays
// around each octahedral texel's direction, weighted by max(0, cos)^power (a
// cosine-power lobe, the filter DDGI uses for visibility; rays below the
// cutoff weight are skipped), misses at max_distance. One invocation per
// texel; workgroup (x, y) covers texels [64x, 64x + 64) of probe y.
//
// The lobe test runs in the probe's unrotated frame: the texel's direction
// is turned back by the probe's rotation, and only the rays on the list of
// the query cell holding it are visited (src/bake/depth_lists.h: every ray
// that can pass the cutoff is on it, in ascending order), about an eighth of
// the rays at the default power instead of all of them.
// CPU reference: pb_bake_depth_cpu (src/bake/bake_cpu.c), over all rays.
// Output: the pass's 2 moments per texel added to the probe slot's sums, 2 floats per texel, in the
// slot's block (src/bake/depth_sums.h), which hold the sums over the passes on the device (pass 0
// stores): the host reads them once, after the last pass, where it used to add every submission's
// moments into 4 KiB of fresh doubles per probe.
#extension GL_GOOGLE_include_directive : require

#include "bake.glsl"
#include "octahedral.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    pb_addr params;
} pc;

// The query cell holding d (pb_depth_query_cell); the octahedral encoding is
// the run-time sampler's (probe_sample_core.glsl, included by bake.glsl).
uint depth_query_cell(vec3 d, uint res)
{
    vec2 uv = pb_oct_encode(d);
    float fx = floor((uv.x * 0.5 + 0.5) * float(res)), fy = floor((uv.y * 0.5 + 0.5) * float(res));
    uint cx = fx < 0.0 ? 0u : (fx >= float(res) ? res - 1u : uint(fx));
    uint cy = fy < 0.0 ? 0u : (fy >= float(res) ? res - 1u : uint(fy));
    return cy * res + cx;
}

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    uint texels = P.octmap_res * P.octmap_res;
    uint local = gl_WorkGroupID.y;
    uint texel = gl_WorkGroupID.x * 64u + gl_LocalInvocationID.x;
    if (texel >= texels)
        return;
    uint probe = probe_slot(P, local);
    vec3 td = oct_texel_direction(texel % P.octmap_res, texel / P.octmap_res, P.octmap_res);
    // R^T td (pb_depth_unrotate): the rows of the probe's rotation, weighted
    Vec4Buf rot = Vec4Buf(P.rotations);
    vec3 r0 = rot.v[3u * probe].xyz, r1 = rot.v[3u * probe + 1u].xyz, r2 = rot.v[3u * probe + 2u].xyz;
    precise vec3 tl;
    for (int k = 0; k < 3; ++k)
        tl[k] = (r0[k] * td.x + r1[k] * td.y) + r2[k] * td.z;
    UintBuf lists = UintBuf(P.depth_lists);
    uint res = lists.v[0];
    uint cell = depth_query_cell(tl, res);
    uint first = lists.v[1u + cell], end = lists.v[2u + cell], base = 2u + res * res;
    Vec4Buf dirs = Vec4Buf(P.directions), rays = Vec4Buf(P.rays);
    uint ray0 = local * P.rays_per_probe;
    float wsum = 0.0, m1 = 0.0, m2 = 0.0;
    for (uint k = first; k < end; ++k) {
        uint r = lists.v[base + k];
        vec3 s = dirs.v[r].xyz;
        precise float c = (tl.x * s.x + tl.y * s.y) + tl.z * s.z;
        if (c <= P.lobe_cutoff)
            continue; // weight below cutoff^power: negligible (pb_depth_lobe_cutoff)
        float w = pow(c, P.lobe_power);
        float dist = min(abs(rays.v[ray0 + r].w), P.max_distance);
        wsum += w;
        m1 += w * dist;
        m2 += w * dist * dist;
    }
    float d1 = wsum > 0.0 ? m1 / wsum : P.max_distance;
    float d2 = wsum > 0.0 ? m2 / wsum : P.max_distance * P.max_distance;
    // the slot's block of sums (one unless the device's allocations are too small for all)
    uint block = probe / P.depth_block_probes;
    UintBuf table = UintBuf(P.depth_sum);
    FloatRW sums = FloatRW(uvec2(table.v[2u * block], table.v[2u * block + 1u]));
    uint at = 2u * (texels * (probe - block * P.depth_block_probes) + texel); // written by this invocation only
    if (P.pass_index != 0u) {
        d1 += sums.v[at];
        d2 += sums.v[at + 1u];
    }
    sums.v[at] = d1;
    sums.v[at + 1u] = d2;
}
