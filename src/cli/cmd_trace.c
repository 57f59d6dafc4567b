#define _POSIX_C_SOURCE 200809L
/* probebake trace: probe-style rays through the device's BVH kernel, with
 * throughput, and --verify against the CPU traversal. */
#include "cli/cli.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_trace(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a SCENE file", "trace");
    pb_log log = {cli_log_to_stderr, (void *)&o->log};
    pb_scene_desc sd = {log, 0};
    pb_scene *s = NULL;
    pb_bvh *bvh = NULL;
    pb_context *ctx = NULL;
    pb_gpu_scene *gs = NULL;
    pb_ray *rays = NULL;
    pb_hit *hits = NULL, *ref = NULL;
    pb_error err;
    int rc = 1;
    /* the device first: one that matches nothing is said before a large scene's load */
    pb_context_desc cd = cli_context_desc(o, o->device, log);
    if (cli_context_create(&cd, "--device", &ctx, &err) != PB_OK)
        goto out;
    if (pb_scene_load(o->scene, &sd, &s, &err) != PB_OK || pb_bvh_build(s, NULL, &bvh, &err) != PB_OK ||
        pb_gpu_scene_create(ctx, s, bvh, &gs, &err) != PB_OK)
        goto out;
    pb_probe_grid grid;
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, o->probes, &grid);
    uint32_t probes = pb_probe_grid_count(&grid);
    uint64_t n64 = (uint64_t)probes * o->rays;
    if (n64 > (1u << 28)) {
        pb_error e2 = {PB_ERROR_INVALID_ARGUMENT, ""};
        snprintf(e2.message, sizeof e2.message, "%s: %llu rays requested; at most 2^28 per trace", o->scene,
                 (unsigned long long)n64);
        err = e2;
        goto out;
    }
    uint32_t n = (uint32_t)n64;
    rays = malloc((size_t)n * sizeof *rays);
    hits = malloc((size_t)n * sizeof *hits);
    if (!rays || !hits) {
        snprintf(err.message, sizeof err.message, "out of host memory for %u rays", n);
        goto out;
    }
    if (pb_probe_rays(&grid, 0, probes, o->rays, o->seed, rays) != PB_OK) {
        snprintf(err.message, sizeof err.message, "out of host memory generating rays");
        goto out;
    }
    pb_trace_stats ts;
    if (pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, &ts, &err) != PB_OK)
        goto out;
    uint64_t traversal = 0, total = pb_gpu_scene_bytes(gs, &traversal);
    uint32_t missed = 0, back = 0;
    for (uint32_t i = 0; i < n; ++i) {
        missed += hits[i].triangle == PB_NO_HIT;
        back += hits[i].triangle != PB_NO_HIT && hits[i].backface;
    }
    printf("scene      %s: %u triangles\n", o->scene, s->triangle_count);
    printf("bvh        %u nodes, %u leaves, depth %u, SAH %.2f, %.1f ms on %u threads\n", bvh->stats.nodes,
           bvh->stats.leaves, bvh->stats.depth, bvh->stats.sah_cost, bvh->stats.build_ms, bvh->stats.threads);
    printf("device     %s: %.1f MiB uploaded, %.1f bytes/triangle for traversal\n", pb_context_device(ctx)->name,
           total / 1048576.0, s->triangle_count ? (double)traversal / s->triangle_count : 0.0);
    printf("trace      %u probe%s x %u ray%s = %u ray%s in %u submit%s: kernel %.1f ms (%.2f Mrays/s), wall %.1f ms "
           "(%.2f Mrays/s)\n", probes, cli_plural(probes), o->rays, cli_plural(o->rays), n, cli_plural(n), ts.submits,
           cli_plural(ts.submits), ts.kernel_ms,
           ts.kernel_ms > 0 ? n / (ts.kernel_ms * 1e3) : 0.0, ts.wall_ms, n / (ts.wall_ms * 1e3));
    printf("hits       %.1f%% hit, %.1f%% of hits on back faces\n", 100.0 * (n - missed) / n,
           n - missed ? 100.0 * back / (n - missed) : 0.0);
    if (o->verify) {
        ref = malloc((size_t)n * sizeof *ref);
        if (!ref) {
            snprintf(err.message, sizeof err.message, "out of host memory for the CPU reference");
            goto out;
        }
        pb_trace_cpu(s, bvh, rays, n, PB_TRACE_CLOSEST, ref, 0);
        uint32_t mismatches = 0;
        for (uint32_t i = 0; i < n; ++i) {
            int same = hits[i].triangle == ref[i].triangle;
            float tol = 1e-5f * fmaxf(1.f, fabsf(ref[i].t));
            if (!same && hits[i].triangle != PB_NO_HIT && ref[i].triangle != PB_NO_HIT)
                same = fabsf(hits[i].t - ref[i].t) <= tol; /* a tie between two triangles */
            else if (same && hits[i].triangle != PB_NO_HIT)
                same = fabsf(hits[i].t - ref[i].t) <= tol;
            mismatches += !same;
        }
        printf("verify     GPU vs CPU reference: %u mismatch%s of %u ray%s\n", mismatches, mismatches == 1 ? "" : "es", n,
               cli_plural(n));
        if (mismatches) {
            snprintf(err.message, sizeof err.message, "%s: GPU and CPU traces differ on %u rays", o->scene,
                     mismatches);
            goto out;
        }
    }
    if (o->validation && pb_context_validation_messages(ctx)) {
        snprintf(err.message, sizeof err.message, "%u Vulkan validation messages", pb_context_validation_messages(ctx));
        goto out;
    }
    rc = 0;
out:
    free(rays), free(hits), free(ref);
    pb_gpu_scene_destroy(gs);
    pb_context_destroy(ctx);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    return rc ? cli_fail(&err) : 0;
}
