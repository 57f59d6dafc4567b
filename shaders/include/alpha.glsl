// Alpha-mask test at a hit: src/bvh/alpha.h. Nearest texel, so CPU and GPU
// make the same keep/cut decision.
#ifndef PB_ALPHA_GLSL
#define PB_ALPHA_GLSL

#include "scene.glsl"
#include "rng.glsl"

float wrap_coord(float x, uint mode)
{
    if (isnan(x) || isinf(x))
        return 0.0;
    if (mode == 1u)
        return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
    if (mode == 2u) {
        precise float f = x - 2.0 * floor(x * 0.5);
        return f > 1.0 ? 2.0 - f : f;
    }
    precise float fr = x - floor(x);
    return fr;
}

uint texel_index(float s, float t, uint w, uint h, uint wrap_s, uint wrap_t)
{
    precise float x = wrap_coord(s, wrap_s) * float(w);
    precise float y = wrap_coord(t, wrap_t) * float(h);
    int ix = int(floor(x)), iy = int(floor(y));
    ix = ix < 0 ? 0 : (ix >= int(w) ? int(w) - 1 : ix);
    iy = iy < 0 ? 0 : (iy >= int(h) ? int(h) - 1 : iy);
    return uint(iy) * w + uint(ix);
}

// The RGBA8 word of texture `tex` (>= 0) at uv, nearest texel
// (pb_texture_texel in src/bvh/alpha.h).
uint texture_texel(SceneRefs s, int tex, vec2 uv)
{
    Texture t = TextureBuf(s.textures).t[tex];
    return UintBuf(s.texels).v[t.offset + texel_index(uv.x, uv.y, t.width, t.height, t.wrap & 0xffu, t.wrap >> 8)];
}

// Threshold of an alpha-blended surface at a hit: src/bvh/alpha.h says why
// a hash of the hit point.
float alpha_blend_threshold(uint material, float u, float v)
{
    uint h = pb_hash32(material ^ pb_hash32(floatBitsToUint(u) ^ pb_hash32(floatBitsToUint(v))));
    return float(h >> 8) * (1.0 / 16777216.0);
}

// True when leaf-ordered triangle `tri` (flags f) is opaque at (u, v).
bool alpha_opaque(SceneRefs s, uint tri, uint f, float u, float v)
{
    Material m = MaterialBuf(s.materials).m[f & ~PB_FLAG_ALPHA_MASK];
    float a = m.base_alpha;
    if (m.texture >= 0)
        a *= float(texture_texel(s, m.texture, surface_uv(s, tri, u, v)) >> 24) * (1.0 / 255.0);
    if ((s.flags & PB_SCENE_VERTEX_COLORS) != 0u)
        a *= vertex_color(s, tri, u, v).a;
    if (m.mode == 2u) // glTF BLEND
        return a > alpha_blend_threshold(f & ~PB_FLAG_ALPHA_MASK, u, v);
    return a >= m.cutoff;
}

#endif
