#define _POSIX_C_SOURCE 200809L
/* probebake info: what the loader made of a scene file (triangles kept and
 * dropped, materials, textures, lights, cameras, extensions, bounds). */
#include "cli/cli.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char *light_type(uint32_t t)
{
    return t == PB_LIGHT_DIRECTIONAL ? "directional" : t == PB_LIGHT_SPOT ? "spot" : "point";
}

/* "A, B" as a JSON array of strings ["A", "B"] (names hold no commas) */
static void json_name_list(const char *list)
{
    printf("[");
    for (const char *p = list; *p;) {
        const char *e = strstr(p, ", ");
        size_t n = e ? (size_t)(e - p) : strlen(p);
        char name[512];
        snprintf(name, sizeof name, "%.*s", (int)n, p);
        printf("%s", p == list ? "" : ", ");
        json_string(name);
        p += n + (e ? 2 : 0);
    }
    printf("]");
}

/* A world coordinate to the millimetre, in at least 6 significant digits:
 * "%.6g" printed a scene 1e7 m from the origin as 1e+07 .. 1e+07. */
static json_num mm(double x)
{
    json_num j;
    double a = fabs(x);
    int digits = a >= 1e3 ? (int)floor(log10(a)) + 4 : 6;
    snprintf(j.s, sizeof j.s, "%.*g", digits > 17 ? 17 : digits, x);
    return j;
}

int cmd_info(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a SCENE file", "info");
    pb_scene_desc sd = {{cli_log_to_stderr, (void *)&o->log}, 0};
    sd.face_normals = (uint32_t)o->face_normals;
    sd.no_normal_maps = (uint32_t)o->no_normal_maps;
    pb_scene *s;
    pb_error err;
    if (pb_scene_load(o->scene, &sd, &s, &err) != PB_OK)
        return cli_fail(&err);
    const pb_scene_stats *st = &s->stats;
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = s->bounds_min[k] + s->origin[k];
        hi[k] = s->bounds_max[k] + s->origin[k];
    }
    uint64_t smooth = pb_scene_bent_triangles(s); /* shaded with their vertex normals */
    uint32_t emissive = 0, masked = 0, blended = 0, glass = pb_scene_glass_materials(s);
    uint32_t normal_mapped = pb_scene_normal_mapped(s);
    uint64_t tangent_tris = pb_scene_tangent_triangles(s); /* normal maps framed by the file's TANGENT */
    for (uint32_t m = 0; m < s->material_count; ++m) {
        const pb_material *mt = &s->materials[m];
        emissive += mt->emissive[0] > 0 || mt->emissive[1] > 0 || mt->emissive[2] > 0;
        masked += mt->alpha_mode == PB_ALPHA_MASK;
        blended += mt->alpha_mode == PB_ALPHA_BLEND;
    }
    if (o->json) {
        printf("{\n  \"file\": ");
        json_string(o->scene);
        printf(",\n  \"triangles\": %u,\n  \"triangles_in\": %llu,\n  \"dropped_degenerate\": %llu,\n"
               "  \"dropped_nonfinite\": %llu,\n  \"primitives\": %u,\n  \"primitives_skipped\": %u,\n"
               "  \"normals_generated\": %u,\n  \"smooth_triangles\": %llu,\n  \"tangent_triangles\": %llu,\n"
               "  \"nodes\": %u,\n",
               s->triangle_count, (unsigned long long)st->triangles_in, (unsigned long long)st->dropped_degenerate,
               (unsigned long long)st->dropped_nonfinite, st->primitives, st->primitives_skipped,
               st->normals_generated, (unsigned long long)smooth, (unsigned long long)tangent_tris, st->nodes);
        printf("  \"materials\": %u,\n  \"emissive_materials\": %u,\n  \"masked_materials\": %u,\n"
               "  \"blended_materials\": %u,\n  \"glass_materials\": %u,\n  \"normal_mapped_materials\": %u,\n"
               "  \"textures\": %u,\n  \"textures_in\": %u,\n  \"textures_unread\": %u,\n",
               s->material_count, emissive, masked, blended, glass, normal_mapped, s->texture_count, st->textures_in,
               st->textures_unread);
        printf("  \"lights\": [");
        for (uint32_t i = 0; i < s->light_count; ++i) {
            const pb_light *l = &s->lights[i];
            printf("%s{\"type\": \"%s\", \"name\": ", i ? ", " : "", light_type(l->type));
            json_string(l->name);
            printf(", \"color\": [%s, %s, %s], \"intensity\": %s, \"range\": %s, \"position\": [%s, %s, %s]}",
                   J(l->color[0]).s, J(l->color[1]).s, J(l->color[2]).s, J(l->intensity).s, J(l->range).s,
                   J(l->position[0] + s->origin[0]).s, J(l->position[1] + s->origin[1]).s,
                   J(l->position[2] + s->origin[2]).s);
        }
        printf("],\n  \"cameras\": [");
        for (uint32_t i = 0; i < s->camera_count; ++i) {
            const pb_camera *c = &s->cameras[i];
            printf("%s{\"name\": ", i ? ", " : "");
            json_string(c->name);
            printf(", \"perspective\": %s, \"yfov\": %s, \"position\": [%s, %s, %s]}",
                   c->perspective ? "true" : "false", J(c->yfov).s, J(c->position[0] + s->origin[0]).s,
                   J(c->position[1] + s->origin[1]).s, J(c->position[2] + s->origin[2]).s);
        }
        printf("],\n  \"extensions_used\": ");
        json_name_list(st->extensions_used);
        printf(",\n  \"extensions_applied\": ");
        json_name_list(st->extensions_applied);
        printf(",\n  \"bounds_min\": [%s, %s, %s],\n  \"bounds_max\": [%s, %s, %s],\n"
               "  \"origin\": [%s, %s, %s]\n}\n",
               J(lo[0]).s, J(lo[1]).s, J(lo[2]).s, J(hi[0]).s, J(hi[1]).s, J(hi[2]).s, J17(s->origin[0]).s,
               J17(s->origin[1]).s, J17(s->origin[2]).s);
    } else {
        printf("scene       %s\n", o->scene);
        printf("triangles   %u kept of %llu (%llu degenerate, %llu NaN/Inf dropped)\n", s->triangle_count,
               (unsigned long long)st->triangles_in, (unsigned long long)st->dropped_degenerate,
               (unsigned long long)st->dropped_nonfinite);
        printf("primitives  %u (%u points/lines skipped, %u without normals: flat normals generated), %u node%s\n",
               st->primitives, st->primitives_skipped, st->normals_generated, st->nodes, cli_plural(st->nodes));
        printf("shading     %llu of %u triangles smooth (vertex normals bent from the face), %llu with the file's "
               "tangents for a normal map\n", (unsigned long long)smooth, s->triangle_count,
               (unsigned long long)tangent_tris);
        printf("materials   %u (%u emissive, %u alpha-masked, %u blended, %u of them thin glass; %u normal-mapped)\n",
               s->material_count, emissive, masked, blended, glass, normal_mapped);
        printf("textures    %u", s->texture_count);
        if (st->textures_unread)
            printf(" (of the file's %u, %u the bake never reads, not decoded: occlusion or unused maps)",
                   st->textures_in, st->textures_unread);
        printf("\n");
        printf("lights      %u", s->light_count);
        for (uint32_t i = 0; i < s->light_count; ++i) { /* names and extensions as the file spells them: printable */
            printf("%s%s '", i ? ", " : ": ", light_type(s->lights[i].type));
            cli_fputs_printable(s->lights[i].name, stdout);
            printf("' %g", s->lights[i].intensity);
        }
        printf("\ncameras     %u\n", s->camera_count);
        if (st->extensions_used[0]) {
            printf("extensions  used: ");
            cli_fputs_printable(st->extensions_used, stdout);
            printf("; applied: ");
            cli_fputs_printable(st->extensions_applied[0] ? st->extensions_applied : "none", stdout);
            printf("\n");
        }
        printf("bounds      (%s, %s, %s) .. (%s, %s, %s) m\n", mm(lo[0]).s, mm(lo[1]).s, mm(lo[2]).s, mm(hi[0]).s,
               mm(hi[1]).s, mm(hi[2]).s);
    }
    pb_scene_destroy(s);
    return 0;
}
