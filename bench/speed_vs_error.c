/* speed_vs_error: what each bake setting buys, in time and in error.
 *
 *   speed_vs_error [--probes N] [--rays A,B,...] [--bounces A,B,...] [--size WxH]
 *                  [--ref-rays N] [--ref-passes N] [--ref-spp N] [--out DIR] [SCENE ...]
 *
 * Per scene: the trace kernel's and Embree's rays/s on the same probe rays
 * (the device ratio); then per bounce count a converged reference (path
 * traced, ref-rays x ref-passes) and a path-traced reference image; then for
 * --indirect path and volume and each ray count, one bake pass: GPU time
 * (trace + SH + depth timestamps) and wall time against
 *   (a) probe error: relative RMSE of irradiance luminance over valid probes
 *       and 64 directions, against the converged reference volume;
 *   (b) image error: relative RMSE of a probe-lit image (4 spp) against the
 *       path-traced image, over surface pixels.
 * Writes DIR/speed_vs_error.csv, a gnuplot script and, when gnuplot is on
 * PATH, DIR/speed_vs_error.png (log-log, error against GPU time). */
#define _POSIX_C_SOURCE 200809L
#include "common/common.h"
#include "embree_peer.h"
#include "bench_util.h"
#include "probebake/probebake.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>


static int parse_list(const char *s, uint32_t *out, int max)
{
    int n = 0;
    while (*s && n < max) {
        char *end;
        unsigned long v = strtoul(s, &end, 10);
        if (end == s)
            break;
        out[n++] = (uint32_t)v;
        s = *end == ',' ? end + 1 : end;
    }
    return n;
}

static const char *base_name(const char *p)
{
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

int main(int argc, char **argv)
{
    uint32_t probes = 128, rays[16] = {32, 128, 512, 2048, 4096}, bounces[8] = {1, 3}, W = 128, H = 96;
    uint32_t ref_rays = 1024, ref_passes = 8, ref_spp = 256;
    int nrays = 5, nbounces = 2, nscenes = 0;
    const char *out_dir = "bench/out", *scenes[16];
    int validation = 0; /* --validation: fail on any Vulkan validation message */
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--probes") && v)
            probes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--rays") && v)
            nrays = parse_list(argv[++i], rays, 16);
        else if (!strcmp(a, "--bounces") && v)
            nbounces = parse_list(argv[++i], bounces, 8);
        else if (!strcmp(a, "--size") && v)
            sscanf(argv[++i], "%ux%u", &W, &H);
        else if (!strcmp(a, "--ref-rays") && v)
            ref_rays = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--ref-passes") && v)
            ref_passes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--ref-spp") && v)
            ref_spp = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--out") && v)
            out_dir = argv[++i];
        else if (!strcmp(a, "--validation"))
            validation = 1;
        else if (a[0] == '-') {
            fprintf(stderr, "speed_vs_error: unknown option %s\n", a);
            return 2;
        } else if (nscenes < 16)
            scenes[nscenes++] = a;
    }
    if (!nscenes)
        nscenes = bench_default_scenes("speed_vs_error", scenes, 16);
    mkdir(out_dir, 0755);
    char csv_path[1024], gp_path[1024], png_path[1024];
    snprintf(csv_path, sizeof csv_path, "%s/speed_vs_error.csv", out_dir);
    snprintf(gp_path, sizeof gp_path, "%s/speed_vs_error.gp", out_dir);
    snprintf(png_path, sizeof png_path, "%s/speed_vs_error.png", out_dir);
    FILE *csv = fopen(csv_path, "w");
    if (!csv) {
        fprintf(stderr, "speed_vs_error: cannot write %s\n", csv_path);
        return 1;
    }
    pb_context *ctx = NULL;
    pb_error err;
    pb_context_desc cd = {NULL, (uint32_t)validation, 0, 0, {0}};
    if (pb_context_create(&cd, &ctx, &err) != PB_OK) {
        fprintf(stderr, "speed_vs_error: %s\n", err.message);
        return 1;
    }
    RTCDevice edev = rtcNewDevice(NULL);
    char device[256]; /* CSV-safe: llvmpipe's name has a comma */
    snprintf(device, sizeof device, "%s", pb_context_device(ctx)->name);
    for (char *c = device; *c; ++c)
        if (*c == ',')
            *c = ';';
    fprintf(csv, "scene,device,indirect,bounces,rays_per_probe,probes,gpu_ms,wall_ms,probe_rel_rmse,image_rel_rmse,"
                 "trace_mrays,embree_mrays\n");
    printf("device: %s; %u probes, reference %u rays x %u passes, images %ux%u (reference %u spp)\n",
           pb_context_device(ctx)->name, probes, ref_rays, ref_passes, W, H, ref_spp);
    printf("%-16s %-6s %3s %6s %10s %10s %10s %10s\n", "scene", "mode", "bnc", "rays", "GPU ms", "wall ms", "probe err",
           "image err");
    for (int si = 0; si < nscenes; ++si) {
        pb_scene *s;
        pb_bvh *bvh;
        pb_gpu_scene *gs;
        if (!bench_open_scene(ctx, "speed_vs_error", scenes[si], &s, &bvh, &gs))
            continue;
        const char *name = base_name(scenes[si]);
        pb_bake_desc d = {0};
        pb_probe_grid_fit(s->bounds_min, s->bounds_max, probes, &d.grid);
        d.octmap_res = 16;
        /* device against Embree on the same probe rays */
        double trace_mrays = 0, embree_mrays = 0;
        {
            uint32_t P = pb_probe_grid_count(&d.grid), n = P * 256;
            pb_ray *pr = malloc((size_t)n * sizeof *pr);
            pb_hit *hits = malloc((size_t)n * sizeof *hits);
            float *et = malloc((size_t)n * sizeof *et);
            embree_peer peer;
            if (pr && hits && et && pb_probe_rays(&d.grid, 0, P, 256, 1, pr) == PB_OK &&
                pb_trace(ctx, gs, pr, n, PB_TRACE_CLOSEST, hits, NULL, &err) == PB_OK) /* untimed: warms it */
                trace_mrays = bench_trace_rate(ctx, gs, pr, n, hits);
            if (pr && et && embree_peer_build(edev, s, 0, &peer)) {
                embree_peer_trace(&peer, pr, n, et);
                embree_mrays = n / (embree_peer_trace(&peer, pr, n, et) * 1e3);
                embree_peer_release(&peer);
            }
            free(pr), free(hits), free(et);
        }
        printf("%-16.16s trace kernel %.3f Mrays/s, Embree %.3f Mrays/s: ratio %.3f\n", name, trace_mrays, embree_mrays,
               embree_mrays > 0 ? trace_mrays / embree_mrays : 0.0);
        /* a camera: the scene's first, else the bounds seen from the front */
        pb_render_desc rd;
        memset(&rd, 0, sizeof rd);
        if (s->camera_count) {
            pb_camera_from_scene(&s->cameras[0], &rd.camera);
        } else {
            float ext = 0.f;
            for (int k = 0; k < 3; ++k)
                ext = fmaxf(ext, s->bounds_max[k] - s->bounds_min[k]);
            for (int k = 0; k < 3; ++k) {
                float c = 0.5f * (s->bounds_min[k] + s->bounds_max[k]);
                rd.camera.eye[k] = c + (k == 1 ? 0.3f * ext : k == 2 ? 1.2f * ext : 0.f);
                rd.camera.forward[k] = c - rd.camera.eye[k];
            }
            rd.camera.up[1] = 1.f;
            rd.camera.yfov = 0.9f;
        }
        rd.width = W, rd.height = H;
        uint64_t pixels = (uint64_t)W * H;
        float *truth = malloc(pixels * 16), *img = malloc(pixels * 16);
        for (int bi = 0; bi < nbounces && truth && img; ++bi) {
            pb_volume ref;
            d.bounces = bounces[bi];
            d.indirect_volume = 0;
            d.rays_per_probe = ref_rays, d.passes = ref_passes, d.seed = 1000;
            if (pb_bake(ctx, s, gs, &d, &ref, &err) != PB_OK) {
                fprintf(stderr, "speed_vs_error: %s: %s\n", name, err.message);
                continue;
            }
            /* a volume of N bounces lights surfaces with light of N + 1 reflections at the probes, plus the
             * reflection at the surface: the matching reference traces N + 1 bounces after the first hit */
            if (!s->camera_count && bi == 0) {
                /* no camera in the file: stand at the valid probe nearest the bounds' centre (open space by
                 * construction) and look along +X, a little down */
                double best = INFINITY;
                for (uint32_t p = 0; p < ref.probe_count; ++p) {
                    if (!(ref.probe_flags[p] & PB_PROBE_VALID) || (ref.probe_flags[p] & PB_PROBE_OUTSIDE))
                        continue;
                    double pos[3], dd = 0;
                    pb_volume_probe_position(&ref, p, pos);
                    for (int k = 0; k < 3; ++k) {
                        double c = s->origin[k] + 0.5 * (s->bounds_min[k] + s->bounds_max[k]);
                        dd += (pos[k] - c) * (pos[k] - c);
                    }
                    if (dd < best) {
                        best = dd;
                        for (int k = 0; k < 3; ++k)
                            rd.camera.eye[k] = (float)(pos[k] - s->origin[k]);
                    }
                }
                rd.camera.forward[0] = 1.f, rd.camera.forward[1] = -0.2f, rd.camera.forward[2] = 0.3f;
                rd.camera.up[0] = 0.f, rd.camera.up[1] = 1.f, rd.camera.up[2] = 0.f;
                rd.camera.yfov = 1.2f;
            }
            rd.mode = PB_RENDER_REFERENCE, rd.spp = ref_spp, rd.bounces = bounces[bi] + 1, rd.seed = 1000;
            rd.volume = NULL;
            if (pb_render(ctx, s, gs, &rd, truth, NULL, NULL, &err) != PB_OK) {
                fprintf(stderr, "speed_vs_error: %s: %s\n", name, err.message);
                pb_volume_free(&ref);
                continue;
            }
            for (int mode = 0; mode < 2; ++mode)
                for (int ri = 0; ri < nrays; ++ri) {
                    pb_volume v;
                    d.indirect_volume = (uint32_t)mode;
                    d.rays_per_probe = rays[ri], d.passes = 1, d.seed = 7;
                    if (ri == 0 && !bench_warm_bake(ctx, s, gs, &d, &err)) { /* volume mode's kernels are others */
                        fprintf(stderr, "speed_vs_error: %s: %s\n", name, err.message);
                        break;
                    }
                    double t0 = pb_now_ms();
                    if (pb_bake(ctx, s, gs, &d, &v, &err) != PB_OK) {
                        fprintf(stderr, "speed_vs_error: %s: %s\n", name, err.message);
                        continue;
                    }
                    double wall = pb_now_ms() - t0, gpu = v.timings.trace + v.timings.sh + v.timings.octmap;
                    double perr = bench_volume_rmse(&v, &ref), ierr = -1;
                    pb_sample_volume sv;
                    if (pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK) {
                        pb_render_desc pd = rd;
                        pd.mode = PB_RENDER_PROBES, pd.spp = 4, pd.seed = 5, pd.volume = &sv;
                        pd.volume_direct = (v.flags & PB_VOLUME_DIRECT) != 0;
                        uint64_t surface = 0;
                        for (uint64_t q = 0; q < pixels; ++q)
                            surface += truth[4 * q + 3] > 0.f;
                        if (surface && pb_render(ctx, s, gs, &pd, img, NULL, NULL, &err) == PB_OK)
                            ierr = pb_image_relative_rmse(img, truth, W, H); /* -1: no surface in view */
                        pb_sample_volume_free(&sv);
                    }
                    const char *m = mode ? "volume" : "path";
                    printf("%-16.16s %-6s %3u %6u %10.1f %10.1f %10.4f %10.4f\n", name, m, bounces[bi], rays[ri], gpu,
                           wall, perr, ierr);
                    fflush(stdout);
                    fprintf(csv, "%s,%s,%s,%u,%u,%u,%.3f,%.3f,%.6f,%.6f,%.4f,%.4f\n", name, device, m, bounces[bi], rays[ri], v.probe_count, gpu, wall, perr, ierr,
                            trace_mrays, embree_mrays);
                    fflush(csv);
                    pb_volume_free(&v);
                }
            pb_volume_free(&ref);
        }
        free(truth), free(img);
        pb_gpu_scene_destroy(gs);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
    }
    fclose(csv);
    rtcReleaseDevice(edev);
    uint32_t vmsgs = pb_context_validation_messages(ctx);
    if (vmsgs)
        fprintf(stderr, "%s: %u Vulkan validation messages\n", argv[0], vmsgs);
    pb_context_destroy(ctx);
    /* the plot: probe error against GPU time, log-log, one line per scene / mode / bounces */
    FILE *gp = fopen(gp_path, "w");
    if (gp) {
        fprintf(gp,
                "set terminal pngcairo size 1100,700\nset output '%s'\nset datafile separator ','\n"
                "set logscale xy\nset xlabel 'bake GPU time (ms)'\nset ylabel 'relative RMSE of probe irradiance'\n"
                "set key outside right\nset grid\n"
                "scenes = system(\"tail -n +2 '%s' | cut -d, -f1 | sort -u | tr '\\\\n' ' '\")\n"
                "plot for [s in scenes] for [m in 'path volume'] for [b in '1 3'] '%s' using "
                "((strcol(1) eq s && strcol(3) eq m && strcol(4) eq b) ? $7 : 1/0):9 with linespoints "
                "title s.' '.m.' '.b.' bnc'\n",
                png_path, csv_path, csv_path);
        fclose(gp);
        bench_run_gnuplot(gp_path, png_path);
    }
    printf("wrote %s\n", csv_path);
    return vmsgs ? 1 : 0;
}
