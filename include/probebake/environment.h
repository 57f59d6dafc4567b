/*
 * probebake environment: the light arriving from infinitely far away, a
 * uniform colour or an equirectangular radiance map (docs/conventions.md
 * fixes the mapping), and its importance-sampling table.
 *
 * Mapping (local frame = glTF axes, +Y up): a direction d, turned by
 * -rotation about +Y, has u = 0.5 + atan2(d.x, -d.z) / 2pi and
 * v = acos(d.y) / pi; row 0 of the image is straight up and the image's
 * centre looks along -Z. Radiance is constant over a texel (nearest lookup),
 * so the sampling density below is exact.
 *
 * Sampling: a texel in proportion to luminance x sin(theta of its centre)
 * (its solid angle), by an alias table; then a uniform (u, v) inside it. The
 * solid-angle density of direction d in texel j is
 *   pdf(d) = P_j W H / (2 pi^2 sin theta(d)).
 */
#ifndef PROBEBAKE_ENVIRONMENT_H
#define PROBEBAKE_ENVIRONMENT_H

#include "probebake/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest map kept: wider maps are box-filtered down (by whole factors)
 * to at most this width. Irradiance probes are band-limited (SH L2), and
 * 2048 keeps a 0.5 degree sun within about three texels for sampling. */
#define PB_ENVIRONMENT_MAX_WIDTH 2048u

typedef struct pb_environment {
    uint32_t width, height;      /* texels; equirectangular maps have width = 2 x height */
    float *rgb;                  /* 3 floats per texel, linear radiance (intensity applied), row 0 = up */
    float rotation_deg;          /* about +Y, counter-clockwise seen from above */
    char path[1024];             /* file it came from, "" for a uniform colour */
    uint64_t negative_values;    /* channel values below 0 in the file, read as 0 (lossy EXR compression) */
    float most_negative;         /* the lowest of them (0 if none) */
} pb_environment;

/* Reads a Radiance .hdr (RGBE) or OpenEXR map (the first part's display
 * window; R, G, B or a grey Y channel; any compression), scales it by
 * `intensity` and box-filters it to at most PB_ENVIRONMENT_MAX_WIDTH.
 * Negative values, which lossy EXR compression leaves near black, read as 0
 * and are counted. Returns PB_ERROR_IO (cannot read), PB_ERROR_PARSE
 * (neither format, undecodable, no colour channel, a bad size),
 * PB_ERROR_UNSUPPORTED (luminance-chroma or deep EXR) or
 * PB_ERROR_INVALID_ARGUMENT (intensity not finite and >= 0, NaN or infinite
 * texels), each naming the file. */
pb_result pb_environment_load(const char *path, float intensity, float rotation_deg, pb_environment *out,
                              pb_error *err);

/* A uniform colour as a map (1 x 32: rows weight sampling by solid angle). */
pb_result pb_environment_uniform(const float rgb[3], pb_environment *out, pb_error *err);

void pb_environment_free(pb_environment *env);

/* Radiance of the environment in direction d (unit, local frame). */
void pb_environment_radiance(const pb_environment *env, const float d[3], float rgb[3]);

/* The sampling table the kernels read, one 32-byte record per texel:
 * radiance, P_j (probability of the texel), alias-table probability and
 * alias. count 0 when the environment is black (nothing to sample). */
typedef struct pb_env_texel {
    float rgb[3];
    float p;
    float keep;
    uint32_t alias;
    float pad[2];
} pb_env_texel;

typedef struct pb_env_table {
    uint32_t width, height, count;
    float cos_rot, sin_rot;      /* of rotation_deg */
    pb_env_texel *texels;
} pb_env_table;

pb_result pb_env_table_build(const pb_environment *env, pb_env_table *out, pb_error *err);
void pb_env_table_free(pb_env_table *t);

/* The kernels' functions in C (shaders/include/environment.glsl): the texel
 * a direction falls in, the direction of (u, v), and the solid-angle
 * density of sampling d. */
uint32_t pb_env_texel_of(const pb_env_table *t, const float d[3]);
void pb_env_direction(const pb_env_table *t, float u, float v, float d[3]);
float pb_env_pdf(const pb_env_table *t, const float d[3]);
/* Draws a direction from three uniform numbers; returns its density. */
float pb_env_sample(const pb_env_table *t, float u0, float u1, float u2, float d[3]);

#ifdef __cplusplus
}
#endif
#endif
