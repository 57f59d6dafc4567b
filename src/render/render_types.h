/* C mirror of RenderParams (shaders/comp/render.comp). */
#ifndef PB_RENDER_TYPES_H
#define PB_RENDER_TYPES_H

#include "sample/sample_gpu.h"

typedef struct gpu_render_params {
    float eye[4], forward[4], right[4], up[4];
    gpu_volume_refs volume;
    uint64_t image, image_direct;
    uint32_t width, height, spp, mode;
    uint32_t seed, bounces, first_row, rows;
    uint32_t volume_direct, first_sample, sample_count, show_probes;
} gpu_render_params;
_Static_assert(offsetof(gpu_render_params, volume) == 64, "RenderParams layout");
_Static_assert(sizeof(gpu_render_params) == 224, "RenderParams layout");

/* The camera basis both sides use: forward unit, right and up scaled by the
 * half-field of view (and the aspect ratio for right). */
void pb_render_camera_basis(const pb_camera_view *c, uint32_t width, uint32_t height, float fwd[3], float right[3],
                            float up[3]);

/* Fills the zero fields of d with their defaults (spp, bounces). */
void pb_render_defaults(pb_render_desc *d);

/* Checks a render desc; PB_ERROR_INVALID_ARGUMENT with the problem. */
pb_result pb_render_check(const pb_render_desc *d, pb_error *err);

#endif
