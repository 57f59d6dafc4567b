/* Shading normals (shading_normals.h). */
#include "bake/shading_normals.h"

#include "probebake/octahedral.h"

#include <math.h>

static uint32_t snorm16(float x)
{
    float c = x < -1.f ? -1.f : (x > 1.f ? 1.f : x);
    return (uint32_t)(int32_t)lrintf(c * 32767.f) & 0xffffu;
}

uint32_t pb_normal_pack(const float n[3])
{
    float uv[2];
    pb_oct_encode(n, uv);
    return snorm16(uv[0]) | snorm16(uv[1]) << 16;
}

/* unpackSnorm2x16 of GLSL, then the octahedral decode */
void pb_normal_unpack(uint32_t w, float n[3])
{
    float uv[2] = {(float)(int16_t)(w & 0xffffu) / 32767.f, (float)(int16_t)(w >> 16) / 32767.f};
    for (int k = 0; k < 2; ++k)
        uv[k] = uv[k] < -1.f ? -1.f : uv[k];
    pb_oct_decode(uv, n);
}

void pb_shading_normal_cpu(const pb_scene *s, uint32_t tri, float u, float v, const float ng[3], float ns[3])
{
    float n0[3], n1[3], n2[3];
    const float *vn = s->normals + 9 * (size_t)tri;
    pb_normal_unpack(pb_normal_pack(vn), n0);
    pb_normal_unpack(pb_normal_pack(vn + 3), n1);
    pb_normal_unpack(pb_normal_pack(vn + 6), n2);
    float w0 = 1.f - u - v, n[3];
    for (int k = 0; k < 3; ++k)
        n[k] = w0 * n0[k] + u * n1[k] + v * n2[k];
    float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l > 1e-6f)) { /* opposite vertex normals cancel: the face's */
        ns[0] = ng[0], ns[1] = ng[1], ns[2] = ng[2];
        return;
    }
    float side = n[0] * ng[0] + n[1] * ng[1] + n[2] * ng[2] < 0.f ? -1.f : 1.f;
    for (int k = 0; k < 3; ++k)
        ns[k] = side * n[k] / l;
}
