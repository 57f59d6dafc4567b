/* decode_bench: what decoding a scene's images ahead, on the host's
 * threads, buys its load (pb_scene_desc.decode_ahead; docs/scene.md,
 * "Textures"). The peer is the same load decoding them in turn, in the same
 * run: the two alternate (a machine's slow phase falls on both), each scene
 * --runs times each way, and the table gives medians, ranges and the ratio.
 * Both ways must make the same scene (every texel, texture and material,
 * hashed): the cost in error is none by construction, and the bench exits 1
 * if it were not so. No GPU.
 *
 *   decode_bench [--runs N] [--json FILE] [--csv FILE] SCENE...
 *
 * scripts/make_many_images_scene.py makes a scene of many large textures;
 * bench/RESULTS.md, "Images decoded ahead on the host's threads", has the
 * numbers. */
#define _POSIX_C_SOURCE 200809L
#include "bench_util.h"
#include "common/common.h"
#include "probebake/probebake.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_RUNS = 64 };

/* What a load made, decoding or not: pb_scene_hash (geometry, materials),
 * then every texture's fields and every texel */
static uint64_t scene_hash(const pb_scene *s)
{
    uint64_t h = pb_hash64(s->texels, (size_t)s->texel_count * sizeof *s->texels, pb_scene_hash(s));
    for (uint32_t t = 0; t < s->texture_count; ++t) {
        const pb_texture *x = &s->textures[t];
        uint64_t f[6] = {x->width, x->height, x->offset, x->wrap_s, x->wrap_t, x->srgb};
        h = pb_hash64(f, sizeof f, h);
    }
    return pb_hash64(&s->texture_count, sizeof s->texture_count, h);
}

/* One timed load; 0 with a message on failure. */
static int load_once(const char *path, uint32_t mode, double *ms, uint64_t *hash, uint32_t *textures)
{
    pb_scene_desc sd = {{0}, 0};
    sd.decode_ahead = mode;
    pb_scene *s = NULL;
    pb_error err;
    double t0 = pb_now_ms();
    if (pb_scene_load(path, &sd, &s, &err) != PB_OK) {
        fprintf(stderr, "decode_bench: %s\n", err.message);
        return 0;
    }
    *ms = pb_now_ms() - t0;
    *hash = scene_hash(s);
    *textures = s->texture_count;
    pb_scene_destroy(s);
    return 1;
}

static double lowest(const double *v, uint32_t n)
{
    double m = v[0];
    for (uint32_t i = 1; i < n; ++i)
        m = v[i] < m ? v[i] : m;
    return m;
}

static double highest(const double *v, uint32_t n)
{
    double m = v[0];
    for (uint32_t i = 1; i < n; ++i)
        m = v[i] > m ? v[i] : m;
    return m;
}

int main(int argc, char **argv)
{
    uint32_t runs = 7;
    const char *json_path = NULL, *csv_path = NULL;
    int first = 1;
    for (; first < argc && argv[first][0] == '-'; first += 2) {
        const char *a = argv[first], *v = first + 1 < argc ? argv[first + 1] : NULL;
        if (!strcmp(a, "--runs") && v)
            runs = (uint32_t)strtoul(v, NULL, 10);
        else if (!strcmp(a, "--json") && v)
            json_path = v;
        else if (!strcmp(a, "--csv") && v)
            csv_path = v;
        else {
            fprintf(stderr, "decode_bench: unknown option %s\nusage: decode_bench [--runs N] [--json FILE] "
                            "[--csv FILE] SCENE...\n", a);
            return 2;
        }
    }
    if (first >= argc || runs < 1 || runs > MAX_RUNS) {
        fprintf(stderr, "usage: decode_bench [--runs N (1..%d)] [--json FILE] [--csv FILE] SCENE...\n", MAX_RUNS);
        return 2;
    }
    FILE *json = json_path ? fopen(json_path, "w") : NULL, *csv = csv_path ? fopen(csv_path, "w") : NULL;
    if ((json_path && !json) || (csv_path && !csv)) {
        fprintf(stderr, "decode_bench: cannot write %s\n", json_path && !json ? json_path : csv_path);
        return 1;
    }
    printf("host: %u threads; pb_scene_load's wall time, %u alternating runs each way; ms\n", pb_host_threads(), runs);
    printf("%-28s %8s %24s %24s %9s %5s\n", "scene", "textures", "in turn: median (range)", "ahead: median (range)",
           "turn/ahd", "same");
    if (csv)
        fprintf(csv, "scene,run,mode,ms\n");
    if (json)
        fprintf(json, "{\"host_threads\": %u, \"runs\": %u, \"scenes\": [", pb_host_threads(), runs);
    int rc = 0;
    for (int i = first; i < argc; ++i) {
        double ms[2][MAX_RUNS];
        uint64_t first_hash = 0;
        uint32_t textures = 0;
        int same = 1;
        for (uint32_t r = 0; r < runs; ++r)
            for (int k = 0; k < 2; ++k) { /* way 0: in turn (the peer), 1: ahead; each first every other run */
                int way = k ^ (int)(r & 1);
                uint64_t h;
                if (!load_once(argv[i], way ? PB_DECODE_AHEAD_ALWAYS : PB_DECODE_AHEAD_NEVER, &ms[way][r], &h,
                               &textures))
                    return 1;
                if (r == 0 && k == 0)
                    first_hash = h;
                same &= h == first_hash;
                if (csv)
                    fprintf(csv, "%s,%u,%s,%.1f\n", argv[i], r, way ? "ahead" : "in_turn", ms[way][r]);
            }
        double m0 = bench_median(ms[0], runs), m1 = bench_median(ms[1], runs);
        const char *name = strrchr(argv[i], '/') ? strrchr(argv[i], '/') + 1 : argv[i];
        char a[64], b[64];
        snprintf(a, sizeof a, "%.1f (%.1f-%.1f)", m0, lowest(ms[0], runs), highest(ms[0], runs));
        snprintf(b, sizeof b, "%.1f (%.1f-%.1f)", m1, lowest(ms[1], runs), highest(ms[1], runs));
        printf("%-28.28s %8u %24s %24s %8.2fx %5s\n", name, textures, a, b, m0 / m1, same ? "yes" : "NO");
        if (json)
            fprintf(json, "%s\n  {\"scene\": \"%s\", \"textures\": %u, \"in_turn_ms\": %.1f, \"ahead_ms\": %.1f, "
                    "\"ratio\": %.4f, \"same\": %s}", i > first ? "," : "", name, textures, m0, m1, m0 / m1,
                    same ? "true" : "false");
        if (!same) {
            fprintf(stderr, "decode_bench: %s: the two ways made different scenes\n", argv[i]);
            rc = 1;
        }
    }
    printf("turn/ahd: the load decoding in turn over the load decoding ahead (> 1: ahead is faster); same: every "
           "texel, texture and material alike both ways\n");
    if (json) {
        fprintf(json, "\n]}\n");
        fclose(json);
    }
    if (csv)
        fclose(csv);
    return rc;
}
