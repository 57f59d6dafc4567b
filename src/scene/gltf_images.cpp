// glTF images to RGBA8 (gltf_images.h).
#include "scene/gltf_images.h"

extern "C" {
#include "common/common.h"
#include "scene/ktx2_read.h"
}

#include <avif/avif.h>
#include <stb_image.h>
#include <webp/decode.h>

#include <cstring>

namespace pb_gltf {
namespace {

// tinygltf hands an image stored in a bufferView to the loader without
// checking that the view lies inside its buffer: a view past the end would
// have the decoder read past it. So the view is checked here first.
bool image_bytes_inside(const image_ctx *ctx, const tinygltf::Image *image, int index, const unsigned char *bytes,
                        int size)
{
    if (image->bufferView < 0)
        return true; // a data URI or a file: tinygltf decoded or read exactly those bytes
    const tinygltf::Model &m = *ctx->model;
    bool inside = false;
    if ((size_t)image->bufferView < m.bufferViews.size()) {
        const tinygltf::BufferView &v = m.bufferViews[(size_t)image->bufferView];
        if (v.buffer >= 0 && (size_t)v.buffer < m.buffers.size()) {
            const std::vector<unsigned char> &data = m.buffers[(size_t)v.buffer].data;
            inside = v.byteOffset <= data.size() && v.byteLength <= data.size() - v.byteOffset && size >= 0 &&
                     (size_t)size == v.byteLength && bytes == data.data() + v.byteOffset;
        }
    }
    if (!inside)
        pb_logf(&ctx->log, PB_LOG_WARN, "%s: image %d: bufferView %d lies outside its buffer; its factor is used",
                ctx->path, index, image->bufferView);
    return inside;
}

// Whether an image's pixel count fits the limits; warns when it does not.
bool image_fits(const image_ctx *ctx, int index, int w, int h)
{
    uint64_t n = (uint64_t)w * (uint64_t)h;
    if (n <= ctx->max_pixels && n <= ctx->left_pixels)
        return true;
    pb_logf(&ctx->log, PB_LOG_WARN, "%s: image %d is %d x %d pixels, more than the %llu pixels %s; its factor is used",
            ctx->path, index, w, h, (unsigned long long)(n > ctx->max_pixels ? ctx->max_pixels : ctx->left_pixels),
            n > ctx->max_pixels ? "an image may decode to" : "the file's images may still decode to");
    return false;
}

// A decoded image of w x h RGBA8 pixels becomes the glTF image's, and counts
// against the file's pixel budget.
void keep_rgba(image_ctx *ctx, tinygltf::Image *image, const unsigned char *px, int w, int h)
{
    ctx->left_pixels -= (uint64_t)w * (uint64_t)h;
    image->width = w;
    image->height = h;
    image->image.assign(px, px + (size_t)w * h * 4);
}

// RIFF container of a WebP image
bool is_webp(const unsigned char *bytes, int size)
{
    return size >= 12 && memcmp(bytes, "RIFF", 4) == 0 && memcmp(bytes + 8, "WEBP", 4) == 0;
}

bool load_webp(tinygltf::Image *image, int index, const unsigned char *bytes, int size, image_ctx *ctx)
{
    int w = 0, h = 0;
    unsigned char *px = nullptr;
    // the header first, as for stb: nothing is allocated for a size past the limits
    if (WebPGetInfo(bytes, (size_t)size, &w, &h) && w > 0 && h > 0) {
        if (!image_fits(ctx, index, w, h))
            return true;
        int iw = w, ih = h;
        px = WebPDecodeRGBA(bytes, (size_t)size, &w, &h);
        if (px && (w != iw || h != ih)) {
            WebPFree(px);
            px = nullptr;
        }
    }
    if (!px) {
        pb_logf(&ctx->log, PB_LOG_WARN,
                "%s: image %d could not be decoded (corrupt WebP); a texture reading it falls back to its core "
                "image if it has one, else to its material's factor",
                ctx->path, index);
        return true;
    }
    keep_rgba(ctx, image, px, w, h);
    WebPFree(px);
    return true;
}

// KTX2 (KHR_texture_basisu): Basis Universal's ETC1S or UASTC decoded by
// scene/ktx2_read.c, after the header's size is checked against the limits.
// A malformed file is warned about and left undecoded, so a texture reading
// it falls back to its core image or its factor.
bool load_ktx2(tinygltf::Image *image, int index, const unsigned char *bytes, int size, image_ctx *ctx)
{
    pb_ktx2_info info;
    const char *why = nullptr;
    if (pb_ktx2_peek(bytes, (size_t)size, &info, &why) == 0) {
        if (info.width > INT32_MAX / 4 || info.height > INT32_MAX / 4 ||
            !image_fits(ctx, index, (int)info.width, (int)info.height))
            return true;
        image->image.resize((size_t)info.width * info.height * 4);
        if (pb_ktx2_decode(bytes, (size_t)size, image->image.data(), &why) == 0) {
            ctx->left_pixels -= (uint64_t)info.width * info.height;
            image->width = (int)info.width;
            image->height = (int)info.height;
            return true;
        }
        image->image.clear();
    }
    pb_logf(&ctx->log, PB_LOG_WARN,
            "%s: image %d (KTX2) could not be decoded: %s; a texture reading it falls back to its core image if it "
            "has one, else to its material's factor",
            ctx->path, index, why);
    return true;
}

// AVIF (ISOBMFF with an AVIF brand), for EXT_texture_avif
bool is_avif(const unsigned char *bytes, int size)
{
    avifROData data = {bytes, (size_t)size};
    return size >= 12 && avifPeekCompatibleFileType(&data);
}

// libavif with its AV1 decoder: the header is parsed first (sizes checked
// against the limits before any frame is decoded), then the first frame,
// converted to 8-bit RGBA (alpha 255 where the file has none).
bool load_avif(tinygltf::Image *image, int index, const unsigned char *bytes, int size, image_ctx *ctx)
{
    avifDecoder *dec = avifDecoderCreate();
    bool ok = false;
    uint32_t w = 0, h = 0;
    if (dec) {
        dec->maxThreads = 1;
        dec->ignoreExif = dec->ignoreXMP = AVIF_TRUE;
        ok = avifDecoderSetIOMemory(dec, bytes, (size_t)size) == AVIF_RESULT_OK &&
             avifDecoderParse(dec) == AVIF_RESULT_OK && dec->image->width > 0 && dec->image->height > 0 &&
             dec->image->width <= INT32_MAX && dec->image->height <= INT32_MAX;
        if (ok) {
            w = dec->image->width, h = dec->image->height;
            if (!image_fits(ctx, index, (int)w, (int)h)) {
                avifDecoderDestroy(dec);
                return true;
            }
            ok = avifDecoderNextImage(dec) == AVIF_RESULT_OK && dec->image->width == w && dec->image->height == h;
        }
        if (ok) {
            avifRGBImage rgb;
            avifRGBImageSetDefaults(&rgb, dec->image);
            rgb.format = AVIF_RGB_FORMAT_RGBA;
            rgb.depth = 8;
            avifRGBImageAllocatePixels(&rgb);
            ok = rgb.pixels && avifImageYUVToRGB(dec->image, &rgb) == AVIF_RESULT_OK;
            if (ok) {
                image->image.resize((size_t)w * h * 4);
                for (uint32_t y = 0; y < h; ++y)
                    memcpy(image->image.data() + (size_t)y * w * 4, rgb.pixels + (size_t)y * rgb.rowBytes, (size_t)w * 4);
            }
            avifRGBImageFreePixels(&rgb);
        }
        avifDecoderDestroy(dec);
    }
    if (!ok) {
        image->image.clear();
        pb_logf(&ctx->log, PB_LOG_WARN,
                "%s: image %d could not be decoded (corrupt AVIF); a texture reading it falls back to its core "
                "image if it has one, else to its material's factor",
                ctx->path, index);
        return true;
    }
    ctx->left_pixels -= (uint64_t)w * (uint64_t)h;
    image->width = (int)w;
    image->height = (int)h;
    return true;
}

// A file's image bytes to RGBA8 pixels in image->image (left empty, with a
// warning, where they do not decode or exceed the limits).
bool decode(tinygltf::Image *image, int index, const unsigned char *bytes, int size, image_ctx *ctx)
{
    if (is_webp(bytes, size))
        return load_webp(image, index, bytes, size, ctx);
    if (is_avif(bytes, size))
        return load_avif(image, index, bytes, size, ctx);
    if (pb_ktx2_is(bytes, (size_t)size))
        return load_ktx2(image, index, bytes, size, ctx);
    // the header first: stb allocates what it claims before reading the data
    int w = 0, h = 0, c = 0;
    unsigned char *px = nullptr;
    if (stbi_info_from_memory(bytes, size, &w, &h, &c) && w > 0 && h > 0) {
        if (!image_fits(ctx, index, w, h))
            return true;
        int iw = w, ih = h;
        px = stbi_load_from_memory(bytes, size, &w, &h, &c, 4);
        if (px && (w != iw || h != ih)) { // never past what the header said
            stbi_image_free(px);
            px = nullptr;
        }
    }
    if (!px || w <= 0 || h <= 0) {
        pb_logf(&ctx->log, PB_LOG_WARN, "%s: image %d could not be decoded (%s); its factor is used", ctx->path,
                index, stbi_failure_reason() ? stbi_failure_reason() : "unknown");
        if (px)
            stbi_image_free(px);
        return true;
    }
    keep_rgba(ctx, image, px, w, h);
    stbi_image_free(px);
    return true;
}

} // namespace

bool load_image(tinygltf::Image *image, const int index, std::string *, std::string *, int, int,
                const unsigned char *bytes, int size, void *user)
{
    image_ctx *ctx = static_cast<image_ctx *>(user);
    image->width = image->height = 0;
    image->component = 4;
    image->bits = 8;
    image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    image->image.clear();
    if (ctx->skip || index < 0 || size <= 0 || !image_bytes_inside(ctx, image, index, bytes, size))
        return true;
    image->image.assign(bytes, bytes + size);
    if ((size_t)index >= ctx->encoded.size())
        ctx->encoded.resize((size_t)index + 1, 0);
    ctx->encoded[(size_t)index] = 1;
    return true;
}

bool decode_image(image_ctx *ctx, int index)
{
    if (!ctx->model || index < 0 || (size_t)index >= ctx->model->images.size())
        return false;
    tinygltf::Image &image = ctx->model->images[(size_t)index];
    if ((size_t)index < ctx->encoded.size() && ctx->encoded[(size_t)index]) {
        ctx->encoded[(size_t)index] = 0;
        std::vector<unsigned char> bytes;
        bytes.swap(image.image);
        early_image *e = (size_t)index < ctx->early.size() ? &ctx->early[(size_t)index] : nullptr;
        if (e && e->width > 0) {
            // decoded ahead: the header's check and the charge, as decode makes them
            if (image_fits(ctx, index, e->width, e->height)) {
                ctx->left_pixels -= (uint64_t)e->width * (uint64_t)e->height;
                image.width = e->width;
                image.height = e->height;
                image.image.swap(e->rgba);
            }
            *e = early_image();
        } else
            decode(&image, index, bytes.data(), (int)bytes.size(), ctx);
    }
    return image.width > 0 && image.height > 0 && image.image.size() == (size_t)image.width * image.height * 4;
}

namespace {

// One batch of prefetch_images: each image decoded on a thread of its own
// into its early_image, with a context whose log only counts (a decode that
// says anything is not kept) and whose budget is not charged yet.
struct prefetch_job {
    image_ctx *ctx;
    const int *batch;
};

void count_messages(pb_log_level, const char *, void *user)
{
    ++*static_cast<int *>(user);
}

void prefetch_range(void *user, uint64_t begin, uint64_t end)
{
    const prefetch_job *job = static_cast<const prefetch_job *>(user);
    for (uint64_t i = begin; i < end; ++i) {
        int index = job->batch[i], said = 0;
        const std::vector<unsigned char> &bytes = job->ctx->model->images[(size_t)index].image;
        // no exception may leave a thread (nor cross pb_parallel_for's C frames): an
        // allocation that fails here fails again in turn, where the loader reports it
        try {
            image_ctx quiet = {job->ctx->path, {count_messages, &said}, 0, job->ctx->max_pixels, UINT64_MAX,
                               job->ctx->model, {}, {}, PB_DECODE_AHEAD_NEVER};
            tinygltf::Image out;
            decode(&out, index, bytes.data(), (int)bytes.size(), &quiet);
            if (said == 0 && out.width > 0 && out.height > 0 &&
                out.image.size() == (size_t)out.width * (size_t)out.height * 4) {
                early_image &e = job->ctx->early[(size_t)index];
                e.width = out.width;
                e.height = out.height;
                e.rgba.swap(out.image);
            }
        } catch (...) {
        }
    }
}

} // namespace

void prefetch_images(image_ctx *ctx, const std::vector<int> &order)
{
    if (!ctx->model || ctx->skip || ctx->ahead == PB_DECODE_AHEAD_NEVER)
        return;
    std::vector<int> todo; // once each, those still holding their file bytes
    std::vector<char> seen(ctx->model->images.size(), 0);
    size_t bytes = 0;
    for (int index : order)
        if (index >= 0 && (size_t)index < seen.size() && !seen[(size_t)index] && (size_t)index < ctx->encoded.size() &&
            ctx->encoded[(size_t)index]) {
            seen[(size_t)index] = 1;
            todo.push_back(index);
            bytes += ctx->model->images[(size_t)index].image.size();
        }
    uint32_t threads = pb_host_threads();
    // nothing to overlap, or less to decode than starting threads costs (a
    // millisecond's worth: TextureTransformTest's five small PNGs load 1 ms
    // slower decoded ahead)
    if (ctx->ahead == PB_DECODE_AHEAD_AUTO && (todo.size() < 2 || threads < 2 || bytes < ((size_t)1 << 20)))
        return;
    if (todo.empty())
        return;
    ctx->early.resize(ctx->model->images.size());
    uint64_t decoded = 0;
    for (size_t first = 0; first < todo.size() && decoded <= ctx->left_pixels; first += threads) {
        size_t count = todo.size() - first < threads ? todo.size() - first : threads;
        prefetch_job job = {ctx, todo.data() + first};
        pb_parallel_for(count, 1, threads, prefetch_range, &job);
        for (size_t i = first; i < first + count; ++i)
            decoded += (uint64_t)ctx->early[(size_t)todo[i]].width * (uint64_t)ctx->early[(size_t)todo[i]].height;
    }
}

void release_images(image_ctx *ctx)
{
    if (!ctx->model)
        return;
    for (tinygltf::Image &image : ctx->model->images)
        std::vector<unsigned char>().swap(image.image);
    ctx->encoded.assign(ctx->encoded.size(), 0);
    std::vector<early_image>().swap(ctx->early);
}

} // namespace pb_gltf
