/* Shading data shared by the bake and the renderer (src/bake/shading.h). */
#include "bake/shading.h"
#include "common/common.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int radiometric_ok(float x)
{
    return x >= 0.f && x <= PB_MAX_RADIOMETRIC; /* false for NaN and Inf */
}

pb_result pb_bake_check_light(const pb_scene *scene, const float sky[3], const pb_environment *environment,
                              pb_error *err)
{
    const char *file = scene->path[0] ? scene->path : "scene";
    for (uint32_t m = 0; m < scene->material_count; ++m)
        for (int k = 0; k < 3; ++k)
            if (!radiometric_ok(scene->materials[m].emissive[k]))
                return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                               "%s: material %u '%s' emits %g (emissive factor x strength): radiances must be finite, "
                               ">= 0 and at most %g", file, m, scene->materials[m].name,
                               (double)scene->materials[m].emissive[k], (double)PB_MAX_RADIOMETRIC);
    for (uint32_t l = 0; l < scene->light_count; ++l) {
        const pb_light *L = &scene->lights[l];
        for (int k = 0; k < 3; ++k)
            if (!radiometric_ok(L->intensity) || !radiometric_ok(L->color[k]) ||
                !radiometric_ok(L->color[k] * L->intensity))
                return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                               "%s: light %u '%s' has intensity %g and colour (%g, %g, %g): colour x intensity must "
                               "be finite, >= 0 and at most %g", file, l, L->name, (double)L->intensity,
                               (double)L->color[0], (double)L->color[1], (double)L->color[2],
                               (double)PB_MAX_RADIOMETRIC);
        if (!isfinite(L->range) || L->range < 0.f)
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: light %u '%s' has range %g: must be finite and >= 0",
                           file, l, L->name, (double)L->range);
    }
    for (int k = 0; k < 3; ++k)
        if (!radiometric_ok(sky[k]))
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                           "sky radiance (%g, %g, %g): each must be finite, >= 0 and at most %g", (double)sky[0],
                           (double)sky[1], (double)sky[2], (double)PB_MAX_RADIOMETRIC);
    if (environment && environment->rgb)
        for (uint64_t i = 0; i < 3ull * environment->width * environment->height; ++i)
            if (!radiometric_ok(environment->rgb[i]))
                return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                               "%s: environment texel %llu is %g after the intensity: radiances must be finite, >= 0 "
                               "and at most %g", environment->path[0] ? environment->path : "environment",
                               (unsigned long long)(i / 3), (double)environment->rgb[i], (double)PB_MAX_RADIOMETRIC);
    return PB_OK;
}

static pb_result upload(pb_context *ctx, pb_buffer *b, uint64_t bytes, const char *what, const void *data,
                        pb_error *err)
{
    pb_result r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, what, b, err);
    if (r == PB_OK && data)
        r = pb_buffer_upload(ctx, b, 0, data, bytes, err);
    return r;
}

pb_result pb_shading_host(const pb_scene *scene, const float sky[3], const pb_environment *environment,
                          pb_bake_emitters *emit, pb_env_table *env, pb_error *err)
{
    memset(env, 0, sizeof *env);
    pb_result r = pb_bake_emitters_build(scene, emit, err);
    if (r != PB_OK)
        return r;
    pb_environment sky_env;
    memset(&sky_env, 0, sizeof sky_env);
    if (!environment && (sky[0] > 0.f || sky[1] > 0.f || sky[2] > 0.f))
        r = pb_environment_uniform(sky, &sky_env, err);
    if (r == PB_OK)
        r = pb_env_table_build(environment ? environment : &sky_env, env, err);
    if (r == PB_OK && env->count == 0)
        pb_env_table_free(env); /* black: nothing to look up or sample */
    pb_environment_free(&sky_env);
    if (r != PB_OK)
        pb_bake_emitters_free(emit);
    return r;
}

int pb_shading_draws_lights(const pb_scene *scene, uint32_t max_lights_per_hit)
{
    return scene->light_count > (max_lights_per_hit ? max_lights_per_hit : 8u);
}

pb_result pb_shading_create(pb_context *ctx, const pb_scene *scene, const pb_gpu_scene *gs, const float sky[3],
                            const pb_environment *environment, uint32_t max_lights_per_hit, pb_shading *out,
                            pb_error *err)
{
    memset(out, 0, sizeof *out);
    out->light_count = scene->light_count;
    uint32_t L = scene->light_count ? scene->light_count : 1, M = scene->material_count;
    uint32_t T = scene->triangle_count ? scene->triangle_count : 1;
    gpu_light *lights = calloc(L, sizeof *lights);
    gpu_shade_material *mats = calloc(M, sizeof *mats);
    uint32_t *leaf_of = pb_malloc_large(T * sizeof *leaf_of);
    float *pdf_leaf = pb_calloc_large(T, sizeof *pdf_leaf);
    gpu_emitter *ge = NULL;
    pb_result r = PB_OK;
    if (!lights || !mats || !leaf_of || !pdf_leaf)
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for shading data");
    if (r == PB_OK)
        r = pb_shading_host(scene, sky, environment, &out->emit, &out->env_table, err);
    if (r == PB_OK && !(ge = malloc((out->emit.count ? out->emit.count : 1) * sizeof *ge)))
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for emitters");
    if (r == PB_OK) {
        pb_bake_lights(scene, lights);
        pb_bake_materials(scene, mats);
        /* emitters in the kernels' leaf order */
        for (uint32_t k = 0; k < scene->triangle_count; ++k)
            leaf_of[gs->tri_order[k]] = k;
        for (uint32_t t = 0; t < scene->triangle_count; ++t)
            pdf_leaf[leaf_of[t]] = out->emit.pdf_area[t];
        for (uint32_t i = 0; i < out->emit.count; ++i)
            ge[i] = (gpu_emitter){leaf_of[out->emit.tri[i]], out->emit.prob[i], out->emit.alias[i], 0.f};
        r = upload(ctx, &out->materials, (uint64_t)M * sizeof *mats, "materials", mats, err);
    }
    if (r == PB_OK)
        r = upload(ctx, &out->lights, (uint64_t)L * sizeof *lights, "lights", lights, err);
    if (r == PB_OK)
        r = upload(ctx, &out->emitters, (out->emit.count ? out->emit.count : 1) * sizeof *ge, "emitter table", ge, err);
    if (r == PB_OK)
        r = upload(ctx, &out->emit_pdf, (uint64_t)T * 4, "emitter densities", pdf_leaf, err);
    if (r == PB_OK)
        r = upload(ctx, &out->env, (out->env_table.count ? out->env_table.count : 1) * sizeof(pb_env_texel),
                   "environment map", out->env_table.count ? (const void *)out->env_table.texels : NULL, err);
    free(lights), free(mats), free(leaf_of), free(pdf_leaf), free(ge);
    /* many lights: the table hits draw one light from */
    if (r == PB_OK && pb_shading_draws_lights(scene, max_lights_per_hit))
        r = pb_light_table_build(scene, &out->lights_drawn, err);
    if (r == PB_OK && out->lights_drawn.count) {
        uint32_t n = out->lights_drawn.count;
        gpu_emitter *t = malloc(n * sizeof *t);
        if (!t) {
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u lights", n);
        } else {
            for (uint32_t i = 0; i < n; ++i)
                t[i] = (gpu_emitter){i, out->lights_drawn.keep[i], out->lights_drawn.alias[i], out->lights_drawn.p[i]};
            r = upload(ctx, &out->light_table, (uint64_t)n * sizeof *t, "light table", t, err);
            out->light_select = 1;
            free(t);
        }
    }
    if (r != PB_OK)
        pb_shading_destroy(ctx, out);
    return r;
}

void pb_shading_params(const pb_shading *s, gpu_bake_params *prm)
{
    prm->materials = s->materials.address;
    prm->lights = s->lights.address;
    prm->light_count = s->light_count;
    prm->emitters = s->emitters.address;
    prm->emit_pdf = s->emit_pdf.address;
    prm->emitter_count = s->emit.count;
    prm->light_select = s->light_select;
    prm->light_table = s->light_select ? s->light_table.address : 0;
    if (s->env_table.width) {
        prm->env = s->env.address;
        prm->env_width = s->env_table.width, prm->env_height = s->env_table.height;
        prm->env_count = s->env_table.count;
        prm->env_rotation[0] = s->env_table.cos_rot, prm->env_rotation[1] = s->env_table.sin_rot;
    }
}

void pb_shading_destroy(pb_context *ctx, pb_shading *s)
{
    pb_buffer *b[6] = {&s->materials, &s->lights, &s->emitters, &s->emit_pdf, &s->env, &s->light_table};
    for (int i = 0; i < 6; ++i)
        pb_buffer_destroy(ctx, b[i]);
    pb_light_table_free(&s->lights_drawn);
    pb_bake_emitters_free(&s->emit);
    pb_env_table_free(&s->env_table);
    memset(s, 0, sizeof *s);
}
