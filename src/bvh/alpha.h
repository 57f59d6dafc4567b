/* Alpha-mask test at a hit, shared by the CPU traversal and brute force;
 * shaders/include/alpha.glsl does the same. Nearest-texel sampling: a cutoff
 * is a hard threshold, and point sampling keeps CPU and GPU decisions equal
 * (bilinear weights would differ in the last bit and flip edge texels). */
#ifndef PB_ALPHA_H
#define PB_ALPHA_H

#include "probebake/scene.h"

#include <math.h>

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

/* 1 when scene triangle `tri` is opaque at barycentrics (u, v). */
static inline int pb_alpha_opaque(const pb_scene *s, uint32_t tri, float u, float v)
{
    const pb_material *m = &s->materials[s->material[tri]];
    if (m->alpha_mode != PB_ALPHA_MASK)
        return 1;
    float a = m->base_color[3];
    if (m->base_color_texture >= 0) {
        const pb_texture *tx = &s->textures[m->base_color_texture];
        const float *uv = s->texcoords + 6 * (size_t)tri;
        float w0 = 1.f - u - v;
        float ts = w0 * uv[0] + u * uv[2] + v * uv[4];
        float tt = w0 * uv[1] + u * uv[3] + v * uv[5];
        uint32_t texel = s->texels[tx->offset + pb_texel_index(ts, tt, tx->width, tx->height, tx->wrap_s, tx->wrap_t)];
        a *= (float)(texel >> 24) * (1.f / 255.f);
    }
    return a >= m->alpha_cutoff;
}

#endif
