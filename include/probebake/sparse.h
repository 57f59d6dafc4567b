/*
 * probebake sparse layout: probes in bricks at up to three densities
 * (docs/sparse.md).
 *
 * A brick is 4 x 4 x 4 probes spanning 3 x 3 x 3 cells of its level. Level
 * spacings grow by 3x from the finest (the volume's spacing) to the coarsest,
 * so one cell of level l is exactly one brick of level l + 1, and every
 * lattice point of a coarser level is one of the finer levels: a probe is
 * keyed by its index on the finest lattice and stored once, however many
 * bricks (of any level) share it. Bricks sharing a face share its probes, so
 * the interpolant is continuous between bricks of one level.
 *
 * Lookup: the indirection grid has one entry per coarsest brick ("cell").
 * An entry of depth 0 names the level-0 brick there (or none); an entry of
 * depth d > 0 points at a chunk of (3^d)^3 brick indices, one per sub-cell
 * of the finest level inside, x fastest: the finest brick covering it.
 */
#ifndef PROBEBAKE_SPARSE_H
#define PROBEBAKE_SPARSE_H

#include "probebake/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PB_SPARSE_MAX_LEVELS 3u
#define PB_SPARSE_BRICK_PROBES 64u      /* 4 x 4 x 4, x fastest */
#define PB_SPARSE_EMPTY 0x0fffffffu     /* no brick: inside solid geometry or outside the bake */
#define PB_SPARSE_DEPTH_SHIFT 28u       /* indirection entry: depth << 28 | brick or chunk offset */

typedef struct pb_sparse_brick {
    uint32_t level;                     /* 0 coarsest .. levels - 1 finest */
    uint32_t coord[3];                  /* brick coordinates at its level: lattice indices 3 coord .. 3 coord + 3 */
} pb_sparse_brick;

typedef struct pb_sparse_layout {
    uint32_t levels;                    /* 1 .. PB_SPARSE_MAX_LEVELS */
    uint32_t cells[3];                  /* indirection grid: coarsest bricks per axis */
    uint32_t brick_count;
    pb_sparse_brick *bricks;
    uint32_t *brick_probes;             /* 64 per brick: the volume's probe index, x fastest */
    uint32_t *indirection;              /* cells[0] cells[1] cells[2] entries, x fastest */
    uint32_t chunk_count;               /* entries in chunks */
    uint32_t *chunks;                   /* brick indices (or PB_SPARSE_EMPTY) */
} pb_sparse_layout;

/* Lattice steps of level `level` in finest-lattice units: 3^(levels - 1 - level). */
uint32_t pb_sparse_step(uint32_t levels, uint32_t level);

/* The coarsest brick (cell, x fastest, of cells[3]) that brick br lies in:
 * what a sparse bake sorts bricks by, and splits into parts by. */
uint64_t pb_sparse_coarsest_cell(const uint32_t cells[3], const pb_sparse_brick *br);

/* Builds the layout of `count` bricks (any order, no duplicates, each inside
 * the grid of cells): brick probes keyed by their finest-lattice index and
 * numbered in order of first use (brick by brick, x fastest), the
 * indirection grid and the chunks. *probe_count receives the number of
 * distinct probes, *keys (if not NULL, malloc'd, caller frees) their finest
 * lattice indices, 3 per probe. PB_ERROR_INVALID_ARGUMENT for a brick
 * outside the cells, a bad level or a duplicate; PB_ERROR_OUT_OF_HOST_MEMORY. */
pb_result pb_sparse_layout_build(uint32_t levels, const uint32_t cells[3], const pb_sparse_brick *bricks,
                                 uint32_t count, pb_sparse_layout *out, uint32_t *probe_count, uint32_t **keys,
                                 pb_error *err);

/* Deep copy (arrays malloc'd). */
pb_result pb_sparse_layout_copy(const pb_sparse_layout *src, pb_sparse_layout *dst, pb_error *err);

void pb_sparse_layout_free(pb_sparse_layout *l);

/* Checks the layout read from a file against a volume of probe_count
 * probes: sizes, levels, every index in range, every entry's depth and
 * chunk within bounds, every chunk entry a brick of the right level range
 * covering its sub-cell. Returns PB_ERROR_PARSE with the first problem. */
pb_result pb_sparse_layout_validate(const pb_sparse_layout *l, uint32_t probe_count, pb_error *err);

/* Per probe of a volume of probe_count probes laid out by l: the finest
 * level among the bricks that hold it (finest, may be NULL) and the first
 * brick that names it (first, may be NULL; UINT32_MAX for none). */
void pb_sparse_probe_levels(const pb_sparse_layout *l, uint32_t probe_count, uint8_t *finest, uint32_t *first);

/* The layout as the run-time samplers read it (pb_sparse_word in
 * shaders/include/probe_sample_core.glsl; the texture export's sparse.ktx2):
 * four word offsets (indirection, chunks, bricks, brick probes), then those
 * tables, a brick as four words (coordinates x, y, z, level). *words is
 * malloc'd. PB_ERROR_OUT_OF_HOST_MEMORY (also past 2^32 words). */
pb_result pb_sparse_layout_words(const pb_sparse_layout *l, uint32_t **words, uint32_t *count);

/* The brick serving point u, given in units of cells relative to the
 * lattice origin (clamped into the grid of cells): the finest brick whose
 * cell covers it, or PB_SPARSE_EMPTY. */
uint32_t pb_sparse_find(const pb_sparse_layout *l, const float u[3]);

#ifdef __cplusplus
}
#endif
#endif
