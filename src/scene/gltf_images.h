// Images of a glTF file decoded to RGBA8 for tinygltf's image callback:
// stb_image (PNG, JPEG, ...), libwebp (WebP, for EXT_texture_webp) or libavif
// (AVIF, for EXT_texture_avif). An
// image that fails to decode, reaches past its buffer, or whose header claims
// more pixels than the limits allow is a warning (the material falls back to
// its factor), never a failed load.
#pragma once

#include "probebake/base.h"

#include <tiny_gltf.h>

#include <cstdint>
#include <string>

namespace pb_gltf {

struct image_ctx {
    const char *path;
    pb_log log;
    int skip;
    uint64_t max_pixels;  // per image
    uint64_t left_pixels; // what the file's images may still decode to
    const tinygltf::Model *model; // being filled: its buffers and views are read before images in views
};

// tinygltf::LoadImageDataFunction; `user` is an image_ctx.
bool load_image(tinygltf::Image *image, const int index, std::string *, std::string *, int, int,
                const unsigned char *bytes, int size, void *user);

} // namespace pb_gltf
