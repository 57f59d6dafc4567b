/* The bake context its stages share, and the stages (src/bake/bake.c runs
 * them in order over one bake_job, as Godot's lightmapper runs its steps):
 *
 *   place.c      1 the probe set and its memory budget, 2 positions
 *   resources.c  3 device buffers, the guide, light cells and the kernels
 *   relocate.c   4 probes moved out of geometry and off walls
 *   classify.c   5 probes inside geometry flagged, not traced
 *   passes.c     6 the trace passes (and --target-error's stopping)
 *   volume.c     7 SH, depth tiles and validity into the volume
 *   pass.c       one relocation or bake pass in bounded submissions, shared by 4-6
 *   wave.c       a bake pass's paths as a wavefront (--schedule wavefront), for pass.c
 *
 * Dilation (8) is dilate_gpu.c's; the write is the caller's. */
#ifndef PB_BAKE_STAGES_JOB_H
#define PB_BAKE_STAGES_JOB_H

#include "bake/bake_types.h"
#include "bake/convergence.h"
#include "bake/depth_sums.h"
#include "bake/gpu_scene.h"
#include "bake/guide.h"
#include "bake/light_cells_gpu.h"
#include "bake/scene_hash_job.h"
#include "bake/shading.h"
#include "sample/sample_gpu.h"
#include "gpu/gpu.h"
#include "probebake/bake.h"

typedef struct bake_buffers {
    pb_buffer params, probes, rotations, directions, rays, reduced, list, counters;
    pb_buffer relocation_directions; /* the relocation passes' fewer directions (unallocated when as many) */
    pb_buffer depth_lists;         /* bake_depth's ray lists per query cell (depth_lists.h) */
    pb_depth_sums sums;            /* bake_depth's moment sums over the passes (depth_sums.h) */
    pb_buffer nee;                 /* probe NEE: 2 vec4 per ray of a submission (unallocated when off) */
    pb_buffer guide, guide_slots;  /* path guiding's table and entry index (unallocated when off) */
    pb_guide guide_host;           /* its host copy and grid */
    const pb_light_cells_gpu *light; /* light cells (the GPU scene's, learned once per seed); NULL: off */
    pb_shading shading;
    pb_sample_buffers feedback;
    pb_pipeline trace, sh, depth;
    pb_pipeline wave;              /* bake_wave, --schedule wavefront only (else unmade) */
    pb_buffer wave_queues, wave_paths, wave_counts; /* its queues, path states, and queue sizes read back */
    uint32_t wave_capacity;        /* paths per wavefront submission (0: megakernel); set by stage 1 */
    uint32_t features;             /* PB_FEATURE_*: the code the pipelines were specialised to keep */
} bake_buffers;

/* Destroys what stage 3 made (each buffer may be unallocated). */
void pb_bake_buffers_release(pb_context *ctx, bake_buffers *b);

/* What one pass needs; per-probe host arrays are indexed by global probe. */
typedef struct bake_run {
    pb_context *ctx;
    bake_buffers *B;
    pb_gpu_scene *gs;
    const pb_bake_desc *d;
    const pb_scene *scene;
    uint32_t P, rpp, n, chunk;
    uint32_t chunk_now;            /* probes per submission now: shrinks so one takes ~0.25 s (Ctrl-C, watchdogs) */
    float *probes, *rotations, *reduced;
    double *sh_sum, *backfaces, *hits;
    double t_trace, t_sh, t_depth; /* GPU timestamps, ms */
    float *near;                   /* 8 per probe: nearest back t + dir, nearest front t + dir */
    uint64_t traversals;           /* BVH traversals of relocation and bake passes (counted by bake_trace) */
    uint64_t long_paths;           /* paths whose traversal loops ran past 32768 iterations */
    gpu_volume_refs feedback;      /* --indirect volume: the previous bounce's volume (probes 0: none) */
    pb_convergence *conv;          /* per probe: passes done and the spread of their estimates */
    uint32_t relocation_rpp;       /* rays per probe of a relocation pass (<= rpp) */
} bake_run;

/* The bake context: what its stages share. Per-probe host arrays are
 * indexed by local probe: i < own is global probe first + i, the rest are
 * the floor sample's probes of other parts (see pb_bake_stage_probe_set, place.c). */
typedef struct bake_job {
    pb_context *ctx;
    const pb_scene *scene;
    pb_gpu_scene *gs;
    pb_scene_hash_job scene_hash;  /* the volume's scene hash, on its own thread (when gs has none for the scene) */
    pb_bake_desc d;                /* checked, defaults filled */
    uint32_t total, first, step, own, P; /* the bake's probes; this run's part (first, first + step, ...,
                                            own of them); traced here (own + samples) */
    uint32_t stride;               /* of the floor sample (shard.h) */
    uint32_t rpp, n, chunk;
    uint64_t reduced_floats;
    uint32_t *global;              /* per local probe: its global index */
    uint32_t *floor_list, floor_count; /* local indices of the floor sample */
    float *probes, *rotations, *directions, *reduced, *offsets, *near;
    double *sh_sum, *backfaces, *hits;
    uint32_t *active, *converged_at;
    uint64_t relocation_rays;      /* probe rays the relocation passes traced */
    uint32_t relocated_with;       /* rays per probe of each relocation iteration; 0: none ran */
    float *inside;                 /* per probe: the back-face share of relocation's rays where it ends up
                                      (NaN: not measured there) */
    uint8_t *skip;                 /* per probe: 1 if classified inside geometry, not traced (stage 5) */
    uint32_t skipped;
    uint32_t moved_last;           /* probes the last relocation iteration moved (j->active holds them) */
    pb_convergence conv;
    bake_buffers B;
    bake_run run;
} bake_job;

/* Whether global probe p is one of this run's part's own. */
static inline int bake_job_holds(const bake_job *j, uint64_t p)
{
    return p >= j->first && (p - j->first) % j->step == 0 && (p - j->first) / j->step < j->own;
}

/* The parameters of a pass (relocating: a relocation pass) over the probes
 * of `list` (NULL: all), all but its submission's probe range (pass.c). */
void pb_bake_pass_params(const bake_run *run, uint32_t pass, int relocating, const uint32_t *list,
                         gpu_bake_params *prm);
/* One pass over the `total` probes of `list` (NULL: all) in bounded
 * submissions, its results added to the run's sums (pass.c). */
pb_result pb_bake_run_pass(bake_run *run, uint32_t pass, int relocating, const uint32_t *list, uint32_t total,
                           pb_error *err);
/* Paths per wavefront submission on this device for `paths` rays of the
 * largest submission (0 unless d->schedule is the wavefront), and the
 * device memory its buffers take (wave.c). */
uint32_t pb_bake_wave_capacity(const pb_context *ctx, const pb_bake_desc *d, uint32_t rpp, uint64_t paths);
uint64_t pb_bake_wave_bytes(uint32_t capacity);
/* Its buffers, for B->wave_capacity paths (none when 0; wave.c). */
pb_result pb_bake_wave_buffers(pb_context *ctx, bake_buffers *B, pb_error *err);
/* bake_wave's share of one submission: its `paths` rays, traced to the end
 * in one or more submissions before the caller's SH and depth (wave.c). */
pb_result pb_bake_wave_trace(bake_run *run, const gpu_bake_params *prm, uint32_t paths, pb_error *err);

/* The back-face share of the last relocation pass for the `count` probes of
 * `list` (NULL: all) where they stand, into j->inside (relocate.c). */
void pb_bake_record_inside(bake_job *j, const uint32_t *list, uint32_t count);

pb_result pb_bake_stage_probe_set(bake_job *j, pb_error *err);
pb_result pb_bake_stage_place(bake_job *j, pb_error *err);
pb_result pb_bake_stage_resources(bake_job *j, const pb_sample_volume *feedback, pb_error *err);
pb_result pb_bake_stage_relocate(bake_job *j, pb_error *err);
pb_result pb_bake_stage_classify(bake_job *j, pb_error *err);
pb_result pb_bake_stage_passes(bake_job *j, pb_error *err);
pb_result pb_bake_stage_volume(bake_job *j, pb_volume *out, pb_error *err);

#endif
