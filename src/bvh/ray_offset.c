/* Robust secondary-ray origins (Wächter & Binder, "A Fast and Robust Method
 * for Avoiding Self-Intersection", Ray Tracing Gems, 2019). Away from the
 * world origin the point is pushed along the normal by a number of float
 * ulps proportional to the normal component (integer arithmetic on the bit
 * pattern), which scales with |p| by construction; within 1/32 of the origin,
 * where ulps are tiny, by a fixed 2^-16 along the normal instead.
 * shaders/include/ray_offset.glsl is the same function. */
#include "probebake/trace.h"

#include <math.h>
#include <string.h>

#define OFFSET_ORIGIN (1.0f / 32.0f)
#define OFFSET_FLOAT_SCALE (1.0f / 65536.0f)
#define OFFSET_INT_SCALE 256.0f

void pb_offset_ray_origin(const float p[3], const float n[3], float out[3])
{
    for (int k = 0; k < 3; ++k) {
        int32_t of = (int32_t)(OFFSET_INT_SCALE * n[k]);
        int32_t bits;
        memcpy(&bits, &p[k], 4);
        bits += p[k] < 0.f ? -of : of;
        float pi;
        memcpy(&pi, &bits, 4);
        out[k] = fabsf(p[k]) < OFFSET_ORIGIN ? p[k] + OFFSET_FLOAT_SCALE * n[k] : pi;
    }
}
