/* What the glTF fuzzer does with one input file, shared by the harness
 * (fuzz_scene_load.c) and its regression replay (test_fuzz_corpus.c): load it
 * and build the BVH the bake would. Returns 1 if it loaded, 0 if it was
 * refused, -1 if refused without a message (a bug: every failure must say
 * what failed). */
#ifndef PB_FUZZ_SCENE_EXERCISE_H
#define PB_FUZZ_SCENE_EXERCISE_H

#include "probebake/probebake.h"

static inline void pb_fuzz_quiet(pb_log_level level, const char *msg, void *user)
{
    (void)level, (void)msg, (void)user;
}

static inline int pb_fuzz_scene_exercise(const char *path)
{
    /* Images under tighter limits than the defaults (8192^2 each, 16 of them):
     * a 64 KiB input holds hundreds of 144-byte headers claiming the most an
     * image may have, and the fuzzer stops at 2 GB. The defaults' own check
     * is tested in test_scene (oversized_texture_refused_unread). */
    pb_scene_desc d = {{pb_fuzz_quiet, NULL}, 0, 2048u * 2048u, 8u * 2048u * 2048u};
    pb_scene *s = NULL;
    pb_error err;
    if (pb_scene_load(path, &d, &s, &err) != PB_OK)
        return err.message[0] ? 0 : -1;
    /* every vertex normal is a unit vector (the shading normals read them
     * unchecked): a non-finite or unnormalized one is a loader bug */
    for (uint64_t i = 0; i < 3ull * s->triangle_count; ++i) {
        const float *n = s->normals + 3 * i;
        float l2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (!(l2 > 0.99f && l2 < 1.01f))
            __builtin_trap();
    }
    (void)pb_scene_bent_triangles(s);
    (void)pb_scene_hash(s);
    pb_bvh *bvh = NULL;
    pb_bvh_desc bd = {0, 0, 1, 0.f, 0.f};
    if (pb_bvh_build(s, &bd, &bvh, &err) == PB_OK)
        pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    return 1;
}

#endif
