// Run-time sampling, Vulkan GLSL: probe data in buffers reached by device
// address. Set pb_volume (a private global) before calling
// pb_volume_irradiance; the sampling itself is probe_sample_core.glsl.
// Layout (src/bake/probe_sample.c, pb_sample_volume): per probe a vec4
// (position, flags as uint bits), 27 floats of irradiance SH (coefficient
// major, RGB), and (n+2)^2 uints per depth tile, each two halves
// (mean, mean squared) in depth units as in the volume file.
#ifndef PB_PROBE_SAMPLE_GLSL
#define PB_PROBE_SAMPLE_GLSL

#include "address.glsl"

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer PbVec4Buf { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer PbFloatBuf { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer PbUintBuf { uint v[]; };

struct PbVolumeRefs {
    pb_addr probes;    // vec4 per probe
    pb_addr sh;        // 27 floats per probe
    pb_addr depth;     // (n+2)^2 uints per probe
    float depth_unit;   // metres per depth unit of the tiles
    uint levels;        // 0: a grid; 1-3: a sparse volume of that many levels
    vec4 origin_nbias;  // grid (or lattice) origin, normal bias
    vec4 spacing_vbias; // grid spacing (sparse: the finest level's), view bias
    ivec4 counts_res;   // probes per axis (sparse: coarsest cells per axis), octmap_res
    pb_addr sparse;    // sparse: the layout tables (uint words, pb_sparse_word)
    uint probe_count;   // sparse: probes (the grid's are its counts)
    uint pad;
};

PbVolumeRefs pb_volume;

vec4 pb_probe_position(int probe)
{
    return PbVec4Buf(pb_volume.probes).v[probe];
}

uint pb_probe_flags(int probe)
{
    return PbUintBuf(pb_volume.probes).v[4 * probe + 3];
}

vec3 pb_probe_sh(int probe, int k)
{
    PbFloatBuf b = PbFloatBuf(pb_volume.sh);
    int i = 27 * probe + 3 * k;
    return vec3(b.v[i], b.v[i + 1], b.v[i + 2]);
}

vec2 pb_probe_depth(int probe, ivec2 texel)
{
    int side = pb_volume.counts_res.w + 2;
    return unpackHalf2x16(PbUintBuf(pb_volume.depth).v[side * side * probe + side * texel.y + texel.x]);
}

uint pb_sparse_word(int i)
{
    return PbUintBuf(pb_volume.sparse).v[i];
}

#define PB_SPARSE
#include "probe_sample_core.glsl"

PbVolumeGrid pb_volume_grid(PbVolumeRefs r)
{
    return PbVolumeGrid(r.origin_nbias.xyz, r.spacing_vbias.xyz, r.counts_res.xyz, r.counts_res.w, r.origin_nbias.w,
                        r.spacing_vbias.w, r.depth_unit);
}

// Irradiance at p from the volume r, grid or sparse.
vec3 pb_volume_irradiance(PbVolumeRefs r, vec3 p, vec3 n, vec3 v)
{
    PbVolumeGrid g = pb_volume_grid(r);
    return r.levels == 0u ? pb_sample_irradiance(g, p, n, v) : pb_sample_sparse(g, int(r.levels), p, n, v);
}

#endif
