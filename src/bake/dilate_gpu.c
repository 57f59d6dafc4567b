/* Dilation on the device: dilate.comp, `rounds` rounds in one submission
 * (the states ping-pong between two buffers, the SH are filled in place),
 * then the volume's SH and flags back. The bake's last stage on a grid; pb_volume_dilate (the CPU
 * reference, dilate.c) writes the same bytes. */
#include "bake/dilate.h"
#include "bake/gpu_types.h"
#include "common/common.h"
#include "gpu/gpu.h"
#include "probebake/bake.h"

#include "dilate.spv.h"

#include <stdlib.h>
#include <string.h>

static pb_result make_neighbours(pb_context *ctx, const uint32_t *neighbours, uint32_t P, pb_buffer *out,
                                 pb_error *err)
{
    uint64_t bytes = (uint64_t)P * PB_DILATE_NEIGHBOURS * 4;
    pb_result r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, "dilation neighbours", out, err);
    return r == PB_OK ? pb_buffer_upload(ctx, out, 0, neighbours, bytes, err) : r;
}

pb_result pb_volume_dilate_gpu(pb_context *ctx, pb_volume *v, uint32_t rounds, pb_error *err)
{
    pb_error_clear(err);
    const pb_sparse_layout *sp = (v->flags & PB_VOLUME_SPARSE) ? v->sparse : NULL;
    if (!(v->flags & PB_VOLUME_GRID) && !sp)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "dilation needs a grid or sparse volume");
    uint32_t P = v->probe_count;
    uint64_t sh_bytes = (uint64_t)P * 27 * 4, state_bytes = (uint64_t)P * 4;
    pb_buffer sh = {0}, state[2] = {{0}}, table = {0}, down = {0}, nbrs = {0};
    pb_pipeline pipe = {0};
    uint32_t *st = malloc((size_t)state_bytes);
    uint32_t *neighbours = sp ? pb_dilate_sparse_neighbours(sp, P) : NULL;
    float recip[PB_DILATE_TABLE];
    if (!st || (sp && !neighbours)) {
        free(st), free(neighbours);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for dilation");
    }
    pb_dilate_reciprocals(recip);
    for (uint32_t p = 0; p < P; ++p)
        st[p] = (v->probe_flags[p] & PB_PROBE_VALID) ? PB_DILATE_VALID : PB_DILATE_EMPTY;
    pb_result r = pb_buffer_create(ctx, sh_bytes, PB_MEMORY_DEVICE, "dilation SH", &sh, err);
    for (int i = 0; i < 2 && r == PB_OK; ++i)
        r = pb_buffer_create(ctx, state_bytes, PB_MEMORY_DEVICE, "dilation state", &state[i], err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, sizeof recip, PB_MEMORY_DEVICE, "dilation weights", &table, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &sh, 0, v->sh, sh_bytes, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &state[0], 0, st, state_bytes, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &table, 0, recip, sizeof recip, err);
    if (r == PB_OK && neighbours)
        r = make_neighbours(ctx, neighbours, P, &nbrs, err);
    if (r == PB_OK)
        r = pb_pipeline_create(ctx, pb_spv_dilate, sizeof pb_spv_dilate, sizeof(dilate_push), NULL, 0, 64, "dilate",
                               &pipe, err);
    uint32_t last = rounds % 2; /* the states the last round writes */
    if (r == PB_OK && (!sh.mapped || !state[last].mapped))
        r = pb_buffer_create(ctx, sh_bytes + state_bytes, PB_MEMORY_DOWNLOAD, "dilation download", &down, err);
    if (r == PB_OK)
        r = pb_cmd_begin(ctx, err);
    if (r == PB_OK) {
        for (uint32_t k = 0; k < rounds; ++k) {
            uint32_t a = k % 2, b = 1 - a;
            dilate_push push = {sh.address,    state[a].address, state[b].address, table.address,
                                nbrs.address, 0,                {v->counts[0], v->counts[1], v->counts[2], P}};
            pb_cmd_dispatch(ctx, &pipe, &push, (P + 63) / 64);
            pb_cmd_barrier(ctx);
        }
        if (down.size) {
            pb_cmd_copy(ctx, &sh, 0, &down, 0, sh_bytes);
            pb_cmd_copy(ctx, &state[last], 0, &down, sh_bytes, state_bytes);
        }
        pb_cmd_barrier_to_host(ctx);
        r = pb_cmd_submit_wait(ctx, NULL, err);
    }
    if (r == PB_OK) {
        const float *res_sh = down.size ? (const float *)down.mapped : (const float *)sh.mapped;
        const uint32_t *res_st = down.size ? (const uint32_t *)((const char *)down.mapped + sh_bytes)
                                           : (const uint32_t *)state[last].mapped;
        memcpy(v->sh, res_sh, (size_t)sh_bytes);
        for (uint32_t p = 0; p < P; ++p)
            if (res_st[p] == PB_DILATE_FILLED)
                v->probe_flags[p] |= PB_PROBE_DILATED;
    }
    pb_pipeline_destroy(ctx, &pipe);
    pb_buffer_destroy(ctx, &sh);
    for (int i = 0; i < 2; ++i)
        pb_buffer_destroy(ctx, &state[i]);
    pb_buffer_destroy(ctx, &table);
    pb_buffer_destroy(ctx, &down);
    pb_buffer_destroy(ctx, &nbrs);
    free(st), free(neighbours);
    return r;
}
