/* The sRGB transfer functions (IEC 61966-2-1) in C: colour textures are
 * decoded with them (the C side of shaders/include/bake.glsl's
 * srgb_to_linear) and display images encoded. */
#ifndef PB_COMMON_SRGB_H
#define PB_COMMON_SRGB_H

#include <math.h>

static inline float pb_srgb_to_linear(float c)
{
    return c > 0.04045f ? powf((c + 0.055f) / 1.055f, 2.4f) : c / 12.92f;
}

/* clamped to [0, 1] */
static inline float pb_linear_to_srgb(float l)
{
    l = l < 0.f ? 0.f : (l > 1.f ? 1.f : l);
    return l <= 0.0031308f ? 12.92f * l : 1.055f * powf(l, 1.f / 2.4f) - 0.055f;
}

#endif
