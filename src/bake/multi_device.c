/* A bake on several devices at once: part i of N (bake --shard) on device
 * i, one host thread each, then pb_volume_merge in memory. Every random
 * number is keyed by seed, probe, pass and ray, so on devices of one driver
 * the result is the bytes of a one-device bake (timings aside); on different
 * hardware each part is what that device computes. Path guiding's guide is
 * host work: the parts share one (guide_cache.h). */
#include "bake/gpu_scene.h"
#include "bake/guide_cache.h"
#include "common/common.h"
#include "probebake/bake.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One progress line for all parts: the mean of their fractions, reported
 * under a lock; a cancel from the caller's callback stops every part. */
typedef struct progress_share {
    pthread_mutex_t lock;
    float *fraction;
    uint32_t count;
    pb_progress_fn fn;
    void *user;
    int cancel;
} progress_share;

typedef struct device_part {
    pb_context *ctx;
    pb_gpu_scene *gs;
    const pb_scene *scene;
    pb_bake_desc desc;
    const pb_sparse_desc *sparse;   /* NULL: a grid or points */
    uint32_t index;
    progress_share *share;
    pb_volume vol;
    pb_error err;
    pb_result result;
} device_part;

static int part_progress(float fraction, const char *label, void *user)
{
    device_part *p = user;
    progress_share *s = p->share;
    pthread_mutex_lock(&s->lock);
    s->fraction[p->index] = fraction;
    float mean = 0.f;
    for (uint32_t i = 0; i < s->count; ++i)
        mean += s->fraction[i] / (float)s->count;
    if (s->fn && s->fn(mean, label, s->user))
        s->cancel = 1;
    int cancel = s->cancel;
    pthread_mutex_unlock(&s->lock);
    return cancel;
}

static void *bake_part(void *arg)
{
    device_part *p = arg;
    p->result = p->sparse ? pb_bake_sparse(p->ctx, p->scene, p->gs, &p->desc, p->sparse, &p->vol, NULL, &p->err)
                          : pb_bake(p->ctx, p->scene, p->gs, &p->desc, &p->vol, &p->err);
    if (p->result != PB_OK) { /* the others stop at their next progress report */
        pthread_mutex_lock(&p->share->lock);
        p->share->cancel = 1;
        pthread_mutex_unlock(&p->share->lock);
    }
    return NULL;
}

pb_result pb_bake_devices(pb_context *const *ctxs, pb_gpu_scene *const *scenes, uint32_t count, const pb_scene *scene,
                          const pb_bake_desc *desc, const pb_sparse_desc *sparse, pb_volume *out, pb_error *err)
{
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    if (count == 0)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "no devices to bake on");
    if (desc->shard_count)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "a bake on several devices is already split by device: "
                                                       "give --devices or --shard, not both");
    if (count == 1)
        return sparse ? pb_bake_sparse(ctxs[0], scene, scenes[0], desc, sparse, out, NULL, err)
                      : pb_bake(ctxs[0], scene, scenes[0], desc, out, err);
    device_part *parts = calloc(count, sizeof *parts);
    pthread_t *threads = calloc(count, sizeof *threads);
    struct pb_guide_cache **own_guides = calloc(count, sizeof *own_guides);
    progress_share share = {PTHREAD_MUTEX_INITIALIZER, calloc(count, sizeof(float)), count, desc->progress,
                            desc->progress_user, 0};
    if (!parts || !threads || !own_guides || !share.fraction) {
        free(parts), free(threads), free(own_guides), free(share.fraction);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u devices", count);
    }
    /* the guide is host work, the same for every part: the parts share the
     * first device's cache, so one learns it while the others wait for it */
    if (!scenes[0]->guide_cache && pb_guide_cache_create(&scenes[0]->guide_cache, err) != PB_OK) {
        free(parts), free(threads), free(own_guides), free(share.fraction);
        return err->code;
    }
    for (uint32_t i = 1; i < count; ++i)
        own_guides[i] = scenes[i]->guide_cache, scenes[i]->guide_cache = scenes[0]->guide_cache;
    uint32_t started = 0;
    for (uint32_t i = 0; i < count; ++i) {
        device_part *p = &parts[i];
        *p = (device_part){ctxs[i], scenes[i], scene, *desc, sparse, i, &share, {0}, {0}, PB_OK};
        p->desc.shard_index = i, p->desc.shard_count = count;
        p->desc.progress = part_progress, p->desc.progress_user = p;
        if (pthread_create(&threads[i], NULL, bake_part, p) != 0) {
            p->result = pb_fail(&p->err, PB_ERROR_OUT_OF_HOST_MEMORY, "could not start a thread for device %u", i);
            share.cancel = 1;
            break;
        }
        ++started;
    }
    for (uint32_t i = 0; i < started; ++i)
        pthread_join(threads[i], NULL);
    for (uint32_t i = 1; i < count; ++i)
        scenes[i]->guide_cache = own_guides[i];
    /* the first real failure, before the cancellations it caused */
    int pick = -1;
    for (uint32_t i = 0; i < count && pick < 0; ++i)
        if (parts[i].result != PB_OK && parts[i].result != PB_ERROR_CANCELLED)
            pick = (int)i;
    for (uint32_t i = 0; i < count && pick < 0; ++i)
        if (parts[i].result != PB_OK)
            pick = (int)i;
    pb_result r = pick < 0 ? PB_OK : parts[pick].result;
    if (pick >= 0)
        *err = parts[pick].err;
    if (r == PB_OK) {
        pb_volume *vols = calloc(count, sizeof *vols);
        char (*names)[64] = calloc(count, sizeof *names);
        const char **name_ptrs = calloc(count, sizeof *name_ptrs);
        if (!vols || !names || !name_ptrs) {
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory merging %u parts", count);
        } else {
            for (uint32_t i = 0; i < count; ++i) {
                vols[i] = parts[i].vol;
                snprintf(names[i], sizeof names[i], "part %u (device %u)", i, i);
                name_ptrs[i] = names[i];
            }
            r = pb_volume_merge(vols, name_ptrs, count, out, err);
        }
        free(vols), free(names), free(name_ptrs);
    }
    for (uint32_t i = 0; i < count; ++i)
        pb_volume_free(&parts[i].vol);
    pthread_mutex_destroy(&share.lock);
    free(parts), free(threads), free(own_guides), free(share.fraction);
    return r;
}
