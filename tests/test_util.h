/* Minimal test harness: one static function per behaviour, run in order by
 * main through RUN(). CHECK prints each failure with file and line and
 * counts it; a test fails when its count is non-zero. SKIP says why. */
#ifndef PB_TEST_UTIL_H
#define PB_TEST_UTIL_H

#define _POSIX_C_SOURCE 200809L
#include "probebake/probebake.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static int t_failures, t_passed, t_failed, t_skipped, t_skip_current;

/* Seconds on the monotonic clock: each behaviour's OK line says how long it
 * took, so the suite's slow cases are named in every CI log. */
static inline double t_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define CHECK(cond)                                                                                                  \
    do {                                                                                                             \
        if (!(cond)) {                                                                                               \
            fprintf(stderr, "  FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond);                                         \
            t_failures++;                                                                                            \
        }                                                                                                            \
    } while (0)

#define CHECKF(cond, ...)                                                                                            \
    do {                                                                                                             \
        if (!(cond)) {                                                                                               \
            fprintf(stderr, "  FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);                                         \
            fprintf(stderr, __VA_ARGS__);                                                                            \
            fprintf(stderr, "\n");                                                                                   \
            t_failures++;                                                                                            \
        }                                                                                                            \
    } while (0)

static inline void skip(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "  SKIP: ");
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\n");
    va_end(ap);
    t_skip_current = 1;
}

/* PB_TEST_ONLY=NAME runs only the behaviours whose names contain NAME. */
#define RUN(fn)                                                                                                      \
    do {                                                                                                             \
        if (getenv("PB_TEST_ONLY") && !strstr(#fn, getenv("PB_TEST_ONLY")))                                          \
            break;                                                                                                   \
        int before = t_failures;                                                                                     \
        t_skip_current = 0;                                                                                          \
        fprintf(stderr, "[ RUN  ] %s\n", #fn);                                                                       \
        double t_start = t_now();                                                                                    \
        fn();                                                                                                        \
        if (t_failures != before) {                                                                                  \
            t_failed++;                                                                                              \
            fprintf(stderr, "[ FAIL ] %s\n", #fn);                                                                   \
        } else if (t_skip_current) {                                                                                 \
            t_skipped++;                                                                                             \
            fprintf(stderr, "[ SKIP ] %s\n", #fn);                                                                   \
        } else {                                                                                                     \
            t_passed++;                                                                                              \
            fprintf(stderr, "[  OK  ] %s (%.1f s)\n", #fn, t_now() - t_start);                                       \
        }                                                                                                            \
    } while (0)

static inline int test_summary(void)
{
    printf("%d passed, %d failed, %d skipped\n", t_passed, t_failed, t_skipped);
    return t_failed ? 1 : 0;
}

/* Work sizes: the full counts normally; a tenth when PB_TEST_QUICK=1 (the
 * sanitizer run, which checks memory safety rather than statistics). */
static inline uint32_t scaled(uint32_t n)
{
    const char *q = getenv("PB_TEST_QUICK");
    return q && q[0] == '1' ? (n + 9) / 10 : n;
}

/* Paths: PB_SOURCE_DIR is set by tests/CMakeLists.txt. */
static inline const char *source_path(const char *rel)
{
    static char buf[8][1024];
    static int slot;
    char *b = buf[slot++ & 7];
    snprintf(b, 1024, "%s/%s", PB_SOURCE_DIR, rel);
    return b;
}

static inline int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* A fresh temporary directory for files a test writes. */
static inline const char *temp_dir(void)
{
    static char dir[256];
    if (!dir[0]) {
        snprintf(dir, sizeof dir, "/tmp/probebake-test-XXXXXX");
        if (!mkdtemp(dir)) {
            perror("mkdtemp");
            exit(2);
        }
    }
    return dir;
}

static inline const char *write_file(const char *name, const void *data, size_t size)
{
    static char paths[8][512];
    static int slot;
    char *p = paths[slot++ & 7];
    snprintf(p, 512, "%s/%s", temp_dir(), name);
    FILE *f = fopen(p, "wb");
    if (!f || fwrite(data, 1, size, f) != size) {
        perror(p);
        exit(2);
    }
    fclose(f);
    return p;
}

/* A whole file's bytes, NUL-terminated past *size (NULL where it cannot be
 * read); size may be NULL. */
static inline unsigned char *read_bytes(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *b = NULL;
    long n = -1;
    if (f && fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (b = malloc((size_t)n + 1)) && fread(b, 1, (size_t)n, f) != (size_t)n) {
        free(b);
        b = NULL;
    }
    if (f)
        fclose(f);
    if (b)
        b[n] = 0;
    if (size)
        *size = b ? (size_t)n : 0;
    return b;
}

static inline char *read_text(const char *path)
{
    return (char *)read_bytes(path, NULL);
}

static inline char *base64(const void *data, size_t n)
{
    static const char tbl[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const unsigned char *p = data;
    char *out = malloc(4 * ((n + 2) / 3) + 1), *o = out;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0) | (i + 2 < n ? p[i + 2] : 0);
        *o++ = tbl[v >> 18 & 63];
        *o++ = tbl[v >> 12 & 63];
        *o++ = i + 1 < n ? tbl[v >> 6 & 63] : '=';
        *o++ = i + 2 < n ? tbl[v & 63] : '=';
    }
    *o = '\0';
    return out;
}

/* Deterministic random numbers for tests (xorshift64*). */
typedef struct test_rng {
    uint64_t s;
} test_rng;

static inline double rng_uniform(test_rng *r)
{
    r->s ^= r->s >> 12;
    r->s ^= r->s << 25;
    r->s ^= r->s >> 27;
    return (double)((r->s * 2685821657736338717ull) >> 11) * (1.0 / 9007199254740992.0);
}

static inline void rng_direction(test_rng *r, float d[3])
{
    double z = 2.0 * rng_uniform(r) - 1.0, phi = 6.283185307179586 * rng_uniform(r);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = (float)(s * cos(phi));
    d[1] = (float)(s * sin(phi));
    d[2] = (float)z;
}

/* Warnings and errors of the library on stderr, indented under the test. */
/* A scene's only light: white, directional, of `intensity`, shining along
 * (dx, dy, dz) (the scene owns it; a failed allocation fails the test). */
static inline void test_directional_light(pb_scene *s, float intensity, float dx, float dy, float dz)
{
    s->lights = calloc(1, sizeof(pb_light));
    s->light_count = s->lights != NULL;
    if (!s->lights) {
        fprintf(stderr, "  out of memory for a light\n");
        t_failures++;
        return;
    }
    s->lights[0].type = PB_LIGHT_DIRECTIONAL;
    s->lights[0].color[0] = s->lights[0].color[1] = s->lights[0].color[2] = 1.f;
    s->lights[0].intensity = intensity;
    s->lights[0].direction[0] = dx, s->lights[0].direction[1] = dy, s->lights[0].direction[2] = dz;
}

static inline void test_log_line(pb_log_level level, const char *msg, void *user)
{
    (void)user;
    if (level >= PB_LOG_WARN)
        fprintf(stderr, "  [%s] %s\n", level == PB_LOG_WARN ? "warn" : "error", msg);
}

/* Whether this is the portable kernels' run (PB_TEST_PORTABLE_KERNELS=1, test_gpu_context). */
static inline int test_portable_kernels(void)
{
    const char *portable = getenv("PB_TEST_PORTABLE_KERNELS");
    return portable && strcmp(portable, "1") == 0;
}

/* PB_TEST_SCENE_LOADS=address or texel: how the GPU tests' kernels read the
 * BVH (pb_scene_loads); unset, the device's default. */
static inline uint32_t test_scene_loads(void)
{
    const char *loads = getenv("PB_TEST_SCENE_LOADS");
    return !loads ? PB_SCENE_LOADS_AUTO
           : !strcmp(loads, "address") ? PB_SCENE_LOADS_ADDRESS
           : !strcmp(loads, "texel") ? PB_SCENE_LOADS_TEXEL : 99u; /* refused by pb_context_create */
}

/* The GPU tests' context: PB_TEST_DEVICE (or the best device) with the
 * validation layer on; PB_TEST_PORTABLE_KERNELS=1 masks shaderInt64 and
 * shaderFloat64 off (the kernels for devices without them);
 * PB_TEST_SCENE_LOADS picks the BVH loads. NULL, after printing why and a
 * failed summary line, when there is none: the caller returns 1. */
static inline pb_context *test_gpu_context(void)
{
    pb_context_desc d = {getenv("PB_TEST_DEVICE"), 1, 0, 0, {test_log_line, NULL}};
    d.portable_kernels = test_portable_kernels();
    d.scene_loads = test_scene_loads();
    pb_context *ctx = NULL;
    pb_error err;
    if (pb_context_create(&d, &ctx, &err) != PB_OK) {
        fprintf(stderr, "no Vulkan device with validation: %s\n", err.message);
        printf("0 passed, 1 failed, 0 skipped\n");
        return NULL;
    }
    if (d.portable_kernels && pb_context_native64(ctx)) {
        fprintf(stderr, "PB_TEST_PORTABLE_KERNELS=1 but the context runs the native64 kernels\n");
        printf("0 passed, 1 failed, 0 skipped\n");
        pb_context_destroy(ctx);
        return NULL;
    }
    printf("kernels: %s\n", pb_context_native64(ctx) ? "native64 (shaderInt64 + shaderFloat64)"
                                                       : "portable (no shaderInt64, no shaderFloat64)");
    return ctx;
}

/* Ends a GPU test program: the validation layer (synchronisation
 * validation included) must have stayed silent through every test, which is
 * reported as a test of its own; frees the context; returns the exit code. */
static inline int test_gpu_finish(pb_context *ctx)
{
    uint32_t n = pb_context_validation_messages(ctx);
    fprintf(stderr, "[ RUN  ] validation_layer_stayed_silent\n");
    if (n) {
        fprintf(stderr, "  %u validation messages\n[ FAIL ] validation_layer_stayed_silent\n", n);
        t_failed++;
    } else {
        fprintf(stderr, "[  OK  ] validation_layer_stayed_silent\n");
        t_passed++;
    }
    pb_context_destroy(ctx);
    return test_summary();
}

#endif
