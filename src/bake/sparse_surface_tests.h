/* Where the sparse refinement looks for error: points on the surfaces inside
 * a level's cells, which is where a renderer samples the volume. A probe in
 * a cell's open air can be predicted well while the wall through that cell
 * is lit wrongly by the coarse cage (docs/sparse.md, "Placement", step 3). */
#ifndef PB_BAKE_SPARSE_SURFACE_TESTS_H
#define PB_BAKE_SPARSE_SURFACE_TESTS_H

#include "probebake/base.h"
#include "probebake/bvh.h"
#include "probebake/scene.h"

#include <stdint.h>

/* Sub-cells per axis a cell may be split into for its tests (the sparse
 * bake splits 9-spacing cells into 3; 4^3 * 6 slots still fit the 512 its
 * random-number ids leave per cell). */
#define PB_CELL_TESTS_SUB_MAX 4

typedef struct pb_cell_tests {
    uint32_t count;
    float *x;           /* 3 per test: a point on a surface, scene local frame */
    float *n;           /* 3 per test: the unit normal of its lit side */
    uint32_t *cell;     /* per test: its cell's index in the caller's list */
    uint32_t *slot;     /* per test: sub-cell * 6 + normal axis (0..5), part of its random-number id */
} pb_cell_tests;

typedef struct pb_cell_test_desc {
    double origin[3];   /* cell c spans origin + c * size to origin + (c + 1) * size, scene local frame */
    double size[3];
    double margin[3];   /* a cell at coordinate 0 reaches this much further down: the bake bounds do */
    uint32_t sub;       /* 1..PB_CELL_TESTS_SUB_MAX: the cell's tests are its sub^3 sub-cells' */
} pb_cell_test_desc;

/* Test points for `cell_count` cells (3 lattice coordinates each): of the
 * triangles whose boxes overlap the cell (a query of bvh), per sub-cell and
 * normal axis (+-x, +-y, +-z) the point nearest the sub-cell's centre,
 * where it lies inside that sub-cell; x is offset off the surface as a ray
 * origin (pb_offset_ray_origin). One point per cell misses what a large
 * cell holds away from its centre (a lit statue at the centre of a 9 m cell
 * hides the dark wall at its edge). The lit side is the front, or for a
 * double-sided material the side facing the centre. Emissive surfaces are
 * skipped (no probe lights them in an image). A cell's tests depend on that
 * cell alone, so a shard gets the whole bake's. A cell no surface crosses
 * gets none. */
pb_result pb_cell_surface_tests(const pb_scene *s, const pb_bvh *bvh, const pb_cell_test_desc *d, const uint32_t *cells,
                                uint32_t cell_count, pb_cell_tests *out, pb_error *err);
void pb_cell_tests_free(pb_cell_tests *t);

#endif
