/* scratch: where the Cornell box's probe variance comes from: rays whose first hit is near the ceiling */
#include "probebake/probebake.h"
#include "bake/shading.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
int main(int argc, char **argv)
{
    const char *path = argv[1];
    uint32_t B = atoi(argv[2]), rpp = 256, passes = 16;
    float ycut = atof(argv[3]);
    pb_scene_desc sd = {{0}, 0};
    pb_error err;
    pb_scene *s; pb_bvh *bvh;
    if (pb_scene_load(path, &sd, &s, &err) || pb_bvh_build(s, NULL, &bvh, &err)) { puts(err.message); return 1; }
    pb_bake_emitters em; pb_env_table env; float zero[3] = {0};
    pb_shading_host(s, zero, NULL, &em, &env, &err);
    pb_bake_desc d; memset(&d, 0, sizeof d);
    d.grid.counts[0] = d.grid.counts[1] = d.grid.counts[2] = 4;
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, 64, &d.grid);
    d.seed = 1;
    uint32_t P = d.grid.counts[0] * d.grid.counts[1] * d.grid.counts[2];
    float *probes = calloc(P * 4, 4), *rot = malloc(P * 48), *dirs = malloc(rpp * 16), *rays = malloc((size_t)P * rpp * 16);
    float *nee = malloc((size_t)P * rpp * 32);
    pb_sf_directions(rpp, dirs);
    float dx = s->bounds_max[0] - s->bounds_min[0], dy = s->bounds_max[1] - s->bounds_min[1], dz = s->bounds_max[2] - s->bounds_min[2];
    pb_bake_pass pp; memset(&pp, 0, sizeof pp);
    pp.scene = s, pp.bvh = bvh, pp.env = env.width ? &env : NULL, pp.emitters = &em, pp.bounces = B, pp.direct = 1;
    pp.max_distance = sqrtf(dx * dx + dy * dy + dz * dz), pp.lobe_power = 50, pp.seed = 1, pp.octmap_res = 8, pp.nee = nee;
    double *m2_all = calloc(P, 8), *m2_ring = calloc(P, 8), *m1_all = calloc(P, 8), *m1_ring = calloc(P, 8), *nring = calloc(P, 8);
    for (uint32_t pass = 0; pass < passes; ++pass) {
        for (uint32_t p = 0; p < P; ++p) {
            uint32_t id; float m[9];
            pb_bake_probe_position(s, &d, p, probes + 4 * p, &id);
            memcpy(&probes[4 * p + 3], &id, 4);
            pb_random_rotation(1, id, pass, m);
            for (int r = 0; r < 3; ++r) for (int c = 0; c < 4; ++c) rot[12 * p + 4 * r + c] = c < 3 ? m[3 * r + c] : 0.f;
        }
        pp.probes = probes, pp.rotations = rot, pp.directions = dirs, pp.probe_count = P, pp.rays_per_probe = rpp, pp.pass_index = pass;
        pb_bake_trace_cpu(&pp, rays);
        for (uint32_t p = 0; p < P; ++p)
            for (uint32_t r = 0; r < rpp; ++r) {
                const float *o = rays + 4 * ((size_t)p * rpp + r);
                const float *R = rot + 12 * p, *dd = dirs + 4 * r;
                float w[3];
                for (int k = 0; k < 3; ++k) w[k] = R[4 * k] * dd[0] + R[4 * k + 1] * dd[1] + R[4 * k + 2] * dd[2];
                float t = fabsf(o[3]);
                float hy = probes[4 * p + 1] + w[1] * t, hx = probes[4 * p] + w[0] * t, hz = probes[4 * p + 2] + w[2] * t; /* rotation row/col convention may be transposed: checked below */
                const float *n = nee + 8 * ((size_t)p * rpp + r);
                double x = 0.2126 * (o[0] + n[0]) + 0.7152 * (o[1] + n[1]) + 0.0722 * (o[2] + n[2]);
                float half = atof(argv[4]);
                int ring = t < pp.max_distance && hy > ycut && fabsf(hx) < half && fabsf(hz) < half;
                m2_all[p] += x * x, m1_all[p] += x;
                if (ring) m2_ring[p] += x * x, m1_ring[p] += x, nring[p] += 1;
            }
    }
    double N = (double)rpp * passes, share_sum = 0, shm_sum = 0; int cnt = 0;
    double shares[64];
    for (uint32_t p = 0; p < P; ++p) {
        double mean = m1_all[p] / N, var = m2_all[p] / N - mean * mean;
        if (!(m2_all[p] > 0)) continue;
        double share = m2_ring[p] / m2_all[p];
        shares[cnt++] = share;
        share_sum += share, shm_sum += m1_ring[p] / m1_all[p];
        (void)var;
    }
    printf("%s B=%u ycut %.2f: mean share of E[x^2] from rays first hitting above ycut: %.3f; of the mean: %.3f\n", path, B, ycut, share_sum / cnt, shm_sum / cnt);
    return 0;
}
