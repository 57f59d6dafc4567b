/* pb_gpu_batch (gpu.h): a test kernel over a batch of inputs. The kernel
 * writes straight into host-visible memory, as sample_gpu.c does. */
#include "common/common.h"
#include "gpu/gpu.h"

#include <stddef.h>
#include <string.h>

#define BATCH_EXTRA_MAX 96u /* 32 + 96: Vulkan's guaranteed 128 bytes of push constants */

typedef struct batch_push {
    uint64_t inputs, outputs;
    uint32_t count, pad[3];
    unsigned char extra[BATCH_EXTRA_MAX];
} batch_push;
_Static_assert(offsetof(batch_push, extra) == 32 && sizeof(batch_push) == 128, "batch kernels' push constants");

pb_result pb_gpu_batch(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, const char *name, const void *extra,
                       uint32_t extra_bytes, const void *in, uint32_t in_stride, void *out, uint32_t out_stride,
                       uint32_t count, pb_error *err)
{
    pb_error_clear(err);
    if (extra_bytes > BATCH_EXTRA_MAX)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: %u bytes of push constants past the batch's 32, at most %u",
                       name, extra_bytes, BATCH_EXTRA_MAX);
    if (count == 0)
        return PB_OK;
    uint64_t in_bytes = (uint64_t)count * in_stride, out_bytes = (uint64_t)count * out_stride;
    pb_buffer ib = {0}, ob = {0};
    pb_pipeline pipe = {0};
    pb_result r = pb_buffer_create(ctx, in_bytes, PB_MEMORY_DEVICE, name, &ib, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, out_bytes, PB_MEMORY_DOWNLOAD, name, &ob, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &ib, 0, in, in_bytes, err);
    if (r == PB_OK)
        r = pb_pipeline_create(ctx, spirv, spirv_bytes, 32 + extra_bytes, NULL, 0, 64, name, &pipe, err);
    if (r == PB_OK)
        r = pb_cmd_begin(ctx, err);
    if (r == PB_OK) {
        batch_push push = {ib.address, ob.address, count, {0, 0, 0}, {0}};
        if (extra_bytes)
            memcpy(push.extra, extra, extra_bytes);
        pb_cmd_dispatch(ctx, &pipe, &push, (count + 63) / 64);
        pb_cmd_barrier_to_host(ctx);
        r = pb_cmd_submit_wait(ctx, NULL, err);
    }
    if (r == PB_OK)
        memcpy(out, ob.mapped, (size_t)out_bytes);
    pb_pipeline_destroy(ctx, &pipe);
    pb_buffer_destroy(ctx, &ib);
    pb_buffer_destroy(ctx, &ob);
    return r;
}
