/* lockstep_model: what SIMD lanes cost the traversal, counted, not timed.
 *
 *   lockstep_model [--probes N] [--rays N] [--lanes N] [--json FILE] [SCENE ...]
 *
 * llvmpipe runs 8 invocations as the lanes of one 256-bit vector (on AVX-512
 * CPUs too, unless LP_NATIVE_VECTOR_WIDTH=512 asks for 16; --lanes): a loop
 * runs until its last lane leaves, and lanes that left wait. This drives the
 * reference traversal (src/bvh/bvh_walk.h, the kernel's loop in C) for groups
 * of consecutive rays side by side and counts the iterations a group runs,
 * under five schedules of the same per-ray work:
 *
 *   kernel     every live lane takes a node step, then the triangle loop runs
 *              to the longest run of hit-leaf triangles among the lanes
 *              (shaders/include/traverse.glsl);
 *   postponed  a lane takes node steps until it holds triangles (or is done),
 *              and the triangle loop runs once no lane still needs a step
 *              (Aila and Laine 2009's postponed leaves); a node's inner
 *              children are chosen at its step, before its triangles;
 *   shared     the kernel's node loop, then the triangles of all lanes' runs
 *              as one list, one test per lane per iteration (a lane tests
 *              another lane's triangle against that lane's ray);
 *   pairs, quads  the same within groups of 2 or 4 neighbouring lanes.
 *
 * Rays: probe rays as trace_bench makes them (pb_probe_rays), their bounce
 * rays (bench/bounce_rays.c: one cosine bounce from each first front hit, as
 * the bake's kernel meets them), and shadow rays from those bounce origins to
 * a point below the middle of the scene's top (any hit ends a ray). Per ray:
 * node steps and triangle tests; per group: the iterations of each loop;
 * lane use = per-ray work x lanes / group iterations. Which schedule is faster
 * depends on what a step and a test cost (bench/RESULTS.md, "SIMD lanes
 * counted"); the counts are exact for this BVH and these rays. The probe rays'
 * hits under the kernel's schedule are checked against pb_trace_cpu's (exit
 * 1 on a difference): side by side, the lanes walk as the reference does; and
 * the shared schedules must take the kernel's node steps and tests in no more
 * triangle-loop iterations. */
#define _POSIX_C_SOURCE 200809L
#include "bvh/bvh_walk.h"
#include "probebake/probebake.h"

#include "bounce_rays.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_LANES = 64, KINDS = 3, SCHEDULES = 5 };
static const char *kind_names[KINDS] = {"probe", "bounce", "shadow"};
static const char *schedule_names[SCHEDULES] = {"kernel", "postponed", "shared", "pairs", "quads"};

typedef struct lane {
    pb_bvh_walk w;
    uint32_t next_test; /* index in the run */
    int any_hit, more, done;
} lane;

typedef struct counts {
    double steps, tests;         /* summed over rays */
    double node_iters, tri_iters; /* summed over groups */
} counts;

typedef struct model {
    const pb_scene *scene;
    const pb_bvh *bvh;
    counts *c;
} model;

static int holds_tests(const lane *l) { return !l->done && l->next_test < l->w.run; }

static void lane_test(const model *m, lane *l)
{
    if (pb_bvh_walk_test(&l->w, m->scene, m->bvh, l->next_test++) && l->any_hit)
        l->done = 1;
    m->c->tests++;
    if (!l->done && l->next_test == l->w.run && !l->more)
        l->done = 1; /* postponed: the node chosen at the step was the last */
}

/* the triangle loop: one test per lane holding one, until none does */
static void triangle_loop(const model *m, lane *g, uint32_t n)
{
    for (;;) {
        int any = 0;
        for (uint32_t l = 0; l < n; ++l)
            if (holds_tests(&g[l])) {
                lane_test(m, &g[l]);
                any = 1;
            }
        if (!any)
            return;
        m->c->tri_iters++;
    }
}

/* shared triangle tests: each `width` lanes' runs of triangles as one list
 * (lane order), `width` tests per iteration, any lane testing any of its
 * group's triangles against that lane's ray */
static void shared_tests(const model *m, lane *g, uint32_t n, uint32_t width)
{
    uint32_t most = 0; /* the busiest group's iterations */
    for (uint32_t a = 0; a < n; a += width) {
        uint32_t sum = 0;
        for (uint32_t l = a; l < a + width && l < n; ++l)
            sum += g[l].done ? 0 : g[l].w.run;
        most = (sum + width - 1) / width > most ? (sum + width - 1) / width : most;
    }
    m->c->tri_iters += most;
    for (uint32_t l = 0; l < n; ++l)
        while (holds_tests(&g[l]))
            lane_test(m, &g[l]);
}

/* the kernel's schedule: node step for every live lane, then the longest run
 * (width 0), or the runs shared by groups of `width` lanes */
static void run_kernel(const model *m, lane *g, uint32_t n, uint32_t width)
{
    for (;;) {
        int live = 0;
        for (uint32_t l = 0; l < n; ++l)
            if (!g[l].done) {
                pb_bvh_walk_step(&g[l].w, m->bvh);
                g[l].next_test = 0;
                m->c->steps++;
                live = 1;
            }
        if (!live)
            return;
        m->c->node_iters++;
        if (width)
            shared_tests(m, g, n, width);
        else
            triangle_loop(m, g, n); /* `more` stays 1 here: the next node is chosen after */
        for (uint32_t l = 0; l < n; ++l)
            if (!g[l].done && !pb_bvh_walk_next(&g[l].w))
                g[l].done = 1;
    }
}

/* postponed leaves, inner children chosen at the step */
static void run_postponed(const model *m, lane *g, uint32_t n)
{
    for (;;) {
        for (;;) {
            int stepped = 0;
            for (uint32_t l = 0; l < n; ++l) {
                lane *x = &g[l];
                if (x->done || holds_tests(x))
                    continue;
                if (!x->more) {
                    x->done = 1;
                    continue;
                }
                pb_bvh_walk_step(&x->w, m->bvh);
                x->next_test = 0;
                x->more = pb_bvh_walk_next(&x->w);
                m->c->steps++;
                stepped = 1;
            }
            if (!stepped)
                break;
            m->c->node_iters++;
        }
        triangle_loop(m, g, n);
        int live = 0;
        for (uint32_t l = 0; l < n; ++l)
            live |= !g[l].done;
        if (!live)
            return;
    }
}

/* Counts both schedules over rays[0..count) in groups of `lanes`; returns
 * how many closest hits of the kernel's schedule differ from `ref`
 * (pb_trace_cpu's, where given): the lanes must walk as the reference does. */
static uint32_t model_rays(const pb_scene *s, const pb_bvh *bvh, const pb_ray *rays, uint32_t count, uint32_t lanes,
                           int any_hit, const pb_hit *ref, counts out[SCHEDULES])
{
    uint32_t wrong = 0;
    for (int sc = 0; sc < SCHEDULES; ++sc) {
        model m = {s, bvh, &out[sc]};
        memset(&out[sc], 0, sizeof out[sc]);
        for (uint32_t g0 = 0; g0 + lanes <= count; g0 += lanes) {
            lane g[MAX_LANES];
            for (uint32_t l = 0; l < lanes; ++l) {
                pb_bvh_walk_start(&g[l].w, &rays[g0 + l]);
                g[l].next_test = 0, g[l].any_hit = any_hit, g[l].more = 1, g[l].done = bvh->triangle_count == 0;
            }
            if (sc == 1)
                run_postponed(&m, g, lanes);
            else /* kernel, shared by all lanes, pairs, quads */
                run_kernel(&m, g, lanes, sc == 0 ? 0 : sc == 2 ? lanes : sc == 3 ? 2 : 4);
            for (uint32_t l = 0; sc == 0 && ref && l < lanes; ++l) {
                const pb_bvh_walk *w = &g[l].w;
                uint32_t tri = w->best == PB_NO_HIT ? PB_NO_HIT : bvh->tri_order[w->best];
                const pb_hit *h = &ref[g0 + l];
                wrong += tri != h->triangle || (tri != PB_NO_HIT && (w->tmax != h->t || w->u != h->u || w->v != h->v));
            }
        }
    }
    return wrong;
}

int main(int argc, char **argv)
{
    uint32_t probes = 1024, per_probe = 256, lanes = 8;
    const char *json = "bench/out/lockstep_model.json";
    const char *scenes[16];
    int scene_count = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--probes") && i + 1 < argc)
            probes = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--rays") && i + 1 < argc)
            per_probe = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--lanes") && i + 1 < argc)
            lanes = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--json") && i + 1 < argc)
            json = argv[++i];
        else if (argv[i][0] != '-' && scene_count < 16)
            scenes[scene_count++] = argv[i];
        else {
            fprintf(stderr, "usage: lockstep_model [--probes N] [--rays N] [--lanes N] [--json FILE] [SCENE ...]\n");
            return 2;
        }
    }
    if (!probes || probes > 65536 || !per_probe || per_probe > 4096 || !lanes || lanes > MAX_LANES) {
        fprintf(stderr, "lockstep_model: --probes 1..65536, --rays 1..4096, --lanes 1..%d\n", MAX_LANES);
        return 2;
    }
    if (!scene_count)
        scenes[scene_count++] = "tests/scenes/demo.gltf";
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.tmp", json);
    FILE *f = fopen(tmp, "w"); /* renamed to `json` once every scene is in */
    if (!f) {
        fprintf(stderr, "lockstep_model: %s: cannot write\n", json);
        return 1;
    }
    fprintf(f, "{\n  \"lanes\": %u, \"probes\": %u, \"rays_per_probe\": %u,\n  \"results\": [", lanes, probes, per_probe);
    printf("%u lanes; per ray: node steps, triangle tests; per group: loop iterations (lane use)\n", lanes);
    printf("%-22s %-7s %8s %7s %7s |", "scene", "rays", "count", "steps", "tests");
    for (int sc = 0; sc < SCHEDULES; ++sc) {
        char label[64];
        snprintf(label, sizeof label, "%s: nodes / tris", schedule_names[sc]);
        printf(" %-25s |", label);
    }
    printf("\n");
    int first = 1, status = 0;
    for (int si = 0; si < scene_count; ++si) {
        pb_scene *s = NULL;
        pb_bvh *bvh = NULL;
        pb_error err;
        pb_scene_desc sd = {{0}, 1};
        if (pb_scene_load(scenes[si], &sd, &s, &err) != PB_OK || pb_bvh_build(s, NULL, &bvh, &err) != PB_OK) {
            fprintf(stderr, "lockstep_model: %s\n", err.message);
            pb_scene_destroy(s);
            status = 1;
            continue;
        }
        pb_probe_grid grid;
        pb_probe_grid_fit(s->bounds_min, s->bounds_max, probes, &grid);
        uint32_t n = pb_probe_grid_count(&grid) * per_probe;
        pb_ray *rays = malloc((size_t)n * sizeof *rays), *rays2 = malloc((size_t)n * sizeof *rays2);
        pb_hit *hits = malloc((size_t)n * sizeof *hits);
        if (!rays || !rays2 || !hits || pb_probe_rays(&grid, 0, n / per_probe, per_probe, 1, rays) != PB_OK) {
            fprintf(stderr, "lockstep_model: %s: out of host memory for %u rays\n", scenes[si], n);
            free(rays), free(rays2), free(hits);
            pb_bvh_destroy(bvh), pb_scene_destroy(s);
            fclose(f), remove(tmp);
            return 1;
        }
        pb_trace_cpu(s, bvh, rays, n, PB_TRACE_CLOSEST, hits, 0);
        memcpy(rays2, rays, (size_t)n * sizeof *rays);
        uint32_t nb = bench_bounce_rays(s, rays2, hits, n, 0);
        const char *name = strrchr(scenes[si], '/') ? strrchr(scenes[si], '/') + 1 : scenes[si];
        for (int kind = 0; kind < KINDS; ++kind) {
            const pb_ray *kr = kind == 0 ? rays : rays2;
            uint32_t kn = kind == 0 ? n : nb;
            if (kind == 2) { /* the bounce rays' origins to one light point */
                float lp[3] = {0.5f * (s->bounds_min[0] + s->bounds_max[0]),
                               s->bounds_max[1] - 0.05f * (s->bounds_max[1] - s->bounds_min[1]),
                               0.5f * (s->bounds_min[2] + s->bounds_max[2])};
                for (uint32_t i = 0; i < nb; ++i) {
                    float d[3], len = 0.f;
                    for (int a = 0; a < 3; ++a)
                        d[a] = lp[a] - rays2[i].origin[a], len += d[a] * d[a];
                    len = sqrtf(len);
                    for (int a = 0; a < 3; ++a)
                        rays2[i].direction[a] = len > 0.f ? d[a] / len : (a == 1 ? 1.f : 0.f);
                    rays2[i].tmin = 0.f, rays2[i].tmax = len * 0.999f;
                }
            }
            counts c[SCHEDULES];
            uint32_t wrong = model_rays(s, bvh, kr, kn, lanes, kind == 2, kind == 0 ? hits : NULL, c);
            if (wrong) {
                fprintf(stderr, "lockstep_model: %s: %u of %u probe rays' hits differ from pb_trace_cpu's\n",
                        scenes[si], wrong, kn);
                status = 1;
            }
            /* sharing moves triangle tests between lanes, never node steps, and a
             * group's shared tests never take more iterations than its longest run */
            for (int sc = 2; sc < SCHEDULES; ++sc)
                if (c[sc].node_iters != c[0].node_iters || c[sc].steps != c[0].steps ||
                    c[sc].tests != c[0].tests || c[sc].tri_iters > c[0].tri_iters) {
                    fprintf(stderr, "lockstep_model: %s, %s rays: the %s schedule counts %.0f / %.0f iterations "
                                    "against the kernel's %.0f / %.0f\n", scenes[si], kind_names[kind],
                            schedule_names[sc], c[sc].node_iters, c[sc].tri_iters, c[0].node_iters, c[0].tri_iters);
                    status = 1;
                }
            double rays_in = (double)(kn / lanes * lanes), groups = rays_in / lanes;
            double steps = c[0].steps / rays_in, tests = c[0].tests / rays_in;
            printf("%-22.22s %-7s %8.0f %7.2f %7.2f |", name, kind_names[kind], rays_in, steps, tests);
            for (int sc = 0; sc < SCHEDULES; ++sc)
                printf(" %5.2f (%2.0f%%) / %5.2f (%2.0f%%) |", c[sc].node_iters / groups,
                       100.0 * c[sc].steps / (c[sc].node_iters * lanes), c[sc].tri_iters / groups,
                       100.0 * c[sc].tests / (c[sc].tri_iters * lanes));
            printf("\n");
            for (int sc = 0; sc < SCHEDULES; ++sc) {
                fprintf(f, "%s\n    {\"scene\": \"%s\", \"rays\": \"%s\", \"count\": %.0f, \"schedule\": \"%s\", "
                           "\"steps_per_ray\": %.4f, \"tests_per_ray\": %.4f, \"node_iterations_per_group\": %.4f, "
                           "\"triangle_iterations_per_group\": %.4f}",
                        first ? "" : ",", name, kind_names[kind], rays_in, schedule_names[sc], c[sc].steps / rays_in,
                        c[sc].tests / rays_in, c[sc].node_iters / groups, c[sc].tri_iters / groups);
                first = 0;
            }
        }
        free(rays), free(rays2), free(hits);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
    }
    fprintf(f, "\n  ]\n}\n");
    if (fclose(f) != 0 || status != 0 || rename(tmp, json) != 0) {
        remove(tmp);
        if (status == 0)
            fprintf(stderr, "lockstep_model: %s: cannot write\n", json);
        return 1;
    }
    printf("wrote %s\n", json);
    return 0;
}
