/* bake_bench: bake time per stage and error against a long bake.
 *
 *   bake_bench [--probes N] [--reference-passes N] [--bounces N] [--repeat N]
 *              [--schedule megakernel|wavefront|restart[:K]]
 *              [--json FILE] [SCENE ...]
 *
 * For each scene: a reference bake (256 rays x --reference-passes passes,
 * default 32), then bakes at 64, 128 and 256 rays per probe (1 pass, other
 * seeds). Error: relative RMSE of irradiance over valid probes and 64
 * directions, sqrt(mean (E - E_ref)^2) / mean(E_ref), luminance-weighted RGB.
 * Time: GPU timestamps of the trace, SH and depth kernels, and wall time.
 *
 * Throughput: the bake's BVH traversals (probe, bounce and shadow rays,
 * relocation included, counted by the kernel) per second of all its GPU
 * time (trace + SH + depth), against the trace kernel's rays per second on
 * 256 probe rays per probe of the same grid, same device, same run. The
 * target is a ratio >= 0.7: shading, projection, filtering and relocation
 * cost at most 30 %. "vs bnc" divides by the trace kernel's rate on the
 * bounce rays of those probe rays instead (one cosine ray from each first
 * front hit, bounce_rays.h): most of the bake's traversals are such rays,
 * which start on surfaces and cost more than probe rays on any tracer.
 * "vs own" divides by the trace kernel's rate on the bake's own probe rays:
 * the same 256 rays per probe, from where the bake traced each probe (after
 * relocation) and only from the probes it traced (not those it found inside
 * geometry); the grid's probe rays include rays from probes in rock or
 * outside the level, which the bake never traces.
 *
 * --repeat N (default 3): each row is N rounds of one timed trace of the
 * probe rays, one of their bounce rays and one bake (same seed: their
 * traversal counts and errors must agree, else the bench says so and
 * fails). The ratios are medians of the rounds' ratios, the times those of
 * the bake of median GPU time. On lavapipe a run's rate can be off by 2x and
 * drifts within a process (bench/RESULTS.md), so each ratio pairs a bake with
 * trace runs made next to it. */
#define _POSIX_C_SOURCE 200809L
#include "common/common.h"
#include "bench_util.h"
#include "bounce_rays.h"
#include "probebake/probebake.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The bake's own probe rays: of the grid's rays (`per_probe` per probe), those
 * of each probe v traced (not flagged inside geometry), moved to where it
 * traced them (its relocated position, in the scene's local frame). Returns
 * how many were written to out. */
static uint32_t own_probe_rays(const pb_scene *s, const pb_volume *v, const pb_ray *grid_rays, uint32_t per_probe,
                               pb_ray *out)
{
    uint32_t n = 0;
    for (uint32_t p = 0; p < v->probe_count; ++p) {
        if (v->probe_flags[p] & PB_PROBE_INSIDE)
            continue;
        float at[3];
        for (int c = 0; c < 3; ++c)
            at[c] = (float)(v->origin[c] + (double)v->base[3 * p + c] + (double)v->offset[3 * p + c] - s->origin[c]);
        for (uint32_t r = 0; r < per_probe; ++r) {
            out[n] = grid_rays[(size_t)p * per_probe + r];
            memcpy(out[n++].origin, at, sizeof at);
        }
    }
    return n;
}

typedef struct row {
    char scene[128];
    uint32_t probes, rays, passes;
    double trace_ms, sh_ms, depth_ms, wall_ms, rmse;
    uint64_t traversals;
    double trace_kernel_mrays;    /* trace.comp on this scene's probe rays */
    double bounce_kernel_mrays;   /* trace.comp on their bounce rays */
    double own_kernel_mrays;      /* trace.comp on the bake's own probe rays (its traced probes, relocated) */
    double vs_trace, vs_bounce, vs_own; /* the bake's traversal rate over those, medians of the rounds */
} row;


int main(int argc, char **argv)
{
    uint32_t probes = 256, ref_passes = 32, bounces = 2, repeat = 3;
    const char *json = "bench/out/bake_bench.json";
    int validation = 0; /* --validation: fail on any Vulkan validation message */
    uint32_t schedule = PB_SCHEDULE_MEGAKERNEL, paths_per_lane = 0; /* of the timed bakes (not the reference's) */
    const char *scenes[16];
    int nscenes = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--probes") && i + 1 < argc)
            probes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--reference-passes") && i + 1 < argc)
            ref_passes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--bounces") && i + 1 < argc)
            bounces = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
            repeat = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(argv[i], "--json") && i + 1 < argc)
            json = argv[++i];
        else if (!strcmp(argv[i], "--validation"))
            validation = 1;
        else if (!strcmp(argv[i], "--schedule") && i + 1 < argc) {
            if (!pb_bake_schedule_parse(argv[++i], &schedule, &paths_per_lane)) {
                fprintf(stderr, "bake_bench: --schedule %s: megakernel, wavefront or restart[:K], K 1-%u\n", argv[i],
                        PB_MAX_PATHS_PER_LANE);
                return 2;
            }
        }
        else if (argv[i][0] == '-') {
            fprintf(stderr, "bake_bench: unknown option %s\n", argv[i]);
            return 2;
        } else if (nscenes < 16)
            scenes[nscenes++] = argv[i];
    }
    if (repeat < 1 || repeat > 15) {
        fprintf(stderr, "bake_bench: --repeat %u is out of range 1..15\n", repeat);
        return 2;
    }
    if (!nscenes)
        nscenes = bench_default_scenes("bake_bench", scenes, 16);
    pb_context *ctx = NULL;
    pb_error err;
    pb_context_desc cd = {NULL, (uint32_t)validation, 0, 0, {0}};
    if (pb_context_create(&cd, &ctx, &err) != PB_OK) {
        fprintf(stderr, "bake_bench: %s\n", err.message);
        return 1;
    }
    char sched[32];
    pb_bake_schedule_name(&(pb_bake_desc){.schedule = schedule, .paths_per_lane = paths_per_lane}, sched, sizeof sched);
    printf("device: %s; %u probes, %u bounces, reference 256 rays x %u passes; medians of %u runs; schedule %s\n",
           pb_context_device(ctx)->name, probes, bounces, ref_passes, repeat, sched);
    printf("%-18s %6s %6s %9s %8s %8s %9s %9s %9s %7s %7s %7s %8s\n", "scene", "rays", "passes", "trace ms", "sh ms",
           "depth ms", "wall ms", "Mrays/s", "Mtrav/s", "vs trc", "vs bnc", "vs own", "rel RMSE");
    row rows[64];
    int nrows = 0, nondeterministic = 0;
    for (int si = 0; si < nscenes; ++si) {
        pb_scene *s;
        pb_bvh *bvh;
        pb_gpu_scene *gs;
        if (!bench_open_scene(ctx, "bake_bench", scenes[si], &s, &bvh, &gs))
            continue;
        const char *name = strrchr(scenes[si], '/') ? strrchr(scenes[si], '/') + 1 : scenes[si];
        pb_bake_desc d = {0};
        pb_probe_grid_fit(s->bounds_min, s->bounds_max, probes, &d.grid);
        d.bounces = bounces;
        d.octmap_res = 16;
        /* scenes with lights or emissive surfaces light themselves; a dim sky for the rest */
        int self_lit = s->light_count > 0;
        for (uint32_t m = 0; m < s->material_count && !self_lit; ++m)
            self_lit = s->materials[m].emissive[0] > 0.f || s->materials[m].emissive[1] > 0.f ||
                       s->materials[m].emissive[2] > 0.f;
        if (!self_lit)
            d.sky[0] = d.sky[1] = d.sky[2] = 0.2f;
        /* the trace kernel on 256 probe rays per probe of this grid and on
         * their bounce rays, timed beside each bake below (one warm-up each) */
        uint32_t P = pb_probe_grid_count(&d.grid), n = P * 256, nb = 0;
        pb_ray *rays = malloc((size_t)n * sizeof *rays), *brays = malloc((size_t)n * sizeof *brays);
        pb_ray *orays = malloc((size_t)n * sizeof *orays);
        pb_hit *hits = malloc((size_t)n * sizeof *hits);
        if (rays && brays && orays && hits && pb_probe_rays(&d.grid, 0, P, 256, 1, rays) == PB_OK &&
            pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, NULL, &err) == PB_OK) {
            memcpy(brays, rays, (size_t)n * sizeof *rays);
            nb = bench_bounce_rays(s, brays, hits, n, 0);
            if (nb && pb_trace(ctx, gs, brays, nb, PB_TRACE_CLOSEST, hits, NULL, &err) != PB_OK)
                nb = 0;
        } else {
            n = 0;
        }
        double all_trace[48], all_bounce[48], all_own[48];
        uint32_t nall = 0;
        pb_volume ref;
        d.rays_per_probe = 256;
        d.passes = ref_passes;
        d.seed = 1000;
        double t0 = pb_now_ms();
        if (pb_bake(ctx, s, gs, &d, &ref, &err) != PB_OK) {
            fprintf(stderr, "bake_bench: %s: %s\n", name, err.message);
        } else {
            double ref_ms = pb_now_ms() - t0;
            uint32_t no = own_probe_rays(s, &ref, rays, n / P, orays);
            uint32_t rays_list[3] = {64, 128, 256};
            for (int ri = 0; ri < 3; ++ri) {
                d.rays_per_probe = rays_list[ri];
                d.passes = 1;
                d.seed = 7;
                d.schedule = schedule, d.paths_per_lane = paths_per_lane;
                row run[16];
                double vs_trace[16], vs_bounce[16], vs_own[16];
                uint32_t done = 0;
                for (; done < repeat; ++done) {
                    double tr = bench_trace_rate(ctx, gs, rays, n, hits);
                    double br = bench_trace_rate(ctx, gs, brays, nb, hits);
                    double orate = bench_trace_rate(ctx, gs, orays, no, hits);
                    if (nall < 48)
                        all_trace[nall] = tr, all_bounce[nall] = br, all_own[nall++] = orate;
                    pb_volume v;
                    t0 = pb_now_ms();
                    if (pb_bake(ctx, s, gs, &d, &v, &err) != PB_OK) {
                        fprintf(stderr, "bake_bench: %s\n", err.message);
                        break;
                    }
                    row *r = &run[done];
                    memset(r, 0, sizeof *r);
                    snprintf(r->scene, sizeof r->scene, "%s", name);
                    r->probes = v.probe_count;
                    r->rays = rays_list[ri];
                    r->passes = 1;
                    r->wall_ms = pb_now_ms() - t0;
                    r->trace_ms = v.timings.trace, r->sh_ms = v.timings.sh, r->depth_ms = v.timings.octmap;
                    r->rmse = bench_volume_rmse(&v, &ref);
                    r->traversals = v.traversals;
                    r->trace_kernel_mrays = tr;
                    r->bounce_kernel_mrays = br;
                    r->own_kernel_mrays = orate;
                    pb_volume_free(&v);
                    double gpu = r->trace_ms + r->sh_ms + r->depth_ms;
                    double mtrav = gpu > 0 ? (double)r->traversals / (gpu * 1e3) : 0.0;
                    vs_trace[done] = tr > 0 ? mtrav / tr : 0.0;
                    vs_bounce[done] = br > 0 ? mtrav / br : 0.0;
                    vs_own[done] = orate > 0 ? mtrav / orate : 0.0;
                    if (r->traversals != run[0].traversals || r->rmse != run[0].rmse) {
                        fprintf(stderr, "bake_bench: %s, %u rays: the same bake gave %llu traversals and RMSE %.6f, then %llu and %.6f\n",
                                name, r->rays, (unsigned long long)run[0].traversals, run[0].rmse,
                                (unsigned long long)r->traversals, r->rmse);
                        nondeterministic = 1;
                    }
                }
                if (done < repeat)
                    continue;
                /* the run of median GPU time stands for the row */
                uint32_t pick = 0;
                for (uint32_t a = 0; a < repeat; ++a) {
                    double ga = run[a].trace_ms + run[a].sh_ms + run[a].depth_ms;
                    uint32_t below = 0, equal_before = 0;
                    for (uint32_t b = 0; b < repeat; ++b) {
                        double gb = run[b].trace_ms + run[b].sh_ms + run[b].depth_ms;
                        below += gb < ga;
                        equal_before += gb == ga && b < a;
                    }
                    if (below + equal_before == repeat / 2)
                        pick = a;
                }
                row *r = &rows[nrows++];
                *r = run[pick];
                double trace_rates[16], bounce_rates[16], own_rates[16];
                for (uint32_t k = 0; k < repeat; ++k)
                    trace_rates[k] = run[k].trace_kernel_mrays, bounce_rates[k] = run[k].bounce_kernel_mrays,
                    own_rates[k] = run[k].own_kernel_mrays;
                r->trace_kernel_mrays = bench_median(trace_rates, repeat);
                r->bounce_kernel_mrays = bench_median(bounce_rates, repeat);
                r->own_kernel_mrays = bench_median(own_rates, repeat);
                r->vs_trace = bench_median(vs_trace, repeat);
                r->vs_bounce = bench_median(vs_bounce, repeat);
                r->vs_own = bench_median(vs_own, repeat);
                double probe_rays = (double)r->probes * r->rays, gpu_ms = r->trace_ms + r->sh_ms + r->depth_ms;
                double mtrav = gpu_ms > 0 ? (double)r->traversals / (gpu_ms * 1e3) : 0.0;
                printf("%-18.18s %6u %6u %9.1f %8.1f %8.1f %9.1f %9.3f %9.3f %7.2f %7.2f %7.2f %8.4f\n", name, r->rays, 1u,
                       r->trace_ms, r->sh_ms, r->depth_ms, r->wall_ms, r->trace_ms > 0 ? probe_rays / (r->trace_ms * 1e3) : 0.0,
                       mtrav, r->vs_trace, r->vs_bounce, r->vs_own, r->rmse);
                fflush(stdout);
            }
            printf("%-18.18s reference: %.0f ms wall; trace kernel alone %.3f Mrays/s on probe rays, %.3f on bounce rays, "
                   "%.3f on the bake's own probe rays (%u of %u probes)\n",
                   name, ref_ms, bench_median(all_trace, nall), bench_median(all_bounce, nall), bench_median(all_own, nall),
                   no / (n / P), P);
            pb_volume_free(&ref);
        }
        free(rays), free(brays), free(orays), free(hits);
        pb_gpu_scene_destroy(gs);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
    }
    mkdir("bench/out", 0755);
    FILE *f = fopen(json, "w");
    if (f) {
        fprintf(f, "{\n  \"bench\": \"bake\",\n  \"device\": \"%s\",\n  \"bounces\": %u,\n  \"reference_passes\": %u,\n"
                   "  \"repeat\": %u,\n  \"schedule\": \"%s\",\n  \"results\": [\n", pb_context_device(ctx)->name, bounces,
                ref_passes, repeat, sched);
        for (int i = 0; i < nrows; ++i)
            fprintf(f,
                    "    {\"scene\": \"%s\", \"probes\": %u, \"rays_per_probe\": %u, \"passes\": %u, \"trace_ms\": %.3f, "
                    "\"sh_ms\": %.3f, \"depth_ms\": %.3f, \"wall_ms\": %.3f, \"relative_rmse\": %.6f, "
                    "\"traversals\": %llu, \"trace_kernel_mrays_per_s\": %.4f, \"bounce_kernel_mrays_per_s\": %.4f, "
                    "\"own_kernel_mrays_per_s\": %.4f, \"vs_trace\": %.4f, \"vs_bounce\": %.4f, \"vs_own\": %.4f}%s\n",
                    rows[i].scene, rows[i].probes, rows[i].rays, rows[i].passes, rows[i].trace_ms, rows[i].sh_ms,
                    rows[i].depth_ms, rows[i].wall_ms, rows[i].rmse, (unsigned long long)rows[i].traversals,
                    rows[i].trace_kernel_mrays, rows[i].bounce_kernel_mrays, rows[i].own_kernel_mrays, rows[i].vs_trace,
                    rows[i].vs_bounce, rows[i].vs_own, i + 1 < nrows ? "," : "");
        fprintf(f, "  ]\n}\n");
        fclose(f);
        printf("wrote %s\n", json);
    }
    uint32_t vmsgs = pb_context_validation_messages(ctx);
    if (vmsgs)
        fprintf(stderr, "%s: %u Vulkan validation messages\n", argv[0], vmsgs);
    pb_context_destroy(ctx);
    return vmsgs || nondeterministic ? 1 : 0;
}
