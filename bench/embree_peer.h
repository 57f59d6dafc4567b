/* The CPU peer every bench compares against: Embree 3 (Debian's
 * libembree-dev), rtcIntersect1 on all host cores, same triangles (local
 * frame) and rays. */
#ifndef PB_EMBREE_PEER_H
#define PB_EMBREE_PEER_H

#include "probebake/probebake.h"

#include <embree3/rtcore.h>

typedef struct embree_peer {
    RTCScene scene;
    double build_ms;
} embree_peer;

int embree_peer_build(RTCDevice dev, const pb_scene *s, embree_peer *out);
/* Closest hits of n rays (t: n distances out, INFINITY on a miss). Returns wall ms. */
double embree_peer_trace(const embree_peer *p, const pb_ray *rays, uint32_t n, float *t);
void embree_peer_release(embree_peer *p);

#endif
