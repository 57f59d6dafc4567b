/* Upload of the scene and its BVH, in leaf order, and the trace pipelines.
 * Sizes are checked against the device before anything is allocated. */
#include "bake/gpu_scene.h"
#include "bake/guide_cache.h"
#include "bake/light_cells_gpu.h"
#include "bake/normal_map.h"
#include "bake/shading_normals.h"
#include "common/common.h"
#include "probebake/scene.h"


#include <stdlib.h>
#include <string.h>

/* The texel views of nodes and triangles and the descriptor set holding
 * them. Made whichever loads the kernels use (they name the views either
 * way); views longer than the device allows are cut, and the kernels then
 * read through addresses. */
static pb_result make_scene_set(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, pb_error *err)
{
    uint64_t max_texels = ctx->limits.maxTexelBufferElements;
    uint64_t node_texels = gs->nodes.size / 16, tri_texels = gs->tris.size / 16;
    int fits = node_texels <= max_texels && tri_texels <= max_texels;
    if (ctx->scene_texels && !fits && ctx->desc.scene_loads == PB_SCENE_LOADS_TEXEL)
        return pb_fail(err, PB_ERROR_TOO_LARGE,
                       "%s: texel loads need %llu texels for the BVH and %llu for its triangles; device %s allows "
                       "%llu (maxTexelBufferElements): use address loads (--scene-loads address)",
                       scene->path[0] ? scene->path : "scene",
                       (unsigned long long)node_texels, (unsigned long long)tri_texels, ctx->info.name,
                       (unsigned long long)max_texels);
    gs->texel_loads = ctx->scene_texels && fits;
    if (ctx->scene_texels && !fits)
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "%s: over the device's %llu texels per view: address loads",
                scene->path[0] ? scene->path : "scene", (unsigned long long)max_texels);
    VkBufferViewCreateInfo bv = {VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    bv.format = VK_FORMAT_R32G32B32A32_UINT;
    bv.buffer = gs->nodes.buffer;
    bv.range = 16 * (node_texels < max_texels ? node_texels : max_texels);
    VkResult vr = ctx->vk.vkCreateBufferView(ctx->device, &bv, NULL, &gs->node_view);
    if (vr == VK_SUCCESS) {
        bv.buffer = gs->tris.buffer;
        bv.range = 16 * (tri_texels < max_texels ? tri_texels : max_texels);
        vr = ctx->vk.vkCreateBufferView(ctx->device, &bv, NULL, &gs->tri_view);
    }
    VkDescriptorPoolSize ps = {VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 2};
    VkDescriptorPoolCreateInfo dp = {VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dp.maxSets = 1;
    dp.poolSizeCount = 1;
    dp.pPoolSizes = &ps;
    if (vr == VK_SUCCESS)
        vr = ctx->vk.vkCreateDescriptorPool(ctx->device, &dp, NULL, &gs->set_pool);
    VkDescriptorSetAllocateInfo da = {VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    da.descriptorPool = gs->set_pool;
    da.descriptorSetCount = 1;
    da.pSetLayouts = &ctx->scene_set_layout;
    if (vr == VK_SUCCESS)
        vr = ctx->vk.vkAllocateDescriptorSets(ctx->device, &da, &gs->set);
    if (vr != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "scene texel views");
    VkWriteDescriptorSet w[2] = {{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}, {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}};
    for (uint32_t i = 0; i < 2; ++i) {
        w[i].dstSet = gs->set;
        w[i].dstBinding = i;
        w[i].descriptorCount = 1;
        w[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
        w[i].pTexelBufferView = i ? &gs->tri_view : &gs->node_view;
    }
    ctx->vk.vkUpdateDescriptorSets(ctx->device, 2, w, 0, NULL);
    return PB_OK;
}

static pb_result upload_array(pb_context *ctx, pb_buffer *b, const void *data, uint64_t bytes, const char *what,
                              pb_error *err)
{
    pb_result r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, what, b, err);
    if (r == PB_OK && bytes)
        r = pb_buffer_upload(ctx, b, 0, data, bytes, err);
    return r;
}

/* The per-triangle records, triangle k in the BVH's leaf order. */
typedef struct scene_fill {
    const pb_scene *scene;
    const pb_bvh *bvh;
} scene_fill;

static void fill_tris(void *user, void *out, uint64_t first, uint64_t n)
{
    const scene_fill *f = user;
    gpu_tri *t = out;
    for (uint64_t i = 0; i < n; ++i) {
        uint64_t k = first + i;
        uint32_t m = f->scene->material[f->bvh->tri_order[k]];
        const pb_material *pm = &f->scene->materials[m];
        memcpy(t[i].v, f->bvh->tri_positions + 9 * k, 36); /* the BVH's positions are in leaf order already */
        /* thin glass is opaque to the traversal: glass_step (bake.glsl) lets rays through */
        t[i].flags = m | (pm->alpha_mode != PB_ALPHA_OPAQUE && !(pm->transmission > 0.f) ? PB_FLAG_ALPHA_MASK : 0u);
    }
}

static void fill_uvs(void *user, void *out, uint64_t first, uint64_t n)
{
    const scene_fill *f = user;
    for (uint64_t i = 0; i < n; ++i)
        memcpy((float *)out + 6 * i, f->scene->texcoords + 6 * (size_t)f->bvh->tri_order[first + i], 24);
}

static void fill_colors(void *user, void *out, uint64_t first, uint64_t n)
{
    const scene_fill *f = user;
    for (uint64_t i = 0; i < n; ++i)
        memcpy((float *)out + 12 * i, f->scene->colors + 12 * (size_t)f->bvh->tri_order[first + i], 48);
}

static void fill_tangents(void *user, void *out, uint64_t first, uint64_t n)
{
    const scene_fill *f = user;
    for (uint64_t i = 0; i < n; ++i)
        pb_tangents_pack(f->scene->tangents + 12 * (size_t)f->bvh->tri_order[first + i], (uint32_t *)out + 4 * i);
}

static void fill_normals(void *user, void *out, uint64_t first, uint64_t n)
{
    const scene_fill *f = user;
    for (uint64_t i = 0; i < n; ++i) {
        const float *nv = f->scene->normals + 9 * (size_t)f->bvh->tri_order[first + i];
        for (int v = 0; v < 3; ++v)
            ((uint32_t *)out)[3 * i + v] = pb_normal_pack(nv + 3 * v);
    }
}

pb_result pb_gpu_scene_create(pb_context *ctx, const pb_scene *scene, const pb_bvh *bvh, pb_gpu_scene **out,
                              pb_error *err)
{
    pb_error_clear(err);
    *out = NULL;
    if (bvh->triangle_count != scene->triangle_count)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "BVH (%u triangles) does not belong to scene %s (%u)",
                       bvh->triangle_count, scene->path, scene->triangle_count);
    if (bvh->stats.depth > PB_BVH_MAX_DEPTH || bvh->stats.wide_depth > PB_BVH_MAX_DEPTH)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "BVH depth %u exceeds %d", bvh->stats.depth, PB_BVH_MAX_DEPTH);
    uint32_t n = scene->triangle_count;
    int smooth = pb_scene_bent_triangles(scene) != 0; /* else the kernels keep the face normals */
    int glass = pb_scene_glass_materials(scene) != 0; /* else the kernels compile glass_step out */
    int mapped = pb_scene_normal_mapped(scene) != 0;  /* else the kernels compile normal maps out */
    int tangents = mapped && scene->tangents;         /* else every normal map's frame is from the UVs */
    uint64_t sizes[6] = {
        (uint64_t)bvh->wide_node_count * sizeof(pb_bvh4_node),
        (uint64_t)n * sizeof(gpu_tri) + 16u, /* + a texel: the last record's texels end 8 bytes past it */
        (uint64_t)n * ((scene->colors ? 72u : 24u) + (smooth ? 12u : 0u) + (tangents ? 16u : 0u)),
        (uint64_t)scene->material_count * sizeof(gpu_material),
        (uint64_t)scene->texture_count * sizeof(gpu_texture),
        scene->texel_count * 4u,
    };
    static const char *const names[6] = {"BVH nodes", "triangles",
                                         "texture coordinates, vertex colours, normals and tangents",
                                         "materials", "textures", "texels"};
    uint64_t total = 0;
    for (int i = 0; i < 6; ++i) {
        total += sizes[i];
        if (ctx->max_allocation && sizes[i] > ctx->max_allocation)
            return pb_fail(err, PB_ERROR_TOO_LARGE,
                           "%s: %s needs %.1f MiB in one allocation; device %s allows %.1f MiB "
                           "(maxMemoryAllocationSize)", scene->path, names[i], sizes[i] / 1048576.0,
                           ctx->info.name, ctx->max_allocation / 1048576.0);
    }
    if (ctx->info.device_local_bytes && total > ctx->info.device_local_bytes / 10 * 9)
        return pb_fail(err, PB_ERROR_TOO_LARGE, "%s: scene needs %.1f MiB of device memory; device %s has %.1f MiB",
                       scene->path, total / 1048576.0, ctx->info.name, ctx->info.device_local_bytes / 1048576.0);
    if (scene->texel_count > UINT32_MAX)
        return pb_fail(err, PB_ERROR_TOO_LARGE, "%s: more than 2^32 texels", scene->path);

    pb_gpu_scene *gs = calloc(1, sizeof *gs);
    gpu_material *mats = malloc((size_t)(scene->material_count ? scene->material_count : 1) * sizeof *mats);
    gpu_texture *texs = malloc((size_t)(scene->texture_count ? scene->texture_count : 1) * sizeof *texs);
    if (gs)
        gs->tri_order = pb_malloc_large((size_t)(n ? n : 1) * 4);
    if (!gs || !mats || !texs || !gs->tri_order) {
        free(mats), free(texs);
        if (gs)
            free(gs->tri_order);
        free(gs);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory preparing the scene upload");
    }
    for (uint32_t m = 0; m < scene->material_count; ++m) {
        const pb_material *pm = &scene->materials[m];
        mats[m] = (gpu_material){pm->base_color[3], pm->alpha_cutoff, pm->base_color_texture, pm->alpha_mode};
    }
    for (uint32_t t = 0; t < scene->texture_count; ++t) {
        const pb_texture *pt = &scene->textures[t];
        texs[t] = (gpu_texture){(uint32_t)pt->offset, pt->width, pt->height, pt->wrap_s | (pt->wrap_t << 8)};
    }
    memcpy(gs->tri_order, bvh->tri_order, (size_t)n * 4);
    gs->triangle_count = n;
    gs->stack_size = PB_BVH_STACK_SIZE(bvh->stats.wide_depth);

    /* The per-triangle arrays are made where the device reads them, on all
     * host cores (pb_buffer_fill), in tri_uv's layout (scene.glsl's
     * SceneRefs): texture coordinates, vertex colours, packed normals. */
    const scene_fill f = {scene, bvh};
    const uint64_t uv_bytes = (uint64_t)n * 24u, color_bytes = scene->colors ? (uint64_t)n * 48u : 0u;
    static const uint32_t zero_texel[4];
    pb_result r = upload_array(ctx, &gs->nodes, bvh->wide_nodes, sizes[0], names[0], err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, sizes[1], PB_MEMORY_DEVICE, names[1], &gs->tris, err);
    if (r == PB_OK)
        r = pb_buffer_fill(ctx, &gs->tris, 0, sizeof(gpu_tri), n, fill_tris, (void *)&f, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &gs->tris, (uint64_t)n * sizeof(gpu_tri), zero_texel, 16, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, sizes[2], PB_MEMORY_DEVICE, names[2], &gs->tri_uv, err);
    /* only a texture reads texture coordinates (surface_uv in scene.glsl):
     * a scene without one leaves them unwritten (the terrain's 100 MB) */
    if (r == PB_OK && scene->texture_count)
        r = pb_buffer_fill(ctx, &gs->tri_uv, 0, 24, n, fill_uvs, (void *)&f, err);
    if (r == PB_OK && scene->colors)
        r = pb_buffer_fill(ctx, &gs->tri_uv, uv_bytes, 48, n, fill_colors, (void *)&f, err);
    if (r == PB_OK && smooth)
        r = pb_buffer_fill(ctx, &gs->tri_uv, uv_bytes + color_bytes, 12, n, fill_normals, (void *)&f, err);
    if (r == PB_OK && tangents)
        r = pb_buffer_fill(ctx, &gs->tri_uv, uv_bytes + color_bytes + (smooth ? (uint64_t)n * 12u : 0u), 16, n,
                           fill_tangents, (void *)&f, err);
    if (r == PB_OK) r = upload_array(ctx, &gs->materials, mats, sizes[3], names[3], err);
    if (r == PB_OK) r = upload_array(ctx, &gs->textures, texs, sizes[4], names[4], err);
    if (r == PB_OK) r = upload_array(ctx, &gs->texels, scene->texels, sizes[5], names[5], err);
    free(mats), free(texs);
    if (r == PB_OK)
        r = make_scene_set(ctx, scene, gs, err);
    if (r != PB_OK) {
        pb_gpu_scene_destroy_ctx(ctx, gs);
        return r;
    }
    gs->refs = (gpu_scene_refs){gs->nodes.address, gs->tris.address, gs->tri_uv.address, gs->materials.address,
                                gs->textures.address, gs->texels.address, n,
                                (scene->colors ? PB_SCENE_VERTEX_COLORS : 0u) |
                                    (smooth ? PB_SCENE_SHADING_NORMALS : 0u) | (glass ? PB_SCENE_TRANSMISSION : 0u) |
                                    (mapped ? PB_SCENE_NORMAL_MAPS : 0u) | (tangents ? PB_SCENE_TANGENTS : 0u)};
    gs->ctx = ctx;
    gs->bvh = bvh;
    gs->bytes = total;
    gs->traversal_bytes = sizes[0] + sizes[1];
    *out = gs;
    return PB_OK;
}

void pb_gpu_scene_destroy_ctx(pb_context *ctx, pb_gpu_scene *gs)
{
    pb_light_cells_gpu_free(ctx, gs->light_cells);
    pb_guide_cache_destroy(gs->guide_cache);
    pb_pipeline_destroy(ctx, &gs->trace_closest);
    pb_pipeline_destroy(ctx, &gs->trace_any);
    pb_buffer *bufs[8] = {&gs->nodes, &gs->tris, &gs->tri_uv, &gs->materials, &gs->textures, &gs->texels,
                          &gs->rays, &gs->hits};
    for (int i = 0; i < 8; ++i)
        pb_buffer_destroy(ctx, bufs[i]);
    if (gs->set_pool)
        ctx->vk.vkDestroyDescriptorPool(ctx->device, gs->set_pool, NULL);
    if (gs->node_view)
        ctx->vk.vkDestroyBufferView(ctx->device, gs->node_view, NULL);
    if (gs->tri_view)
        ctx->vk.vkDestroyBufferView(ctx->device, gs->tri_view, NULL);
    free(gs->tri_order);
    free(gs);
}

void pb_gpu_scene_destroy(pb_gpu_scene *gs)
{
    if (gs)
        pb_gpu_scene_destroy_ctx(gs->ctx, gs);
}

uint64_t pb_gpu_scene_bytes(const pb_gpu_scene *gs, uint64_t *traversal_bytes)
{
    if (traversal_bytes)
        *traversal_bytes = gs->traversal_bytes;
    return gs->bytes;
}
