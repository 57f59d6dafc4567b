/* Normal maps (normal_map.h): normal_mapped of shaders/include/normal_map.glsl. */
#include "bake/normal_map.h"

#include "bake/shading_normals.h"
#include "bvh/alpha.h"

#include <math.h>
#include <string.h>

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void pb_tangents_pack(const float t12[12], uint32_t out[4])
{
    int all = 1;
    for (int v = 0; v < 3; ++v) {
        all &= t12[4 * v + 3] != 0.f;
        out[v] = t12[4 * v + 3] != 0.f ? pb_normal_pack(t12 + 4 * v) : 0u;
    }
    out[3] = (all ? 1u : 0u) | (all && t12[3] < 0.f ? 2u : 0u);
}

void pb_normal_mapped_cpu(const pb_scene *sc, int32_t tex, float scale, uint32_t tri, float u, float v, float s,
                          float t, const float e1[3], const float e2[3], const float n[3], const float ng[3], int back,
                          float out[3])
{
    memcpy(out, n, 3 * sizeof(float));
    /* the file's tangent, as the kernels read it (file_tangent in normal_map.glsl) */
    uint32_t packed[4] = {0, 0, 0, 0};
    if (sc->tangents)
        pb_tangents_pack(sc->tangents + 12 * (size_t)tri, packed);
    float hand = 0.f, ft[3] = {0, 0, 0};
    if (packed[3] & 1u) {
        float t0[3], t1[3], t2[3], w0 = 1.f - u - v;
        pb_normal_unpack(packed[0], t0), pb_normal_unpack(packed[1], t1), pb_normal_unpack(packed[2], t2);
        for (int k = 0; k < 3; ++k)
            ft[k] = w0 * t0[k] + u * t1[k] + v * t2[k];
        hand = packed[3] & 2u ? -1.f : 1.f;
    }
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
    const float *axis = hand != 0.f ? ft : dpdu; /* the frame's first axis, before it is made orthogonal to n */
    float along = dot3(axis, nf);
    for (int k = 0; k < 3; ++k)
        tu[k] = axis[k] - along * nf[k];
    float lt = sqrtf(dot3(tu, tu));
    if (!((hand != 0.f || det != 0.f) && lt > 1e-20f && lt < 1e30f))
        return;
    float T[3] = {tu[0] / lt, tu[1] / lt, tu[2] / lt};
    float B[3] = {nf[1] * T[2] - nf[2] * T[1], nf[2] * T[0] - nf[0] * T[2], nf[0] * T[1] - nf[1] * T[0]};
    /* glTF's bitangent is w (n x t); from the coordinates, n x T turned against dp/dv */
    float turn = hand != 0.f ? hand : (dot3(B, dpdv) > 0.f ? -1.f : 1.f);
    for (int k = 0; k < 3; ++k)
        B[k] *= turn;
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
