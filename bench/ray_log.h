/* The rays a CPU path tracer casts, recorded as it casts them and put back
 * in the order the bake's lane groups trace them: what a tracer alone pays
 * for exactly the bake's rays (peer_paths' "em own" and "kr ..." columns).
 *
 * pb_bake_trace_cpu traces each path whole on one thread (its probe ray,
 * then shadow and bounce rays in turn), so each thread's record is a run of
 * whole paths; a path starts with a closest-hit ray from a probe's position.
 * The bake's kernel runs a subgroup's W consecutive paths of a probe in
 * lockstep (W = 8 on llvmpipe's 256-bit vectors, 32 on NVIDIA), their k-th
 * rays together: ray_log_lockstep lists the rays that way. */
#ifndef PB_BENCH_RAY_LOG_H
#define PB_BENCH_RAY_LOG_H

#include "probebake/probebake.h"

#include <stdatomic.h>

#define RAY_LOG_THREADS 256
#define RAY_LOG_MAX_LANES 128      /* a subgroup's lanes at most */
#define RAY_LOG_WORKGROUP_PATHS 64 /* bake_trace.comp's workgroup; pb_bake_trace_cpu's ranges are as long */

typedef struct ray_log_thread {
    pb_ray *rays;
    uint8_t *any;
    uint64_t count, capacity;
    int failed; /* out of host memory */
} ray_log_thread;

typedef struct ray_log {
    uint32_t lanes;      /* paths per lane group: the device's subgroup size (llvmpipe 8 on 256-bit vectors) */
    pb_ray_cast_fn cast; /* the tracer that answers the rays */
    void *cast_user;
    uint64_t generation; /* tells a worker thread's slot of an earlier log from this one's */
    _Atomic uint32_t threads;
    ray_log_thread thread[RAY_LOG_THREADS];
} ray_log;

/* An empty log in front of cast (cast_user), laid out for lane groups of
 * `lanes` paths (clamped to 1..RAY_LOG_MAX_LANES). */
void ray_log_init(ray_log *log, uint32_t lanes, pb_ray_cast_fn cast, void *cast_user);
/* pb_ray_cast_fn: records the ray in the calling thread's record, then casts it. */
void ray_log_cast(void *user, const pb_ray *ray, pb_trace_mode mode, pb_hit *hit);
/* Total rays recorded; 0 when a thread ran out of memory or out of slots. */
uint64_t ray_log_count(const ray_log *log);
/* How ray_log_lockstep lays the rays out. */
typedef enum ray_log_layout {
    RAY_LOG_PACKED, /* lane-group order, only rays */
    RAY_LOG_GROUPS, /* each W entries of a list are one lane group's k-th rays of that kind; a lane whose
                       path has none (it ended or casts the other kind) holds an idle ray (tmax -1: it ends
                       at the first box), as the bake's lane waits */
    RAY_LOG_MIXED,  /* as GROUPS, but both kinds in one list (closest): a lane group's k-th rays together,
                       as the bake's one trace loop runs them; its shadow rays then pay a closest hit */
    RAY_LOG_PACKED_MIXED, /* as PACKED, both kinds in one list (closest): no idle lane, kinds not kept apart,
                             as a compaction that moves paths between lanes and keeps the groups' order
                             would run them (a lane that restarts paths falls out of step instead:
                             ray_log_restart) */
    RAY_LOG_FIRST_COMPACTED, /* the probe rays in the bake's groups, then the paths that go on packed W to a
                                group, their later rays as MIXED: a schedule that compacts once, after the
                                first hit (one list, closest) */
    RAY_LOG_WORKGROUP, /* per workgroup of RAY_LOG_WORKGROUP_PATHS paths and per step k, the k-th rays of its
                          paths still going packed W to a lane group in path order, idle lanes only in the
                          step's last group: a kernel that compacts its workgroup's paths before each ray
                          (through shared memory, at a barrier) would trace them (one list, closest) */
    RAY_LOG_LAYOUTS    /* how many */
} ray_log_layout;

/* The recorded rays in lane-group order, closest-hit and any-hit ones apart
 * (each list keeps that order; MIXED, PACKED_MIXED, FIRST_COMPACTED,
 * WORKGROUP: all in closest, any empty). probes: the
 * P probe positions (4 floats each; the first 3 read). Returns 1; 0 when out
 * of memory or nothing was recorded; -1 when a record does not start with a
 * path. The lists are malloc'ed, the caller's. */
int ray_log_lockstep(const ray_log *log, const float *probes, uint32_t P, ray_log_layout layout, pb_ray **closest,
                     uint64_t *closest_count, pb_ray **any, uint64_t *any_count);
/* The recorded rays as lanes that restart paths would trace them: a lane
 * group of W lanes holds W K consecutive paths, lane l paths l, l + W, ...,
 * l + W (K - 1); each loop iteration every lane casts its path's next ray,
 * and a lane whose path has ended begins its next path at the next
 * iteration t with t % M == 0 (M 1: at once), idle until then. One list,
 * each W entries one iteration's rays (both kinds; idle lanes' rays end at
 * the first box), to be traced to their closest hits. K 1 is
 * RAY_LOG_MIXED. A lane group spans W K paths of one record, so with
 * W K above a parallel range of paths (pb_bake_trace_cpu's 64) the record
 * must come from one thread (peer_paths then pins its recording run to
 * one CPU). Returns as ray_log_lockstep. */
int ray_log_restart(const ray_log *log, const float *probes, uint32_t P, uint32_t K, uint32_t M, pb_ray **rays,
                    uint64_t *count);
void ray_log_free(ray_log *log);

#endif
