/* pb_offset_ray_origins_gpu: the ray_offset.comp kernel over a batch of
 * points. Small and synchronous: it exists to test shaders/include/
 * ray_offset.glsl against pb_offset_ray_origin, which the bake's kernels use. */
#include "bake/gpu_types.h"
#include "common/common.h"
#include "gpu/gpu.h"

#include "ray_offset.spv.h"

#include <stdlib.h>
#include <string.h>

pb_result pb_offset_ray_origins_gpu(pb_context *ctx, const float *points, const float *normals, uint32_t count,
                                    float *origins, pb_error *err)
{
    pb_error_clear(err);
    if (count == 0)
        return PB_OK;
    uint64_t bytes = (uint64_t)count * 16;
    pb_buffer in_p = {0}, in_n = {0}, out = {0}, down = {0};
    pb_pipeline pipe = {0};
    float *tmp = malloc((size_t)bytes);
    if (!tmp)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    pb_result r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, "offset points", &in_p, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, "offset normals", &in_n, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, "offset origins", &out, err);
    for (int pass = 0; pass < 2 && r == PB_OK; ++pass) {
        const float *src = pass ? normals : points;
        for (uint32_t i = 0; i < count; ++i) {
            memcpy(tmp + 4 * (size_t)i, src + 3 * (size_t)i, 12);
            tmp[4 * (size_t)i + 3] = 0.f;
        }
        r = pb_buffer_upload(ctx, pass ? &in_n : &in_p, 0, tmp, bytes, err);
    }
    if (r == PB_OK)
        r = pb_pipeline_create(ctx, pb_spv_ray_offset, sizeof pb_spv_ray_offset, sizeof(ray_offset_push), NULL, 0,
                               64, "ray_offset", &pipe, err);
    if (r == PB_OK && !out.mapped)
        r = pb_buffer_create(ctx, bytes, PB_MEMORY_DOWNLOAD, "offset download", &down, err);
    if (r == PB_OK)
        r = pb_cmd_begin(ctx, err);
    if (r == PB_OK) {
        ray_offset_push push = {in_p.address, in_n.address, out.address, count, 0};
        pb_cmd_dispatch(ctx, &pipe, &push, (count + 63) / 64);
        if (!out.mapped) {
            pb_cmd_barrier(ctx);
            pb_cmd_copy(ctx, &out, 0, &down, 0, bytes);
        }
        pb_cmd_barrier_to_host(ctx);
        r = pb_cmd_submit_wait(ctx, NULL, err);
    }
    if (r == PB_OK) {
        const float *res = out.mapped ? out.mapped : down.mapped;
        for (uint32_t i = 0; i < count; ++i)
            memcpy(origins + 3 * (size_t)i, res + 4 * (size_t)i, 12);
    }
    pb_pipeline_destroy(ctx, &pipe);
    pb_buffer_destroy(ctx, &in_p);
    pb_buffer_destroy(ctx, &in_n);
    pb_buffer_destroy(ctx, &out);
    pb_buffer_destroy(ctx, &down);
    free(tmp);
    return r;
}
