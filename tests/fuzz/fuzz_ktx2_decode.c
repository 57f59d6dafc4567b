/* libFuzzer harness for the KTX2 reader and its ETC1S and UASTC decoders
 * (src/scene/ktx2_read.c, basis_etc1s.c, basis_uastc.c), straight at the bytes rather than
 * through a glTF: any result is fine, a crash, leak, sanitizer report or a
 * failure without a reason is not. Seeds: tests/fuzz/ktx2_corpus (the files
 * of tests/data/ktx2 and what the fuzzer found). */
#include "ktx2_exercise.h"

#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (pb_fuzz_ktx2_exercise(data, size) < 0)
        abort();
    return 0;
}
