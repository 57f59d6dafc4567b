// Path tracing shared by the bake (bake_trace.comp) and the renderer
// (render.comp): the radiance arriving along a ray. Emission, punctual lights
// with shadow rays, emissive triangles and the environment sampled at every
// hit and MIS-combined with bounce rays, Lambertian bounces with Russian
// roulette from the second reflection on, and a terminal bounce ray after
// the last reflection (docs/bake.md). CPU reference: path_radiance in
// src/bake/bake_cpu.c.
#ifndef PB_PATH_GLSL
#define PB_PATH_GLSL

#include "traverse.glsl"
#include "bake.glsl"
#include "guide.glsl"
#include "light_cells.glsl"
#include "spherical_triangle.glsl"
#include "normal_map.glsl"

// Multiple importance sampling, power heuristic: the weight of a sample
// drawn with density a when density b could also have drawn it.
// Emissive triangles to sample (alias table over them); false where compiled out.
bool bake_emitters(BakeParams P)
{
    return bake_feature(PB_FEATURE_EMITTERS) && P.emitter_count > 0u;
}

float power_heuristic(float a, float b)
{
    return a * a / (a * a + b * b);
}

vec3 cosine_direction(vec3 n, float u1, float u2)
{
    // orthonormal basis (Duff et al. 2017) and Malley's method
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    vec3 bt = vec3(b, sgn + n.y * n.y * a, -n.y);
    float r = sqrt(u1), phi = 2.0 * PB_PI * u2;
    return normalize(t * (r * cos(phi)) + bt * (r * sin(phi)) + n * sqrt(max(0.0, 1.0 - u1)));
}

// The solid-angle density with which sample_emitter draws a direction
// toward an emitter triangle of area density pa (its probability over its
// area), area tri_area and solid angle sa (0: sampled by area), meeting it
// at distance dist and cosine cos_e.
float emitter_density(float pa, float tri_area, float sa, float dist, float cos_e)
{
    return spherical_triangle_sampled(sa) ? pa * tri_area / sa : pa * dist * dist / cos_e;
}

// The solid angle of emitter triangle t seen from x where the bake samples
// it by solid angle (spherical_triangle.glsl), else 0.
float emitter_solid_angle(BakeParams P, vec3 x, Tri t)
{
    if (!bake_feature(PB_FEATURE_SOLID_ANGLE) || P.emitters_by_area != 0u)
        return 0.0;
    return spherical_triangle_area(x, t.v0, t.v1, t.v2);
}

// One emissive triangle, picked by power (alias table) or from the light
// cell holding x, and a direction toward it: uniform over its solid angle
// where that is large enough, else toward a uniform point on it. Returns the
// direction, the distance to the triangle, its emitted radiance toward x,
// and the solid-angle density of drawing that direction (0 when its back
// faces x or it is degenerate). Three random numbers, a fourth in a light
// cell.
struct EmitterSample {
    vec3 w;
    float dist;
    vec3 Le;
    float pdf;
};

EmitterSample sample_emitter(BakeParams P, vec3 x, inout uint state)
{
    SceneRefs s = P.scene;
    float u0 = rng_next(state), u1 = rng_next(state), u2 = rng_next(state);
    int lc = light_cell(P, x);
    uint etri;
    float ratio = 1.0;
    if (lc >= 0) {
        etri = light_cell_sample(P, lc, u0, rng_next(state), ratio);
    } else {
        EmitterBuf table = EmitterBuf(P.emitters);
        float xe = u0 * float(P.emitter_count);
        uint ei = min(uint(xe), P.emitter_count - 1u);
        Emitter e = table.e[ei];
        etri = xe - float(ei) < e.prob ? e.tri : table.e[e.alias].tri;
    }
    Tri et = load_tri(s.tris, etri);
    vec3 ee1 = et.v1 - et.v0, ee2 = et.v2 - et.v0;
    vec3 ne = cross(ee1, ee2);
    float sa = emitter_solid_angle(P, x, et);
    float b1, b2;
    EmitterSample es;
    if (spherical_triangle_sampled(sa)) {
        es.w = spherical_triangle_sample(x, et.v0, et.v1, et.v2, sa, u1, u2);
        // where it meets the triangle: distance and barycentrics (Moller-Trumbore)
        vec3 pv = cross(es.w, ee2);
        float inv = 1.0 / dot(ee1, pv);
        vec3 tv = x - et.v0;
        vec3 qv = cross(tv, ee1);
        b1 = clamp(dot(tv, pv) * inv, 0.0, 1.0);
        b2 = clamp(dot(es.w, qv) * inv, 0.0, 1.0 - b1);
        es.dist = dot(ee2, qv) * inv;
    } else {
        float su = sqrt(u1);
        b1 = su * (1.0 - u2), b2 = su * u2;
        vec3 to = et.v0 + b1 * ee1 + b2 * ee2 - x;
        es.dist = length(to);
        es.w = to / es.dist;
    }
    ShadeMaterial em = load_shade_material(P.materials, et.flags & ~PB_FLAG_ALPHA_MASK);
    float cos_e = -dot(normalize(ne), es.w);
    if ((em.tex.z & PB_MATERIAL_DOUBLE_SIDED) != 0)
        cos_e = abs(cos_e);
    float pa = FloatBuf(P.emit_pdf).v[etri] * ratio;
    es.pdf = cos_e > 0.0 && es.dist > 0.0 ? emitter_density(pa, 0.5 * length(ne), sa, es.dist, cos_e) : 0.0;
    vec2 yuv = em.tex.y >= 0 ? surface_uv(s, etri, b1, b2) : vec2(0.0);
    es.Le = em.emissive_metallic.rgb * texture_rgb(s, em.tex.y, yuv);
    return es;
}

// Next-event estimation of one emissive triangle (sample_emitter) as a
// shadow ray, MIS-weighted against cosine-weighted bounce sampling (power
// heuristic). ng decides the side light may come from, the shading normal ns
// gives the cosine. Its light is emitted radiance x cos / (pi pdf) x weight: the
// caller multiplies by throughput x albedo. (A function of its own also keeps
// glslang's `precise` analysis of path_radiance small: inlined there, it ran
// out of memory.)
ShadowRay emitter_nee_ray(BakeParams P, vec3 x, vec3 ng, vec3 ns, int ge, inout uint state)
{
    EmitterSample es = sample_emitter(P, x, state);
    float cos_x = dot(ns, es.w);
    if (!(cos_x > 0.0 && dot(ng, es.w) > 0.0 && es.pdf > 0.0))
        return no_shadow_ray();
    float pb = bounce_pdf(P, ge, cos_x, es.w);
    float wl = power_heuristic(es.pdf, pb);
    ShadowRay r;
    r.w = es.w;
    r.tmax = es.dist * 0.9999;
    r.L = es.Le * (cos_x / (PB_PI * es.pdf) * wl);
    return r;
}

// Probe NEE (--probe-nee): the light a probe sees directly (emitters and
// the environment), sampled from the probe by light sampling and
// MIS-combined (power heuristic) with the probe rays that find it (uniform
// over the sphere, density 1 / 4pi). One light sample per ray: an emitter
// with probability probe_emitter_share, else the environment. Returns
// (radiance x weight / (4pi pdf), direction): the SH projection weighs it
// like a probe ray (4pi / rays).
float probe_emitter_share(BakeParams P)
{
    return bake_emitters(P) ? (bake_env(P).count > 0u ? 0.5 : 1.0) : 0.0;
}

// The light sample of probe_light_nee before its shadow ray: the direction
// w, the distance to trace, the radiance and the factor k = weight / (4pi pdf)
// it is scaled by; false when there is none.
bool probe_nee_sample(BakeParams P, vec3 x, inout uint state, out vec3 w, out vec3 L, out float tmax, out float k)
{
    Env env = bake_env(P);
    float share = probe_emitter_share(P);
    float us = rng_next(state);
    float pdf;
    w = vec3(0.0, 1.0, 0.0), L = vec3(0.0), tmax = -1.0, k = 0.0;
    if (us < share) {
        EmitterSample es = sample_emitter(P, x, state);
        w = es.w, L = es.Le, tmax = es.dist * 0.9999, pdf = share * es.pdf;
    } else {
        if (env.count == 0u)
            return false;
        float u0 = rng_next(state), u1 = rng_next(state), u2 = rng_next(state);
        w = env_sample(env, u0, u1, u2).xyz;
        L = env_radiance(env, w), tmax = PB_INF, pdf = (1.0 - share) * env_pdf(env, w);
    }
    if (!(pdf > 0.0))
        return false;
    float wl = power_heuristic(pdf, 1.0 / (4.0 * PB_PI));
    k = wl / (4.0 * PB_PI * pdf);
    return true;
}

vec4[2] probe_light_nee(BakeParams P, vec3 x, inout uint state)
{
    vec4 r[2];
    r[0] = vec4(0.0);
    r[1] = vec4(0.0, 1.0, 0.0, 0.0);
    vec3 w, L;
    float tmax, k;
    if (!probe_nee_sample(P, x, state, w, L, tmax, k))
        return r;
    r[1] = vec4(w, 0.0);
    vec3 T = shadow_transmittance(P, x, w, tmax);
    if (T == vec3(0.0))
        return r;
    r[0] = vec4(L * T * k, 0.0);
    return r;
}

// Next-event estimation of the environment: a direction by texel power as a
// shadow ray, MIS against cosine-weighted bounce sampling (power heuristic).
// Its light is radiance x cos / (pi pdf) x weight, like emitter_nee_ray's.
ShadowRay env_nee_ray(BakeParams P, Env env, vec3 ng, vec3 ns, int ge, inout uint state)
{
    float u0 = rng_next(state), u1 = rng_next(state), u2 = rng_next(state);
    vec3 w = env_sample(env, u0, u1, u2).xyz;
    float cos_x = dot(ns, w);
    float pe = env_pdf(env, w);
    if (!(cos_x > 0.0 && dot(ng, w) > 0.0 && pe > 0.0))
        return no_shadow_ray();
    float pb = bounce_pdf(P, ge, cos_x, w);
    float wl = power_heuristic(pe, pb);
    ShadowRay r;
    r.w = w;
    r.tmax = PB_INF;
    r.L = env_radiance(env, w) * (cos_x / (PB_PI * pe) * wl);
    return r;
}

// A punctual light's shadow ray from a reflecting hit: the cosine is the
// shading normal's, and a light below the geometric surface adds nothing.
ShadowRay surface_light_ray(Light l, vec3 x, vec3 ng, vec3 ns)
{
    ShadowRay r = light_ray(l, x, ns, true);
    return r.tmax >= 0.0 && dot(ng, r.w) > 0.0 ? r : no_shadow_ray();
}

// --clamp-indirect: a contribution of reflected light (all but emission and
// sky seen along the probe ray itself) is scaled down so its largest
// channel is at most `limit` (biased; off at 0).
vec3 clamp_indirect(vec3 c, float limit)
{
    float m = max(c.r, max(c.g, c.b));
    return limit > 0.0 && m > limit ? c * (limit / m) : c;
}

struct PathResult {
    vec3 L;          // radiance along the ray
    vec3 L_direct;   // the part that reflected at most once (emission seen, direct light at the first hit)
    vec3 L_seen;     // the part that did not reflect: emission or environment seen along the ray
    float first_t;   // distance to the first hit, negative on a back face, PB_INF on a miss
    bool shade;      // the first hit is a surface that reflects (front face or double-sided)
    vec3 x;          // first hit, offset off the surface along its geometric normal
    vec3 n;          // its shading normal, facing the ray's origin
    vec3 albedo;     // its diffuse albedo
};

// Light a ray finds (emission, the environment) at vertex `bounce`: it has
// reflected `bounce` times; reflected light is clamped on request.
void add_found(inout PathResult res, vec3 c, uint bounce, float clamp_limit)
{
    if (bounce >= 1u)
        c = clamp_indirect(c, clamp_limit);
    res.L += c;
    if (bounce <= 1u)
        res.L_direct += c;
    if (bounce == 0u)
        res.L_seen += c;
}

// What path_radiance's one ray in flight is for
#define PB_RAY_BOUNCE 0u  // the probe ray or a bounce: closest hit
#define PB_RAY_LIGHT 1u   // a punctual light's shadow ray: adds to the irradiance E
#define PB_RAY_NEE 2u     // an emitter's or the environment's shadow ray: adds to c
// and, at a reflecting hit, which light sample comes next
#define PB_NEXT_LIGHTS 0u
#define PB_NEXT_EMITTER 1u
#define PB_NEXT_ENV 2u
#define PB_NEXT_BOUNCE 3u

// What path_radiance's loop carries from one ray to the next: the path's
// result so far, the ray in flight and the current reflecting hit (where its
// shadow rays start, what they add to). A wavefront bake (bake_wave.comp)
// keeps it in memory between its dispatches.
struct PathState {
    PathResult res;
    vec3 o, dir, throughput;
    float bsdf_pdf; // of the direction that led to the current hit (0: the first ray, not MIS-weighted)
    uvec2 ray;      // (in flight, next light sample)
    uint bounce, light;
    vec3 x, ng, ns, albedo, E, c;
    int ge;
    ShadowRay sr;
    // Thin glass (bake.glsl, glass_step): a ray it lets through goes on from
    // its far side, `past` along, tinted; shadow rays then find their hits
    // nearest first (closest hit), so that each layer is met in order.
    vec3 beyond;
    float past;
    uint layers;
};

PathState path_begin(vec3 o, vec3 dir)
{
    PathState ps;
    ps.res.L = vec3(0.0);
    ps.res.L_direct = vec3(0.0);
    ps.res.L_seen = vec3(0.0);
    ps.res.first_t = PB_INF;
    ps.res.shade = false;
    ps.res.x = o;
    ps.res.n = vec3(0.0, 1.0, 0.0);
    ps.res.albedo = vec3(0.0);
    ps.o = o;
    ps.dir = dir;
    ps.throughput = vec3(1.0);
    ps.bsdf_pdf = 0.0;
    ps.ray = uvec2(PB_RAY_BOUNCE, PB_NEXT_LIGHTS);
    ps.bounce = 0u;
    ps.light = 0u;
    ps.x = o;
    ps.ng = vec3(0.0, 1.0, 0.0);
    ps.ns = ps.ng;
    ps.albedo = vec3(0.0);
    ps.E = vec3(0.0);
    ps.c = vec3(0.0);
    ps.ge = -1;
    ps.sr = no_shadow_ray();
    ps.beyond = vec3(0.0);
    ps.past = 0.0;
    ps.layers = 0u;
    return ps;
}

// One ray of a path: the ray in flight is traced, what it finds is taken,
// and the next ray is chosen: at each reflecting hit the shadow rays of its
// light samples (punctual lights, one emitter, the environment) one at a
// time, then the next bounce. Returns false when the path is done.
//
// `bounces`: reflections after the first hit; `see_direct`: count light that
// reaches the origin unreflected (emission or sky seen along the ray itself);
// `first_hit_only`: stop at the first hit, having set first_t (relocation
// needs no light). Random numbers are drawn in the order of the CPU
// reference (src/bake/bake_cpu.c), which traces each ray where it is drawn.
bool path_step(BakeParams P, inout PathState ps, uint bounces, bool see_direct, bool first_hit_only,
               inout uint state)
{
    SceneRefs s = P.scene;
    Env env = bake_env(P);
    LightBuf lights = LightBuf(P.lights);
    FloatBuf emit_pdf = FloatBuf(P.emit_pdf);
    bool light_select = bake_feature(PB_FEATURE_LIGHT_SELECT) && P.light_select != 0u;
    bool glass = bake_glass(P);
    bool bounce_ray = ps.ray.x == PB_RAY_BOUNCE;
    vec3 rd = bounce_ray ? ps.dir : ps.sr.w;
    TraceResult tr = trace_ray(s, ps.layers != 0u ? ps.beyond : bounce_ray ? ps.o : ps.x, rd, 0.0,
                               (bounce_ray ? PB_INF : ps.sr.tmax) - ps.past, !bounce_ray && !glass);
    if (glass) {
        GlassStep g = ps.layers < PB_GLASS_LAYERS ? glass_step(P, tr, rd) : GlassStep(false, vec3(1.0), vec3(0.0));
        if (g.pass) {
            if (bounce_ray)
                ps.throughput *= g.w;
            else
                ps.sr.L *= g.w;
            ps.beyond = g.origin;
            ps.past += tr.t;
            ++ps.layers;
            return true;
        }
        tr.t += ps.past; // from the ray's origin: the probe's depth, the emitter's MIS density
        ps.past = 0.0;
        ps.layers = 0u;
    }
    if (ps.ray.x == PB_RAY_LIGHT) {
        ps.E += tr.tri == PB_NO_HIT ? ps.sr.L : vec3(0.0);
    } else if (ps.ray.x == PB_RAY_NEE) {
        ps.c += ps.throughput * ps.albedo * (tr.tri == PB_NO_HIT ? ps.sr.L : vec3(0.0));
    } else if (tr.tri == PB_NO_HIT) {
        if (ps.bounce > 0u || see_direct) {
            float w = 1.0;
            // the density of the ray that found it: its bounce's, or for a probe
            // ray under probe NEE the uniform sphere's (else 0: weight 1)
            bool probe_nee = ps.bounce == 0u && bake_feature(PB_FEATURE_PROBE_NEE) && !addr_null(P.nee);
            float found_pdf = probe_nee ? 1.0 / (4.0 * PB_PI) : ps.bsdf_pdf;
            if (found_pdf > 0.0 && env.count > 0u) { // the environment could also have been sampled: MIS
                float pe = env_pdf(env, ps.dir) * (probe_nee ? 1.0 - probe_emitter_share(P) : 1.0);
                w = power_heuristic(found_pdf, pe);
            }
            add_found(ps.res, ps.throughput * env_radiance(env, ps.dir) * w, ps.bounce, P.indirect_clamp);
        }
        return false;
    } else {
        Tri t = load_tri(s.tris, tr.tri);
        vec3 e1 = t.v1 - t.v0, e2 = t.v2 - t.v0;
        ps.ng = normalize(cross(e1, e2));
        bool back = dot(ps.ng, ps.dir) > 0.0;
        if (ps.bounce == 0u)
            ps.res.first_t = back ? -tr.t : tr.t;
        if (first_hit_only)
            return false;
        ShadeMaterial m = load_shade_material(P.materials, t.flags & ~PB_FLAG_ALPHA_MASK);
        if (back) {
            if ((m.tex.z & PB_MATERIAL_DOUBLE_SIDED) == 0)
                return false; // inside a single-sided surface: no light
            ps.ng = -ps.ng;
        }
        NormalMap nm = NormalMap(-1, 0.0);
        if (bake_feature(PB_FEATURE_NORMAL_MAPS) && (s.flags & PB_SCENE_NORMAL_MAPS) != 0u)
            nm = load_normal_map(P.materials, t.flags & ~PB_FLAG_ALPHA_MASK);
        int tt = glass ? load_tau_texture(P.materials, t.flags & ~PB_FLAG_ALPHA_MASK) : -1;
        // read once: the textures' coordinates, and the normal map's frame
        TriUV tuv = TriUV(vec2(0.0), vec2(0.0), vec2(0.0));
        vec2 uv = vec2(0.0);
        if (m.tex.x >= 0 || m.tex.y >= 0 || nm.tex >= 0 || tt >= 0) {
            tuv = load_tri_uv(s, tr.tri);
            uv = interpolate_uv(tuv, tr.u, tr.v);
        }
        if ((ps.bounce > 0u || see_direct) && m.emissive_metallic.rgb != vec3(0.0)) {
            float w = 1.0;
            // the density with which NEE at the ray's origin draws this point
            float pa = bake_emitters(P) ? emit_pdf.v[tr.tri] * light_cell_ratio(P, light_cell(P, ps.o), tr.tri) : 0.0;
            bool probe_nee = ps.bounce == 0u && bake_feature(PB_FEATURE_PROBE_NEE) && !addr_null(P.nee);
            float found_pdf = probe_nee ? 1.0 / (4.0 * PB_PI) : ps.bsdf_pdf;
            if (found_pdf > 0.0 && pa > 0.0) { // this emitter could also have been sampled: MIS
                float pl = emitter_density(pa, 0.5 * length(cross(e1, e2)), emitter_solid_angle(P, ps.o, t), tr.t,
                                           abs(dot(ps.ng, ps.dir))) *
                           (probe_nee ? probe_emitter_share(P) : 1.0);
                w = power_heuristic(found_pdf, pl);
            }
            add_found(ps.res, ps.throughput * m.emissive_metallic.rgb * texture_rgb(s, m.tex.y, uv) * w, ps.bounce,
                      P.indirect_clamp);
        }
        if (ps.bounce > bounces)
            return false; // the terminal ray: it only gathers emission (see below)
        vec4 base = texture_rgba(s, m.tex.x, uv);
        ps.albedo = m.base_color.rgb * base.rgb * diffuse_share(m, base.a, tau_red(s, tt, uv));
        if (bake_feature(PB_FEATURE_VERTEX_COLORS) && (s.flags & PB_SCENE_VERTEX_COLORS) != 0u)
            ps.albedo *= vertex_color(s, tr.tri, tr.u, tr.v).rgb;
        ps.x = offset_ray_origin(t.v0 + tr.u * e1 + tr.v * e2, ps.ng);
        bool smooth_shaded = bake_feature(PB_FEATURE_SHADING_NORMALS) && (s.flags & PB_SCENE_SHADING_NORMALS) != 0u;
        ps.ns = smooth_shaded ? shading_normal(s, tr.tri, tr.u, tr.v, ps.ng) : ps.ng;
        if (nm.tex >= 0)
            ps.ns = normal_mapped(s, nm.tex, nm.scale, tr.tri, tr.u, tr.v, tuv, uv, e1, e2, ps.ns, ps.ng, back);
        if (ps.bounce == 0u) {
            ps.res.shade = true;
            ps.res.x = ps.x;
            ps.res.n = ps.ns;
            ps.res.albedo = ps.albedo;
        }
        ps.E = vec3(0.0);
        ps.light = 0u;
        ps.ray.y = PB_NEXT_LIGHTS;
    }
    // The next ray: this hit's next light sample that needs one, else the bounce
    ps.ray.x = PB_RAY_BOUNCE;
    while (ps.ray.y == PB_NEXT_LIGHTS) {
        if (!bake_feature(PB_FEATURE_LIGHTS) || ps.light >= (light_select ? 1u : P.light_count)) {
            ps.c = ps.throughput * ps.albedo * (ps.E / PB_PI);
            ps.ge = guide_entry(P, ps.x, ps.ng);
            ps.ray.y = PB_NEXT_EMITTER;
        } else if (light_select) {
            // many lights: one, drawn in proportion to its power, over its probability
            EmitterBuf table = EmitterBuf(P.light_table);
            float xl = rng_next(state) * float(P.light_count);
            uint li = min(uint(xl), P.light_count - 1u);
            Emitter le = table.e[li];
            uint pick = xl - float(li) < le.prob ? li : le.alias;
            Emitter chosen = table.e[pick];
            ps.sr = surface_light_ray(lights.l[chosen.tri], ps.x, ps.ng, ps.ns);
            ps.sr.L /= chosen.pad;
            ps.light = 1u;
            if (ps.sr.tmax >= 0.0) {
                ps.ray.x = PB_RAY_LIGHT;
                break;
            }
        } else {
            ps.sr = surface_light_ray(lights.l[ps.light], ps.x, ps.ng, ps.ns);
            ++ps.light;
            if (ps.sr.tmax >= 0.0) {
                ps.ray.x = PB_RAY_LIGHT;
                break;
            }
        }
    }
    if (ps.ray.x != PB_RAY_BOUNCE)
        return true;
    if (ps.ray.y == PB_NEXT_EMITTER) {
        ps.ray.y = PB_NEXT_ENV;
        if (bake_emitters(P) && ps.albedo != vec3(0.0)) {
            ps.sr = emitter_nee_ray(P, ps.x, ps.ng, ps.ns, ps.ge, state);
            if (ps.sr.tmax >= 0.0) {
                ps.ray.x = PB_RAY_NEE;
                return true;
            }
        }
    }
    if (ps.ray.y == PB_NEXT_ENV) {
        ps.ray.y = PB_NEXT_BOUNCE;
        if (env.count > 0u && ps.albedo != vec3(0.0)) {
            ps.sr = env_nee_ray(P, env, ps.ng, ps.ns, ps.ge, state);
            if (ps.sr.tmax >= 0.0) {
                ps.ray.x = PB_RAY_NEE;
                return true;
            }
        }
    }
    // every light sample of this hit is in: its light, then the bounce
    ps.c = clamp_indirect(ps.c, P.indirect_clamp);
    ps.res.L += ps.c;
    if (ps.bounce == 0u)
        ps.res.L_direct += ps.c;
    // After the last reflection one more (terminal) bounce ray gathers the
    // emission and environment the light samples above are MIS-weighted
    // against; without it their weights would miss the bounce share (a
    // bias), and weight 1 instead gives fireflies near emitters.
    if (ps.bounce >= bounces && !bake_emitters(P) && env.count == 0u)
        return false;
    if (ps.bounce >= 1u) { // Russian roulette from the second reflection on
        float q = min(0.95, max(ps.albedo.r, max(ps.albedo.g, ps.albedo.b)));
        if (rng_next(state) >= q)
            return false;
        ps.throughput /= q;
    }
    ps.throughput *= ps.albedo;
    if (max(ps.throughput.r, max(ps.throughput.g, ps.throughput.b)) <= 0.0)
        return false;
    // The cosine lobe is the shading normal's; a direction below the
    // geometric surface would leave through it, and no light comes from there.
    if (ps.ge >= 0) { // guided: the learned distribution or the cosine lobe, weighed by the mixture
        float uc = rng_next(state), u1 = rng_next(state), u2 = rng_next(state), u3 = rng_next(state);
        ps.dir = uc < PB_GUIDE_SHARE ? guide_sample(P, ps.ge, u1, u2, u3) : cosine_direction(ps.ns, u1, u2);
        float cosine = dot(ps.ns, ps.dir);
        if (!(cosine > 0.0 && dot(ps.ng, ps.dir) > 0.0))
            return false;
        ps.bsdf_pdf = bounce_pdf(P, ps.ge, cosine, ps.dir);
        ps.throughput *= cosine / (PB_PI * ps.bsdf_pdf);
    } else {
        float u1 = rng_next(state), u2 = rng_next(state);
        ps.dir = cosine_direction(ps.ns, u1, u2);
        if (!(dot(ps.ng, ps.dir) > 0.0))
            return false;
        ps.bsdf_pdf = max(0.0, dot(ps.ns, ps.dir)) / PB_PI;
    }
    ps.o = ps.x;
    ++ps.bounce;
    return true;
}

// The radiance arriving along one ray: path_step until the path is done. The
// compiled kernel holds one traversal instead of one per kind of ray, and
// lanes whose rays are of different kinds traverse together.
PathResult path_radiance(BakeParams P, vec3 o, vec3 dir, uint bounces, bool see_direct, bool first_hit_only,
                         inout uint state)
{
    PathState ps = path_begin(o, dir);
    while (path_step(P, ps, bounces, see_direct, first_hit_only, state)) {
    }
    return ps.res;
}

// A probe ray's result: its radiance (plus, under --indirect volume, the
// last volume's light reflected at its first hit) and its first hit's signed
// distance, clamped to max_distance, into rays[i]. d: the probe ray.
void store_probe_ray(BakeParams P, uint i, vec3 d, PathResult pr)
{
    if (bake_feature(PB_FEATURE_VOLUME) && !addr_null(P.volume.probes) && pr.shade) {
        pb_volume = P.volume;
        pr.L += pr.albedo / PB_PI * pb_volume_irradiance(pb_volume, pr.x, pr.n, -d);
    }
    float first_distance = isinf(pr.first_t) ? P.max_distance : sign(pr.first_t) * min(abs(pr.first_t), P.max_distance);
    Vec4RW(P.rays).v[i] = vec4(pr.L, first_distance);
}

// Probe NEE: probe ray i's light sample (an emitter or the environment) drawn
// from the probe once its path is done, with the random numbers where the
// path left them (as the CPU reference draws it), into nee[2i], nee[2i + 1].
void store_probe_nee(BakeParams P, uint i, vec3 origin, inout uint state)
{
    if (!bake_feature(PB_FEATURE_PROBE_NEE) || addr_null(P.nee))
        return;
    vec4 nr[2] = vec4[2](vec4(0.0), vec4(0.0, 1.0, 0.0, 0.0));
    if (P.direct != 0u && (bake_emitters(P) || bake_env(P).count > 0u))
        nr = probe_light_nee(P, origin, state);
    Vec4RW(P.nee).v[2u * i] = nr[0];
    Vec4RW(P.nee).v[2u * i + 1u] = nr[1];
}

#endif
