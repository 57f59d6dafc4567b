/* Probe grids and their ray sets: spherical Fibonacci directions (Keinert et
 * al. 2015) rotated per probe by a uniformly random rotation (Shoemake's
 * quaternion from three uniforms). Randomness keys only on (seed, probe,
 * stream), so a probe's rays never depend on which other probes are traced.
 *
 * Order: consecutive Fibonacci indices lie ~137 degrees apart in azimuth, so
 * a SIMD group or GPU warp tracing them diverges as much as it can. Each
 * probe's directions are emitted in Morton order of their octahedral
 * coordinates instead: the same set, with neighbours traced together. */
#include "probebake/trace.h"

#include <math.h>
#include <stdlib.h>

typedef struct keyed {
    uint32_t key, index;
} keyed;

static int compare_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key ? 1 : (x->index > y->index) - (x->index < y->index);
}

static uint32_t spread_bits(uint32_t v) /* 16 bits -> even bits of 32 */
{
    v &= 0xffffu;
    v = (v | (v << 8)) & 0x00ff00ffu;
    v = (v | (v << 4)) & 0x0f0f0f0fu;
    v = (v | (v << 2)) & 0x33333333u;
    v = (v | (v << 1)) & 0x55555555u;
    return v;
}

/* Morton key of a unit direction's octahedral coordinates. */
static uint32_t direction_key(const float d[3])
{
    float l1 = fabsf(d[0]) + fabsf(d[1]) + fabsf(d[2]);
    float u = d[0] / l1, v = d[1] / l1;
    if (d[2] < 0.f) {
        float pu = (1.f - fabsf(v)) * (u >= 0.f ? 1.f : -1.f);
        float pv = (1.f - fabsf(u)) * (v >= 0.f ? 1.f : -1.f);
        u = pu, v = pv;
    }
    uint32_t qu = (uint32_t)fminf(65535.f, fmaxf(0.f, (u * 0.5f + 0.5f) * 65535.f));
    uint32_t qv = (uint32_t)fminf(65535.f, fmaxf(0.f, (v * 0.5f + 0.5f) * 65535.f));
    return spread_bits(qu) | (spread_bits(qv) << 1);
}

uint32_t pb_hash32(uint32_t x)
{
    uint32_t state = x * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

float pb_random01(uint32_t seed, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t h = pb_hash32(seed ^ pb_hash32(a ^ pb_hash32(b ^ pb_hash32(c))));
    return (float)(h >> 8) * (1.0f / 16777216.0f);
}

void pb_probe_grid_fit(const float lo[3], const float hi[3], uint32_t target_probes, pb_probe_grid *g)
{
    double ext[3], vol = 1.0;
    int dims = 0;
    for (int k = 0; k < 3; ++k) {
        ext[k] = hi[k] > lo[k] ? (double)hi[k] - lo[k] : 0.0;
        if (ext[k] > 0) {
            vol *= ext[k];
            ++dims;
        }
    }
    if (target_probes < 1)
        target_probes = 1;
    double s = dims ? pow(vol / target_probes, 1.0 / dims) : 1.0;
    for (int k = 0; k < 3; ++k) {
        uint32_t n = ext[k] > 0 ? (uint32_t)fmax(1.0, floor(ext[k] / s + 0.5)) : 1u;
        g->counts[k] = n;
        g->spacing[k] = ext[k] > 0 ? (float)(ext[k] / n) : 0.f;
        g->origin[k] = (float)(lo[k] + 0.5 * g->spacing[k]);
        if (!(ext[k] > 0))
            g->origin[k] = 0.5f * (lo[k] + hi[k]);
    }
}

uint32_t pb_probe_grid_count(const pb_probe_grid *g)
{
    return g->counts[0] * g->counts[1] * g->counts[2];
}

pb_result pb_sf_directions(uint32_t n, float *out4)
{
    const float golden = 1.61803398874989485f;
    const float two_pi = 6.28318530717958648f;
    float *dirs = malloc((size_t)n * 3 * sizeof(float));
    keyed *order = malloc((size_t)n * sizeof(keyed));
    if (!dirs || !order) {
        free(dirs), free(order);
        return PB_ERROR_OUT_OF_HOST_MEMORY;
    }
    for (uint32_t r = 0; r < n; ++r) {
        float z = 1.f - (2.f * (float)r + 1.f) / (float)n;
        float rad = sqrtf(fmaxf(0.f, 1.f - z * z));
        float phi = two_pi * ((float)r / golden - floorf((float)r / golden));
        float *d = dirs + 3 * r;
        d[0] = rad * cosf(phi), d[1] = rad * sinf(phi), d[2] = z;
        order[r].key = direction_key(d);
        order[r].index = r;
    }
    qsort(order, n, sizeof *order, compare_keyed);
    for (uint32_t r = 0; r < n; ++r) {
        const float *d = dirs + 3 * order[r].index;
        out4[4 * r] = d[0], out4[4 * r + 1] = d[1], out4[4 * r + 2] = d[2], out4[4 * r + 3] = 0.f;
    }
    free(dirs);
    free(order);
    return PB_OK;
}

void pb_random_rotation(uint32_t seed, uint32_t probe, uint32_t pass, float m[9])
{
    const float two_pi = 6.28318530717958648f;
    float u1 = pb_random01(seed, probe, pass, 0), u2 = pb_random01(seed, probe, pass, 1),
          u3 = pb_random01(seed, probe, pass, 2);
    float a = sqrtf(1.f - u1), b = sqrtf(u1);
    float qx = a * sinf(two_pi * u2), qy = a * cosf(two_pi * u2), qz = b * sinf(two_pi * u3), qw = b * cosf(two_pi * u3);
    m[0] = 1 - 2 * (qy * qy + qz * qz), m[1] = 2 * (qx * qy - qz * qw), m[2] = 2 * (qx * qz + qy * qw);
    m[3] = 2 * (qx * qy + qz * qw), m[4] = 1 - 2 * (qx * qx + qz * qz), m[5] = 2 * (qy * qz - qx * qw);
    m[6] = 2 * (qx * qz - qy * qw), m[7] = 2 * (qy * qz + qx * qw), m[8] = 1 - 2 * (qx * qx + qy * qy);
}

pb_result pb_probe_rays(const pb_probe_grid *g, uint32_t first, uint32_t count, uint32_t per_probe, uint32_t seed,
                        pb_ray *out)
{
    float *dirs = malloc((size_t)per_probe * 4 * sizeof(float));
    if (!dirs || pb_sf_directions(per_probe, dirs) != PB_OK) {
        free(dirs);
        return PB_ERROR_OUT_OF_HOST_MEMORY;
    }
    for (uint32_t p = first; p < first + count; ++p) {
        uint32_t i = p % g->counts[0], j = (p / g->counts[0]) % g->counts[1], k = p / (g->counts[0] * g->counts[1]);
        float pos[3] = {g->origin[0] + (float)i * g->spacing[0], g->origin[1] + (float)j * g->spacing[1],
                        g->origin[2] + (float)k * g->spacing[2]};
        float m[9];
        pb_random_rotation(seed, p, 0, m);
        for (uint32_t r = 0; r < per_probe; ++r) {
            const float *d = dirs + 4 * r;
            pb_ray *ray = &out[(size_t)(p - first) * per_probe + r];
            for (int c = 0; c < 3; ++c) {
                ray->origin[c] = pos[c];
                ray->direction[c] = (m[3 * c] * d[0] + m[3 * c + 1] * d[1]) + m[3 * c + 2] * d[2];
            }
            ray->tmin = 0.f;
            ray->tmax = INFINITY;
        }
    }
    free(dirs);
    return PB_OK;
}
