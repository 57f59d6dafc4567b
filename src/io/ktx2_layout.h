/* What KTX 2.0's writer (io/ktx2.c) and reader (scene/ktx2_read.c) share of
 * the file's layout (Khronos, "KTX File Format Specification" 2.0, 3.1-3.9):
 * the identifier, then nine 32-bit header words, the index (four 32-bit and
 * two 64-bit words) and one level entry of three 64-bit words per level. */
#ifndef PB_IO_KTX2_LAYOUT_H
#define PB_IO_KTX2_LAYOUT_H

static const unsigned char pb_ktx2_identifier[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};

enum {
    PB_KTX2_HEADER_BYTES = 12 + 9 * 4, /* identifier and header words: vkFormat .. supercompressionScheme */
    PB_KTX2_INDEX_BYTES = 4 * 4 + 2 * 8, /* dfd and kvd offset/length, sgd offset/length */
    PB_KTX2_LEVELS_AT = PB_KTX2_HEADER_BYTES + PB_KTX2_INDEX_BYTES,
    PB_KTX2_LEVEL_BYTES = 3 * 8, /* byteOffset, byteLength, uncompressedByteLength */
};

#endif
