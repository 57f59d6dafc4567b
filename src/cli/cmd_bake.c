#define _POSIX_C_SOURCE 200809L
/* probebake bake: a probe volume from a scene, with progress, a summary of
 * what was baked, and the file written atomically (Ctrl-C leaves the old
 * one). */
#include "cli/cli.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The sparse layout's settings from --max-level, --refine-error,
 * --refine-test, --refine-seams and --seam-error (0: the library's default). */
static pb_sparse_desc sparse_desc_from_options(const options *o)
{
    pb_sparse_desc sd = {o->has_max_level ? o->max_level + 1 : 0, o->refine_error, o->refine_test, 0,
                         o->refine_seams, o->seam_error};
    return sd;
}

/* --devices all|LIST: the devices to bake on, as pb_context_desc.device
 * strings ("N" indices or name parts; one may repeat, which on lavapipe
 * runs two logical devices of one driver). Returns how many, 0 on error. */
static uint32_t device_list(const char *spec, char names[][64], uint32_t capacity, pb_error *err)
{
    uint32_t n = 0;
    if (!strcmp(spec, "all")) {
        pb_device_info infos[64];
        uint32_t count = 0;
        if (pb_enumerate_devices(infos, 64, &count, err) != PB_OK)
            return 0;
        for (uint32_t i = 0; i < count && i < 64 && n < capacity; ++i)
            if (infos[i].usable)
                snprintf(names[n++], 64, "%u", infos[i].index);
        if (!n)
            snprintf(err->message, sizeof err->message, "--devices all: no usable Vulkan device");
        return n;
    }
    for (const char *c = spec; *c && n < capacity;) {
        size_t len = strcspn(c, ",");
        if (len == 0 || len >= 64) {
            snprintf(err->message, sizeof err->message, "--devices '%s': an empty or overlong entry", spec);
            return 0;
        }
        if (len == 3 && !strncmp(c, "all", 3)) {
            snprintf(err->message, sizeof err->message, "--devices '%s': 'all' stands alone, not in a list", spec);
            return 0;
        }
        memcpy(names[n], c, len);
        names[n++][len] = '\0';
        c += len + (c[len] == ',');
    }
    if (n == capacity)
        snprintf(err->message, sizeof err->message, "--devices '%s': at most %u devices", spec, capacity - 1);
    return n < capacity ? n : 0;
}

/* The devices a bake runs on, opened before the scene is read: a device
 * that matches nothing (or none at all) is said before a large scene's load
 * and BVH, not after. One for --device (or the default pick), one per entry
 * of --devices. */
enum { MAX_DEVICES = 33 };
typedef struct bake_devices {
    uint32_t count;
    char names[MAX_DEVICES][64];
    pb_context *ctxs[MAX_DEVICES];
} bake_devices;

static pb_result open_devices(const options *o, pb_log log, bake_devices *dv, pb_error *err)
{
    memset(dv, 0, sizeof *dv);
    if (!o->devices) {
        pb_context_desc cd = cli_context_desc(o, o->device, log);
        pb_result r = cli_context_create(&cd, "--device", &dv->ctxs[0], err);
        dv->count = r == PB_OK;
        return r;
    }
    uint32_t n = device_list(o->devices, dv->names, MAX_DEVICES, err);
    if (!n)
        return err->code = PB_ERROR_INVALID_ARGUMENT;
    char option[96];
    snprintf(option, sizeof option, "--devices '%.80s'", o->devices);
    /* one after another (instance set-up is not for threads) */
    for (; dv->count < n; ++dv->count) {
        pb_context_desc cd = cli_context_desc(o, dv->names[dv->count], log);
        pb_result r = cli_context_create(&cd, option, &dv->ctxs[dv->count], err);
        if (r != PB_OK)
            return r;
    }
    return PB_OK;
}

static void close_devices(bake_devices *dv)
{
    for (uint32_t i = 0; i < dv->count; ++i)
        pb_context_destroy(dv->ctxs[i]);
    dv->count = 0;
}

/* Validation messages on any device fail the bake (--validation). */
static pb_result check_validation(const options *o, const bake_devices *dv, pb_error *err)
{
    for (uint32_t i = 0; o->validation && i < dv->count; ++i)
        if (pb_context_validation_messages(dv->ctxs[i])) {
            if (o->devices)
                snprintf(err->message, sizeof err->message, "%u Vulkan validation messages on device %s",
                         pb_context_validation_messages(dv->ctxs[i]), dv->names[i]);
            else
                snprintf(err->message, sizeof err->message, "%u Vulkan validation messages",
                         pb_context_validation_messages(dv->ctxs[i]));
            return err->code = PB_ERROR_VULKAN;
        }
    return PB_OK;
}

/* The bake on every device of --devices, merged (pb_bake_devices). */
static pb_result bake_on_devices(const options *o, const bake_devices *dv, const pb_scene *s, const pb_bvh *bvh,
                                 pb_bake_desc *d, pb_volume *vol, pb_error *err)
{
    uint32_t n = dv->count;
    pb_gpu_scene *scenes[MAX_DEVICES] = {0};
    pb_result r = PB_OK;
    double upload_ms = 0.0; /* summed over the devices, as the parts' other timings are */
    for (uint32_t i = 0; i < n && r == PB_OK; ++i) {
        double t0 = cli_now_ms();
        r = pb_gpu_scene_create(dv->ctxs[i], s, bvh, &scenes[i], err);
        upload_ms += cli_now_ms() - t0;
    }
    if (r == PB_OK && !o->log.quiet)
        fprintf(stderr, "probebake: %u devices, one part each:", n);
    for (uint32_t i = 0; r == PB_OK && !o->log.quiet && i < n; ++i)
        fprintf(stderr, "%s %s", i ? "," : "", pb_context_device(dv->ctxs[i])->name);
    if (r == PB_OK && !o->log.quiet)
        fprintf(stderr, "\n");
    if (r == PB_OK) {
        cli_defer_signals(); /* from here a signal cancels the bake or the write */
        pb_sparse_desc sd = sparse_desc_from_options(o);
        r = pb_bake_devices(dv->ctxs, scenes, n, s, d, o->sparse ? &sd : NULL, vol, err);
    }
    if (r == PB_OK)
        vol->timings.upload = upload_ms;
    for (uint32_t i = 0; i < n; ++i)
        pb_gpu_scene_destroy(scenes[i]);
    return r;
}

/* Option combinations, refused before any file is read (usage errors, exit 2). */
static int check_combinations(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a SCENE file", "bake");
    if (!o->output)
        return cli_usage_error("%s needs -o OUT.probes", "bake");
    if (o->has_spacing && o->has_counts)
        return cli_usage_error("%s: give --spacing or --counts, not both", "bake");
    if (o->points && (o->has_spacing || o->has_counts || o->has_bounds))
        return cli_usage_error("%s: --points replaces the grid; drop --spacing, --counts and --bounds", "bake");
    if (!o->sparse && (o->has_max_level || o->refine_error > 0.f || o->has_refine_test || o->has_refine_seams ||
                       o->seam_error > 0.f))
        return cli_usage_error("%s: --max-level, --refine-error, --refine-test, --refine-seams and --seam-error "
                               "shape a sparse layout: add --layout sparse", "bake");
    if (o->seam_error > 0.f && !o->refine_seams)
        return cli_usage_error("%s: --seam-error sets the seam test's threshold: add --refine-seams N", "bake");
    if (o->sparse && o->points)
        return cli_usage_error("%s: --layout sparse places its own probes: not with --points", "bake");
    if (o->devices && (o->device || o->shard_count))
        return cli_usage_error(o->device ? "%s: --devices splits the bake by device: drop --device"
                                         : "%s: --devices splits the bake by device: drop --shard", "bake");
    return 0;
}

/* The grid from --counts, --spacing or the default fit, over --bounds or the
 * scene's bounds, in the scene's local frame. */
static pb_result grid_from_options(const options *o, const pb_scene *s, pb_probe_grid *g, pb_error *err)
{
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = o->has_bounds ? (float)(o->bounds[k] - s->origin[k]) : s->bounds_min[k];
        hi[k] = o->has_bounds ? (float)(o->bounds[3 + k] - s->origin[k]) : s->bounds_max[k];
    }
    memset(g, 0, sizeof *g);
    if (o->has_counts) {
        for (int k = 0; k < 3; ++k) {
            g->counts[k] = o->counts[k];
            g->spacing[k] = (hi[k] - lo[k]) / (float)o->counts[k];
            g->origin[k] = lo[k] + 0.5f * g->spacing[k];
        }
    } else if (o->has_spacing) {
        for (int k = 0; k < 3; ++k) {
            double n = floor((hi[k] - lo[k]) / o->spacing);
            if (n > 65536) {
                snprintf(err->message, sizeof err->message,
                         "--spacing %g gives %.0f probes along an axis; at most 65536", o->spacing, n);
                return err->code = PB_ERROR_INVALID_ARGUMENT;
            }
            g->counts[k] = n < 1 ? 1u : (uint32_t)n;
            g->spacing[k] = o->spacing;
            g->origin[k] = 0.5f * (lo[k] + hi[k]) - 0.5f * o->spacing * (float)(g->counts[k] - 1);
        }
    } else {
        pb_probe_grid_fit(lo, hi, 2048, g); /* a room at roughly 0.3 m */
    }
    return PB_OK;
}

/* The bake's settings: the command line, then the preset q (may be NULL)
 * for what it leaves out, then the defaults. */
static void desc_from_options(const options *o, const pb_bake_quality *q, const pb_environment *env, pb_bake_desc *d)
{
    d->rays_per_probe = o->has_rays ? o->rays : q ? q->rays_per_probe : 256;
    d->target_error = o->target_error > 0.f ? o->target_error : q ? q->target_error : 0.f;
    d->passes = o->passes ? o->passes : q ? q->passes : (d->target_error > 0.f ? 64 : 4);
    d->bounces = o->has_bounces ? o->bounces : 2;
    d->octmap_res = o->octmap_res ? o->octmap_res : 16;
    d->seed = o->has_seed ? o->seed : 1;
    d->exclude_direct = o->direct && !strcmp(o->direct, "exclude");
    d->probe_nee = o->probe_nee ? !strcmp(o->probe_nee, "on") : q ? q->probe_nee : 1u;
    d->guide_paths = o->guide ? (!strcmp(o->guide, "on") ? PB_GUIDE_DEFAULT_PATHS : 0u) : q ? q->guide_paths : 0u;
    d->light_cells = o->light_cells ? !strcmp(o->light_cells, "on") : q ? q->light_cells : 1u;
    d->emitters_by_area = (uint32_t)o->emitters_by_area;
    d->schedule = o->schedule;
    d->paths_per_lane = o->paths_per_lane;
    memcpy(d->sky, o->sky, sizeof d->sky);
    d->environment = o->env ? env : NULL;
    d->indirect_volume = (uint32_t)o->indirect_volume;
    d->sh_window = o->sh_window;
    d->indirect_clamp = o->indirect_clamp;
    d->max_lights_per_hit = o->max_lights_per_hit;
    d->relocation_rays = o->relocation_rays;
    d->inside_fraction = o->skip_inside && !strcmp(o->skip_inside, "off") ? 1.f : 0.f; /* 0: the library's default */
    d->sh_window_width = o->sh_window_width;
    d->shard_index = o->shard_index, d->shard_count = o->shard_count;
}

/* "probebake: baking ...": every setting the bake runs with, and what is
 * biased on request. */
static void print_banner(const options *o, const pb_bake_quality *q, const pb_bake_desc *d, const pb_environment *env,
                         const pb_points *pts, uint64_t probes)
{
    char light[1200], clamp_text[32], part[96] = "", where[160];
    if (o->env)
        snprintf(light, sizeof light, "environment %s (%ux%u, x%g, turned %g deg)", o->env, env->width, env->height,
                 o->env_intensity, o->env_rotation);
    else
        snprintf(light, sizeof light, "sky (%g, %g, %g)", d->sky[0], d->sky[1], d->sky[2]);
    if (o->points)
        snprintf(where, sizeof where, "%u points from %.100s", pts->count, o->points);
    else if (o->sparse)
        snprintf(where, sizeof where, "sparse bricks over %u x %u x %u finest lattice points, spacing %.3g m, "
                 "max level %u, refine error %g", d->grid.counts[0], d->grid.counts[1], d->grid.counts[2],
                 d->grid.spacing[0], o->has_max_level ? o->max_level : PB_SPARSE_MAX_LEVELS - 1,
                 o->refine_error > 0.f ? o->refine_error : 0.1);
    else
        snprintf(where, sizeof where, "%u x %u x %u = %llu probe%s, spacing %.3g m", d->grid.counts[0],
                 d->grid.counts[1], d->grid.counts[2], (unsigned long long)probes, cli_plural(probes),
                 d->grid.spacing[0]);
    if (o->shard_count && o->sparse)
        snprintf(part, sizeof part, ", part %u of %u (a range of coarsest bricks)", o->shard_index, o->shard_count);
    else if (o->shard_count) /* dealt (shard.h) */
        snprintf(part, sizeof part, ", part %u of %u (probes %u, %u, ... every %u: %u of them)", o->shard_index,
                 o->shard_count, o->shard_index, o->shard_index + o->shard_count, o->shard_count,
                 pb_shard_dealt_count((uint32_t)probes, o->shard_index, o->shard_count));
    fprintf(stderr,
            "probebake: baking %s%s%s%s: %s, %u ray%s x %s%u pass%s%s, %u bounce%s, "
            "%s, octmap %u, direct %s, indirect %s, probe NEE %s, guiding %s, light cells %s, emitters by %s, seed %u\n",
            o->scene, q ? " at quality " : "", q ? q->name : "", part, where, d->rays_per_probe,
            cli_plural(d->rays_per_probe), d->target_error > 0.f ? "up to " : "", d->passes,
            d->passes == 1 ? "" : "es", d->target_error > 0.f ? " (until converged)" : "", d->bounces,
            cli_plural(d->bounces), light, d->octmap_res, d->exclude_direct ? "excluded" : "included",
            d->indirect_volume ? "volume" : "path", d->probe_nee ? "on" : "off",
            /* --indirect volume bakes one bounce at a time: no bounce rays to guide */
            d->guide_paths && d->bounces && !d->indirect_volume ? "on" : "off", d->light_cells ? "on" : "off",
            d->emitters_by_area ? "area" : "solid angle", d->seed);
    if (d->schedule != PB_SCHEDULE_MEGAKERNEL) {
        char sched[32];
        fprintf(stderr, "probebake: schedule %s (the default's volume, bit for bit)\n",
                pb_bake_schedule_name(d, sched, sizeof sched));
    }
    if (d->indirect_clamp > 0.f || d->sh_window)
        fprintf(stderr, "probebake: biased on request:%s%s%s\n",
                d->indirect_clamp > 0.f ? " reflected light clamped per path to radiance " : "",
                d->indirect_clamp > 0.f ? (snprintf(clamp_text, sizeof clamp_text, "%g", d->indirect_clamp), clamp_text)
                                        : "",
                d->sh_window == 1 ? " SH Hanning window" : d->sh_window == 2 ? " SH Lanczos window" : "");
}

/* The sparse layout's line of the report: bricks and probes per level, and
 * what refinement tested (a --devices bake's parts keep their own counts). */
static void print_sparse_report(FILE *report, const options *o, const pb_volume *vol, const pb_sparse_stats *st)
{
    fprintf(report, "sparse: %u levels, bricks", vol->sparse->levels);
    if (o->devices) {
        uint32_t per_level[3] = {0, 0, 0};
        for (uint32_t b = 0; b < vol->sparse->brick_count; ++b)
            per_level[vol->sparse->bricks[b].level]++;
        for (uint32_t l = 0; l < vol->sparse->levels; ++l)
            fprintf(report, " %u", per_level[l]);
        fprintf(report, "\n");
        return;
    }
    for (uint32_t l = 0; l < vol->sparse->levels; ++l)
        fprintf(report, " %u", st->bricks[l]);
    fprintf(report, " (%u dropped inside geometry), probes baked per level", st->dropped[0] + st->dropped[1] + st->dropped[2]);
    for (uint32_t l = 0; l < vol->sparse->levels; ++l)
        fprintf(report, " %u", st->probes[l]);
    fprintf(report, "; cells tested %u, refined %u (%u at seams), not tested (no surface near or inside, or solid) %u, "
                    "beyond the bounds %u; %u bakes, %u test probes thrown away",
            st->tested[0] + st->tested[1], st->refined[0] + st->refined[1], st->seam_refined[0] + st->seam_refined[1],
            st->skipped[0] + st->skipped[1], st->beyond[0] + st->beyond[1], st->bakes,
            st->test_probes[0] + st->test_probes[1]);
    if (!o->shard_count)
        fprintf(report, "; %u probes inside geometry dropped (no lookup weighs them)", vol->probes_dropped);
    fprintf(report, "\n");
}

/* What was written: probes by flag, paths and their error, and time. */
static void print_report(FILE *report, const options *o, const pb_bake_desc *d, const pb_volume *vol,
                         const pb_sparse_stats *st, uint64_t probes)
{
    uint32_t valid = 0, outside = 0, relocated = 0, dilated = 0, converged = 0, inside = 0;
    for (uint32_t i = 0; i < vol->probe_count; ++i) {
        valid += (vol->probe_flags[i] & PB_PROBE_VALID) != 0;
        outside += (vol->probe_flags[i] & PB_PROBE_OUTSIDE) != 0;
        relocated += (vol->probe_flags[i] & PB_PROBE_RELOCATED) != 0;
        dilated += (vol->probe_flags[i] & PB_PROBE_DILATED) != 0;
        converged += (vol->probe_flags[i] & PB_PROBE_CONVERGED) != 0;
        inside += (vol->probe_flags[i] & PB_PROBE_INSIDE) != 0;
    }
    if (o->sparse)
        print_sparse_report(report, o, vol, st);
    if (o->shard_count && o->sparse)
        fprintf(report, "wrote %s: part %u of %u, %u probes in %u bricks grown from coarsest brick %u on (of %u), "
                "undilated (probebake merge joins the parts) (%u valid, %u relocated, %u invalid, %u outside",
                o->output, o->shard_index, o->shard_count, vol->probe_count, vol->sparse->brick_count,
                vol->shard.first, vol->shard.total, valid, relocated, vol->probe_count - valid, outside);
    else if (o->shard_count)
        fprintf(report, "wrote %s: part %u of %u, %u of %llu probes, undilated (probebake merge joins the parts) (%u "
                "valid, %u relocated, %u invalid of which %u inside geometry, not traced, %u outside", o->output,
                o->shard_index, o->shard_count, vol->probe_count, (unsigned long long)probes, valid, relocated,
                vol->probe_count - valid, inside, outside);
    else if (o->sparse && vol->probes_dropped) /* the one invalid probe left is the empty one of step 7 */
        fprintf(report, "wrote %s: %u probes (%u valid, %u relocated, %u inside geometry dropped for one empty probe, "
                "%u outside", o->output, vol->probe_count, valid, relocated, vol->probes_dropped, outside);
    else
        fprintf(report, "wrote %s: %llu probe%s (%u valid, %u relocated, %u invalid of which %u dilated and %u inside "
                "geometry, not traced, %u outside", o->output, (unsigned long long)probes, cli_plural(probes),
                valid, relocated, vol->probe_count - valid, dilated, inside, outside);
    if (d->target_error > 0.f)
        fprintf(report, ", %u converged before the last pass", converged);
    double rays = (double)vol->rays_traced;
    fprintf(report, "), %.3g probe rays in %s%u pass%s\n", rays, d->target_error > 0.f ? "up to " : "",
            vol->settings.passes, vol->settings.passes == 1 ? "" : "es"); /* pass, passes */
    cli_print_error_summary(report, vol);
    const pb_volume_timings *t = &vol->timings;
    fprintf(report, "time: load %.0f ms, bvh %.1f ms, upload %.1f ms; GPU trace %.0f ms (%.2f M probe rays/s, %.2f M "
                    "traversals/s), sh %.0f ms, depth %.0f ms (relocation: %.0f ms of trace and sh); total %.0f ms wall\n",
            t->load, t->bvh, t->upload, t->trace, t->trace > 0 ? rays / (t->trace * 1e3) : 0.0,
            t->trace > 0 ? (double)vol->traversals / (t->trace * 1e3) : 0.0, t->sh, t->octmap, t->relocate, t->total);
}

/* The bake on one device (--device, or the default pick). */
static pb_result bake_on_device(const options *o, pb_context *ctx, const pb_scene *s, const pb_bvh *bvh,
                                const pb_bake_desc *d, pb_volume *vol, pb_sparse_stats *stats, pb_error *err)
{
    pb_gpu_scene *gs = NULL;
    double upload_ms = cli_now_ms();
    pb_result r = pb_gpu_scene_create(ctx, s, bvh, &gs, err);
    upload_ms = cli_now_ms() - upload_ms;
    if (r == PB_OK) {
        cli_defer_signals(); /* from here a signal cancels the bake or the write */
        if (o->sparse) {
            pb_sparse_desc sd = sparse_desc_from_options(o);
            r = pb_bake_sparse(ctx, s, gs, d, &sd, vol, stats, err);
        } else {
            r = pb_bake(ctx, s, gs, d, vol, err);
        }
    }
    if (r == PB_OK)
        vol->timings.upload = upload_ms; /* the caller's, as load and bvh are */
    pb_gpu_scene_destroy(gs);
    return r;
}

/* A step before the bake's progress line: said (info) when it took a
 * second or more, where a large scene's user waits for it; else a debug
 * line. */
static void log_slow_step(const options *o, double ms, const char *fmt, ...)
{
    char what[512], line[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    snprintf(line, sizeof line, "%s (%.0f ms)", what, ms);
    cli_log_to_stderr(ms >= 1000.0 ? PB_LOG_INFO : PB_LOG_DEBUG, line, (void *)&o->log);
}

int cmd_bake(const options *o)
{
    int usage = check_combinations(o);
    if (usage)
        return usage;
    pb_log log = {cli_log_to_stderr, (void *)&o->log};
    pb_scene_desc scd = {log, 0};
    scd.face_normals = (uint32_t)o->face_normals;
    scd.no_normal_maps = (uint32_t)o->no_normal_maps;
    pb_scene *s = NULL;
    pb_bvh *bvh = NULL;
    pb_volume vol = {0};
    pb_sparse_stats stats = {0};
    pb_points pts = {0};
    pb_environment env = {0};
    pb_bake_desc d = {0};
    bake_devices dv = {0};
    pb_error err = {0};
    int rc = 1;
    double t0 = cli_now_ms();
    /* the output is checked before any work: not a directory, writable,
     * not one of the inputs (hard links and symlinks too) */
    const char *inputs[3] = {o->scene, o->env, o->points};
    if (pb_output_check(o->output, inputs, 3, &err) != PB_OK)
        goto out;
    if (o->points && pb_points_read(o->points, &pts, &err) != PB_OK)
        goto out;
    if (cli_environment(o, &env, &err) != PB_OK)
        goto out;
    /* every setting that needs no scene, before a large scene's load */
    const pb_bake_quality *q = pb_bake_quality_find(o->quality);
    if (o->points)
        d.points = &pts;
    desc_from_options(o, q, &env, &d);
    pb_sparse_desc sd = sparse_desc_from_options(o);
    pb_bake_desc split = d; /* --devices LIST of two or more bakes parts, as --shard does ("all": known later) */
    if (o->devices && strchr(o->devices, ','))
        split.shard_index = 0, split.shard_count = 2;
    if (pb_bake_check_settings(&split, o->sparse ? &sd : NULL, &err) != PB_OK)
        goto out;
    if (open_devices(o, log, &dv, &err) != PB_OK)
        goto out;
    double load_ms = cli_now_ms();
    if (pb_scene_load(o->scene, &scd, &s, &err) != PB_OK ||
        pb_bake_check_light(s, o->sky, o->env ? &env : NULL, &err) != PB_OK)
        goto out;
    load_ms = cli_now_ms() - load_ms;
    log_slow_step(o, load_ms, "%s: %u triangles loaded", o->scene, s->triangle_count);
    if (s->triangle_count == 0 && !o->has_bounds && !o->points) {
        snprintf(err.message, sizeof err.message, "%s: no triangles and no --bounds: nowhere to put probes", o->scene);
        goto out;
    }
    if (!o->points && grid_from_options(o, s, &d.grid, &err) != PB_OK)
        goto out;
    uint64_t probes = o->points ? pts.count : (uint64_t)d.grid.counts[0] * d.grid.counts[1] * d.grid.counts[2];
    if (o->shard_count > probes) {
        snprintf(err.message, sizeof err.message, "--shard %u/%u: only %llu probes to share", o->shard_index,
                 o->shard_count, (unsigned long long)probes);
        goto out;
    }
    if (!o->log.quiet)
        print_banner(o, q, &d, &env, &pts, probes);
    if (d.target_error > 0.f && d.passes <= PB_TARGET_ERROR_MIN_PASSES)
        fprintf(stderr, "probebake: warning: --target-error stops a probe after %u passes at the earliest; with --passes "
                        "%u every probe takes all %u\n", PB_TARGET_ERROR_MIN_PASSES, d.passes, d.passes);
    if (pb_bvh_build(s, NULL, &bvh, &err) != PB_OK)
        goto out;
    log_slow_step(o, bvh->stats.build_ms, "BVH of %u triangles built on %u thread%s", s->triangle_count,
                  bvh->stats.threads, bvh->stats.threads == 1 ? "" : "s");
    cli_progress_state ps = {isatty(2) && !o->log.quiet, cli_now_ms(), probes * d.rays_per_probe * d.passes};
    d.progress = cli_progress;
    d.progress_user = &ps;
    pb_result r = o->devices ? bake_on_devices(o, &dv, s, bvh, &d, &vol, &err)
                             : bake_on_device(o, dv.ctxs[0], s, bvh, &d, &vol, &stats, &err);
    if (ps.show)
        fprintf(stderr, "\n");
    if (r != PB_OK || check_validation(o, &dv, &err) != PB_OK)
        goto out;
    close_devices(&dv); /* before the write, which needs none */
    if (o->sparse)
        probes = vol.probe_count;
    vol.timings.load = load_ms;
    vol.timings.bvh = bvh->stats.build_ms;
    vol.timings.total = cli_now_ms() - t0;
    double write_t0 = cli_now_ms();
    if (pb_volume_write_ex(o->output, &vol, cli_interrupted, NULL, &err) != PB_OK)
        goto out;
    log_slow_step(o, cli_now_ms() - write_t0, "%s: %.1f MiB written", o->output,
                  pb_volume_file_bytes(&vol) / 1048576.0);
    print_report(strcmp(o->output, "-") ? stdout : stderr, /* stdout carries the volume for -o - */
                 o, &d, &vol, &stats, probes);
    rc = 0;
out:
    pb_volume_free(&vol);
    pb_points_free(&pts);
    pb_environment_free(&env);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    close_devices(&dv);
    return rc ? cli_fail(&err) : 0;
}
