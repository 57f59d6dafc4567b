// Robust secondary-ray origin (Wächter & Binder 2019): src/bvh/ray_offset.c.
// Far from the origin the point moves along the normal by a number of float
// ulps (integer steps on the bit pattern) proportional to the normal
// component; within 1/32 of the origin by a fixed 2^-16 along the normal.
#ifndef PB_RAY_OFFSET_GLSL
#define PB_RAY_OFFSET_GLSL

#define PB_OFFSET_ORIGIN (1.0 / 32.0)
#define PB_OFFSET_FLOAT_SCALE (1.0 / 65536.0)
#define PB_OFFSET_INT_SCALE 256.0

vec3 offset_ray_origin(vec3 p, vec3 n)
{
    vec3 o;
    for (int k = 0; k < 3; ++k) {
        precise float scaled = PB_OFFSET_INT_SCALE * n[k];
        int of = int(scaled);
        int bits = floatBitsToInt(p[k]) + (p[k] < 0.0 ? -of : of);
        precise float near_origin = p[k] + PB_OFFSET_FLOAT_SCALE * n[k];
        o[k] = abs(p[k]) < PB_OFFSET_ORIGIN ? near_origin : intBitsToFloat(bits);
    }
    return o;
}

#endif
