/* Collapse of the child-pair BVH into the 4-wide quantized BVH that
 * traversals walk (bvh_wide.c; layout in include/probebake/bvh.h). */
#ifndef PB_BVH_WIDE_H
#define PB_BVH_WIDE_H

#include "probebake/bvh.h"

/* Fills bvh->wide_nodes, wide_node_count and the wide stats from
 * bvh->nodes. Returns 0 when out of host memory. */
int pb_bvh_collapse_wide(pb_bvh *bvh);

/* Scale of a quantized axis: 2^(e - 127), built from its bits as the kernel does. */
static inline float pb_bvh4_scale(uint8_t e)
{
    union { uint32_t u; float f; } b = {(uint32_t)e << 23};
    return b.f;
}

/* Decoded (conservative) box of child slot i. */
void pb_bvh4_child_box(const pb_bvh4_node *n, uint32_t i, float lo[3], float hi[3]);

#endif
