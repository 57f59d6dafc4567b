/* Quality presets (bake --quality): the path budget, the stopping error and
 * the estimators (probe NEE and light cells always; path guiding too where
 * many paths repay its training: it wins 3.9x in a room lit through a
 * doorway and costs at most 13 % elsewhere) a user ships with, measured by bench/paths_to_error on the
 * hard scenes (bench/RESULTS.md, "Paths to error"). */
#include "probebake/bake.h"

#include <string.h>

static const pb_bake_quality presets[] = {
    /* a quick look: 256 paths per probe, every probe alike */
    {"preview", 128, 2, 0.f, 1, 0, 1},
    /* what a user ships: each probe until the standard error of its
     * irradiance along every axis is 2 % (at most 256 passes, 65,536
     * paths): p95 per-axis error 4.5 % on the doorway scene */
    {"production", 256, 256, 0.02f, 1, PB_GUIDE_DEFAULT_PATHS, 1},
    /* a converged bake to compare against: 0.25 %, at most 2^20 paths */
    {"reference", 256, 4096, 0.0025f, 1, PB_GUIDE_DEFAULT_PATHS, 1},
};

const pb_bake_quality *pb_bake_quality_find(const char *name)
{
    for (size_t i = 0; i < sizeof presets / sizeof presets[0]; ++i)
        if (name && !strcmp(presets[i].name, name))
            return &presets[i];
    return NULL;
}
