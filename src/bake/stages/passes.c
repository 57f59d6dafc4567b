/* Stage 6: the trace passes (stages/job.h). */
#include "bake/stages/job.h"
#include "common/common.h"

/* Stage 6, the trace passes over the probes not classified inside. With a
 * target error, probes whose irradiance estimate has converged (after at
 * least 4 passes, along every axis the standard error of the mean is below
 * target x the mean, or x the floor where that is larger: convergence.h)
 * drop out and the rest keep going. The floor is taken once, after pass 4,
 * over the floor sample's traced probes, whose probes of other parts are
 * then done. */
pb_result pb_bake_stage_passes(bake_job *j, pb_error *err)
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
        r = pb_bake_run_pass(&j->run, pass, 0, listed ? j->active : NULL, active_count, err);
        if (r != PB_OK || !(d->target_error > 0.f) || pass + 1 < PB_TARGET_ERROR_MIN_PASSES)
            continue;
        uint32_t keep = 0;
        if (pass + 1 == PB_TARGET_ERROR_MIN_PASSES) {
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
