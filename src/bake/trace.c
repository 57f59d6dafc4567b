/* pb_trace: rays through trace.comp in bounded submissions. Each submission
 * carries at most rays_per_submit rays: copy in (when the device is not
 * UMA), dispatch between two timestamps, copy out. */
#include "bake/gpu_scene.h"
#include "gpu/gpu.h"

#include "trace.spv.h"
#include "trace_native64.spv.h"
#include "common/common.h"

#include <string.h>

static pb_result ensure_capacity(pb_context *ctx, pb_gpu_scene *gs, uint32_t rays, pb_error *err)
{
    if (gs->ray_capacity >= rays)
        return PB_OK;
    pb_buffer_destroy(ctx, &gs->rays);
    pb_buffer_destroy(ctx, &gs->hits);
    gs->ray_capacity = 0;
    pb_result r = pb_buffer_create(ctx, (uint64_t)rays * sizeof(pb_ray), PB_MEMORY_DEVICE, "ray buffer", &gs->rays, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, (uint64_t)rays * sizeof(pb_hit), PB_MEMORY_DEVICE, "hit buffer", &gs->hits, err);
    if (r == PB_OK)
        gs->ray_capacity = rays;
    return r;
}

pb_result pb_trace(pb_context *ctx, pb_gpu_scene *gs, const pb_ray *rays, uint32_t count, pb_trace_mode mode,
                   pb_hit *hits, pb_trace_stats *stats, pb_error *err)
{
    pb_error_clear(err);
    double t0 = pb_now_ms();
    pb_trace_stats st = {0};
    if (count == 0) {
        if (stats)
            *stats = st;
        return PB_OK;
    }
    uint32_t chunk = ctx->desc.rays_per_submit < count ? ctx->desc.rays_per_submit : count;
    pb_result r = ensure_capacity(ctx, gs, chunk, err);
    pb_buffer in_staging = {0}, out_staging = {0};
    int staged = !gs->rays.mapped || !gs->hits.mapped;
    if (r == PB_OK && staged) {
        r = pb_buffer_create(ctx, (uint64_t)chunk * sizeof(pb_ray), PB_MEMORY_UPLOAD, "ray staging", &in_staging, err);
        if (r == PB_OK)
            r = pb_buffer_create(ctx, (uint64_t)chunk * sizeof(pb_hit), PB_MEMORY_DOWNLOAD, "hit staging",
                                 &out_staging, err);
    }
    /* made on first use: a bake never traces through this kernel, and on
     * lavapipe each of the two costs 15-20 ms to create */
    pb_pipeline *pipe = mode == PB_TRACE_ANY ? &gs->trace_any : &gs->trace_closest;
    if (r == PB_OK && !pipe->pipeline) {
        uint32_t spec[3] = {gs->stack_size, gs->texel_loads, mode == PB_TRACE_ANY};
        r = pb_pipeline_create(ctx, PB_KERNEL_SPIRV(ctx, trace), sizeof(trace_push), spec, 3, 64,
                               mode == PB_TRACE_ANY ? "trace (any)" : "trace (closest)", pipe, err);
    }
    for (uint32_t done = 0; r == PB_OK && done < count; done += chunk) {
        uint32_t n = count - done < chunk ? count - done : chunk;
        memcpy(staged ? in_staging.mapped : gs->rays.mapped, rays + done, (size_t)n * sizeof(pb_ray));
        if ((r = pb_cmd_begin(ctx, err)) != PB_OK)
            break;
        if (staged) {
            pb_cmd_copy(ctx, &in_staging, 0, &gs->rays, 0, (uint64_t)n * sizeof(pb_ray));
            pb_cmd_barrier(ctx);
        }
        trace_push push = {gs->refs, gs->rays.address, gs->hits.address, n, pb_dispatch_spread((n + 63) / 64)};
        pb_cmd_timestamp(ctx);
        pb_cmd_bind_set(ctx, pipe, gs->set);
        pb_cmd_dispatch(ctx, pipe, &push, (n + 63) / 64);
        pb_cmd_timestamp(ctx);
        if (staged) {
            pb_cmd_barrier(ctx);
            pb_cmd_copy(ctx, &gs->hits, 0, &out_staging, 0, (uint64_t)n * sizeof(pb_hit));
        }
        pb_cmd_barrier_to_host(ctx);
        double ms = 0;
        if ((r = pb_cmd_submit_wait(ctx, &ms, err)) != PB_OK)
            break;
        st.kernel_ms += ms;
        st.submits++;
        memcpy(hits + done, staged ? out_staging.mapped : gs->hits.mapped, (size_t)n * sizeof(pb_hit));
        for (uint32_t i = done; i < done + n; ++i)
            if (hits[i].triangle != PB_NO_HIT)
                hits[i].triangle = hits[i].triangle < gs->triangle_count ? gs->tri_order[hits[i].triangle]
                                                                         : PB_NO_HIT;
    }
    pb_buffer_destroy(ctx, &in_staging);
    pb_buffer_destroy(ctx, &out_staging);
    st.wall_ms = pb_now_ms() - t0;
    if (stats)
        *stats = st;
    return r;
}
