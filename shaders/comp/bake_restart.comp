#version 460
// bake_restart (--schedule restart): bake_trace's paths, K to an invocation.
// A lane of bake_trace idles from the end of its path until the longest path
// of its lane group ends; here a lane begins its next path as soon as its last
// one ends, so its group waits only at the end of K paths. The same paths,
// random numbers and results as bake_trace, bit for bit (test_bake); what
// differs is only which invocation traces which path, and that lanes leave
// step with one another (bench/RESULTS.md, "Restarts built"; docs/bake.md, "Schedules").
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
    uint n = P.probe_count * P.rays_per_probe, K = pc.paths_per_lane, long_paths = 0u;
    bool first_hit_only = P.pass_index >= PB_RELOCATION_PASS, see_direct = P.direct != 0u;
    bool nee = bake_feature(PB_FEATURE_PROBE_NEE) && !addr_null(P.nee);
    // One loop over all K paths, one ray per iteration: a lane whose path
    // ends begins its next in the next iteration. (A loop per path would
    // keep the lanes in step: each would wait at its end for the group's
    // longest path, as bake_trace's do.)
    uint k = 0u, i = 0u, state = 0u;
    vec3 d = vec3(0.0);
    PathState ps;
    bool live = false;
    for (;;) {
        if (!live) {
            i = k < K ? restart_path(wg, lid, k) : n;
            if (i >= n)
                break; // later paths of this lane are further on
            ++k;
            uint probe = probe_slot(P, i / P.rays_per_probe), ray = i % P.rays_per_probe;
            d = probe_ray_direction(P, probe, ray);
            state = rng_seed(P.seed, probe_id(P, probe), P.pass_index, ray);
            ps = path_begin(Vec4Buf(P.probes).v[probe].xyz, d);
            live = true;
        }
        if (!path_step(P, ps, P.bounces, see_direct, first_hit_only, state)) {
            store_probe_ray(P, i, d, ps.res);
            if (nee) // its light sample is drawn after the loop, from where the path left the random numbers
                UintRW(P.nee).v[8u * i] = state;
            // llvmpipe's loop cap counts every loop iteration of an invocation,
            // so its later paths are the ones at risk (bake_trace counts the same)
            long_paths += pb_loop_steps > 32768u ? 1u : 0u;
            live = false;
        }
    }
    // Probe NEE's shadow rays, the lanes in step: traced inside the loop, each
    // would stall the lanes whose paths go on.
    for (uint j = 0u; nee && j < k; ++j) {
        uint at = restart_path(wg, lid, j), s = UintRW(P.nee).v[8u * at];
        store_probe_nee(P, at, Vec4Buf(P.probes).v[probe_slot(P, at / P.rays_per_probe)].xyz, s);
    }
    if (!addr_null(P.counters)) {
        atomicAdd(UintRW(P.counters).v[0], pb_traversals);
        if (long_paths > 0u)
            atomicAdd(UintRW(P.counters).v[1], long_paths);
    }
}
