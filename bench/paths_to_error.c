/* paths_to_error: how many paths per probe each estimator needs for a given
 * irradiance error, against a converged reference (issue 12).
 *
 *   paths_to_error [--methods A,B,..] [--max-passes N] [--ref-paths N] [--ref-dir DIR]
 *                  [--make-reference] [--seed S] [--out DIR] [--validation] [SCENE ...]
 *
 * SCENE is one of the built-in cases (default: all present):
 *   doorway  tests/scenes/doorway.gltf: room B lit only through a doorway
 *   panel    tests/scenes/panel.gltf: a small bright panel and an occluder
 *   demo     tests/scenes/demo.gltf: a room with a 1 m^2 ceiling panel and a lamp
 *   cornell  ../shared/scenes/cornell/cornellBox.gltf
 *   crypt    ../shared/scenes/openarena/oacmpdm1.glb (5,776 small emitters)
 * (the last two are skipped with a message when ../shared is absent).
 *
 * Reference: the plain estimator at --ref-paths paths per probe (default
 * 2^20, 4096 rays x 256 passes, seed 1000), made once and cached in
 * DIR/<scene>.probes (bench/results/reference/); a cached file for another
 * scene or grid is refused (re-make it with --make-reference).
 *
 * Error per probe and axis: the irradiance (luminance) toward +-x, +-y, +-z
 * against the reference's, |E - E_ref| / max(E_ref, 5 % of the mean E_ref of
 * the scene), over the reference's valid probes. The sweep bakes at the
 * reference's (relocated) probe positions as points keyed by their grid
 * index: relocation is seeded, so baked again probes would land elsewhere.
 * Reported: the median and the 95th percentile.
 *
 * Each method bakes a sweep (256 rays x 1, 2, 4, ... passes for fixed
 * estimators, a falling --target-error for adaptive ones, seed 7 or --seed:
 * one seed's p95 moves by about 15 % between seeds on the Cornell box, so a
 * comparison of two estimators there wants several); the
 * paths per probe at which the median falls to 2 % and the p95 to 5 % are
 * interpolated log-log between sweep points (or extrapolated from the last
 * one as 1/sqrt(paths), marked ~). Each is compared with the plain path
 * tracer ("plain", always run first) in the same run: fewer paths (x) and
 * the GPU and wall time that buys.
 *
 * Writes DIR/paths_to_error.csv (every sweep point), DIR/paths_to_error.json
 * (the summary), a gnuplot script and, with gnuplot, DIR/paths_to_error.png
 * (p95 error against paths per probe, log-log). */
#define _POSIX_C_SOURCE 200809L
#include "common/common.h"
#include "bench_util.h"
#include "probebake/probebake.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MEDIAN_TARGET 0.02
#define P95_TARGET 0.05
#define MAX_SWEEP 16

typedef struct bench_case {
    const char *name, *path;
    uint32_t counts[3];          /* 0: a grid of `fit` probes over the bounds */
    double first[3], spacing;    /* scene coordinates of probe (0,0,0) */
    uint32_t fit;
} bench_case;

static const bench_case cases[] = {
    {"doorway", "tests/scenes/doorway.gltf", {8, 2, 4}, {-3.55, 1.0, -1.5}, 1.0, 0},
    {"panel", "tests/scenes/panel.gltf", {4, 3, 4}, {-1.5, 0.5, -1.5}, 1.0, 0},
    {"demo", "tests/scenes/demo.gltf", {0, 0, 0}, {0, 0, 0}, 0, 64},
    {"cornell", "../shared/scenes/cornell/cornellBox.gltf", {0, 0, 0}, {0, 0, 0}, 0, 64},
    {"crypt", "../shared/scenes/openarena/oacmpdm1.glb", {0, 0, 0}, {0, 0, 0}, 0, 160},
};
#define CASE_COUNT (int)(sizeof cases / sizeof cases[0])

/* An estimator under test: what it sets in the desc, and whether its sweep
 * runs over passes (fixed) or over target errors (adaptive). */
typedef struct method {
    const char *name;
    int adaptive;                /* 1: swept by target error (per-probe stopping) */
    uint32_t probe_nee;          /* pb_bake_desc.probe_nee */
    uint32_t guide_paths;        /* pb_bake_desc.guide_paths */
    uint32_t light_cells;        /* pb_bake_desc.light_cells */
    uint32_t emitters_by_area;   /* pb_bake_desc.emitters_by_area: the emitter sampler before solid angle */
} method;

static const method methods[] = {
    {"plain", 0, 0, 0},
    {"adaptive", 1, 0, 0},
    {"probe-nee", 0, 1, 0},
    {"nee+adapt", 1, 1, 0},
    {"guided", 0, 0, PB_GUIDE_DEFAULT_PATHS},
    {"nee+guide", 0, 1, PB_GUIDE_DEFAULT_PATHS},
    {"nee+cells", 0, 1, 0, 1},
    {"nee+cells+guide", 0, 1, PB_GUIDE_DEFAULT_PATHS, 1},
    {"all", 1, 1, PB_GUIDE_DEFAULT_PATHS, 1},  /* the production preset's estimators */
    {"plain-area", 0, 0, 0, 0, 1},              /* plain and all with emitters drawn by area */
    {"all-area", 1, 1, PB_GUIDE_DEFAULT_PATHS, 1, 1},
};
#define METHOD_COUNT (int)(sizeof methods / sizeof methods[0])

static void apply_method(const method *m, pb_bake_desc *d)
{
    d->probe_nee = m->probe_nee;
    d->guide_paths = m->guide_paths;
    d->light_cells = m->light_cells;
    d->emitters_by_area = m->emitters_by_area;
}

typedef struct point {
    double paths;                /* mean paths per probe */
    double gpu_ms, wall_ms;
    double median, p95;
} point;

/* Median and p95 of the per-axis relative irradiance error of v against ref
 * (header comment). *compared: probes compared, *moved: valid reference
 * probes left out because v has them elsewhere (none when v was baked at
 * the reference's positions, as the sweep is). */
static void axis_errors(const pb_volume *v, const pb_volume *ref, double *median, double *p95, uint32_t *compared,
                        uint32_t *moved)
{
    static const float axes[6][4] = {{1, 0, 0, 0}, {-1, 0, 0, 0}, {0, 1, 0, 0}, {0, -1, 0, 0}, {0, 0, 1, 0}, {0, 0, -1, 0}};
    uint32_t P = ref->probe_count;
    double *err = malloc((size_t)P * 6 * sizeof *err), *eref = malloc((size_t)P * 6 * sizeof *eref);
    uint32_t n = 0;
    double mean = 0;
    *compared = *moved = 0;
    *median = *p95 = NAN;
    if (!err || !eref)
        goto out;
    for (uint32_t p = 0; p < P; ++p) {
        if (!(ref->probe_flags[p] & PB_PROBE_VALID))
            continue;
        double a[3], b[3];
        pb_volume_probe_position(v, p, a);
        pb_volume_probe_position(ref, p, b);
        if (fabs(a[0] - b[0]) + fabs(a[1] - b[1]) + fabs(a[2] - b[2]) > 1e-4) {
            ++*moved;
            continue;
        }
        ++*compared;
        for (int a = 0; a < 6; ++a) {
            float e[3], r[3];
            pb_sh_eval(v->sh + 27 * (size_t)p, axes[a], e);
            pb_sh_eval(ref->sh + 27 * (size_t)p, axes[a], r);
            double le = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
            double lr = 0.2126 * r[0] + 0.7152 * r[1] + 0.0722 * r[2];
            err[n] = le - lr, eref[n] = lr, mean += lr, ++n;
        }
    }
    if (!n)
        goto out;
    mean /= n;
    for (uint32_t i = 0; i < n; ++i)
        err[i] = fabs(err[i]) / fmax(eref[i], 0.05 * mean);
    qsort(err, n, sizeof *err, bench_cmp_double);
    *median = err[n / 2];
    *p95 = err[(size_t)((n - 1) * 0.95 + 0.5)];
out:
    free(err), free(eref);
}

/* Paths (and times) at which the error series falls to `target`: log-log
 * interpolation between the sweep points around it; past the last point,
 * 1/sqrt(paths) from it (*how = '~'); at or below the first, the first
 * (*how = '<'). Errors are taken as the running minimum, so noise that
 * lifts a later point does not move the crossing back. */
static void crossing(const point *pts, int n, int use_p95, double target, double *paths, double *gpu, double *wall,
                     char *how)
{
    *how = ' ';
    double prev_e = INFINITY;
    for (int i = 0; i < n; ++i) {
        double e = fmin(prev_e, use_p95 ? pts[i].p95 : pts[i].median);
        if (e <= target) {
            if (i == 0) {
                *how = '<';
                *paths = pts[0].paths, *gpu = pts[0].gpu_ms, *wall = pts[0].wall_ms;
                return;
            }
            double e0 = prev_e, f = (log(e0) - log(target)) / (log(e0) - log(e));
            if (!(f >= 0 && f <= 1))
                f = 1;
            *paths = exp(log(pts[i - 1].paths) + f * (log(pts[i].paths) - log(pts[i - 1].paths)));
            *gpu = exp(log(pts[i - 1].gpu_ms) + f * (log(pts[i].gpu_ms) - log(pts[i - 1].gpu_ms)));
            *wall = exp(log(pts[i - 1].wall_ms) + f * (log(pts[i].wall_ms) - log(pts[i - 1].wall_ms)));
            return;
        }
        prev_e = e;
    }
    *how = '~';
    double k = prev_e / target;
    k *= k;
    *paths = pts[n - 1].paths * k, *gpu = pts[n - 1].gpu_ms * k, *wall = pts[n - 1].wall_ms * k;
}

static int parse_names(const char *s, const char **out, int max, const char *const *known, int nknown,
                       const char *what)
{
    int n = 0;
    char buf[256];
    snprintf(buf, sizeof buf, "%s", s);
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        int found = -1;
        for (int k = 0; k < nknown; ++k)
            if (!strcmp(tok, known[k]))
                found = k;
        if (found < 0) {
            fprintf(stderr, "paths_to_error: unknown %s '%s'\n", what, tok);
            exit(2);
        }
        if (n < max)
            out[n++] = known[found];
    }
    return n;
}

static int file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

/* Mean paths per probe from the file's accounting. */
static double mean_paths(const pb_volume *v)
{
    double sum = 0;
    for (uint32_t p = 0; p < v->probe_count; ++p)
        sum += v->probe_paths[p];
    return v->probe_count ? sum / v->probe_count : 0.0;
}

typedef struct summary {
    const char *scene, *method;
    double paths[2], gpu[2], wall[2]; /* [0]: median 2 %, [1]: p95 5 % */
    char how[2];
} summary;

int main(int argc, char **argv)
{
    uint32_t max_passes = 64, ref_paths = 1u << 20, seed = 7;
    const char *ref_dir = "bench/results/reference", *out_dir = "bench/out/paths_to_error";
    const char *method_names[METHOD_COUNT], *scene_names[CASE_COUNT];
    int nmethods = 0, nscenes = 0, make_ref = 0, validation = 0;
    const char *known_m[METHOD_COUNT], *known_s[CASE_COUNT];
    for (int k = 0; k < METHOD_COUNT; ++k)
        known_m[k] = methods[k].name;
    for (int k = 0; k < CASE_COUNT; ++k)
        known_s[k] = cases[k].name;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--methods") && v)
            nmethods = parse_names(argv[++i], method_names, METHOD_COUNT, known_m, METHOD_COUNT, "method");
        else if (!strcmp(a, "--max-passes") && v)
            max_passes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--ref-paths") && v)
            ref_paths = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--ref-dir") && v)
            ref_dir = argv[++i];
        else if (!strcmp(a, "--seed") && v)
            seed = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--out") && v)
            out_dir = argv[++i];
        else if (!strcmp(a, "--make-reference"))
            make_ref = 1;
        else if (!strcmp(a, "--validation"))
            validation = 1;
        else if (a[0] == '-') {
            fprintf(stderr, "paths_to_error: unknown option %s\n", a);
            return 2;
        } else {
            nscenes += parse_names(a, scene_names + nscenes, CASE_COUNT - nscenes, known_s, CASE_COUNT, "scene");
        }
    }
    if (!nmethods)
        for (int k = 0; k < METHOD_COUNT; ++k)
            method_names[nmethods++] = methods[k].name;
    if (!nscenes)
        for (int k = 0; k < CASE_COUNT; ++k)
            scene_names[nscenes++] = cases[k].name;
    if (max_passes < 1 || max_passes > 4096 || ref_paths < 256 || seed == 1000) {
        fprintf(stderr, "paths_to_error: --max-passes must be 1..4096, --ref-paths at least 256 and --seed not the "
                        "reference's (1000)\n");
        return 2;
    }
    mkdir(out_dir, 0755);
    mkdir(ref_dir, 0755);
    char csv_path[1024], json_path[1024], gp_path[1024], png_path[1024];
    snprintf(csv_path, sizeof csv_path, "%s/paths_to_error.csv", out_dir);
    snprintf(json_path, sizeof json_path, "%s/paths_to_error.json", out_dir);
    snprintf(gp_path, sizeof gp_path, "%s/paths_to_error.gp", out_dir);
    snprintf(png_path, sizeof png_path, "%s/paths_to_error.png", out_dir);
    FILE *csv = fopen(csv_path, "w");
    if (!csv) {
        fprintf(stderr, "paths_to_error: cannot write %s: %s\n", csv_path, strerror(errno));
        return 1;
    }
    fprintf(csv, "scene,method,param,paths_per_probe,gpu_ms,wall_ms,median,p95\n");
    pb_context *ctx = NULL;
    pb_error err;
    pb_context_desc cd = {NULL, (uint32_t)validation, 0, 0, {0}};
    if (pb_context_create(&cd, &ctx, &err) != PB_OK) {
        fprintf(stderr, "paths_to_error: %s\n", err.message);
        return 1;
    }
    printf("device: %s; error: per-axis irradiance against %u paths per probe; targets median %.0f %%, p95 %.0f %%\n",
           pb_context_device(ctx)->name, ref_paths, 100 * MEDIAN_TARGET, 100 * P95_TARGET);
    summary *sums = calloc((size_t)nscenes * nmethods, sizeof *sums);
    int nsums = 0, failed = 0;
    for (int si = 0; si < nscenes; ++si) {
        const bench_case *c = NULL;
        for (int k = 0; k < CASE_COUNT; ++k)
            if (!strcmp(cases[k].name, scene_names[si]))
                c = &cases[k];
        if (!file_exists(c->path)) {
            printf("%s: %s not present, skipped\n", c->name, c->path);
            continue;
        }
        pb_scene *s;
        pb_bvh *bvh;
        pb_gpu_scene *gs;
        if (!bench_open_scene(ctx, "paths_to_error", c->path, &s, &bvh, &gs)) {
            failed = 1;
            continue;
        }
        pb_bake_desc base;
        memset(&base, 0, sizeof base);
        if (c->fit) {
            pb_probe_grid_fit(s->bounds_min, s->bounds_max, c->fit, &base.grid);
        } else {
            for (int k = 0; k < 3; ++k) {
                base.grid.counts[k] = c->counts[k];
                base.grid.spacing[k] = (float)c->spacing;
                base.grid.origin[k] = (float)(c->first[k] - s->origin[k]);
            }
        }
        base.bounces = 2;
        /* the reference: cached, or made now */
        char ref_path[1024];
        snprintf(ref_path, sizeof ref_path, "%s/%s.probes", ref_dir, c->name);
        pb_volume ref;
        memset(&ref, 0, sizeof ref);
        int have = !make_ref && file_exists(ref_path) && pb_volume_read(ref_path, &ref, &err) == PB_OK;
        if (have && (ref.settings.scene_hash != pb_scene_hash(s) || ref.probe_count != pb_probe_grid_count(&base.grid) ||
                     mean_paths(&ref) < 0.5 * ref_paths)) {
            fprintf(stderr, "paths_to_error: %s: made for another scene, grid or path count; re-make it with "
                            "--make-reference\n", ref_path);
            pb_volume_free(&ref);
            failed = 1;
            goto next_scene;
        }
        if (!have) {
            pb_bake_desc d = base;
            d.rays_per_probe = ref_paths >= 4096 ? 4096 : 256;
            d.passes = ref_paths / d.rays_per_probe;
            d.seed = 1000, d.octmap_res = 4;
            printf("%s: making the reference (%u rays x %u passes per probe) ...\n", c->name, d.rays_per_probe,
                   d.passes);
            fflush(stdout);
            double t0 = pb_now_ms();
            if (pb_bake(ctx, s, gs, &d, &ref, &err) != PB_OK || pb_volume_write(ref_path, &ref, &err) != PB_OK) {
                fprintf(stderr, "paths_to_error: %s: %s\n", c->name, err.message);
                pb_volume_free(&ref);
                failed = 1;
                goto next_scene;
            }
            printf("%s: reference written to %s in %.1f s\n", c->name, ref_path, (pb_now_ms() - t0) / 1e3);
        }
        /* the sweep bakes at the reference's probe positions (relocation is
         * seeded: baked again, probes would land elsewhere), keyed by their
         * grid index as in the reference, with no relocation */
        pb_points pts = {ref.probe_count, malloc((size_t)ref.probe_count * 3 * sizeof(double)),
                         malloc((size_t)ref.probe_count * sizeof(uint32_t)), 0.0};
        if (!pts.positions || !pts.ids) {
            fprintf(stderr, "paths_to_error: out of memory\n");
            pb_points_free(&pts);
            pb_volume_free(&ref);
            failed = 1;
            goto next_scene;
        }
        for (uint32_t p = 0; p < ref.probe_count; ++p) {
            pb_volume_probe_position(&ref, p, pts.positions + 3 * (size_t)p);
            pts.ids[p] = p;
        }
        base.points = &pts;
        uint32_t valid = 0;
        for (uint32_t p = 0; p < ref.probe_count; ++p)
            valid += (ref.probe_flags[p] & PB_PROBE_VALID) != 0;
        /* the reference's own noise: its relative standard errors (DC), a floor under what the sweep can show */
        double *rse = malloc((size_t)ref.probe_count * sizeof *rse);
        uint32_t nr = 0;
        for (uint32_t p = 0; rse && p < ref.probe_count; ++p)
            if ((ref.probe_flags[p] & PB_PROBE_VALID) && ref.probe_std_error[p] >= 0.f)
                rse[nr++] = ref.probe_std_error[p];
        if (nr)
            qsort(rse, nr, sizeof *rse, bench_cmp_double);
        printf("\n%s (%u probes, %u valid; reference %.0f paths per probe, its standard error median %.2f %%, "
               "p95 %.2f %%)\n", c->name, ref.probe_count, valid, mean_paths(&ref), nr ? 100 * rse[nr / 2] : NAN,
               nr ? 100 * rse[(size_t)((nr - 1) * 0.95 + 0.5)] : NAN);
        free(rse);
        printf("  %-10s %8s %10s %10s %10s %9s %9s\n", "method", "param", "paths/prb", "GPU ms", "wall ms", "median",
               "p95");
        int plain_index = -1;
        for (int mi = 0; mi < nmethods; ++mi) {
            const method *m = NULL;
            for (int k = 0; k < METHOD_COUNT; ++k)
                if (!strcmp(methods[k].name, method_names[mi]))
                    m = &methods[k];
            point pts[MAX_SWEEP];
            int np = 0;
            uint32_t compared = 0, moved = 0;
            {
                pb_bake_desc w = base;
                apply_method(m, &w);
                w.seed = seed, w.octmap_res = 16;
                if (!bench_warm_bake(ctx, s, gs, &w, &err)) {
                    fprintf(stderr, "paths_to_error: %s %s: %s\n", c->name, m->name, err.message);
                    failed = 1;
                    continue;
                }
            }
            for (int step = 0; step < MAX_SWEEP; ++step) {
                pb_bake_desc d = base;
                apply_method(m, &d);
                d.rays_per_probe = 256, d.seed = seed, d.octmap_res = 16;
                double param;
                if (m->adaptive) {
                    d.target_error = (float)(0.32 / (1u << step));
                    d.passes = max_passes;
                    param = d.target_error;
                } else {
                    d.passes = 1u << step;
                    if (d.passes > max_passes)
                        break;
                    param = d.passes;
                }
                pb_volume v;
                double t0 = pb_now_ms();
                if (pb_bake(ctx, s, gs, &d, &v, &err) != PB_OK) {
                    fprintf(stderr, "paths_to_error: %s %s: %s\n", c->name, m->name, err.message);
                    failed = 1;
                    break;
                }
                point *pt = &pts[np++];
                pt->wall_ms = pb_now_ms() - t0;
                pt->gpu_ms = v.timings.trace + v.timings.sh + v.timings.octmap;
                pt->paths = mean_paths(&v);
                axis_errors(&v, &ref, &pt->median, &pt->p95, &compared, &moved);
                pb_volume_free(&v);
                printf("  %-10s %8.4g %10.0f %10.1f %10.1f %8.2f%% %8.2f%%\n", m->name, param, pt->paths, pt->gpu_ms,
                       pt->wall_ms, 100 * pt->median, 100 * pt->p95);
                fflush(stdout);
                fprintf(csv, "%s,%s,%g,%.1f,%.3f,%.3f,%.6f,%.6f\n", c->name, m->name, param, pt->paths, pt->gpu_ms,
                        pt->wall_ms, pt->median, pt->p95);
                fflush(csv);
                /* adaptive sweeps end where the pass cap binds: near it, or where the paths stop growing
                 * past a quarter of it (probes that cannot converge, or have no variance, hold the mean) */
                double cap = 256.0 * max_passes;
                if (m->adaptive && (pt->paths >= 0.9 * cap ||
                                    (np >= 2 && pt->paths <= 1.01 * pts[np - 2].paths && pt->paths > 0.25 * cap)))
                    break;
                if (pt->p95 < 0.5 * P95_TARGET && pt->median < 0.5 * MEDIAN_TARGET)
                    break; /* well past both targets */
            }
            if (!np)
                continue;
            summary *u = &sums[nsums++];
            u->scene = c->name, u->method = m->name;
            crossing(pts, np, 0, MEDIAN_TARGET, &u->paths[0], &u->gpu[0], &u->wall[0], &u->how[0]);
            crossing(pts, np, 1, P95_TARGET, &u->paths[1], &u->gpu[1], &u->wall[1], &u->how[1]);
            if (!strcmp(m->name, "plain"))
                plain_index = nsums - 1;
            if (moved)
                printf("  (%u probes compared, %u left out: not where the reference's are)\n", compared, moved);
        }
        /* the scene's summary against the plain path tracer */
        printf("  to reach   %-10s %12s %8s %10s %10s %8s %8s\n", "method", "paths/probe", "fewer", "GPU s", "wall s",
               "GPU x", "wall x");
        for (int k = 0; k < nsums; ++k) {
            summary *u = &sums[k];
            if (strcmp(u->scene, c->name))
                continue;
            for (int t = 0; t < 2; ++t) {
                const summary *pl = plain_index >= 0 ? &sums[plain_index] : NULL;
                printf("  %-9s  %-10s %c%11.0f %7.2fx %10.2f %10.2f %7.2fx %7.2fx\n", t ? "p95 5%" : "median 2%",
                       u->method, u->how[t], u->paths[t], pl ? pl->paths[t] / u->paths[t] : 0.0, u->gpu[t] / 1e3,
                       u->wall[t] / 1e3, pl ? pl->gpu[t] / u->gpu[t] : 0.0, pl ? pl->wall[t] / u->wall[t] : 0.0);
            }
        }
        pb_points_free(&pts);
        pb_volume_free(&ref);
    next_scene:
        pb_gpu_scene_destroy(gs);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
    }
    fclose(csv);
    FILE *js = fopen(json_path, "w");
    if (js) {
        fprintf(js, "{\n  \"device\": \"%s\",\n  \"reference_paths\": %u,\n  \"targets\": {\"median\": %g, \"p95\": %g},\n"
                    "  \"results\": [",
                pb_context_device(ctx)->name, ref_paths, MEDIAN_TARGET, P95_TARGET);
        for (int k = 0; k < nsums; ++k) {
            const summary *u = &sums[k];
            fprintf(js, "%s\n    {\"scene\": \"%s\", \"method\": \"%s\"", k ? "," : "", u->scene, u->method);
            for (int t = 0; t < 2; ++t)
                fprintf(js, ", \"%s\": {\"paths_per_probe\": %.1f, \"gpu_ms\": %.2f, \"wall_ms\": %.2f, "
                            "\"estimate\": \"%s\"}",
                        t ? "p95" : "median", u->paths[t], u->gpu[t], u->wall[t],
                        u->how[t] == '~' ? "extrapolated" : u->how[t] == '<' ? "at most" : "interpolated");
            fprintf(js, "}");
        }
        fprintf(js, "\n  ]\n}\n");
        fclose(js);
        printf("\nwrote %s\n", json_path);
    }
    free(sums);
    FILE *gp = fopen(gp_path, "w");
    if (gp) {
        /* one panel per scene, its methods as curves */
        fprintf(gp,
                "set terminal pngcairo size 1400,1000\nset output '%s'\nset datafile separator ','\n"
                "set logscale xy\nset xlabel 'paths per probe'\nset ylabel 'p95 per-axis irradiance error'\n"
                "set key top right font ',8'\nset grid\n"
                "scenes = system(\"tail -n +2 '%s' | cut -d, -f1 | awk '!s[$0]++' | tr '\\\\n' ' '\")\n"
                "methods = system(\"tail -n +2 '%s' | cut -d, -f2 | awk '!s[$0]++' | tr '\\\\n' ' '\")\n"
                "n = words(scenes)\nset multiplot layout (n + 1) / 2, 2\n"
                "do for [sc in scenes] {\n  set title sc\n"
                "  plot for [m in methods] '%s' using ((strcol(1) eq sc && strcol(2) eq m) ? $4 : 1/0):8 "
                "with linespoints title m, %g with lines dt 2 title 'p95 target'\n}\nunset multiplot\n",
                png_path, csv_path, csv_path, csv_path, P95_TARGET);
        fclose(gp);
        bench_run_gnuplot(gp_path, png_path);
    }
    printf("wrote %s\n", csv_path);
    uint32_t vmsgs = pb_context_validation_messages(ctx);
    if (vmsgs)
        fprintf(stderr, "paths_to_error: %u Vulkan validation messages\n", vmsgs);
    pb_context_destroy(ctx);
    return vmsgs || failed ? 1 : 0;
}
