/* KTX 2.0 files (Khronos, "KTX File Format Specification" 2.0): one
 * uncompressed 2D image, one mip level, no supercompression, with the Data
 * Format Descriptor a reader needs for the formats the texture export writes
 * (float, and 32-bit unsigned integer for a sparse volume's layout). Three.js's KTX2Loader, libktx and Vulkan loaders read it. */
#ifndef PB_IO_KTX2_H
#define PB_IO_KTX2_H

#include <stddef.h>

#include <stdint.h>

#define PB_VK_FORMAT_R16G16_SFLOAT 83u
#define PB_VK_FORMAT_R32_UINT 98u
#define PB_VK_FORMAT_R32G32B32A32_SFLOAT 109u

typedef struct pb_ktx2_image {
    uint32_t vk_format;           /* one of the three above */
    uint32_t width, height;
    const void *texels;           /* float (R32G32B32A32), uint16_t halves (R16G16) or uint32_t (R32_UINT)
                                     per component; row y
                                     at y * width texels (KTX2's first row is texture row 0) */
} pb_ktx2_image;

/* The file's bytes (malloc'd) for img; NULL when out of memory or the format
 * is not one of the above. */
unsigned char *pb_ktx2_encode(const pb_ktx2_image *img, uint64_t *size);

#endif
