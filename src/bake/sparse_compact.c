/* Placement step 7 (docs/sparse.md): a probe in rock is dilated for the
 * stitching of the level seams, then never read again by a lookup. On The
 * Crypt 29 % of a sparse volume's probes are such: their SH and depth tiles
 * were 29 % of its bytes, for no pixel. */
#include "bake/sparse_compact.h"
#include "common/common.h"
#include "probebake/sparse.h"

#include <stdlib.h>
#include <string.h>

#define UNSET UINT32_MAX

pb_result pb_sparse_drop_invalid(pb_volume *v, pb_error *err)
{
    v->probes_dropped = 0;
    pb_sparse_layout *sp = v->sparse;
    if (!sp)
        return PB_OK;
    uint32_t invalid = 0;
    for (uint32_t p = 0; p < v->probe_count; ++p)
        invalid += !(v->probe_flags[p] & PB_PROBE_VALID);
    if (invalid == 0)
        return PB_OK;
    uint32_t *to = malloc((size_t)v->probe_count * sizeof *to);
    if (!to)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u probes", v->probe_count);
    for (uint32_t p = 0; p < v->probe_count; ++p)
        to[p] = UNSET;
    /* new numbers by first use in brick order; every invalid slot names the empty probe */
    uint32_t next = 0, empty = UNSET;
    size_t slots = (size_t)PB_SPARSE_BRICK_PROBES * sp->brick_count;
    for (size_t s = 0; s < slots; ++s) {
        uint32_t p = sp->brick_probes[s];
        if (v->probe_flags[p] & PB_PROBE_VALID) {
            if (to[p] == UNSET)
                to[p] = next++;
        } else if (empty == UNSET) {
            empty = next++;
        }
    }
    pb_volume c = *v; /* scalars and the layout carry over; the per-probe arrays are new */
    c.sparse = NULL;
    c.probe_count = next;
    pb_result r = pb_volume_alloc(&c, err);
    if (r != PB_OK) {
        free(to);
        return r;
    }
    size_t halves = (size_t)pb_volume_tile_halves(v->octmap_res);
    for (uint32_t p = 0; p < v->probe_count; ++p) {
        uint32_t q = to[p];
        if (q == UNSET)
            continue;
        memcpy(c.base + 3 * (size_t)q, v->base + 3 * (size_t)p, 3 * sizeof(float));
        memcpy(c.offset + 3 * (size_t)q, v->offset + 3 * (size_t)p, 3 * sizeof(float));
        memcpy(c.sh + 27 * (size_t)q, v->sh + 27 * (size_t)p, 27 * sizeof(float));
        memcpy(c.depth + halves * q, v->depth + halves * p, halves * sizeof(uint16_t));
        c.probe_flags[q] = v->probe_flags[p];
        c.probe_paths[q] = v->probe_paths[p];
        c.probe_std_error[q] = v->probe_std_error[p];
    }
    /* the empty probe: pb_volume_alloc's zeros, no flags, unknown error */
    for (size_t s = 0; s < slots; ++s) {
        uint32_t p = sp->brick_probes[s];
        sp->brick_probes[s] = to[p] == UNSET ? empty : to[p];
    }
    free(to);
    v->sparse = NULL; /* kept: c takes the layout */
    pb_volume_free(v);
    c.sparse = sp;
    *v = c;
    v->probes_dropped = invalid;
    return PB_OK;
}
