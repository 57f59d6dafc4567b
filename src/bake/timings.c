/* Stage timings summed over bakes (timings.h). */
#include "bake/timings.h"

void pb_volume_timings_add(pb_volume_timings *sum, const pb_volume_timings *t)
{
    sum->load += t->load, sum->bvh += t->bvh, sum->upload += t->upload, sum->trace += t->trace;
    sum->sh += t->sh, sum->octmap += t->octmap, sum->relocate += t->relocate, sum->total += t->total;
}
