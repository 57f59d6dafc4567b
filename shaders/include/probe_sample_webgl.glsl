// Run-time sampling, WebGL2 / GLSL ES 3.00: probe data in textures.
// scripts/make_runtime_glsl.sh inlines probe_sample_core.glsl after this
// into runtime/probe_sample.glsl, the one file a web renderer pastes in.
// Textures (docs/sampling.md has the loader's recipe):
//   pb_probes  RGBA32F: texel i = probe i: relocated position, flags (as a float)
//   pb_sh      RGBA32F: 7 texels per probe: the 27 irradiance SH floats
//              (coefficient major, RGB) and one zero
//   pb_depth   RG16F:   depth tiles of (n+2)^2 texels, pb_depth_tiles_per_row
//              tiles per row; texel = (mean, mean squared) distance in
//              units of pb_depth_unit metres (the file's depth unit)
// Texel i of pb_probes and pb_sh is at (i % pb_tex_width, i / pb_tex_width).
// A sparse volume (bricks, docs/sparse.md): #define PB_SPARSE before this file
// and bind, besides the three above,
//   pb_sparse  R32UI:   the layout tables (pb_sparse_word), word i at texel i
//              as above; pb_levels the volume's levels (1 to 3); the grid
//              uniforms then hold the lattice origin, the finest spacing and
//              the coarsest cells per axis.
precision highp float;
precision highp int;

uniform highp sampler2D pb_probes;
uniform highp sampler2D pb_sh;
uniform highp sampler2D pb_depth;
uniform int pb_tex_width;
uniform int pb_depth_tiles_per_row;
uniform vec3 pb_grid_origin;
uniform vec3 pb_grid_spacing;
uniform ivec3 pb_grid_counts;
uniform int pb_octmap_res;
uniform float pb_normal_bias; // default 0.1 (of the smallest spacing)
uniform float pb_view_bias;   // default 0.1
uniform float pb_depth_unit;  // metres per depth unit: the volume file's (header offset 180)

ivec2 pb_texel_2d(int i)
{
    return ivec2(i % pb_tex_width, i / pb_tex_width);
}

vec4 pb_probe_position(int probe)
{
    return texelFetch(pb_probes, pb_texel_2d(probe), 0);
}

uint pb_probe_flags(int probe)
{
    return uint(texelFetch(pb_probes, pb_texel_2d(probe), 0).w);
}

float pb_sh_float(int probe, int f)
{
    int i = 28 * probe + f;
    vec4 t = texelFetch(pb_sh, pb_texel_2d(i / 4), 0);
    int c = i % 4;
    return c == 0 ? t.x : (c == 1 ? t.y : (c == 2 ? t.z : t.w));
}

vec3 pb_probe_sh(int probe, int k)
{
    return vec3(pb_sh_float(probe, 3 * k), pb_sh_float(probe, 3 * k + 1), pb_sh_float(probe, 3 * k + 2));
}

vec2 pb_probe_depth(int probe, ivec2 texel)
{
    int side = pb_octmap_res + 2;
    ivec2 tile = ivec2(probe % pb_depth_tiles_per_row, probe / pb_depth_tiles_per_row);
    return texelFetch(pb_depth, tile * side + texel, 0).rg;
}

#ifdef PB_SPARSE
uniform highp usampler2D pb_sparse;
uniform int pb_levels;

uint pb_sparse_word(int i)
{
    return texelFetch(pb_sparse, pb_texel_2d(i), 0).r;
}
#endif

// ---- probe_sample_core.glsl follows (inlined) ----
