// Bake data and shading shared by bake_trace.comp and bake_reduce.comp.
// Mirrors src/bake/bake_types.h; the CPU reference is src/bake/bake_cpu.c.
//
// Modelled: Lambertian surfaces, albedo = base colour x texture (nearest
// texel, sRGB decoded) x (1 - metallic); emission = emissive factor x
// strength x emissive texture; KHR_lights_punctual lights (point, spot with
// the glTF cone falloff, directional) with shadow rays and the range window
// glTF recommends; an environment (uniform or an equirectangular map);
// emissive triangles and the environment sampled at every surface hit
// (alias tables) and combined with bounce rays by multiple importance
// sampling (power heuristic). Back faces of single-sided materials are black
// (the ray is inside geometry); alpha-blended surfaces pass light
// stochastically (alpha.glsl), thin glass tinted (glass_step). docs/bake.md.
#ifndef PB_BAKE_GLSL
#define PB_BAKE_GLSL

#include "traverse.glsl"
#include "rng.glsl"
#include "ray_offset.glsl"
#include "environment.glsl"
#include "probe_sample.glsl"

#define PB_PI 3.14159265358979324
#define PB_LIGHT_DIRECTIONAL 0u
#define PB_LIGHT_POINT 1u
#define PB_LIGHT_SPOT 2u

struct ShadeMaterial {
    vec4 base_color;
    vec4 emissive_metallic; // rgb emission (strength applied), w metallic
    ivec4 tex;              // base colour texture, emissive texture, PB_MATERIAL_* bits, transmission (float bits)
    // then (load_normal_map) the normal texture and its scale (float bits), (load_tau_texture) the
    // transmission texture and a word of padding
};
// ShadeMaterial.tex.z bits (src/bake/bake_types.h)
#define PB_MATERIAL_DOUBLE_SIDED 1
#define PB_MATERIAL_TAU_IN_ALPHA 2 // the colour texture's alpha scales transmission (not coverage)

struct Light {
    vec4 position_type;     // xyz local position, w type (as float)
    vec4 direction_range;   // xyz unit direction the light points, w range (0 = infinite)
    vec4 radiance;          // rgb colour x intensity
    vec4 cone;              // x cos(outer), y 1 / max(1e-3, cos(inner) - cos(outer))
};

// Material `index` of the ShadeMaterial array at `materials` (8 64-bit
// words each, src/bake/bake_types.h), its first six words (scene.glsl's
// PB_WORD): on lavapipe a divergent load is one masked load per SIMD lane
// and component, so 64-bit components halve them (bench/RESULTS.md,
// "Shading loads"). The seventh word (the normal map) and the eighth (the
// transmission texture) are read apart, only by scenes with normal maps or
// glass (load_normal_map, load_tau_texture).
ShadeMaterial load_shade_material(pb_addr materials, uint index)
{
    Words64 w = Words64(materials);
    uvec2 wd[6];
    for (uint i = 0u; i < 6u; ++i)
        wd[i] = PB_WORD(w, 8u * index + i);
    ShadeMaterial m;
    m.base_color = uintBitsToFloat(uvec4(wd[0], wd[1]));
    m.emissive_metallic = uintBitsToFloat(uvec4(wd[2], wd[3]));
    m.tex = ivec4(uvec4(wd[4], wd[5]));
    return m;
}

// Material `index`'s normal map: its texture (-1: none) and the scale of
// the sampled normal's X and Y.
struct NormalMap {
    int tex;
    float scale;
};
NormalMap load_normal_map(pb_addr materials, uint index)
{
    uvec2 wd = PB_WORD(Words64(materials), 8u * index + 6u);
    return NormalMap(int(wd.x), uintBitsToFloat(wd.y));
}

// Material `index`'s transmission texture (pb_material.transmission_texture;
// -1: none): its red channel scales transmission per texel.
int load_tau_texture(pb_addr materials, uint index)
{
    return int(PB_WORD(Words64(materials), 8u * index + 7u).x);
}
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer LightBuf { Light l[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Vec4Buf { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4RW { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer FloatRW { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UintRW { uint v[]; };

struct BakeParams {
    SceneRefs scene;
    pb_addr materials;     // ShadeMaterial[]
    pb_addr lights;        // Light[]
    pb_addr probes;        // vec4 per probe slot: local position, w = probe id (uint bits; keys its random numbers)
    pb_addr rotations;     // 3 vec4 rows per probe (this pass)
    pb_addr directions;    // vec4 per ray index: the unrotated spherical Fibonacci set
    pb_addr rays;          // out/in: vec4 per ray: radiance rgb, w = distance (negative: back face)
    pb_addr reduced;       // out: per probe of the submission, see bake_sh.comp
    pb_addr probe_list;    // 0: probes first_probe.. in order; else uint slots, read from first_probe on
    pb_addr emitters;      // Emitter[]: the alias table over emissive triangles by power
    pb_addr emit_pdf;      // float per leaf-ordered triangle: area density when sampled (p_i / area), 0 if not an emitter
    pb_addr env;           // EnvTexel[] (environment.glsl); 0: no environment (black)
    pb_addr counters;      // uint: BVH traversals of this submission are added here; 0: not counted
    pb_addr nee;           // probe NEE: 2 vec4 per ray (weighted radiance / 4pi, 0; direction, 0); 0: off
    vec4 env_rotation;      // x cos, y sin of the environment's rotation about +Y
    uint first_probe;
    uint probe_count;       // in this submission
    uint rays_per_probe;
    uint pass_index;
    uint seed;
    uint bounces;
    uint light_count;
    uint octmap_res;
    float max_distance;
    float lobe_power;
    uint direct;            // 1: light straight from lights and sky included
    float lobe_cutoff;      // depth filter skips rays with cos below this: weight < cutoff^power
    uint emitter_count;
    uint env_width, env_height;
    uint env_count;         // texels to sample; 0: none (black environment)
    PbVolumeRefs volume;    // --indirect volume: the previous bounce's volume (volume.probes 0: none)
    pb_addr light_table;   // Emitter[] over punctual lights (tri = light index, pad = probability)
    uint light_select;      // 1: one punctual light drawn per hit by power; 0: every light
    float indirect_clamp;   // > 0: reflected light is clamped per path contribution to this radiance
    pb_addr guide;          // path guiding: vec4 per learned slot and bin (guide.glsl); 0: off
    pb_addr guide_slots;    // uint per entry: its slot, or ~0 (not learned)
    vec4 guide_origin;      // xyz the grid's corner (local), w 1 / cell size
    uvec4 guide_dims;       // cells per axis
    vec4 light_origin;      // light cells (light_cells.glsl): xyz the grid's corner (local), w 1 / cell size
    uvec4 light_dims;       // cells per axis, w clusters
    pb_addr light_cells;    // vec4 per slot and cluster (alias keep, alias, ratio, 0); 0: off
    pb_addr light_cell_slots; // uint per cell: its slot, or ~0 (by power)
    pb_addr light_clusters; // 2 uint per cluster: first member, member count
    pb_addr light_members;  // Emitter[] in cluster order, alias local to the cluster
    pb_addr light_cluster_of; // uint per leaf-ordered triangle: its cluster
    pb_addr depth_lists;    // the depth filter's ray lists per query cell (src/bake/depth_lists.h)
    pb_addr depth_sum;      // bake_depth's sums over the passes: the address of each block of probe slots
    uint depth_block_probes; // probe slots per block; each holds 2 floats per texel per slot (depth_sums.h)
    uint emitters_by_area;  // 1: emitters sampled by area alone; 0: by solid angle where near (spherical_triangle.glsl)
};

// The estimators and scene features a pipeline is built for (host:
// pb_bake_features in src/bake/bake_features.c). Specialised to a bake's
// mask, the code of what is off is compiled out: lavapipe then neither
// compiles it (each inlined traversal costs pipeline time) nor keeps its
// registers live. The runtime checks stay; the mask only removes code that
// they would skip. Default all on: render.comp and the tests' kernels.
layout(constant_id = 2) const uint PB_BAKE_FEATURES = 0xffffffffu;
#define PB_FEATURE_PROBE_NEE 1u
#define PB_FEATURE_GUIDE 2u
#define PB_FEATURE_LIGHT_CELLS 4u
#define PB_FEATURE_VOLUME 8u
#define PB_FEATURE_LIGHT_SELECT 16u
#define PB_FEATURE_EMITTERS 32u
#define PB_FEATURE_ENVIRONMENT 64u
#define PB_FEATURE_LIGHTS 128u
#define PB_FEATURE_VERTEX_COLORS 256u
#define PB_FEATURE_SHADING_NORMALS 512u
#define PB_FEATURE_TRANSMISSION 1024u
#define PB_FEATURE_SOLID_ANGLE 2048u
#define PB_FEATURE_NORMAL_MAPS 4096u

// Pass indices from here on are relocation passes (src/bake/bake_types.h):
// they read only each probe ray's first hit
#define PB_RELOCATION_PASS 0x80000000u

bool bake_feature(uint f)
{
    return (PB_BAKE_FEATURES & f) != 0u;
}

Env bake_env(BakeParams P)
{
    return Env(P.env, P.env_width, P.env_height, bake_feature(PB_FEATURE_ENVIRONMENT) ? P.env_count : 0u,
               P.env_rotation.x, P.env_rotation.y);
}

struct Emitter {
    uint tri;               // leaf-ordered triangle
    float prob;             // alias table: keep this slot with this probability
    uint alias;             // else take this one
    float pad;
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer EmitterBuf { Emitter e[]; };

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer BakeParamsBuf { BakeParams p; };

// The cell of a grid of cubes (corner origin.xyz, 1 / edge origin.w, dims
// per axis) that holds x, clamped into the grid, x fastest: path guiding's
// and light cells' grids (pb_cell_grid_index in src/bake/surface_cells.c).
uint grid_cell(vec3 x, vec4 origin, uvec3 dims)
{
    uvec3 c;
    for (int k = 0; k < 3; ++k) {
        float f = floor((x[k] - origin[k]) * origin.w);
        c[k] = f < 0.0 ? 0u : (f >= float(dims[k]) ? dims[k] - 1u : uint(f));
    }
    return (c.z * dims.y + c.y) * dims.x + c.x;
}

// The probe slot the `local`-th invocation of this submission works on.
uint probe_slot(BakeParams P, uint local)
{
    return !addr_null(P.probe_list) ? UintBuf(P.probe_list).v[P.first_probe + local] : P.first_probe + local;
}

// Read as an integer: small ids are denormal floats, and a float load may
// flush them to zero (lavapipe does), which would give probes one stream.
uint probe_id(BakeParams P, uint slot)
{
    return UintBuf(P.probes).v[4u * slot + 3u];
}

// Ray direction r of a probe in a pass: the probe's rotation rows times the
// unrotated direction, summed in a fixed order. Not `precise`: glslang 12's
// NoContraction propagation from here through the traversal's precise code
// exhausts memory (24 GB) on bake_trace.comp, so a driver may fuse these
// multiply-adds and directions can differ from the C reference by an ulp; the
// bake tests compare with tolerances for that.
vec3 probe_ray_direction(BakeParams P, uint probe, uint ray)
{
    Vec4Buf rot = Vec4Buf(P.rotations);
    vec3 sf = Vec4Buf(P.directions).v[ray].xyz;
    vec3 d;
    for (uint k = 0u; k < 3u; ++k) {
        vec3 row = rot.v[3u * probe + k].xyz;
        d[k] = (row.x * sf.x + row.y * sf.y) + row.z * sf.z;
    }
    return d;
}

vec3 srgb_to_linear(vec3 c)
{
    vec3 lo = c / 12.92;
    vec3 hi = pow((c + 0.055) / 1.055, vec3(2.4));
    return mix(lo, hi, greaterThan(c, vec3(0.04045)));
}

// Texture `tex` at uv, nearest texel: linear colour (sRGB decoded) and alpha;
// white and opaque for no texture.
vec4 texture_rgba(SceneRefs s, int tex, vec2 uv)
{
    if (tex < 0)
        return vec4(1.0);
    uint texel = texture_texel(s, tex, uv);
    vec3 c = vec3(float(texel & 0xffu), float((texel >> 8) & 0xffu), float((texel >> 16) & 0xffu)) / 255.0;
    return vec4(srgb_to_linear(c), float(texel >> 24) * (1.0 / 255.0));
}

vec3 texture_rgb(SceneRefs s, int tex, vec2 uv)
{
    return texture_rgba(s, tex, uv).rgb;
}

// Thin transmissive surfaces (KHR_materials_transmission, docs/bake.md "Thin
// glass"): the traversal meets them as opaque, and the ray's owner decides
// here whether it goes through. A surface of coverage a (alpha: factor x
// texture x vertex colour) and transmission tau lets a ray through with
// probability 1 - a (1 - tau) (the alpha blend's hashed threshold, so CPU
// and GPU decide alike), and on average (1 - a) + a tau c of the light, c
// its base colour there: a ray that passes carries that over its
// probability. CPU reference: glass_step in src/bake/bake_cpu.c.
bool bake_glass(BakeParams P)
{
    return bake_feature(PB_FEATURE_TRANSMISSION) && (P.scene.flags & PB_SCENE_TRANSMISSION) != 0u;
}

// Layers of glass a ray goes through at most; the next one stops it.
#define PB_GLASS_LAYERS 64u

// A glass material's tau at a colour texel of alpha `a`: scaled by it
// where the material keeps its transmission texture there.
// `r`: the transmission texture's red there (tau_red), 1 without one.
float glass_tau(ShadeMaterial m, float a, float r)
{
    float tau = intBitsToFloat(m.tex.w);
    return (m.tex.z & PB_MATERIAL_TAU_IN_ALPHA) != 0 ? tau * a : tau * r;
}

// The red of transmission texture `tt` at uv, 1 for none (tt < 0).
float tau_red(SceneRefs s, int tt, vec2 uv)
{
    return tt >= 0 ? float(texture_texel(s, tt, uv) & 0xffu) * (1.0 / 255.0) : 1.0;
}

// The share of the light meeting a surface that it reflects diffusely, of
// its base colour: 1 - metallic; for thin glass the dielectric part's
// 1 - transmissionFactor over the share that does not pass,
// ((1 - metallic) - tau) / (1 - tau). `a`: the colour texel's alpha, `r`
// the transmission texture's red (glass_tau).
float diffuse_share(ShadeMaterial m, float a, float r)
{
    float keep = 1.0 - m.emissive_metallic.w, tau = glass_tau(m, a, r);
    return tau > 0.0 ? (tau < 1.0 ? max(0.0, keep - tau) / (1.0 - tau) : 0.0) : keep;
}

struct GlassStep {
    bool pass;      // the ray goes on
    vec3 w;         // its tint
    vec3 origin;    // where it goes on from: the hit, offset to the far side
};

GlassStep glass_step(BakeParams P, TraceResult tr, vec3 rd)
{
    GlassStep g;
    g.pass = false;
    g.w = vec3(1.0);
    g.origin = vec3(0.0);
    if (tr.tri == PB_NO_HIT)
        return g;
    SceneRefs s = P.scene;
    Tri t = load_tri(s.tris, tr.tri);
    uint mat = t.flags & ~PB_FLAG_ALPHA_MASK;
    ShadeMaterial m = load_shade_material(P.materials, mat);
    if (!(intBitsToFloat(m.tex.w) > 0.0))
        return g;
    int tt = load_tau_texture(P.materials, mat);
    vec2 uv = m.tex.x >= 0 || tt >= 0 ? surface_uv(s, tr.tri, tr.u, tr.v) : vec2(0.0);
    vec4 tx = m.tex.x >= 0 ? texture_rgba(s, m.tex.x, uv) : vec4(1.0);
    float tau = glass_tau(m, tx.a, tau_red(s, tt, uv));
    if ((m.tex.z & PB_MATERIAL_TAU_IN_ALPHA) != 0)
        tx.a = 1.0; // transmission, not coverage
    vec4 c = m.base_color * tx;
    if ((s.flags & PB_SCENE_VERTEX_COLORS) != 0u)
        c *= vertex_color(s, tr.tri, tr.u, tr.v);
    float opaque = c.a * (1.0 - tau);
    if (opaque > alpha_blend_threshold(mat, tr.u, tr.v))
        return g;
    g.pass = true;
    g.w = ((1.0 - c.a) + c.a * tau * c.rgb) / (1.0 - opaque);
    vec3 e1 = t.v1 - t.v0, e2 = t.v2 - t.v0, n = normalize(cross(e1, e2));
    g.origin = offset_ray_origin(t.v0 + tr.u * e1 + tr.v * e2, dot(n, rd) > 0.0 ? n : -n);
    return g;
}

// One layer of a shadow ray from x along w (to tmax), `layers` layers of
// thin glass passed so far: true when it passed one more, with x, tmax and
// the transmittance T moved past it; false when it is done (T = 0 where
// anything else blocks it). bake_wave.comp steps probe NEE's rays with it.
bool shadow_layer(BakeParams P, inout vec3 x, vec3 w, inout float tmax, inout vec3 T, uint layers)
{
    bool glass = bake_glass(P);
    TraceResult tr = trace_ray(P.scene, x, w, 0.0, tmax, !glass);
    if (tr.tri == PB_NO_HIT)
        return false;
    GlassStep g = glass && layers < PB_GLASS_LAYERS ? glass_step(P, tr, w) : GlassStep(false, vec3(1.0), vec3(0.0));
    if (!g.pass) {
        T = vec3(0.0);
        return false;
    }
    T *= g.w;
    x = g.origin;
    tmax -= tr.t;
    return true;
}

// The share of the light a shadow ray from x along w (to tmax) carries past
// thin glass, per channel; 0 where anything else blocks it.
vec3 shadow_transmittance(BakeParams P, vec3 x, vec3 w, float tmax)
{
    vec3 T = vec3(1.0);
    for (uint layers = 0u; shadow_layer(P, x, w, tmax, T, layers); ++layers) {
    }
    return T;
}

// A shadow ray from a surface point and the light it adds when nothing
// blocks it. tmax < 0: no ray (the sample adds nothing).
struct ShadowRay {
    vec3 w;
    float tmax;
    vec3 L;
};

ShadowRay no_shadow_ray()
{
    ShadowRay r;
    r.w = vec3(0.0, 1.0, 0.0);
    r.tmax = -1.0;
    r.L = vec3(0.0);
    return r;
}

// The irradiance a punctual light gives a surface at x with unit normal n
// (pass n = 0 for a point without orientation: no cosine), as a shadow ray.
ShadowRay light_ray(Light l, vec3 x, vec3 n, bool oriented)
{
    uint type = uint(l.position_type.w);
    vec3 to_light;
    float dist;
    float falloff = 1.0;
    if (type == PB_LIGHT_DIRECTIONAL) {
        to_light = -l.direction_range.xyz;
        dist = PB_INF;
    } else {
        vec3 v = l.position_type.xyz - x;
        float d2 = dot(v, v);
        if (d2 <= 0.0)
            return no_shadow_ray();
        dist = sqrt(d2);
        to_light = v / dist;
        falloff = 1.0 / d2;
        float range = l.direction_range.w;
        if (range > 0.0) {
            float q = dist / range;
            falloff *= clamp(1.0 - q * q * q * q, 0.0, 1.0);
        }
        if (type == PB_LIGHT_SPOT) {
            float cd = dot(l.direction_range.xyz, -to_light);
            float a = clamp((cd - l.cone.x) * l.cone.y, 0.0, 1.0);
            falloff *= a * a;
        }
    }
    float cosine = oriented ? dot(n, to_light) : 1.0;
    if (cosine <= 0.0 || falloff <= 0.0)
        return no_shadow_ray();
    ShadowRay r;
    r.w = to_light;
    r.tmax = dist;
    r.L = l.radiance.rgb * (cosine * falloff);
    return r;
}

// light_ray with its shadow ray traced (through thin glass)
vec3 light_irradiance(BakeParams P, Light l, vec3 x, vec3 n, bool oriented)
{
    ShadowRay r = light_ray(l, x, n, oriented);
    if (r.tmax < 0.0)
        return vec3(0.0);
    return r.L * shadow_transmittance(P, x, r.w, r.tmax);
}

#endif
