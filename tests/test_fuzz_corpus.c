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

/* Calls fn on every file of the folder at rel (skipped with a message where
 * absent); returns the files seen. */
typedef void (*file_fn)(const char *path, const char *name, void *user);
static uint32_t each_file(const char *rel, file_fn fn, void *user)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", source_path(rel));
    DIR *d = opendir(dir);
    if (!d) {
        skip("%s absent", rel);
        return 0;
    }
    uint32_t files = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (getenv("PB_FUZZ_VERBOSE"))
            fprintf(stderr, "  %s\n", path);
        ++files;
        fn(path, e->d_name, user);
    }
    closedir(d);
    return files;
}

typedef struct tally {
    uint32_t ok, unnamed, special; /* exercised, refused without a message, the kind's own count */
} tally;

/* the scene harness: the input as a .glb or .gltf (named by its magic, as
 * the harness names it), loaded (its images decoded ahead and in turn, the
 * same) and its BVH built */
static void scene_input(const char *path, const char *name, void *user)
{
    tally *t = user;
    size_t size = 0;
    unsigned char *bytes = read_bytes(path, &size);
    if (!bytes)
        return;
    int glb = size >= 4 && !memcmp(bytes, "glTF", 4);
    const char *copy = write_file(glb ? "input.glb" : "input.gltf", bytes, size);
    free(bytes);
    int r = pb_fuzz_scene_exercise(copy);
    t->ok += r > 0;
    t->unnamed += r == -1;
    CHECKF(r >= 0, "%s: %s", name,
           r == -1 ? "refused without a message" : "its images decoded ahead and in turn gave different scenes or messages");
}

static void load_all(const char *rel)
{
    tally t = {0, 0, 0};
    uint32_t files = each_file(rel, scene_input, &t);
    fprintf(stderr, "  %s: %u inputs, %u loaded, the rest refused with a message\n", rel, files, t.ok);
    CHECK(t.unnamed == 0);
}

static void corpus(void)
{
    load_all("tests/fuzz/corpus");
}

static void crashers(void)
{
    load_all("tests/fuzz/crashers");
}

static void volume_input(const char *path, const char *name, void *user)
{
    (void)name;
    tally *t = user;
    int sparse, r = pb_fuzz_volume_exercise(path, &sparse);
    t->unnamed += r < 0;
    t->ok += r > 0;
    t->special += r > 0 && sparse;
}

/* The volume reader's inputs (tests/fuzz/volume_corpus: seed-* and
 * what fuzz_volume_read found): read, laid out for sampling and sampled as
 * the harness does; the seeds (a grid and two sparse layouts) must read. */
static void volume_corpus(void)
{
    tally t = {0, 0, 0};
    uint32_t files = each_file("tests/fuzz/volume_corpus", volume_input, &t);
    fprintf(stderr, "  %u volumes, %u read (%u sparse), the rest refused with a message\n", files, t.ok, t.special);
    CHECK(t.unnamed == 0 && t.special >= 2 && t.ok >= 3);
}

static void ktx2_input(const char *path, const char *name, void *user)
{
    tally *t = user;
    size_t size = 0;
    unsigned char *bytes = read_bytes(path, &size);
    if (!bytes)
        return;
    int r = pb_fuzz_ktx2_exercise(bytes, size);
    free(bytes);
    t->unnamed += r < 0;
    t->ok += r > 0;
    t->special += r > 0 && !strncmp(name, "seed-etc1s", 10);
}

/* The KTX2 decoder's inputs (tests/fuzz/ktx2_corpus: seed-* are the files of
 * tests/data/ktx2, the rest what fuzz_ktx2_decode found): decoded as the
 * harness does; the six seed-etc1s-* files must decode. */
static void ktx2_corpus(void)
{
    tally t = {0, 0, 0};
    uint32_t files = each_file("tests/fuzz/ktx2_corpus", ktx2_input, &t);
    fprintf(stderr, "  %u KTX2 files, %u decoded, the rest refused with a reason\n", files, t.ok);
    CHECK(t.unnamed == 0 && t.special >= 6);
}

int main(void)
{
    RUN(corpus);
    RUN(crashers);
    RUN(volume_corpus);
    RUN(ktx2_corpus);
    return test_summary();
}
