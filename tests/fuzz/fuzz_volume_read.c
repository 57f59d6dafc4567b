/* libFuzzer harness for the volume reader (pb_volume_read), whose sparse
 * layout section (version 4) is a table of indices into other tables: each
 * input is written to a file and read; a volume that reads must also lay
 * out for sampling and sample without a sanitizer report. Any result is
 * fine, a crash, leak or sanitizer report is not, and a failure must say
 * what failed. Seeds: tests/fuzz/volume_corpus. */
#define _POSIX_C_SOURCE 200809L
#include "probebake/probebake.h"

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
    pb_volume v;
    pb_error err;
    if (pb_volume_read(path, &v, &err) == PB_OK) {
        pb_sample_volume sv;
        double o[3] = {0, 0, 0};
        if (pb_sample_volume_build(&v, o, 0.f, 0.f, &sv, &err) == PB_OK) {
            /* a few points across the volume's extent */
            for (int i = 0; i < 8; ++i) {
                float p[3], n[3] = {0.f, 1.f, 0.f}, rgb[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = (float)(v.origin[k] + (i >> k & 1) * 10.0 * v.spacing[k]);
                pb_sample_cpu(&sv, p, n, n, rgb);
            }
            pb_sample_volume_free(&sv);
        }
        pb_volume_free(&v);
    } else if (!err.message[0]) {
        abort();
    }
    remove(path);
    return 0;
}
