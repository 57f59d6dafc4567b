#define _POSIX_C_SOURCE 200809L
/* The error summary of a volume, printed by bake and by inspect. */
#include "cli/cli.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Paths and relative standard errors over the volume's probes (median, p95,
 * worst), where known. */
void cli_print_error_summary(FILE *out, const pb_volume *v)
{
    uint64_t paths = 0;
    uint32_t lo = UINT32_MAX, hi = 0, known = 0;
    float *e = malloc(v->probe_count * sizeof *e);
    for (uint32_t i = 0; i < v->probe_count; ++i) {
        paths += v->probe_paths[i];
        lo = v->probe_paths[i] < lo ? v->probe_paths[i] : lo;
        hi = v->probe_paths[i] > hi ? v->probe_paths[i] : hi;
        if (e && v->probe_std_error[i] != PB_STD_ERROR_UNKNOWN)
            e[known++] = v->probe_std_error[i];
    }
    fprintf(out, "paths       %llu in all, %u to %u per probe\n", (unsigned long long)paths, lo, hi);
    if (known) {
        qsort(e, known, sizeof *e, compare_floats);
        /* p95 by nearest rank, the smallest error at least 95 % of the probes
         * reach (of 5 probes, the worst); never below the median */
        uint32_t p95 = (uint32_t)ceil(0.95 * known) - 1;
        fprintf(out, "std error   irradiance, relative: median %.3g %%, p95 %.3g %%, worst %.3g %% (%u probe%s)\n",
               100.0 * e[known / 2], 100.0 * e[p95], 100.0 * e[known - 1], known, cli_plural(known));
    } else {
        fprintf(out, "std error   unknown (%s)\n", v->file_version && v->file_version < 3 ? "file older than version 3" : "one pass per probe");
    }
    free(e);
}
