/* Rays recorded per thread, re-ordered into lane groups: see ray_log.h. */
#include "ray_log.h"

#include <stdlib.h>
#include <string.h>

/* Which slot of which log the calling thread writes: worker threads outlive
 * a log, so a slot is valid only for the generation it was taken in. */
static _Thread_local struct {
    uint64_t generation;
    uint32_t slot;
} this_thread;
static _Atomic uint64_t generations = 1;

void ray_log_init(ray_log *log, pb_ray_cast_fn cast, void *cast_user)
{
    memset(log, 0, sizeof *log);
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
static uint64_t append_kind(const ray_log_thread *t, const uint64_t *start, uint64_t lanes, uint64_t k, int any,
                            int idle, pb_ray *list, uint64_t n)
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
    for (uint64_t l = 0; l < (idle ? RAY_LOG_LANES : lanes); ++l) {
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

/* Lays out every record's rays in lane groups into c and a (NULL: counts
 * only); start: room for each record's path starts. Returns 0 when a record
 * does not start with a path (rays before it: not a path tracer's record). */
static int lay_out(const ray_log *log, const float *sorted, uint32_t P, ray_log_layout layout, uint64_t *start,
                   pb_ray *c, uint64_t *nc, pb_ray *a, uint64_t *na)
{
    uint32_t threads = atomic_load(&log->threads);
    *nc = *na = 0;
    for (uint32_t ti = 0; ti < threads; ++ti) {
        const ray_log_thread *t = &log->thread[ti];
        uint64_t paths = 0;
        for (uint64_t i = 0; i < t->count; ++i)
            if (!t->any[i] && at_probe(sorted, P, t->rays[i].origin))
                start[paths++] = i;
        if (t->count && (!paths || start[0] != 0))
            return 0;
        start[paths] = t->count;
        for (uint64_t g = 0; g < paths; g += RAY_LOG_LANES) {
            uint64_t lanes = paths - g < RAY_LOG_LANES ? paths - g : RAY_LOG_LANES, longest = 0;
            for (uint64_t l = 0; l < lanes; ++l) {
                uint64_t len = start[g + l + 1] - start[g + l];
                longest = len > longest ? len : longest;
            }
            for (uint64_t k = 0; k < longest; ++k) {
                if (layout == RAY_LOG_MIXED) {
                    *nc = append_kind(t, start + g, lanes, k, -1, 1, c, *nc);
                    continue;
                }
                *nc = append_kind(t, start + g, lanes, k, 0, layout == RAY_LOG_GROUPS, c, *nc);
                *na = append_kind(t, start + g, lanes, k, 1, layout == RAY_LOG_GROUPS, a, *na);
            }
        }
    }
    return 1;
}

int ray_log_lockstep(const ray_log *log, const float *probes, uint32_t P, ray_log_layout layout, pb_ray **closest,
                     uint64_t *closest_count, pb_ray **any, uint64_t *any_count)
{
    uint64_t total = ray_log_count(log), nc = 0, na = 0;
    float *sorted = malloc((size_t)P * 3 * sizeof *sorted);
    uint64_t *start = malloc((total + 1) * sizeof *start);
    pb_ray *c = NULL, *a = NULL;
    int ok = total && sorted && start, paths = 1;
    for (uint32_t p = 0; ok && p < P; ++p)
        memcpy(sorted + 3 * (size_t)p, probes + 4 * (size_t)p, 3 * sizeof(float));
    if (ok) {
        qsort(sorted, P, 3 * sizeof(float), cmp_position);
        ok = paths = lay_out(log, sorted, P, layout, start, NULL, &nc, NULL, &na);
    }
    if (ok) {
        c = malloc((nc ? nc : 1) * sizeof *c), a = malloc((na ? na : 1) * sizeof *a);
        ok = c && a && lay_out(log, sorted, P, layout, start, c, &nc, a, &na);
    }
    free(sorted), free(start);
    if (!ok) {
        free(c), free(a);
        return paths ? 0 : -1;
    }
    *closest = c, *closest_count = nc, *any = a, *any_count = na;
    return 1;
}

void ray_log_free(ray_log *log)
{
    for (uint32_t i = 0; i < RAY_LOG_THREADS; ++i)
        free(log->thread[i].rays), free(log->thread[i].any);
    memset(log, 0, sizeof *log);
}
