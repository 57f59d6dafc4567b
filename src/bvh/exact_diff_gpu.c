/* pb_exact_diff_gpu: the exact_diff.comp kernel over a batch of inputs.
 * Small and synchronous: it exists to test shaders/include/exact_diff.glsl
 * against pb_exact_diff bit for bit, on inputs traversal rarely reaches. */
#include "bvh/exact_diff.h"
#include "gpu/gpu.h"

#include "exact_diff.spv.h"

pb_result pb_exact_diff_gpu(pb_context *ctx, const float *abcd, uint32_t count, float *out, pb_error *err)
{
    return pb_gpu_batch(ctx, pb_spv_exact_diff, sizeof pb_spv_exact_diff, "exact_diff", NULL, 0, abcd, 16, out, 4, count,
                        err);
}
