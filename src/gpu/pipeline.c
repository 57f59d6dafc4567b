/* Compute pipelines. Kernels read their arrays through buffer device
 * addresses passed as push constants; the one descriptor set, the same
 * layout in every pipeline, holds the scene's BVH nodes and triangles as
 * texel views for devices that read them faster that way (scene.glsl). */
#include "common/common.h"
#include "gpu/gpu.h"

#include <stdlib.h>
#include <string.h>

static pb_pipeline_entry *cache_find(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, uint32_t push_size,
                                     const uint32_t *spec, uint32_t spec_count, uint32_t local_size)
{
    for (uint32_t i = 0; i < ctx->pipeline_count; ++i) {
        pb_pipeline_entry *e = &ctx->pipelines[i];
        if (e->spirv == spirv && e->spirv_bytes == spirv_bytes && e->push_size == push_size &&
            e->local_size == local_size && e->spec_count == spec_count &&
            (!spec_count || !memcmp(e->spec, spec, spec_count * sizeof *spec)))
            return e;
    }
    return NULL;
}

/* Keeps p in the context's cache; 0 (and p stays the caller's) when out of memory. */
static int cache_add(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, uint32_t push_size,
                     const uint32_t *spec, uint32_t spec_count, uint32_t local_size, const pb_pipeline *p)
{
    if (ctx->pipeline_count == ctx->pipeline_capacity) {
        uint32_t cap = ctx->pipeline_capacity ? 2 * ctx->pipeline_capacity : 16;
        pb_pipeline_entry *grown = realloc(ctx->pipelines, cap * sizeof *grown);
        if (!grown)
            return 0;
        ctx->pipelines = grown, ctx->pipeline_capacity = cap;
    }
    pb_pipeline_entry *e = &ctx->pipelines[ctx->pipeline_count++];
    memset(e, 0, sizeof *e);
    e->spirv = spirv, e->spirv_bytes = spirv_bytes, e->push_size = push_size, e->local_size = local_size;
    e->spec_count = spec_count;
    if (spec_count)
        memcpy(e->spec, spec, spec_count * sizeof *spec);
    e->pipeline = *p;
    e->pipeline.cached = 1;
    return 1;
}

pb_result pb_pipeline_create(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, uint32_t push_size,
                             const uint32_t *spec, uint32_t spec_count, uint32_t local_size, const char *what,
                             pb_pipeline *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (spec_count > 16)
        spec_count = 16;
    const pb_pipeline_entry *hit = cache_find(ctx, spirv, spirv_bytes, push_size, spec, spec_count, local_size);
    if (hit) {
        *out = hit->pipeline;
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "kernel %s: pipeline reused", what);
        return PB_OK;
    }
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
    plci.setLayoutCount = 1;
    plci.pSetLayouts = &ctx->scene_set_layout;
    vr = ctx->vk.vkCreatePipelineLayout(ctx->device, &plci, NULL, &out->layout);
    if (vr != VK_SUCCESS) {
        ctx->vk.vkDestroyShaderModule(ctx->device, module, NULL);
        return pb_vk_fail(ctx, err, vr, what);
    }
    VkSpecializationMapEntry entries[16];
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
    ++ctx->pipelines_created;
    if (cache_add(ctx, spirv, spirv_bytes, push_size, spec, spec_count, local_size, out))
        out->cached = 1;
    /* driver compile time: on lavapipe the bake's kernels take most of a small bake's host time */
    pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "kernel %s: pipeline created in %.1f ms", what, pb_now_ms() - t0);
    return PB_OK;
}

void pb_pipeline_destroy(pb_context *ctx, pb_pipeline *p)
{
    if (p->cached) { /* the context's: it goes with the context */
        memset(p, 0, sizeof *p);
        return;
    }
    if (p->pipeline)
        ctx->vk.vkDestroyPipeline(ctx->device, p->pipeline, NULL);
    if (p->layout)
        ctx->vk.vkDestroyPipelineLayout(ctx->device, p->layout, NULL);
    memset(p, 0, sizeof *p);
}

void pb_pipeline_cache_release(pb_context *ctx)
{
    for (uint32_t i = 0; i < ctx->pipeline_count; ++i) {
        pb_pipeline *p = &ctx->pipelines[i].pipeline;
        p->cached = 0;
        pb_pipeline_destroy(ctx, p);
    }
    free(ctx->pipelines);
    ctx->pipelines = NULL;
    ctx->pipeline_count = ctx->pipeline_capacity = 0;
}
