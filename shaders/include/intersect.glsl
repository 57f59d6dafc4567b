// Ray/box and watertight ray/triangle tests: src/bvh/intersect.h operation
// for operation (see there for why). `precise` forbids FMA contraction and
// reassociation, so every device rounds exactly as the C reference. Edge
// functions are adaptive: float when provably right in sign, else the exact
// value rounded once: in double where the device has shaderFloat64
// (PB_NATIVE64, 8 % faster on lavapipe), else in 32-bit integers
// (exact_diff.glsl). Both give the same float (see edge_exact).
#ifndef PB_INTERSECT_GLSL
#define PB_INTERSECT_GLSL

#extension GL_EXT_control_flow_attributes : require

#include "exact_diff.glsl"

#define PB_FLT_MIN 1.17549435e-38
#define PB_SLAB_MARGIN 1.9073486e-6 // 2^-19: node_boxes' slab widening, see intersect.h

struct RayPre {
    vec3 org;
    vec3 idir;
    int kx, ky, kz;
    float sx, sy, sz;
};

// 1/b as intersect.h's pb_rcp, operation for operation: GLSL's division may
// be 2.5 ulp off and differs between drivers, so no hit value may depend on
// it. Only the box test's 1/dir divides (it need only be conservative).
float pb_rcp(float b)
{
    // Selects, not branches: llvmpipe runs both sides of every branch anyway.
    // The scaling by 2^64 or 2^-64 (|b| outside [2^-100, 2^100]) is exact.
    precise float m = abs(b);
    float s = m < uintBitsToFloat(0x0D800000u) ? uintBitsToFloat(0x5F800000u)
                                               : (m > uintBitsToFloat(0x71800000u) ? uintBitsToFloat(0x1F800000u) : 1.0);
    precise float ms = m * s;
    precise float y = uintBitsToFloat(0x7EF311C3u - floatBitsToUint(ms));
    for (int i = 0; i < 3; ++i) {
        precise float e = 1.0 - ms * y;
        y = y + y * e;
    }
    y *= s;
    y = m == 0.0 ? PB_INF : (isinf(m) ? 0.0 : y); // NaN stays NaN
    return uintBitsToFloat(floatBitsToUint(y) | (floatBitsToUint(b) & 0x80000000u));
}

RayPre ray_prepare(vec3 org, vec3 dir)
{
    RayPre r;
    vec3 ad = abs(dir);
    int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (dir[kz] < 0.0) {
        int t = kx;
        kx = ky;
        ky = t;
    }
    r.kx = kx;
    r.ky = ky;
    r.kz = kz;
    r.sz = pb_rcp(dir[kz]);
    precise float sx = dir[kx] * r.sz;
    precise float sy = dir[ky] * r.sz;
    r.sx = sx;
    r.sy = sy;
    for (int k = 0; k < 3; ++k) {
        float d = dir[k];
        if (abs(d) < 1e-30)
            d = d < 0.0 ? -1e-30 : 1e-30;
        r.idir[k] = 1.0 / d;
    }
    r.org = org;
    return r;
}

// Entry distances of a 4-wide node's child boxes, clipped to [tmin, tmax],
// +inf for a miss or an unused slot: slab distances q * B + A in the node's
// frame, widened by a bound on their rounding (intersect.h's
// pb_ray_node_boxes, operation for operation, and why).
void node_boxes(RayPre r, vec3 origin, vec3 scale, vec4 qlo[3], vec4 qhi[3], uint used, float tmin, float tmax,
                out float d[4])
{
    vec3 an, af, b;
    vec4 qn[3], qf[3];
    for (int k = 0; k < 3; ++k) {
        precise float a = (origin[k] - r.org[k]) * r.idir[k];
        precise float e = PB_SLAB_MARGIN * (abs(a) + (abs(origin[k]) + 256.0 * scale[k]) * abs(r.idir[k]));
        precise float n = a - e;
        precise float f = a + e;
        an[k] = n;
        af[k] = f;
        b[k] = scale[k] * r.idir[k];
        bool flip = r.idir[k] < 0.0; // the hi bound is the near one
        qn[k] = flip ? qhi[k] : qlo[k];
        qf[k] = flip ? qlo[k] : qhi[k];
    }
    for (int i = 0; i < 4; ++i) {
        float t0 = tmin, t1 = tmax;
        for (int k = 0; k < 3; ++k) {
            precise float tn = fma(qn[k][i], b[k], an[k]);
            precise float tf = fma(qf[k][i], b[k], af[k]);
            t0 = tn > t0 ? tn : t0;
            t1 = tf < t1 ? tf : t1;
        }
        d[i] = uint(i) < used && t0 <= t1 ? t0 : PB_INF;
    }
}

// On a hit with tmin < t < tmax: true, t, and barycentrics of v1 (u), v2 (v).
#define PB_EDGE_ERROR_BOUND 2.5e-7 // float rounding bound of a*b - c*d, see intersect.h

// a*b - c*d in float; `sure` when its sign (and so the value the tests use)
// is provably the exact one's
float edge_estimate(float a, float b, float c, float d, out bool sure)
{
    precise float p = a * b;
    precise float q = c * d;
    precise float r = p - q;
    precise float bound = PB_EDGE_ERROR_BOUND * (abs(p) + abs(q));
    sure = abs(r) > bound;
    return r;
}

// a*b - c*d exactly, rounded once to float (where edge_estimate is unsure)
float edge_exact(float a, float b, float c, float d)
{
#ifdef PB_NATIVE64
    // Reached only when a*b and c*d are within a factor 1 + 5e-7 (then the
    // double difference of the exact double products is exact, and one
    // rounding to float is exact_diff's) or both are below float range (then
    // the result is tiny either way).
    precise double e = double(a) * double(b) - double(c) * double(d);
    float f = float(e);
    if (e != 0.0LF && !(abs(f) >= PB_FLT_MIN))
        f = e > 0.0LF ? 1e-37 : -1e-37;
    return f;
#else
    return exact_diff(a, b, c, d);
#endif
}

bool ray_triangle(RayPre r, vec3 v0, vec3 v1, vec3 v2, float tmin, float tmax, out float t, out float u, out float v)
{
    precise vec3 A = v0 - r.org;
    precise vec3 B = v1 - r.org;
    precise vec3 C = v2 - r.org;
    precise float Ax = A[r.kx] - r.sx * A[r.kz];
    precise float Ay = A[r.ky] - r.sy * A[r.kz];
    precise float Bx = B[r.kx] - r.sx * B[r.kz];
    precise float By = B[r.ky] - r.sy * B[r.kz];
    precise float Cx = C[r.kx] - r.sx * C[r.kz];
    precise float Cy = C[r.ky] - r.sy * C[r.kz];
    bool su, sv, sw;
    precise float U = edge_estimate(Cx, By, Cy, Bx, su);
    precise float V = edge_estimate(Ax, Cy, Ay, Cx, sv);
    precise float W = edge_estimate(Bx, Ay, By, Ax, sw);
    if (!(su && sv && sw)) {
        // The exact values, in one loop that is not unrolled: one copy of
        // edge_exact per triangle test, not three (the three doubled the
        // portable bake kernel's compile time on lavapipe; NVIDIA's compiler
        // took 25-50 s over it, 1.3 s over this)
        float q[12] = float[12](Cx, By, Cy, Bx, Ax, Cy, Ay, Cx, Bx, Ay, By, Ax);
        float e[3] = float[3](U, V, W);
        uint unsure = (su ? 0u : 1u) | (sv ? 0u : 2u) | (sw ? 0u : 4u);
        [[dont_unroll]] for (int i = 0; i < 3; ++i)
            if ((unsure & (1u << i)) != 0u)
                e[i] = edge_exact(q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]);
        U = e[0];
        V = e[1];
        W = e[2];
    }
    t = 0.0;
    u = 0.0;
    v = 0.0;
    if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0))
        return false;
    precise float det = U + V + W;
    if (det == 0.0)
        return false;
    precise float Az = r.sz * A[r.kz];
    precise float Bz = r.sz * B[r.kz];
    precise float Cz = r.sz * C[r.kz];
    precise float T = U * Az + V * Bz + W * Cz;
    if (det < 0.0) {
        T = -T;
        det = -det;
        U = -U;
        V = -V;
        W = -W;
    }
    precise float lo = tmin * det;
    precise float hi = tmax * det;
    if (!(T > lo) || !(T < hi))
        return false;
    float inv = pb_rcp(det);
    precise float tt = T * inv;
    precise float uu = V * inv;
    precise float vv = W * inv;
    t = tt;
    u = uu;
    v = vv;
    return true;
}

bool is_backface(vec3 v0, vec3 v1, vec3 v2, vec3 dir)
{
    precise vec3 e1 = v1 - v0;
    precise vec3 e2 = v2 - v0;
    precise vec3 n = vec3(e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x);
    precise float d = n.x * dir.x + n.y * dir.y + n.z * dir.z;
    return d > 0.0;
}

#endif
