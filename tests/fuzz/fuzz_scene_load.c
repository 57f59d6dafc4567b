/* libFuzzer harness for the glTF loader and the scene builder behind it
 * (scripts/fuzz.sh builds it with clang and runs it). Each input is written
 * to a file (the loader reads paths, and external buffers resolve beside
 * it) and loaded; any result is fine, a crash, leak or sanitizer report is
 * not. A .glb magic picks the .glb name, else .gltf. */
#define _POSIX_C_SOURCE 200809L
#include "probebake/probebake.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void quiet(pb_log_level level, const char *msg, void *user)
{
    (void)level, (void)msg, (void)user;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int glb = size >= 4 && memcmp(data, "glTF", 4) == 0;
    snprintf(path, sizeof path, "/tmp/pb_fuzz_%d.%s", (int)getpid(), glb ? "glb" : "gltf");
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    pb_scene_desc d = {{quiet, NULL}, 0};
    pb_scene *s = NULL;
    pb_error err;
    if (pb_scene_load(path, &d, &s, &err) == PB_OK) {
        /* what the bake does next with a scene: bounds, a BVH */
        pb_bvh *bvh = NULL;
        pb_bvh_desc bd = {0, 0, 1, 0.f, 0.f};
        if (pb_bvh_build(s, &bd, &bvh, &err) == PB_OK)
            pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
    } else if (!err.message[0]) {
        abort(); /* a failure must say what failed */
    }
    remove(path);
    return 0;
}
