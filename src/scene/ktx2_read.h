/* KTX2 images as glTF's KHR_texture_basisu stores them, read to RGBA8.
 *
 * The container (Khronos KTX 2.0: header, level index, data format
 * descriptor, supercompression global data) is parsed here, bounds-checked
 * field by field; the base level's first image is decoded: ETC1S
 * (BasisLZ, basis_etc1s.h) or UASTC (stored as it is or Zstandard
 * supercompressed, basis_uastc.h). */
#ifndef PB_SCENE_KTX2_READ_H
#define PB_SCENE_KTX2_READ_H

#include <stddef.h>
#include <stdint.h>

typedef enum pb_ktx2_codec {
    PB_KTX2_ETC1S, /* Basis Universal ETC1S, BasisLZ supercompressed: decoded */
    PB_KTX2_UASTC, /* Basis Universal UASTC, none or Zstandard supercompressed: decoded */
    PB_KTX2_OTHER, /* a Vulkan format or another model: not decoded */
} pb_ktx2_codec;

typedef struct pb_ktx2_info {
    uint32_t width, height; /* the base level's */
    pb_ktx2_codec codec;
    int has_alpha; /* an alpha slice (ETC1S) or channel (UASTC) */
} pb_ktx2_info;

/* Whether the bytes start with KTX2's identifier. */
int pb_ktx2_is(const uint8_t *bytes, size_t size);

/* Reads the header and descriptor: 0, or -1 with *why set (a static
 * string) where the container is malformed. */
int pb_ktx2_peek(const uint8_t *bytes, size_t size, pb_ktx2_info *info, const char **why);

/* Decodes the base level's first image into rgba (width x height x 4 bytes,
 * rows top-down as stored; alpha 255 without an alpha slice or channel). 0,
 * or -1 with *why set: a malformed file, a codec not decoded, or out of
 * memory. */
int pb_ktx2_decode(const uint8_t *bytes, size_t size, uint8_t *rgba, const char **why);

#endif
