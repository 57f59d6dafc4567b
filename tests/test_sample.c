/* The run-time sampling function (shaders/include/probe_sample_core.glsl)
 * against its C reference, and against physics: a volume baked under a
 * constant sky samples to pi L everywhere; behind a thin wall the probes on
 * the lit side are not seen (Chebyshev visibility), in front of it they are. */
#include "scenes_gen.h"

static pb_context *ctx;

/* Bakes s with d; the volume is the caller's (pb_volume_free). */
static int bake(const pb_scene *s, const pb_bake_desc *d, pb_volume *v)
{
    pb_bvh *bvh = NULL;
    pb_gpu_scene *gs = NULL;
    pb_error err;
    int ok = pb_bvh_build(s, NULL, &bvh, &err) == PB_OK && pb_gpu_scene_create(ctx, s, bvh, &gs, &err) == PB_OK &&
             pb_bake(ctx, s, gs, d, v, &err) == PB_OK;
    if (!ok) {
        fprintf(stderr, "  bake: %s\n", err.message);
        t_failures++;
    }
    pb_gpu_scene_destroy(gs);
    pb_bvh_destroy(bvh);
    return ok;
}

/* Random queries over the scene's bounds (and a margin outside, where the
 * cage clamps), random normals and views: the kernel against
 * pb_sample_cpu. Returns the queries beyond 1e-4 relative. */
static uint32_t gpu_against_cpu(const pb_scene *s, const pb_sample_volume *sv, uint32_t n, double *scale_out)
{
    pb_error err;
    float *p = malloc(n * 16), *nn = malloc(n * 16), *vw = malloc(n * 16), *g = malloc(n * 16);
    test_rng r = {3};
    for (uint32_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            float lo = s->bounds_min[k] - 0.3f, hi = s->bounds_max[k] + 0.3f;
            p[4 * i + k] = lo + (hi - lo) * (float)rng_uniform(&r);
        }
        rng_direction(&r, nn + 4 * i);
        rng_direction(&r, vw + 4 * i);
        p[4 * i + 3] = nn[4 * i + 3] = vw[4 * i + 3] = 0.f;
    }
    uint32_t bad = n;
    double worst = 0, scale = 0;
    if (pb_sample_gpu(ctx, sv, p, nn, vw, n, g, &err) != PB_OK) {
        fprintf(stderr, "  pb_sample_gpu: %s\n", err.message);
    } else {
        bad = 0;
        for (uint32_t i = 0; i < n; ++i) {
            float c[3];
            pb_sample_cpu(sv, p + 4 * i, nn + 4 * i, vw + 4 * i, c);
            for (int k = 0; k < 3; ++k) {
                double diff = fabs(c[k] - g[4 * i + k]);
                worst = fmax(worst, diff);
                scale = fmax(scale, fabs(c[k]));
                bad += diff > 1e-4 * fmax(1.0, fabs(c[k])) || !isfinite(g[4 * i + k]);
            }
        }
        fprintf(stderr, "  %u queries: largest |GPU - CPU| %.2e (values up to %.2f), %u beyond 1e-4 relative\n", n,
                worst, scale, bad);
    }
    *scale_out = scale;
    free(p), free(nn), free(vw), free(g);
    return bad;
}

static void shader_matches_c_reference(void)
{
    pb_scene *s = load_demo();
    pb_error err;
    if (!s)
        return;
    pb_bake_desc d = {0};
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, 60, &d.grid);
    d.rays_per_probe = 64;
    d.passes = 1;
    d.bounces = 1;
    d.octmap_res = 8;
    pb_volume v;
    if (bake(s, &d, &v)) {
        pb_sample_volume sv;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        double scale;
        CHECK(gpu_against_cpu(s, &sv, 20000, &scale) == 0 && scale > 0);
        pb_sample_volume_free(&sv);
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* The sparse lookup (indirection, chunks, bricks) in the kernel against
 * pb_sample_cpu, on a sparse bake of the demo scene refined to all three
 * levels, so every path of the lookup runs: a cell of depth 0, and chunks
 * of depth 1 and 2 naming bricks of each level. */
static void sparse_shader_matches_c_reference(void)
{
    pb_scene *s = load_demo();
    pb_error err;
    if (!s)
        return;
    pb_bake_desc d = {0};
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, 4000, &d.grid);
    d.rays_per_probe = 32;
    d.passes = 1;
    d.bounces = 1;
    d.octmap_res = 4;
    pb_sparse_desc sd = {3, 0.05f};
    pb_sparse_stats st;
    pb_volume v;
    pb_bvh *bvh = NULL;
    pb_gpu_scene *gs = NULL;
    int ok = pb_bvh_build(s, NULL, &bvh, &err) == PB_OK && pb_gpu_scene_create(ctx, s, bvh, &gs, &err) == PB_OK &&
             pb_bake_sparse(ctx, s, gs, &d, &sd, &v, &st, &err) == PB_OK;
    CHECKF(ok, "%s", err.message);
    if (ok) {
        fprintf(stderr, "  bricks per level %u %u %u, %u probes\n", st.bricks[0], st.bricks[1], st.bricks[2],
                v.probe_count);
        CHECK(st.bricks[0] > 0 && st.bricks[1] > 0 && st.bricks[2] > 0);
        pb_sample_volume sv;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        CHECK(sv.levels == 3);
        double scale;
        CHECK(gpu_against_cpu(s, &sv, 20000, &scale) == 0 && scale > 0);
        pb_sample_volume_free(&sv);
        pb_volume_free(&v);
    }
    pb_gpu_scene_destroy(gs);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
}

/* A floor under a constant sky, probes 3x2x3 above it: the sampled
 * irradiance is pi L for upward normals at any point over the floor, since
 * every probe sees the sky's upper hemisphere unoccluded (the floor itself
 * is black), and a hemisphere's irradiance is exact at SH L1. The floor is
 * 10 km wide: the sky a probe sees below its horizon past the floor's edge
 * would otherwise add about Omega / 4 pi (0.5 % at 50 m). */
static void constant_sky_constant_irradiance(void)
{
    double floor[18] = {-5e3, 0, -5e3, -5e3, 0, 5e3, 5e3, 0, 5e3, -5e3, 0, -5e3, 5e3, 0, 5e3, 5e3, 0, -5e3};
    pb_material m = pb_material_default();
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.f;
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_from_triangles(floor, 2, NULL, &m, 1, &s, &err) == PB_OK, "%s", err.message);
    pb_bake_desc d = {0};
    d.grid.counts[0] = 3, d.grid.counts[1] = 2, d.grid.counts[2] = 3;
    for (int k = 0; k < 3; ++k) {
        d.grid.spacing[k] = 1.f;
        d.grid.origin[k] = (k == 1 ? 0.5f : -1.f) - (float)s->origin[k];
    }
    d.rays_per_probe = 1024;
    d.passes = 1;
    d.octmap_res = 8;
    d.sky[0] = 0.5f, d.sky[1] = 1.f, d.sky[2] = 2.f;
    pb_volume v;
    if (bake(s, &d, &v)) {
        pb_sample_volume sv;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        test_rng r = {9};
        float worst = 0;
        for (int i = 0; i < 2000; ++i) {
            float p[3] = {(float)(3 * rng_uniform(&r) - 1.5), (float)(0.01 + 1.5 * rng_uniform(&r)),
                          (float)(3 * rng_uniform(&r) - 1.5)};
            for (int k = 0; k < 3; ++k)
                p[k] -= (float)s->origin[k];
            float up[3] = {0, 1, 0}, e[3];
            pb_sample_cpu(&sv, p, up, up, e);
            for (int k = 0; k < 3; ++k)
                worst = fmaxf(worst, fabsf(e[k] / (3.14159265f * d.sky[k]) - 1.f));
        }
        fprintf(stderr, "  E / (pi L) - 1 for upward normals: at most %.2e over 2000 points\n", worst);
        CHECK(worst < 2e-3f);
        pb_sample_volume_free(&sv);
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* A 2 cm thick wall at x = 0 (20 x 20 m), a point light at x = -2, direct
 * light only; probes at x = -0.75, -0.25, 0.25, 0.75. A point 0.1 m behind the
 * wall, facing away from it, sits in a cage with lit probes at x = -0.25:
 * they must not light it (their depth towards it is the wall); a point 0.1 m
 * in front, facing the light, is lit. */
static void thin_wall_visibility(void)
{
    double p[12 * 9];
    /* a box [-0.01, 0.01] x [-10, 10] x [-10, 10], outward faces */
    double lo[3] = {-0.01, -10, -10}, hi[3] = {0.01, 10, 10};
    box_tris(p, lo, hi, 0);
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_from_triangles(p, 12, NULL, NULL, 0, &s, &err) == PB_OK, "%s", err.message);
    s->lights = calloc(1, sizeof(pb_light));
    s->light_count = 1;
    pb_light *l = &s->lights[0];
    l->type = PB_LIGHT_POINT;
    l->color[0] = l->color[1] = l->color[2] = 1.f;
    l->intensity = 10.f;
    l->position[0] = (float)(-2.0 - s->origin[0]);
    l->position[1] = (float)-s->origin[1];
    l->position[2] = (float)-s->origin[2];
    pb_bake_desc d = {0};
    d.grid.counts[0] = 4, d.grid.counts[1] = 2, d.grid.counts[2] = 2;
    d.grid.spacing[0] = d.grid.spacing[1] = d.grid.spacing[2] = 0.5f;
    d.grid.origin[0] = -0.75f - (float)s->origin[0];
    d.grid.origin[1] = -0.25f - (float)s->origin[1];
    d.grid.origin[2] = -0.25f - (float)s->origin[2];
    d.rays_per_probe = 1024;
    d.passes = 1;
    d.bounces = 0;
    d.octmap_res = 16;
    d.skip_relocation = 1;
    pb_volume v;
    if (bake(s, &d, &v)) {
        pb_sample_volume sv;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        float behind[3] = {0.1f, 0.f, 0.f}, front[3] = {-0.1f, 0.f, 0.f};
        for (int k = 0; k < 3; ++k)
            behind[k] -= (float)s->origin[k], front[k] -= (float)s->origin[k];
        float px[3] = {1, 0, 0}, nx[3] = {-1, 0, 0}, eb[3], ef[3];
        pb_sample_cpu(&sv, behind, px, px, eb);
        pb_sample_cpu(&sv, front, nx, nx, ef);
        /* the lit probes' own irradiance towards -x, for scale */
        float lit[3];
        pb_sh_eval(v.sh + 27 * 1, nx, lit);
        fprintf(stderr, "  behind the wall %.4g, in front %.4g (a lit probe: %.4g)\n", eb[0], ef[0], lit[0]);
        CHECK(lit[0] > 0.1f);
        CHECK(ef[0] > 0.5f * lit[0]);
        CHECK(eb[0] < 0.01f * lit[0]);
        pb_sample_volume_free(&sv);
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* Two closed rooms (x < 0 and x > 0, 2 x 2 x 2 m each) split by a wall 5 mm
 * thick, 1 % of the 0.5 m probe spacing; a point light in the left room.
 * No light reaches the right room, but every cage around the wall holds
 * probes from both sides: through the sampler, points in the dark room
 * (on its floor, walls and the wall's dark face) must get under 2 % of what
 * the mirrored points in the lit room get. */
static void thin_wall_between_rooms(void)
{
    double p[24 * 9];
    double lo[3] = {-2, 0, -1}, hi[3] = {2, 2, 1}, wlo[3] = {-0.0025, 0, -1}, whi[3] = {0.0025, 2, 1};
    uint32_t n = box_tris(p, lo, hi, 1);
    n += box_tris(p + 9 * n, wlo, whi, 0);
    pb_material m = pb_material_default();
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.7f;
    m.metallic = 0.f;
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_from_triangles(p, n, NULL, &m, 1, &s, &err) == PB_OK, "%s", err.message);
    if (!s)
        return;
    s->lights = calloc(1, sizeof(pb_light));
    s->light_count = 1;
    s->lights[0].type = PB_LIGHT_POINT;
    s->lights[0].color[0] = s->lights[0].color[1] = s->lights[0].color[2] = 1.f;
    s->lights[0].intensity = 20.f;
    double lp[3] = {-1, 1.2, 0.3};
    for (int k = 0; k < 3; ++k)
        s->lights[0].position[k] = (float)(lp[k] - s->origin[k]);
    pb_bake_desc d = {0};
    d.grid.counts[0] = 8, d.grid.counts[1] = 4, d.grid.counts[2] = 4;
    for (int k = 0; k < 3; ++k) {
        d.grid.spacing[k] = 0.5f;
        d.grid.origin[k] = (float)((k == 0 ? -1.75 : k == 1 ? 0.25 : -0.75) - s->origin[k]);
    }
    d.rays_per_probe = 512, d.passes = 2, d.bounces = 2, d.octmap_res = 16;
    pb_volume v;
    if (bake(s, &d, &v)) {
        pb_sample_volume sv;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        /* points on the floor, the far walls and the wall's faces, mirrored across x = 0 */
        test_rng r = {21};
        double dark = 0, lit = 0, worst = 0;
        for (int i = 0; i < 400; ++i) {
            float q[3], nrm[3] = {0, 0, 0};
            int kind = i % 4;
            float a = (float)rng_uniform(&r), b = (float)rng_uniform(&r);
            if (kind == 0) { /* floor */
                q[0] = 0.02f + 1.9f * a, q[1] = 0.001f, q[2] = -0.95f + 1.9f * b, nrm[1] = 1.f;
            } else if (kind == 1) { /* the dividing wall's face */
                q[0] = 0.0026f, q[1] = 0.05f + 1.9f * a, q[2] = -0.95f + 1.9f * b, nrm[0] = 1.f;
            } else if (kind == 2) { /* the far end wall */
                q[0] = 1.999f, q[1] = 0.05f + 1.9f * a, q[2] = -0.95f + 1.9f * b, nrm[0] = -1.f;
            } else { /* the ceiling */
                q[0] = 0.02f + 1.9f * a, q[1] = 1.999f, q[2] = -0.95f + 1.9f * b, nrm[1] = -1.f;
            }
            float qd[3], ql[3], nd[3], nl[3], ed[3], el[3];
            for (int k = 0; k < 3; ++k) {
                qd[k] = (float)(q[k] - s->origin[k]);
                ql[k] = (float)((k == 0 ? -q[k] : q[k]) - s->origin[k]);
                nd[k] = nrm[k], nl[k] = k == 0 ? -nrm[k] : nrm[k];
            }
            pb_sample_cpu(&sv, qd, nd, nd, ed);
            pb_sample_cpu(&sv, ql, nl, nl, el);
            dark += ed[0], lit += el[0];
            if (kind == 1)
                worst = fmax(worst, ed[0] / fmax(1e-6, el[0]));
        }
        fprintf(stderr, "  dark room / lit room irradiance: %.4f on average, %.4f worst on the wall's dark face "
                "(wall 1%% of the spacing)\n", dark / lit, worst);
        CHECK(lit > 0 && dark / lit < 0.02);
        pb_sample_volume_free(&sv);
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* A probe lit by a single delta (an HDR sun) has negative L2 irradiance
 * behind it (-0.04 of the peak); the sampler never returns a negative or
 * NaN irradiance, on the device or in C. */
static void ringing_never_negative(void)
{
    pb_volume v;
    memset(&v, 0, sizeof v);
    v.flags = PB_VOLUME_IRRADIANCE | PB_VOLUME_GRID;
    v.probe_count = 2;
    v.counts[0] = 2, v.counts[1] = v.counts[2] = 1;
    v.spacing[0] = 1.0;
    v.octmap_res = 4;
    v.settings.max_distance = 10.f;
    pb_error err;
    CHECK(pb_volume_alloc(&v, &err) == PB_OK);
    float sun[3] = {0.3f, 0.8f, -0.52f}, e0[3] = {1e5f, 1e5f, 1e5f};
    float l = sqrtf(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]);
    for (int k = 0; k < 3; ++k)
        sun[k] /= l;
    for (uint32_t p = 0; p < 2; ++p) {
        v.base[3 * p] = (float)p;
        v.probe_flags[p] = PB_PROBE_VALID;
        pb_sh_add_delta(v.sh + 27 * p, sun, e0);
        pb_sh_radiance_to_irradiance(v.sh + 27 * p);
        for (uint64_t t = 0; t < pb_volume_tile_halves(4) / 2; ++t) {
            v.depth[pb_volume_tile_halves(4) * p + 2 * t] = pb_half_from_float(5.f);
            v.depth[pb_volume_tile_halves(4) * p + 2 * t + 1] = pb_half_from_float(25.f);
        }
    }
    double o[3] = {0, 0, 0};
    pb_sample_volume sv;
    CHECK(pb_sample_volume_build(&v, o, 0.f, 0.f, &sv, &err) == PB_OK);
    uint32_t n = 4096, bad = 0;
    float *pt = malloc(n * 16), *nn = malloc(n * 16), *g = malloc(n * 16);
    test_rng r = {4};
    float raw_min = 0.f;
    for (uint32_t i = 0; i < n; ++i) {
        pt[4 * i] = (float)rng_uniform(&r), pt[4 * i + 1] = pt[4 * i + 2] = 0.f, pt[4 * i + 3] = 0.f;
        rng_direction(&r, nn + 4 * i);
        nn[4 * i + 3] = 0.f;
        float e[3];
        pb_sh_eval(v.sh, nn + 4 * i, e);
        raw_min = fminf(raw_min, e[0]);
    }
    CHECKF(pb_sample_gpu(ctx, &sv, pt, nn, nn, n, g, &err) == PB_OK, "%s", err.message);
    for (uint32_t i = 0; i < n; ++i) {
        float c[3];
        pb_sample_cpu(&sv, pt + 4 * i, nn + 4 * i, nn + 4 * i, c);
        for (int k = 0; k < 3; ++k)
            bad += !(c[k] >= 0.f) || !(g[4 * i + k] >= 0.f) || !isfinite(g[4 * i + k]);
    }
    fprintf(stderr, "  raw SH down to %.3g of the peak; sampled: %u negative or NaN of %u\n", raw_min / 1.0625e5f, bad,
            3 * n);
    CHECK(raw_min < 0.f && bad == 0);
    free(pt), free(nn), free(g);
    pb_sample_volume_free(&sv);
    pb_volume_free(&v);
}

/* pb_sample_volume_adopt takes the volume's SH and depth arrays instead of
 * copying them: the same sampler as pb_sample_volume_build, word for word
 * (each texel's mean in the low half of its word), the volume's two arrays
 * gone; refused, it leaves the volume whole. */
static void adopted_sampler_is_the_copied_one(void)
{
    pb_volume v;
    memset(&v, 0, sizeof v);
    v.flags = PB_VOLUME_IRRADIANCE | PB_VOLUME_GRID;
    v.probe_count = 12;
    v.counts[0] = 3, v.counts[1] = 2, v.counts[2] = 2;
    v.spacing[0] = v.spacing[1] = v.spacing[2] = 0.5;
    v.origin[0] = 1.0;
    v.octmap_res = 6;
    v.settings.max_distance = 10.f;
    pb_error err;
    CHECK(pb_volume_alloc(&v, &err) == PB_OK);
    uint64_t halves = pb_volume_tile_halves(v.octmap_res) * (uint64_t)v.probe_count;
    for (uint32_t p = 0; p < v.probe_count; ++p) {
        v.offset[3 * p + 1] = 0.01f * (float)p;
        v.probe_flags[p] = p % 5 ? PB_PROBE_VALID : PB_PROBE_RELOCATED;
    }
    for (uint32_t i = 0; i < 27 * v.probe_count; ++i)
        v.sh[i] = 0.25f * (float)i - 3.f;
    for (uint64_t h = 0; h < halves; ++h)
        v.depth[h] = (uint16_t)(h * 7919u + 13u);
    double o[3] = {0.5, -1.0, 2.0};
    pb_sample_volume copied, adopted;
    CHECK(pb_sample_volume_build(&v, o, 0.f, 0.f, &copied, &err) == PB_OK);
    uint16_t first_mean = v.depth[0], first_square = v.depth[1];
    const float *sh = v.sh;
    CHECK(pb_sample_volume_adopt(&v, o, 0.f, 0.f, &adopted, &err) == PB_OK);
    uint32_t P = v.probe_count;
    int same = !memcmp(copied.probes, adopted.probes, (size_t)P * 16) &&
               !memcmp(copied.sh, adopted.sh, (size_t)P * 27 * sizeof(float)) &&
               !memcmp(copied.depth, adopted.depth, halves / 2 * sizeof(uint32_t)) &&
               !memcmp(copied.origin, adopted.origin, sizeof copied.origin) &&
               copied.probe_count == adopted.probe_count && copied.octmap_res == adopted.octmap_res &&
               copied.depth_unit == adopted.depth_unit;
    fprintf(stderr, "  adopted sampler %s the copied one; the volume's arrays %s\n", same ? "is" : "DIFFERS FROM",
            !v.sh && !v.depth ? "taken" : "LEFT");
    CHECK(same && adopted.sh == sh && !v.sh && !v.depth);
    CHECK(adopted.depth[0] == ((uint32_t)first_mean | (uint32_t)first_square << 16));
    float pt[3] = {0.9f, -0.7f, -1.8f}, n[3] = {0.f, 1.f, 0.f}, a[3], b[3];
    pb_sample_cpu(&copied, pt, n, n, a);
    pb_sample_cpu(&adopted, pt, n, n, b);
    CHECK(!memcmp(a, b, sizeof a));
    pb_sample_volume_free(&copied);
    pb_sample_volume_free(&adopted);
    /* a point set: refused, its arrays its own */
    v.flags = PB_VOLUME_IRRADIANCE;
    pb_volume_free_probes(&v);
    CHECK(pb_volume_alloc(&v, &err) == PB_OK);
    const float *kept_sh = v.sh;
    const uint16_t *kept_depth = v.depth;
    CHECK(pb_sample_volume_adopt(&v, o, 0.f, 0.f, &adopted, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "point set") && v.sh == kept_sh && v.depth == kept_depth);
    pb_volume_free(&v);
}

static void point_sets_refused(void)
{
    pb_volume v;
    memset(&v, 0, sizeof v);
    v.probe_count = 1;
    v.octmap_res = 4;
    pb_sample_volume sv;
    pb_error err;
    double o[3] = {0, 0, 0};
    CHECK(pb_sample_volume_build(&v, o, 0.f, 0.f, &sv, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "point set"));
}

int main(void)
{
    if (!(ctx = test_gpu_context()))
        return 1;
    RUN(shader_matches_c_reference);
    RUN(sparse_shader_matches_c_reference);
    RUN(constant_sky_constant_irradiance);
    RUN(thin_wall_visibility);
    RUN(thin_wall_between_rooms);
    RUN(ringing_never_negative);
    RUN(point_sets_refused);
    RUN(adopted_sampler_is_the_copied_one);
    return test_gpu_finish(ctx);
}
