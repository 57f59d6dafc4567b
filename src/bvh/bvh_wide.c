/* The traced BVH: the child-pair tree collapsed into 4-wide nodes whose child
 * boxes are quantized to 8 bits per bound in the node's frame (as CWBVH,
 * Ylitie et al. 2017, with 4 children). One 64-byte node holds four boxes
 * where a child-pair node holds two, so a ray fetches half the bytes and
 * takes half the steps.
 *
 * Collapse: a wide node's children are its pair node's children, where each
 * inner child is replaced by that child's own two children. Node 0 is the
 * root, every child follows its parent, and a node's inner children are
 * consecutive. Leaf order is then renumbered node by node, so a node's
 * leaves are consecutive too, and a node names its children by two indices
 * and four 5-bit slot codes: 48 bytes, three texels, where naming each child
 * took 24 bytes and a fourth texel (one image load, a call into llvmpipe's
 * image function, per texel: bench/RESULTS.md).
 *
 * Quantization is conservative and exact to decode: bound q of axis k
 * decodes to origin[k] + q * 2^e[k]. The product is exact (8 bits times a
 * power of two), so the sum is one rounding on every device, fused or not;
 * the builder steps each q until its decoded value encloses the true bound
 * under that rounding. */
#include "bvh/bvh_wide.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SLOT_UNUSED 0xffffffffu /* wide_state.child of a slot past a node's children */

typedef struct wide_slot {
    float lo[3], hi[3];
    uint32_t child; /* pair node index (count 0) or first triangle */
    uint32_t count;
} wide_slot;

typedef struct wide_state {
    const pb_bvh *bvh;
    pb_bvh4_node *out;
    uint32_t (*child)[4]; /* per wide node: pair leaf's first triangle, wide node index or SLOT_UNUSED */
    uint8_t (*count)[4];  /* leaf triangles, 0 for an inner or empty slot */
    uint32_t next, depth;
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

/* Writes the wide node of pair node `pair` at `index`; its inner children get
 * consecutive indices, in slot order, so a traversal can name a node's
 * pending children by the first one's index and their ranks. */
static void emit(wide_state *ws, uint32_t pair, uint32_t index, uint32_t depth)
{
    const pb_bvh_node *n = &ws->bvh->nodes[pair];
    wide_slot slot[4];
    uint32_t k = 0;
    for (int s = 0; s < 2; ++s) {
        wide_slot c;
        if (!gather_slots(n, s, &c))
            continue;
        if (c.count) {
            slot[k++] = c;
            continue;
        }
        const pb_bvh_node *m = &ws->bvh->nodes[c.child];
        for (int t = 0; t < 2; ++t)
            k += gather_slots(m, t, &slot[k]);
    }
    if (depth + 1 > ws->depth)
        ws->depth = depth + 1;
    pb_bvh4_node *w = &ws->out[index];
    memset(w, 0, sizeof *w);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < k; ++i)
        for (int a = 0; a < 3; ++a) {
            lo[a] = slot[i].lo[a] < lo[a] ? slot[i].lo[a] : lo[a];
            hi[a] = slot[i].hi[a] > hi[a] ? slot[i].hi[a] : hi[a];
        }
    float scale[3];
    for (int a = 0; a < 3; ++a) {
        if (k == 0)
            lo[a] = hi[a] = 0.f;
        w->origin[a] = lo[a];
        w->exponent[a] = (uint8_t)axis_exponent(lo[a], hi[a]);
        scale[a] = pb_bvh4_scale(w->exponent[a]);
    }
    uint32_t *child = ws->child[index];
    for (uint32_t i = 0; i < 4; ++i) {
        child[i] = SLOT_UNUSED;
        ws->count[index][i] = 0;
        if (i >= k)
            continue;
        for (int a = 0; a < 3; ++a) {
            w->qbox[a][0][i] = quantize_lo(lo[a], scale[a], slot[i].lo[a]);
            w->qbox[a][1][i] = quantize_hi(lo[a], scale[a], slot[i].hi[a]);
        }
        ws->count[index][i] = (uint8_t)slot[i].count;
    }
    /* siblings first, then each sibling's subtree */
    for (uint32_t i = 0; i < k; ++i)
        child[i] = slot[i].count ? slot[i].child : ws->next++;
    for (uint32_t i = 0; i < k; ++i)
        if (!slot[i].count)
            emit(ws, slot[i].child, ws->child[index][i], depth + 1);
}

/* Leaf order renumbered node by node (a node's leaves in slot order), the
 * slots encoded, and the pair nodes' leaves and the triangle arrays moved to
 * the new order. The visit order of any traversal is unchanged. */
static int encode(pb_bvh *bvh, const wide_state *ws)
{
    uint32_t n = bvh->triangle_count;
    uint32_t *moved = malloc((size_t)(n ? n : 1) * sizeof *moved); /* old first triangle -> new */
    uint32_t *order = malloc((size_t)(n ? n : 1) * sizeof *order);
    float *pos = malloc((size_t)(n ? n : 1) * 9 * sizeof *pos);
    if (!moved || !order || !pos) {
        free(moved), free(order), free(pos);
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
            memcpy(pos + 9 * (size_t)next, bvh->tri_positions + 9 * (size_t)c, 9 * k * sizeof *pos);
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
    free(bvh->tri_positions);
    bvh->tri_order = order;
    bvh->tri_positions = pos;
    return 1;
}

int pb_bvh_collapse_wide(pb_bvh *bvh)
{
    /* every wide node consumes at least one pair node */
    size_t cap = bvh->node_count ? bvh->node_count : 1;
    bvh->wide_nodes = calloc(cap, sizeof(pb_bvh4_node));
    wide_state ws = {bvh, bvh->wide_nodes, malloc(cap * sizeof *ws.child), malloc(cap * sizeof *ws.count), 1, 0};
    int ok = bvh->wide_nodes && ws.child && ws.count;
    if (ok) {
        emit(&ws, 0, 0, 0);
        ok = encode(bvh, &ws);
    }
    free(ws.child);
    free(ws.count);
    bvh->wide_node_count = ok ? ws.next : 0;
    bvh->stats.wide_nodes = bvh->wide_node_count;
    bvh->stats.wide_depth = ws.depth;
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
