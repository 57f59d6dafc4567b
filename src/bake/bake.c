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
#include "bake/bake_data.h"
#include "bake/indirect_volume.h"
#include "bake/convergence.h"
#include "bake/shard.h"
#include "bake/gpu_scene.h"
#include "bake/bake_features.h"
#include "bake/depth_lists.h"
#include "bake/depth_sums.h"
#include "bake/guide.h"
#include "bake/guide_cache.h"
#include "bake/light_cells.h"
#include "bake/light_cells_gpu.h"
#include "bake/shading.h"
#include "sample/sample_gpu.h"
#include "common/common.h"
#include "probebake/bake.h"
#include "probebake/octahedral.h"
#include "probebake/sh.h"

#include "bake_depth.spv.h"
#include "bake_sh.spv.h"
#include "bake_sh_native64.spv.h"
#include "bake_trace.spv.h"
#include "bake_trace_native64.spv.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct bake_buffers {
    pb_buffer params, probes, rotations, directions, rays, reduced, list, counters;
    pb_buffer relocation_directions; /* the relocation passes' fewer directions (unallocated when as many) */
    pb_buffer depth_lists;         /* bake_depth's ray lists per query cell (depth_lists.h) */
    pb_depth_sums sums;            /* bake_depth's moment sums over the passes (depth_sums.h) */
    pb_buffer nee;                 /* probe NEE: 2 vec4 per ray of a submission (unallocated when off) */
    pb_buffer guide, guide_slots;  /* path guiding's table and entry index (unallocated when off) */
    pb_guide guide_host;           /* its host copy and grid */
    const pb_light_cells_gpu *light; /* light cells (the GPU scene's, learned once per seed); NULL: off */
    pb_shading shading;
    pb_sample_buffers feedback;
    pb_pipeline trace, sh, depth;
    uint32_t features;             /* PB_FEATURE_*: the code the pipelines were specialised to keep */
} bake_buffers;

static void release(pb_context *ctx, bake_buffers *b)
{
    pb_buffer *bufs[13] = {&b->params, &b->probes, &b->rotations, &b->directions, &b->rays, &b->reduced,
                           &b->list, &b->counters, &b->nee, &b->guide, &b->guide_slots, &b->depth_lists,
                           &b->relocation_directions};
    for (int i = 0; i < 13; ++i)
        pb_buffer_destroy(ctx, bufs[i]);
    pb_depth_sums_destroy(ctx, &b->sums);
    pb_guide_free(&b->guide_host);
    pb_shading_destroy(ctx, &b->shading);
    pb_sample_release(ctx, &b->feedback);
    pb_pipeline_destroy(ctx, &b->trace);
    pb_pipeline_destroy(ctx, &b->sh);
    pb_pipeline_destroy(ctx, &b->depth);
}

uint32_t pb_bake_passes(const pb_bake_desc *d)
{
    return d->passes ? d->passes : d->target_error > 0.f ? 64 : 4;
}

static pb_result check_desc(const pb_scene *s, pb_bake_desc *d, pb_error *err)
{
    if (!d->rays_per_probe) d->rays_per_probe = 256;
    d->passes = pb_bake_passes(d);
    if (!(d->target_error >= 0.f) || !(d->target_error < 1.f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "target error %g: must be in [0, 1) (a relative error)",
                       d->target_error);
    if (!d->octmap_res) d->octmap_res = 16;
    if (d->lobe_power == 0.f) d->lobe_power = 50.f;
    if (d->invalid_backface_fraction == 0.f) d->invalid_backface_fraction = 0.25f;
    if (d->inside_fraction == 0.f) d->inside_fraction = d->invalid_backface_fraction + PB_INSIDE_MARGIN;
    if (d->max_distance == 0.f) {
        float dx = s->bounds_max[0] - s->bounds_min[0], dy = s->bounds_max[1] - s->bounds_min[1],
              dz = s->bounds_max[2] - s->bounds_min[2];
        d->max_distance = fmaxf(1e-3f, sqrtf(dx * dx + dy * dy + dz * dz));
    }
    if (d->points) {
        if (d->points->count == 0 || d->points->count > (1u << 24))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u probe points: need 1 to 2^24", d->points->count);
        if (!(d->points->spacing >= 0) || !isfinite(d->points->spacing))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "points spacing must be finite and >= 0");
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
    if (d->rays_per_probe > 65536)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u rays per probe: at most 65536", d->rays_per_probe);
    if (!d->relocation_rays)
        d->relocation_rays = d->rays_per_probe < PB_RELOCATION_RAYS_DEFAULT ? d->rays_per_probe : PB_RELOCATION_RAYS_DEFAULT;
    if (d->relocation_rays > d->rays_per_probe)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u relocation rays per probe: at most the %u rays per probe "
                       "of a pass", d->relocation_rays, d->rays_per_probe);
    if (d->passes > 1000000)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u passes: at most 1e6", d->passes);
    if (d->sh_window > PB_SH_WINDOW_LANCZOS || !(d->sh_window_width >= 0.f) || d->sh_window_width > 1e3f)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "SH window %u (width %g): none, hanning or lanczos, width in "
                       "(0, 1000]", d->sh_window, d->sh_window_width);
    if (!(d->indirect_clamp >= 0.f) || !isfinite(d->indirect_clamp))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "indirect clamp %g: must be finite and >= 0 (0: off)",
                       d->indirect_clamp);
    if (d->bounces > 64)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u bounces: at most 64", d->bounces);
    if (d->octmap_res > 64)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "octahedral map %u: at most 64 texels per side", d->octmap_res);
    pb_result r = pb_bake_check_light(s, d->sky, d->environment, err);
    if (r != PB_OK)
        return r;
    if (d->environment && (!d->environment->rgb || !d->environment->width || !d->environment->height ||
                           (uint64_t)d->environment->width * d->environment->height > (1u << 24) ||
                           !isfinite(d->environment->rotation_deg)))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "environment map: empty, over 2^24 texels, or a non-finite rotation");
    if (!(d->max_distance > 0.f) || !isfinite(d->max_distance) || !(d->lobe_power > 0.f) ||
        !(d->invalid_backface_fraction > 0.f && d->invalid_backface_fraction <= 1.f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "max distance and lobe power must be positive, the "
                                                       "invalid back-face fraction in (0, 1]");
    if (!(d->inside_fraction > 0.f) || !isfinite(d->inside_fraction))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "inside fraction %g: must be in (0, 1), or >= 1 to trace every "
                       "probe", d->inside_fraction);
    return PB_OK;
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


/* What one pass needs; per-probe host arrays are indexed by global probe. */
typedef struct bake_run {
    pb_context *ctx;
    bake_buffers *B;
    pb_gpu_scene *gs;
    const pb_bake_desc *d;
    const pb_scene *scene;
    uint32_t P, rpp, n, chunk;
    uint32_t chunk_now;            /* probes per submission now: shrinks so one takes ~0.25 s (Ctrl-C, watchdogs) */
    float *probes, *rotations, *reduced;
    double *sh_sum, *backfaces, *hits;
    double t_trace, t_sh, t_depth; /* GPU timestamps, ms */
    float *near;                   /* 8 per probe: nearest back t + dir, nearest front t + dir */
    uint64_t traversals;           /* BVH traversals of relocation and bake passes (counted by bake_trace) */
    uint64_t long_paths;           /* paths whose traversal loops ran past 32768 iterations */
    gpu_volume_refs feedback;      /* --indirect volume: the previous bounce's volume (probes 0: none) */
    pb_convergence *conv;          /* per probe: passes done and the spread of their estimates */
    uint32_t relocation_rpp;       /* rays per probe of a relocation pass (<= rpp) */
} bake_run;

/* The parameters of a pass, all but its submission's probe range: the one
 * place they are made, so the pipelines' feature mask (stage_resources) and
 * every pass's agree. */
static void pass_params(const bake_run *run, uint32_t pass, int relocating, const uint32_t *list,
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

/* One pass over every probe, in bounded submissions. A relocation pass
 * (relocating = 1) skips the depth filter and only records back faces and
 * the nearest hits; a bake pass accumulates SH, depth, back faces and hits. */
static pb_result run_pass(bake_run *run, uint32_t pass, int relocating, const uint32_t *list, uint32_t total,
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
    for (uint32_t first = 0; r == PB_OK && first < total; first += count) {
        count = total - first < run->chunk_now ? total - first : run->chunk_now;
        double t_submit = pb_now_ms();
        gpu_bake_params prm;
        pass_params(run, pass, relocating, list, &prm);
        prm.first_probe = first, prm.probe_count = count;
        if (pb_bake_features(&prm) & ~B->features) /* the pipelines were made without code this pass needs */
            return pb_fail(err, PB_ERROR_UNSUPPORTED, "bake pass %u needs kernel features 0x%x, the pipelines have 0x%x",
                           pass, pb_bake_features(&prm), B->features);
        memset(B->counters.mapped, 0, 8);
        memcpy(B->params.mapped, &prm, sizeof prm);
        if ((r = pb_cmd_begin(ctx, err)) != PB_OK)
            break;
        bake_push push = {B->params.address};
        pb_cmd_timestamp(ctx);
        pb_cmd_bind_set(ctx, &B->trace, run->gs->set);
        pb_cmd_dispatch(ctx, &B->trace, &push, (count * rpp + 63) / 64);
        pb_cmd_timestamp(ctx);
        pb_cmd_barrier(ctx);
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
        if (ctx->interval_count >= 2) {
            run->t_trace += ctx->intervals_ms[0];
            run->t_sh += ctx->intervals_ms[1];
            run->t_depth += ctx->interval_count >= 3 ? ctx->intervals_ms[2] : 0.0;
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

/* Moves probes after a relocation pass: one with too many back faces goes
 * out along its nearest back-face direction, past the surface; one closer
 * than min_front to a front face moves away from it. Offsets are bounded to
 * 45 % of the spacing per axis, so a probe stays inside its cell. Looks at
 * the `count` probes of `list` (NULL: all), the ones the pass traced; writes
 * those whose position changed to `moved` (may be `list`: it is read ahead of
 * the writes) and returns their number. */
static uint32_t relocate(bake_run *run, float *offsets, const uint32_t *list, uint32_t count, uint32_t *moved_list)
{
    const pb_bake_desc *d = run->d;
    float sp = INFINITY, bounds[3];
    for (int k = 0; k < 3; ++k) {
        float spacing_k = d->points ? (float)d->points->spacing : d->grid.spacing[k];
        bounds[k] = 0.45f * spacing_k;
        if (spacing_k > 0.f)
            sp = fminf(sp, spacing_k);
    }
    if (!isfinite(sp))
        sp = d->max_distance;
    float margin = 0.05f * sp, min_front = 0.2f * sp;
    uint32_t moved = 0;
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t p = list ? list[i] : i;
        const float *nr = run->near + 8 * (size_t)p;
        float *off = offsets + 3 * (size_t)p, step[3] = {0, 0, 0};
        float back_fraction = (float)(run->backfaces[p] / run->relocation_rpp);
        if (back_fraction > d->invalid_backface_fraction && nr[0] < d->max_distance) {
            for (int k = 0; k < 3; ++k)
                step[k] = nr[1 + k] * (nr[0] + margin);
        } else if (back_fraction <= d->invalid_backface_fraction && nr[4] < min_front) {
            for (int k = 0; k < 3; ++k)
                step[k] = -nr[5 + k] * (min_front - nr[4]);
        } else {
            continue;
        }
        int changed = 0;
        for (int k = 0; k < 3; ++k) {
            float bound = bounds[k];
            float o = off[k] + step[k];
            o = o > bound ? bound : (o < -bound ? -bound : o);
            changed |= o != off[k];
            run->probes[4 * (size_t)p + k] += o - off[k];
            off[k] = o;
        }
        if (changed)
            moved_list[moved++] = p;
    }
    return moved;
}

void pb_bake_probe_position(const pb_scene *scene, const pb_bake_desc *d, uint32_t p, float local[3], uint32_t *id)
{
    double world[3];
    if (d->points) {
        for (int k = 0; k < 3; ++k)
            world[k] = d->points->positions[3 * (size_t)p + k];
        *id = d->points->ids ? d->points->ids[p] : p;
    } else {
        uint32_t ijk[3] = {p % d->grid.counts[0], (p / d->grid.counts[0]) % d->grid.counts[1],
                           p / (d->grid.counts[0] * d->grid.counts[1])};
        for (int k = 0; k < 3; ++k)
            world[k] = scene->origin[k] + ((double)d->grid.origin[k] + (double)ijk[k] * (double)d->grid.spacing[k]);
        *id = p;
    }
    for (int k = 0; k < 3; ++k)
        local[k] = (float)(world[k] - scene->origin[k]);
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

/* One bake; feedback: the previous bounce's volume (--indirect volume) or NULL. */
/* The bake context: what its stages share. Per-probe host arrays are
 * indexed by local probe: i < own is global probe first + i, the rest are
 * the floor sample's probes of other parts (see stage_probe_set). */
typedef struct bake_job {
    pb_context *ctx;
    const pb_scene *scene;
    pb_gpu_scene *gs;
    pb_bake_desc d;                /* checked, defaults filled */
    uint32_t total, first, step, own, P; /* the bake's probes; this run's part (first, first + step, ...,
                                            own of them); traced here (own + samples) */
    uint32_t stride;               /* of the floor sample (shard.h) */
    uint32_t rpp, n, chunk;
    uint64_t reduced_floats;
    uint32_t *global;              /* per local probe: its global index */
    uint32_t *floor_list, floor_count; /* local indices of the floor sample */
    float *probes, *rotations, *directions, *reduced, *offsets, *near;
    double *sh_sum, *backfaces, *hits;
    uint32_t *active, *converged_at;
    uint64_t relocation_rays;      /* probe rays the relocation passes traced */
    uint32_t relocated_with;       /* rays per probe of each relocation iteration; 0: none ran */
    float *inside;                 /* per probe: the back-face share of relocation's rays where it ends up
                                      (NaN: not measured there) */
    uint8_t *skip;                 /* per probe: 1 if classified inside geometry, not traced (stage 5) */
    uint32_t skipped;
    uint32_t moved_last;           /* probes the last relocation iteration moved (j->active holds them) */
    pb_convergence conv;
    bake_buffers B;
    bake_run run;
} bake_job;

/* Whether global probe p is one of this run's part's own. */
static int bake_job_holds(const bake_job *j, uint64_t p)
{
    return p >= j->first && (p - j->first) % j->step == 0 && (p - j->first) / j->step < j->own;
}

/* Stage 1, the probe set and its budget: every probe, or a part's dealt
 * probes followed, under --target-error, by the floor sample's probes outside it
 * (traced for the 4 passes the floor needs, never written); device and host
 * memory checked before anything is allocated. */
static pb_result stage_probe_set(bake_job *j, pb_error *err)
{
    const pb_bake_desc *d = &j->d;
    pb_context *ctx = j->ctx;
    j->total = d->points ? d->points->count : d->grid.counts[0] * d->grid.counts[1] * d->grid.counts[2];
    j->first = 0, j->step = 1, j->own = j->total, j->stride = pb_floor_stride(j->total);
    if (d->shard_count && (d->shard_index >= d->shard_count || d->shard_count > j->total))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "shard %u/%u: need 0 <= I < N <= the %u probes",
                       d->shard_index, d->shard_count, j->total);
    if (d->shard_count) /* dealt: probes I, I + N, ... (shard.h) */
        j->first = d->shard_index, j->step = d->shard_count,
        j->own = pb_shard_dealt_count(j->total, d->shard_index, d->shard_count);
    uint32_t samples = 0;
    for (uint64_t s = 0; d->target_error > 0.f && s < j->total; s += j->stride)
        samples += !bake_job_holds(j, s);
    uint32_t P = j->P = j->own + samples;
    uint32_t rpp = j->rpp = d->rays_per_probe, n = j->n = d->octmap_res, texels = n * n;
    uint32_t chunk = ctx->desc.rays_per_submit / rpp;
    chunk = chunk < 1 ? 1 : (chunk > P ? P : chunk);
    if (chunk > ctx->limits.maxComputeWorkGroupCount[1]) /* bake_depth dispatches one row per probe */
        chunk = ctx->limits.maxComputeWorkGroupCount[1];
    j->chunk = chunk;
    uint64_t reduced_floats = j->reduced_floats = (uint64_t)chunk * PB_REDUCED_SH_STRIDE;
    uint64_t need = (uint64_t)P * (16 + 48 + (uint64_t)texels * 8) + (uint64_t)rpp * 16 +
                    (uint64_t)chunk * rpp * (d->probe_nee ? 48 : 16) + reduced_floats * 4;
    if (ctx->info.device_local_bytes && need > ctx->info.device_local_bytes / 2)
        return pb_fail(err, PB_ERROR_TOO_LARGE,
                       "%u probes x %u rays need %.1f MiB of device memory; the budget is half of %s's %.1f MiB "
                       "(%.1f MiB): use fewer probes or rays, or a smaller octahedral map",
                       P, rpp, need / 1048576.0, ctx->info.name, ctx->info.device_local_bytes / 1048576.0,
                       ctx->info.device_local_bytes / 2097152.0);
    /* host memory too: lavapipe (Mesa 25) reports a heap as large as host
     * memory, so the device check alone lets through bakes whose host
     * accumulators (SH sums in double, a window of depth sums read back, the
     * volume) cannot be allocated */
    uint64_t tile_bytes = pb_volume_tile_halves(n) * 2u;
    uint64_t host_need = (uint64_t)P * (16 + 48 + 27 * 8 + 16 + 24 + 12 + 16 + 24 + 136 + tile_bytes) +
                         (uint64_t)chunk * texels * 8 + (uint64_t)rpp * 16 + reduced_floats * 4;
    uint64_t host_have = pb_host_memory_bytes();
    if (host_have && host_need > host_have / 2)
        return pb_fail(err, PB_ERROR_TOO_LARGE,
                       "%u probes x %u rays need %.1f MiB of host memory; the budget is half of this machine's %.1f MiB "
                       "(%.1f MiB): use fewer probes or a smaller octahedral map",
                       P, rpp, host_need / 1048576.0, host_have / 1048576.0, host_have / 2097152.0);
    /* the largest buffer, bake_depth's sums: within the allocation limit in blocks */
    return pb_depth_sums_plan(ctx, P, texels, &j->B.sums, err);
}

/* Stage 2, place: the host arrays, the local-to-global map, the floor
 * sample, and every probe's position and id (which keys its random
 * numbers). */
static pb_result stage_place(bake_job *j, pb_error *err)
{
    uint32_t P = j->P, rpp = j->rpp;
    j->probes = calloc((size_t)P * 4, sizeof(float));
    j->rotations = malloc((size_t)P * 12 * sizeof(float));
    j->directions = malloc((size_t)rpp * 4 * sizeof(float));
    j->sh_sum = calloc((size_t)P * 27, sizeof(double));
    j->backfaces = calloc(P, sizeof(double)), j->hits = calloc(P, sizeof(double));
    j->reduced = malloc((size_t)j->reduced_floats * sizeof(float));
    j->converged_at = calloc(P, sizeof(uint32_t));
    j->active = malloc(P * sizeof *j->active);
    j->offsets = calloc((size_t)P * 3, sizeof(float));
    j->near = malloc((size_t)P * 8 * sizeof(float));
    j->inside = malloc((size_t)P * sizeof(float));
    j->skip = calloc(P, 1);
    j->global = malloc((size_t)P * sizeof *j->global);
    j->floor_list = malloc(PB_FLOOR_SAMPLE * sizeof *j->floor_list);
    if (!j->probes || !j->rotations || !j->directions || !j->sh_sum || !j->backfaces || !j->hits ||
        !j->reduced || !j->converged_at || !j->active || !j->offsets || !j->near || !j->global || !j->floor_list ||
        !j->inside || !j->skip ||
        !pb_convergence_init(&j->conv, P) || pb_sf_directions(rpp, j->directions) != PB_OK)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u probes", P);
    for (uint32_t i = 0; i < j->own; ++i)
        j->global[i] = pb_shard_probe(j->first, j->step, i);
    for (uint64_t s = 0, extra = j->own; j->d.target_error > 0.f && s < j->total; s += j->stride) {
        int mine = bake_job_holds(j, s);
        if (!mine)
            j->global[extra] = (uint32_t)s;
        j->floor_list[j->floor_count++] = mine ? (uint32_t)(s - j->first) / j->step : (uint32_t)extra++;
    }
    for (uint32_t p = 0; p < P; ++p) {
        uint32_t id;
        pb_bake_probe_position(j->scene, &j->d, j->global[p], j->probes + 4 * (size_t)p, &id);
        memcpy(&j->probes[4 * p + 3], &id, 4);
    }
    return PB_OK;
}

/* The kernel features of this bake's relocation and trace passes. */
static uint32_t bake_kernel_features(const bake_run *run)
{
    gpu_bake_params relocation, bake;
    pass_params(run, PB_RELOCATION_PASS, 1, NULL, &relocation);
    pass_params(run, 0, 0, NULL, &bake);
    return pb_bake_features(&relocation) | pb_bake_features(&bake);
}

/* Stage 3, the device side: shading data, the guide when on, probe and ray
 * buffers, the previous volume for --indirect volume, then the three
 * pipelines, made while the light cells are learned; then the pass runner
 * over them. */
static pb_result stage_resources(bake_job *j, const pb_sample_volume *feedback, pb_error *err)
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
    pb_pipeline_request kernels[3] = {
        {PB_KERNEL_SPIRV(ctx, bake_trace), sizeof(bake_push), spec, 3, 64, "bake_trace", &B->trace},
        {PB_KERNEL_SPIRV(ctx, bake_sh), sizeof(bake_push), spec, 3, 64, "bake_sh", &B->sh},
        {pb_spv_bake_depth, sizeof pb_spv_bake_depth, sizeof(bake_push), spec, 3, 64, "bake_depth", &B->depth}};
    pb_pipeline_batch batch;
    if (r == PB_OK)
        r = pb_pipelines_begin(ctx, kernels, 3, &batch, err);
    if (r == PB_OK) {
        pb_result learned = PB_OK;
        if (d->light_cells)
            learned = pb_light_cells_gpu_get(ctx, j->scene, j->gs, d->seed, &B->shading.emit, &B->light, NULL, err);
        pb_result made = pb_pipelines_end(ctx, &batch, learned == PB_OK ? err : NULL);
        r = learned != PB_OK ? learned : made;
    }
    uint32_t needed = bake_kernel_features(&j->run);
    if (r == PB_OK && (needed & ~planned)) { /* a plan that missed a part: made again rather than run without it */
        pb_logf(&ctx->desc.log, PB_LOG_WARN, "bake kernels planned with features 0x%x, the bake needs 0x%x: made again",
                planned, needed);
        spec[2] = needed;
        r = pb_pipelines_begin(ctx, kernels, 3, &batch, err);
        if (r == PB_OK)
            r = pb_pipelines_end(ctx, &batch, err);
    }
    B->features = spec[2];
    char names[160];
    pb_bake_features_name(B->features, names, sizeof names);
    pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "bake kernels specialised to: %s", names);
    return r;
}

/* The back-face share of the last relocation pass's rays for the `count`
 * probes of `list` (NULL: all) where they stand. */
static void record_inside(bake_job *j, const uint32_t *list, uint32_t count)
{
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t p = list ? list[i] : i;
        j->inside[p] = (float)(j->backfaces[p] / j->run.relocation_rpp);
    }
}

/* Stage 4, relocate: probes in geometry move out, probes against a wall
 * move away. The first iteration traces every probe; each later one only
 * the probes the one before moved (the rest stay where they were tested).
 * Iterations use their own pass numbers (RNG streams), so the bake passes
 * that follow are the same whatever relocation did. Records each probe's
 * back-face share where it was last tested (stage 5 reads it). */
static pb_result stage_relocate(bake_job *j, pb_error *err)
{
    const pb_bake_desc *d = &j->d;
    uint32_t P = j->P;
    uint32_t iterations = d->skip_relocation || j->scene->triangle_count == 0 ? 0 : 3;
    if (d->points && !(d->points->spacing > 0))
        iterations = 0; /* no cell to stay in */
    pb_result r = PB_OK;
    const uint32_t *list = NULL; /* then j->active, free until the trace passes */
    j->relocated_with = iterations ? j->run.relocation_rpp : 0u;
    for (uint32_t p = 0; p < P; ++p)
        j->inside[p] = NAN;
    uint32_t count = P;
    for (uint32_t it = 0; r == PB_OK && it < iterations && count > 0; ++it) {
        memset(j->backfaces, 0, P * sizeof(double));
        r = run_pass(&j->run, PB_RELOCATION_PASS + it, 1, list, count, err);
        if (r != PB_OK)
            break;
        j->relocation_rays += (uint64_t)count * j->run.relocation_rpp;
        record_inside(j, list, count);
        uint32_t moved = relocate(&j->run, j->offsets, list, count, j->active);
        pb_logf(&j->ctx->desc.log, PB_LOG_DEBUG, "relocation %u: %u probes traced, %u moved", it + 1, count, moved);
        if (moved)
            r = pb_buffer_upload(j->ctx, &j->B.probes, 0, j->probes, (uint64_t)P * 16, err);
        for (uint32_t i = 0; i < moved; ++i)
            j->inside[j->active[i]] = NAN; /* not tested where it went */
        list = j->active, count = moved;
    }
    j->moved_last = iterations ? count : 0;
    memset(j->backfaces, 0, P * sizeof(double));
    memset(j->hits, 0, P * sizeof(double));
    return r;
}

/* Stage 5, classify: a probe whose relocation rays, where it ends up, hit
 * back faces more often than d->inside_fraction is inside geometry. Its
 * passes would only confirm it invalid and be thrown away by dilation, so
 * it is flagged PB_PROBE_INSIDE and not traced (DDGI's probe
 * classification). The probes the last relocation iteration moved are
 * tested once more first, with their own pass number, without moving. */
static pb_result stage_classify(bake_job *j, pb_error *err)
{
    const pb_bake_desc *d = &j->d;
    pb_result r = PB_OK;
    if (!j->relocated_with || !(d->inside_fraction < 1.f))
        return PB_OK;
    if (j->moved_last) { /* j->active holds them (stage 4) */
        memset(j->backfaces, 0, j->P * sizeof(double));
        r = run_pass(&j->run, PB_RELOCATION_PASS + 3, 1, j->active, j->moved_last, err);
        if (r != PB_OK)
            return r;
        j->relocation_rays += (uint64_t)j->moved_last * j->run.relocation_rpp;
        record_inside(j, j->active, j->moved_last);
        memset(j->backfaces, 0, j->P * sizeof(double));
        memset(j->hits, 0, j->P * sizeof(double));
    }
    j->skipped = 0;
    for (uint32_t p = 0; p < j->P; ++p) {
        j->skip[p] = j->inside[p] > d->inside_fraction;
        j->skipped += j->skip[p];
    }
    pb_logf(&j->ctx->desc.log, PB_LOG_DEBUG, "classification: %u probes retested, %u of %u inside geometry (not traced)",
            j->moved_last, j->skipped, j->P);
    return r;
}

/* Stage 6, the trace passes over the probes not classified inside. With a
 * target error, probes whose irradiance estimate has converged (after at
 * least 4 passes, along every axis the standard error of the mean is below
 * target x the mean, or x the floor where that is larger: convergence.h)
 * drop out and the rest keep going. The floor is taken once, after pass 4,
 * over the floor sample's traced probes, whose probes of other parts are
 * then done. */
static pb_result stage_trace_passes(bake_job *j, pb_error *err)
{
    const pb_bake_desc *d = &j->d;
    uint32_t active_count = 0;
    for (uint32_t p = 0; p < j->P; ++p)
        if (!j->skip[p])
            j->active[active_count++] = p;
    int listed = d->target_error > 0.f || j->skipped;
    /* start the submission size afresh: relocation's rays stop at their first
     * hits, so the size its passes grew to would make a bake pass's first
     * submission run for seconds (a late Ctrl-C, a watchdog) */
    j->run.chunk_now = 0;
    double floor = 0.0;
    pb_result r = PB_OK;
    for (uint32_t pass = 0; r == PB_OK && pass < d->passes && active_count > 0; ++pass) {
        r = run_pass(&j->run, pass, 0, listed ? j->active : NULL, active_count, err);
        if (r != PB_OK || !(d->target_error > 0.f) || pass + 1 < 4)
            continue;
        uint32_t keep = 0;
        if (pass + 1 == 4) {
            floor = pb_convergence_floor(&j->conv, j->floor_list, j->floor_count);
            for (uint32_t i = 0; i < active_count; ++i)
                if (j->active[i] < j->own)
                    j->active[keep++] = j->active[i];
            active_count = keep, keep = 0;
        }
        for (uint32_t i = 0; i < active_count; ++i) {
            uint32_t p = j->active[i];
            if (pb_convergence_reached(&j->conv, p, d->target_error, floor))
                j->converged_at[p] = pass + 1;
            else
                j->active[keep++] = p;
        }
        active_count = keep;
    }
    return r;
}

/* Stage 7's per-probe work (SH, flags, accounting, depth tiles with their
 * borders) over a range of probes: each probe writes only its own slots, so
 * ranges run on all host cores (on an H100 this stage was a quarter of a
 * 16k-probe bake's wall time, single-threaded). */
typedef struct volume_fill {
    const bake_job *j;
    pb_volume *out;
    const float *sums;             /* the device's depth sums of probes first.. (a run of them) */
    uint32_t first;
} volume_fill;

static void volume_fill_range(void *user, uint64_t begin, uint64_t end)
{
    const volume_fill *vf = user;
    const bake_job *j = vf->j;
    const pb_bake_desc *d = &j->d;
    pb_volume *out = vf->out;
    uint32_t rpp = j->rpp, n = j->n, texels = n * n;
    const uint32_t *passes_done = j->conv.passes;
    for (uint32_t p = vf->first + (uint32_t)begin; p < vf->first + (uint32_t)end; ++p) {
        uint32_t id;
        float local[3];
        pb_bake_probe_position(j->scene, d, j->global[p], local, &id);
        for (int k = 0; k < 3; ++k) {
            /* relative to the volume origin (the grid's first probe, or the scene origin for points) */
            out->base[3 * p + k] = d->points ? local[k] : (float)((double)local[k] - (double)d->grid.origin[k]);
            out->offset[3 * p + k] = j->offsets[3 * p + k];
        }
        uint16_t *tile = out->depth + pb_volume_tile_halves(n) * p;
        uint32_t relocated = j->offsets[3 * p] != 0.f || j->offsets[3 * p + 1] != 0.f || j->offsets[3 * p + 2] != 0.f
                                 ? PB_PROBE_RELOCATED
                                 : 0u;
        if (j->skip[p]) { /* classified inside (stage 5): no light, no free distance; dilation fills its SH */
            memset(out->sh + 27 * (size_t)p, 0, 27 * sizeof(float));
            memset(tile, 0, pb_volume_tile_halves(n) * sizeof *tile);
            out->probe_flags[p] = PB_PROBE_INSIDE | relocated;
            out->probe_paths[p] = 0;
            continue;
        }
        float c[27];
        uint32_t done_p = passes_done[p] ? passes_done[p] : 1;
        for (int k = 0; k < 27; ++k)
            c[k] = (float)(j->sh_sum[27 * (size_t)p + k] / done_p);
        pb_sh_radiance_to_irradiance(c);
        pb_sh_apply_window(c, (pb_sh_window_kind)d->sh_window, d->sh_window_width);
        memcpy(out->sh + 27 * (size_t)p, c, sizeof c);
        double rays_total = (double)rpp * done_p;
        uint32_t f = relocated;
        if (j->hits[p] == 0)
            f |= PB_PROBE_OUTSIDE;
        if (j->backfaces[p] / rays_total <= d->invalid_backface_fraction)
            f |= PB_PROBE_VALID;
        if (j->converged_at[p] && j->converged_at[p] < d->passes)
            f |= PB_PROBE_CONVERGED;
        out->probe_flags[p] = f;
        out->probe_paths[p] = (uint32_t)fmin((double)passes_done[p] * rpp, (double)UINT32_MAX);
        float rse = pb_convergence_relative_error(&j->conv, p);
        if (rse >= 0.f)
            out->probe_std_error[p] = rse;
        double unit = out->depth_unit; /* a power of two: the division is exact */
        for (uint32_t by = 0; by < n + 2; ++by)
            for (uint32_t bx = 0; bx < n + 2; ++bx) {
                uint32_t x, y;
                pb_oct_border_source(bx, by, n, &x, &y);
                const float *m = vf->sums + 2 * ((size_t)texels * (p - vf->first) + (size_t)y * n + x);
                tile[2 * (by * (n + 2) + bx)] = pb_half_from_float((float)((double)m[0] / done_p / unit));
                tile[2 * (by * (n + 2) + bx) + 1] =
                    pb_half_from_float((float)((double)m[1] / done_p / (unit * unit)));
            }
    }
}

static void volume_fill_run(void *user, const float *sums, uint32_t first, uint32_t n)
{
    volume_fill *vf = user;
    vf->sums = sums, vf->first = first;
    pb_parallel_for(n, 64, 0, volume_fill_range, vf);
}

/* Stage 7, SH, depth and validity: the passes' means as irradiance SH
 * (windowed if asked) and depth tiles with borders, each probe's flags,
 * paths and standard error, into the volume (a part's, for a shard). */
static pb_result stage_volume(bake_job *j, pb_volume *out, pb_error *err)
{
    const pb_bake_desc *d = &j->d;
    uint32_t own = j->own, rpp = j->rpp, n = j->n;
    out->flags = PB_VOLUME_IRRADIANCE | (d->points ? 0u : PB_VOLUME_GRID) | (d->exclude_direct ? 0u : PB_VOLUME_DIRECT) |
                 (d->shard_count ? PB_VOLUME_SHARD : 0u);
    out->probe_count = own;
    if (d->shard_count)
        out->shard = (pb_volume_shard){d->shard_index, d->shard_count, j->first, j->total, j->step};
    if (d->points) {
        out->counts[0] = j->total, out->counts[1] = out->counts[2] = 1;
    } else {
        memcpy(out->counts, d->grid.counts, sizeof out->counts);
    }
    out->octmap_res = n;
    for (int k = 0; k < 3; ++k) {
        out->origin[k] = j->scene->origin[k] + (d->points ? 0.0 : (double)d->grid.origin[k]);
        out->spacing[k] = d->points ? 0.0 : d->grid.spacing[k];
    }
    uint32_t passes_max = 0;
    const uint32_t *passes_done = j->conv.passes;
    for (uint32_t p = 0; p < own; ++p) {
        passes_max = passes_done[p] > passes_max ? passes_done[p] : passes_max;
        out->rays_traced += (uint64_t)passes_done[p] * rpp;
    }
    out->settings = (pb_volume_settings){d->seed,         0, rpp, passes_max, d->bounces, 0, d->target_error,
                                        d->max_distance, d->sh_window, d->sh_window_width, d->indirect_clamp};
    out->settings.scene_hash = pb_scene_hash(j->scene);
    out->settings.relocation_rays = j->relocated_with;
    out->settings.techniques = (d->probe_nee ? PB_TECHNIQUE_PROBE_NEE : 0u) |
                               (j->B.guide_host.table ? PB_TECHNIQUE_GUIDING : 0u) |
                               (j->B.light && j->B.light->host.table ? PB_TECHNIQUE_LIGHT_CELLS : 0u) |
                               (j->B.shading.emit.count && !d->emitters_by_area ? PB_TECHNIQUE_SOLID_ANGLE : 0u);
    snprintf(out->device, sizeof out->device, "%.127s", j->ctx->info.name);
    pb_result r = pb_volume_alloc(out, err);
    if (r != PB_OK)
        return r;
    /* The device's depth sums, a run at a time: in place where mapped
     * (lavapipe, UMA), else at most a submission's probes through one
     * download buffer, each run filled as it lands (no host copy of all
     * sums: its first touch would cost what summing them on the host did) */
    volume_fill vf = {j, out, NULL, 0};
    return pb_depth_sums_read(j->ctx, &j->B.sums, own, j->chunk, volume_fill_run, &vf, err);
}

static void bake_job_free(bake_job *j)
{
    release(j->ctx, &j->B);
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
        r = stage_probe_set(&j, err);
    if (r != PB_OK)
        return r;
    if (!scene_emits_light(scene, &j.d))
        pb_logf(&ctx->desc.log, PB_LOG_WARN,
                "%s: no lights, no emissive surfaces and a black sky: the volume will be black (give --sky or --env)",
                scene->path[0] ? scene->path : "scene");
    /* wall time per stage, and the GPU time inside relocation and the passes
     * (--verbose): what a small bake spends besides tracing */
    double t[7], gpu_relocate = 0, gpu_passes = 0;
    t[0] = pb_now_ms();
    r = stage_place(&j, err);
    t[1] = pb_now_ms();
    if (r == PB_OK)
        r = stage_resources(&j, feedback, err);
    t[2] = pb_now_ms();
    if (r == PB_OK)
        r = stage_relocate(&j, err);
    if (r == PB_OK)
        r = stage_classify(&j, err);
    t[3] = pb_now_ms();
    gpu_relocate = j.run.t_trace + j.run.t_sh;
    if (r == PB_OK)
        r = stage_trace_passes(&j, err);
    t[4] = pb_now_ms();
    gpu_passes = j.run.t_trace + j.run.t_sh + j.run.t_depth - gpu_relocate;
    if (r == PB_OK)
        r = stage_volume(&j, out, err);
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
        out->timings.octmap = j.run.t_depth;
        out->timings.total = pb_now_ms() - t_start;
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
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    if (desc->shard_count)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "--indirect volume samples the whole previous bounce's volume: a part cannot bake it alone "
                       "(shard the path-traced bake instead)");
    if (desc->points)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "--indirect volume samples the previous bounce's grid: it needs a grid, not points");
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
