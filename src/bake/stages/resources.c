/* Stage 3: the bake's device side (stages/job.h). */
#include "bake/stages/job.h"
#include "bake/bake_features.h"
#include "bake/depth_lists.h"
#include "bake/guide_cache.h"
#include "bake/light_cells.h"
#include "common/common.h"
#include "bake_depth.spv.h"
#include "bake_restart.spv.h"
#include "bake_restart_native64.spv.h"
#include "bake_sh.spv.h"
#include "bake_sh_native64.spv.h"
#include "bake_trace.spv.h"
#include "bake_trace_native64.spv.h"
#include "bake_wave.spv.h"
#include "bake_wave_native64.spv.h"

#include <stdlib.h>
#include <string.h>

void pb_bake_buffers_release(pb_context *ctx, bake_buffers *b)
{
    pb_buffer *bufs[16] = {&b->params, &b->probes, &b->rotations, &b->directions, &b->rays, &b->reduced,
                           &b->list, &b->counters, &b->nee, &b->guide, &b->guide_slots, &b->depth_lists,
                           &b->relocation_directions, &b->wave_queues, &b->wave_paths, &b->wave_counts};
    for (int i = 0; i < 16; ++i)
        pb_buffer_destroy(ctx, bufs[i]);
    pb_depth_sums_destroy(ctx, &b->sums);
    pb_guide_free(&b->guide_host);
    pb_shading_destroy(ctx, &b->shading);
    pb_sample_release(ctx, &b->feedback);
    pb_pipeline_destroy(ctx, &b->trace);
    pb_pipeline_destroy(ctx, &b->sh);
    pb_pipeline_destroy(ctx, &b->depth);
    pb_pipeline_destroy(ctx, &b->wave);
}

static pb_result make_buffer(pb_context *ctx, pb_buffer *b, uint64_t bytes, pb_memory_kind kind, const char *what,
                             const void *data, pb_error *err)
{
    pb_result r = pb_buffer_create(ctx, bytes, kind, what, b, err);
    if (r == PB_OK && data)
        r = pb_buffer_upload(ctx, b, 0, data, bytes, err);
    return r;
}

/* Path guiding's stage: the guide learned on the host from training paths
 * that start on the surfaces (src/bake/guide.c: they depend on the scene and
 * seed only), then uploaded. Needs the host BVH the GPU scene was made from.
 * The GPU scene keeps the guide for later bakes with the same key
 * (guide_cache.h): a sparse bake's levels learn it once. */
static pb_result learn_guide(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *d,
                             bake_buffers *B, pb_error *err)
{
    pb_bake_pass tp;
    memset(&tp, 0, sizeof tp);
    tp.scene = scene, tp.bvh = gs->bvh, tp.seed = d->seed, tp.bounces = d->bounces, tp.direct = 1;
    tp.env = B->shading.env_table.width ? &B->shading.env_table : NULL;
    tp.emitters = &B->shading.emit;
    tp.light_table = B->shading.light_select ? &B->shading.lights_drawn : NULL;
    tp.max_distance = d->max_distance, tp.indirect_clamp = d->indirect_clamp;
    tp.emitters_by_area = d->emitters_by_area;
    double t0 = pb_now_ms();
    pb_guide *g = &B->guide_host;
    pb_result r = gs->guide_cache ? PB_OK : pb_guide_cache_create(&gs->guide_cache, err);
    pb_guide_key key = pb_guide_key_make(d, &tp);
    int learned = 0;
    if (r == PB_OK)
        r = pb_guide_cache_get(gs->guide_cache, &key, &tp, d->guide_paths, g, &learned, err);
    if (r != PB_OK || !g->table)
        return r;
    if (learned)
        pb_logf(&ctx->desc.log, PB_LOG_INFO, "path guiding: %u training paths, %u of %u entries learned (%.0f ms)",
                d->guide_paths, g->learned, g->entries, pb_now_ms() - t0);
    else
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "path guiding: reused (seed %u, %u of %u entries)", d->seed, g->learned,
                g->entries);
    r = make_buffer(ctx, &B->guide_slots, (uint64_t)g->entries * 4, PB_MEMORY_DEVICE, "path guiding index", g->slot,
                    err);
    if (r == PB_OK)
        r = make_buffer(ctx, &B->guide, (uint64_t)(g->learned ? g->learned : 1) * PB_GUIDE_BINS * 16,
                        PB_MEMORY_DEVICE, "path guiding table", g->table, err);
    return r;
}


/* The kernel features of this bake's relocation and trace passes. */
static uint32_t bake_kernel_features(const bake_run *run)
{
    gpu_bake_params relocation, bake;
    pb_bake_pass_params(run, PB_RELOCATION_PASS, 1, NULL, &relocation);
    pb_bake_pass_params(run, 0, 0, NULL, &bake);
    return pb_bake_features(&relocation) | pb_bake_features(&bake);
}

/* Stage 3, the device side: shading data, the guide when on, probe and ray
 * buffers, the previous volume for --indirect volume, then the three
 * pipelines, made while the light cells are learned; then the pass runner
 * over them. */
pb_result pb_bake_stage_resources(bake_job *j, const pb_sample_volume *feedback, pb_error *err)
{
    pb_context *ctx = j->ctx;
    const pb_bake_desc *d = &j->d;
    bake_buffers *B = &j->B;
    uint32_t P = j->P, rpp = j->rpp, chunk = j->chunk;
    pb_result r = make_buffer(ctx, &B->params, sizeof(gpu_bake_params), PB_MEMORY_UPLOAD, "bake parameters", NULL, err);
    if (r == PB_OK)
        r = pb_shading_create(ctx, j->scene, j->gs, d->sky, d->environment, d->max_lights_per_hit, &B->shading, err);
    if (r == PB_OK && d->guide_paths && d->bounces)
        r = learn_guide(ctx, j->scene, j->gs, d, B, err);
    if (r == PB_OK)
        r = make_buffer(ctx, &B->probes, (uint64_t)P * 16, PB_MEMORY_DEVICE, "probe positions", j->probes, err);
    if (r == PB_OK)
        r = make_buffer(ctx, &B->rotations, (uint64_t)P * 48, PB_MEMORY_DEVICE, "probe rotations", NULL, err);
    if (r == PB_OK)
        r = make_buffer(ctx, &B->directions, (uint64_t)rpp * 16, PB_MEMORY_DEVICE, "ray directions", j->directions,
                        err);
    if (r == PB_OK) {
        pb_depth_lists dl;
        r = pb_depth_lists_build(j->directions, rpp, pb_depth_lobe_cutoff(d->lobe_power), PB_DEPTH_QUERY_RES, &dl,
                                 err);
        if (r == PB_OK) {
            pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "depth filter: %.1f of %u rays per texel on average, at most %u",
                    dl.mean, rpp, dl.longest);
            r = make_buffer(ctx, &B->depth_lists, (uint64_t)dl.word_count * 4, PB_MEMORY_DEVICE,
                            "depth filter ray lists", dl.words, err);
        }
        pb_depth_lists_free(&dl);
    }
    if (r == PB_OK && d->relocation_rays != rpp) { /* relocation's own, smaller spherical Fibonacci set */
        float *dirs = malloc((size_t)d->relocation_rays * 4 * sizeof(float));
        if (!dirs || pb_sf_directions(d->relocation_rays, dirs) != PB_OK)
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u relocation directions",
                        d->relocation_rays);
        else
            r = make_buffer(ctx, &B->relocation_directions, (uint64_t)d->relocation_rays * 16, PB_MEMORY_DEVICE,
                            "relocation ray directions", dirs, err);
        free(dirs);
    }
    if (r == PB_OK)
        r = make_buffer(ctx, &B->rays, (uint64_t)chunk * rpp * 16, PB_MEMORY_DEVICE, "probe rays", NULL, err);
    if (r == PB_OK && d->probe_nee)
        r = make_buffer(ctx, &B->nee, (uint64_t)chunk * rpp * 32, PB_MEMORY_DEVICE, "probe NEE samples", NULL, err);
    if (r == PB_OK)
        r = make_buffer(ctx, &B->reduced, j->reduced_floats * 4, PB_MEMORY_DOWNLOAD, "probe results", NULL, err);
    if (r == PB_OK) /* pass 0 stores, later passes add: never read before written */
        r = pb_depth_sums_create(ctx, &B->sums, err);
    if (r == PB_OK)
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "depth sums: %.1f MiB in %u block%s of up to %u probes",
                (double)P * B->sums.probe_bytes / 1048576.0, B->sums.block_count, B->sums.block_count > 1 ? "s" : "",
                B->sums.block_probes);
    if (r == PB_OK)
        r = make_buffer(ctx, &B->list, (uint64_t)P * 4, PB_MEMORY_DEVICE, "active probe list", NULL, err);
    if (r == PB_OK)
        r = make_buffer(ctx, &B->counters, 16, PB_MEMORY_DOWNLOAD, "traversal counter", NULL, err);
    j->run = (bake_run){ctx,          B,         j->gs,        d,         j->scene,  P,      rpp,
                        j->n,         chunk,     0,            j->probes, j->rotations, j->reduced, j->sh_sum,
                        j->backfaces, j->hits,   0,            0,         0,         j->near,
                        0,            0,         {0},          &j->conv};
    j->run.relocation_rpp = d->relocation_rays;
    if (r == PB_OK && feedback) {
        r = pb_sample_upload(ctx, feedback, &B->feedback, err);
        j->run.feedback = B->feedback.refs;
    }
    /* The kernels are made on worker threads while the light cells are
     * learned (lavapipe: 0.2 s of NIR work beside 0.2 s of shadow rays on
     * The Crypt). They keep only the code some pass of this bake may run;
     * whether the cells make tables is known only once they are measured,
     * so their code is in whenever they may (the kernel skips it when a
     * pass has none, light_cells.glsl). */
    uint32_t planned = bake_kernel_features(&j->run);
    if (d->light_cells && B->shading.emit.count && j->scene->triangle_count)
        planned |= PB_FEATURE_LIGHT_CELLS;
    uint32_t spec[3] = {j->gs->stack_size, j->gs->texel_loads, planned};
    if (r == PB_OK)
        r = pb_bake_wave_buffers(ctx, B, err);
    pb_pipeline_request kernels[4] = {
        {PB_KERNEL_SPIRV(ctx, bake_trace), sizeof(bake_push), spec, 3, 64, "bake_trace", &B->trace},
        {PB_KERNEL_SPIRV(ctx, bake_sh), sizeof(bake_push), spec, 3, 64, "bake_sh", &B->sh},
        {pb_spv_bake_depth, sizeof pb_spv_bake_depth, sizeof(bake_push), spec, 3, 64, "bake_depth", &B->depth},
        {PB_KERNEL_SPIRV(ctx, bake_wave), sizeof(wave_push), spec, 3, 64, "bake_wave", &B->wave}};
    if (d->schedule == PB_SCHEDULE_RESTART) /* its paths and relocation's, one path per invocation there */
        kernels[0] = (pb_pipeline_request){PB_KERNEL_SPIRV(ctx, bake_restart), sizeof(bake_push), spec, 3, 64,
                                           "bake_restart", &B->trace};
    pb_pipeline_batch batch;
    if (r == PB_OK)
        r = pb_pipelines_begin(ctx, kernels, B->wave_capacity ? 4 : 3, &batch, err);
    if (r == PB_OK) {
        pb_result learned = PB_OK;
        if (d->light_cells)
            learned = pb_light_cells_gpu_get(ctx, j->scene, j->gs, d->seed, &B->shading.emit, &B->light, NULL, err);
        pb_result made = pb_pipelines_end(ctx, &batch, learned == PB_OK ? err : NULL);
        r = learned != PB_OK ? learned : made;
    }
    /* the plan covers every pass: the light cells add only the bit planned for
     * them, and each pass checks its own features against these (pass.c) */
    B->features = planned;
    char names[160];
    pb_bake_features_name(B->features, names, sizeof names);
    pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "bake kernels specialised to: %s", names);
    return r;
}
