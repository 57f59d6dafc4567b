#version 460
// bake_wave: a bake pass's paths as a wavefront (--schedule wavefront;
// docs/bake.md, "Schedules"). The paths of a submission keep their state in
// memory between dispatches (PathState, path.glsl) and wait in queues by the
// kind of their next ray. Each step dispatch takes one queue and traces one
// ray of each path in it with path_step, so a lane group traces only
// closest-hit rays (probe and bounce rays) or only shadow rays, and no lane
// idles on a finished path. The random numbers and the arithmetic are
// bake_trace's: the same outputs, bit for bit.
//   mode 0 (begin): one invocation per path: its state, queued as a closest hit
//   mode 1 (size):  one invocation: the dispatch size of queue in_q; queue zero_q emptied
//   mode 2 (step):  one invocation per path of queue in_q (dispatched indirectly)
// CPU reference: pb_bake_trace_cpu (src/bake/bake_cpu.c), as for bake_trace.
#extension GL_GOOGLE_include_directive : require

#define PB_COUNT_TRAVERSALS
#include "path.glsl"

layout(local_size_x = 64) in;

// wave_push in src/bake/bake_types.h
layout(push_constant) uniform Push {
    pb_addr params;
    pb_addr wave;  // WaveBuf
    pb_addr paths; // PB_WAVE_VEC4 vec4 then PB_WAVE_UVEC4 uvec4 per path, each array `capacity` long
    uint mode;
    uint in_q;
    uint out_c;    // the queue of paths whose next ray is a closest hit
    uint out_s;    // and of those whose next ray is a shadow ray
    uint zero_q;
    uint capacity;
} pc;

// The queues: 0-1 closest-hit rays, 2-3 shadow rays (src/bake/stages/wave.c).
layout(buffer_reference, std430, buffer_reference_align = 16) buffer WaveBuf {
    uint count[4];
    uvec4 size;    // vkCmdDispatchIndirect's (x, y, z) at byte 16
    uint q[];      // 4 queues of `capacity` path indices
};
layout(buffer_reference, std430, buffer_reference_align = 16) buffer UVec4RW { uvec4 v[]; };

#define PB_RAY_PROBE 3u // probe NEE's shadow ray, traced after the path (bake_trace's probe_light_nee)

// A path's state between steps: only what path_step reads later. The bake
// reads neither L_direct nor L_seen; o equals x wherever path_step reads it
// (a bounce ray leaves from the last hit; the probe ray from the probe,
// where path_begin puts x too); the bounce direction and the shadow ray's
// share a slot, as a step reads only its own ray's. res.x, n and albedo
// only for --indirect volume, beyond and past only for thin glass.
// PB_WAVE_PATH_VEC4 in src/bake/bake_types.h is their sum.
#define PB_WAVE_VEC4 14u
#define PB_WAVE_UVEC4 2u

// The paths' integer words, after the float ones (64-bit address arithmetic in 32-bit words).
UVec4RW path_words()
{
    uint off = PB_WAVE_VEC4 * 16u * pc.capacity, lo = pc.paths.x + off;
    return UVec4RW(uvec2(lo, pc.paths.y + (lo < off ? 1u : 0u)));
}

void store_path(uint i, PathState ps, uint rng, uint traversals)
{
    Vec4RW f = Vec4RW(pc.paths);
    uint c = pc.capacity;
    bool shadow = ps.ray.x != PB_RAY_BOUNCE;
    f.v[0u * c + i] = vec4(ps.res.L, ps.res.first_t);
    f.v[1u * c + i] = vec4(ps.x, ps.bsdf_pdf);
    f.v[2u * c + i] = vec4(ps.throughput, ps.sr.tmax);
    f.v[3u * c + i] = vec4(ps.ng, 0.0);
    f.v[4u * c + i] = vec4(ps.ns, 0.0);
    f.v[5u * c + i] = vec4(ps.albedo, 0.0);
    f.v[6u * c + i] = vec4(ps.E, 0.0);
    f.v[7u * c + i] = vec4(ps.c, 0.0);
    f.v[8u * c + i] = vec4(shadow ? ps.sr.w : ps.dir, 0.0);
    f.v[9u * c + i] = vec4(ps.sr.L, 0.0);
    if (bake_feature(PB_FEATURE_VOLUME)) {
        f.v[10u * c + i] = vec4(ps.res.x, 0.0);
        f.v[11u * c + i] = vec4(ps.res.n, 0.0);
        f.v[12u * c + i] = vec4(ps.res.albedo, 0.0);
    }
    if (bake_feature(PB_FEATURE_TRANSMISSION))
        f.v[13u * c + i] = vec4(ps.beyond, ps.past);
    UVec4RW u = path_words();
    u.v[0u * c + i] = uvec4(ps.ray.x | ps.ray.y << 8u | (ps.res.shade ? 1u << 16u : 0u), ps.bounce, ps.light,
                            uint(ps.ge));
    u.v[1u * c + i] = uvec4(rng, traversals, ps.layers, 0u);
}

PathState load_path(uint i, out uint rng, out uint traversals)
{
    Vec4RW f = Vec4RW(pc.paths);
    uint c = pc.capacity;
    PathState ps;
    vec4 a;
    a = f.v[0u * c + i], ps.res.L = a.xyz, ps.res.first_t = a.w;
    a = f.v[1u * c + i], ps.x = a.xyz, ps.bsdf_pdf = a.w;
    a = f.v[2u * c + i], ps.throughput = a.xyz, ps.sr.tmax = a.w;
    ps.ng = f.v[3u * c + i].xyz;
    ps.ns = f.v[4u * c + i].xyz;
    ps.albedo = f.v[5u * c + i].xyz;
    ps.E = f.v[6u * c + i].xyz;
    ps.c = f.v[7u * c + i].xyz;
    ps.dir = f.v[8u * c + i].xyz;
    ps.sr.w = ps.dir;
    ps.sr.L = f.v[9u * c + i].xyz;
    ps.o = ps.x;
    ps.res.L_direct = vec3(0.0);
    ps.res.L_seen = vec3(0.0);
    ps.res.x = vec3(0.0), ps.res.n = vec3(0.0, 1.0, 0.0), ps.res.albedo = vec3(0.0);
    if (bake_feature(PB_FEATURE_VOLUME)) {
        ps.res.x = f.v[10u * c + i].xyz;
        ps.res.n = f.v[11u * c + i].xyz;
        ps.res.albedo = f.v[12u * c + i].xyz;
    }
    ps.beyond = vec3(0.0), ps.past = 0.0;
    if (bake_feature(PB_FEATURE_TRANSMISSION))
        a = f.v[13u * c + i], ps.beyond = a.xyz, ps.past = a.w;
    UVec4RW u = path_words();
    uvec4 w0 = u.v[0u * c + i], w1 = u.v[1u * c + i];
    ps.ray = uvec2(w0.x & 255u, (w0.x >> 8u) & 255u);
    ps.res.shade = (w0.x & (1u << 16u)) != 0u;
    ps.bounce = w0.y, ps.light = w0.z, ps.ge = int(w0.w);
    rng = w1.x, traversals = w1.y, ps.layers = w1.z;
    return ps;
}

// bake_trace's tail once path i is done: the --indirect volume's light at
// the first hit, the ray's radiance and depth, and probe NEE's light sample,
// whose shadow ray is then the path's next (true). x holds the probe, E the
// transmittance so far, bsdf_pdf the sample's factor.
bool finish_path(BakeParams P, uint i, inout PathState ps, inout uint state)
{
    uint probe = probe_slot(P, i / P.rays_per_probe);
    vec3 origin = Vec4Buf(P.probes).v[probe].xyz;
    store_probe_ray(P, i, probe_ray_direction(P, probe, i % P.rays_per_probe), ps.res);
    if (!bake_feature(PB_FEATURE_PROBE_NEE) || addr_null(P.nee))
        return false;
    vec4 nr[2] = vec4[2](vec4(0.0), vec4(0.0, 1.0, 0.0, 0.0));
    vec3 w, L;
    float tmax, k;
    bool sampled = P.direct != 0u && (bake_emitters(P) || bake_env(P).count > 0u) &&
                   probe_nee_sample(P, origin, state, w, L, tmax, k);
    if (sampled) {
        nr[1] = vec4(w, 0.0);
        ps.ray.x = PB_RAY_PROBE;
        ps.x = origin, ps.sr.w = w, ps.sr.L = L, ps.sr.tmax = tmax, ps.bsdf_pdf = k;
        ps.E = vec3(1.0), ps.layers = 0u;
    }
    Vec4RW(P.nee).v[2u * i] = nr[0];
    Vec4RW(P.nee).v[2u * i + 1u] = nr[1];
    return sampled;
}

// One layer of probe NEE's shadow ray (shadow_layer, as probe_light_nee's
// shadow_transmittance takes it); true while it goes on through thin glass.
bool probe_ray_step(BakeParams P, uint i, inout PathState ps)
{
    vec3 x = ps.layers != 0u ? ps.beyond : ps.x;
    if (shadow_layer(P, x, ps.sr.w, ps.sr.tmax, ps.E, ps.layers)) {
        ps.beyond = x;
        ++ps.layers;
        return true;
    }
    if (ps.E != vec3(0.0))
        Vec4RW(P.nee).v[2u * i] = vec4(ps.sr.L * ps.E * ps.bsdf_pdf, 0.0);
    return false;
}

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    WaveBuf W = WaveBuf(pc.wave);
    uint k = gl_GlobalInvocationID.x;
    if (pc.mode == 0u) {
        uint total = P.probe_count * P.rays_per_probe;
        if (k >= total)
            return;
        uint probe = probe_slot(P, k / P.rays_per_probe), ray = k % P.rays_per_probe;
        PathState ps = path_begin(Vec4Buf(P.probes).v[probe].xyz, probe_ray_direction(P, probe, ray));
        store_path(k, ps, rng_seed(P.seed, probe_id(P, probe), P.pass_index, ray), 0u);
        W.q[k] = k; // queue 0, in order
        if (k == 0u)
            W.count = uint[4](total, 0u, 0u, 0u);
        return;
    }
    if (pc.mode == 1u) {
        if (k == 0u) {
            W.size = uvec4((W.count[pc.in_q] + 63u) / 64u, 1u, 1u, 0u);
            W.count[pc.zero_q] = 0u;
        }
        return;
    }
    if (k >= W.count[pc.in_q])
        return;
    uint i = W.q[pc.in_q * pc.capacity + k];
    uint state, traversals;
    PathState ps = load_path(i, state, traversals);
    bool more;
    if (ps.ray.x == PB_RAY_PROBE) {
        more = probe_ray_step(P, i, ps);
    } else {
        more = path_step(P, ps, P.bounces, P.direct != 0u, false, state);
        if (!more)
            more = finish_path(P, i, ps, state);
    }
    traversals += pb_traversals;
    if (!more) {
        if (!addr_null(P.counters))
            atomicAdd(UintRW(P.counters).v[0], traversals);
        return;
    }
    store_path(i, ps, state, traversals);
    uint q = ps.ray.x == PB_RAY_BOUNCE ? pc.out_c : pc.out_s;
    W.q[q * pc.capacity + atomicAdd(W.count[q], 1u)] = i;
}
