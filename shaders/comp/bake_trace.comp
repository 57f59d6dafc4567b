#version 460
// bake_trace: one invocation per probe ray of this pass. The ray leaves the
// probe along the spherical-Fibonacci direction turned by the probe's
// rotation for this pass, and returns the radiance arriving along it (path
// traced: emission, punctual lights with shadow rays, Lambertian bounces with
// Russian roulette after the second) and the distance to the first hit
// (negative on a back face; max_distance on a miss).
// CPU reference: pb_bake_trace_cpu (src/bake/bake_cpu.c).
#extension GL_GOOGLE_include_directive : require

#include "traverse.glsl"
#include "bake.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    uint64_t params;
} pc;

vec3 cosine_direction(vec3 n, float u1, float u2)
{
    // orthonormal basis (Duff et al. 2017) and Malley's method
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    vec3 bt = vec3(b, sgn + n.y * n.y * a, -n.y);
    float r = sqrt(u1), phi = 2.0 * PB_PI * u2;
    return normalize(t * (r * cos(phi)) + bt * (r * sin(phi)) + n * sqrt(max(0.0, 1.0 - u1)));
}

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    uint i = gl_GlobalInvocationID.x;
    if (i >= P.probe_count * P.rays_per_probe)
        return;
    uint probe = probe_slot(P, i / P.rays_per_probe), ray = i % P.rays_per_probe;
    vec3 d = probe_ray_direction(P, probe, ray);
    vec3 origin = Vec4Buf(P.probes).v[probe].xyz;
    uint state = rng_seed(P.seed, probe_id(P, probe), P.pass_index, ray);
    SceneRefs s = P.scene;
    ShadeMaterialBuf mats = ShadeMaterialBuf(P.materials);
    LightBuf lights = LightBuf(P.lights);

    vec3 L = vec3(0.0), throughput = vec3(1.0);
    float first_distance = P.max_distance;
    vec3 o = origin, dir = d;
    for (uint bounce = 0u;; ++bounce) {
        TraceResult tr = trace_ray(s, o, dir, 0.0, PB_INF, false);
        if (tr.tri == PB_NO_HIT) {
            if (bounce > 0u || P.direct != 0u)
                L += throughput * P.sky.rgb;
            break;
        }
        Tri t = load_tri(s.tris, tr.tri);
        vec3 e1 = t.v1 - t.v0, e2 = t.v2 - t.v0;
        vec3 ng = normalize(cross(e1, e2));
        bool back = dot(ng, dir) > 0.0;
        if (bounce == 0u)
            first_distance = back ? -min(tr.t, P.max_distance) : min(tr.t, P.max_distance);
        ShadeMaterial m = mats.m[t.flags & ~PB_FLAG_ALPHA_MASK];
        if (back) {
            if (m.tex.z == 0)
                break; // inside a single-sided surface: no light
            ng = -ng;
        }
        FloatBuf uvs = FloatBuf(s.tri_uv);
        uint b = 6u * tr.tri;
        float w0 = 1.0 - tr.u - tr.v;
        vec2 uv = w0 * vec2(uvs.v[b], uvs.v[b + 1u]) + tr.u * vec2(uvs.v[b + 2u], uvs.v[b + 3u]) +
                  tr.v * vec2(uvs.v[b + 4u], uvs.v[b + 5u]);
        if (bounce > 0u || P.direct != 0u)
            L += throughput * m.emissive_metallic.rgb * texture_rgb(s, m.tex.y, uv);
        vec3 albedo = m.base_color.rgb * texture_rgb(s, m.tex.x, uv) * (1.0 - m.emissive_metallic.w);
        vec3 x = offset_ray_origin(t.v0 + tr.u * e1 + tr.v * e2, ng);
        vec3 E = vec3(0.0);
        for (uint k = 0u; k < P.light_count; ++k)
            E += light_irradiance(s, lights.l[k], x, ng, true);
        L += throughput * albedo * (E / PB_PI);
        if (bounce >= P.bounces)
            break;
        if (bounce >= 1u) { // Russian roulette from the second reflection on
            float q = min(0.95, max(albedo.r, max(albedo.g, albedo.b)));
            if (rng_next(state) >= q)
                break;
            throughput /= q;
        }
        throughput *= albedo;
        if (max(throughput.r, max(throughput.g, throughput.b)) <= 0.0)
            break;
        float u1 = rng_next(state), u2 = rng_next(state);
        dir = cosine_direction(ng, u1, u2);
        o = x;
    }
    Vec4RW(P.rays).v[i] = vec4(L, first_distance);
}
