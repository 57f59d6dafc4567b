/* OpenEXR environment maps, read by the OpenEXR library (Debian
 * libopenexr-dev): every compression, half, float and uint channels, scanline
 * and tiled files. Most HDR environments ship as EXR, often DWA-compressed,
 * which no single-header reader decodes. */
#ifndef PB_IO_ENVIRONMENT_EXR_H
#define PB_IO_ENVIRONMENT_EXR_H

#include "probebake/base.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* 1 when the 4 bytes are OpenEXR's magic number. */
int pb_exr_magic(const unsigned char bytes[4]);

/* Reads the display window of the file's first part as RGB floats, row 0
 * at the top (*rgb malloc'd, 3 per texel; the caller frees it). Texels the
 * data window leaves out are 0; a file with only a Y channel is grey.
 * Values are as stored: NaN, infinite and negative texels are the caller's
 * to judge. At most `max_texels` texels (display and data window alike).
 * Errors name the file and the problem: PB_ERROR_PARSE (not decodable, no
 * R, G, B or Y channel, a size outside limits), PB_ERROR_UNSUPPORTED
 * (luminance-chroma or deep data), PB_ERROR_OUT_OF_HOST_MEMORY. */
pb_result pb_exr_read_rgb(const char *path, uint64_t max_texels, float **rgb, uint32_t *width, uint32_t *height,
                          pb_error *err);

#ifdef __cplusplus
}
#endif

#endif
