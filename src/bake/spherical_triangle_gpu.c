/* pb_spherical_triangle_gpu: the spherical_triangle.comp kernel over a
 * batch of inputs. Small and synchronous: it exists to test
 * shaders/include/spherical_triangle.glsl against spherical_triangle.c. */
#include "bake/spherical_triangle.h"
#include "gpu/gpu.h"

#include "spherical_triangle.spv.h"

pb_result pb_spherical_triangle_gpu(pb_context *ctx, const float *inputs, uint32_t count, float *out, pb_error *err)
{
    return pb_gpu_batch(ctx, pb_spv_spherical_triangle, sizeof pb_spv_spherical_triangle, "spherical_triangle", NULL, 0,
                        inputs, 80, out, 16, count, err);
}
