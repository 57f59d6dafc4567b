#version 460
// bake_restart (--schedule restart): bake_trace's paths, K to an invocation.
// A lane of bake_trace idles from the end of its path until the longest path
// of its lane group ends; here a lane begins its next path as soon as its last
// one ends, so its group waits only at the end of K paths. The same paths,
// random numbers and results as bake_trace, bit for bit (test_bake); what
// differs is only which invocation traces which path, and that lanes leave
// step with one another (bench/RESULTS.md, "The bake's own rays replayed").
// CPU reference: pb_bake_trace_cpu (src/bake/bake_cpu.c).
#extension GL_GOOGLE_include_directive : require

#define PB_COUNT_TRAVERSALS
#include "path.glsl"
#include "dispatch_order.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    pb_addr params;
    uint spread;         // dispatch_order.glsl
    uint paths_per_lane; // K
    uint lane_group;     // w: a divisor of 64 (the device's subgroup size)
} pc;

// The k-th path of invocation `lid` of workgroup `wg`: a workgroup takes 64K
// consecutive paths; each run of w invocations takes w K of them and its
// lane l the paths l, l + w, l + 2w, ..., so that the group's k-th paths are
// w neighbouring rays of one probe, as a lane group's are in bake_trace.
uint restart_path(uint wg, uint lid, uint k)
{
    uint w = pc.lane_group, K = pc.paths_per_lane;
    return (wg * 64u + (lid / w) * w) * K + k * w + lid % w;
}

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    uint wg = spread_group(gl_WorkGroupID.x, gl_NumWorkGroups.x, pc.spread), lid = gl_LocalInvocationID.x;
    uint n = P.probe_count * P.rays_per_probe, long_paths = 0u;
    bool first_hit_only = P.pass_index >= PB_RELOCATION_PASS, see_direct = P.direct != 0u;
    for (uint k = 0u; k < pc.paths_per_lane; ++k) {
        uint i = restart_path(wg, lid, k);
        if (i >= n)
            break; // later paths of this lane are further on
        uint probe = probe_slot(P, i / P.rays_per_probe), ray = i % P.rays_per_probe;
        vec3 d = probe_ray_direction(P, probe, ray);
        vec3 origin = Vec4Buf(P.probes).v[probe].xyz;
        uint state = rng_seed(P.seed, probe_id(P, probe), P.pass_index, ray);
        PathResult pr = path_radiance(P, origin, d, P.bounces, see_direct, first_hit_only, state);
        store_probe_ray(P, i, d, pr);
        store_probe_nee(P, i, origin, state);
        // llvmpipe's loop cap counts every loop iteration of an invocation, so
        // its later paths are the ones at risk (bake_trace counts the same)
        long_paths += pb_loop_steps > 32768u ? 1u : 0u;
    }
    if (!addr_null(P.counters)) {
        atomicAdd(UintRW(P.counters).v[0], pb_traversals);
        if (long_paths > 0u)
            atomicAdd(UintRW(P.counters).v[1], long_paths);
    }
}
