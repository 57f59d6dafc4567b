/*
 * probebake render: pictures of a scene lit by a baked volume, and the
 * path-traced truth to judge them by (issue 4). A compute kernel
 * (shaders/comp/render.comp) traces one camera path per pixel and sample:
 * primary hit, direct light with the bake's light code, and indirect light
 * from the volume through the run-time sampler or path traced.
 */
#ifndef PROBEBAKE_RENDER_H
#define PROBEBAKE_RENDER_H

#include "probebake/bake.h"
#include "probebake/sample.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum pb_render_mode {
    PB_RENDER_DIRECT = 0,     /* emission seen + light reflected once */
    PB_RENDER_REFERENCE = 1,  /* path traced, `bounces` reflections after the first hit */
    PB_RENDER_PROBES = 2,     /* direct (unless the volume has it) + albedo / pi x volume irradiance */
    PB_RENDER_INDIRECT = 3    /* albedo / pi x volume irradiance only */
} pb_render_mode;

typedef struct pb_camera_view {
    float eye[3];             /* scene-local frame */
    float forward[3], up[3];  /* need not be unit or orthogonal; up must not be parallel to forward */
    float yfov;               /* radians, in (0, pi) */
} pb_camera_view;

typedef struct pb_render_desc {
    pb_camera_view camera;
    uint32_t width, height;   /* 1..16384 each */
    pb_render_mode mode;
    uint32_t spp;             /* default 1 (probes, direct), 64 (reference) */
    uint32_t bounces;         /* reference: default 8 (Russian roulette beyond the second) */
    uint32_t seed;
    const pb_sample_volume *volume; /* probes / indirect modes */
    /* NULL, or `volume` already on ctx's device (pb_sample_upload,
     * src/sample/sample_gpu.h), used instead of uploading its arrays for the
     * call: the caller may then free the host's SH and depth (a million
     * probes: 1.4 GB) */
    const struct pb_sample_buffers *volume_buffers;
    uint32_t volume_direct;   /* the volume's irradiance includes direct light (PB_VOLUME_DIRECT) */
    float sky[3];             /* as pb_bake_desc */
    const pb_environment *environment;
    uint32_t show_probes;     /* debug view: probes as spheres lit by their SH (invalid red, grid homes of
                                 relocated ones grey); needs volume */
    uint32_t emitters_by_area; /* as pb_bake_desc: emitter light samples drawn by area (0: by solid angle) */
    pb_progress_fn progress;  /* NULL, or called after each band of rows; nonzero cancels (PB_ERROR_CANCELLED) */
    void *progress_user;
} pb_render_desc;

/* Whether a render reads the volume: the probes and indirect modes, and the
 * probe spheres of any mode. */
static inline int pb_render_reads_volume(const pb_render_desc *d)
{
    return d->mode == PB_RENDER_PROBES || d->mode == PB_RENDER_INDIRECT || d->show_probes;
}

/* Linear radiance image, 4 floats per pixel, row 0 at the top: rgb and the
 * fraction of samples whose first hit reflects (a surface mask); `direct`
 * (may be NULL) the part of each pixel that reflected at most once. */
pb_result pb_render(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_render_desc *desc, float *rgba,
                    float *direct, double *gpu_ms, pb_error *err);

/* CPU reference of the kernel (tests). */
pb_result pb_render_cpu(const pb_scene *scene, const pb_bvh *bvh, const pb_render_desc *desc, float *rgba,
                        float *direct, pb_error *err);

/* Camera from a glTF camera of the scene (yfov 0.8 rad for orthographic). */
void pb_camera_from_scene(const pb_camera *c, pb_camera_view *out);

/* A view of a scene that has no camera (src/render/default_view.c): from in
 * front of its bounds, above, looking at their centre (how an object or a
 * terrain is seen), where from there a small grid of CPU rays through bvh
 * meets the fronts of surfaces (or double-sided ones) at least as often as
 * the backs of single-sided ones. Else (a level or a room seen from outside,
 * whose walls show their black backs; an empty view) the view from inside
 * the bounds whose rays meet the most fronts, far ones (a quarter of the
 * bounds away) counting fully and nearer ones less, less the backs, times
 * log2(1 + the different triangles they meet): eyes on a 5 x 3 x 5 lattice
 * of the bounds looking along the four horizontal axes, a little down.
 * Deterministic; width x height is the image's size (its aspect). */
void pb_camera_default(const pb_scene *s, const pb_bvh *bvh, float yfov, uint32_t width, uint32_t height,
                       pb_camera_view *out);

/* --- images --- */

/* Tone mapping for display: linear x 2^exposure, the ACES filmic fit
 * (Narkowicz 2015), sRGB encoding, 8 bits. Monotonic in every channel. */
float pb_tonemap_aces(float x);
float pb_srgb_encode(float linear);
/* Exposure (EV) that maps the log-average luminance of the surface pixels
 * (alpha > 0; all pixels if none) to middle grey 0.18, but no higher than
 * puts their 99th-percentile luminance at 4 (so that a mostly black image's
 * lit parts do not clip). */
float pb_auto_exposure(const float *rgba, uint32_t width, uint32_t height);
void pb_tonemap_image(const float *rgba, uint32_t width, uint32_t height, float exposure_ev, unsigned char *rgb8);

/* Relative error heat map of a against reference b (luminance): black 0,
 * blue, green, yellow, red at >= max_error. */
void pb_error_heatmap(const float *a, const float *b, uint32_t width, uint32_t height, float max_error,
                      unsigned char *rgb8);

/* Relative RMSE of luminance over surface pixels (alpha > 0 in b):
 * sqrt(mean (a - b)^2) / mean b. */
double pb_image_relative_rmse(const float *a, const float *b, uint32_t width, uint32_t height);

/* What each pixel's centre sees, from the camera of desc (width, height,
 * camera) on the host BVH: PB_PIXEL_NONE (a miss or the back of a
 * single-sided surface), PB_PIXEL_SURFACE (a reflecting surface that does
 * not emit) or PB_PIXEL_EMITTER. The image metric leaves emitters out. */
enum { PB_PIXEL_NONE = 0, PB_PIXEL_SURFACE = 1, PB_PIXEL_EMITTER = 2 };
void pb_render_pixel_classes(const pb_scene *scene, const pb_bvh *bvh, const pb_render_desc *desc, uint8_t *cls);

/* Error of image a against reference b over the non-emissive surface
 * pixels (cls PB_PIXEL_SURFACE) that are not next to an emitter pixel (the
 * 8 neighbours: their colour mixes the emitter's along the edge). Luminance;
 * relative_rmse = sqrt(mean (a - b)^2) / mean b; p95_relative = the 95th
 * percentile of |a - b| / max(b, 1 % of mean b) per pixel. */
typedef struct pb_image_metrics {
    double relative_rmse, p95_relative;
    uint64_t pixels;          /* compared */
} pb_image_metrics;
void pb_image_surface_metrics(const float *a, const float *b, const uint8_t *cls, uint32_t width, uint32_t height,
                              pb_image_metrics *out);
/* The same over the surface pixels whose mask entry equals `want`. */
void pb_image_surface_metrics_where(const float *a, const float *b, const uint8_t *cls, const uint8_t *mask,
                                    uint8_t want, uint32_t width, uint32_t height, pb_image_metrics *out);

/* Where a sparse volume's levels meet, per surface pixel of desc's camera
 * (cls from pb_render_pixel_classes): the sampler looks its brick up at the
 * biased shading point; PB_SEAM_LEVELS where a brick of another level
 * serves a point half a finest cell away along an axis (the band where a
 * seam between levels would show), PB_SEAM_UNSERVED where no brick serves
 * the point (black), else PB_SEAM_NONE. sv: the volume as sampled (frame =
 * the scene's local frame); layout: its bricks. level: NULL, or receives the
 * level of the brick serving each surface pixel (PB_LEVEL_NONE elsewhere):
 * which level an error sits at. */
enum { PB_LEVEL_NONE = 255 };
enum { PB_SEAM_NONE = 0, PB_SEAM_LEVELS = 1, PB_SEAM_UNSERVED = 2 };
struct pb_sample_volume;
struct pb_sparse_layout;
void pb_render_seam_pixels(const pb_scene *scene, const pb_bvh *bvh, const pb_render_desc *desc,
                           const struct pb_sample_volume *sv, const struct pb_sparse_layout *layout,
                           const uint8_t *cls, uint8_t *seam, uint8_t *level);

/* Writes 8-bit RGB PNG (stb_image_write) or linear PFM (little-endian,
 * bottom row first as PFM says), atomically. PB_ERROR_IO naming the path. */
pb_result pb_write_png(const char *path, const unsigned char *rgb8, uint32_t width, uint32_t height, pb_error *err);
pb_result pb_write_pfm(const char *path, const float *rgba, uint32_t width, uint32_t height, pb_error *err);
/* Reads a colour PFM (either byte order) into a malloc'd RGBA image, top
 * row first, alpha 1. PB_ERROR_IO naming the path for anything else: wrong
 * magic, truncated pixels, non-finite values. */
pb_result pb_read_pfm(const char *path, float **rgba, uint32_t *width, uint32_t *height, pb_error *err);

/* --- debug views of a volume (probebake inspect --atlas / --sh-view) --- */

/* Tiles of `tile` pixels for `probes` probes, row by row with 1-pixel gaps. */
void pb_atlas_layout(uint32_t probes, uint32_t tile, uint32_t *columns, uint32_t *width, uint32_t *height);
/* The depth tiles with their borders: grey = sqrt(mean distance / max
 * distance), red where the distance's spread is large (edges). */
pb_result pb_volume_depth_atlas(const pb_volume *v, unsigned char **rgb8, uint32_t *width, uint32_t *height,
                                pb_error *err);
/* Each probe's SH irradiance / pi over the sphere, octahedral tiles of
 * `tile` pixels, one automatic exposure for all. rgb8 is malloc'd. */
pb_result pb_volume_sh_atlas(const pb_volume *v, uint32_t tile, unsigned char **rgb8, uint32_t *width,
                             uint32_t *height, pb_error *err);

#ifdef __cplusplus
}
#endif
#endif
