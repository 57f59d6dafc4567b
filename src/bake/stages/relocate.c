/* Stage 4: relocation (stages/job.h). */
#include "bake/stages/job.h"
#include "common/common.h"

#include <math.h>
#include <string.h>

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

/* The back-face share of the last relocation pass's rays for the `count`
 * probes of `list` (NULL: all) where they stand. */
void pb_bake_record_inside(bake_job *j, const uint32_t *list, uint32_t count)
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
pb_result pb_bake_stage_relocate(bake_job *j, pb_error *err)
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
        r = pb_bake_run_pass(&j->run, PB_RELOCATION_PASS + it, 1, list, count, err);
        if (r != PB_OK)
            break;
        j->relocation_rays += (uint64_t)count * j->run.relocation_rpp;
        pb_bake_record_inside(j, list, count);
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
