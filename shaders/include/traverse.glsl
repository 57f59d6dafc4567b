// BVH traversal: src/bvh/bvh_traverse.c in GLSL. Child-pair nodes; a leaf's
// triangles are tested as soon as its box is hit; the nearer inner child is
// visited first and the farther one pushed. At most one entry per level is
// ever on the stack, and STACK_SIZE (a specialisation constant) is the BVH's
// depth + 1, so the stack cannot overflow.
#ifndef PB_TRAVERSE_GLSL
#define PB_TRAVERSE_GLSL

#include "scene.glsl"
#include "intersect.glsl"
#include "alpha.glsl"

layout(constant_id = 0) const uint STACK_SIZE = 64u;

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
    uint stack[STACK_SIZE];
    uint sp = 0u;
    uint node = 0u;
    for (;;) {
#ifdef PB_COUNT_TRAVERSALS
        ++pb_loop_steps;
#endif
        Node nd = load_node(s.nodes, node);
        float d[2];
        d[0] = nd.c.x == -1 ? PB_INF : ray_box(r, vec3(nd.x.x, nd.y.x, nd.z.x), vec3(nd.x.y, nd.y.y, nd.z.y), tmin, tmax);
        d[1] = nd.c.y == -1 ? PB_INF : ray_box(r, vec3(nd.x.z, nd.y.z, nd.z.z), vec3(nd.x.w, nd.y.w, nd.z.w), tmin, tmax);
        for (int sl = 0; sl < 2; ++sl) {
            uint count = uint(nd.c[2 + sl]);
            if (count == 0u || !(d[sl] < PB_INF && d[sl] <= tmax))
                continue;
            uint first = uint(nd.c[sl]);
            for (uint k = first; k < first + count; ++k) {
                Tri tri = load_tri(s.tris, k);
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
            d[sl] = PB_INF;
        }
        bool go0 = nd.c.z == 0 && d[0] < PB_INF && d[0] <= tmax; // a miss is +inf, tmax may be too
        bool go1 = nd.c.w == 0 && d[1] < PB_INF && d[1] <= tmax;
        if (go0 && go1) {
            bool near1 = d[1] < d[0];
            stack[sp++] = uint(near1 ? nd.c.x : nd.c.y);
            node = uint(near1 ? nd.c.y : nd.c.x);
        } else if (go0) {
            node = uint(nd.c.x);
        } else if (go1) {
            node = uint(nd.c.y);
        } else {
            if (sp == 0u)
                break;
            node = stack[--sp];
        }
    }
    return res;
}

#endif
