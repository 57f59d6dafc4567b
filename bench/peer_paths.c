/* peer_paths: what a path costs the bake on this Vulkan device against a CPU
 * path tracer on this host's cores, path for path.
 *
 *   peer_paths [--probes N] [--rays N] [--passes N] [--bounces N] [--methods plain,all,nee,cells,guide]
 *              [--repeat N] [--restart K[:M]] [--out DIR] [--validation] [SCENE ...]
 *
 * The peer is the bake's own CPU reference path tracer (src/bake/bake_cpu.c:
 * the kernels' estimators line by line, the same random numbers) casting its
 * rays with Embree 3 on all host threads (pb_bake_pass.cast), so both trace
 * the same paths to the same error, and the ratio of their rates is the
 * ratio of their times to any accuracy. Per scene and method, one bake of
 * --passes passes of --probes probes (a fitted grid, not relocated) x
 * --rays rays, --bounces bounces:
 *   bake   GPU time of the trace kernel (timestamps: paths, shading, every
 *          ray), and of all three kernels (trace + SH + depth);
 *   peer   wall time of the same paths on the host (Embree's rays);
 *   own    the same C path tracer over the bake's BVH (pb_trace_cpu);
 * the issue-11 ratio for both tracers ("trc"): traversals (probe, bounce and
 * shadow rays, as the kernel counts them) per second of path tracing, over
 * the same tracer's rate on plain probe rays (256 per probe of the grid,
 * timed in each round): the bake's on all its GPU time (trace + SH + depth)
 * against the trace kernel, bake_bench's "vs trc"; the peer's on its wall
 * time against Embree's rtcIntersect1 on all threads. Beside them each
 * tracer's rate on those probe rays' bounce rays over its probe-ray rate
 * ("b/t", bounce_rays.h): the ceiling of "trc" for paths made of bounce rays.
 * Then each tracer alone on exactly the rays the peer cast (recorded once,
 * bench/ray_log.h), per second over its probe-ray rate: "em own", Embree
 * (the "trc" of a path tracer on Embree whose shading cost nothing);
 * "kr own", the trace kernel with the rays packed in the bake's lane-group
 * order (8 paths of a probe, their k-th rays together); "kr grp" and "kr
 * mix", the kernel with the rays in the bake's very lane groups, a lane
 * whose path has ended idle (kinds of ray apart, or together as the bake's
 * one trace loop runs them); "kr pmx", packed with both kinds together (as
 * a compaction that moves paths between lanes, keeping the groups' order,
 * would trace them); "kr 1cp", the probe rays in the bake's groups, then
 * the paths that go on packed 8 to a group (a schedule that compacts once,
 * after the first hit); "kr wg", each workgroup's 64 paths compacted before
 * every ray (the k-th rays of those still going, packed); with
 * --restart K:M, "kr rst", the rays as lanes that each trace K paths, an
 * idle lane beginning its next one every M loop iterations, would trace
 * them (ray_log_restart: a schedule measured before it is built). Between
 * "kr own" and the bake's "trc" lie the lanes its schedule leaves idle, its
 * shading and its SH and depth kernels.
 * And "agree": the relative RMSE of the peer's irradiance against the
 * bake's (64 directions per valid probe), which is noise-sized only where
 * a hit decides differently (a blended surface's hashed threshold, a
 * Russian roulette draw), else ~1e-7. The run fails where the C path
 * tracer over the bake's own BVH is off the bake by more than
 * AGREE_OWN_MAX in a scene without blended surfaces: then the peer does
 * not trace the bake's paths (or the kernels left their CPU reference).
 * Methods: plain (no probe NEE, light cells or guiding) and all (probe
 * NEE, light cells, path guiding: the production preset's estimators with
 * a fixed path count). Times are medians of --repeat rounds (default 3; the
 * bake and its peers alternate within each round, as lavapipe drifts),
 * after an untimed bake that has the driver compile the kernels
 * (bench_warm_bake).
 * Writes DIR/peer_paths.csv and DIR/peer_paths.json (default bench/out). */
#define _GNU_SOURCE /* sched_setaffinity */
#include "bake/gpu_scene.h"
#include "bake/guide_cache.h"
#include "bake/light_cells_gpu.h"
#include "bake/shading.h"
#include "bench_util.h"
#include "bounce_rays.h"
#include "common/common.h"
#include "embree_peer.h"
#include "probebake/probebake.h"
#include "ray_log.h"

#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct method {
    const char *name;
    uint32_t probe_nee, light_cells, guide_paths;
} method;

/* plain and all by default; each estimator alone on request, to tell what
 * each one's shading costs the kernel (--methods plain,nee,cells,guide,all) */
static const method methods[] = {
    {"plain", 0, 0, 0},
    {"all", 1, 1, PB_GUIDE_DEFAULT_PATHS},
    {"nee", 1, 0, 0},
    {"cells", 0, 1, 0},
    {"guide", 0, 0, PB_GUIDE_DEFAULT_PATHS},
};
#define METHOD_COUNT (int)(sizeof methods / sizeof methods[0])
#define MAX_REPEAT 15
#define LAYOUTS RAY_LOG_LAYOUTS
#define RESTART LAYOUTS /* own_rays' slot for --restart's schedule */
#define AGREE_OWN_MAX 1e-3 /* a rare Russian roulette draw flipped by rounding moves ~1e-4 */

typedef struct row {
    const char *scene, *method;
    uint64_t paths;
    double bake_trace_ms, bake_gpu_ms, peer_ms, own_ms; /* medians of the rounds */
    double agree_peer, agree_own;                        /* relative RMSE against the bake */
    uint64_t bake_trav, peer_trav;                       /* traversals of one bake, of the peer's paths */
    double bake_trc, peer_trc, kernel_bt, embree_bt;     /* medians of the rounds' ratios */
    double embree_own, kernel_own[LAYOUTS + 1]; /* alone on the peer's rays over the probe-ray rate; 0: none */
} row;

/* The CPU tracer's inputs that pb_bake learned on the device side and keeps
 * with the GPU scene (the light cells, the guide), and the shading tables. */
typedef struct peer_inputs {
    pb_bake_emitters emit;
    pb_env_table env;
    pb_light_table lights;
    int draws_lights;
} peer_inputs;

/* Runs the CPU path tracer of tmpl over every pass of d, as pb_bake places,
 * turns and lights its probes; sh: 27 irradiance coefficients per probe
 * (NULL: paths only, not the SH projection, whose punctual lights' shadow
 * rays are no path's).
 * Returns the wall ms of the path tracing (pb_bake_trace_cpu) alone, or a
 * negative number when out of memory; *trav: the traversals it made. */
static double cpu_bake(const pb_scene *s, const pb_bake_desc *d, pb_bake_pass tmpl, uint32_t P, float *sh,
                       uint64_t *trav)
{
    uint32_t rpp = d->rays_per_probe, n = d->octmap_res ? d->octmap_res : 16;
    float *probes = calloc((size_t)P * 4, sizeof(float)), *rot = malloc((size_t)P * 48);
    float *dirs = malloc((size_t)rpp * 16), *rays = malloc((size_t)P * rpp * 16);
    float *red = calloc((size_t)P * (40 + 2 * n * n), sizeof(float));
    float *nee = d->probe_nee ? malloc((size_t)P * rpp * 32) : NULL;
    double *sum = calloc((size_t)P * 27, sizeof(double)), ms = 0.0;
    *trav = 0;
    if (!probes || !rot || !dirs || !rays || !red || !sum || (d->probe_nee && !nee)) {
        ms = -1.0;
        goto out;
    }
    for (uint32_t pass = 0; pass < d->passes; ++pass) {
        pb_bake_pass_inputs(s, d, P, rpp, pass, probes, rot, dirs);
        pb_bake_pass pp = tmpl;
        pp.probes = probes, pp.probe_list = NULL, pp.rotations = rot, pp.directions = dirs;
        pp.first_probe = 0, pp.probe_count = P, pp.rays_per_probe = rpp, pp.pass_index = pass;
        pp.octmap_res = n, pp.nee = nee;
        double t0 = pb_now_ms();
        *trav += pb_bake_trace_cpu(&pp, rays);
        ms += pb_now_ms() - t0;
        if (!sh)
            continue;
        pb_bake_sh_cpu(&pp, rays, red);
        for (uint32_t p = 0; p < P; ++p)
            for (int k = 0; k < 27; ++k)
                sum[27 * (size_t)p + k] += red[40 * (size_t)p + k] / (double)d->passes;
    }
    for (uint32_t p = 0; sh && p < P; ++p) {
        for (int k = 0; k < 27; ++k)
            sh[27 * (size_t)p + k] = (float)sum[27 * (size_t)p + k];
        pb_sh_radiance_to_irradiance(sh + 27 * (size_t)p);
    }
out:
    free(probes), free(rot), free(dirs), free(rays), free(red), free(nee), free(sum);
    return ms;
}

/* The rays the peer cast, laid out in each of ray_log.h's layouts (indexed
 * by ray_log_layout) and, when asked, as --restart's schedule. real: how
 * many rays (the layouts with idle lanes hold more entries). */
typedef struct own_rays {
    pb_ray *closest[LAYOUTS + 1], *any[LAYOUTS + 1]; /* [RESTART]: ray_log_restart's list, if asked */
    uint64_t closest_count[LAYOUTS + 1], any_count[LAYOUTS + 1], real;
    pb_hit *hits; /* room for the longest list */
} own_rays;

static void own_rays_free(own_rays *o)
{
    for (int k = 0; k <= LAYOUTS; ++k)
        free(o->closest[k]), free(o->any[k]);
    free(o->hits);
    memset(o, 0, sizeof *o);
}

/* The trace kernel's Mrays/s on the rays of layout k (closest-hit and
 * any-hit rays in one call each; idle lanes not counted); 0 when it fails. */
static double kernel_rate_own(pb_context *ctx, pb_gpu_scene *gs, const own_rays *o, int k)
{
    pb_error err;
    pb_trace_stats sc = {0}, sa = {0};
    if ((o->closest_count[k] && pb_trace(ctx, gs, o->closest[k], (uint32_t)o->closest_count[k], PB_TRACE_CLOSEST,
                                         o->hits, &sc, &err) != PB_OK) ||
        (o->any_count[k] &&
         pb_trace(ctx, gs, o->any[k], (uint32_t)o->any_count[k], PB_TRACE_ANY, o->hits, &sa, &err) != PB_OK))
        return 0.0;
    double ms = sc.kernel_ms + sa.kernel_ms;
    return ms > 0 ? o->real / (ms * 1e3) : 0.0;
}

/* The peer's rays, from one untimed run of the peer's paths (trav: the
 * traversals of a timed run). Returns 1; 0 and no rays when they do not fit
 * in host memory (the record, its packed layouts and the hits take about 4
 * copies of the rays, and each of the 3 layouts with idle lanes up to one
 * per 8 lanes of a group: all kept to a quarter of the machine's memory);
 * -1 when the record is not the peer's paths (another count of rays, rays
 * before a path's first, lists that lose or add rays): the bench is wrong. */
static int record_rays(const pb_scene *s, const pb_bake_desc *d, pb_bake_pass tmpl, uint32_t P,
                       const embree_peer *peer, uint64_t trav, uint32_t lanes, uint32_t restart_k, uint32_t restart_m,
                       own_rays *o)
{
    memset(o, 0, sizeof *o);
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    uint64_t copies = 4 + 3 * (lanes > 8 ? lanes / 8 : 1);
    if (pages <= 0 || page <= 0 || copies * trav * sizeof(pb_ray) > (uint64_t)pages * (uint64_t)page / 4)
        return 0;
    ray_log *log = malloc(sizeof *log);
    float *pos = malloc((size_t)P * 4 * sizeof *pos);
    uint64_t logged = 0;
    int ok = log && pos, wrong = 0;
    for (uint32_t p = 0; ok && p < P; ++p) {
        uint32_t id;
        pb_bake_probe_position(s, d, p, pos + 4 * (size_t)p, &id);
    }
    if (ok) {
        ray_log_init(log, lanes, embree_peer_cast, (void *)peer);
        tmpl.cast = ray_log_cast, tmpl.cast_user = log;
        /* where a restart schedule's lane group spans more paths than one of
         * pb_bake_trace_cpu's parallel ranges (64, aligned), on one CPU, so
         * that it runs on one thread and the record holds the paths in order */
        cpu_set_t saved, one;
        int pinned = restart_k * log->lanes > 64 && sched_getaffinity(0, sizeof saved, &saved) == 0;
        CPU_ZERO(&one);
        for (int c = 0; pinned && c < CPU_SETSIZE; ++c)
            if (CPU_ISSET(c, &saved)) {
                CPU_SET(c, &one);
                break;
            }
        pinned = pinned && sched_setaffinity(0, sizeof one, &one) == 0;
        ok = cpu_bake(s, d, tmpl, P, NULL, &logged) >= 0 && ray_log_count(log) > 0;
        if (pinned)
            sched_setaffinity(0, sizeof saved, &saved);
        wrong = ok && (logged != trav || ray_log_count(log) != trav);
        for (int k = 0; ok && !wrong && k < LAYOUTS; ++k) {
            int laid = ray_log_lockstep(log, pos, P, (ray_log_layout)k, &o->closest[k], &o->closest_count[k],
                                        &o->any[k], &o->any_count[k]);
            ok = laid > 0, wrong = laid < 0;
        }
        if (ok && !wrong && restart_k) {
            int laid = ray_log_restart(log, pos, P, restart_k, restart_m, &o->closest[RESTART],
                                       &o->closest_count[RESTART]);
            ok = laid > 0, wrong = laid < 0;
        }
        wrong |= ok && o->closest_count[RAY_LOG_PACKED] + o->any_count[RAY_LOG_PACKED] != trav;
        ray_log_free(log);
    }
    uint64_t longest = 0;
    for (int k = 0; ok && k <= LAYOUTS; ++k) {
        longest = o->closest_count[k] > longest ? o->closest_count[k] : longest;
        longest = o->any_count[k] > longest ? o->any_count[k] : longest;
    }
    o->real = trav;
    if (ok)
        ok = (o->hits = malloc(longest * sizeof *o->hits)) != NULL;
    free(log), free(pos);
    if (!ok || wrong)
        own_rays_free(o);
    return wrong ? -1 : ok;
}

/* Relative RMSE of the irradiance of sh (27 per probe) against the volume's,
 * over its valid probes and 64 directions (bench_volume_rmse's metric). */
static double agreement(const pb_volume *v, const float *sh)
{
    pb_volume a = *v;
    a.sh = (float *)sh;
    return bench_volume_rmse(&a, v);
}

int main(int argc, char **argv)
{
    uint32_t probes = 256, rays = 256, passes = 2, bounces = 3, repeat = 3, restart_k = 0, restart_m = 1;
    const char *out_dir = "bench/out", *scenes[16];
    int nscenes = 0, validation = 0, use[METHOD_COUNT] = {1, 1};
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--probes") && v)
            probes = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--rays") && v)
            rays = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--passes") && v)
            passes = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--bounces") && v)
            bounces = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--repeat") && v)
            repeat = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--out") && v)
            out_dir = argv[++i];
        else if (!strcmp(a, "--restart") && v) {
            if (sscanf(argv[++i], "%u:%u", &restart_k, &restart_m) < 1 || !restart_k || !restart_m ||
                restart_k > 1024) {
                fprintf(stderr, "peer_paths: --restart K[:M]: paths per lane K (1 to 1024), restart every M "
                        "iterations (at least 1; default 1)\n");
                return 2;
            }
        } else if (!strcmp(a, "--validation"))
            validation = 1;
        else if (!strcmp(a, "--methods") && v) {
            const char *list = argv[++i];
            for (int m = 0; m < METHOD_COUNT; ++m) {
                size_t l = strlen(methods[m].name);
                const char *f = strstr(list, methods[m].name);
                use[m] = f && (f == list || f[-1] == ',') && (f[l] == ',' || f[l] == 0);
            }
        } else if (a[0] == '-') {
            fprintf(stderr, "peer_paths: unknown option %s\n", a);
            return 2;
        } else if (nscenes < 16)
            scenes[nscenes++] = a;
    }
    if (!probes || !rays || !passes || !repeat || repeat > MAX_REPEAT) {
        fprintf(stderr, "peer_paths: --probes, --rays and --passes must be at least 1, --repeat 1 to %d\n",
                MAX_REPEAT);
        return 2;
    }
    if (!nscenes)
        nscenes = bench_default_scenes("peer_paths", scenes, 16);
    mkdir(out_dir, 0755);
    char csv_path[1024], json_path[1024];
    snprintf(csv_path, sizeof csv_path, "%s/peer_paths.csv", out_dir);
    snprintf(json_path, sizeof json_path, "%s/peer_paths.json", out_dir);
    FILE *csv = fopen(csv_path, "w"), *json = fopen(json_path, "w");
    if (!csv || !json) {
        fprintf(stderr, "peer_paths: cannot write %s: %s\n", csv ? json_path : csv_path, strerror(errno));
        return 1;
    }
    pb_context *ctx = NULL;
    pb_error err;
    pb_context_desc cd = {NULL, (uint32_t)validation, 0, 0, {0}};
    if (pb_context_create(&cd, &ctx, &err) != PB_OK) {
        fprintf(stderr, "peer_paths: %s\n", err.message);
        return 1;
    }
    RTCDevice edev = rtcNewDevice(NULL);
    /* the bake's lane groups: a subgroup of consecutive paths (8 on llvmpipe's 256-bit vectors) */
    uint32_t lanes = pb_context_device(ctx)->subgroup_size ? pb_context_device(ctx)->subgroup_size : 8;
    printf("device: %s; peer: the bake's CPU path tracer on Embree %d.%d.%d, %u host threads; %u probes x %u rays x "
           "%u passes, %u bounces, median of %u rounds; lane groups of %u paths in the replays\n",
           pb_context_device(ctx)->name, RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH, pb_host_threads(),
           probes, rays, passes, bounces, repeat, lanes);
    printf("%-12s %-6s %9s %10s %10s %10s %10s %8s %8s %10s %10s "
           "%6s %6s %6s %6s %6s %6s %6s %6s %6s %6s %6s %6s %6s\n", "scene",
           "method", "paths", "bake ms", "all GPU", "peer ms", "own ms", "vs peer", "vs own", "agree peer", "agree own",
           "trv/pa", "bk trc", "krn bt", "kr own", "kr grp", "kr mix", "kr pmx", "kr 1cp", "kr wg", "kr rst", "pr trc",
           "emb bt", "em own");
    fprintf(csv, "scene,method,paths,bake_trace_ms,bake_gpu_ms,peer_ms,own_ms,vs_peer,vs_own,agree_peer,agree_own,"
                 "bake_traversals,peer_traversals,bake_trc,kernel_bounce_over_probe,kernel_own_rays_over_probe,"
                 "kernel_own_groups_over_probe,kernel_own_mixed_groups_over_probe,kernel_own_packed_mixed_over_probe,"
                 "kernel_own_first_compacted_over_probe,kernel_own_workgroup_compacted_over_probe,"
                 "kernel_own_restart_over_probe,"
                 "peer_trc,"
                 "embree_bounce_over_probe,embree_own_rays_over_probe\n");
    fprintf(json, "{\"device\": \"%s\", \"peer\": \"Embree %d.%d.%d\", \"host_threads\": %u, \"probes\": %u, "
                  "\"rays\": %u, \"passes\": %u, \"bounces\": %u, \"repeat\": %u, \"restart_k\": %u, "
                  "\"restart_m\": %u, \"lanes\": %u, \"rows\": [",
            pb_context_device(ctx)->name, RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH, pb_host_threads(),
            probes, rays, passes, bounces, repeat, restart_k, restart_m, lanes);
    int failed = 0, first_row = 1;
    for (int si = 0; si < nscenes; ++si) {
        pb_scene *s;
        pb_bvh *bvh;
        pb_gpu_scene *gs;
        if (!bench_open_scene(ctx, "peer_paths", scenes[si], &s, &bvh, &gs)) {
            failed = 1;
            continue;
        }
        embree_peer peer;
        peer_inputs in;
        pb_ray *prays = NULL, *brays = NULL;
        pb_hit *hits = NULL;
        float *dist = NULL;
        memset(&peer, 0, sizeof peer);
        memset(&in, 0, sizeof in);
        float zero[3] = {0, 0, 0};
        in.draws_lights = pb_shading_draws_lights(s, 0);
        if (!embree_peer_build(edev, s, 1, &peer) ||
            pb_shading_host(s, zero, NULL, &in.emit, &in.env, &err) != PB_OK ||
            (in.draws_lights && pb_light_table_build(s, &in.lights, &err) != PB_OK)) {
            fprintf(stderr, "peer_paths: %s: %s\n", scenes[si], err.message);
            failed = 1;
            goto next_scene;
        }
        const char *name = strrchr(scenes[si], '/') ? strrchr(scenes[si], '/') + 1 : scenes[si];
        /* 256 probe rays per probe of the bakes' grid and their bounce rays,
         * each tracer's reference rates ("trc", "b/t"), timed in every round */
        pb_probe_grid grid;
        pb_probe_grid_fit(s->bounds_min, s->bounds_max, probes, &grid);
        uint32_t n = pb_probe_grid_count(&grid) * 256, nb = 0;
        prays = malloc((size_t)n * sizeof *prays), brays = malloc((size_t)n * sizeof *brays);
        hits = malloc((size_t)n * sizeof *hits), dist = malloc((size_t)n * sizeof *dist);
        if (!prays || !brays || !hits || !dist || pb_probe_rays(&grid, 0, n / 256, 256, 1, prays) != PB_OK ||
            pb_trace(ctx, gs, prays, n, PB_TRACE_CLOSEST, hits, NULL, &err) != PB_OK) {
            fprintf(stderr, "peer_paths: %s: the reference rays: %s\n", scenes[si],
                    prays && brays && hits && dist ? err.message : "out of host memory");
            failed = 1;
            goto next_scene;
        }
        memcpy(brays, prays, (size_t)n * sizeof *prays);
        nb = bench_bounce_rays(s, brays, hits, n, 0);
        int blended = 0; /* hits there pass by hashed hit bits, which float rounding changes */
        for (uint32_t k = 0; k < s->material_count; ++k)
            blended |= s->materials[k].alpha_mode == PB_ALPHA_BLEND;
        for (int mi = 0; mi < METHOD_COUNT; ++mi) {
            if (!use[mi])
                continue;
            const method *m = &methods[mi];
            pb_bake_desc d;
            memset(&d, 0, sizeof d);
            d.grid = grid; /* the reference rays' grid */
            d.rays_per_probe = rays, d.passes = passes, d.bounces = bounces, d.seed = 1;
            d.skip_relocation = 1; /* the peer places probes where the grid puts them */
            d.probe_nee = m->probe_nee, d.light_cells = m->light_cells, d.guide_paths = m->guide_paths;
            d.lobe_power = 50.f;
            float dx = s->bounds_max[0] - s->bounds_min[0], dy = s->bounds_max[1] - s->bounds_min[1],
                  dz = s->bounds_max[2] - s->bounds_min[2];
            d.max_distance = fmaxf(1e-3f, sqrtf(dx * dx + dy * dy + dz * dz));
            uint32_t P = pb_probe_grid_count(&d.grid);
            double bake_ms[MAX_REPEAT], gpu_ms[MAX_REPEAT], peer_ms[MAX_REPEAT], own_ms[MAX_REPEAT];
            double bake_trc[MAX_REPEAT], peer_trc[MAX_REPEAT], kernel_bt[MAX_REPEAT], embree_bt[MAX_REPEAT];
            double embree_own[MAX_REPEAT], kernel_own[LAYOUTS + 1][MAX_REPEAT];
            own_rays own;
            memset(&own, 0, sizeof own);
            uint64_t bake_trav = 0, peer_trav = 0, own_trav = 0;
            double agree_peer = 0, agree_own = 0;
            float *sh = malloc((size_t)P * 27 * sizeof *sh);
            int ok = sh != NULL && bench_warm_bake(ctx, s, gs, &d, &err);
            if (sh && !ok)
                fprintf(stderr, "peer_paths: %s, %s: %s\n", name, m->name, err.message);
            for (uint32_t r = 0; ok && r < repeat; ++r) {
                double kt = bench_trace_rate(ctx, gs, prays, n, hits), kb = bench_trace_rate(ctx, gs, brays, nb, hits);
                double et = n / (embree_peer_trace(&peer, prays, n, dist) * 1e3);
                double eb = nb ? nb / (embree_peer_trace(&peer, brays, nb, dist) * 1e3) : 0.0;
                pb_volume v;
                if (pb_bake(ctx, s, gs, &d, &v, &err) != PB_OK) {
                    fprintf(stderr, "peer_paths: %s, %s: %s\n", name, m->name, err.message);
                    ok = 0;
                    break;
                }
                bake_ms[r] = v.timings.trace;
                gpu_ms[r] = v.timings.trace + v.timings.sh + v.timings.octmap;
                bake_trav = v.traversals;
                /* what pb_bake learned for this bake, kept with the GPU scene */
                pb_bake_pass tmpl;
                memset(&tmpl, 0, sizeof tmpl);
                tmpl.scene = s, tmpl.bvh = bvh, tmpl.seed = d.seed, tmpl.bounces = d.bounces, tmpl.direct = 1;
                tmpl.env = in.env.width ? &in.env : NULL, tmpl.emitters = &in.emit;
                tmpl.light_table = in.draws_lights ? &in.lights : NULL;
                tmpl.max_distance = d.max_distance, tmpl.lobe_power = d.lobe_power;
                tmpl.light_cells = m->light_cells && gs->light_cells && gs->light_cells->host.table
                                       ? &gs->light_cells->host
                                       : NULL;
                tmpl.guide = m->guide_paths && gs->guide_cache && gs->guide_cache->valid ? &gs->guide_cache->guide
                                                                                          : NULL;
                tmpl.cast = embree_peer_cast, tmpl.cast_user = &peer;
                peer_ms[r] = cpu_bake(s, &d, tmpl, P, sh, &peer_trav);
                agree_peer = agreement(&v, sh);
                tmpl.cast = NULL;
                own_ms[r] = cpu_bake(s, &d, tmpl, P, sh, &own_trav);
                /* the peer's rays once (untimed), then each tracer alone on them in each round */
                if (r == 0 && peer_ms[0] >= 0 &&
                    record_rays(s, &d, tmpl, P, &peer, peer_trav, lanes, restart_k, restart_m, &own) < 0) {
                    fprintf(stderr, "peer_paths: %s, %s: the peer's recorded rays are not its %llu traversals in "
                            "whole paths\n", name, m->name, (unsigned long long)peer_trav);
                    ok = 0;
                }
                embree_own[r] = 0.0;
                for (int k = 0; k <= LAYOUTS; ++k)
                    kernel_own[k][r] = 0.0;
                if (own.real) {
                    double ems = embree_peer_cast_all(&peer, own.closest[0], own.closest_count[0], PB_TRACE_CLOSEST) +
                                 embree_peer_cast_all(&peer, own.any[0], own.any_count[0], PB_TRACE_ANY);
                    embree_own[r] = ems > 0 && et > 0 ? own.real / (ems * 1e3) / et : 0.0;
                    for (int k = 0; k <= LAYOUTS; ++k)
                        kernel_own[k][r] = kt > 0 ? kernel_rate_own(ctx, gs, &own, k) / kt : 0.0;
                }
                agree_own = agreement(&v, sh);
                pb_volume_free(&v);
                if (peer_ms[r] < 0 || own_ms[r] < 0) {
                    fprintf(stderr, "peer_paths: %s, %s: out of host memory\n", name, m->name);
                    ok = 0;
                }
                /* traversals per ms over Mrays/s: both per microsecond */
                bake_trc[r] = kt > 0 ? bake_trav / (gpu_ms[r] * 1e3) / kt : 0.0;
                peer_trc[r] = et > 0 ? peer_trav / (peer_ms[r] * 1e3) / et : 0.0;
                kernel_bt[r] = kt > 0 ? kb / kt : 0.0;
                embree_bt[r] = et > 0 ? eb / et : 0.0;
            }
            free(sh);
            own_rays_free(&own);
            if (!ok) {
                failed = 1;
                continue;
            }
            if (!blended && !(agree_own <= AGREE_OWN_MAX)) {
                fprintf(stderr, "peer_paths: %s, %s: the C path tracer on the bake's BVH is %.2e off the bake "
                        "(at most %.0e): it does not trace the bake's paths\n", name, m->name, agree_own,
                        AGREE_OWN_MAX);
                failed = 1;
            }
            if (!blended && (own_trav > bake_trav + bake_trav / 1000 || bake_trav > own_trav + own_trav / 1000)) {
                fprintf(stderr, "peer_paths: %s, %s: the C path tracer on the bake's BVH made %llu traversals, the "
                        "bake %llu: they do not count the same rays\n", name, m->name, (unsigned long long)own_trav,
                        (unsigned long long)bake_trav);
                failed = 1;
            }
            row w = {name, m->name, (uint64_t)P * rays * passes, bench_median(bake_ms, repeat),
                     bench_median(gpu_ms, repeat), bench_median(peer_ms, repeat), bench_median(own_ms, repeat),
                     agree_peer, agree_own, bake_trav, peer_trav, bench_median(bake_trc, repeat),
                     bench_median(peer_trc, repeat), bench_median(kernel_bt, repeat), bench_median(embree_bt, repeat),
                     bench_median(embree_own, repeat),
                     {bench_median(kernel_own[0], repeat), bench_median(kernel_own[1], repeat),
                      bench_median(kernel_own[2], repeat), bench_median(kernel_own[3], repeat),
                      bench_median(kernel_own[4], repeat), bench_median(kernel_own[5], repeat),
                      bench_median(kernel_own[RESTART], repeat)}};
            double vs_peer = w.peer_ms / w.bake_trace_ms, vs_own = w.own_ms / w.bake_trace_ms;
            printf("%-12.12s %-6s %9llu %10.1f %10.1f %10.1f %10.1f %7.3fx %7.3fx %10.2e %10.2e "
                   "%6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f\n",
                   w.scene, w.method, (unsigned long long)w.paths, w.bake_trace_ms, w.bake_gpu_ms, w.peer_ms, w.own_ms,
                   vs_peer, vs_own, w.agree_peer, w.agree_own, (double)w.bake_trav / w.paths, w.bake_trc, w.kernel_bt,
                   w.kernel_own[0], w.kernel_own[1], w.kernel_own[2], w.kernel_own[3], w.kernel_own[4],
                   w.kernel_own[5], w.kernel_own[RESTART], w.peer_trc, w.embree_bt, w.embree_own);
            fprintf(csv,
                    "%s,%s,%llu,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%.3e,%.3e,%llu,%llu,"
                    "%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n",
                    w.scene, w.method, (unsigned long long)w.paths, w.bake_trace_ms, w.bake_gpu_ms, w.peer_ms,
                    w.own_ms, vs_peer, vs_own, w.agree_peer, w.agree_own, (unsigned long long)w.bake_trav,
                    (unsigned long long)w.peer_trav, w.bake_trc, w.kernel_bt, w.kernel_own[0], w.kernel_own[1],
                    w.kernel_own[2], w.kernel_own[3], w.kernel_own[4], w.kernel_own[5], w.kernel_own[RESTART],
                    w.peer_trc, w.embree_bt, w.embree_own);
            fprintf(json,
                    "%s\n  {\"scene\": \"%s\", \"method\": \"%s\", \"paths\": %llu, \"bake_trace_ms\": %.3f, "
                    "\"bake_gpu_ms\": %.3f, \"peer_ms\": %.3f, \"own_ms\": %.3f, \"vs_peer\": %.4f, \"vs_own\": %.4f, "
                    "\"agree_peer\": %.3e, \"agree_own\": %.3e, \"bake_traversals\": %llu, \"peer_traversals\": %llu, "
                    "\"bake_trc\": %.4f, \"kernel_bounce_over_probe\": %.4f, \"peer_trc\": %.4f, "
                    "\"kernel_own_rays_over_probe\": %.4f, \"kernel_own_groups_over_probe\": %.4f, "
                    "\"kernel_own_mixed_groups_over_probe\": %.4f, \"kernel_own_packed_mixed_over_probe\": %.4f, "
                    "\"kernel_own_first_compacted_over_probe\": %.4f, "
                    "\"kernel_own_workgroup_compacted_over_probe\": %.4f, \"kernel_own_restart_over_probe\": %.4f, "
                    "\"embree_bounce_over_probe\": %.4f, "
                    "\"embree_own_rays_over_probe\": %.4f}",
                    first_row ? "" : ",", w.scene, w.method, (unsigned long long)w.paths, w.bake_trace_ms,
                    w.bake_gpu_ms, w.peer_ms, w.own_ms, vs_peer, vs_own, w.agree_peer, w.agree_own,
                    (unsigned long long)w.bake_trav, (unsigned long long)w.peer_trav, w.bake_trc, w.kernel_bt,
                    w.peer_trc, w.kernel_own[0], w.kernel_own[1], w.kernel_own[2], w.kernel_own[3],
                    w.kernel_own[4], w.kernel_own[5], w.kernel_own[RESTART], w.embree_bt, w.embree_own);
            first_row = 0;
        }
    next_scene:
        free(prays), free(brays), free(hits), free(dist);
        if (peer.scene)
            embree_peer_release(&peer);
        pb_bake_emitters_free(&in.emit);
        pb_env_table_free(&in.env);
        if (in.draws_lights)
            pb_light_table_free(&in.lights);
        pb_gpu_scene_destroy(gs);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
    }
    fprintf(json, "\n]}\n");
    fclose(csv), fclose(json);
    printf("vs peer / vs own: the bake's paths per second of trace-kernel GPU time over the CPU path tracer's per "
           "second of wall time (Embree's rays / the bake's BVH on the host); > 1: the bake is faster\n"
           "trv/pa: the bake's traversals per path; bk trc / pr trc: the bake's traversals per second of all its GPU "
           "time over the trace kernel's probe rays per second (bake_bench's \"vs trc\", issue 11's >= 0.7), the "
           "peer's per second of its wall time over Embree's; krn bt / emb bt: each tracer's bounce rays per second "
           "over its probe rays per second; kr own / em own: each tracer alone on the rays the peer cast "
           "(recorded; packed in the bake's lane-group order) over its probe rays per second: a path tracer's \"trc\" "
           "on it with no shading cost; kr grp: the same rays in the bake's very lane groups, a lane whose path has "
           "ended or casts the other kind idle; kr mix: the same with both kinds in one lane group as the bake's one "
           "trace loop runs them, all traced to their closest hit; kr pmx: packed, both kinds in one list (closest "
           "hits), as a compaction that moves paths between lanes and keeps the groups' order would trace them; "
           "kr 1cp: the probe rays in the bake's groups, then the paths that go on packed to groups (one "
           "compaction, after the first hit); kr wg: each workgroup's paths compacted before each ray (a "
           "workgroup's k-th rays of its paths still going, packed); kr rst: --restart K:M's schedule (K paths per "
           "lane, an idle lane begins its next path every M iterations; ray_log.h); 0.00: not measured (no "
           "--restart, or the recorded rays would take more than a quarter of host memory)\n");
    printf("wrote %s\nwrote %s\n", csv_path, json_path);
    rtcReleaseDevice(edev);
    pb_context_destroy(ctx);
    return failed;
}
