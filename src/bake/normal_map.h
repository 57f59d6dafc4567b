/* Normal maps (glTF normalTexture): the shading normal bent by a texel of
 * tangent-space normals, in the file's tangent frame (glTF TANGENT) where the
 * triangle has one, else in a frame made from its texture coordinates
 * (docs/bake.md, "Normal maps"). The CPU reference of
 * shaders/include/normal_map.glsl, the same arithmetic in the same order.
 * Only scenes with pb_scene_normal_mapped (scene.h) > 0 bend normals; the
 * others' kernels compile this out. */
#ifndef PB_NORMAL_MAP_H
#define PB_NORMAL_MAP_H

#include "probebake/scene.h"

#include <stdint.h>

/* A triangle's file tangents (pb_scene.tangents, 12 floats) as the kernels
 * read them: three 16-bit octahedral words (pb_normal_pack), then a word of
 * bits: 1 where all three corners have one (else the frame comes from the
 * texture coordinates), 2 where the first corner's handedness is negative
 * (glTF gives a triangle's corners one handedness). */
void pb_tangents_pack(const float t12[12], uint32_t out[4]);

/* Shading normal n of scene triangle `tri` (edges e1, e2 from its first
 * corner) at barycentrics (u, v), bent by texture `tex` (>= 0) at (s, t),
 * its texel's X and Y times `scale`; its frame from the file's tangents
 * where the triangle has them (pb_scene.tangents), else from its texture
 * coordinates. n and ng face the ray's origin; `back`: the ray met the
 * triangle's back face. out = n where the frame or the texel is degenerate,
 * or where the bent normal would leave the geometric surface. */
void pb_normal_mapped_cpu(const pb_scene *sc, int32_t tex, float scale, uint32_t tri, float u, float v, float s,
                          float t, const float e1[3], const float e2[3], const float n[3], const float ng[3], int back,
                          float out[3]);

#endif
