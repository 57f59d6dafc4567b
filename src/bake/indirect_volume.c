/* --indirect volume's bounce loop (indirect_volume.h). */
#include "bake/indirect_volume.h"
#include "bake/timings.h"

#include <string.h>

pb_result pb_indirect_volume_bounces(const pb_scene *scene, const pb_bake_desc *desc, pb_bounce_fn bake, void *user,
                                     pb_volume *out, pb_error *err)
{
    memset(out, 0, sizeof *out);
    /* bounce k shades the probe rays' first hits with the volume of bounce
     * k - 1, baked without direct light (the hits' direct light is already
     * sampled); the last bounce includes direct light if the caller asked */
    pb_bake_desc d = *desc;
    d.indirect_volume = 0;
    d.bounces = 0;
    pb_sample_volume fb;
    memset(&fb, 0, sizeof fb);
    pb_volume_timings t;
    memset(&t, 0, sizeof t);
    uint64_t rays = 0, traversals = 0, relocation_rays = 0;
    pb_result r = PB_OK;
    for (uint32_t k = 0; r == PB_OK && k <= desc->bounces; ++k) {
        d.exclude_direct = k < desc->bounces ? 1 : desc->exclude_direct;
        pb_volume v;
        r = bake(user, &d, k ? &fb : NULL, &v, err);
        if (r != PB_OK)
            break;
        pb_volume_timings_add(&t, &v.timings);
        rays += v.rays_traced, traversals += v.traversals, relocation_rays += v.relocation_rays;
        pb_sample_volume_free(&fb);
        if (k < desc->bounces) {
            r = pb_sample_volume_build(&v, scene->origin, 0.f, 0.f, &fb, err);
            pb_volume_free(&v);
        } else {
            *out = v;
        }
    }
    pb_sample_volume_free(&fb);
    if (r != PB_OK)
        return r;
    out->timings = t;
    out->rays_traced = rays, out->traversals = traversals, out->relocation_rays = relocation_rays;
    out->settings.bounces = desc->bounces;
    out->settings.indirect_mode = 1;
    return PB_OK;
}
