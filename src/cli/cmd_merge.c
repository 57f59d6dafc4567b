#define _POSIX_C_SOURCE 200809L
/* probebake merge OUT PART...: the parts of a sharded bake (bake --shard I/N)
 * into the volume one process would have written, byte for byte apart from
 * the timings. A foreign, missing or duplicated part is a one-line error
 * naming it, and nothing is written. */
#include "cli/cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A grid's parts one at a time: every header checked first (nothing is
 * allocated for a foreign, missing or duplicated part), then each part read
 * whole, copied into the volume and freed, in part index order. The whole
 * volume and one part are in memory at once, not every part besides. */
static pb_result merge_streamed(const options *o, const pb_volume *headers, pb_volume *merged, pb_error *err)
{
    uint32_t n = o->part_count;
    const char *const *names = (const char *const *)o->parts;
    pb_result r = pb_volume_merge_begin(headers, names, n, merged, err);
    for (uint32_t k = 0; k < n && r == PB_OK; ++k)
        for (uint32_t i = 0; i < n && r == PB_OK; ++i) {
            if (headers[i].shard.index != k)
                continue;
            pb_volume part;
            r = pb_volume_read(names[i], &part, err);
            if (r == PB_OK)
                r = pb_volume_merge_add(merged, &part, &headers[i], names[i], err);
            pb_volume_free(&part);
            if (r == PB_OK && cli_interrupted(NULL)) {
                r = err->code = PB_ERROR_CANCELLED;
                snprintf(err->message, sizeof err->message, "%s: cancelled; nothing written", o->scene);
            }
        }
    if (r == PB_OK)
        pb_volume_merge_end(merged);
    return r;
}

int cmd_merge(const options *o)
{
    if (!o->scene || o->part_count == 0)
        return cli_usage_error("%s needs OUT.probes and the parts to join (merge OUT PART...)", "merge");
    const char *out_path = o->scene;
    uint32_t n = o->part_count;
    pb_volume *parts = calloc(n, sizeof *parts), merged;
    memset(&merged, 0, sizeof merged);
    pb_error err;
    memset(&err, 0, sizeof err);
    int rc = 1;
    if (!parts) {
        snprintf(err.message, sizeof err.message, "out of host memory for %u parts", n);
        goto out;
    }
    /* the output before any work: not a directory, writable, not a part */
    if (pb_output_check(out_path, (const char *const *)o->parts, n, &err) != PB_OK)
        goto out;
    for (uint32_t i = 0; i < n; ++i) /* headers first: a grid's parts are then read one at a time */
        if (pb_volume_read_header(o->parts[i], &parts[i], &err) != PB_OK)
            goto out;
    cli_defer_signals(); /* from here a signal cancels the merge or the write */
    if (parts[0].flags & PB_VOLUME_SPARSE) { /* bricks are stitched across parts: all of them at once */
        for (uint32_t i = 0; i < n; ++i)
            if (pb_volume_read(o->parts[i], &parts[i], &err) != PB_OK)
                goto out;
        if (pb_volume_merge(parts, (const char *const *)o->parts, n, &merged, &err) != PB_OK)
            goto out;
    } else if (merge_streamed(o, parts, &merged, &err) != PB_OK) {
        goto out;
    }
    if (pb_volume_write_ex(out_path, &merged, cli_interrupted, NULL, &err) != PB_OK)
        goto out;
    uint32_t dilated = 0;
    for (uint32_t p = 0; p < merged.probe_count; ++p)
        dilated += (merged.probe_flags[p] & PB_PROBE_DILATED) != 0;
    FILE *report = strcmp(out_path, "-") ? stdout : stderr;
    /* a sparse bake's parts share the probes on their faces: the whole's count */
    if (merged.sparse)
        fprintf(report, "wrote %s: %u parts, %u probes in sparse bricks, level seams stitched (%u inside geometry "
                "dropped), %u passes at most\n", out_path, n, merged.probe_count, merged.probes_dropped,
                merged.settings.passes);
    else
        fprintf(report, "wrote %s: %u parts, %u probes (%u dilated across parts), %u passes at most\n", out_path, n,
                merged.probe_count, dilated, merged.settings.passes);
    rc = 0;
out:
    for (uint32_t i = 0; parts && i < n; ++i)
        pb_volume_free(&parts[i]);
    free(parts);
    pb_volume_free(&merged);
    return rc ? cli_fail(&err) : 0;
}
