#include "bake/bake_data.h"
#include "probebake/trace.h"

#include <math.h>
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
        g->tex[2] = (int32_t)m->double_sided;
        g->tex[3] = 0;
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
