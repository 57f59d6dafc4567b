/* Regression inputs from fuzzing (scripts/fuzz.sh): every file in
 * tests/fuzz/corpus and tests/fuzz/crashers is loaded as the harness loads
 * it, then its BVH built. None may crash or trip the sanitizers (this test
 * runs under ASan/UBSan in CI), and every failure must carry a message. */
#define _POSIX_C_SOURCE 200809L
#include "test_util.h"
#include "fuzz/scene_exercise.h"
#include "fuzz/ktx2_exercise.h"
#include "fuzz/volume_exercise.h"

#include <dirent.h>

static void load_all(const char *rel)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", source_path(rel));
    DIR *d = opendir(dir);
    if (!d) {
        skip("%s absent", rel);
        return;
    }
    uint32_t files = 0, loaded = 0, unnamed = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char src[2048], dst[256];
        snprintf(src, sizeof src, "%s/%s", dir, e->d_name);
        /* the harness names inputs by their magic */
        FILE *f = fopen(src, "rb");
        if (!f)
            continue;
        char magic[4] = {0};
        size_t got = fread(magic, 1, 4, f);
        fclose(f);
        snprintf(dst, sizeof dst, "%s", (got == 4 && !memcmp(magic, "glTF", 4)) ? "input.glb" : "input.gltf");
        char *text = NULL;
        size_t size = 0;
        f = fopen(src, "rb");
        if (f) {
            fseek(f, 0, SEEK_END);
            size = (size_t)ftell(f);
            fseek(f, 0, SEEK_SET);
            text = malloc(size ? size : 1);
            size = text ? fread(text, 1, size, f) : 0;
            fclose(f);
        }
        const char *path = write_file(dst, text, size);
        free(text);
        ++files;
        if (getenv("PB_FUZZ_VERBOSE"))
            fprintf(stderr, "  %s\n", src);
        int got_it = pb_fuzz_scene_exercise(path);
        loaded += got_it > 0;
        unnamed += got_it < 0;
    }
    closedir(d);
    fprintf(stderr, "  %s: %u inputs, %u loaded, the rest refused with a message\n", rel, files, loaded);
    CHECK(unnamed == 0);
}

static void corpus(void)
{
    load_all("tests/fuzz/corpus");
}

static void crashers(void)
{
    load_all("tests/fuzz/crashers");
}

/* The volume reader's inputs (tests/fuzz/volume_corpus: seed-* and
 * what fuzz_volume_read found): read, laid out for sampling and sampled as
 * the harness does; the seeds (a grid and two sparse layouts) must read. */
static void volume_corpus(void)
{
    const char *dir = source_path("tests/fuzz/volume_corpus");
    DIR *d = opendir(dir);
    if (!d) {
        skip("tests/fuzz/volume_corpus absent");
        return;
    }
    uint32_t files = 0, read = 0, sparse = 0, unnamed = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        ++files;
        int is_sparse, r = pb_fuzz_volume_exercise(path, &is_sparse);
        unnamed += r < 0;
        read += r > 0;
        sparse += r > 0 && is_sparse;
    }
    closedir(d);
    fprintf(stderr, "  %u volumes, %u read (%u sparse), the rest refused with a message\n", files, read, sparse);
    CHECK(unnamed == 0 && sparse >= 2 && read >= 3);
}

/* The KTX2 decoder's inputs (tests/fuzz/ktx2_corpus: seed-* are the files of
 * tests/data/ktx2, the rest what fuzz_ktx2_decode found): decoded as the
 * harness does; the six seed-etc1s-* files must decode. */
static void ktx2_corpus(void)
{
    const char *dir = source_path("tests/fuzz/ktx2_corpus");
    DIR *d = opendir(dir);
    if (!d) {
        skip("tests/fuzz/ktx2_corpus absent");
        return;
    }
    uint32_t files = 0, decoded = 0, unnamed = 0, seeds = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        FILE *f = fopen(path, "rb");
        uint8_t *data = NULL;
        long n = -1;
        if (f && fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
            (data = malloc((size_t)n + 1)) && fread(data, 1, (size_t)n, f) != (size_t)n)
            n = -1;
        if (f)
            fclose(f);
        if (data && n >= 0) {
            ++files;
            int r = pb_fuzz_ktx2_exercise(data, (size_t)n);
            unnamed += r < 0;
            decoded += r > 0;
            seeds += r > 0 && !strncmp(e->d_name, "seed-etc1s", 10);
        }
        free(data);
    }
    closedir(d);
    fprintf(stderr, "  %u KTX2 files, %u decoded, the rest refused with a reason\n", files, decoded);
    CHECK(unnamed == 0 && seeds >= 6);
}

int main(void)
{
    RUN(corpus);
    RUN(crashers);
    RUN(volume_corpus);
    RUN(ktx2_corpus);
    return test_summary();
}
