/*
 * probebake BVH: binned SAH build, flattened for the GPU, CPU reference traversal.
 *
 * Layout (docs/bvh.md): a binary BVH stored as "child pairs". Each node
 * (64 bytes) holds the bounds of both of its children and how to reach
 * them, so one fetch tests two boxes:
 *
 *   float lo_hi_x[4] = { c0.lo.x, c0.hi.x, c1.lo.x, c1.hi.x }
 *   float lo_hi_y[4], lo_hi_z[4]      (likewise)
 *   int32 child[2]    node index (count == 0) or first leaf-ordered triangle
 *   uint32 count[2]   triangles in the leaf, 0 for an inner node
 *
 * Node 0 is the root; children are stored depth first. Triangles are
 * reordered so each leaf's triangles are contiguous ("leaf order");
 * tri_order[k] is the scene index of leaf-ordered triangle k. An empty child
 * slot (a scene with one leaf) has count 0, child -1 and an inverted box.
 *
 * Traversals (GPU and the CPU reference) walk a 4-wide form of the same
 * tree (src/bvh/bvh_wide.c): each node (48 bytes) holds up to four child
 * boxes quantized to 8 bits per bound in the node's frame:
 *
 *   float origin[3]            the frame's corner
 *   uint8 exponent[3]          axis scale 2^(exponent - 127)
 *   uint8 qbox[3][2][4]        [axis][lo, hi][child]: bound = origin + q * scale
 *   uint32 inner               index of the first inner child (24 bits)
 *   uint32 leaf                first triangle of the first leaf child (28 bits)
 *   slot codes, 5 bits each    0 empty, 1..16 a leaf of that many triangles,
 *                              31 an inner node; in the spare bits above
 *
 * Decoded boxes enclose the exact ones; node 0 is the root. A node's inner
 * children have consecutive indices in slot order from `inner`, and its
 * leaves' triangles are consecutive in slot order from `leaf` (the build
 * renumbers leaf order so), so a node names its children in 8 bytes: 48
 * bytes is three 16-byte texels (docs/bvh.md). Traversals name pending
 * siblings by the first one and their ranks.
 */
#ifndef PROBEBAKE_BVH_H
#define PROBEBAKE_BVH_H

#include "probebake/base.h"
#include "probebake/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pb_scene pb_scene;

typedef struct pb_bvh_node {
    float lo_hi_x[4];
    float lo_hi_y[4];
    float lo_hi_z[4];
    int32_t child[2];
    uint32_t count[2];
} pb_bvh_node;

/* Slot codes of a 4-wide node (5 bits each): a leaf is its triangle count. */
#define PB_BVH4_SLOT_EMPTY 0u
#define PB_BVH4_SLOT_INNER 31u

typedef struct pb_bvh4_node {
    float origin[3];
    uint8_t exponent[3];
    uint8_t codes_lo;   /* slot codes, bits 0-7 */
    uint8_t qbox[3][2][4];
    uint32_t inner;     /* first inner child | slot codes bits 8-15 << 24 */
    uint32_t leaf;      /* first leaf triangle | slot codes bits 16-19 << 28 */
} pb_bvh4_node;

typedef struct pb_bvh_stats {
    uint32_t nodes;           /* inner nodes (each holds two child boxes) */
    uint32_t leaves;
    uint32_t depth;           /* edges from the root to the deepest leaf */
    uint32_t max_leaf_size;   /* largest leaf actually built */
    uint32_t wide_nodes;      /* 4-wide nodes the traversals walk */
    uint32_t wide_depth;      /* their depth */
    double wide_steps;        /* summed surface area of their boxes over the root's: expected node steps per ray
                                 through the root box, rays spread evenly (what the collapse minimises) */
    double sah_cost;          /* expected cost per ray, traversal step = 1 */
    double build_ms;          /* wall time of the build (binning + flatten) */
    uint32_t threads;         /* host threads used */
} pb_bvh_stats;

typedef struct pb_bvh {
    uint32_t node_count;
    pb_bvh_node *nodes;
    uint32_t wide_node_count;
    pb_bvh4_node *wide_nodes; /* the traversed form (see above) */
    uint32_t triangle_count;
    uint32_t *tri_order;      /* leaf order -> scene triangle index */
    float *tri_positions;     /* 9 floats per leaf-ordered triangle */
    pb_bvh_stats stats;
} pb_bvh;

/* Zero fields mean the defaults listed on each line. */
typedef struct pb_bvh_desc {
    uint32_t max_leaf_size;   /* default 2; 1..16 */
    uint32_t bins;            /* default 16; 4..64 */
    uint32_t threads;         /* default: every host core this process may use (affinity mask) */
    float traversal_cost;     /* SAH cost of one node step, default 2.0 (see docs/bvh.md) */
    float intersection_cost;  /* SAH cost of one triangle test, default 1.0 */
    uint32_t max_wide_nodes;  /* refuse (TOO_LARGE) a BVH of more 4-wide nodes; default and
                                 at most PB_BVH4_MAX_NODES, what a traversal can address */
} pb_bvh_desc;

/* Deepest child-pair tree the build makes. A traversal keeps a node's pending
 * inner children as one group and pushes at most one group per 4-wide level,
 * so its stack needs wide_depth + 1 entries (PB_BVH_STACK_SIZE); the GPU
 * kernel is specialised with this, so overflow cannot happen. A group names
 * its first node in 24 bits, so a BVH has at most PB_BVH4_MAX_NODES 4-wide
 * nodes (about 75 M triangles at the default leaves of 2; the build refuses
 * more with TOO_LARGE, pb_bvh_desc.max_wide_nodes), and a node names its
 * first leaf triangle in 28 bits (PB_BVH4_MAX_TRIANGLES). */
#define PB_BVH_MAX_DEPTH 64
#define PB_BVH_STACK_SIZE(wide_depth) ((wide_depth) + 1u)
#define PB_BVH4_MAX_NODES (1u << 24)
#define PB_BVH4_MAX_TRIANGLES (1u << 28)

/* Builds the BVH of `scene` (which must outlive nothing: the BVH copies the
 * positions it needs). Deterministic: the result does not depend on the
 * number of threads. desc may be NULL.
 *  Returns PB_ERROR_INVALID_ARGUMENT for out-of-range desc fields. */
pb_result pb_bvh_build(const pb_scene *scene, const pb_bvh_desc *desc, pb_bvh **out, pb_error *err);

/* Frees the BVH. NULL is allowed. */
void pb_bvh_destroy(pb_bvh *bvh);

/* Bytes the GPU needs for nodes + leaf-ordered triangle data. */
uint64_t pb_bvh_gpu_bytes(const pb_bvh *bvh);

#ifdef __cplusplus
}
#endif
#endif
