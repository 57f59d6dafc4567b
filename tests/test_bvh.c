/* BVH build and the CPU references: structure, determinism, bounded depth on
 * hostile inputs, traversal == brute force, watertightness, robust origins.
 * CPU only (also run under ASan/UBSan). */
#define _GNU_SOURCE /* sched_setaffinity */
#include "scenes_gen.h"
#include "exact_inputs.h"
#include "bvh/intersect.h"
#include "bvh/bvh_wide.h"
#include "common/common.h"

#include <float.h>
#include <sched.h>

/* Every triangle in exactly one leaf; each child box holds its subtree. */
static uint32_t check_node(const pb_bvh *b, uint32_t node, const float lo[3], const float hi[3], uint32_t depth,
                           uint32_t *seen, uint32_t *max_depth)
{
    uint32_t bad = 0;
    const pb_bvh_node *n = &b->nodes[node];
    for (int s = 0; s < 2; ++s) {
        if (n->child[s] == -1) {
            bad += n->count[s] != 0;
            continue;
        }
        float clo[3] = {n->lo_hi_x[2 * s], n->lo_hi_y[2 * s], n->lo_hi_z[2 * s]};
        float chi[3] = {n->lo_hi_x[2 * s + 1], n->lo_hi_y[2 * s + 1], n->lo_hi_z[2 * s + 1]};
        for (int k = 0; k < 3; ++k)
            bad += clo[k] < lo[k] || chi[k] > hi[k];
        if (depth + 1 > *max_depth)
            *max_depth = depth + 1;
        if (n->count[s]) {
            for (uint32_t t = (uint32_t)n->child[s]; t < (uint32_t)n->child[s] + n->count[s]; ++t) {
                if (t >= b->triangle_count) {
                    ++bad;
                    continue;
                }
                seen[t]++;
                const float *p = b->tri_positions + 9 * (size_t)t;
                for (int v = 0; v < 9; ++v)
                    bad += p[v] < clo[v % 3] || p[v] > chi[v % 3];
            }
        } else {
            bad += (uint32_t)n->child[s] >= b->node_count || (uint32_t)n->child[s] <= node;
            if ((uint32_t)n->child[s] < b->node_count && (uint32_t)n->child[s] > node)
                bad += check_node(b, (uint32_t)n->child[s], clo, chi, depth + 1, seen, max_depth);
        }
    }
    return bad;
}

typedef struct wide_check {
    const pb_bvh *b;
    uint32_t *seen, max_depth, bad, loose;
} wide_check;

/* The traced 4-wide form: every triangle in exactly one leaf, used slots
 * first, each decoded child box encloses its subtree's triangles
 * (conservative quantization) and overshoots them by at most one
 * quantization step per bound (tight).
 * Returns the exact bounds of the subtree's vertices. */
static void check_wide_node(wide_check *c, uint32_t node, uint32_t depth, float lo[3], float hi[3])
{
    const pb_bvh4_node *n = &c->b->wide_nodes[node];
    for (int k = 0; k < 3; ++k)
        lo[k] = INFINITY, hi[k] = -INFINITY;
    if (depth + 1 > c->max_depth)
        c->max_depth = depth + 1;
    /* the slots as traversals decode them: inner children and leaves'
     * triangles consecutive in slot order by construction, so what is
     * checked is that they are the right ones (the boxes below enclose
     * them, each triangle in one leaf) and that empty slots come last */
    uint32_t child[4], count[4], used = pb_bvh4_slots(n, child, count);
    c->bad += used < 2 && node != 0; /* a pair node's two children at least, but at the root */
    /* traversals take the first `used` slots: no code may follow them (the
     * layout of include/probebake/bvh.h, read here without the decoder) */
    uint32_t codes = n->codes_lo | (n->inner >> 24) << 8 | (n->leaf >> 28) << 16;
    c->bad += used < 4 && (codes >> (5 * used)) != 0;
    for (uint32_t i = 0; i < 4; ++i) {
        if (i >= used) {
            c->bad += count[i] != 0;
            continue;
        }
        if (!count[i])
            child[i] += pb_bvh4_first_inner(n);
        float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
        if (count[i]) {
            for (uint32_t t = child[i]; t < child[i] + count[i]; ++t) {
                if (t >= c->b->triangle_count) {
                    ++c->bad;
                    continue;
                }
                c->seen[t]++;
                const float *p = c->b->tri_positions + 9 * (size_t)t;
                for (int v = 0; v < 9; ++v) {
                    clo[v % 3] = fminf(clo[v % 3], p[v]);
                    chi[v % 3] = fmaxf(chi[v % 3], p[v]);
                }
            }
        } else if (child[i] <= node || child[i] >= c->b->wide_node_count) {
            ++c->bad;
            continue;
        } else {
            check_wide_node(c, child[i], depth + 1, clo, chi);
        }
        float qlo[3], qhi[3];
        pb_bvh4_child_box(n, i, qlo, qhi);
        for (int k = 0; k < 3; ++k) {
            c->bad += !(qlo[k] <= clo[k]) || !(qhi[k] >= chi[k]);
            /* one step of slack, plus the rounding of the decode near large origins */
            float step = pb_bvh4_scale(n->exponent[k]), ulp = fabsf(n->origin[k]) * FLT_EPSILON;
            c->loose += clo[k] - qlo[k] > step + ulp || qhi[k] - chi[k] > step + 2 * ulp;
            lo[k] = fminf(lo[k], clo[k]);
            hi[k] = fmaxf(hi[k], chi[k]);
        }
    }
    /* each axis's scale is the finest whose 255 steps reach the node's extent */
    for (int k = 0; k < 3; ++k) {
        float half_step = pb_bvh4_scale((uint8_t)(n->exponent[k] - 1));
        c->loose += n->exponent[k] > 1 && n->origin[k] + 255.f * half_step >= hi[k];
    }
}

static void check_wide(const pb_bvh *b, const char *what)
{
    wide_check c = {b, calloc(b->triangle_count + 1, sizeof(uint32_t)), 0, 0, 0};
    float lo[3], hi[3];
    CHECK(b->wide_node_count >= 1 && b->wide_node_count <= b->node_count);
    if (b->triangle_count)
        check_wide_node(&c, 0, 0, lo, hi);
    uint32_t once = 0;
    for (uint32_t t = 0; t < b->triangle_count; ++t)
        once += c.seen[t] == 1;
    CHECKF(c.bad == 0, "%s: %u violations in the 4-wide BVH (a box not enclosing its triangles, or a slot code after the used ones)", what, c.bad);
    CHECKF(c.loose == 0, "%s: %u quantized bounds looser than one step or scales coarser than needed", what, c.loose);
    CHECKF(once == b->triangle_count, "%s: %u of %u triangles in exactly one 4-wide leaf", what, once,
           b->triangle_count);
    CHECKF(!b->triangle_count || c.max_depth == b->stats.wide_depth, "%s: 4-wide depth %u, stats say %u", what,
           c.max_depth, b->stats.wide_depth);
    CHECK(b->stats.wide_depth <= b->stats.depth || b->triangle_count == 0);
    free(c.seen);
}

static void check_structure(const pb_scene *s, const pb_bvh *b, const char *what)
{
    check_wide(b, what);
    uint32_t *seen = calloc(b->triangle_count + 1, sizeof *seen);
    uint32_t *order_seen = calloc(b->triangle_count + 1, sizeof *order_seen);
    float lo[3] = {-INFINITY, -INFINITY, -INFINITY}, hi[3] = {INFINITY, INFINITY, INFINITY};
    uint32_t max_depth = 0;
    uint32_t bad = b->triangle_count ? check_node(b, 0, lo, hi, 0, seen, &max_depth) : 0;
    CHECKF(bad == 0, "%s: %u structural violations", what, bad);
    uint32_t once = 0;
    for (uint32_t t = 0; t < b->triangle_count; ++t) {
        once += seen[t] == 1;
        if (b->tri_order[t] < s->triangle_count)
            order_seen[b->tri_order[t]]++;
        /* leaf-ordered positions are the scene's triangle */
        CHECK(memcmp(b->tri_positions + 9 * (size_t)t, s->positions + 9 * (size_t)b->tri_order[t], 36) == 0);
    }
    CHECKF(once == b->triangle_count, "%s: %u of %u triangles in exactly one leaf", what, once, b->triangle_count);
    for (uint32_t t = 0; t < s->triangle_count; ++t)
        CHECKF(order_seen[t] == 1, "%s: tri_order is not a permutation at %u", what, t);
    CHECKF(max_depth == b->stats.depth, "%s: depth %u, stats say %u", what, max_depth, b->stats.depth);
    CHECK(b->stats.depth <= PB_BVH_MAX_DEPTH);
    CHECK(b->stats.max_leaf_size <= 2); /* the default bound */
    free(seen);
    free(order_seen);
}

static void structure_of_random_soups(void)
{
    uint32_t sizes[] = {1, 2, 3, 5, 17, 100, 4096, scaled(30000)};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
        pb_scene *s = random_soup(sizes[i], 0.2f, i + 1, NULL);
        pb_bvh *b = NULL;
        pb_error err;
        CHECK(pb_bvh_build(s, NULL, &b, &err) == PB_OK);
        char what[64];
        snprintf(what, sizeof what, "soup of %u", sizes[i]);
        if (b)
            check_structure(s, b, what);
        pb_bvh_destroy(b);
        pb_scene_destroy(s);
    }
}

/* The collapse by whole levels (each inner child of a pair node replaced by
 * its two children): its summed wide-node area over the root's, from the
 * pair tree. */
static double level_area(const pb_bvh *b, uint32_t q)
{
    const pb_bvh_node *n = &b->nodes[q];
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, sum = 0;
    for (int s = 0; s < 2; ++s) {
        if (n->child[s] == -1)
            continue;
        const float *x = n->lo_hi_x, *y = n->lo_hi_y, *z = n->lo_hi_z;
        double l[3] = {x[2 * s], y[2 * s], z[2 * s]}, h[3] = {x[2 * s + 1], y[2 * s + 1], z[2 * s + 1]};
        for (int a = 0; a < 3; ++a)
            lo[a] = fmin(lo[a], l[a]), hi[a] = fmax(hi[a], h[a]);
        if (n->count[s])
            continue;
        const pb_bvh_node *m = &b->nodes[n->child[s]];
        for (int t = 0; t < 2; ++t)
            if (m->child[t] != -1 && !m->count[t])
                sum += level_area(b, (uint32_t)m->child[t]);
    }
    float e0 = (float)hi[0] - (float)lo[0], e1 = (float)hi[1] - (float)lo[1], e2 = (float)hi[2] - (float)lo[2];
    return sum + (e0 * e1 + e1 * e2 + e2 * e0);
}

/* The collapse minimises the expected node steps (summed wide-node area):
 * never more than the collapse by whole levels, one of the covers it chose
 * from, and at least the root's one step. */
static void collapse_minimises_expected_steps(void)
{
    const char *shared[] = {"cornell/cornellBox.gltf", "openarena/oacmpdm1.glb"};
    for (int i = 0; i < 6; ++i) {
        pb_scene *s = NULL;
        pb_error err;
        char what[256];
        if (i < 4) {
            uint32_t n[] = {5, 100, 4096, scaled(30000)};
            s = random_soup(n[i], 0.2f, 40 + i, NULL);
            snprintf(what, sizeof what, "soup of %u", n[i]);
        } else {
            char path[1024];
            snprintf(path, sizeof path, "%s/../shared/scenes/%s", PB_SOURCE_DIR, shared[i - 4]);
            pb_scene_desc d = {{0}, 1};
            if (access(path, R_OK) != 0 || pb_scene_load(path, &d, &s, &err) != PB_OK) {
                fprintf(stderr, "  %s not present: skipped\n", shared[i - 4]);
                continue;
            }
            snprintf(what, sizeof what, "%s", shared[i - 4]);
        }
        pb_bvh *b = NULL;
        CHECK(pb_bvh_build(s, NULL, &b, &err) == PB_OK);
        if (b) {
            const pb_bvh_node *r = &b->nodes[0];
            double lo[3], hi[3];
            for (int a = 0; a < 3; ++a) {
                const float *v = a == 0 ? r->lo_hi_x : a == 1 ? r->lo_hi_y : r->lo_hi_z;
                lo[a] = fmin(v[0], r->child[1] != -1 ? v[2] : v[0]);
                hi[a] = fmax(v[1], r->child[1] != -1 ? v[3] : v[1]);
            }
            float e0 = (float)hi[0] - (float)lo[0], e1 = (float)hi[1] - (float)lo[1], e2 = (float)hi[2] - (float)lo[2];
            double level = level_area(b, 0) / (e0 * e1 + e1 * e2 + e2 * e0);
            fprintf(stderr, "  %s: %u wide nodes, %.3f expected steps (by whole levels %.3f)\n", what,
                    b->wide_node_count, b->stats.wide_steps, level);
            /* both are sums of the same float areas; 1e-6 covers their rounding */
            CHECKF(b->stats.wide_steps <= level * (1 + 1e-6), "%s: %.6f steps, more than by whole levels (%.6f)",
                   what, b->stats.wide_steps, level);
            CHECK(b->stats.wide_steps >= 1.0);
        }
        pb_bvh_destroy(b);
        pb_scene_destroy(s);
    }
}

static void empty_scene_builds_and_misses(void)
{
    pb_scene *s = random_soup(0, 0.1f, 1, NULL);
    pb_bvh *b = NULL;
    pb_error err;
    CHECK(pb_bvh_build(s, NULL, &b, &err) == PB_OK);
    if (!b)
        return;
    CHECK(b->triangle_count == 0 && b->node_count == 1);
    pb_ray ray = {{0, 0, 0}, 0, {1, 0, 0}, INFINITY};
    pb_hit hit;
    pb_trace_cpu(s, b, &ray, 1, PB_TRACE_CLOSEST, &hit, 1);
    CHECK(hit.triangle == PB_NO_HIT);
    pb_bvh_destroy(b);
    pb_scene_destroy(s);
}

static void build_is_deterministic_across_threads(void)
{
    /* large enough for parallel binning (ranges of 16,384 or more), shared and kept tasks, and a
     * collapse covered and quantized in parallel */
    pb_scene *s = random_soup(scaled(100000) < 70000 ? 70000 : 100000, 0.05f, 42, NULL);
    pb_bvh *b[3] = {NULL, NULL, NULL};
    uint32_t threads[3] = {1, 2, 5};
    pb_error err;
    for (int i = 0; i < 3; ++i) {
        pb_bvh_desc d = {0};
        d.threads = threads[i];
        CHECK(pb_bvh_build(s, &d, &b[i], &err) == PB_OK);
    }
    for (int i = 1; i < 3; ++i) {
        if (!b[0] || !b[i])
            break;
        CHECK(b[i]->node_count == b[0]->node_count);
        CHECK(memcmp(b[i]->nodes, b[0]->nodes, (size_t)b[0]->node_count * sizeof(pb_bvh_node)) == 0);
        CHECK(b[i]->wide_node_count == b[0]->wide_node_count &&
              memcmp(b[i]->wide_nodes, b[0]->wide_nodes, (size_t)b[0]->wide_node_count * sizeof(pb_bvh4_node)) == 0);
        CHECK(memcmp(b[i]->tri_order, b[0]->tri_order, (size_t)b[0]->triangle_count * 4) == 0);
    }
    if (b[0])
        check_structure(s, b[0], "100k soup");
    for (int i = 0; i < 3; ++i)
        pb_bvh_destroy(b[i]);
    pb_scene_destroy(s);
}

/* Host threads (the BVH build's, the volume's, Embree's in the benches) are
 * as many as the cores this process may use: under a narrowed affinity mask
 * (a Slurm job's cgroup, taskset) they must not be as many as the machine's. */
static void host_threads_follow_affinity(void)
{
    cpu_set_t all, one;
    CHECK(sched_getaffinity(0, sizeof all, &all) == 0);
    CHECK(pb_host_threads() == (uint32_t)CPU_COUNT(&all));
    int first = 0;
    while (first < CPU_SETSIZE && !CPU_ISSET(first, &all))
        ++first;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    CHECK(sched_setaffinity(0, sizeof one, &one) == 0);
    CHECK(pb_host_threads() == 1u);
    CHECK(sched_setaffinity(0, sizeof all, &all) == 0);
    CHECK(pb_host_threads() == (uint32_t)CPU_COUNT(&all));
}

static void hostile_inputs_keep_depth_bounded(void)
{
    /* 5000 copies of one triangle: identical centroids, no SAH split exists */
    double *p = malloc(5000 * 9 * sizeof(double));
    for (int t = 0; t < 5000; ++t)
        for (int k = 0; k < 9; ++k)
            p[9 * t + k] = (k == 3 || k == 7) ? 1.0 : 0.0;
    pb_scene *s = NULL;
    pb_error err;
    CHECK(pb_scene_from_triangles(p, 5000, NULL, NULL, 0, &s, &err) == PB_OK);
    pb_bvh *b = NULL;
    CHECK(s && pb_bvh_build(s, NULL, &b, &err) == PB_OK);
    if (b) {
        check_structure(s, b, "identical triangles");
        pb_ray ray = {{-0.3f, -0.3f, 1}, 0, {0, 0, -1}, INFINITY}; /* local frame: origin at (0.5,0.5,0) */
        pb_hit hit;
        pb_trace_cpu(s, b, &ray, 1, PB_TRACE_CLOSEST, &hit, 1);
        CHECK(hit.triangle != PB_NO_HIT && fabsf(hit.t - 1.f) < 1e-6f);
    }
    pb_bvh_destroy(b);
    pb_scene_destroy(s);
    free(p);

    /* geometric progression along +-x (centred, so rebasing keeps it): each
     * binned-SAH level can only peel off the few largest triangles, which
     * without the depth guard makes a chain ~100 levels deep */
    uint32_t n = 2 * 110;
    p = malloc((size_t)n * 9 * sizeof(double));
    for (uint32_t t = 0; t < n; ++t) {
        double x = ldexp(1.0, (int)(t / 2)) * ((t & 1) ? -1.0 : 1.0);
        double tri[9] = {x, 0, 0, x * 1.1, 0, 0, x, 1, 0};
        memcpy(p + 9 * t, tri, sizeof tri);
    }
    CHECK(pb_scene_from_triangles(p, n, NULL, NULL, 0, &s, &err) == PB_OK);
    b = NULL;
    CHECK(s && pb_bvh_build(s, NULL, &b, &err) == PB_OK);
    if (b) {
        check_structure(s, b, "geometric progression");
        fprintf(stderr, "  geometric progression: depth %u (bound %d)\n", b->stats.depth, PB_BVH_MAX_DEPTH);
        CHECK(b->stats.depth > 20); /* the hostile case really is deep... */
        /* ...and traversal still finds every triangle */
        pb_ray *rays = malloc(n * sizeof *rays);
        pb_hit *h = malloc(n * sizeof *h), *hb = malloc(n * sizeof *hb);
        for (uint32_t t = 0; t < n; ++t) {
            const float *q = s->positions + 9 * (size_t)t;
            pb_ray ry = {{q[0] + 0.01f * (q[3] - q[0]), 0.01f, 1}, 0, {0, 0, -1}, INFINITY};
            rays[t] = ry;
        }
        pb_trace_cpu(s, b, rays, n, PB_TRACE_CLOSEST, h, 1);
        pb_trace_brute(s, rays, n, PB_TRACE_CLOSEST, hb, 1);
        CHECK(compare_hits("progression", rays, h, hb, n, NULL) == 0);
        uint32_t found = 0;
        for (uint32_t t = 0; t < n; ++t)
            found += h[t].triangle == t;
        CHECKF(found == n, "%u of %u triangles found", found, n);
        free(rays), free(h), free(hb);
    }
    pb_bvh_destroy(b);
    pb_scene_destroy(s);
    free(p);
}

static void bad_desc_is_refused(void)
{
    pb_scene *s = random_soup(10, 0.1f, 1, NULL);
    pb_bvh *b = (pb_bvh *)1;
    pb_error err;
    pb_bvh_desc d = {0};
    d.max_leaf_size = 99;
    CHECK(pb_bvh_build(s, &d, &b, &err) == PB_ERROR_INVALID_ARGUMENT && b == NULL);
    CHECK(strstr(err.message, "leaf") != NULL);
    d.max_leaf_size = 0;
    d.bins = 2;
    CHECK(pb_bvh_build(s, &d, &b, &err) == PB_ERROR_INVALID_ARGUMENT);
    pb_scene_destroy(s);
    /* more 4-wide nodes than allowed (the default limit is what a traversal's
     * 24-bit group index addresses, about 100 M triangles: too big to build
     * here, so the same check at a lower limit) */
    s = random_soup(4096, 0.05f, 3, NULL);
    pb_bvh_desc w = {0};
    CHECK(pb_bvh_build(s, &w, &b, &err) == PB_OK && b->wide_node_count > 8);
    uint32_t nodes = b ? b->wide_node_count : 0;
    pb_bvh_destroy(b);
    w.max_wide_nodes = nodes - 1;
    CHECK(pb_bvh_build(s, &w, &b, &err) == PB_ERROR_TOO_LARGE && b == NULL);
    CHECKF(strstr(err.message, "4-wide nodes") && !strchr(err.message, '\n'), "%s", err.message);
    w.max_wide_nodes = nodes;
    CHECK(pb_bvh_build(s, &w, &b, &err) == PB_OK);
    pb_bvh_destroy(b);
    /* more triangles than a node's 28-bit first leaf triangle names: refused
     * before anything is read or allocated (the scene is a shallow copy that
     * only claims them) */
    pb_scene huge = *s;
    huge.triangle_count = PB_BVH4_MAX_TRIANGLES + 1u;
    CHECK(pb_bvh_build(&huge, NULL, &b, &err) == PB_ERROR_TOO_LARGE && b == NULL);
    CHECKF(strstr(err.message, "triangles") && !strchr(err.message, '\n'), "%s", err.message);
    pb_scene_destroy(s);
}

static void traversal_matches_brute_force(void)
{
    struct {
        uint32_t tris;
        float size;
    } cases[] = {{1000, 0.3f}, {20000, 0.05f}};
    for (int c = 0; c < 2; ++c) {
        pb_scene *s = random_soup(cases[c].tris, cases[c].size, 7 + c, NULL);
        pb_bvh *b = NULL;
        pb_error err;
        CHECK(pb_bvh_build(s, NULL, &b, &err) == PB_OK);
        if (!b)
            continue;
        uint32_t n = scaled(100000);
        pb_ray *rays = random_rays(s->bounds_min, s->bounds_max, n, 11 + c);
        pb_hit *h1 = malloc(n * sizeof *h1), *h2 = malloc(n * sizeof *h2), *h3 = malloc(n * sizeof *h3);
        pb_trace_cpu(s, b, rays, n, PB_TRACE_CLOSEST, h1, 0);
        pb_trace_brute(s, rays, n, PB_TRACE_CLOSEST, h2, 0);
        uint32_t ties = 0, bad = compare_hits("bvh vs brute", rays, h1, h2, n, &ties);
        uint32_t hits = 0;
        for (uint32_t i = 0; i < n; ++i)
            hits += h2[i].triangle != PB_NO_HIT;
        fprintf(stderr, "  soup %u: %u rays, %u hits, %u ties, %u mismatches\n", cases[c].tris, n, hits, ties, bad);
        CHECK(bad == 0);
        CHECK(hits > n / 10 && hits < n); /* the test sees both hits and misses */
        /* any-hit: occlusion agrees with closest hit */
        pb_trace_cpu(s, b, rays, n, PB_TRACE_ANY, h3, 0);
        uint32_t occ_bad = 0;
        for (uint32_t i = 0; i < n; ++i) {
            int occ = h3[i].triangle != PB_NO_HIT;
            occ_bad += occ != (h2[i].triangle != PB_NO_HIT);
            if (occ)
                occ_bad += !(h3[i].t > rays[i].tmin && h3[i].t < rays[i].tmax);
        }
        CHECK(occ_bad == 0);
        free(rays), free(h1), free(h2), free(h3);
        pb_bvh_destroy(b);
        pb_scene_destroy(s);
    }
}

/* pb_trace_brute screens each block of triangles in the ray's sheared
 * frame before the triangle test; this is the brute force without the
 * screen (opaque scenes only): every triangle through pb_ray_triangle. */
static void brute_unscreened(const pb_scene *s, const pb_ray *rays, uint32_t n, pb_hit *hits)
{
    for (uint32_t i = 0; i < n; ++i) {
        pb_ray_pre r;
        pb_ray_prepare(rays[i].origin, rays[i].direction, &r);
        float tmax = rays[i].tmax, bu = 0.f, bv = 0.f;
        uint32_t best = PB_NO_HIT;
        for (uint32_t k = 0; k < s->triangle_count; ++k) {
            const float *p = s->positions + 9 * (size_t)k;
            float t, u, v;
            if (pb_ray_triangle(&r, p, p + 3, p + 6, rays[i].tmin, tmax, &t, &u, &v))
                tmax = t, best = k, bu = u, bv = v;
        }
        hits[i].triangle = best, hits[i].t = best == PB_NO_HIT ? rays[i].tmax : tmax;
        hits[i].u = best == PB_NO_HIT ? 0.f : bu, hits[i].v = best == PB_NO_HIT ? 0.f : bv;
    }
}

/* The screen only skips tests that return no hit: on rays through the
 * sphere's vertices and along its edges (sheared coordinates of exactly 0)
 * and on random soups, the screened brute force finds the same triangle,
 * t, u and v as every triangle tested. */
static void brute_force_screen_skips_only_misses(void)
{
    float *verts;
    uint32_t nv;
    pb_scene *sphere = closed_sphere(48, 96, &verts, &nv);
    pb_scene *soup = random_soup(3000, 0.1f, 17, NULL);
    pb_scene *scenes[2] = {sphere, soup};
    for (int c = 0; c < 2; ++c) {
        const pb_scene *s = scenes[c];
        uint32_t n = scaled(8000);
        pb_ray *rays = c == 0 ? sphere_probe_rays(s, n, 9) : random_rays(s->bounds_min, s->bounds_max, n, 23);
        pb_hit *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
        pb_trace_brute(s, rays, n, PB_TRACE_CLOSEST, a, 0);
        brute_unscreened(s, rays, n, b);
        uint32_t differ = 0, hits = 0;
        for (uint32_t i = 0; i < n; ++i) {
            differ += a[i].triangle != b[i].triangle || memcmp(&a[i].t, &b[i].t, 4) || memcmp(&a[i].u, &b[i].u, 4) ||
                      memcmp(&a[i].v, &b[i].v, 4);
            hits += b[i].triangle != PB_NO_HIT;
        }
        fprintf(stderr, "  %s: %u rays, %u hits, %u differ\n", c == 0 ? "sphere at vertices and edges" : "soup", n,
                hits, differ);
        CHECK(differ == 0 && hits > 0);
        free(rays), free(a), free(b);
    }
    pb_scene_destroy(soup);
    pb_scene_destroy(sphere);
    free(verts);
}

static void watertight_sphere_cpu(void)
{
    float *verts;
    uint32_t nv;
    pb_scene *s = closed_sphere(48, 96, &verts, &nv);
    pb_bvh *b = NULL;
    pb_error err;
    CHECK(pb_bvh_build(s, NULL, &b, &err) == PB_OK);
    uint32_t n = scaled(1000000);
    pb_ray *rays = sphere_probe_rays(s, n, 5);
    pb_hit *h = malloc(n * sizeof *h);
    pb_trace_cpu(s, b, rays, n, PB_TRACE_CLOSEST, h, 0);
    uint32_t escaped = 0, front = 0;
    for (uint32_t i = 0; i < n; ++i) {
        escaped += h[i].triangle == PB_NO_HIT;
        front += h[i].triangle != PB_NO_HIT && !h[i].backface;
    }
    fprintf(stderr, "  %u triangles, %u rays at vertices and edges: %u escaped\n", s->triangle_count, n, escaped);
    CHECK(escaped == 0);
    CHECK(front == 0); /* from inside, every hit is on a back face */
    free(rays), free(h), free(verts);
    pb_bvh_destroy(b);
    pb_scene_destroy(s);
}

/* Secondary rays leave a hit point; without an offset many re-hit their own
 * triangle at t ~ 0, with the robust offset none does. */
static void robust_offset_avoids_self_intersection(void)
{
    /* triangles up to 1e5 from the local origin (the frame the kernels see),
     * where a float ulp is ~0.008: rounding of hit points is large */
    test_rng g = {1234};
    uint32_t nt = scaled(20000);
    double *tp = malloc((size_t)nt * 9 * sizeof(double));
    for (uint32_t t = 0; t < nt; ++t) {
        double c[3];
        for (int k = 0; k < 3; ++k)
            c[k] = 1e5 * (2 * rng_uniform(&g) - 1);
        for (int k = 0; k < 9; ++k)
            tp[9 * t + k] = c[k % 3] + 2e4 * (rng_uniform(&g) - 0.5);
    }
    pb_scene *s = NULL;
    pb_error err;
    CHECK(pb_scene_from_triangles(tp, nt, NULL, NULL, 0, &s, &err) == PB_OK);
    free(tp);
    pb_bvh *b = NULL;
    CHECK(s && pb_bvh_build(s, NULL, &b, &err) == PB_OK);
    if (!b)
        return;
    uint32_t n = scaled(50000);
    pb_ray *rays = random_rays(s->bounds_min, s->bounds_max, n, 3);
    pb_hit *h = malloc(n * sizeof *h);
    pb_trace_cpu(s, b, rays, n, PB_TRACE_CLOSEST, h, 0);
    pb_ray *sec = malloc(n * sizeof *sec), *raw = malloc(n * sizeof *raw);
    uint32_t *src = malloc(n * sizeof *src), m = 0;
    test_rng r = {77};
    for (uint32_t i = 0; i < n; ++i) {
        if (h[i].triangle == PB_NO_HIT)
            continue;
        const float *p = s->positions + 9 * (size_t)h[i].triangle;
        float hp[3], e1[3], e2[3], ng[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = p[3 + k] - p[k];
            e2[k] = p[6 + k] - p[k];
            hp[k] = p[k] + h[i].u * e1[k] + h[i].v * e2[k];
        }
        ng[0] = e1[1] * e2[2] - e1[2] * e2[1];
        ng[1] = e1[2] * e2[0] - e1[0] * e2[2];
        ng[2] = e1[0] * e2[1] - e1[1] * e2[0];
        float l = sqrtf(ng[0] * ng[0] + ng[1] * ng[1] + ng[2] * ng[2]);
        float side = h[i].backface ? 1.f : -1.f; /* back to where the ray came from */
        for (int k = 0; k < 3; ++k)
            ng[k] *= side / l;
        float d[3];
        rng_direction(&r, d);
        float dn = d[0] * ng[0] + d[1] * ng[1] + d[2] * ng[2];
        if (dn < 0)
            for (int k = 0; k < 3; ++k)
                d[k] = -d[k];
        pb_offset_ray_origin(hp, ng, sec[m].origin);
        memcpy(sec[m].direction, d, sizeof d);
        sec[m].tmin = 0.f;
        sec[m].tmax = INFINITY;
        raw[m] = sec[m];
        memcpy(raw[m].origin, hp, sizeof hp);
        src[m++] = h[i].triangle;
    }
    pb_hit *h2 = malloc(m * sizeof *h2);
    uint32_t self_raw = 0, self_off = 0;
    pb_trace_cpu(s, b, raw, m, PB_TRACE_CLOSEST, h2, 0);
    for (uint32_t i = 0; i < m; ++i)
        self_raw += h2[i].triangle == src[i];
    pb_trace_cpu(s, b, sec, m, PB_TRACE_CLOSEST, h2, 0);
    for (uint32_t i = 0; i < m; ++i)
        self_off += h2[i].triangle == src[i];
    fprintf(stderr, "  %u secondary rays: %u self-hits without offset, %u with\n", m, self_raw, self_off);
    CHECK(m > scaled(1000));
    CHECK(self_raw > 0); /* the test can see the failure it guards against */
    CHECK(self_off == 0);
    free(rays), free(h), free(sec), free(raw), free(src), free(h2);
    pb_bvh_destroy(b);
    pb_scene_destroy(s);
}

/* Regression (The Crypt, triangle 48801): a sliver whose float edge
 * functions round to U = W = 0 looked "hit" by a ray passing 35 m away. The
 * exact-sign edge functions reject it; a ray through its middle still hits. */
static void sliver_has_no_phantom_hit(void)
{
    double tri[9] = {30.8864021, 5.74039984, -5.68959999, 31.6039467, 6.45795012, -5.68959999,
                     31.1340523, 5.98804998, -5.68959999};
    /* two copies mirrored through the origin keep the AABB centre at 0, so the
     * local frame equals these coordinates */
    double both[18];
    for (int k = 0; k < 9; ++k) {
        both[k] = tri[k];
        both[9 + k] = -tri[k];
    }
    pb_scene *s = NULL;
    pb_error err;
    CHECK(pb_scene_from_triangles(both, 2, NULL, NULL, 0, &s, &err) == PB_OK);
    if (!s)
        return;
    CHECK(s->positions[0] == (float)tri[0] && s->positions[5] == (float)tri[5]);
    pb_ray far = {{0x1.4f6f4p+0f, -0x1.d642ep+1f, -0x1.3b34b4p+5f}, 0.f,
                  {-0x1.27c3a8p-3f, -0x1.3875dap-1f, 0x1.8ece04p-1f}, INFINITY};
    pb_hit h;
    pb_trace_brute(s, &far, 1, PB_TRACE_CLOSEST, &h, 1);
    CHECKF(h.triangle == PB_NO_HIT, "phantom hit on triangle %u at t = %g", h.triangle, h.t);
    float c[3] = {(float)((tri[0] + tri[3] + tri[6]) / 3), (float)((tri[1] + tri[4] + tri[7]) / 3), 0.f};
    pb_ray through = {{c[0], c[1], 0.f}, 0.f, {0, 0, -1}, INFINITY};
    pb_trace_brute(s, &through, 1, PB_TRACE_CLOSEST, &h, 1);
    CHECK(h.triangle == 0 && fabsf(h.t - 5.6896f) < 1e-5f);
    pb_scene_destroy(s);
}

static void offset_is_tiny_and_on_the_right_side(void)
{
    test_rng r = {5};
    uint32_t bad = 0;
    for (uint32_t i = 0; i < scaled(100000); ++i) {
        float p[3], n[3], o[3];
        double mag = pow(10.0, 12.0 * rng_uniform(&r) - 6.0);
        for (int k = 0; k < 3; ++k)
            p[k] = (float)((2 * rng_uniform(&r) - 1) * mag);
        rng_direction(&r, n);
        pb_offset_ray_origin(p, n, o);
        double along = 0, dist = 0, pl = 0;
        for (int k = 0; k < 3; ++k) {
            along += ((double)o[k] - p[k]) * n[k];
            dist += ((double)o[k] - p[k]) * ((double)o[k] - p[k]);
            pl = fmax(pl, fabs(p[k]));
        }
        /* moves along +n, by at most a few hundred ulps of |p| (or 2^-16 near 0) */
        bad += !(along >= 0) || sqrt(dist) > fmax(pl * 256 * 3 * 1.2e-7, 3.0 / 65536);
    }
    CHECK(bad == 0);
}

/* pb_exact_diff is the exact a*b - c*d rounded once: equal to the double
 * computation wherever that is exact (checked by two-sum), right in sign
 * everywhere, 0 exactly when a*b == c*d. And wherever the edge function's
 * float path is uncertain, it equals the double fallback the native64
 * kernels use, so both kernel variants return the same bits. */
static float double_fallback(float a, float b, float c, float d)
{
    double e = (double)a * b - (double)c * d;
    float f = (float)e;
    if (e != 0.0 && !(fabsf(f) >= FLT_MIN))
        f = e > 0.0 ? 1e-37f : -1e-37f;
    return f;
}

static void exact_diff_is_exact(void)
{
    test_rng r = {77};
    uint32_t n = 3000000, compared = 0, uncertain = 0, bad_value = 0, bad_sign = 0, bad_fallback = 0;
    for (uint32_t i = 0; i < n; ++i) {
        float q[4];
        exact_inputs(&r, i, q);
        float f = pb_exact_diff(q[0], q[1], q[2], q[3]);
        double p = (double)q[0] * q[1], m = (double)q[2] * q[3], e = p - m;
        double bv = e - p, err = (p - (e - bv)) + (-m - bv); /* two-sum: e + err == p - m exactly */
        int sign = p > m ? 1 : p < m ? -1 : 0;
        if ((f > 0.f ? 1 : f < 0.f ? -1 : 0) != sign)
            ++bad_sign;
        if (err == 0.0 && fabs(e) <= FLT_MAX) {
            ++compared;
            if (memcmp(&(float){double_fallback(q[0], q[1], q[2], q[3])}, &f, 4) != 0) {
                if (bad_value < 5)
                    fprintf(stderr, "  %a*%a - %a*%a: %a, double %a\n", q[0], q[1], q[2], q[3], f, e);
                ++bad_value;
            }
        }
        float fp = q[0] * q[1], fq = q[2] * q[3], fr = fp - fq;
        if (isfinite(fp) && isfinite(fq) && !(fabsf(fr) > PB_EDGE_ERROR_BOUND * (fabsf(fp) + fabsf(fq)))) {
            ++uncertain;
            float g = double_fallback(q[0], q[1], q[2], q[3]);
            bad_fallback += memcmp(&g, &f, 4) != 0;
        }
    }
    printf("  %u inputs: %u compared with an exact double, %u where the float path is uncertain\n", n, compared,
           uncertain);
    CHECKF(compared > n / 2 && uncertain > n / 10, "too few useful inputs (%u, %u)", compared, uncertain);
    CHECKF(bad_sign == 0, "%u results of the wrong sign", bad_sign);
    CHECKF(bad_value == 0, "%u results differ from the exact double rounded once", bad_value);
    CHECKF(bad_fallback == 0, "%u uncertain edge functions where the double fallback differs", bad_fallback);
    CHECK(pb_exact_diff(3.f, 5.f, 5.f, 3.f) == 0.f && !signbit(pb_exact_diff(3.f, 5.f, 5.f, 3.f)));
    /* 1 + 2^-24 is a tie: nearest-even keeps 1; 1 + 3*2^-24 rounds up to 1 + 2^-22 */
    CHECK(pb_exact_diff(1.f + 0x1p-23f, 1.f, 0x1p-12f, 0x1p-12f) == 1.f);
    CHECK(pb_exact_diff(1.f + 0x1p-22f, 1.f, 0x1p-12f, 0x1p-12f) == 1.f + 0x1p-22f);
    CHECK(pb_exact_diff(0x1p-100f, 0x1p-100f, 0.f, 0.f) == 1e-37f);
    CHECK(pb_exact_diff(0x1p100f, 0x1p100f, -0x1p100f, 0x1p100f) == INFINITY);
}

/* pb_rcp, the reciprocal the CPU and every device compute alike: its error
 * bound (< 1.49u, u = 2^-24) over every float mantissa in
 * [0.5, 2) (the guess and the steps scale exactly with the exponent), at
 * scaled exponents, and its special values. */
static void reciprocal_is_accurate_everywhere(void)
{
    double worst = 0.0;
    for (uint32_t bits = 0x3f000000u; bits < 0x40000000u; ++bits) {
        float b;
        memcpy(&b, &bits, 4);
        double e = fabs((double)pb_rcp(b) * (double)b - 1.0);
        worst = e > worst ? e : worst;
    }
    printf("  pb_rcp over [0.5, 2): worst relative error %.3f u\n", worst / 0x1p-24);
    CHECKF(worst < 1.49 * 0x1p-24, "pb_rcp error %.3g u", worst / 0x1p-24);
    const float samples[] = {1e-35f, 3e-31f, 7.1e-20f, 0.3f, 3.0f, -5.5f, 1e10f, 2e30f, 3e35f, -1e-33f};
    for (size_t i = 0; i < sizeof samples / sizeof *samples; ++i) {
        double b = samples[i], e = fabs((double)pb_rcp(samples[i]) * b - 1.0);
        CHECKF(e < 1.49 * 0x1p-24, "pb_rcp(%g): error %.3g u", b, e / 0x1p-24);
    }
    CHECK(pb_rcp(0.f) == INFINITY && pb_rcp(-0.f) == -INFINITY);
    CHECK(pb_rcp(INFINITY) == 0.f && pb_rcp(-INFINITY) == 0.f && signbit(pb_rcp(-INFINITY)));
    CHECK(isnan(pb_rcp(NAN)));
    CHECK(pb_rcp(2.f) == 0.5f && pb_rcp(-0.25f) == -4.f);
}

/* pb_ray_node_boxes never culls a box the ray touches. Random nodes at
 * scene scales from 1e-3 to 1e4 m; rays that start at or next to a small
 * child far from its node's origin (where the node-frame form cancels), in
 * random, near-parallel and axis-parallel directions; 1/dir perturbed by up
 * to the 2.5 ulp a Vulkan division may be off. Reference: the exact slab
 * interval of the decoded box (pb_bvh4_child_box, what encloses the
 * geometry), in double: the box test's entry may not be later than the
 * exact one. The same rays with no widening must cull some of those boxes,
 * or these rays would not test it. */
static float unit_random(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) * 0x1p-24f;
}

static void node_boxes_are_conservative(void)
{
    static const float scales[] = {1e-3f, 1.f, 100.f, 1e4f};
    uint32_t rng = 12345u, touched = 0, late_unwidened = 0, lost_unwidened = 0;
    for (int iter = 0; iter < 200000; ++iter) {
        float R = scales[iter % 4];
        pb_bvh4_node nd;
        memset(&nd, 0, sizeof nd);
        float scale[3];
        for (int k = 0; k < 3; ++k) {
            nd.origin[k] = R * (2.f * unit_random(&rng) - 1.f);
            double extent = R * pow(10.0, -4.0 * unit_random(&rng)); /* the node: R down to 1e-4 R */
            int e = 127 + (int)ceil(log2(extent / 255.0));
            nd.exponent[k] = (uint8_t)(e < 1 ? 1 : e > 254 ? 254 : e);
            scale[k] = pb_bvh4_scale(nd.exponent[k]);
            for (int i = 0; i < 4; ++i) { /* small boxes, often far out in the node's frame */
                uint32_t lo = iter & 1 ? 200u + (uint32_t)(55.f * unit_random(&rng))
                                       : (uint32_t)(255.f * unit_random(&rng));
                uint32_t hi = lo + (uint32_t)(3.f * unit_random(&rng));
                nd.qbox[k][0][i] = (uint8_t)lo;
                nd.qbox[k][1][i] = (uint8_t)(hi > 255u ? 255u : hi);
            }
        }
        float lo[4][3], hi[4][3];
        for (uint32_t i = 0; i < 4; ++i)
            pb_bvh4_child_box(&nd, i, lo[i], hi[i]);
        /* origin: around child c's box (on a face a quarter of the time) */
        uint32_t c = (uint32_t)iter % 4u;
        float org[3], dir[3];
        for (int k = 0; k < 3; ++k) {
            float w = hi[c][k] - lo[c][k] + scale[k];
            org[k] = iter % 16 < 4 ? (k == iter % 3 ? lo[c][k] : hi[c][k])
                                   : lo[c][k] + w * (3.f * unit_random(&rng) - 1.f);
        }
        double n2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            dir[k] = 2.f * unit_random(&rng) - 1.f;
            n2 += (double)dir[k] * dir[k];
        }
        for (int k = 0; k < 3; ++k)
            dir[k] = (float)(dir[k] / sqrt(n2));
        if (iter % 5 == 1)
            dir[iter % 3] = 0.f; /* parallel to a slab */
        else if (iter % 5 == 2)
            dir[iter % 3] *= 1e-6f;
        pb_ray_pre r;
        pb_ray_prepare(org, dir, &r);
        for (int k = 0; k < 3; ++k) /* a device's division, up to 2.5 ulp off */
            r.idir[k] *= 1.f + (2.f * unit_random(&rng) - 1.f) * 5.f * 0x1p-24f;
        float tmax = iter % 3 ? INFINITY : R * unit_random(&rng);
        float d[4], d0[4];
        pb_ray_node_boxes(&r, nd.origin, scale, nd.qbox, 4, 0.f, tmax, d);
        pb_ray_node_boxes_widened(&r, nd.origin, scale, nd.qbox, 4, 0.f, tmax, 0.f, d0);
        for (uint32_t i = 0; i < 4; ++i) {
            double t0 = 0.0, t1 = tmax;
            for (int k = 0; k < 3; ++k) {
                double dk = fabsf(dir[k]) < 1e-30f ? (dir[k] < 0.f ? -1e-30 : 1e-30) : dir[k]; /* as pb_ray_prepare */
                double a = ((double)lo[i][k] - org[k]) / dk, b = ((double)hi[i][k] - org[k]) / dk;
                t0 = fmax(t0, fmin(a, b));
                t1 = fmin(t1, fmax(a, b));
            }
            if (!(t0 <= t1))
                continue;
            touched++;
            late_unwidened += !(d0[i] <= t0 * (1.0 + 0x1p-50));
            lost_unwidened += d0[i] == INFINITY;
            CHECKF(d[i] <= t0 * (1.0 + 0x1p-50), "iteration %d child %u: entry %.9g, the box test says %.9g", iter, i,
                   t0, (double)d[i]);
        }
    }
    printf("  %u touched boxes kept, entered no later than exactly; without the widening %u were entered "
           "later and %u culled\n", touched, late_unwidened, lost_unwidened);
    CHECK(touched > 50000);
    CHECK(lost_unwidened > 0);
}

int main(void)
{
    RUN(structure_of_random_soups);
    RUN(collapse_minimises_expected_steps);
    RUN(empty_scene_builds_and_misses);
    RUN(build_is_deterministic_across_threads);
    RUN(host_threads_follow_affinity);
    RUN(hostile_inputs_keep_depth_bounded);
    RUN(bad_desc_is_refused);
    RUN(traversal_matches_brute_force);
    RUN(watertight_sphere_cpu);
    RUN(brute_force_screen_skips_only_misses);
    RUN(reciprocal_is_accurate_everywhere);
    RUN(sliver_has_no_phantom_hit);
    RUN(robust_offset_avoids_self_intersection);
    RUN(offset_is_tiny_and_on_the_right_side);
    RUN(exact_diff_is_exact);
    RUN(node_boxes_are_conservative);
    return test_summary();
}
