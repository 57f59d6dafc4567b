/* pb_exact_diff_gpu: the exact_diff.comp kernel over a batch of inputs.
 * Small and synchronous: it exists to test shaders/include/exact_diff.glsl
 * against pb_exact_diff bit for bit, on inputs traversal rarely reaches. */
#include "bvh/exact_diff.h"
#include "common/common.h"
#include "gpu/gpu.h"

#include "exact_diff.spv.h"

#include <string.h>

typedef struct exact_diff_push {
    uint64_t inputs;  /* vec4 (a, b, c, d) per entry */
    uint64_t outputs; /* float per entry */
    uint32_t count, pad[3];
} exact_diff_push;
_Static_assert(sizeof(exact_diff_push) == 32, "exact_diff.comp push constants");

pb_result pb_exact_diff_gpu(pb_context *ctx, const float *abcd, uint32_t count, float *out, pb_error *err)
{
    pb_error_clear(err);
    if (count == 0)
        return PB_OK;
    uint64_t in_bytes = (uint64_t)count * 16, out_bytes = (uint64_t)count * 4;
    pb_buffer in = {0}, res = {0};
    pb_pipeline pipe = {0};
    /* the kernel writes straight into host-visible memory, as sample_gpu.c does */
    pb_result r = pb_buffer_create(ctx, in_bytes, PB_MEMORY_DEVICE, "exact_diff inputs", &in, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, out_bytes, PB_MEMORY_DOWNLOAD, "exact_diff outputs", &res, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &in, 0, abcd, in_bytes, err);
    if (r == PB_OK)
        r = pb_pipeline_create(ctx, pb_spv_exact_diff, sizeof pb_spv_exact_diff, sizeof(exact_diff_push), NULL, 0, 64,
                               "exact_diff", &pipe, err);
    if (r == PB_OK)
        r = pb_cmd_begin(ctx, err);
    if (r == PB_OK) {
        exact_diff_push push = {in.address, res.address, count, {0, 0, 0}};
        pb_cmd_dispatch(ctx, &pipe, &push, (count + 63) / 64);
        pb_cmd_barrier_to_host(ctx);
        r = pb_cmd_submit_wait(ctx, NULL, err);
    }
    if (r == PB_OK)
        memcpy(out, res.mapped, (size_t)out_bytes);
    pb_pipeline_destroy(ctx, &pipe);
    pb_buffer_destroy(ctx, &in);
    pb_buffer_destroy(ctx, &res);
    return r;
}
