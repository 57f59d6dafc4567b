/* Compute pipelines. Kernels read their arrays through buffer device
 * addresses passed as push constants; the one descriptor set, the same
 * layout in every pipeline, holds the scene's BVH nodes and triangles as
 * texel views for devices that read them faster that way (scene.glsl). */
#include "common/common.h"
#include "gpu/gpu.h"

#include <pthread.h>
#include <stdio.h>
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

/* The driver's part of a pipeline: shader module, layout, pipeline. Touches
 * no context state but the device and its tables, so worker threads may run
 * it side by side (Vulkan's create calls need no external synchronisation);
 * on failure *out is destroyed and *stage names the call. */
static VkResult make_pipeline(pb_context *ctx, const pb_pipeline_request *q, pb_pipeline *out, const char **stage)
{
    memset(out, 0, sizeof *out);
    VkShaderModuleCreateInfo smci = {VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smci.codeSize = q->spirv_bytes;
    smci.pCode = q->spirv;
    VkShaderModule module;
    *stage = "vkCreateShaderModule";
    VkResult vr = ctx->vk.vkCreateShaderModule(ctx->device, &smci, NULL, &module);
    if (vr != VK_SUCCESS)
        return vr;
    VkPushConstantRange range = {VK_SHADER_STAGE_COMPUTE_BIT, 0, q->push_size};
    VkPipelineLayoutCreateInfo plci = {VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    plci.pushConstantRangeCount = q->push_size ? 1 : 0;
    plci.pPushConstantRanges = &range;
    plci.setLayoutCount = 1;
    plci.pSetLayouts = &ctx->scene_set_layout;
    *stage = "vkCreatePipelineLayout";
    vr = ctx->vk.vkCreatePipelineLayout(ctx->device, &plci, NULL, &out->layout);
    if (vr != VK_SUCCESS) {
        ctx->vk.vkDestroyShaderModule(ctx->device, module, NULL);
        return vr;
    }
    VkSpecializationMapEntry entries[16];
    for (uint32_t i = 0; i < q->spec_count; ++i)
        entries[i] = (VkSpecializationMapEntry){i, i * 4u, 4};
    VkSpecializationInfo si = {q->spec_count, entries, q->spec_count * 4u, q->spec};
    VkComputePipelineCreateInfo cpci = {VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpci.stage.module = module;
    cpci.stage.pName = "main";
    cpci.stage.pSpecializationInfo = q->spec_count ? &si : NULL;
    cpci.layout = out->layout;
    *stage = "vkCreateComputePipelines";
    vr = ctx->vk.vkCreateComputePipelines(ctx->device, VK_NULL_HANDLE, 1, &cpci, NULL, &out->pipeline);
    ctx->vk.vkDestroyShaderModule(ctx->device, module, NULL);
    if (vr != VK_SUCCESS) {
        pb_pipeline_destroy(ctx, out);
        return vr;
    }
    out->push_size = q->push_size;
    out->local_size = q->local_size;
    return VK_SUCCESS;
}

static void *make_pipeline_job(void *arg)
{
    pb_pipeline_job *job = arg;
    double t0 = pb_now_ms();
    if (job->inject) {
        memset(&job->made, 0, sizeof job->made);
        job->result = VK_ERROR_OUT_OF_HOST_MEMORY, job->stage = "vkCreateComputePipelines (injected fault)";
        return NULL;
    }
    job->result = make_pipeline(job->ctx, &job->request, &job->made, &job->stage);
    job->ms = pb_now_ms() - t0;
    return NULL;
}

/* Adds one request: a cached pipeline is copied out at once, a new one
 * becomes a job, on a thread of its own when `threaded` (else, or when no
 * thread starts, pb_pipelines_end makes it). */
static pb_result batch_add(pb_context *ctx, pb_pipeline_batch *batch, const pb_pipeline_request *request, int threaded,
                           pb_error *err)
{
    pb_pipeline_request q = *request;
    if (q.spec_count > 16)
        q.spec_count = 16;
    memset(q.out, 0, sizeof *q.out);
    const pb_pipeline_entry *hit = cache_find(ctx, q.spirv, q.spirv_bytes, q.push_size, q.spec, q.spec_count, q.local_size);
    if (hit) {
        *q.out = hit->pipeline;
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "kernel %s: pipeline reused", q.what);
        return PB_OK;
    }
    if (q.push_size > ctx->limits.maxPushConstantsSize)
        return pb_fail(err, PB_ERROR_UNSUPPORTED, "%s: kernel %s needs %u bytes of push constants, device allows %u",
                       ctx->info.name, q.what, q.push_size, ctx->limits.maxPushConstantsSize);
    if (batch->count == PB_PIPELINE_BATCH_MAX)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "more than %u new pipelines in one batch", PB_PIPELINE_BATCH_MAX);
    pb_pipeline_job *job = &batch->jobs[batch->count++];
    job->ctx = ctx;
    job->request = q;
    job->inject = ++ctx->pipeline_jobs == ctx->desc.fail_pipeline;
    if (q.spec_count) /* the caller's array may not outlive the call (and may be NULL when empty) */
        memcpy(job->spec, q.spec, q.spec_count * sizeof *q.spec);
    job->request.spec = job->spec;
    job->threaded = threaded && pthread_create(&job->thread, NULL, make_pipeline_job, job) == 0;
    return PB_OK;
}

pb_result pb_pipelines_begin(pb_context *ctx, const pb_pipeline_request *requests, uint32_t count,
                             pb_pipeline_batch *batch, pb_error *err)
{
    memset(batch, 0, sizeof *batch);
    for (uint32_t i = 0; i < count; ++i) {
        pb_result r = batch_add(ctx, batch, &requests[i], 1, err);
        if (r != PB_OK) {
            pb_pipelines_end(ctx, batch, NULL); /* joins the started ones */
            /* the requests up to i were handed an output (cached: forgotten; a
             * pipeline the cache could not keep: destroyed); the rest are cleared */
            for (uint32_t k = 0; k < count; ++k)
                if (k <= i)
                    pb_pipeline_destroy(ctx, requests[k].out);
                else
                    memset(requests[k].out, 0, sizeof *requests[k].out);
            return r;
        }
    }
    return PB_OK;
}

pb_result pb_pipelines_end(pb_context *ctx, pb_pipeline_batch *batch, pb_error *err)
{
    pb_result r = PB_OK;
    for (uint32_t i = 0; i < batch->count; ++i) {
        pb_pipeline_job *job = &batch->jobs[i];
        if (job->threaded)
            pthread_join(job->thread, NULL);
        else
            make_pipeline_job(job);
    }
    /* the context's cache, counters and log are touched here, on the caller's thread */
    for (uint32_t i = 0; i < batch->count; ++i) {
        pb_pipeline_job *job = &batch->jobs[i];
        const pb_pipeline_request *q = &job->request;
        if (job->result != VK_SUCCESS) {
            if (r == PB_OK) {
                char what[160];
                snprintf(what, sizeof what, "%s (kernel %s)", job->stage, q->what);
                r = err ? pb_vk_fail(ctx, err, job->result, what) : PB_ERROR_VULKAN;
            }
            continue;
        }
        ++ctx->pipelines_created;
        *q->out = job->made;
        if (cache_add(ctx, q->spirv, q->spirv_bytes, q->push_size, q->spec, q->spec_count, q->local_size, &job->made))
            q->out->cached = 1;
        /* driver compile time: on lavapipe the bake's kernels take most of a small bake's host time */
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "kernel %s: pipeline created in %.1f ms%s", q->what, job->ms,
                job->threaded ? " on a worker thread" : "");
    }
    if (r != PB_OK) /* all or nothing: the made ones stay cached, the caller's copies are cleared */
        for (uint32_t i = 0; i < batch->count; ++i)
            pb_pipeline_destroy(ctx, batch->jobs[i].request.out);
    memset(batch, 0, sizeof *batch);
    return r;
}

pb_result pb_pipeline_create(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, uint32_t push_size,
                             const uint32_t *spec, uint32_t spec_count, uint32_t local_size, const char *what,
                             pb_pipeline *out, pb_error *err)
{
    pb_pipeline_request q = {spirv, spirv_bytes, push_size, spec, spec_count, local_size, what, out};
    pb_pipeline_batch batch;
    memset(&batch, 0, sizeof batch);
    pb_result r = batch_add(ctx, &batch, &q, 0, err); /* one kernel: made on this thread */
    return r == PB_OK ? pb_pipelines_end(ctx, &batch, err) : r;
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
