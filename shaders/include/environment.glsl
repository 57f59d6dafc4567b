// Environment light: mapping, lookup and importance sampling of an
// equirectangular radiance map. C mirror: src/bake/environment.c; the maths
// is in include/probebake/environment.h.
#ifndef PB_ENVIRONMENT_GLSL
#define PB_ENVIRONMENT_GLSL

#include "scene.glsl"

struct EnvTexel {
    vec3 rgb;               // radiance
    float p;                // probability of drawing this texel
    float keep;             // alias table
    uint alias;
    vec2 pad;
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer EnvBuf { EnvTexel t[]; };

struct Env {
    pb_addr texels;        // EnvTexel[]; 0: no environment
    uint width, height, count; // count 0: nothing to sample (black)
    float c, s;             // cos, sin of the rotation about +Y
};

uint env_texel_of(Env e, vec3 d)
{
    vec3 r = vec3(e.c * d.x - e.s * d.z, d.y, e.s * d.x + e.c * d.z);
    float u = 0.5 + atan(r.x, -r.z) * (0.5 / 3.14159265358979324);
    float v = acos(clamp(r.y, -1.0, 1.0)) * (1.0 / 3.14159265358979324);
    int x = clamp(int(floor(u * float(e.width))), 0, int(e.width) - 1);
    int y = clamp(int(floor(v * float(e.height))), 0, int(e.height) - 1);
    return uint(y) * e.width + uint(x);
}

vec3 env_radiance(Env e, vec3 d)
{
    if (addr_null(e.texels))
        return vec3(0.0);
    return EnvBuf(e.texels).t[env_texel_of(e, d)].rgb;
}

// Solid-angle density of drawing d with env_sample.
float env_pdf(Env e, vec3 d)
{
    float st = sqrt(max(0.0, 1.0 - d.y * d.y));
    if (e.count == 0u || !(st > 0.0))
        return 0.0;
    return EnvBuf(e.texels).t[env_texel_of(e, d)].p * float(e.width * e.height) /
           (2.0 * 3.14159265358979324 * 3.14159265358979324 * st);
}

// A direction drawn by texel luminance x solid angle; returns its density (w).
vec4 env_sample(Env e, float u0, float u1, float u2)
{
    EnvBuf tx = EnvBuf(e.texels);
    float x = u0 * float(e.count);
    uint i = min(uint(x), e.count - 1u);
    EnvTexel ti = tx.t[i];
    uint j = x - float(i) < ti.keep ? i : ti.alias;
    float u = (float(j % e.width) + u1) / float(e.width);
    float v = (float(j / e.width) + u2) / float(e.height);
    float phi = 2.0 * 3.14159265358979324 * (u - 0.5), theta = 3.14159265358979324 * v;
    float st = sin(theta);
    vec3 r = vec3(st * sin(phi), cos(theta), -st * cos(phi));
    vec3 d = vec3(e.c * r.x + e.s * r.z, r.y, -e.s * r.x + e.c * r.z);
    float pdf = st > 0.0 ? tx.t[j].p * float(e.width * e.height) / (2.0 * 3.14159265358979324 * 3.14159265358979324 * st) : 0.0;
    return vec4(d, pdf);
}

#endif
