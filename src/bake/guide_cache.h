/* Path guiding's guide, kept across bakes. It depends on the scene, its BVH,
 * the seed and a few shading settings only (guide.h), yet every bake learned
 * it again on the host: about 250 ms of training paths on the demo scene,
 * five times in its sparse bake, and once per device, all at once, in a
 * --devices bake. A GPU scene keeps one cache (pb_gpu_scene.guide_cache);
 * pb_bake_devices points every part's GPU scene at one shared cache for the
 * bake, so N devices learn it once. */
#ifndef PB_GUIDE_CACHE_H
#define PB_GUIDE_CACHE_H

#include "bake/guide.h"

#include <pthread.h>

/* Everything a guide is learned from. Compared as bytes: made by
 * pb_guide_key_make only (it zeroes the padding). */
typedef struct pb_guide_key {
    const void *scene, *bvh; /* identities: a GPU scene's BVH outlives it */
    uint32_t seed, bounces, paths, max_lights_per_hit, emitters_by_area;
    float max_distance, indirect_clamp, sky[3];
    uint64_t environment; /* hash of the map's size, rotation and texels (24 ms for the largest,
                             2048 x 1024, here); 0: none (the uniform sky) */
} pb_guide_key;

typedef struct pb_guide_cache {
    pthread_mutex_t lock; /* the parts of a --devices bake share one cache */
    int valid;
    pb_guide_key key;
    pb_guide guide;
    uint32_t learns; /* guides learned into it so far (the tests read it) */
} pb_guide_cache;

pb_result pb_guide_cache_create(pb_guide_cache **out, pb_error *err);
void pb_guide_cache_destroy(pb_guide_cache *c);

/* The key of a checked bake description's guide, learned from `pass` (its
 * scene, BVH, seed and bounces) with d's shading settings. */
pb_guide_key pb_guide_key_make(const pb_bake_desc *d, const pb_bake_pass *pass);

/* *out: a copy of the guide for `key` (the caller frees it with
 * pb_guide_free). The cache learns it from `pass` and `paths`
 * (pb_guide_build) unless it holds that key's already. *learned: 1 when
 * this call learned it. Another key's guide is replaced. */
pb_result pb_guide_cache_get(pb_guide_cache *c, const pb_guide_key *key, const pb_bake_pass *pass, uint32_t paths,
                             pb_guide *out, int *learned, pb_error *err);

#endif
