/* pb_render: the render kernel over the image in bands of rows (each
 * submission bounded by rays_per_submit camera paths). */
#include "bake/shading.h"
#include "common/common.h"
#include "common/vec3.h"
#include "probebake/render.h"
#include "render/render_types.h"

#include "render.spv.h"
#include "render_native64.spv.h"

#define PB_RENDER_SAMPLES_PER_DISPATCH 4u

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void normalize3(float v[3])
{
    float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k)
        v[k] = l > 0.f ? v[k] / l : 0.f;
}

void pb_render_camera_basis(const pb_camera_view *c, uint32_t width, uint32_t height, float fwd[3], float right[3],
                            float up[3])
{
    memcpy(fwd, c->forward, 12);
    normalize3(fwd);
    pb_cross3(fwd, c->up, right);
    normalize3(right);
    pb_cross3(right, fwd, up);
    float t = tanf(0.5f * c->yfov), aspect = (float)width / (float)height;
    for (int k = 0; k < 3; ++k)
        right[k] *= t * aspect, up[k] *= t;
}

void pb_camera_from_scene(const pb_camera *c, pb_camera_view *out)
{
    memcpy(out->eye, c->position, 12);
    memcpy(out->forward, c->forward, 12);
    memcpy(out->up, c->up, 12);
    out->yfov = c->perspective && c->yfov > 0.f ? c->yfov : 0.8f;
}

void pb_render_defaults(pb_render_desc *d)
{
    if (!d->spp)
        d->spp = d->mode == PB_RENDER_REFERENCE ? 64 : 1;
    if (!d->bounces)
        d->bounces = 8;
}

pb_result pb_render_check(const pb_render_desc *d, pb_error *err)
{
    if (d->width < 1 || d->height < 1 || d->width > 16384 || d->height > 16384)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "image size %ux%u: each side must be 1..16384", d->width,
                       d->height);
    if (!(d->camera.yfov > 1e-4f && d->camera.yfov < 3.1415f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "field of view %g degrees: must be in (0, 180)",
                       d->camera.yfov * 57.29578f);
    float c[3];
    pb_cross3(d->camera.forward, d->camera.up, c);
    for (int k = 0; k < 3; ++k)
        if (!isfinite(d->camera.eye[k]) || !isfinite(d->camera.forward[k]) || !isfinite(d->camera.up[k]))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "camera position and directions must be finite");
    if (!(c[0] * c[0] + c[1] * c[1] + c[2] * c[2] > 1e-12f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "camera: the up vector is parallel to the view direction (or zero)");
    if (pb_render_reads_volume(d) && !d->volume)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "probes and indirect modes, and showing probes, need a volume");
    if (d->mode > PB_RENDER_INDIRECT)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "unknown render mode %u", (unsigned)d->mode);
    if (d->spp > 65536 || d->bounces > 64)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "spp at most 65536, bounces at most 64");
    return PB_OK;
}

pb_result pb_render(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_render_desc *desc, float *rgba,
                    float *direct, double *gpu_ms, pb_error *err)
{
    pb_error_clear(err);
    pb_result r = pb_render_check(desc, err);
    if (r == PB_OK)
        r = pb_bake_check_light(scene, desc->sky, desc->environment, err);
    if (r != PB_OK)
        return r;
    pb_render_desc d = *desc;
    pb_render_defaults(&d);
    uint64_t pixels = (uint64_t)d.width * d.height;
    uint32_t rows_per = (uint32_t)(ctx->desc.rays_per_submit / ((uint64_t)d.width * d.spp));
    rows_per = rows_per < 1 ? 1 : (rows_per > d.height ? d.height : rows_per);
    pb_shading sh;
    memset(&sh, 0, sizeof sh);
    pb_sample_buffers vb;
    memset(&vb, 0, sizeof vb);
    pb_buffer params = {0}, rparams = {0}, img = {0}, imgd = {0};
    pb_pipeline pipe = {0};
    r = pb_shading_create(ctx, scene, gs, d.sky, d.environment, 0, &sh, err);
    const pb_sample_buffers *volume = &vb; /* the caller's, or uploaded here for the call */
    if (r == PB_OK && d.volume && pb_render_reads_volume(&d)) {
        if (d.volume_buffers)
            volume = d.volume_buffers;
        else
            r = pb_sample_upload(ctx, d.volume, &vb, err);
    }
    if (r == PB_OK)
        r = pb_buffer_create(ctx, sizeof(gpu_bake_params), PB_MEMORY_UPLOAD, "render scene parameters", &params, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, sizeof(gpu_render_params) * ((d.spp + PB_RENDER_SAMPLES_PER_DISPATCH - 1) /
                                                               PB_RENDER_SAMPLES_PER_DISPATCH),
                             PB_MEMORY_UPLOAD, "render parameters", &rparams, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, pixels * 16, PB_MEMORY_DOWNLOAD, "image", &img, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, pixels * 16, PB_MEMORY_DOWNLOAD, "direct image", &imgd, err);
    uint32_t spec[2] = {gs->stack_size, gs->texel_loads};
    if (r == PB_OK)
        r = pb_pipeline_create(ctx, PB_KERNEL_SPIRV(ctx, render), 16, spec, 2, 64, "render", &pipe, err);
    if (r == PB_OK) {
        gpu_bake_params prm;
        memset(&prm, 0, sizeof prm);
        prm.scene = gs->refs;
        pb_shading_params(&sh, &prm);
        prm.emitters_by_area = d.emitters_by_area;
        memcpy(params.mapped, &prm, sizeof prm);
    }
    gpu_render_params rp;
    memset(&rp, 0, sizeof rp);
    float fwd[3], right[3], up[3];
    pb_render_camera_basis(&d.camera, d.width, d.height, fwd, right, up);
    memcpy(rp.eye, d.camera.eye, 12), memcpy(rp.forward, fwd, 12), memcpy(rp.right, right, 12), memcpy(rp.up, up, 12);
    rp.volume = volume->refs;
    rp.image = img.address, rp.image_direct = imgd.address;
    rp.width = d.width, rp.height = d.height, rp.spp = d.spp, rp.mode = (uint32_t)d.mode;
    rp.seed = d.seed, rp.bounces = d.bounces, rp.volume_direct = d.volume_direct;
    rp.show_probes = d.show_probes && d.volume;
    double ms = 0;
    /* Work is cut into submissions of about a quarter second (prompt
     * cancel, GPU watchdogs): bands of rows of about 16k pixels, and within
     * a band as many 4-sample dispatches as fit the time, adapted as it
     * goes (halved when slow, doubled when fast). */
    const uint32_t S = PB_RENDER_SAMPLES_PER_DISPATCH;
    uint32_t band_rows = (uint32_t)(16384u / d.width);
    band_rows = band_rows < 1 ? 1 : (band_rows > rows_per ? rows_per : band_rows);
    uint32_t groups_per_submit = 1; /* of S samples */
    uint64_t push0 = params.address;
    uint64_t work_done = 0, work_total = (uint64_t)d.height * d.spp;
    for (uint32_t row = 0; r == PB_OK && row < d.height; row += rp.rows) {
        rp.first_row = row;
        rp.rows = d.height - row < band_rows ? d.height - row : band_rows;
        for (uint32_t k = 0; k < d.spp; k += S) { /* one parameter record per dispatch of this band */
            gpu_render_params *mp = (gpu_render_params *)rparams.mapped + k / S;
            *mp = rp;
            mp->first_sample = k;
            mp->sample_count = d.spp - k < S ? d.spp - k : S;
        }
        for (uint32_t k0 = 0; r == PB_OK && k0 < d.spp;) {
            double t_submit = pb_now_ms();
            uint32_t k1 = k0 + groups_per_submit * S;
            k1 = k1 > d.spp ? d.spp : k1;
            if ((r = pb_cmd_begin(ctx, err)) != PB_OK)
                break;
            pb_cmd_timestamp(ctx);
            for (uint32_t k = k0; k < k1; k += S) {
                uint64_t pk[2] = {push0, rparams.address + (uint64_t)(k / S) * sizeof rp};
                if (k > k0)
                    pb_cmd_barrier(ctx);
                pb_cmd_bind_set(ctx, &pipe, gs->set);
                pb_cmd_dispatch(ctx, &pipe, pk, (rp.rows * d.width + 63) / 64);
            }
            pb_cmd_timestamp(ctx);
            pb_cmd_barrier_to_host(ctx);
            r = pb_cmd_submit_wait(ctx, NULL, err);
            if (r == PB_OK && ctx->interval_count >= 1)
                ms += ctx->intervals_ms[0];
            double took = pb_now_ms() - t_submit;
            if (took > 250.0 && groups_per_submit > 1)
                groups_per_submit /= 2;
            else if (took < 60.0 && groups_per_submit < 1024)
                groups_per_submit *= 2;
            work_done += (uint64_t)rp.rows * (k1 - k0);
            k0 = k1;
            if (r == PB_OK && d.progress && d.progress((float)work_done / (float)work_total, "rendering", d.progress_user))
                r = pb_fail(err, PB_ERROR_CANCELLED, "render cancelled");
        }
    }
    /* sums to means */
    if (r == PB_OK)
        for (uint64_t i = 0; i < 4 * pixels; ++i) {
            ((float *)img.mapped)[i] /= (float)d.spp;
            ((float *)imgd.mapped)[i] /= (float)d.spp;
        }
    if (r == PB_OK) {
        memcpy(rgba, img.mapped, (size_t)pixels * 16);
        if (direct)
            memcpy(direct, imgd.mapped, (size_t)pixels * 16);
        for (uint64_t i = 0; i < 4 * pixels; ++i)
            if (!isfinite(rgba[i]) || (direct && !isfinite(direct[i]))) {
                r = pb_fail(err, PB_ERROR_VULKAN, "render produced a non-finite pixel (%llu)",
                            (unsigned long long)(i / 4));
                break;
            }
    }
    if (gpu_ms)
        *gpu_ms = ms;
    pb_pipeline_destroy(ctx, &pipe);
    pb_buffer_destroy(ctx, &params), pb_buffer_destroy(ctx, &rparams);
    pb_buffer_destroy(ctx, &img), pb_buffer_destroy(ctx, &imgd);
    pb_sample_release(ctx, &vb);
    pb_shading_destroy(ctx, &sh);
    return r;
}
