// Octahedral mapping: include/probebake/octahedral.h (+Z in the centre).
#ifndef PB_OCTAHEDRAL_GLSL
#define PB_OCTAHEDRAL_GLSL

float sign_not_zero(float v)
{
    return v >= 0.0 ? 1.0 : -1.0;
}

vec3 oct_decode(vec2 uv)
{
    float x = uv.x, y = uv.y, z = 1.0 - abs(x) - abs(y);
    if (z < 0.0) {
        float fx = (1.0 - abs(y)) * sign_not_zero(x);
        float fy = (1.0 - abs(x)) * sign_not_zero(y);
        x = fx;
        y = fy;
    }
    return normalize(vec3(x, y, z));
}

vec3 oct_texel_direction(uint x, uint y, uint n)
{
    return oct_decode(vec2(-1.0 + (2.0 * float(x) + 1.0) / float(n), -1.0 + (2.0 * float(y) + 1.0) / float(n)));
}

#endif
