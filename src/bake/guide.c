/* Path guiding: the cache learned from surface-sampled training paths
 * (guide.h). */
#include "bake/guide.h"
#include "bake/alias.h"
#include "common/common.h"
#include "probebake/trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI_F 3.14159265358979324f
#define PB_GUIDE_PASS 0xC0000000u  /* the training paths' pass number in the RNG key */

void pb_equal_area_decode(float s, float t, float dir[3])
{
    float u = 2.f * s - 1.f, v = 2.f * t - 1.f, au = fabsf(u), av = fabsf(v);
    float d = 1.f - (au + av), r = 1.f - fabsf(d);
    float phi = (r == 0.f ? 1.f : (av - au) / r + 1.f) * (PI_F / 4.f);
    float z = d < 0.f ? -(1.f - r * r) : 1.f - r * r;
    float sr = r * sqrtf(fmaxf(0.f, 2.f - r * r));
    dir[0] = (u < 0.f ? -1.f : 1.f) * sr * cosf(phi);
    dir[1] = (v < 0.f ? -1.f : 1.f) * sr * sinf(phi);
    dir[2] = z;
}

void pb_equal_area_encode(const float dir[3], float *s, float *t)
{
    float ax = fabsf(dir[0]), ay = fabsf(dir[1]), az = fabsf(dir[2]);
    float r = sqrtf(fmaxf(0.f, 1.f - az));
    float phi = ax == 0.f && ay == 0.f ? 0.f : atan2f(ay, ax);
    float v = phi * (2.f / PI_F) * r, u = r - v;
    if (dir[2] < 0.f) {
        float tu = u;
        u = 1.f - v, v = 1.f - tu;
    }
    u = dir[0] < 0.f ? -u : u;
    v = dir[1] < 0.f ? -v : v;
    *s = 0.5f * (u + 1.f), *t = 0.5f * (v + 1.f);
}

static uint32_t bin_of(const float dir[3])
{
    float s, t;
    pb_equal_area_encode(dir, &s, &t);
    uint32_t bx = (uint32_t)fminf(fmaxf(s * 8.f, 0.f), 7.f), by = (uint32_t)fminf(fmaxf(t * 8.f, 0.f), 7.f);
    return by * 8u + bx;
}

static uint32_t entry_index(const pb_guide *g, const float x[3], const float n[3])
{
    float ax = fabsf(n[0]), ay = fabsf(n[1]), az = fabsf(n[2]);
    uint32_t axis = ax >= ay && ax >= az ? 0u : (ay >= az ? 1u : 2u);
    uint32_t cls = 2u * axis + (n[axis] < 0.f ? 1u : 0u);
    return pb_cell_grid_index(&g->grid, x) * 6u + cls;
}

int32_t pb_guide_entry(const pb_guide *g, const float x[3], const float n[3])
{
    if (!g || !g->table)
        return -1;
    uint32_t slot = g->slot[entry_index(g, x, n)];
    return slot == ~0u ? -1 : (int32_t)slot;
}

void pb_guide_sample(const pb_guide *g, int32_t slot, float u1, float u2, float u3, float dir[3])
{
    const float *b = g->table + 4 * (size_t)slot * PB_GUIDE_BINS;
    float xb = u1 * (float)PB_GUIDE_BINS;
    uint32_t i = (uint32_t)xb < PB_GUIDE_BINS - 1u ? (uint32_t)xb : PB_GUIDE_BINS - 1u;
    uint32_t alias;
    memcpy(&alias, &b[4 * i + 1], 4);
    uint32_t bin = xb - (float)i < b[4 * i] ? i : alias;
    pb_equal_area_decode(((float)(bin % 8u) + u2) * 0.125f, ((float)(bin / 8u) + u3) * 0.125f, dir);
}

float pb_guide_pdf(const pb_guide *g, int32_t slot, const float dir[3])
{
    const float *b = g->table + 4 * (size_t)slot * PB_GUIDE_BINS;
    return b[4 * bin_of(dir) + 2] * ((float)PB_GUIDE_BINS / (4.f * PI_F));
}

typedef struct train_job {
    const pb_bake_pass *pass;
    pb_path_ctx path;
    const pb_surface_sampler *surface;
    uint32_t paths;
    const pb_guide *g;
    float *records;               /* 3 per path: entry (uint bits, ~0 none), bin (uint bits), luminance */
} train_job;

static void train_range(void *user, uint64_t begin, uint64_t end)
{
    train_job *j = user;
    const pb_scene *s = j->pass->scene;
    for (uint64_t i = begin; i < end; ++i) {
        float *rec = j->records + 3 * i;
        uint32_t none = ~0u;
        memcpy(&rec[0], &none, 4);
        uint32_t state = pb_rng_seed_cpu(j->pass->seed, (uint32_t)i, PB_GUIDE_PASS, 0u);
        float n[3], x[3];
        if (!pb_surface_point(s, j->surface, &state, x, n))
            continue;
        float dir[3];
        float u3 = pb_rng_next_cpu(&state), u4 = pb_rng_next_cpu(&state);
        pb_cosine_direction_cpu(n, u3, u4, dir);
        /* the bake path this stands for has reflected once already, at x;
         * emission and sky found straight along the training ray are left
         * out: next-event estimation brings those, and a guide drawn to a
         * small emitter only takes bounces from where they are needed (the
         * Cornell box: 0.74x the plain tracer's paths with it) */
        uint32_t rest = j->pass->bounces ? j->pass->bounces - 1u : 0u;
        pb_path_result r = pb_path_radiance_cpu(&j->path, x, dir, rest, 0, &state);
        uint32_t ue = entry_index(j->g, x, n), bin = bin_of(dir);
        float lum = pb_luminance(r.L);
        if (!isfinite(lum) || lum < 0.f)
            continue;
        memcpy(&rec[0], &ue, 4);
        memcpy(&rec[1], &bin, 4);
        rec[2] = lum;
    }
}

pb_result pb_guide_build(const pb_bake_pass *pass, uint32_t paths, pb_guide *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    const pb_scene *s = pass->scene;
    if (!paths || !s->triangle_count)
        return PB_OK; /* nothing learned: every bounce samples the cosine lobe */
    pb_surface_sampler surface;
    if (!pb_surface_sampler_init(s, &surface))
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for path guiding");
    /* the grid: cubes sized so that the surface in a cell gets about
     * PB_GUIDE_CELL_RECORDS training paths, at most 64 cells per axis */
    pb_cell_grid_fit(s, surface.area_total, PB_GUIDE_CELL_RECORDS, paths, &out->grid);
    out->entries = 6u * pb_cell_grid_cells(&out->grid);
    size_t bins = (size_t)out->entries * PB_GUIDE_BINS;
    out->slot = malloc(out->entries * sizeof(uint32_t));
    float *records = malloc((size_t)paths * 3 * sizeof(float));
    double *sum = calloc(bins, sizeof(double));
    uint32_t *count = calloc(bins, sizeof(uint32_t)), *per_entry = calloc(out->entries, sizeof(uint32_t));
    train_job j;
    memset(&j, 0, sizeof j);
    pb_result r = PB_OK;
    if (!out->slot || !records || !sum || !count || !per_entry ||
        !pb_path_ctx_init(&j.path, pass)) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for path guiding (%u entries)", out->entries);
        goto done;
    }
    memset(out->slot, 0xff, out->entries * sizeof(uint32_t));
    if (!(surface.area_total > 0.0))
        goto done; /* no area at all: nothing to learn */
    j.pass = pass, j.surface = &surface, j.paths = paths;
    j.g = out, j.records = records;
    pb_parallel_for(paths, 256, 0, train_range, &j);
    /* in path order, so the sums do not depend on the threads */
    for (uint32_t i = 0; i < paths; ++i) {
        uint32_t e, b;
        memcpy(&e, &records[3 * (size_t)i], 4);
        memcpy(&b, &records[3 * (size_t)i + 1], 4);
        if (e == ~0u)
            continue;
        sum[(size_t)e * PB_GUIDE_BINS + b] += records[3 * (size_t)i + 2];
        count[(size_t)e * PB_GUIDE_BINS + b]++;
        per_entry[e]++;
    }
    /* per learned entry: mean radiance per bin times the cosine to the entry's axis */
    uint32_t learnable = 0;
    for (uint32_t e = 0; e < out->entries; ++e)
        learnable += per_entry[e] >= PB_GUIDE_MIN_RECORDS;
    out->table = calloc((size_t)(learnable ? learnable : 1) * PB_GUIDE_BINS * 4, sizeof(float));
    if (!out->table) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for path guiding (%u entries)", learnable);
        goto done;
    }
    for (uint32_t e = 0; e < out->entries; ++e) {
        if (per_entry[e] < PB_GUIDE_MIN_RECORDS)
            continue;
        uint32_t cls = e % 6u, axis = cls / 2u;
        float sign = cls & 1u ? -1.f : 1.f;
        /* each bin's mean is shrunk toward the entry's (one pseudo-record of
         * it): a bin no path saw keeps the entry's average radiance rather
         * than none, so the guide never starves a direction it has not
         * explored (the cosine part of the mixture would then carry it at
         * 1 / (1 - share) times the weight: the closed box's worst probe
         * went from 2 % to 8 % without this) */
        double entry_sum = 0, w[PB_GUIDE_BINS], total = 0;
        for (uint32_t b = 0; b < PB_GUIDE_BINS; ++b)
            entry_sum += sum[(size_t)e * PB_GUIDE_BINS + b];
        double entry_mean = entry_sum / per_entry[e];
        for (uint32_t b = 0; b < PB_GUIDE_BINS; ++b) {
            size_t k = (size_t)e * PB_GUIDE_BINS + b;
            float d[3];
            pb_equal_area_decode(((float)(b % 8u) + 0.5f) * 0.125f, ((float)(b / 8u) + 0.5f) * 0.125f, d);
            double cosine = fmax(0.0, sign * d[axis]);
            w[b] = (sum[k] + entry_mean) / (count[k] + 1.0) * cosine;
            total += w[b];
        }
        if (!(total > 0.0) || !isfinite(total))
            continue;
        float kp[PB_GUIDE_BINS];
        uint32_t al[PB_GUIDE_BINS];
        int built = pb_alias_build(w, PB_GUIDE_BINS, kp, al);
        if (built < 0) {
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for path guiding");
            break;
        }
        if (!built)
            continue;
        float *tb = out->table + 4 * (size_t)out->learned * PB_GUIDE_BINS;
        for (uint32_t b = 0; b < PB_GUIDE_BINS; ++b) {
            tb[4 * b] = kp[b];
            memcpy(&tb[4 * b + 1], &al[b], 4);
            tb[4 * b + 2] = (float)(w[b] / total);
        }
        out->slot[e] = out->learned++;
    }
done:
    pb_path_ctx_free(&j.path);
    pb_surface_sampler_free(&surface);
    free(records), free(sum), free(count), free(per_entry);
    if (r != PB_OK)
        pb_guide_free(out);
    return r;
}

void pb_guide_free(pb_guide *g)
{
    free(g->table), free(g->slot);
    memset(g, 0, sizeof *g);
}
