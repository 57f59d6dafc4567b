/* KTX 2.0 files (Khronos, "KTX File Format Specification" 2.0): one
 * uncompressed 2D image, one mip level, no supercompression, with the Data
 * Format Descriptor a reader needs for the formats the texture export writes
 * (float, and 32-bit unsigned integer for a sparse volume's layout).
 * Three.js's KTX2Loader, libktx and Vulkan loaders read it. */
#ifndef PB_IO_KTX2_H
#define PB_IO_KTX2_H

#include "probebake/base.h"
#include "probebake/files.h"

#include <stddef.h>

#include <stdint.h>

#define PB_VK_FORMAT_R16G16_SFLOAT 83u
#define PB_VK_FORMAT_R32_UINT 98u
#define PB_VK_FORMAT_R32G32B32A32_SFLOAT 109u

/* Rows [y0, y0 + count) of an image, row y at (y - y0) * width texels of
 * out: floats (R32G32B32A32), uint16_t halves (R16G16) or uint32_t
 * (R32_UINT) per component, in the host's order. KTX2's first row is
 * texture row 0. */
typedef void (*pb_ktx2_rows_fn)(void *user, uint32_t y0, uint32_t count, void *out);

/* Writes a KTX2 file of one width x height image in vk_format (one of the
 * three above) to path's temporary file (files.h's pb_output_begin), its
 * texels asked of `rows` a band of rows at a time and written as they come:
 * the image is never whole in memory. The file is not in place until the
 * caller commits *staged (pb_output_commit), or aborts it: an export stages
 * all its files before it commits any. PB_ERROR_INVALID_ARGUMENT for another
 * format; on an error *staged is NULL and nothing is left. */
pb_result pb_ktx2_stage(const char *path, uint32_t vk_format, uint32_t width, uint32_t height, pb_ktx2_rows_fn rows,
                        void *user, pb_output **staged, pb_error *err);

#endif
