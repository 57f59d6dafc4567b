/* Path guiding (pb_bake_desc.guide_paths): where the light comes from, per
 * region and surface orientation, learned before the bake from training
 * paths that start on the scene's surfaces, and used to draw bounce
 * directions from a mixture of that distribution and the cosine lobe
 * (unbiased: the mixture's density weighs every sample). The training set
 * depends only on the scene and the seed, not on which probes are baked, so
 * any subset of probes still bakes to the same bytes as the whole.
 *
 * The cache: a grid of cubic cells sized so that a cell's surface gets
 * about 256 training paths (at most 64 cells per axis); per cell 6 entries,
 * one per dominant normal axis (+-x, +-y, +-z); per learned entry (at least
 * 32 paths) 64 bins of directions in the equal-area octahedral square
 * (8 x 8), each with the mean radiance the training paths brought from
 * there, times the cosine to the entry's axis. shaders/include/guide.glsl reads the same table. */
#ifndef PB_BAKE_GUIDE_H
#define PB_BAKE_GUIDE_H

#include "bake/path_cpu.h"
#include "bake/surface_cells.h"

#define PB_GUIDE_BINS 64u
#define PB_GUIDE_SHARE 0.5f /* probability of a guided bounce where an entry is learned (3/4 won 4.44x
                                on the doorway against 3.88x, but lost 0.75x on the Cornell box) */
#define PB_GUIDE_MIN_RECORDS 32u     /* an entry with fewer training paths is not learned */
#define PB_GUIDE_CELL_RECORDS 256.0  /* training paths a cell's surface gets on average */

typedef struct pb_guide {
    pb_cell_grid grid;
    uint32_t entries;             /* cells x 6 */
    uint32_t *slot;               /* per entry: its learned table slot, or ~0 (not learned) */
    uint32_t learned;             /* slots in the table */
    float *table;                 /* 4 floats per slot and bin: alias keep probability, alias bin (uint
                                     bits), the bin's probability, 0 */
} pb_guide;

/* Learns the cache from `paths` training paths of the shading that `pass`
 * describes (scene, BVH, lights, emitters, environment; its seed and
 * bounces): points drawn on the surfaces by area, cosine-distributed
 * directions, radiance from pb_path_radiance_cpu. */
pb_result pb_guide_build(const pb_bake_pass *pass, uint32_t paths, pb_guide *out, pb_error *err);
void pb_guide_free(pb_guide *g);

/* The kernel's functions, for the CPU reference: the learned slot for a
 * point and its normal (-1: none), a guided direction from 3 random
 * numbers, and the guided density of a direction (per steradian). */
int32_t pb_guide_entry(const pb_guide *g, const float x[3], const float n[3]);
void pb_guide_sample(const pb_guide *g, int32_t slot, float u1, float u2, float u3, float dir[3]);
float pb_guide_pdf(const pb_guide *g, int32_t slot, const float dir[3]);

/* The equal-area octahedral map (Clarberg 2008): [0,1]^2 <-> unit sphere. */
void pb_equal_area_decode(float s, float t, float dir[3]);
void pb_equal_area_encode(const float dir[3], float *s, float *t);

#endif
