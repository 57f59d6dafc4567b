/* The sampling volume on the device, and pb_sample_gpu: the probe_sample
 * kernel over a batch of queries (the test of the shipped GLSL). */
#include "sample/sample_gpu.h"
#include "common/common.h"

#include "probe_sample.spv.h"

#include <stdlib.h>
#include <string.h>

pb_result pb_sample_upload(pb_context *ctx, const pb_sample_volume *s, pb_sample_buffers *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t P = s->probe_count, depth_bytes = pb_sample_depth_bytes(P, s->octmap_res);
    pb_result r = pb_buffer_create(ctx, P * 16, PB_MEMORY_DEVICE, "volume probes", &out->probes, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &out->probes, 0, s->probes, P * 16, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, P * 27 * 4, PB_MEMORY_DEVICE, "volume SH", &out->sh, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &out->sh, 0, s->sh, P * 27 * 4, err);
    if (r == PB_OK)
        r = pb_buffer_create(ctx, depth_bytes, PB_MEMORY_DEVICE, "volume depth", &out->depth, err);
    if (r == PB_OK)
        r = pb_buffer_upload(ctx, &out->depth, 0, s->depth, depth_bytes, err);
    if (r == PB_OK && s->levels) {
        uint64_t bytes = (uint64_t)s->sparse_word_count * 4;
        r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, "volume sparse layout", &out->sparse, err);
        if (r == PB_OK)
            r = pb_buffer_upload(ctx, &out->sparse, 0, s->sparse_words, bytes, err);
    }
    if (r != PB_OK) {
        pb_sample_release(ctx, out);
        return r;
    }
    gpu_volume_refs *g = &out->refs;
    g->probes = out->probes.address, g->sh = out->sh.address, g->depth = out->depth.address;
    g->levels = s->levels;
    g->probe_count = s->probe_count;
    g->sparse = s->levels ? out->sparse.address : 0;
    for (int k = 0; k < 3; ++k) {
        g->origin_nbias[k] = s->origin[k];
        g->spacing_vbias[k] = s->spacing[k];
        g->counts_res[k] = s->counts[k];
    }
    g->origin_nbias[3] = s->normal_bias;
    g->spacing_vbias[3] = s->view_bias;
    g->counts_res[3] = s->octmap_res;
    g->depth_unit = s->depth_unit;
    return PB_OK;
}

void pb_sample_release(pb_context *ctx, pb_sample_buffers *b)
{
    pb_buffer_destroy(ctx, &b->probes);
    pb_buffer_destroy(ctx, &b->sh);
    pb_buffer_destroy(ctx, &b->depth);
    pb_buffer_destroy(ctx, &b->sparse);
    memset(b, 0, sizeof *b);
}

pb_result pb_sample_gpu(pb_context *ctx, const pb_sample_volume *s, const float *p4, const float *n4,
                        const float *view4, uint32_t count, float *rgb4, pb_error *err)
{
    pb_error_clear(err);
    if (count == 0)
        return PB_OK;
    float *interleaved = malloc((size_t)count * 48); /* 3 vec4 per query: point, normal, view */
    if (!interleaved)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u queries", count);
    for (uint32_t i = 0; i < count; ++i) {
        memcpy(interleaved + 12 * (size_t)i, p4 + 4 * (size_t)i, 16);
        memcpy(interleaved + 12 * (size_t)i + 4, n4 + 4 * (size_t)i, 16);
        memcpy(interleaved + 12 * (size_t)i + 8, view4 + 4 * (size_t)i, 16);
    }
    pb_sample_buffers vb;
    pb_result r = pb_sample_upload(ctx, s, &vb, err);
    if (r == PB_OK) /* the batch's push constants, then the volume's references */
        r = pb_gpu_batch(ctx, pb_spv_probe_sample, sizeof pb_spv_probe_sample, "probe_sample", &vb.refs,
                         sizeof vb.refs, interleaved, 48, rgb4, 16, count, err);
    free(interleaved);
    pb_sample_release(ctx, &vb);
    return r;
}
