/* libFuzzer harness for the volume reader (pb_volume_read), whose sparse
 * layout section (version 4) is a table of indices into other tables: each
 * input is written to a file and read; a volume that reads must also lay
 * out for sampling and sample without a sanitizer report. Any result is
 * fine, a crash, leak or sanitizer report is not, and a failure must say
 * what failed. Seeds: tests/fuzz/volume_corpus. */
#define _POSIX_C_SOURCE 200809L
#include "volume_exercise.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/pb_fuzz_volume_%d.probes", (int)getpid());
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    int sparse;
    if (pb_fuzz_volume_exercise(path, &sparse) < 0)
        abort();
    remove(path);
    return 0;
}
