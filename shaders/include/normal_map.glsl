// Normal maps (glTF normalTexture): the shading normal bent by a texel of
// tangent-space normals. CPU reference: src/bake/normal_map.c, the same
// arithmetic in the same order.
#ifndef PB_NORMAL_MAP_GLSL
#define PB_NORMAL_MAP_GLSL

#include "alpha.glsl"

// The shading normal n of a triangle (edges e1, e2 from its first corner,
// texture coordinates c), bent by texture `tex` at uv. glTF's texel c is the
// normal (2 c - 1) x (scale, scale, 1) in a frame whose X runs along
// increasing u and Y against increasing v (up the image). The frame is the
// triangle's own, from its texture coordinates' derivatives (dp/du and
// dp/dv, constant over it; a file's TANGENT is not read, docs/scene.md),
// made orthogonal to n: T = dp/du less its part along n, B = n x T turned
// against dp/dv, which also turns it for mirrored texture coordinates.
// n and ng face the ray's origin; on a back face (`back`) the frame is the
// front's and the bent normal is turned back, as the surface's relief
// seen from behind. n itself where the frame or the texel is degenerate,
// or where the bent normal would leave the geometric surface.
vec3 normal_mapped(SceneRefs s, int tex, float scale, TriUV c, vec2 uv, vec3 e1, vec3 e2, vec3 n, vec3 ng,
                   bool back)
{
    precise float du1 = c.c1.x - c.c0.x, dv1 = c.c1.y - c.c0.y;
    precise float du2 = c.c2.x - c.c0.x, dv2 = c.c2.y - c.c0.y;
    precise float det = du1 * dv2 - du2 * dv1;
    // dp/du and dp/dv times det; only their directions are used, so det's sign
    precise vec3 dpdu = dv2 * e1 - dv1 * e2, dpdv = du1 * e2 - du2 * e1;
    float sgn = det < 0.0 ? -1.0 : 1.0;
    dpdu *= sgn;
    dpdv *= sgn;
    vec3 nf = back ? -n : n;
    precise vec3 tu = dpdu - dot(dpdu, nf) * nf;
    float lt = length(tu);
    if (!(det != 0.0 && lt > 1e-20 && lt < 1e30))
        return n;
    vec3 T = tu / lt;
    vec3 B = cross(nf, T);
    B = dot(B, dpdv) > 0.0 ? -B : B;
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
