/* Scene entry points: load from glTF, build from a soup, destroy. */
#include "common/common.h"
#include "scene/scene_builder.h"

#include <math.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

pb_material pb_material_default(void)
{
    pb_material m;
    memset(&m, 0, sizeof m);
    for (int k = 0; k < 4; ++k)
        m.base_color[k] = 1.f;
    m.metallic = 1.f; /* glTF defaults; a material without pbrMetallicRoughness gets these too */
    m.roughness = 1.f;
    m.alpha_cutoff = 0.5f;
    m.base_color_texture = -1;
    m.emissive_texture = -1;
    m.normal_texture = -1;
    m.normal_scale = 1.f;
    m.transmission_texture = -1;
    m.alpha_mode = PB_ALPHA_OPAQUE;
    return m;
}

pb_result pb_scene_load(const char *path, const pb_scene_desc *desc, pb_scene **out, pb_error *err)
{
    pb_error_clear(err);
    if (!out)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "pb_scene_load: out is NULL");
    *out = NULL;
    if (!path || !path[0])
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "no scene file given");
    pb_scene_desc d;
    memset(&d, 0, sizeof d);
    if (desc)
        d = *desc;
    if (!d.max_texture_pixels)
        d.max_texture_pixels = PB_MAX_TEXTURE_PIXELS;
    if (!d.max_texture_total_pixels)
        d.max_texture_total_pixels = PB_MAX_TEXTURE_TOTAL_PIXELS;
    if (d.decode_ahead > PB_DECODE_AHEAD_NEVER)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "pb_scene_load: decode_ahead %u is not 0, 1 or 2",
                       d.decode_ahead);
    pb_scene_builder b;
    pb_sb_init(&b, d.log);
    pb_result r = pb_gltf_read(path, &d, &b, err);
    if (r == PB_OK)
        r = pb_sb_finish(&b, path, out, err);
    pb_sb_free(&b);
    return r;
}

pb_result pb_scene_from_triangles(const double *world_positions, uint32_t triangle_count,
                                  const uint32_t *material_ids, const pb_material *materials,
                                  uint32_t material_count, pb_scene **out, pb_error *err)
{
    pb_error_clear(err);
    *out = NULL;
    if (triangle_count && !world_positions)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "pb_scene_from_triangles: positions are NULL");
    pb_scene_builder b;
    pb_log nolog = {0};
    pb_sb_init(&b, nolog);
    for (uint32_t i = 0; i < material_count && materials; ++i)
        pb_sb_add_material(&b, &materials[i]);
    for (uint32_t i = 0; i < triangle_count; ++i) {
        uint32_t m = material_ids ? material_ids[i] : 0;
        if (!pb_sb_add_triangle(&b, world_positions + 9 * (uint64_t)i, NULL, NULL, NULL, m))
            break;
    }
    pb_result r = pb_sb_finish(&b, "<memory>", out, err);
    if (*out)
        (*out)->path[0] = '\0';
    pb_sb_free(&b);
    return r;
}

typedef struct bent_count {
    const pb_scene *s;
    _Atomic uint64_t bent;
} bent_count;

static void count_bent(void *user, uint64_t begin, uint64_t end)
{
    bent_count *c = user;
    const pb_scene *s = c->s;
    uint64_t bent = 0;
    for (uint64_t t = begin; t < end; ++t) {
        /* the face normal in double, as the builder gives triangles without normals */
        const float *p = s->positions + 9 * t, *n = s->normals + 9 * t;
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k)
            e1[k] = (double)p[3 + k] - p[k], e2[k] = (double)p[6 + k] - p[k];
        double g[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double l = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (!(l > 0.0))
            continue; /* no face normal to bend from (the builder drops such triangles) */
        int b = 0;
        for (int v = 0; v < 3; ++v)
            b |= !(fabs(g[0] * n[3 * v] + g[1] * n[3 * v + 1] + g[2] * n[3 * v + 2]) >= PB_BENT_NORMAL_COS * l);
        bent += (uint64_t)b;
    }
    atomic_fetch_add(&c->bent, bent); /* a sum: the same in any order */
}

/* On all host cores: a large scene's load, upload and hash each ask. */
uint64_t pb_scene_bent_triangles(const pb_scene *s)
{
    bent_count c = {s, 0};
    pb_parallel_for(s->triangle_count, 1u << 16, 0, count_bent, &c);
    return atomic_load(&c.bent);
}

void pb_scene_destroy(pb_scene *s)
{
    if (!s)
        return;
    free(s->positions);
    free(s->normals);
    free(s->texcoords);
    free(s->colors);
    free(s->tangents);
    free(s->material);
    free(s->materials);
    free(s->textures);
    free(s->texels);
    free(s->lights);
    free(s->cameras);
    free(s);
}

uint32_t pb_scene_normal_mapped(const pb_scene *s)
{
    uint32_t mapped = 0;
    for (uint32_t i = 0; i < s->material_count; ++i)
        mapped += s->materials[i].normal_texture >= 0;
    return mapped;
}

uint64_t pb_scene_tangent_triangles(const pb_scene *s)
{
    uint64_t n = 0;
    for (uint32_t t = 0; s->tangents && t < s->triangle_count; ++t) {
        const float *w = s->tangents + 12 * (size_t)t + 3;
        n += w[0] != 0.f && w[4] != 0.f && w[8] != 0.f;
    }
    return n;
}

uint32_t pb_scene_glass_materials(const pb_scene *s)
{
    uint32_t glass = 0;
    for (uint32_t i = 0; i < s->material_count; ++i)
        glass += s->materials[i].transmission > 0.f;
    return glass;
}

/* The materials' bytes before `transmission` (what pb_material held before
 * it), then the transmissions where any is not 0. */
_Static_assert(offsetof(pb_material, transmission) == 120, "volumes' scene hashes assume the 120-byte material");
static uint64_t materials_hash(const pb_scene *scene)
{
    const size_t head = offsetof(pb_material, transmission);
    unsigned char *bytes = calloc(scene->material_count * head + 1, 1);
    if (!bytes)
        return 0; /* out of host memory: the bake will not get far either */
    for (uint32_t i = 0; i < scene->material_count; ++i)
        memcpy(bytes + i * head, &scene->materials[i], head);
    uint64_t h = pb_hash64(bytes, scene->material_count * head, 0);
    free(bytes);
    int transmissive = pb_scene_glass_materials(scene) != 0;
    for (uint32_t i = 0; transmissive && i < scene->material_count; ++i) {
        h = pb_hash64(&scene->materials[i].transmission, sizeof(float), h);
        if (scene->materials[i].transmission_in_alpha) /* else the hash it had before the flag */
            h = pb_hash64(&scene->materials[i].transmission_in_alpha, sizeof(uint32_t), h);
        if (scene->materials[i].transmission_texture >= 0) /* else the hash it had before the texture */
            h = pb_hash64(&scene->materials[i].transmission_texture, sizeof(int32_t), h);
    }
    /* normal maps, where a material has one (else the hash it had before) */
    int mapped = pb_scene_normal_mapped(scene) != 0;
    for (uint32_t i = 0; mapped && i < scene->material_count; ++i) {
        h = pb_hash64(&scene->materials[i].normal_texture, sizeof(int32_t), h);
        h = pb_hash64(&scene->materials[i].normal_scale, sizeof(float), h);
    }
    return h;
}

uint64_t pb_scene_hash(const pb_scene *scene)
{
    uint64_t h = pb_hash64(scene->positions, (size_t)scene->triangle_count * 36, materials_hash(scene));
    /* vertex normals that shade are part of what was baked; face normals add
     * nothing, so a flat scene (or --shading-normals face) keeps the hash it
     * had before vertex normals were read */
    h = pb_scene_bent_triangles(scene) ? pb_hash64(scene->normals, (size_t)scene->triangle_count * 36, h) : h;
    /* the file's tangents, where a normal map reads them (else the hash it had before) */
    return scene->tangents ? pb_hash64(scene->tangents, (size_t)scene->triangle_count * 48, h) : h;
}
