/* A bake's settings, defaulted and checked before any scene or device is
 * touched (settings.c): pb_bake, pb_bake_sparse and pb_bake_check_settings
 * share these, so a front end can refuse a bad command line before it
 * loads a large scene. */
#ifndef PB_BAKE_SETTINGS_H
#define PB_BAKE_SETTINGS_H

#include "probebake/bake.h"

/* Fills the zero fields of d that need no scene: rays, passes, octahedral
 * map, relocation rays, lobe power, back-face and inside fractions. */
void pb_bake_settings_default(pb_bake_desc *d);

/* The checks on a defaulted d that need no scene and no grid (the grid's
 * counts come from the scene's bounds; pb_bake checks them). */
pb_result pb_bake_settings_check(const pb_bake_desc *d, pb_error *err);

/* sd with its zero fields defaulted, then checked against desc (itself not
 * checked here). */
pb_result pb_sparse_settings(const pb_bake_desc *desc, const pb_sparse_desc *sd, pb_sparse_desc *out,
                             pb_error *err);

/* Both: desc's settings checked (on a defaulted copy), then, when sparse is
 * not NULL, its layout's into *sd. pb_bake_check_settings and
 * pb_bake_sparse are this. */
pb_result pb_bake_settings(const pb_bake_desc *desc, const pb_sparse_desc *sparse, pb_sparse_desc *sd,
                           pb_error *err);

#endif
