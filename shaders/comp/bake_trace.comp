#version 460
// bake_trace: one invocation per probe ray of this pass. The ray leaves the
// probe along the spherical-Fibonacci direction turned by the probe's
// rotation for this pass, and returns the radiance arriving along it (path
// traced: emission, punctual lights, emitters and the environment with shadow rays, Lambertian bounces with
// Russian roulette after the second) and the distance to the first hit
// (negative on a back face; max_distance on a miss). Under probe NEE it also
// writes one light sample (emitter or environment) drawn from the probe
// (path.glsl).
// CPU reference: pb_bake_trace_cpu (src/bake/bake_cpu.c).
#extension GL_GOOGLE_include_directive : require

#define PB_COUNT_TRAVERSALS
#include "path.glsl"
#include "dispatch_order.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    pb_addr params;
    uint spread; // dispatch_order.glsl
} pc;

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    uint i = spread_group(gl_WorkGroupID.x, gl_NumWorkGroups.x, pc.spread) * 64u + gl_LocalInvocationID.x;
    if (i >= P.probe_count * P.rays_per_probe)
        return;
    uint probe = probe_slot(P, i / P.rays_per_probe), ray = i % P.rays_per_probe;
    vec3 d = probe_ray_direction(P, probe, ray);
    vec3 origin = Vec4Buf(P.probes).v[probe].xyz;
    uint state = rng_seed(P.seed, probe_id(P, probe), P.pass_index, ray);
    // a relocation pass reads only the first hits: no shading, no shadow or bounce rays
    PathResult pr = path_radiance(P, origin, d, P.bounces, P.direct != 0u, P.pass_index >= PB_RELOCATION_PASS, state);
    store_probe_ray(P, i, d, pr);
    store_probe_nee(P, i, origin, state);
    if (!addr_null(P.counters)) {
        atomicAdd(UintRW(P.counters).v[0], pb_traversals);
        // near llvmpipe's per-invocation loop cap (65535 iterations, triangle
        // loops included), where it silently cuts paths short: the host warns
        if (pb_loop_steps > 32768u)
            atomicAdd(UintRW(P.counters).v[1], 1u);
    }
}
