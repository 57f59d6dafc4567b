/* Alias tables (Walker 1977, Vose 1991): O(1) sampling of a discrete
 * distribution. Slot i keeps itself with probability prob[i], else alias[i].
 * Sampling with one uniform u in [0,1): i = floor(u n), frac = u n - i,
 * result = frac < prob[i] ? i : alias[i] (shaders/include/bake.glsl too). */
#ifndef PB_ALIAS_H
#define PB_ALIAS_H

#include <stdint.h>

/* weights: n >= 1 non-negative values with a positive sum. prob, alias: n
 * entries out. Returns 0 when out of memory or the weights sum to 0. */
int pb_alias_build(const double *weights, uint32_t n, float *prob, uint32_t *alias);

uint32_t pb_alias_sample(const float *prob, const uint32_t *alias, uint32_t n, float u);

#endif
