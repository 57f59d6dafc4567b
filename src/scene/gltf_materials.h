// Materials and textures of a glTF file: decoded images to scene textures,
// glTF materials (metallic-roughness, spec-gloss, unlit, emissive strength,
// texture transforms, metallic textures folded into the colour,
// transmission as coverage) to pb_material.
#pragma once

#include "scene/gltf_reader.h"

namespace pb_gltf {

// Every glTF texture as a scene texture (r.texture_map; -1 where its image did
// not decode). skip: textures are not decoded (info, bench).
pb_result read_textures(reader &r, int skip);
// Every material, then the default one for primitives without (r.default_material),
// and each material's UV transform (r.uv_transform).
void read_materials(reader &r);

} // namespace pb_gltf
