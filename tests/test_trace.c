/* The trace kernel against its CPU references, on a Vulkan device with the
 * validation layer on: random soups (also with leaves of 1 to 16), the demo
 * scene and the shared real scenes; watertightness; far offsets; alpha
 * masks; any-hit; bounded submissions; refusals. The last test fails on any
 * validation message. */
#include "scenes_gen.h"
#include "bake/gpu_scene.h"
#include "gpu/gpu.h"
#include "bvh/exact_diff.h"
#include "exact_inputs.h"

#include <stb_image_write.h>

#include <dirent.h>

static pb_context *ctx;

static const pb_log test_log = {test_log_line, NULL};

typedef struct traced {
    pb_bvh *bvh;
    pb_gpu_scene *gs;
} traced;

static int prepare(const pb_scene *s, const pb_bvh_desc *bd, traced *t)
{
    pb_error err;
    t->bvh = NULL;
    t->gs = NULL;
    if (pb_bvh_build(s, bd, &t->bvh, &err) != PB_OK || pb_gpu_scene_create(ctx, s, t->bvh, &t->gs, &err) != PB_OK) {
        fprintf(stderr, "  prepare: %s\n", err.message);
        t_failures++;
        return 0;
    }
    return 1;
}

static void release(traced *t)
{
    pb_gpu_scene_destroy(t->gs);
    pb_bvh_destroy(t->bvh);
}

/* GPU == CPU BVH (== brute force when `brute`) for `rays`, closest and any.
 * The portable run (PB_TEST_PORTABLE_KERNELS) compares its kernels with the
 * same CPU BVH traversal and leaves the brute-force check of that traversal,
 * which no kernel takes part in, to the native run (93 of this suite's 99 s
 * on two AVX2 cores when it checked every ray). */
enum { BRUTE_STRIDE = 4 };

/* `bd`: the BVH's build options (NULL: the defaults). Returns the largest
 * leaf of the BVH it built (0 when it could not build one). */
static uint32_t check_three_ways(const char *what, const pb_scene *s, const pb_bvh_desc *bd, const pb_ray *rays,
                                 uint32_t n, int brute)
{
    if (brute && test_portable_kernels())
        brute = 0;
    traced t;
    if (!prepare(s, bd, &t))
        return 0;
    uint32_t max_leaf = t.bvh->stats.max_leaf_size;
    pb_hit *g = malloc(n * sizeof *g), *c = malloc(n * sizeof *c), *b = malloc(n * sizeof *b);
    pb_error err;
    pb_trace_stats st;
    pb_result r = pb_trace(ctx, t.gs, rays, n, PB_TRACE_CLOSEST, g, &st, &err);
    CHECKF(r == PB_OK, "%s", err.message);
    pb_trace_cpu(s, t.bvh, rays, n, PB_TRACE_CLOSEST, c, 0);
    uint32_t ties = 0, bad = compare_hits(what, rays, g, c, n, &ties);
    /* brute force costs rays x triangles: every 4th ray (25,000 of a case's
     * 100,000) checks the traversal the GPU was just compared with on all */
    uint32_t bad_brute = 0, hits = 0, nb = (n + BRUTE_STRIDE - 1) / BRUTE_STRIDE;
    if (brute) {
        pb_ray *sub = malloc(nb * sizeof *sub);
        pb_hit *cs = malloc(nb * sizeof *cs);
        CHECK(sub && cs);
        if (!sub || !cs)
            nb = 0;
        for (uint32_t i = 0; i < nb; ++i)
            sub[i] = rays[i * BRUTE_STRIDE], cs[i] = c[i * BRUTE_STRIDE];
        pb_trace_brute(s, sub, nb, PB_TRACE_CLOSEST, b, 0);
        bad_brute = compare_hits(what, sub, cs, b, nb, NULL);
        free(sub), free(cs);
    }
    for (uint32_t i = 0; i < n; ++i)
        hits += g[i].triangle != PB_NO_HIT;
    fprintf(stderr, "  %s: %u triangles, %u rays, %u hits, %u ties; GPU vs CPU %u mismatches%s", what,
            s->triangle_count, n, hits, ties, bad,
            brute ? "" : test_portable_kernels() ? "; CPU vs brute force: the native run's\n" : "\n");
    if (brute)
        fprintf(stderr, ", CPU vs brute force %u of %u\n", bad_brute, nb);
    CHECK(bad == 0);
    CHECK(bad_brute == 0);
    CHECK(hits > 0);
    /* any-hit on the GPU: occluded exactly when the closest hit exists */
    r = pb_trace(ctx, t.gs, rays, n, PB_TRACE_ANY, b, NULL, &err);
    CHECKF(r == PB_OK, "%s", err.message);
    uint32_t occ_bad = 0;
    for (uint32_t i = 0; i < n; ++i) {
        int occ = b[i].triangle != PB_NO_HIT;
        occ_bad += occ != (c[i].triangle != PB_NO_HIT);
        if (occ)
            occ_bad += !(b[i].t > rays[i].tmin && b[i].t < rays[i].tmax);
    }
    CHECKF(occ_bad == 0, "%s: any-hit disagrees on %u rays", what, occ_bad);
    free(g), free(c), free(b);
    release(&t);
    return max_leaf;
}

static void random_soups_gpu_cpu_brute(void)
{
    struct {
        uint32_t tris;
        float size;
    } cases[] = {{2000, 0.3f}, {30000, 0.05f}};
    for (int i = 0; i < 2; ++i) {
        pb_scene *s = random_soup(cases[i].tris, cases[i].size, 100 + i, NULL);
        pb_ray *rays = random_rays(s->bounds_min, s->bounds_max, 100000, 200 + i);
        char what[64];
        snprintf(what, sizeof what, "soup %u", cases[i].tris);
        check_three_ways(what, s, NULL, rays, 100000, 1);
        free(rays);
        pb_scene_destroy(s);
    }
}

/* Leaves other than the default (2), up to the builder's bound (16): the
 * kernel's run of a node's hit-leaf triangles is long only with long leaves,
 * and the default BVH no longer has any. */
static void leaf_sizes_gpu_cpu_brute(void)
{
    /* 2000 random triangles, then 4 fans of 40 around shared centres, which
     * splits hardly separate: leaves of 9 or more at the bound 16 */
    enum { SOUP = 2000, FANS = 4, FAN = 40 };
    pb_scene *soup = random_soup(SOUP, 0.6f, 150, NULL);
    double *p = malloc((size_t)(SOUP + FANS * FAN) * 9 * sizeof(double));
    CHECK(soup && p);
    if (!soup || !p) {
        pb_scene_destroy(soup), free(p);
        return;
    }
    for (size_t i = 0; i < (size_t)SOUP * 9; ++i)
        p[i] = soup->positions[i];
    for (int f = 0; f < FANS; ++f)
        for (int k = 0; k < FAN; ++k) {
            double *t = p + 9 * (size_t)(SOUP + f * FAN + k), a = 6.283185307179586 * k / FAN;
            for (int v = 0; v < 3; ++v) {
                double b = a + 2.0943951023931953 * v;
                t[3 * v + 0] = -0.6 + 0.4 * f + 0.3 * cos(b);
                t[3 * v + 1] = 0.3 * sin(b);
                t[3 * v + 2] = (v - 1) * 0.05 * sin(a);
            }
        }
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_from_triangles(p, SOUP + FANS * FAN, NULL, NULL, 0, &s, &err) == PB_OK, "%s", err.message);
    pb_scene_destroy(soup);
    free(p);
    if (!s)
        return;
    uint32_t sizes[] = {1, 8, 16};
    pb_ray *rays = random_rays(s->bounds_min, s->bounds_max, 50000, 250);
    for (int i = 0; i < 3; ++i) {
        pb_bvh_desc bd = {0};
        bd.max_leaf_size = sizes[i];
        char what[64];
        snprintf(what, sizeof what, "soup, leaves of %u", sizes[i]);
        uint32_t built = check_three_ways(what, s, &bd, rays, 50000, 1);
        CHECKF(sizes[i] < 16 ? built == sizes[i] : built > 8, "leaves of at most %u: the largest built has %u triangles",
               sizes[i], built);
    }
    free(rays);
    pb_scene_destroy(s);
}

/* Probe-style rays over a scene's bounds plus random rays inside them. */
static pb_ray *scene_rays(const pb_scene *s, uint32_t n, uint32_t seed)
{
    pb_probe_grid grid;
    uint32_t per_probe = 256, probes = n / 2 / per_probe;
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, probes, &grid);
    probes = pb_probe_grid_count(&grid);
    if ((uint64_t)probes * per_probe > n / 2)
        probes = n / 2 / per_probe;
    pb_ray *rays = random_rays(s->bounds_min, s->bounds_max, n, seed);
    pb_probe_rays(&grid, 0, probes, per_probe, seed, rays);
    return rays;
}

static void demo_scene_gpu_cpu_brute(void)
{
    pb_scene *s = load_demo();
    if (!s)
        return;
    pb_ray *rays = scene_rays(s, 100000, 3);
    check_three_ways("demo", s, NULL, rays, 100000, 1);
    free(rays);
    pb_scene_destroy(s);
}

static void shared_scenes_gpu_cpu_brute(void)
{
    const char *scenes[] = {"cornell/cornellBox.gltf", "openarena/oacmpdm1.glb"};
    int found = 0;
    for (int i = 0; i < 2; ++i) {
        char path[1024];
        snprintf(path, sizeof path, "%s/../shared/scenes/%s", PB_SOURCE_DIR, scenes[i]);
        if (!file_exists(path)) {
            fprintf(stderr, "  %s not present: skipped\n", scenes[i]);
            continue;
        }
        ++found;
        pb_scene *s = NULL;
        pb_error err;
        pb_scene_desc d = {{0}, 1}; /* geometry only */
        CHECKF(pb_scene_load(path, &d, &s, &err) == PB_OK, "%s", err.message);
        if (!s)
            continue;
        pb_ray *rays = scene_rays(s, 100000, 7 + i);
        check_three_ways(scenes[i], s, NULL, rays, 100000, 1);
        free(rays);
        pb_scene_destroy(s);
    }
    if (!found)
        skip("../shared/scenes not present (Cornell box, The Crypt)");
}

static void watertight_sphere_gpu(void)
{
    float *verts;
    uint32_t nv;
    pb_scene *s = closed_sphere(48, 96, &verts, &nv);
    traced t;
    if (!prepare(s, NULL, &t))
        return;
    uint32_t n = 1000000;
    pb_ray *rays = sphere_probe_rays(s, n, 9);
    pb_hit *h = malloc(n * sizeof *h);
    pb_error err;
    CHECKF(pb_trace(ctx, t.gs, rays, n, PB_TRACE_CLOSEST, h, NULL, &err) == PB_OK, "%s", err.message);
    uint32_t escaped = 0;
    for (uint32_t i = 0; i < n; ++i)
        escaped += h[i].triangle == PB_NO_HIT;
    fprintf(stderr, "  GPU: %u rays at vertices and edges of a closed sphere: %u escaped\n", n, escaped);
    CHECK(escaped == 0);
    free(rays), free(h), free(verts);
    release(&t);
    pb_scene_destroy(s);
}

/* The demo scene moved 1e6 m away (a translation on its root node) gives the
 * same hits, in local terms, as at the origin. */
static void far_from_origin_same_hits(void)
{
    char *text = read_text(source_path("tests/scenes/demo.gltf"));
    CHECK(text != NULL);
    if (!text)
        return;
    const char *key = "\"name\": \"room\",";
    char *at = strstr(text, key);
    CHECK(at != NULL);
    if (!at) {
        free(text);
        return;
    }
    size_t pre = (size_t)(at - text) + strlen(key);
    const char *ins = " \"translation\": [1000000.0, -250000.0, 1000000.0],";
    char *moved = malloc(strlen(text) + strlen(ins) + 1);
    memcpy(moved, text, pre);
    strcpy(moved + pre, ins);
    strcat(moved, text + pre);
    const char *far_path = write_file("demo_far.gltf", moved, strlen(moved));
    pb_scene *a = NULL, *b = NULL;
    pb_error err;
    CHECK(pb_scene_load(source_path("tests/scenes/demo.gltf"), NULL, &a, &err) == PB_OK);
    CHECKF(pb_scene_load(far_path, NULL, &b, &err) == PB_OK, "%s", err.message);
    if (a && b) {
        CHECK(b->origin[0] == 1e6 && b->origin[1] == 1.5 - 250000.0 && b->origin[2] == 1e6);
        CHECK(a->triangle_count == b->triangle_count);
        traced ta, tb;
        if (prepare(a, NULL, &ta) && prepare(b, NULL, &tb)) {
            uint32_t n = 100000;
            pb_ray *rays = scene_rays(a, n, 17);
            pb_hit *ha = malloc(n * sizeof *ha), *hb = malloc(n * sizeof *hb);
            CHECK(pb_trace(ctx, ta.gs, rays, n, PB_TRACE_CLOSEST, ha, NULL, &err) == PB_OK);
            CHECK(pb_trace(ctx, tb.gs, rays, n, PB_TRACE_CLOSEST, hb, NULL, &err) == PB_OK);
            uint32_t bad = compare_hits("far", rays, hb, ha, n, NULL);
            fprintf(stderr, "  demo at 1e6 m: %u of %u rays differ from the demo at the origin\n", bad, n);
            CHECK(bad == 0);
            free(rays), free(ha), free(hb);
            release(&ta);
            release(&tb);
        }
    }
    pb_scene_destroy(a);
    pb_scene_destroy(b);
    free(text);
    free(moved);
}

typedef struct png_buf {
    unsigned char data[4096];
    int size;
} png_buf;

static void png_sink(void *user, void *data, int size)
{
    png_buf *b = user;
    if (b->size + size <= (int)sizeof b->data) {
        memcpy(b->data + b->size, data, (size_t)size);
        b->size += size;
    }
}

/* A masked 4x4 checker quad at z=0 over an opaque quad at z=-1: a ray down
 * through a texel centre stops at z=0 exactly when that texel is opaque. */
static void alpha_mask_cuts_out(void)
{
    unsigned char px[4 * 4 * 4];
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            unsigned char *p = px + 4 * (4 * y + x);
            p[0] = p[1] = p[2] = 200;
            p[3] = ((x + y) & 1) ? 0 : 255;
        }
    png_buf png = {{0}, 0};
    CHECK(stbi_write_png_to_func(png_sink, &png, 4, 4, 4, px, 16) != 0);
    char *png64 = base64(png.data, (size_t)png.size);
    /* front quad (-1..1)^2 at z=0 with uv (0,0) at the top-left, back quad at z=-1 */
    float pos[24] = {-1, 1, 0, 1, 1, 0, 1, -1, 0, -1, -1, 0, -1, 1, -1, 1, 1, -1, 1, -1, -1, -1, -1, -1};
    float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    uint16_t idx[6] = {0, 3, 2, 0, 2, 1};
    unsigned char bin[96 + 32 + 12];
    memcpy(bin, pos, 96);
    memcpy(bin + 96, uv, 32);
    memcpy(bin + 128, idx, 12);
    char *bin64 = base64(bin, sizeof bin);
    char *json = malloc(16384);
    snprintf(json, 16384,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1]}],"
             "\"nodes\":[{\"mesh\":0},{\"mesh\":1}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":2},\"indices\":3,"
             "\"material\":0}]},{\"primitives\":[{\"attributes\":{\"POSITION\":1,\"TEXCOORD_0\":2},\"indices\":3,"
             "\"material\":1}]}],"
             "\"materials\":[{\"alphaMode\":\"MASK\",\"alphaCutoff\":0.5,\"doubleSided\":true,"
             "\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}},{}],"
             "\"textures\":[{\"source\":0,\"sampler\":0}],\"samplers\":[{\"wrapS\":33071,\"wrapT\":33071}],"
             "\"images\":[{\"uri\":\"data:image/png;base64,%s\"}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":0,\"byteOffset\":48,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
             "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":96},{\"buffer\":0,\"byteOffset\":96,\"byteLength\":32},"
             "{\"buffer\":0,\"byteOffset\":128,\"byteLength\":12}],"
             "\"buffers\":[{\"byteLength\":140,\"uri\":\"data:application/octet-stream;base64,%s\"}]}",
             png64, bin64);
    const char *path = write_file("alpha.gltf", json, strlen(json));
    free(json), free(png64), free(bin64);
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_load(path, NULL, &s, &err) == PB_OK, "%s", err.message);
    if (!s)
        return;
    CHECK(s->texture_count == 1 && s->materials[0].alpha_mode == PB_ALPHA_MASK);
    traced t;
    if (!prepare(s, NULL, &t)) {
        pb_scene_destroy(s);
        return;
    }
    /* rays through a 64x64 grid; local frame: the scene is rebased to z centre -0.5 */
    uint32_t n = 64 * 64;
    pb_ray *rays = malloc(n * sizeof *rays);
    pb_hit *g = malloc(n * sizeof *g), *c = malloc(n * sizeof *c), *a = malloc(n * sizeof *a);
    int *expect_front = malloc(n * sizeof *expect_front);
    for (uint32_t i = 0; i < n; ++i) {
        float x = -1.f + (2.f * (float)(i % 64) + 1.f) / 64.f, y = 1.f - (2.f * (float)(i / 64) + 1.f) / 64.f;
        pb_ray r = {{x, y, 1.5f}, 0.f, {0, 0, -1}, 1.8f}; /* stops short of the back quad for any-hit */
        rays[i] = r;
        int tx = (int)((x + 1.f) * 2.f), ty = (int)((1.f - y) * 2.f); /* texel under the ray */
        expect_front[i] = ((tx + ty) & 1) == 0;
    }
    CHECK(pb_trace(ctx, t.gs, rays, n, PB_TRACE_CLOSEST, g, NULL, &err) == PB_OK);
    pb_trace_cpu(s, t.bvh, rays, n, PB_TRACE_CLOSEST, c, 1);
    CHECK(compare_hits("alpha", rays, g, c, n, NULL) == 0);
    uint32_t wrong = 0, front = 0;
    for (uint32_t i = 0; i < n; ++i) {
        int hit_front = g[i].triangle != PB_NO_HIT && fabsf(g[i].t - 1.f) < 1e-5f;
        front += hit_front;
        wrong += hit_front != expect_front[i];
    }
    fprintf(stderr, "  %u rays: %u stopped by opaque texels, %u disagree with the texture\n", n, front, wrong);
    CHECK(wrong == 0);
    CHECK(front == n / 2);
    /* any-hit with tmax short of the back quad: occluded exactly on opaque texels */
    CHECK(pb_trace(ctx, t.gs, rays, n, PB_TRACE_ANY, a, NULL, &err) == PB_OK);
    wrong = 0;
    for (uint32_t i = 0; i < n; ++i)
        wrong += (a[i].triangle != PB_NO_HIT) != expect_front[i];
    CHECK(wrong == 0);
    free(rays), free(g), free(c), free(a), free(expect_front);
    release(&t);
    pb_scene_destroy(s);
}

/* An alpha-BLEND quad of alpha 0.3 over an opaque one: each ray stops on it
 * with probability 0.3 (hashed threshold, src/bvh/alpha.h), the fraction is
 * within 4 sigma of the binomial, and GPU and CPU make the same choices. */
static void alpha_blend_stochastic(void)
{
    double quads[2][4][3] = {{{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}},
                             {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}}};
    double p[4 * 9];
    uint32_t mat[4];
    for (int q = 0; q < 2; ++q)
        for (int t = 0; t < 2; ++t) {
            int idx[2][3] = {{0, 1, 2}, {0, 2, 3}};
            for (int v = 0; v < 3; ++v)
                for (int k = 0; k < 3; ++k)
                    p[9 * (2 * q + t) + 3 * v + k] = quads[q][idx[t][v]][k];
            mat[2 * q + t] = (uint32_t)q;
        }
    pb_material m[2] = {pb_material_default(), pb_material_default()};
    m[0].alpha_mode = PB_ALPHA_BLEND;
    m[0].base_color[3] = 0.3f;
    m[0].double_sided = 1;
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_from_triangles(p, 4, mat, m, 2, &s, &err) == PB_OK, "%s", err.message);
    traced t;
    if (!s || !prepare(s, NULL, &t)) {
        pb_scene_destroy(s);
        return;
    }
    uint32_t n = 1u << 16;
    pb_ray *rays = malloc(n * sizeof *rays);
    pb_hit *g = malloc(n * sizeof *g), *c = malloc(n * sizeof *c), *a = malloc(n * sizeof *a);
    test_rng r = {77};
    float zf = 0.f - (float)s->origin[2];
    for (uint32_t i = 0; i < n; ++i) {
        pb_ray ray = {{(float)(1.8 * rng_uniform(&r) - 0.9), (float)(1.8 * rng_uniform(&r) - 0.9), zf + 1.f}, 0.f,
                      {0, 0, -1}, 2.5f};
        rays[i] = ray;
    }
    CHECK(pb_trace(ctx, t.gs, rays, n, PB_TRACE_CLOSEST, g, NULL, &err) == PB_OK);
    pb_trace_cpu(s, t.bvh, rays, n, PB_TRACE_CLOSEST, c, 1);
    CHECK(compare_hits("blend", rays, g, c, n, NULL) == 0);
    CHECK(pb_trace(ctx, t.gs, rays, n, PB_TRACE_ANY, a, NULL, &err) == PB_OK);
    uint32_t front = 0, back = 0, any_diff = 0;
    for (uint32_t i = 0; i < n; ++i) {
        front += g[i].triangle != PB_NO_HIT && s->material[g[i].triangle] == 0;
        back += g[i].triangle != PB_NO_HIT && s->material[g[i].triangle] == 1;
        any_diff += (a[i].triangle != PB_NO_HIT) != (g[i].triangle != PB_NO_HIT);
    }
    double f = (double)front / n, sigma = sqrt(0.3 * 0.7 / n);
    fprintf(stderr, "  %u rays: %.4f stopped by the alpha-0.3 blend quad (sigma %.4f), %u went on to the back\n", n,
            f, sigma, back);
    CHECK(fabs(f - 0.3) < 4 * sigma);
    CHECK(front + back == n);
    CHECK(any_diff == 0);
    free(rays), free(g), free(c), free(a);
    release(&t);
    pb_scene_destroy(s);
}

/* Synchronisation validation is on and works: two copies through one
 * buffer with no barrier between them (a read-after-write hazard) are
 * reported. A context of its own, so the suite's context stays silent. */
static void sync_validation_catches_a_missing_barrier(void)
{
    pb_context_desc d = {getenv("PB_TEST_DEVICE"), 1, 0, 0, {NULL, NULL}};
    pb_context *c = NULL;
    pb_error err;
    CHECKF(pb_context_create(&d, &c, &err) == PB_OK, "%s", err.message);
    if (!c)
        return;
    pb_buffer a = {0}, b = {0}, x = {0};
    CHECK(pb_buffer_create(c, 4096, PB_MEMORY_DEVICE, "a", &a, &err) == PB_OK);
    CHECK(pb_buffer_create(c, 4096, PB_MEMORY_DEVICE, "b", &b, &err) == PB_OK);
    CHECK(pb_buffer_create(c, 4096, PB_MEMORY_DEVICE, "x", &x, &err) == PB_OK);
    uint32_t before = pb_context_validation_messages(c);
    if (pb_cmd_begin(c, &err) == PB_OK) {
        pb_cmd_copy(c, &a, 0, &b, 0, 4096);
        pb_cmd_copy(c, &b, 0, &x, 0, 4096); /* reads what the first copy writes: no barrier */
        CHECK(pb_cmd_submit_wait(c, NULL, &err) == PB_OK);
    }
    uint32_t after = pb_context_validation_messages(c);
    fprintf(stderr, "  %u validation message(s) for the missing barrier\n", after - before);
    CHECK(after > before);
    pb_buffer_destroy(c, &a), pb_buffer_destroy(c, &b), pb_buffer_destroy(c, &x);
    pb_context_destroy(c);
}

/* pb_dispatch_spread (src/gpu/dispatch_order.c): for every dispatch of 40
 * to 8 x 65535 workgroups whose blocks of 8 admit one, the stride is coprime
 * to the number of blocks, so the kernels' block b -> b s mod blocks is a
 * permutation, and it is neither the identity (1) nor the mirror (blocks - 1);
 * where no such stride exists (fewer than 5 blocks, or 6), and above 8 x 65535
 * workgroups, the order is kept. (The kernels' results against the CPU
 * references, in this suite and test_bake, run with dispatches above 40
 * workgroups.) */
static void dispatch_spread_permutes_blocks(void)
{
    uint32_t bad = 0, checked = 0, kept = 0;
    for (uint32_t n = 1; n <= 8u * 65535u; n += n < 4096 ? 1 : 97) {
        uint32_t blocks = n / 8, s = pb_dispatch_spread(n), a = s, b = blocks;
        while (b) {
            uint32_t t = a % b;
            a = b, b = t;
        }
        /* a spreading stride exists: blocks >= 5 but 6 (7 has 2..5, 8 has 3, 5, ...) */
        int exists = blocks >= 5 && blocks != 6;
        bad += exists ? (a != 1 || s <= 1 || s >= blocks - 1) : s != 1;
        kept += !exists;
        ++checked;
    }
    fprintf(stderr, "  %u dispatch sizes (%u too small to spread), %u strides wrong\n", checked, kept, bad);
    CHECK(checked > 8000 && bad == 0 && kept == 47); /* n 1-39 and 48-55 */
    CHECK(pb_dispatch_spread(8u * 65536u) == 1);
}

/* Splitting the work into many submissions, and copying through staging
 * buffers (the discrete-GPU path) instead of mapped memory, changes no result. */
static void bounded_submissions_same_bytes(void)
{
    pb_scene *s = random_soup(5000, 0.1f, 3, NULL);
    pb_context_desc d = {NULL, 1, 4096, 1, test_log};
    pb_context *small = NULL;
    pb_error err;
    CHECKF(pb_context_create(&d, &small, &err) == PB_OK, "%s", err.message);
    if (!small)
        return;
    pb_bvh *b = NULL;
    pb_gpu_scene *g1 = NULL, *g2 = NULL;
    CHECK(pb_bvh_build(s, NULL, &b, &err) == PB_OK);
    CHECK(pb_gpu_scene_create(ctx, s, b, &g1, &err) == PB_OK);
    CHECK(pb_gpu_scene_create(small, s, b, &g2, &err) == PB_OK);
    CHECK(g2 && g2->nodes.mapped == NULL); /* the staging path is the one under test */
    uint32_t n = 50000;
    pb_ray *rays = random_rays(s->bounds_min, s->bounds_max, n, 4);
    pb_hit *h1 = malloc(n * sizeof *h1), *h2 = malloc(n * sizeof *h2);
    pb_trace_stats st1, st2;
    CHECK(pb_trace(ctx, g1, rays, n, PB_TRACE_CLOSEST, h1, &st1, &err) == PB_OK);
    CHECK(pb_trace(small, g2, rays, n, PB_TRACE_CLOSEST, h2, &st2, &err) == PB_OK);
    CHECK(st1.submits == 1);
    CHECKF(st2.submits == (n + 4095) / 4096, "%u submits", st2.submits);
    CHECK(memcmp(h1, h2, n * sizeof *h1) == 0);
    CHECK(pb_context_validation_messages(small) == 0);
    free(rays), free(h1), free(h2);
    pb_gpu_scene_destroy(g1);
    pb_gpu_scene_destroy(g2);
    pb_bvh_destroy(b);
    pb_context_destroy(small);
    pb_scene_destroy(s);
}

/* pb_buffer_fill: records made in place (mapped memory) or a staging
 * buffer's worth at a time (a context that stages), on all host cores, are
 * the records asked for, at the offset asked for, and nothing else moves. A
 * 40-byte record does not divide the 16 MiB staging buffer, and a million of
 * them take three. */
typedef struct fill_pattern {
    uint32_t words; /* per record */
    uint32_t seed;
} fill_pattern;

static uint32_t fill_word(const fill_pattern *p, uint64_t record, uint32_t w)
{
    return pb_hash32((uint32_t)record * 2654435761u ^ (uint32_t)(record >> 32) ^ w * 40503u ^ p->seed);
}

static void fill_records(void *user, void *out, uint64_t first, uint64_t n)
{
    const fill_pattern *p = user;
    for (uint64_t i = 0; i < n; ++i)
        for (uint32_t w = 0; w < p->words; ++w)
            ((uint32_t *)out)[i * p->words + w] = fill_word(p, first + i, w);
}

static void buffer_fill_mapped_and_staged(void)
{
    pb_context_desc d = {NULL, 1, 0, 1, test_log};
    pb_context *staged = NULL;
    pb_error err;
    CHECKF(pb_context_create(&d, &staged, &err) == PB_OK, "%s", err.message);
    if (!staged)
        return;
    const uint64_t count = 1000000, offset = 24, tail = 8;
    const fill_pattern pat = {10, 7}; /* 40-byte records */
    const size_t bytes = (size_t)(offset + count * 40 + tail);
    uint8_t *sentinel = malloc(bytes), *back = malloc(bytes);
    for (size_t i = 0; i < bytes; ++i)
        sentinel[i] = (uint8_t)(i * 7 + 3);
    pb_context *ctxs[2] = {ctx, staged};
    for (int c = 0; c < 2; ++c) {
        pb_buffer b;
        CHECK(pb_buffer_create(ctxs[c], bytes, PB_MEMORY_DEVICE, "fill test", &b, &err) == PB_OK);
        CHECK(c == 0 || b.mapped == NULL); /* the second context stages */
        CHECK(pb_buffer_upload(ctxs[c], &b, 0, sentinel, bytes, &err) == PB_OK);
        CHECKF(pb_buffer_fill(ctxs[c], &b, offset, 40, count, fill_records, (void *)&pat, &err) == PB_OK, "%s",
               err.message);
        /* one record too many, or a record past the end: refused, nothing written */
        CHECK(pb_buffer_fill(ctxs[c], &b, offset, 40, count + 1, fill_records, (void *)&pat, &err) ==
              PB_ERROR_INVALID_ARGUMENT);
        CHECK(pb_buffer_fill(ctxs[c], &b, bytes - 39, 40, 1, fill_records, (void *)&pat, &err) ==
              PB_ERROR_INVALID_ARGUMENT);
        memset(back, 0, bytes);
        CHECK(pb_buffer_download(ctxs[c], &b, 0, back, bytes, &err) == PB_OK);
        uint64_t bad = 0;
        for (uint64_t i = 0; i < count; ++i)
            for (uint32_t w = 0; w < 10; ++w) {
                uint32_t got;
                memcpy(&got, back + offset + 40 * i + 4 * w, 4);
                bad += got != fill_word(&pat, i, w);
            }
        CHECKF(bad == 0, "%s: %llu words wrong", c ? "staged" : "mapped", (unsigned long long)bad);
        CHECK(memcmp(back, sentinel, offset) == 0);
        CHECK(memcmp(back + bytes - tail, sentinel + bytes - tail, tail) == 0);
        pb_buffer_destroy(ctxs[c], &b);
    }
    CHECK(pb_context_validation_messages(staged) == 0);
    free(sentinel), free(back);
    pb_context_destroy(staged);
}

/* shaders/include/ray_offset.glsl == pb_offset_ray_origin, bit for bit, over
 * magnitudes from 1e-7 to 1e7 (both sides of the 1/32 switch), signs, zeros. */
static void ray_offset_gpu_matches_cpu(void)
{
    uint32_t n = 100000;
    float *p = malloc(n * 12), *nn = malloc(n * 12), *g = malloc(n * 12);
    test_rng r = {31};
    for (uint32_t i = 0; i < n; ++i) {
        double mag = pow(10.0, 14.0 * rng_uniform(&r) - 7.0);
        for (int k = 0; k < 3; ++k)
            p[3 * i + k] = (i % 97 == 0 && k == 1) ? 0.f : (float)((2 * rng_uniform(&r) - 1) * mag);
        rng_direction(&r, nn + 3 * i);
    }
    pb_error err;
    CHECKF(pb_offset_ray_origins_gpu(ctx, p, nn, n, g, &err) == PB_OK, "%s", err.message);
    uint32_t bad = 0;
    for (uint32_t i = 0; i < n; ++i) {
        float c[3];
        pb_offset_ray_origin(p + 3 * i, nn + 3 * i, c);
        if (memcmp(c, g + 3 * i, 12) != 0) {
            if (bad < 5)
                fprintf(stderr, "  point %u (%a %a %a): CPU %a %a %a GPU %a %a %a\n", i, p[3 * i], p[3 * i + 1],
                        p[3 * i + 2], c[0], c[1], c[2], g[3 * i], g[3 * i + 1], g[3 * i + 2]);
            ++bad;
        }
    }
    CHECKF(bad == 0, "%u of %u origins differ", bad, n);
    free(p), free(nn), free(g);
}

/* exact_diff.glsl on the device equals pb_exact_diff bit for bit, on inputs
 * of every kind (tests/exact_inputs.h): denormals, ties, cancellation. */
static void exact_diff_gpu_matches_cpu(void)
{
    uint32_t n = 600000;
    float *in = malloc((size_t)n * 16), *out = malloc((size_t)n * 4);
    test_rng r = {91};
    for (uint32_t i = 0; i < n; ++i)
        exact_inputs(&r, i, in + 4 * (size_t)i);
    pb_error err;
    CHECKF(pb_exact_diff_gpu(ctx, in, n, out, &err) == PB_OK, "%s", err.message);
    uint32_t bad = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const float *q = in + 4 * (size_t)i;
        float c = pb_exact_diff(q[0], q[1], q[2], q[3]);
        if (memcmp(&c, out + i, 4) != 0) {
            if (bad < 5)
                fprintf(stderr, "  %a*%a - %a*%a: CPU %a GPU %a\n", q[0], q[1], q[2], q[3], c, out[i]);
            ++bad;
        }
    }
    CHECKF(bad == 0, "%u of %u results differ", bad, n);
    free(in), free(out);
}

/* The portable kernels declare neither Float64 nor Int64 (nor Int64Atomics),
 * so a device without shaderFloat64/shaderInt64 can create them; the native64
 * ones do declare them (or the variant would be pointless). Read from the
 * SPIR-V the build embedded (build/shaders). */
static int spirv_capabilities(const char *path, uint32_t *caps, int max)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    uint32_t words[1 << 16];
    size_t n = 0, got;
    while ((got = fread(words + n, 4, (sizeof words / 4) - n, f)) > 0 && n < sizeof words / 4)
        n += got;
    fclose(f);
    int count = 0;
    if (n < 5 || words[0] != 0x07230203u)
        return -1;
    for (size_t i = 5; i < n;) {
        uint32_t len = words[i] >> 16, op = words[i] & 0xffffu;
        if (len == 0)
            return -1;
        if (op == 17 && i + 1 < n && count < max) /* OpCapability */
            caps[count++] = words[i + 1];
        i += len;
    }
    return count;
}

/* Instructions with opcode `op` in a SPIR-V file, or -1 if unreadable. */
static int spirv_op_count(const char *path, uint32_t op)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    static uint32_t words[1 << 18];
    size_t n = fread(words, 4, sizeof words / 4, f);
    fclose(f);
    if (n < 5 || words[0] != 0x07230203u)
        return -1;
    int count = 0;
    for (size_t i = 5; i < n;) {
        uint32_t len = words[i] >> 16;
        if (len == 0)
            return -1;
        count += (words[i] & 0xffffu) == op;
        i += len;
    }
    return count;
}

/* The trace kernels' hits must be the CPU's on every device, and Vulkan lets
 * a division be 2.5 ulp off (an H100's was: its alpha-blend cuts and some t
 * differed from the CPU's). So hit values never come from a division
 * (intersect.glsl's pb_rcp): the one OpFDiv left is the box test's 1/dir in
 * ray_prepare's loop, which only culls (a second would be a hit value's). */
/* Hits of `rays` on context c (closest, then any) with the scene's loads
 * reported through *texels; 0 when the scene could not be made. */
static int trace_on(pb_context *c, const pb_scene *s, const pb_bvh *bvh, const pb_ray *rays, uint32_t n,
                    pb_hit *closest, pb_hit *any, uint32_t *texels)
{
    pb_gpu_scene *gs = NULL;
    pb_error err;
    pb_result r = pb_gpu_scene_create(c, s, bvh, &gs, &err);
    CHECKF(r == PB_OK, "%s", err.message);
    if (r != PB_OK)
        return 0;
    *texels = gs->texel_loads;
    r = pb_trace(c, gs, rays, n, PB_TRACE_CLOSEST, closest, NULL, &err);
    CHECKF(r == PB_OK, "%s", err.message);
    r = pb_trace(c, gs, rays, n, PB_TRACE_ANY, any, NULL, &err);
    CHECKF(r == PB_OK, "%s", err.message);
    pb_gpu_scene_destroy(gs);
    return 1;
}

/* Texel loads and address loads of the BVH read the same words, so every
 * hit must be the same bit for bit, closest and any, on scenes with an odd
 * and an even triangle count (the last record's texels reach into the
 * padding texel) and on the demo. The context of this run against one with
 * the other loads; then the view limit: asked-for texel loads over
 * maxTexelBufferElements are refused, and the default falls back. */
static void texel_and_address_loads_same_hits(void)
{
    pb_context_desc d = {getenv("PB_TEST_DEVICE"), 1, 0, 0, {test_log_line, NULL}};
    d.portable_kernels = test_portable_kernels();
    d.scene_loads = ctx->scene_texels ? PB_SCENE_LOADS_ADDRESS : PB_SCENE_LOADS_TEXEL;
    pb_context *other = NULL;
    pb_error err;
    CHECKF(pb_context_create(&d, &other, &err) == PB_OK, "%s", err.message);
    if (!other)
        return;
    CHECK(other->scene_texels != ctx->scene_texels);
    pb_scene *scenes[3] = {random_soup(2001, 0.3f, 31, NULL), random_soup(1000, 0.2f, 32, NULL), load_demo()};
    const uint32_t n = 50000;
    pb_hit *h[4];
    for (int i = 0; i < 4; ++i)
        h[i] = malloc(n * sizeof *h[i]);
    for (int k = 0; k < 3; ++k) {
        pb_scene *s = scenes[k];
        pb_bvh *bvh = NULL;
        if (!s || pb_bvh_build(s, NULL, &bvh, &err) != PB_OK) {
            CHECKF(0, "scene %d: %s", k, s ? err.message : "not made");
            continue;
        }
        pb_ray *rays = scene_rays(s, n, 40 + k);
        uint32_t tex_a = 9, tex_b = 9;
        if (trace_on(ctx, s, bvh, rays, n, h[0], h[1], &tex_a) &&
            trace_on(other, s, bvh, rays, n, h[2], h[3], &tex_b)) {
            uint32_t hits = 0;
            for (uint32_t i = 0; i < n; ++i)
                hits += h[0][i].triangle != PB_NO_HIT;
            fprintf(stderr, "  %u triangles: %u of %u rays hit; texel loads %u here, %u there\n", s->triangle_count,
                    hits, n, tex_a, tex_b);
            CHECK(hits > n / 10);
            CHECK(tex_a == (uint32_t)ctx->scene_texels && tex_b == (uint32_t)other->scene_texels);
            CHECKF(!memcmp(h[0], h[2], n * sizeof *h[0]), "%u triangles: closest hits differ", s->triangle_count);
            CHECKF(!memcmp(h[1], h[3], n * sizeof *h[1]), "%u triangles: any hits differ", s->triangle_count);
        }
        free(rays);
        pb_bvh_destroy(bvh);
    }
    /* the view limit, lowered on the texel context: refused when asked for */
    /* (the context asking for texels: this run's other one when this one reads addresses) */
    pb_context *asked = other->desc.scene_loads == PB_SCENE_LOADS_TEXEL ? other : NULL;
    uint32_t limit = ctx->limits.maxTexelBufferElements;
    pb_bvh *bvh = NULL;
    CHECK(pb_bvh_build(scenes[0], NULL, &bvh, &err) == PB_OK);
    if (asked && bvh) {
        asked->limits.maxTexelBufferElements = 64;
        pb_gpu_scene *gs = NULL;
        pb_result r = pb_gpu_scene_create(asked, scenes[0], bvh, &gs, &err);
        fprintf(stderr, "  texel loads over the limit: %s\n", err.message);
        CHECK(r == PB_ERROR_TOO_LARGE && strstr(err.message, "maxTexelBufferElements") && !gs);
        pb_gpu_scene_destroy(gs);
        asked->limits.maxTexelBufferElements = limit;
    }
    /* the default on a CPU device falls back to addresses, and still hits */
    if (ctx->desc.scene_loads == PB_SCENE_LOADS_AUTO && ctx->scene_texels && bvh) {
        ctx->limits.maxTexelBufferElements = 64;
        uint32_t tex = 9;
        pb_ray *rays = scene_rays(scenes[0], n, 40);
        uint32_t tex_other = 9; /* the other context reads addresses here */
        if (trace_on(ctx, scenes[0], bvh, rays, n, h[0], h[1], &tex) &&
            trace_on(other, scenes[0], bvh, rays, n, h[2], h[3], &tex_other)) {
            CHECK(tex == 0 && tex_other == 0);
            CHECK(!memcmp(h[0], h[2], n * sizeof *h[0]) && !memcmp(h[1], h[3], n * sizeof *h[1]));
        }
        ctx->limits.maxTexelBufferElements = limit;
        free(rays);
    }
    pb_bvh_destroy(bvh);
    for (int i = 0; i < 4; ++i)
        free(h[i]);
    for (int k = 0; k < 3; ++k)
        pb_scene_destroy(scenes[k]);
    CHECKF(pb_context_validation_messages(other) == 0, "%u validation messages on the second context",
           pb_context_validation_messages(other));
    pb_context_destroy(other);
}

static void trace_kernels_divide_only_for_boxes(void)
{
    const char *names[] = {"trace.spv", "trace_native64.spv"};
    for (int i = 0; i < 2; ++i) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", PB_SHADER_DIR, names[i]);
        int n = spirv_op_count(path, 136); /* OpFDiv */
        CHECKF(n == 1, "%s: %d OpFDiv, expected the box test's one (-1: unreadable)", path, n);
    }
}

static int has_64bit_capability(const char *path)
{
    uint32_t caps[64];
    int n = spirv_capabilities(path, caps, 64);
    if (n <= 0)
        return -1;
    for (int i = 0; i < n; ++i)
        if (caps[i] == 10 || caps[i] == 11 || caps[i] == 12) /* Float64, Int64, Int64Atomics */
            return 1;
    return 0;
}

/* The file names of every kernel the build embedded (each .spv in
 * build/shaders, whatever CMakeLists.txt lists), up to `cap`; -1 when the
 * folder cannot be listed. */
#define KERNEL_NAME_MAX 64
static int embedded_kernels(char names[][KERNEL_NAME_MAX], int cap)
{
    DIR *dir = opendir(PB_SHADER_DIR);
    CHECKF(dir != NULL, "cannot list %s", PB_SHADER_DIR);
    if (!dir)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(dir)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len >= 5 && len < KERNEL_NAME_MAX && strcmp(e->d_name + len - 4, ".spv") == 0 && n < cap)
            memcpy(names[n++], e->d_name, len + 1);
    }
    closedir(dir);
    return n;
}

/* Every kernel the build embedded: the portable ones declare no 64-bit
 * capability, each <name>_native64 does, and each has its portable twin. */
static void portable_kernels_need_no_64bit_types(void)
{
    char names[64][KERNEL_NAME_MAX];
    int count = embedded_kernels(names, 64), portable = 0, native = 0;
    for (int i = 0; i < count; ++i) {
        size_t len = strlen(names[i]);
        char path[1024];
        snprintf(path, sizeof path, "%s/%.*s", PB_SHADER_DIR, KERNEL_NAME_MAX, names[i]);
        int is_native = len > 13 && strcmp(names[i] + len - 13, "_native64.spv") == 0;
        int has64 = has_64bit_capability(path);
        CHECKF(has64 >= 0, "cannot read %s", path);
        CHECKF(has64 == is_native, "%s: %s", path,
               is_native ? "declares no 64-bit capability" : "declares Float64 or Int64");
        if (is_native) {
            char twin[1024];
            snprintf(twin, sizeof twin, "%s/%.*s.spv", PB_SHADER_DIR, (int)(len - 13), names[i]);
            CHECKF(has_64bit_capability(twin) == 0, "%s has no portable twin %s", path, twin);
            ++native;
        } else {
            ++portable;
        }
    }
    printf("  %d portable kernels, %d native64 variants\n", portable, native);
    CHECKF(portable >= 8 && native >= 3, "only %d portable and %d native64 kernels found", portable, native);
}

/* Every kernel the build embedded went through spirv-opt (CMakeLists.txt):
 * one function, the entry point, and no call left in it. lavapipe lowers
 * and optimizes a module on every pipeline creation, and glslang's calls
 * and locals made that most of a small bake's wall time (bench/RESULTS.md,
 * "SPIR-V optimized before it is embedded"). */
static void embedded_kernels_are_inlined(void)
{
    char names[64][KERNEL_NAME_MAX];
    int count = embedded_kernels(names, 64);
    for (int i = 0; i < count; ++i) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%.*s", PB_SHADER_DIR, KERNEL_NAME_MAX, names[i]);
        int functions = spirv_op_count(path, 54 /* OpFunction */), calls = spirv_op_count(path, 57 /* OpFunctionCall */);
        CHECKF(functions == 1 && calls == 0, "%s: %d functions and %d calls, want the entry point alone", path,
               functions, calls);
    }
    printf("  %d kernels, each one function with no call\n", count);
    CHECKF(count >= 11, "only %d kernels found", count);
}

/* Which memory a buffer takes, on tables like real devices': a discrete GPU
 * with resizable BAR (an H100's kinds: device-local; host; host cached;
 * device-local and host-visible but uncached) must keep device buffers
 * unmapped (reading through the BAR ran at 1/1000 of the kernel there), and
 * a UMA device (lavapipe: one cached device-local type) maps them. */
static void memory_choice_on_discrete_and_uma(void)
{
    const VkMemoryPropertyFlags DL = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, HV = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
                                HC = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, CA = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
    VkPhysicalDeviceMemoryProperties bar = {0};
    bar.memoryTypeCount = 4;
    bar.memoryTypes[0].propertyFlags = DL;
    bar.memoryTypes[1].propertyFlags = HV | HC;
    bar.memoryTypes[2].propertyFlags = HV | HC | CA;
    bar.memoryTypes[3].propertyFlags = DL | HV | HC;
    pb_memory_choice c = pb_buffer_memory_choice(&bar, 0xfu, PB_MEMORY_DEVICE, 0);
    CHECKF(c.type == 0 && !c.mapped, "discrete device buffer: type %d mapped %d", c.type, c.mapped);
    c = pb_buffer_memory_choice(&bar, 0x8u, PB_MEMORY_DEVICE, 0); /* only the BAR type allowed */
    CHECKF(c.type == 3 && !c.mapped, "BAR-only device buffer: type %d mapped %d", c.type, c.mapped);
    c = pb_buffer_memory_choice(&bar, 0xfu, PB_MEMORY_DOWNLOAD, 0);
    CHECKF(c.type == 2 && c.mapped, "discrete download: type %d mapped %d", c.type, c.mapped);
    c = pb_buffer_memory_choice(&bar, 0xfu, PB_MEMORY_UPLOAD, 0);
    CHECKF(c.type == 1 && c.mapped, "discrete upload: type %d mapped %d", c.type, c.mapped);
    VkPhysicalDeviceMemoryProperties uma = {0};
    uma.memoryTypeCount = 1;
    uma.memoryTypes[0].propertyFlags = DL | HV | HC | CA;
    c = pb_buffer_memory_choice(&uma, 0x1u, PB_MEMORY_DEVICE, 0);
    CHECKF(c.type == 0 && c.mapped, "UMA device buffer: type %d mapped %d", c.type, c.mapped);
    c = pb_buffer_memory_choice(&uma, 0x1u, PB_MEMORY_DEVICE, 1);
    CHECKF(c.type == 0 && !c.mapped, "UMA device buffer, staging forced: type %d mapped %d", c.type, c.mapped);
    c = pb_buffer_memory_choice(&uma, 0x0u, PB_MEMORY_DEVICE, 0);
    CHECK(c.type == -1);
}

/* Pipelines made on worker threads (pb_pipelines_begin / end: the bake makes
 * its kernels while it learns its light cells). Push sizes no kernel uses
 * make the keys new to this context's cache. */
static uint32_t *read_spirv(const char *name, size_t *bytes)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", PB_SHADER_DIR, name);
    FILE *f = fopen(path, "rb");
    uint32_t *words = NULL;
    *bytes = 0;
    if (f && fseek(f, 0, SEEK_END) == 0) {
        long n = ftell(f);
        if (n > 0 && (words = malloc((size_t)n)) && fseek(f, 0, SEEK_SET) == 0 && fread(words, 1, (size_t)n, f) == (size_t)n)
            *bytes = (size_t)n;
    }
    if (f)
        fclose(f);
    CHECKF(*bytes > 0, "cannot read %s", path);
    return words;
}

/* the context's cache keys pipelines by the address of their words: these
 * live until the context is gone (main) */
static uint32_t *pb_spv_dilate, *pb_spv_ray_offset;

static void pipelines_made_on_worker_threads(void)
{
    size_t dilate_bytes, offset_bytes;
    pb_spv_dilate = read_spirv("dilate.spv", &dilate_bytes);
    pb_spv_ray_offset = read_spirv("ray_offset.spv", &offset_bytes);
    if (!dilate_bytes || !offset_bytes)
        return;
    pb_error err;
    pb_pipeline a, b, a2, b2, c, over;
    pb_pipeline_request q[2] = {{pb_spv_dilate, dilate_bytes, 116, NULL, 0, 64, "dilate (test)", &a},
                                {pb_spv_ray_offset, offset_bytes, 116, NULL, 0, 64, "ray_offset (test)", &b}};
    pb_pipeline_batch batch;
    uint32_t made0 = ctx->pipelines_created;
    CHECK(pb_pipelines_begin(ctx, q, 2, &batch, &err) == PB_OK);
    CHECK(batch.count == 2);
    CHECK(pb_pipelines_end(ctx, &batch, &err) == PB_OK);
    CHECKF(ctx->pipelines_created == made0 + 2, "%u pipelines made, 2 expected", ctx->pipelines_created - made0);
    CHECK(a.pipeline && b.pipeline && a.pipeline != b.pipeline && a.cached && b.cached && a.push_size == 116);
    /* the same requests again: handed out from the cache, no thread, nothing made */
    q[0].out = &a2, q[1].out = &b2;
    CHECK(pb_pipelines_begin(ctx, q, 2, &batch, &err) == PB_OK && batch.count == 0);
    CHECK(pb_pipelines_end(ctx, &batch, &err) == PB_OK);
    CHECK(ctx->pipelines_created == made0 + 2 && a2.pipeline == a.pipeline && b2.pipeline == b.pipeline);
    /* and a single one made on the caller's thread is found by a batch */
    CHECK(pb_pipeline_create(ctx, pb_spv_dilate, dilate_bytes, 120, NULL, 0, 64, "dilate (test)", &c, &err) ==
          PB_OK);
    /* a request the device refuses fails the batch before anything runs
     * unjoined: every out is cleared, the one started is kept by the cache */
    uint32_t too_big = ctx->limits.maxPushConstantsSize + 4;
    pb_pipeline_request bad[3] = {
        {pb_spv_ray_offset, offset_bytes, 124, NULL, 0, 64, "ray_offset (test)", &a2},
        {pb_spv_dilate, dilate_bytes, 120, NULL, 0, 64, "dilate (test)", &b2},
        {pb_spv_dilate, dilate_bytes, too_big, NULL, 0, 64, "dilate (test, too big)", &over}};
    made0 = ctx->pipelines_created;
    CHECK(pb_pipelines_begin(ctx, bad, 3, &batch, &err) == PB_ERROR_UNSUPPORTED);
    CHECKF(strstr(err.message, "push constants") && strstr(err.message, "too big"), "message: %s", err.message);
    CHECK(!a2.pipeline && !b2.pipeline && !over.pipeline && batch.count == 0);
    CHECK(ctx->pipelines_created == made0 + 1);
    /* a driver failure on a worker thread (injected, as OUT_OF_HOST_MEMORY):
     * end names the call and the kernel, clears every output, and keeps the
     * ones made in the cache, so nothing leaks (the validation layer reports
     * objects left at device destruction) */
    pb_pipeline d0, d1, d2;
    pb_pipeline_request three[3] = {
        {pb_spv_dilate, dilate_bytes, 128, NULL, 0, 64, "dilate (test)", &d0},
        {pb_spv_ray_offset, offset_bytes, 128, NULL, 0, 64, "ray_offset (test, fails)", &d1},
        {pb_spv_dilate, dilate_bytes, 132, NULL, 0, 64, "dilate (test)", &d2}};
    made0 = ctx->pipelines_created;
    ctx->desc.fail_pipeline = ctx->pipeline_jobs + 2;
    CHECK(pb_pipelines_begin(ctx, three, 3, &batch, &err) == PB_OK && batch.count == 3);
    CHECK(pb_pipelines_end(ctx, &batch, &err) == PB_ERROR_OUT_OF_HOST_MEMORY);
    CHECKF(strstr(err.message, "out of host memory during vkCreateComputePipelines (injected fault) (kernel "
                               "ray_offset (test, fails))") != NULL, "message: %s", err.message);
    CHECK(!d0.pipeline && !d1.pipeline && !d2.pipeline && batch.count == 0);
    CHECK(ctx->pipelines_created == made0 + 2);
    ctx->desc.fail_pipeline = 0;
    pb_pipeline_destroy(ctx, &a), pb_pipeline_destroy(ctx, &b), pb_pipeline_destroy(ctx, &c);
}

static void device_choice_and_refusals(void)
{
    pb_context *c = (pb_context *)1;
    pb_error err;
    pb_context_desc d = {"no such device", 0, 0, 0, {0}};
    CHECK(pb_context_create(&d, &c, &err) == PB_ERROR_NO_DEVICE && c == NULL);
    CHECK(strstr(err.message, "no such device") != NULL);
    d.device = "99";
    CHECK(pb_context_create(&d, &c, &err) == PB_ERROR_NO_DEVICE);
    d.device = "0";
    CHECK(pb_context_create(&d, &c, &err) == PB_OK);
    pb_context_destroy(c);

    pb_device_info infos[8];
    uint32_t count = 0;
    CHECK(pb_enumerate_devices(infos, 8, &count, &err) == PB_OK && count >= 1);
    CHECK(count >= 1 && infos[0].name[0] && infos[0].subgroup_size > 0);

    /* an allocation over maxMemoryAllocationSize is refused before Vulkan sees it */
    pb_buffer big;
    uint64_t before = ctx->allocated;
    CHECK(pb_buffer_create(ctx, ctx->max_allocation + 1, PB_MEMORY_DEVICE, "test array", &big, &err) ==
          PB_ERROR_TOO_LARGE);
    CHECK(strstr(err.message, "test array") != NULL && ctx->allocated == before);
}

int main(void)
{
    if (!(ctx = test_gpu_context()))
        return 1;
    fprintf(stderr, "device: %s (%s)\n", pb_context_device(ctx)->name, pb_context_device(ctx)->driver);
    RUN(random_soups_gpu_cpu_brute);
    RUN(leaf_sizes_gpu_cpu_brute);
    RUN(demo_scene_gpu_cpu_brute);
    RUN(shared_scenes_gpu_cpu_brute);
    RUN(watertight_sphere_gpu);
    RUN(far_from_origin_same_hits);
    RUN(alpha_mask_cuts_out);
    RUN(alpha_blend_stochastic);
    RUN(sync_validation_catches_a_missing_barrier);
    RUN(dispatch_spread_permutes_blocks);
    RUN(bounded_submissions_same_bytes);
    RUN(buffer_fill_mapped_and_staged);
    RUN(ray_offset_gpu_matches_cpu);
    RUN(exact_diff_gpu_matches_cpu);
    RUN(portable_kernels_need_no_64bit_types);
    RUN(embedded_kernels_are_inlined);
    RUN(texel_and_address_loads_same_hits);
    RUN(trace_kernels_divide_only_for_boxes);
    RUN(memory_choice_on_discrete_and_uma);
    RUN(pipelines_made_on_worker_threads);
    RUN(device_choice_and_refusals);
    int rc = test_gpu_finish(ctx);
    free(pb_spv_dilate), free(pb_spv_ray_offset);
    return rc;
}
