/* surface_bound: how many of a grid's probes any layout needs if it keeps
 * that grid's spacing at every surface (issue 14's bound).
 *
 *   surface_bound SCENE SPACING...
 *
 * For each spacing, the grid `probebake bake --spacing` would place (the
 * same origin and counts, cmd_bake.c), the cells that some triangle passes
 * through, and the distinct corner probes of those cells: a sampler
 * shading a surface point interpolates its cell's eight corners, so a
 * layout as fine as the grid at every surface holds at least these.
 * Triangles are walked on a barycentric lattice of a tenth of the spacing
 * (a sliver thinner than that may miss a cell it grazes, so the count is a
 * slight underestimate). No GPU; no timings. */
#include "probebake/scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int count(const pb_scene *s, double h, uint32_t n[3], size_t *cells_hit, size_t *cells_all, size_t *probes)
{
    double o[3];
    for (int k = 0; k < 3; ++k) {
        double c = floor(((double)s->bounds_max[k] - s->bounds_min[k]) / h);
        n[k] = c < 1 ? 1u : (uint32_t)c;
        o[k] = 0.5 * ((double)s->bounds_min[k] + s->bounds_max[k]) - 0.5 * h * (n[k] - 1);
    }
    size_t N = (size_t)n[0] * n[1] * n[2];
    unsigned char *cell = calloc(N, 1), *probe = calloc(N, 1);
    if (!cell || !probe) {
        free(cell), free(probe);
        return 0;
    }
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const float *p = s->positions + 9 * (size_t)t;
        double edge = 0;
        for (int a = 0; a < 3; ++a) {
            int b = (a + 1) % 3;
            double d2 = 0;
            for (int k = 0; k < 3; ++k)
                d2 += ((double)p[3 * a + k] - p[3 * b + k]) * ((double)p[3 * a + k] - p[3 * b + k]);
            edge = fmax(edge, sqrt(d2));
        }
        int m = (int)ceil(edge / (0.1 * h)) + 1;
        for (int i = 0; i <= m; ++i)
            for (int j = 0; j <= m - i; ++j) {
                double u = (double)i / m, v = (double)j / m, w = 1 - u - v;
                long c[3];
                int inside = 1;
                for (int k = 0; k < 3; ++k) {
                    double x = w * p[k] + u * p[3 + k] + v * p[6 + k];
                    c[k] = (long)floor((x - o[k]) / h);
                    inside &= c[k] >= 0 && c[k] + 1 < (long)n[k];
                }
                if (inside)
                    cell[c[0] + n[0] * (c[1] + (size_t)n[1] * c[2])] = 1;
            }
    }
    *cells_hit = 0, *probes = 0;
    *cells_all = (size_t)(n[0] > 1 ? n[0] - 1 : 0) * (n[1] > 1 ? n[1] - 1 : 0) * (n[2] > 1 ? n[2] - 1 : 0);
    for (uint32_t z = 0; z + 1 < n[2]; ++z)
        for (uint32_t y = 0; y + 1 < n[1]; ++y)
            for (uint32_t x = 0; x + 1 < n[0]; ++x) {
                if (!cell[x + n[0] * (y + (size_t)n[1] * z)])
                    continue;
                ++*cells_hit;
                for (int i = 0; i < 8; ++i)
                    probe[(x + (i & 1)) + n[0] * ((y + ((i >> 1) & 1)) + (size_t)n[1] * (z + (i >> 2)))] = 1;
            }
    for (size_t i = 0; i < N; ++i)
        *probes += probe[i];
    free(cell), free(probe);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: surface_bound SCENE SPACING...\n");
        return 2;
    }
    pb_scene_desc sd;
    memset(&sd, 0, sizeof sd);
    sd.skip_textures = 1;
    pb_scene *s = NULL;
    pb_error err;
    if (pb_scene_load(argv[1], &sd, &s, &err) != PB_OK) {
        fprintf(stderr, "surface_bound: error: %s\n", err.message);
        return 1;
    }
    printf("%-10s %16s %12s %14s %14s %10s\n", "spacing m", "grid", "probes", "surface cells", "their corners",
           "vs grid");
    int rc = 0;
    for (int a = 2; a < argc; ++a) {
        char *end = NULL;
        double h = strtod(argv[a], &end);
        uint32_t n[3];
        size_t hit, all, probes;
        if (!end || *end || !(h > 0) || !isfinite(h)) {
            fprintf(stderr, "surface_bound: error: spacing '%s' is not a positive number\n", argv[a]);
            rc = 2;
            break;
        }
        if (!count(s, h, n, &hit, &all, &probes)) {
            fprintf(stderr, "surface_bound: error: out of host memory at spacing %g\n", h);
            rc = 1;
            break;
        }
        size_t N = (size_t)n[0] * n[1] * n[2];
        char grid[48];
        snprintf(grid, sizeof grid, "%ux%ux%u", n[0], n[1], n[2]);
        printf("%-10g %16s %12zu %6zu of %-6zu %14zu %10.3f\n", h, grid, N, hit, all, probes, (double)probes / N);
    }
    pb_scene_destroy(s);
    return rc;
}
