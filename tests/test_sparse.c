/* The sparse layout's refinement against physics (docs/sparse.md): under a
 * uniform sky over an infinite floor the irradiance is the same everywhere,
 * so no cell may be subdivided, though cells near the floor are tested; a
 * sun behind the edge of a roof casts a sharp shadow boundary through open
 * air and onto the floor, and the cells it crosses must be subdivided (with
 * the default surface test, where the floor and the roof show it). Also: a
 * sparse volume written and read back samples identically. */
#include "scenes_gen.h"
#include "bake/dilate.h"
#include "bake/sparse_miss.h"
#include "bake/sparse_stitch.h"
#include "bake/sparse_surface_tests.h"
#include "common/common.h"

static pb_context *ctx;

#define FLOOR_Y 0.3   /* between lattice planes of every level (spacing 0.5 m) */
#define ROOF_Y 6.2
#define ROOF_EDGE_X 6.9

/* Quad from (x0, z0) to (x1, z1) at height y, facing up (or down). */
static void quad(double *p, double x0, double z0, double x1, double z1, double y, int up)
{
    double a[3] = {x0, y, z0}, b[3] = {x0, y, z1}, c[3] = {x1, y, z1}, d[3] = {x1, y, z0};
    const double *v[6] = {a, b, c, a, c, d};
    for (int i = 0; i < 6; ++i)
        memcpy(p + 3 * (up ? i : 5 - i), v[i], 3 * sizeof(double));
}

/* A grey floor 10 km wide; with `roof`, a thin slab over x < ROOF_EDGE_X and a
 * sun straight down, so the air under the roof's edge holds a sharp shadow
 * boundary (the plane x = ROOF_EDGE_X). */
static pb_scene *floor_scene(int roof)
{
    double p[3 * 18];
    quad(p, -5e3, -5e3, 5e3, 5e3, FLOOR_Y, 1);
    quad(p + 18, -5e3, -5e3, ROOF_EDGE_X, 5e3, ROOF_Y + 0.001, 1);
    quad(p + 36, -5e3, -5e3, ROOF_EDGE_X, 5e3, ROOF_Y - 0.001, 0);
    pb_material m = pb_material_default();
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.5f;
    pb_scene *s = NULL;
    pb_error err;
    if (pb_scene_from_triangles(p, roof ? 6 : 2, NULL, &m, 1, &s, &err) != PB_OK) {
        fprintf(stderr, "  scene: %s\n", err.message);
        t_failures++;
        return NULL;
    }
    if (roof) {
        test_directional_light(s, 5.f, 0.f, -1.f, 0.f);
    }
    return s;
}

/* 28^3 finest lattice points 0.5 m apart from the world origin. With two
 * levels (spacings 1.5 m and 0.5 m) that is 3 x 3 x 3 coarsest bricks of
 * 4.5 m, each of 27 cells of 1.5 m; a cell refined becomes a level-1 brick
 * of 1.5 m (its coordinates count 1.5 m steps). */
static pb_bake_desc sparse_desc(const pb_scene *s)
{
    pb_bake_desc d = {0};
    for (int k = 0; k < 3; ++k) {
        d.grid.counts[k] = 28;
        d.grid.spacing[k] = 0.5f;
        d.grid.origin[k] = (float)(0.0 - s->origin[k]);
    }
    d.rays_per_probe = 1024;
    d.passes = 4;
    d.bounces = 1;
    d.octmap_res = 4;
    d.sky[0] = d.sky[1] = d.sky[2] = 1.f;
    return d;
}

static int sparse_bake(const pb_scene *s, const pb_bake_desc *d, const pb_sparse_desc *sd, pb_volume *v,
                       pb_sparse_stats *st)
{
    pb_bvh *bvh = NULL;
    pb_gpu_scene *gs = NULL;
    pb_error err;
    int ok = pb_bvh_build(s, NULL, &bvh, &err) == PB_OK && pb_gpu_scene_create(ctx, s, bvh, &gs, &err) == PB_OK &&
             pb_bake_sparse(ctx, s, gs, d, sd, v, st, &err) == PB_OK;
    if (!ok) {
        fprintf(stderr, "  sparse bake: %s\n", err.message);
        t_failures++;
    } else if (!d->target_error) {
        /* the surface test's probes take more passes (pb_sparse_desc.test_pass_scale); the volume's do not */
        CHECKF(v->settings.passes == d->passes, "volume records %u passes, baked with %u", v->settings.passes, d->passes);
    }
    pb_gpu_scene_destroy(gs);
    pb_bvh_destroy(bvh);
    return ok;
}

static void uniform_sky_is_not_refined(void)
{
    pb_scene *s = floor_scene(0);
    if (!s)
        return;
    pb_bake_desc d = sparse_desc(s);
    pb_sparse_desc sd = {2, 0.05f};
    pb_sparse_stats st;
    pb_volume v;
    if (sparse_bake(s, &d, &sd, &v, &st)) {
        fprintf(stderr, "  level 0: %u cells tested, %u far from the floor, %u refined; bricks %u + %u\n",
                st.tested[0], st.skipped[0], st.refined[0], st.bricks[0], st.bricks[1]);
        CHECK(st.tested[0] >= 9); /* the cells along the floor */
        CHECK(st.refined[0] == 0 && st.bricks[1] == 0);
        CHECK(v.sparse && v.sparse->brick_count == 27 && st.bricks[0] == 27);
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* The surface test's probes are traced with test_pass_scale times the bake's
 * passes (default 4); the volume records the bake's own. On the uniform sky
 * nothing is refined either way, so the two bakes place the same probes and
 * differ by the tests' extra passes alone. */
static void surface_tests_take_more_passes(void)
{
    pb_scene *s = floor_scene(0);
    if (!s)
        return;
    pb_bake_desc d = sparse_desc(s);
    pb_sparse_desc one = {2, 0.05f, PB_REFINE_TEST_SURFACE, 1}, dflt = {2, 0.05f, PB_REFINE_TEST_SURFACE, 0};
    pb_sparse_stats s1, s4;
    pb_volume v1, v4;
    if (sparse_bake(s, &d, &one, &v1, &s1)) {
        if (sparse_bake(s, &d, &dflt, &v4, &s4)) {
            uint64_t extra = 3ull * s1.test_probes[0] * d.rays_per_probe * d.passes;
            fprintf(stderr, "  %u test probes; rays traced %llu at 1x, %llu at the default (extra at least %llu)\n",
                    s1.test_probes[0], (unsigned long long)v1.rays_traced, (unsigned long long)v4.rays_traced,
                    (unsigned long long)extra);
            CHECK(s1.test_probes[0] > 0 && s4.test_probes[0] == s1.test_probes[0]);
            CHECK(v4.probe_count == v1.probe_count);
            CHECK(v4.rays_traced >= v1.rays_traced + extra);
            CHECK(v4.settings.passes == d.passes && v1.settings.passes == d.passes);
            pb_volume_free(&v4);
        }
        pb_volume_free(&v1);
    }
    pb_sparse_desc bad = {2, 0.05f, PB_REFINE_TEST_SURFACE, 65};
    pb_volume vb;
    pb_error err;
    CHECK(pb_bake_sparse(ctx, s, NULL, &d, &bad, &vb, NULL, &err) == PB_ERROR_INVALID_ARGUMENT);
    CHECKF(strstr(err.message, "at most 64") != NULL, "%s", err.message);
    pb_scene_destroy(s);
}

/* The seam test (placement step 3): a finer brick's hanging probes test the
 * coarser cells beside them. On the shadow boundary at E = 0.05 it refines
 * cells beside the refined ones (at 0.1 it finds none to add here), never on
 * the open sunlit side (the coarse level is right there), never a cell apart
 * from every other fine brick, and it only adds bricks: every brick of the
 * plain placement stays. */
static void seam_test_refines_only_where_coarse_errs(void)
{
    pb_scene *s = floor_scene(1);
    if (!s)
        return;
    pb_bake_desc d = sparse_desc(s);
    d.sky[0] = d.sky[1] = d.sky[2] = 0.05f;
    pb_sparse_desc plain = {2, 0.05f}, seams = {2, 0.05f, PB_REFINE_TEST_SURFACE, 0, 4};
    pb_sparse_stats sp, ss;
    pb_volume vp, vs;
    if (sparse_bake(s, &d, &plain, &vp, &sp)) {
        if (sparse_bake(s, &d, &seams, &vs, &ss)) {
            uint32_t sunlit = 0, missing = 0, alone = 0;
            const pb_sparse_layout *ls = vs.sparse;
            for (uint32_t b = 0; b < ls->brick_count; ++b) {
                if (ls->bricks[b].level != 1)
                    continue;
                sunlit += ls->bricks[b].coord[0] >= 6;
                int touches = 0; /* another fine brick within one brick along every axis */
                for (uint32_t o = 0; o < ls->brick_count && !touches; ++o) {
                    int near = o != b && ls->bricks[o].level == 1;
                    for (int k = 0; k < 3 && near; ++k)
                        near = abs((int)ls->bricks[o].coord[k] - (int)ls->bricks[b].coord[k]) <= 1;
                    touches = near;
                }
                alone += !touches;
            }
            for (uint32_t a = 0; a < vp.sparse->brick_count; ++a) {
                int found = 0;
                for (uint32_t b = 0; b < vs.sparse->brick_count && !found; ++b)
                    found = !memcmp(&vp.sparse->bricks[a], &vs.sparse->bricks[b], sizeof(pb_sparse_brick));
                missing += !found;
            }
            fprintf(stderr, "  plain: %u cells refined, %u bricks; seam test: %u refined (%u at seams), %u bricks, "
                    "%u on the open sunlit side, %u apart, %u plain bricks missing\n", sp.refined[0],
                    vp.sparse->brick_count, ss.refined[0], ss.seam_refined[0], vs.sparse->brick_count, sunlit, alone,
                    missing);
            CHECK(sp.seam_refined[0] == 0 && vp.settings.seam_rounds == 0 && vs.settings.seam_rounds == 4);
            CHECK(vp.settings.seam_error == 0.f && vs.settings.seam_error == 0.05f); /* default: the refine error */
            CHECK(ss.seam_refined[0] > 0 && ss.refined[0] == sp.refined[0] + ss.seam_refined[0]);
            CHECK(missing == 0 && sunlit == 0 && alone == 0);
            /* the gate itself (pb_sparse_seam_misses), on this layout: with every probe's SH the
             * same (uniform light, no noise) no coarser cell misses; with one hanging probe's
             * light tripled, the cells it hangs on do, and only cells beside it */
            float sh0[27];
            memcpy(sh0, vs.sh, sizeof sh0);
            for (uint32_t p = 0; p < vs.probe_count; ++p) {
                memcpy(vs.sh + 27 * (size_t)p, sh0, sizeof sh0);
                vs.probe_std_error[p] = 0.f;
            }
            pb_sparse_brick *cells = NULL;
            uint32_t n = 0, hang = UINT32_MAX, hb = 0;
            pb_error err;
            CHECK(pb_sparse_seam_misses(&vs, 1, &cells, &n, &err) == PB_OK && n == 0);
            free(cells);
            /* the first valid face probe off the coarse lattice whose tripling some coarser cell sees */
            uint32_t tried = 0;
            for (uint32_t b = 0; b < ls->brick_count && hang == UINT32_MAX && tried < 400; ++b) {
                if (ls->bricks[b].level != 1)
                    continue;
                for (uint32_t i = 0; i < 64 && hang == UINT32_MAX && tried < 400; ++i) {
                    uint32_t off[3] = {i & 3u, (i >> 2) & 3u, i >> 4}, p = ls->brick_probes[64 * (size_t)b + i];
                    int face = off[0] % 3 == 0 || off[1] % 3 == 0 || off[2] % 3 == 0;
                    int lattice = off[0] % 3 == 0 && off[1] % 3 == 0 && off[2] % 3 == 0;
                    if (!face || lattice || !(vs.probe_flags[p] & PB_PROBE_VALID))
                        continue;
                    tried++;
                    for (int c = 0; c < 27; ++c)
                        vs.sh[27 * (size_t)p + c] *= 3.f;
                    CHECK(pb_sparse_seam_misses(&vs, 1, &cells, &n, &err) == PB_OK);
                    if (n) {
                        hang = p, hb = b;
                        break;
                    }
                    free(cells);
                    memcpy(vs.sh + 27 * (size_t)p, sh0, sizeof sh0);
                }
            }
            CHECK(hang != UINT32_MAX);
            if (hang != UINT32_MAX) {
                uint32_t far = 0;
                for (uint32_t c = 0; c < n; ++c) /* beside the probe's brick: one brick away at most */
                    for (int k = 0; k < 3; ++k)
                        far += abs((int)cells[c].coord[k] - (int)ls->bricks[hb].coord[k]) > 1;
                fprintf(stderr, "  gate: uniform light 0 cells missed; one hanging probe x3 (of %u tried): %u cells, "
                        "%u far\n", tried, n, far);
                CHECK(n >= 1 && n <= 4 && far == 0);
                free(cells);
                /* --seam-error: the coarser cells all predict sh0, so the tripled probe misses
                 * them by 2 max / mean of sh0's irradiance along the six axes (the measure of
                 * sparse_miss.h); a threshold below that refines the same cells, one above none */
                float lum_max = 0.f, lum_mean = 0.f;
                for (int a = 0; a < 6; ++a) {
                    float e[3];
                    pb_sh_eval(sh0, pb_sparse_miss_axes[a], e);
                    lum_max = fmaxf(lum_max, pb_luminance(e));
                    lum_mean += pb_luminance(e) / 6.f;
                }
                float miss = 2.f * lum_max / lum_mean;
                uint32_t below = 0, above = 0;
                vs.settings.seam_error = 0.9f * miss;
                CHECK(pb_sparse_seam_misses(&vs, 1, &cells, &below, &err) == PB_OK);
                free(cells);
                vs.settings.seam_error = 1.1f * miss;
                CHECK(pb_sparse_seam_misses(&vs, 1, &cells, &above, &err) == PB_OK);
                free(cells);
                fprintf(stderr, "  the tripled probe's miss %.3f: seam error 0.9x it %u cells, 1.1x it %u\n", miss,
                        below, above);
                CHECK(below == n && above == 0);
            }
            pb_volume_free(&vs);
        }
        pb_volume_free(&vp);
    }
    pb_scene_destroy(s);
}

static void shadow_boundary_is_refined(void)
{
    pb_scene *s = floor_scene(1);
    if (!s)
        return;
    pb_bake_desc d = sparse_desc(s);
    d.sky[0] = d.sky[1] = d.sky[2] = 0.05f;
    pb_sparse_desc sd = {2, 0.1f};
    pb_sparse_stats st;
    pb_volume v;
    if (sparse_bake(s, &d, &sd, &v, &st)) {
        /* cells the boundary plane x = 6.9 crosses below the roof: x in [6, 7.5), y below 6 m;
         * the open sunlit side past x = 9 m sees the same sun, sky and lit floor everywhere */
        uint32_t across = 0, sunlit = 0, fine = 0;
        for (uint32_t b = 0; b < v.sparse->brick_count; ++b) {
            const pb_sparse_brick *br = &v.sparse->bricks[b];
            if (br->level != 1)
                continue;
            fine++;
            across += br->coord[0] == 4 && br->coord[1] <= 3;
            sunlit += br->coord[0] >= 6;
        }
        fprintf(stderr, "  level 0: %u cells tested, %u refined; %u fine bricks, %u across the shadow boundary, "
                "%u on the open sunlit side\n", st.tested[0], st.refined[0], fine, across, sunlit);
        CHECK(st.refined[0] > 0);
        CHECKF(across >= 3, "%u refined cells across the shadow boundary under the roof", across);
        CHECKF(sunlit == 0, "%u refined cells on the open sunlit side", sunlit);
        /* and the finer level predicts the boundary better: irradiance just
         * outside and just inside the shadow, 0.6 m either side of it */
        pb_sample_volume sv;
        pb_error err;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        float up[3] = {0, 1, 0}, lit[3], dark[3];
        float pl[3] = {(float)(ROOF_EDGE_X + 0.6 - s->origin[0]), (float)(2.0 - s->origin[1]), (float)(6.75 - s->origin[2])};
        float pd[3] = {(float)(ROOF_EDGE_X - 0.6 - s->origin[0]), pl[1], pl[2]};
        pb_sample_cpu(&sv, pl, up, up, lit);
        pb_sample_cpu(&sv, pd, up, up, dark);
        fprintf(stderr, "  upward irradiance 0.6 m outside the shadow %.3f, inside %.3f (sun alone: 5)\n", lit[1],
                dark[1]);
        CHECK(lit[1] > 4.f && dark[1] < 1.5f);
        pb_sample_volume_free(&sv);
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* A solid box on the floor (outward faces: probes inside it are invalid)
 * under a sky and a slanted sun, whose shadow makes the cells around it refine. */
static const double BOX_LO[3] = {4.1, FLOOR_Y, 3.7}, BOX_HI[3] = {7.3, 3.4, 6.9};

static pb_scene *box_scene(void)
{
    double p[3 * 6 + 9 * 12];
    quad(p, -5e3, -5e3, 5e3, 5e3, FLOOR_Y, 1);
    uint32_t t = 2 + box_tris(p + 18, BOX_LO, BOX_HI, 0);
    pb_material m = pb_material_default();
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 0.5f;
    pb_scene *s = NULL;
    pb_error err;
    if (pb_scene_from_triangles(p, t, NULL, &m, 1, &s, &err) != PB_OK) {
        fprintf(stderr, "  scene: %s\n", err.message);
        t_failures++;
        return NULL;
    }
    test_directional_light(s, 5.f, -0.6f, -0.8f, 0.f);
    return s;
}

/* The surface test's points (sparse_surface_tests.h): per cell (or
 * sub-cell) and normal axis, the surface point nearest its centre, on its
 * lit side. The cell [3, 4.5) x [0, 1.5) x [3, 4.5) m holds the floor beside
 * the box and three of the box's faces; the cell above the floor's holds no
 * surface. */
static void surface_tests_sit_nearest_the_cell_centre(void)
{
    pb_scene *s = box_scene();
    pb_bvh *bvh = NULL;
    pb_error err;
    if (!s || pb_bvh_build(s, NULL, &bvh, &err) != PB_OK) {
        CHECK(0);
        pb_scene_destroy(s);
        return;
    }
    pb_cell_test_desc td = {{-s->origin[0], -s->origin[1], -s->origin[2]}, {1.5, 1.5, 1.5}, {0, 0, 0}, 1};
    const uint32_t cells[3 * 3] = {0, 0, 0, 0, 2, 0, 2, 0, 2};
    pb_cell_tests ct;
    CHECK(pb_cell_surface_tests(s, bvh, &td, cells, 3, &ct, &err) == PB_OK);
    /* expected: cell 0 the floor under its centre; cell 2 the floor, the box's -x and -z faces, and
     * its bottom face (on the floor, facing down: its test probe is inside geometry and not judged) */
    const double want[5][7] = {{0, 0.75, FLOOR_Y, 0.75, 0, 1, 0},
                               {2, 3.75, FLOOR_Y, 3.75, 0, 1, 0},
                               {2, BOX_LO[0], 0.75, 3.75, -1, 0, 0},
                               {2, BOX_LO[0], 0.75, BOX_LO[2], 0, 0, -1},
                               {2, BOX_LO[0], FLOOR_Y, 3.75, 0, -1, 0}};
    CHECKF(ct.count == 5, "%u tests", ct.count);
    uint32_t found = 0;
    for (uint32_t i = 0; i < ct.count; ++i)
        for (int w = 0; w < 5; ++w) {
            double d = 0, dn = 0;
            for (int k = 0; k < 3; ++k) {
                d = fmax(d, fabs(ct.x[3 * i + k] + s->origin[k] - want[w][1 + k]));
                dn = fmax(dn, fabs(ct.n[3 * i + k] - want[w][4 + k]));
            }
            found += ct.cell[i] == (uint32_t)want[w][0] && d < 1e-3 && dn < 1e-6;
        }
    CHECKF(found == 5, "%u of the 5 expected test points found", found);
    pb_cell_tests_free(&ct);

    /* a 4.5 m cell split into 3^3 sub-cells tests exactly what its 27 cells
     * of 1.5 m test one by one (same points and normals, slot = sub-cell * 6
     * + normal axis) */
    uint32_t small[27 * 3], big[3] = {0, 0, 0};
    for (uint32_t c = 0; c < 27; ++c)
        small[3 * c] = c % 3, small[3 * c + 1] = (c / 3) % 3, small[3 * c + 2] = c / 9;
    pb_cell_tests one, split;
    pb_cell_test_desc tb = td;
    tb.size[0] = tb.size[1] = tb.size[2] = 4.5, tb.sub = 3;
    CHECK(pb_cell_surface_tests(s, bvh, &td, small, 27, &one, &err) == PB_OK);
    CHECK(pb_cell_surface_tests(s, bvh, &tb, big, 1, &split, &err) == PB_OK);
    uint32_t same = 0;
    for (uint32_t i = 0; i < split.count; ++i)
        for (uint32_t k = 0; k < one.count; ++k)
            same += split.cell[i] == 0 && split.slot[i] == one.cell[k] * 6 + one.slot[k] &&
                    !memcmp(split.x + 3 * i, one.x + 3 * k, 12) && !memcmp(split.n + 3 * i, one.n + 3 * k, 12);
    CHECKF(one.count > 12 && split.count == one.count && same == one.count,
           "sub-cells: %u tests, the 27 cells: %u, %u the same", split.count, one.count, same);
    pb_cell_tests_free(&one), pb_cell_tests_free(&split);

    /* the bounds reach below the lattice: with the lattice origin 0.2 m above
     * the floor, cell 0 tests the floor only with a margin */
    pb_cell_test_desc tm = td;
    tm.origin[1] += FLOOR_Y + 0.2;
    CHECK(pb_cell_surface_tests(s, bvh, &tm, cells, 1, &ct, &err) == PB_OK);
    CHECKF(ct.count == 0, "%u tests below the cell without a margin", ct.count);
    pb_cell_tests_free(&ct);
    tm.margin[1] = 0.5;
    CHECK(pb_cell_surface_tests(s, bvh, &tm, cells, 1, &ct, &err) == PB_OK);
    CHECKF(ct.count == 1 && fabs(ct.x[1] + s->origin[1] - FLOOR_Y) < 1e-3 && ct.n[1] == 1.f,
           "%u tests with a 0.5 m margin (the floor expected)", ct.count);
    pb_cell_tests_free(&ct);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
}

/* The box scene's bake: one quick pass under a dim sky. */
static pb_bake_desc box_desc(const pb_scene *s)
{
    pb_bake_desc d = sparse_desc(s);
    d.rays_per_probe = 256;
    d.passes = 1;
    d.sky[0] = d.sky[1] = d.sky[2] = 0.2f;
    return d;
}

/* Done-when of issue 14: no probe inside solid geometry is ever sampled.
 * Random points of free space near the box (above the floor, outside it) are
 * sampled with the C reference (the GPU sampler equals it: test_sample);
 * every probe given a weight must be valid, and every point must get one. */
static void solid_probes_are_never_sampled(void)
{
    pb_scene *s = box_scene();
    if (!s)
        return;
    pb_bake_desc d = box_desc(s);
    pb_sparse_desc sd = {2, 0.1f};
    pb_sparse_stats st;
    pb_volume v;
    if (sparse_bake(s, &d, &sd, &v, &st)) {
        pb_sample_volume sv;
        pb_error err;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        uint32_t invalid = 0;
        for (uint32_t i = 0; i < v.probe_count; ++i)
            invalid += !(v.probe_flags[i] & PB_PROBE_VALID);
        test_rng r = {11};
        uint32_t points = 0, bad = 0, unlit = 0, near_solid = 0;
        while (points < 100000) {
            double q[3];
            for (int k = 0; k < 3; ++k) /* within 1.5 m of the box: where cages reach into it */
                q[k] = BOX_LO[k] - 1.5 + (BOX_HI[k] - BOX_LO[k] + 3.0) * rng_uniform(&r);
            int in_box = 1;
            for (int k = 0; k < 3; ++k)
                in_box &= q[k] > BOX_LO[k] - 0.01 && q[k] < BOX_HI[k] + 0.01;
            if (in_box || q[1] < FLOOR_Y + 0.01)
                continue; /* not free space */
            points++;
            float p[3], n[3], rgb[3], w[8];
            int probe[8];
            for (int k = 0; k < 3; ++k)
                p[k] = (float)(q[k] - s->origin[k]);
            rng_direction(&r, n);
            pb_sample_cage_cpu(&sv, p, n, n, rgb, probe, w);
            float valid_weight = 0.f;
            int solid_in_cage = 0;
            for (int i = 0; i < 8; ++i) {
                if (probe[i] < 0)
                    continue;
                int valid = (v.probe_flags[probe[i]] & PB_PROBE_VALID) != 0;
                solid_in_cage |= !valid;
                if (w[i] > 0.f && !valid)
                    bad++;
                if (valid)
                    valid_weight += w[i];
            }
            near_solid += solid_in_cage;
            unlit += !(valid_weight > 0.99f);
        }
        fprintf(stderr, "  %u probes, %u inside geometry; %u free-space points, %u with a solid probe in their "
                "cage: %u weights on solid probes, %u points without valid weight\n", v.probe_count, invalid, points,
                near_solid, bad, unlit);
        CHECK(invalid > 0 && near_solid > 1000); /* the case arises */
        CHECKF(bad == 0, "%u weights on probes inside geometry", bad);
        CHECKF(unlit == 0, "%u free-space points with no valid probe", unlit);
        pb_sample_volume_free(&sv);
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* Placement step 7 (docs/sparse.md): a bake's probes inside geometry are
 * dropped and their brick slots name one empty probe. Against the same bake
 * kept whole (one part, dilated and stitched as merge does, not compacted):
 * every lookup whose cage holds a valid probe is bit for bit the same, a
 * cage of only invalid probes is black, the valid probes keep their data,
 * and the file reads back. */
static void invalid_probes_are_dropped(void)
{
    pb_scene *s = box_scene();
    if (!s)
        return;
    pb_bake_desc d = box_desc(s);
    d.shard_index = 0, d.shard_count = 1;
    pb_sparse_desc sd = {2, 0.1f};
    pb_sparse_stats st;
    pb_volume part, whole, c;
    pb_error err;
    if (!sparse_bake(s, &d, &sd, &part, &st)) {
        pb_scene_destroy(s);
        return;
    }
    const char *name = "part";
    CHECKF(pb_volume_merge(&part, &name, 1, &c, &err) == PB_OK, "%s", err.message);
    whole = part; /* the merge's stages without the last: dilation and stitching (whole owns part's arrays) */
    whole.flags &= ~(uint32_t)PB_VOLUME_SHARD;
    pb_volume_dilate(&whole, PB_DILATION_ROUNDS);
    CHECKF(pb_sparse_stitch(&whole, &err) == PB_OK, "%s", err.message);
    uint32_t invalid = 0;
    for (uint32_t i = 0; i < whole.probe_count; ++i)
        invalid += !(whole.probe_flags[i] & PB_PROBE_VALID);
    CHECK(invalid > 50); /* the case arises: the box's inside */
    CHECKF(c.probe_count == whole.probe_count - invalid + 1 && c.probes_dropped == invalid,
           "%u probes kept of %u, %u dropped, %u invalid", c.probe_count, whole.probe_count, c.probes_dropped,
           invalid);
    /* numbered by first use, the one empty probe included; no other invalid probe left */
    uint32_t seen = 0, empty = UINT32_MAX, bad_number = 0, bad_data = 0, bad_empty = 0;
    size_t slots = (size_t)64 * c.sparse->brick_count, halves = pb_volume_tile_halves(c.octmap_res);
    CHECK(c.sparse->brick_count == whole.sparse->brick_count);
    for (size_t k = 0; k < slots && c.sparse->brick_count == whole.sparse->brick_count; ++k) {
        uint32_t q = c.sparse->brick_probes[k], p = whole.sparse->brick_probes[k];
        if (q == seen)
            seen++;
        else if (q > seen)
            bad_number++;
        if (whole.probe_flags[p] & PB_PROBE_VALID) {
            bad_data += memcmp(c.sh + 27 * (size_t)q, whole.sh + 27 * (size_t)p, 27 * sizeof(float)) != 0 ||
                        memcmp(c.depth + halves * q, whole.depth + halves * p, halves * 2) != 0 ||
                        memcmp(c.base + 3 * (size_t)q, whole.base + 3 * (size_t)p, 12) != 0 ||
                        memcmp(c.offset + 3 * (size_t)q, whole.offset + 3 * (size_t)p, 12) != 0 ||
                        c.probe_flags[q] != whole.probe_flags[p];
        } else {
            if (empty == UINT32_MAX)
                empty = q;
            bad_empty += q != empty;
        }
    }
    CHECKF(bad_number == 0 && seen == c.probe_count, "%u slots out of first-use order, %u of %u probes named",
           bad_number, seen, c.probe_count);
    CHECKF(bad_data == 0, "%u kept probes changed", bad_data);
    CHECKF(bad_empty == 0 && empty < c.probe_count, "%u invalid slots not on the empty probe", bad_empty);
    if (empty < c.probe_count) {
        float zero[27] = {0};
        CHECK(c.probe_flags[empty] == 0 && !memcmp(c.sh + 27 * (size_t)empty, zero, sizeof zero));
    }
    /* lookups near and inside the box: the same where any valid probe is in the cage, else black */
    pb_sample_volume a, b;
    CHECK(pb_sample_volume_build(&whole, s->origin, 0.f, 0.f, &a, &err) == PB_OK);
    CHECK(pb_sample_volume_build(&c, s->origin, 0.f, 0.f, &b, &err) == PB_OK);
    test_rng r = {23};
    uint32_t same = 0, differ = 0, black = 0, unlit_cages = 0;
    for (int i = 0; i < 100000; ++i) {
        float p[3], n[3], ca[3], cb[3], w[8];
        int probe[8];
        for (int k = 0; k < 3; ++k)
            p[k] = (float)(BOX_LO[k] - 1.5 + (BOX_HI[k] - BOX_LO[k] + 3.0) * rng_uniform(&r) - s->origin[k]);
        rng_direction(&r, n);
        pb_sample_cage_cpu(&a, p, n, n, ca, probe, w);
        pb_sample_cpu(&b, p, n, n, cb);
        /* the sampler's fallback (no valid probe with a trilinear weight: a point in the box) reads the
         * invalid probes' dilated light; every other lookup weighs valid probes only */
        int any_valid = 0;
        for (int k = 0; k < 8; ++k)
            any_valid |= probe[k] >= 0 && (whole.probe_flags[probe[k]] & PB_PROBE_VALID) && w[k] > 0.f;
        if (any_valid) {
            int eq = !memcmp(ca, cb, sizeof ca);
            same += eq, differ += !eq;

        } else {
            unlit_cages++;
            black += cb[0] == 0.f && cb[1] == 0.f && cb[2] == 0.f;
        }
    }
    fprintf(stderr, "  %u probes, %u inside geometry dropped; lookups: %u the same, %u differ, %u fallbacks to "
            "invalid probes (%u black)\n", whole.probe_count, c.probes_dropped, same, differ, unlit_cages, black);
    CHECKF(differ == 0 && same > 50000, "%u lookups differ", differ);
    CHECKF(unlit_cages > 1000 && black == unlit_cages, "%u of %u fallback lookups black", black, unlit_cages);
    pb_sample_volume_free(&a);
    pb_sample_volume_free(&b);
    /* the file reads back (the layout's checks accept shared empty slots) and samples alike */
    char path[] = "/tmp/pb-sparse-XXXXXX";
    int fd = mkstemp(path);
    close(fd);
    pb_volume back;
    CHECKF(pb_volume_write(path, &c, &err) == PB_OK, "%s", err.message);
    if (pb_volume_read(path, &back, &err) == PB_OK) {
        CHECK(back.probe_count == c.probe_count &&
              !memcmp(back.sparse->brick_probes, c.sparse->brick_probes, slots * 4));
        pb_volume_free(&back);
    } else {
        CHECKF(0, "%s", err.message);
    }
    unlink(path);
    pb_volume_free(&whole);
    pb_volume_free(&c);
    pb_scene_destroy(s);
}

/* Trilinear irradiance (no visibility) at q from the cage `probe` of
 * pb_sample_cage_cpu: corner i is offset (i&1, i>>1&1, i>>2&1); their base
 * (lattice) positions give the cage's origin and spacing. Evaluated where the
 * sampler interpolates: q moved along n by `bias` (view = n). */
static float cage_trilinear(const pb_volume *v, const pb_scene *s, const int probe[8], const float q[3],
                            const float n[3], float bias, float *spacing)
{
    const float *b0 = v->base + 3 * (size_t)probe[0], *b7 = v->base + 3 * (size_t)probe[7];
    float a[3], e = 0.f;
    for (int k = 0; k < 3; ++k)
        a[k] = (float)(((double)(q[k] + n[k] * bias) + s->origin[k] - v->origin[k] - b0[k]) / (b7[k] - b0[k]));
    *spacing = b7[0] - b0[0];
    for (int i = 0; i < 8; ++i) {
        float w = 1.f, rgb[3];
        for (int k = 0; k < 3; ++k)
            w *= ((i >> k) & 1) ? a[k] : 1.f - a[k];
        pb_sh_eval(v->sh + 27 * (size_t)probe[i], n, rgb);
        e += w * pb_luminance(rgb);
    }
    return e;
}

/* Seams where a finer brick meets a coarser one (docs/sparse.md, Tests).
 * The bound derived: stitching gives the finer side's hanging face probes
 * the coarser brick's trilinear SH, and bilinear interpolation reproduces a
 * bilinear function on a refinement of it, so the trilinear (SH) part of the
 * interpolant is continuous across the face: its jump 2e-6 m either side
 * must be float noise, 1e-4 of the cages' mean (band-0) irradiance. What
 * remains is the visibility weighting; each side is a convex combination of
 * its own cage's probes, so the jump of the full sampler is bounded by the
 * spread (max - min) of the irradiance over the two cages' valid probes;
 * measured here against that bound. */
static void level_seams_are_bounded(void)
{
    pb_scene *s = floor_scene(1);
    if (!s)
        return;
    pb_bake_desc d = sparse_desc(s);
    d.sky[0] = d.sky[1] = d.sky[2] = 0.05f;
    d.rays_per_probe = 256;
    d.passes = 1;
    pb_sparse_desc sd = {2, 0.1f};
    pb_sparse_stats st;
    pb_volume v;
    if (sparse_bake(s, &d, &sd, &v, &st)) {
        pb_sample_volume sv;
        pb_error err;
        CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &sv, &err) == PB_OK);
        test_rng r = {5};
        uint32_t seams = 0, over = 0;
        float bias = (sv.normal_bias + sv.view_bias) * 0.5f; /* view = n; finest spacing 0.5 m */
        double worst_tri = 0.0, worst_full = 0.0, sum_full = 0.0;
        uint32_t kept = 0, over_kept = 0; /* points next to a probe left unstitched, and beyond its miss */
        for (uint32_t b = 0; b < v.sparse->brick_count; ++b) {
            const pb_sparse_brick *br = &v.sparse->bricks[b];
            if (br->level != 1)
                continue;
            for (int face = 0; face < 6; ++face)
                for (int t = 0; t < 64; ++t) {
                    /* a point on this fine brick's face (1.5 m cube at 1.5 m steps), and just either side */
                    int ax = face >> 1;
                    float q[3], qi[3], qo[3], n[3];
                    for (int k = 0; k < 3; ++k) {
                        double lo = 1.5 * br->coord[k];
                        q[k] = (float)(lo + (k == ax ? 1.5 * (face & 1) : 1.5 * rng_uniform(&r)) - s->origin[k]);
                    }
                    if ((double)q[1] + s->origin[1] < FLOOR_Y + 0.2)
                        continue; /* below the floor: not free space */
                    rng_direction(&r, n);
                    /* the sampler interpolates at q + bias n: start there less it, 2e-5 m either side */
                    for (int k = 0; k < 3; ++k)
                        q[k] -= n[k] * bias;
                    memcpy(qi, q, sizeof q), memcpy(qo, q, sizeof q);
                    qi[ax] += (face & 1) ? -2e-6f : 2e-6f;
                    qo[ax] += (face & 1) ? 2e-6f : -2e-6f;
                    int pi[8], po[8];
                    float wi[8], wo[8], ei[3], eo[3], si, so;
                    pb_sample_cage_cpu(&sv, qi, n, n, ei, pi, wi);
                    pb_sample_cage_cpu(&sv, qo, n, n, eo, po, wo);
                    if (pi[0] < 0 || po[0] < 0)
                        continue;
                    float ti = cage_trilinear(&v, s, pi, qi, n, bias, &si),
                          to = cage_trilinear(&v, s, po, qo, n, bias, &so);
                    if (!(so > si * 2.f))
                        continue; /* not a level boundary: the neighbour is as fine */
                    seams++;
                    float lo = 1e30f, hi = -1e30f, scale = 1e-3f;
                    for (int i = 0; i < 16; ++i) {
                        int p = i < 8 ? pi[i] : po[i - 8];
                        float rgb[3];
                        pb_sh_eval(v.sh + 27 * (size_t)p, n, rgb);
                        float l = fmaxf(pb_luminance(rgb), 0.f);
                        /* scale: the probe's irradiance averaged over directions (its SH band 0); the
                         * value along n can be far smaller (facing away from the sun), where a
                         * relative measure would be rounding of the larger coefficients */
                        scale = fmaxf(scale, fabsf(pb_luminance(v.sh + 27 * (size_t)p)) * 0.2820948f);
                        if (!(v.probe_flags[p] & PB_PROBE_VALID))
                            continue;
                        lo = fminf(lo, l), hi = fmaxf(hi, l);
                    }
                    if (fabsf(ti - to) / scale > 1e-4f && getenv("PB_DEBUG_SEAMS"))
                        fprintf(stderr, "    seam at %.4f %.4f %.4f face %d: fine %.6f coarse %.6f scale %.4f spacings %.2f %.2f\n",
                                (double)q[0] + s->origin[0], (double)q[1] + s->origin[1], (double)q[2] + s->origin[2],
                                face, ti, to, scale, si, so);
                    /* the fine cage's corners on the face: what the coarser side
                     * holds there (its trilinear at the corner) against the probe;
                     * stitched probes match it, a probe the coarser level misses by
                     * more than the refine error keeps its bake */
                    float miss = 0.f;
                    for (int i = 0; i < 8; ++i) {
                        const float *c = v.base + 3 * (size_t)pi[i];
                        float qc[3], rgb[3], so_c;
                        for (int k = 0; k < 3; ++k)
                            qc[k] = (float)((double)c[k] + v.origin[k] - s->origin[k]);
                        if (fabsf(qc[ax] - (float)((double)q[ax] + (double)n[ax] * bias)) > 1e-3f)
                            continue; /* not on the face */
                        pb_sh_eval(v.sh + 27 * (size_t)pi[i], n, rgb);
                        miss = fmaxf(miss, fabsf(pb_luminance(rgb) - cage_trilinear(&v, s, po, qc, n, 0.f, &so_c)));
                    }
                    if (miss <= 1e-4f * scale)
                        worst_tri = fmax(worst_tri, fabsf(ti - to) / scale);
                    else
                        kept++, over_kept += fabsf(ti - to) > miss + 1e-4f * scale;
                    float jump = fabsf(pb_luminance(ei) - pb_luminance(eo));
                    over += jump > (hi - lo) + 1e-5f * scale;
                    float rel = jump / fmaxf(hi - lo, 1e-6f);
                    worst_full = fmax(worst_full, rel);
                    sum_full += rel;
                }
        }
        fprintf(stderr, "  %u points on fine/coarse brick faces: trilinear jump at most %.2g of the mean irradiance; "
                "full sampler's jump %.3f (mean) and %.3f (worst) of its bound, %u over it\n", seams, worst_tri,
                seams ? sum_full / seams : 0.0, worst_full, over);
        CHECK(seams > 100);
        fprintf(stderr, "  %u of them next to a face probe the coarser level misses by more than the refine error "
                "(left unstitched): %u jumps beyond that miss\n", kept, over_kept);
        CHECKF(worst_tri < 1e-4, "trilinear jump %.3g across a level boundary", worst_tri);
        CHECKF(over_kept == 0, "%u jumps beyond the unstitched probes' miss", over_kept);
        CHECK(seams - kept > 100); /* both kinds of face point arise */
        CHECKF(over == 0, "%u jumps beyond the bound", over);
        pb_sample_volume_free(&sv);

        /* The rule itself: stitched again with no refine error recorded (stitch
         * everywhere), every hanging probe takes the coarser value; with two
         * levels those values do not depend on the first stitching (level-0
         * probes never hang), so the probes that change are exactly the ones
         * left with their bake, and the coarser value must miss each by more
         * than the refine error (one pass: no standard error to allow). */
        size_t n27 = 27 * (size_t)v.probe_count;
        float *first = malloc(n27 * sizeof *first);
        CHECK(first != NULL);
        if (first) {
            memcpy(first, v.sh, n27 * sizeof *first);
            float tol = v.settings.refine_error;
            v.settings.refine_error = 0.f;
            CHECK(pb_sparse_stitch(&v, &err) == PB_OK);
            static const float axes[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
            uint32_t unstitched = 0, wrongly = 0;
            for (uint32_t p = 0; p < v.probe_count; ++p) {
                if (!memcmp(first + 27 * (size_t)p, v.sh + 27 * (size_t)p, 27 * sizeof *first))
                    continue;
                ++unstitched;
                CHECK(v.probe_flags[p] & PB_PROBE_VALID); /* dilated probes are always stitched */
                float worst = 0.f, mean = 0.f;
                for (int a = 0; a < 6; ++a) {
                    float e[3], c[3];
                    pb_sh_eval(first + 27 * (size_t)p, axes[a], e);
                    pb_sh_eval(v.sh + 27 * (size_t)p, axes[a], c);
                    worst = fmaxf(worst, fabsf(pb_luminance(e) - pb_luminance(c)));
                    mean += pb_luminance(c) / 6.f;
                }
                wrongly += !(worst > tol * mean);
            }
            fprintf(stderr, "  stitched everywhere, %u hanging probes change (left with their bake), %u of them "
                    "within the refine error %.2f of the coarser value\n", unstitched, wrongly, (double)tol);
            CHECK(unstitched > 0);
            CHECKF(wrongly == 0, "%u probes left unstitched that the coarser level does not miss", wrongly);
            free(first);
        }
        pb_volume_free(&v);
    }
    pb_scene_destroy(s);
}

/* A sparse bake written and read back: same layout, same samples. */
static void sparse_file_round_trip(void)
{
    pb_scene *s = floor_scene(1);
    if (!s)
        return;
    pb_bake_desc d = sparse_desc(s);
    d.rays_per_probe = 64;
    d.passes = 1;
    pb_sparse_desc sd = {2, 0.1f};
    pb_sparse_stats st;
    pb_volume v, w;
    pb_error err;
    char path[] = "/tmp/pb-sparse-XXXXXX";
    int fd = mkstemp(path);
    close(fd);
    if (sparse_bake(s, &d, &sd, &v, &st)) {
        v.settings.seam_rounds = 2, v.settings.seam_error = 0.375f; /* as a seam-tested bake records them */
        CHECKF(pb_volume_write(path, &v, &err) == PB_OK, "%s", err.message);
        CHECKF(pb_volume_read(path, &w, &err) == PB_OK, "%s", err.message);
        CHECK(w.file_version == 4 && (w.flags & PB_VOLUME_SPARSE) && w.sparse);
        CHECK(w.settings.refine_error == 0.1f && w.settings.seam_rounds == 2 && w.settings.seam_error == 0.375f);
        if (w.sparse) {
            CHECK(w.sparse->levels == v.sparse->levels && w.sparse->brick_count == v.sparse->brick_count &&
                  w.sparse->chunk_count == v.sparse->chunk_count);
            CHECK(memcmp(w.sparse->brick_probes, v.sparse->brick_probes,
                         (size_t)v.sparse->brick_count * 64 * 4) == 0);
            CHECK(memcmp(w.sparse->chunks, v.sparse->chunks, (size_t)v.sparse->chunk_count * 4) == 0);
            pb_sample_volume a, b;
            CHECK(pb_sample_volume_build(&v, s->origin, 0.f, 0.f, &a, &err) == PB_OK);
            CHECK(pb_sample_volume_build(&w, s->origin, 0.f, 0.f, &b, &err) == PB_OK);
            test_rng r = {7};
            uint32_t differ = 0;
            for (int i = 0; i < 2000; ++i) {
                float p[3], n[3], ca[3], cb[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = (float)(13.5 * rng_uniform(&r) - s->origin[k]);
                rng_direction(&r, n);
                pb_sample_cpu(&a, p, n, n, ca);
                pb_sample_cpu(&b, p, n, n, cb);
                differ += memcmp(ca, cb, sizeof ca) != 0;
            }
            CHECK(differ == 0);
            pb_sample_volume_free(&a);
            pb_sample_volume_free(&b);
            pb_volume_free(&w);
        }
        pb_volume_free(&v);
    }
    unlink(path);
    pb_scene_destroy(s);
}

/* Dilation of a sparse volume (a real two-level bake, the fuzz seed
 * tests/fuzz/volume_corpus/seed-sparse2, with random SH and a third of its
 * probes invalid): the kernel equals pb_volume_dilate bit for bit, and each
 * probe's neighbours are one step of its finest level away on the lattice,
 * in the slot of their offset. */
static void sparse_dilation_kernel_matches_cpu_reference(void)
{
    pb_volume a, b;
    pb_error err;
    if (pb_volume_read(source_path("tests/fuzz/volume_corpus/seed-sparse2"), &a, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
        return;
    }
    uint32_t P = a.probe_count, state = 99, invalid = 0;
    for (uint32_t p = 0; p < P; ++p) {
        for (int c = 0; c < 27; ++c) {
            state = state * 1664525u + 1013904223u;
            a.sh[27 * p + c] = (float)(state >> 8) / 16777216.f * 4.f - 1.f;
        }
        state = state * 1664525u + 1013904223u;
        int valid = (state >> 16) % 3 != 0;
        a.probe_flags[p] = valid ? PB_PROBE_VALID : 0u;
        invalid += !valid;
    }
    CHECK(pb_volume_read(source_path("tests/fuzz/volume_corpus/seed-sparse2"), &b, &err) == PB_OK);
    memcpy(b.sh, a.sh, 27 * sizeof(float) * P);
    memcpy(b.probe_flags, a.probe_flags, 4 * P);
    /* the neighbour table's geometry */
    uint32_t *nb = pb_dilate_sparse_neighbours(a.sparse, P), finest[1024] = {0}, misplaced = 0, links = 0, full = 0;
    CHECK(nb && P <= 1024);
    for (uint32_t br = 0; br < a.sparse->brick_count; ++br)
        for (uint32_t i = 0; i < 64; ++i) {
            uint32_t p = a.sparse->brick_probes[64 * br + i];
            finest[p] = a.sparse->bricks[br].level > finest[p] ? a.sparse->bricks[br].level : finest[p];
        }
    for (uint32_t p = 0; nb && p < P; ++p) {
        uint32_t step = pb_sparse_step(a.sparse->levels, finest[p]), k = 0, have = 0;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if (!dx && !dy && !dz)
                        continue;
                    uint32_t q = nb[26 * p + k++];
                    if (q == PB_DILATE_NONE)
                        continue;
                    ++links, ++have;
                    int d[3] = {dx, dy, dz};
                    for (int c = 0; c < 3; ++c) {
                        double want = d[c] * (double)step * a.spacing[c];
                        misplaced += fabs((double)a.base[3 * q + c] - a.base[3 * p + c] - want) > 1e-4 * a.spacing[c];
                    }
                }
        full += have == 26;
    }
    pb_volume_dilate(&a, PB_DILATION_ROUNDS);
    pb_result r = pb_volume_dilate_gpu(ctx, &b, PB_DILATION_ROUNDS, &err);
    CHECKF(r == PB_OK, "%s", err.message);
    uint32_t dilated = 0;
    for (uint32_t p = 0; p < P; ++p)
        dilated += (a.probe_flags[p] & PB_PROBE_DILATED) != 0;
    int same = r == PB_OK && !memcmp(a.sh, b.sh, 27 * sizeof(float) * P) && !memcmp(a.probe_flags, b.probe_flags, 4 * P);
    fprintf(stderr, "  %u probes in %u bricks (%u levels), %u invalid: %u dilated; %u neighbour links (%u probes with "
            "all 26), %u off the lattice; kernel %s the CPU reference\n", P, a.sparse->brick_count, a.sparse->levels,
            invalid, dilated, links, full, misplaced, same ? "==" : "!=");
    CHECK(same && dilated == invalid && misplaced == 0 && full > 0);
    free(nb);
    pb_volume_free(&a);
    pb_volume_free(&b);
}

int main(void)
{
    if (!(ctx = test_gpu_context()))
        return 1;
    RUN(uniform_sky_is_not_refined);
    RUN(surface_tests_take_more_passes);
    RUN(shadow_boundary_is_refined);
    RUN(seam_test_refines_only_where_coarse_errs);
    RUN(sparse_file_round_trip);
    RUN(surface_tests_sit_nearest_the_cell_centre);
    RUN(solid_probes_are_never_sampled);
    RUN(invalid_probes_are_dropped);
    RUN(level_seams_are_bounded);
    RUN(sparse_dilation_kernel_matches_cpu_reference);
    return test_gpu_finish(ctx);
}
