// Run-time sampling of a probebake volume: irradiance at a shading point
// from the 8-probe cage around it (docs/sampling.md). Written in the common
// subset of Vulkan GLSL 4.60 and GLSL ES 3.00, so the same text serves the
// baker (probe_sample.glsl), WebGL2 (runtime/probe_sample.glsl) and any
// renderer. C reference: src/bake/probe_sample.c (pb_sample_cpu).
//
// The includer defines, over its own storage:
//   vec4 pb_probe_position(int probe)            relocated position (xyz), same frame as p
//   uint pb_probe_flags(int probe)               PB_PROBE_* of docs/format.md
//   vec3 pb_probe_sh(int probe, int k)           irradiance SH coefficient k (RGB)
//   vec2 pb_probe_depth(int probe, ivec2 texel)  (mean, mean squared) distance in depth units
//                                                (PbVolumeGrid.depth_unit metres), bordered tile texel
#ifndef PB_PROBE_SAMPLE_CORE_GLSL
#define PB_PROBE_SAMPLE_CORE_GLSL

#define PB_SAMPLE_PROBE_VALID 1u

struct PbVolumeGrid {
    vec3 origin;        // probe (0,0,0) before relocation, same frame as the shading points
    vec3 spacing;       // metres per cell on each axis (unused on axes with one probe)
    ivec3 counts;       // probes per axis, x fastest
    int octmap_res;     // n: interior texels per side of a depth tile
    float normal_bias;  // shading point moved along the normal by this x the smallest spacing
    float view_bias;    // and towards the viewer by this x the smallest spacing
    float depth_unit;   // metres per depth unit of pb_probe_depth (a power of two; docs/format.md)
};

// Octahedral encoding (Cigolle et al. 2014), +Z hemisphere in the centre.
vec2 pb_oct_encode(vec3 d)
{
    float l1 = abs(d.x) + abs(d.y) + abs(d.z);
    vec2 uv = d.xy / l1;
    if (d.z < 0.0) {
        vec2 s = vec2(uv.x >= 0.0 ? 1.0 : -1.0, uv.y >= 0.0 ? 1.0 : -1.0);
        uv = (1.0 - abs(uv.yx)) * s;
    }
    return uv;
}

// Irradiance SH L2 (basis order and constants of docs/conventions.md) at normal n.
vec3 pb_sh_irradiance(int probe, vec3 n)
{
    vec3 e = pb_probe_sh(probe, 0) * 0.28209479177387814;
    e += pb_probe_sh(probe, 1) * (0.48860251190291992 * n.y);
    e += pb_probe_sh(probe, 2) * (0.48860251190291992 * n.z);
    e += pb_probe_sh(probe, 3) * (0.48860251190291992 * n.x);
    e += pb_probe_sh(probe, 4) * (1.09254843059207907 * n.x * n.y);
    e += pb_probe_sh(probe, 5) * (1.09254843059207907 * n.y * n.z);
    e += pb_probe_sh(probe, 6) * (0.31539156525252005 * (3.0 * n.z * n.z - 1.0));
    e += pb_probe_sh(probe, 7) * (1.09254843059207907 * n.x * n.z);
    e += pb_probe_sh(probe, 8) * (0.54627421529603953 * (n.x * n.x - n.y * n.y));
    return e;
}

// Depth moments towards dir, bilinear over the bordered tile (the border
// makes the four texels valid across the octahedral folds).
vec2 pb_depth_moments(int probe, int n, vec3 dir)
{
    vec2 f = (pb_oct_encode(dir) * 0.5 + 0.5) * float(n) + 0.5;
    vec2 i0 = clamp(floor(f), vec2(0.0), vec2(float(n)));
    vec2 t = clamp(f - i0, vec2(0.0), vec2(1.0));
    ivec2 b = ivec2(i0);
    vec2 m00 = pb_probe_depth(probe, b);
    vec2 m10 = pb_probe_depth(probe, b + ivec2(1, 0));
    vec2 m01 = pb_probe_depth(probe, b + ivec2(0, 1));
    vec2 m11 = pb_probe_depth(probe, b + ivec2(1, 1));
    return mix(mix(m00, m10, t.x), mix(m01, m11, t.x), t.y);
}

// Chebyshev's bound on the chance that the point at distance r is visible
// from the probe, given the mean and mean square of its depth; cubed to
// sharpen the falloff (as DDGI does). 1 in front of the mean.
float pb_chebyshev(vec2 m, float r)
{
    if (r <= m.x)
        return 1.0;
    float var = abs(m.y - m.x * m.x);
    float d = r - m.x;
    float c = var / (var + d * d);
    return c * c * c;
}

#ifdef PB_SPARSE
int pb_brick_probe(int brick, int local);
#endif

// Probe at cage corner ijk: in a grid its index, in a brick (brick >= 0)
// the probe the brick names there.
int pb_cage_probe(PbVolumeGrid g, int brick, ivec3 ijk)
{
    int local = ijk.x + g.counts.x * (ijk.y + g.counts.y * ijk.z);
#ifdef PB_SPARSE
    if (brick >= 0)
        return pb_brick_probe(brick, local);
#endif
    return local;
}

// Irradiance at point p with unit normal n, seen from unit direction v
// (from p towards the viewer; pass n where there is no viewer), from the
// cage of grid g (brick < 0) or of brick number brick, a 4 x 4 x 4 grid g.
vec3 pb_sample_cage(PbVolumeGrid g, int brick, vec3 p, vec3 n, vec3 v)
{
    float smin = 1e30;
    for (int k = 0; k < 3; ++k)
        if (g.counts[k] > 1)
            smin = min(smin, g.spacing[k]);
    if (smin >= 1e30)
        smin = 0.0; // a single probe: no scale to bias by
    vec3 biased = p + (n * g.normal_bias + v * g.view_bias) * smin;
    vec3 rel = vec3(0.0);
    for (int k = 0; k < 3; ++k)
        rel[k] = g.counts[k] > 1 ? (biased[k] - g.origin[k]) / g.spacing[k] : 0.0;
    ivec3 base = clamp(ivec3(floor(rel)), ivec3(0), max(g.counts - 2, ivec3(0)));
    vec3 alpha = clamp(rel - vec3(base), vec3(0.0), vec3(1.0));
    vec3 sum = vec3(0.0), sum_tri = vec3(0.0);
    float wsum = 0.0, wsum_tri = 0.0;
    for (int i = 0; i < 8; ++i) {
        ivec3 off = ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        ivec3 ijk = min(base + off, g.counts - 1);
        int probe = pb_cage_probe(g, brick, ijk);
        vec3 tri3 = mix(1.0 - alpha, alpha, vec3(off));
        float wt = tri3.x * tri3.y * tri3.z;
        vec3 e = pb_sh_irradiance(probe, n);
        sum_tri += wt * e;
        wsum_tri += wt;
        if ((pb_probe_flags(probe) & PB_SAMPLE_PROBE_VALID) == 0u)
            continue; // inside geometry: its value was dilated, its depth is meaningless
        vec3 pp = pb_probe_position(probe).xyz;
        // smooth backface term: probes behind the surface count less
        vec3 to_probe = pp - p;
        float dl = length(to_probe);
        float wb = (dl > 0.0 ? dot(to_probe / dl, n) : 1.0) * 0.5 + 0.5;
        float w = wb * wb + 0.2;
        // visibility from the probe's depth moments
        vec3 from_probe = biased - pp;
        float r = length(from_probe);
        vec2 m = pb_depth_moments(probe, g.octmap_res, r > 0.0 ? from_probe / r : n);
        w *= pb_chebyshev(m, r / g.depth_unit); // the moments are in depth units
        w = max(w, 1e-6);
        // crush tiny weights: a probe that barely counts should not count at all
        if (w < 0.2)
            w *= w * w * 25.0;
        w *= wt;
        sum += w * e;
        wsum += w;
    }
    // all eight probes invalid or weightless: plain trilinear of their (dilated) values
    vec3 e = wsum > 0.0 ? sum / wsum : (wsum_tri > 0.0 ? sum_tri / wsum_tri : vec3(0.0));
    return max(e, vec3(0.0)); // SH ringing can go negative; light cannot
}

// Irradiance from a grid volume (pb_sample_cage over the whole grid).
vec3 pb_sample_irradiance(PbVolumeGrid g, vec3 p, vec3 n, vec3 v)
{
    return pb_sample_cage(g, -1, p, n, v);
}

#ifdef PB_SPARSE
// Sparse volumes (docs/sparse.md): the includer defines
//   uint pb_sparse_word(int i)   word i of the layout tables: four offsets
//                                (indirection, chunks, bricks, brick probes),
//                                then the tables (src/sample/probe_sample.c)
#define PB_SPARSE_EMPTY 0x0fffffffu

int pb_brick_probe(int brick, int local)
{
    return int(pb_sparse_word(int(pb_sparse_word(3)) + 64 * brick + local));
}

// The finest brick whose cell covers u (in coarsest-cell units from the
// lattice origin, clamped into the cells), or -1.
int pb_sparse_brick_at(vec3 u, ivec3 cells)
{
    vec3 c = clamp(floor(u), vec3(0.0), vec3(cells) - 1.0);
    vec3 f = clamp(u - c, vec3(0.0), vec3(1.0));
    ivec3 ci = ivec3(c);
    uint e = pb_sparse_word(int(pb_sparse_word(0)) + ci.x + cells.x * (ci.y + cells.y * ci.z));
    uint d = e >> 28u;
    uint b = e & PB_SPARSE_EMPTY;
    if (d != 0u) {
        int m = d == 1u ? 3 : 9;
        ivec3 s = clamp(ivec3(floor(f * float(m))), ivec3(0), ivec3(m - 1));
        b = pb_sparse_word(int(pb_sparse_word(1)) + int(b) + s.x + m * (s.y + m * s.z));
    }
    return b == PB_SPARSE_EMPTY ? -1 : int(b);
}

// Irradiance from a sparse volume: g.origin is the lattice origin, g.spacing
// the finest level's, g.counts the cells; levels is 1 to 3. The brick
// serving p (finest available) is sampled as a 4 x 4 x 4 grid; no brick
// (solid or outside): black.
vec3 pb_sample_sparse(PbVolumeGrid g, int levels, vec3 p, vec3 n, vec3 v)
{
    int span = levels == 1 ? 3 : (levels == 2 ? 9 : 27); // finest cells per coarsest brick
    vec3 cell = g.spacing * float(span);
    // the brick is looked up where its cage is interpolated, at the biased
    // point: looked up at p, a point near a brick face would be served by a
    // cage it lies outside of (clamped), a seam across level boundaries
    float fmin = min(g.spacing.x, min(g.spacing.y, g.spacing.z));
    vec3 pb = p + (n * g.normal_bias + v * g.view_bias) * fmin;
    int b = pb_sparse_brick_at((pb - g.origin) / cell, g.counts);
    if (b < 0)
        return vec3(0.0);
    int at = int(pb_sparse_word(2)) + 4 * b;
    int level = int(pb_sparse_word(at + 3));
    int step = levels - 1 - level == 0 ? 1 : (levels - 1 - level == 1 ? 3 : 9);
    ivec3 coord = ivec3(int(pb_sparse_word(at)), int(pb_sparse_word(at + 1)), int(pb_sparse_word(at + 2)));
    PbVolumeGrid bg = g;
    bg.origin = g.origin + vec3(3 * step * coord) * g.spacing;
    bg.spacing = g.spacing * float(step);
    bg.counts = ivec3(4);
    // the bias stays a fraction of the finest spacing: scaled by a coarse
    // brick's it would carry the point through walls (leaks)
    bg.normal_bias = g.normal_bias / float(step);
    bg.view_bias = g.view_bias / float(step);
    return pb_sample_cage(bg, b, p, n, v);
}
#endif

#endif
