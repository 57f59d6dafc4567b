#define _POSIX_C_SOURCE 200809L
/* probebake inspect: a volume file's summary, every probe as JSON, or the
 * debug images (--atlas, --sh-view). */
#include "cli/cli.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void print_flags(uint32_t f)
{
    static const char *const names[] = {"valid", "relocated", "dilated", "outside", "converged", "inside"};
    int first = 1;
    printf("[");
    for (int b = 0; b < 6; ++b)
        if (f & (1u << b)) {
            printf("%s\"%s\"", first ? "" : ", ", names[b]);
            first = 0;
        }
    printf("]");
}

/* Bricks per level, and probes per level of the brick that first names them. */
typedef struct sparse_census {
    uint32_t bricks[3], probes[3];
} sparse_census;

/* The seam test's threshold after its rounds, where recorded (0 with no seam test and in older files) */
static const char *seam_threshold(const pb_volume_settings *s, char out[64])
{
    out[0] = '\0';
    if (s->seam_rounds && s->seam_error > 0.f)
        snprintf(out, 64, ", where missed by more than %g", (double)s->seam_error);
    return out;
}

static sparse_census census(const pb_volume *v)
{
    sparse_census c = {{0}, {0}};
    const pb_sparse_layout *sp = v->sparse;
    uint32_t seen = 0;
    for (uint32_t b = 0; b < sp->brick_count; ++b) {
        c.bricks[sp->bricks[b].level]++;
        for (uint32_t i = 0; i < PB_SPARSE_BRICK_PROBES; ++i)
            if (sp->brick_probes[PB_SPARSE_BRICK_PROBES * b + i] == seen) { /* probes are numbered by first use */
                c.probes[sp->bricks[b].level]++;
                seen++;
            }
    }
    return c;
}

static void print_probe_json(const pb_volume *v, uint32_t i, int last)
{
    double p[3];
    pb_volume_probe_position(v, i, p);
    printf("    {\"index\": %u, \"position\": [%s, %s, %s], \"offset\": [%s, %s, %s], \"flags\": ", i, J(p[0]).s,
           J(p[1]).s, J(p[2]).s, J(v->offset[3 * i]).s, J(v->offset[3 * i + 1]).s, J(v->offset[3 * i + 2]).s);
    print_flags(v->probe_flags[i]);
    float se = v->probe_std_error[i];
    printf(", \"paths\": %u, \"std_error\": %s", v->probe_paths[i], se == PB_STD_ERROR_UNKNOWN ? "null" : J(se).s);
    printf(", \"sh\": [");
    for (int c = 0; c < 27; ++c)
        printf("%s%s", c ? ", " : "", J(v->sh[27 * (size_t)i + c]).s);
    printf("]}%s\n", last ? "" : ",");
}

static const char *window_name(uint32_t w)
{
    return w == 1 ? "hanning" : w == 2 ? "lanczos" : "none";
}

/* The file's techniques as JSON array items. */
static const char *technique_list(uint32_t t, char buf[96])
{
    static const char *names[4] = {"probe-nee", "guiding", "light-cells", "solid-angle"};
    buf[0] = 0;
    for (int k = 0; k < 4; ++k)
        if (t & (1u << k))
            snprintf(buf + strlen(buf), 96 - strlen(buf), "%s\"%s\"", buf[0] ? ", " : "", names[k]);
    return buf;
}

static const char *refine_test_json(uint32_t recorded)
{
    return recorded == 1u + PB_REFINE_TEST_SURFACE ? "\"surface\"" : recorded == 1u + PB_REFINE_TEST_PROBE ? "\"probe\"" : "null";
}

/* The debug images (--atlas, --sh-view): both outputs checked and both
 * images made before either is written, and the first removed if the second
 * cannot be: a failure leaves neither. */
static pb_result write_views(const options *o, const pb_volume *v, pb_error *err)
{
    const char *views[2] = {o->atlas, o->sh_view};
    unsigned char *img[2] = {NULL, NULL};
    uint32_t w[2] = {0, 0}, h[2] = {0, 0};
    const char *inputs[1] = {o->scene};
    pb_result r = PB_OK;
    for (int k = 0; k < 2 && r == PB_OK; ++k)
        if (views[k])
            r = pb_output_check(views[k], inputs, 1, err);
    for (int k = 0; k < 2 && r == PB_OK; ++k)
        if (views[k])
            r = k == 0 ? pb_volume_depth_atlas(v, &img[k], &w[k], &h[k], err)
                       : pb_volume_sh_atlas(v, 16, &img[k], &w[k], &h[k], err);
    int written = 0;
    for (int k = 0; k < 2 && r == PB_OK; ++k)
        if (views[k] && (r = pb_write_png(views[k], img[k], w[k], h[k], err)) == PB_OK)
            written |= 1 << k;
    if (r != PB_OK && (written & 1))
        remove(views[0]);
    free(img[0]), free(img[1]);
    if (r != PB_OK)
        return r;
    for (int k = 0; k < 2 && !o->json; ++k)
        if (views[k])
            printf("wrote %s: %ux%u, %s of %u probe%s%s\n", views[k], w[k], h[k],
                   k == 0 ? "depth atlas" : "SH irradiance view", v->probe_count, cli_plural(v->probe_count),
                   v->sparse ? "; tile frames by finest level (0 blue, 1 green, 2 red), dim on odd bricks" : "");
    return PB_OK;
}

/* Probes per flag bit: valid, relocated, dilated, outside, converged, inside. */
static void count_flags(const pb_volume *v, uint32_t counts[6])
{
    for (int b = 0; b < 6; ++b)
        counts[b] = 0;
    for (uint32_t i = 0; i < v->probe_count; ++i)
        for (int b = 0; b < 6; ++b)
            counts[b] += (v->probe_flags[i] >> b) & 1u;
}

static const char *volume_kind(const pb_volume *v)
{
    return v->flags & PB_VOLUME_IRRADIANCE ? "irradiance" : "radiance";
}

/* --json: the header's fields, then every probe (or only --probe's) */
static void print_json(const options *o, const pb_volume *v)
{
    const pb_volume_settings *s = &v->settings;
    const char *kind = volume_kind(v);
    char techniques[96];
    uint32_t counts[6];
    count_flags(v, counts);
    printf("{\n  \"file\": ");
    json_string(o->scene);
    printf(",\n  \"version\": %u,\n  \"probes\": %u,\n  \"grid\": %s,\n  \"counts\": [%u, %u, %u],\n"
           "  \"origin\": [%s, %s, %s],\n  \"spacing\": [%s, %s, %s],\n  \"sh\": \"%s\",\n"
           "  \"direct\": %s,\n  \"octmap_res\": %u,\n  \"max_distance\": %s,\n  \"depth_unit\": %s,\n"
           "  \"seed\": %llu,\n"
           "  \"scene_hash\": \"%016llx\",\n  \"rays_per_probe\": %u,\n  \"passes\": %u,\n  \"bounces\": %u,\n"
           "  \"indirect\": \"%s\",\n  \"sh_window\": \"%s\",\n  \"sh_window_width\": %s,\n  \"indirect_clamp\": %s,\n"
           "  \"techniques\": [%s],\n  \"relocation_rays\": %u,\n  \"device\": ",
           v->file_version, v->probe_count, v->flags & PB_VOLUME_GRID ? "true" : "false", v->counts[0], v->counts[1],
           v->counts[2], J17(v->origin[0]).s, J17(v->origin[1]).s, J17(v->origin[2]).s, J(v->spacing[0]).s,
           J(v->spacing[1]).s, J(v->spacing[2]).s, kind, v->flags & PB_VOLUME_DIRECT ? "true" : "false", v->octmap_res,
           J(s->max_distance).s, J(v->depth_unit).s, (unsigned long long)s->seed,
           (unsigned long long)s->scene_hash, s->rays_per_probe, s->passes, s->bounces,
           s->indirect_mode ? "volume" : "path", window_name(s->sh_window), J(s->sh_window_width).s,
           J(s->indirect_clamp).s, technique_list(s->techniques, techniques), s->relocation_rays);
    json_string(v->device);
    if (v->flags & PB_VOLUME_SHARD)
        printf(",\n  \"shard\": {\"index\": %u, \"count\": %u, \"first\": %u, \"step\": %u, \"total\": %u}",
               v->shard.index, v->shard.count, v->shard.first, v->shard.step > 1 ? v->shard.step : 1u, v->shard.total);
    if (v->sparse) {
        sparse_census c = census(v);
        printf(",\n  \"sparse\": {\"levels\": %u, \"cells\": [%u, %u, %u], \"bricks\": [%u, %u, %u], "
               "\"probes\": [%u, %u, %u], \"chunk_entries\": %u, \"bytes\": %llu, \"refine_error\": %g, "
               "\"refine_test\": %s, \"test_pass_scale\": %u, \"seam_rounds\": %u, \"seam_error\": %g}",
               v->sparse->levels, v->sparse->cells[0], v->sparse->cells[1], v->sparse->cells[2], c.bricks[0],
               c.bricks[1], c.bricks[2], c.probes[0], c.probes[1], c.probes[2], v->sparse->chunk_count,
               (unsigned long long)pb_volume_file_bytes(v), (double)s->refine_error,
               refine_test_json(s->refine_test), s->test_pass_scale, s->seam_rounds,
               (double)s->seam_error);
    }
    printf(",\n  \"valid\": %u, \"relocated\": %u, \"dilated\": %u, \"outside\": %u, \"converged\": %u, "
           "\"inside\": %u,\n  \"probe_list\": [\n", counts[0], counts[1], counts[2], counts[3], counts[4], counts[5]);
    if (o->has_probe)
        print_probe_json(v, o->probe, 1);
    else
        for (uint32_t i = 0; i < v->probe_count; ++i)
            print_probe_json(v, i, i + 1 == v->probe_count);
    printf("  ]\n}\n");
}

/* --probe I: one probe's position, flags, error and SH */
static void print_probe(const pb_volume *v, uint32_t probe)
{
    const char *kind = volume_kind(v);
    double p[3];
    pb_volume_probe_position(v, probe, p);
    printf("probe %u at (%.6g, %.6g, %.6g), offset (%g, %g, %g), flags ", probe, p[0], p[1], p[2],
           v->offset[3 * probe], v->offset[3 * probe + 1], v->offset[3 * probe + 2]);
    print_flags(v->probe_flags[probe]);
    float se = v->probe_std_error[probe];
    printf("\n%u paths, ", v->probe_paths[probe]);
    if (se == PB_STD_ERROR_UNKNOWN)
        printf("standard error unknown (%s)\n", v->file_version && v->file_version < 3 ? "file older than version 3" : "one pass, or passes around a zero mean");
    else
        printf("relative standard error of its irradiance %.3g %%\n", 100.0 * se);
    printf("%s SH (R G B per coefficient):\n", kind);
    for (int c = 0; c < 9; ++c)
        printf("  %d: %12.6g %12.6g %12.6g\n", c, v->sh[27 * (size_t)probe + 3 * c],
               v->sh[27 * (size_t)probe + 3 * c + 1], v->sh[27 * (size_t)probe + 3 * c + 2]);
}

/* the summary: grid or bricks, shard, flags, content, bake settings, error, times */
static void print_summary(const options *o, const pb_volume *v)
{
    const pb_volume_settings *s = &v->settings;
    const char *kind = volume_kind(v);
    uint32_t counts[6];
    count_flags(v, counts);
    printf("volume      %s (format version %u)\n", o->scene, v->file_version);
    if (v->flags & PB_VOLUME_GRID)
        printf("probes      %u = %u x %u x %u, spacing (%g, %g, %g) m\n", v->probe_count, v->counts[0],
               v->counts[1], v->counts[2], v->spacing[0], v->spacing[1], v->spacing[2]);
    else if (v->sparse) {
        sparse_census c = census(v);
        char seam[64];
        printf("probes      %u in %u bricks (sparse, %u levels, finest spacing (%g, %g, %g) m, %u x %u x %u "
               "coarsest cells)\n", v->probe_count, v->sparse->brick_count, v->sparse->levels, v->spacing[0],
               v->spacing[1], v->spacing[2], v->sparse->cells[0], v->sparse->cells[1], v->sparse->cells[2]);
        for (uint32_t l = 0; l < v->sparse->levels; ++l)
            printf("level %u     spacing %g m: %u bricks, %u probes first used there\n", l,
                   v->spacing[0] * pb_sparse_step(v->sparse->levels, l), c.bricks[l], c.probes[l]);
        printf("bytes       %llu (%u chunk entries)\n", (unsigned long long)pb_volume_file_bytes(v),
               v->sparse->chunk_count);
        if (s->refine_test == 1u + PB_REFINE_TEST_SURFACE)
            printf("refined     where off by more than %g: surface test, its probes at %ux the passes; seam test "
                   "%u rounds%s\n", (double)s->refine_error, s->test_pass_scale, s->seam_rounds,
                   seam_threshold(s, seam));
        else if (s->refine_test == 1u + PB_REFINE_TEST_PROBE)
            printf("refined     where off by more than %g: probe test; seam test %u rounds%s\n",
                   (double)s->refine_error, s->seam_rounds, seam_threshold(s, seam));
        else if (s->refine_error > 0.f)
            printf("refined     where off by more than %g (test not recorded: an older file)\n",
                   (double)s->refine_error);
        else
            printf("refined     not recorded (a file written before it)\n");
    } else
        printf("probes      %u placed points\n", v->probe_count);
    if ((v->flags & PB_VOLUME_SHARD) && v->sparse)
        printf("part        %u of %u: bricks grown from coarsest brick %u on (of %u), undilated, unstitched "
               "(probebake merge joins the parts)\n", v->shard.index, v->shard.count, v->shard.first, v->shard.total);
    else if ((v->flags & PB_VOLUME_SHARD) && v->shard.step > 1)
        printf("part        %u of %u: probes %u, %u, ... every %u of %u, undilated (probebake merge joins the "
               "parts)\n", v->shard.index, v->shard.count, v->shard.first, v->shard.first + v->shard.step, v->shard.step,
               v->shard.total);
    else if (v->flags & PB_VOLUME_SHARD)
        printf("part        %u of %u: probes %u..%u of %u, undilated (probebake merge joins the parts)\n",
               v->shard.index, v->shard.count, v->shard.first, v->shard.first + v->probe_count - 1, v->shard.total);
    char moved_with[48] = "";
    if (s->relocation_rays)
        snprintf(moved_with, sizeof moved_with, " (with %u rays per probe)", s->relocation_rays);
    printf("flags       %u valid, %u relocated%s, %u dilated, %u inside geometry (not traced), %u outside, %u "
           "converged\n", counts[0], counts[1], moved_with, counts[2], counts[5], counts[3], counts[4]);
    printf("content     %s SH L2, direct light %s; depth %ux%u (+1 border) per probe, misses at %g m\n", kind,
           v->flags & PB_VOLUME_DIRECT ? "included" : "excluded", v->octmap_res, v->octmap_res, s->max_distance);
    printf("bake        %u rays x %u passes, %u bounces (indirect %s), probe NEE %s, guiding %s, light cells %s, "
           "emitters by %s, seed %llu, device ", s->rays_per_probe, s->passes, s->bounces,
           s->indirect_mode ? "volume" : "path", s->techniques & PB_TECHNIQUE_PROBE_NEE ? "on" : "off",
           s->techniques & PB_TECHNIQUE_GUIDING ? "on" : "off",
           s->techniques & PB_TECHNIQUE_LIGHT_CELLS ? "on" : "off",
           s->techniques & PB_TECHNIQUE_SOLID_ANGLE ? "solid angle" : "area, if any", (unsigned long long)s->seed);
    cli_fputs_printable(v->device[0] ? v->device : "?", stdout); /* the file's: printable */
    printf("\n");
    if (s->sh_window || s->indirect_clamp > 0.f)
        printf("biased      SH window %s (W %g), indirect clamp %g\n", window_name(s->sh_window),
               s->sh_window_width > 0.f ? s->sh_window_width : 3.f, s->indirect_clamp);
    cli_print_error_summary(stdout, v);
    const pb_volume_timings *t = &v->timings;
    printf("time        load %.3g ms, bvh %.3g ms, upload %.3g ms; GPU trace %.3g ms, sh %.3g ms, depth %.3g ms "
           "(relocation: %.3g ms of trace and sh); %.4g ms total\n", t->load, t->bvh, t->upload, t->trace, t->sh, t->octmap,
           t->relocate, t->total);
}

int cmd_inspect(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a VOLUME file", "inspect");
    pb_volume v;
    pb_error err;
    if (pb_volume_read(o->scene, &v, &err) != PB_OK)
        return cli_fail(&err);
    if (o->has_probe && o->probe >= v.probe_count) {
        fprintf(stderr, "probebake: error: %s: probe %u does not exist (%u probe%s)\n", o->scene, o->probe,
                v.probe_count, cli_plural(v.probe_count));
        pb_volume_free(&v);
        return 1;
    }
    if (write_views(o, &v, &err) != PB_OK) {
        pb_volume_free(&v);
        return cli_fail(&err);
    }
    if (o->json)
        print_json(o, &v);
    else if (o->has_probe)
        print_probe(&v, o->probe);
    else
        print_summary(o, &v);
    pb_volume_free(&v);
    return 0;
}
