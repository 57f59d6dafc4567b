/* Colour textures rewritten on the host for what the kernels read. The
 * kernels read one colour texture per material (its colour the albedo, its
 * alpha the coverage), so textures that scale either are folded into it:
 * glTF's metallic (metallicFactor x the metallicRoughness texture's blue
 * channel, linear; a Lambertian bake reflects base colour x (1 - metallic))
 * into the colour, and for a material that was opaque
 * KHR_materials_transmission's texture (red) into the alpha, as the scale of
 * its transmission. One walk does both (texture_fold.c). */
#ifndef PB_SCENE_TEXTURE_FOLD_H
#define PB_SCENE_TEXTURE_FOLD_H

#include "scene/scene_builder.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Adds an sRGB texture holding base x (1 - factor x metallic): at each texel
 * of the finer of the two sizes, the nearest texels of both (as the kernels
 * sample, at the texel's centre), linear products rounded back to sRGB, the
 * base's alpha and wrap modes. base < 0: no base colour texture, so the
 * texture is (1 - factor x metallic) alone, grey, opaque, with the metallic
 * texture's size and wrap modes. Returns its index, or -1 out of host memory. */
int32_t pb_sb_fold_metallic(pb_scene_builder *b, int32_t base, int32_t metallic_roughness, float factor);

/* Adds a texture whose alpha is the transmission texture's red channel as it
 * stands, for a material that was opaque (pb_material.transmission_in_alpha:
 * the kernels scale its transmission by it per texel and take coverage 1),
 * at each texel of the finer of the two sizes (nearest texels, at texel
 * centres); colour, wrap modes and colour space the base's (white, sRGB,
 * with the transmission texture's wraps, when base < 0). A material that was
 * alpha-blended keeps its coverage in its alpha and reads the transmission
 * texture beside it (pb_material.transmission_texture). -1 out of host
 * memory. */
int32_t pb_sb_fold_transmission_scale(pb_scene_builder *b, int32_t base, int32_t transmission);

/* Texture `tex` as it reads under alpha mode OPAQUE, for a material that
 * becomes alpha-blended (KHR_materials_transmission): itself when every texel
 * has alpha 255, else a copy with alpha 255. -1 out of host memory. */
int32_t pb_sb_opaque_texture(pb_scene_builder *b, int32_t tex);

#ifdef __cplusplus
}
#endif

#endif
