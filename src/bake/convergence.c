/* Per-probe convergence across passes (convergence.h). Sums are in double:
 * a pass's estimate is one float sum over its rays, so adding passes loses
 * nothing however many there are. */
#include "bake/convergence.h"
#include "probebake/sh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const float axes[6][4] = {{1, 0, 0, 0}, {-1, 0, 0, 0}, {0, 1, 0, 0}, {0, -1, 0, 0}, {0, 0, 1, 0}, {0, 0, -1, 0}};

int pb_convergence_init(pb_convergence *c, uint32_t probes)
{
    memset(c, 0, sizeof *c);
    c->probes = probes;
    c->passes = calloc(probes, sizeof *c->passes);
    c->dc_sum = calloc(probes, sizeof(double));
    c->dc_sq = calloc(probes, sizeof(double));
    c->axis_sum = calloc((size_t)probes * 6, sizeof(double));
    c->axis_sq = calloc((size_t)probes * 6, sizeof(double));
    if (!c->passes || !c->dc_sum || !c->dc_sq || !c->axis_sum || !c->axis_sq) {
        pb_convergence_free(c);
        return 0;
    }
    return 1;
}

void pb_convergence_free(pb_convergence *c)
{
    free(c->passes), free(c->dc_sum), free(c->dc_sq), free(c->axis_sum), free(c->axis_sq);
    memset(c, 0, sizeof *c);
}

static double luminance(const float rgb[3])
{
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

void pb_convergence_add(pb_convergence *c, uint32_t p, const float sh[27])
{
    double dc = luminance(sh);
    c->dc_sum[p] += dc;
    c->dc_sq[p] += dc * dc;
    float irr[27];
    memcpy(irr, sh, sizeof irr);
    pb_sh_radiance_to_irradiance(irr);
    for (int a = 0; a < 6; ++a) {
        float e[3];
        pb_sh_eval(irr, axes[a], e);
        double l = luminance(e);
        c->axis_sum[6 * (size_t)p + a] += l;
        c->axis_sq[6 * (size_t)p + a] += l * l;
    }
    c->passes[p]++;
}

double pb_pass_std_error(uint32_t k, double sum, double sq, double *mean)
{
    *mean = k ? sum / k : 0.0;
    if (k < 2)
        return 0.0;
    double var = fmax(0.0, (sq - k * *mean * *mean) / (k - 1));
    return sqrt(var / k);
}

float pb_convergence_relative_error(const pb_convergence *c, uint32_t p)
{
    double mean, se = pb_pass_std_error(c->passes[p], c->dc_sum[p], c->dc_sq[p], &mean);
    if (c->passes[p] < 2 || (mean == 0.0 && se != 0.0))
        return -1.f;
    return mean != 0.0 ? (float)(se / fabs(mean)) : 0.f;
}

double pb_convergence_floor(const pb_convergence *c, const uint32_t *list, uint32_t count)
{
    double sum = 0;
    uint64_t n = 0;
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t p = list[i];
        if (!c->passes[p])
            continue;
        for (int a = 0; a < 6; ++a)
            sum += fabs(c->axis_sum[6 * (size_t)p + a] / c->passes[p]);
        n += 6;
    }
    return n ? 0.05 * sum / (double)n : 0.0;
}

int pb_convergence_reached(const pb_convergence *c, uint32_t p, double target, double floor)
{
    for (int a = 0; a < 6; ++a) {
        double mean, se = pb_pass_std_error(c->passes[p], c->axis_sum[6 * (size_t)p + a], c->axis_sq[6 * (size_t)p + a],
                                            &mean);
        if (!(se <= target * fmax(fabs(mean), floor)))
            return 0;
    }
    return 1;
}
