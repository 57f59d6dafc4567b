// Normal maps (glTF normalTexture): the shading normal bent by a texel of
// tangent-space normals. CPU reference: src/bake/normal_map.c, the same
// arithmetic in the same order.
#ifndef PB_NORMAL_MAP_GLSL
#define PB_NORMAL_MAP_GLSL

#include "alpha.glsl"

// The file's tangents of leaf-ordered triangle `tri` (PB_SCENE_TANGENTS:
// pb_tangents_pack's four words) at (u, v), where all three corners have
// one: xyz interpolated, w the handedness (+-1); 0 where they do not, or the
// scene has none.
vec4 file_tangent(SceneRefs s, uint tri, float u, float v)
{
    if ((s.flags & PB_SCENE_TANGENTS) == 0u)
        return vec4(0.0);
    UintBuf w = UintBuf(s.tri_uv);
    uint b = ((s.flags & PB_SCENE_VERTEX_COLORS) != 0u ? 18u : 6u) * s.triangle_count +
             ((s.flags & PB_SCENE_SHADING_NORMALS) != 0u ? 3u : 0u) * s.triangle_count + 4u * tri;
    uint bits = w.v[b + 3u];
    if ((bits & 1u) == 0u)
        return vec4(0.0);
    vec3 t0 = oct_decode(unpackSnorm2x16(w.v[b]));
    vec3 t1 = oct_decode(unpackSnorm2x16(w.v[b + 1u]));
    vec3 t2 = oct_decode(unpackSnorm2x16(w.v[b + 2u]));
    precise float w0 = 1.0 - u - v;
    precise vec3 t = w0 * t0 + u * t1 + v * t2;
    return vec4(t, (bits & 2u) != 0u ? -1.0 : 1.0);
}

// The shading normal n of leaf-ordered triangle `tri` (edges e1, e2 from
// its first corner, texture coordinates c) at barycentrics (u, v), bent by
// texture `tex` at uv. glTF's texel c is the normal (2 c - 1) x (scale,
// scale, 1) in a frame whose X runs along increasing u and Y against
// increasing v (up the image): the file's tangent t and handedness w where
// the triangle has them (T = t made orthogonal to n, B = w (n x T), as glTF
// defines the bitangent), else the triangle's own frame from its texture
// coordinates' derivatives (dp/du and dp/dv, constant over it: T = dp/du
// made orthogonal to n, B = n x T turned against dp/dv, which also turns
// it for mirrored texture coordinates; docs/bake.md). n and ng face the
// ray's origin; on a back face (`back`) the frame is the front's and the
// bent normal is turned back, as the surface's relief seen from behind. n
// itself where the frame or the texel is degenerate, or where the bent
// normal would leave the geometric surface.
vec3 normal_mapped(SceneRefs s, int tex, float scale, uint tri, float u, float v, TriUV c, vec2 uv, vec3 e1, vec3 e2,
                   vec3 n, vec3 ng, bool back)
{
    vec4 ft = file_tangent(s, tri, u, v);
    precise float du1 = c.c1.x - c.c0.x, dv1 = c.c1.y - c.c0.y;
    precise float du2 = c.c2.x - c.c0.x, dv2 = c.c2.y - c.c0.y;
    precise float det = du1 * dv2 - du2 * dv1;
    // dp/du and dp/dv times det; only their directions are used, so det's sign
    precise vec3 dpdu = dv2 * e1 - dv1 * e2, dpdv = du1 * e2 - du2 * e1;
    float sgn = det < 0.0 ? -1.0 : 1.0;
    dpdu *= sgn;
    dpdv *= sgn;
    vec3 nf = back ? -n : n;
    vec3 axis = ft.w != 0.0 ? ft.xyz : dpdu; // the frame's first axis, before it is made orthogonal to n
    precise vec3 tu = axis - dot(axis, nf) * nf;
    float lt = length(tu);
    if (!((ft.w != 0.0 || det != 0.0) && lt > 1e-20 && lt < 1e30))
        return n;
    vec3 T = tu / lt;
    vec3 B = cross(nf, T);
    B *= ft.w != 0.0 ? ft.w : (dot(B, dpdv) > 0.0 ? -1.0 : 1.0);
    uint texel = texture_texel(s, tex, uv);
    vec3 rgb = vec3(float(texel & 0xffu), float((texel >> 8) & 0xffu), float((texel >> 16) & 0xffu)) / 255.0;
    precise vec3 m = (2.0 * rgb - 1.0) * vec3(scale, scale, 1.0);
    precise vec3 p = m.x * T + m.y * B + m.z * nf;
    float lp = length(p);
    if (!(lp > 1e-6 && lp < 1e30))
        return n;
    p = (back ? -p : p) / lp;
    return dot(p, ng) > 0.0 ? p : n;
}

#endif
