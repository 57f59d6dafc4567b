/* Stages 1 and 2: the probe set with its memory budget, and every probe's
 * position (stages/job.h). */
#include "bake/stages/job.h"
#include "bake/shard.h"
#include "common/common.h"

#include <stdlib.h>
#include <string.h>

/* Stage 1, the probe set and its budget: every probe, or a part's dealt
 * probes followed, under --target-error, by the floor sample's probes outside it
 * (traced for the 4 passes the floor needs, never written); device and host
 * memory checked before anything is allocated. */
pb_result pb_bake_stage_probe_set(bake_job *j, pb_error *err)
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
    uint32_t wave_capacity = j->B.wave_capacity = pb_bake_wave_capacity(ctx, d, rpp, (uint64_t)chunk * rpp);
    uint64_t need = (uint64_t)P * (16 + 48 + (uint64_t)texels * 8) + (uint64_t)rpp * 16 +
                    (uint64_t)chunk * rpp * (d->probe_nee ? 48 : 16) + reduced_floats * 4 +
                    (wave_capacity ? pb_bake_wave_bytes(wave_capacity) : 0);
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
pb_result pb_bake_stage_place(bake_job *j, pb_error *err)
{
    uint32_t P = j->P, rpp = j->rpp;
    /* per probe: a million probes' arrays are hundreds of MB (common.h) */
    j->probes = pb_calloc_large((size_t)P * 4, sizeof(float));
    j->rotations = pb_malloc_large((size_t)P * 12 * sizeof(float));
    j->directions = malloc((size_t)rpp * 4 * sizeof(float));
    j->sh_sum = pb_calloc_large((size_t)P * 27, sizeof(double));
    j->backfaces = pb_calloc_large(P, sizeof(double)), j->hits = pb_calloc_large(P, sizeof(double));
    j->reduced = pb_malloc_large((size_t)j->reduced_floats * sizeof(float));
    j->converged_at = pb_calloc_large(P, sizeof(uint32_t));
    j->active = pb_malloc_large(P * sizeof *j->active);
    j->offsets = pb_calloc_large((size_t)P * 3, sizeof(float));
    j->near = pb_malloc_large((size_t)P * 8 * sizeof(float));
    j->inside = pb_malloc_large((size_t)P * sizeof(float));
    j->skip = pb_calloc_large(P, 1);
    j->global = pb_malloc_large((size_t)P * sizeof *j->global);
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
