/* Shard ranges and the floor sample (shard.h). */
#include "bake/shard.h"
#include "bake/timings.h"

#include <stdio.h>
#include <string.h>

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

void pb_shard_account(pb_volume *whole, const pb_volume *part)
{
    if (part->settings.passes > whole->settings.passes)
        whole->settings.passes = part->settings.passes;
    pb_volume_timings_add(&whole->timings, &part->timings);
    whole->rays_traced += part->rays_traced, whole->traversals += part->traversals;
    whole->relocation_rays += part->relocation_rays;
    if (strcmp(part->device, whole->device) && !strstr(whole->device, part->device)) {
        size_t len = strlen(whole->device);
        snprintf(whole->device + len, sizeof whole->device - len, " + %s", part->device);
    }
}
