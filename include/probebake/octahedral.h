/*
 * probebake octahedral mapping (Cigolle et al., "A Survey of Efficient
 * Representations for Independent Unit Vectors", JCGT 2014): the unit sphere
 * folded onto the square [-1,1]^2, the +Z hemisphere in the centre diamond
 * and the -Z hemisphere in the four corners.
 *
 * Texels: a map of n x n interior texels; texel (x, y) covers
 * u in [-1 + 2x/n, -1 + 2(x+1)/n], v likewise with y, so x grows with u and
 * y with v. A bordered tile is (n+2) x (n+2): interior texel (x, y) sits at
 * (x+1, y+1), and the 1-texel border repeats the texels that are its
 * neighbours across the fold (edges mirrored, corners from the opposite
 * corner), so hardware bilinear filtering is seamless.
 */
#ifndef PROBEBAKE_OCTAHEDRAL_H
#define PROBEBAKE_OCTAHEDRAL_H

#include "probebake/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Unit direction -> (u, v) in [-1,1]^2. */
void pb_oct_encode(const float d[3], float uv[2]);

/* (u, v) in [-1,1]^2 -> unit direction. */
void pb_oct_decode(const float uv[2], float d[3]);

/* Direction through the centre of interior texel (x, y) of an n x n map. */
void pb_oct_texel_direction(uint32_t x, uint32_t y, uint32_t n, float d[3]);

/* For texel (bx, by) of an (n+2) x (n+2) bordered tile, the interior texel
 * (x, y) in [0,n)^2 whose value it holds (itself shifted for interior ones). */
void pb_oct_border_source(uint32_t bx, uint32_t by, uint32_t n, uint32_t *x, uint32_t *y);

#ifdef __cplusplus
}
#endif
#endif
