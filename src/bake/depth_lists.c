/* Ray lists of the depth filter's query cells (depth_lists.h). */
#include "bake/depth_lists.h"

#include "common/common.h"
#include "probebake/octahedral.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

uint32_t pb_depth_query_cell(const float d[3], uint32_t res)
{
    float uv[2];
    pb_oct_encode(d, uv);
    uint32_t c[2];
    for (int k = 0; k < 2; ++k) {
        float f = floorf((uv[k] * 0.5f + 0.5f) * (float)res);
        c[k] = f < 0.f ? 0u : (f >= (float)res ? res - 1u : (uint32_t)f);
    }
    return c[1] * res + c[0];
}

void pb_depth_unrotate(const float *rot, const float d[3], float out[3])
{
    for (int k = 0; k < 3; ++k)
        out[k] = (rot[k] * d[0] + rot[4 + k] * d[1]) + rot[8 + k] * d[2];
}

/* The largest angle between a cell's centre direction and any direction the
 * cell holds, from a 9 x 9 lattice over the cell's square including its edges
 * (the farthest points are on the edges; the caller adds a margin). */
static double cell_radius(uint32_t x, uint32_t y, uint32_t res, const float centre[3])
{
    double worst = 0.0;
    for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 8; ++j) {
            float uv[2] = {-1.f + 2.f * ((float)x + (float)i / 8.f) / (float)res,
                           -1.f + 2.f * ((float)y + (float)j / 8.f) / (float)res};
            float d[3];
            pb_oct_decode(uv, d);
            double c = (double)d[0] * centre[0] + (double)d[1] * centre[1] + (double)d[2] * centre[2];
            worst = fmax(worst, acos(fmin(1.0, fmax(-1.0, c))));
        }
    return worst;
}

pb_result pb_depth_lists_build(const float *dirs4, uint32_t n, float cutoff, uint32_t res, pb_depth_lists *out,
                               pb_error *err)
{
    memset(out, 0, sizeof *out);
    const uint32_t cells = res * res;
    double lobe = acos(fmin(1.0, fmax(-1.0, (double)cutoff)));
    /* first pass: lengths; second: indices (the same test both times) */
    double *reach = malloc(cells * sizeof *reach);
    float *centres = malloc((size_t)cells * 3 * sizeof(float));
    uint32_t *starts = malloc(((size_t)cells + 1) * sizeof *starts);
    if (!reach || !centres || !starts) {
        free(reach), free(centres), free(starts);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the depth filter's ray lists");
    }
    uint64_t total = 0;
    for (uint32_t q = 0; q < cells; ++q) {
        float *c = centres + 3 * q;
        pb_oct_texel_direction(q % res, q / res, res, c);
        /* 5 % and 1 mrad over the sampled radius: lattice spacing and float
         * rounding of the kernel's encode (a direction on a cell edge may be
         * put in the neighbour, whose radius covers it as well) */
        double a = lobe + cell_radius(q % res, q / res, res, c) * 1.05 + 1e-3;
        reach[q] = a >= 3.141592653589793 ? -2.0 : cos(a);
        starts[q] = (uint32_t)total;
        for (uint32_t r = 0; r < n; ++r) {
            const float *s = dirs4 + 4 * (size_t)r;
            total += (double)c[0] * s[0] + (double)c[1] * s[1] + (double)c[2] * s[2] >= reach[q];
        }
    }
    starts[cells] = (uint32_t)total;
    uint64_t words = 2ull + cells + total;
    if (words > UINT32_MAX) {
        free(reach), free(centres), free(starts);
        return pb_fail(err, PB_ERROR_TOO_LARGE, "the depth filter's ray lists for %u rays need %llu words", n,
                       (unsigned long long)words);
    }
    out->words = malloc(words * sizeof(uint32_t));
    if (!out->words) {
        free(reach), free(centres), free(starts);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the depth filter's ray lists");
    }
    out->word_count = (size_t)words;
    out->res = res;
    out->words[0] = res;
    uint32_t *index = out->words + 2 + cells;
    for (uint32_t q = 0; q < cells; ++q) {
        const float *c = centres + 3 * q;
        out->words[1 + q] = starts[q];
        uint32_t k = starts[q];
        for (uint32_t r = 0; r < n; ++r) {
            const float *s = dirs4 + 4 * (size_t)r;
            if ((double)c[0] * s[0] + (double)c[1] * s[1] + (double)c[2] * s[2] >= reach[q])
                index[k++] = r;
        }
        uint32_t len = starts[q + 1] - starts[q];
        out->longest = len > out->longest ? len : out->longest;
    }
    out->words[1 + cells] = starts[cells];
    out->mean = cells ? (double)total / cells : 0.0;
    free(reach), free(centres), free(starts);
    return PB_OK;
}

void pb_depth_lists_free(pb_depth_lists *l)
{
    free(l->words);
    memset(l, 0, sizeof *l);
}
