#ifndef PB_BENCH_BOUNCE_RAYS_H
#define PB_BENCH_BOUNCE_RAYS_H

#include "probebake/probebake.h"

/* The bake's bounce rays, without the bake: from each probe ray's first hit
 * (offset off the surface as the bake offsets it) a cosine-distributed
 * direction about the geometric normal facing the probe. Rays that miss or
 * hit a back face leave no bounce ray. In place; returns the new count.
 * sorted: ordered by direction (an 8 x 8 octahedral bin) and then by the
 * Morton code of the origin (32 cells per axis over the scene's bounds), what a
 * wavefront bake would trace between bounces. */
uint32_t bench_bounce_rays(const pb_scene *s, pb_ray *rays, const pb_hit *hits, uint32_t n, int sorted);

#endif
