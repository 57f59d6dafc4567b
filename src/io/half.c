/* IEEE 754 binary16 <-> binary32, round to nearest even (volume.h). The depth
 * moments in the file are halves: 11 significant bits are plenty for mean
 * distances at room-scale probe spacing (docs/format.md says when not). */
#include "io/half_pairs.h"
#include "probebake/volume.h"

#include <string.h>

uint16_t pb_half_from_float(float f)
{
    uint32_t x;
    memcpy(&x, &f, 4);
    uint32_t sign = (x >> 16) & 0x8000u;
    uint32_t exp = (x >> 23) & 0xffu, mant = x & 0x7fffffu;
    if (exp == 0xffu) /* Inf stays Inf; NaN stays a (quiet) NaN */
        return (uint16_t)(sign | 0x7c00u | (mant ? 0x200u | (mant >> 13) : 0u));
    int e = (int)exp - 127 + 15;
    if (e >= 31)
        return (uint16_t)(sign | 0x7c00u);
    if (e <= 0) { /* subnormal half, or zero */
        if (e < -10)
            return (uint16_t)sign;
        uint32_t full = mant | 0x800000u;
        uint32_t shift = (uint32_t)(14 - e);
        uint32_t h = full >> shift, rem = full & ((1u << shift) - 1u), halfway = 1u << (shift - 1u);
        if (rem > halfway || (rem == halfway && (h & 1u)))
            ++h;
        return (uint16_t)(sign | h);
    }
    uint32_t h = ((uint32_t)e << 10) | (mant >> 13), rem = mant & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u)))
        ++h; /* a carry into the exponent is right, up to Inf */
    return (uint16_t)(sign | h);
}

float pb_half_to_float(uint16_t h)
{
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16, exp = (h >> 10) & 0x1fu, mant = h & 0x3ffu, x;
    if (exp == 0) {
        if (!mant) {
            x = sign;
        } else { /* subnormal: normalise */
            int e = -1;
            do {
                ++e;
                mant <<= 1;
            } while (!(mant & 0x400u));
            x = sign | ((uint32_t)(127 - 15 - e) << 23) | ((mant & 0x3ffu) << 13);
        }
    } else if (exp == 31) {
        x = sign | 0x7f800000u | (mant << 13);
    } else {
        x = sign | ((exp - 15 + 127) << 23) | (mant << 13);
    }
    float f;
    memcpy(&f, &x, 4);
    return f;
}

/* ------------------------------------------------------------ in bulk */

static void pairs_scalar(const float *in, uint16_t *out, uint32_t pairs, double div0, double div1)
{
    for (uint32_t i = 0; i < pairs; ++i) {
        out[2 * i] = pb_half_from_float((float)((double)in[2 * i] / div0));
        out[2 * i + 1] = pb_half_from_float((float)((double)in[2 * i + 1] / div1));
    }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <cpuid.h>
#include <immintrin.h>

pb_half_path pb_half_best_path(void)
{
    unsigned a, b, c, d;
    if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & bit_OSXSAVE) || !(c & bit_AVX) || !(c & bit_F16C))
        return PB_HALF_SCALAR;
    unsigned lo, hi;
    __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    return (lo & 6u) == 6u ? PB_HALF_F16C : PB_HALF_SCALAR; /* the OS saves XMM and YMM registers */
}

/* Four pairs at a time: the division in double and the rounding to float
 * as the scalar path does them (the same IEEE operations, in lanes), then
 * vcvtps2ph with round-to-nearest-even, which keeps a NaN's payload quiet
 * as pb_half_from_float does. */
__attribute__((target("avx,f16c"))) static void pairs_f16c(const float *in, uint16_t *out, uint32_t pairs,
                                                            double div0, double div1)
{
    const __m256d div = _mm256_setr_pd(div0, div1, div0, div1);
    uint32_t i = 0;
    for (; i + 4 <= pairs; i += 4) {
        __m256d lo = _mm256_div_pd(_mm256_cvtps_pd(_mm_loadu_ps(in + 2 * i)), div);
        __m256d hi = _mm256_div_pd(_mm256_cvtps_pd(_mm_loadu_ps(in + 2 * i + 4)), div);
        __m256 f = _mm256_set_m128(_mm256_cvtpd_ps(hi), _mm256_cvtpd_ps(lo));
        _mm_storeu_si128((__m128i *)(out + 2 * i), _mm256_cvtps_ph(f, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
    }
    pairs_scalar(in + 2 * i, out + 2 * i, pairs - i, div0, div1);
}

void pb_half_pairs(pb_half_path path, const float *in, uint16_t *out, uint32_t pairs, double div0, double div1)
{
    if (path == PB_HALF_F16C)
        pairs_f16c(in, out, pairs, div0, div1);
    else
        pairs_scalar(in, out, pairs, div0, div1);
}
#else
pb_half_path pb_half_best_path(void)
{
    return PB_HALF_SCALAR;
}

void pb_half_pairs(pb_half_path path, const float *in, uint16_t *out, uint32_t pairs, double div0, double div1)
{
    (void)path;
    pairs_scalar(in, out, pairs, div0, div1);
}
#endif
