/* A bake's settings: defaults and the checks that need neither scene nor
 * device (settings.h). */
#include "bake/settings.h"
#include "common/common.h"
#include "probebake/sparse.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void pb_bake_settings_default(pb_bake_desc *d)
{
    if (!d->rays_per_probe)
        d->rays_per_probe = 256;
    d->passes = pb_bake_passes(d);
    if (!d->octmap_res)
        d->octmap_res = 16;
    if (d->lobe_power == 0.f)
        d->lobe_power = 50.f;
    if (d->invalid_backface_fraction == 0.f)
        d->invalid_backface_fraction = 0.25f;
    if (d->inside_fraction == 0.f)
        d->inside_fraction = d->invalid_backface_fraction + PB_INSIDE_MARGIN;
    if (!d->relocation_rays)
        d->relocation_rays = d->rays_per_probe < PB_RELOCATION_RAYS_DEFAULT ? d->rays_per_probe
                                                                             : PB_RELOCATION_RAYS_DEFAULT;
    if (!d->paths_per_lane)
        d->paths_per_lane = PB_PATHS_PER_LANE_DEFAULT;
}

int pb_bake_schedule_parse(const char *text, uint32_t *schedule, uint32_t *paths_per_lane)
{
    unsigned k = 0;
    char end = 0;
    if (!text)
        return 0;
    if (!strcmp(text, "megakernel") || !strcmp(text, "wavefront")) {
        *schedule = text[0] == 'w' ? PB_SCHEDULE_WAVEFRONT : PB_SCHEDULE_MEGAKERNEL, *paths_per_lane = 0;
        return 1;
    }
    if (strncmp(text, "restart", 7) ||
        (text[7] && (text[7] != ':' || sscanf(text + 8, "%u%c", &k, &end) != 1 || k < 1 || k > PB_MAX_PATHS_PER_LANE)))
        return 0;
    *schedule = PB_SCHEDULE_RESTART, *paths_per_lane = k;
    return 1;
}

const char *pb_bake_schedule_name(const pb_bake_desc *desc, char *buf, size_t size)
{
    uint32_t k = desc->paths_per_lane ? desc->paths_per_lane : PB_PATHS_PER_LANE_DEFAULT;
    if (desc->schedule == PB_SCHEDULE_RESTART)
        snprintf(buf, size, "restart:%u", k);
    else
        snprintf(buf, size, "%s", desc->schedule == PB_SCHEDULE_WAVEFRONT ? "wavefront" : "megakernel");
    return buf;
}

pb_result pb_bake_settings_check(const pb_bake_desc *d, pb_error *err)
{
    if (!(d->target_error >= 0.f) || !(d->target_error < 1.f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "target error %g: must be in [0, 1) (a relative error)",
                       d->target_error);
    if (d->points && (d->points->count == 0 || d->points->count > (1u << 24)))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u probe points: need 1 to 2^24", d->points->count);
    if (d->points && (!(d->points->spacing >= 0) || !isfinite(d->points->spacing)))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "points spacing must be finite and >= 0");
    if (d->rays_per_probe > 65536)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u rays per probe: at most 65536", d->rays_per_probe);
    if (d->relocation_rays > d->rays_per_probe)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u relocation rays per probe: at most the %u rays per probe "
                       "of a pass", d->relocation_rays, d->rays_per_probe);
    if (d->passes > 1000000)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u passes: at most 1e6", d->passes);
    if (d->sh_window > PB_SH_WINDOW_LANCZOS || !(d->sh_window_width >= 0.f) || d->sh_window_width > 1e3f)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "SH window %u (width %g): none, hanning or lanczos, width in "
                       "(0, 1000]", d->sh_window, d->sh_window_width);
    if (!(d->indirect_clamp >= 0.f) || !isfinite(d->indirect_clamp))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "indirect clamp %g: must be finite and >= 0 (0: off)",
                       d->indirect_clamp);
    if (d->bounces > 64)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u bounces: at most 64", d->bounces);
    if (d->octmap_res > 64)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "octahedral map %u: at most 64 texels per side", d->octmap_res);
    if (d->schedule > PB_SCHEDULE_RESTART)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "schedule %u: 0 (one kernel per path), 1 (a wavefront) or 2 (restarts)", d->schedule);
    if (d->paths_per_lane > PB_MAX_PATHS_PER_LANE)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%u paths per lane: at most %u", d->paths_per_lane,
                       PB_MAX_PATHS_PER_LANE);
    if (d->environment && (!d->environment->rgb || !d->environment->width || !d->environment->height ||
                           (uint64_t)d->environment->width * d->environment->height > (1u << 24) ||
                           !isfinite(d->environment->rotation_deg)))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "environment map: empty, over 2^24 texels, or a non-finite rotation");
    if (!(d->lobe_power > 0.f) || !(d->invalid_backface_fraction > 0.f && d->invalid_backface_fraction <= 1.f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "lobe power must be positive, the invalid back-face "
                                                       "fraction in (0, 1]");
    if (!(d->inside_fraction > 0.f) || !isfinite(d->inside_fraction))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "inside fraction %g: must be in (0, 1), or >= 1 to trace every "
                       "probe", d->inside_fraction);
    /* --indirect volume's bounces each sample the whole previous volume */
    if (d->indirect_volume && d->bounces && d->shard_count)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "--indirect volume samples the whole previous bounce's volume: a part (--shard, --devices) "
                       "cannot bake it alone (split the path-traced bake instead)");
    if (d->indirect_volume && d->bounces && d->points)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "--indirect volume samples the previous bounce's grid: it needs a grid, not points");
    return PB_OK;
}

pb_result pb_sparse_settings(const pb_bake_desc *desc, const pb_sparse_desc *sd, pb_sparse_desc *out,
                             pb_error *err)
{
    pb_sparse_desc s = *sd;
    if (s.levels == 0)
        s.levels = 3;
    if (s.refine_error == 0.f)
        s.refine_error = 0.1f;
    if (s.test_pass_scale == 0)
        s.test_pass_scale = 4;
    if (s.seam_error == 0.f)
        s.seam_error = s.refine_error;
    *out = s;
    if (!(s.seam_error > 0.f) || !isfinite(s.seam_error))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "--seam-error %g: must be a positive number",
                       (double)s.seam_error);
    if (s.seam_rounds > 8)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "--refine-seams %u: at most 8 rounds", s.seam_rounds);
    if (s.test_pass_scale > 64)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "sparse bake: the surface test's probes at %u times the bake's passes: at most 64",
                       s.test_pass_scale);
    if (s.levels > PB_SPARSE_MAX_LEVELS)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "--max-level %u: the sparse layout has at most %u levels (0-%u)",
                       s.levels - 1, PB_SPARSE_MAX_LEVELS, PB_SPARSE_MAX_LEVELS - 1);
    if (!(s.refine_error > 0.f) || !isfinite(s.refine_error))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "--refine-error %g: must be a positive number",
                       (double)s.refine_error);
    if (s.test == PB_REFINE_TEST_SURFACE && !(s.refine_error < 1.f))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "--refine-error %g: the surface test's error is relative to the larger of prediction and "
                       "bake, so at most 1: give less than 1 (or --refine-test probe)", (double)s.refine_error);
    if (s.test > PB_REFINE_TEST_PROBE)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "sparse bake: unknown refinement test %u", s.test);
    if (desc->points)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "--layout sparse places its own probes: not with --points");
    /* each of a sparse bake's bakes takes --target-error's floor from its own
     * probes, which a part does not have all of */
    if (desc->shard_count && desc->target_error > 0.f)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "--target-error in a sparse bake depends on every probe of each level: its parts (--shard, "
                       "--devices) could not merge into the whole bake; give fixed --passes (or bake it in one part)");
    return PB_OK;
}

pb_result pb_bake_settings(const pb_bake_desc *desc, const pb_sparse_desc *sparse, pb_sparse_desc *sd,
                           pb_error *err)
{
    pb_bake_desc d = *desc;
    pb_bake_settings_default(&d);
    pb_result r = pb_bake_settings_check(&d, err);
    if (r == PB_OK && sparse)
        r = pb_sparse_settings(desc, sparse, sd, err);
    return r;
}

pb_result pb_bake_check_settings(const pb_bake_desc *desc, const pb_sparse_desc *sparse, pb_error *err)
{
    pb_error_clear(err);
    pb_sparse_desc sd;
    return pb_bake_settings(desc, sparse, &sd, err);
}
