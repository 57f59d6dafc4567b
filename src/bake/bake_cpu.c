/* CPU references of bake_trace.comp, bake_sh.comp and bake_depth.comp,
 * written step for step like the GLSL (shaders/include/bake.glsl). Random
 * numbers are the same integers; transcendental functions (pow, sqrt,
 * sin/cos of sampling) may differ in the last bits between host and device,
 * so paths agree exactly only until their first random bounce: tests compare
 * bounce-0 rays one by one and multi-bounce results statistically. */
#include "bake/alias.h"
#include "bake/bake_data.h"
#include "bake/depth_lists.h"
#include "bake/guide.h"
#include "bake/light_cells.h"
#include "bake/normal_map.h"
#include "bake/path_cpu.h"
#include "bake/shading_normals.h"
#include "bake/spherical_triangle.h"
#include "bvh/alpha.h"
#include "common/common.h"
#include "common/srgb.h"
#include "common/vec3.h"
#include "probebake/bake.h"
#include "probebake/octahedral.h"
#include "probebake/sh.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define PI_F 3.14159265358979324f

uint32_t pb_rng_seed_cpu(uint32_t seed, uint32_t probe, uint32_t pass, uint32_t ray)
{
    return pb_hash32(seed ^ pb_hash32(probe ^ pb_hash32(pass ^ pb_hash32(ray))));
}

float pb_rng_next_cpu(uint32_t *state)
{
    *state = pb_hash32(*state);
    return (float)(*state >> 8) * (1.0f / 16777216.0f);
}

#define rng_seed pb_rng_seed_cpu
#define rng_next pb_rng_next_cpu

/* power_heuristic of path.glsl */
static float power_heuristic(float a, float b)
{
    return a * a / (a * a + b * b);
}

static uint32_t slot_of(const pb_bake_pass *p, uint32_t local)
{
    return p->probe_list ? p->probe_list[p->first_probe + local] : p->first_probe + local;
}

static void probe_ray_direction(const pb_bake_pass *p, uint32_t probe, uint32_t ray, float d[3])
{
    const float *sf = p->directions + 4 * (size_t)ray;
    for (int k = 0; k < 3; ++k) {
        const float *row = p->rotations + 12 * (size_t)probe + 4 * k;
        float a = row[0] * sf[0], b = row[1] * sf[1], c = row[2] * sf[2];
        d[k] = (a + b) + c;
    }
}

/* texture_rgba of bake.glsl: linear colour and alpha, white and opaque for no texture */
static void texture_rgba(const pb_scene *s, int32_t tex, float u, float v, float rgba[4])
{
    if (tex < 0) {
        rgba[0] = rgba[1] = rgba[2] = rgba[3] = 1.f;
        return;
    }
    uint32_t texel = pb_texture_texel(s, tex, u, v);
    for (int k = 0; k < 3; ++k)
        rgba[k] = pb_srgb_to_linear((float)((texel >> (8 * k)) & 0xffu) / 255.f);
    rgba[3] = (float)(texel >> 24) * (1.f / 255.f);
}

/* tau_red of bake.glsl: the red of transmission texture tt, 1 for none */
static float tau_red(const pb_scene *s, int32_t tt, float u, float v)
{
    return tt >= 0 ? (float)(pb_texture_texel(s, tt, u, v) & 0xffu) * (1.f / 255.f) : 1.f;
}

static void texture_rgb(const pb_scene *s, int32_t tex, float u, float v, float rgb[3])
{
    float rgba[4];
    texture_rgba(s, tex, u, v, rgba);
    memcpy(rgb, rgba, 3 * sizeof(float));
}

typedef struct hit {
    uint32_t tri;
    float t, u, v;
} hit;

/* traversals made by the calling thread's current range (pb_parallel_for
 * runs a range on one thread) */
static _Thread_local uint64_t traversals;

static hit trace(const pb_bake_pass *p, const float o[3], const float d[3], float tmax, pb_trace_mode mode)
{
    ++traversals;
    pb_ray ray = {{o[0], o[1], o[2]}, 0.f, {d[0], d[1], d[2]}, tmax};
    pb_hit h;
    if (p->cast)
        p->cast(p->cast_user, &ray, mode, &h);
    else
        pb_trace_cpu(p->scene, p->bvh, &ray, 1, mode, &h, 1);
    hit r = {h.triangle, h.t, h.u, h.v};
    return r;
}

/* Triangle tri's edges from its first corner and its unit face normal (the
 * kernels' normalize(cross(e1, e2))). */
static void face_normal(const pb_scene *s, uint32_t tri, float e1[3], float e2[3], float n[3])
{
    const float *v0 = s->positions + 9 * (size_t)tri, *v1 = v0 + 3, *v2 = v0 + 6;
    for (int k = 0; k < 3; ++k)
        e1[k] = v1[k] - v0[k], e2[k] = v2[k] - v0[k];
    pb_cross3(e1, e2, n);
    float nl = pb_length3(n);
    for (int k = 0; k < 3; ++k)
        n[k] /= nl;
}

/* bake.glsl's bound on the layers of glass one ray goes through */
#define PB_GLASS_LAYERS 64u

/* glass_step of bake.glsl: 1 when hit h of a ray along rd is on thin glass
 * that lets it through, with its tint w and the origin it goes on from. */
static int glass_step(const pb_scene *s, hit h, const float rd[3], float w[3], float origin[3])
{
    if (h.tri == PB_NO_HIT)
        return 0;
    uint32_t mi = s->material[h.tri];
    const pb_material *m = &s->materials[mi];
    float tau = m->transmission;
    if (!(tau > 0.f))
        return 0;
    float c[4] = {m->base_color[0], m->base_color[1], m->base_color[2], m->base_color[3]};
    const float *uv = s->texcoords + 6 * (size_t)h.tri;
    float w0 = 1.f - h.u - h.v, tu = w0 * uv[0] + h.u * uv[2] + h.v * uv[4], tv = w0 * uv[1] + h.u * uv[3] + h.v * uv[5];
    tau *= tau_red(s, m->transmission_texture, tu, tv);
    if (m->base_color_texture >= 0) {
        float tx[4];
        texture_rgba(s, m->base_color_texture, tu, tv, tx);
        if (m->transmission_in_alpha) /* transmission, not coverage (glass_tau) */
            tau *= tx[3], tx[3] = 1.f;
        for (int k = 0; k < 4; ++k)
            c[k] *= tx[k];
    }
    if (s->colors) {
        float vc[4];
        pb_vertex_color(s, h.tri, h.u, h.v, vc);
        for (int k = 0; k < 4; ++k)
            c[k] *= vc[k];
    }
    float opaque = c[3] * (1.f - tau);
    if (opaque > pb_alpha_blend_threshold(mi, h.u, h.v))
        return 0;
    for (int k = 0; k < 3; ++k)
        w[k] = ((1.f - c[3]) + c[3] * tau * c[k]) / (1.f - opaque);
    const float *v0 = s->positions + 9 * (size_t)h.tri;
    float e1[3], e2[3], n[3], x[3];
    face_normal(s, h.tri, e1, e2, n);
    float side = n[0] * rd[0] + n[1] * rd[1] + n[2] * rd[2] > 0.f ? 1.f : -1.f;
    for (int k = 0; k < 3; ++k) {
        n[k] *= side;
        x[k] = v0[k] + h.u * e1[k] + h.v * e2[k];
    }
    pb_offset_ray_origin(x, n, origin);
    return 1;
}

/* shadow_transmittance of bake.glsl: 1 and the share T of the light a
 * shadow ray from x along w (to tmax) carries past thin glass, or 0 where
 * anything else blocks it. With glass, hits are found nearest first. */
static int shadow_transmittance(const pb_bake_pass *p, int glass, const float x_in[3], const float w[3], float tmax,
                                float T[3])
{
    float x[3] = {x_in[0], x_in[1], x_in[2]};
    T[0] = T[1] = T[2] = 1.f;
    for (uint32_t layers = 0;; ++layers) {
        hit h = trace(p, x, w, tmax, glass ? PB_TRACE_CLOSEST : PB_TRACE_ANY);
        if (h.tri == PB_NO_HIT)
            return 1;
        float g[3];
        if (!glass || layers >= PB_GLASS_LAYERS || !glass_step(p->scene, h, w, g, x))
            return 0;
        for (int k = 0; k < 3; ++k)
            T[k] *= g[k];
        tmax -= h.t;
    }
}

/* light_irradiance of bake.glsl; with ng (not NULL), surface_light_ray of
 * path.glsl: n is then the shading normal, and a light below the geometric
 * surface adds nothing */
static void light_irradiance(const pb_bake_pass *p, int glass, const gpu_light *l, const float x[3], const float n[3],
                             const float *ng, int oriented, float E[3])
{
    uint32_t type = (uint32_t)l->position_type[3];
    float to_light[3], dist, falloff = 1.f;
    E[0] = E[1] = E[2] = 0.f;
    if (type == PB_LIGHT_DIRECTIONAL) {
        for (int k = 0; k < 3; ++k)
            to_light[k] = -l->direction_range[k];
        dist = INFINITY;
    } else {
        float v[3] = {l->position_type[0] - x[0], l->position_type[1] - x[1], l->position_type[2] - x[2]};
        float d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (d2 <= 0.f)
            return;
        dist = sqrtf(d2);
        for (int k = 0; k < 3; ++k)
            to_light[k] = v[k] / dist;
        falloff = 1.f / d2;
        float range = l->direction_range[3];
        if (range > 0.f) {
            float q = dist / range;
            float w = 1.f - q * q * q * q;
            falloff *= w < 0.f ? 0.f : (w > 1.f ? 1.f : w);
        }
        if (type == PB_LIGHT_SPOT) {
            float cd = -(l->direction_range[0] * to_light[0] + l->direction_range[1] * to_light[1] +
                         l->direction_range[2] * to_light[2]);
            float a = (cd - l->cone[0]) * l->cone[1];
            a = a < 0.f ? 0.f : (a > 1.f ? 1.f : a);
            falloff *= a * a;
        }
    }
    float cosine = oriented ? n[0] * to_light[0] + n[1] * to_light[1] + n[2] * to_light[2] : 1.f;
    if (cosine <= 0.f || falloff <= 0.f)
        return;
    if (ng && !(ng[0] * to_light[0] + ng[1] * to_light[1] + ng[2] * to_light[2] > 0.f))
        return;
    float T[3];
    if (!shadow_transmittance(p, glass, x, to_light, dist, T))
        return;
    for (int k = 0; k < 3; ++k)
        E[k] = l->radiance[k] * (cosine * falloff) * T[k];
}

void pb_cosine_direction_cpu(const float n[3], float u1, float u2, float out[3])
{
    float sgn = n[2] >= 0.f ? 1.f : -1.f;
    float a = -1.f / (sgn + n[2]);
    float b = n[0] * n[1] * a;
    float t[3] = {1.f + sgn * n[0] * n[0] * a, sgn * b, -sgn * n[0]};
    float bt[3] = {b, sgn + n[1] * n[1] * a, -n[1]};
    float r = sqrtf(u1), phi = 2.f * PI_F * u2;
    float c = r * cosf(phi), s = r * sinf(phi), z = sqrtf(fmaxf(0.f, 1.f - u1));
    float d[3];
    for (int k = 0; k < 3; ++k)
        d[k] = t[k] * c + bt[k] * s + n[k] * z;
    float l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int k = 0; k < 3; ++k)
        out[k] = d[k] / l;
}

typedef struct trace_ctx {
    pb_path_ctx path;
    float *rays;
    _Atomic uint64_t traversals;
} trace_ctx;

/* bounce_pdf of path.glsl: the density with which a vertex's bounce draws
 * direction w (cos_x = its cosine to the normal): the cosine lobe, or where
 * the guide has learned entry ge, the mixture with the guided density. */
static float bounce_pdf(const pb_bake_pass *p, int32_t ge, float cos_x, const float w[3])
{
    float pc = fmaxf(cos_x, 0.f) / PI_F;
    return ge < 0 ? pc : (1.f - PB_GUIDE_SHARE) * pc + PB_GUIDE_SHARE * pb_guide_pdf(p->guide, ge, w);
}

static float clampf(float x, float lo, float hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* emitter_density of path.glsl: the solid-angle density with which
 * sample_emitter draws a direction toward an emitter triangle of area
 * density pa, area tri_area and solid angle sa (0: sampled by area), meeting
 * it at distance dist and cosine cos_e. */
static float emitter_density(float pa, float tri_area, float sa, float dist, float cos_e)
{
    return pb_spherical_triangle_sampled(sa) ? pa * tri_area / sa : pa * dist * dist / cos_e;
}

/* emitter_solid_angle of path.glsl: the solid angle of emitter triangle v
 * seen from x where it is sampled by solid angle, else 0. */
static float emitter_solid_angle(const pb_path_ctx *c, const float x[3], const float *v)
{
    return c->p->emitters_by_area ? 0.f : pb_spherical_triangle_area(x, v, v + 3, v + 6);
}

/* sample_emitter of path.glsl: one emissive triangle by power (or from the
 * light cell holding x), and a direction toward it: uniform over its solid
 * angle where that is large enough, else toward a uniform point on it.
 * pdf 0: its back faces x, or degenerate. */
typedef struct emitter_sample {
    float w[3], dist, Le[3], pdf;
} emitter_sample;

static emitter_sample sample_emitter(const pb_path_ctx *c, const pb_bake_emitters *em, const float x[3],
                                     uint32_t *state)
{
    const pb_scene *s = c->p->scene;
    emitter_sample es;
    float u0 = rng_next(state), u1 = rng_next(state), u2 = rng_next(state), ratio = 1.f;
    int32_t lc = pb_light_cells_slot(c->p->light_cells, x);
    uint32_t etri = lc >= 0 ? pb_light_cells_sample(c->p->light_cells, lc, u0, rng_next(state), &ratio)
                            : em->tri[pb_alias_sample(em->prob, em->alias, em->count, u0)];
    const float *v0 = s->positions + 9 * (size_t)etri, *v1 = v0 + 3, *v2 = v0 + 6;
    float e1[3], e2[3], ne[3], b1, b2;
    for (int k = 0; k < 3; ++k)
        e1[k] = v1[k] - v0[k], e2[k] = v2[k] - v0[k];
    pb_cross3(e1, e2, ne);
    float sa = emitter_solid_angle(c, x, v0);
    if (pb_spherical_triangle_sampled(sa)) {
        pb_spherical_triangle_sample(x, v0, v1, v2, sa, u1, u2, es.w);
        /* where it meets the triangle: distance and barycentrics (Moller-Trumbore) */
        float pv[3], tv[3], qv[3];
        pb_cross3(es.w, e2, pv);
        float inv = 1.f / pb_dot3(e1, pv);
        for (int k = 0; k < 3; ++k)
            tv[k] = x[k] - v0[k];
        pb_cross3(tv, e1, qv);
        b1 = clampf(pb_dot3(tv, pv) * inv, 0.f, 1.f);
        b2 = clampf(pb_dot3(es.w, qv) * inv, 0.f, 1.f - b1);
        es.dist = pb_dot3(e2, qv) * inv;
    } else {
        float su = sqrtf(u1), to[3];
        b1 = su * (1.f - u2), b2 = su * u2;
        for (int k = 0; k < 3; ++k)
            to[k] = v0[k] + b1 * e1[k] + b2 * e2[k] - x[k];
        es.dist = sqrtf(pb_dot3(to, to));
        for (int k = 0; k < 3; ++k)
            es.w[k] = to[k] / es.dist;
    }
    float nl = pb_length3(ne);
    const gpu_shade_material *m = &c->materials[s->material[etri]];
    float cos_e = -pb_dot3(ne, es.w) / nl;
    if (m->tex[2] & PB_MATERIAL_DOUBLE_SIDED)
        cos_e = fabsf(cos_e);
    float pa = em->pdf_area[etri] * ratio;
    es.pdf = cos_e > 0.f && es.dist > 0.f ? emitter_density(pa, 0.5f * nl, sa, es.dist, cos_e) : 0.f;
    const float *uv = s->texcoords + 6 * (size_t)etri;
    float w0 = 1.f - b1 - b2, tu = w0 * uv[0] + b1 * uv[2] + b2 * uv[4], tv = w0 * uv[1] + b1 * uv[3] + b2 * uv[5];
    float et[3];
    texture_rgb(s, m->tex[1], tu, tv, et);
    for (int k = 0; k < 3; ++k)
        es.Le[k] = m->emissive_metallic[k] * et[k];
    return es;
}

/* Next-event estimation of one emissive triangle (emitter_nee_ray of path.glsl). */
static void emitter_nee(const pb_path_ctx *c, const pb_bake_emitters *em, const float x[3], const float ng[3],
                        const float ns[3], int32_t ge, const float albedo[3], const float thr[3], uint32_t *state,
                        float L[3])
{
    emitter_sample es = sample_emitter(c, em, x, state);
    float cos_x = pb_dot3(ns, es.w);
    if (!(cos_x > 0.f && pb_dot3(ng, es.w) > 0.f && es.pdf > 0.f))
        return;
    float T[3];
    if (!shadow_transmittance(c->p, c->glass, x, es.w, es.dist * 0.9999f, T))
        return;
    float pb = bounce_pdf(c->p, ge, cos_x, es.w), wl = power_heuristic(es.pdf, pb);
    for (int k = 0; k < 3; ++k)
        L[k] += thr[k] * albedo[k] * (es.Le[k] * T[k]) * (cos_x / (PI_F * es.pdf) * wl);
}

/* probe_emitter_share of path.glsl: the probability that probe NEE's light
 * sample is an emitter (else the environment). */
static float probe_emitter_share(const pb_bake_pass *p)
{
    int env = p->env && p->env->count;
    return p->emitters && p->emitters->count ? (env ? 0.5f : 1.f) : 0.f;
}

/* probe_light_nee of path.glsl: out[0..2] weighted radiance / 4pi, out[4..6]
 * the direction (8 floats, as the kernel's two vec4). */
static void probe_light_nee(const pb_path_ctx *c, const float x[3], uint32_t *state, float out[8])
{
    const pb_bake_pass *p = c->p;
    memset(out, 0, 8 * sizeof *out);
    out[5] = 1.f;
    float share = probe_emitter_share(p), us = rng_next(state);
    float w[3], L[3], tmax, pdf;
    if (us < share) {
        emitter_sample es = sample_emitter(c, p->emitters, x, state);
        memcpy(w, es.w, sizeof w);
        memcpy(L, es.Le, sizeof L);
        tmax = es.dist * 0.9999f, pdf = share * es.pdf;
    } else {
        if (!p->env || !p->env->count)
            return;
        float u0 = rng_next(state), u1 = rng_next(state), u2 = rng_next(state);
        pb_env_sample(p->env, u0, u1, u2, w);
        memcpy(L, p->env->texels[pb_env_texel_of(p->env, w)].rgb, sizeof L);
        tmax = INFINITY, pdf = (1.f - share) * pb_env_pdf(p->env, w);
    }
    if (!(pdf > 0.f))
        return;
    memcpy(out + 4, w, sizeof w);
    float T[3];
    if (!shadow_transmittance(p, c->glass, x, w, tmax, T))
        return;
    float wl = power_heuristic(pdf, 1.f / (4.f * PI_F));
    for (int k = 0; k < 3; ++k)
        out[k] = L[k] * T[k] * (wl / (4.f * PI_F * pdf));
}

/* env_nee_ray of path.glsl */
static void env_nee(const pb_path_ctx *c, const float x[3], const float ng[3], const float ns[3], int32_t ge,
                    const float albedo[3], const float thr[3], uint32_t *state, float L[3])
{
    const pb_bake_pass *p = c->p;
    const pb_env_table *env = p->env;
    float u0 = rng_next(state), u1 = rng_next(state), u2 = rng_next(state);
    float w[3];
    pb_env_sample(env, u0, u1, u2, w);
    float cos_x = pb_dot3(ns, w);
    float pe = pb_env_pdf(env, w);
    if (!(cos_x > 0.f && pb_dot3(ng, w) > 0.f && pe > 0.f))
        return;
    float T[3];
    if (!shadow_transmittance(p, c->glass, x, w, INFINITY, T))
        return;
    float pb = bounce_pdf(p, ge, cos_x, w), wl = power_heuristic(pe, pb);
    const float *Le = env->texels[pb_env_texel_of(env, w)].rgb;
    for (int k = 0; k < 3; ++k)
        L[k] += thr[k] * albedo[k] * ((Le[k] * T[k]) * (cos_x / (PI_F * pe) * wl));
}

/* diffuse_share of bake.glsl; a: the colour texel's alpha, r: the
 * transmission texture's red (glass_tau) */
static float diffuse_share(const gpu_shade_material *m, float a, float r)
{
    float keep = 1.f - m->emissive_metallic[3], tau;
    memcpy(&tau, &m->tex[3], 4);
    if (m->tex[2] & PB_MATERIAL_TAU_IN_ALPHA)
        tau *= a;
    else
        tau *= r;
    return tau > 0.f ? (tau < 1.f ? fmaxf(0.f, keep - tau) / (1.f - tau) : 0.f) : keep;
}

/* clamp_indirect of path.glsl */
static void clamp_indirect(float c[3], float limit)
{
    float m = fmaxf(c[0], fmaxf(c[1], c[2]));
    if (limit > 0.f && m > limit)
        for (int k = 0; k < 3; ++k)
            c[k] *= limit / m;
}

/* add_found of path.glsl */
static void add_found(pb_path_result *res, float c[3], uint32_t bounce, float clamp_limit)
{
    if (bounce >= 1)
        clamp_indirect(c, clamp_limit);
    for (int k = 0; k < 3; ++k) {
        res->L[k] += c[k];
        if (bounce <= 1)
            res->L_direct[k] += c[k];
        if (bounce == 0)
            res->L_seen[k] += c[k];
    }
}

pb_path_result pb_path_radiance_cpu(const pb_path_ctx *c, const float o_in[3], const float dir_in[3], uint32_t bounces,
                                    int see_direct, uint32_t *state)
{
    const pb_bake_pass *p = c->p;
    const pb_scene *s = p->scene;
    pb_path_result res;
    memset(&res, 0, sizeof res);
    res.first_t = INFINITY;
    res.n[1] = 1.f;
    memcpy(res.x, o_in, sizeof res.x);
    float thr[3] = {1, 1, 1}, bsdf_pdf = 0.f;
    const pb_bake_emitters *em = p->emitters && p->emitters->count ? p->emitters : NULL;
    int env_sampled = p->env && p->env->count;
    float o[3] = {o_in[0], o_in[1], o_in[2]}, dir[3] = {dir_in[0], dir_in[1], dir_in[2]};
    for (uint32_t bounce = 0;; ++bounce) {
        /* through thin glass (glass_step): on from its far side, tinted */
        float from[3] = {o[0], o[1], o[2]}, past = 0.f;
        hit h;
        for (uint32_t layers = 0;; ++layers) {
            h = trace(p, from, dir, INFINITY, PB_TRACE_CLOSEST);
            float g[3];
            if (!c->glass || layers >= PB_GLASS_LAYERS || !glass_step(s, h, dir, g, from))
                break;
            for (int k = 0; k < 3; ++k)
                thr[k] *= g[k];
            past += h.t;
        }
        if (c->glass)
            h.t += past; /* from the ray's origin: the probe's depth, the emitter's MIS density */
        if (h.tri == PB_NO_HIT) {
            if ((bounce > 0 || see_direct) && p->env && p->env->width) {
                float w = 1.f;
                int probe_nee = bounce == 0 && p->nee;
                float found_pdf = probe_nee ? 1.f / (4.f * PI_F) : bsdf_pdf;
                if (found_pdf > 0.f && p->env->count) {
                    float pe = pb_env_pdf(p->env, dir) * (probe_nee ? 1.f - probe_emitter_share(p) : 1.f);
                    w = power_heuristic(found_pdf, pe);
                }
                const float *Le = p->env->texels[pb_env_texel_of(p->env, dir)].rgb;
                float cv[3] = {thr[0] * Le[0] * w, thr[1] * Le[1] * w, thr[2] * Le[2] * w};
                add_found(&res, cv, bounce, p->indirect_clamp);
            }
            break;
        }
        const float *v0 = s->positions + 9 * (size_t)h.tri;
        float e1[3], e2[3], ng[3];
        face_normal(s, h.tri, e1, e2, ng);
        int back = ng[0] * dir[0] + ng[1] * dir[1] + ng[2] * dir[2] > 0.f;
        if (bounce == 0)
            res.first_t = back ? -h.t : h.t;
        const gpu_shade_material *m = &c->materials[s->material[h.tri]];
        if (back) {
            if (!(m->tex[2] & PB_MATERIAL_DOUBLE_SIDED))
                break;
            for (int k = 0; k < 3; ++k)
                ng[k] = -ng[k];
        }
        const float *uv = s->texcoords + 6 * (size_t)h.tri;
        float w0 = 1.f - h.u - h.v;
        float tu = w0 * uv[0] + h.u * uv[2] + h.v * uv[4], tv = w0 * uv[1] + h.u * uv[3] + h.v * uv[5];
        float base[4];
        if ((bounce > 0 || see_direct) &&
            (m->emissive_metallic[0] != 0.f || m->emissive_metallic[1] != 0.f || m->emissive_metallic[2] != 0.f)) {
            float w = 1.f, pa = em ? em->pdf_area[h.tri] * pb_light_cells_ratio(p->light_cells,
                                                                            pb_light_cells_slot(p->light_cells, o),
                                                                            h.tri)
                                   : 0.f;
            int probe_nee = bounce == 0 && p->nee;
            float found_pdf = probe_nee ? 1.f / (4.f * PI_F) : bsdf_pdf;
            if (found_pdf > 0.f && pa > 0.f) {
                float ne[3];
                pb_cross3(e1, e2, ne);
                float pl = emitter_density(pa, 0.5f * pb_length3(ne), emitter_solid_angle(c, o, v0), h.t,
                                           fabsf(ng[0] * dir[0] + ng[1] * dir[1] + ng[2] * dir[2])) *
                           (probe_nee ? probe_emitter_share(p) : 1.f);
                w = power_heuristic(found_pdf, pl);
            }
            float et[3];
            texture_rgb(s, m->tex[1], tu, tv, et);
            float cv[3];
            for (int k = 0; k < 3; ++k)
                cv[k] = thr[k] * m->emissive_metallic[k] * et[k] * w;
            add_found(&res, cv, bounce, p->indirect_clamp);
        }
        if (bounce > bounces)
            break; /* the terminal ray only gathers emission */
        texture_rgba(s, m->tex[0], tu, tv, base);
        float albedo[3], xp[3], x[3], E[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k) {
            albedo[k] = m->base_color[k] * base[k] * diffuse_share(m, base[3], tau_red(s, m->tau_texture, tu, tv));
            xp[k] = v0[k] + h.u * e1[k] + h.v * e2[k];
        }
        if (s->colors) {
            float vc[4];
            pb_vertex_color(s, h.tri, h.u, h.v, vc);
            for (int k = 0; k < 3; ++k)
                albedo[k] *= vc[k];
        }
        pb_offset_ray_origin(xp, ng, x);
        float ns[3] = {ng[0], ng[1], ng[2]};
        if (c->smooth)
            pb_shading_normal_cpu(s, h.tri, h.u, h.v, ng, ns);
        if (m->normal_map[0] >= 0) {
            float scale, bent[3];
            memcpy(&scale, &m->normal_map[1], 4);
            pb_normal_mapped_cpu(s, m->normal_map[0], scale, h.tri, h.u, h.v, tu, tv, e1, e2, ns, ng, back, bent);
            memcpy(ns, bent, sizeof bent);
        }
        if (bounce == 0) {
            res.shade = 1;
            memcpy(res.x, x, sizeof x);
            memcpy(res.n, ns, sizeof ns);
            memcpy(res.albedo, albedo, sizeof albedo);
        }
        if (p->light_table && p->light_table->count) { /* many lights: one drawn by power */
            const pb_light_table *lt = p->light_table;
            uint32_t pick = pb_alias_sample(lt->keep, lt->alias, lt->count, rng_next(state));
            light_irradiance(p, c->glass, &c->lights[pick], x, ns, ng, 1, E);
            for (int k = 0; k < 3; ++k)
                E[k] /= lt->p[pick];
        } else {
            for (uint32_t l = 0; l < s->light_count; ++l) {
                float El[3];
                light_irradiance(p, c->glass, &c->lights[l], x, ns, ng, 1, El);
                for (int k = 0; k < 3; ++k)
                    E[k] += El[k];
            }
        }
        float cc[3];
        for (int k = 0; k < 3; ++k)
            cc[k] = thr[k] * albedo[k] * (E[k] / PI_F);
        int32_t ge = pb_guide_entry(p->guide, x, ng);
        if (em && (albedo[0] != 0.f || albedo[1] != 0.f || albedo[2] != 0.f))
            emitter_nee(c, em, x, ng, ns, ge, albedo, thr, state, cc);
        if (env_sampled && (albedo[0] != 0.f || albedo[1] != 0.f || albedo[2] != 0.f))
            env_nee(c, x, ng, ns, ge, albedo, thr, state, cc);
        clamp_indirect(cc, p->indirect_clamp);
        for (int k = 0; k < 3; ++k) {
            res.L[k] += cc[k];
            if (bounce == 0)
                res.L_direct[k] += cc[k];
        }
        if (bounce >= bounces && !em && !env_sampled)
            break; /* no terminal ray needed: nothing to MIS against */
        if (bounce >= 1) {
            float q = fminf(0.95f, fmaxf(albedo[0], fmaxf(albedo[1], albedo[2])));
            if (rng_next(state) >= q)
                break;
            for (int k = 0; k < 3; ++k)
                thr[k] /= q;
        }
        for (int k = 0; k < 3; ++k)
            thr[k] *= albedo[k];
        if (fmaxf(thr[0], fmaxf(thr[1], thr[2])) <= 0.f)
            break;
        /* the shading normal's cosine lobe; below the geometric surface no light comes */
        if (ge >= 0) { /* guided: the learned distribution or the cosine lobe, weighed by the mixture */
            float uc = rng_next(state), u1 = rng_next(state), u2 = rng_next(state), u3 = rng_next(state);
            if (uc < PB_GUIDE_SHARE)
                pb_guide_sample(p->guide, ge, u1, u2, u3, dir);
            else
                pb_cosine_direction_cpu(ns, u1, u2, dir);
            float cosine = pb_dot3(ns, dir);
            if (!(cosine > 0.f && pb_dot3(ng, dir) > 0.f))
                break;
            bsdf_pdf = bounce_pdf(p, ge, cosine, dir);
            for (int k = 0; k < 3; ++k)
                thr[k] *= cosine / (PI_F * bsdf_pdf);
        } else {
            float u1 = rng_next(state), u2 = rng_next(state);
            pb_cosine_direction_cpu(ns, u1, u2, dir);
            if (!(pb_dot3(ng, dir) > 0.f))
                break;
            bsdf_pdf = fmaxf(0.f, pb_dot3(ns, dir)) / PI_F;
        }
        memcpy(o, x, sizeof x);
    }
    return res;
}

static void trace_range(void *user, uint64_t begin, uint64_t end)
{
    trace_ctx *c = user;
    const pb_bake_pass *p = c->path.p;
    traversals = 0;
    for (uint64_t i = begin; i < end; ++i) {
        uint32_t probe = slot_of(p, (uint32_t)(i / p->rays_per_probe)), ray = (uint32_t)(i % p->rays_per_probe);
        float d[3];
        probe_ray_direction(p, probe, ray, d);
        uint32_t state = rng_seed(p->seed, pb_probe_record_id(p->probes + 4 * (size_t)probe), p->pass_index, ray);
        const float *o = p->probes + 4 * (size_t)probe;
        pb_path_result r = pb_path_radiance_cpu(&c->path, o, d, p->bounces, (int)p->direct, &state);
        if (p->volume && r.shade) {
            float view[3] = {-d[0], -d[1], -d[2]}, e[3];
            pb_sample_cpu(p->volume, r.x, r.n, view, e);
            for (int k = 0; k < 3; ++k)
                r.L[k] += r.albedo[k] / PI_F * e[k];
        }
        if (p->nee) {
            float *nr = p->nee + 8 * i;
            memset(nr, 0, 8 * sizeof *nr);
            nr[5] = 1.f;
            if (p->direct && ((p->emitters && p->emitters->count) || (p->env && p->env->count)))
                probe_light_nee(&c->path, o, &state, nr);
        }
        float first = isinf(r.first_t) ? p->max_distance
                                        : (r.first_t < 0.f ? -fminf(-r.first_t, p->max_distance)
                                                           : fminf(r.first_t, p->max_distance));
        float *out = c->rays + 4 * i;
        out[0] = r.L[0], out[1] = r.L[1], out[2] = r.L[2], out[3] = first;
    }
    atomic_fetch_add(&c->traversals, traversals);
}

int pb_path_ctx_init(pb_path_ctx *c, const pb_bake_pass *p)
{
    const pb_scene *s = p->scene;
    c->p = p;
    c->lights = malloc((s->light_count ? s->light_count : 1) * sizeof(gpu_light));
    c->materials = malloc((s->material_count ? s->material_count : 1) * sizeof(gpu_shade_material));
    if (!c->lights || !c->materials) {
        pb_path_ctx_free(c);
        return 0;
    }
    pb_bake_lights(s, c->lights);
    pb_bake_materials(s, c->materials);
    c->smooth = pb_scene_bent_triangles(s) != 0; /* as pb_gpu_scene_create decides */
    c->glass = pb_scene_glass_materials(s) != 0; /* as pb_gpu_scene_create decides */
    return 1;
}

void pb_path_ctx_free(pb_path_ctx *c)
{
    free(c->lights), free(c->materials);
    c->lights = NULL, c->materials = NULL;
}

void pb_bake_pass_inputs(const pb_scene *scene, const pb_bake_desc *d, uint32_t P, uint32_t rays_per_probe,
                         uint32_t pass, float *probes, float *rotations, float *directions)
{
    for (uint32_t p = 0; p < P; ++p) {
        uint32_t id;
        pb_bake_probe_position(scene, d, p, probes + 4 * (size_t)p, &id);
        memcpy(&probes[4 * (size_t)p + 3], &id, 4);
    }
    pb_bake_rotations(d->seed, pass, probes, P, rotations); /* as the bake's passes turn them */
    pb_sf_directions(rays_per_probe, directions);
}

uint64_t pb_bake_trace_cpu(const pb_bake_pass *p, float *rays)
{
    trace_ctx c;
    memset(&c, 0, sizeof c);
    c.rays = rays;
    if (!pb_path_ctx_init(&c.path, p))
        return 0;
    pb_parallel_for((uint64_t)p->probe_count * p->rays_per_probe, 64, 0, trace_range, &c);
    pb_path_ctx_free(&c.path);
    return atomic_load(&c.traversals);
}

void pb_bake_sh_cpu(const pb_bake_pass *p, const float *rays, float *reduced)
{
    const pb_scene *s = p->scene;
    gpu_light *lights = malloc((s->light_count ? s->light_count : 1) * sizeof(gpu_light));
    if (!lights)
        return;
    pb_bake_lights(s, lights);
    int glass = pb_scene_glass_materials(s) != 0;
    float w = 4.f * PI_F / (float)p->rays_per_probe;
    for (uint32_t local = 0; local < p->probe_count; ++local) {
        uint32_t probe = slot_of(p, local);
        float c[27] = {0}, backfaces = 0.f, hits = 0.f;
        float back_t = p->max_distance, front_t = p->max_distance, back_d[3] = {0, 0, 0}, front_d[3] = {0, 0, 0};
        for (uint32_t r = 0; r < p->rays_per_probe; ++r) {
            float d[3], y[9];
            probe_ray_direction(p, probe, r, d);
            const float *o = rays + 4 * ((size_t)local * p->rays_per_probe + r);
            pb_sh_basis(d, y);
            for (int k = 0; k < 9; ++k) {
                c[3 * k] += w * o[0] * y[k];
                c[3 * k + 1] += w * o[1] * y[k];
                c[3 * k + 2] += w * o[2] * y[k];
            }
            if (p->nee) {
                const float *nr = p->nee + 8 * ((size_t)local * p->rays_per_probe + r);
                pb_sh_basis(nr + 4, y);
                for (int k = 0; k < 9; ++k) {
                    c[3 * k] += w * nr[0] * y[k];
                    c[3 * k + 1] += w * nr[1] * y[k];
                    c[3 * k + 2] += w * nr[2] * y[k];
                }
            }
            backfaces += o[3] < 0.f ? 1.f : 0.f;
            hits += fabsf(o[3]) < p->max_distance ? 1.f : 0.f;
            if (o[3] < 0.f && -o[3] < back_t) {
                back_t = -o[3];
                memcpy(back_d, d, sizeof d);
            } else if (o[3] >= 0.f && o[3] < front_t) {
                front_t = o[3];
                memcpy(front_d, d, sizeof d);
            }
        }
        if (p->direct) {
            const float *x = p->probes + 4 * (size_t)probe;
            for (uint32_t k = 0; k < s->light_count; ++k) {
                const gpu_light *l = &lights[k];
                float E[3], n0[3] = {0, 0, 0};
                light_irradiance(p, glass, l, x, n0, NULL, 0, E);
                if (E[0] == 0.f && E[1] == 0.f && E[2] == 0.f)
                    continue;
                float to[3];
                if ((uint32_t)l->position_type[3] == PB_LIGHT_DIRECTIONAL) {
                    for (int j = 0; j < 3; ++j)
                        to[j] = -l->direction_range[j];
                } else {
                    float v[3] = {l->position_type[0] - x[0], l->position_type[1] - x[1], l->position_type[2] - x[2]};
                    float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                    for (int j = 0; j < 3; ++j)
                        to[j] = v[j] / len;
                }
                pb_sh_add_delta(c, to, E);
            }
        }
        float *out = reduced + PB_REDUCED_SH_STRIDE * (size_t)local;
        memcpy(out, c, sizeof c);
        out[27] = backfaces, out[28] = hits;
        out[29] = back_t, out[30] = back_d[0], out[31] = back_d[1], out[32] = back_d[2];
        out[33] = front_t, out[34] = front_d[0], out[35] = front_d[1], out[36] = front_d[2];
        out[37] = out[38] = out[39] = 0.f;
    }
    free(lights);
}

void pb_bake_depth_cpu(const pb_bake_pass *p, const float *rays, float *reduced)
{
    uint32_t n = p->octmap_res, texels = n * n;
    float cutoff = pb_depth_lobe_cutoff(p->lobe_power);
    for (uint64_t i = 0; i < (uint64_t)p->probe_count * texels; ++i) {
        uint32_t local = (uint32_t)(i / texels), texel = (uint32_t)(i % texels);
        uint32_t probe = slot_of(p, local);
        float td[3], tl[3];
        pb_oct_texel_direction(texel % n, texel / n, n, td);
        /* the lobe test in the probe's unrotated frame, where the kernel's ray
         * lists live (depth_lists.h): the texel turned back, the rays as stored */
        pb_depth_unrotate(p->rotations + 12 * (size_t)probe, td, tl);
        float wsum = 0.f, m1 = 0.f, m2 = 0.f;
        for (uint32_t r = 0; r < p->rays_per_probe; ++r) {
            const float *d = p->directions + 4 * (size_t)r;
            float c = (tl[0] * d[0] + tl[1] * d[1]) + tl[2] * d[2];
            if (c <= cutoff)
                continue;
            float w = powf(c, p->lobe_power);
            float dist = fminf(fabsf(rays[4 * ((size_t)local * p->rays_per_probe + r) + 3]), p->max_distance);
            wsum += w;
            m1 += w * dist;
            m2 += w * dist * dist;
        }
        float *out = reduced + PB_REDUCED_SH_STRIDE * (size_t)p->probe_count + 2 * i;
        out[0] = wsum > 0.f ? m1 / wsum : p->max_distance;
        out[1] = wsum > 0.f ? m2 / wsum : p->max_distance * p->max_distance;
    }
}
