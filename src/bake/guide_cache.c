/* Path guiding's guide, kept across bakes: guide_cache.h. */
#include "bake/guide_cache.h"
#include "common/common.h"

#include <stdlib.h>
#include <string.h>

pb_result pb_guide_cache_create(pb_guide_cache **out, pb_error *err)
{
    *out = NULL;
    pb_guide_cache *c = calloc(1, sizeof *c);
    if (!c)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the path guiding cache");
    if (pthread_mutex_init(&c->lock, NULL) != 0) {
        free(c);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "cannot create the path guiding cache's lock");
    }
    *out = c;
    return PB_OK;
}

void pb_guide_cache_destroy(pb_guide_cache *c)
{
    if (!c)
        return;
    pb_guide_free(&c->guide);
    pthread_mutex_destroy(&c->lock);
    free(c);
}

pb_guide_key pb_guide_key_make(const pb_bake_desc *d, const pb_bake_pass *pass)
{
    pb_guide_key k;
    memset(&k, 0, sizeof k); /* padding too: keys compare as bytes */
    k.scene = pass->scene, k.bvh = pass->bvh;
    k.seed = pass->seed, k.bounces = pass->bounces, k.paths = d->guide_paths;
    k.max_lights_per_hit = d->max_lights_per_hit, k.emitters_by_area = d->emitters_by_area;
    k.max_distance = pass->max_distance, k.indirect_clamp = pass->indirect_clamp;
    const pb_environment *env = d->environment;
    if (env) { /* a map: its content, not its address (a caller may load another into the same memory) */
        uint64_t h = pb_hash64(&env->width, sizeof env->width, 0x9e3779b97f4a7c15ull);
        h = pb_hash64(&env->height, sizeof env->height, h);
        h = pb_hash64(&env->rotation_deg, sizeof env->rotation_deg, h);
        h = pb_hash64(env->rgb, (size_t)env->width * env->height * 3 * sizeof(float), h);
        k.environment = h | 1u; /* never 0, which stands for no map */
    } else {
        memcpy(k.sky, d->sky, sizeof k.sky);
    }
    return k;
}

static pb_result guide_copy(const pb_guide *src, pb_guide *dst, pb_error *err)
{
    memset(dst, 0, sizeof *dst);
    if (!src->table)
        return PB_OK; /* nothing learned */
    size_t slots = (size_t)src->entries, floats = (size_t)(src->learned ? src->learned : 1) * PB_GUIDE_BINS * 4;
    dst->slot = malloc(slots * sizeof(uint32_t));
    dst->table = malloc(floats * sizeof(float));
    if (!dst->slot || !dst->table) {
        pb_guide_free(dst);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for path guiding (%u entries)",
                       src->entries);
    }
    memcpy(dst->slot, src->slot, slots * sizeof(uint32_t));
    memcpy(dst->table, src->table, floats * sizeof(float));
    dst->grid = src->grid, dst->entries = src->entries, dst->learned = src->learned;
    return PB_OK;
}

pb_result pb_guide_cache_get(pb_guide_cache *c, const pb_guide_key *key, const pb_bake_pass *pass, uint32_t paths,
                             pb_guide *out, int *learned, pb_error *err)
{
    memset(out, 0, sizeof *out);
    *learned = 0;
    pthread_mutex_lock(&c->lock); /* a second part waits here for the first's guide rather than learning its own */
    pb_result r = PB_OK;
    if (!c->valid || memcmp(&c->key, key, sizeof *key) != 0) {
        pb_guide_free(&c->guide);
        c->valid = 0;
        r = pb_guide_build(pass, paths, &c->guide, err);
        if (r == PB_OK)
            c->valid = 1, c->key = *key, *learned = 1, c->learns++;
    }
    if (r == PB_OK)
        r = guide_copy(&c->guide, out, err);
    pthread_mutex_unlock(&c->lock);
    return r;
}
