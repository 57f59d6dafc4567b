/* Compressed glTF (issue 15) baked on the host: the Draco, meshopt and
 * quantized variants of the demo scene and the shared Cornell box
 * (tests/gltf_compress) go through the CPU reference of the bake kernels
 * (bake_cpu.c: the same paths, emitters and light as the kernels) and must
 * agree with their originals within the bound docs/scene.md states. CPU
 * only, so the CI's sanitizer run covers the decoders and the bake of what
 * they decoded. (test_bake runs the same comparison through the kernels.) */
#include "compressed_variants.h"
#include "test_util.h"

#include "bake/convergence.h"
#include "common/common.h"

/* The irradiance luminance (DC) of each probe of d's grid, per pass:
 * E[probe * passes + pass], by the CPU reference of the bake kernels. */
static int cpu_bake(const pb_scene *s, const pb_bake_desc *d, uint32_t passes, double *E)
{
    pb_bvh *bvh = NULL;
    pb_error err;
    pb_bake_emitters em;
    memset(&em, 0, sizeof em);
    if (pb_bvh_build(s, NULL, &bvh, &err) != PB_OK || pb_bake_emitters_build(s, &em, &err) != PB_OK) {
        CHECKF(0, "%s", err.message);
        pb_bvh_destroy(bvh);
        return 0;
    }
    uint32_t P = d->grid.counts[0] * d->grid.counts[1] * d->grid.counts[2], rpp = d->rays_per_probe;
    float *probes = calloc((size_t)P * 4, sizeof(float)), *rot = malloc((size_t)P * 48);
    float *dirs = malloc((size_t)rpp * 16), *rays = malloc((size_t)P * rpp * 16);
    float *red = calloc((size_t)P * (40 + 2 * 16), sizeof(float));
    float dx = s->bounds_max[0] - s->bounds_min[0], dy = s->bounds_max[1] - s->bounds_min[1],
          dz = s->bounds_max[2] - s->bounds_min[2];
    for (uint32_t pass = 0; pass < passes; ++pass) {
        pb_bake_pass_inputs(s, d, P, rpp, pass, probes, rot, dirs);
        pb_bake_pass pp = {0};
        pp.scene = s, pp.bvh = bvh, pp.probes = probes, pp.rotations = rot, pp.directions = dirs;
        pp.probe_count = P, pp.rays_per_probe = rpp, pp.pass_index = pass, pp.seed = d->seed;
        pp.bounces = d->bounces, pp.octmap_res = 4, pp.direct = 1, pp.emitters = &em;
        pp.max_distance = sqrtf(dx * dx + dy * dy + dz * dz), pp.lobe_power = 50.f;
        pb_bake_trace_cpu(&pp, rays);
        pb_bake_sh_cpu(&pp, rays, red);
        for (uint32_t p = 0; p < P; ++p) {
            float c[27];
            memcpy(c, red + 40 * p, sizeof c);
            pb_sh_radiance_to_irradiance(c);
            E[(size_t)p * passes + pass] = pb_luminance(c);
        }
    }
    free(probes), free(rot), free(dirs), free(rays), free(red);
    pb_bake_emitters_free(&em);
    pb_bvh_destroy(bvh);
    return 1;
}

static void compressed_scenes_bake_on_the_host_like_originals(void)
{
    const uint32_t passes = VARIANT_PASSES, P = 27;
    for (int si = 0; si < PB_VARIANT_SOURCES; ++si) {
        const char *src, *tag, *path;
        pb_scene *o = variant_original(si, &src, &tag);
        if (!o)
            continue;
        /* 3 x 3 x 3 probes in the middle of the bounds, at fractions that are
         * no round coordinate of these scenes: a probe lying on a surface
         * (the demo's boxes end at round numbers) is inside or outside by
         * less than any quantization step, and no encoding can keep that
         * (the bake's relocation moves such probes; this reference has none) */
        pb_bake_desc d = {0};
        for (int k = 0; k < 3; ++k) {
            float e = o->bounds_max[k] - o->bounds_min[k];
            d.grid.counts[k] = 3;
            d.grid.spacing[k] = 0.2113f * e;
            d.grid.origin[k] = o->bounds_min[k] + 0.2837f * e;
        }
        d.rays_per_probe = scaled(320) & ~31u, d.bounces = 2, d.seed = 5;
        double Eo[27 * VARIANT_PASSES], Ec[27 * VARIANT_PASSES];
        int ok = cpu_bake(o, &d, passes, Eo);
        for (size_t vi = 0; ok && vi < PB_VARIANT_COUNT; ++vi) {
            const pb_variant *v = &pb_variants[vi];
            if (strcmp(v->ext, "glb") != 0)
                continue; /* the .gltf forms decode the same streams (test_scene) */
            pb_scene *c = variant_scene(src, tag, v, &path);
            if (!c)
                continue;
            pb_bake_desc dc = d;
            variant_grid_frame(o, c, &dc.grid);
            if (cpu_bake(c, &dc, passes, Ec)) {
                double ea[27], sa[27], eb[27], sb[27];
                for (uint32_t p = 0; p < P; ++p) {
                    double so = 0, qo = 0, sc = 0, qc = 0;
                    for (uint32_t k = 0; k < passes; ++k) {
                        so += Eo[p * passes + k], qo += Eo[p * passes + k] * Eo[p * passes + k];
                        sc += Ec[p * passes + k], qc += Ec[p * passes + k] * Ec[p * passes + k];
                    }
                    sa[p] = pb_pass_std_error(passes, so, qo, &ea[p]);
                    sb[p] = pb_pass_std_error(passes, sc, qc, &eb[p]);
                }
                char label[64];
                snprintf(label, sizeof label, "%-7s %-11s", tag, v->mode);
                variant_check_bake(path, label, ea, sa, eb, sb, P);
            }
            pb_scene_destroy(c);
        }
        pb_scene_destroy(o);
    }
}

int main(void)
{
    RUN(compressed_scenes_bake_on_the_host_like_originals);
    return test_summary();
}
