// Path guiding (src/bake/guide.h): the learned cache of where light comes
// from, per grid cell and dominant normal axis (an index of slots), 64
// equal-area octahedral bins per learned slot; bounce directions come from a mixture of it and the cosine
// lobe. CPU reference: src/bake/guide.c.
#ifndef PB_GUIDE_GLSL
#define PB_GUIDE_GLSL

#define PB_GUIDE_BINS 64u
#define PB_GUIDE_SHARE 0.5

// Equal-area octahedral map (Clarberg 2008): [0,1]^2 <-> unit sphere.
vec3 equal_area_decode(float s, float t)
{
    float u = 2.0 * s - 1.0, v = 2.0 * t - 1.0, au = abs(u), av = abs(v);
    float d = 1.0 - (au + av), r = 1.0 - abs(d);
    float phi = (r == 0.0 ? 1.0 : (av - au) / r + 1.0) * (3.14159265358979324 / 4.0);
    float z = d < 0.0 ? -(1.0 - r * r) : 1.0 - r * r;
    float sr = r * sqrt(max(0.0, 2.0 - r * r));
    return vec3((u < 0.0 ? -1.0 : 1.0) * sr * cos(phi), (v < 0.0 ? -1.0 : 1.0) * sr * sin(phi), z);
}

uint guide_bin(vec3 dir)
{
    float ax = abs(dir.x), ay = abs(dir.y), az = abs(dir.z);
    float r = sqrt(max(0.0, 1.0 - az));
    float phi = ax == 0.0 && ay == 0.0 ? 0.0 : atan(ay, ax);
    float v = phi * (2.0 / 3.14159265358979324) * r, u = r - v;
    if (dir.z < 0.0) {
        float tu = u;
        u = 1.0 - v;
        v = 1.0 - tu;
    }
    u = dir.x < 0.0 ? -u : u;
    v = dir.y < 0.0 ? -v : v;
    float s = 0.5 * (u + 1.0), t = 0.5 * (v + 1.0);
    uint bx = uint(min(max(s * 8.0, 0.0), 7.0)), by = uint(min(max(t * 8.0, 0.0), 7.0));
    return by * 8u + bx;
}

// The learned slot for a point and its normal, or -1.
int guide_entry(BakeParams P, vec3 x, vec3 n)
{
    if (!bake_feature(PB_FEATURE_GUIDE) || addr_null(P.guide))
        return -1;
    vec3 a = abs(n);
    uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
    uint cls = 2u * axis + (n[axis] < 0.0 ? 1u : 0u);
    uint e = grid_cell(x, P.guide_origin, P.guide_dims.xyz) * 6u + cls;
    uint slot = UintBuf(P.guide_slots).v[e];
    return slot == 0xffffffffu ? -1 : int(slot);
}

vec3 guide_sample(BakeParams P, int slot, float u1, float u2, float u3)
{
    Vec4Buf table = Vec4Buf(P.guide);
    uint base = uint(slot) * PB_GUIDE_BINS;
    float xb = u1 * float(PB_GUIDE_BINS);
    uint i = min(uint(xb), PB_GUIDE_BINS - 1u);
    vec4 b = table.v[base + i];
    uint bin = xb - float(i) < b.x ? i : floatBitsToUint(b.y);
    return equal_area_decode((float(bin % 8u) + u2) * 0.125, (float(bin / 8u) + u3) * 0.125);
}

float guide_pdf(BakeParams P, int slot, vec3 dir)
{
    return Vec4Buf(P.guide).v[uint(slot) * PB_GUIDE_BINS + guide_bin(dir)].z * (float(PB_GUIDE_BINS) / (4.0 * 3.14159265358979324));
}

// The density with which a vertex's bounce draws w (cos_x: its cosine to
// the normal): the cosine lobe, or the mixture where slot ge is learned.
float bounce_pdf(BakeParams P, int ge, float cos_x, vec3 w)
{
    float pc = max(cos_x, 0.0) / 3.14159265358979324;
    return ge < 0 ? pc : (1.0 - PB_GUIDE_SHARE) * pc + PB_GUIDE_SHARE * guide_pdf(P, ge, w);
}

#endif
