/* Per-probe convergence across passes (--target-error): the spread of each
 * pass's estimate gives the standard error of the mean, for the file's
 * accounting (DC luminance) and for the stopping rule (irradiance along the
 * six axes, the directions bench/paths_to_error scores). */
#ifndef PB_BAKE_CONVERGENCE_H
#define PB_BAKE_CONVERGENCE_H

#include <stdint.h>

typedef struct pb_convergence {
    uint32_t probes;
    uint32_t *passes;              /* per probe: passes accumulated */
    double *dc_sum, *dc_sq;        /* per probe: luminance of each pass's DC radiance coefficient */
    double *axis_sum, *axis_sq;    /* 6 per probe: luminance of each pass's irradiance along +-x, +-y, +-z */
} pb_convergence;

/* 0 on out of memory. */
int pb_convergence_init(pb_convergence *c, uint32_t probes);
void pb_convergence_free(pb_convergence *c);

/* One pass's radiance SH (27 coefficients) of probe p. */
void pb_convergence_add(pb_convergence *c, uint32_t p, const float sh[27]);

/* Standard error of the mean of k per-pass estimates from their sum and sum
 * of squares; *mean gets the mean. k < 2: 0. */
double pb_pass_std_error(uint32_t k, double sum, double sq, double *mean);

/* The file's relative standard error of probe p (DC luminance), or -1 where
 * it cannot be estimated (fewer than 2 passes, or a zero mean with spread). */
float pb_convergence_relative_error(const pb_convergence *c, uint32_t p);

/* The floor under the stopping rule's denominators: 5 % of the mean axis
 * irradiance over probes list[0..n-1] (so a probe facing black surfaces
 * need not resolve them beyond that; the bench scores alike). The bake
 * takes it once, after 4 passes, over a fixed sample of its probes
 * (shard.h), so that each part of a sharded bake stops its probes exactly
 * as the whole bake does. */
double pb_convergence_floor(const pb_convergence *c, const uint32_t *list, uint32_t n);

/* Whether probe p has converged: along every axis the standard error is at
 * most target x max(|mean|, floor). */
int pb_convergence_reached(const pb_convergence *c, uint32_t p, double target, double floor);

#endif
