#define _POSIX_C_SOURCE 200809L
/* probebake merge OUT PART...: the parts of a sharded bake (bake --shard I/N)
 * into the volume one process would have written, byte for byte apart from
 * the timings. A foreign, missing or duplicated part is a one-line error
 * naming it, and nothing is written. */
#include "cli/cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Adds one part, read whole, to the merge; `i` is its place on the command line. */
typedef pb_result (*add_part_fn)(void *merging, pb_volume *merged, const pb_volume *part, const pb_volume *header,
                                 const char *name, pb_error *err);

/* Each part read whole, handed to `add` and freed, in part index order
 * (headers[i] says which part file i is); a signal stops between parts. */
static pb_result add_parts_in_order(const options *o, const pb_volume *headers, add_part_fn add, void *merging,
                                    pb_volume *merged, pb_error *err)
{
    uint32_t n = o->part_count;
    pb_result r = PB_OK;
    for (uint32_t k = 0; k < n && r == PB_OK; ++k)
        for (uint32_t i = 0; i < n && r == PB_OK; ++i) {
            if (headers[i].shard.index != k)
                continue;
            pb_volume part;
            r = pb_volume_read(o->parts[i], &part, err);
            if (r == PB_OK)
                r = add(merging, merged, &part, &headers[i], o->parts[i], err);
            pb_volume_free(&part);
            if (r == PB_OK && cli_interrupted(NULL)) {
                r = err->code = PB_ERROR_CANCELLED;
                snprintf(err->message, sizeof err->message, "%s: cancelled; nothing written", o->scene);
            }
        }
    return r;
}

static pb_result add_grid_part(void *merging, pb_volume *merged, const pb_volume *part, const pb_volume *header,
                               const char *name, pb_error *err)
{
    (void)merging;
    return pb_volume_merge_add(merged, part, header, name, err);
}

static pb_result add_sparse_part(void *merging, pb_volume *merged, const pb_volume *part, const pb_volume *header,
                                 const char *name, pb_error *err)
{
    (void)header, (void)name; /* the merging state holds what begin saw of each part, and its name */
    return pb_sparse_merge_add(merging, merged, part, err);
}

/* A grid's parts one at a time: every header checked first (nothing is
 * allocated for a foreign, missing or duplicated part), then each part read
 * whole, copied into the volume and freed, in part index order. The whole
 * volume and one part are in memory at once, not every part besides. */
static pb_result merge_grid(const options *o, const pb_volume *headers, pb_volume *merged, pb_error *err)
{
    pb_result r = pb_volume_merge_begin(headers, (const char *const *)o->parts, o->part_count, merged, err);
    if (r == PB_OK)
        r = add_parts_in_order(o, headers, add_grid_part, NULL, merged, err);
    if (r == PB_OK)
        pb_volume_merge_end(merged);
    return r;
}

/* A sparse bake's parts, also one at a time: their headers checked first
 * (a foreign or missing part is refused before any part is read whole),
 * then each read whole once for its layout (its probes freed at once), then,
 * once the whole layout is built, again for its probes, in part index order;
 * bricks are stitched across parts at the end, in the whole volume. Each
 * part is read twice, and the whole volume and one part are in memory at
 * once, not every part. */
static pb_result merge_sparse(const options *o, pb_volume *layouts, pb_volume *merged, pb_error *err)
{
    uint32_t n = o->part_count;
    pb_result r = pb_volume_merge_check(layouts, (const char *const *)o->parts, n, err);
    for (uint32_t i = 0; i < n && r == PB_OK; ++i) {
        pb_volume_free(&layouts[i]);
        r = pb_volume_read(o->parts[i], &layouts[i], err);
        pb_volume_free_probes(&layouts[i]);
    }
    pb_sparse_merging *m = NULL;
    if (r == PB_OK)
        r = pb_volume_merge_sparse_begin(layouts, (const char *const *)o->parts, n, merged, &m, err);
    if (r == PB_OK)
        r = add_parts_in_order(o, layouts, add_sparse_part, m, merged, err);
    if (r == PB_OK)
        return pb_sparse_merge_end(m, merged, err);
    pb_sparse_merging_free(m);
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
    for (uint32_t i = 0; i < n; ++i) /* headers first: the parts are then read one at a time */
        if (pb_volume_read_header(o->parts[i], &parts[i], &err) != PB_OK)
            goto out;
    cli_defer_signals(); /* from here a signal cancels the merge or the write */
    if ((parts[0].flags & PB_VOLUME_SPARSE ? merge_sparse(o, parts, &merged, &err)
                                           : merge_grid(o, parts, &merged, &err)) != PB_OK)
        goto out;
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
