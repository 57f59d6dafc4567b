/* Stage timings summed over the bakes that make one volume: a sharded
 * bake's parts, --indirect volume's bounces, a sparse bake's levels. Field by
 * field: the struct's doubles are named members, not an array. */
#ifndef PB_BAKE_TIMINGS_H
#define PB_BAKE_TIMINGS_H

#include "probebake/volume.h"

void pb_volume_timings_add(pb_volume_timings *sum, const pb_volume_timings *t);

#endif
