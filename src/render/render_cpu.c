/* CPU reference of render.comp, step for step (pb_path_radiance_cpu and
 * pb_sample_cpu are the C references of the code it includes). */
#include "bake/path_cpu.h"
#include "bake/shading.h"
#include "common/common.h"
#include "probebake/sh.h"
#include "probebake/render.h"
#include "render/render_types.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static uint32_t rng_seed(uint32_t seed, uint32_t a, uint32_t b, uint32_t c)
{
    return pb_hash32(seed ^ pb_hash32(a ^ pb_hash32(b ^ pb_hash32(c))));
}

static float rng_next(uint32_t *state)
{
    *state = pb_hash32(*state);
    return (float)(*state >> 8) * (1.0f / 16777216.0f);
}

/* probe_spheres of render.comp */
static int probe_spheres(const pb_sample_volume *v, const float o[3], const float d[3], float t_scene, float color[3])
{
    float smin = 1e30f;
    for (int k = 0; k < 3; ++k)
        if (v->counts[k] > 1)
            smin = fminf(smin, v->spacing[k]);
    float r = smin < 1e30f ? 0.08f * smin : 0.05f, best = t_scene;
    /* a sparse volume's probes have no grid home: no relocation marker */
    int count = v->levels ? (int)v->probe_count : v->counts[0] * v->counts[1] * v->counts[2], hit = 0;
    color[0] = color[1] = color[2] = 0.f;
    for (int p = 0; p < count; ++p) {
        uint32_t pf;
        memcpy(&pf, &v->probes[4 * (size_t)p + 3], 4);
        if (v->levels && pf == 0)
            continue; /* a sparse volume's empty probe (docs/sparse.md, step 7): not a place */
        int ijk[3] = {p % v->counts[0], (p / v->counts[0]) % v->counts[1], p / (v->counts[0] * v->counts[1])};
        float home[3], c[3];
        for (int k = 0; k < 3; ++k)
            c[k] = v->probes[4 * (size_t)p + k],
            home[k] = v->levels ? c[k] : v->origin[k] + (float)ijk[k] * v->spacing[k];
        for (int s = 0; s < 2; ++s) {
            const float *cs = s == 0 ? c : home;
            float rs = s == 0 ? r : 0.5f * r;
            float dh[3] = {c[0] - home[0], c[1] - home[1], c[2] - home[2]};
            if (s == 1 && sqrtf(dh[0] * dh[0] + dh[1] * dh[1] + dh[2] * dh[2]) <= r)
                break;
            float oc[3] = {o[0] - cs[0], o[1] - cs[1], o[2] - cs[2]};
            float b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
            float c2 = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - rs * rs, disc = b * b - c2;
            if (disc < 0.f)
                continue;
            float t = -b - sqrtf(disc);
            if (!(t > 0.f && t < best))
                continue;
            best = t, hit = 1;
            float n[3];
            for (int k = 0; k < 3; ++k)
                n[k] = o[k] + t * d[k] - cs[k];
            float nl = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int k = 0; k < 3; ++k)
                n[k] /= nl;
            if (s == 1) {
                color[0] = color[1] = color[2] = 0.3f;
            } else if (!(pf & PB_PROBE_VALID)) {
                color[0] = 1.f, color[1] = color[2] = 0.05f;
            } else {
                pb_sh_eval(v->sh + 27 * (size_t)p, n, color);
                for (int k = 0; k < 3; ++k)
                    color[k] = fmaxf(color[k], 0.f) / 3.14159265358979324f;
            }
        }
    }
    return hit;
}

typedef struct render_job {
    const pb_render_desc *d;
    pb_path_ctx path;
    float fwd[3], right[3], up[3];
    float *rgba, *direct;
} render_job;

static void render_rows(void *user, uint64_t begin, uint64_t end)
{
    const render_job *j = user;
    const pb_render_desc *d = j->d;
    for (uint64_t i = begin; i < end; ++i) {
        uint32_t px = (uint32_t)(i % d->width), py = (uint32_t)(i / d->width);
        /* sums per dispatch of 4 samples, then added, as render.comp and pb_render do */
        float acc[4] = {0, 0, 0, 0}, acc_d[3] = {0, 0, 0};
        float sum[3] = {0, 0, 0}, sum_d[3] = {0, 0, 0}, surface = 0.f;
        for (uint32_t k = 0; k < d->spp; ++k) {
            if (k % 4 == 0) {
                memset(sum, 0, sizeof sum), memset(sum_d, 0, sizeof sum_d);
                surface = 0.f;
            }
            uint32_t state = rng_seed(d->seed, py * d->width + px, k, 0x52454e44u);
            float jx = d->spp == 1 ? 0.5f : rng_next(&state);
            float jy = d->spp == 1 ? 0.5f : rng_next(&state);
            float sx = ((float)px + jx) / (float)d->width * 2.f - 1.f;
            float sy = 1.f - ((float)py + jy) / (float)d->height * 2.f;
            float dir[3];
            for (int c = 0; c < 3; ++c)
                dir[c] = j->fwd[c] + sx * j->right[c] + sy * j->up[c];
            float l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            for (int c = 0; c < 3; ++c)
                dir[c] /= l;
            uint32_t bounces = d->mode == PB_RENDER_REFERENCE ? d->bounces : 0;
            pb_path_result pr = pb_path_radiance_cpu(&j->path, d->camera.eye, dir, bounces, 1, &state);
            float L[3] = {pr.L[0], pr.L[1], pr.L[2]};
            if (d->mode == PB_RENDER_PROBES || d->mode == PB_RENDER_INDIRECT) {
                float V[3] = {0, 0, 0};
                if (pr.shade) {
                    float view[3] = {-dir[0], -dir[1], -dir[2]}, e[3];
                    pb_sample_cpu(d->volume, pr.x, pr.n, view, e);
                    for (int c = 0; c < 3; ++c)
                        V[c] = pr.albedo[c] / 3.14159265358979324f * e[c];
                }
                for (int c = 0; c < 3; ++c)
                    L[c] = d->mode == PB_RENDER_INDIRECT ? V[c] : (d->volume_direct ? pr.L_seen[c] : pr.L[c]) + V[c];
            }
            if (d->show_probes && d->volume) {
                float col[3];
                if (probe_spheres(d->volume, d->camera.eye, dir, isinf(pr.first_t) ? INFINITY : fabsf(pr.first_t), col))
                    memcpy(L, col, sizeof col);
            }
            for (int c = 0; c < 3; ++c)
                sum[c] += L[c], sum_d[c] += pr.L_direct[c];
            surface += pr.shade ? 1.f : 0.f;
            if (k % 4 == 3 || k + 1 == d->spp) {
                for (int c = 0; c < 3; ++c)
                    acc[c] = k < 4 ? sum[c] : acc[c] + sum[c], acc_d[c] = k < 4 ? sum_d[c] : acc_d[c] + sum_d[c];
                acc[3] = k < 4 ? surface : acc[3] + surface;
            }
        }
        for (int c = 0; c < 3; ++c) {
            j->rgba[4 * i + c] = acc[c] / (float)d->spp;
            if (j->direct)
                j->direct[4 * i + c] = acc_d[c] / (float)d->spp;
        }
        j->rgba[4 * i + 3] = acc[3] / (float)d->spp;
        if (j->direct)
            j->direct[4 * i + 3] = 0.f;
    }
}

pb_result pb_render_cpu(const pb_scene *scene, const pb_bvh *bvh, const pb_render_desc *desc, float *rgba,
                        float *direct, pb_error *err)
{
    pb_error_clear(err);
    pb_result r = pb_render_check(desc, err);
    if (r != PB_OK)
        return r;
    pb_render_desc d = *desc;
    pb_render_defaults(&d);
    pb_bake_emitters emit;
    pb_env_table env;
    if ((r = pb_shading_host(scene, d.sky, d.environment, &emit, &env, err)) != PB_OK)
        return r;
    pb_light_table lights_drawn;
    memset(&lights_drawn, 0, sizeof lights_drawn);
    if (pb_shading_draws_lights(scene, 0) && (r = pb_light_table_build(scene, &lights_drawn, err)) != PB_OK) {
        pb_bake_emitters_free(&emit);
        pb_env_table_free(&env);
        return r;
    }
    pb_bake_pass pass;
    memset(&pass, 0, sizeof pass);
    pass.scene = scene, pass.bvh = bvh, pass.env = env.width ? &env : NULL, pass.emitters = &emit;
    pass.light_table = lights_drawn.count ? &lights_drawn : NULL;
    pass.emitters_by_area = d.emitters_by_area;
    render_job j;
    memset(&j, 0, sizeof j);
    j.d = &d, j.rgba = rgba, j.direct = direct;
    pb_render_camera_basis(&d.camera, d.width, d.height, j.fwd, j.right, j.up);
    if (!pb_path_ctx_init(&j.path, &pass)) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    } else {
        pb_parallel_for((uint64_t)d.width * d.height, 16, 0, render_rows, &j);
        pb_path_ctx_free(&j.path);
    }
    pb_bake_emitters_free(&emit);
    pb_env_table_free(&env);
    pb_light_table_free(&lights_drawn);
    return r;
}
