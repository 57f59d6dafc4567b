/* pb_spherical_triangle_gpu: the spherical_triangle.comp kernel over a
 * batch of inputs. Small and synchronous: it exists to test
 * shaders/include/spherical_triangle.glsl against spherical_triangle.c. */
#include "bake/spherical_triangle.h"
#include "common/common.h"
#include "gpu/gpu.h"

#include "spherical_triangle.spv.h"

#include <string.h>

typedef struct spherical_triangle_push {
    uint64_t inputs;  /* 5 vec4 per entry */
    uint64_t outputs; /* vec4 per entry */
    uint32_t count, pad[3];
} spherical_triangle_push;
_Static_assert(sizeof(spherical_triangle_push) == 32, "spherical_triangle.comp push constants");

pb_result pb_spherical_triangle_gpu(pb_context *ctx, const float *inputs, uint32_t count, float *out, pb_error *err)
{
    pb_error_clear(err);
    if (count == 0)
        return PB_OK;
    uint64_t in_bytes = (uint64_t)count * 80, out_bytes = (uint64_t)count * 16;
    pb_buffer in = {0}, res = {0};
    pb_pipeline pipe = {0};
    pb_result r = pb_buffer_create(ctx, in_bytes, PB_MEMORY_DEVICE, "spherical_triangle inputs", &in, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, out_bytes, PB_MEMORY_DOWNLOAD, "spherical_triangle outputs", &res, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &in, 0, inputs, in_bytes, err);
    if (r == PB_OK)
        r = pb_pipeline_create(ctx, pb_spv_spherical_triangle, sizeof pb_spv_spherical_triangle,
                               sizeof(spherical_triangle_push), NULL, 0, 64, "spherical_triangle", &pipe, err);
    if (r == PB_OK)
        r = pb_cmd_begin(ctx, err);
    if (r == PB_OK) {
        spherical_triangle_push push = {in.address, res.address, count, {0, 0, 0}};
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
