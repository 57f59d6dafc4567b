/* Scratch (bench/RESULTS.md, "Lane groups across neighbouring probes"): the
 * kernel's loop iterations per ray under five ways of filling a lane group of 8,
 * counted with bench/lockstep_model.c's schedule. Not built by CMake: to run it,
 * copy it into bench/ and add
 *   add_executable(layout_model layout_model.c bounce_rays.c)
 *   target_include_directories(layout_model PRIVATE ${CMAKE_SOURCE_DIR}/src)
 *   target_link_libraries(layout_model PRIVATE probebake_core)
 * then: build/bench/layout_model SCENE [PROBES [RAYS]]. Output: layout_model.txt. */
#define main lockstep_main
#include "lockstep_model.c"
#undef main
#include "bake/path_cpu.h"

/* groups: G groups of 8 probe indices (-1 = none) */
static void cost(const pb_scene *s, const pb_bvh *bvh, const pb_ray *rays, const uint8_t *dead, uint32_t n, int any, double *per_live, double *live_frac)
{
    counts c; memset(&c, 0, sizeof c);
    model m = {s, bvh, &c};
    double live = 0;
    for (uint32_t g0 = 0; g0 + 8 <= n; g0 += 8) {
        lane g[8];
        for (uint32_t l = 0; l < 8; ++l) {
            pb_bvh_walk_start(&g[l].w, &rays[g0 + l]);
            g[l].next_test = 0, g[l].any_hit = any, g[l].more = 1, g[l].done = dead[g0 + l];
            live += !dead[g0 + l];
        }
        run_kernel(&m, g, 8, 0);
    }
    *per_live = (c.node_iters + c.tri_iters) * 8.0 / live; /* lane-iterations per live ray */
    *live_frac = live / n;
    (void)per_live;
}

int main(int argc, char **argv)
{
    const char *scene = argv[1];
    uint32_t probes = argc > 2 ? atoi(argv[2]) : 1024, R = argc > 3 ? atoi(argv[3]) : 256;
    pb_scene *s = NULL; pb_bvh *bvh = NULL; pb_error err;
    pb_scene_desc sd = {{0}, 1};
    if (pb_scene_load(scene, &sd, &s, &err) != PB_OK || pb_bvh_build(s, NULL, &bvh, &err) != PB_OK) { fprintf(stderr, "%s\n", err.message); return 1; }
    pb_probe_grid grid; pb_probe_grid_fit(s->bounds_min, s->bounds_max, probes, &grid);
    uint32_t P = pb_probe_grid_count(&grid), nx = grid.counts[0], ny = grid.counts[1], nz = grid.counts[2];
    pb_ray *base = malloc((size_t)P * R * sizeof *base);
    pb_probe_rays(&grid, 0, P, R, 1, base);
    printf("%s: %u probes (%ux%ux%u), %u rays\n", scene, P, nx, ny, nz, R);
    for (int layout = 0; layout < 5; ++layout) {
        /* groups of 8 probes */
        uint32_t maxg = P + 8 * 64; int32_t *grp = malloc((size_t)maxg * 8 * sizeof *grp); uint32_t G = 0;
        if (layout <= 1) { /* 0: per-probe (each group = one probe, 8 rays); 1: rows of 8 probes */
            for (uint32_t p = 0; p < P; p += 8, ++G) for (int l = 0; l < 8; ++l) grp[G*8+l] = p + l < P ? (int)(p + l) : -1;
        } else if (layout == 2) { /* 2x2x2 blocks */
            for (uint32_t k = 0; k < nz; k += 2) for (uint32_t j = 0; j < ny; j += 2) for (uint32_t i = 0; i < nx; i += 2, ++G)
                for (int l = 0; l < 8; ++l) { uint32_t a = i + (l & 1), b = j + ((l >> 1) & 1), c = k + (l >> 2);
                    grp[G*8+l] = a < nx && b < ny && c < nz ? (int)(a + nx * (b + ny * c)) : -1; }
        } else { /* 3: blocks, but per-probe rotation kept; 4: shared rotation, per-probe bounce randomness */
            for (uint32_t k = 0; k < nz; k += 2) for (uint32_t j = 0; j < ny; j += 2) for (uint32_t i = 0; i < nx; i += 2, ++G)
                for (int l = 0; l < 8; ++l) { uint32_t a = i + (l & 1), b = j + ((l >> 1) & 1), c = k + (l >> 2);
                    grp[G*8+l] = a < nx && b < ny && c < nz ? (int)(a + nx * (b + ny * c)) : -1; }
        }
        uint32_t n = layout == 0 ? P * R : G * 8 * R;
        pb_ray *ray = malloc((size_t)n * sizeof *ray), *b = malloc((size_t)n * sizeof *b);
        uint8_t *dead = calloc(n, 1), *bdead = calloc(n, 1);
        uint32_t *rix = malloc((size_t)n * 4);
        pb_hit *hit = malloc((size_t)n * sizeof *hit);
        if (layout == 0) { memcpy(ray, base, (size_t)n * sizeof *ray); for (uint32_t i = 0; i < n; ++i) rix[i] = i; }
        else for (uint32_t g = 0; g < G; ++g) for (uint32_t r = 0; r < R; ++r) for (int l = 0; l < 8; ++l) {
            size_t i = ((size_t)g * R + r) * 8 + l; int p = grp[g*8+l];
            rix[i] = layout >= 3 ? (p < 0 ? 0 : (uint32_t)p) * R + r : r; /* shared randomness key */
            if (p < 0) { ray[i] = base[0]; ray[i].tmax = 0.f; dead[i] = 1; continue; }
            ray[i] = base[(size_t)p * R + r];
            if (layout != 3) for (int c = 0; c < 3; ++c) ray[i].direction[c] = base[r].direction[c]; /* probe 0's rotation */
        }
        pb_trace_cpu(s, bvh, ray, n, PB_TRACE_CLOSEST, hit, 0);
        for (uint32_t i = 0; i < n; ++i) {
            const pb_hit *h = &hit[i];
            if (dead[i] || h->triangle == PB_NO_HIT || h->backface) { bdead[i] = 1; b[i] = base[0]; b[i].tmax = 0.f; continue; }
            const float *p = s->positions + 9 * (size_t)h->triangle;
            float e1[3], e2[3], x[3], ng[3];
            for (int k = 0; k < 3; ++k) e1[k] = p[3+k]-p[k], e2[k] = p[6+k]-p[k];
            ng[0] = e1[1]*e2[2]-e1[2]*e2[1]; ng[1] = e1[2]*e2[0]-e1[0]*e2[2]; ng[2] = e1[0]*e2[1]-e1[1]*e2[0];
            float len = sqrtf(ng[0]*ng[0]+ng[1]*ng[1]+ng[2]*ng[2]);
            if (!(len > 0.f)) { bdead[i] = 1; b[i] = base[0]; b[i].tmax = 0.f; continue; }
            float facing = ng[0]*ray[i].direction[0]+ng[1]*ray[i].direction[1]+ng[2]*ray[i].direction[2];
            for (int k = 0; k < 3; ++k) { ng[k] /= facing > 0.f ? -len : len; x[k] = p[k] + h->u*e1[k] + h->v*e2[k]; }
            pb_offset_ray_origin(x, ng, b[i].origin);
            pb_cosine_direction_cpu(ng, pb_random01(7, rix[i], 0, 0), pb_random01(7, rix[i], 1, 0), b[i].direction);
            b[i].tmin = 0.f; b[i].tmax = INFINITY;
        }
        double pr, pl, br, bl, sr, sl;
        cost(s, bvh, ray, dead, n, 0, &pr, &pl);
        cost(s, bvh, b, bdead, n, 0, &br, &bl);
        float lp[3] = {0.5f*(s->bounds_min[0]+s->bounds_max[0]), s->bounds_max[1]-0.05f*(s->bounds_max[1]-s->bounds_min[1]), 0.5f*(s->bounds_min[2]+s->bounds_max[2])};
        for (uint32_t i = 0; i < n; ++i) if (!bdead[i]) {
            float d[3], l2 = 0.f;
            for (int a = 0; a < 3; ++a) d[a] = lp[a]-b[i].origin[a], l2 += d[a]*d[a];
            l2 = sqrtf(l2);
            for (int a = 0; a < 3; ++a) b[i].direction[a] = l2 > 0.f ? d[a]/l2 : (a == 1);
            b[i].tmin = 0.f, b[i].tmax = l2 * 0.999f;
        }
        cost(s, bvh, b, bdead, n, 1, &sr, &sl);
        static const char *nm[] = {"per-probe (now)", "rows of 8 probes, shared rot", "2x2x2 blocks, shared rot", "2x2x2 blocks, own rot", "2x2x2, shared rot, own bounce"};
        printf("%-30s lane-iters per live ray: probe %6.2f (live %.2f)  bounce %6.2f (live %.2f)  shadow %6.2f\n", nm[layout], pr, pl, br, bl, sr);
        free(ray); free(b); free(dead); free(bdead); free(rix); free(hit); free(grp);
    }
    return 0;
}
