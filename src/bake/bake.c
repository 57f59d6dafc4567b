/* pb_bake: the bake's host loop (include/probebake/bake.h).
 *
 *   stages over one bake_job: probe set (and memory budget) -> place ->
 *   device resources -> relocate -> classify -> trace passes -> SH, depth, validity ->
 *   dilation (a grid's; merge dilates a sharded bake's parts)
 *   per pass:   rotations for every probe
 *     per chunk of probes (at most rays_per_submit rays): one submission of
 *       bake_trace -> bake_sh -> bake_depth, then accumulate on the host
 *
 * Accumulation is in double on the host, one float sum per pass and probe
 * from the GPU: the per-pass sums are over at most rays_per_probe terms, so
 * adding passes never loses precision however many there are. */
#include "bake/stages/job.h"
#include "bake/indirect_volume.h"
#include "bake/settings.h"
#include "common/common.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

uint32_t pb_bake_passes(const pb_bake_desc *d)
{
    return d->passes ? d->passes : d->target_error > 0.f ? 64 : 4;
}

/* The settings (settings.c), then what needs the scene: the grid, the
 * points' coordinates, the maximum distance, the light. */
static pb_result check_desc(const pb_scene *s, pb_bake_desc *d, pb_error *err)
{
    pb_bake_settings_default(d);
    pb_result r = pb_bake_settings_check(d, err);
    if (r != PB_OK)
        return r;
    if (d->max_distance == 0.f) {
        float dx = s->bounds_max[0] - s->bounds_min[0], dy = s->bounds_max[1] - s->bounds_min[1],
              dz = s->bounds_max[2] - s->bounds_min[2];
        d->max_distance = fmaxf(1e-3f, sqrtf(dx * dx + dy * dy + dz * dz));
    }
    if (!(d->max_distance > 0.f) || !isfinite(d->max_distance))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "max distance %g: must be positive and finite",
                       d->max_distance);
    if (d->points) {
        for (uint64_t i = 0; i < 3ull * d->points->count; ++i) {
            double x = d->points->positions[i];
            if (!(fabs(x) <= PB_MAX_COORDINATE) || !(fabs(x - s->origin[i % 3]) <= PB_MAX_COORDINATE))
                return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                               "probe point %llu (id %u) has coordinate %g: must be finite and within +-%g m of the "
                               "origin and of the scene", (unsigned long long)(i / 3), d->points->ids ? d->points->ids[i / 3] : (uint32_t)(i / 3), x,
                               PB_MAX_COORDINATE);
        }
    } else {
        uint64_t probes = (uint64_t)d->grid.counts[0] * d->grid.counts[1] * d->grid.counts[2];
        if (!probes || probes > (1u << 24))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "probe grid %ux%ux%u: need 1 to 2^24 probes",
                           d->grid.counts[0], d->grid.counts[1], d->grid.counts[2]);
        for (int k = 0; k < 3; ++k)
            if (!isfinite(d->grid.origin[k]) || !(d->grid.spacing[k] >= 0.f) || !isfinite(d->grid.spacing[k]))
                return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "probe grid origin and spacing must be finite, spacing >= 0");
    }
    return pb_bake_check_light(s, d->sky, d->environment, err);
}

/* Whether anything in the scene or its environment emits light. */
static int scene_emits_light(const pb_scene *s, const pb_bake_desc *d)
{
    if (s->light_count)
        return 1;
    for (uint32_t m = 0; m < s->material_count; ++m)
        if (s->materials[m].emissive[0] > 0.f || s->materials[m].emissive[1] > 0.f || s->materials[m].emissive[2] > 0.f)
            return 1;
    if (d->environment) {
        for (uint64_t i = 0; i < 3ull * d->environment->width * d->environment->height; ++i)
            if (d->environment->rgb[i] > 0.f)
                return 1;
        return 0;
    }
    return d->sky[0] > 0.f || d->sky[1] > 0.f || d->sky[2] > 0.f;
}

static void bake_job_free(bake_job *j)
{
    pb_bake_buffers_release(j->ctx, &j->B);
    free(j->probes), free(j->rotations), free(j->directions), free(j->sh_sum);
    free(j->backfaces), free(j->hits), free(j->reduced), free(j->offsets), free(j->near);
    free(j->inside), free(j->skip);
    free(j->active), free(j->converged_at), free(j->global), free(j->floor_list);
    pb_convergence_free(&j->conv);
}

/* One bake as its stages over one context: probe set, place, device
 * resources, relocate, classify, trace passes, SH / depth / validity, then dilation
 * (dilate_gpu.c; a grid's, not a part's: merge dilates parts). */
static pb_result bake_once(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc_in,
                           const pb_sample_volume *feedback, pb_volume *out, pb_error *err)
{
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    double t_start = pb_now_ms();
    bake_job j;
    memset(&j, 0, sizeof j);
    j.ctx = ctx, j.scene = scene, j.gs = gs, j.d = *desc_in;
    pb_result r = check_desc(scene, &j.d, err);
    if (r == PB_OK)
        r = pb_bake_stage_probe_set(&j, err);
    if (r != PB_OK)
        return r;
    if (gs->hashed_scene != scene)
        pb_scene_hash_start(&j.scene_hash, scene); /* beside the stages, until the volume stage needs it */
    if (!scene_emits_light(scene, &j.d))
        pb_logf(&ctx->desc.log, PB_LOG_WARN,
                "%s: no lights, no emissive surfaces and a black sky: the volume will be black (give --sky or --env)",
                scene->path[0] ? scene->path : "scene");
    /* wall time per stage, and the GPU time inside relocation and the passes
     * (--verbose): what a small bake spends besides tracing */
    double t[7], gpu_relocate = 0, gpu_passes = 0;
    t[0] = pb_now_ms();
    r = pb_bake_stage_place(&j, err);
    t[1] = pb_now_ms();
    if (r == PB_OK)
        r = pb_bake_stage_resources(&j, feedback, err);
    t[2] = pb_now_ms();
    if (r == PB_OK)
        r = pb_bake_stage_relocate(&j, err);
    if (r == PB_OK)
        r = pb_bake_stage_classify(&j, err);
    t[3] = pb_now_ms();
    gpu_relocate = j.run.t_trace + j.run.t_sh;
    if (r == PB_OK)
        r = pb_bake_stage_passes(&j, err);
    t[4] = pb_now_ms();
    gpu_passes = j.run.t_trace + j.run.t_sh + j.run.t_depth - gpu_relocate;
    if (r == PB_OK)
        r = pb_bake_stage_volume(&j, out, err);
    t[5] = pb_now_ms();
    /* points have no grid neighbourhood (invalid ones stay flagged); a
     * part's neighbours are in other parts (pb_volume_merge dilates) */
    if (r == PB_OK && !j.d.points && !j.d.shard_count)
        r = pb_volume_dilate_gpu(ctx, out, PB_DILATION_ROUNDS, err);
    t[6] = pb_now_ms();
    if (r == PB_OK)
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG,
                "bake stages, wall ms: place %.1f, resources and pipelines %.1f, relocate %.1f (GPU %.1f), passes "
                "%.1f (GPU %.1f), volume %.1f, dilate %.1f", t[1] - t[0], t[2] - t[1], t[3] - t[2], gpu_relocate,
                t[4] - t[3], gpu_passes, t[5] - t[4], t[6] - t[5]);
    if (r == PB_OK) {
        out->traversals = j.run.traversals;
        out->relocation_rays = j.relocation_rays;
        if (j.run.long_paths)
            pb_logf(&ctx->desc.log, PB_LOG_WARN,
                    "%llu paths ran over 32768 traversal steps in one invocation; llvmpipe (lavapipe) silently cuts "
                    "loops past 65535, so on lavapipe such paths may be cut short (fewer lights or bounces help)",
                    (unsigned long long)j.run.long_paths);
        out->timings.trace = j.run.t_trace;
        out->timings.sh = j.run.t_sh;
        out->timings.relocate = gpu_relocate; /* a part of trace and sh */
        out->timings.octmap = j.run.t_depth;
        out->timings.total = pb_now_ms() - t_start;
    }
    if (j.scene_hash.scene) { /* joined whatever the outcome: the caller may free the scene next */
        gs->scene_hash = pb_scene_hash_wait(&j.scene_hash);
        gs->hashed_scene = scene;
    }
    bake_job_free(&j);
    if (r != PB_OK)
        pb_volume_free(out);
    return r;
}

pb_result pb_bake_bounce(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc,
                         const pb_sample_volume *volume, pb_volume *out, pb_error *err)
{
    if (desc->indirect_volume || desc->bounces) {
        pb_error_clear(err);
        memset(out, 0, sizeof *out);
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "one bounce of --indirect volume shades first hits only: bounces must be 0 (got %u)",
                       desc->bounces);
    }
    return bake_once(ctx, scene, gs, desc, volume, out, err);
}

typedef struct grid_bounce {
    pb_context *ctx;
    const pb_scene *scene;
    pb_gpu_scene *gs;
} grid_bounce;

static pb_result grid_bounce_bake(void *user, const pb_bake_desc *d, const pb_sample_volume *previous, pb_volume *out,
                                  pb_error *err)
{
    grid_bounce *g = user;
    return pb_bake_bounce(g->ctx, g->scene, g->gs, d, previous, out, err);
}

pb_result pb_bake(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc,
                  pb_volume *out, pb_error *err)
{
    if (!desc->indirect_volume || desc->bounces == 0)
        return bake_once(ctx, scene, gs, desc, NULL, out, err);
    memset(out, 0, sizeof *out);
    pb_result checked = pb_bake_check_settings(desc, NULL, err); /* a part or points refused before bounce 1 */
    if (checked != PB_OK)
        return checked;
    /* each bounce samples the previous volume on the device, its depth tiles
     * one buffer: refused before the first bounce, not after it (counts past
     * 2^24 probes are bake_once's to refuse) */
    uint64_t probes = (uint64_t)desc->grid.counts[0] * desc->grid.counts[1] * desc->grid.counts[2];
    uint64_t tiles = pb_sample_depth_bytes(probes, desc->octmap_res ? desc->octmap_res : 16);
    if (ctx->max_allocation && probes <= (1u << 24) && tiles > ctx->max_allocation)
        return pb_fail(err, PB_ERROR_TOO_LARGE,
                       "--indirect volume samples each bounce's volume on the device: %llu probes' depth tiles need "
                       "%.1f MiB in one buffer, over the %.1f MiB %s allows (maxMemoryAllocationSize): use fewer "
                       "probes, a smaller octahedral map, or --indirect path",
                       (unsigned long long)probes, tiles / 1048576.0, ctx->max_allocation / 1048576.0, ctx->info.name);
    grid_bounce g = {ctx, scene, gs};
    return pb_indirect_volume_bounces(scene, desc, grid_bounce_bake, &g, out, err);
}
