/* Vertex colour (glTF COLOR_0) at a hit: the corners' linear RGBA
 * interpolated by the hit's barycentrics, white where the scene has none.
 * It multiplies the base colour, albedo and alpha alike (glTF's rule; the
 * emissive colour is not touched). vertex_color() in shaders/include/
 * scene.glsl computes the same, in the same order (the CPU references are
 * compared bit for bit with the kernels). */
#ifndef PB_VERTEX_COLOR_H
#define PB_VERTEX_COLOR_H

#include "probebake/scene.h"

static inline void pb_vertex_color(const pb_scene *s, uint32_t tri, float u, float v, float out[4])
{
    if (!s->colors) {
        out[0] = out[1] = out[2] = out[3] = 1.f;
        return;
    }
    const float *c = s->colors + 12 * (size_t)tri;
    float w0 = 1.f - u - v;
    for (int k = 0; k < 4; ++k)
        out[k] = w0 * c[k] + u * c[4 + k] + v * c[8 + k];
}

#endif
