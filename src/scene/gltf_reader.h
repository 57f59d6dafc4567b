// What the glTF reader's files share: the file being read and what is
// decoded alongside it (gltf_load.cpp reads nodes, meshes and accessors,
// gltf_materials.cpp materials and textures).
#pragma once

#include "scene/scene_builder.h"

#include <tiny_gltf.h>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace pb_gltf {

typedef double mat4[16]; // column-major, as glTF

struct image_ctx; // gltf_images.h

struct reader {
    const tinygltf::Model &m;
    const char *path;
    pb_scene_builder *b;
    pb_error *err;
    std::vector<int32_t> texture_map; // glTF texture -> pb texture (-1: none / failed / not read yet)
    uint32_t default_material = 0;
    std::vector<std::array<double, 6>> uv_transform; // per material: KHR_texture_transform of its UVs
    // EXT_meshopt_compression: the decoded bytes of each compressed bufferView
    std::vector<std::vector<unsigned char>> view_data;
    std::vector<char> view_decoded;
    // KHR_draco_mesh_compression: the accessors of the primitive being read,
    // decoded (tightly packed bytes and element count), in place of their views
    struct decoded_accessor {
        std::vector<unsigned char> bytes;
        size_t count;
    };
    std::map<int, decoded_accessor> draco_accessors;
    // colour textures with a metallic texture folded in: (base, metallic texture, factor bits) -> texture
    std::map<std::array<int64_t, 3>, int32_t> folded;
    // pb_scene_desc.face_normals: NORMAL is read (and checked) but the face normals are kept
    bool face_normals = false;
    // the file's images, decoded when a texture the bake reads needs one
    image_ctx *images = nullptr;
    // per glTF texture: made yet (texture_of makes it when a material first
    // reads it), and whether some material reads it as colour (sRGB)
    std::vector<char> texture_read;
    std::vector<int> texture_srgb;
    bool skip_textures = false; // pb_scene_desc.skip_textures: none is made
    bool no_normal_maps = false; // pb_scene_desc.no_normal_maps: normalTexture not read
};

// A one-line error naming the file; returns `code`.
pb_result fail(reader &r, pb_result code, const std::string &what);

} // namespace pb_gltf
