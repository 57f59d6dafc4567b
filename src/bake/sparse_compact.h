/* Dropping a sparse volume's unsampled probes (docs/sparse.md, placement
 * step 7): the last stage of a sparse bake, and of merging its parts. */
#ifndef PB_BAKE_SPARSE_COMPACT_H
#define PB_BAKE_SPARSE_COMPACT_H

#include "probebake/volume.h"

/* A probe inside geometry (not PB_PROBE_VALID) gets no weight from the
 * sampler wherever a valid probe is in the cage, and its depth is never
 * read; a kept brick still names it. Every brick slot naming one is
 * pointed at a single "empty" probe instead (flags 0, zero SH and depth,
 * at the lattice origin), and the invalid probes are dropped: a cage of
 * only invalid probes then samples black, as a point with no brick does.
 * Probes stay numbered by first use in brick order (pb_sparse_layout_build's
 * rule), so a bake and a merge of its parts compact alike. Sets
 * v->probes_dropped to the number removed. No-op for grids and volumes with
 * no invalid probe. Run after dilation and stitching, which read them. */
pb_result pb_sparse_drop_invalid(pb_volume *v, pb_error *err);

#endif
