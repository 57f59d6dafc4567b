/* The traced BVH: the child-pair tree collapsed into 4-wide nodes whose child
 * boxes are quantized to 8 bits per bound in the node's frame (as CWBVH,
 * Ylitie et al. 2017, with 4 children). One 64-byte node holds four boxes
 * where a child-pair node holds two, so a ray fetches half the bytes and
 * takes half the steps.
 *
 * Collapse: a wide node's children are its pair node's children, where each
 * inner child is replaced by that child's own two children. Node 0 is the
 * root, every child follows its parent, and a node's inner children are
 * consecutive.
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

typedef struct wide_slot {
    float lo[3], hi[3];
    uint32_t child; /* pair node index (count 0) or first triangle */
    uint32_t count;
} wide_slot;

typedef struct wide_state {
    const pb_bvh *bvh;
    pb_bvh4_node *out;
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
    for (uint32_t i = 0; i < 4; ++i) {
        w->child[i] = PB_BVH4_EMPTY;
        if (i >= k)
            continue;
        for (int a = 0; a < 3; ++a) {
            w->qbox[a][0][i] = quantize_lo(lo[a], scale[a], slot[i].lo[a]);
            w->qbox[a][1][i] = quantize_hi(lo[a], scale[a], slot[i].hi[a]);
        }
        w->count[i] = (uint8_t)slot[i].count;
    }
    /* siblings first, then each sibling's subtree */
    for (uint32_t i = 0; i < k; ++i)
        w->child[i] = slot[i].count ? slot[i].child : ws->next++;
    for (uint32_t i = 0; i < k; ++i)
        if (!slot[i].count)
            emit(ws, slot[i].child, ws->out[index].child[i], depth + 1);
}

int pb_bvh_collapse_wide(pb_bvh *bvh)
{
    /* every wide node consumes at least one pair node */
    bvh->wide_nodes = calloc(bvh->node_count ? bvh->node_count : 1, sizeof(pb_bvh4_node));
    if (!bvh->wide_nodes)
        return 0;
    wide_state ws = {bvh, bvh->wide_nodes, 1, 0};
    emit(&ws, 0, 0, 0);
    bvh->wide_node_count = ws.next;
    bvh->stats.wide_nodes = ws.next;
    bvh->stats.wide_depth = ws.depth;
    return 1;
}

void pb_bvh4_child_box(const pb_bvh4_node *n, uint32_t i, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; ++a) {
        float scale = pb_bvh4_scale(n->exponent[a]);
        lo[a] = decode(n->origin[a], n->qbox[a][0][i], scale);
        hi[a] = decode(n->origin[a], n->qbox[a][1][i], scale);
    }
}
