/* C mirror of PbVolumeRefs (shaders/include/probe_sample.glsl) and the
 * device copy of a pb_sample_volume, shared by pb_sample_gpu and the
 * renderer. */
#ifndef PB_SAMPLE_GPU_H
#define PB_SAMPLE_GPU_H

#include "gpu/gpu.h"
#include "probebake/sample.h"

#include <stddef.h>

typedef struct gpu_volume_refs {
    uint64_t probes, sh, depth;
    float depth_unit;
    uint32_t levels; /* 0: grid; 1-3: sparse */
    float origin_nbias[4];
    float spacing_vbias[4];
    int32_t counts_res[4];
    uint64_t sparse; /* layout tables (pb_sample_volume.sparse_words) */
    uint32_t probe_count, pad;
} gpu_volume_refs;
_Static_assert(sizeof(gpu_volume_refs) == 96, "PbVolumeRefs layout");
_Static_assert(offsetof(gpu_volume_refs, depth_unit) == 24 && offsetof(gpu_volume_refs, origin_nbias) == 32 &&
                   offsetof(gpu_volume_refs, sparse) == 80,
               "PbVolumeRefs layout");

typedef struct pb_sample_buffers {
    pb_buffer probes, sh, depth, sparse;
    gpu_volume_refs refs;
} pb_sample_buffers;

/* Bytes of the uploaded depth tiles of `probes` probes (one uint32, two
 * halves, per bordered texel): a single buffer, so bounded by the device's
 * maxMemoryAllocationSize (--indirect volume checks before its first bounce). */
static inline uint64_t pb_sample_depth_bytes(uint64_t probes, uint32_t octmap_res)
{
    uint64_t side = (uint64_t)octmap_res + 2;
    return probes * side * side * 4;
}

pb_result pb_sample_upload(pb_context *ctx, const pb_sample_volume *s, pb_sample_buffers *out, pb_error *err);
void pb_sample_release(pb_context *ctx, pb_sample_buffers *b);

#endif
