// Images of a glTF file decoded to RGBA8: stb_image (PNG, JPEG, ...), libwebp
// (WebP, for EXT_texture_webp) or libavif (AVIF, for EXT_texture_avif).
// tinygltf's image callback only keeps each image's file bytes; an image is
// decoded when a texture the bake reads needs it (decode_image), so normal,
// occlusion and other maps the bake never samples cost neither decoding nor
// the pixel budget. An image that fails to decode, reaches past its buffer,
// or whose header claims more pixels than the limits allow is a warning (the
// material falls back to its factor), never a failed load.
#pragma once

#include "probebake/base.h"

#include <tiny_gltf.h>

#include <cstdint>
#include <string>
#include <vector>

namespace pb_gltf {

// An image decoded ahead of its turn (prefetch_images), held until the
// material pass asks for it.
struct early_image {
    int width = 0, height = 0; // 0: none held
    std::vector<unsigned char> rgba;
};

struct image_ctx {
    const char *path;
    pb_log log;
    int skip;
    uint64_t max_pixels;  // per image
    uint64_t left_pixels; // what the file's images may still decode to
    tinygltf::Model *model; // being filled: its buffers and views are read before images in views
    std::vector<char> encoded;  // per image: image.image holds its file bytes, not decoded yet
    std::vector<early_image> early; // per image: decoded by prefetch_images, not yet asked for
    uint32_t ahead;                 // pb_scene_desc::decode_ahead
};

// tinygltf::LoadImageDataFunction; `user` is an image_ctx. Keeps the image's
// file bytes in image->image, undecoded (width 0).
bool load_image(tinygltf::Image *image, const int index, std::string *, std::string *, int, int,
                const unsigned char *bytes, int size, void *user);
// Decodes image `index` of ctx->model in place, once (later calls only
// answer); whether it now holds width x height RGBA8 pixels.
bool decode_image(image_ctx *ctx, int index);
// Decodes the images `order` names on the host's threads, ahead of the
// decode_image calls that will ask for them, a batch of one per thread at a
// time, until what they decoded passes the file's pixel budget. Only what
// decoded without a word is kept; decode_image then charges the budget and
// warns as if it decoded it at that moment, so the scene and the messages
// are the same as decoding in turn (what failed is decoded again in turn, to
// say why). A cache: the order need not be exact. ctx->ahead chooses when.
void prefetch_images(image_ctx *ctx, const std::vector<int> &order);
// Frees every image's bytes and pixels once the scene holds its textures.
void release_images(image_ctx *ctx);

} // namespace pb_gltf
