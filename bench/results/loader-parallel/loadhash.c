/* prints one line per scene: a hash of everything pb_scene_load makes, or its error */
#include "probebake/scene.h"
#include "common/common.h"
#include <stdio.h>
#include <string.h>
#include <stdlib.h>
int main(int argc, char **argv)
{
    for (int a = 1; a < argc; ++a) {
        for (int fn = 0; fn < 2; ++fn) {
            pb_scene_desc d;
            memset(&d, 0, sizeof d);
            d.face_normals = (uint32_t)fn;
            pb_scene *s = NULL;
            pb_error err;
            memset(&err, 0, sizeof err);
            if (pb_scene_load(argv[a], &d, &s, &err) != PB_OK) {
                printf("%s fn%d ERR %d %s\n", argv[a], fn, err.code, err.message);
                continue;
            }
            uint64_t n = s->triangle_count, h = 0;
            h = pb_hash64(s->positions, n * 36, h);
            h = pb_hash64(s->normals, n * 36, h);
            h = pb_hash64(s->texcoords, n * 24, h);
            h = pb_hash64(s->material, n * 4, h);
            if (s->colors) h = pb_hash64(s->colors, n * 48, h);
            h = pb_hash64(s->origin, sizeof s->origin, h);
            h = pb_hash64(s->bounds_min, sizeof s->bounds_min, h);
            h = pb_hash64(s->bounds_max, sizeof s->bounds_max, h);
            h = pb_hash64(&s->stats, sizeof s->stats, h);
            h = pb_hash64(s->materials, s->material_count * sizeof *s->materials, h);
            if (getenv("LH_PARTS")) { /* each array's own hash, to see which one differs */
                const void *part[10] = {s->positions, s->normals, s->texcoords, s->material, s->colors,
                                        s->origin, s->bounds_min, s->bounds_max, &s->stats, s->materials};
                size_t bytes[10] = {n * 36, n * 36, n * 24, n * 4, s->colors ? n * 48 : 0, 24, 12, 12,
                                    sizeof s->stats, s->material_count * sizeof *s->materials};
                for (int q = 0; q < 10; ++q)
                    printf("%04llx ", (unsigned long long)(pb_hash64(part[q], bytes[q], 0) & 0xffff));
                printf("\n");
            }
            printf("%s fn%d %u tris %016llx in %llu deg %llu nonfin %llu colors %d\n", argv[a], fn, s->triangle_count,
                   (unsigned long long)h, (unsigned long long)s->stats.triangles_in,
                   (unsigned long long)s->stats.dropped_degenerate, (unsigned long long)s->stats.dropped_nonfinite,
                   s->colors != NULL);
            pb_scene_destroy(s);
        }
    }
    return 0;
}
