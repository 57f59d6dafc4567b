// A triangle seen from a point, sampled by solid angle (Arvo 1995,
// "Stratified sampling of spherical triangles"): every direction toward it
// equally likely, density 1 / (its solid angle). Area sampling's density
// d^2 / (cos_e area) swings over a triangle close to the point, and the
// light it brings with it; this one does not. Tiny triangles (far away,
// seen edge-on) keep area sampling, where both are alike and differences
// of nearly equal unit vectors below lose their digits. CPU reference:
// src/bake/spherical_triangle.c, same arithmetic in the same order.
// docs/bake.md, "Emitters by solid angle".
#ifndef PB_SPHERICAL_TRIANGLE_GLSL
#define PB_SPHERICAL_TRIANGLE_GLSL

// Solid angles (sr) between which a triangle is sampled by solid angle.
#define PB_SPH_MIN_SOLID_ANGLE 1e-2
#define PB_SPH_MAX_SOLID_ANGLE 6.2

// atan(y, x) for y >= 0, in [0, pi], to float's rounding (6e-8 relative)
// alike on every device and the host: GLSL's atan may be as coarse as 4096
// ulp and differs between drivers, and the solid angle divides the light.
// An odd polynomial on [-tan(pi/8), tan(pi/8)] (least squares, relative
// error), reached by min/max and, above tan(pi/8), the pi/4 shift
// atan(q) = pi/4 + atan((lo - hi) / (lo + hi)): one division either way.
float atan_nonneg(float y, float x)
{
    float ax = abs(x), hi = max(ax, y), lo = min(ax, y);
    if (!(hi > 0.0))
        return 0.0;
    bool shift = lo > 0.41421356 * hi;
    float a = shift ? (lo - hi) / (lo + hi) : lo / hi, base = shift ? 0.78539816 : 0.0;
    precise float w = a * a;
    precise float p = (((-6.092343107e-02 * w + 1.060001552e-01) * w - 1.424448639e-01) * w + 1.999853104e-01) * w -
              3.333331645e-01;
    precise float r = base + (a + a * w * p);
    if (y > ax)
        r = 1.5707963 - r;
    return x < 0.0 ? 3.1415927 - r : r;
}

// sin h and cos h for h in [0, pi] (clamped into it), to float's rounding
// (1e-7) alike on every device and the host: GLSL allows sin and cos an
// absolute error of 2^-11 and drivers differ. Least-squares polynomials on
// [-pi/4, pi/4] for r = h - q pi/2, where h - q (pi/2's float) is exact
// (Sterbenz) before q times its low part; the quadrant q then picks.
vec2 sincos_0_pi(float h)
{
    h = min(max(h, 0.0), 3.14159274);
    float q = h > 2.35619449 ? 2.0 : (h > 0.785398163 ? 1.0 : 0.0);
    precise float r = (h - q * 1.57079637) - q * -4.37113883e-8;
    precise float w = r * r;
    precise float ps = (-1.953543542e-04 * w + 8.332310244e-03) * w - 1.666665673e-01;
    precise float pc = (2.444946222e-05 * w - 1.388745848e-03) * w + 4.166664928e-02;
    precise float sr = r + r * w * ps, cr = (1.0 - 0.5 * w) + w * w * pc;
    return q == 0.0 ? vec2(sr, cr) : (q == 1.0 ? vec2(cr, -sr) : vec2(-sr, -cr));
}

// Solid angle of the triangle (v0, v1, v2) seen from x: Van Oosterom and
// Strackee's formula for the corners p_i = v_i - x of lengths l_i,
// tan(area / 2) = |p0.(p1 x p2)| / (l0 l1 l2 + (p0.p1) l2 + (p1.p2) l0 + (p2.p0) l1),
// no vector normalized. The triple product is taken as
// p0.((v1 - v0) x (v2 - v0)), which keeps its digits where the corners'
// directions nearly share a plane (small or edge-on triangles). `precise`:
// a driver that fuses or reorders these rounds differently from the C
// reference (lavapipe did, by 1e-4 of some probes' light).
float spherical_triangle_area(vec3 x, vec3 v0, vec3 v1, vec3 v2)
{
    vec3 p0 = v0 - x, p1 = v1 - x, p2 = v2 - x;
    float l0 = length(p0), l1 = length(p1), l2 = length(p2);
    precise float num = abs(dot(p0, cross(v1 - v0, v2 - v0)));
    precise float den = l0 * l1 * l2 + dot(p0, p1) * l2 + dot(p1, p2) * l0 + dot(p2, p0) * l1;
    return 2.0 * atan_nonneg(num, den);
}

bool spherical_triangle_sampled(float area)
{
    return area >= PB_SPH_MIN_SOLID_ANGLE && area <= PB_SPH_MAX_SOLID_ANGLE;
}

// A direction toward the triangle (v0, v1, v2) seen from x, uniform over its
// solid angle `area` (spherical_triangle_area) for u1, u2 uniform in [0, 1).
// Arvo's two steps. First the point C' on the arc from A toward C at which
// the triangle A B C' spans u1 x area; where Arvo solves for cos(A, C'),
// whose sine then loses half its digits as C' nears A (7e-4 rad off in
// float), this solves Van Oosterom and Strackee's formula for that triangle
// for tau = tan(angle(A, C') / 2) in closed form, which keeps them:
// tau = (1 + A.B) sin(h) / (k cos(h) - (B.P) sin(h)), h = u1 area / 2, P the
// unit tangent from A toward C, k = |A.(B x P)|. Then a point on the arc
// from B to C' with 1 - cos of its angle from B uniform.
vec3 spherical_triangle_sample(vec3 x, vec3 v0, vec3 v1, vec3 v2, float area, float u1, float u2)
{
    vec3 A = normalize(v0 - x), B = normalize(v1 - x), C = normalize(v2 - x);
    vec3 P = normalize(C - dot(C, A) * A);
    float k = abs(dot(A, cross(B, P))), bp = dot(B, P);
    float h = 0.5 * u1 * area;
    vec2 sc = sincos_0_pi(h);
    float sh = sc.x, ch = sc.y;
    float den = k * ch - bp * sh;
    float tau_c = length(C - A) / length(C + A); // C' = C at u1 = 1
    float tau = (1.0 + dot(A, B)) * sh / den;
    if (!(den > 0.0 && tau < tau_c))
        tau = tau_c;
    float t2 = tau * tau;
    vec3 Cs = ((1.0 - t2) * A + (2.0 * tau) * P) / (1.0 + t2);
    // 1 - cos(B, C') = |C' - B|^2 / 2 keeps its digits when C' is near B
    vec3 d = Cs - B;
    float e = u2 * 0.5 * dot(d, d);
    float z = 1.0 - e;
    vec3 b_perp = Cs - dot(Cs, B) * B;
    float bl = length(b_perp);
    if (!(bl > 0.0))
        return B;
    return normalize(z * B + sqrt(max(0.0, e * (2.0 - e))) / bl * b_perp);
}

#endif
