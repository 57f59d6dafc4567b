/* Merging the parts of a sparse bake (bake --layout sparse --shard I/N). */
#ifndef PB_BAKE_SPARSE_MERGE_H
#define PB_BAKE_SPARSE_MERGE_H

#include "probebake/bake.h"

/* parts[k] is part k of N (pb_volume_merge has checked that they are one
 * bake's, each once). Part k holds the bricks grown from its range of
 * coarsest bricks (pb_shard_range over them); probes on the faces between
 * parts are in both, and must be equal where both parts name the same
 * device (else the lowest part's are kept). The whole: bricks level by level,
 * parts in order (the order a one-process bake appends them), probes as
 * pb_sparse_layout_build numbers them, then dilation and stitching. */
pb_result pb_sparse_merge(const pb_volume *const *parts, const char *const *names, uint32_t N, pb_volume *out,
                          pb_error *err);

/* The same in steps (pb_volume_merge_sparse_begin's work once it has
 * ordered and checked the parts): parts[k] need hold only part k's header
 * and sparse layout; pb_sparse_merge_add (bake.h) then copies the parts'
 * probes one part at a time, in index order, so the first part to hold a
 * shared probe is the one whose record stays. */
pb_result pb_sparse_merge_begin(const pb_volume *const *parts, const char *const *names, uint32_t N, pb_volume *out,
                                pb_sparse_merging **merging, pb_error *err);

#endif
