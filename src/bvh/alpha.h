/* Alpha-mask test at a hit, shared by the CPU traversal and brute force;
 * shaders/include/alpha.glsl does the same. Nearest-texel sampling: a cutoff
 * is a hard threshold, and point sampling keeps CPU and GPU decisions equal
 * (bilinear weights would differ in the last bit and flip edge texels). */
#ifndef PB_ALPHA_H
#define PB_ALPHA_H

#include "probebake/scene.h"
#include "probebake/trace.h"
#include "scene/vertex_color.h"

#include <math.h>
#include <string.h>

static inline float pb_wrap_coord(float x, uint32_t mode)
{
    if (!isfinite(x))
        return 0.f;
    if (mode == PB_WRAP_CLAMP)
        return x < 0.f ? 0.f : (x > 1.f ? 1.f : x);
    if (mode == PB_WRAP_MIRROR) {
        float f = x - 2.f * floorf(x * 0.5f); /* [0,2) */
        return f > 1.f ? 2.f - f : f;
    }
    return x - floorf(x);
}

/* Texel index of (s,t) in a w x h texture, nearest. */
static inline uint32_t pb_texel_index(float s, float t, uint32_t w, uint32_t h, uint32_t wrap_s, uint32_t wrap_t)
{
    float x = pb_wrap_coord(s, wrap_s) * (float)w;
    float y = pb_wrap_coord(t, wrap_t) * (float)h;
    int ix = (int)floorf(x), iy = (int)floorf(y);
    ix = ix < 0 ? 0 : (ix >= (int)w ? (int)w - 1 : ix);
    iy = iy < 0 ? 0 : (iy >= (int)h ? (int)h - 1 : iy);
    return (uint32_t)iy * w + (uint32_t)ix;
}

/* The RGBA8 word of scene texture `tex` (>= 0) at (s, t), nearest texel
 * (texture_texel in alpha.glsl). */
static inline uint32_t pb_texture_texel(const pb_scene *sc, int32_t tex, float s, float t)
{
    const pb_texture *tx = &sc->textures[tex];
    return sc->texels[tx->offset + pb_texel_index(s, t, tx->width, tx->height, tx->wrap_s, tx->wrap_t)];
}

/* The stochastic threshold of an alpha-blended surface at a hit: a hash of
 * the material and the hit's barycentric bits ("hashed alpha testing",
 * Wyman and McGuire 2017, keyed on the surface point instead of a per-ray
 * random number). Every ray meets a different point, so a ray passes with
 * probability 1 - alpha, and CPU and GPU decide alike without a random
 * stream threaded through the traversal. */
static inline float pb_alpha_blend_threshold(uint32_t material, float u, float v)
{
    uint32_t ub, vb;
    memcpy(&ub, &u, 4), memcpy(&vb, &v, 4);
    uint32_t h = pb_hash32(material ^ pb_hash32(ub ^ pb_hash32(vb)));
    return (float)(h >> 8) * (1.f / 16777216.f);
}

/* 1 when scene triangle `tri` is opaque at barycentrics (u, v): MASK
 * surfaces where alpha >= cutoff, BLEND ones where alpha > a hashed
 * threshold (so alpha 0 always passes, alpha 1 never). */
static inline int pb_alpha_opaque(const pb_scene *s, uint32_t tri, float u, float v)
{
    const pb_material *m = &s->materials[s->material[tri]];
    if (m->alpha_mode != PB_ALPHA_MASK && m->alpha_mode != PB_ALPHA_BLEND)
        return 1;
    if (m->transmission > 0.f)
        return 1; /* thin glass: the ray's owner decides (glass_step in src/bake/bake_cpu.c) */
    float a = m->base_color[3];
    if (m->base_color_texture >= 0) {
        const float *uv = s->texcoords + 6 * (size_t)tri;
        float w0 = 1.f - u - v;
        float ts = w0 * uv[0] + u * uv[2] + v * uv[4];
        float tt = w0 * uv[1] + u * uv[3] + v * uv[5];
        a *= (float)(pb_texture_texel(s, m->base_color_texture, ts, tt) >> 24) * (1.f / 255.f);
    }
    if (s->colors) {
        float vc[4];
        pb_vertex_color(s, tri, u, v, vc);
        a *= vc[3];
    }
    if (m->alpha_mode == PB_ALPHA_BLEND)
        return a > pb_alpha_blend_threshold(s->material[tri], u, v);
    return a >= m->alpha_cutoff;
}

#endif
