/* The metallic texture folded into the base colour (metallic_fold.h). */
#include "scene/metallic_fold.h"
#include "bvh/alpha.h"
#include "common/srgb.h"

#include <math.h>
#include <stdlib.h>

int32_t pb_sb_fold_metallic(pb_scene_builder *b, int32_t base, int32_t metallic_roughness, float factor)
{
    /* copies: adding the texture may move the builder's arrays */
    const pb_texture mr = b->textures[metallic_roughness];
    const pb_texture bt = base >= 0 ? b->textures[base] : mr;
    uint32_t W = bt.width > mr.width ? bt.width : mr.width, H = bt.height > mr.height ? bt.height : mr.height;
    uint32_t *out = malloc((size_t)W * H * sizeof *out);
    if (!out) {
        b->out_of_memory = 1;
        return -1;
    }
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
            float s = ((float)x + 0.5f) / (float)W, t = ((float)y + 0.5f) / (float)H;
            uint32_t m = b->texels[mr.offset + pb_texel_index(s, t, mr.width, mr.height, PB_WRAP_CLAMP, PB_WRAP_CLAMP)];
            float keep = 1.f - factor * (float)((m >> 16) & 0xffu) / 255.f; /* blue: metalness */
            keep = keep < 0.f ? 0.f : (keep > 1.f ? 1.f : keep);
            uint32_t c = base >= 0 ? b->texels[bt.offset + pb_texel_index(s, t, bt.width, bt.height, PB_WRAP_CLAMP,
                                                                         PB_WRAP_CLAMP)]
                                   : 0xffffffffu;
            uint32_t texel = c & 0xff000000u;
            for (int k = 0; k < 3; ++k) {
                float l = pb_srgb_to_linear((float)((c >> (8 * k)) & 0xffu) / 255.f) * keep;
                texel |= (uint32_t)lrintf(pb_linear_to_srgb(l) * 255.f) << (8 * k);
            }
            out[(size_t)y * W + x] = texel;
        }
    int32_t id = pb_sb_add_texture(b, out, W, H, bt.wrap_s, bt.wrap_t, 1);
    free(out);
    return id;
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

int32_t pb_sb_fold_transmission(pb_scene_builder *b, int32_t base, int base_opaque, int32_t transmission,
                                float pass)
{
    const pb_texture tt = b->textures[transmission];
    const pb_texture bt = base >= 0 ? b->textures[base] : tt;
    uint32_t W = bt.width > tt.width ? bt.width : tt.width, H = bt.height > tt.height ? bt.height : tt.height;
    uint32_t *out = malloc((size_t)W * H * sizeof *out);
    if (!out) {
        b->out_of_memory = 1;
        return -1;
    }
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
            float s = ((float)x + 0.5f) / (float)W, t = ((float)y + 0.5f) / (float)H;
            uint32_t r = b->texels[tt.offset + pb_texel_index(s, t, tt.width, tt.height, PB_WRAP_CLAMP, PB_WRAP_CLAMP)];
            float keep = 1.f - pass * (float)(r & 0xffu) / 255.f; /* red: transmission */
            keep = keep < 0.f ? 0.f : (keep > 1.f ? 1.f : keep);
            uint32_t c = base >= 0 ? b->texels[bt.offset + pb_texel_index(s, t, bt.width, bt.height, PB_WRAP_CLAMP,
                                                                         PB_WRAP_CLAMP)]
                                   : 0xffffffffu;
            float a = base_opaque ? 1.f : (float)(c >> 24) / 255.f;
            out[(size_t)y * W + x] = (c & 0x00ffffffu) | (uint32_t)lrintf(a * keep * 255.f) << 24;
        }
    int32_t id = pb_sb_add_texture(b, out, W, H, bt.wrap_s, bt.wrap_t, base >= 0 ? bt.srgb : 1u);
    free(out);
    return id;
}
