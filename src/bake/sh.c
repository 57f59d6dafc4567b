/* Real SH L2: basis, projection, clamped-cosine convolution, evaluation.
 * Constants and order: include/probebake/sh.h. */
#include "probebake/sh.h"

#include <math.h>

#define SH_C0 0.28209479177387814f  /* 1 / (2 sqrt(pi)) */
#define SH_C1 0.48860251190291992f  /* sqrt(3 / (4 pi)) */
#define SH_C2 1.09254843059207907f  /* sqrt(15 / (4 pi)) */
#define SH_C3 0.31539156525252005f  /* sqrt(5 / (16 pi)) */
#define SH_C4 0.54627421529603953f  /* sqrt(15 / (16 pi)) */

void pb_sh_basis(const float d[3], float y[PB_SH_COUNT])
{
    float x = d[0], yy = d[1], z = d[2];
    y[0] = SH_C0;
    y[1] = SH_C1 * yy;
    y[2] = SH_C1 * z;
    y[3] = SH_C1 * x;
    y[4] = SH_C2 * x * yy;
    y[5] = SH_C2 * yy * z;
    y[6] = SH_C3 * (3.f * z * z - 1.f);
    y[7] = SH_C2 * x * z;
    y[8] = SH_C4 * (x * x - yy * yy);
}

void pb_sh_add(float c[3 * PB_SH_COUNT], const float d[3], const float rgb[3], float weight)
{
    float y[PB_SH_COUNT];
    pb_sh_basis(d, y);
    for (int i = 0; i < PB_SH_COUNT; ++i)
        for (int k = 0; k < 3; ++k)
            c[3 * i + k] += weight * rgb[k] * y[i];
}

void pb_sh_add_delta(float c[3 * PB_SH_COUNT], const float d[3], const float irradiance_rgb[3])
{
    pb_sh_add(c, d, irradiance_rgb, 1.f);
}

void pb_sh_radiance_to_irradiance(float c[3 * PB_SH_COUNT])
{
    static const float band[PB_SH_COUNT] = {
        3.14159265358979324f,                                              /* pi */
        2.09439510239319549f, 2.09439510239319549f, 2.09439510239319549f, /* 2pi/3 */
        0.78539816339744831f, 0.78539816339744831f, 0.78539816339744831f, /* pi/4 */
        0.78539816339744831f, 0.78539816339744831f};
    for (int i = 0; i < PB_SH_COUNT; ++i)
        for (int k = 0; k < 3; ++k)
            c[3 * i + k] *= band[i];
}

void pb_sh_eval(const float c[3 * PB_SH_COUNT], const float d[3], float rgb[3])
{
    float y[PB_SH_COUNT];
    pb_sh_basis(d, y);
    for (int k = 0; k < 3; ++k) {
        float s = 0.f;
        for (int i = 0; i < PB_SH_COUNT; ++i)
            s += c[3 * i + k] * y[i];
        rgb[k] = s;
    }
}

float pb_sh_window_factor(pb_sh_window_kind kind, float width, int band)
{
    const float pi = 3.14159265358979324f;
    float w = width > 0.f ? width : 3.f;
    float x = pi * (float)band / w;
    if (band == 0 || kind == PB_SH_WINDOW_NONE)
        return 1.f;
    if (kind == PB_SH_WINDOW_HANNING)
        return x >= pi ? 0.f : 0.5f * (1.f + cosf(x));
    return x >= pi ? 0.f : sinf(x) / x; /* lanczos */
}

void pb_sh_apply_window(float c[3 * PB_SH_COUNT], pb_sh_window_kind kind, float width)
{
    static const int band_of[PB_SH_COUNT] = {0, 1, 1, 1, 2, 2, 2, 2, 2};
    for (int i = 0; i < PB_SH_COUNT; ++i) {
        float f = pb_sh_window_factor(kind, width, band_of[i]);
        for (int k = 0; k < 3; ++k)
            c[3 * i + k] *= f;
    }
}
