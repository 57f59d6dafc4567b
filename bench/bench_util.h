/* Shared by the benches: the probe error metric, medians, scene setup. */
#ifndef PB_BENCH_UTIL_H
#define PB_BENCH_UTIL_H

#include "probebake/probebake.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* qsort's comparison of doubles. */
static inline int bench_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median of v[0..n) (the upper one of an even count), v unchanged; n <= 64. */
static inline double bench_median(const double *v, uint32_t n)
{
    double t[64];
    if (!n || n > 64)
        return 0.0;
    for (uint32_t i = 0; i < n; ++i)
        t[i] = v[i];
    qsort(t, n, sizeof *t, bench_cmp_double);
    return t[n / 2];
}

/* The trace kernel's Mrays/s (closest hits, kernel time) in one timed run of
 * n rays; 0 when it fails or n is 0. hits: n entries of scratch. */
static inline double bench_trace_rate(pb_context *ctx, pb_gpu_scene *gs, const pb_ray *rays, uint32_t n,
                                      pb_hit *hits)
{
    pb_error err;
    pb_trace_stats st;
    if (!n || pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, &st, &err) != PB_OK || !(st.kernel_ms > 0))
        return 0.0;
    return n / (st.kernel_ms * 1e3);
}

/* Relative RMSE of irradiance luminance of volume a against ref, over ref's
 * valid probes and 64 spherical-Fibonacci directions:
 * sqrt(mean (E - E_ref)^2) / mean(E_ref). */
static inline double bench_volume_rmse(const pb_volume *a, const pb_volume *ref)
{
    float dirs[64 * 4];
    pb_sf_directions(64, dirs);
    double se = 0, sum = 0;
    uint64_t n = 0;
    for (uint32_t p = 0; p < ref->probe_count; ++p) {
        if (!(ref->probe_flags[p] & PB_PROBE_VALID))
            continue;
        for (int i = 0; i < 64; ++i) {
            float e[3], r[3];
            pb_sh_eval(a->sh + 27 * (size_t)p, dirs + 4 * i, e);
            pb_sh_eval(ref->sh + 27 * (size_t)p, dirs + 4 * i, r);
            double le = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
            double lr = 0.2126 * r[0] + 0.7152 * r[1] + 0.0722 * r[2];
            se += (le - lr) * (le - lr), sum += lr, ++n;
        }
    }
    return n && sum > 0 ? sqrt(se / n) / (sum / n) : 0.0;
}

/* Loads a scene, builds its BVH and uploads it; on failure prints
 * "tool: message", frees what was made and returns 0. */
static inline int bench_open_scene(pb_context *ctx, const char *tool, const char *path, pb_scene **s, pb_bvh **bvh,
                                   pb_gpu_scene **gs)
{
    pb_scene_desc sd = {{0}, 0};
    pb_error err;
    *s = NULL, *bvh = NULL, *gs = NULL;
    if (pb_scene_load(path, &sd, s, &err) != PB_OK || pb_bvh_build(*s, NULL, bvh, &err) != PB_OK ||
        pb_gpu_scene_create(ctx, *s, *bvh, gs, &err) != PB_OK) {
        fprintf(stderr, "%s: %s\n", tool, err.message);
        pb_bvh_destroy(*bvh);
        pb_scene_destroy(*s);
        return 0;
    }
    return 1;
}

/* llvmpipe (lavapipe) compiles a pipeline's machine code at its first
 * dispatch, inside the GPU timestamps: 0.2-0.4 s per set of bake kernels
 * when Mesa's shader cache is cold (a fresh machine, or any shader change).
 * An untimed bake of d's probes with d's estimators, one pass of 64 rays,
 * first keeps that out of a bench's GPU times. Its seed is another, so what
 * the GPU scene learns per seed (light cells, guide) is still learned, and
 * timed, by the bench's own first bake. Returns 0 with err on failure. */
static inline int bench_warm_bake(pb_context *ctx, const pb_scene *s, pb_gpu_scene *gs, const pb_bake_desc *d,
                                  pb_error *err)
{
    pb_bake_desc w = *d;
    w.passes = 1, w.target_error = 0.f, w.rays_per_probe = 64, w.seed = d->seed + 1u;
    pb_volume v;
    if (pb_bake(ctx, s, gs, &w, &v, err) != PB_OK)
        return 0;
    pb_volume_free(&v);
    return 1;
}

/* The benches' scenes when none are named: the demo scene, and the shared
 * Cornell box and The Crypt when ../shared is beside the checkout. */
static inline int bench_default_scenes(const char *tool, const char **scenes, int max)
{
    static const char *def[] = {"tests/scenes/demo.gltf", "../shared/scenes/cornell/cornellBox.gltf",
                                "../shared/scenes/openarena/oacmpdm1.glb"};
    int n = 0;
    for (int i = 0; i < 3 && n < max; ++i) {
        FILE *f = fopen(def[i], "rb");
        if (f) {
            fclose(f);
            scenes[n++] = def[i];
        } else {
            fprintf(stderr, "%s: %s not present, skipped\n", tool, def[i]);
        }
    }
    return n;
}

/* Draws png with the gnuplot script gp when gnuplot is on PATH, and says
 * which happened. */
static inline void bench_run_gnuplot(const char *gp, const char *png)
{
    char cmd[2200];
    snprintf(cmd, sizeof cmd, "command -v gnuplot >/dev/null && gnuplot '%s' 2>/dev/null", gp);
    if (system(cmd) == 0)
        printf("wrote %s\n", png);
    else
        printf("gnuplot not found or failed: %s not drawn (script %s)\n", png, gp);
}

#endif
