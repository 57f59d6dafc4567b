#include "bake/depth_sums.h"

#include "common/common.h"

#include <string.h>

/* bake_depth indexes a block's floats with 32-bit integers */
#define PB_DEPTH_SUM_INDEX_BYTES ((uint64_t)1 << 34)

pb_result pb_depth_sums_plan(const pb_context *ctx, uint32_t probes, uint32_t texels, pb_depth_sums *out,
                             pb_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t limit = PB_DEPTH_SUM_INDEX_BYTES;
    if (ctx->max_allocation && ctx->max_allocation < limit)
        limit = ctx->max_allocation;
    out->probes = probes, out->probe_bytes = (uint64_t)texels * 8;
    if (limit < out->probe_bytes)
        return pb_fail(err, PB_ERROR_TOO_LARGE,
                       "one probe's depth sums (%u octahedral texels) need %.1f KiB, over the %.1f KiB %s allows in "
                       "one allocation (maxMemoryAllocationSize): use a smaller octahedral map",
                       texels, out->probe_bytes / 1024.0, limit / 1024.0, ctx->info.name);
    /* blocks the volume stage can free one by one (depth_sums.h), unless
     * that would take more than half the table */
    uint64_t total = (uint64_t)probes * out->probe_bytes, release = PB_DEPTH_SUM_RELEASE_BYTES;
    uint64_t half_table = (total + PB_DEPTH_SUM_BLOCKS_MAX / 2 - 1) / (PB_DEPTH_SUM_BLOCKS_MAX / 2);
    release = release > half_table ? release : half_table;
    uint64_t per_block = (limit < release ? limit : release) / out->probe_bytes;
    per_block = per_block ? per_block : 1;
    out->block_probes = per_block < probes ? (uint32_t)per_block : (probes ? probes : 1);
    uint64_t blocks = probes ? ((uint64_t)probes + out->block_probes - 1) / out->block_probes : 1;
    if (blocks > PB_DEPTH_SUM_BLOCKS_MAX)
        return pb_fail(err, PB_ERROR_TOO_LARGE,
                       "%u probes' depth sums (%u octahedral texels each) need %.1f MiB, %llu allocations of the "
                       "%.1f MiB %s allows (maxMemoryAllocationSize), over %u: bake in parts (--shard I/N) or use a "
                       "smaller octahedral map",
                       probes, texels, (double)probes * out->probe_bytes / 1048576.0, (unsigned long long)blocks,
                       limit / 1048576.0, ctx->info.name, PB_DEPTH_SUM_BLOCKS_MAX);
    out->block_count = (uint32_t)blocks;
    return PB_OK;
}

pb_result pb_depth_sums_create(pb_context *ctx, pb_depth_sums *s, pb_error *err)
{
    uint64_t address[PB_DEPTH_SUM_BLOCKS_MAX];
    pb_result r = PB_OK;
    for (uint32_t b = 0; r == PB_OK && b < s->block_count; ++b) {
        uint32_t first = b * s->block_probes, n = s->probes - first < s->block_probes ? s->probes - first
                                                                                      : s->block_probes;
        r = pb_buffer_create(ctx, (uint64_t)n * s->probe_bytes, PB_MEMORY_DEVICE, "depth sums", &s->block[b], err);
        address[b] = s->block[b].address;
    }
    if (r == PB_OK)
        r = pb_buffer_create(ctx, (uint64_t)s->block_count * 8, PB_MEMORY_DEVICE, "depth sum blocks", &s->table, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &s->table, 0, address, (uint64_t)s->block_count * 8, err);
    return r;
}

void pb_depth_sums_destroy(pb_context *ctx, pb_depth_sums *s)
{
    for (uint32_t b = 0; b < PB_DEPTH_SUM_BLOCKS_MAX; ++b)
        pb_buffer_destroy(ctx, &s->block[b]);
    pb_buffer_destroy(ctx, &s->table);
}

pb_result pb_depth_sums_drain(pb_context *ctx, pb_depth_sums *s, uint32_t count, uint32_t window,
                              pb_depth_sums_fn fn, void *user, pb_error *err)
{
    if (count == 0)
        return PB_OK;
    if (s->block[0].mapped) {
        for (uint32_t first = 0, b = 0; first < count; first += s->block_probes, ++b) {
            fn(user, s->block[b].mapped, first, count - first < s->block_probes ? count - first : s->block_probes);
            pb_buffer_destroy(ctx, &s->block[b]);
        }
        return PB_OK;
    }
    /* a discrete GPU: the copy of a window, then the host's work on it */
    window = window < 1 ? 1 : (window > count ? count : window);
    window = window < s->block_probes ? window : s->block_probes; /* a run never crosses a block */
    pb_buffer staging;
    pb_result r = pb_buffer_create(ctx, (uint64_t)window * s->probe_bytes, PB_MEMORY_DOWNLOAD, "depth sums read back",
                                   &staging, err);
    for (uint32_t first = 0, n = 0; r == PB_OK && first < count; first += n) {
        uint32_t b = first / s->block_probes, in_block = first - b * s->block_probes;
        n = count - first < window ? count - first : window;
        n = n < s->block_probes - in_block ? n : s->block_probes - in_block;
        if ((r = pb_cmd_begin(ctx, err)) != PB_OK)
            break;
        pb_cmd_copy(ctx, &s->block[b], (uint64_t)in_block * s->probe_bytes, &staging, 0, (uint64_t)n * s->probe_bytes);
        pb_cmd_barrier_to_host(ctx);
        if ((r = pb_cmd_submit_wait(ctx, NULL, err)) != PB_OK)
            break;
        fn(user, staging.mapped, first, n);
        if (in_block + n == s->block_probes || first + n == count) /* the block's last run */
            pb_buffer_destroy(ctx, &s->block[b]);
    }
    pb_buffer_destroy(ctx, &staging);
    return r;
}
