/*
 * probebake bake: light a probe grid (issue 3; first slice).
 *
 * Per pass, every probe traces `rays_per_probe` rays (spherical Fibonacci,
 * turned by a random rotation keyed on (seed, probe, pass)); each returns the
 * radiance arriving along it, path traced (shaders/include/bake.glsl says
 * what is modelled). The rays are projected onto SH L2 and filtered into
 * octahedral depth moments; passes are averaged. Punctual lights the probe
 * sees directly enter the SH as projected deltas. The result is a pb_volume
 * with irradiance SH.
 *
 * Before the passes, up to 3 relocation iterations (relocation_rays
 * first-hit rays per probe each) move probes out of geometry (along the
 * nearest back face) and away from walls they nearly touch, within 45 % of
 * a cell. After the passes, probes still seeing more than
 * invalid_backface_fraction back faces are invalid and take the
 * distance-weighted mean of valid neighbours (dilation).
 *
 * Light: punctual lights, emissive triangles and the environment, each
 * sampled at every surface hit (docs/bake.md says what is modelled).
 */
#ifndef PROBEBAKE_BAKE_H
#define PROBEBAKE_BAKE_H

#include "probebake/base.h"
#include "probebake/scene.h"
#include "probebake/bvh.h"
#include "probebake/device.h"
#include "probebake/trace.h"
#include "probebake/volume.h"
#include "probebake/environment.h"
#include "probebake/sample.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Probes at given positions (docs/bake.md, --points). */
/* Probe points (and grids) must lie within this many metres of the world
 * origin and of the scene: squared distances in the bake's float
 * arithmetic then stay below 1e30, far from float's 3.4e38. */
#define PB_MAX_COORDINATE 1e15

typedef struct pb_points {
    uint32_t count;
    double *positions;            /* 3 per point, scene (glTF world) coordinates */
    uint32_t *ids;                /* per point: keys its random numbers */
    double spacing;               /* relocation bound: 45 % of it per axis; 0: no relocation */
} pb_points;

/* Reads a points file ({"spacing": s, "points": [[x,y,z] | {"id": i, "position": [x,y,z]}, ...]}).
 * Returns PB_ERROR_IO or PB_ERROR_PARSE naming the file and the problem. */
pb_result pb_points_read(const char *path, pb_points *out, pb_error *err);
void pb_points_free(pb_points *p);

/* Relocation's rays per probe and iteration by default. It decides only
 * whether a probe is in a wall or too near one, and where it moves; the
 * volume's validity and light come from the passes' rays. bench/RESULTS.md,
 * "Relocation with 64 rays", has what fewer rays change. */
#define PB_RELOCATION_RAYS_DEFAULT 64u

/* A probe is classified inside geometry when its relocation rays see back
 * faces this much more often than invalid_backface_fraction allows: 0.35
 * by default. On five scenes no probe the passes call valid was above it
 * (bench/RESULTS.md, "Probes inside geometry not traced"). */
#define PB_INSIDE_MARGIN 0.1f

/* Progress: fraction done in [0,1] and a label; return nonzero to cancel. */
typedef int (*pb_progress_fn)(float fraction, const char *label, void *user_data);

/* How a bake pass's paths run on the device (docs/bake.md, "Schedules"):
 * one invocation per path that traces all of its rays; a wavefront whose
 * dispatches each trace one ray of every path waiting for that kind of ray
 * (closest hit or shadow); or restarts: one invocation per K paths, which
 * begins its next path as soon as its last ends (paths_per_lane). All write
 * the same volume, bit for bit; on lavapipe the wavefront is 1.1-1.8x slower
 * (bench/RESULTS.md, "A wavefront bake"). */
typedef enum pb_bake_schedule {
    PB_SCHEDULE_MEGAKERNEL = 0,
    PB_SCHEDULE_WAVEFRONT = 1,
    PB_SCHEDULE_RESTART = 2
} pb_bake_schedule;
#define PB_PATHS_PER_LANE_DEFAULT 8 /* PB_SCHEDULE_RESTART's K when paths_per_lane is 0 */
#define PB_MAX_PATHS_PER_LANE 64

/* Passes every probe takes under a target error before it may stop: its
 * standard error is estimated from the passes' spread, and the floor of
 * the stopping rule from their first 4 (docs/bake.md). With --passes at or
 * below it a target error stops nothing. */
#define PB_TARGET_ERROR_MIN_PASSES 4u

/* Zero fields mean the defaults listed on each line. */
typedef struct pb_bake_desc {
    pb_probe_grid grid;           /* counts >= 1 (pb_probe_grid_fit helps), unless points is set */
    const pb_points *points;      /* NULL: the grid; else these probes (no grid, no dilation) */
    uint32_t rays_per_probe;      /* default 256 */
    uint32_t passes;              /* default 4; with target_error, the most passes (default 64) */
    float target_error;           /* 0: fixed passes; else a probe stops once, along each axis, the standard
                                     error of its irradiance is below target_error x its mean (or x 5 % of
                                     the mean over all probes, if larger), after at least
                                     PB_TARGET_ERROR_MIN_PASSES passes; the bake stops when all have */
    uint32_t bounces;             /* reflections after the first hit (0 is direct light only; the CLI defaults to 2) */
    uint32_t octmap_res;          /* default 16 */
    uint32_t seed;                /* default 0 is a valid seed */
    uint32_t exclude_direct;      /* 1: only indirect light (renderers that light directly) */
    float sky[3];                 /* uniform sky radiance, default black (ignored with an environment) */
    const pb_environment *environment; /* NULL: the uniform sky; else this map (pb_environment_load) */
    float max_distance;           /* default: the scene's bounding-box diagonal */
    float lobe_power;             /* cosine power of the depth filter, default 50 */
    float invalid_backface_fraction; /* default 0.25: above it a probe is inside geometry (invalid) */
    uint32_t skip_relocation;     /* 1: probes stay on the grid (default: 3 relocation iterations) */
    float inside_fraction;        /* a probe whose relocation rays, where it ends up, hit more back faces
                                     than this is inside geometry: flagged PB_PROBE_INSIDE and not traced
                                     (default invalid_backface_fraction + PB_INSIDE_MARGIN; >= 1: every
                                     probe is traced). Only where relocation runs */
    uint32_t relocation_rays;     /* first-hit rays per probe in each relocation iteration, at most
                                     rays_per_probe (default PB_RELOCATION_RAYS_DEFAULT, or rays_per_probe
                                     if fewer) */
    uint32_t sh_window;           /* pb_sh_window_kind applied to the stored irradiance SH (default none) */
    float sh_window_width;        /* its W, default 3 */
    float indirect_clamp;         /* > 0: reflected light (all but what a probe ray sees directly) is clamped
                                     per path contribution to this radiance (biased, against fireflies);
                                     default 0, off */
    uint32_t max_lights_per_hit;  /* default 8: with more punctual lights, each hit draws one by power
                                     (alias table) instead of tracing a shadow ray to every light */
    uint32_t indirect_volume;     /* 1: each bounce shades first hits from the previous bounce's volume through
                                     the run-time sampler (bounces + 1 bakes, grid or sparse; fast, biased); 0: path tracing */
    uint32_t probe_nee;           /* 1: the light a probe sees directly (emitters, environment) is also
                                     sampled from the probe (one light sample per probe ray, a shadow ray)
                                     and MIS-combined with its rays (unbiased; docs/bake.md, "Estimators") */
    uint32_t guide_paths;         /* > 0: path guiding, learned before the bake from this many training paths
                                     started on the scene's surfaces; bounce directions are drawn from a
                                     mixture of the learned distribution and the cosine lobe (unbiased;
                                     docs/bake.md, "Estimators"); 0: off. The GPU scene keeps what it
                                     learned for later bakes with the same settings */
    uint32_t light_cells;         /* 1: next-event estimation draws emitters per region of space by the light
                                     shadow rays measured from there, mixed with their power (unbiased;
                                     docs/bake.md, "Estimators"); 0: by power alone */
    uint32_t emitters_by_area;    /* 1: next-event estimation draws a uniform point on the emitter triangle
                                     (the density swings near it); 0: a uniform direction toward it where
                                     it spans 0.01 sr or more (docs/bake.md, "Emitters by solid angle") */
    uint32_t schedule;            /* pb_bake_schedule of the bake passes (relocation always runs as one kernel);
                                     default PB_SCHEDULE_MEGAKERNEL */
    uint32_t paths_per_lane;      /* PB_SCHEDULE_RESTART: paths each invocation traces, 1 to 64; 0: 8 */
    uint32_t shard_index, shard_count; /* count > 0: bake part `index` (0-based) of `count` only: a contiguous
                                     range of the probes (grid or points), undilated, as a volume with
                                     PB_VOLUME_SHARD; pb_volume_merge joins the parts into the very bytes
                                     of the whole bake (timings aside). 0: the whole volume */
    pb_progress_fn progress;
    void *progress_user;
} pb_bake_desc;

/* A quality preset (bake --quality): rays per pass, the most passes, the
 * target error (0: every probe runs all passes), whether probe NEE is on
 * and path guiding's training paths.
 * src/bake/quality.c says what each is for; docs/bake.md, with numbers. */
typedef struct pb_bake_quality {
    const char *name;             /* "preview", "production", "reference" */
    uint32_t rays_per_probe, passes;
    float target_error;
    uint32_t probe_nee;
    uint32_t guide_paths;         /* path guiding's training paths (0: off) */
    uint32_t light_cells;         /* pb_bake_desc.light_cells */
} pb_bake_quality;

/* Path guiding's training paths when it is on and no count is given. */
#define PB_GUIDE_DEFAULT_PATHS (1u << 18)

/* The preset of that name, or NULL. */
const pb_bake_quality *pb_bake_quality_find(const char *name);

typedef struct pb_gpu_scene pb_gpu_scene;

/* Rounds of dilation a grid bake runs (its last stage). */
#define PB_DILATION_ROUNDS 8u

/* Dilation (src/bake/dilate.c): each invalid probe takes the
 * distance-weighted mean SH of its valid (or already filled) neighbours,
 * round after round (Jacobi), up to `rounds`; filled ones get
 * PB_PROBE_DILATED. Grid volumes (3x3x3 cells) and sparse ones (the
 * neighbours on the probe's finest level, pb_dilate_sparse_neighbours);
 * placed points are left as they are (the GPU version refuses them). */
void pb_volume_dilate(pb_volume *v, uint32_t rounds);
/* The same on the device (src/bake/dilate_gpu.c, shaders/comp/dilate.comp):
 * every round in one submission, the same bytes as pb_volume_dilate. */
pb_result pb_volume_dilate_gpu(pb_context *ctx, pb_volume *v, uint32_t rounds, pb_error *err);

/* Joins the parts of a sharded bake (src/bake/merge.c): they must be one
 * bake's (same scene hash, grid or points, settings, seed), disjoint and
 * complete (every part 0 .. N-1 exactly once); `names` (one per part, for
 * messages) say which file is at fault. Then the cross-part stages
 * (dilation) run, and *out is the volume a one-process bake writes, byte
 * for byte apart from the timings (summed) and, if parts ran on different
 * devices, the device name. PB_ERROR_INVALID_ARGUMENT for a foreign,
 * missing or duplicated part. */
pb_result pb_volume_merge(const pb_volume *parts, const char *const *names, uint32_t count, pb_volume *out,
                          pb_error *err);

/* Every check pb_volume_merge makes from the parts' headers alone
 * (pb_volume_read_header): one bake's parts, each once, none missing. A
 * sparse merge in steps runs it before it reads any part's layout, so a
 * foreign or missing part is refused before the parts are read whole. */
pb_result pb_volume_merge_check(const pb_volume *headers, const char *const *names, uint32_t count, pb_error *err);

/* The same merge of a grid's (or points') parts in steps, so that only one
 * part need be in memory beside the whole (`probebake merge`): begin makes
 * every check pb_volume_merge makes from the parts' headers
 * (pb_volume_read_header) and allocates *out; then each part, read whole,
 * is added (in part index order, as pb_volume_merge adds them; `header` is
 * what begin saw of it, and a part that no longer matches it is an error
 * naming the file); end dilates across the parts. A sparse bake's parts
 * have their own steps (below; begin refuses them). On an error after
 * begin the caller frees *out. */
pb_result pb_volume_merge_begin(const pb_volume *headers, const char *const *names, uint32_t count, pb_volume *out,
                                pb_error *err);
pb_result pb_volume_merge_add(pb_volume *out, const pb_volume *part, const pb_volume *header, const char *name,
                              pb_error *err);
void pb_volume_merge_end(pb_volume *out);

/* A sparse bake's parts merged in steps, so that only one part's probes
 * need be in memory beside the whole (`probebake merge`): begin takes every
 * part's header and sparse layout (pb_volume_read, then
 * pb_volume_free_probes), makes every check pb_volume_merge makes, builds
 * the whole layout and allocates *out; add takes the parts whole, one at a
 * time in part index order, each refused (naming its file) if it is not the
 * part begin saw; end dilates and stitches across the parts and drops the
 * probes in rock, as pb_volume_merge does, and frees *m. On an error the
 * caller frees *out, and *m with pb_sparse_merging_free unless end ran. */
typedef struct pb_sparse_merging pb_sparse_merging;
pb_result pb_volume_merge_sparse_begin(const pb_volume *layouts, const char *const *names, uint32_t count,
                                       pb_volume *out, pb_sparse_merging **m, pb_error *err);
pb_result pb_sparse_merge_add(pb_sparse_merging *m, pb_volume *out, const pb_volume *part, pb_error *err);
pb_result pb_sparse_merge_end(pb_sparse_merging *m, pb_volume *out, pb_error *err);
void pb_sparse_merging_free(pb_sparse_merging *m);

typedef struct pb_sparse_desc pb_sparse_desc;

/* A bake on `count` devices at once (src/bake/multi_device.c): part i of
 * count (as desc->shard_index / shard_count, which must be 0 here) on
 * ctxs[i] with its uploaded scene scenes[i], one host thread per device,
 * joined by pb_volume_merge. On devices of one driver the result is a
 * one-device bake's, byte for byte apart from the timings. desc->progress
 * hears the mean fraction of all parts, from any of their threads (one at a
 * time); its cancel stops every part. sparse: NULL for a grid (or points),
 * else a sparse bake split by coarsest brick (pb_bake_sparse's parts). The
 * parts share scenes[0]'s path guiding cache for the call: the guide is
 * learned once, on the host, and scenes[0] keeps it. */
pb_result pb_bake_devices(pb_context *const *ctxs, pb_gpu_scene *const *scenes, uint32_t count, const pb_scene *scene,
                          const pb_bake_desc *desc, const pb_sparse_desc *sparse, pb_volume *out, pb_error *err);

/* Where probe `probe` starts, in the scene's local frame, and its id. The one
 * rounding rule for grids and points alike: the world position in double
 * (scene origin + grid origin + index x spacing, or the point), then
 * (float)(world - scene origin). So a points file holding a grid's world
 * positions (printed with 17 digits) and grid indices as ids places and
 * keys its probes exactly as the grid does. */
void pb_bake_probe_position(const pb_scene *scene, const pb_bake_desc *desc, uint32_t probe, float local[3],
                            uint32_t *id);

/* The light a bake or render would compute with: every material's emission
 * (emissive factor x strength), every punctual light's colour x intensity,
 * the sky and every environment texel (NULL: none) must be finite, >= 0 and
 * at most PB_MAX_RADIOMETRIC (scene.h), and light ranges finite and >= 0.
 * Returns PB_ERROR_INVALID_ARGUMENT naming the file and the material,
 * light or texel. Host only: pb_bake and pb_render call it before any
 * device work; a front end may call it right after loading. */
pb_result pb_bake_check_light(const pb_scene *scene, const float sky[3], const pb_environment *environment,
                              pb_error *err);

/* --- The sparse layout (src/bake/sparse_bake.c, docs/sparse.md) --- */

/* Where a cell's refinement test bakes its truth. */
typedef enum pb_refine_test {
    PB_REFINE_TEST_SURFACE = 0,   /* probes at points on the surfaces inside the cell, along their normals
                                     (where a renderer samples); thrown away after the test */
    PB_REFINE_TEST_PROBE = 1      /* one probe inside the cell, all six axes (a finer-lattice point, kept if
                                     the cell is refined) */
} pb_refine_test;

/* Zero fields mean the defaults listed on each line. */
typedef struct pb_sparse_desc {
    uint32_t levels;              /* default 3 (bake --max-level 2): spacings F, 3F, 9F */
    float refine_error;           /* default 0.1: a cell of a brick is subdivided where the coarser level's
                                     prediction misses the test's baked irradiance by more than this
                                     fraction (and by 3 of its standard errors): of the larger of the two
                                     for the surface test (so below 1), of the mean prediction for the
                                     probe test */
    uint32_t test;                /* pb_refine_test: what the prediction is checked against; default surface */
    uint32_t test_pass_scale;     /* default 4, at most 64: the surface test's probes are traced with this many
                                     times the bake's passes (pb_bake_passes). Their standard error gates the refinement, so noisy tests
                                     leave dark, noisy surfaces coarse (bench/RESULTS.md, "The Crypt's
                                     remaining gap") */
    uint32_t seam_rounds;         /* default 0 (off), at most 8: rounds of the seam test, which refines a
                                     coarser cell where a finer brick's hanging probe on its face misses
                                     its value there (docs/sparse.md, placement step 3) */
    float seam_error;             /* default refine_error: the miss (relative to the mean prediction, above 3
                                     of the probe's standard errors) past which the seam test refines; coarse
                                     cells beside refined ones mostly miss by several E (bench/RESULTS.md,
                                     "A seam threshold"), so a larger value refines only the worst of them */
} pb_sparse_desc;

/* What the refinement did, per level. */
typedef struct pb_sparse_stats {
    uint32_t bricks[3];           /* bricks kept at each level */
    uint32_t probes[3];           /* probes first baked for each level (shared probes counted once) */
    uint32_t dropped[3];          /* bricks dropped: every probe inside solid geometry */
    uint32_t tested[3];           /* cells of each level tested for subdivision (a probe baked inside) */
    uint32_t skipped[3];          /* cells not tested: no surface within two cells of its corners, no
                                     valid corner (solid), or (surface test) no surface inside */
    uint32_t beyond[3];           /* cells not tested: wholly outside the bake bounds (the coarsest
                                     bricks overshoot them) */
    uint32_t refined[3];          /* cells subdivided into a brick of the next level */
    uint32_t seam_refined[3];     /* of those, by the seam test: a hanging probe of the next level on the
                                     cell's face missed the cell's value there */
    uint32_t test_probes[3];      /* surface test: probes baked to test the cells of each level, thrown away */
    uint32_t bakes;               /* pb_bake calls */
} pb_sparse_stats;

/* A sparse bake: desc->grid's origin is the lattice origin, its spacing the
 * finest level's and its counts the extent; desc->points and shards are
 * refused; with --indirect volume every bounce is a placement of its own.
 * Coarsest bricks cover the extent; each level's cells near surfaces are
 * tested (sd->test: probes at the surface points nearest the centres of
 * the cell's sub-cells of at most 3 finest spacings, or one probe inside),
 * and where the coarser level mispredicts them (sd->refine_error) the cell
 * becomes a brick of the next level. Bricks
 * whose probes are all inside geometry are dropped. Invalid probes are
 * dilated (on the device, as a grid's); then probes on the faces of a finer
 * brick next to a coarser one take what the coarser brick's sampler holds
 * there (trilinear weights times visibility), so the interpolant does not
 * jump in open air and no light crosses a wall (docs/sparse.md).
 * stats may be NULL. */
pb_result pb_bake_sparse(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc,
                         const pb_sparse_desc *sd, pb_volume *out, pb_sparse_stats *stats, pb_error *err);

/* The checks pb_bake and pb_bake_sparse (sparse: non-NULL) make on desc
 * that need neither the scene nor a device: ray, pass, bounce and map
 * limits, the SH window, the clamp, estimator and split combinations, the
 * sparse layout's settings. Everything but the grid's counts, the points'
 * coordinates and the light, which need the scene. A front end calls it
 * before it loads a scene, so a bad command line fails at once. Returns
 * PB_ERROR_INVALID_ARGUMENT with the bake's own message. */
pb_result pb_bake_check_settings(const pb_bake_desc *desc, const pb_sparse_desc *sparse, pb_error *err);

/* A schedule as front ends name it: "megakernel", "wavefront", "restart" or
 * "restart:K" (K 1 to PB_MAX_PATHS_PER_LANE) into *schedule and *paths_per_lane
 * (0 unless given). Returns 0 for any other text, leaving both alone. */
int pb_bake_schedule_parse(const char *text, uint32_t *schedule, uint32_t *paths_per_lane);

/* desc's schedule by that name ("restart:8" with its K filled in), into buf. */
const char *pb_bake_schedule_name(const pb_bake_desc *desc, char *buf, size_t size);

/* The passes a bake of desc takes (at most, under target_error): desc->passes,
 * or its default when 0. */
uint32_t pb_bake_passes(const pb_bake_desc *desc);

/* Bakes into *out (arrays allocated; pb_volume_free releases them).
 * Returns PB_ERROR_INVALID_ARGUMENT before any GPU work for bad descs,
 * PB_ERROR_TOO_LARGE when the grid does not fit the device, and
 * PB_ERROR_CANCELLED when the progress callback asks. */
pb_result pb_bake(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc, pb_volume *out,
                  pb_error *err);

/* One bounce of --indirect volume: a bake (bounces 0, indirect_volume 0)
 * whose probe rays' first hits also reflect the irradiance `volume` holds
 * there (the previous bounce's, grid or sparse; NULL: none). Grids, points
 * and parts alike: pb_bake's bounce loop and the sparse bake's are made of it. */
pb_result pb_bake_bounce(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, const pb_bake_desc *desc,
                         const pb_sample_volume *volume, pb_volume *out, pb_error *err);

/* Emissive triangles as next-event-estimation light sources: an alias table
 * over their power (area x luminance of the emissive factor x strength), in
 * scene triangle order, and per scene triangle the area density of a sampled
 * point (probability / area; 0 for non-emitters). */
typedef struct pb_bake_emitters {
    uint32_t count;
    uint32_t *tri;                /* scene triangle of each emitter */
    float *prob;                  /* alias table */
    uint32_t *alias;
    float *pdf_area;              /* per scene triangle */
} pb_bake_emitters;

pb_result pb_bake_emitters_build(const pb_scene *scene, pb_bake_emitters *out, pb_error *err);
void pb_bake_emitters_free(pb_bake_emitters *e);

/* Punctual lights drawn one per hit in proportion to their power (luminance
 * of colour x intensity), for scenes with many lights. */
typedef struct pb_light_table {
    uint32_t count;
    float *keep;                  /* alias table */
    uint32_t *alias;
    float *p;                     /* probability of each light */
} pb_light_table;

/* count 0 (nothing allocated) when the scene has no light of positive power. */
pb_result pb_light_table_build(const pb_scene *scene, pb_light_table *out, pb_error *err);
void pb_light_table_free(pb_light_table *t);

/* --- CPU references of the bake kernels (tests) --- */

/* A ray caster for the CPU reference path tracer: answers one ray as
 * pb_trace_cpu would (closest hit, or any hit for a shadow ray; alpha cut
 * outs honoured). bench/peer_paths plugs Embree in to time the same paths
 * on a CPU peer. */
typedef void (*pb_ray_cast_fn)(void *user, const pb_ray *ray, pb_trace_mode mode, pb_hit *hit);

/* Everything a bake kernel reads for one pass, on the host. */
typedef struct pb_bake_pass {
    const pb_scene *scene;
    const pb_bvh *bvh;
    const float *probes;          /* 4 per probe slot: local position, w = probe id (uint bits) */
    const uint32_t *probe_list;   /* NULL: slots first_probe.. in order; else slots from probe_list[first_probe] */
    const float *rotations;       /* 12 per probe (3 rows of 4) */
    const float *directions;      /* 4 per ray index */
    uint32_t first_probe, probe_count, rays_per_probe, pass_index, seed, bounces, octmap_res, direct;
    const pb_env_table *env;      /* NULL: black */
    float max_distance, lobe_power;
    const pb_bake_emitters *emitters; /* NULL or count 0: no next-event estimation of emitters */
    const pb_sample_volume *volume;   /* --indirect volume: the previous bounce's volume, or NULL */
    const pb_light_table *light_table; /* non-NULL: one light drawn per hit (as max_lights_per_hit decides) */
    float indirect_clamp;             /* as pb_bake_desc */
    float *nee;                       /* probe NEE: out of trace, in to SH, 8 floats per ray (weighted
                                         radiance / 4pi, 0, direction, 0); NULL: off */
    const struct pb_guide *guide;     /* path guiding's learned cache (src/bake/guide.h); NULL: off */
    const struct pb_light_cells *light_cells; /* emitters drawn per cell (src/bake/light_cells.h); NULL: by power */
    uint32_t emitters_by_area;        /* as pb_bake_desc */
    pb_ray_cast_fn cast;              /* the CPU reference's rays: NULL traces pb_trace_cpu over bvh */
    void *cast_user;
} pb_bake_pass;

/* A pass's per-probe host inputs as pb_bake makes them for probes 0..P-1
 * of d (not relocated): probes (4 per probe: local position, w = probe id
 * bits), rotations (12 per probe) and the rays_per_probe directions (4 per
 * ray), for the CPU references of the tests and benches. */
void pb_bake_pass_inputs(const pb_scene *scene, const pb_bake_desc *d, uint32_t P, uint32_t rays_per_probe,
                         uint32_t pass, float *probes, float *rotations, float *directions);

/* bake_trace.comp: rays out, 4 floats per ray (radiance, signed distance).
 * Returns the BVH traversals it made (rays, shadow rays), as the kernel counts. */
uint64_t pb_bake_trace_cpu(const pb_bake_pass *p, float *rays);
/* bake_sh.comp and bake_depth.comp: reduced out, 40 floats per probe (27 SH,
 * back faces, hits, nearest back hit t + direction, nearest front hit t +
 * direction, 3 zeros) then the pass's 2 depth moments per probe texel. (The
 * depth kernel adds its moments to sums over the passes on the device.) */
void pb_bake_sh_cpu(const pb_bake_pass *p, const float *rays, float *reduced);
void pb_bake_depth_cpu(const pb_bake_pass *p, const float *rays, float *reduced);

#ifdef __cplusplus
}
#endif
#endif
