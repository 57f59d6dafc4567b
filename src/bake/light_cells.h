/* Light cells (pb_bake_desc.light_cells): next-event estimation draws an
 * emissive triangle by how much light it brings to the region of the point
 * being lit, not by its power alone. With thousands of small emitters spread
 * over a level (The Crypt: 5,776 triangles of light strips and flames), a
 * draw by power mostly lands on lights far away or behind walls.
 *
 * Emitters are grouped into at most 256 clusters (a grid over their
 * centroids). Space is cut into cubic cells; for each cell that holds
 * enough of 2^16 surface points (drawn by area, keyed by the seed only, so
 * any subset of probes bakes to the same bytes), the clusters nearest by
 * power over distance squared are measured with shadow rays from the cell's
 * points, and the cell's distribution over clusters is
 *   q(c) = a share(c) + (1 - a) E(c) / sum E,
 * share(c) the cluster's part of the emitted power, E(c) its measured
 * unoccluded light, a = PB_LIGHT_CELL_POWER_SHARE (defensive: every emitter
 * keeps at least a times its power density, so nothing that lights a cell is
 * ever missed and the estimator stays unbiased). Within a cluster a triangle
 * is drawn by power, so its density is the power density times
 * q(c) / share(c), the cell's "ratio", which is all the MIS weights need.
 * A point in a cell without a table draws by power, as without the option.
 * shaders/include/light_cells.glsl reads the same tables. */
#ifndef PB_BAKE_LIGHT_CELLS_H
#define PB_BAKE_LIGHT_CELLS_H

#include "bake/path_cpu.h"
#include "bake/surface_cells.h"

#define PB_LIGHT_CELL_POINTS (1u << 16)  /* surface points the cells are measured from */
#define PB_LIGHT_CELL_MIN_POINTS 8u      /* a cell with fewer gets no table (draws by power) */
#define PB_LIGHT_CELL_CANDIDATES 64u     /* clusters per cell measured with shadow rays */
#define PB_LIGHT_CELL_RAYS 48u           /* shadow rays per cell and candidate cluster */
#define PB_LIGHT_CLUSTERS_MAX 256u
#define PB_LIGHT_CELL_POWER_SHARE 0.5f   /* a: the part of q drawn by power */

typedef struct pb_light_cells {
    pb_cell_grid grid;
    uint32_t *slot;               /* per cell: its table slot, or ~0 (draws by power) */
    uint32_t learned;             /* slots */
    uint32_t clusters;
    uint32_t *cluster_range;      /* 2 per cluster: first member, member count */
    uint32_t *member_tri;         /* per emitter in cluster order: scene triangle */
    float *member_keep;           /* alias table within each cluster, by power */
    uint32_t *member_alias;       /* (indices local to the cluster) */
    uint32_t *cluster_of;         /* per scene triangle: its cluster (0 for non-emitters) */
    float *table;                 /* 4 floats per slot and cluster: alias keep probability, alias cluster
                                     (uint bits), ratio q(c) / share(c), 0 */
} pb_light_cells;

/* Traces a batch of shadow rays (any hit): as pb_trace_cpu over the pass's
 * BVH, or on a device (pb_trace: its hits are the host's, so the tables are
 * the same bytes); an error stops the build. */
typedef pb_result (*pb_shadow_batch_fn)(void *user, const pb_ray *rays, uint32_t count, pb_hit *hits,
                                        pb_error *err);

/* Measures the cells for the scene, BVH, emitters and seed of `pass`, its
 * shadow rays traced by `trace` (NULL: pb_trace_cpu over pass->bvh on all
 * host threads). Leaves *out empty (slot NULL) when the scene has no
 * emitters. */
pb_result pb_light_cells_build(const pb_bake_pass *pass, pb_shadow_batch_fn trace, void *trace_user,
                               pb_light_cells *out, pb_error *err);
void pb_light_cells_free(pb_light_cells *lc);

/* The kernel's functions, for the CPU reference: the table slot of the cell
 * holding x (-1: draw by power), an emitter (scene triangle) drawn from a
 * slot with two random numbers and its ratio, and the ratio of a triangle's
 * density in a slot to its power density (1 for slot -1). */
int32_t pb_light_cells_slot(const pb_light_cells *lc, const float x[3]);
uint32_t pb_light_cells_sample(const pb_light_cells *lc, int32_t slot, float u0, float u1, float *ratio);
float pb_light_cells_ratio(const pb_light_cells *lc, int32_t slot, uint32_t tri);

#endif
