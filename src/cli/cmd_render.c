#define _POSIX_C_SOURCE 200809L
/* probebake render: pictures of the scene lit by a volume (probes,
 * indirect), its direct light alone, the path-traced reference, or the
 * relative-error heat map of probes against reference (diff), with the
 * error metrics. */
#include "cli/cli.h"
#include "common/common.h"
#include "render/render_types.h"

#include <math.h>
#include <unistd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int mode_of(const char *m, pb_render_mode *out, int *diff)
{
    *diff = 0;
    if (!strcmp(m, "probes"))
        *out = PB_RENDER_PROBES;
    else if (!strcmp(m, "reference"))
        *out = PB_RENDER_REFERENCE;
    else if (!strcmp(m, "direct"))
        *out = PB_RENDER_DIRECT;
    else if (!strcmp(m, "indirect"))
        *out = PB_RENDER_INDIRECT;
    else if (!strcmp(m, "diff"))
        *out = PB_RENDER_PROBES, *diff = 1;
    else
        return 0;
    return 1;
}

/* "x.png" -> "x.pfm" (or appended when there is no .png) */
static void sibling(const char *path, const char *ext, char *out, size_t n)
{
    snprintf(out, n, "%s", path);
    char *dot = strrchr(out, '.');
    if (dot && !strcmp(dot, ".png"))
        *dot = 0;
    size_t l = strlen(out);
    snprintf(out + l, n - l, "%s", ext);
}

/* The sampler of volume `path` (read into v) in the scene's frame; a volume
 * baked from another scene is a warning, a failure names the file. */
static pb_result sampler_of(const options *o, const char *path, pb_volume *v, const pb_scene *s, pb_sample_volume *sv,
                            pb_error *err)
{
    if (pb_scene_hash(s) != v->settings.scene_hash && !o->log.quiet)
        fprintf(stderr, "probebake: warning: %s was baked from a different scene than %s\n", path, o->scene);
    pb_result r = pb_sample_volume_adopt(v, s->origin, 0.f, 0.f, sv, err);
    if (r != PB_OK) {
        char m[sizeof err->message];
        memcpy(m, err->message, sizeof m);
        snprintf(err->message, sizeof err->message, "%.200s: %.300s", path, m);
    }
    return r;
}

/* Option combinations, refused before any file is read (usage errors, exit 2). */
static int check_combinations(const options *o, const char *mode_name, pb_render_mode mode, int diff)
{
    if (!o->scene)
        return cli_usage_error("%s needs a SCENE", "render");
    if (!o->output)
        return cli_usage_error("%s needs -o IMG.png", "render");
    if ((mode == PB_RENDER_PROBES || mode == PB_RENDER_INDIRECT) && !o->volume)
        return cli_usage_error("--mode %s needs --volume V.probes", mode_name);
    if (o->has_camera && (o->has_eye || o->has_target))
        return cli_usage_error("%s: give --camera or --eye/--target, not both", "render");
    if (o->has_eye != o->has_target)
        return cli_usage_error("%s: --eye and --target go together", "render");
    if (o->pfm && !strcmp(o->output, "-"))
        return cli_usage_error("%s: --pfm writes beside -o FILE; -o - has no file to write beside", "render");
    if (o->reference && !diff)
        return cli_usage_error("%s: --reference REF.pfm is for --mode diff", "render");
    if (o->seams_of && !diff)
        return cli_usage_error("%s: --seams-of SPARSE.probes is for --mode diff", "render");
    if (o->show_probes && !o->volume)
        return cli_usage_error("%s: --show-probes needs --volume V.probes", "render");
    return 0;
}

/* The camera: --eye/--target, else the scene's (--camera, default its
 * first), else *chosen_later = 1 and a view of the bounds' centre from the
 * front, above, which pb_camera_default with the BVH may replace. */
static pb_result camera_from_options(const options *o, const pb_scene *s, pb_camera_view *cam, int *chosen_later,
                                     pb_error *err)
{
    *chosen_later = 0;
    float yfov = (o->fov_deg > 0.f ? o->fov_deg : 50.f) * 0.017453293f;
    if (o->has_eye) {
        double len2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            cam->eye[k] = (float)(o->eye[k] - s->origin[k]);
            cam->forward[k] = (float)(o->target[k] - o->eye[k]);
            cam->up[k] = o->has_up ? (float)o->up[k] : (k == 1 ? 1.f : 0.f);
            len2 += (o->target[k] - o->eye[k]) * (o->target[k] - o->eye[k]);
        }
        if (!(len2 > 0.0)) {
            snprintf(err->message, sizeof err->message, "--eye and --target are the same point: no view direction");
            return err->code = PB_ERROR_INVALID_ARGUMENT;
        }
        /* straight down or up with no --up: +Y cannot be the image's up, so
         * -Z is (a plan view with the scene's far side at the top) */
        if (!o->has_up && fabs(o->target[1] - o->eye[1]) > 0.9999 * sqrt(len2))
            cam->up[0] = 0.f, cam->up[1] = 0.f, cam->up[2] = -1.f;
        cam->yfov = yfov;
    } else if (s->camera_count > 0) {
        if (o->camera >= s->camera_count) {
            snprintf(err->message, sizeof err->message, "%s: camera %u does not exist (%u camera%s)", o->scene,
                     o->camera, s->camera_count, cli_plural(s->camera_count));
            return err->code = PB_ERROR_INVALID_ARGUMENT;
        }
        pb_camera_from_scene(&s->cameras[o->camera], cam);
        if (o->fov_deg > 0.f)
            cam->yfov = yfov;
    } else if (o->has_camera) {
        snprintf(err->message, sizeof err->message, "%s: the scene has no cameras", o->scene);
        return err->code = PB_ERROR_INVALID_ARGUMENT;
    } else {
        pb_camera_default(s, NULL, yfov, 1, 1, cam); /* from outside, until the BVH can tell */
        *chosen_later = 1;
    }
    return PB_OK;
}

/* --mode diff's measurements: the probe image against the reference, on
 * the whole image, its indirect part, its non-emissive surfaces, and for a
 * sparse volume where its levels meet, elsewhere and per level. */
typedef struct diff_metrics {
    double rmse, rmse_indirect; /* NaN indirect: a given reference has no direct part to take away */
    double ms_ref;
    uint32_t ref_spp;
    pb_image_metrics surf, seams, off_seams, at_level[PB_SPARSE_MAX_LEVELS];
    uint64_t unserved;
    uint32_t levels; /* 0: no sparse volume, so no seams */
} diff_metrics;

/* The diff of `img` (probes, rendered with d): the reference rendered
 * unless `ref` was read from --reference, the direct image subtracted from
 * both for the indirect metric (img_direct, ref_direct: scratch of the
 * image's size), the heat map into rgb8. */
static pb_result measure_diff(const options *o, pb_context *ctx, const pb_scene *s, pb_gpu_scene *gs,
                              const pb_bvh *bvh, const pb_render_desc *d, const pb_volume *mv,
                              const pb_sample_volume *msv, const float *img, float *img_direct, float *ref,
                              float *ref_direct, unsigned char *rgb8, diff_metrics *m, pb_error *err)
{
    uint64_t pixels = (uint64_t)d->width * d->height;
    memset(m, 0, sizeof *m);
    m->levels = msv->levels > 0 && mv->sparse ? mv->sparse->levels : 0;
    pb_render_desc dr = *d;
    dr.mode = PB_RENDER_REFERENCE;
    dr.spp = m->ref_spp = o->has_spp ? o->spp * 16 : 256;
    if (!o->reference && pb_render(ctx, s, gs, &dr, ref, ref_direct, &m->ms_ref, err) != PB_OK)
        return err->code;
    if (o->reference) /* coverage is the camera's: the probe image's (a PFM has no alpha) */
        for (uint64_t i = 0; i < pixels; ++i)
            ref[4 * i + 3] = img[4 * i + 3];
    pb_render_desc dd = *d;
    dd.mode = PB_RENDER_DIRECT;
    float *direct_img = malloc(pixels * 16);
    uint8_t *cls = malloc(pixels);
    uint8_t *seam = m->levels ? malloc(pixels) : NULL, *level = m->levels ? malloc(pixels) : NULL;
    pb_result r = PB_OK;
    if (!direct_img || !cls || (m->levels && (!seam || !level))) {
        snprintf(err->message, sizeof err->message, "out of host memory for a %ux%u image", d->width, d->height);
        r = err->code = PB_ERROR_OUT_OF_HOST_MEMORY;
    } else {
        r = pb_render(ctx, s, gs, &dd, direct_img, NULL, NULL, err);
    }
    if (r == PB_OK) {
        m->rmse = pb_image_relative_rmse(img, ref, d->width, d->height);
        pb_render_pixel_classes(s, bvh, d, cls);
        pb_image_surface_metrics(img, ref, cls, d->width, d->height, &m->surf);
        if (m->levels) {
            pb_render_seam_pixels(s, bvh, d, msv, mv->sparse, cls, seam, level);
            pb_image_surface_metrics_where(img, ref, cls, seam, PB_SEAM_LEVELS, d->width, d->height, &m->seams);
            pb_image_surface_metrics_where(img, ref, cls, seam, PB_SEAM_NONE, d->width, d->height, &m->off_seams);
            for (uint32_t l = 0; l < m->levels && l < PB_SPARSE_MAX_LEVELS; ++l)
                pb_image_surface_metrics_where(img, ref, cls, level, (uint8_t)l, d->width, d->height, &m->at_level[l]);
            for (uint64_t i = 0; i < pixels; ++i)
                m->unserved += seam[i] == PB_SEAM_UNSERVED;
        }
        /* a given reference comes without its direct part (ref_direct was never written): no indirect metric */
        for (uint64_t i = 0; !o->reference && i < pixels; ++i) {
            for (int c = 0; c < 3; ++c) {
                img_direct[4 * i + c] = img[4 * i + c] - direct_img[4 * i + c]; /* probes: indirect part */
                ref_direct[4 * i + c] = ref[4 * i + c] - ref_direct[4 * i + c]; /* reference: indirect part */
            }
            img_direct[4 * i + 3] = img[4 * i + 3], ref_direct[4 * i + 3] = ref[4 * i + 3];
        }
        m->rmse_indirect = o->reference ? NAN : pb_image_relative_rmse(img_direct, ref_direct, d->width, d->height);
        pb_error_heatmap(img, ref, d->width, d->height, 0.5f, rgb8);
    }
    free(direct_img), free(cls), free(seam), free(level);
    return r;
}

static void print_json(FILE *report, const options *o, const char *mode_name, const pb_render_desc *d, uint32_t spp,
                       double ms, const diff_metrics *m)
{
    fprintf(report, "{\"image\": \"%s\", \"mode\": \"%s\", \"width\": %u, \"height\": %u, \"spp\": %u, \"gpu_ms\": %.3f",
            o->output, mode_name, d->width, d->height, spp, ms);
    if (m) {
        char ind[32] = "null";
        if (!o->reference)
            snprintf(ind, sizeof ind, "%.6f", m->rmse_indirect);
        if (o->reference)
            fprintf(report, ", \"reference\": \"%s\"", o->reference);
        else
            fprintf(report, ", \"reference_spp\": %u, \"reference_gpu_ms\": %.3f", m->ref_spp, m->ms_ref);
        fprintf(report, ", \"relative_rmse\": %.6f, \"relative_rmse_indirect\": %s, \"relative_rmse_surfaces\": %.6f, "
                "\"p95_relative_error\": %.6f, \"surface_pixels\": %llu",
                m->rmse, ind, m->surf.relative_rmse, m->surf.p95_relative, (unsigned long long)m->surf.pixels);
        if (m->levels) {
            fprintf(report, ", \"seam_pixels\": %llu, \"relative_rmse_seams\": %.6f, \"p95_relative_error_seams\": %.6f, "
                    "\"off_seam_pixels\": %llu, \"relative_rmse_off_seams\": %.6f, \"p95_relative_error_off_seams\": %.6f, "
                    "\"unserved_pixels\": %llu",
                    (unsigned long long)m->seams.pixels, m->seams.relative_rmse, m->seams.p95_relative,
                    (unsigned long long)m->off_seams.pixels, m->off_seams.relative_rmse, m->off_seams.p95_relative,
                    (unsigned long long)m->unserved);
            fprintf(report, ", \"levels\": ["); /* where the error sits: the pixels each level serves */
            for (uint32_t l = 0; l < m->levels && l < PB_SPARSE_MAX_LEVELS; ++l)
                fprintf(report, "%s{\"level\": %u, \"pixels\": %llu, \"relative_rmse\": %.6f, "
                        "\"p95_relative_error\": %.6f}", l ? ", " : "", l, (unsigned long long)m->at_level[l].pixels,
                        m->at_level[l].relative_rmse, m->at_level[l].p95_relative);
            fprintf(report, "]");
        }
    }
    fprintf(report, "}\n");
}

static void print_text(FILE *report, const options *o, const char *mode_name, const pb_render_desc *d, uint32_t spp,
                       double ms, const diff_metrics *m)
{
    fprintf(report, "wrote %s: %ux%u, %s, %u spp, GPU %.0f ms\n", o->output, d->width, d->height, mode_name, spp, ms);
    if (!m)
        return;
    if (o->reference)
        fprintf(report, "probes vs %s: relative RMSE %.4f of the image; non-emissive surfaces (%llu pixels): "
                "relative RMSE %.4f, p95 per-pixel error %.4f; heat map: black 0, red >= 50 %%\n",
                o->reference, m->rmse, (unsigned long long)m->surf.pixels, m->surf.relative_rmse, m->surf.p95_relative);
    else
        fprintf(report, "probes vs reference (%u spp, GPU %.0f ms): relative RMSE %.4f of the image, %.4f of the indirect "
                "light; non-emissive surfaces (%llu pixels): relative RMSE %.4f, p95 per-pixel error %.4f; heat map: "
                "black 0, red >= 50 %%\n",
                m->ref_spp, m->ms_ref, m->rmse, m->rmse_indirect, (unsigned long long)m->surf.pixels,
                m->surf.relative_rmse, m->surf.p95_relative);
    if (m->levels)
        fprintf(report, "where levels meet (%llu pixels): relative RMSE %.4f, p95 %.4f; elsewhere (%llu): %.4f, p95 "
                "%.4f; %llu surface pixels served by no brick\n", (unsigned long long)m->seams.pixels,
                m->seams.relative_rmse, m->seams.p95_relative, (unsigned long long)m->off_seams.pixels,
                m->off_seams.relative_rmse, m->off_seams.p95_relative, (unsigned long long)m->unserved);
    for (uint32_t l = 0; l < m->levels && l < PB_SPARSE_MAX_LEVELS; ++l)
        fprintf(report, "%s level %u: %llu pixels, relative RMSE %.4f, p95 %.4f%s", l ? ";" : "served by", l,
                (unsigned long long)m->at_level[l].pixels, m->at_level[l].relative_rmse, m->at_level[l].p95_relative,
                l + 1 == m->levels ? "\n" : "");
}

int cmd_render(const options *o)
{
    pb_render_mode mode;
    int diff;
    const char *mode_name = o->mode ? o->mode : (o->volume ? "probes" : "reference");
    if (!mode_of(mode_name, &mode, &diff))
        return cli_usage_error("--mode '%s': use probes, reference, direct, indirect or diff", mode_name);
    int usage = check_combinations(o, mode_name, mode, diff);
    if (usage)
        return usage;
    char pfm[1100];
    sibling(o->output, ".pfm", pfm, sizeof pfm);
    pb_log log = {cli_log_to_stderr, (void *)&o->log};
    pb_scene_desc sd = {log, 0};
    sd.face_normals = (uint32_t)o->face_normals;
    sd.no_normal_maps = (uint32_t)o->no_normal_maps;
    pb_scene *s = NULL;
    pb_bvh *bvh = NULL;
    pb_context *ctx = NULL;
    pb_gpu_scene *gs = NULL;
    /* the volume lit by, and --seams-of's, whose seams and levels the diff measures */
    pb_volume vol = {0}, seams_vol = {0};
    pb_sample_volume sv = {0}, seams_sv = {0};
    pb_sample_buffers volume_buffers = {0};
    pb_environment env = {0};
    pb_error err = {0};
    float *img = NULL, *img_direct = NULL, *ref = NULL, *ref_direct = NULL;
    unsigned char *rgb8 = NULL;
    int rc = 1;
    uint32_t width = o->width ? o->width : 640, height = o->height ? o->height : 480;
    /* outputs checked before any work: not a directory, writable, no input */
    const char *inputs[5] = {o->scene, o->env, o->volume, o->reference, o->seams_of};
    if (pb_output_check(o->output, inputs, 5, &err) != PB_OK || (o->pfm && pb_output_check(pfm, inputs, 5, &err) != PB_OK))
        goto out;
    /* the device next: one that matches nothing is said before large files are read */
    pb_context_desc cd = cli_context_desc(o, o->device, log);
    if (cli_context_create(&cd, "--device", &ctx, &err) != PB_OK)
        goto out;
    if (o->volume && pb_volume_read(o->volume, &vol, &err) != PB_OK)
        goto out;
    if (o->seams_of && pb_volume_read(o->seams_of, &seams_vol, &err) != PB_OK)
        goto out;
    if (o->seams_of && !seams_vol.sparse) {
        snprintf(err.message, sizeof err.message, "%s: not a sparse volume: it has no seams (--seams-of)", o->seams_of);
        err.code = PB_ERROR_INVALID_ARGUMENT;
        goto out;
    }
    if (o->reference) { /* a converged reference, read and checked before any device work */
        uint32_t rw = 0, rh = 0;
        if (pb_read_pfm(o->reference, &ref, &rw, &rh, &err) != PB_OK)
            goto out;
        if (rw != width || rh != height) {
            snprintf(err.message, sizeof err.message, "%s: the reference is %ux%u, the render %ux%u (--size)",
                     o->reference, rw, rh, width, height);
            err.code = PB_ERROR_INVALID_ARGUMENT;
            goto out;
        }
    }
    if (cli_environment(o, &env, &err) != PB_OK)
        goto out;
    if (pb_scene_load(o->scene, &sd, &s, &err) != PB_OK ||
        pb_bake_check_light(s, o->sky, o->env ? &env : NULL, &err) != PB_OK)
        goto out;
    if ((o->volume && sampler_of(o, o->volume, &vol, s, &sv, &err) != PB_OK) ||
        (o->seams_of && sampler_of(o, o->seams_of, &seams_vol, s, &seams_sv, &err) != PB_OK))
        goto out;
    /* the samplers hold the probes now (their SH and depth taken over, not
     * copied); the volumes' headers and sparse layouts stay (a million probes:
     * 1.4 GB less beside the samplers and the device's copy) */
    pb_volume_free_probes(&vol);
    pb_volume_free_probes(&seams_vol);
    pb_render_desc d = {0};
    d.width = width;
    d.height = height;
    d.mode = mode;
    /* a diff's probe image: 16 samples per pixel unless told (its own noise
     * stays out of the metric: the reference has 16x more) */
    d.spp = o->has_spp ? o->spp : (diff ? 16u : 0u);
    /* with a volume of N bounces, the matching reference traces N + 1 after the first hit (the volume's
     * light reflects once more at the surface); without one, 8 */
    d.bounces = o->has_bounces ? o->bounces : (o->volume ? vol.settings.bounces + 1 : 8);
    d.seed = o->has_seed ? o->seed : 1;
    d.emitters_by_area = (uint32_t)o->emitters_by_area;
    d.volume = o->volume ? &sv : NULL;
    d.volume_direct = (vol.flags & PB_VOLUME_DIRECT) != 0;
    memcpy(d.sky, o->sky, sizeof d.sky);
    d.environment = o->env ? &env : NULL;
    d.show_probes = (uint32_t)o->show_probes;
    int default_view;
    if (camera_from_options(o, s, &d.camera, &default_view, &err) != PB_OK)
        goto out;
    if (pb_render_check(&d, &err) != PB_OK) /* before any device work */
        goto out;
    if (pb_bvh_build(s, NULL, &bvh, &err) != PB_OK)
        goto out;
    if (default_view) { /* no camera: from outside, or from inside where outside shows only walls' backs */
        pb_camera_default(s, bvh, d.camera.yfov, width, height, &d.camera);
        if (!o->log.quiet)
            fprintf(stderr, "probebake: info: %s has no camera: seen from (%.3g, %.3g, %.3g) towards (%.2f, %.2f, %.2f) "
                    "(--eye and --target choose)\n", o->scene, d.camera.eye[0] + s->origin[0],
                    d.camera.eye[1] + s->origin[1], d.camera.eye[2] + s->origin[2], d.camera.forward[0],
                    d.camera.forward[1], d.camera.forward[2]);
    }
    if (pb_gpu_scene_create(ctx, s, bvh, &gs, &err) != PB_OK)
        goto out;
    /* the volume on the device once for every render below; the host keeps
     * only what the seam metric reads (the layout), not its SH and depth */
    if (d.volume && pb_render_reads_volume(&d)) {
        if (pb_sample_upload(ctx, &sv, &volume_buffers, &err) != PB_OK)
            goto out;
        d.volume_buffers = &volume_buffers;
        free(sv.sh), free(sv.depth);
        sv.sh = NULL, sv.depth = NULL;
    }
    uint64_t pixels = (uint64_t)d.width * d.height;
    img = malloc(pixels * 16), img_direct = malloc(pixels * 16), rgb8 = malloc(pixels * 3);
    if (diff && !ref)
        ref = malloc(pixels * 16);
    if (diff)
        ref_direct = malloc(pixels * 16);
    if (!img || !img_direct || !rgb8 || (diff && (!ref || !ref_direct))) {
        snprintf(err.message, sizeof err.message, "out of host memory for a %ux%u image", d.width, d.height);
        goto out;
    }
    double ms = 0;
    uint32_t spp = d.spp ? d.spp : (mode == PB_RENDER_REFERENCE ? 64 : 1);
    cli_progress_state ps = {isatty(2) && !o->log.quiet, cli_now_ms(), pixels * spp};
    d.progress = cli_progress;
    d.progress_user = &ps;
    cli_defer_signals(); /* from here a signal cancels the render; no image is written */
    pb_result rr = pb_render(ctx, s, gs, &d, img, img_direct, &ms, &err);
    if (ps.show)
        fprintf(stderr, "\n");
    if (rr != PB_OK)
        goto out;
    diff_metrics m;
    if (diff) {
        if (measure_diff(o, ctx, s, gs, bvh, &d, o->seams_of ? &seams_vol : &vol, o->seams_of ? &seams_sv : &sv, img,
                         img_direct, ref, ref_direct, rgb8, &m, &err) != PB_OK)
            goto out;
    } else {
        float ev = o->has_exposure ? o->exposure : pb_auto_exposure(img, d.width, d.height);
        pb_tonemap_image(img, d.width, d.height, ev, rgb8);
    }
    if (o->validation && pb_context_validation_messages(ctx)) {
        snprintf(err.message, sizeof err.message, "%u Vulkan validation messages", pb_context_validation_messages(ctx));
        goto out;
    }
    if (cli_interrupted(NULL)) { /* images are written in one short call: cancel before it */
        err.code = PB_ERROR_CANCELLED;
        snprintf(err.message, sizeof err.message, "cancelled; no image written");
        goto out;
    }
    if (o->pfm && pb_write_pfm(pfm, img, d.width, d.height, &err) != PB_OK)
        goto out;
    if (pb_write_png(o->output, rgb8, d.width, d.height, &err) != PB_OK) {
        if (o->pfm) /* not half of the pair: the linear image written just before goes too */
            remove(pfm);
        goto out;
    }
    FILE *report = strcmp(o->output, "-") ? stdout : stderr; /* stdout carries the image for -o - */
    if (o->json)
        print_json(report, o, mode_name, &d, spp, ms, diff ? &m : NULL);
    else
        print_text(report, o, mode_name, &d, spp, ms, diff ? &m : NULL);
    rc = 0;
out:
    free(img), free(img_direct), free(ref), free(ref_direct), free(rgb8);
    pb_sample_volume_free(&sv);
    pb_volume_free(&vol);
    pb_sample_volume_free(&seams_sv);
    pb_volume_free(&seams_vol);
    pb_environment_free(&env);
    if (ctx)
        pb_sample_release(ctx, &volume_buffers);
    pb_gpu_scene_destroy(gs);
    pb_context_destroy(ctx);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    return rc ? cli_fail(&err) : 0;
}
