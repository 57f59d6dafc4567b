/* Shard ranges and the floor sample (shard.h). */
#include "bake/shard.h"

void pb_shard_range(uint32_t total, uint32_t index, uint32_t count, uint32_t *first, uint32_t *n)
{
    uint64_t a = (uint64_t)total * index / count, b = (uint64_t)total * (index + 1) / count;
    *first = (uint32_t)a;
    *n = (uint32_t)(b - a);
}

uint32_t pb_floor_stride(uint32_t total)
{
    return total <= PB_FLOOR_SAMPLE ? 1u : (total + PB_FLOOR_SAMPLE - 1) / PB_FLOOR_SAMPLE;
}
