/* --indirect volume's bounce loop, one for every layout: bounces + 1 bakes,
 * bake k's probe rays' first hits reflecting bake k - 1's volume. */
#ifndef PB_BAKE_INDIRECT_VOLUME_H
#define PB_BAKE_INDIRECT_VOLUME_H

#include "probebake/bake.h"

/* One bounce: a bake of desc (bounces 0, indirect_volume 0) whose first
 * hits also reflect `previous` (NULL on the first bounce) into *out. */
typedef pb_result (*pb_bounce_fn)(void *user, const pb_bake_desc *desc, const pb_sample_volume *previous,
                                  pb_volume *out, pb_error *err);

/* Runs bake for bounces 0 .. desc->bounces: all but the last without the
 * light a probe sees directly (the hits sample it), the last as desc asks.
 * *out is the last bounce's volume, with every bounce's timings, rays and
 * traversals summed, and the settings saying indirect mode. */
pb_result pb_indirect_volume_bounces(const pb_scene *scene, const pb_bake_desc *desc, pb_bounce_fn bake, void *user,
                                     pb_volume *out, pb_error *err);

#endif
