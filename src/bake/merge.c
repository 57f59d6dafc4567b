/* probebake merge: the parts of a sharded bake back into the one volume a
 * single process would have baked. Every check runs before anything is
 * allocated, and each names the file at fault. */
#include "bake/shard.h"
#include "bake/sparse_merge.h"
#include "common/common.h"
#include "probebake/bake.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* What must be equal in every part of one bake: "" if a and b agree, else
 * the first field that differs. */
static const char *differs(const pb_volume *a, const pb_volume *b)
{
    const pb_volume_settings *x = &a->settings, *y = &b->settings;
    if (x->scene_hash != y->scene_hash)
        return "scene hash (another scene, or another version of it)";
    if (a->flags != b->flags)
        return "kind (grid or points, direct light, irradiance)";
    if (a->shard.count != b->shard.count || a->shard.total != b->shard.total)
        return "number of parts or probes";
    if ((a->shard.step > 1) != (b->shard.step > 1))
        return "split (dealt probes, or a contiguous range from a probebake before 2026-11-27)";
    /* a sparse part's counts are its own probes' (P, 1, 1) */
    if ((!(a->flags & PB_VOLUME_SPARSE) && memcmp(a->counts, b->counts, sizeof a->counts)) ||
        memcmp(a->origin, b->origin, sizeof a->origin) || memcmp(a->spacing, b->spacing, sizeof a->spacing))
        return "grid (counts, origin or spacing)";
    if (x->seed != y->seed)
        return "seed";
    if (a->octmap_res != b->octmap_res || a->depth_unit != b->depth_unit || x->max_distance != y->max_distance)
        return "depth map settings";
    if (x->rays_per_probe != y->rays_per_probe || x->bounces != y->bounces || x->indirect_mode != y->indirect_mode ||
        x->target_error != y->target_error || x->sh_window != y->sh_window ||
        x->sh_window_width != y->sh_window_width || x->indirect_clamp != y->indirect_clamp ||
        x->techniques != y->techniques)
        return "bake settings (rays, bounces, target error, SH window, clamp or estimators)";
    /* under a target error each part records the most passes its probes
     * took, and the whole the most of all; without one every traced probe
     * takes --passes (a part whose probes all lie inside geometry traced
     * none and records 0) */
    if (x->target_error == 0.f && x->passes && y->passes && x->passes != y->passes)
        return "pass count (--passes)";
    if (x->relocation_rays != y->relocation_rays)
        return "relocation ray count (--relocation-rays)";
    if (x->refine_error != y->refine_error)
        return "sparse refine error";
    if (x->refine_test != y->refine_test || x->test_pass_scale != y->test_pass_scale ||
        x->seam_rounds != y->seam_rounds || x->seam_error != y->seam_error)
        return "sparse refinement test (--refine-test, its passes, --refine-seams or --seam-error)";
    return "";
}

/* The checks every merge makes before it allocates (header fields only),
 * and the parts in index order (by_index, name_of: N entries each, the
 * caller frees them). */
static pb_result check_parts(const pb_volume *parts, const char *const *names, uint32_t count,
                             const pb_volume ***by_index_out, const char ***name_of_out, pb_error *err)
{
    *by_index_out = NULL, *name_of_out = NULL;
    if (count == 0)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "no parts to merge");
    for (uint32_t i = 0; i < count; ++i)
        if (!(parts[i].flags & PB_VOLUME_SHARD))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: not a part of a sharded bake (bake --shard I/N)",
                           names[i]);
    for (uint32_t i = 1; i < count; ++i) {
        const char *d = differs(&parts[0], &parts[i]);
        if (d[0])
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: not a part of the same bake as %s: its %s differs",
                           names[i], names[0], d);
    }
    uint32_t N = parts[0].shard.count, total = parts[0].shard.total;
    /* each part once: by index, then its probes must be the ones its index gives */
    const pb_volume **by_index = calloc(N, sizeof *by_index);
    const char **name_of = calloc(N, sizeof *name_of);
    if (!by_index || !name_of) {
        free(by_index), free(name_of);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory merging %u parts", N);
    }
    pb_result r = PB_OK;
    for (uint32_t i = 0; i < count && r == PB_OK; ++i) {
        const pb_volume_shard *s = &parts[i].shard;
        uint32_t first, n;
        pb_shard_range(total, s->index, N, &first, &n);
        if (by_index[s->index])
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: part %u/%u is given twice (also %s)", names[i], s->index,
                        N, name_of[s->index]);
        else if ((parts[i].flags & PB_VOLUME_SPARSE) && s->first != first)
            /* a sparse part: a range of coarsest bricks (`total` of them), checked brick by brick in sparse_merge.c */
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: part %u/%u starts at coarsest brick %u, not %u as a part "
                        "of %u must", names[i], s->index, N, s->first, first, total);
        else if (!(parts[i].flags & PB_VOLUME_SPARSE) && s->step > 1 &&
                 (s->step != N || s->first != s->index ||
                  parts[i].probe_count != pb_shard_dealt_count(total, s->index, N)))
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                        "%s: part %u/%u holds %u probes from %u every %u, not %u from %u every %u as a part of %u "
                        "probes must", names[i], s->index, N, parts[i].probe_count, s->first, s->step,
                        pb_shard_dealt_count(total, s->index, N), s->index, N, total);
        else if (!(parts[i].flags & PB_VOLUME_SPARSE) && s->step <= 1 && (s->first != first || parts[i].probe_count != n))
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                        "%s: part %u/%u holds probes %u..%u, not %u..%u as a part of %u probes must", names[i],
                        s->index, N, s->first, s->first + parts[i].probe_count - 1, first, first + n - 1, total);
        by_index[s->index] = &parts[i];
        name_of[s->index] = names[i];
    }
    for (uint32_t k = 0; k < N && r == PB_OK; ++k)
        if (!by_index[k])
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "part %u/%u is missing (%u of %u parts given, first %s)", k, N,
                        count, N, names[0]);
    if (r != PB_OK) {
        free(by_index), free(name_of);
        return r;
    }
    *by_index_out = by_index, *name_of_out = name_of;
    return PB_OK;
}

pb_result pb_volume_merge_check(const pb_volume *headers, const char *const *names, uint32_t count, pb_error *err)
{
    pb_error_clear(err);
    const pb_volume **by_index;
    const char **name_of;
    pb_result r = check_parts(headers, names, count, &by_index, &name_of, err);
    if (r == PB_OK)
        free(by_index), free(name_of);
    return r;
}

pb_result pb_volume_merge_begin(const pb_volume *headers, const char *const *names, uint32_t count, pb_volume *out,
                                pb_error *err)
{
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    if (count && (headers[0].flags & PB_VOLUME_SPARSE))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: a sparse bake's parts are merged together "
                       "(pb_volume_merge): their bricks are stitched across parts", names[0]);
    const pb_volume **by_index;
    const char **name_of;
    pb_result r = check_parts(headers, names, count, &by_index, &name_of, err);
    if (r != PB_OK)
        return r;
    /* the whole volume: the header of part 0; its probes come with each part */
    const pb_volume *p0 = by_index[0];
    out->flags = p0->flags & ~PB_VOLUME_SHARD;
    out->probe_count = p0->shard.total;
    memcpy(out->counts, p0->counts, sizeof out->counts);
    out->octmap_res = p0->octmap_res;
    memcpy(out->origin, p0->origin, sizeof out->origin);
    memcpy(out->spacing, p0->spacing, sizeof out->spacing);
    out->settings = p0->settings;
    out->depth_unit = p0->depth_unit;
    snprintf(out->device, sizeof out->device, "%s", p0->device);
    free(by_index), free(name_of);
    return pb_volume_alloc(out, err);
}

pb_result pb_volume_merge_sparse_begin(const pb_volume *layouts, const char *const *names, uint32_t count,
                                       pb_volume *out, pb_sparse_merging **m, pb_error *err)
{
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    *m = NULL;
    const pb_volume **by_index;
    const char **name_of;
    pb_result r = check_parts(layouts, names, count, &by_index, &name_of, err);
    for (uint32_t i = 0; i < count && r == PB_OK; ++i) /* one kind of part, each with its layout */
        if (!(layouts[i].flags & PB_VOLUME_SPARSE) || !layouts[i].sparse)
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: not a part of a sparse bake (or its layout unread)",
                        names[i]);
    if (r == PB_OK)
        r = pb_sparse_merge_begin(by_index, name_of, layouts[0].shard.count, out, m, err);
    free(by_index), free(name_of);
    return r;
}

pb_result pb_volume_merge_add(pb_volume *out, const pb_volume *part, const pb_volume *header, const char *name,
                              pb_error *err)
{
    const char *d = differs(header, part);
    if (d[0] || part->probe_count != header->probe_count || memcmp(&part->shard, &header->shard, sizeof part->shard))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: changed while it was merged (its %s)", name,
                       d[0] ? d : "part or probe count");
    uint64_t halves = pb_volume_tile_halves(out->octmap_res);
    size_t step = part->shard.step > 1 ? part->shard.step : 1; /* dealt, or contiguous (older parts) */
    for (size_t i = 0; i < part->probe_count; ++i) {
        size_t g = part->shard.first + i * step;
        memcpy(out->base + 3 * g, part->base + 3 * i, 12);
        memcpy(out->offset + 3 * g, part->offset + 3 * i, 12);
        out->probe_flags[g] = part->probe_flags[i];
        memcpy(out->sh + 27 * g, part->sh + 27 * i, 108);
        memcpy(out->depth + halves * g, part->depth + halves * i, 2 * halves);
        out->probe_paths[g] = part->probe_paths[i];
        out->probe_std_error[g] = part->probe_std_error[i];
    }
    pb_shard_account(out, part);
    return PB_OK;
}

void pb_volume_merge_end(pb_volume *out)
{
    /* the stages that need neighbours across parts */
    if (out->flags & PB_VOLUME_GRID)
        pb_volume_dilate(out, PB_DILATION_ROUNDS);
}

pb_result pb_volume_merge(const pb_volume *parts, const char *const *names, uint32_t count, pb_volume *out,
                          pb_error *err)
{
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    if (count && (parts[0].flags & PB_VOLUME_SPARSE)) {
        const pb_volume **by_index;
        const char **name_of;
        pb_result r = check_parts(parts, names, count, &by_index, &name_of, err);
        if (r == PB_OK)
            r = pb_sparse_merge(by_index, name_of, parts[0].shard.count, out, err);
        free(by_index), free(name_of);
        return r;
    }
    pb_result r = pb_volume_merge_begin(parts, names, count, out, err);
    /* in index order, as the parts' devices are named and their timings summed */
    for (uint32_t k = 0; k < count && r == PB_OK; ++k)
        for (uint32_t i = 0; i < count && r == PB_OK; ++i)
            if (parts[i].shard.index == k)
                r = pb_volume_merge_add(out, &parts[i], &parts[i], names[i], err);
    if (r != PB_OK) {
        pb_volume_free(out);
        return r;
    }
    pb_volume_merge_end(out);
    return PB_OK;
}
