/* The CPU peer every bench compares against: Embree 3 (Debian's
 * libembree-dev), rtcIntersect1 on all host cores, same triangles (local
 * frame) and rays. With alpha, alpha-masked and blended surfaces are cut out
 * as the bake's traversal cuts them (bvh/alpha.h, an Embree filter). */
#ifndef PB_EMBREE_PEER_H
#define PB_EMBREE_PEER_H

#include "probebake/probebake.h"

#include <embree3/rtcore.h>

typedef struct embree_peer {
    RTCScene scene;
    double build_ms;
} embree_peer;

int embree_peer_build(RTCDevice dev, const pb_scene *s, int alpha, embree_peer *out);
/* Closest hits of n rays (t: n distances out, INFINITY on a miss). Returns wall ms. */
double embree_peer_trace(const embree_peer *p, const pb_ray *rays, uint32_t n, float *t);
/* One ray, closest or any hit (pb_ray_cast_fn; user: the embree_peer):
 * triangle, t, u, v; backface is not set (the path tracer reads none). */
void embree_peer_cast(void *user, const pb_ray *ray, pb_trace_mode mode, pb_hit *hit);
/* n rays cast one by one as embree_peer_cast casts them, on all host
 * threads, hits dropped. Returns wall ms. */
double embree_peer_cast_all(const embree_peer *p, const pb_ray *rays, uint64_t n, pb_trace_mode mode);
void embree_peer_release(embree_peer *p);

#endif
