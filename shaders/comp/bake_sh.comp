#version 460
// bake_sh: one invocation per probe. Projects this pass's ray radiances onto
// SH L2 (weight 4pi / rays: the directions are uniform; under probe NEE the
// light sample each ray drew too, already divided by 4pi x its density),
// adds the punctual lights the probe sees directly as projected deltas
// (irradiance I/d^2 with a shadow ray from the probe; when direct light is
// included), and counts back faces and hits. Output per probe (PB_REDUCED_SH_STRIDE = 40 floats at
// reduced[40 * probe_in_submission]): 27 radiance coefficients, back-face
// count, hit count, then the nearest back-face hit (distance, direction) and
// the nearest front-face hit (distance, direction), which drive relocation;
// max_distance when there is none.
// CPU reference: pb_bake_sh_cpu (src/bake/bake_cpu.c).
#extension GL_GOOGLE_include_directive : require

#include "traverse.glsl"
#include "bake.glsl"
#include "sh.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    pb_addr params;
} pc;

void main()
{
    BakeParams P = BakeParamsBuf(pc.params).p;
    uint local = gl_GlobalInvocationID.x;
    if (local >= P.probe_count)
        return;
    uint probe = probe_slot(P, local);
    Vec4Buf rays = Vec4Buf(P.rays);
    float c[27];
    for (int k = 0; k < 27; ++k)
        c[k] = 0.0;
    float backfaces = 0.0, hits = 0.0;
    float back_t = P.max_distance, front_t = P.max_distance;
    vec3 back_d = vec3(0.0), front_d = vec3(0.0);
    float w = 4.0 * PB_PI / float(P.rays_per_probe);
    for (uint r = 0u; r < P.rays_per_probe; ++r) {
        vec3 d = probe_ray_direction(P, probe, r);
        vec4 o = rays.v[local * P.rays_per_probe + r];
        float y[9];
        sh_basis(d, y);
        for (int k = 0; k < 9; ++k) {
            c[3 * k] += w * o.r * y[k];
            c[3 * k + 1] += w * o.g * y[k];
            c[3 * k + 2] += w * o.b * y[k];
        }
        if (bake_feature(PB_FEATURE_PROBE_NEE) && !addr_null(P.nee)) { // probe NEE: the light sample drawn with this ray
            Vec4Buf nee = Vec4Buf(P.nee);
            uint j = 2u * (local * P.rays_per_probe + r);
            vec3 L = nee.v[j].rgb;
            sh_basis(nee.v[j + 1u].xyz, y);
            for (int k = 0; k < 9; ++k) {
                c[3 * k] += w * L.r * y[k];
                c[3 * k + 1] += w * L.g * y[k];
                c[3 * k + 2] += w * L.b * y[k];
            }
        }
        backfaces += o.w < 0.0 ? 1.0 : 0.0;
        hits += abs(o.w) < P.max_distance ? 1.0 : 0.0;
        if (o.w < 0.0 && -o.w < back_t) {
            back_t = -o.w;
            back_d = d;
        } else if (o.w >= 0.0 && o.w < front_t) {
            front_t = o.w;
            front_d = d;
        }
    }
    if (bake_feature(PB_FEATURE_LIGHTS) && P.direct != 0u) {
        vec3 x = Vec4Buf(P.probes).v[probe].xyz;
        LightBuf lights = LightBuf(P.lights);
        for (uint k = 0u; k < P.light_count; ++k) {
            Light l = lights.l[k];
            vec3 E = light_irradiance(P, l, x, vec3(0.0), false);
            if (E == vec3(0.0))
                continue;
            vec3 to_light = uint(l.position_type.w) == PB_LIGHT_DIRECTIONAL ? -l.direction_range.xyz
                                                                              : normalize(l.position_type.xyz - x);
            float y[9];
            sh_basis(to_light, y);
            for (int j = 0; j < 9; ++j) {
                c[3 * j] += E.r * y[j];
                c[3 * j + 1] += E.g * y[j];
                c[3 * j + 2] += E.b * y[j];
            }
        }
    }
    FloatRW out_ = FloatRW(P.reduced);
    uint base = 40u * local;
    for (int k = 0; k < 27; ++k)
        out_.v[base + uint(k)] = c[k];
    out_.v[base + 27u] = backfaces;
    out_.v[base + 28u] = hits;
    out_.v[base + 29u] = back_t;
    out_.v[base + 30u] = back_d.x;
    out_.v[base + 31u] = back_d.y;
    out_.v[base + 32u] = back_d.z;
    out_.v[base + 33u] = front_t;
    out_.v[base + 34u] = front_d.x;
    out_.v[base + 35u] = front_d.y;
    out_.v[base + 36u] = front_d.z;
    for (uint k = 37u; k < 40u; ++k)
        out_.v[base + k] = 0.0;
}
