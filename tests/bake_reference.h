/* The CPU reference's inputs for a bake pass, built exactly as pb_bake
 * builds them, for the tests that run bake_cpu.c beside the kernels
 * (test_bake) or alone (test_compressed). */
#ifndef PB_TEST_BAKE_REFERENCE_H
#define PB_TEST_BAKE_REFERENCE_H

#include "test_util.h"

/* Host inputs of one pass for the CPU reference, built as pb_bake builds
 * them: probe records (position, id), rotations, the direction set. */
static inline void reference_inputs(const pb_scene *s, const pb_bake_desc *d, uint32_t P, uint32_t rpp, uint32_t pass,
                             float *probes, float *rot, float *dirs)
{
    for (uint32_t p = 0; p < P; ++p) {
        uint32_t id;
        pb_bake_probe_position(s, d, p, probes + 4 * p, &id);
        memcpy(&probes[4 * p + 3], &id, 4);
        float m[9];
        pb_random_rotation(d->seed, id, pass, m);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                rot[12 * p + 4 * r + c] = c < 3 ? m[3 * r + c] : 0.f;
    }
    pb_sf_directions(rpp, dirs);
}

#endif
