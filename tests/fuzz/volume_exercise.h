/* What the volume fuzzer does with one input file, shared by the harness
 * (fuzz_volume_read.c) and its regression replay (test_fuzz_corpus.c): read
 * it; if it reads, lay it out for sampling and sample eight points across
 * its extent. Returns 1 if it read (*sparse: with a sparse layout), 0 if it
 * was refused, -1 if refused without a message (a bug: every failure must
 * say what failed). */
#ifndef PB_FUZZ_VOLUME_EXERCISE_H
#define PB_FUZZ_VOLUME_EXERCISE_H

#include "probebake/probebake.h"

static inline int pb_fuzz_volume_exercise(const char *path, int *sparse)
{
    pb_volume v;
    pb_error err;
    *sparse = 0;
    if (pb_volume_read(path, &v, &err) != PB_OK)
        return err.message[0] ? 0 : -1;
    *sparse = v.sparse != NULL;
    pb_sample_volume sv;
    double o[3] = {0, 0, 0};
    if (pb_sample_volume_build(&v, o, 0.f, 0.f, &sv, &err) == PB_OK) {
        for (int i = 0; i < 8; ++i) {
            float p[3], n[3] = {0.f, 1.f, 0.f}, rgb[3];
            for (int k = 0; k < 3; ++k)
                p[k] = (float)(v.origin[k] + (i >> k & 1) * 10.0 * v.spacing[k]);
            pb_sample_cpu(&sv, p, n, n, rgb);
        }
        pb_sample_volume_free(&sv);
    }
    pb_volume_free(&v);
    return 1;
}

#endif
