/* Stitching a sparse volume's level seams (docs/sparse.md, placement step 6):
 * the last stage of a sparse bake, and of merging its parts. */
#ifndef PB_BAKE_SPARSE_STITCH_H
#define PB_BAKE_SPARSE_STITCH_H

#include "probebake/volume.h"

/* Every probe on the face of a level-l brick that a coarser brick next to it
 * does not have takes what that brick's sampler holds there: its cage's
 * trilinear weights times each probe's Chebyshev visibility of the point,
 * invalid probes none, normalised (coarse levels first); a baked (valid)
 * probe only where that value misses it by no more than the volume's refine
 * error and its noise, else it keeps its bake. Run after dilation.
 * Reads only the volume, so a bake and a merge of its parts stitch alike. */
pb_result pb_sparse_stitch(pb_volume *v, pb_error *err);

/* The seam test of a placement (docs/sparse.md, placement step 3): every
 * valid hanging probe of a level-`level` brick tests the coarser cell next
 * to it, one level up, on that cell's face. Where the cell's value there
 * misses the probe's bake as pb_sparse_stitch judges it (the refine error
 * and 3 standard errors), that cell is returned, as a level-`level` brick
 * coordinate inside the same coarsest brick (*cells: malloc'd, *count; each
 * once). v: an undilated, unstitched sparse volume (the placement so far). */
pb_result pb_sparse_seam_misses(const pb_volume *v, uint32_t level, pb_sparse_brick **cells, uint32_t *count,
                                pb_error *err);

#endif
