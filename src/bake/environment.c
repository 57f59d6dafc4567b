/* Environment light: the sampling table and the kernels' mapping and
 * sampling functions in C (shaders/include/environment.glsl does the same,
 * operation for operation). include/probebake/environment.h has the maths. */
#include "bake/alias.h"
#include "common/common.h"
#include "probebake/environment.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI_F 3.14159265358979324f

pb_result pb_environment_uniform(const float rgb[3], pb_environment *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    out->width = 1, out->height = 32;
    out->rgb = malloc(3 * 32 * sizeof(float));
    if (!out->rgb)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sky");
    for (uint32_t i = 0; i < 32; ++i)
        memcpy(out->rgb + 3 * i, rgb, 3 * sizeof(float));
    return PB_OK;
}

void pb_environment_free(pb_environment *env)
{
    free(env->rgb);
    memset(env, 0, sizeof *env);
}

/* d turned by -rotation about +Y: the frame the image is defined in */
static void unrotate(float c, float s, const float d[3], float o[3])
{
    o[0] = c * d[0] - s * d[2];
    o[1] = d[1];
    o[2] = s * d[0] + c * d[2];
}

uint32_t pb_env_texel_of(const pb_env_table *t, const float d[3])
{
    float e[3];
    unrotate(t->cos_rot, t->sin_rot, d, e);
    float u = 0.5f + atan2f(e[0], -e[2]) * (0.5f / PI_F);
    float v = acosf(fminf(1.f, fmaxf(-1.f, e[1]))) * (1.f / PI_F);
    int x = (int)floorf(u * (float)t->width), y = (int)floorf(v * (float)t->height);
    x = x < 0 ? 0 : (x >= (int)t->width ? (int)t->width - 1 : x);
    y = y < 0 ? 0 : (y >= (int)t->height ? (int)t->height - 1 : y);
    return (uint32_t)y * t->width + (uint32_t)x;
}

void pb_env_direction(const pb_env_table *t, float u, float v, float d[3])
{
    float phi = 2.f * PI_F * (u - 0.5f), theta = PI_F * v;
    float st = sinf(theta);
    float e[3] = {st * sinf(phi), cosf(theta), -st * cosf(phi)};
    /* turn by +rotation */
    d[0] = t->cos_rot * e[0] + t->sin_rot * e[2];
    d[1] = e[1];
    d[2] = -t->sin_rot * e[0] + t->cos_rot * e[2];
}

float pb_env_pdf(const pb_env_table *t, const float d[3])
{
    if (!t->count)
        return 0.f;
    float st = sqrtf(fmaxf(0.f, 1.f - d[1] * d[1]));
    if (!(st > 0.f))
        return 0.f;
    float p = t->texels[pb_env_texel_of(t, d)].p;
    return p * (float)(t->width * t->height) / (2.f * PI_F * PI_F * st);
}

float pb_env_sample(const pb_env_table *t, float u0, float u1, float u2, float d[3])
{
    float x = u0 * (float)t->count;
    uint32_t i = (uint32_t)x;
    if (i > t->count - 1)
        i = t->count - 1;
    uint32_t j = x - (float)i < t->texels[i].keep ? i : t->texels[i].alias;
    float u = ((float)(j % t->width) + u1) / (float)t->width;
    float v = ((float)(j / t->width) + u2) / (float)t->height;
    pb_env_direction(t, u, v, d);
    float st = sinf(PI_F * v);
    if (!(st > 0.f))
        return 0.f;
    return t->texels[j].p * (float)(t->width * t->height) / (2.f * PI_F * PI_F * st);
}

void pb_environment_radiance(const pb_environment *env, const float d[3], float rgb[3])
{
    float a = env->rotation_deg * (PI_F / 180.f);
    pb_env_table t = {env->width, env->height, 0, cosf(a), sinf(a), NULL};
    const float *c = env->rgb + 3 * (size_t)pb_env_texel_of(&t, d);
    rgb[0] = c[0], rgb[1] = c[1], rgb[2] = c[2];
}

pb_result pb_env_table_build(const pb_environment *env, pb_env_table *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t n = (uint64_t)env->width * env->height;
    if (!n || !env->rgb)
        return PB_OK;
    float a = env->rotation_deg * (PI_F / 180.f);
    out->width = env->width, out->height = env->height;
    out->cos_rot = cosf(a), out->sin_rot = sinf(a);
    double *w = malloc(n * sizeof *w);
    float *keep = malloc(n * sizeof *keep);
    uint32_t *alias = malloc(n * sizeof *alias);
    out->texels = calloc(n, sizeof *out->texels);
    if (!w || !keep || !alias || !out->texels) {
        free(w), free(keep), free(alias);
        pb_env_table_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the environment table");
    }
    double total = 0;
    for (uint64_t i = 0; i < n; ++i) {
        const float *c = env->rgb + 3 * i;
        double theta = 3.14159265358979324 * ((double)(i / env->width) + 0.5) / env->height;
        w[i] = (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) * sin(theta);
        w[i] = w[i] > 0 ? w[i] : 0;
        total += w[i];
    }
    int built = total > 0 ? pb_alias_build(w, (uint32_t)n, keep, alias) : 0;
    if (built < 0) {
        free(w), free(keep), free(alias);
        pb_env_table_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the environment's sampling table");
    }
    if (built) {
        for (uint64_t i = 0; i < n; ++i) {
            pb_env_texel *e = &out->texels[i];
            memcpy(e->rgb, env->rgb + 3 * i, sizeof e->rgb);
            e->p = (float)(w[i] / total);
            e->keep = keep[i];
            e->alias = alias[i];
        }
        out->count = (uint32_t)n;
    } else {
        /* black: nothing to sample; radiance lookups still work */
        for (uint64_t i = 0; i < n; ++i)
            memcpy(out->texels[i].rgb, env->rgb + 3 * i, sizeof out->texels[i].rgb);
    }
    free(w), free(keep), free(alias);
    return PB_OK;
}

void pb_env_table_free(pb_env_table *t)
{
    free(t->texels);
    memset(t, 0, sizeof *t);
}
