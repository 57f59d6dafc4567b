/* The traced BVH: the child-pair tree collapsed into 4-wide nodes whose child
 * boxes are quantized to 8 bits per bound in the node's frame (as CWBVH,
 * Ylitie et al. 2017, with 4 children). One 64-byte node holds four boxes
 * where a child-pair node holds two, so a ray fetches half the bytes and
 * takes half the steps.
 *
 * Collapse: a wide node's children are a cover of its pair node's subtree
 * by at most four pair-tree children, chosen to minimise the expected node
 * steps (see `cover`). Node 0 is the root, every child follows its parent,
 * and a node's inner children are consecutive. Leaf order is then
 * renumbered node by node, so a node's leaves are consecutive too, and a
 * node names its children by two indices and four 5-bit slot codes: 48
 * bytes, three texels, where naming each child took 24 bytes and a fourth
 * texel (one image load, a call into llvmpipe's image function, per texel:
 * bench/RESULTS.md).
 *
 * Quantization is conservative and exact to decode: bound q of axis k
 * decodes to origin[k] + q * 2^e[k]. The product is exact (8 bits times a
 * power of two), so the sum is one rounding on every device, fused or not;
 * the builder steps each q until its decoded value encloses the true bound
 * under that rounding. */
#include "bvh/bvh_wide.h"
#include "common/common.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SLOT_UNUSED 0xffffffffu /* wide_state.child of a slot past a node's children */

typedef struct wide_slot {
    float lo[3], hi[3];
    uint32_t child; /* pair node index (count 0) or first triangle */
    uint32_t count;
} wide_slot;

#define COVER_DEPTH 6 /* 2^6 subtrees: enough to share among threads, few enough to merge above */

typedef struct wide_state {
    const pb_bvh *bvh;
    pb_bvh4_node *out;
    uint32_t (*child)[4]; /* per wide node: pair leaf's first triangle, wide node index or SLOT_UNUSED */
    uint8_t (*count)[4];  /* leaf triangles, 0 for an inner or empty slot */
    uint32_t next, depth;
    double area, root_area; /* summed surface area of the emitted wide nodes' boxes, the root's */
    double (*cost)[5];   /* per pair node: [j], j = 2..4: cheapest cover by j slots; [1]: as one slot */
    uint8_t (*split)[5]; /* [j]: slots of that cover under the first child; [1]: the cover's j */
    uint32_t *pair;      /* per wide node: the pair node it covers (`plan` writes it, `quantize` reads it) */
    uint32_t tasks[1u << COVER_DEPTH]; /* pair nodes at COVER_DEPTH, whose subtrees `cover` on all threads */
    uint32_t task_count;
} wide_state;

static uint32_t gather_slots(const pb_bvh_node *n, int s, wide_slot *slot)
{
    slot->lo[0] = n->lo_hi_x[2 * s], slot->hi[0] = n->lo_hi_x[2 * s + 1];
    slot->lo[1] = n->lo_hi_y[2 * s], slot->hi[1] = n->lo_hi_y[2 * s + 1];
    slot->lo[2] = n->lo_hi_z[2 * s], slot->hi[2] = n->lo_hi_z[2 * s + 1];
    slot->child = (uint32_t)n->child[s];
    slot->count = n->count[s];
    return n->child[s] != -1;
}

static float decode(float origin, uint32_t q, float scale)
{
    return origin + (float)q * scale;
}

/* Smallest exponent whose 255 steps reach from lo to hi (under the decode's
 * rounding: the loop settles it from one below the exact estimate). */
static uint32_t axis_exponent(float lo, float hi)
{
    int e = -126;
    if (hi > lo) {
        double need = ((double)hi - (double)lo) / 255.0;
        e = (int)ceil(log2(need)) - 1;
        e = e < -126 ? -126 : e > 127 ? 127 : e;
    }
    while (e < 127 && decode(lo, 255, pb_bvh4_scale((uint8_t)(e + 127))) < hi)
        ++e;
    return (uint32_t)(e + 127);
}

static uint8_t quantize_lo(float origin, float scale, float v)
{
    double f = floor(((double)v - (double)origin) / (double)scale);
    uint32_t q = f < 0 ? 0 : f > 255 ? 255 : (uint32_t)f;
    while (q < 255 && decode(origin, q + 1, scale) <= v)
        ++q;
    while (q > 0 && decode(origin, q, scale) > v)
        --q;
    return (uint8_t)q;
}

static uint8_t quantize_hi(float origin, float scale, float v)
{
    double f = ceil(((double)v - (double)origin) / (double)scale);
    uint32_t q = f < 0 ? 0 : f > 255 ? 255 : (uint32_t)f;
    while (q > 0 && decode(origin, q - 1, scale) >= v)
        --q;
    while (q < 255 && decode(origin, q, scale) < v)
        ++q;
    return (uint8_t)q;
}

/* The cover (Ylitie, Karras and Laine 2017, with 4 slots). A ray takes a
 * step at every wide node whose box it enters, so for rays spread evenly the
 * expected steps are proportional to the summed surface area of the wide
 * nodes. A pair node as one slot of its parent costs its own area plus its
 * cheapest cover by 2-4 slots; a leaf slot costs nothing here (each leaf is
 * tested when its box is hit, wherever it sits). Bottom-up over the pair
 * tree, then read top-down by `emit`. Against the collapse by whole levels
 * it had before, at leaves of 8: The Crypt 7,411 wide nodes instead of 8,672
 * and 10 % fewer steps per ray (bench/RESULTS.md). What the area leaves out: a leaf moved
 * up beside a nearer inner sibling is tested before that sibling's hits can
 * cull it (a penalty for it measured worse). */
static float slot_area(const wide_slot *c)
{
    return pb_box_area(c->lo, c->hi);
}

static double slot_cost(const wide_state *ws, const wide_slot *c, int j)
{
    if (j == 1)
        return c->count ? 0.0 : ws->cost[c->child][1];
    return c->count ? INFINITY : ws->cost[c->child][j];
}

/* Pair node q's covers, from its children's (computed before). */
static void cover_node(wide_state *ws, uint32_t q)
{
    wide_slot c[2];
    int has[2];
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int s = 0; s < 2; ++s) {
        has[s] = gather_slots(&ws->bvh->nodes[q], s, &c[s]);
        if (!has[s])
            continue;
        for (int a = 0; a < 3; ++a) {
            lo[a] = c[s].lo[a] < lo[a] ? c[s].lo[a] : lo[a];
            hi[a] = c[s].hi[a] > hi[a] ? c[s].hi[a] : hi[a];
        }
    }
    double best_any = INFINITY;
    ws->split[q][1] = 0; /* no cover of 2-4 slots (fewer than two triangles): the children as they are */
    for (int j = 2; j <= 4; ++j) {
        double best = INFINITY;
        int arg = 0;
        for (int a = 0; a <= j; ++a) { /* a slots for the first child, j - a for the second */
            double x = has[0] ? (a ? slot_cost(ws, &c[0], a) : INFINITY) : (a ? INFINITY : 0.0);
            double y = has[1] ? (j - a ? slot_cost(ws, &c[1], j - a) : INFINITY) : (j - a ? INFINITY : 0.0);
            if (x + y < best)
                best = x + y, arg = a;
        }
        ws->cost[q][j] = best;
        ws->split[q][j] = (uint8_t)arg;
        if (best < best_any)
            best_any = best, ws->split[q][1] = (uint8_t)j;
    }
    wide_slot box = {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, q, 0};
    ws->cost[q][1] = slot_area(&box) + (best_any < INFINITY ? best_any : 0.0);
}

/* Covers of q's subtree, bottom-up. A node's covers depend on its
 * children's alone, so subtrees can be covered in any order, on any thread. */
static void cover(wide_state *ws, uint32_t q)
{
    for (int s = 0; s < 2; ++s) {
        wide_slot c;
        if (gather_slots(&ws->bvh->nodes[q], s, &c) && !c.count)
            cover(ws, c.child);
    }
    cover_node(ws, q);
}

/* The inner pair nodes at COVER_DEPTH under q (at `depth`), as tasks. */
static void collect_tasks(wide_state *ws, uint32_t q, uint32_t depth)
{
    if (depth == COVER_DEPTH) {
        ws->tasks[ws->task_count++] = q;
        return;
    }
    for (int s = 0; s < 2; ++s) {
        wide_slot c;
        if (gather_slots(&ws->bvh->nodes[q], s, &c) && !c.count)
            collect_tasks(ws, c.child, depth + 1);
    }
}

static void cover_tasks(void *user, uint64_t begin, uint64_t end)
{
    wide_state *ws = user;
    for (uint64_t t = begin; t < end; ++t)
        cover(ws, ws->tasks[t]);
}

/* The nodes above COVER_DEPTH, once the tasks' subtrees are covered. */
static void cover_top(wide_state *ws, uint32_t q, uint32_t depth)
{
    if (depth == COVER_DEPTH)
        return;
    for (int s = 0; s < 2; ++s) {
        wide_slot c;
        if (gather_slots(&ws->bvh->nodes[q], s, &c) && !c.count)
            cover_top(ws, c.child, depth + 1);
    }
    cover_node(ws, q);
}

/* The slots of pair node q's cheapest cover by j slots (j = 0: its
 * children), appended to out. */
static uint32_t cover_slots(const wide_state *ws, uint32_t q, int j, wide_slot *out)
{
    uint32_t k = 0;
    if (j == 0) {
        for (int s = 0; s < 2; ++s)
            k += gather_slots(&ws->bvh->nodes[q], s, &out[k]);
        return k;
    }
    int part[2] = {ws->split[q][j], j - ws->split[q][j]};
    for (int s = 0; s < 2; ++s) {
        wide_slot c;
        if (!part[s] || !gather_slots(&ws->bvh->nodes[q], s, &c))
            continue;
        if (part[s] == 1)
            out[k++] = c;
        else
            k += cover_slots(ws, c.child, part[s], out + k);
    }
    return k;
}

/* The box around a wide node's k slots. */
static void slots_box(const wide_slot *slot, uint32_t k, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; ++a)
        lo[a] = INFINITY, hi[a] = -INFINITY;
    for (uint32_t i = 0; i < k; ++i)
        for (int a = 0; a < 3; ++a) {
            lo[a] = slot[i].lo[a] < lo[a] ? slot[i].lo[a] : lo[a];
            hi[a] = slot[i].hi[a] > hi[a] ? slot[i].hi[a] : hi[a];
        }
}

/* Emission, first half, in tree order: the wide node of pair node `pair`
 * gets `index`, its inner children consecutive indices in slot order (so a
 * traversal can name a node's pending children by the first one's index and
 * their ranks), then each child's subtree follows. Records the node's slots'
 * children and counts, its pair node, the depth and the summed area. */
static void plan(wide_state *ws, uint32_t pair, uint32_t index, uint32_t depth)
{
    wide_slot slot[4];
    uint32_t k = cover_slots(ws, pair, ws->split[pair][1], slot);
    if (depth + 1 > ws->depth)
        ws->depth = depth + 1;
    ws->pair[index] = pair;
    if (k) {
        wide_slot box = {{0}, {0}, 0, 0};
        slots_box(slot, k, box.lo, box.hi);
        ws->area += slot_area(&box);
        if (index == 0)
            ws->root_area = slot_area(&box);
    }
    uint32_t *child = ws->child[index];
    for (uint32_t i = 0; i < 4; ++i) {
        child[i] = SLOT_UNUSED;
        ws->count[index][i] = i < k ? (uint8_t)slot[i].count : 0;
    }
    /* siblings first, then each sibling's subtree */
    for (uint32_t i = 0; i < k; ++i)
        child[i] = slot[i].count ? slot[i].child : ws->next++;
    for (uint32_t i = 0; i < k; ++i)
        if (!slot[i].count)
            plan(ws, slot[i].child, ws->child[index][i], depth + 1);
}

/* Emission, second half: wide node `index`'s frame and quantized boxes,
 * which depend on its own slots alone (most of the emission's work), so
 * nodes are written on all threads. The slots are gathered again from the
 * pair node rather than kept from `plan` (128 bytes per node; gathering is
 * cheap beside the quantization). */
static void quantize_node(const wide_state *ws, uint32_t index)
{
    wide_slot slot[4];
    uint32_t pair = ws->pair[index];
    uint32_t k = cover_slots(ws, pair, ws->split[pair][1], slot);
    pb_bvh4_node *w = &ws->out[index];
    memset(w, 0, sizeof *w);
    float lo[3], hi[3], scale[3];
    slots_box(slot, k, lo, hi);
    for (int a = 0; a < 3; ++a) {
        if (k == 0)
            lo[a] = hi[a] = 0.f;
        w->origin[a] = lo[a];
        w->exponent[a] = (uint8_t)axis_exponent(lo[a], hi[a]);
        scale[a] = pb_bvh4_scale(w->exponent[a]);
    }
    for (uint32_t i = 0; i < k; ++i)
        for (int a = 0; a < 3; ++a) {
            w->qbox[a][0][i] = quantize_lo(lo[a], scale[a], slot[i].lo[a]);
            w->qbox[a][1][i] = quantize_hi(lo[a], scale[a], slot[i].hi[a]);
        }
}

static void quantize_nodes(void *user, uint64_t begin, uint64_t end)
{
    for (uint64_t w = begin; w < end; ++w)
        quantize_node(user, (uint32_t)w);
}

/* Leaf order renumbered node by node (a node's leaves in slot order), the
 * slots encoded, and the pair nodes' leaves and tri_order moved to the new
 * order. The visit order of any traversal is unchanged. */
static int encode(pb_bvh *bvh, const wide_state *ws)
{
    uint32_t n = bvh->triangle_count;
    uint32_t *moved = pb_malloc_large((size_t)(n ? n : 1) * sizeof *moved); /* old first triangle -> new */
    uint32_t *order = pb_malloc_large((size_t)(n ? n : 1) * sizeof *order);
    if (!moved || !order) {
        free(moved), free(order);
        return 0;
    }
    uint32_t next = 0;
    for (uint32_t w = 0; w < ws->next; ++w) {
        pb_bvh4_node *nd = &ws->out[w];
        uint32_t codes = 0, inner = 0, leaf = next, inners = 0;
        for (uint32_t i = 0; i < 4; ++i) {
            uint32_t c = ws->child[w][i], k = ws->count[w][i];
            if (c == SLOT_UNUSED)
                continue;
            if (!k) {
                inner = inners++ ? inner : c;
                codes |= PB_BVH4_SLOT_INNER << (5 * i);
                continue;
            }
            codes |= k << (5 * i);
            moved[c] = next;
            memcpy(order + next, bvh->tri_order + c, k * sizeof *order);
            next += k;
        }
        nd->codes_lo = (uint8_t)(codes & 0xffu);
        nd->inner = inner | (codes >> 8 & 0xffu) << 24;
        nd->leaf = leaf | (codes >> 16) << 28;
    }
    for (uint32_t p = 0; p < bvh->node_count; ++p)
        for (int s = 0; s < 2; ++s)
            if (bvh->nodes[p].count[s])
                bvh->nodes[p].child[s] = (int32_t)moved[bvh->nodes[p].child[s]];
    free(moved);
    free(bvh->tri_order);
    bvh->tri_order = order;
    return 1;
}

int pb_bvh_collapse_wide(pb_bvh *bvh, uint32_t threads)
{
    /* every wide node consumes at least one pair node */
    size_t cap = bvh->node_count ? bvh->node_count : 1;
    wide_state ws;
    memset(&ws, 0, sizeof ws);
    ws.bvh = bvh;
    ws.out = bvh->wide_nodes = pb_calloc_large(cap, sizeof(pb_bvh4_node));
    ws.child = pb_malloc_large(cap * sizeof *ws.child);
    ws.count = pb_malloc_large(cap * sizeof *ws.count);
    ws.cost = pb_malloc_large(cap * sizeof *ws.cost);
    ws.split = pb_malloc_large(cap * sizeof *ws.split);
    ws.pair = pb_malloc_large(cap * sizeof *ws.pair);
    ws.next = 1;
    int ok = bvh->wide_nodes && ws.child && ws.count && ws.cost && ws.split && ws.pair;
    if (ok) {
        collect_tasks(&ws, 0, 0);
        pb_parallel_for(ws.task_count, 1, threads, cover_tasks, &ws);
        cover_top(&ws, 0, 0);
        plan(&ws, 0, 0, 0);
        pb_parallel_for(ws.next, 4096, threads, quantize_nodes, &ws);
        ok = encode(bvh, &ws);
    }
    free(ws.child);
    free(ws.count);
    free(ws.cost);
    free(ws.split);
    free(ws.pair);
    bvh->wide_node_count = ok ? ws.next : 0;
    bvh->stats.wide_nodes = bvh->wide_node_count;
    bvh->stats.wide_depth = ws.depth;
    bvh->stats.wide_steps = ws.root_area > 0 ? ws.area / ws.root_area : 1.0;
    return ok;
}

void pb_bvh4_child_box(const pb_bvh4_node *n, uint32_t i, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; ++a) {
        float scale = pb_bvh4_scale(n->exponent[a]);
        lo[a] = decode(n->origin[a], n->qbox[a][0][i], scale);
        hi[a] = decode(n->origin[a], n->qbox[a][1][i], scale);
    }
}
