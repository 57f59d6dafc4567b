/* Writes a small, fully specified volume for the CLI tests of `inspect`:
 * a 3 x 2 x 1 grid at a far origin, probe 1 relocated, probe 4 dilated, SH
 * coefficient c of probe i equal to i + c / 100, depth half i equal to
 * (i mod 1000) / 8. Usage: make_test_volume OUT */
#include "probebake/probebake.h"

#include <stdio.h>
#include <string.h>

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: make_test_volume OUT\n");
        return 2;
    }
    pb_volume v;
    memset(&v, 0, sizeof v);
    v.flags = PB_VOLUME_GRID | PB_VOLUME_IRRADIANCE | PB_VOLUME_DIRECT;
    v.probe_count = 6;
    v.counts[0] = 3, v.counts[1] = 2, v.counts[2] = 1;
    v.octmap_res = 8;
    v.origin[0] = 1e6, v.origin[1] = 2.0, v.origin[2] = -5.0;
    v.spacing[0] = v.spacing[1] = v.spacing[2] = 1.0;
    v.settings.seed = 7;
    v.settings.rays_per_probe = 256;
    v.settings.passes = 4;
    v.settings.bounces = 2;
    v.settings.max_distance = 30.f;
    snprintf(v.device, sizeof v.device, "fixture");
    pb_error err;
    if (pb_volume_alloc(&v, &err) != PB_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    for (uint32_t i = 0; i < 6; ++i) {
        v.base[3 * i] = (float)(i % 3);
        v.base[3 * i + 1] = (float)(i / 3);
        v.probe_flags[i] = PB_PROBE_VALID;
        for (int c = 0; c < 27; ++c)
            v.sh[27 * i + c] = (float)i + (float)c / 100.f;
        v.probe_paths[i] = 1024u * (i + 1u);
        v.probe_std_error[i] = i == 5 ? PB_STD_ERROR_UNKNOWN : 0.25f / (float)(1u << i);
    }
    /* depth texels distinct and finite (readers and the texture export are
     * checked texel by texel) */
    uint64_t halves = 6 * pb_volume_tile_halves(v.octmap_res);
    for (uint64_t i = 0; i < halves; ++i)
        v.depth[i] = pb_half_from_float((float)(i % 1000) * 0.125f);
    v.offset[3 * 1 + 1] = 0.25f;
    v.probe_flags[1] |= PB_PROBE_RELOCATED;
    v.probe_flags[4] = PB_PROBE_DILATED;
    int rc = pb_volume_write(argv[1], &v, &err) == PB_OK ? 0 : 1;
    if (rc)
        fprintf(stderr, "%s\n", err.message);
    pb_volume_free(&v);
    return rc;
}
