/* libFuzzer harness for the glTF loader and the scene builder behind it
 * (scripts/fuzz.sh builds it with clang and runs it). Each input is written
 * to a file (the loader reads paths, and external buffers resolve beside
 * it) and loaded; any result is fine, a crash, leak or sanitizer report is
 * not. A .glb magic picks the .glb name, else .gltf. */
#define _POSIX_C_SOURCE 200809L
#include "scene_exercise.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
    if (pb_fuzz_scene_exercise(path) < 0)
        abort(); /* a failure must say what failed */
    remove(path);
    return 0;
}
