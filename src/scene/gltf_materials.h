// Materials and textures of a glTF file: decoded images to scene textures,
// glTF materials (metallic-roughness, spec-gloss, unlit, emissive strength,
// texture transforms, metallic textures folded into the colour,
// transmission as coverage) to pb_material.
#pragma once

#include "scene/gltf_reader.h"

namespace pb_gltf {

// Prepares the glTF textures to be made on demand (r.texture_map, all -1 until
// a material reads one). skip: none is ever decoded (info, bench).
pb_result read_textures(reader &r, int skip);
// Every material, then the default one for primitives without (r.default_material),
// and each material's UV transform (r.uv_transform). The textures it reads
// where the bake samples (colour, emissive, a metallic texture folded under a
// factor > 0, transmission) are decoded and made as it goes; the rest are
// counted in stats.textures_unread.
void read_materials(reader &r);

} // namespace pb_gltf
