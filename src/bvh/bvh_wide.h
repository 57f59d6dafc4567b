/* Collapse of the child-pair BVH into the 4-wide quantized BVH that
 * traversals walk (bvh_wide.c; layout in include/probebake/bvh.h). */
#ifndef PB_BVH_WIDE_H
#define PB_BVH_WIDE_H

#include "probebake/bvh.h"

/* Fills bvh->wide_nodes, wide_node_count and the wide stats from
 * bvh->nodes, and renumbers leaf order (tri_order, tri_positions and the
 * pair nodes' leaves) so each wide node's leaves are consecutive. Returns 0
 * when out of host memory. */
int pb_bvh_collapse_wide(pb_bvh *bvh);

/* Scale of a quantized axis: 2^(e - 127), built from its bits as the kernel does. */
static inline float pb_bvh4_scale(uint8_t e)
{
    union { uint32_t u; float f; } b = {(uint32_t)e << 23};
    return b.f;
}

/* Child slots of a node as the traversals use them: child[i] is the node
 * index of an inner child, the first triangle of a leaf or PB_BVH4_EMPTY;
 * count[i] the leaf's triangles, 0 for inner and empty slots. The kernels'
 * load_node4 (shaders/include/scene.glsl) decodes the same bits. */
static inline void pb_bvh4_slots(const pb_bvh4_node *n, uint32_t child[4], uint32_t count[4])
{
    uint32_t codes = n->codes_lo | (n->inner >> 24) << 8 | (n->leaf >> 28) << 16;
    uint32_t inner = n->inner & 0xffffffu, leaf = n->leaf & 0xfffffffu;
    for (int i = 0; i < 4; ++i) {
        uint32_t c = (codes >> (5 * i)) & 31u;
        count[i] = c == PB_BVH4_SLOT_INNER ? 0u : c;
        child[i] = c == PB_BVH4_SLOT_EMPTY ? PB_BVH4_EMPTY : c == PB_BVH4_SLOT_INNER ? inner : leaf;
        inner += c == PB_BVH4_SLOT_INNER;
        leaf += count[i];
    }
}

/* Decoded (conservative) box of child slot i. */
void pb_bvh4_child_box(const pb_bvh4_node *n, uint32_t i, float lo[3], float hi[3]);

#endif
