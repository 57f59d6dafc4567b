/* Rays recorded per thread, re-ordered into lane groups: see ray_log.h. */
#include "ray_log.h"

#include <stdlib.h>
#include <string.h>

/* Which slot of which log the calling thread writes. A thread can outlive a
 * log (the one that calls pb_parallel_for works in every pass), so a slot
 * is valid only for the log generation it was taken in; pb_parallel_for's
 * workers are new threads each call and take new slots. */
static _Thread_local struct {
    uint64_t generation;
    uint32_t slot;
} this_thread;
static _Atomic uint64_t generations = 1;

void ray_log_init(ray_log *log, uint32_t lanes, pb_ray_cast_fn cast, void *cast_user)
{
    memset(log, 0, sizeof *log);
    log->lanes = lanes < 1 ? 1 : (lanes > RAY_LOG_MAX_LANES ? RAY_LOG_MAX_LANES : lanes);
    log->cast = cast, log->cast_user = cast_user;
    log->generation = atomic_fetch_add(&generations, 1);
}

static int append(ray_log_thread *t, const pb_ray *ray, int any)
{
    if (t->count == t->capacity) {
        uint64_t cap = t->capacity ? 2 * t->capacity : 1 << 16;
        pb_ray *r = realloc(t->rays, cap * sizeof *r);
        if (r)
            t->rays = r;
        uint8_t *a = r ? realloc(t->any, cap) : NULL;
        if (!a)
            return 0;
        t->any = a, t->capacity = cap;
    }
    t->rays[t->count] = *ray, t->any[t->count++] = (uint8_t)any;
    return 1;
}

void ray_log_cast(void *user, const pb_ray *ray, pb_trace_mode mode, pb_hit *hit)
{
    ray_log *log = user;
    if (this_thread.generation != log->generation) {
        this_thread.generation = log->generation;
        this_thread.slot = atomic_fetch_add(&log->threads, 1);
    }
    if (this_thread.slot < RAY_LOG_THREADS) {
        ray_log_thread *t = &log->thread[this_thread.slot];
        if (!t->failed && !append(t, ray, mode == PB_TRACE_ANY))
            t->failed = 1;
    }
    log->cast(log->cast_user, ray, mode, hit);
}

uint64_t ray_log_count(const ray_log *log)
{
    uint32_t n = atomic_load(&log->threads);
    if (n > RAY_LOG_THREADS)
        return 0;
    uint64_t total = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (log->thread[i].failed)
            return 0;
        total += log->thread[i].count;
    }
    return total;
}

static int cmp_position(const void *a, const void *b)
{
    return memcmp(a, b, 3 * sizeof(float));
}

/* The P probe positions (4 floats each, 3 read) sorted for at_probe;
 * malloc'ed, NULL when out of memory. */
static float *sorted_positions(const float *probes, uint32_t P)
{
    float *sorted = malloc((size_t)(P ? P : 1) * 3 * sizeof *sorted);
    if (!sorted)
        return NULL;
    for (uint32_t p = 0; p < P; ++p)
        memcpy(sorted + 3 * (size_t)p, probes + 4 * (size_t)p, 3 * sizeof(float));
    qsort(sorted, P, 3 * sizeof(float), cmp_position);
    return sorted;
}

/* 1 when o is one of the sorted probe positions (compared bit for bit: a
 * path's first ray leaves from the probe's position itself) */
static int at_probe(const float *sorted, uint32_t P, const float o[3])
{
    return bsearch(o, sorted, P, 3 * sizeof(float), cmp_position) != NULL;
}

/* Appends to list the k-th rays of the lane group's paths (start[0..lanes]
 * bound them) of one kind (any: 0 closest, 1 any-hit, -1 both); with idle, a lane
 * with no such ray gets an idle ray (one that ends at once) so that the
 * list's lane groups are the bake's. list NULL: counts only. Returns the
 * new count. */
static uint64_t append_kind(const ray_log_thread *t, const uint64_t *start, uint64_t lanes, uint32_t w, uint64_t k,
                            int any, int idle, pb_ray *list, uint64_t n)
{
    int some = 0;
    const pb_ray *model = NULL;
    for (uint64_t l = 0; l < lanes; ++l) {
        uint64_t i = start[l] + k;
        if (i < start[l + 1] && (any < 0 || t->any[i] == any))
            some = 1, model = &t->rays[i];
    }
    if (!some)
        return n;
    for (uint64_t l = 0; l < (idle ? w : lanes); ++l) {
        uint64_t i = start[l] + k;
        if (l < lanes && i < start[l + 1] && (any < 0 || t->any[i] == any)) {
            if (list)
                list[n] = t->rays[i];
            ++n;
        } else if (idle) {
            if (list)
                list[n] = *model, list[n].tmin = 0.f, list[n].tmax = -1.f; /* misses every box */
            ++n;
        }
    }
    return n;
}

/* Where each path of record t begins (start[0..paths], start[paths] = the
 * record's end); sorted: the probe positions. Returns the number of paths;
 * 0 when the record does not begin with a path. */
static uint64_t path_starts(const ray_log_thread *t, const float *sorted, uint32_t P, uint64_t *start)
{
    uint64_t paths = 0;
    for (uint64_t i = 0; i < t->count; ++i)
        if (!t->any[i] && at_probe(sorted, P, t->rays[i].origin))
            start[paths++] = i;
    if (!paths || start[0] != 0)
        return 0;
    start[paths] = t->count;
    return paths;
}

/* RAY_LOG_FIRST_COMPACTED for one record (paths bounded by start): every
 * path's first ray in groups of w, then the paths that go on, w consecutive
 * ones to a group, their later rays in step (both kinds, idle lanes).
 * out NULL: counts only. Returns the new count. */
static uint64_t lay_out_first_compacted(const ray_log_thread *t, const uint64_t *start, uint64_t paths, uint32_t w,
                                        pb_ray *out, uint64_t n)
{
    for (uint64_t g = 0; g < paths; g += w) /* the probe rays, as the bake's groups trace them */
        n = append_kind(t, start + g, paths - g < w ? paths - g : w, w, 0, -1, 1, out, n);
    uint64_t lane_begin[RAY_LOG_MAX_LANES], lane_end[RAY_LOG_MAX_LANES];
    uint32_t lanes = 0;
    for (uint64_t p = 0; p <= paths; ++p) {
        if (p < paths && start[p + 1] - start[p] > 1) { /* goes on: a lane of the current group */
            lane_begin[lanes] = start[p] + 1, lane_end[lanes++] = start[p + 1];
            if (lanes < w)
                continue;
        }
        if (lanes == 0 || (p < paths && lanes < w))
            continue;
        uint64_t longest = 0;
        for (uint32_t l = 0; l < lanes; ++l)
            longest = lane_end[l] - lane_begin[l] > longest ? lane_end[l] - lane_begin[l] : longest;
        for (uint64_t k = 0; k < longest; ++k) {
            const pb_ray *model = NULL;
            for (uint32_t l = 0; l < lanes && !model; ++l)
                if (lane_begin[l] + k < lane_end[l])
                    model = &t->rays[lane_begin[l] + k];
            for (uint32_t l = 0; l < w; ++l, ++n) {
                if (!out)
                    continue;
                int has = l < lanes && lane_begin[l] + k < lane_end[l];
                out[n] = has ? t->rays[lane_begin[l] + k] : *model;
                if (!has)
                    out[n].tmin = 0.f, out[n].tmax = -1.f; /* idle: misses every box */
            }
        }
        lanes = 0;
    }
    return n;
}

/* RAY_LOG_WORKGROUP for one record: for each workgroup of paths and each
 * step k, the k-th rays of its paths still going, in path order, packed w to
 * a lane group, the last group of the step filled with idle lanes. out NULL:
 * counts only. Returns the new count. */
static uint64_t lay_out_workgroup(const ray_log_thread *t, const uint64_t *start, uint64_t paths, uint32_t w,
                                  pb_ray *out, uint64_t n)
{
    for (uint64_t g = 0; g < paths; g += RAY_LOG_WORKGROUP_PATHS) {
        uint64_t size = paths - g < RAY_LOG_WORKGROUP_PATHS ? paths - g : RAY_LOG_WORKGROUP_PATHS, longest = 0;
        for (uint64_t p = g; p < g + size; ++p)
            longest = start[p + 1] - start[p] > longest ? start[p + 1] - start[p] : longest;
        for (uint64_t k = 0; k < longest; ++k) {
            uint64_t live = 0;
            const pb_ray *model = NULL;
            for (uint64_t p = g; p < g + size; ++p)
                if (start[p] + k < start[p + 1]) {
                    model = &t->rays[start[p] + k];
                    if (out)
                        out[n + live] = *model;
                    ++live;
                }
            for (; live % w; ++live)
                if (out)
                    out[n + live] = *model, out[n + live].tmin = 0.f, out[n + live].tmax = -1.f; /* idle */
            n += live;
        }
    }
    return n;
}

/* A path's place in the restart schedule's lane: which of its rays is next. */
typedef struct lane_state {
    uint64_t next, end; /* the current path's next ray and its end; next == end: none in flight */
    uint32_t paths_done;
} lane_state;

/* Lays out one record's paths as lanes that restart: see ray_log_restart.
 * out NULL: counts only. Returns the new count. */
static uint64_t lay_out_restart(const ray_log_thread *t, const uint64_t *start, uint64_t paths, uint32_t w,
                                uint32_t K, uint32_t M, pb_ray *out, uint64_t n)
{
    uint64_t span = (uint64_t)w * K; /* paths per lane group */
    for (uint64_t g = 0; g < paths; g += span) {
        lane_state lane[RAY_LOG_MAX_LANES] = {{0}};
        for (uint64_t it = 0;; ++it) {
            int live = 0;
            const pb_ray *model = NULL;
            const pb_ray *ray[RAY_LOG_MAX_LANES] = {NULL};
            for (uint32_t l = 0; l < w; ++l) {
                lane_state *s = &lane[l];
                uint64_t path = g + l + (uint64_t)w * s->paths_done;
                if (s->next == s->end && s->paths_done < K && path < paths && it % M == 0) {
                    s->next = start[path], s->end = start[path + 1]; /* the lane's next path begins */
                    ++s->paths_done;
                }
                if (s->next < s->end) {
                    ray[l] = model = &t->rays[s->next++];
                    live = 1;
                } else if (s->paths_done < K && g + l + (uint64_t)w * s->paths_done < paths) {
                    live = 1; /* waiting for the next restart */
                }
            }
            if (!live)
                break;
            if (!model)
                continue; /* every lane waits: an iteration that traces nothing */
            for (uint32_t l = 0; l < w; ++l, ++n) {
                if (!out)
                    continue;
                out[n] = ray[l] ? *ray[l] : *model;
                if (!ray[l])
                    out[n].tmin = 0.f, out[n].tmax = -1.f; /* idle: misses every box */
            }
        }
    }
    return n;
}

/* Lays out every record's rays in lane groups into c and a (NULL: counts
 * only): as `layout`, or with K nonzero as ray_log_restart's schedule (K
 * paths per lane, restarts every M iterations; all in c). start: room for
 * each record's path starts. Returns 0 when a record does not start with a
 * path (rays before it: not a path tracer's record). */
static int lay_out(const ray_log *log, const float *sorted, uint32_t P, ray_log_layout layout, uint32_t K,
                   uint32_t M, uint64_t *start, pb_ray *c, uint64_t *nc, pb_ray *a, uint64_t *na)
{
    uint32_t threads = atomic_load(&log->threads), w = log->lanes;
    *nc = *na = 0;
    for (uint32_t ti = 0; ti < threads; ++ti) {
        const ray_log_thread *t = &log->thread[ti];
        uint64_t paths = path_starts(t, sorted, P, start);
        if (t->count && !paths)
            return 0;
        if (K) {
            *nc = lay_out_restart(t, start, paths, w, K, M, c, *nc);
            continue;
        }
        if (layout == RAY_LOG_FIRST_COMPACTED) {
            *nc = lay_out_first_compacted(t, start, paths, w, c, *nc);
            continue;
        }
        if (layout == RAY_LOG_WORKGROUP) {
            *nc = lay_out_workgroup(t, start, paths, w, c, *nc);
            continue;
        }
        for (uint64_t g = 0; g < paths; g += w) {
            uint64_t lanes = paths - g < w ? paths - g : w, longest = 0;
            for (uint64_t l = 0; l < lanes; ++l) {
                uint64_t len = start[g + l + 1] - start[g + l];
                longest = len > longest ? len : longest;
            }
            for (uint64_t k = 0; k < longest; ++k) {
                if (layout == RAY_LOG_MIXED || layout == RAY_LOG_PACKED_MIXED) {
                    *nc = append_kind(t, start + g, lanes, w, k, -1, layout == RAY_LOG_MIXED, c, *nc);
                    continue;
                }
                *nc = append_kind(t, start + g, lanes, w, k, 0, layout == RAY_LOG_GROUPS, c, *nc);
                *na = append_kind(t, start + g, lanes, w, k, 1, layout == RAY_LOG_GROUPS, a, *na);
            }
        }
    }
    return 1;
}

/* ray_log_lockstep and ray_log_restart: count, allocate, lay out. */
static int lists(const ray_log *log, const float *probes, uint32_t P, ray_log_layout layout, uint32_t K, uint32_t M,
                 pb_ray **closest, uint64_t *closest_count, pb_ray **any, uint64_t *any_count)
{
    uint64_t total = ray_log_count(log), nc = 0, na = 0;
    float *sorted = sorted_positions(probes, P);
    uint64_t *start = malloc((total + 1) * sizeof *start);
    pb_ray *c = NULL, *a = NULL;
    int ok = total && sorted && start, paths = 1;
    if (ok)
        ok = paths = lay_out(log, sorted, P, layout, K, M, start, NULL, &nc, NULL, &na);
    if (ok) {
        c = malloc((nc ? nc : 1) * sizeof *c), a = malloc((na ? na : 1) * sizeof *a);
        ok = c && a && lay_out(log, sorted, P, layout, K, M, start, c, &nc, a, &na);
    }
    free(sorted), free(start);
    if (!ok) {
        free(c), free(a);
        return paths ? 0 : -1;
    }
    *closest = c, *closest_count = nc;
    if (any)
        *any = a, *any_count = na;
    else
        free(a); /* empty: the restart schedule's rays are all in closest */
    return 1;
}

int ray_log_lockstep(const ray_log *log, const float *probes, uint32_t P, ray_log_layout layout, pb_ray **closest,
                     uint64_t *closest_count, pb_ray **any, uint64_t *any_count)
{
    return lists(log, probes, P, layout, 0, 1, closest, closest_count, any, any_count);
}

int ray_log_restart(const ray_log *log, const float *probes, uint32_t P, uint32_t K, uint32_t M, pb_ray **rays,
                    uint64_t *count)
{
    if (!K || !M)
        return 0;
    return lists(log, probes, P, RAY_LOG_MIXED, K, M, rays, count, NULL, NULL);
}

void ray_log_free(ray_log *log)
{
    for (uint32_t i = 0; i < RAY_LOG_THREADS; ++i)
        free(log->thread[i].rays), free(log->thread[i].any);
    memset(log, 0, sizeof *log);
}
