/* Where the sparse refinement looks for error: points on the surfaces inside
 * a level's cells, which is where a renderer samples the volume. A probe in
 * a cell's open air can be predicted well while the wall through that cell
 * is lit wrongly by the coarse cage (docs/sparse.md, "Refinement"). */
#ifndef PB_BAKE_SPARSE_SURFACE_TESTS_H
#define PB_BAKE_SPARSE_SURFACE_TESTS_H

#include "probebake/base.h"
#include "probebake/bvh.h"
#include "probebake/scene.h"

#include <stdint.h>

/* At most this many test points per cell: for each dominant normal axis
 * (+-x, +-y, +-z), the surface point nearest the cell's centre. */
#define PB_CELL_TESTS_MAX 6

typedef struct pb_cell_tests {
    uint32_t count;
    float *x;           /* 3 per test: a point on a surface, scene local frame */
    float *n;           /* 3 per test: the unit normal of its lit side */
    uint32_t *cell;     /* per test: its cell's index in the caller's list */
    uint32_t *bucket;   /* per test: its normal axis (0..5), part of its random-number id */
} pb_cell_tests;

/* Test points for `cell_count` cells (3 lattice coordinates each; cell c
 * spans origin + c * size to origin + (c + 1) * size, scene local frame):
 * of the triangles whose boxes overlap the cell (a query of bvh), the point
 * nearest the centre, where it lies inside the cell, per normal axis; x is
 * offset off the surface as a ray origin (pb_offset_ray_origin). The lit
 * side is the front, or for a double-sided material the side facing the
 * centre. Emissive surfaces are skipped (no probe lights them in an image).
 * A cell's tests depend on that cell alone, so a shard gets the whole
 * bake's. A cell no surface crosses gets none. */
pb_result pb_cell_surface_tests(const pb_scene *s, const pb_bvh *bvh, const double origin[3], const double size[3],
                                const uint32_t *cells, uint32_t cell_count, pb_cell_tests *out, pb_error *err);
void pb_cell_tests_free(pb_cell_tests *t);

#endif
