/* Alias tables (Walker 1977, Vose 1991): O(1) sampling of a discrete
 * distribution. Slot i keeps itself with probability prob[i], else alias[i].
 * Sampling with one uniform u in [0,1): i = floor(u n), frac = u n - i,
 * result = frac < prob[i] ? i : alias[i] (shaders/include/bake.glsl too). */
#ifndef PB_ALIAS_H
#define PB_ALIAS_H

#include <stdint.h>

/* weights: n >= 1 non-negative values. prob, alias: n entries out. Returns
 * 1 with the table built, 0 when the weights sum to 0 (nothing to draw;
 * prob and alias untouched), -1 when out of host memory: callers must tell
 * the two apart (once, every caller read a failed allocation as "no weight"
 * and went on: punctual lights or an environment map were silently left
 * out of the bake, and the light cells drew from an unbuilt table). */
int pb_alias_build(const double *weights, uint32_t n, float *prob, uint32_t *alias);

uint32_t pb_alias_sample(const float *prob, const uint32_t *alias, uint32_t n, float u);

#endif
