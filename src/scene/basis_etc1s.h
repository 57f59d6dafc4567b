/* ETC1S texels as Basis Universal stores them (BasisLZ, KTX2's
 * supercompression scheme 1), decoded to RGBA8 on the host.
 *
 * An ETC1S block is one ETC1 base colour (5 bits a channel) with one
 * intensity table, and sixteen 2-bit selectors picking one of the four
 * colours base + table[s]. BasisLZ keeps the file's distinct endpoints and
 * selector patterns in two codebooks, and each slice (one image, or the
 * alpha of one) is a Huffman-coded stream of indices into them, predicted
 * from the neighbouring blocks. Written from Binomial's published
 * specification of the .basis format (sections 6-10), whose codebooks and
 * slices KTX2 carries unchanged. Every read is bounds-checked: a corrupt
 * stream is an error, never a read past the bytes given. */
#ifndef PB_SCENE_BASIS_ETC1S_H
#define PB_SCENE_BASIS_ETC1S_H

#include <stddef.h>
#include <stdint.h>

typedef struct pb_etc1s_huffman pb_etc1s_huffman; /* a canonical prefix code */

typedef struct pb_etc1s_endpoint {
    uint8_t color5[3]; /* base colour, 5 bits a channel */
    uint8_t inten;     /* intensity table, 0-7 */
} pb_etc1s_endpoint;

/* What every slice of a file shares: the two codebooks and the slices'
 * four prefix codes. Owned; pb_etc1s_codebooks_free releases it. */
typedef struct pb_etc1s_codebooks {
    pb_etc1s_endpoint *endpoints;
    uint32_t *selectors; /* 16 x 2 bits: byte y is row y, texel x at bits 2x */
    uint32_t endpoint_count, selector_count;
    pb_etc1s_huffman *endpoint_pred, *delta_endpoint, *selector, *selector_rle;
    uint32_t history_size; /* the selector history buffer's length, <= 64 */
} pb_etc1s_codebooks;

/* Reads the endpoint codebook, the selector codebook and the slices' prefix
 * codes from their three byte ranges. 0 on success; otherwise -1 with *why
 * naming what is wrong (a static string) and nothing left allocated. */
int pb_etc1s_codebooks_read(pb_etc1s_codebooks *cb, const uint8_t *endpoints, size_t endpoints_size,
                            uint32_t endpoint_count, const uint8_t *selectors, size_t selectors_size,
                            uint32_t selector_count, const uint8_t *tables, size_t tables_size, const char **why);
void pb_etc1s_codebooks_free(pb_etc1s_codebooks *cb);

/* Decodes one slice of width x height texels into rgba (width x height x 4
 * bytes, rows top-down). channels PB_ETC1S_RGB writes red, green and blue;
 * PB_ETC1S_ALPHA writes the slice's green into alpha, which is how ETC1S
 * carries an alpha channel. 0 on success, else -1 with *why set (the pixels
 * then partly written). */
enum { PB_ETC1S_RGB = 0, PB_ETC1S_ALPHA = 1 };
int pb_etc1s_slice_decode(const pb_etc1s_codebooks *cb, const uint8_t *data, size_t size, uint32_t width,
                          uint32_t height, int channels, uint8_t *rgba, const char **why);

#endif
