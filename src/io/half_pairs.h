/* Depth moments to halves in bulk: the volume stage's inner loop, where a
 * million probes' tiles are 650 million conversions. */
#ifndef PB_IO_HALF_PAIRS_H
#define PB_IO_HALF_PAIRS_H

#include <stdint.h>

/* How to convert: one value at a time on any CPU, or four pairs at a time
 * with F16C (x86-64). The caller asks once which this CPU has, and names it
 * in each call. */
typedef enum pb_half_path { PB_HALF_SCALAR, PB_HALF_F16C } pb_half_path;

/* The fastest path this CPU runs (cpuid: AVX, F16C, and an OS that saves
 * their registers). */
pb_half_path pb_half_best_path(void);

/* For i < 2 * pairs: out[i] = pb_half_from_float((float)((double)in[i] /
 * div[i & 1])), bit for bit on either path: a texel's mean distance and mean
 * square, each over its own divisor. PB_HALF_F16C only where
 * pb_half_best_path says so. */
void pb_half_pairs(pb_half_path path, const float *in, uint16_t *out, uint32_t pairs, double div0, double div1);

#endif
