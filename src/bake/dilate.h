/* Dilation's arithmetic, shared by the CPU reference (dilate.c) and the
 * host side of the kernel (dilate_gpu.c, shaders/comp/dilate.comp): float
 * sums in a fixed neighbour order and no division, so the kernel and the
 * reference agree bit for bit on every device (Vulkan rounds +, -, x
 * correctly; division only to 2.5 ulp). The weight sum's reciprocal comes
 * from a table over how many face, edge and corner neighbours were filled. */
#ifndef PB_BAKE_DILATE_H
#define PB_BAKE_DILATE_H

#include "probebake/sparse.h"

#include <stdint.h>

/* A neighbour's weight by its squared distance in cells (1, 2, 3): 1 / d. */
#define PB_DILATE_W1 1.0f
#define PB_DILATE_W2 0.70710677f /* (float)(1 / sqrt(2)) */
#define PB_DILATE_W3 0.57735026f /* (float)(1 / sqrt(3)) */

/* Reciprocal table: entry (n1 * 13 + n2) * 9 + n3 for n1 <= 6 face, n2 <=
 * 12 edge and n3 <= 8 corner neighbours filled: (float)(1 / (n1 w1 + n2 w2
 * + n3 w3)) with the sum in double (0 for no neighbour). */
#define PB_DILATE_TABLE (7 * 13 * 9)
void pb_dilate_reciprocals(float table[PB_DILATE_TABLE]);

/* Probe states between rounds: not filled, valid, filled by dilation. */
enum { PB_DILATE_EMPTY = 0, PB_DILATE_VALID = 1, PB_DILATE_FILLED = 2 };

/* Neighbours are visited in one order everywhere: offsets (dx, dy, dz) in
 * {-1, 0, 1}^3 without (0, 0, 0), dz slowest, dx fastest; slot k of the 26. */
#define PB_DILATE_NEIGHBOURS 26u
#define PB_DILATE_NONE 0xffffffffu

/* A sparse volume's neighbour table: 26 probe indices per probe (slot order
 * above; PB_DILATE_NONE where there is none). A probe's neighbours are those
 * of its finest level: the probes one step of that level away in the bricks
 * of that level that hold it (bricks share probes on the finest lattice, so
 * several bricks name the same neighbour). malloc'd; NULL when out of
 * memory. */
uint32_t *pb_dilate_sparse_neighbours(const pb_sparse_layout *l, uint32_t probe_count);

#endif
