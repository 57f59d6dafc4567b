/* ray_log_test: the replay's layouts (ray_log.h) on a record made by hand,
 * against what each layout is defined to be. No device.
 *
 * Two probes, 8 paths each (one lane group per probe), of known lengths and
 * kinds: path p of probe q casts a probe ray from q's position (closest),
 * then len(p) - 1 rays alternating any-hit (shadow) and closest (bounce).
 * Each ray's tmin carries its identity (probe, path, index in the path), so
 * a layout's order can be read back. */
#include "ray_log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PATHS 8
#define PROBES 2
#define LANES 8 /* one probe's paths to a lane group */

static const uint32_t lengths[PROBES][PATHS] = {{1, 3, 5, 2, 1, 4, 3, 6}, {2, 2, 2, 2, 2, 2, 2, 2}};
static const float probe_at[PROBES][4] = {{1.f, 2.f, 3.f, 0.f}, {-4.f, 5.f, 0.5f, 0.f}};

static int failures;
#define CHECK(c, ...)                                                                                                \
    do {                                                                                                             \
        if (!(c)) {                                                                                                  \
            fprintf(stderr, "ray_log_test: " __VA_ARGS__);                                                           \
            fputc('\n', stderr);                                                                                     \
            ++failures;                                                                                              \
        }                                                                                                            \
    } while (0)

static float ident(uint32_t q, uint32_t p, uint32_t k)
{
    return (float)(q * 10000 + p * 100 + k);
}

static int kind_any(uint32_t k)
{
    return k % 2 == 1; /* rays 1, 3, ...: shadow rays */
}

static void no_cast(void *user, const pb_ray *ray, pb_trace_mode mode, pb_hit *hit)
{
    (void)user, (void)ray, (void)mode;
    memset(hit, 0, sizeof *hit);
}

/* The record: every path of each probe in order, on this thread. */
static uint64_t record(ray_log *log)
{
    uint64_t n = 0;
    ray_log_init(log, LANES, no_cast, NULL);
    for (uint32_t q = 0; q < PROBES; ++q)
        for (uint32_t p = 0; p < PATHS; ++p)
            for (uint32_t k = 0; k < lengths[q][p]; ++k, ++n) {
                pb_ray r;
                memset(&r, 0, sizeof r);
                if (k == 0)
                    memcpy(r.origin, probe_at[q], sizeof r.origin);
                else
                    r.origin[0] = 100.f + (float)n, r.origin[1] = (float)k; /* a surface point, no probe's */
                r.direction[2] = 1.f;
                r.tmin = ident(q, p, k), r.tmax = 1e30f;
                pb_hit h;
                ray_log_cast(log, &r, kind_any(k) ? PB_TRACE_ANY : PB_TRACE_CLOSEST, &h);
            }
    return n;
}

static int idle(const pb_ray *r)
{
    return r->tmax < 0.f;
}

/* The expected list of one kind (-1: both) in lane groups, with idle lanes
 * (groups != 0) or packed; returns its length, identities in want (idle: -1). */
static uint32_t expected(int kind, int groups, float *want)
{
    uint32_t n = 0;
    for (uint32_t q = 0; q < PROBES; ++q) {
        uint32_t longest = 0;
        for (uint32_t p = 0; p < PATHS; ++p)
            longest = lengths[q][p] > longest ? lengths[q][p] : longest;
        for (uint32_t k = 0; k < longest; ++k) {
            int some = 0;
            for (uint32_t p = 0; p < PATHS; ++p)
                some |= k < lengths[q][p] && (kind < 0 || kind_any(k) == kind);
            for (uint32_t p = 0; some && p < PATHS; ++p) {
                if (k < lengths[q][p] && (kind < 0 || kind_any(k) == kind))
                    want[n++] = ident(q, p, k);
                else if (groups)
                    want[n++] = -1.f;
            }
        }
    }
    return n;
}

/* The expected RAY_LOG_FIRST_COMPACTED list: each probe's 8 probe rays, then
 * the paths longer than one ray (both probes', in order), 8 to a group,
 * their rays 1.. in step, idle lanes -1. */
static uint32_t expected_first_compacted(float *want)
{
    uint32_t n = 0, q_of[PROBES * PATHS], p_of[PROBES * PATHS], on = 0;
    for (uint32_t q = 0; q < PROBES; ++q)
        for (uint32_t p = 0; p < PATHS; ++p) {
            want[n++] = ident(q, p, 0);
            if (lengths[q][p] > 1)
                q_of[on] = q, p_of[on++] = p;
        }
    for (uint32_t g = 0; g < on; g += LANES) {
        uint32_t lanes = on - g < LANES ? on - g : LANES, longest = 0;
        for (uint32_t l = 0; l < lanes; ++l)
            longest = lengths[q_of[g + l]][p_of[g + l]] > longest ? lengths[q_of[g + l]][p_of[g + l]] : longest;
        for (uint32_t k = 1; k < longest; ++k)
            for (uint32_t l = 0; l < LANES; ++l)
                want[n++] = l < lanes && k < lengths[q_of[g + l]][p_of[g + l]] ? ident(q_of[g + l], p_of[g + l], k)
                                                                                 : -1.f;
    }
    return n;
}

/* The expected RAY_LOG_WORKGROUP list: all 16 paths are one workgroup; at
 * each step the rays of the paths still going, in order, padded to a
 * multiple of LANES with idle lanes. */
static uint32_t expected_workgroup(float *want)
{
    uint32_t n = 0, longest = 0;
    for (uint32_t q = 0; q < PROBES; ++q)
        for (uint32_t p = 0; p < PATHS; ++p)
            longest = lengths[q][p] > longest ? lengths[q][p] : longest;
    for (uint32_t k = 0; k < longest; ++k) {
        uint32_t live = 0;
        for (uint32_t q = 0; q < PROBES; ++q)
            for (uint32_t p = 0; p < PATHS; ++p)
                if (k < lengths[q][p])
                    want[n + live++] = ident(q, p, k);
        for (; live % LANES; ++live)
            want[n + live] = -1.f;
        n += live;
    }
    return n;
}

static void check_list(const char *what, const pb_ray *got, uint64_t n, const float *want, uint32_t m)
{
    CHECK(n == m, "%s: %llu rays, expected %u", what, (unsigned long long)n, m);
    for (uint32_t i = 0; i < m && i < n; ++i) {
        float g = idle(&got[i]) ? -1.f : got[i].tmin;
        CHECK(g == want[i], "%s: entry %u is %g, expected %g", what, i, g, want[i]);
    }
}

int main(void)
{
    ray_log *log = malloc(sizeof *log);
    float want[1024];
    if (!log)
        return 1;
    uint64_t n = record(log);
    CHECK(ray_log_count(log) == n, "count %llu, cast %llu", (unsigned long long)ray_log_count(log),
          (unsigned long long)n);

    pb_ray *c[RAY_LOG_LAYOUTS], *a[RAY_LOG_LAYOUTS];
    uint64_t nc[RAY_LOG_LAYOUTS], na[RAY_LOG_LAYOUTS];
    for (int L = 0; L < RAY_LOG_LAYOUTS; ++L)
        CHECK(ray_log_lockstep(log, &probe_at[0][0], PROBES, (ray_log_layout)L, &c[L], &nc[L], &a[L], &na[L]) == 1,
              "layout %d refused", L);
    if (failures)
        return 1;
    check_list("packed, closest", c[RAY_LOG_PACKED], nc[RAY_LOG_PACKED], want, expected(0, 0, want));
    check_list("packed, any", a[RAY_LOG_PACKED], na[RAY_LOG_PACKED], want, expected(1, 0, want));
    CHECK(nc[RAY_LOG_PACKED] + na[RAY_LOG_PACKED] == n, "packed lists hold %llu of %llu rays",
          (unsigned long long)(nc[RAY_LOG_PACKED] + na[RAY_LOG_PACKED]), (unsigned long long)n);
    check_list("groups, closest", c[RAY_LOG_GROUPS], nc[RAY_LOG_GROUPS], want, expected(0, 1, want));
    check_list("groups, any", a[RAY_LOG_GROUPS], na[RAY_LOG_GROUPS], want, expected(1, 1, want));
    check_list("mixed", c[RAY_LOG_MIXED], nc[RAY_LOG_MIXED], want, expected(-1, 1, want));
    check_list("packed mixed", c[RAY_LOG_PACKED_MIXED], nc[RAY_LOG_PACKED_MIXED], want, expected(-1, 0, want));
    check_list("first compacted", c[RAY_LOG_FIRST_COMPACTED], nc[RAY_LOG_FIRST_COMPACTED], want,
               expected_first_compacted(want));
    check_list("workgroup", c[RAY_LOG_WORKGROUP], nc[RAY_LOG_WORKGROUP], want, expected_workgroup(want));
    CHECK(na[RAY_LOG_MIXED] == 0 && na[RAY_LOG_PACKED_MIXED] == 0 && na[RAY_LOG_FIRST_COMPACTED] == 0 &&
              na[RAY_LOG_WORKGROUP] == 0,
          "one-list layouts left rays in the any list");

    /* K 1: the bake's own groups, byte for byte */
    pb_ray *r;
    uint64_t nr;
    CHECK(ray_log_restart(log, &probe_at[0][0], PROBES, 1, 1, &r, &nr) == 1, "restart 1:1 refused");
    if (!failures) {
        CHECK(nr == nc[RAY_LOG_MIXED] && !memcmp(r, c[RAY_LOG_MIXED], nr * sizeof *r),
              "restart K 1 is not the mixed layout");
        free(r);
    }
    /* K 2, M 1: one group of 8 lanes over both probes' 16 paths; lane l runs
     * path l of probe 0, then at once path l of probe 1. Lane l's rays in
     * iteration order are the two paths' rays end to end. */
    CHECK(ray_log_restart(log, &probe_at[0][0], PROBES, 2, 1, &r, &nr) == 1, "restart 2:1 refused");
    if (!failures) {
        uint32_t longest = 0;
        for (uint32_t l = 0; l < PATHS; ++l)
            longest = lengths[0][l] + lengths[1][l] > longest ? lengths[0][l] + lengths[1][l] : longest;
        CHECK(nr == (uint64_t)LANES * longest, "restart 2:1: %llu entries, expected %u",
              (unsigned long long)nr, LANES * longest);
        for (uint32_t it = 0; it < longest && nr == (uint64_t)LANES * longest; ++it)
            for (uint32_t l = 0; l < PATHS; ++l) {
                uint32_t first = lengths[0][l];
                float w = it < first ? ident(0, l, it)
                                     : (it < first + lengths[1][l] ? ident(1, l, it - first) : -1.f);
                const pb_ray *g = &r[LANES * it + l];
                CHECK((idle(g) ? -1.f : g->tmin) == w, "restart 2:1: iteration %u lane %u is %g, expected %g", it,
                      l, idle(g) ? -1.f : g->tmin, w);
            }
        free(r);
    }
    /* K 2, M 4: lane 0 (path of length 1) ends at iteration 0 and waits for
     * iteration 4 to begin probe 1's path 0 */
    CHECK(ray_log_restart(log, &probe_at[0][0], PROBES, 2, 4, &r, &nr) == 1, "restart 2:4 refused");
    if (!failures) {
        for (uint32_t it = 1; it < 4 && LANES * it < nr; ++it)
            CHECK(idle(&r[LANES * it]), "restart 2:4: lane 0 is not idle at iteration %u", it);
        CHECK(nr > LANES * 4u && r[LANES * 4].tmin == ident(1, 0, 0),
              "restart 2:4: lane 0 does not begin its second path at iteration 4");
        free(r);
    }
    /* a record that does not begin with a path is refused */
    ray_log bad;
    ray_log_init(&bad, LANES, no_cast, NULL);
    pb_ray stray;
    memset(&stray, 0, sizeof stray);
    stray.origin[0] = 77.f, stray.tmax = 1.f;
    pb_hit h;
    ray_log_cast(&bad, &stray, PB_TRACE_CLOSEST, &h);
    pb_ray *x, *y;
    uint64_t nx, ny;
    CHECK(ray_log_lockstep(&bad, &probe_at[0][0], PROBES, RAY_LOG_PACKED, &x, &nx, &y, &ny) == -1,
          "a record without a path's first ray was laid out");
    CHECK(ray_log_restart(&bad, &probe_at[0][0], PROBES, 2, 1, &x, &nx) == -1,
          "a record without a path's first ray was laid out as a restart schedule");
    ray_log_free(&bad);

    for (int L = 0; L < RAY_LOG_LAYOUTS; ++L)
        free(c[L]), free(a[L]);
    ray_log_free(log);
    free(log);
    if (failures)
        return 1;
    printf("ray_log_test: %llu rays, every layout as defined\n", (unsigned long long)n);
    return 0;
}
