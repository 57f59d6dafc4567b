#version 460
// render: one invocation per pixel of a row band; spp camera paths per
// pixel, averaged. Modes (include/probebake/render.h):
//   direct     emission seen + light reflected once (shadow rays, NEE, MIS)
//   reference  path traced to `bounces` reflections (the ground truth)
//   probes     direct light (unless the volume holds it) + albedo / pi x the
//              volume's irradiance through the run-time sampler
//   indirect   albedo / pi x the volume's irradiance only
// Adds per pixel the radiance sums (rgb, a = samples whose first hit
// reflects) and the part that reflected at most once; the host divides by
// spp. A dispatch traces a few samples per pixel, not all: llvmpipe caps
// the loop iterations one invocation may run (65535, counted across the
// traversal loops of all its rays) and silently ends loops past it.
// CPU reference: pb_render_cpu (src/render/render_cpu.c).
#extension GL_GOOGLE_include_directive : require

#include "path.glsl"
#include "probe_sample.glsl"

layout(local_size_x = 64) in;

struct RenderParams {
    vec4 eye;
    vec4 forward;       // unit
    vec4 right;         // scaled: tan(fov / 2) x aspect
    vec4 up;            // scaled: tan(fov / 2)
    PbVolumeRefs volume;
    pb_addr image;     // vec4 per pixel
    pb_addr image_direct;
    uint width, height, spp, mode;
    uint seed, bounces, first_row, rows;
    uint volume_direct; // the volume's irradiance includes direct light
    uint first_sample;  // this dispatch traces samples first_sample .. first_sample + sample_count - 1
    uint sample_count;
    uint show_probes;   // draw the volume's probes as spheres (debug view)
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer RenderParamsBuf { RenderParams r; };

layout(push_constant) uniform Push {
    pb_addr bake_params;
    pb_addr render_params;
} pc;

#define MODE_DIRECT 0u
#define MODE_REFERENCE 1u
#define MODE_PROBES 2u
#define MODE_INDIRECT 3u

// Debug view: the nearest probe sphere along the ray, if nearer than t_scene.
// Valid probes are white diffuse spheres lit by their own SH (radiance E/pi
// at the sphere's normal), invalid ones red; a relocated probe's grid
// position shows as a smaller grey sphere. Returns false when none is hit.
bool probe_spheres(vec3 o, vec3 d, float t_scene, out vec3 color)
{
    PbVolumeGrid g = pb_volume_grid(pb_volume);
    float smin = 1e30;
    for (int k = 0; k < 3; ++k)
        if (g.counts[k] > 1)
            smin = min(smin, g.spacing[k]);
    float r = smin < 1e30 ? 0.08 * smin : 0.05;
    // a sparse volume's probes have no grid home: no relocation marker
    int count = pb_volume.levels == 0u ? g.counts.x * g.counts.y * g.counts.z : int(pb_volume.probe_count);
    float best = t_scene;
    bool hit = false;
    color = vec3(0.0);
    for (int p = 0; p < count; ++p) {
        ivec3 ijk = ivec3(p % g.counts.x, (p / g.counts.x) % g.counts.y, p / (g.counts.x * g.counts.y));
        vec3 c = pb_probe_position(p).xyz;
        vec3 home = pb_volume.levels == 0u ? g.origin + vec3(ijk) * g.spacing : c;
        for (int s = 0; s < 2; ++s) {
            vec3 cs = s == 0 ? c : home;
            float rs = s == 0 ? r : 0.5 * r;
            if (s == 1 && distance(c, home) <= r)
                break; // not relocated (visibly)
            vec3 oc = o - cs;
            float b = dot(oc, d), c2 = dot(oc, oc) - rs * rs, disc = b * b - c2;
            if (disc < 0.0)
                continue;
            float t = -b - sqrt(disc);
            if (!(t > 0.0 && t < best))
                continue;
            best = t;
            hit = true;
            vec3 n = normalize(o + t * d - cs);
            if (s == 1)
                color = vec3(0.3);
            else if ((pb_probe_flags(p) & PB_SAMPLE_PROBE_VALID) == 0u)
                color = vec3(1.0, 0.05, 0.05);
            else
                color = max(pb_sh_irradiance(p, n), vec3(0.0)) / PB_PI;
        }
    }
    return hit;
}

void main()
{
    BakeParams P = BakeParamsBuf(pc.bake_params).p;
    RenderParams R = RenderParamsBuf(pc.render_params).r;
    uint i = gl_GlobalInvocationID.x;
    if (i >= R.width * R.rows)
        return;
    uint px = i % R.width, py = R.first_row + i / R.width;
    pb_volume = R.volume;
    vec3 sum = vec3(0.0), sum_direct = vec3(0.0);
    float surface = 0.0;
    for (uint k = R.first_sample; k < R.first_sample + R.sample_count; ++k) {
        uint state = rng_seed(R.seed, py * R.width + px, k, 0x52454e44u);
        float jx = R.spp == 1u ? 0.5 : rng_next(state), jy = R.spp == 1u ? 0.5 : rng_next(state);
        float sx = (float(px) + jx) / float(R.width) * 2.0 - 1.0;
        float sy = 1.0 - (float(py) + jy) / float(R.height) * 2.0;
        vec3 dir = normalize(R.forward.xyz + sx * R.right.xyz + sy * R.up.xyz);
        uint bounces = R.mode == MODE_REFERENCE ? R.bounces : 0u;
        PathResult pr = path_radiance(P, R.eye.xyz, dir, bounces, true, false, state);
        vec3 L = pr.L, Ld = pr.L_direct;
        if (R.mode == MODE_PROBES || R.mode == MODE_INDIRECT) {
            vec3 V = vec3(0.0);
            if (pr.shade)
                V = pr.albedo / PB_PI * pb_volume_irradiance(pb_volume, pr.x, pr.n, -dir);
            if (R.mode == MODE_INDIRECT)
                L = V;
            else
                L = (R.volume_direct != 0u ? pr.L_seen : pr.L) + V;
        }
        if (R.show_probes != 0u) {
            vec3 c;
            if (probe_spheres(R.eye.xyz, dir, isinf(pr.first_t) ? PB_INF : abs(pr.first_t), c))
                L = c;
        }
        sum += L;
        sum_direct += Ld;
        surface += pr.shade ? 1.0 : 0.0;
    }
    uint pixel = py * R.width + px;
    vec4 acc = vec4(sum, surface), acc_direct = vec4(sum_direct, 0.0);
    if (R.first_sample > 0u) {
        acc += Vec4RW(R.image).v[pixel];
        acc_direct += Vec4RW(R.image_direct).v[pixel];
    }
    Vec4RW(R.image).v[pixel] = acc;
    Vec4RW(R.image_direct).v[pixel] = acc_direct;
}
