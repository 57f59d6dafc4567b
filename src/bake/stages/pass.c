/* One pass over a bake's probes: its parameters, bounded submissions of
 * bake_trace -> bake_sh -> bake_depth, and its results added to the
 * probes' sums (stages/job.h). */
#include "bake/stages/job.h"
#include "bake/bake_features.h"
#include "common/common.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The parameters of a pass, all but its submission's probe range: the one
 * place they are made, so the pipelines' feature mask (resources.c) and
 * every pass's agree. */
void pb_bake_pass_params(const bake_run *run, uint32_t pass, int relocating, const uint32_t *list,
                        gpu_bake_params *prm)
{
    const bake_buffers *B = run->B;
    const pb_bake_desc *d = run->d;
    memset(prm, 0, sizeof *prm);
    prm->scene = run->gs->refs;
    pb_shading_params(&B->shading, prm);
    prm->probes = B->probes.address;
    prm->rotations = B->rotations.address, prm->directions = B->directions.address, prm->rays = B->rays.address;
    prm->reduced = B->reduced.address;
    prm->depth_lists = B->depth_lists.address, prm->depth_sum = B->sums.table.address;
    prm->depth_block_probes = B->sums.block_probes;
    prm->probe_list = list ? B->list.address : 0;
    prm->counters = B->counters.address;
    prm->indirect_clamp = d->indirect_clamp;
    prm->emitters_by_area = d->emitters_by_area;
    if (!relocating) {
        prm->volume = run->feedback;
        prm->nee = B->nee.address; /* 0 unless probe NEE is on */
        if (B->guide_host.table) {
            const pb_guide *g = &B->guide_host;
            prm->guide = B->guide.address, prm->guide_slots = B->guide_slots.address;
            memcpy(prm->guide_origin, g->grid.origin, sizeof g->grid.origin);
            prm->guide_origin[3] = g->grid.inv_cell;
            memcpy(prm->guide_dims, g->grid.dims, sizeof g->grid.dims);
        }
        if (B->light && B->light->host.table) {
            const pb_light_cells *lc = &B->light->host;
            memcpy(prm->light_origin, lc->grid.origin, sizeof lc->grid.origin);
            prm->light_origin[3] = lc->grid.inv_cell;
            memcpy(prm->light_dims, lc->grid.dims, sizeof lc->grid.dims);
            prm->light_dims[3] = lc->clusters;
            prm->light_cells = B->light->table.address, prm->light_cell_slots = B->light->slots.address;
            prm->light_clusters = B->light->clusters.address, prm->light_members = B->light->members.address;
            prm->light_cluster_of = B->light->cluster_of.address;
        }
    }
    prm->rays_per_probe = relocating ? run->relocation_rpp : run->rpp, prm->pass_index = pass;
    if (relocating && run->relocation_rpp != run->rpp)
        prm->directions = B->relocation_directions.address;
    prm->seed = relocating ? PB_RELOCATION_SEED : d->seed, prm->bounces = relocating ? 0 : d->bounces;
    prm->octmap_res = run->n, prm->max_distance = d->max_distance, prm->lobe_power = d->lobe_power;
    prm->direct = !d->exclude_direct, prm->lobe_cutoff = pb_depth_lobe_cutoff(d->lobe_power);
}

/* A submission's results (run->reduced) added to its probes' sums. Each
 * probe appears once in a submission and owns its slots, so ranges of
 * probes run on all host cores; the sums are the serial loop's bit for bit.
 * The depth moments are summed on the device (bake_depth.comp): added here
 * they cost 4 KiB of fresh doubles per probe at 16x16, whose first touch
 * (page faults) made the first pass's host work 10x the later passes'. */
typedef struct pass_results {
    bake_run *run;
    const uint32_t *list;
    uint32_t first, count;
    int relocating;
} pass_results;

/* bake_restart's lane group: the invocations whose K paths interleave, as
 * wide as the device's subgroup, so that a subgroup's first rays leave one
 * probe along neighbouring directions as in bake_trace. The mapping is a
 * permutation of each workgroup's paths whatever the width (the kernel needs
 * no subgroup operations); a width that does not divide 64 gives 64. */
static uint32_t restart_lane_group(pb_context *ctx)
{
    uint32_t w = pb_context_device(ctx)->subgroup_size;
    return w && w <= 64 && 64 % w == 0 ? w : 64;
}

static void add_pass_results(void *user, uint64_t begin, uint64_t end)
{
    const pass_results *pr = user;
    bake_run *run = pr->run;
    for (uint32_t l = (uint32_t)begin; l < (uint32_t)end; ++l) {
        const float *o = run->reduced + PB_REDUCED_SH_STRIDE * (size_t)l;
        uint32_t p = pr->list ? pr->list[pr->first + l] : pr->first + l;
        run->backfaces[p] += o[27];
        if (pr->relocating) {
            memcpy(run->near + 8 * (size_t)p, o + 29, 8 * sizeof(float));
            continue;
        }
        for (int c = 0; c < 27; ++c)
            run->sh_sum[27 * (size_t)p + c] += o[c];
        run->hits[p] += o[28];
        pb_convergence_add(run->conv, p, o);
    }
}

/* One pass over every probe, in bounded submissions (a wavefront's trace
 * in submissions of its own before each one: wave.c). A relocation pass
 * (relocating = 1) skips the depth filter and only records back faces and
 * the nearest hits; a bake pass accumulates SH, depth, back faces and hits. */
pb_result pb_bake_run_pass(bake_run *run, uint32_t pass, int relocating, const uint32_t *list, uint32_t total,
                          pb_error *err)
{
    pb_context *ctx = run->ctx;
    bake_buffers *B = run->B;
    const pb_bake_desc *d = run->d;
    uint32_t P = run->P, rpp = relocating ? run->relocation_rpp : run->rpp, n = run->n, texels = n * n;
    pb_bake_rotations(relocating ? PB_RELOCATION_SEED : d->seed, pass, run->probes, P, run->rotations);
    pb_result r = pb_buffer_upload(ctx, &B->rotations, 0, run->rotations, (uint64_t)P * 48, err);
    if (r == PB_OK && list)
        r = pb_buffer_upload(ctx, &B->list, 0, list, (uint64_t)total * 4, err);
    if (!run->chunk_now) { /* start at about 64k rays, then adapt */
        uint32_t start = 65536u / rpp;
        run->chunk_now = start < 1 ? 1 : (start > run->chunk ? run->chunk : start);
    }
    uint32_t count = 0;
    int wave = B->wave_capacity && !relocating; /* relocation traces first hits only: one kernel */
    for (uint32_t first = 0; r == PB_OK && first < total; first += count) {
        count = total - first < run->chunk_now ? total - first : run->chunk_now;
        if (wave && (uint64_t)count * rpp > B->wave_capacity)
            count = B->wave_capacity / rpp;
        double t_submit = pb_now_ms();
        gpu_bake_params prm;
        pb_bake_pass_params(run, pass, relocating, list, &prm);
        prm.first_probe = first, prm.probe_count = count;
        if (pb_bake_features(&prm) & ~B->features) /* the pipelines were made without code this pass needs */
            return pb_fail(err, PB_ERROR_UNSUPPORTED, "bake pass %u needs kernel features 0x%x, the pipelines have 0x%x",
                           pass, pb_bake_features(&prm), B->features);
        memset(B->counters.mapped, 0, 8);
        memcpy(B->params.mapped, &prm, sizeof prm);
        if (wave && (r = pb_bake_wave_trace(run, &prm, count * rpp, err)) != PB_OK)
            break;
        if ((r = pb_cmd_begin(ctx, err)) != PB_OK)
            break;
        /* bake_restart (--schedule restart) traces K paths per invocation; relocation, first hits only, 1 */
        uint32_t K = d->schedule == PB_SCHEDULE_RESTART && !relocating ? d->paths_per_lane : 1;
        uint32_t groups = (count * rpp + 64 * K - 1) / (64 * K);
        bake_push push = {B->params.address, pb_dispatch_spread(groups), K, restart_lane_group(ctx), 0};
        if (!wave) {
            pb_cmd_timestamp(ctx);
            pb_cmd_bind_set(ctx, &B->trace, run->gs->set);
            pb_cmd_dispatch(ctx, &B->trace, &push, groups);
            pb_cmd_timestamp(ctx);
            pb_cmd_barrier(ctx);
        }
        pb_cmd_timestamp(ctx);
        pb_cmd_bind_set(ctx, &B->sh, run->gs->set);
        pb_cmd_dispatch(ctx, &B->sh, &push, (count + 63) / 64);
        pb_cmd_timestamp(ctx);
        if (!relocating) {
            pb_cmd_timestamp(ctx);
            pb_cmd_bind_set(ctx, &B->depth, run->gs->set);
            pb_cmd_dispatch2(ctx, &B->depth, &push, (texels + 63) / 64, count);
            pb_cmd_timestamp(ctx);
        }
        pb_cmd_barrier_to_host(ctx);
        if ((r = pb_cmd_submit_wait(ctx, NULL, err)) != PB_OK)
            break;
        /* keep each submission near a quarter second: a cancel then takes
         * effect promptly, and slow devices stay clear of watchdogs; the
         * split never changes results (every random number is keyed by probe) */
        double took = pb_now_ms() - t_submit;
        if (took > 250.0 && run->chunk_now > 1)
            run->chunk_now = run->chunk_now / 2 > 1 ? run->chunk_now / 2 : 1;
        else if (took < 60.0 && run->chunk_now < run->chunk)
            run->chunk_now = run->chunk_now * 2 < run->chunk ? run->chunk_now * 2 : run->chunk;
        const double *ms = ctx->intervals_ms + (wave ? 0 : 1); /* the wavefront timed its own submissions */
        if (ctx->interval_count >= 2 - (uint32_t)wave) {
            run->t_trace += wave ? 0.0 : ctx->intervals_ms[0];
            run->t_sh += ms[0];
            run->t_depth += ctx->interval_count >= 3 - (uint32_t)wave ? ms[1] : 0.0;
        }
        uint32_t n_trav[2];
        memcpy(n_trav, B->counters.mapped, 8);
        run->traversals += n_trav[0];
        run->long_paths += n_trav[1];
        memcpy(run->reduced, B->reduced.mapped, (size_t)count * PB_REDUCED_SH_STRIDE * 4);
        pass_results pr = {run, list, first, count, relocating};
        pb_parallel_for(count, 64, 0, add_pass_results, &pr);
        if (d->progress) {
            char label[64];
            float f = relocating ? 0.f : ((float)pass + (float)(first + count) / (float)total) / (float)d->passes;
            if (relocating)
                snprintf(label, sizeof label, "relocating");
            else
                snprintf(label, sizeof label, "pass %u/%u", pass + 1, d->passes);
            if (d->progress(f, label, d->progress_user))
                r = pb_fail(err, PB_ERROR_CANCELLED, "bake cancelled");
        }
    }
    return r;
}
