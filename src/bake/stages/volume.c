/* Stage 7: SH, depth and validity into the volume (stages/job.h). */
#include "bake/stages/job.h"
#include "common/common.h"
#include "io/half_pairs.h"
#include "probebake/octahedral.h"
#include "probebake/sh.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Stage 7's per-probe work (SH, flags, accounting, depth tiles with their
 * borders) over a range of probes: each probe writes only its own slots, so
 * ranges run on all host cores (on an H100 this stage was a quarter of a
 * 16k-probe bake's wall time, single-threaded). */
typedef struct volume_fill {
    const bake_job *j;
    pb_volume *out;
    const float *sums;             /* the device's depth sums of probes first.. (a run of them) */
    uint32_t first;
    pb_half_path half_path;        /* the CPU's fastest conversion to halves */
} volume_fill;

/* A probe's depth tile from its texels' summed distance and square (m, n x
 * n pairs): their means over the passes in depth units, as halves, with a
 * one-texel border that repeats the texel across the octahedron's edge
 * (octahedral.h). Dividing by passes x unit (an exact power-of-two multiple)
 * rounds as dividing by each in turn did. */
static void depth_tile(pb_half_path path, const float *m, uint16_t *tile, uint32_t n, uint32_t passes, double unit)
{
    double div_mean = (double)passes * unit, div_square = div_mean * unit;
    uint32_t w = n + 2;
    for (uint32_t y = 0; y < n; ++y)
        pb_half_pairs(path, m + 2 * (size_t)y * n, tile + 2 * ((y + 1) * w + 1), n, div_mean, div_square);
    for (uint32_t by = 0; by < w; ++by)
        for (uint32_t bx = 0; bx < w; bx += (by == 0 || by == w - 1) ? 1 : w - 1) { /* the border only */
            uint32_t x, y;
            pb_oct_border_source(bx, by, n, &x, &y);
            memcpy(tile + 2 * (by * w + bx), tile + 2 * ((y + 1) * w + x + 1), 2 * sizeof *tile);
        }
}

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
        depth_tile(vf->half_path, vf->sums + 2 * (size_t)texels * (p - vf->first), tile, n, done_p, out->depth_unit);
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
pb_result pb_bake_stage_volume(bake_job *j, pb_volume *out, pb_error *err)
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
    out->settings.scene_hash =
        j->gs->hashed_scene == j->scene ? j->gs->scene_hash : pb_scene_hash_wait(&j->scene_hash);
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
     * sums: its first touch would cost what summing them on the host did),
     * and each block freed once filled (on UMA, the sums give back what the
     * tiles take) */
    volume_fill vf = {j, out, NULL, 0, pb_half_best_path()};
    return pb_depth_sums_drain(j->ctx, &j->B.sums, own, j->chunk, volume_fill_run, &vf, err);
}
