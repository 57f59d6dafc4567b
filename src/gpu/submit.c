/* One command buffer per context, recorded, submitted and waited for: the
 * caller bounds each submission's work (rays_per_submit) so no single submit
 * runs long enough to trip a desktop GPU's watchdog (about 2 s on Windows'
 * TDR, similar on Linux drivers with a display attached). */
#include "common/common.h"
#include "gpu/gpu.h"

pb_result pb_cmd_begin(pb_context *ctx, pb_error *err)
{
    VkCommandBufferBeginInfo bi = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VkResult vr = ctx->vk.vkBeginCommandBuffer(ctx->cmd, &bi);
    if (vr != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkBeginCommandBuffer");
    ctx->recording = 1;
    ctx->timestamp_count = 0;
    if (ctx->timestamps)
        ctx->vk.vkCmdResetQueryPool(ctx->cmd, ctx->timestamps, 0, ctx->timestamp_capacity);
    return PB_OK;
}

/* The pipeline and its push constants, before either kind of dispatch. */
static void bind_and_push(pb_context *ctx, const pb_pipeline *p, const void *push)
{
    ctx->vk.vkCmdBindPipeline(ctx->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    if (p->push_size)
        ctx->vk.vkCmdPushConstants(ctx->cmd, p->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, p->push_size, push);
}

void pb_cmd_dispatch2(pb_context *ctx, const pb_pipeline *p, const void *push, uint32_t groups_x, uint32_t groups_y)
{
    bind_and_push(ctx, p, push);
    ctx->vk.vkCmdDispatch(ctx->cmd, groups_x, groups_y, 1);
}

void pb_cmd_dispatch_indirect(pb_context *ctx, const pb_pipeline *p, const void *push, const pb_buffer *args,
                              VkDeviceSize offset)
{
    bind_and_push(ctx, p, push);
    ctx->vk.vkCmdDispatchIndirect(ctx->cmd, args->buffer, offset);
}

void pb_cmd_bind_set(pb_context *ctx, const pb_pipeline *p, VkDescriptorSet set)
{
    ctx->vk.vkCmdBindDescriptorSets(ctx->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout, 0, 1, &set, 0, NULL);
}

void pb_cmd_dispatch(pb_context *ctx, const pb_pipeline *p, const void *push, uint32_t groups)
{
    pb_cmd_dispatch2(ctx, p, push, groups, 1);
}

void pb_cmd_barrier(pb_context *ctx)
{
    VkMemoryBarrier mb = {VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                       VK_ACCESS_TRANSFER_WRITE_BIT;
    VkPipelineStageFlags stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    ctx->vk.vkCmdPipelineBarrier(ctx->cmd, stages, stages, 0, 1, &mb, 0, NULL, 0, NULL);
}

void pb_cmd_barrier_indirect(pb_context *ctx)
{
    VkMemoryBarrier mb = {VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    ctx->vk.vkCmdPipelineBarrier(ctx->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                 VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &mb, 0,
                                 NULL, 0, NULL);
}

void pb_cmd_copy(pb_context *ctx, const pb_buffer *src, VkDeviceSize src_offset, const pb_buffer *dst,
                 VkDeviceSize dst_offset, VkDeviceSize size)
{
    VkBufferCopy region = {src_offset, dst_offset, size};
    ctx->vk.vkCmdCopyBuffer(ctx->cmd, src->buffer, dst->buffer, 1, &region);
}

void pb_cmd_timestamp(pb_context *ctx)
{
    if (!ctx->timestamps || ctx->timestamp_count >= ctx->timestamp_capacity)
        return;
    ctx->vk.vkCmdWriteTimestamp(ctx->cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, ctx->timestamps,
                                ctx->timestamp_count++);
}

pb_result pb_cmd_submit_wait(pb_context *ctx, double *gpu_ms, pb_error *err)
{
    if (gpu_ms)
        *gpu_ms = 0;
    ctx->recording = 0;
    VkResult vr = ctx->vk.vkEndCommandBuffer(ctx->cmd);
    if (vr != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkEndCommandBuffer");
    VkSubmitInfo si = {VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &ctx->cmd;
    if (++ctx->submissions == ctx->desc.fail_submission) {
        ctx->vk.vkResetCommandBuffer(ctx->cmd, 0);
        return pb_vk_fail(ctx, err, VK_ERROR_DEVICE_LOST, "vkQueueSubmit (injected fault)");
    }
    if ((vr = ctx->vk.vkQueueSubmit(ctx->queue, 1, &si, ctx->fence)) != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkQueueSubmit");
    /* wait in slices so a hung device is reported rather than waited on forever */
    const uint64_t slice = 1000000000ull; /* 1 s */
    uint32_t waited = 0;
    for (;;) {
        vr = ctx->vk.vkWaitForFences(ctx->device, 1, &ctx->fence, VK_TRUE, slice);
        if (vr != VK_TIMEOUT)
            break;
        if (++waited >= 600) { /* 10 minutes for one submission: treat as a hang */
            return pb_fail(err, PB_ERROR_DEVICE_LOST, "%s: a submission did not finish in 600 s", ctx->info.name);
        }
    }
    if (vr != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkWaitForFences");
    ctx->vk.vkResetFences(ctx->device, 1, &ctx->fence);
    ctx->vk.vkResetCommandBuffer(ctx->cmd, 0);
    ctx->interval_count = 0;
    if (ctx->timestamp_count >= 2) {
        uint64_t ts[64];
        uint32_t n = ctx->timestamp_count & ~1u;
        vr = ctx->vk.vkGetQueryPoolResults(ctx->device, ctx->timestamps, 0, n, sizeof ts, ts, sizeof(uint64_t),
                                           VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
        if (vr == VK_SUCCESS)
            for (uint32_t i = 0; i < n; i += 2) {
                double ms = (double)((ts[i + 1] - ts[i]) & ctx->timestamp_mask) * ctx->timestamp_period_ns * 1e-6;
                if (gpu_ms)
                    *gpu_ms += ms;
                ctx->intervals_ms[ctx->interval_count++] = ms;
            }
    }
    return PB_OK;
}

void pb_cmd_barrier_to_host(pb_context *ctx)
{
    VkMemoryBarrier mb = {VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    ctx->vk.vkCmdPipelineBarrier(ctx->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                                 VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, NULL, 0, NULL);
}
