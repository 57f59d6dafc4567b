/* Stage 5: classification (stages/job.h). */
#include "bake/stages/job.h"
#include "common/common.h"

#include <string.h>

/* Stage 5, classify: a probe whose relocation rays, where it ends up, hit
 * back faces more often than d->inside_fraction is inside geometry. Its
 * passes would only confirm it invalid and be thrown away by dilation, so
 * it is flagged PB_PROBE_INSIDE and not traced (DDGI's probe
 * classification). The probes the last relocation iteration moved are
 * tested once more first, with their own pass number, without moving. */
pb_result pb_bake_stage_classify(bake_job *j, pb_error *err)
{
    const pb_bake_desc *d = &j->d;
    pb_result r = PB_OK;
    if (!j->relocated_with || !(d->inside_fraction < 1.f))
        return PB_OK;
    if (j->moved_last) { /* j->active holds them (stage 4) */
        memset(j->backfaces, 0, j->P * sizeof(double));
        r = pb_bake_run_pass(&j->run, PB_RELOCATION_PASS + 3, 1, j->active, j->moved_last, err);
        if (r != PB_OK)
            return r;
        j->relocation_rays += (uint64_t)j->moved_last * j->run.relocation_rpp;
        pb_bake_record_inside(j, j->active, j->moved_last);
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
