/* Dilation, the bake's last stage on a grid: invalid probes (inside
 * geometry) take their valid neighbours' light. A stage of its own because
 * it needs neighbours: a sharded bake runs it in pb_volume_merge. */
#include "probebake/bake.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Invalid probes take the distance-weighted mean of valid (or already
 * filled) grid neighbours, round after round (Jacobi: each round reads the
 * previous one), up to `rounds`. */
void pb_volume_dilate(pb_volume *v, uint32_t rounds)
{
    uint32_t P = v->probe_count, nx = v->counts[0], ny = v->counts[1], nz = v->counts[2];
    uint32_t *filled = malloc(P * sizeof *filled);
    if (!filled)
        return;
    for (uint32_t p = 0; p < P; ++p)
        filled[p] = (v->probe_flags[p] & PB_PROBE_VALID) != 0;
    for (uint32_t round = 0; round < rounds; ++round) {
        uint32_t *next = malloc(P * sizeof *next);
        if (!next)
            break;
        memcpy(next, filled, P * sizeof *next);
        int changed = 0;
        for (uint32_t p = 0; p < P; ++p) {
            if (filled[p])
                continue;
            int x = (int)(p % nx), y = (int)((p / nx) % ny), z = (int)(p / (nx * ny));
            double sum[27] = {0}, wsum = 0;
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        int qx = x + dx, qy = y + dy, qz = z + dz;
                        if ((dx | dy | dz) == 0 || qx < 0 || qy < 0 || qz < 0 || qx >= (int)nx || qy >= (int)ny ||
                            qz >= (int)nz)
                            continue;
                        uint32_t q = (uint32_t)qx + nx * ((uint32_t)qy + ny * (uint32_t)qz);
                        if (!filled[q])
                            continue;
                        double w = 1.0 / sqrt((double)(dx * dx + dy * dy + dz * dz));
                        for (int c = 0; c < 27; ++c)
                            sum[c] += w * v->sh[27 * (size_t)q + c];
                        wsum += w;
                    }
            if (wsum > 0) {
                for (int c = 0; c < 27; ++c)
                    v->sh[27 * (size_t)p + c] = (float)(sum[c] / wsum);
                v->probe_flags[p] |= PB_PROBE_DILATED;
                next[p] = 1;
                changed = 1;
            }
        }
        memcpy(filled, next, P * sizeof *next);
        free(next);
        if (!changed)
            break;
    }
    free(filled);
}
