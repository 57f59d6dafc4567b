/* Volume files and half floats: exhaustive half round trips, rounding
 * against a reference, file round trip, atomic writes, every malformed-file
 * error. CPU only. */
#define _DEFAULT_SOURCE /* mknod, makedev, symlink */
#include "test_util.h"
#include "common/common.h"
#include "io/half_pairs.h"

#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/sysmacros.h>
#include <sys/un.h>

#include <stb_image.h>

/* Every finite half converts to float and back to itself; NaNs stay NaN;
 * +-0 and +-Inf keep their bit patterns. (Exhaustive: the domain is small.) */
static void half_round_trip_exhaustive(void)
{
    uint32_t bad = 0;
    for (uint32_t h = 0; h < 65536; ++h) {
        float f = pb_half_to_float((uint16_t)h);
        uint16_t back = pb_half_from_float(f);
        int is_nan = (h & 0x7c00u) == 0x7c00u && (h & 0x3ffu);
        if (is_nan ? !(f != f) || (back & 0x7c00u) != 0x7c00u || !(back & 0x3ffu) : back != h) {
            if (bad < 5)
                fprintf(stderr, "  half %04x -> %a -> %04x\n", h, f, back);
            ++bad;
        }
    }
    CHECK(bad == 0);
    CHECK(pb_half_to_float(0x3c00u) == 1.f && pb_half_to_float(0x0001u) == ldexpf(1.f, -24));
    CHECK(pb_half_to_float(0x7bffu) == 65504.f);
}

/* float -> half is the nearest half, ties to even: checked against a search
 * over the sorted positive halves, on values biased to the hard places. */
static void half_rounding_matches_reference(void)
{
    test_rng r = {17};
    uint32_t bad = 0, n = scaled(200000);
    for (uint32_t i = 0; i < n; ++i) {
        float f;
        switch (i % 4) {
        case 0: f = (float)ldexp(rng_uniform(&r) + 0.5, (int)(rng_uniform(&r) * 44) - 28); break;
        case 1: { uint16_t h = (uint16_t)(rng_uniform(&r) * 0x7bff); /* exact midpoints between halves */
                  f = 0.5f * (pb_half_to_float(h) + pb_half_to_float((uint16_t)(h + 1))); break; }
        case 2: f = (float)(rng_uniform(&r) * 70000.0); break;
        default: f = (float)(rng_uniform(&r) * 1e-4); break;
        }
        if (i & 8)
            f = -f;
        /* reference: nearest of the two neighbouring halves, ties to even */
        float a = fabsf(f);
        uint16_t lo = 0, hi = 0x7c00u; /* find largest half <= a */
        while (lo < hi) {
            uint16_t mid = (uint16_t)((lo + hi + 1) / 2);
            if (pb_half_to_float(mid) <= a) lo = mid; else hi = (uint16_t)(mid - 1);
        }
        uint16_t want = lo;
        if (lo < 0x7c00u) {
            double dl = (double)a - pb_half_to_float(lo);
            /* above the largest half (65504) the next step would be 65536: that rounds to Inf */
            double dh = (lo + 1 == 0x7c00u ? 65536.0 : (double)pb_half_to_float((uint16_t)(lo + 1))) - (double)a;
            if (dh < dl || (dh == dl && (lo & 1u)))
                want = (uint16_t)(lo + 1);
        }
        want = (uint16_t)(want | (f < 0 || (f == 0 && signbit(f)) ? 0x8000u : 0u));
        uint16_t got = pb_half_from_float(f);
        if (got != want) {
            if (bad < 5)
                fprintf(stderr, "  %a: got %04x want %04x\n", f, got, want);
            ++bad;
        }
    }
    CHECKF(bad == 0, "%u of %u conversions differ", bad, n);
    CHECK(pb_half_from_float(1e6f) == 0x7c00u && pb_half_from_float(-1e6f) == 0xfc00u);
    CHECK(pb_half_from_float(NAN) != 0x7c00u && (pb_half_from_float(NAN) & 0x7c00u) == 0x7c00u);
}

/* The volume stage's bulk conversion (F16C on x86-64) gives the halves that
 * one conversion at a time gives, bit for bit: every sign and exponent,
 * every 10-bit half mantissa, the dropped bits at and around each rounding
 * midpoint (a subnormal half's midpoint moves with the exponent), NaN
 * payloads; divisors that keep those midpoints (powers of two) and ones that
 * do not (a pass count times the depth unit); run lengths that leave a tail. */
static void half_pairs_match_one_at_a_time(void)
{
    uint32_t count = 512u * 1024u * 8u;
    float *in = malloc(count * sizeof *in);
    uint16_t *fast = malloc(count * sizeof *fast), *slow = malloc(count * sizeof *slow);
    CHECK(in && fast && slow);
    test_rng r = {29};
    uint32_t k = 0;
    for (uint32_t se = 0; se < 512; ++se) /* sign and exponent */
        for (uint32_t top = 0; top < 1024; ++top) {
            int e = (int)(se & 255u) - 127 + 15; /* the half's biased exponent */
            uint32_t cut = e >= 1 ? 13u : e >= -10 ? (uint32_t)(14 - e) : 24u; /* bits a half drops */
            uint32_t mid = 1u << (cut - 1u);
            uint32_t low[8] = {0, 1, mid - 1u, mid, mid + 1u, (1u << cut) - 1u, 0, 0};
            low[6] = (uint32_t)(rng_uniform(&r) * 8388608.0);
            low[7] = mid | (1u << cut); /* a tie whose kept part is odd */
            for (int i = 0; i < 8; ++i) {
                uint32_t bits = (se << 23) | (((top << 13) | low[i]) & 0x7fffffu);
                memcpy(&in[k++], &bits, 4);
            }
        }
    pb_half_path best = pb_half_best_path();
    const double divs[5][2] = {{1, 1}, {0.125, 0.015625}, {3 * 0.125, 3 * 0.015625}, {7 * 16.0, 7 * 256.0},
                               {1023 * ldexp(1, -9), 1023 * ldexp(1, -18)}};
    uint32_t bad = 0;
    for (int d = 0; d < 5; ++d) {
        memset(fast, 0, count * sizeof *fast);
        uint32_t pairs = count / 2, at = 0;
        for (uint32_t run = 1; at < pairs; run = run % 37 + 1) { /* runs of 1 to 37 pairs */
            uint32_t m = pairs - at < run ? pairs - at : run;
            pb_half_pairs(best, in + 2 * at, fast + 2 * at, m, divs[d][0], divs[d][1]);
            at += m;
        }
        pb_half_pairs(PB_HALF_SCALAR, in, slow, pairs, divs[d][0], divs[d][1]);
        for (uint32_t i = 0; i < count; ++i) {
            uint16_t want = pb_half_from_float((float)((double)in[i] / divs[d][i & 1]));
            if (fast[i] != want || slow[i] != want) {
                if (bad < 5)
                    fprintf(stderr, "  %a / %g: fast %04x scalar %04x want %04x\n", in[i], divs[d][i & 1], fast[i],
                            slow[i], want);
                ++bad;
            }
        }
    }
    CHECKF(bad == 0, "%u of %u conversions differ", bad, 5 * count);
    fprintf(stderr, "  bulk conversion: %s\n", best == PB_HALF_F16C ? "F16C" : "scalar only (no F16C on this CPU)");
    free(in);
    free(fast);
    free(slow);
}

static void fill(pb_volume *v, uint32_t nx, uint32_t ny, uint32_t nz, uint32_t n)
{
    memset(v, 0, sizeof *v);
    v->flags = PB_VOLUME_GRID | PB_VOLUME_IRRADIANCE | PB_VOLUME_DIRECT;
    v->probe_count = nx * ny * nz;
    v->counts[0] = nx, v->counts[1] = ny, v->counts[2] = nz;
    v->octmap_res = n;
    v->origin[0] = 1e7 + 0.25, v->origin[1] = -3.5, v->origin[2] = 42.0;
    v->spacing[0] = v->spacing[1] = v->spacing[2] = 0.5;
    v->settings = (pb_volume_settings){0xdeadbeefcafeull, 0x1234567890abcdefull, 256, 8, 3, 1, 0.01f, 64.f, 2, 2.5f, 7.f};
    v->timings = (pb_volume_timings){1, 2, 3, 4, 5, 6, 7, 28};
    snprintf(v->device, sizeof v->device, "test device");
    CHECK(pb_volume_alloc(v, NULL) == PB_OK);
    test_rng r = {5};
    for (uint32_t i = 0; i < v->probe_count; ++i) {
        for (int k = 0; k < 3; ++k) {
            v->base[3 * i + k] = (float)((i % (k == 0 ? nx : k == 1 ? ny : nz)) * 0.5);
            v->offset[3 * i + k] = (float)(rng_uniform(&r) - 0.5) * 0.1f;
        }
        v->probe_flags[i] = PB_PROBE_VALID | (i % 3 == 0 ? PB_PROBE_RELOCATED : 0);
        for (int c = 0; c < 27; ++c)
            v->sh[27 * i + c] = (float)(rng_uniform(&r) * 10 - 2);
        v->probe_paths[i] = 256u * (1u + i % 8u);
        v->probe_std_error[i] = i % 5 == 4 ? PB_STD_ERROR_UNKNOWN : (float)(rng_uniform(&r) * 0.2);
    }
    for (uint64_t t = 0; t < v->probe_count * pb_volume_tile_halves(n); ++t)
        v->depth[t] = pb_half_from_float((float)(rng_uniform(&r) * 20));
}

static void file_round_trip(void)
{
    pb_volume v, w;
    fill(&v, 4, 3, 2, 16);
    char path[512];
    snprintf(path, sizeof path, "%s/grid.probes", temp_dir());
    pb_error err;
    CHECKF(pb_volume_write(path, &v, &err) == PB_OK, "%s", err.message);
    CHECKF(pb_volume_read(path, &w, &err) == PB_OK, "%s", err.message);
    CHECK(w.probe_count == 24 && w.octmap_res == 16 && w.flags == v.flags);
    CHECK(memcmp(w.counts, v.counts, sizeof v.counts) == 0 && memcmp(w.origin, v.origin, sizeof v.origin) == 0);
    CHECK(memcmp(&w.settings, &v.settings, sizeof v.settings) == 0);
    CHECK(memcmp(&w.timings, &v.timings, sizeof v.timings) == 0);
    CHECK(strcmp(w.device, "test device") == 0);
    CHECK(v.depth_unit == 0.5f && w.depth_unit == v.depth_unit); /* max distance 64 -> 64 / 128 */
    CHECK(memcmp(w.base, v.base, 24 * 12) == 0 && memcmp(w.offset, v.offset, 24 * 12) == 0);
    CHECK(memcmp(w.probe_flags, v.probe_flags, 24 * 4) == 0 && memcmp(w.sh, v.sh, 24 * 27 * 4) == 0);
    CHECK(memcmp(w.depth, v.depth, 24 * pb_volume_tile_halves(16) * 2) == 0);
    CHECK(memcmp(w.probe_paths, v.probe_paths, 24 * 4) == 0 && memcmp(w.probe_std_error, v.probe_std_error, 24 * 4) == 0);
    CHECK(w.file_version == PB_VOLUME_VERSION && PB_VOLUME_VERSION == 4);
    double p[3];
    pb_volume_probe_position(&w, 1, p);
    CHECK(fabs(p[0] - (1e7 + 0.25 + 0.5 + w.offset[3])) < 1e-9);
    /* size per probe at the default octmap size stays under 1.5 KB */
    double per_probe = (double)(pb_volume_file_bytes(&v) - 512) / v.probe_count;
    fprintf(stderr, "  %.0f bytes per probe at 16x16 octmaps\n", per_probe);
    CHECK(per_probe <= 1536);
    pb_volume_free(&w);
    pb_volume_free(&v);
}

static int count_files(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        n += e->d_name[0] != '.';
    if (d)
        closedir(d);
    return n;
}

/* A write that cannot complete leaves neither the target nor a temporary. */
static void failed_write_leaves_nothing(void)
{
    pb_volume v;
    fill(&v, 2, 2, 2, 4);
    char dir[512], path[600];
    snprintf(dir, sizeof dir, "%s/atomic", temp_dir());
    mkdir(dir, 0755);
    pb_error err;
    snprintf(path, sizeof path, "%s/missing-dir/out.probes", dir);
    CHECK(pb_volume_write(path, &v, &err) == PB_ERROR_IO && strstr(err.message, path) != NULL);
    CHECK(count_files(dir) == 0);
    /* an existing good file survives a failed rewrite untouched */
    snprintf(path, sizeof path, "%s/keep.probes", dir);
    CHECK(pb_volume_write(path, &v, &err) == PB_OK);
    pb_volume broken = v;
    broken.sh = NULL;
    CHECK(pb_volume_write(path, &broken, &err) == PB_ERROR_INVALID_ARGUMENT);
    pb_volume w;
    CHECK(pb_volume_read(path, &w, &err) == PB_OK && w.probe_count == 8);
    pb_volume_free(&w);
    CHECK(count_files(dir) == 1);
    pb_volume_free(&v);
}

static void malformed_files_get_clear_errors(void)
{
    pb_volume v, w;
    fill(&v, 2, 2, 1, 8);
    char path[512];
    snprintf(path, sizeof path, "%s/src.probes", temp_dir());
    pb_error err;
    CHECK(pb_volume_write(path, &v, &err) == PB_OK);
    char *bytes = malloc(pb_volume_file_bytes(&v));
    FILE *f = fopen(path, "rb");
    size_t size = fread(bytes, 1, pb_volume_file_bytes(&v), f);
    fclose(f);
    CHECK(size == pb_volume_file_bytes(&v));

    struct {
        const char *name;
        size_t offset;
        uint32_t value;
        size_t keep;
        pb_result want;
        const char *needle;
    } cases[] = {
        {"magic.probes", 0, 0x21212121u, 0, PB_ERROR_PARSE, "not a probebake volume"},
        {"version.probes", 8, 99, 0, PB_ERROR_UNSUPPORTED, "version 99"},
        {"count.probes", 20, 0, 0, PB_ERROR_PARSE, "probe count"},
        {"grid.probes", 24, 7, 0, PB_ERROR_PARSE, "grid counts"},
        {"octmap.probes", 36, 1000, 0, PB_ERROR_PARSE, "octahedral"},
        {"section.probes", 160, 12345, 0, PB_ERROR_PARSE, "section offsets"},
        {"unit.probes", 180, 0, 0, PB_ERROR_PARSE, "depth unit"},
        {"unit-nan.probes", 180, 0x7fc00000u, 0, PB_ERROR_PARSE, "depth unit"},
        {"depth-format.probes", 128, 1, 0, PB_ERROR_PARSE, "depth format"},
        {"truncated.probes", 0, 0, 1000, PB_ERROR_PARSE, "truncated"},
        {"accounting-offset.probes", 392, 16, 0, PB_ERROR_PARSE, "section offsets"},
        {"std-error-negative.probes", size - 4, 0xbf000000u, 0, PB_ERROR_PARSE, "probe 3 has a negative or non-finite standard error"},
        {"std-error-nan.probes", size - 4, 0x7fc00000u, 0, PB_ERROR_PARSE, "standard error"},
        {"header.probes", 0, 0, 100, PB_ERROR_PARSE, "truncated header"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char *copy = malloc(size);
        memcpy(copy, bytes, size);
        size_t n = size;
        if (cases[i].keep)
            n = cases[i].keep < 200 ? cases[i].keep : size - cases[i].keep;
        else
            memcpy(copy + cases[i].offset, &cases[i].value, 4);
        const char *p = write_file(cases[i].name, copy, n);
        pb_result r = pb_volume_read(p, &w, &err);
        CHECKF(r == cases[i].want, "%s: got %s (%s)", cases[i].name, pb_result_name(r), err.message);
        CHECKF(strstr(err.message, p) && strstr(err.message, cases[i].needle), "%s: message '%s'", cases[i].name,
               err.message);
        free(copy);
    }
    CHECK(pb_volume_read("/nonexistent/x.probes", &w, &err) == PB_ERROR_IO);
    free(bytes);
    pb_volume_free(&v);
}

/* A hand-made sparse layout over 2 x 1 x 1 cells of three levels: a level-0
 * brick in cell 0 with a level-1 brick inside and a level-2 brick inside
 * that; in cell 1 only a level-1 brick (the rest of cell 1 is empty). */
static const pb_sparse_brick test_bricks[4] = {{0, {0, 0, 0}}, {1, {1, 1, 1}}, {2, {4, 4, 4}}, {1, {4, 0, 0}}};
static const uint32_t test_cells[3] = {2, 1, 1};

/* pb_sparse_find names, for random points, the finest brick whose region
 * holds the point (found by testing every brick), or none; probes are
 * shared: a probe of the level-1 brick on a level-0 lattice point is the
 * level-0 brick's. */
static void sparse_lookup_finds_the_finest_brick(void)
{
    pb_sparse_layout l;
    uint32_t P = 0, *keys = NULL;
    pb_error err;
    CHECKF(pb_sparse_layout_build(3, test_cells, test_bricks, 4, &l, &P, &keys, &err) == PB_OK, "%s", err.message);
    CHECK(pb_sparse_layout_validate(&l, P, &err) == PB_OK);
    /* the three bricks of cell 0 share lattice points: fewer than 4 x 64 probes */
    fprintf(stderr, "  %u bricks, %u probes, %u chunk entries\n", l.brick_count, P, l.chunk_count);
    CHECK(P < 4 * 64 && l.chunk_count == 729 + 27);
    uint32_t shared = 0;
    for (uint32_t i = 0; i < 64; ++i)
        for (uint32_t j = 0; j < 64; ++j)
            shared += l.brick_probes[i] == l.brick_probes[64 + j];
    CHECK(shared == 8); /* level-1 brick (1,1,1) spans lattice 3..6 of level 1: 3 and 6 are level-0 points */
    test_rng r = {11};
    uint32_t wrong = 0, empty = 0;
    for (int i = 0; i < 100000; ++i) {
        float u[3] = {(float)(2.0 * rng_uniform(&r)), (float)rng_uniform(&r), (float)rng_uniform(&r)};
        uint32_t want = PB_SPARSE_EMPTY, want_level = 0;
        for (uint32_t b = 0; b < 4; ++b) {
            const pb_sparse_brick *br = &test_bricks[b];
            double n = br->level == 0 ? 1 : br->level == 1 ? 3 : 9;
            int inside = 1;
            for (int k = 0; k < 3; ++k)
                inside &= floor((double)u[k] * n) == br->coord[k];
            if (inside && (want == PB_SPARSE_EMPTY || br->level > want_level))
                want = b, want_level = br->level;
        }
        uint32_t got = pb_sparse_find(&l, u);
        wrong += got != want;
        empty += got == PB_SPARSE_EMPTY;
    }
    fprintf(stderr, "  100000 points: %u wrong, %u in no brick\n", wrong, empty);
    CHECK(wrong == 0 && empty > 0);
    /* points past the cells clamp to the nearest cell */
    float far[3] = {-5.f, 0.5f, 0.5f};
    CHECK(pb_sparse_find(&l, far) == 0);
    pb_sparse_brick dup[2] = {{1, {1, 1, 1}}, {1, {1, 1, 1}}}, out[1] = {{1, {6, 0, 0}}};
    pb_sparse_layout bad;
    uint32_t bad_P;
    CHECK(pb_sparse_layout_build(3, test_cells, dup, 2, &bad, &bad_P, NULL, &err) == PB_ERROR_INVALID_ARGUMENT);
    CHECK(pb_sparse_layout_build(3, test_cells, out, 1, &bad, &bad_P, NULL, &err) == PB_ERROR_INVALID_ARGUMENT);
    pb_sparse_brick finer[1] = {{3, {0, 0, 0}}}; /* level 3 of 3 levels (0-2) */
    CHECK(pb_sparse_layout_build(3, test_cells, finer, 1, &bad, &bad_P, NULL, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "brick 0 has level 3 of 3"));
    CHECK(pb_sparse_layout_build(0, test_cells, test_bricks, 4, &bad, &bad_P, NULL, &err) == PB_ERROR_INVALID_ARGUMENT &&
          strstr(err.message, "0 levels"));
    /* a deep copy: the same tables, its own arrays */
    pb_sparse_layout c;
    CHECKF(pb_sparse_layout_copy(&l, &c, &err) == PB_OK, "%s", err.message);
    CHECK(c.brick_count == l.brick_count && c.chunk_count == l.chunk_count && c.bricks != l.bricks &&
          c.brick_probes != l.brick_probes && c.indirection != l.indirection && c.chunks != l.chunks &&
          !memcmp(c.bricks, l.bricks, l.brick_count * sizeof *l.bricks) &&
          !memcmp(c.brick_probes, l.brick_probes, (size_t)l.brick_count * PB_SPARSE_BRICK_PROBES * sizeof(uint32_t)) &&
          !memcmp(c.indirection, l.indirection, (size_t)test_cells[0] * test_cells[1] * test_cells[2] * 4) &&
          !memcmp(c.chunks, l.chunks, l.chunk_count * sizeof(uint32_t)) && pb_sparse_layout_validate(&c, P, &err) == PB_OK);
    float mid[3] = {0.5f, 0.5f, 0.5f};
    uint32_t found = pb_sparse_find(&l, mid);
    c.brick_probes[0] ^= 1u;
    pb_sparse_layout_free(&c);
    CHECK(pb_sparse_find(&l, mid) == found && pb_sparse_layout_validate(&l, P, &err) == PB_OK);
    free(keys);
    pb_sparse_layout_free(&l);
}

/* A sparse volume survives a write and a read; damaged layouts are refused
 * with the file named and nothing allocated (ASan watches). */
static void sparse_files_round_trip_and_refuse_damage(void)
{
    pb_sparse_layout *l = calloc(1, sizeof *l);
    uint32_t P = 0;
    pb_error err;
    CHECK(pb_sparse_layout_build(3, test_cells, test_bricks, 4, l, &P, NULL, &err) == PB_OK);
    pb_volume v, w;
    fill(&v, P, 1, 1, 4);
    v.flags = PB_VOLUME_SPARSE | PB_VOLUME_IRRADIANCE;
    v.sparse = l;
    char path[512];
    snprintf(path, sizeof path, "%s/sparse.probes", temp_dir());
    CHECKF(pb_volume_write(path, &v, &err) == PB_OK, "%s", err.message);
    CHECKF(pb_volume_read(path, &w, &err) == PB_OK, "%s", err.message);
    CHECK(w.file_version == 4 && (w.flags & PB_VOLUME_SPARSE) && w.sparse && w.probe_count == P);
    if (w.sparse) {
        CHECK(w.sparse->levels == 3 && w.sparse->brick_count == 4 && w.sparse->chunk_count == l->chunk_count);
        CHECK(memcmp(w.sparse->bricks, l->bricks, 4 * sizeof *l->bricks) == 0);
        CHECK(memcmp(w.sparse->brick_probes, l->brick_probes, 4 * 64 * 4) == 0);
        CHECK(memcmp(w.sparse->indirection, l->indirection, 2 * 4) == 0);
        CHECK(memcmp(w.sparse->chunks, l->chunks, (size_t)l->chunk_count * 4) == 0);
    }
    CHECK(memcmp(w.sh, v.sh, (size_t)P * 27 * 4) == 0);
    pb_volume_free(&w);
    uint64_t size = pb_volume_file_bytes(&v);
    char *bytes = malloc(size);
    FILE *f = fopen(path, "rb");
    CHECK(fread(bytes, 1, size, f) == size);
    fclose(f);
    uint64_t at = 0;
    memcpy(&at, bytes + 416, 8);
    uint64_t chunks = at + 32 + 4 * 16 + 4 * 64 * 4 + 2 * 4;
    struct {
        const char *name;
        uint64_t offset;
        uint32_t value;
        const char *needle;
    } cases[] = {
        {"sparse-levels.probes", at, 4, "levels"},
        {"sparse-brick-level.probes", at + 32 + 12, 3, "level 3"},
        {"sparse-brick-probe.probes", at + 32 + 64, P, "names probe"},
        {"sparse-chunk-elsewhere.probes", chunks, 3, "elsewhere"},
        {"sparse-chunk-range.probes", chunks, 77, "names brick 77"},
        {"sparse-depth.probes", at + 32 + 4 * 16 + 4 * 64 * 4, 3u << 28, "depth 3"},
        {"sparse-cells.probes", at + 4, 1u << 21, "too many cells"},
        {"sparse-offset.probes", 416, 8, "section offsets"},
        {"sparse-flag-v3.probes", 8, 3, "sparse flag"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char *copy = malloc(size);
        memcpy(copy, bytes, size);
        memcpy(copy + cases[i].offset, &cases[i].value, 4);
        const char *p = write_file(cases[i].name, copy, size);
        pb_result r = pb_volume_read(p, &w, &err);
        CHECKF(r == PB_ERROR_PARSE && strstr(err.message, p) && strstr(err.message, cases[i].needle),
               "%s: %s '%s'", cases[i].name, pb_result_name(r), err.message);
        free(copy);
    }
    free(bytes);
    pb_volume_free(&v);
}

/* The depth unit: a power of two u with max distance / u in (64, 128], so
 * mean squares stay <= 16384 in float16 at any scale from 1e-6 m to 1e30 m. */
static void depth_unit_bounds_the_reach(void)
{
    test_rng r = {23};
    uint32_t bad = 0;
    for (int i = 0; i < 20000; ++i) {
        float d = i < 64 ? ldexpf(1.f, i - 20) : (float)ldexp(rng_uniform(&r) + 0.5, (int)(rng_uniform(&r) * 120) - 20);
        float u = pb_volume_depth_unit(d);
        int e;
        float m = frexpf(u, &e);
        float q = d / u;
        uint16_t h2 = pb_half_from_float(q * q);
        if (m != 0.5f || !(q > 64.f && q <= 128.f) || (h2 & 0x7c00u) == 0x7c00u) {
            if (bad++ < 5)
                fprintf(stderr, "  max distance %g: unit %g, reach %g units\n", d, u, q);
        }
    }
    CHECKF(bad == 0, "%u of 20000 units wrong", bad);
    CHECK(pb_volume_depth_unit(0.f) == 1.f && pb_volume_depth_unit(NAN) == 1.f && pb_volume_depth_unit(INFINITY) == 1.f);
    CHECK(pb_volume_depth_unit(128.f) == 1.f && pb_volume_depth_unit(128.5f) == 2.f);
}

/* No file holds NaN or Inf: the writer refuses, naming the probe, and leaves
 * no file (nor a temporary) behind. */
static void writer_refuses_nonfinite_values(void)
{
    char dir[512], path[600];
    snprintf(dir, sizeof dir, "%s/nonfinite", temp_dir());
    mkdir(dir, 0755);
    snprintf(path, sizeof path, "%s/out.probes", dir);
    const char *what[] = {"position", "offset", "SH", "depth", "depth2", "std error", "origin", "unit"};
    for (int c = 0; c < 8; ++c) {
        pb_volume v;
        fill(&v, 3, 2, 2, 4);
        uint64_t tile = pb_volume_tile_halves(4);
        switch (c) {
        case 0: v.base[3 * 5 + 1] = NAN; break;
        case 1: v.offset[3 * 5 + 2] = INFINITY; break;
        case 2: v.sh[27 * 5 + 13] = -INFINITY; break;
        case 3: v.depth[tile * 5 + 7] = 0x7c00u; break;          /* +Inf half */
        case 4: v.depth[tile * 5 + tile - 1] = 0x7e00u; break;   /* NaN half */
        case 5: v.probe_std_error[5] = -0.5f; break;             /* only -1 means unknown */
        case 6: v.origin[1] = NAN; break;
        default: v.depth_unit = INFINITY; break;
        }
        pb_error err;
        pb_result r = pb_volume_write(path, &v, &err);
        int names_probe = c >= 6 ? strstr(err.message, "probe ") == NULL : strstr(err.message, "probe 5 ") != NULL;
        CHECKF(r == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, path) && names_probe, "%s: %s: %s", what[c],
               pb_result_name(r), err.message);
        CHECKF(count_files(dir) == 0, "%s: a file was left", what[c]);
        pb_volume_free(&v);
    }
}

/* A version-1 file (depth in metres, its squares +Inf past 256 m) reads as a
 * version-2 volume: finite texels in the depth unit, overflowed ones at the
 * max distance. */
/* v written to temp_dir()/name and read back as bytes (*size of them). */
static unsigned char *written_bytes(const pb_volume *v, const char *name, size_t *size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", temp_dir(), name);
    pb_error err;
    CHECK(pb_volume_write(path, v, &err) == PB_OK);
    *size = (size_t)pb_volume_file_bytes(v);
    unsigned char *b = malloc(*size);
    FILE *f = fopen(path, "rb");
    CHECK(f && fread(b, 1, *size, f) == *size);
    if (f)
        fclose(f);
    return b;
}

/* A version-3 file's bytes as version 2 wrote them: no accounting section
 * (the last one) and no offset for it. Returns the version-2 size. */
static size_t strip_to_version2(unsigned char *b)
{
    uint64_t at;
    memcpy(&at, b + 392, 8);
    memset(b + 392, 0, 8);
    uint32_t two = 2;
    memcpy(b + 8, &two, 4);
    return (size_t)at; /* the section starts at the aligned end of the depth atlas, which ends version 2's file */
}

static void version2_files_read(void)
{
    pb_volume v, w;
    fill(&v, 3, 2, 1, 4);
    pb_error err;
    size_t size;
    unsigned char *b = written_bytes(&v, "v3.probes", &size);
    size_t v2 = strip_to_version2(b);
    CHECK(v2 < size && size - v2 >= 6 * 8);
    const char *p2 = write_file("version2.probes", b, v2);
    CHECKF(pb_volume_read(p2, &w, &err) == PB_OK, "%s", err.message);
    CHECK(w.file_version == 2);
    uint32_t unknown = 0, paths_ok = 0;
    for (uint32_t i = 0; i < w.probe_count; ++i) {
        unknown += w.probe_std_error[i] == PB_STD_ERROR_UNKNOWN;
        paths_ok += w.probe_paths[i] == v.settings.passes * v.settings.rays_per_probe; /* what every probe got */
    }
    CHECK(unknown == w.probe_count && paths_ok == w.probe_count);
    CHECK(memcmp(w.sh, v.sh, 6 * 27 * 4) == 0 && memcmp(w.depth, v.depth, 6 * pb_volume_tile_halves(4) * 2) == 0);
    pb_volume_free(&w);
    /* a version-2 file with the version-3 section's bytes after it is not one */
    const char *p3 = write_file("version2-long.probes", b, size);
    CHECK(pb_volume_read(p3, &w, &err) == PB_ERROR_PARSE && strstr(err.message, "header describes"));
    free(b);
    pb_volume_free(&v);
}

static void version1_files_convert(void)
{
    pb_volume v, w;
    fill(&v, 2, 2, 1, 4); /* max distance 64 m */
    char path[512];
    pb_error err;
    size_t size;
    unsigned char *b = written_bytes(&v, "v1.probes", &size);
    size = strip_to_version2(b);
    uint32_t one = 1, zero = 0;
    memcpy(b + 8, &one, 4);   /* version 1 */
    memcpy(b + 128, &one, 4); /* depth format 1: metres */
    memcpy(b + 180, &zero, 4);
    uint64_t depth_at;
    memcpy(&depth_at, b + 168, 8);
    uint64_t texels = 4 * pb_volume_tile_halves(4) / 2;
    for (uint64_t t = 0; t < texels; ++t) {
        /* texel 0: 10 m (100 m^2); 1: 300 m whose square overflowed; 2: NaN; others 40 m */
        uint16_t m1 = pb_half_from_float(t == 0 ? 10.f : t == 1 ? 300.f : 40.f);
        uint16_t m2 = t == 0 ? pb_half_from_float(100.f) : t == 1 ? 0x7c00u : pb_half_from_float(1600.f);
        if (t == 2)
            m1 = m2 = 0x7e00u;
        memcpy(b + depth_at + 4 * t, &m1, 2);
        memcpy(b + depth_at + 4 * t + 2, &m2, 2);
    }
    const char *p1 = write_file("version1.probes", b, size);
    CHECKF(pb_volume_read(p1, &w, &err) == PB_OK, "%s", err.message);
    CHECK(w.depth_unit == 0.5f);
    uint32_t nonfinite = 0;
    for (uint64_t i = 0; i < 2 * texels; ++i)
        nonfinite += (w.depth[i] & 0x7c00u) == 0x7c00u;
    CHECKF(nonfinite == 0, "%u non-finite halves after conversion", nonfinite);
    CHECK(pb_half_to_float(w.depth[0]) == 20.f && pb_half_to_float(w.depth[1]) == 400.f);
    CHECK(pb_half_to_float(w.depth[2]) == 128.f && pb_half_to_float(w.depth[3]) == 16384.f); /* clamped to 64 m */
    CHECK(pb_half_to_float(w.depth[4]) == 128.f && pb_half_to_float(w.depth[5]) == 16384.f); /* NaN: likewise */
    CHECK(pb_half_to_float(w.depth[6]) == 80.f && pb_half_to_float(w.depth[7]) == 6400.f);
    CHECK(memcmp(w.sh, v.sh, 4 * 27 * 4) == 0);
    /* and writes back as the current version with finite depth */
    snprintf(path, sizeof path, "%s/v1-rewritten.probes", temp_dir());
    CHECK(pb_volume_write(path, &w, &err) == PB_OK);
    free(b);
    pb_volume_free(&w);
    pb_volume_free(&v);
}

/* ------------------------------------------------------------ output rules (issue 10) */

static uint64_t g_fifo_read;

static void *drain_fifo(void *path)
{
    int fd = open(path, O_RDONLY);
    char buf[65536];
    ssize_t n;
    while (fd >= 0 && (n = read(fd, buf, sizeof buf)) > 0)
        g_fifo_read += (uint64_t)n;
    if (fd >= 0)
        close(fd);
    return NULL;
}

static mode_t mode_of(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0 ? st.st_mode : 0;
}

/* Devices and FIFOs are written into, never renamed over; directories and
 * sockets refused; symlinks written through; modes follow the umask or the
 * replaced file; a cancelled write replaces nothing and leaves no temporary.
 * Device nodes are made here with mknod (as root), never the machine's /dev. */
static void outputs_never_replace_what_they_are_not(void)
{
    pb_volume v;
    fill(&v, 2, 2, 2, 4);
    uint64_t bytes = pb_volume_file_bytes(&v);
    char dir[512], p[700], q[700];
    snprintf(dir, sizeof dir, "%s/outputs", temp_dir());
    mkdir(dir, 0755);
    pb_error err;
    if (geteuid() == 0) {
        snprintf(p, sizeof p, "%s/null", dir);
        CHECK(mknod(p, S_IFCHR | 0666, makedev(1, 3)) == 0);
        CHECKF(pb_volume_write(p, &v, &err) == PB_OK, "%s", err.message);
        CHECK(S_ISCHR(mode_of(p)));
        snprintf(q, sizeof q, "%s/full", dir);
        CHECK(mknod(q, S_IFCHR | 0666, makedev(1, 7)) == 0);
        pb_result r = pb_volume_write(q, &v, &err);
        CHECKF(r == PB_ERROR_IO && strstr(err.message, q) && strstr(err.message, "No space left on device"), "%s",
               err.message);
        CHECK(S_ISCHR(mode_of(q)));
        unlink(p), unlink(q);
    } else {
        fprintf(stderr, "  not root: device nodes not made (FIFO, directory, socket, links and modes still run)\n");
    }
    /* a FIFO with a reader gets every byte, and stays a FIFO */
    snprintf(p, sizeof p, "%s/pipe", dir);
    CHECK(mkfifo(p, 0644) == 0);
    pthread_t reader;
    g_fifo_read = 0;
    pthread_create(&reader, NULL, drain_fifo, p);
    CHECKF(pb_volume_write(p, &v, &err) == PB_OK, "%s", err.message);
    pthread_join(reader, NULL);
    CHECK(g_fifo_read == bytes && S_ISFIFO(mode_of(p)));
    unlink(p);
    /* a directory and a socket are errors */
    snprintf(p, sizeof p, "%s/sub", dir);
    mkdir(p, 0755);
    CHECK(pb_volume_write(p, &v, &err) == PB_ERROR_IO && strstr(err.message, "is a directory"));
    CHECK(pb_output_check(p, NULL, 0, &err) == PB_ERROR_IO && strstr(err.message, "is a directory"));
    struct sockaddr_un sa = {.sun_family = AF_UNIX};
    char sp[700];
    snprintf(sp, sizeof sp, "%s/sock", dir);
    int fits = strlen(sp) < sizeof sa.sun_path;
    if (fits)
        memcpy(sa.sun_path, sp, strlen(sp) + 1);
    int sfd = socket(AF_UNIX, SOCK_STREAM, 0);
    if (sfd >= 0 && fits && bind(sfd, (struct sockaddr *)&sa, sizeof sa) == 0) {
        CHECK(pb_volume_write(sa.sun_path, &v, &err) == PB_ERROR_IO && strstr(err.message, "socket"));
        CHECK(pb_output_check(sa.sun_path, NULL, 0, &err) == PB_ERROR_IO && strstr(err.message, "socket"));
        unlink(sa.sun_path);
    }
    if (sfd >= 0)
        close(sfd);
    /* modes: a new file follows the umask, a replaced one keeps its mode */
    snprintf(p, sizeof p, "%s/new.probes", dir);
    mode_t old = umask(022);
    CHECK(pb_volume_write(p, &v, &err) == PB_OK && (mode_of(p) & 0777) == 0644);
    unlink(p);
    umask(077);
    CHECK(pb_volume_write(p, &v, &err) == PB_OK && (mode_of(p) & 0777) == 0600);
    umask(old);
    chmod(p, 0640);
    CHECK(pb_volume_write(p, &v, &err) == PB_OK && (mode_of(p) & 0777) == 0640);
    /* a symlink is written through: existing target and a target to be */
    snprintf(q, sizeof q, "%s/link.probes", dir);
    CHECK(symlink("new.probes", q) == 0);
    CHECK(pb_volume_write(q, &v, &err) == PB_OK && S_ISLNK(mode_of(q)) && S_ISREG(mode_of(p)));
    unlink(q);
    CHECK(symlink("sub/later.probes", q) == 0);
    CHECKF(pb_volume_write(q, &v, &err) == PB_OK, "%s", err.message);
    snprintf(p, sizeof p, "%s/sub/later.probes", dir);
    CHECK(S_ISLNK(mode_of(q)) && S_ISREG(mode_of(p)));
    /* the same file as an input: by name, hard link or symlink */
    char hard[700];
    snprintf(hard, sizeof hard, "%s/hard.probes", dir);
    CHECK(link(p, hard) == 0);
    const char *inputs[2] = {NULL, p};
    CHECK(pb_output_check(p, inputs, 2, &err) == PB_ERROR_INVALID_ARGUMENT && strstr(err.message, "same file"));
    CHECK(pb_output_check(hard, inputs, 2, &err) == PB_ERROR_INVALID_ARGUMENT);
    CHECK(pb_output_check(q, inputs, 2, &err) == PB_ERROR_INVALID_ARGUMENT);
    snprintf(q, sizeof q, "%s/missing/x.probes", dir);
    CHECK(pb_output_check(q, NULL, 0, &err) == PB_ERROR_IO && strstr(err.message, "No such file or directory"));
    snprintf(q, sizeof q, "%s/fresh.probes", dir);
    CHECK(pb_output_check(q, inputs, 2, &err) == PB_OK && mode_of(q) == 0); /* the check leaves nothing */
    CHECK(pb_output_check("-", inputs, 2, &err) == PB_OK);
    pb_volume_free(&v);
}

static int cancel_on_call(void *user)
{
    int *calls = user;
    return --*calls <= 0;
}

/* A write cancelled at any point (first chunk, before the rename) leaves
 * the previous file as it was and no temporary beside it. */
/* For the writes that must replace nothing: a scratch folder `name` (dir)
 * holding p = keep.probes, a 4-probe volume v, and `big`, 2048 probes
 * (~2.9 MB: several pieces of the writer) to fail writing over it. */
static void replace_setup(const char *name, char dir[512], char p[700], pb_volume *v, pb_volume *big)
{
    fill(v, 2, 2, 1, 4);
    fill(big, 16, 16, 8, 16);
    snprintf(dir, 512, "%s/%s", temp_dir(), name);
    mkdir(dir, 0755);
    snprintf(p, 700, "%s/keep.probes", dir);
    pb_error err;
    CHECK(pb_volume_write(p, v, &err) == PB_OK);
}

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* One exported KTX2 file: its texels (a pointer into *bytes, which the
 * caller frees) after checking the identifier, format, size and level
 * index against the file's length. NULL if any disagree. */
static const unsigned char *ktx2_texels(const char *dir, const char *name, uint32_t format, uint32_t texel_bytes,
                                        uint32_t *w, uint32_t *h, unsigned char **bytes)
{
    char path[700];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    uint64_t size = 0;
    pb_error err;
    *bytes = NULL;
    if (pb_input_read(path, 1u << 30, bytes, &size, &err) != PB_OK || size < 104)
        return NULL;
    const unsigned char *b = *bytes;
    *w = le32(b + 20), *h = le32(b + 24);
    uint64_t at = le32(b + 80), length = le32(b + 88);
    int ok = b[0] == 0xAB && !memcmp(b + 1, "KTX 20", 6) && le32(b + 12) == format &&
             length == (uint64_t)*w * *h * texel_bytes && at % texel_bytes == 0 && at + length == size;
    return ok ? b + at : NULL;
}

/* The texture export's files hold the volume's values where docs/format.md
 * ("Texture contract") puts them: texel p of pb_probes is probe p's
 * position and flags, texels 7p..7p+6 of pb_sh its 27 coefficients and a
 * zero, probe p's depth tile (border included) at tile (p % T, p / T) of
 * pb_depth, zeros past the last probe. The files are made a 1 MiB band of
 * rows at a time: 10,000 probes make pb_sh two bands and pb_depth 13. */
static void exported_textures_hold_the_volume(void)
{
    pb_volume v;
    fill(&v, 100, 10, 10, 16);
    char dir[512];
    snprintf(dir, sizeof dir, "%s/textures", temp_dir());
    pb_error err;
    CHECKF(pb_volume_export_textures(&v, dir, &err) == PB_OK, "%s", err.message);
    unsigned char *pb = NULL, *sb = NULL, *db = NULL;
    uint32_t pw, ph, sw, shh, dw, dh, tile = v.octmap_res + 2, bad = 0;
    const unsigned char *pt = ktx2_texels(dir, "probes.ktx2", 109, 16, &pw, &ph, &pb);
    const unsigned char *st = ktx2_texels(dir, "sh.ktx2", 109, 16, &sw, &shh, &sb);
    const unsigned char *dt = ktx2_texels(dir, "depth.ktx2", 83, 4, &dw, &dh, &db);
    CHECK(pt && st && dt && pw == sw && ph > 1 && shh > 1);
    if (pt && st && dt) {
        uint32_t T = dw / tile;
        for (uint32_t p = 0; p < pw * ph; ++p)
            for (int k = 0; k < 4; ++k) {
                float want = p >= v.probe_count ? 0.f
                             : k < 3        ? v.base[3 * p + k] + v.offset[3 * p + k]
                                            : (float)v.probe_flags[p];
                uint32_t got = le32(pt + 16 * p + 4 * k), w;
                memcpy(&w, &want, 4);
                bad += got != w;
            }
        for (uint32_t c = 0; c < 4 * sw * shh; ++c) {
            uint32_t p = c / 28, k = c % 28, w;
            float want = p < v.probe_count && k < 27 ? v.sh[27 * p + k] : 0.f;
            memcpy(&w, &want, 4);
            bad += le32(st + 4 * c) != w;
        }
        for (uint32_t y = 0; y < dh; ++y)
            for (uint32_t x = 0; x < dw; ++x) {
                uint32_t p = y / tile * T + x / tile;
                for (int k = 0; k < 2; ++k) {
                    uint16_t want = p < v.probe_count
                                        ? v.depth[pb_volume_tile_halves(v.octmap_res) * p +
                                                  2 * ((y % tile) * tile + x % tile) + k]
                                        : 0u;
                    const unsigned char *q = dt + 4 * ((size_t)y * dw + x) + 2 * k;
                    bad += (uint16_t)(q[0] | q[1] << 8) != want;
                }
            }
        CHECK(T * tile == dw && (dh / tile) * T >= v.probe_count);
    }
    CHECKF(bad == 0, "%u texel components differ from the volume", bad);
    free(pb), free(sb), free(db);
    pb_volume_free(&v);
}

/* A write the file system stops halfway (here the file size limit, EFBIG;
 * a full disk is ENOSPC) is an I/O error naming the path, and what it was
 * replacing is untouched with no temporary file beside it: the file is
 * written in pieces as it is encoded, never whole from memory. */
static void write_failing_midway_replaces_nothing(void)
{
    pb_volume v, big, w;
    char dir[512], p[700];
    replace_setup("midway", dir, p, &v, &big);
    pb_error err;
    struct rlimit old, small;
    CHECK(getrlimit(RLIMIT_FSIZE, &old) == 0);
    small = old;
    small.rlim_cur = 1u << 20;
    void (*was)(int) = signal(SIGXFSZ, SIG_IGN); /* else the kernel ends the process */
    CHECK(setrlimit(RLIMIT_FSIZE, &small) == 0);
    pb_result r = pb_volume_write(p, &big, &err);
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, was);
    CHECKF(r == PB_ERROR_IO && strstr(err.message, p) && strstr(err.message, "write failed"), "%s: %s",
           pb_result_name(r), err.message);
    CHECK(count_files(dir) == 1);
    CHECK(pb_volume_read(p, &w, &err) == PB_OK && w.probe_count == 4);
    pb_volume_free(&w);
    pb_volume_free(&big);
    pb_volume_free(&v);
}

static void cancelled_write_replaces_nothing(void)
{
    pb_volume v, big, w;
    char dir[512], p[700];
    replace_setup("cancel", dir, p, &v, &big);
    pb_error err;
    for (int when = 1; when <= 4; ++when) {
        int calls = when;
        pb_result r = pb_volume_write_ex(p, &big, cancel_on_call, &calls, &err);
        CHECKF(r == PB_ERROR_CANCELLED, "cancel at call %d: %s", when, pb_result_name(r));
        CHECK(count_files(dir) == 1);
        CHECK(pb_volume_read(p, &w, &err) == PB_OK && w.probe_count == 4);
        pb_volume_free(&w);
    }
    pb_volume_free(&big);
    pb_volume_free(&v);
}

/* The debug views of a sparse volume mark levels: the gap pixel above and
 * left of each tile is its finest level's colour (level 0 blue, 1 green),
 * full or half bright by its first brick's parity (a real two-level file,
 * the fuzz seed tests/fuzz/volume_corpus/seed-sparse2). */
static void sparse_atlas_marks_levels(void)
{
    pb_volume v;
    pb_error err;
    if (pb_volume_read(source_path("tests/fuzz/volume_corpus/seed-sparse2"), &v, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
        return;
    }
    uint32_t P = v.probe_count, level[1024] = {0}, first[1024];
    CHECK(P <= 1024);
    for (uint32_t p = 0; p < P && p < 1024; ++p)
        first[p] = UINT32_MAX;
    for (uint32_t b = 0; b < v.sparse->brick_count; ++b)
        for (uint32_t i = 0; i < 64; ++i) {
            uint32_t p = v.sparse->brick_probes[64 * b + i];
            if (p >= 1024)
                continue;
            if (v.sparse->bricks[b].level > level[p])
                level[p] = v.sparse->bricks[b].level;
            if (first[p] == UINT32_MAX)
                first[p] = b;
        }
    const unsigned char want[2][3] = {{40, 90, 255}, {40, 220, 60}};
    for (int view = 0; view < 2; ++view) {
        unsigned char *img = NULL;
        uint32_t w = 0, h = 0, columns, tile = view == 0 ? v.octmap_res + 2 : 16, wrong = 0, per_level[2] = {0, 0};
        pb_result r = view == 0 ? pb_volume_depth_atlas(&v, &img, &w, &h, &err)
                                : pb_volume_sh_atlas(&v, tile, &img, &w, &h, &err);
        CHECKF(r == PB_OK, "%s", err.message);
        pb_atlas_layout(P, tile, &columns, &w, &h);
        for (uint32_t p = 0; r == PB_OK && p < P && p < 1024; ++p) {
            uint32_t x = (p % columns) * (tile + 1), y = (p / columns) * (tile + 1); /* the gap corner */
            const unsigned char *px = img + 3 * ((size_t)y * w + x), *c = want[level[p] ? 1 : 0];
            int dim = first[p] % 2;
            for (int k = 0; k < 3; ++k)
                wrong += px[k] != (dim ? c[k] / 2 : c[k]);
            per_level[level[p] ? 1 : 0]++;
        }
        fprintf(stderr, "  %s: %u tiles of level 0, %u of level 1; %u wrong frame channels\n",
                view == 0 ? "depth atlas" : "SH view", per_level[0], per_level[1], wrong);
        CHECK(wrong == 0 && per_level[0] > 0 && per_level[1] > 0);
        free(img);
    }
    pb_volume_free(&v);
}

/* The mapping of /proc/self/smaps that holds address `at`: 1 if advised
 * for huge pages ("hg"), 0 if not, -1 if not found; *lo, *hi its bounds. */
static int huge_advice_at(FILE *f, uintptr_t at, uintptr_t *lo, uintptr_t *hi)
{
    char line[512];
    int inside = 0, advised = -1;
    rewind(f);
    while (fgets(line, sizeof line, f)) {
        unsigned long a, b;
        char *dash = strchr(line, '-'), *space = strchr(line, ' ');
        if (dash && space && dash < space && sscanf(line, "%lx-%lx ", &a, &b) == 2) {
            inside = at >= a && at < b;
            if (inside)
                *lo = a, *hi = b;
        } else if (inside && !strncmp(line, "VmFlags:", 8)) {
            advised = strstr(line, " hg") != NULL;
        }
    }
    return advised;
}

/* Large arrays come zeroed (a volume's) and, on Linux, advised for huge
 * pages in one piece (pb_calloc_large, pb_realloc_large): the kernel's map
 * of this process shows the advice ("hg") on the mapping of the volume's
 * depth tiles, and on an array grown by realloc from 16 to 64 MiB, whose
 * mapping still holds the whole array (advice on part of a mapping splits
 * it, and glibc's realloc then copies instead of moving it). */
static void large_arrays_ask_for_huge_pages(void)
{
    pb_volume v;
    memset(&v, 0, sizeof v);
    v.probe_count = 20000, v.octmap_res = 16; /* 25 MiB of depth tiles */
    v.settings.max_distance = 10.f;
    pb_error err;
    CHECK(pb_volume_alloc(&v, &err) == PB_OK);
    size_t halves = (size_t)v.probe_count * pb_volume_tile_halves(16), nonzero = 0;
    for (size_t i = 0; v.depth && i < halves; i += 997)
        nonzero += v.depth[i] != 0;
    CHECK(v.depth && nonzero == 0);
    size_t bytes = (size_t)16 << 20;
    uint32_t *grown = pb_malloc_large(bytes), kept = 1;
    for (int step = 0; grown && step < 2; ++step) {
        for (size_t i = 0; i < bytes / 4; i += 1024)
            grown[i] = (uint32_t)i;
        uint32_t *g = pb_realloc_large(grown, 2 * bytes);
        if (!g)
            break;
        grown = g;
        for (size_t i = 0; i < bytes / 4; i += 1024)
            kept &= grown[i] == (uint32_t)i;
        bytes *= 2;
    }
    FILE *f = fopen("/proc/self/smaps", "r");
    if (!f) {
        fprintf(stderr, "  skipped the advice: no /proc/self/smaps\n");
    } else {
        uintptr_t lo = 0, hi = 0, glo = 0, ghi = 0;
        int depth = huge_advice_at(f, (uintptr_t)v.depth + ((uintptr_t)4 << 20), &lo, &hi);
        int mapped = huge_advice_at(f, (uintptr_t)grown, &glo, &ghi);
        int whole = glo <= (uintptr_t)grown && ghi >= (uintptr_t)grown + bytes;
        fclose(f);
        fprintf(stderr, "  the depth tiles' mapping %s; the grown array's %s, %s\n",
                depth < 0 ? "NOT FOUND" : depth ? "is advised for huge pages" : "is NOT advised",
                mapped < 0 ? "NOT FOUND" : mapped ? "advised" : "NOT advised",
                whole ? "in one piece" : "SPLIT");
        CHECK(depth == 1 && mapped == 1 && whole);
    }
    CHECK(grown && kept && bytes == (size_t)64 << 20);
    free(grown);
    pb_volume_free(&v);
}

/* pb_write_png (zlib, filters chosen per row) read back by another decoder
 * (stb_image): every byte of images whose rows favour each filter (flat,
 * ramps across and down, noise), at widths of 1, 3 and 97 pixels. */
static void png_reads_back(void)
{
    static const uint32_t sizes[4][2] = {{1, 1}, {3, 5}, {97, 4}, {64, 64}};
    test_rng r = {5};
    for (int s = 0; s < 4; ++s) {
        uint32_t w = sizes[s][0], h = sizes[s][1];
        unsigned char *px = malloc((size_t)w * h * 3);
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    uint32_t kind = (y / 8 + (uint32_t)c) % 4; /* flat, across, down, noise */
                    uint32_t v = kind == 0 ? 200u : kind == 1 ? 3u * x : kind == 2 ? 5u * y
                                                                     : (uint32_t)(rng_uniform(&r) * 256.0);
                    px[3 * ((size_t)y * w + x) + c] = (unsigned char)(v & 255u);
                }
        char path[512];
        snprintf(path, sizeof path, "%s/img%d.png", temp_dir(), s);
        pb_error err;
        CHECKF(pb_write_png(path, px, w, h, &err) == PB_OK, "%s", err.message);
        int rw = 0, rh = 0, rc = 0;
        unsigned char *back = stbi_load(path, &rw, &rh, &rc, 3);
        CHECKF(back && (uint32_t)rw == w && (uint32_t)rh == h && rc == 3 && !memcmp(back, px, (size_t)w * h * 3),
               "%ux%u: %s", w, h, back ? "other pixels" : stbi_failure_reason());
        stbi_image_free(back);
        free(px);
    }
}

int main(void)
{
    RUN(half_round_trip_exhaustive);
    RUN(half_rounding_matches_reference);
    RUN(half_pairs_match_one_at_a_time);
    RUN(file_round_trip);
    RUN(failed_write_leaves_nothing);
    RUN(malformed_files_get_clear_errors);
    RUN(depth_unit_bounds_the_reach);
    RUN(writer_refuses_nonfinite_values);
    RUN(version1_files_convert);
    RUN(version2_files_read);
    RUN(outputs_never_replace_what_they_are_not);
    RUN(exported_textures_hold_the_volume);
    RUN(cancelled_write_replaces_nothing);
    RUN(write_failing_midway_replaces_nothing);
    RUN(sparse_lookup_finds_the_finest_brick);
    RUN(sparse_files_round_trip_and_refuse_damage);
    RUN(sparse_atlas_marks_levels);
    RUN(large_arrays_ask_for_huge_pages);
    RUN(png_reads_back);
    return test_summary();
}
