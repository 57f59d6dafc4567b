/* Shading normals: the file's vertex normals, interpolated across each
 * triangle, in the cosines of reflection. The geometric normal still decides
 * which side a ray leaves from and where its origin is offset to; the
 * shading normal only weighs (and, for bounces, draws) directions on that
 * side (docs/bake.md, "Shading normals"). The kernels read each vertex
 * normal as one 32-bit word, 16-bit octahedral coordinates; the CPU
 * reference packs the scene's normals alike, so both use the same vectors.
 * Only scenes with pb_scene_bent_triangles (scene.h) > 0 shade smooth; the
 * others keep the face normal, and their kernels compile this out. */
#ifndef PB_SHADING_NORMALS_H
#define PB_SHADING_NORMALS_H

#include "probebake/scene.h"

#include <stdint.h>

/* A unit vector as two 16-bit signed-normalized octahedral coordinates (x in
 * the low half), and back: within 1e-4 radians. */
uint32_t pb_normal_pack(const float n[3]);
void pb_normal_unpack(uint32_t w, float n[3]);

/* The shading normal of scene triangle `tri` at barycentrics (u, v), as the
 * kernels compute it (scene.glsl, shading_normal): the packed vertex normals
 * interpolated and normalized, turned to the side of ng (the geometric
 * normal, already facing the ray's origin); ng where they cancel. */
void pb_shading_normal_cpu(const pb_scene *s, uint32_t tri, float u, float v, const float ng[3], float ns[3]);

#endif
