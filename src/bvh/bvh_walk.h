/* The reference traversal as a walker one ray at a time, one node step or one
 * triangle test per call: pb_trace_cpu drives it to the end of each ray, and
 * bench/lockstep_model.c drives eight of them as the kernel's SIMD lanes
 * (shaders/include/traverse.glsl is the same loop). Leaf-order triangle
 * indices throughout. */
#ifndef PB_BVH_WALK_H
#define PB_BVH_WALK_H

#include "bvh/intersect.h"
#include "probebake/bvh.h"
#include "probebake/scene.h"
#include "probebake/trace.h"

typedef struct pb_bvh_walk {
    pb_ray_pre r;
    float tmin, tmax;
    uint32_t best; /* leaf order, PB_NO_HIT until a hit */
    float u, v;
    uint32_t node, group, sp;
    uint32_t stack[PB_BVH_STACK_SIZE(PB_BVH_MAX_DEPTH)]; /* pending groups */
    /* the node last stepped: slots near to far, its hit leaves as one run of
     * `run` triangles (e[i]: the run's end after sorted slot i) */
    float d[4];
    uint32_t ch[4], cnt[4], e[4], first, run;
} pb_bvh_walk;

void pb_bvh_walk_start(pb_bvh_walk *w, const pb_ray *ray);
/* The current node's boxes: sets the run of triangles to test next. */
void pb_bvh_walk_step(pb_bvh_walk *w, const pb_bvh *bvh);
/* Tests the run's triangle i (alpha masks included); 1 on a hit, which
 * shortens tmax. */
int pb_bvh_walk_test(pb_bvh_walk *w, const pb_scene *scene, const pb_bvh *bvh, uint32_t i);
/* After the run: the next node from this node's hit inner children (with the
 * tmax its triangles left) or the stack; 0 when the ray is done. */
int pb_bvh_walk_next(pb_bvh_walk *w);

#endif
