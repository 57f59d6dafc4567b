/* KTX 2.0 writer (ktx2.h). */
#include "io/ktx2.h"
#include "io/ktx2_layout.h"
#include "common/common.h"
#include "probebake/files.h"

#include <stdlib.h>
#include <string.h>

static void put_u32(unsigned char *b, uint32_t v)
{
    for (int k = 0; k < 4; ++k)
        b[k] = (unsigned char)(v >> (8 * k));
}

static void put_u64(unsigned char *b, uint64_t v)
{
    for (int k = 0; k < 8; ++k)
        b[k] = (unsigned char)(v >> (8 * k));
}

#define BAND_BYTES (1u << 20) /* texels asked for and written at a time */

pb_result pb_ktx2_stage(const char *path, uint32_t vk_format, uint32_t width, uint32_t height, pb_ktx2_rows_fn rows,
                        void *user, pb_output **staged, pb_error *err)
{
    *staged = NULL;
    uint32_t channels, bits;
    if (vk_format == PB_VK_FORMAT_R32G32B32A32_SFLOAT)
        channels = 4, bits = 32;
    else if (vk_format == PB_VK_FORMAT_R16G16_SFLOAT)
        channels = 2, bits = 16;
    else if (vk_format == PB_VK_FORMAT_R32_UINT)
        channels = 1, bits = 32;
    else
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: VkFormat %u is not one the texture export writes", path,
                       vk_format);
    uint32_t texel = channels * bits / 8, dfd_bytes = 4 + 24 + 16 * channels;
    uint32_t dfd_at = PB_KTX2_LEVELS_AT + PB_KTX2_LEVEL_BYTES; /* identifier, header, index, one level */
    /* level data aligned to lcm(texel size, 4): 16 or 4 here */
    uint32_t data_at = (dfd_at + dfd_bytes + texel - 1) / texel * texel;
    uint64_t row_bytes = (uint64_t)width * texel, data_bytes = row_bytes * height;
    uint32_t band = row_bytes && row_bytes < BAND_BYTES ? (uint32_t)(BAND_BYTES / row_bytes) : 1u;
    unsigned char head[256];
    memset(head, 0, sizeof head);
    unsigned char *b = head;
    memcpy(b, pb_ktx2_identifier, sizeof pb_ktx2_identifier);
    uint32_t header[9] = {vk_format, bits / 8, width, height, 0 /* 2D */, 0 /* not an array */,
                          1 /* faces */, 1 /* levels */, 0 /* no supercompression */};
    for (int k = 0; k < 9; ++k)
        put_u32(b + 12 + 4 * k, header[k]);
    put_u32(b + 48, dfd_at), put_u32(b + 52, dfd_bytes); /* DFD; no key/value data, no supercompression data */
    put_u64(b + PB_KTX2_LEVELS_AT, data_at), put_u64(b + PB_KTX2_LEVELS_AT + 8, data_bytes);
    put_u64(b + PB_KTX2_LEVELS_AT + 16, data_bytes);
    /* Data Format Descriptor: one basic block (Khronos Data Format 1.3) */
    unsigned char *d = b + dfd_at;
    put_u32(d, dfd_bytes);
    put_u32(d + 4, 0);                                   /* vendor 0 (Khronos), descriptor type 0 (basic) */
    put_u32(d + 8, 2u | (24u + 16u * channels) << 16);   /* version 2, block size */
    put_u32(d + 12, 1u | 1u << 8 | 1u << 16);             /* model RGBSDA, primaries BT.709, transfer linear */
    put_u32(d + 16, 0);                                  /* texel block 1 x 1 x 1 x 1 */
    put_u32(d + 20, texel);                              /* bytes in plane 0 */
    put_u32(d + 24, 0);
    static const uint32_t channel_id[4] = {0, 1, 2, 15}; /* R, G, B, A */
    int integer = vk_format == PB_VK_FORMAT_R32_UINT;
    for (uint32_t c = 0; c < channels; ++c) {
        unsigned char *s = d + 28 + 16 * c;
        /* bit offset, bit length - 1, channel with the FLOAT and SIGNED qualifiers (none for unsigned integers) */
        put_u32(s, c * bits | (bits - 1u) << 16 | (channel_id[c] | (integer ? 0u : 0x80u | 0x40u)) << 24);
        put_u32(s + 4, 0);                               /* sample position */
        put_u32(s + 8, integer ? 0u : 0xBF800000u);      /* lower: 0, or -1.0f */
        put_u32(s + 12, integer ? 0xFFFFFFFFu : 0x3F800000u); /* upper: the largest value, or 1.0f */
    }
    uint64_t band_bytes = band * row_bytes;
    band_bytes = band_bytes ? band_bytes : 1u;
    void *texels = malloc((size_t)band_bytes);
    unsigned char *bytes = malloc((size_t)band_bytes);
    pb_output *out = NULL;
    pb_result r = texels && bytes ? pb_output_begin(path, NULL, NULL, &out, err)
                                  : pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    if (r == PB_OK)
        r = pb_output_put(out, head, data_at, err);
    for (uint32_t y = 0; y < height && r == PB_OK; y += band) {
        uint32_t count = height - y < band ? height - y : band;
        rows(user, y, count, texels);
        /* components little-endian whatever the host: floats or uint32 (32 bits) or halves (R16G16) */
        uint64_t components = (uint64_t)width * count * channels;
        for (uint64_t i = 0; i < components; ++i) {
            if (bits == 32) {
                uint32_t v;
                memcpy(&v, (const uint32_t *)texels + i, 4);
                put_u32(bytes + 4 * i, v);
            } else {
                uint16_t v = ((const uint16_t *)texels)[i];
                bytes[2 * i] = (unsigned char)v, bytes[2 * i + 1] = (unsigned char)(v >> 8);
            }
        }
        r = pb_output_put(out, bytes, (uint64_t)count * row_bytes, err);
    }
    if (r == PB_OK)
        *staged = out;
    else
        pb_output_abort(out);
    free(texels);
    free(bytes);
    return r;
}
