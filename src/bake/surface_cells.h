/* What path guiding and light cells both learn from: points drawn on the
 * scene's surfaces by area, and a grid of cubic cells sized so that a cell's
 * surface gets a given number of them on average. */
#ifndef PB_BAKE_SURFACE_CELLS_H
#define PB_BAKE_SURFACE_CELLS_H

#include "probebake/scene.h"

#include <stdint.h>

typedef struct pb_cell_grid {
    float origin[3], inv_cell;    /* local coordinates of the grid's corner, 1 / cell size */
    uint32_t dims[3];             /* at most 64 per axis */
} pb_cell_grid;

/* Cubes over the scene's bounds holding about `per_cell` of `points` points
 * drawn by area (surface area per cell = per_cell / points of the total), at
 * least 1/64 and at most 1/2 of the bounds' largest extent. */
void pb_cell_grid_fit(const pb_scene *s, double area_total, double per_cell, uint32_t points, pb_cell_grid *g);
/* Cubes of edge `cell` from the bounds' corner, at most 64 per axis. */
void pb_cell_grid_set(const pb_scene *s, float cell, pb_cell_grid *g);
uint32_t pb_cell_grid_cells(const pb_cell_grid *g);
/* The cell holding x (clamped into the grid), x fastest. */
uint32_t pb_cell_grid_index(const pb_cell_grid *g, const float x[3]);

double pb_triangle_area(const float *v);

/* Draws triangles by area: an alias table over the scene's triangles. */
typedef struct pb_surface_sampler {
    float *keep;
    uint32_t *alias;
    double area_total;            /* 0: no area (nothing can be drawn) */
} pb_surface_sampler;

/* Returns 0 when out of host memory. */
int pb_surface_sampler_init(const pb_scene *s, pb_surface_sampler *out);
void pb_surface_sampler_free(pb_surface_sampler *ss);
/* A point drawn by area with 3 or 4 numbers of `state` (a double-sided
 * triangle's side by a fourth): x offset off the surface along n, n the
 * unit normal of that side. Returns 0 for a degenerate triangle. */
int pb_surface_point(const pb_scene *s, const pb_surface_sampler *ss, uint32_t *state, float x[3], float n[3]);

#endif
