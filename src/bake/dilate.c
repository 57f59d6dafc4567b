/* Dilation, the bake's last stage on a grid or sparse bricks: invalid probes (inside
 * geometry) take their valid neighbours' light. A stage of its own because
 * it needs neighbours: the bake runs it on the device (dilate_gpu.c), a
 * sharded bake in pb_volume_merge on the host, with this function, which is
 * also the kernel's CPU reference: the same float arithmetic in the same
 * order (dilate.h), so the two write the same bytes. */
#include "bake/dilate.h"
#include "probebake/bake.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void pb_dilate_reciprocals(float table[PB_DILATE_TABLE])
{
    for (int n1 = 0; n1 < 7; ++n1)
        for (int n2 = 0; n2 < 13; ++n2)
            for (int n3 = 0; n3 < 9; ++n3) {
                double w = n1 + n2 / sqrt(2.0) + n3 / sqrt(3.0);
                table[(n1 * 13 + n2) * 9 + n3] = w > 0 ? (float)(1.0 / w) : 0.f;
            }
}

uint32_t *pb_dilate_sparse_neighbours(const pb_sparse_layout *l, uint32_t P)
{
    uint32_t *table = malloc((size_t)P * PB_DILATE_NEIGHBOURS * sizeof *table);
    uint8_t *finest = calloc(P ? P : 1, 1);
    if (!table || !finest) {
        free(table), free(finest);
        return NULL;
    }
    for (uint64_t i = 0; i < (uint64_t)P * PB_DILATE_NEIGHBOURS; ++i)
        table[i] = PB_DILATE_NONE;
    pb_sparse_probe_levels(l, P, finest, NULL);
    for (uint32_t b = 0; b < l->brick_count; ++b) {
        const uint32_t *probes = l->brick_probes + PB_SPARSE_BRICK_PROBES * (size_t)b;
        for (int i = 0; i < (int)PB_SPARSE_BRICK_PROBES; ++i) {
            uint32_t p = probes[i];
            if (finest[p] != l->bricks[b].level)
                continue;
            int x = i & 3, y = (i >> 2) & 3, z = i >> 4, slot = 0;
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        if (!dx && !dy && !dz)
                            continue;
                        int qx = x + dx, qy = y + dy, qz = z + dz, k = slot++;
                        if (qx < 0 || qy < 0 || qz < 0 || qx > 3 || qy > 3 || qz > 3)
                            continue;
                        table[PB_DILATE_NEIGHBOURS * (size_t)p + k] = probes[qx + 4 * (qy + 4 * qz)];
                    }
        }
    }
    free(finest);
    return table;
}

/* One round (Jacobi: reads `state` and `sh`, writes `next` and `out`) over a
 * grid (neighbours NULL: the 3x3x3 cells around) or a neighbour table. */
static int dilate_round(const pb_volume *v, const uint32_t *neighbours, const float *table, const uint32_t *state,
                        const float *sh, uint32_t *next, float *out)
{
    uint32_t P = v->probe_count, nx = v->counts[0], ny = v->counts[1], nz = v->counts[2];
    int changed = 0;
    for (uint32_t p = 0; p < P; ++p) {
        next[p] = state[p];
        memcpy(out + 27 * (size_t)p, sh + 27 * (size_t)p, 27 * sizeof(float));
        if (state[p] != PB_DILATE_EMPTY)
            continue;
        int x = (int)(p % nx), y = (int)((p / nx) % ny), z = (int)(p / (nx * ny)), slot = 0;
        float sum[27] = {0};
        int n[4] = {0, 0, 0, 0};
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 == 0)
                        continue;
                    uint32_t q;
                    if (neighbours) {
                        q = neighbours[PB_DILATE_NEIGHBOURS * (size_t)p + (uint32_t)slot++];
                        if (q == PB_DILATE_NONE)
                            continue;
                    } else {
                        int qx = x + dx, qy = y + dy, qz = z + dz;
                        if (qx < 0 || qy < 0 || qz < 0 || qx >= (int)nx || qy >= (int)ny || qz >= (int)nz)
                            continue;
                        q = (uint32_t)qx + nx * ((uint32_t)qy + ny * (uint32_t)qz);
                    }
                    if (state[q] == PB_DILATE_EMPTY)
                        continue;
                    float w = d2 == 1 ? PB_DILATE_W1 : d2 == 2 ? PB_DILATE_W2 : PB_DILATE_W3;
                    n[d2]++;
                    for (int c = 0; c < 27; ++c)
                        sum[c] = sum[c] + w * sh[27 * (size_t)q + c];
                }
        if (n[1] + n[2] + n[3] == 0)
            continue;
        float r = table[(n[1] * 13 + n[2]) * 9 + n[3]];
        for (int c = 0; c < 27; ++c)
            out[27 * (size_t)p + c] = sum[c] * r;
        next[p] = PB_DILATE_FILLED;
        changed = 1;
    }
    return changed;
}

/* Invalid probes take the distance-weighted mean of valid (or already
 * filled) neighbours (grid cells, or a sparse volume's neighbour table),
 * round after round, up to `rounds`. */
void pb_volume_dilate(pb_volume *v, uint32_t rounds)
{
    uint32_t P = v->probe_count;
    const pb_sparse_layout *sp = (v->flags & PB_VOLUME_SPARSE) ? v->sparse : NULL;
    if (!(v->flags & PB_VOLUME_GRID) && !sp)
        return; /* placed points have no neighbours */
    uint32_t *state = malloc(2 * (size_t)P * sizeof *state);
    uint32_t *neighbours = sp ? pb_dilate_sparse_neighbours(sp, P) : NULL;
    float *sh = malloc((size_t)P * 27 * sizeof *sh), table[PB_DILATE_TABLE];
    if (!state || !sh || (sp && !neighbours)) {
        free(state), free(sh), free(neighbours);
        return;
    }
    pb_dilate_reciprocals(table);
    for (uint32_t p = 0; p < P; ++p)
        state[p] = (v->probe_flags[p] & PB_PROBE_VALID) ? PB_DILATE_VALID : PB_DILATE_EMPTY;
    /* ping-pong between v's arrays and the scratch ones */
    uint32_t *cur = state, *nxt = state + P;
    float *a = v->sh, *b = sh;
    for (uint32_t round = 0; round < rounds; ++round) {
        int changed = dilate_round(v, neighbours, table, cur, a, nxt, b);
        uint32_t *ts = cur;
        cur = nxt, nxt = ts;
        float *tf = a;
        a = b, b = tf;
        if (!changed)
            break;
    }
    if (a != v->sh)
        memcpy(v->sh, a, (size_t)P * 27 * sizeof *sh);
    for (uint32_t p = 0; p < P; ++p)
        if (cur[p] == PB_DILATE_FILLED)
            v->probe_flags[p] |= PB_PROBE_DILATED;
    free(state), free(sh), free(neighbours);
}
