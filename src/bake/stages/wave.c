/* A bake pass's paths as a wavefront (--schedule wavefront; docs/bake.md,
 * "Schedules"): bake_wave.comp keeps each path's state in memory and its
 * index in one of two queues, closest-hit rays and shadow rays, each double
 * buffered (0-1 and 2-3): one collects while the other is stepped. A step
 * is two dispatches: one lane sizes the queue and empties its twin, then
 * one invocation per queued path (vkCmdDispatchIndirect) traces its ray and
 * appends the path to the queue of its next. A submission records rounds
 * of one closest-hit step and as many shadow steps as a hit can have light
 * samples (at most 16); paths that outlast them (thin glass layers, many
 * lights) go on in the next submission, which the queue sizes read back
 * decide. */
#include "bake/stages/job.h"
#include "common/common.h"

#include <string.h>

/* Paths per submission: the state of 2^14 stays in a CPU's cache (lavapipe,
 * The Crypt: 2^14 paths 0.47-0.50 s, 2^18 0.59-0.65 s; bench/RESULTS.md);
 * a GPU needs a few hundred thousand lanes in flight. */
#define WAVE_PATHS_CPU (1u << 14)
#define WAVE_PATHS_GPU (1u << 18)

uint32_t pb_bake_wave_capacity(const pb_context *ctx, const pb_bake_desc *d, uint32_t rpp, uint64_t paths)
{
    if (d->schedule != PB_SCHEDULE_WAVEFRONT)
        return 0;
    uint64_t cap = ctx->info.type == PB_DEVICE_CPU ? WAVE_PATHS_CPU : WAVE_PATHS_GPU;
    cap = cap < paths ? cap : paths;
    return (uint32_t)(cap > rpp ? cap : rpp); /* at least one probe's rays */
}

/* The queues' buffer: 4 sizes and the indirect dispatch's arguments, then 4 queues of indices. */
static uint64_t queue_bytes(uint32_t capacity)
{
    return 32 + 4ull * 4 * capacity;
}

static uint64_t path_bytes(uint32_t capacity)
{
    return 16ull * PB_WAVE_PATH_VEC4 * capacity;
}

uint64_t pb_bake_wave_bytes(uint32_t capacity)
{
    return queue_bytes(capacity) + path_bytes(capacity) + 16; /* and the sizes read back */
}

pb_result pb_bake_wave_buffers(pb_context *ctx, bake_buffers *B, pb_error *err)
{
    uint32_t capacity = B->wave_capacity;
    if (!capacity)
        return PB_OK;
    pb_result r = pb_buffer_create(ctx, queue_bytes(capacity), PB_MEMORY_DEVICE, "wavefront queues",
                                   &B->wave_queues, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, path_bytes(capacity), PB_MEMORY_DEVICE, "wavefront paths", &B->wave_paths, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, 16, PB_MEMORY_DOWNLOAD, "wavefront queue sizes", &B->wave_counts, err);
    return r;
}

/* One step: the queue collecting rays of `kind` (0 closest hit, 1 shadow)
 * is traced, and its twin collects from now on. */
static void wave_step(pb_context *ctx, const bake_buffers *B, wave_push *wp, uint32_t pending[2], int kind)
{
    uint32_t in = pending[kind], twin = in ^ 1u;
    wp->mode = 1, wp->in_q = in, wp->zero_q = twin;
    pb_cmd_dispatch(ctx, &B->wave, wp, 1);
    pb_cmd_barrier_indirect(ctx);
    wp->mode = 2;
    wp->out_c = kind == 0 ? twin : pending[0];
    wp->out_s = kind == 1 ? twin : pending[1];
    pb_cmd_dispatch_indirect(ctx, &B->wave, wp, &B->wave_queues, 16);
    pb_cmd_barrier(ctx);
    pending[kind] = twin;
}

pb_result pb_bake_wave_trace(bake_run *run, const gpu_bake_params *prm, uint32_t paths, pb_error *err)
{
    pb_context *ctx = run->ctx;
    bake_buffers *B = run->B;
    wave_push wp = {B->params.address, B->wave_queues.address, B->wave_paths.address, 0, 0, 0, 0, 0,
                    B->wave_capacity};
    uint32_t pending[2] = {0, 2};
    /* a hit's light samples: its punctual lights (or the one drawn), an emitter, the environment;
     * at most 16 shadow steps a round (many lights take further submissions) */
    uint32_t shadows = (prm->light_select ? 1u : prm->light_count) + 2u, rounds = prm->bounces + 2u;
    uint32_t per_round = shadows < 16u ? shadows : 16u;
    /* a submission moves every path at least one ray on, and a path has at most rounds x
     * (1 + shadows) + 1 rays, each of them through up to 64 layers of thin glass (PB_GLASS_LAYERS) */
    uint64_t most = ((uint64_t)rounds * (1u + shadows) + 1u) * 65u + 1u;
    for (uint64_t submission = 0;; ++submission) {
        if (submission == most)
            return pb_fail(err, PB_ERROR_VULKAN, "wavefront: paths still queued after %llu submissions",
                           (unsigned long long)most);
        pb_result r = pb_cmd_begin(ctx, err);
        if (r != PB_OK)
            return r;
        pb_cmd_timestamp(ctx);
        pb_cmd_bind_set(ctx, &B->wave, run->gs->set);
        if (submission == 0) {
            wp.mode = 0;
            pb_cmd_dispatch(ctx, &B->wave, &wp, (paths + 63) / 64);
            pb_cmd_barrier(ctx);
        }
        for (uint32_t round = 0; round < rounds; ++round) {
            wave_step(ctx, B, &wp, pending, 0);
            for (uint32_t k = 0; k < per_round; ++k)
                wave_step(ctx, B, &wp, pending, 1);
        }
        wave_step(ctx, B, &wp, pending, 1); /* probe NEE's rays of the paths the last round ended */
        pb_cmd_timestamp(ctx);
        pb_cmd_copy(ctx, &B->wave_queues, 0, &B->wave_counts, 0, 16);
        pb_cmd_barrier_to_host(ctx);
        if ((r = pb_cmd_submit_wait(ctx, NULL, err)) != PB_OK)
            return r;
        if (ctx->interval_count >= 1)
            run->t_trace += ctx->intervals_ms[0];
        uint32_t sizes[4];
        memcpy(sizes, B->wave_counts.mapped, sizeof sizes);
        if (!sizes[pending[0]] && !sizes[pending[1]]) {
            if (submission)
                pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "wavefront: %llu submissions for %u paths",
                        (unsigned long long)submission + 1, paths);
            return PB_OK;
        }
    }
}
