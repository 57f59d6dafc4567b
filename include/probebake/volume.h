/*
 * probebake volume: a baked probe volume in memory and its file (docs/format.md).
 *
 * A volume is a set of probes (a regular grid, or points an artist placed),
 * each with a base position, a relocation offset, flags, 27 SH coefficients
 * (9 RGB, basis and order of sh.h) and an octahedral depth tile of
 * (n+2) x (n+2) texels holding (mean distance, mean squared distance).
 * Positions are in the scene's *original* coordinates: base positions are
 * float offsets from a double `origin`, so they keep precision anywhere.
 *
 * Files are written atomically: to a temporary file beside the target, then
 * renamed over it, so a failed or interrupted write never leaves a partial
 * file under the target name.
 */
#ifndef PROBEBAKE_VOLUME_H
#define PROBEBAKE_VOLUME_H

#include "probebake/base.h"
#include "probebake/files.h"
#include "probebake/sparse.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Version 2: depth texels in units of depth_unit (version 1 stored metres,
 * whose squares overflow float16 past 256 m; the reader converts).
 * Version 3: per-probe accounting. Version 4: the sparse layout section. */
#define PB_VOLUME_VERSION 4

enum {
    PB_VOLUME_IRRADIANCE = 1u << 0,     /* SH holds irradiance (else radiance) */
    PB_VOLUME_DIRECT = 1u << 1,         /* direct light included */
    PB_VOLUME_GRID = 1u << 2,           /* probes form counts[0] x counts[1] x counts[2], x fastest */
    PB_VOLUME_SHARD = 1u << 3,          /* a part of a bake (pb_volume_shard), for probebake merge */
    PB_VOLUME_SPARSE = 1u << 4          /* probes in bricks (pb_volume.sparse, sparse.h); origin is the lattice
                                           origin, spacing the finest level's, counts (P, 1, 1) */
};

/* The part of a bake a shard file holds (bake --shard I/N): probes
 * first, first + step, ... (probe_count of them) of `total`, undilated
 * (dilation needs neighbours across parts: pb_volume_merge runs it).
 * A grid's or points' part I is dealt (first I, step N), so every part holds
 * a share of every region; step 1 is a contiguous range (parts written
 * before 2026-11-27, and a sparse part's coarsest bricks). count 0: a whole
 * volume. */
typedef struct pb_volume_shard {
    uint32_t index, count;              /* part `index` of `count` (0-based) */
    uint32_t first, total;              /* its first probe, and the whole bake's probe count */
    uint32_t step;                      /* between its probes: count (dealt), or 0 or 1 (contiguous) */
} pb_volume_shard;

/* How many of `total` probes part `index` of `count` holds when they are
 * dealt: those p < total with p mod count == index. */
static inline uint32_t pb_shard_dealt_count(uint32_t total, uint32_t index, uint32_t count)
{
    return index < total ? (uint32_t)(((uint64_t)total - index + count - 1) / count) : 0u;
}

enum {
    PB_PROBE_VALID = 1u << 0,
    PB_PROBE_RELOCATED = 1u << 1,
    PB_PROBE_DILATED = 1u << 2,         /* invalid, value taken from valid neighbours */
    PB_PROBE_OUTSIDE = 1u << 3,         /* every ray left the scene: no surface nearby */
    PB_PROBE_CONVERGED = 1u << 4,       /* reached the target error before the last pass */
    PB_PROBE_INSIDE = 1u << 5           /* invalid: relocation's rays found it inside geometry, so it was not
                                           traced (zero SH and depth before dilation; pb_bake_desc.inside_fraction) */
};

typedef struct pb_volume_settings {
    uint64_t seed;
    uint64_t scene_hash;
    uint32_t rays_per_probe;            /* per pass */
    uint32_t passes;
    uint32_t bounces;
    uint32_t indirect_mode;             /* 0 path tracing, 1 previous volume */
    float target_error;                 /* 0: fixed pass count */
    float max_distance;                 /* depth of rays that miss, metres */
    uint32_t sh_window;                 /* pb_sh_window_kind applied to the SH (0 none) */
    float sh_window_width;              /* its W (0: the default, 3) */
    float indirect_clamp;               /* reflected light clamped per path to this radiance (0: off) */
    uint32_t techniques;                /* PB_TECHNIQUE_* bits: variance reduction the bake used */
    float refine_error;                 /* sparse: --refine-error the layout was placed with (0: not recorded) */
    uint32_t refine_test;               /* sparse: 1 + the pb_refine_test it was placed with (0: not recorded) */
    uint32_t test_pass_scale;           /* sparse, surface test: its probes' passes per bake pass (0: not
                                           recorded, or the probe test) */
    uint32_t seam_rounds;               /* sparse: rounds of the seam test (0: off, or not recorded) */
    float seam_error;                   /* sparse: the seam test's threshold (0: refine_error, or not recorded) */
    uint32_t relocation_rays;           /* rays per probe of each relocation iteration (0: no relocation, or not
                                           recorded: files before 2026-11-27 relocated with rays_per_probe) */
} pb_volume_settings;

/* Variance-reduction techniques (pb_volume_settings.techniques). */
enum {
    PB_TECHNIQUE_PROBE_NEE = 1u << 0,   /* light seen by probes sampled from the probe too (MIS) */
    PB_TECHNIQUE_GUIDING = 1u << 1,     /* bounce directions guided by a learned cache (mixture pdf) */
    PB_TECHNIQUE_LIGHT_CELLS = 1u << 2, /* emitters drawn per cell by measured light (mixture with power) */
    PB_TECHNIQUE_SOLID_ANGLE = 1u << 3  /* emitter triangles near a point sampled by solid angle */
};

/* Stage timings in milliseconds (0 for stages that did not run). pb_bake
 * fills trace, sh, octmap, relocate (the relocation's GPU time, a part of
 * trace and sh) and total; load, bvh and upload (pb_gpu_scene_create) are
 * the caller's, who ran those steps (the CLI sets them). */
typedef struct pb_volume_timings {
    double load, bvh, upload, trace, sh, octmap, relocate, total;
} pb_volume_timings;

typedef struct pb_volume {
    uint32_t flags;                     /* PB_VOLUME_* */
    uint32_t probe_count;
    uint32_t counts[3];                 /* grid counts; (probe_count, 1, 1) for point sets */
    uint32_t octmap_res;                /* n: interior texels per side */
    double origin[3];                   /* original coordinates; base positions are relative to it */
    double spacing[3];                  /* grid spacing (0 for point sets) */
    pb_volume_settings settings;
    pb_volume_timings timings;
    char device[128];
    float depth_unit;                   /* metres per depth unit: texels hold (d / unit, d^2 / unit^2); a power of two */
    pb_volume_shard shard;              /* with PB_VOLUME_SHARD: which part of a bake this is */
    uint64_t rays_traced;               /* probe rays of the bake passes (set by pb_bake; not stored in files) */
    uint64_t traversals;                /* BVH traversals of relocation and bake passes: probe, bounce, shadow rays (ditto) */
    uint64_t relocation_rays;           /* probe rays of the relocation passes: all probes, then those that moved (ditto) */
    uint32_t probes_dropped;            /* sparse: probes inside geometry dropped by the bake or merge (ditto) */
    uint32_t file_version;              /* format version of the file it was read from; 0 if not read */
    /* per probe, caller- or reader-owned arrays (pb_volume_free frees them) */
    float *base;                        /* 3 per probe, relative to origin */
    float *offset;                      /* 3 per probe: relocation, metres */
    uint32_t *probe_flags;              /* PB_PROBE_* */
    float *sh;                          /* 27 per probe */
    uint16_t *depth;                    /* (n+2)^2 texels x 2 halves per probe, tile after tile, in depth_unit */
    uint32_t *probe_paths;              /* paths (probe rays) traced for each probe over all its passes */
    float *probe_std_error;             /* relative standard error of its irradiance, or PB_STD_ERROR_UNKNOWN */
    pb_sparse_layout *sparse;           /* with PB_VOLUME_SPARSE: the bricks (owned; pb_volume_free frees it) */
} pb_volume;

/* probe_std_error where it cannot be estimated: one pass, a version 1-2
 * file, or a probe whose mean irradiance is zero while its passes differ. */
#define PB_STD_ERROR_UNKNOWN (-1.0f)

/* The depth unit for a volume whose rays see at most max_distance metres:
 * the smallest power of two u with max_distance / u <= 128, so the stored
 * mean square, at most 128^2 = 16384, can never overflow float16 (65504)
 * at any scene scale, and scaling by u is exact. Non-positive or
 * non-finite max_distance: 1. */
float pb_volume_depth_unit(float max_distance);

/* Bytes of one depth tile and of the whole file for a volume's sizes. */
uint64_t pb_volume_tile_halves(uint32_t octmap_res);
uint64_t pb_volume_file_bytes(const pb_volume *v);

/* Allocates the per-probe arrays for v->probe_count probes and
 * v->octmap_res, zeroed. Returns PB_ERROR_OUT_OF_HOST_MEMORY or
 * PB_ERROR_INVALID_ARGUMENT (no probes, octmap_res outside 1..256). */
pb_result pb_volume_alloc(pb_volume *v, pb_error *err);

/* Frees the per-probe arrays and a sparse layout (the struct itself is the
 * caller's). */
void pb_volume_free(pb_volume *v);

/* Frees the per-probe arrays only (positions, flags, SH, depth, accounting),
 * keeping the header fields and a sparse layout: for a caller done with the
 * probes' values (a sampler built from them) that still needs the rest.
 * pb_volume_free frees what is left. */
void pb_volume_free_probes(pb_volume *v);

/* Writes v to `path` by the output rules of files.h (atomic for regular
 * files, directly into devices and FIFOs, through symlinks, "-" for
 * standard output). Returns PB_ERROR_IO naming the path, or
 * PB_ERROR_INVALID_ARGUMENT naming the probe when any value (position,
 * offset, SH, depth texel, origin, spacing, depth unit) is NaN or infinite:
 * no file ever holds one. */
pb_result pb_volume_write(const char *path, const pb_volume *v, pb_error *err);

/* pb_volume_write with cancellation (files.h: checked between chunks and
 * before the rename; PB_ERROR_CANCELLED replaces nothing). */
pb_result pb_volume_write_ex(const char *path, const pb_volume *v, pb_cancel_fn cancel, void *user, pb_error *err);

/* Reads and validates a volume file into *v (arrays owned by v afterwards).
 * Version-1 files (depth in metres) are converted to depth units on read;
 * their overflowed (infinite) texels become max_distance and its square.
 * Returns PB_ERROR_IO (cannot read), PB_ERROR_PARSE (not a volume, truncated,
 * inconsistent sizes), PB_ERROR_UNSUPPORTED (newer version). */
pb_result pb_volume_read(const char *path, pb_volume *v, pb_error *err);

/* The header alone: every field pb_volume_read would set but the arrays
 * (NULL; nothing to free), after the same checks of the header, the section
 * offsets and the file's size, with the same errors. Values are not checked
 * (a NaN origin, a probe's) nor the sparse layout read: pb_volume_read may
 * still refuse the file for them. For a merge that checks its parts before
 * it holds any (pb_volume_merge_begin). */
pb_result pb_volume_read_header(const char *path, pb_volume *v, pb_error *err);

/* Original-coordinate position of probe i: origin + base + offset (double). */
void pb_volume_probe_position(const pb_volume *v, uint32_t i, double out[3]);

/* The textures of the WebGL2 sampler (runtime/probe_sample.glsl,
 * docs/sampling.md) as files a web or game engine loads without our reader,
 * written into directory `dir` (made if missing): probes.ktx2 (RGBA32F, one
 * texel per probe: relocated position in the volume's frame, flags),
 * sh.ktx2 (RGBA32F, 7 texels per probe: the 27 SH floats, a zero),
 * depth.ktx2 (RG16F, the depth tiles side by side) and manifest.json (the
 * sampler's uniforms, the frame's origin, sizes and encodings;
 * docs/format.md, "Texture contract"), the manifest last. Grid volumes
 * only: PB_ERROR_INVALID_ARGUMENT otherwise; PB_ERROR_IO naming the path. */
pb_result pb_volume_export_textures(const pb_volume *v, const char *dir, pb_error *err);

/* IEEE half <-> float, round to nearest even; NaN stays NaN, overflow is Inf. */
uint16_t pb_half_from_float(float f);
float pb_half_to_float(uint16_t h);

#ifdef __cplusplus
}
#endif
#endif
