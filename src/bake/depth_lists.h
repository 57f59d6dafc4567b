/* Which probe rays can reach an octahedral depth texel's filter lobe.
 *
 * The depth filter weighs every ray of a probe by max(0, cos)^power and skips
 * those below a cutoff (cos <= pb_depth_lobe_cutoff): about 8 % of the rays
 * at the default power 50, yet the kernel used to test all of them for every
 * texel. A probe's rays are one fixed set (the unrotated spherical-Fibonacci
 * directions) turned by the probe's rotation, so the test can run in the
 * unrotated frame instead: turn the texel's direction back, find the cell of a
 * fixed Q x Q octahedral query map that holds it, and visit only that cell's
 * list of rays, which holds every ray within the cutoff angle of any direction
 * in the cell (plus a margin). Lists are in ascending ray order, so the sums
 * see the same rays in the same order as the loop over all of them: the result
 * is the same to the bit (test_sh checks this over random rotations).
 *
 * One buffer, as the kernel reads it (uint32 words):
 *   [0]                 Q
 *   [1 .. Q*Q+1]        first index of each cell's list, then the end
 *   [Q*Q+2 ..]          ray indices, cell after cell */
#ifndef PB_DEPTH_LISTS_H
#define PB_DEPTH_LISTS_H

#include "probebake/base.h"

#include <stddef.h>
#include <stdint.h>

#define PB_DEPTH_QUERY_RES 32u

typedef struct pb_depth_lists {
    uint32_t *words;  /* the buffer above */
    size_t word_count;
    uint32_t res;     /* Q */
    uint32_t longest; /* the longest list (rays) */
    double mean;      /* mean list length (rays) */
} pb_depth_lists;

/* Lists for `n` unrotated directions (4 floats each, as pb_sf_directions)
 * and a cutoff cosine. PB_ERROR_OUT_OF_HOST_MEMORY, or PB_ERROR_TOO_LARGE
 * where the buffer would pass 2^32 words. */
pb_result pb_depth_lists_build(const float *dirs4, uint32_t n, float cutoff, uint32_t res, pb_depth_lists *out,
                               pb_error *err);
void pb_depth_lists_free(pb_depth_lists *l);

/* The query cell of an (unrotated-frame) direction: what bake_depth.comp
 * computes, operation for operation. */
uint32_t pb_depth_query_cell(const float d[3], uint32_t res);

/* A texel direction turned into the unrotated frame of a probe whose rotation
 * has rows rot[0..2] (stride 4 floats, as the bake uploads them): R^T d. */
void pb_depth_unrotate(const float *rot_rows4, const float d[3], float out[3]);

#endif
