/* Binned SAH BVH build on all host cores, then a depth-first flatten into
 * child-pair nodes (see include/probebake/bvh.h and docs/bvh.md).
 *
 * Memory: triangles are 32-byte boxes (with their scene indices beside them)
 * that binning streams through and partitioning swaps in place; a partition
 * also gathers both children's bounds, so no level needs a separate bounds
 * pass. Boxes have four lanes, the fourth unused, so that the compiler makes
 * each min, max and centroid of a box one vector instruction.
 *
 * Parallelism: tasks (a node, its range and its bounds) go through a shared
 * stack. A worker splits its range, pushes one child and keeps the other, so
 * every core is busy once the top levels are split; a child of fewer than
 * SHARE_MIN triangles goes on the worker's own stack instead, as a lock and
 * a wake-up per node cost more than such a subtree's work. Ranges of
 * PAR_BIN_MIN triangles or more are binned in parallel, so the first levels
 * of a large scene do not run on one core.
 *
 * Determinism: a node's split depends only on its primitive range, and the
 * flatten walks the tree in a fixed order, so the output is byte-identical
 * whatever the thread count or scheduling. */
#define _POSIX_C_SOURCE 200809L
#include "bvh/bvh_wide.h"
#include "common/common.h"
#include "probebake/bvh.h"
#include "probebake/scene.h"

#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define MAX_BINS 64
#define PAR_BIN_MIN (1u << 14) /* bin ranges this large on several threads */
#define PAR_PARTS 16
#define SHARE_MIN 1024u /* subtrees smaller than this are not shared between threads */
#define LOCAL_TASKS PB_BVH_MAX_DEPTH

/* Four float lanes, x, y, z and one unused, in GCC's and Clang's vector
 * extension: a box's min, max and centroid are then one vector operation
 * each where the target has SIMD (SSE2 on x86-64, NEON on arm64), from one
 * source. */
typedef float f4 __attribute__((vector_size(16)));
typedef int32_t i4 __attribute__((vector_size(16)));

/* a < b ? a : b and a > b ? a : b, lane by lane (NaN as those expressions
 * take it: the second operand) */
static inline f4 f4_min(f4 a, f4 b)
{
    i4 m = a < b;
    return (f4)(((i4)a & m) | ((i4)b & ~m));
}

static inline f4 f4_max(f4 a, f4 b)
{
    i4 m = a > b;
    return (f4)(((i4)a & m) | ((i4)b & ~m));
}

typedef struct aabb {
    f4 lo, hi;
} aabb;

/* A triangle as the builder sees it is its box (lane 3 zero), stored
 * contiguously and swapped in place by partitioning, so binning and
 * partitioning stream through memory; its scene index moves with it in a
 * parallel array. Centroids are used doubled (lo + hi): the same ordering
 * without a multiply. */
typedef aabb prim;

/* Bounds of a range: of the boxes, and of the doubled centroids. */
typedef struct range_info {
    aabb box, cbox;
} range_info;

typedef struct build_node {
    float lo[3], hi[3]; /* its box */
    uint32_t left, right; /* build-node indices, valid when count == 0 */
    uint32_t begin, count;
} build_node;

typedef struct task {
    uint32_t node, begin, end, depth;
    range_info info;
} task;

typedef struct builder {
    prim *prims;
    uint32_t *index; /* scene index of each prim */
    build_node *nodes;
    atomic_uint node_count;
    uint32_t bins, max_leaf;
    float tc, ic;
    /* task stack */
    pthread_mutex_t lock;
    pthread_cond_t cond;
    task *stack;
    uint32_t stack_size, stack_cap;
    uint32_t busy; /* tasks being worked on */
    uint32_t threads;
} builder;

static void box_empty(aabb *b)
{
    b->lo = (f4){INFINITY, INFINITY, INFINITY, INFINITY};
    b->hi = -b->lo;
}

static void box_grow(aabb *b, const aabb *o)
{
    b->lo = f4_min(o->lo, b->lo);
    b->hi = f4_max(o->hi, b->hi);
}

static void info_empty(range_info *ri)
{
    box_empty(&ri->box);
    box_empty(&ri->cbox);
}

static inline void info_add(range_info *ri, const prim *p)
{
    f4 c = p->lo + p->hi;
    box_grow(&ri->box, p);
    ri->cbox.lo = f4_min(c, ri->cbox.lo);
    ri->cbox.hi = f4_max(c, ri->cbox.hi);
}

static inline float box_area(const aabb *b)
{
    float lo[3] = {b->lo[0], b->lo[1], b->lo[2]}, hi[3] = {b->hi[0], b->hi[1], b->hi[2]};
    return pb_box_area(lo, hi);
}

typedef struct bin_set {
    aabb box[3][MAX_BINS];
    uint32_t count[3][MAX_BINS];
} bin_set;

static void bin_set_clear(bin_set *s, uint32_t bins)
{
    for (int a = 0; a < 3; ++a)
        for (uint32_t i = 0; i < bins; ++i) {
            box_empty(&s->box[a][i]);
            s->count[a][i] = 0;
        }
}

/* The bin of a doubled centroid c. Clamped as a float: converting one out
 * of int's range (an infinite scale on a huge, degenerate or overflowing
 * box) is undefined; NaN goes to bin 0. */
static inline uint32_t bin_of(float c, float lo, float scale, float last)
{
    float f = (c - lo) * scale;
    f = f > 0.f ? f : 0.f;
    f = f < last ? f : last;
    return (uint32_t)(int32_t)f;
}

/* All three axes' bins of a box at once, each as bin_of gives it. */
static inline i4 bins_of(const prim *p, const aabb *cbox, f4 scale, f4 last)
{
    f4 f = (p->lo + p->hi - cbox->lo) * scale;
    f = f4_min(f4_max(f, (f4){0.f, 0.f, 0.f, 0.f}), last);
    return __builtin_convertvector(f, i4);
}

static f4 bin_scales(const builder *bd, const aabb *cbox)
{
    f4 scale = {0.f, 0.f, 0.f, 0.f};
    for (int a = 0; a < 3; ++a) {
        float ext = cbox->hi[a] - cbox->lo[a];
        scale[a] = ext > 0.f ? (float)bd->bins / ext : 0.f;
    }
    return scale;
}

static void bin_range(const builder *bd, uint32_t begin, uint32_t end, const aabb *cbox, bin_set *s)
{
    f4 scale = bin_scales(bd, cbox), last = {0.f, 0.f, 0.f, 0.f};
    last += (float)(bd->bins - 1);
    for (uint32_t i = begin; i < end; ++i) {
        const prim *p = &bd->prims[i];
        i4 b = bins_of(p, cbox, scale, last);
        for (int a = 0; a < 3; ++a) {
            s->count[a][b[a]]++;
            box_grow(&s->box[a][b[a]], p);
        }
    }
}

typedef struct par_bin {
    const builder *bd;
    const aabb *cbox;
    uint32_t base, chunk;
    bin_set parts[PAR_PARTS];
} par_bin;

static void par_bin_fn(void *user, uint64_t b, uint64_t e)
{
    par_bin *pb = user;
    for (uint64_t part = b; part < e; ++part) {
        uint32_t begin = pb->base + (uint32_t)part * pb->chunk;
        bin_set_clear(&pb->parts[part], pb->bd->bins);
        bin_range(pb->bd, begin, begin + pb->chunk, pb->cbox, &pb->parts[part]);
    }
}

/* Bins [begin,end) by doubled centroid within cbox into s, which arrives
 * empty; on several threads for large ranges. Parts are merged in a fixed
 * order: thread-count independent. */
static void bin_all(const builder *bd, uint32_t begin, uint32_t end, const aabb *cbox, bin_set *s, par_bin *scratch)
{
    uint32_t n = end - begin;
    if (n < PAR_BIN_MIN || bd->threads <= 1) {
        bin_range(bd, begin, end, cbox, s);
        return;
    }
    par_bin *pb = scratch;
    pb->bd = bd;
    pb->cbox = cbox;
    pb->base = begin;
    pb->chunk = n / PAR_PARTS;
    pb_parallel_for(PAR_PARTS, 1, bd->threads, par_bin_fn, pb);
    for (int p = 0; p < PAR_PARTS; ++p)
        for (int a = 0; a < 3; ++a)
            for (uint32_t i = 0; i < bd->bins; ++i) {
                s->count[a][i] += pb->parts[p].count[a][i];
                box_grow(&s->box[a][i], &pb->parts[p].box[a][i]);
            }
    bin_range(bd, begin + PAR_PARTS * pb->chunk, end, cbox, s); /* remainder */
}

typedef struct sort_key {
    float key;
    uint32_t index; /* scene index: unique, breaks ties deterministically */
    uint32_t pos;   /* where the record is in the scratch copy */
} sort_key;

static int compare_keys(const void *pa, const void *pb)
{
    const sort_key *a = pa, *b = pb;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return a->index < b->index ? -1 : a->index > b->index;
}

static uint32_t ceil_log2(uint32_t x)
{
    uint32_t l = 0;
    while ((1ull << l) < x)
        ++l;
    return l;
}

/* Halves [begin,end) after sorting along the longest centroid axis (ties by
 * scene index: deterministic). Rare: no SAH split exists, or the depth guard. */
static uint32_t median_split(builder *bd, uint32_t begin, uint32_t end, const aabb *cbox)
{
    uint32_t n = end - begin;
    int a = 0;
    for (int k = 1; k < 3; ++k)
        if (cbox->hi[k] - cbox->lo[k] > cbox->hi[a] - cbox->lo[a])
            a = k;
    sort_key *keys = pb_malloc_large((size_t)n * sizeof *keys);
    prim *tmp = pb_malloc_large((size_t)n * sizeof *tmp);
    if (keys && tmp) {
        for (uint32_t i = 0; i < n; ++i) {
            const prim *p = &bd->prims[begin + i];
            keys[i] = (sort_key){p->lo[a] + p->hi[a], bd->index[begin + i], i};
            tmp[i] = *p;
        }
        qsort(keys, n, sizeof *keys, compare_keys);
        for (uint32_t i = 0; i < n; ++i) {
            bd->prims[begin + i] = tmp[keys[i].pos];
            bd->index[begin + i] = keys[i].index;
        }
    } /* without memory, the unsorted halves still terminate */
    free(keys);
    free(tmp);
    return begin + n / 2;
}
static void info_range(const builder *bd, uint32_t begin, uint32_t end, range_info *ri)
{
    info_empty(ri);
    for (uint32_t i = begin; i < end; ++i)
        info_add(ri, &bd->prims[i]);
}

/* The best split of one axis' bins, if better than *best_cost: a sweep from
 * the right, then from the left, over the bins that hold triangles. A split
 * after an empty bin leaves the same triangles on each side as one after
 * the last bin before it that holds any, so only those are candidates: the
 * first of equal costs, as a sweep over every bin would choose. */
static void sweep(const bin_set *bins, int a, const uint32_t *used, uint32_t u, float *best_cost, int *best_axis,
                  uint32_t *best_bin)
{
    float right_cost[MAX_BINS];
    aabb acc;
    box_empty(&acc);
    uint32_t cnt = 0;
    for (uint32_t j = u; j-- > 1;) {
        box_grow(&acc, &bins->box[a][used[j]]);
        cnt += bins->count[a][used[j]];
        right_cost[j] = box_area(&acc) * (float)cnt;
    }
    box_empty(&acc);
    cnt = 0;
    for (uint32_t j = 0; j + 1 < u; ++j) {
        box_grow(&acc, &bins->box[a][used[j]]);
        cnt += bins->count[a][used[j]];
        float c = box_area(&acc) * (float)cnt + right_cost[j + 1];
        if (c < *best_cost) {
            *best_cost = c;
            *best_axis = a;
            *best_bin = used[j] + 1;
        }
    }
}

/* Splits task t or makes it a leaf. Returns the split position (begin < mid
 * < end) and both children's bounds, or 0 for a leaf. */
static uint32_t split_node(builder *bd, build_node *node, const task *t, par_bin *scratch, bin_set *bins,
                           range_info *left, range_info *right)
{
    uint32_t begin = t->begin, end = t->end, n = end - begin;
    const range_info *ri = &t->info;
    for (int k = 0; k < 3; ++k)
        node->lo[k] = ri->box.lo[k], node->hi[k] = ri->box.hi[k];
    if (n <= 1)
        return 0;

    /* depth guard: if the remaining levels could exceed the bound, halve */
    uint32_t leaves_needed = (n + bd->max_leaf - 1) / bd->max_leaf;
    int force_median = t->depth + ceil_log2(leaves_needed) + 2 >= PB_BVH_MAX_DEPTH;

    float best_cost = INFINITY;
    int best_axis = -1;
    uint32_t best_bin = 0;
    if (!force_median) {
        bin_all(bd, begin, end, &ri->cbox, bins, scratch);
        for (int a = 0; a < 3; ++a) {
            uint32_t used[MAX_BINS], u = 0; /* the axis' bins that hold triangles, in order */
            for (uint32_t i = 0; i < bd->bins; ++i)
                if (bins->count[a][i])
                    used[u++] = i;
            if (ri->cbox.hi[a] > ri->cbox.lo[a])
                sweep(bins, a, used, u, &best_cost, &best_axis, &best_bin);
            for (uint32_t j = 0; j < u; ++j) { /* leave the set empty for the next node */
                box_empty(&bins->box[a][used[j]]);
                bins->count[a][used[j]] = 0;
            }
        }
    }
    float area = box_area(&ri->box);
    float leaf_cost = bd->ic * (float)n;
    float split_cost = area > 0.f ? bd->tc + bd->ic * best_cost / area : bd->tc + bd->ic * (float)n;
    if (n <= bd->max_leaf && (best_axis < 0 || leaf_cost <= split_cost))
        return 0;

    uint32_t mid;
    if (best_axis >= 0) {
        /* partition in place, gathering both children's bounds on the way */
        const int a = best_axis;
        f4 scale = bin_scales(bd, &ri->cbox);
        float last = (float)(bd->bins - 1);
        info_empty(left);
        info_empty(right);
        uint32_t i = begin, j = end;
        while (i < j) {
            prim *p = &bd->prims[i];
            if (bin_of(p->lo[a] + p->hi[a], ri->cbox.lo[a], scale[a], last) < best_bin) {
                info_add(left, p);
                ++i;
            } else {
                --j;
                prim tmp = *p;
                *p = bd->prims[j];
                bd->prims[j] = tmp;
                uint32_t t = bd->index[i];
                bd->index[i] = bd->index[j];
                bd->index[j] = t;
                info_add(right, &bd->prims[j]);
            }
        }
        mid = i;
        if (mid > begin && mid < end)
            return mid;
    }
    /* no usable split (identical centroids) or depth guard: sorted halves */
    mid = median_split(bd, begin, end, &ri->cbox);
    info_range(bd, begin, mid, left);
    info_range(bd, mid, end, right);
    return mid;
}

static void push_task(builder *bd, const task *t)
{
    pthread_mutex_lock(&bd->lock);
    assert(bd->stack_size < bd->stack_cap);
    bd->stack[bd->stack_size++] = *t;
    pthread_cond_signal(&bd->cond);
    pthread_mutex_unlock(&bd->lock);
}

typedef struct worker_arg {
    builder *bd;
    par_bin scratch;
    bin_set bins;
} worker_arg;

static void *worker(void *arg)
{
    builder *bd = ((worker_arg *)arg)->bd;
    par_bin *scratch = &((worker_arg *)arg)->scratch;
    bin_set *bins = &((worker_arg *)arg)->bins;
    bin_set_clear(bins, bd->bins); /* and split_node leaves it empty */
    for (;;) {
        pthread_mutex_lock(&bd->lock);
        while (bd->stack_size == 0 && bd->busy > 0)
            pthread_cond_wait(&bd->cond, &bd->lock);
        if (bd->stack_size == 0) { /* nothing queued, nobody working: done */
            pthread_cond_broadcast(&bd->cond);
            pthread_mutex_unlock(&bd->lock);
            break;
        }
        task t = bd->stack[--bd->stack_size];
        bd->busy++;
        pthread_mutex_unlock(&bd->lock);

        /* Keep one child and share the other, unless it is small: small
         * subtrees stay on this thread's own stack, as sharing them (a lock
         * and a wake-up per node) would cost more than their work. */
        task local[LOCAL_TASKS];
        uint32_t local_count = 0;
        for (;;) {
            build_node *node = &bd->nodes[t.node];
            range_info li, ri;
            uint32_t mid = split_node(bd, node, &t, scratch, bins, &li, &ri);
            if (!mid) {
                node->begin = t.begin;
                node->count = t.end - t.begin;
                if (!local_count)
                    break;
                t = local[--local_count];
                continue;
            }
            uint32_t l = atomic_fetch_add(&bd->node_count, 2);
            node->left = l;
            node->right = l + 1;
            node->count = 0;
            task right = {l + 1, mid, t.end, t.depth + 1, ri};
            if (t.end - mid < SHARE_MIN && local_count < LOCAL_TASKS)
                local[local_count++] = right;
            else
                push_task(bd, &right);
            t = (task){l, t.begin, mid, t.depth + 1, li};
        }

        pthread_mutex_lock(&bd->lock);
        bd->busy--;
        if (bd->busy == 0 && bd->stack_size == 0)
            pthread_cond_broadcast(&bd->cond);
        pthread_mutex_unlock(&bd->lock);
    }
    return NULL;
}

typedef struct flatten_state {
    const builder *bd;
    pb_bvh *bvh;
    uint32_t next;
    uint32_t depth;
    uint32_t leaves, max_leaf;
    double sah, root_area;
} flatten_state;

static void set_child(flatten_state *fs, pb_bvh_node *out, int slot, uint32_t bnode, uint32_t depth);

/* Emits build node `bnode` (an inner node) as flattened node `slot_index`. */
static void emit_inner(flatten_state *fs, uint32_t out_index, uint32_t bnode, uint32_t depth)
{
    const build_node *b = &fs->bd->nodes[bnode];
    pb_bvh_node *out = &fs->bvh->nodes[out_index];
    if (fs->root_area > 0)
        fs->sah += pb_box_area(b->lo, b->hi) / fs->root_area; /* traversal cost 1 per visited pair */
    set_child(fs, out, 0, b->left, depth);
    out = &fs->bvh->nodes[out_index];
    set_child(fs, out, 1, b->right, depth);
}

static void set_child(flatten_state *fs, pb_bvh_node *out, int slot, uint32_t bnode, uint32_t depth)
{
    const build_node *c = &fs->bd->nodes[bnode];
    out->lo_hi_x[2 * slot] = c->lo[0];
    out->lo_hi_x[2 * slot + 1] = c->hi[0];
    out->lo_hi_y[2 * slot] = c->lo[1];
    out->lo_hi_y[2 * slot + 1] = c->hi[1];
    out->lo_hi_z[2 * slot] = c->lo[2];
    out->lo_hi_z[2 * slot + 1] = c->hi[2];
    if (depth + 1 > fs->depth)
        fs->depth = depth + 1;
    if (c->count) {
        out->child[slot] = (int32_t)c->begin;
        out->count[slot] = c->count;
        fs->leaves++;
        fs->max_leaf = c->count > fs->max_leaf ? c->count : fs->max_leaf;
        if (fs->root_area > 0)
            fs->sah += pb_box_area(c->lo, c->hi) / fs->root_area * c->count * fs->bd->ic;
    } else {
        uint32_t idx = fs->next++;
        out->child[slot] = (int32_t)idx;
        out->count[slot] = 0;
        emit_inner(fs, idx, bnode, depth + 1);
    }
}

/* The triangles' boxes, scene indices and the root's bounds, in fixed parts
 * on all threads (min and max merge exactly, in any order). */
#define PRIM_PARTS 64
typedef struct prims_job {
    builder *bd;
    const pb_scene *scene;
    uint32_t chunk;
    range_info part[PRIM_PARTS];
} prims_job;

static void make_prims_fn(void *user, uint64_t first, uint64_t last)
{
    prims_job *pj = user;
    uint32_t n = pj->scene->triangle_count;
    for (uint64_t part = first; part < last; ++part) {
        range_info *ri = &pj->part[part];
        info_empty(ri);
        uint32_t begin = (uint32_t)part * pj->chunk, end = begin + pj->chunk < n ? begin + pj->chunk : n;
        for (uint32_t i = begin; i < end; ++i) {
            const float *p = pj->scene->positions + 9 * (size_t)i;
            prim *pr = &pj->bd->prims[i];
            for (int k = 0; k < 3; ++k) {
                float a = p[k], bb = p[3 + k], c = p[6 + k];
                pr->lo[k] = a < bb ? (a < c ? a : c) : (bb < c ? bb : c);
                pr->hi[k] = a > bb ? (a > c ? a : c) : (bb > c ? bb : c);
            }
            pr->lo[3] = pr->hi[3] = 0.f;
            pj->bd->index[i] = i;
            info_add(ri, pr);
        }
    }
}

static void make_prims(builder *bd, const pb_scene *scene, uint32_t threads, range_info *root)
{
    uint32_t n = scene->triangle_count;
    prims_job pj = {bd, scene, n >= PRIM_PARTS ? (n + PRIM_PARTS - 1) / PRIM_PARTS : 1, {{{{0}}}}};
    pb_parallel_for(PRIM_PARTS, 1, n >= 4096 ? threads : 1, make_prims_fn, &pj);
    info_empty(root);
    for (int p = 0; p < PRIM_PARTS; ++p) {
        box_grow(&root->box, &pj.part[p].box);
        box_grow(&root->cbox, &pj.part[p].cbox);
    }
}

typedef struct positions_job {
    const pb_scene *scene;
    pb_bvh *bvh;
} positions_job;

static void gather_positions(void *user, uint64_t begin, uint64_t end)
{
    const positions_job *pj = user;
    for (uint64_t k = begin; k < end; ++k)
        memcpy(pj->bvh->tri_positions + 9 * k, pj->scene->positions + 9 * (size_t)pj->bvh->tri_order[k],
               9 * sizeof(float));
}

pb_result pb_bvh_build(const pb_scene *scene, const pb_bvh_desc *desc_in, pb_bvh **out, pb_error *err)
{
    pb_error_clear(err);
    *out = NULL;
    pb_bvh_desc d;
    memset(&d, 0, sizeof d);
    if (desc_in)
        d = *desc_in;
    if (!d.max_leaf_size) d.max_leaf_size = 2;
    if (!d.bins) d.bins = 16;
    if (!d.threads) d.threads = pb_host_threads();
    if (d.traversal_cost == 0.f) d.traversal_cost = 2.f;
    if (d.intersection_cost == 0.f) d.intersection_cost = 1.f;
    if (!d.max_wide_nodes || d.max_wide_nodes > PB_BVH4_MAX_NODES) d.max_wide_nodes = PB_BVH4_MAX_NODES;
    if (d.max_leaf_size > 16)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "BVH max leaf size %u is out of range 1..16", d.max_leaf_size);
    if (d.bins < 4 || d.bins > MAX_BINS)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "BVH bin count %u is out of range 4..%d", d.bins, MAX_BINS);
    if (!(d.traversal_cost > 0.f) || !(d.intersection_cost > 0.f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "BVH SAH costs must be positive");
    if (d.threads > 64)
        d.threads = 64;
    if (scene->triangle_count > PB_BVH4_MAX_TRIANGLES)
        return pb_fail(err, PB_ERROR_TOO_LARGE, "%u triangles are more than the %u a BVH node can address",
                       scene->triangle_count, PB_BVH4_MAX_TRIANGLES);

    double t0 = pb_now_ms();
    uint32_t n = scene->triangle_count;
    pb_bvh *bvh = calloc(1, sizeof *bvh);
    builder bd;
    memset(&bd, 0, sizeof bd);
    uint32_t max_nodes = n ? 2 * n : 1;
    bd.prims = pb_malloc_large((size_t)(n ? n : 1) * sizeof(prim));
    bd.index = pb_malloc_large((size_t)(n ? n : 1) * sizeof(uint32_t));
    bd.nodes = pb_calloc_large(max_nodes, sizeof(build_node));
    bd.stack = pb_malloc_large((size_t)max_nodes * sizeof(task));
    uint32_t want = n >= 4096 ? d.threads : 1;
    worker_arg *args = malloc(want * sizeof *args);
    uint32_t inner_cap = n > 1 ? n : 1;
    if (bvh)
        bvh->nodes = pb_calloc_large(inner_cap, sizeof(pb_bvh_node));
    if (!bvh || !bd.prims || !bd.index || !bd.nodes || !bd.stack || !args || !bvh->nodes) {
        free(bd.prims), free(bd.index), free(bd.nodes), free(bd.stack), free(args);
        pb_bvh_destroy(bvh);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory building the BVH of %u triangles", n);
    }
    task root_task = {.node = 0, .begin = 0, .end = n, .depth = 0};
    make_prims(&bd, scene, d.threads, &root_task.info);
    bd.bins = d.bins;
    bd.max_leaf = d.max_leaf_size;
    bd.tc = d.traversal_cost;
    bd.ic = d.intersection_cost;
    bd.threads = d.threads;
    bd.stack_cap = max_nodes;
    atomic_init(&bd.node_count, 1);
    pthread_mutex_init(&bd.lock, NULL);
    pthread_cond_init(&bd.cond, NULL);

    if (n > 0) {
        bd.stack[bd.stack_size++] = root_task;
        pthread_t tids[64];
        uint32_t started = 0;
        for (uint32_t i = 0; i < want; ++i)
            args[i].bd = &bd;
        for (uint32_t i = 1; i < want; ++i)
            if (pthread_create(&tids[started], NULL, worker, &args[started + 1]) == 0)
                ++started;
        worker(&args[0]);
        for (uint32_t i = 0; i < started; ++i)
            pthread_join(tids[i], NULL);
        want = started + 1;
    }
    free(args);

    /* flatten: node 0 is the root's child pair. A root that is a leaf (or an
     * empty scene) becomes one pair with an empty second slot. */
    flatten_state fs = {.bd = &bd, .bvh = bvh, .next = 1};
    const build_node *root = &bd.nodes[0];
    fs.root_area = n ? pb_box_area(root->lo, root->hi) : 0;
    pb_bvh_node *r0 = &bvh->nodes[0];
    memset(r0, 0, sizeof *r0);
    r0->child[0] = r0->child[1] = -1;
    if (n > 0 && root->count == 0) {
        emit_inner(&fs, 0, 0, 0); /* counts the root pair's fetch (area ratio 1) */
    } else if (n > 0) {
        set_child(&fs, r0, 0, 0, 0);
        fs.sah += 1.0;
    }
    bvh->node_count = fs.next;
    bvh->triangle_count = n;
    bvh->tri_order = bd.index; /* leaf order; the collapse renumbers it */
    bd.index = NULL;
    bvh->stats.nodes = fs.next;
    bvh->stats.leaves = fs.leaves;
    bvh->stats.depth = fs.depth;
    bvh->stats.max_leaf_size = fs.max_leaf;
    bvh->stats.sah_cost = fs.sah;
    bvh->stats.threads = n ? want : 1;
    int wide_ok = pb_bvh_collapse_wide(bvh, d.threads);
    if (wide_ok) { /* the positions once, in the final leaf order */
        bvh->tri_positions = pb_malloc_large((size_t)(n ? n : 1) * 9 * sizeof(float));
        wide_ok = bvh->tri_positions != NULL;
        positions_job pj = {scene, bvh};
        if (wide_ok)
            pb_parallel_for(n, 1u << 16, d.threads, gather_positions, &pj);
    }

    pthread_mutex_destroy(&bd.lock);
    pthread_cond_destroy(&bd.cond);
    free(bd.prims);
    free(bd.index); /* NULL: it became tri_order */
    free(bd.nodes);
    free(bd.stack);
    bvh->stats.build_ms = pb_now_ms() - t0;
    if (!wide_ok) {
        pb_bvh_destroy(bvh);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory building the BVH of %u triangles", n);
    }
    if (bvh->wide_node_count > d.max_wide_nodes) {
        uint32_t w = bvh->wide_node_count;
        pb_bvh_destroy(bvh);
        return pb_fail(err, PB_ERROR_TOO_LARGE, "the BVH of %u triangles has %u 4-wide nodes, more than the %u %s", n, w,
                       d.max_wide_nodes, d.max_wide_nodes == PB_BVH4_MAX_NODES ? "a traversal can address" : "allowed");
    }
    *out = bvh;
    return PB_OK;
}

void pb_bvh_destroy(pb_bvh *bvh)
{
    if (!bvh)
        return;
    free(bvh->nodes);
    free(bvh->wide_nodes);
    free(bvh->tri_order);
    free(bvh->tri_positions);
    free(bvh);
}

uint64_t pb_bvh_gpu_bytes(const pb_bvh *bvh)
{
    /* 4-wide nodes (48 bytes) + 36 bytes of positions + 4 bytes of flags per triangle */
    return (uint64_t)bvh->wide_node_count * sizeof(pb_bvh4_node) + (uint64_t)bvh->triangle_count * 40u;
}
