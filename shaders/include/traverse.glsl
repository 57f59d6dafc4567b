// BVH traversal: src/bvh/bvh_traverse.c in GLSL. 4-wide quantized nodes
// (include/probebake/bvh.h): the four child boxes are sorted near to far,
// hit leaves are tested in that order, the nearest hit inner child is
// visited next and the others become the pending group, whose predecessor
// is pushed. At most one entry per level is ever on the stack, and
// STACK_SIZE (a specialisation constant) is wide depth + 1, so the stack
// cannot overflow.
#ifndef PB_TRAVERSE_GLSL
#define PB_TRAVERSE_GLSL

#include "scene.glsl"
#include "intersect.glsl"
#include "alpha.glsl"

layout(constant_id = 0) const uint STACK_SIZE = 65u; // PB_BVH_STACK_SIZE(PB_BVH_MAX_DEPTH)

// Compare-exchange of child slots a and b by box distance; ties keep slot order.
#define PB_SORT2(a, b)                                                          \
    if (d[b] < d[a]) {                                                          \
        float td_ = d[a]; uint tc_ = ch[a], tn_ = cnt[a];                       \
        d[a] = d[b]; ch[a] = ch[b]; cnt[a] = cnt[b];                            \
        d[b] = td_; ch[b] = tc_; cnt[b] = tn_;                                  \
    }

// A group of pending inner siblings (src/bvh/bvh_traverse.c): the first
// sibling's node index, how many are pending (0-3; 0: none) and their ranks
// among the node's inner children, nearest first, 2 bits each.
#define PB_GROUP(first, count, ranks) ((first) << 8u | (count) << 6u | (ranks))
#define PB_GROUP_COUNT(g) (((g) >> 6u) & 3u)

struct TraceResult {
    float t;
    uint tri; // leaf order, PB_NO_HIT on a miss
    float u;
    float v;
};

#ifdef PB_COUNT_TRAVERSALS
uint pb_traversals = 0u; // this invocation's traversals (bake throughput accounting)
uint pb_loop_steps = 0u; // its traversal loop iterations: llvmpipe ends loops past 65535 per invocation
#endif

TraceResult trace_ray(SceneRefs s, vec3 org, vec3 dir, float tmin, float tmax, bool any_hit)
{
#ifdef PB_COUNT_TRAVERSALS
    ++pb_traversals;
#endif
    TraceResult res;
    res.tri = PB_NO_HIT;
    res.u = 0.0;
    res.v = 0.0;
    res.t = tmax;
    if (s.triangle_count == 0u)
        return res;
    RayPre r = ray_prepare(org, dir);
    uint stack[STACK_SIZE]; // pending groups
    uint sp = 0u;
    uint node = 0u;
    uint group = 0u; // no group pending
    for (;;) {
#ifdef PB_COUNT_TRAVERSALS
        ++pb_loop_steps;
#endif
        Node4 nd = load_node4(s.nodes, node);
        float d[4];
        uint ch[4], cnt[4];
        node_boxes(r, nd.origin, nd.scale, nd.qlo, nd.qhi, nd.used, tmin, tmax, d);
        for (int i = 0; i < 4; ++i) {
            ch[i] = nd.child[i];
            cnt[i] = nd.count[i];
        }
        // near to far (ties keep slot order): leaves tested in this order, inner children pushed far first
        PB_SORT2(0, 1);
        PB_SORT2(2, 3);
        PB_SORT2(0, 2);
        PB_SORT2(1, 3);
        PB_SORT2(1, 2);
        // The hit leaves, near to far, as one run of triangles: one loop
        // (llvmpipe runs a loop's body even where no lane enters it).
        uint e[4];
        uint run = 0u;
        for (int i = 0; i < 4; ++i) {
            run += cnt[i] != 0u && d[i] < PB_INF && d[i] <= tmax ? cnt[i] : 0u;
            e[i] = run;
        }
        // Address loads are software-pipelined: the next triangle's words are
        // gathered before this one is tested (+8-12 % on AVX-512 llvmpipe).
        // Texel loads are not: there the pipelined loop's extra live values
        // cost more than the overlap buys (0.89-0.92x the bake's GPU time on
        // AVX2; bench/RESULTS.md). The specialisation constant keeps one loop.
        uint kn = 0u < e[0] ? ch[0] : 0u < e[1] ? ch[1] : 0u < e[2] ? ch[2] : ch[3];
        Tri trin;
        if (PB_SCENE_TEXELS == 0u && run != 0u)
            trin = load_tri(s.tris, kn);
        for (uint j = 0u; j < run; ++j) {
            uint k = kn;
            uint j1 = j + 1u;
            kn = j1 < e[0] ? ch[0] + j1 : j1 < e[1] ? ch[1] + (j1 - e[0]) : j1 < e[2] ? ch[2] + (j1 - e[1]) : ch[3] + (j1 - e[2]);
            Tri tri;
            if (PB_SCENE_TEXELS != 0u) {
                tri = load_tri(s.tris, k);
            } else {
                tri = trin;
                if (j1 < run)
                    trin = load_tri(s.tris, kn);
            }
            float t, u, v;
            if (!ray_triangle(r, tri.v0, tri.v1, tri.v2, tmin, tmax, t, u, v))
                continue;
            uint f = tri.flags;
            if ((f & PB_FLAG_ALPHA_MASK) != 0u && !alpha_opaque(s, k, f, u, v))
                continue;
            tmax = t;
            res.t = t;
            res.tri = k;
            res.u = u;
            res.v = v;
            if (any_hit)
                return res;
        }
        // The hit inner children, near to far, as ranks among the node's
        // inner children (consecutive from `first`): the nearest is next,
        // the rest become the pending group, and the group they replace is
        // the one stack push of this step.
        uint first = nd.first;
        uint n = 0u, ranks = 0u;
        for (int i = 0; i < 4; ++i) {
            bool take = cnt[i] == 0u && d[i] < PB_INF && d[i] <= tmax; // a miss or unused slot is +inf, tmax may be too
            ranks |= take ? ch[i] << (2u * n) : 0u;
            n += take ? 1u : 0u;
        }
        if (n != 0u) {
            node = first + (ranks & 3u);
            if (n > 1u) {
                if (PB_GROUP_COUNT(group) != 0u)
                    stack[sp++] = group;
                group = PB_GROUP(first, n - 1u, ranks >> 2u);
            }
        } else {
            if (PB_GROUP_COUNT(group) == 0u) {
                if (sp == 0u)
                    break;
                group = stack[--sp];
            }
            node = (group >> 8u) + (group & 3u);
            group = PB_GROUP(group >> 8u, PB_GROUP_COUNT(group) - 1u, (group & 63u) >> 2u);
        }
    }
    return res;
}

#endif
