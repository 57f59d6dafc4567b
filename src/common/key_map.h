/* An open-addressing hash map from 64-bit keys to 32-bit values, sized once
 * for a known number of entries (sparse layouts key bricks and lattice
 * points with it). UINT64_MAX is not a valid key. */
#ifndef PB_KEY_MAP_H
#define PB_KEY_MAP_H

#include <stdint.h>

typedef struct pb_key_map {
    uint64_t *keys;
    uint32_t *values;
    uint64_t mask;
    uint64_t count, limit; /* entries, and the most it holds before growing */
} pb_key_map;

#define PB_KEY_MAP_MISSING UINT32_MAX

/* Room for about `entries` (it grows past that). 0: out of memory. */
int pb_key_map_init(pb_key_map *m, uint64_t entries);
void pb_key_map_free(pb_key_map *m);
/* The value of key, or PB_KEY_MAP_MISSING. */
uint32_t pb_key_map_get(const pb_key_map *m, uint64_t key);
/* Sets key's value. 0: out of memory (the map is unchanged). */
int pb_key_map_put(pb_key_map *m, uint64_t key, uint32_t value);

#endif
