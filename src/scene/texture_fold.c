/* Colour textures rewritten for what the kernels read (texture_fold.h). */
#include "scene/texture_fold.h"
#include "bvh/alpha.h"
#include "common/srgb.h"

#include <math.h>
#include <stdlib.h>

/* The walk both folds share: a texture at the finer of the two sizes, each
 * texel from the nearest texels of `base` (white and opaque when base < 0)
 * and of `scale` (at the texel's centre, as the kernels sample): keep = 1 -
 * factor x channel `shift` of scale / 255, clamped to [0, 1], multiplies the
 * base's linear colour (into_alpha 0), or the alpha is the channel itself
 * (into_alpha 1). Wrap modes and colour space the base's (scale's wraps and
 * sRGB when base < 0). */
static int32_t fold(pb_scene_builder *b, int32_t base, int32_t scale, int shift, float factor, int into_alpha)
{
    /* copies: adding the texture may move the builder's arrays */
    const pb_texture st = b->textures[scale];
    const pb_texture bt = base >= 0 ? b->textures[base] : st;
    uint32_t W = bt.width > st.width ? bt.width : st.width, H = bt.height > st.height ? bt.height : st.height;
    uint32_t *out = malloc((size_t)W * H * sizeof *out);
    /* a colour fold's texel channel is a function of two bytes (the base's
     * channel, the scale's): tabulated once, 2^16 transfer-function pairs in
     * place of 3 per texel (12.6 M powf pairs for a 2048^2 texture), the
     * same bits */
    uint8_t *folded = into_alpha ? NULL : malloc(256 * 256);
    /* the nearest texel's column and row in each texture, per output column
     * and row: pb_texel_index's axes are independent, so 2 (W + H) calls in
     * place of 2 W H */
    uint32_t *axes = malloc(2 * ((size_t)W + H) * sizeof *axes);
    if (!out || (!into_alpha && !folded) || !axes) {
        free(out);
        free(folded);
        free(axes);
        b->out_of_memory = 1;
        return -1;
    }
    uint32_t *scol = axes, *bcol = axes + W, *srow = axes + 2 * (size_t)W, *brow = srow + H;
    for (uint32_t x = 0; x < W; ++x) {
        float s = ((float)x + 0.5f) / (float)W;
        scol[x] = pb_texel_index(s, 0.5f, st.width, 1, PB_WRAP_CLAMP, PB_WRAP_CLAMP);
        bcol[x] = pb_texel_index(s, 0.5f, bt.width, 1, PB_WRAP_CLAMP, PB_WRAP_CLAMP);
    }
    for (uint32_t y = 0; y < H; ++y) {
        float t = ((float)y + 0.5f) / (float)H;
        srow[y] = pb_texel_index(0.5f, t, 1, st.height, PB_WRAP_CLAMP, PB_WRAP_CLAMP) * st.width;
        brow[y] = pb_texel_index(0.5f, t, 1, bt.height, PB_WRAP_CLAMP, PB_WRAP_CLAMP) * bt.width;
    }
    if (folded) {
        float linear[256];
        for (int c = 0; c < 256; ++c)
            linear[c] = pb_srgb_to_linear((float)c / 255.f);
        for (int m = 0; m < 256; ++m) {
            float keep = 1.f - factor * (float)m / 255.f;
            keep = keep < 0.f ? 0.f : (keep > 1.f ? 1.f : keep);
            for (int c = 0; c < 256; ++c)
                folded[256 * m + c] = (uint8_t)lrintf(pb_linear_to_srgb(linear[c] * keep) * 255.f);
        }
    }
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
            uint32_t m = b->texels[st.offset + srow[y] + scol[x]];
            uint32_t mb = (m >> shift) & 0xffu;
            uint32_t c = base >= 0 ? b->texels[bt.offset + brow[y] + bcol[x]] : 0xffffffffu;
            uint32_t texel;
            if (into_alpha) {
                texel = (c & 0x00ffffffu) | mb << 24;
            } else {
                texel = c & 0xff000000u;
                for (int k = 0; k < 3; ++k)
                    texel |= (uint32_t)folded[256 * mb + ((c >> (8 * k)) & 0xffu)] << (8 * k);
            }
            out[(size_t)y * W + x] = texel;
        }
    int32_t id = pb_sb_add_texture(b, out, W, H, bt.wrap_s, bt.wrap_t, base >= 0 ? bt.srgb : 1u);
    free(out);
    free(folded);
    free(axes);
    return id;
}

int32_t pb_sb_fold_metallic(pb_scene_builder *b, int32_t base, int32_t metallic_roughness, float factor)
{
    return fold(b, base, metallic_roughness, 16, factor, 0); /* blue: metalness */
}

int32_t pb_sb_fold_transmission_scale(pb_scene_builder *b, int32_t base, int32_t transmission)
{
    return fold(b, base, transmission, 0, 1.f, 1); /* red: transmission */
}

int32_t pb_sb_opaque_texture(pb_scene_builder *b, int32_t tex)
{
    const pb_texture t = b->textures[tex];
    uint64_t n = (uint64_t)t.width * t.height, i = 0;
    while (i < n && (b->texels[t.offset + i] >> 24) == 0xffu)
        ++i;
    if (i == n)
        return tex;
    uint32_t *out = malloc((size_t)n * sizeof *out);
    if (!out) {
        b->out_of_memory = 1;
        return -1;
    }
    for (i = 0; i < n; ++i)
        out[i] = b->texels[t.offset + i] | 0xff000000u;
    int32_t id = pb_sb_add_texture(b, out, t.width, t.height, t.wrap_s, t.wrap_t, t.srgb);
    free(out);
    return id;
}
