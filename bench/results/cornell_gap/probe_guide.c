/* scratch: probe rays importance-sampled from a per-probe histogram learned in earlier passes,
 * against the rotated Fibonacci set: per-axis irradiance std error across passes. */
#include "probebake/probebake.h"
#include "bake/shading.h"
#include "bake/guide.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifndef GRID
#define GRID 8
#endif
#define G GRID
#define BINS (G * G)
static uint32_t hash(uint32_t x) { x ^= x >> 16; x *= 0x7feb352d; x ^= x >> 15; x *= 0x846ca68b; x ^= x >> 16; return x; }
static float rnd(uint32_t *s) { *s = hash(*s + 0x9e3779b9u); return (*s >> 8) * (1.f / 16777216.f); }
static int bin_of(const float d[3]) { float s, t; pb_equal_area_encode(d, &s, &t); int bx = (int)fminf(fmaxf(s * G, 0), G - 1), by = (int)fminf(fmaxf(t * G, 0), G - 1); return by * G + bx; }
static int cmpd(const void *a, const void *b) { double x = *(const double *)a, y = *(const double *)b; return (x > y) - (x < y); }
int main(int argc, char **argv)
{
    const char *path = argv[1];
    uint32_t B = atoi(argv[2]), rpp = 256, learn = atoi(argv[3]), passes = atoi(argv[4]);
    float share = atof(argv[5]);
    pb_scene_desc sd = {{0}, 0};
    pb_error err;
    pb_scene *s; pb_bvh *bvh;
    if (pb_scene_load(path, &sd, &s, &err) || pb_bvh_build(s, NULL, &bvh, &err)) { puts(err.message); return 1; }
    pb_bake_emitters em; pb_env_table env; float zero[3] = {0};
    pb_shading_host(s, zero, NULL, &em, &env, &err);
    pb_bake_desc d; memset(&d, 0, sizeof d);
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, 64, &d.grid);
    d.seed = 1;
    uint32_t P = d.grid.counts[0] * d.grid.counts[1] * d.grid.counts[2];
    float *probes = calloc(P * 4, 4), *rot = malloc(P * 48), *fib = malloc(rpp * 16), *rays = malloc((size_t)P * rpp * 16);
    float *gdirs = malloc(rpp * 16), ident[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}, gray[4 * 256];
    pb_sf_directions(rpp, fib);
    float dx = s->bounds_max[0] - s->bounds_min[0], dy = s->bounds_max[1] - s->bounds_min[1], dz = s->bounds_max[2] - s->bounds_min[2];
    pb_bake_pass pp; memset(&pp, 0, sizeof pp);
    pp.scene = s, pp.bvh = bvh, pp.env = env.width ? &env : NULL, pp.emitters = &em, pp.bounces = B, pp.direct = 1;
    pp.max_distance = sqrtf(dx * dx + dy * dy + dz * dz), pp.lobe_power = 50, pp.seed = 1, pp.octmap_res = 8;
    static const float axes[6][3] = {{1,0,0},{-1,0,0},{0,1,0},{0,-1,0},{0,0,1},{0,0,-1}};
    double *hist = calloc((size_t)P * BINS, 8), *hn = calloc((size_t)P * BINS, 8);
    /* per probe, axis, arm: sum and sum of squares of per-pass estimates */
    double *S[2], *S2[2];
    for (int a = 0; a < 2; ++a) S[a] = calloc(P * 6, 8), S2[a] = calloc(P * 6, 8);
    for (uint32_t p = 0; p < P; ++p) { uint32_t id; pb_bake_probe_position(s, &d, p, probes + 4 * p, &id); memcpy(&probes[4 * p + 3], &id, 4); }
    /* arm 0 (and learning): rotated Fibonacci passes */
    for (uint32_t pass = 0; pass < learn + passes; ++pass) {
        for (uint32_t p = 0; p < P; ++p) {
            uint32_t id; float m[9]; memcpy(&id, &probes[4 * p + 3], 4);
            pb_random_rotation(1, id, pass, m);
            for (int r = 0; r < 3; ++r) for (int c = 0; c < 4; ++c) rot[12 * p + 4 * r + c] = c < 3 ? m[3 * r + c] : 0.f;
        }
        pp.probes = probes, pp.rotations = rot, pp.directions = fib, pp.probe_count = P, pp.rays_per_probe = rpp, pp.pass_index = pass;
        pp.first_probe = 0;
        pb_bake_trace_cpu(&pp, rays);
        for (uint32_t p = 0; p < P; ++p) {
            double e[6] = {0};
            for (uint32_t r = 0; r < rpp; ++r) {
                const float *o = rays + 4 * ((size_t)p * rpp + r), *R = rot + 12 * p, *dd = fib + 4 * r;
                float w[3];
                for (int k = 0; k < 3; ++k) w[k] = R[4 * k] * dd[0] + R[4 * k + 1] * dd[1] + R[4 * k + 2] * dd[2];
                double L = 0.2126 * o[0] + 0.7152 * o[1] + 0.0722 * o[2];
                if (pass < learn) { int b = bin_of(w); hist[p * BINS + b] += L; hn[p * BINS + b] += 1; }
                for (int a = 0; a < 6; ++a) { double c = w[0] * axes[a][0] + w[1] * axes[a][1] + w[2] * axes[a][2]; if (c > 0) e[a] += L * c * 4 * M_PI / rpp; }
            }
            if (pass >= learn) for (int a = 0; a < 6; ++a) S[0][p * 6 + a] += e[a], S2[0][p * 6 + a] += e[a] * e[a];
        }
    }
    /* the learned densities: mean radiance per bin, a floor of 1 % of the mean */
    double *pdf = malloc((size_t)P * BINS * 8), *cdf = malloc((size_t)P * (BINS + 1) * 8);
    for (uint32_t p = 0; p < P; ++p) {
        double tot = 0;
        for (int b = 0; b < BINS; ++b) { double m = hn[p * BINS + b] ? hist[p * BINS + b] / hn[p * BINS + b] : 0; pdf[p * BINS + b] = m; tot += m; }
        double mean = tot / BINS; tot = 0;
        for (int b = 0; b < BINS; ++b) { pdf[p * BINS + b] = fmax(pdf[p * BINS + b], 0.01 * mean + 1e-30); tot += pdf[p * BINS + b]; }
        cdf[p * (BINS + 1)] = 0;
        for (int b = 0; b < BINS; ++b) { pdf[p * BINS + b] /= tot; cdf[p * (BINS + 1) + b + 1] = cdf[p * (BINS + 1) + b] + pdf[p * BINS + b]; }
    }
    /* arm 1: guided passes, one probe at a time (directions per probe) */
    for (uint32_t pass = learn; pass < learn + passes; ++pass) {
        for (uint32_t p = 0; p < P; ++p) {
            uint32_t st = hash(p * 7919u + pass * 104729u + 12345u);
            float q[256];
            for (uint32_t r = 0; r < rpp; ++r) {
                float w[3];
                if (rnd(&st) < share) {
                    float u = rnd(&st), c = 0; int b = 0;
                    while (b < BINS - 1 && cdf[p * (BINS + 1) + b + 1] <= u) ++b;
                    (void)c;
                    pb_equal_area_decode(((b % G) + rnd(&st)) / (float)G, ((b / G) + rnd(&st)) / (float)G, w);
                } else {
                    float z = 1 - 2 * rnd(&st), ph = 2 * M_PI * rnd(&st), rr = sqrtf(fmaxf(0, 1 - z * z));
                    w[0] = rr * cosf(ph), w[1] = rr * sinf(ph), w[2] = z;
                }
                q[r] = (1 - share) / (4 * M_PI) + share * pdf[p * BINS + bin_of(w)] * BINS / (4 * M_PI);
                gdirs[4 * r] = w[0], gdirs[4 * r + 1] = w[1], gdirs[4 * r + 2] = w[2], gdirs[4 * r + 3] = 0;
            }
            pp.probes = probes, pp.rotations = ident, pp.directions = gdirs, pp.rays_per_probe = rpp, pp.pass_index = pass + 1000;
            /* one probe: slot p with rotation ident: pass arrays indexed by global probe, so use a 1-probe view */
            float pr1[4]; memcpy(pr1, probes + 4 * p, 16);
            pp.probes = pr1, pp.probe_count = 1, pp.first_probe = 0;
            pb_bake_trace_cpu(&pp, gray);
            double e[6] = {0};
            for (uint32_t r = 0; r < rpp; ++r) {
                const float *o = gray + 4 * r, *w = gdirs + 4 * r;
                double L = 0.2126 * o[0] + 0.7152 * o[1] + 0.0722 * o[2];
                for (int a = 0; a < 6; ++a) { double c = w[0] * axes[a][0] + w[1] * axes[a][1] + w[2] * axes[a][2]; if (c > 0) e[a] += L * c / (q[r] * rpp); }
            }
            for (int a = 0; a < 6; ++a) S[1][p * 6 + a] += e[a], S2[1][p * 6 + a] += e[a] * e[a];
        }
    }
    double rel[2][64 * 6], meanE[2] = {0}; int n = 0;
    for (uint32_t p = 0; p < P; ++p) for (int a = 0; a < 6; ++a) {
        for (int k = 0; k < 2; ++k) {
            double m = S[k][p * 6 + a] / passes, v = S2[k][p * 6 + a] / passes - m * m;
            rel[k][n] = m > 0 ? sqrt(fmax(v, 0) / passes) / m : 0; meanE[k] += m;
        }
        ++n;
    }
    printf("%s B=%u learn %u passes %u share %.2f: mean E uniform %.4f guided %.4f\n", path, B, learn, passes, share, meanE[0] / n, meanE[1] / n);
    for (int k = 0; k < 2; ++k) { qsort(rel[k], n, 8, cmpd); printf("  %s: rel std err median %.4f p95 %.4f\n", k ? "guided " : "uniform", rel[k][n / 2], rel[k][(int)(0.95 * n)]); }
    return 0;
}
