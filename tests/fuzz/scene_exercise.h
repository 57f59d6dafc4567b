/* What the glTF fuzzer does with one input file, shared by the harness
 * (fuzz_scene_load.c) and its regression replay (test_fuzz_corpus.c): load it
 * and build the BVH the bake would. Returns 1 if it loaded, 0 if it was
 * refused, and for a bug -1 if refused without a message (every failure must
 * say what failed) or -2 if decoding its images ahead changed the scene or
 * the messages. */
#ifndef PB_FUZZ_SCENE_EXERCISE_H
#define PB_FUZZ_SCENE_EXERCISE_H

#include "probebake/probebake.h"

/* The messages of one load, in order (the first 16 KiB: equal prefixes of
 * equal logs stay equal). */
typedef struct pb_fuzz_log {
    char text[16384];
    size_t used;
} pb_fuzz_log;

static inline void pb_fuzz_keep(pb_log_level level, const char *msg, void *user)
{
    pb_fuzz_log *log = (pb_fuzz_log *)user;
    int n = snprintf(log->text + log->used, sizeof log->text - log->used, "%d %s\n", (int)level, msg);
    if (n > 0)
        log->used = log->used + (size_t)n < sizeof log->text ? log->used + (size_t)n : sizeof log->text - 1;
}

/* Whether two loads of one file gave the same textures (pb_scene_hash has
 * the geometry and the materials, not the texels). */
static inline int pb_fuzz_same_textures(const pb_scene *a, const pb_scene *b)
{
    if (a->texture_count != b->texture_count || a->texel_count != b->texel_count ||
        a->stats.textures_unread != b->stats.textures_unread)
        return 0;
    for (uint32_t t = 0; t < a->texture_count; ++t) {
        const pb_texture *x = &a->textures[t], *y = &b->textures[t];
        if (x->width != y->width || x->height != y->height || x->offset != y->offset || x->srgb != y->srgb ||
            x->wrap_s != y->wrap_s || x->wrap_t != y->wrap_t)
            return 0;
    }
    return a->texel_count == 0 || memcmp(a->texels, b->texels, 4 * a->texel_count) == 0;
}

/* Loads the file twice, its images decoded ahead on the host's threads
 * (whatever their size: a fuzzer's are small) and in turn. The loader
 * promises the same scene and the same messages either way; *differ is set
 * where they are not. Returns the load's result, and its scene in *out (the
 * one decoded in turn; NULL on error). */
static inline pb_result pb_fuzz_load_both_ways(const char *path, pb_scene_desc d, pb_scene **out, pb_error *err,
                                               int *differ)
{
    pb_fuzz_log logs[2];
    pb_scene *two[2] = {NULL, NULL};
    pb_error errs[2];
    pb_result rs[2];
    for (int i = 0; i < 2; ++i) {
        logs[i].used = 0;
        logs[i].text[0] = '\0';
        d.log.fn = pb_fuzz_keep;
        d.log.user_data = &logs[i];
        d.decode_ahead = i == 0 ? PB_DECODE_AHEAD_ALWAYS : PB_DECODE_AHEAD_NEVER;
        rs[i] = pb_scene_load(path, &d, &two[i], &errs[i]);
    }
    if (rs[0] != rs[1] || strcmp(errs[0].message, errs[1].message) || strcmp(logs[0].text, logs[1].text) ||
        (rs[0] == PB_OK && rs[1] == PB_OK &&
         (pb_scene_hash(two[0]) != pb_scene_hash(two[1]) || !pb_fuzz_same_textures(two[0], two[1]))))
        *differ = 1;
    pb_scene_destroy(two[0]);
    *out = two[1];
    *err = errs[1];
    return rs[1];
}

static inline int pb_fuzz_scene_exercise(const char *path)
{
    /* Images under tighter limits than the defaults (8192^2 each, 16 of them):
     * a 64 KiB input holds hundreds of 144-byte headers claiming the most an
     * image may have, and the fuzzer stops at 2 GB. The defaults' own check
     * is tested in test_scene (oversized_texture_refused_unread). */
    pb_scene_desc d = {{NULL, NULL}, 0, 2048u * 2048u, 8u * 2048u * 2048u};
    pb_scene *s = NULL;
    pb_error err;
    int differ = 0;
    if (pb_fuzz_load_both_ways(path, d, &s, &err, &differ) != PB_OK) {
        pb_scene_destroy(s);
        return differ ? -2 : err.message[0] ? 0 : -1;
    }
    /* Again with a budget of half the texels it decoded: the charge for each
     * image, and the refusal of those past the budget, also the same both
     * ways (the images decoded ahead are charged only when asked for). */
    if (s->texel_count >= 2) {
        pb_scene *half = NULL;
        d.max_texture_total_pixels = s->texel_count / 2;
        pb_error half_err;
        (void)pb_fuzz_load_both_ways(path, d, &half, &half_err, &differ);
        pb_scene_destroy(half);
    }
    if (differ) {
        pb_scene_destroy(s);
        return -2;
    }
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
