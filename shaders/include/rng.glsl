// Random numbers: src/bake/probe_rays.c (pb_hash32, pb_random01) and
// src/bake/bake_cpu.c (rng_next). Integer-only, so CPU and GPU draw the same
// numbers; every stream is keyed on (seed, probe, pass, ray).
#ifndef PB_RNG_GLSL
#define PB_RNG_GLSL

uint pb_hash32(uint x)
{
    uint state = x * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

uint rng_seed(uint seed, uint probe, uint pass_index, uint ray)
{
    return pb_hash32(seed ^ pb_hash32(probe ^ pb_hash32(pass_index ^ pb_hash32(ray))));
}

float rng_next(inout uint state)
{
    state = pb_hash32(state);
    return float(state >> 8) * (1.0 / 16777216.0);
}

#endif
