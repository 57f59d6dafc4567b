/* pb_key_map: linear probing, half full at most, multiplicative hashing. */
#include "common/key_map.h"

#include <stdlib.h>
#include <string.h>

#define NONE UINT64_MAX

static int alloc_table(pb_key_map *m, uint64_t cap)
{
    m->keys = malloc(cap * sizeof *m->keys);
    m->values = malloc(cap * sizeof *m->values);
    if (!m->keys || !m->values) {
        free(m->keys), free(m->values);
        m->keys = NULL, m->values = NULL;
        return 0;
    }
    for (uint64_t i = 0; i < cap; ++i)
        m->keys[i] = NONE;
    m->mask = cap - 1;
    m->limit = cap / 2;
    m->count = 0;
    return 1;
}

int pb_key_map_init(pb_key_map *m, uint64_t entries)
{
    memset(m, 0, sizeof *m);
    uint64_t cap = 64;
    while (cap < 2 * entries)
        cap <<= 1;
    return alloc_table(m, cap);
}

void pb_key_map_free(pb_key_map *m)
{
    free(m->keys), free(m->values);
    memset(m, 0, sizeof *m);
}

static uint64_t slot(const pb_key_map *m, uint64_t key)
{
    uint64_t h = key * 0x9e3779b97f4a7c15ull;
    uint64_t i = (h ^ (h >> 29)) & m->mask;
    while (m->keys[i] != NONE && m->keys[i] != key)
        i = (i + 1) & m->mask;
    return i;
}

uint32_t pb_key_map_get(const pb_key_map *m, uint64_t key)
{
    uint64_t i = slot(m, key);
    return m->keys[i] == key ? m->values[i] : PB_KEY_MAP_MISSING;
}

int pb_key_map_put(pb_key_map *m, uint64_t key, uint32_t value)
{
    uint64_t i = slot(m, key);
    if (m->keys[i] == key) {
        m->values[i] = value;
        return 1;
    }
    if (m->count + 1 > m->limit) {
        pb_key_map old = *m;
        if (!alloc_table(m, (old.mask + 1) * 2)) {
            *m = old;
            return 0;
        }
        for (uint64_t j = 0; j <= old.mask; ++j)
            if (old.keys[j] != NONE) {
                uint64_t s = slot(m, old.keys[j]);
                m->keys[s] = old.keys[j], m->values[s] = old.values[j];
                m->count++;
            }
        free(old.keys), free(old.values);
        i = slot(m, key);
    }
    m->keys[i] = key, m->values[i] = value;
    m->count++;
    return 1;
}
