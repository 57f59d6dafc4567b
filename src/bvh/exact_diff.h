/* a*b - c*d exactly, rounded once to float, in integer arithmetic.
 *
 * The watertight triangle test needs edge functions with the exact sign
 * (intersect.h). A product of two floats is exact in double, so the fallback
 * once ran in double; that needs shaderFloat64, which many Vulkan devices
 * lack. Error-free products with fma() would avoid doubles, but Vulkan lets
 * fma() be a multiply and an add (lavapipe does exactly that) and lets
 * devices flush denormals, so no float trick is exact everywhere. Integers
 * are: each float is m * 2^e with a 24-bit m, a product of two is a 48-bit
 * integer, and the difference of two such, aligned, fits 128 bits.
 * shaders/include/exact_diff.glsl does the same in 32-bit words (no
 * shaderInt64); both round the exact value to nearest-even, so they agree
 * bit for bit (tests/test_trace.c runs both on the same inputs).
 *
 * Result: 0 when a*b == c*d; else the exact value rounded to float, except
 * that a magnitude below FLT_MIN becomes +-1e-37 (the sign survives devices
 * that flush denormals) and one above FLT_MAX becomes +-inf. Non-finite
 * inputs give the plain float expression. */
#ifndef PB_EXACT_DIFF_H
#define PB_EXACT_DIFF_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "probebake/base.h"

/* Gap, in bits, beyond which the smaller product only decides rounding as a
 * sticky bit: the larger one is P << 80 with P >= 1, so its rounding position
 * sits at bit 54 or above while the smaller, < 2^47 there, stays below it. */
#define PB_EXACT_MAX_SHIFT 80

typedef unsigned __int128 pb_u128;

static inline uint32_t pb_float_bits(float x)
{
    uint32_t b;
    memcpy(&b, &x, 4);
    return b;
}

static inline float pb_exact_diff(float a, float b, float c, float d)
{
    const float in[4] = {a, b, c, d};
    uint32_t m[4], s[4];
    int e[4];
    for (int i = 0; i < 4; ++i) {
        uint32_t bits = pb_float_bits(in[i]);
        uint32_t ex = (bits >> 23) & 0xffu;
        if (ex == 0xffu)
            return a * b - c * d;
        s[i] = bits >> 31;
        m[i] = (bits & 0x7fffffu) | (ex ? 0x800000u : 0u);
        e[i] = (ex ? (int)ex : 1) - 150; /* value = m * 2^e */
    }
    uint64_t P = (uint64_t)m[0] * m[1], Q = (uint64_t)m[2] * m[3];
    int ep = e[0] + e[1], eq = e[2] + e[3];
    uint32_t sp = s[0] ^ s[1], sq = s[2] ^ s[3] ^ 1u; /* signs of +ab and -cd */
    if (P == 0 && Q == 0)
        return 0.f;
    if (P == 0)
        ep = eq;
    if (Q == 0)
        eq = ep;
    /* align both on the smaller exponent */
    pb_u128 X, Y;
    int e0;
    if (ep >= eq) {
        int k = ep - eq;
        if (k > PB_EXACT_MAX_SHIFT)
            k = PB_EXACT_MAX_SHIFT, Q = Q != 0;
        X = (pb_u128)P << k, Y = Q, e0 = ep - k;
    } else {
        int k = eq - ep;
        if (k > PB_EXACT_MAX_SHIFT)
            k = PB_EXACT_MAX_SHIFT, P = P != 0;
        X = P, Y = (pb_u128)Q << k, e0 = eq - k;
    }
    pb_u128 M;
    uint32_t sign;
    if (sp == sq)
        M = X + Y, sign = sp;
    else if (X >= Y)
        M = X - Y, sign = sp;
    else
        M = Y - X, sign = sq;
    if (M == 0)
        return 0.f;
    int h = 127;
    while (!((M >> h) & 1u))
        --h;
    uint32_t mant;
    if (h <= 23) {
        mant = (uint32_t)M << (23 - h);
    } else {
        int sh = h - 23;
        mant = (uint32_t)(M >> sh);
        uint32_t guard = (uint32_t)(M >> (sh - 1)) & 1u;
        int sticky = (M & (((pb_u128)1 << (sh - 1)) - 1)) != 0;
        if (guard && (sticky || (mant & 1u)))
            ++mant;
        if (mant == 0x1000000u)
            mant >>= 1, ++h;
    }
    int x = e0 + h; /* exponent of the leading bit */
    if (x < -126)
        return sign ? -1e-37f : 1e-37f;
    if (x > 127)
        return sign ? -INFINITY : INFINITY;
    uint32_t bits = sign << 31 | (uint32_t)(x + 127) << 23 | (mant & 0x7fffffu);
    float f;
    memcpy(&f, &bits, 4);
    return f;
}

/* The GLSL version on the device, for tests: out[i] = exact_diff of
 * abcd[4i .. 4i+3]. (src/bvh/exact_diff_gpu.c) */
typedef struct pb_context pb_context;
pb_result pb_exact_diff_gpu(pb_context *ctx, const float *abcd, uint32_t count, float *out, pb_error *err);

#endif
