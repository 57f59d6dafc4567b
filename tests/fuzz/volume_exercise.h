/* What the volume fuzzer does with one input file, shared by the harness
 * (fuzz_volume_read.c) and its regression replay (test_fuzz_corpus.c): read
 * it; if it reads, lay it out for sampling and sample eight points across
 * its extent. Returns 1 if it read (*sparse: with a sparse layout), 0 if it
 * was refused, -1 if refused without a message (a bug: every failure must
 * say what failed) or if the header alone reads otherwise than the whole. */
#ifndef PB_FUZZ_VOLUME_EXERCISE_H
#define PB_FUZZ_VOLUME_EXERCISE_H

#include "probebake/probebake.h"

#include <string.h>

/* The header alone (pb_volume_read_header) must agree with the whole read:
 * refused with the same message where that refuses for the header or the
 * sizes, and with the same header fields where that reads. 1 if they agree. */
static inline int pb_fuzz_header_agrees(const char *path, pb_result whole, const pb_volume *v, const pb_error *err)
{
    pb_volume h;
    pb_error herr;
    pb_result r = pb_volume_read_header(path, &h, &herr);
    if (r != PB_OK) /* a header refusal: the whole read refuses it the same way */
        return whole == r && !strcmp(err->message, herr.message);
    if (whole != PB_OK)
        return 1; /* refused for the sections' contents, which the header read does not look at */
    return h.probe_count == v->probe_count && h.flags == v->flags && h.octmap_res == v->octmap_res &&
           !memcmp(h.counts, v->counts, sizeof h.counts) && !memcmp(h.origin, v->origin, sizeof h.origin) &&
           !memcmp(h.spacing, v->spacing, sizeof h.spacing) && h.depth_unit == v->depth_unit &&
           h.file_version == v->file_version && !memcmp(&h.shard, &v->shard, sizeof h.shard) &&
           h.settings.seed == v->settings.seed && h.settings.scene_hash == v->settings.scene_hash &&
           h.settings.passes == v->settings.passes && h.settings.rays_per_probe == v->settings.rays_per_probe &&
           !h.base && !h.depth && !h.sparse;
}

static inline int pb_fuzz_volume_exercise(const char *path, int *sparse)
{
    pb_volume v;
    pb_error err;
    *sparse = 0;
    pb_result whole = pb_volume_read(path, &v, &err);
    if (!pb_fuzz_header_agrees(path, whole, &v, &err)) {
        if (whole == PB_OK)
            pb_volume_free(&v);
        return -1;
    }
    if (whole != PB_OK)
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
