/* bake_depth's moment sums, kept on the device across a bake's passes: two
 * floats (distance, squared distance) per octahedral texel per probe slot,
 * pass 0 stores and later passes add; the host reads them once, after the
 * last pass.
 *
 * One allocation cannot always hold them: NVIDIA allows 4 GiB, 2M probes of
 * 16x16 texels. So they live in blocks of whole probes, each within the
 * device's maxMemoryAllocationSize and within reach of bake_depth's 32-bit
 * float index (16 GiB), and bake_depth finds a slot's block in a table of
 * the blocks' device addresses: block = slot / block_probes.
 *
 * Blocks are also kept to PB_DEPTH_SUM_RELEASE_BYTES where that takes no
 * more than half the table, so that the volume stage can free each block as
 * soon as it has turned it into depth tiles: on lavapipe and other UMA
 * devices device memory is the host's, and a million probes' sums (2 GiB)
 * held whole beside the volume they fill (1.4 GB) were the bake's peak.
 * A bake of under 16k probes at 16x16 texels has one block. */
#ifndef PB_DEPTH_SUMS_H
#define PB_DEPTH_SUMS_H

#include "gpu/gpu.h"

#define PB_DEPTH_SUM_BLOCKS_MAX 64u
#define PB_DEPTH_SUM_RELEASE_BYTES ((uint64_t)128 << 20)

typedef struct pb_depth_sums {
    pb_buffer block[PB_DEPTH_SUM_BLOCKS_MAX];
    pb_buffer table;        /* uint64 device address per block, read by bake_depth */
    uint64_t probe_bytes;   /* 8 per texel */
    uint32_t probes, block_probes, block_count;
} pb_depth_sums;

/* Sizes the blocks for `probes` slots of `texels` texels on ctx and
 * allocates nothing: PB_ERROR_TOO_LARGE, with the way out, when one probe's
 * sums exceed an allocation or more than PB_DEPTH_SUM_BLOCKS_MAX blocks are
 * needed. */
pb_result pb_depth_sums_plan(const pb_context *ctx, uint32_t probes, uint32_t texels, pb_depth_sums *out,
                             pb_error *err);

/* Allocates the planned blocks (device memory, never read before pass 0
 * writes them) and the address table. */
pb_result pb_depth_sums_create(pb_context *ctx, pb_depth_sums *s, pb_error *err);
void pb_depth_sums_destroy(pb_context *ctx, pb_depth_sums *s);

/* Hands the sums of probes 0..count-1 to fn in runs of consecutive probes
 * that lie in one block, and frees each block once its last run is handed
 * over (the sums are read once, after the last pass): in place where the
 * blocks are mapped (UMA), else at most `window` probes at a time through
 * one download buffer, each run handed over as it lands. `sums` holds 2
 * floats per texel of probes first..first+n-1. pb_depth_sums_destroy frees
 * what is left after an error. */
typedef void (*pb_depth_sums_fn)(void *user, const float *sums, uint32_t first, uint32_t n);
pb_result pb_depth_sums_drain(pb_context *ctx, pb_depth_sums *s, uint32_t count, uint32_t window,
                              pb_depth_sums_fn fn, void *user, pb_error *err);

#endif
