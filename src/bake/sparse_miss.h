/* The probe test's measure of a miss (docs/sparse.md, placement steps 3 and
 * 6): one source for refining a cell by a probe baked inside it and for
 * leaving a hanging probe unstitched. */
#ifndef PB_BAKE_SPARSE_MISS_H
#define PB_BAKE_SPARSE_MISS_H

#include <math.h>

/* the directions the irradiance is compared along */
static const float pb_sparse_miss_axes[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

/* Whether `baked` (irradiance luminance along pb_sparse_miss_axes) misses the
 * prediction `pred` by more than `tol`: the worst miss over the mean
 * predicted, against tol and 3 of the baked probe's relative standard errors
 * (none when std_error is not positive: one pass, unknown). */
static inline int pb_sparse_misses(const float pred[6], const float baked[6], float std_error, float tol)
{
    float worst = 0.f, mean = 0.f;
    for (int a = 0; a < 6; ++a) {
        worst = fmaxf(worst, fabsf(baked[a] - pred[a]));
        mean += pred[a] / 6.f;
    }
    float rel = mean > 0.f ? worst / mean : (worst > 0.f ? INFINITY : 0.f);
    float noise = std_error > 0.f ? 3.f * std_error : 0.f;
    return rel > fmaxf(tol, noise);
}

#endif
