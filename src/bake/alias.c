#include "bake/alias.h"
#include "common/common.h"

#include <stdlib.h>

int pb_alias_build(const double *w, uint32_t n, float *prob, uint32_t *alias)
{
    double sum = 0;
    for (uint32_t i = 0; i < n; ++i)
        sum += w[i];
    if (!(sum > 0) || n == 0)
        return 0;
    /* a large scene's surface table: millions of entries in fresh pages */
    double *scaled = pb_malloc_large((size_t)n * sizeof *scaled);
    uint32_t *small = pb_malloc_large((size_t)n * sizeof *small), *large = pb_malloc_large((size_t)n * sizeof *large);
    if (!scaled || !small || !large) {
        free(scaled), free(small), free(large);
        return -1;
    }
    uint32_t ns = 0, nl = 0;
    for (uint32_t i = 0; i < n; ++i) {
        scaled[i] = w[i] * n / sum;
        if (scaled[i] < 1.0)
            small[ns++] = i;
        else
            large[nl++] = i;
    }
    while (ns && nl) {
        uint32_t s = small[--ns], l = large[--nl];
        prob[s] = (float)scaled[s];
        alias[s] = l;
        scaled[l] = (scaled[l] + scaled[s]) - 1.0;
        if (scaled[l] < 1.0)
            small[ns++] = l;
        else
            large[nl++] = l;
    }
    while (nl) { /* what is left is (up to rounding) exactly full */
        uint32_t l = large[--nl];
        prob[l] = 1.f;
        alias[l] = l;
    }
    while (ns) {
        uint32_t s = small[--ns];
        prob[s] = 1.f;
        alias[s] = s;
    }
    free(scaled), free(small), free(large);
    return 1;
}

uint32_t pb_alias_sample(const float *prob, const uint32_t *alias, uint32_t n, float u)
{
    float x = u * (float)n;
    uint32_t i = (uint32_t)x;
    if (i >= n)
        i = n - 1;
    float frac = x - (float)i;
    return frac < prob[i] ? i : alias[i];
}
