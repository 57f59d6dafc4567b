/* UASTC texels as Basis Universal stores them, decoded to RGBA8 on the host.
 *
 * A UASTC block is 128 bits for 4x4 texels: one of 19 modes, each a fixed
 * subset of 4x4 LDR ASTC (RGB, RGBA or luminance-alpha endpoints, one to
 * three subsets from 60 partition patterns BC7 shares, one or two weight
 * planes) with a simpler bit layout than ASTC's, plus a solid-colour mode.
 * Written from Binomial's UASTC LDR 4x4 specification (public domain),
 * with ASTC's endpoint and weight unquantization and interpolation from the
 * Khronos Data Format Specification it points to. A block no mode describes
 * (the reserved mode, or a pattern index past its table) is an error, as
 * Binomial's transcoder treats it. */
#ifndef PB_SCENE_BASIS_UASTC_H
#define PB_SCENE_BASIS_UASTC_H

#include <stddef.h>
#include <stdint.h>

/* Decodes one block to 16 RGBA8 texels, row by row. 0, or -1 where the
 * block is invalid (rgba then undefined). */
int pb_uastc_block_decode(const uint8_t block[16], uint8_t rgba[64]);

/* Decodes an image's blocks (ceil(width / 4) x ceil(height / 4) of them,
 * row by row, 16 bytes each, in size bytes) into width x height x 4 bytes,
 * rows of blocks on all host cores (the same bytes as on one). 0, or -1
 * with *why set (a static string). */
int pb_uastc_image_decode(const uint8_t *blocks, size_t size, uint32_t width, uint32_t height, uint8_t *rgba,
                          const char **why);

#endif
