/* Shards: which probes part I of N of a bake holds, and the sample of
 * probes every part traces for the stopping rule's floor, so that parts bake
 * exactly as the whole would (every random number is keyed by seed, probe,
 * pass and ray; nothing else ties probes together before dilation). */
#ifndef PB_BAKE_SHARD_H
#define PB_BAKE_SHARD_H

#include <stdint.h>

#include "probebake/volume.h"

/* Part `index` of `count` of `total` items: a contiguous range, sizes
 * within one of each other (first = floor(total x index / count)). How a
 * sparse bake splits its coarsest bricks, and how grid parts were split
 * before they were dealt. */
void pb_shard_range(uint32_t total, uint32_t index, uint32_t count, uint32_t *first, uint32_t *n);

/* A grid's or points' part `index` of `count`: probes index, index + count,
 * index + 2 count, ... (pb_shard_dealt_count of them, volume.h). Dealt, not
 * cut into slabs, because work per probe follows the scene: probes in rock
 * stop early, converged probes drop out at their own pass, and The Crypt's
 * four slabs took 0.78-1.21x their mean (bench/RESULTS.md, "Shards"). */
static inline uint32_t pb_shard_probe(uint32_t index, uint32_t count, uint32_t k)
{
    return index + k * count;
}

/* --target-error's floor (convergence.h) is taken from these probes' first 4
 * passes: every stride-th probe, at most PB_FLOOR_SAMPLE of them, the same
 * for a whole bake and for each of its parts. */
#define PB_FLOOR_SAMPLE 256u
uint32_t pb_floor_stride(uint32_t total);

/* What a merge adds to the whole per part: the most passes any part ran,
 * the timings, rays and traversals summed, and the part's device name if
 * the whole does not name it yet. */
void pb_shard_account(pb_volume *whole, const pb_volume *part);

#endif
