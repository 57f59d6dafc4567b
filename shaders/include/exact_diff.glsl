// a*b - c*d exactly, rounded once to float, in 32-bit integer words: no
// shaderFloat64, no shaderInt64, no reliance on fma() being fused or on
// denormals being kept. src/bvh/exact_diff.h is the reference (why, and the
// exact definition of the result); both round the exact value to
// nearest-even and agree bit for bit. 128-bit values are uvec4, x lowest.
#ifndef PB_EXACT_DIFF_GLSL
#define PB_EXACT_DIFF_GLSL

#define PB_EXACT_MAX_SHIFT 80u

// (lo, hi) 64-bit value shifted left by k <= 80, as 128 bits.
uvec4 exact_shl(uvec2 v, uint k)
{
    uint ws = k >> 5u, bs = k & 31u;
    uint w[4] = uint[4](v.x, v.y, 0u, 0u);
    uvec4 r = uvec4(0u);
    for (uint j = ws; j < 4u; ++j) {
        uint lo = w[j - ws] << bs;
        uint carry = (bs != 0u && j > ws) ? w[j - ws - 1u] >> (32u - bs) : 0u;
        r[j] = lo | carry;
    }
    return r;
}

bool exact_ge(uvec4 a, uvec4 b)
{
    for (int i = 3; i >= 0; --i)
        if (a[i] != b[i])
            return a[i] > b[i];
    return true;
}

uvec4 exact_add(uvec4 a, uvec4 b)
{
    uvec4 r;
    uint c = 0u, c1, c2;
    for (int i = 0; i < 4; ++i) {
        uint s = uaddCarry(a[i], b[i], c1);
        r[i] = uaddCarry(s, c, c2);
        c = c1 + c2;
    }
    return r;
}

uvec4 exact_sub(uvec4 a, uvec4 b) // a >= b
{
    uvec4 r;
    uint br = 0u, b1, b2;
    for (int i = 0; i < 4; ++i) {
        uint s = usubBorrow(a[i], b[i], b1);
        r[i] = usubBorrow(s, br, b2);
        br = b1 + b2;
    }
    return r;
}

float exact_diff(float a, float b, float c, float d)
{
    float inp[4] = float[4](a, b, c, d);
    uint m[4], s[4];
    int e[4];
    for (int i = 0; i < 4; ++i) {
        uint bits = floatBitsToUint(inp[i]);
        uint ex = (bits >> 23u) & 0xffu;
        if (ex == 0xffu) {
            precise float r = a * b - c * d;
            return r;
        }
        s[i] = bits >> 31u;
        m[i] = (bits & 0x7fffffu) | (ex != 0u ? 0x800000u : 0u);
        e[i] = (ex != 0u ? int(ex) : 1) - 150; // value = m * 2^e
    }
    uvec2 P, Q;
    umulExtended(m[0], m[1], P.y, P.x);
    umulExtended(m[2], m[3], Q.y, Q.x);
    int ep = e[0] + e[1], eq = e[2] + e[3];
    uint sp = s[0] ^ s[1], sq = s[2] ^ s[3] ^ 1u; // signs of +ab and -cd
    bool pz = (P.x | P.y) == 0u, qz = (Q.x | Q.y) == 0u;
    if (pz && qz)
        return 0.0;
    if (pz)
        ep = eq;
    if (qz)
        eq = ep;
    uvec4 X, Y;
    int e0;
    if (ep >= eq) {
        uint k = uint(ep - eq);
        if (k > PB_EXACT_MAX_SHIFT) {
            k = PB_EXACT_MAX_SHIFT;
            Q = uvec2(qz ? 0u : 1u, 0u);
        }
        X = exact_shl(P, k);
        Y = uvec4(Q, 0u, 0u);
        e0 = ep - int(k);
    } else {
        uint k = uint(eq - ep);
        if (k > PB_EXACT_MAX_SHIFT) {
            k = PB_EXACT_MAX_SHIFT;
            P = uvec2(pz ? 0u : 1u, 0u);
        }
        X = uvec4(P, 0u, 0u);
        Y = exact_shl(Q, k);
        e0 = eq - int(k);
    }
    uvec4 M;
    uint sign;
    if (sp == sq) {
        M = exact_add(X, Y);
        sign = sp;
    } else if (exact_ge(X, Y)) {
        M = exact_sub(X, Y);
        sign = sp;
    } else {
        M = exact_sub(Y, X);
        sign = sq;
    }
    int top = M.w != 0u ? 3 : M.z != 0u ? 2 : M.y != 0u ? 1 : 0;
    if (M[top] == 0u)
        return 0.0;
    int h = 32 * top + findMSB(M[top]);
    uint mant;
    if (h <= 23) {
        mant = M.x << uint(23 - h);
    } else {
        uint sh = uint(h - 23);
        uint w = sh >> 5u, bs = sh & 31u;
        mant = M[w] >> bs;
        if (bs != 0u && w < 3u)
            mant |= M[w + 1u] << (32u - bs);
        mant &= 0xffffffu;
        uint g = sh - 1u; // guard bit position
        uint guard = (M[g >> 5u] >> (g & 31u)) & 1u;
        bool sticky = false;
        for (uint i = 0u; i < 4u; ++i) {
            uint lo = 32u * i;
            if (lo >= g)
                break;
            uint nb = min(g - lo, 32u);
            uint mask = nb == 32u ? 0xffffffffu : (1u << nb) - 1u;
            sticky = sticky || (M[i] & mask) != 0u;
        }
        if (guard != 0u && (sticky || (mant & 1u) != 0u))
            ++mant;
        if (mant == 0x1000000u) {
            mant >>= 1u;
            ++h;
        }
    }
    int x = e0 + h; // exponent of the leading bit
    if (x < -126)
        return sign != 0u ? -1e-37 : 1e-37;
    if (x > 127)
        return uintBitsToFloat((sign << 31u) | 0x7f800000u);
    return uintBitsToFloat((sign << 31u) | (uint(x + 127) << 23u) | (mant & 0x7fffffu));
}

#endif
