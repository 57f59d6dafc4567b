/* Sharded bakes (issue 16): parts of a bake merge to the very bytes of the
 * whole bake (the timings block aside), on a grid, on points and on sparse
 * bricks (issue 14), with a
 * target error (whose floor must not tie parts together); merge refuses
 * foreign, missing, duplicated and misplaced parts; a bake on two devices
 * (two logical devices of one driver here) equals the one-device bake. */
#include "test_util.h"
#include "bake/gpu_scene.h"
#include "bake/guide_cache.h"

static pb_context *ctx;

/* The timings block of the file header (docs/format.md): the only bytes a
 * merged file may differ in. */
enum { TIMINGS_BEGIN = 184, TIMINGS_END = 248 };

typedef struct setup {
    pb_scene *scene;
    pb_bvh *bvh;
    pb_gpu_scene *gs;
} setup;

static int setup_demo(setup *su)
{
    pb_error err;
    memset(su, 0, sizeof *su);
    if (pb_scene_load(source_path("tests/scenes/demo.gltf"), NULL, &su->scene, &err) != PB_OK ||
        pb_bvh_build(su->scene, NULL, &su->bvh, &err) != PB_OK ||
        pb_gpu_scene_create(ctx, su->scene, su->bvh, &su->gs, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
        return 0;
    }
    return 1;
}

static void teardown(setup *su)
{
    pb_gpu_scene_destroy(su->gs);
    pb_bvh_destroy(su->bvh);
    pb_scene_destroy(su->scene);
}

/* 9 x 6 x 10 = 540 probes in the demo scene's cells, as bake --counts
 * places them (more than the floor sample's 256, so the sample is every
 * third probe; two stay inside its boxes, so dilation crosses parts, and
 * relocation's rays classify one of them inside: it is not traced),
 * and a target error that stops some probes early. Path guiding on: each
 * part learns the same guide (it depends on the scene and seed only). */
static pb_bake_desc demo_desc(const pb_scene *s)
{
    pb_bake_desc d = {0};
    const uint32_t counts[3] = {9, 6, 10};
    for (int k = 0; k < 3; ++k) {
        d.grid.counts[k] = counts[k];
        d.grid.spacing[k] = (s->bounds_max[k] - s->bounds_min[k]) / (float)counts[k];
        d.grid.origin[k] = s->bounds_min[k] + 0.5f * d.grid.spacing[k];
    }
    d.rays_per_probe = 32, d.passes = 8, d.target_error = 0.08f, d.bounces = 2, d.octmap_res = 4, d.seed = 1;
    d.probe_nee = 1, d.light_cells = 1, d.guide_paths = 1u << 14;
    return d;
}

/* Writes v and reads the file's bytes back (caller frees). */
static unsigned char *file_bytes(const pb_volume *v, const char *name, size_t *size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", temp_dir(), name);
    pb_error err;
    if (pb_volume_write(path, v, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
        return NULL;
    }
    FILE *f = fopen(path, "rb");
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(*size);
    *size = fread(b, 1, *size, f);
    fclose(f);
    return b;
}

/* 1 when a and b are the same file outside the timings block. */
static int same_but_timings(const pb_volume *a, const pb_volume *b)
{
    size_t na = 0, nb = 0;
    unsigned char *x = file_bytes(a, "a.probes", &na), *y = file_bytes(b, "b.probes", &nb);
    int same = x && y && na == nb && !memcmp(x, y, TIMINGS_BEGIN) &&
               !memcmp(x + TIMINGS_END, y + TIMINGS_END, na - TIMINGS_END);
    free(x), free(y);
    return same;
}

/* Bakes part i of n (a sparse layout's with sd, else a grid's), writes it
 * and reads it back (so the file's shard fields are what merge sees). */
static int bake_layout_part(setup *su, const pb_bake_desc *d, const pb_sparse_desc *sd, uint32_t i, uint32_t n,
                            pb_volume *out)
{
    pb_bake_desc dp = *d;
    dp.shard_index = i, dp.shard_count = n;
    pb_volume v;
    pb_error err;
    pb_result r = sd ? pb_bake_sparse(ctx, su->scene, su->gs, &dp, sd, &v, NULL, &err)
                     : pb_bake(ctx, su->scene, su->gs, &dp, &v, &err);
    if (r != PB_OK) {
        CHECKF(0, "%s part %u/%u: %s", sd ? "sparse" : "grid", i, n, err.message);
        return 0;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/%s%u.probes", temp_dir(), sd ? "sparse" : "part", i);
    r = pb_volume_write(path, &v, &err);
    pb_volume_free(&v);
    if (r == PB_OK)
        r = pb_volume_read(path, out, &err);
    CHECKF(r == PB_OK, "%s", err.message);
    return r == PB_OK;
}

static int bake_part(setup *su, const pb_bake_desc *d, uint32_t i, uint32_t n, pb_volume *out)
{
    return bake_layout_part(su, d, NULL, i, n, out);
}

/* Parts 0..n-1 merged; returns the merge's result (the message in err). */
static pb_result merge_parts(setup *su, const pb_bake_desc *d, uint32_t n, pb_volume *out, pb_error *err)
{
    pb_volume parts[8];
    const char *names[8] = {"p0", "p1", "p2", "p3", "p4", "p5", "p6", "p7"};
    uint32_t made = 0;
    for (uint32_t i = 0; i < n; ++i)
        made += bake_part(su, d, i, n, &parts[made]);
    pb_result r = made == n ? pb_volume_merge(parts, names, n, out, err) : PB_ERROR_INVALID_ARGUMENT;
    for (uint32_t i = 0; i < made; ++i) {
        CHECK(parts[i].flags & PB_VOLUME_SHARD);
        for (uint32_t p = 0; p < parts[i].probe_count; ++p)
            CHECK(!(parts[i].probe_flags[p] & PB_PROBE_DILATED)); /* merge dilates */
        pb_volume_free(&parts[i]);
    }
    return r;
}

static void parts_merge_to_the_whole_bake(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    pb_bake_desc d = demo_desc(su.scene);
    /* the grid, then 40 of its probes as points */
    double positions[120];
    uint32_t ids[40];
    pb_points pts = {40, positions, ids, d.grid.spacing[0]};
    for (uint32_t i = 0; i < 40; ++i) {
        uint32_t p = i * 9 + 3, ijk[3] = {p % d.grid.counts[0], (p / d.grid.counts[0]) % d.grid.counts[1],
                                          p / (d.grid.counts[0] * d.grid.counts[1])};
        ids[i] = p;
        for (int k = 0; k < 3; ++k)
            positions[3 * i + k] = su.scene->origin[k] + (d.grid.origin[k] + (double)ijk[k] * d.grid.spacing[k]);
    }
    for (int points = 0; points <= 1; ++points) {
        pb_bake_desc dd = d;
        dd.points = points ? &pts : NULL;
        pb_volume whole;
        pb_error err;
        if (pb_bake(ctx, su.scene, su.gs, &dd, &whole, &err) != PB_OK) {
            CHECKF(0, "%s", err.message);
            continue;
        }
        uint32_t converged = 0, dilated = 0, valid = 0, inside = 0;
        for (uint32_t p = 0; p < whole.probe_count; ++p) {
            valid += (whole.probe_flags[p] & PB_PROBE_VALID) != 0;
            inside += (whole.probe_flags[p] & PB_PROBE_INSIDE) != 0;
            converged += (whole.probe_flags[p] & PB_PROBE_CONVERGED) != 0;
            dilated += (whole.probe_flags[p] & PB_PROBE_DILATED) != 0;
        }
        const uint32_t counts[4] = {1, 2, 3, 7};
        for (int c = 0; c < 4; ++c) {
            pb_volume merged;
            if (merge_parts(&su, &dd, counts[c], &merged, &err) != PB_OK) {
                CHECKF(0, "%u parts: %s", counts[c], err.message);
                continue;
            }
            int same = same_but_timings(&whole, &merged);
            fprintf(stderr, "  %s, %u probes (%u valid, %u converged early, %u dilated, %u inside, not traced): %u parts "
                    "merge to %s\n", points ? "points" : "grid", whole.probe_count, valid, converged, dilated, inside, counts[c],
                    same ? "the same bytes" : "DIFFERENT bytes");
            CHECK(same);
            pb_volume_free(&merged);
        }
        CHECK(converged > 0); /* the target error did stop probes: the floor was exercised */
        CHECK(points || dilated > 0); /* invalid probes were filled across parts */
        CHECK(points || inside > 0);  /* and some were classified inside geometry by each part alike */
        pb_volume_free(&whole);
    }
    teardown(&su);
}

static void merge_refuses_foreign_missing_duplicated_parts(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    pb_bake_desc d = demo_desc(su.scene);
    d.target_error = 0.f, d.passes = 2;
    pb_volume parts[4], other;
    int ok = 1;
    for (uint32_t i = 0; i < 3; ++i)
        ok &= bake_part(&su, &d, i, 3, &parts[i]);
    pb_bake_desc foreign = d;
    foreign.seed = d.seed + 1;
    ok &= bake_part(&su, &foreign, 2, 3, &other);
    /* the same part as if baked with --passes 3 (only headers are compared) */
    pb_volume more_passes = parts[2];
    more_passes.settings.passes = d.passes + 1;
    if (ok) {
        pb_volume out;
        pb_error err;
        struct {
            const char *what;
            pb_volume v[3];
            uint32_t n;
            const char *needle;
        } cases[] = {
            {"missing", {parts[0], parts[1]}, 2, "part 2/3 is missing"},
            {"duplicated", {parts[0], parts[1], parts[1]}, 3, "given twice"},
            {"foreign", {parts[0], parts[1], other}, 3, "seed differs"},
            {"more passes", {parts[0], parts[1], more_passes}, 3, "its pass count (--passes) differs"},
        };
        const char *names[3] = {"a.probes", "b.probes", "c.probes"};
        for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
            pb_result r = pb_volume_merge(cases[k].v, names, cases[k].n, &out, &err);
            CHECKF(r == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, cases[k].needle) &&
                       !strchr(err.message, '\n'),
                   "%s: %s", cases[k].what, err.message);
            fprintf(stderr, "  %s: %s\n", cases[k].what, err.message);
            CHECK(out.probe_count == 0 && out.sh == NULL);
        }
        /* a part whose probes are not its index's, and a whole volume */
        pb_volume moved[3] = {parts[0], parts[1], parts[2]};
        moved[1].shard.first += 1;
        CHECK(pb_volume_merge(moved, names, 3, &out, &err) == PB_ERROR_INVALID_ARGUMENT &&
              strstr(err.message, "b.probes") && strstr(err.message, "every 3"));
        pb_volume whole = parts[0];
        whole.flags &= ~PB_VOLUME_SHARD;
        CHECK(pb_volume_merge(&whole, names, 1, &out, &err) == PB_ERROR_INVALID_ARGUMENT &&
              strstr(err.message, "not a part"));
    }
    for (uint32_t i = 0; i < 3; ++i)
        pb_volume_free(&parts[i]);
    pb_volume_free(&other);
    teardown(&su);
}

/* probebake merge's way: the parts' headers read alone and checked, then
 * each part read whole and added in turn, the whole and one part in memory.
 * The same volume as pb_volume_merge of all of them, bit for bit; a part
 * that is not the one its header said is an error naming it, and a sparse
 * bake's parts are refused (they are stitched together). */
static void parts_merge_one_at_a_time_from_headers(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    pb_bake_desc d = demo_desc(su.scene);
    d.target_error = 0.f, d.passes = 2;
    pb_volume parts[3], heads[3], all, stepped;
    char paths[3][512];
    const char *names[3] = {paths[0], paths[1], paths[2]};
    int made = 0;
    for (uint32_t i = 0; i < 3; ++i) {
        made += bake_part(&su, &d, i, 3, &parts[made]);
        snprintf(paths[i], sizeof paths[i], "%s/part%u.probes", temp_dir(), i); /* where bake_part wrote it */
    }
    pb_error err;
    if (made == 3 && pb_volume_merge(parts, names, 3, &all, &err) == PB_OK) {
        const uint32_t order[3] = {2, 0, 1}; /* given in any order */
        int heads_ok = 1;
        for (uint32_t i = 0; i < 3; ++i) {
            heads_ok &= pb_volume_read_header(paths[order[i]], &heads[i], &err) == PB_OK;
            CHECK(heads[i].probe_count == parts[order[i]].probe_count && !heads[i].sh && !heads[i].depth &&
                  !memcmp(&heads[i].shard, &parts[order[i]].shard, sizeof heads[i].shard) &&
                  heads[i].depth_unit == parts[order[i]].depth_unit);
        }
        const char *head_names[3] = {paths[order[0]], paths[order[1]], paths[order[2]]};
        pb_result r = heads_ok ? pb_volume_merge_begin(heads, head_names, 3, &stepped, &err) : PB_ERROR_IO;
        for (uint32_t k = 0; k < 3 && r == PB_OK; ++k) /* index order: head i holds part order[i] */
            for (uint32_t i = 0; i < 3 && r == PB_OK; ++i)
                if (order[i] == k) {
                    pb_volume whole;
                    r = pb_volume_read(head_names[i], &whole, &err);
                    if (r == PB_OK)
                        r = pb_volume_merge_add(&stepped, &whole, &heads[i], head_names[i], &err);
                    pb_volume_free(&whole);
                }
        CHECKF(r == PB_OK, "%s", err.message);
        if (r == PB_OK) {
            pb_volume_merge_end(&stepped);
            CHECK(same_but_timings(&all, &stepped) &&
                  !memcmp(&all.timings, &stepped.timings, sizeof all.timings)); /* summed in the same order */
            /* part 0 offered where part 1's header was checked */
            pb_volume probe_sink;
            CHECK(pb_volume_merge_add(&stepped, &parts[0], &heads[2], "p1.probes", &err) == PB_ERROR_INVALID_ARGUMENT &&
                  strstr(err.message, "p1.probes: changed while it was merged"));
            pb_volume sparse_head = heads[0];
            sparse_head.flags |= PB_VOLUME_SPARSE;
            CHECK(pb_volume_merge_begin(&sparse_head, names, 1, &probe_sink, &err) == PB_ERROR_INVALID_ARGUMENT &&
                  strstr(err.message, "sparse") && probe_sink.sh == NULL);
        }
        pb_volume_free(&stepped);
        pb_volume_free(&all);
    }
    for (int i = 0; i < made; ++i)
        pb_volume_free(&parts[i]);
    teardown(&su);
}

/* A copy of part v's header (and shard) for n probes, arrays allocated. */
static int part_like(const pb_volume *v, uint32_t n, pb_volume_shard shard, pb_volume *out)
{
    *out = *v;
    out->base = out->offset = out->sh = out->probe_std_error = NULL;
    out->probe_flags = out->probe_paths = NULL;
    out->depth = NULL;
    out->probe_count = n, out->shard = shard;
    pb_error err;
    CHECKF(pb_volume_alloc(out, &err) == PB_OK, "%s", err.message);
    return out->sh != NULL;
}

/* Parts are dealt: part i of n holds probes i, i + n, ... And contiguous
 * parts, as probebake wrote them before, still merge to the same volume;
 * a mix of the two, or a file whose step is not its count, is refused. */
static void parts_are_dealt_and_older_ranges_still_merge(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    pb_bake_desc d = demo_desc(su.scene);
    enum { N = 3 };
    pb_volume dealt[N], ranges[N] = {{0}}, merged, merged_ranges;
    const char *names[N] = {"p0", "p1", "p2"};
    pb_error err;
    uint32_t made = 0;
    for (uint32_t i = 0; i < N; ++i)
        made += bake_part(&su, &d, i, N, &dealt[made]);
    if (made == N && pb_volume_merge(dealt, names, N, &merged, &err) == PB_OK) {
        uint32_t total = merged.probe_count, undilated = 0, agree = 0;
        uint64_t halves = pb_volume_tile_halves(merged.octmap_res);
        for (uint32_t i = 0; i < N; ++i) {
            CHECK(dealt[i].shard.first == i && dealt[i].shard.step == N && dealt[i].shard.total == total);
            CHECK(dealt[i].probe_count == (total - i + N - 1) / N);
            for (uint32_t k = 0; k < dealt[i].probe_count; ++k) {
                uint32_t g = i + k * N;
                agree += !memcmp(dealt[i].base + 3 * k, merged.base + 3 * g, 12);
                if (!(merged.probe_flags[g] & PB_PROBE_DILATED))
                    ++undilated, agree += !memcmp(dealt[i].sh + 27 * k, merged.sh + 27 * g, 108);
            }
        }
        CHECKF(agree == total + undilated, "%u of %u positions and SH where the part has probe i + kN", agree,
               total + undilated);
        /* contiguous ranges cut from the same probes, through a file (step 0 there) */
        uint32_t built = 0;
        for (uint32_t i = 0; i < N; ++i) {
            uint32_t first = total * i / N, n = total * (i + 1) / N - first;
            if (!part_like(&dealt[0], n, (pb_volume_shard){i, N, first, total, 1}, &ranges[i]))
                continue;
            for (uint32_t k = 0; k < n; ++k) {
                uint32_t g = first + k, from = g % N, at = g / N;
                const pb_volume *v = &dealt[from];
                memcpy(ranges[i].base + 3 * k, v->base + 3 * at, 12);
                memcpy(ranges[i].offset + 3 * k, v->offset + 3 * at, 12);
                ranges[i].probe_flags[k] = v->probe_flags[at];
                memcpy(ranges[i].sh + 27 * k, v->sh + 27 * at, 108);
                memcpy(ranges[i].depth + halves * k, v->depth + halves * at, 2 * halves);
                ranges[i].probe_paths[k] = v->probe_paths[at];
                ranges[i].probe_std_error[k] = v->probe_std_error[at];
            }
            char path[512];
            snprintf(path, sizeof path, "%s/range%u.probes", temp_dir(), i);
            pb_volume back;
            if (pb_volume_write(path, &ranges[i], &err) == PB_OK && pb_volume_read(path, &back, &err) == PB_OK) {
                CHECK(back.shard.step == 1 && back.shard.first == first);
                pb_volume_free(&ranges[i]);
                ranges[i] = back;
                ++built;
            } else {
                CHECKF(0, "%s", err.message);
            }
        }
        if (built == N && pb_volume_merge(ranges, names, N, &merged_ranges, &err) == PB_OK) {
            CHECK(same_but_timings(&merged, &merged_ranges));
            pb_volume_free(&merged_ranges);
        } else {
            CHECKF(0, "contiguous parts: %s", err.message);
        }
        if (built == N) {
            pb_volume mixed[N] = {ranges[0], dealt[1], dealt[2]};
            CHECK(pb_volume_merge(mixed, names, N, &merged_ranges, &err) == PB_ERROR_INVALID_ARGUMENT &&
                  strstr(err.message, "p1") && strstr(err.message, "split"));
            fprintf(stderr, "  mixed: %s\n", err.message);
        }
        /* a dealt part's file whose step is not its count */
        char path[512];
        snprintf(path, sizeof path, "%s/part1.probes", temp_dir());
        FILE *f = fopen(path, "r+b");
        unsigned char two[4] = {2, 0, 0, 0};
        CHECK(f && fseek(f, 444, SEEK_SET) == 0 && fwrite(two, 1, 4, f) == 4);
        if (f)
            fclose(f);
        pb_volume bad;
        CHECK(pb_volume_read(path, &bad, &err) != PB_OK && strstr(err.message, "shard part out of range") &&
              strstr(err.message, "part1.probes"));
        fprintf(stderr, "  step 2 in a part of 3: %s\n", err.message);
        fprintf(stderr, "  %u probes in %u dealt parts: each probe where i + kN says; contiguous parts merge to the "
                        "same bytes\n", total, N);
        pb_volume_free(&merged);
    } else if (made == N) {
        CHECKF(0, "%s", err.message);
    }
    for (uint32_t i = 0; i < made; ++i)
        pb_volume_free(&dealt[i]);
    for (uint32_t i = 0; i < N; ++i)
        pb_volume_free(&ranges[i]);
    teardown(&su);
}

static void shard_parameters_refused(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    pb_bake_desc d = demo_desc(su.scene);
    pb_volume v;
    pb_error err;
    d.shard_index = 3, d.shard_count = 3;
    CHECK(pb_bake(ctx, su.scene, su.gs, &d, &v, &err) == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, "shard 3/3"));
    d.shard_index = 0, d.shard_count = 541; /* more parts than the 540 probes */
    CHECK(pb_bake(ctx, su.scene, su.gs, &d, &v, &err) == PB_ERROR_INVALID_ARGUMENT);
    d.shard_count = 2, d.indirect_volume = 1;
    CHECK(pb_bake(ctx, su.scene, su.gs, &d, &v, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "--indirect volume"));
    teardown(&su);
}

/* A sparse lattice over the demo scene: 0.15 m finest, two levels, so
 * 3 x 3 x 4 coarsest bricks of 1.35 m; fixed passes (a target error's
 * floor would tie each level's probes together and is refused). */
static pb_bake_desc sparse_demo_desc(const pb_scene *s, float spacing)
{
    pb_bake_desc d = {0};
    for (int k = 0; k < 3; ++k) {
        d.grid.spacing[k] = spacing;
        d.grid.counts[k] = (uint32_t)((s->bounds_max[k] - s->bounds_min[k]) / spacing) + 1;
        d.grid.origin[k] = s->bounds_min[k];
    }
    d.rays_per_probe = 32, d.passes = 2, d.bounces = 1, d.octmap_res = 4, d.seed = 1;
    d.probe_nee = 1, d.light_cells = 1, d.guide_paths = 1u << 14;
    return d;
}

/* A sparse bake splits by coarsest brick: each part places and refines its
 * own, and the merge (bricks level by level in part order, shared face
 * probes checked equal, then dilation and stitching) is the whole bake's
 * file, at once or a part at a time. Refused: a part of another refine error or refinement test, a part whose shared probe
 * was changed, a target error, --indirect volume. */
static void sparse_parts_merge_to_the_whole_bake(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    pb_bake_desc d = sparse_demo_desc(su.scene, 0.15f);
    pb_sparse_desc sd = {2, 0.1f};
    pb_volume whole, parts[3], merged;
    pb_error err;
    const char *names[3] = {"s0", "s1", "s2"};
    if (pb_bake_sparse(ctx, su.scene, su.gs, &d, &sd, &whole, NULL, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
        teardown(&su);
        return;
    }
    uint32_t made = 0, part_probes = 0, part_bricks = 0;
    for (uint32_t i = 0; i < 3; ++i)
        made += bake_layout_part(&su, &d, &sd, i, 3, &parts[made]);
    if (made == 3) {
        for (uint32_t i = 0; i < 3; ++i) {
            part_probes += parts[i].probe_count, part_bricks += parts[i].sparse->brick_count;
            CHECK((parts[i].flags & PB_VOLUME_SHARD) && parts[i].sparse && parts[i].shard.total == 36);
        }
        CHECK(pb_volume_merge(parts, names, 3, &merged, &err) == PB_OK);
        int same = same_but_timings(&whole, &merged);
        fprintf(stderr, "  sparse: %u bricks, %u probes; parts %u bricks, %u probes (faces shared): merged file %s\n",
                whole.sparse->brick_count, whole.probe_count, part_bricks, part_probes,
                same ? "the same as the whole bake's" : "DIFFERENT");
        CHECK(same && part_bricks == whole.sparse->brick_count && part_probes > whole.probe_count);
        /* probebake merge's way: the parts' layouts first (probes freed),
         * then each part's probes in turn, given in any order: the same
         * volume, timings summed in the same order */
        const uint32_t order[3] = {1, 2, 0};
        pb_volume layouts[3], stepped;
        char paths[3][512];
        const char *lnames[3] = {paths[0], paths[1], paths[2]};
        int read = 0;
        for (uint32_t i = 0; i < 3; ++i) {
            snprintf(paths[i], sizeof paths[i], "%s/sparse%u.probes", temp_dir(), order[i]); /* bake_layout_part's */
            read += pb_volume_read(paths[i], &layouts[read], &err) == PB_OK;
            if (read == (int)i + 1)
                pb_volume_free_probes(&layouts[i]);
        }
        /* the headers alone: all three pass, two of them are refused for the one missing */
        pb_volume headers[3];
        int heads = 0;
        for (uint32_t i = 0; i < 3; ++i)
            heads += pb_volume_read_header(paths[i], &headers[heads], &err) == PB_OK;
        CHECK(heads == 3 && pb_volume_merge_check(headers, lnames, 3, &err) == PB_OK &&
              pb_volume_merge_check(headers, lnames, 2, &err) == PB_ERROR_INVALID_ARGUMENT &&
              strstr(err.message, "part 0/3 is missing"));
        for (int i = 0; i < heads; ++i)
            pb_volume_free(&headers[i]);
        pb_sparse_merging *m = NULL;
        pb_result r = read == 3 ? pb_volume_merge_sparse_begin(layouts, lnames, 3, &stepped, &m, &err) : PB_ERROR_IO;
        for (uint32_t k = 0; k < 3 && r == PB_OK; ++k) {
            pb_volume part;
            char path[512];
            snprintf(path, sizeof path, "%s/sparse%u.probes", temp_dir(), k);
            r = pb_volume_read(path, &part, &err);
            if (r == PB_OK && k == 1) { /* part 0 again where part 1 is due: named, nothing added */
                CHECK(pb_sparse_merge_add(m, &stepped, &parts[0], &err) == PB_ERROR_INVALID_ARGUMENT &&
                      strstr(err.message, "sparse1.probes: changed while it was merged"));
                /* part 1 with a brick's probe indices shifted: its layout is not the one begin read */
                uint32_t keep = part.sparse->brick_probes[0];
                part.sparse->brick_probes[0] = part.sparse->brick_probes[1];
                CHECK(pb_sparse_merge_add(m, &stepped, &part, &err) == PB_ERROR_INVALID_ARGUMENT &&
                      strstr(err.message, "changed while it was merged"));
                part.sparse->brick_probes[0] = keep;
            }
            if (r == PB_OK)
                r = pb_sparse_merge_add(m, &stepped, &part, &err);
            pb_volume_free(&part);
        }
        if (r == PB_OK) {
            r = pb_sparse_merge_end(m, &stepped, &err);
            m = NULL;
        }
        pb_sparse_merging_free(m);
        CHECKF(r == PB_OK, "%s", err.message);
        CHECK(r == PB_OK && same_but_timings(&merged, &stepped) && same_but_timings(&whole, &stepped) &&
              !memcmp(&merged.timings, &stepped.timings, sizeof merged.timings));
        pb_volume_free(&stepped);
        /* ended with a part missing: refused */
        r = pb_volume_merge_sparse_begin(layouts, lnames, 3, &stepped, &m, &err);
        CHECK(r == PB_OK && pb_sparse_merge_add(m, &stepped, &parts[0], &err) == PB_OK &&
              pb_sparse_merge_end(m, &stepped, &err) == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, "1 of 3"));
        pb_volume_free(&stepped);
        for (int i = 0; i < read; ++i)
            pb_volume_free(&layouts[i]);
        pb_volume_free(&merged);
        /* a probe parts 1 and 0 both hold (a face between their bricks), changed in part 1: named */
        uint32_t shared = UINT32_MAX;
        for (uint32_t p = 0; p < parts[1].probe_count && shared == UINT32_MAX; ++p)
            for (uint32_t q = 0; q < parts[0].probe_count && shared == UINT32_MAX; ++q)
                if (!memcmp(parts[1].base + 3 * (size_t)p, parts[0].base + 3 * (size_t)q, 12))
                    shared = p;
        if (shared != UINT32_MAX) {
            float keep = parts[1].sh[27 * (size_t)shared];
            parts[1].sh[27 * (size_t)shared] += 1.f;
            CHECK(pb_volume_merge(parts, names, 3, &merged, &err) == PB_ERROR_INVALID_ARGUMENT &&
                  strstr(err.message, "differs from"));
            fprintf(stderr, "  changed shared probe: %s\n", err.message);
            parts[1].sh[27 * (size_t)shared] = keep;
        }
        CHECK(shared != UINT32_MAX);
        /* a part placed with another refine error */
        pb_volume other;
        pb_sparse_desc sd2 = {2, 0.2f};
        if (bake_layout_part(&su, &d, &sd2, 2, 3, &other)) {
            pb_volume mixed[3] = {parts[0], parts[1], other};
            CHECK(pb_volume_merge(mixed, names, 3, &merged, &err) == PB_ERROR_INVALID_ARGUMENT &&
                  strstr(err.message, "s2") && strstr(err.message, "refine error"));
            fprintf(stderr, "  other refine error: %s\n", err.message);
            pb_volume_free(&other);
        }
        /* the refinement test is recorded (the parts went through files) and must agree too:
         * a part whose surface test took 2x the passes, not 4x, and one placed by the probe test */
        CHECK(parts[0].settings.refine_test == 1u + PB_REFINE_TEST_SURFACE && parts[0].settings.test_pass_scale == 4u);
        pb_sparse_desc others[2] = {{2, 0.1f, PB_REFINE_TEST_SURFACE, 2}, {2, 0.1f, PB_REFINE_TEST_PROBE, 0}};
        for (int k = 0; k < 2; ++k) {
            if (!bake_layout_part(&su, &d, &others[k], 2, 3, &other))
                continue;
            pb_volume mixed[3] = {parts[0], parts[1], other};
            CHECK(pb_volume_merge(mixed, names, 3, &merged, &err) == PB_ERROR_INVALID_ARGUMENT &&
                  strstr(err.message, "s2") && strstr(err.message, "refinement test"));
            fprintf(stderr, "  other refinement test: %s\n", err.message);
            pb_volume_free(&other);
        }
    }
    for (uint32_t i = 0; i < made; ++i)
        pb_volume_free(&parts[i]);
    pb_volume_free(&whole);
    /* with the seam test, which adds bricks to a level in rounds (then ordered by coarsest brick):
     * the parts still merge to the whole bake's file */
    pb_sparse_desc seams = {2, 0.1f, PB_REFINE_TEST_SURFACE, 0, 2};
    pb_sparse_stats st;
    if (pb_bake_sparse(ctx, su.scene, su.gs, &d, &seams, &whole, &st, &err) == PB_OK) {
        made = 0;
        for (uint32_t i = 0; i < 3; ++i)
            made += bake_layout_part(&su, &d, &seams, i, 3, &parts[made]);
        if (made == 3) {
            CHECK(pb_volume_merge(parts, names, 3, &merged, &err) == PB_OK);
            int same = same_but_timings(&whole, &merged);
            fprintf(stderr, "  sparse with the seam test: %u cells refined at seams, %u bricks; merged file %s\n",
                    st.seam_refined[0], whole.sparse->brick_count, same ? "the same as the whole bake's" : "DIFFERENT");
            CHECK(same && st.seam_refined[0] > 0 && whole.settings.seam_rounds == 2);
            pb_volume_free(&merged);
        }
        for (uint32_t i = 0; i < made; ++i)
            pb_volume_free(&parts[i]);
        pb_volume_free(&whole);
    } else {
        CHECKF(0, "%s", err.message);
    }
    pb_volume v;
    d.shard_index = 0, d.shard_count = 2;
    d.target_error = 0.05f;
    CHECK(pb_bake_sparse(ctx, su.scene, su.gs, &d, &sd, &v, NULL, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "--target-error"));
    d.target_error = 0.f, d.indirect_volume = 1;
    CHECK(pb_bake_sparse(ctx, su.scene, su.gs, &d, &sd, &v, NULL, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "--indirect volume"));
    d.indirect_volume = 0, d.shard_count = 37; /* more parts than coarsest bricks */
    CHECK(pb_bake_sparse(ctx, su.scene, su.gs, &d, &sd, &v, NULL, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "coarsest brick"));
    teardown(&su);
}

/* The second device's log: counts the lines that say it learned a guide. */
static void count_guides_learned(pb_log_level level, const char *msg, void *user)
{
    test_log_line(level, msg, NULL);
    if (strstr(msg, "entries learned"))
        ++*(unsigned *)user;
}

/* Two logical devices of the driver the tests run on: pb_bake_devices
 * (part i on device i, a thread each, merged in memory) is the bake of one.
 * The parts share the first device's path guiding cache: the second device
 * learns no guide (guide_cache.h), the first none beyond its own bakes'. */
/* Any number of parts places what the whole does: each cell's refinement
 * rests on its own coarsest brick only. (Before 2026-11-27 a surface test
 * whose biased lookup read a neighbouring coarsest brick, which its part may
 * not hold, and a threshold on the mean of all of a bake's tests, made 2, 3
 * and 5 parts of this bake refine cells the whole did not.) */
static void sparse_parts_of_any_count_merge_to_the_whole(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    pb_bake_desc d = sparse_demo_desc(su.scene, 0.12f); /* where 2, 3 and 5 parts all differed before */
    d.rays_per_probe = 16, d.passes = 1;
    pb_sparse_desc sd = {2, 0.1f};
    pb_volume whole;
    pb_error err;
    if (pb_bake_sparse(ctx, su.scene, su.gs, &d, &sd, &whole, NULL, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
        teardown(&su);
        return;
    }
    const uint32_t counts[3] = {2, 3, 5};
    const char *names[5] = {"s0", "s1", "s2", "s3", "s4"};
    for (int c = 0; c < 3; ++c) {
        uint32_t n = counts[c], made = 0;
        pb_volume parts[5], merged;
        for (uint32_t i = 0; i < n; ++i)
            made += bake_layout_part(&su, &d, &sd, i, n, &parts[made]);
        if (made == n && pb_volume_merge(parts, names, n, &merged, &err) == PB_OK) {
            int same = same_but_timings(&whole, &merged);
            fprintf(stderr, "  %u sparse parts: %u bricks merged, %s\n", n, merged.sparse->brick_count,
                    same ? "the whole bake's file" : "DIFFERENT from the whole bake's file");
            CHECKF(same, "%u parts: %u bricks, the whole %u", n, merged.sparse->brick_count, whole.sparse->brick_count);
            pb_volume_free(&merged);
        } else if (made == n) {
            CHECKF(0, "%u parts: %s", n, err.message);
        }
        for (uint32_t i = 0; i < made; ++i)
            pb_volume_free(&parts[i]);
    }
    pb_volume_free(&whole);
    teardown(&su);
}

static void two_devices_bake_like_one(void)
{
    setup su;
    if (!setup_demo(&su))
        return;
    unsigned learned_on_second = 0;
    pb_context_desc cd = {getenv("PB_TEST_DEVICE"), 1, 0, 0, {count_guides_learned, &learned_on_second}};
    cd.portable_kernels = pb_context_native64(ctx) ? 0u : 1u;
    pb_context *second = NULL;
    pb_gpu_scene *gs2 = NULL;
    pb_error err;
    if (pb_context_create(&cd, &second, &err) != PB_OK ||
        pb_gpu_scene_create(second, su.scene, su.bvh, &gs2, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
    } else {
        pb_bake_desc d = demo_desc(su.scene);
        pb_volume whole, both;
        pb_context *ctxs[2] = {ctx, second};
        pb_gpu_scene *scenes[2] = {su.gs, gs2};
        if (pb_bake(ctx, su.scene, su.gs, &d, &whole, &err) == PB_OK &&
            pb_bake_devices(ctxs, scenes, 2, su.scene, &d, NULL, &both, &err) == PB_OK) {
            int same = same_but_timings(&whole, &both);
            const pb_guide_cache *gc = su.gs->guide_cache;
            fprintf(stderr, "  2 devices: %s bytes as 1; guides learned: %u on device 0, %u on device 1\n",
                    same ? "the same" : "DIFFERENT", gc ? gc->learns : 0u, learned_on_second);
            CHECK(same);
            CHECK(gc && gc->learns == 1 && learned_on_second == 0);
            CHECK(pb_context_validation_messages(second) == 0);
            pb_volume_free(&both);
        } else {
            CHECKF(0, "%s", err.message);
        }
        pb_volume_free(&whole);
        /* a sparse bake on two devices: parts by coarsest brick, merged */
        pb_bake_desc ds = sparse_demo_desc(su.scene, 0.15f);
        pb_sparse_desc sd = {2, 0.1f};
        if (pb_bake_sparse(ctx, su.scene, su.gs, &ds, &sd, &whole, NULL, &err) == PB_OK &&
            pb_bake_devices(ctxs, scenes, 2, su.scene, &ds, &sd, &both, &err) == PB_OK) {
            int same = same_but_timings(&whole, &both);
            fprintf(stderr, "  sparse on 2 devices: %s bytes as 1\n", same ? "the same" : "DIFFERENT");
            CHECK(same);
            CHECK(su.gs->guide_cache->learns == 2 && learned_on_second == 0); /* one bounce: another key */
            pb_volume_free(&both);
        } else {
            CHECKF(0, "%s", err.message);
        }
        pb_volume_free(&whole);
        d.shard_count = 2; /* already split by device */
        CHECK(pb_bake_devices(ctxs, scenes, 2, su.scene, &d, NULL, &both, &err) == PB_ERROR_INVALID_ARGUMENT);
    }
    pb_gpu_scene_destroy(gs2);
    pb_context_destroy(second);
    teardown(&su);
}

int main(void)
{
    if (!(ctx = test_gpu_context()))
        return 1;
    RUN(parts_merge_to_the_whole_bake);
    RUN(merge_refuses_foreign_missing_duplicated_parts);
    RUN(parts_merge_one_at_a_time_from_headers);
    RUN(parts_are_dealt_and_older_ranges_still_merge);
    RUN(shard_parameters_refused);
    RUN(sparse_parts_merge_to_the_whole_bake);
    RUN(sparse_parts_of_any_count_merge_to_the_whole);
    RUN(two_devices_bake_like_one);
    return test_gpu_finish(ctx);
}
