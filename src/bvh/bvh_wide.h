/* Collapse of the child-pair BVH into the 4-wide quantized BVH that
 * traversals walk (bvh_wide.c; layout in include/probebake/bvh.h). */
#ifndef PB_BVH_WIDE_H
#define PB_BVH_WIDE_H

#include "probebake/bvh.h"

/* Fills bvh->wide_nodes, wide_node_count and the wide stats from
 * bvh->nodes, and renumbers leaf order (tri_order and the pair nodes'
 * leaves) so each wide node's leaves are consecutive; tri_positions, which
 * follow tri_order, are the caller's to fill after it. Returns 0 when out of
 * host memory. Covers and quantizes on up to `threads` threads; the result
 * is the same for any count. */
int pb_bvh_collapse_wide(pb_bvh *bvh, uint32_t threads);

/* Surface area of the box [lo, hi] (0 for an empty axis): the probability
 * weight of both the build's SAH and the collapse's expected steps. */
static inline float pb_box_area(const float lo[3], const float hi[3])
{
    float d[3];
    for (int k = 0; k < 3; ++k) {
        d[k] = hi[k] - lo[k];
        if (!(d[k] > 0.f))
            d[k] = 0.f;
    }
    return 2.f * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
}

/* Scale of a quantized axis: 2^(e - 127), built from its bits as the kernel does. */
static inline float pb_bvh4_scale(uint8_t e)
{
    union { uint32_t u; float f; } b = {(uint32_t)e << 23};
    return b.f;
}

/* Child slots of a node as the traversals use them. Returns the used slots
 * (they come first). child[i] is a leaf's first triangle or an inner
 * child's rank among the node's inner children (its node index is
 * pb_bvh4_first_inner + rank); count[i] the leaf's triangles, 0 for an inner
 * or unused slot. The kernels' load_node4 (shaders/include/scene.glsl)
 * decodes the same bits. */
static inline uint32_t pb_bvh4_first_inner(const pb_bvh4_node *n)
{
    return n->inner & 0xffffffu;
}

static inline uint32_t pb_bvh4_slots(const pb_bvh4_node *n, uint32_t child[4], uint32_t count[4])
{
    uint32_t codes = n->codes_lo | (n->inner >> 24) << 8 | (n->leaf >> 28) << 16;
    uint32_t rank = 0, leaf = n->leaf & 0xfffffffu, used = 0;
    for (int i = 0; i < 4; ++i) {
        uint32_t c = (codes >> (5 * i)) & 31u;
        count[i] = c == PB_BVH4_SLOT_INNER ? 0u : c;
        child[i] = c == PB_BVH4_SLOT_INNER ? rank : leaf;
        rank += c == PB_BVH4_SLOT_INNER;
        leaf += count[i];
        used += c != PB_BVH4_SLOT_EMPTY;
    }
    return used;
}

/* Decoded (conservative) box of child slot i. */
void pb_bvh4_child_box(const pb_bvh4_node *n, uint32_t i, float lo[3], float hi[3]);

#endif
