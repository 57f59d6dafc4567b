/* Inputs (a, b, c, d) for a*b - c*d tests (pb_exact_diff and its GLSL):
 * every kind the exact path must get right, not only what traversal
 * reaches. Shared by test_bvh (against double) and test_trace (GPU). */
#ifndef PB_TEST_EXACT_INPUTS_H
#define PB_TEST_EXACT_INPUTS_H

#include "test_util.h"

#include <math.h>
#include <string.h>

static inline uint32_t exact_rng_u32(test_rng *r)
{
    return (uint32_t)(rng_uniform(r) * 4294967296.0);
}

/* a finite float with exponent field in [lo, hi] (0: zero or denormal) */
static inline float exact_rng_float(test_rng *r, uint32_t lo, uint32_t hi)
{
    uint32_t e = lo + exact_rng_u32(r) % (hi - lo + 1);
    uint32_t m = exact_rng_u32(r) & 0x7fffffu;
    if (exact_rng_u32(r) % 8 == 0)
        m &= 0x7f0000u; /* short mantissas make exact ties */
    uint32_t bits = (exact_rng_u32(r) & 0x80000000u) | e << 23 | m;
    float f;
    memcpy(&f, &bits, 4);
    return f;
}

/* Kind i % 6: any finite bits; a*b ~ c*d (cancellation); c = a and d one
 * ulp from b; c = b, d = a (exactly 0); denormal range; near overflow. */
static inline void exact_inputs(test_rng *r, uint32_t i, float q[4])
{
    switch (i % 6) {
    case 0:
        for (int k = 0; k < 4; ++k)
            q[k] = exact_rng_float(r, 0, 254);
        break;
    case 1:
        q[0] = exact_rng_float(r, 67, 187), q[1] = exact_rng_float(r, 67, 187), q[2] = exact_rng_float(r, 67, 187);
        q[3] = (float)((double)q[0] * q[1] / q[2]);
        for (uint32_t s = exact_rng_u32(r) % 4; s > 0; --s)
            q[3] = nextafterf(q[3], (exact_rng_u32(r) & 1) ? INFINITY : -INFINITY);
        break;
    case 2:
        q[0] = exact_rng_float(r, 1, 254), q[1] = exact_rng_float(r, 60, 190);
        q[2] = q[0], q[3] = nextafterf(q[1], (exact_rng_u32(r) & 1) ? INFINITY : -INFINITY);
        break;
    case 3:
        q[0] = exact_rng_float(r, 0, 254), q[1] = exact_rng_float(r, 0, 254);
        q[2] = q[1], q[3] = q[0];
        break;
    case 4:
        for (int k = 0; k < 4; ++k)
            q[k] = exact_rng_float(r, 0, 70);
        break;
    default:
        for (int k = 0; k < 4; ++k)
            q[k] = exact_rng_float(r, 180, 254);
        break;
    }
}

#endif
