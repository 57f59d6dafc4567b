/* What the KTX2 fuzzer does with one input, shared by the harness
 * (fuzz_ktx2_decode.c) and its regression replay (test_fuzz_corpus.c): peek
 * at the container and, where it reads and is at most 2^22 texels, decode it
 * into a buffer of exactly its size (so a sanitizer sees a write past it).
 * Returns 1 if it decoded, 0 if it was refused, -1 if refused without a
 * reason (a bug: every failure must say what failed) or if the peek's size
 * and the decode disagree. */
#ifndef PB_FUZZ_KTX2_EXERCISE_H
#define PB_FUZZ_KTX2_EXERCISE_H

#include "scene/ktx2_read.h"

#include <stdlib.h>

static inline int pb_fuzz_ktx2_exercise(const uint8_t *data, size_t size)
{
    pb_ktx2_info info;
    const char *why = NULL;
    if (pb_ktx2_peek(data, size, &info, &why) != 0)
        return why && *why ? 0 : -1;
    if (info.width == 0 || info.height == 0)
        return -1;
    if ((uint64_t)info.width * info.height > (1u << 22))
        return 0; /* the loader's pixel limit stands here */
    uint8_t *rgba = malloc((size_t)info.width * info.height * 4);
    if (!rgba)
        return 0;
    why = NULL;
    int r = pb_ktx2_decode(data, size, rgba, &why);
    free(rgba);
    return r == 0 ? 1 : why && *why ? 0 : -1;
}

#endif
