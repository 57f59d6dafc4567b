/* Buffers: every one has a device address (arrays are reached through
 * GL_EXT_buffer_reference, so no binding range limits scene size) and stays
 * mapped when its memory is host-visible. On UMA devices (lavapipe,
 * integrated GPUs) device-local memory is host-visible and uploads are a
 * memcpy; elsewhere they go through a staging buffer. */
#include "common/common.h"
#include "gpu/gpu.h"

#include <stdio.h>
#include <string.h>

#define STAGING_CHUNK (16u << 20)

static int find_memory(const VkPhysicalDeviceMemoryProperties *mp, uint32_t type_bits, VkMemoryPropertyFlags need,
                       VkMemoryPropertyFlags want)
{
    int fallback = -1;
    for (uint32_t i = 0; i < mp->memoryTypeCount; ++i) {
        VkMemoryPropertyFlags f = mp->memoryTypes[i].propertyFlags;
        if (!(type_bits & (1u << i)) || (f & need) != need)
            continue;
        if ((f & want) == want)
            return (int)i;
        if (fallback < 0)
            fallback = (int)i;
    }
    return fallback;
}

pb_memory_choice pb_buffer_memory_choice(const VkPhysicalDeviceMemoryProperties *mp, uint32_t type_bits,
                                         pb_memory_kind kind, int force_staging)
{
    const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    /* Device memory is mapped only where it is also host-cached (UMA: lavapipe,
     * integrated GPUs). A discrete GPU with resizable BAR offers device-local
     * host-visible memory too, but uncached: reading results back through it
     * ran at 1.2 Mrays/s against 1,230 in the kernel on an H100. */
    const VkMemoryPropertyFlags uma = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | host | VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
    pb_memory_choice c = {-1, 0};
    if (kind == PB_MEMORY_DEVICE)
        c.type = find_memory(mp, type_bits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, uma);
    else if (kind == PB_MEMORY_UPLOAD)
        c.type = find_memory(mp, type_bits, host, host);
    else
        c.type = find_memory(mp, type_bits, host, host | VK_MEMORY_PROPERTY_HOST_CACHED_BIT);
    if (c.type < 0)
        c.type = find_memory(mp, type_bits, kind == PB_MEMORY_DEVICE ? 0 : host, 0);
    if (c.type < 0)
        return c;
    VkMemoryPropertyFlags f = mp->memoryTypes[c.type].propertyFlags;
    c.mapped = kind == PB_MEMORY_DEVICE ? (f & uma) == uma && !force_staging : (f & host) == host;
    return c;
}

pb_result pb_buffer_create(pb_context *ctx, VkDeviceSize size, pb_memory_kind kind, const char *what, pb_buffer *out,
                           pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (size == 0)
        size = 16; /* empty arrays still get a valid address */
    if (ctx->max_allocation && size > ctx->max_allocation)
        return pb_fail(err, PB_ERROR_TOO_LARGE,
                       "%s: %s needs %.1f MiB in one allocation, over the device's maxMemoryAllocationSize of "
                       "%.1f MiB", ctx->info.name, what, size / 1048576.0, ctx->max_allocation / 1048576.0);
    VkBufferCreateInfo bci = {VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = size;
    /* texel buffers: the scene's BVH views (gpu_scene.c); harmless on the rest */
    bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT |
                VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    VkResult vr = ctx->vk.vkCreateBuffer(ctx->device, &bci, NULL, &out->buffer);
    if (vr != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, what);
    VkMemoryRequirements req;
    ctx->vk.vkGetBufferMemoryRequirements(ctx->device, out->buffer, &req);
    pb_memory_choice mc = pb_buffer_memory_choice(&ctx->memory, req.memoryTypeBits, kind, (int)ctx->desc.force_staging);
    int type = mc.type;
    if (type < 0) {
        pb_buffer_destroy(ctx, out);
        return pb_fail(err, PB_ERROR_VULKAN, "%s: no memory type for %s", ctx->info.name, what);
    }
    VkMemoryAllocateFlagsInfo flags = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo mai = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &flags};
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = (uint32_t)type;
    vr = ++ctx->allocations == ctx->desc.fail_allocation ? VK_ERROR_OUT_OF_DEVICE_MEMORY
                                                         : ctx->vk.vkAllocateMemory(ctx->device, &mai, NULL, &out->memory);
    if (vr != VK_SUCCESS) {
        pb_buffer_destroy(ctx, out);
        char w[160];
        snprintf(w, sizeof w, "allocation of %.1f MiB for %s", req.size / 1048576.0, what);
        return pb_vk_fail(ctx, err, vr, w);
    }
    if ((vr = ctx->vk.vkBindBufferMemory(ctx->device, out->buffer, out->memory, 0)) != VK_SUCCESS) {
        pb_buffer_destroy(ctx, out);
        return pb_vk_fail(ctx, err, vr, what);
    }
    VkMemoryPropertyFlags f = ctx->memory.memoryTypes[type].propertyFlags;
    if (mc.mapped) {
        if ((vr = ctx->vk.vkMapMemory(ctx->device, out->memory, 0, VK_WHOLE_SIZE, 0, &out->mapped)) != VK_SUCCESS) {
            pb_buffer_destroy(ctx, out);
            return pb_vk_fail(ctx, err, vr, what);
        }
    }
    out->device_local = (f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) != 0;
    VkBufferDeviceAddressInfo ai = {VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    ai.buffer = out->buffer;
    out->address = ctx->vk.vkGetBufferDeviceAddress(ctx->device, &ai);
    out->size = size;
    if (kind == PB_MEMORY_DEVICE)
        ctx->allocated += req.size;
    return PB_OK;
}

void pb_buffer_destroy(pb_context *ctx, pb_buffer *b)
{
    if (b->buffer)
        ctx->vk.vkDestroyBuffer(ctx->device, b->buffer, NULL);
    if (b->memory)
        ctx->vk.vkFreeMemory(ctx->device, b->memory, NULL); /* unmaps implicitly */
    memset(b, 0, sizeof *b);
}

/* Copies between host memory and a buffer that is not mapped, in chunks
 * through one staging buffer, one submission per chunk. */
static pb_result staged_copy(pb_context *ctx, const pb_buffer *buf, VkDeviceSize offset, void *host, VkDeviceSize size,
                             int to_device, pb_error *err)
{
    pb_buffer staging;
    VkDeviceSize chunk = size < STAGING_CHUNK ? size : STAGING_CHUNK;
    pb_result r = pb_buffer_create(ctx, chunk, to_device ? PB_MEMORY_UPLOAD : PB_MEMORY_DOWNLOAD, "staging buffer",
                                   &staging, err);
    if (r != PB_OK)
        return r;
    for (VkDeviceSize done = 0; done < size && r == PB_OK; done += chunk) {
        VkDeviceSize n = size - done < chunk ? size - done : chunk;
        char *h = (char *)host + done;
        if (to_device)
            memcpy(staging.mapped, h, (size_t)n);
        if ((r = pb_cmd_begin(ctx, err)) != PB_OK)
            break;
        if (to_device)
            pb_cmd_copy(ctx, &staging, 0, buf, offset + done, n);
        else
            pb_cmd_copy(ctx, buf, offset + done, &staging, 0, n);
        pb_cmd_barrier_to_host(ctx);
        r = pb_cmd_submit_wait(ctx, NULL, err);
        if (r == PB_OK && !to_device)
            memcpy(h, staging.mapped, (size_t)n);
    }
    pb_buffer_destroy(ctx, &staging);
    return r;
}

pb_result pb_buffer_upload(pb_context *ctx, pb_buffer *dst, VkDeviceSize offset, const void *data, VkDeviceSize size,
                           pb_error *err)
{
    if (size == 0)
        return PB_OK;
    if (offset + size > dst->size)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "upload past the end of a buffer");
    if (dst->mapped) {
        memcpy((char *)dst->mapped + offset, data, (size_t)size);
        return PB_OK;
    }
    return staged_copy(ctx, dst, offset, (void *)data, size, 1, err); /* not written through when uploading */
}

typedef struct fill_job {
    pb_fill_fn fill;
    void *user;
    char *base;            /* where record `first` goes */
    uint64_t first;
    uint32_t record_bytes;
} fill_job;

static void fill_range(void *arg, uint64_t begin, uint64_t end)
{
    const fill_job *j = arg;
    j->fill(j->user, j->base + begin * j->record_bytes, j->first + begin, end - begin);
}

#define FILL_GRAIN 16384u /* records per block handed to a thread */

pb_result pb_buffer_fill(pb_context *ctx, pb_buffer *dst, VkDeviceSize offset, uint32_t record_bytes, uint64_t count,
                         pb_fill_fn fill, void *user, pb_error *err)
{
    if (count == 0)
        return PB_OK;
    if (record_bytes == 0 || offset > dst->size || count > (dst->size - offset) / record_bytes)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "fill past the end of a buffer");
    if (dst->mapped) {
        fill_job j = {fill, user, (char *)dst->mapped + offset, 0, record_bytes};
        pb_parallel_for(count, FILL_GRAIN, 0, fill_range, &j);
        return PB_OK;
    }
    uint64_t per_chunk = STAGING_CHUNK / record_bytes ? STAGING_CHUNK / record_bytes : 1; /* whole records */
    if (per_chunk > count)
        per_chunk = count;
    pb_buffer staging;
    pb_result r = pb_buffer_create(ctx, per_chunk * record_bytes, PB_MEMORY_UPLOAD, "staging buffer", &staging, err);
    for (uint64_t first = 0; r == PB_OK && first < count; first += per_chunk) {
        uint64_t n = count - first < per_chunk ? count - first : per_chunk;
        fill_job j = {fill, user, staging.mapped, first, record_bytes};
        pb_parallel_for(n, FILL_GRAIN, 0, fill_range, &j);
        if ((r = pb_cmd_begin(ctx, err)) != PB_OK)
            break;
        pb_cmd_copy(ctx, &staging, 0, dst, offset + first * record_bytes, n * record_bytes);
        pb_cmd_barrier_to_host(ctx);
        r = pb_cmd_submit_wait(ctx, NULL, err);
    }
    pb_buffer_destroy(ctx, &staging); /* zeroed by a failed create */
    return r;
}

pb_result pb_buffer_download(pb_context *ctx, const pb_buffer *src, VkDeviceSize offset, void *data, VkDeviceSize size,
                             pb_error *err)
{
    if (size == 0)
        return PB_OK;
    if (offset + size > src->size)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "download past the end of a buffer");
    if (src->mapped) {
        memcpy(data, (const char *)src->mapped + offset, (size_t)size);
        return PB_OK;
    }
    return staged_copy(ctx, src, offset, data, size, 0, err);
}
