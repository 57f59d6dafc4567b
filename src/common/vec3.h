/* Float 3-vectors for the CPU references, in the kernels' order of
 * operations (x, then y, then z; the build passes -ffp-contract=off), so
 * they round as GLSL's dot, cross and length do where the device does not
 * fuse either. */
#ifndef PB_VEC3_H
#define PB_VEC3_H

#include <math.h>

static inline float pb_dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void pb_cross3(const float a[3], const float b[3], float c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static inline float pb_length3(const float a[3])
{
    return sqrtf(pb_dot3(a, a));
}

#endif
