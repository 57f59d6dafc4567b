#include "bake/bake_data.h"
#include "bake/alias.h"
#include "common/common.h"
#include "probebake/bake.h"
#include "probebake/trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void pb_bake_lights(const pb_scene *scene, gpu_light *out)
{
    for (uint32_t i = 0; i < scene->light_count; ++i) {
        const pb_light *l = &scene->lights[i];
        gpu_light *g = &out[i];
        memset(g, 0, sizeof *g);
        memcpy(g->position_type, l->position, 12);
        g->position_type[3] = (float)l->type;
        memcpy(g->direction_range, l->direction, 12);
        g->direction_range[3] = l->range;
        for (int k = 0; k < 3; ++k)
            g->radiance[k] = l->color[k] * l->intensity;
        /* glTF spot falloff: smooth from cos(outer) to cos(inner) */
        float co = cosf(l->outer_cone), ci = cosf(l->inner_cone);
        g->cone[0] = co;
        g->cone[1] = 1.f / fmaxf(1e-3f, ci - co);
    }
}

void pb_bake_materials(const pb_scene *scene, gpu_shade_material *out)
{
    for (uint32_t i = 0; i < scene->material_count; ++i) {
        const pb_material *m = &scene->materials[i];
        gpu_shade_material *g = &out[i];
        memcpy(g->base_color, m->base_color, 16);
        memcpy(g->emissive_metallic, m->emissive, 12);
        g->emissive_metallic[3] = m->metallic;
        g->tex[0] = m->base_color_texture;
        g->tex[1] = m->emissive_texture;
        g->tex[2] = (m->double_sided ? PB_MATERIAL_DOUBLE_SIDED : 0) |
                    (m->transmission_in_alpha ? PB_MATERIAL_TAU_IN_ALPHA : 0);
        memcpy(&g->tex[3], &m->transmission, 4); /* float bits */
        g->normal_map[0] = m->normal_texture;
        memcpy(&g->normal_map[1], &m->normal_scale, 4);
        g->tau_texture = m->transmission_texture;
        g->pad = 0;
    }
}

uint32_t pb_probe_record_id(const float *probe4)
{
    uint32_t id;
    memcpy(&id, &probe4[3], 4);
    return id;
}

void pb_bake_rotations(uint32_t seed, uint32_t pass, const float *probes4, uint32_t count, float *out12)
{
    for (uint32_t p = 0; p < count; ++p) {
        float m[9];
        pb_random_rotation(seed, pb_probe_record_id(probes4 + 4 * (size_t)p), pass, m);
        float *o = out12 + 12 * (size_t)p;
        for (int r = 0; r < 3; ++r) {
            o[4 * r] = m[3 * r], o[4 * r + 1] = m[3 * r + 1], o[4 * r + 2] = m[3 * r + 2], o[4 * r + 3] = 0.f;
        }
    }
}

float pb_depth_lobe_cutoff(float power)
{
    return powf(1e-4f, 1.f / power);
}

pb_result pb_bake_emitters_build(const pb_scene *s, pb_bake_emitters *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t n = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const float *e = s->materials[s->material[t]].emissive;
        n += e[0] > 0.f || e[1] > 0.f || e[2] > 0.f;
    }
    out->pdf_area = calloc(s->triangle_count ? s->triangle_count : 1, sizeof(float));
    if (!out->pdf_area)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for emitters");
    if (n == 0)
        return PB_OK;
    double *power = malloc((size_t)n * sizeof *power), *area = malloc((size_t)n * sizeof *area);
    out->tri = malloc((size_t)n * sizeof *out->tri);
    out->prob = malloc((size_t)n * sizeof *out->prob);
    out->alias = malloc((size_t)n * sizeof *out->alias);
    if (!power || !area || !out->tri || !out->prob || !out->alias) {
        free(power), free(area);
        pb_bake_emitters_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u emitters", n);
    }
    double total = 0;
    uint32_t k = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const pb_material *m = &s->materials[s->material[t]];
        const float *e = m->emissive;
        if (!(e[0] > 0.f || e[1] > 0.f || e[2] > 0.f))
            continue;
        const float *p = s->positions + 9 * (size_t)t;
        double e1[3], e2[3];
        for (int c = 0; c < 3; ++c)
            e1[c] = (double)p[3 + c] - p[c], e2[c] = (double)p[6 + c] - p[c];
        double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2], cz = e1[0] * e2[1] - e1[1] * e2[0];
        area[k] = 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
        power[k] = area[k] * (0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2]) * (m->double_sided ? 2.0 : 1.0);
        total += power[k];
        out->tri[k++] = t;
    }
    if (pb_alias_build(power, n, out->prob, out->alias) <= 0) { /* emissive triangles have area: power > 0 */
        free(power), free(area);
        pb_bake_emitters_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the emitter table");
    }
    for (uint32_t i = 0; i < n; ++i)
        out->pdf_area[out->tri[i]] = area[i] > 0 ? (float)(power[i] / total / area[i]) : 0.f;
    out->count = n;
    free(power), free(area);
    return PB_OK;
}

void pb_bake_emitters_free(pb_bake_emitters *e)
{
    free(e->tri), free(e->prob), free(e->alias), free(e->pdf_area);
    memset(e, 0, sizeof *e);
}

pb_result pb_light_table_build(const pb_scene *s, pb_light_table *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t n = s->light_count;
    if (!n)
        return PB_OK;
    double *w = malloc(n * sizeof *w), total = 0;
    out->keep = malloc(n * sizeof *out->keep);
    out->alias = malloc(n * sizeof *out->alias);
    out->p = malloc(n * sizeof *out->p);
    if (!w || !out->keep || !out->alias || !out->p) {
        free(w);
        pb_light_table_free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u lights", n);
    }
    for (uint32_t i = 0; i < n; ++i) {
        const pb_light *l = &s->lights[i];
        double lum = 0.2126 * l->color[0] + 0.7152 * l->color[1] + 0.0722 * l->color[2];
        w[i] = lum * l->intensity > 0 ? lum * l->intensity : 0.0;
        total += w[i];
    }
    int built = total > 0 ? pb_alias_build(w, n, out->keep, out->alias) : 0;
    if (built <= 0) {
        free(w);
        pb_light_table_free(out);
        return built < 0 ? pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u lights", n)
                         : PB_OK; /* nothing that shines: no table */
    }
    for (uint32_t i = 0; i < n; ++i)
        out->p[i] = (float)(w[i] / total);
    out->count = n;
    free(w);
    return PB_OK;
}

void pb_light_table_free(pb_light_table *t)
{
    free(t->keep), free(t->alias), free(t->p);
    memset(t, 0, sizeof *t);
}
