/* The renderer: render.comp against pb_render_cpu in every mode, a constant
 * sky volume lighting a floor evenly, the reference converging like
 * 1/sqrt(spp), and the display pipeline (tone curve, exposure, heat map). */
#include "scenes_gen.h"
#include "render/render_types.h"
#include "sample/sample_gpu.h"

static pb_context *ctx;

typedef struct prepared {
    pb_scene *s;
    pb_bvh *bvh;
    pb_gpu_scene *gs;
    pb_volume vol;
    pb_sample_volume sv;
} prepared;

/* The scene on the device and, with bd, a volume baked from it: a grid, or
 * with sd a sparse layout. */
static int prepare_layout(pb_scene *s, const pb_bake_desc *bd, const pb_sparse_desc *sd, prepared *p)
{
    memset(p, 0, sizeof *p);
    p->s = s;
    pb_error err;
    if (pb_bvh_build(s, NULL, &p->bvh, &err) != PB_OK || pb_gpu_scene_create(ctx, s, p->bvh, &p->gs, &err) != PB_OK ||
        (bd && ((sd ? pb_bake_sparse(ctx, s, p->gs, bd, sd, &p->vol, NULL, &err)
                    : pb_bake(ctx, s, p->gs, bd, &p->vol, &err)) != PB_OK ||
                pb_sample_volume_build(&p->vol, s->origin, 0.f, 0.f, &p->sv, &err) != PB_OK))) {
        fprintf(stderr, "  prepare: %s\n", err.message);
        t_failures++;
        return 0;
    }
    return 1;
}

static int prepare(pb_scene *s, const pb_bake_desc *bd, prepared *p)
{
    return prepare_layout(s, bd, NULL, p);
}

static void release(prepared *p)
{
    pb_sample_volume_free(&p->sv);
    pb_volume_free(&p->vol);
    pb_gpu_scene_destroy(p->gs);
    pb_bvh_destroy(p->bvh);
    pb_scene_destroy(p->s);
}

static float lum(const float *c)
{
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

/* Every mode on the demo scene, GPU against CPU: pixel by pixel for the
 * modes whose randomness stops at the first hit (rounding of sin/cos can
 * still flip a rare shadow ray), image means for the reference. With sd, the
 * volume is a sparse layout (the sparse lookup and sphere view in
 * render.comp against render_cpu.c). */
static void render_matches_cpu(const pb_sparse_desc *sd, int bent)
{
    pb_scene *s = load_demo();
    pb_error err;
    if (!s)
        return;
    if (bent) /* shading normals: every mode shades with them */
        bend_normals(s, 0.4f);
    if (bent >= 2) /* and a normal map bends them */
        CHECK(give_normal_map(s, 8, 0.6f, 3));
    if (bent == 3) /* in the file's tangent frames */
        CHECK(give_tangents(s));
    pb_bake_desc bd = {0};
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, sd ? 500 : 60, &bd.grid);
    bd.rays_per_probe = sd ? 32 : 64;
    bd.passes = 1;
    bd.bounces = 1;
    bd.octmap_res = 8;
    prepared p;
    if (!prepare_layout(s, &bd, sd, &p)) {
        release(&p);
        return;
    }
    uint32_t W = 40, H = 30, n = W * H;
    float *g = malloc(n * 16), *c = malloc(n * 16), *gd = malloc(n * 16), *cd = malloc(n * 16);
    const char *names[6] = {"direct", "reference", "probes", "indirect", "spheres", "direct, by area"};
    float *plain = malloc(n * 16), *direct = malloc(n * 16);
    for (int pass = 0; pass < 6; ++pass) {
        int mode = pass == 4 ? PB_RENDER_PROBES : pass == 5 ? PB_RENDER_DIRECT : pass;
        pb_render_desc d;
        memset(&d, 0, sizeof d);
        d.show_probes = pass == 4;
        d.emitters_by_area = pass == 5; /* the panel's light samples drawn by area, not by solid angle */
        pb_camera_from_scene(&s->cameras[0], &d.camera);
        d.width = W, d.height = H;
        d.mode = (pb_render_mode)mode;
        d.spp = mode == PB_RENDER_REFERENCE ? 64 : 1; /* more than one dispatch's worth of samples */
        d.bounces = 3;
        d.volume = &p.sv;
        d.volume_direct = (p.vol.flags & PB_VOLUME_DIRECT) != 0;
        CHECKF(pb_render(ctx, s, p.gs, &d, g, gd, NULL, &err) == PB_OK, "%s", err.message);
        CHECKF(pb_render_cpu(s, p.bvh, &d, c, cd, &err) == PB_OK, "%s", err.message);
        uint32_t differ = 0, nonfinite = 0;
        double mg = 0, mc = 0;
        for (uint32_t i = 0; i < n; ++i) {
            float a = lum(g + 4 * i), b = lum(c + 4 * i);
            differ += fabsf(a - b) > 1e-3f * fmaxf(1.f, b) || g[4 * i + 3] != c[4 * i + 3];
            nonfinite += !isfinite(a) || !isfinite(lum(gd + 4 * i));
            mg += a, mc += b;
        }
        double rel = fabs(mg - mc) / mc;

        fprintf(stderr, "  %-9s: %u of %u pixels differ, image means differ by %.3f%%\n", names[pass], differ, n,
                100 * rel);
        if (pass == PB_RENDER_PROBES)
            memcpy(plain, g, n * 16);
        if (pass == 0)
            memcpy(direct, g, n * 16);
        if (pass == 0 && bent >= 2) { /* the normal map bends what direct light shows */
            for (uint32_t m = 0; m < s->material_count; ++m)
                s->materials[m].normal_texture = -1;
            CHECKF(pb_render_cpu(s, p.bvh, &d, c, cd, &err) == PB_OK, "%s", err.message);
            for (uint32_t m = 0; m < s->material_count; ++m)
                s->materials[m].normal_texture = (int32_t)s->texture_count - 1;
            uint32_t changed = 0;
            for (uint32_t i = 0; i < n; ++i)
                changed += fabsf(lum(c + 4 * i) - lum(direct + 4 * i)) > 1e-3f * fmaxf(1.f, lum(direct + 4 * i));
            fprintf(stderr, "  %u pixels differ from the CPU's direct image without the normal map\n", changed);
            CHECK(changed > n / 4);
        }
        if (pass == 5) { /* the other sampler: other light samples where the panel lights */
            uint32_t changed = 0;
            for (uint32_t i = 0; i < n; ++i)
                changed += fabsf(lum(g + 4 * i) - lum(direct + 4 * i)) > 1e-3f * fmaxf(1.f, lum(direct + 4 * i));
            fprintf(stderr, "  %u pixels differ from the solid-angle samples\n", changed);
            CHECK(changed > n / 10);
        }
        if (pass == 4) { /* the spheres are there: some pixels changed, not most */
            uint32_t changed = 0;
            for (uint32_t i = 0; i < n; ++i)
                changed += lum(g + 4 * i) != lum(plain + 4 * i);
            fprintf(stderr, "  %u pixels show probe spheres\n", changed);
            CHECK(changed > 0 && changed < n / 2);
        }
        CHECK(nonfinite == 0 && mc > 0);
        if (mode == PB_RENDER_REFERENCE)
            CHECK(rel < 0.02);
        else
            CHECK(differ <= n / 200);
    }
    if (sd) /* refined: chunks and bricks of both levels were looked up */
        CHECK(p.sv.levels == sd->levels && p.vol.sparse && p.vol.sparse->brick_count > 1);
    /* the volume put on the device by the caller (as `render` does, once,
     * before it frees the host's SH and depth): the same probe image, bit
     * for bit, from a sampler without those arrays */
    pb_sample_buffers vb;
    pb_sample_volume layout_only = p.sv;
    layout_only.sh = NULL, layout_only.depth = NULL;
    CHECKF(pb_sample_upload(ctx, &p.sv, &vb, &err) == PB_OK, "%s", err.message);
    pb_render_desc d;
    memset(&d, 0, sizeof d);
    pb_camera_from_scene(&s->cameras[0], &d.camera);
    d.width = W, d.height = H, d.mode = PB_RENDER_PROBES, d.spp = 1, d.bounces = 3;
    d.volume = &layout_only, d.volume_buffers = &vb;
    d.volume_direct = (p.vol.flags & PB_VOLUME_DIRECT) != 0;
    CHECKF(pb_render(ctx, s, p.gs, &d, g, NULL, NULL, &err) == PB_OK, "%s", err.message);
    int same = !memcmp(g, plain, n * 16);
    fprintf(stderr, "  probes, the volume uploaded by the caller: %s image\n", same ? "the same" : "ANOTHER");
    CHECK(same);
    pb_sample_release(ctx, &vb);
    free(g), free(c), free(gd), free(cd), free(plain), free(direct);
    release(&p);
}

static void kernel_matches_cpu_reference(void)
{
    render_matches_cpu(NULL, 0);
}

static void kernel_matches_cpu_with_shading_normals(void)
{
    render_matches_cpu(NULL, 1);
}

static void kernel_matches_cpu_with_normal_maps(void)
{
    render_matches_cpu(NULL, 2);
}

static void kernel_matches_cpu_with_normal_maps_and_tangents(void)
{
    render_matches_cpu(NULL, 3);
}

static void sparse_kernel_matches_cpu_reference(void)
{
    pb_sparse_desc sd = {2, 0.05f};
    render_matches_cpu(&sd, 0);
}

/* A floor of albedo 0.5 under a constant sky L, its volume baked with the
 * floor: in indirect mode every floor pixel is albedo / pi x pi L = 0.5 L
 * (an upward normal's irradiance from a sky hemisphere and a uniform floor
 * is exact at SH L1). */
static void constant_sky_lights_floor_evenly(void)
{
    double floor[18] = {-5e3, 0, -5e3, -5e3, 0, 5e3, 5e3, 0, 5e3, -5e3, 0, -5e3, 5e3, 0, 5e3, 5e3, 0, -5e3};
    pb_material m = pb_material_default();
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.5f;
    m.metallic = 0.f;
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_from_triangles(floor, 2, NULL, &m, 1, &s, &err) == PB_OK, "%s", err.message);
    pb_bake_desc bd = {0};
    bd.grid.counts[0] = 4, bd.grid.counts[1] = 2, bd.grid.counts[2] = 4;
    for (int k = 0; k < 3; ++k) {
        bd.grid.spacing[k] = 1.f;
        bd.grid.origin[k] = (k == 1 ? 0.5f : -1.5f) - (float)s->origin[k];
    }
    bd.rays_per_probe = 1024;
    bd.passes = 1;
    bd.bounces = 1;
    bd.octmap_res = 8;
    bd.sky[0] = bd.sky[1] = bd.sky[2] = 2.f;
    prepared p;
    if (prepare(s, &bd, &p)) {
        uint32_t W = 32, H = 24, n = W * H;
        float *g = malloc(n * 16);
        pb_render_desc d;
        memset(&d, 0, sizeof d);
        float eye[3] = {0.f, 1.2f, 2.f}, target[3] = {0.f, 0.f, 0.f};
        for (int k = 0; k < 3; ++k) {
            d.camera.eye[k] = eye[k] - (float)s->origin[k];
            d.camera.forward[k] = target[k] - eye[k];
        }
        d.camera.up[1] = 1.f;
        d.camera.yfov = 0.6f;
        d.width = W, d.height = H;
        d.mode = PB_RENDER_INDIRECT;
        d.volume = &p.sv;
        d.sky[0] = d.sky[1] = d.sky[2] = 2.f;
        CHECKF(pb_render(ctx, s, p.gs, &d, g, NULL, NULL, &err) == PB_OK, "%s", err.message);
        float worst = 0;
        uint32_t floor_px = 0;
        for (uint32_t i = 0; i < n; ++i)
            if (g[4 * i + 3] > 0.f) {
                ++floor_px;
                for (int k = 0; k < 3; ++k)
                    worst = fmaxf(worst, fabsf(g[4 * i + k] / 1.f - 1.f));
            }
        fprintf(stderr, "  %u floor pixels: radiance / (albedo L) - 1 at most %.2e\n", floor_px, worst);
        CHECK(floor_px > n / 2);
        CHECK(worst < 3e-3f);
        free(g);
    }
    release(&p);
}

/* The reference's error against a 1024-spp render falls like 1/sqrt(spp):
 * the fitted log-log slope over 4, 16 and 64 spp is near -1/2. */
static void reference_converges(void)
{
    pb_scene *s = load_demo();
    pb_error err;
    prepared p;
    if (!s || !prepare(s, NULL, &p)) {
        if (s)
            release(&p);
        return;
    }
    uint32_t W = 24, H = 18, n = W * H;
    float *truth = malloc(n * 16), *img = malloc(n * 16);
    pb_render_desc d;
    memset(&d, 0, sizeof d);
    pb_camera_from_scene(&s->cameras[0], &d.camera);
    d.width = W, d.height = H;
    d.mode = PB_RENDER_REFERENCE;
    d.bounces = 3;
    d.spp = 1024;
    d.seed = 99;
    CHECKF(pb_render(ctx, s, p.gs, &d, truth, NULL, NULL, &err) == PB_OK, "%s", err.message);
    double lx[3], ly[3];
    uint32_t spps[3] = {4, 16, 64};
    for (int i = 0; i < 3; ++i) {
        d.spp = spps[i];
        d.seed = (uint32_t)i + 1;
        CHECKF(pb_render(ctx, s, p.gs, &d, img, NULL, NULL, &err) == PB_OK, "%s", err.message);
        double e = pb_image_relative_rmse(img, truth, W, H);

        lx[i] = log((double)spps[i]), ly[i] = log(e);
        fprintf(stderr, "  %3u spp: relative RMSE %.4f against %u spp\n", spps[i], e, 1024u);
    }
    double mx = (lx[0] + lx[1] + lx[2]) / 3, my = (ly[0] + ly[1] + ly[2]) / 3, sxy = 0, sxx = 0;
    for (int i = 0; i < 3; ++i)
        sxy += (lx[i] - mx) * (ly[i] - my), sxx += (lx[i] - mx) * (lx[i] - mx);
    double slope = sxy / sxx;
    fprintf(stderr, "  log-log slope %.3f (Monte Carlo: -0.5)\n", slope);
    CHECK(slope < -0.35 && slope > -0.65);
    free(truth), free(img);
    release(&p);
}

static void bad_parameters_refused(void)
{
    pb_render_desc d;
    memset(&d, 0, sizeof d);
    d.camera.forward[2] = -1.f, d.camera.up[1] = 1.f, d.camera.yfov = 1.f;
    d.width = 8, d.height = 8;
    d.mode = PB_RENDER_DIRECT;
    pb_error err;
    pb_render_desc b = d;
    b.width = 0;
    CHECK(pb_render_cpu(NULL, NULL, &b, NULL, NULL, &err) == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, "size"));
    b = d, b.camera.yfov = 3.2f;
    CHECK(pb_render_cpu(NULL, NULL, &b, NULL, NULL, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "field of view"));
    b = d, b.camera.up[1] = 0.f, b.camera.up[2] = 1.f;
    CHECK(pb_render_cpu(NULL, NULL, &b, NULL, NULL, &err) == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, "parallel"));
    b = d, b.mode = PB_RENDER_PROBES;
    CHECK(pb_render_cpu(NULL, NULL, &b, NULL, NULL, &err) == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, "volume"));
    b = d, b.camera.eye[0] = NAN;
    CHECK(pb_render_cpu(NULL, NULL, &b, NULL, NULL, &err) == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, "finite"));
}

/* The tone curve and sRGB are monotonic and bounded, exposure scales, auto
 * exposure maps the log-average to middle grey, the heat map is black at 0. */
/* The image metric of `render --mode diff` (issue 14): on a synthetic 5 x 3
 * image with known errors, the surface pixels next to an emitter are left
 * out and the RMSE and p95 come out as computed by hand; on the demo scene
 * the host's pixel classes agree with the kernel's surface mask at 1 spp
 * (a surface wherever the first hit reflects) and find its ceiling panel. */
static void image_metric(void)
{
    /* classes: row 0 = emitter E then surfaces; the two pixels beside E (and
     * the one below it, and diagonal) are left out */
    uint8_t cls[15] = {2, 1, 1, 1, 1,
                       1, 1, 1, 1, 0,
                       1, 1, 1, 1, 1};
    float ref[60], img[60];
    for (int i = 0; i < 15; ++i)
        for (int c = 0; c < 4; ++c)
            ref[4 * i + c] = img[4 * i + c] = 1.f;
    /* luminance 1 everywhere; errors: pixel 1 (excluded, next to E) +9, pixel 7 +0.5, pixel 13 -0.2 */
    for (int c = 0; c < 3; ++c)
        img[4 * 1 + c] = 10.f, img[4 * 7 + c] = 1.5f, img[4 * 13 + c] = 0.8f;
    pb_image_metrics m;
    pb_image_surface_metrics(img, ref, cls, 5, 3, &m);
    /* compared: 15 - 1 emitter - 1 miss - 3 next to E (1, 5, 6) = 10 pixels */
    double rmse = sqrt((0.25 + 0.04) / 10.0);
    fprintf(stderr, "  synthetic: %llu pixels, relative RMSE %.6f (want %.6f), p95 %.4f (want 0.5)\n",
            (unsigned long long)m.pixels, m.relative_rmse, rmse, m.p95_relative);
    CHECK(m.pixels == 10);
    CHECK(fabs(m.relative_rmse - rmse) < 1e-6);
    CHECK(fabs(m.p95_relative - 0.5) < 1e-6); /* sorted: 0 x8, 0.2, 0.5: index round(9 x 0.95) = 9 */

    pb_scene *s = load_demo();
    if (!s)
        return;
    prepared p;
    if (!prepare(s, NULL, &p)) {
        release(&p);
        return;
    }
    uint32_t W = 64, H = 48;
    pb_render_desc d;
    memset(&d, 0, sizeof d);
    pb_camera_from_scene(&s->cameras[0], &d.camera);
    d.width = W, d.height = H, d.mode = PB_RENDER_DIRECT, d.spp = 1;
    float *g = malloc((size_t)W * H * 16);
    uint8_t *c = malloc((size_t)W * H);
    pb_error err;
    if (g && c && pb_render(ctx, s, p.gs, &d, g, NULL, NULL, &err) == PB_OK) {
        pb_render_pixel_classes(s, p.bvh, &d, c);
        uint32_t agree = 0, emitters = 0;
        for (uint32_t i = 0; i < W * H; ++i) {
            agree += (c[i] != PB_PIXEL_NONE) == (g[4 * i + 3] > 0.f);
            emitters += c[i] == PB_PIXEL_EMITTER;
        }
        fprintf(stderr, "  demo: %u of %u pixel classes agree with the kernel's surface mask, %u emitter pixels\n", agree,
                W * H, emitters);
        CHECK(agree == W * H && emitters > 0);
    } else {
        CHECKF(0, "render: %s", err.message);
    }
    free(g), free(c);
    release(&p);
}

static void display_pipeline(void)
{
    float prev = -1.f;
    int mono = 1;
    for (int i = 0; i <= 4000; ++i) {
        float x = powf(10.f, -4.f + i * 0.002f);
        float y = pb_srgb_encode(pb_tonemap_aces(x));
        mono &= y >= prev && y >= 0.f && y <= 1.f;
        prev = y;
    }
    CHECK(mono);
    float img[4 * 4] = {0.5f, 0.5f, 0.5f, 1, 2, 2, 2, 1, 0.5f, 0.5f, 0.5f, 1, 2, 2, 2, 1};
    float ev = pb_auto_exposure(img, 2, 2);
    CHECKF(fabsf(ev - log2f(0.18f / 1.f)) < 1e-3f, "auto exposure %g", ev);
    float neg[8] = {-1.f, -1.f, -1.f, 1, 1, 1, 1, 1}; /* SH ringing can give negative pixels */
    CHECK(isfinite(pb_auto_exposure(neg, 2, 1)));
    /* 95 black surface pixels and 5 of luminance 1 (DamagedHelmet's metal in a
     * diffuse bake): the log-average alone gives EV 10.1, which clips the lit
     * ones 1000-fold; the cap keeps the 99th percentile (1) at 4: EV 2 */
    float dark[4 * 100];
    for (int i = 0; i < 100; ++i)
        for (int c = 0; c < 4; ++c)
            dark[4 * i + c] = c == 3 || i >= 95 ? 1.f : 0.f;
    ev = pb_auto_exposure(dark, 10, 10);
    CHECKF(fabsf(ev - 2.f) < 1e-5f, "auto exposure of a mostly black image %g", ev);
    unsigned char a[12], b[12];
    pb_tonemap_image(img, 2, 2, 0.f, a);
    pb_tonemap_image(img, 2, 2, 1.f, b);
    CHECK(b[0] > a[0] && b[3] >= a[3] && a[3] > a[0]);
    pb_error_heatmap(img, img, 2, 2, 0.5f, a);
    CHECK(a[0] == 0 && a[1] == 0 && a[2] == 0);
    float twice[16];
    for (int i = 0; i < 16; ++i)
        twice[i] = img[i] * ((i % 4) == 3 ? 1.f : 2.f);
    pb_error_heatmap(twice, img, 2, 2, 0.5f, a);
    CHECK(a[0] == 255 && a[1] == 0 && a[2] == 0);
    /* a = 2b: sqrt(mean b^2) / mean b = sqrt((0.25 + 4) / 2) / 1.25 */
    CHECK(fabs(pb_image_relative_rmse(twice, img, 2, 2) - sqrt(2.125) / 1.25) < 1e-6);
}

/* Where the centre ray of view v first meets the scene: 1 a front face, -1 a
 * back face, 0 nothing. */
static int centre_hit(const pb_scene *s, const pb_bvh *bvh, const pb_camera_view *v)
{
    pb_ray r = {{v->eye[0], v->eye[1], v->eye[2]}, 0.f, {v->forward[0], v->forward[1], v->forward[2]}, INFINITY};
    pb_hit h;
    pb_trace_cpu(s, bvh, &r, 1, PB_TRACE_CLOSEST, &h, 1);
    return h.triangle == PB_NO_HIT ? 0 : h.backface ? -1 : 1;
}

static int inside_bounds(const pb_scene *s, const float p[3])
{
    int in = 1;
    for (int k = 0; k < 3; ++k)
        in &= p[k] > s->bounds_min[k] && p[k] < s->bounds_max[k];
    return in;
}

/* A scene without a camera: an object is seen from outside its bounds, a
 * room (or a level) from inside, where its lit fronts are: the view from
 * outside shows only its walls' single-sided backs, which render black. */
static void default_view_sees_fronts(void)
{
    const float yfov = 0.87f;
    pb_error err;
    /* an object: a box facing out; a room: the same box facing in, with a
     * smaller box facing out inside it */
    double lo[3] = {-1, 0, -2}, hi[3] = {1, 1.5, 2}, clo[3] = {-0.3, 0, -0.3}, chi[3] = {0.3, 0.6, 0.3};
    double p[24 * 9];
    for (int room = 0; room < 2; ++room) {
        uint32_t t = box_tris(p, lo, hi, room);
        if (room)
            t += box_tris(p + 9 * t, clo, chi, 0);
        pb_scene *s = NULL;
        pb_bvh *bvh = NULL;
        CHECKF(pb_scene_from_triangles(p, t, NULL, NULL, 0, &s, &err) == PB_OK &&
               pb_bvh_build(s, NULL, &bvh, &err) == PB_OK, "%s", err.message);
        if (!bvh) {
            pb_scene_destroy(s);
            continue;
        }
        pb_camera_view v;
        pb_camera_default(s, bvh, yfov, 4, 3, &v);
        pb_render_desc d = {0};
        d.camera = v, d.width = 8, d.height = 6;
        fprintf(stderr, "  %s: eye (%.2f, %.2f, %.2f), looking (%.2f, %.2f, %.2f): %s the bounds\n",
                room ? "a room" : "an object", v.eye[0], v.eye[1], v.eye[2], v.forward[0], v.forward[1], v.forward[2],
                inside_bounds(s, v.eye) ? "inside" : "outside");
        CHECK(inside_bounds(s, v.eye) == room && centre_hit(s, bvh, &v) == 1 && pb_render_check(&d, &err) == PB_OK);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
    }
    /* the doorway scene (two rooms, a lamp in one, no camera): lit in the
     * default view (path traced), black from outside */
    pb_scene *s = NULL;
    pb_bvh *bvh = NULL;
    CHECKF(pb_scene_load(source_path("tests/scenes/doorway.gltf"), NULL, &s, &err) == PB_OK &&
           pb_bvh_build(s, NULL, &bvh, &err) == PB_OK, "%s", err.message);
    if (bvh) {
        CHECK(s->camera_count == 0);
        pb_render_desc d = {0};
        d.width = 32, d.height = 24, d.mode = PB_RENDER_REFERENCE, d.spp = 4, d.bounces = 3;
        float img[32 * 24 * 4];
        double mean[2] = {0, 0};
        for (int inside = 0; inside < 2; ++inside) {
            pb_camera_default(s, inside ? bvh : NULL, yfov, 32, 24, &d.camera); /* no BVH: the view from outside */
            CHECKF(pb_render_cpu(s, bvh, &d, img, NULL, &err) == PB_OK, "%s", err.message);
            for (int i = 0; i < 32 * 24; ++i)
                mean[inside] += (img[4 * i] + img[4 * i + 1] + img[4 * i + 2]) / (3.0 * 32 * 24);
        }
        fprintf(stderr, "  doorway: mean radiance %.4g from outside, %.4g in the default view\n", mean[0], mean[1]);
        CHECK(mean[0] == 0.0 && mean[1] > 0.0);
    }
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    /* an empty scene: a view of the sky, valid */
    pb_scene *e = NULL;
    CHECKF(pb_scene_from_triangles(NULL, 0, NULL, NULL, 0, &e, &err) == PB_OK, "%s", err.message);
    if (e) {
        pb_render_desc d = {0};
        d.width = 8, d.height = 6;
        pb_camera_default(e, NULL, yfov, 4, 3, &d.camera);
        CHECKF(pb_render_check(&d, &err) == PB_OK, "%s", err.message);
        pb_scene_destroy(e);
    }
}

int main(void)
{
    if (!(ctx = test_gpu_context()))
        return 1;
    RUN(display_pipeline);
    RUN(image_metric);
    RUN(bad_parameters_refused);
    RUN(kernel_matches_cpu_reference);
    RUN(kernel_matches_cpu_with_shading_normals);
    RUN(kernel_matches_cpu_with_normal_maps);
    RUN(kernel_matches_cpu_with_normal_maps_and_tangents);
    RUN(sparse_kernel_matches_cpu_reference);
    RUN(constant_sky_lights_floor_evenly);
    RUN(reference_converges);
    RUN(default_view_sees_fronts);
    return test_gpu_finish(ctx);
}
