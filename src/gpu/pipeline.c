/* Compute pipelines. Kernels read every array through buffer device
 * addresses passed as push constants, so a pipeline layout is just one
 * push-constant range: no descriptor sets to keep in sync with the GLSL. */
#include "common/common.h"
#include "gpu/gpu.h"

#include <string.h>

pb_result pb_pipeline_create(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, uint32_t push_size,
                             const uint32_t *spec, uint32_t spec_count, uint32_t local_size, const char *what,
                             pb_pipeline *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (push_size > ctx->limits.maxPushConstantsSize)
        return pb_fail(err, PB_ERROR_UNSUPPORTED, "%s: kernel %s needs %u bytes of push constants, device allows %u",
                       ctx->info.name, what, push_size, ctx->limits.maxPushConstantsSize);
    double t0 = pb_now_ms();
    VkShaderModuleCreateInfo smci = {VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smci.codeSize = spirv_bytes;
    smci.pCode = spirv;
    VkShaderModule module;
    VkResult vr = ctx->vk.vkCreateShaderModule(ctx->device, &smci, NULL, &module);
    if (vr != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, what);
    VkPushConstantRange range = {VK_SHADER_STAGE_COMPUTE_BIT, 0, push_size};
    VkPipelineLayoutCreateInfo plci = {VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    plci.pushConstantRangeCount = push_size ? 1 : 0;
    plci.pPushConstantRanges = &range;
    vr = ctx->vk.vkCreatePipelineLayout(ctx->device, &plci, NULL, &out->layout);
    if (vr != VK_SUCCESS) {
        ctx->vk.vkDestroyShaderModule(ctx->device, module, NULL);
        return pb_vk_fail(ctx, err, vr, what);
    }
    VkSpecializationMapEntry entries[16];
    if (spec_count > 16)
        spec_count = 16;
    for (uint32_t i = 0; i < spec_count; ++i)
        entries[i] = (VkSpecializationMapEntry){i, i * 4u, 4};
    VkSpecializationInfo si = {spec_count, entries, spec_count * 4u, spec};
    VkComputePipelineCreateInfo cpci = {VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpci.stage.module = module;
    cpci.stage.pName = "main";
    cpci.stage.pSpecializationInfo = spec_count ? &si : NULL;
    cpci.layout = out->layout;
    vr = ctx->vk.vkCreateComputePipelines(ctx->device, VK_NULL_HANDLE, 1, &cpci, NULL, &out->pipeline);
    ctx->vk.vkDestroyShaderModule(ctx->device, module, NULL);
    if (vr != VK_SUCCESS) {
        pb_pipeline_destroy(ctx, out);
        return pb_vk_fail(ctx, err, vr, what);
    }
    out->push_size = push_size;
    out->local_size = local_size;
    /* driver compile time: on lavapipe the bake's kernels take most of a small bake's host time */
    pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "kernel %s: pipeline created in %.1f ms", what, pb_now_ms() - t0);
    return PB_OK;
}

void pb_pipeline_destroy(pb_context *ctx, pb_pipeline *p)
{
    if (p->pipeline)
        ctx->vk.vkDestroyPipeline(ctx->device, p->pipeline, NULL);
    if (p->layout)
        ctx->vk.vkDestroyPipelineLayout(ctx->device, p->layout, NULL);
    memset(p, 0, sizeof *p);
}
