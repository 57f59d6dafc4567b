/* Normal maps (normal_map.h): normal_mapped of shaders/include/normal_map.glsl. */
#include "bake/normal_map.h"

#include "bvh/alpha.h"

#include <math.h>
#include <string.h>

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void pb_normal_mapped_cpu(const pb_scene *sc, int32_t tex, float scale, uint32_t tri, float s, float t,
                          const float e1[3], const float e2[3], const float n[3], const float ng[3], int back,
                          float out[3])
{
    memcpy(out, n, 3 * sizeof(float));
    const float *uv = sc->texcoords + 6 * (size_t)tri;
    float du1 = uv[2] - uv[0], dv1 = uv[3] - uv[1];
    float du2 = uv[4] - uv[0], dv2 = uv[5] - uv[1];
    float det = du1 * dv2 - du2 * dv1;
    /* dp/du and dp/dv times det: only their directions are used */
    float sgn = det < 0.f ? -1.f : 1.f, dpdu[3], dpdv[3], nf[3], tu[3];
    for (int k = 0; k < 3; ++k) {
        dpdu[k] = (dv2 * e1[k] - dv1 * e2[k]) * sgn;
        dpdv[k] = (du1 * e2[k] - du2 * e1[k]) * sgn;
        nf[k] = back ? -n[k] : n[k];
    }
    float along = dot3(dpdu, nf);
    for (int k = 0; k < 3; ++k)
        tu[k] = dpdu[k] - along * nf[k];
    float lt = sqrtf(dot3(tu, tu));
    if (!(det != 0.f && lt > 1e-20f && lt < 1e30f))
        return;
    float T[3] = {tu[0] / lt, tu[1] / lt, tu[2] / lt};
    float B[3] = {nf[1] * T[2] - nf[2] * T[1], nf[2] * T[0] - nf[0] * T[2], nf[0] * T[1] - nf[1] * T[0]};
    if (dot3(B, dpdv) > 0.f)
        for (int k = 0; k < 3; ++k)
            B[k] = -B[k];
    uint32_t texel = pb_texture_texel(sc, tex, s, t);
    float m[3];
    for (int k = 0; k < 3; ++k)
        m[k] = (2.f * ((float)((texel >> (8 * k)) & 0xffu) / 255.f) - 1.f) * (k < 2 ? scale : 1.f);
    float p[3];
    for (int k = 0; k < 3; ++k)
        p[k] = m[0] * T[k] + m[1] * B[k] + m[2] * nf[k];
    float lp = sqrtf(dot3(p, p));
    if (!(lp > 1e-6f && lp < 1e30f))
        return;
    for (int k = 0; k < 3; ++k)
        p[k] = (back ? -p[k] : p[k]) / lp;
    if (dot3(p, ng) > 0.f)
        memcpy(out, p, sizeof p);
}
