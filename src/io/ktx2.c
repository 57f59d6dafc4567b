/* KTX 2.0 encoder (ktx2.h). */
#include "io/ktx2.h"

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

unsigned char *pb_ktx2_encode(const pb_ktx2_image *img, uint64_t *size)
{
    static const unsigned char id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    uint32_t channels, bits;
    if (img->vk_format == PB_VK_FORMAT_R32G32B32A32_SFLOAT)
        channels = 4, bits = 32;
    else if (img->vk_format == PB_VK_FORMAT_R16G16_SFLOAT)
        channels = 2, bits = 16;
    else if (img->vk_format == PB_VK_FORMAT_R32_UINT)
        channels = 1, bits = 32;
    else
        return NULL;
    uint32_t texel = channels * bits / 8, dfd_bytes = 4 + 24 + 16 * channels;
    uint32_t dfd_at = 12 + 36 + 32 + 24; /* identifier, header, index, one level */
    /* level data aligned to lcm(texel size, 4): 16 or 4 here */
    uint64_t data_at = (dfd_at + dfd_bytes + texel - 1) / texel * texel;
    uint64_t data_bytes = (uint64_t)img->width * img->height * texel;
    unsigned char *b = calloc(1, (size_t)(data_at + data_bytes));
    if (!b)
        return NULL;
    memcpy(b, id, 12);
    uint32_t header[9] = {img->vk_format, bits / 8, img->width, img->height, 0 /* 2D */, 0 /* not an array */,
                          1 /* faces */, 1 /* levels */, 0 /* no supercompression */};
    for (int k = 0; k < 9; ++k)
        put_u32(b + 12 + 4 * k, header[k]);
    put_u32(b + 48, dfd_at), put_u32(b + 52, dfd_bytes); /* DFD; no key/value data, no supercompression data */
    put_u64(b + 80, data_at), put_u64(b + 88, data_bytes), put_u64(b + 96, data_bytes);
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
    int integer = img->vk_format == PB_VK_FORMAT_R32_UINT;
    for (uint32_t c = 0; c < channels; ++c) {
        unsigned char *s = d + 28 + 16 * c;
        /* bit offset, bit length - 1, channel with the FLOAT and SIGNED qualifiers (none for unsigned integers) */
        put_u32(s, c * bits | (bits - 1u) << 16 | (channel_id[c] | (integer ? 0u : 0x80u | 0x40u)) << 24);
        put_u32(s + 4, 0);                               /* sample position */
        put_u32(s + 8, integer ? 0u : 0xBF800000u);      /* lower: 0, or -1.0f */
        put_u32(s + 12, integer ? 0xFFFFFFFFu : 0x3F800000u); /* upper: the largest value, or 1.0f */
    }
    /* components little-endian whatever the host: floats or uint32 (32 bits) or halves (R16G16) */
    uint64_t components = (uint64_t)img->width * img->height * channels;
    for (uint64_t i = 0; i < components; ++i) {
        if (bits == 32) {
            uint32_t v;
            memcpy(&v, (const float *)img->texels + i, 4);
            put_u32(b + data_at + 4 * i, v);
        } else {
            uint16_t v = ((const uint16_t *)img->texels)[i];
            b[data_at + 2 * i] = (unsigned char)v, b[data_at + 2 * i + 1] = (unsigned char)(v >> 8);
        }
    }
    *size = data_at + data_bytes;
    return b;
}
