#define _POSIX_C_SOURCE 200809L
/* probebake command line: devices, info, trace. Every failure prints one
 * line "probebake: error: FILE: problem" to stderr and exits non-zero. */
#include "cli/cli.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>



void cli_log_to_stderr(pb_log_level level, const char *msg, void *user)
{
    const cli_log *l = user;
    if (level == PB_LOG_DEBUG && !l->verbose)
        return;
    if (level <= PB_LOG_INFO && l->quiet)
        return;
    static const char *const names[] = {"debug", "info", "warning", "error"};
    fprintf(stderr, "probebake: %s: %s\n", names[level], msg);
}

double cli_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static volatile sig_atomic_t interrupted, deferring; /* see on_signal */

int cli_fail(const pb_error *err)
{
    fprintf(stderr, "probebake: error: %s\n", err->message[0] ? err->message : pb_result_name(err->code));
    /* 128 + the signal, as shells report it (SIGINT 130, SIGTERM 143) */
    return err->code == PB_ERROR_CANCELLED ? 128 + (interrupted ? (int)interrupted : SIGINT) : 1;
}

int cli_parse_floats(const char *s, int n, float *out)
{
    for (int k = 0; k < n; ++k) {
        char *end = NULL;
        double v = strtod(s, &end);
        if (end == s || !isfinite(v))
            return 0;
        out[k] = (float)v;
        if (k + 1 < n) {
            if (*end != ',')
                return 0;
            s = end + 1;
        } else if (*end) {
            return 0;
        }
    }
    return 1;
}

void cli_fault_injection(pb_context_desc *cd)
{
    const char *f = getenv("PB_INJECT_FAULT");
    unsigned n = 0;
    if (!f)
        return;
    if (sscanf(f, "allocation:%u", &n) == 1)
        cd->fail_allocation = n;
    else if (sscanf(f, "submission:%u", &n) == 1)
        cd->fail_submission = n;
}

pb_result cli_environment(const options *o, pb_environment *env, pb_error *err)
{
    memset(env, 0, sizeof *env);
    if (o->env && o->has_sky) {
        snprintf(err->message, sizeof err->message, "--sky and --env both give the environment: choose one");
        return err->code = PB_ERROR_INVALID_ARGUMENT;
    }
    return o->env ? pb_environment_load(o->env, o->env_intensity, o->env_rotation, env, err) : PB_OK;
}

int cli_usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "probebake: error: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, " (see probebake --help)\n");
    return 2;
}

static void print_help(void)
{
    printf("probebake %s - light probe volume baker (glTF 2.0 -> SH L2 + depth octmaps, Vulkan compute)\n\n"
           "usage:\n"
           "  probebake devices [--json]              list Vulkan devices\n"
           "  probebake info SCENE [--json]           scene summary: triangles kept/dropped, materials,\n"
           "                                          textures, lights, cameras, bounds\n"
           "  probebake trace SCENE [options]         trace probe-style rays on the device and report\n"
           "                                          throughput; --verify compares with the CPU reference\n"
           "  probebake bake SCENE -o OUT.probes [bake options]\n"
           "                                          bake a probe volume (irradiance SH L2 + depth octmaps)\n"
           "  probebake inspect VOLUME [--json] [--probe I] [--atlas A.png] [--sh-view S.png]\n"
           "                                          summary of a probe volume file; --json adds every\n"
           "                                          probe (position, flags, 27 irradiance SH coefficients)\n"
           "  probebake render SCENE -o IMG.png [--volume V.probes] [render options]\n"
           "                                          render the scene lit by a volume, or path traced\n"
           "  probebake export VOLUME --textures DIR  the volume as textures a web or game engine loads\n"
           "                                          (KTX2 + manifest.json; docs/format.md)\n"
           "  probebake --help | --version\n\n"
           "options:\n"
           "  --device INDEX|NAME     pick a device (default: discrete > integrated > virtual > CPU)\n"
           "  --validation            enable the Vulkan validation layer (fail on any message)\n"
           "  --probes N              probes in the grid over the scene bounds (trace; default 4096)\n"
           "  --rays N                rays per probe (trace; default 256)\n"
           "  --seed S                random seed (default 1)\n"
           "  --verify                trace on the CPU too and compare hit by hit\n"
           "  --json                  machine-readable output (devices, info, inspect)\n"
           "  --probe I               inspect: only probe I\n"
           "  --verbose, --quiet      more or fewer messages on stderr\n\n"
           "bake options (defaults printed when baking):\n"
           "  --spacing M | --counts X,Y,Z   probe grid (default: about 2048 probes over the bounds)\n"
           "  --bounds x0,y0,z0,x1,y1,z1     grid box in scene coordinates (default: scene bounds)\n"
           "  --rays N  --passes N  --bounces N  --octmap-res N  --seed S\n"
           "  --quality preview|production|reference   rays, passes, target error and estimators for\n"
           "                                 the use (printed; explicit options override it): preview\n"
           "                                 128 x 2 passes; production until 2 %% (at most 256 passes);\n"
           "                                 reference until 0.25 %% (at most 4096 passes)\n"
           "  --target-error E                trace each probe until the standard error of its irradiance\n"
           "                                 along every axis is below E x its value (at least 4, at most\n"
           "                                 --passes passes)\n"
           "  --points FILE.json             probes at given positions instead of a grid:\n"
           "                                 {\"spacing\": S, \"points\": [[x,y,z] | {\"id\": I, \"position\": [x,y,z]}]}\n"
           "  --sky R,G,B                    uniform sky radiance (default black)\n"
           "  --env FILE.hdr                 equirectangular Radiance environment map instead of --sky\n"
           "  --env-intensity K              scale of the map (default 1)\n"
           "  --env-rotation DEG             turn the map about +Y, counter-clockwise from above (default 0)\n"
           "  --direct include|exclude       light straight from lights, emitters and sky (default include)\n"
           "  --probe-nee on|off             emitters and sky a probe sees are also sampled from the probe\n"
           "                                 and MIS-combined with its rays (unbiased; default on)\n"
           "  --guide on|off                 path guiding: bounces drawn toward where light was found by\n"
           "                                 training paths from the surfaces (unbiased; default off, on\n"
           "                                 in the production and reference presets)\n"
           "  --light-cells on|off           emitters drawn per region of space by the light shadow rays\n"
           "                                 measured there, mixed with power (unbiased; default on)\n"
           "  --sh-window none|hanning[:W]|lanczos[:W]   taper SH bands against ringing (default none; W 3)\n"
           "  --max-lights-per-hit N         above N punctual lights, each hit draws one by power (default 8)\n"
           "  --clamp-indirect X             clamp each reflected-light path contribution to radiance X\n"
           "                                 (against fireflies; biased, off by default)\n"
           "  --indirect path|volume         indirect light path traced (default, unbiased) or, per bounce, from\n"
           "                                 the previous bounce's volume through the run-time sampler (fast, biased)\n"
           "render options:\n"
           "  --mode probes|reference|direct|indirect|diff   (default probes with --volume, else reference)\n"
           "  --camera I | --eye x,y,z --target x,y,z [--up x,y,z] [--fov DEG]   (default: glTF camera 0)\n"
           "  --size WxH (default 640x480)  --spp N  --bounces N (reference, default 8)  --seed S\n"
           "  --exposure EV|auto (default auto)  --pfm (linear image beside the PNG)  --json (metrics)\n"
           "  --show-probes   draw the volume's probes: spheres lit by their SH, invalid red, grid homes grey\n"
           "  --sky R,G,B | --env FILE.hdr [...]   the environment, as for bake\n",
           PB_VERSION_STRING);
}



static int parse_u32(const char *s, uint32_t lo, uint32_t hi, uint32_t *out)
{
    char *end = NULL;
    unsigned long long v = strtoull(s, &end, 10);
    if (!s[0] || *end || s[0] == '-' || v < lo || v > hi)
        return 0;
    *out = (uint32_t)v;
    return 1;
}

static int parse(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->probes = 4096;
    o->rays = 256;
    o->seed = 1;
    o->env_intensity = 1.f;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            print_help();
            exit(0);
        } else if (!strcmp(a, "--version")) {
            printf("probebake %s\n", PB_VERSION_STRING);
            exit(0);
        } else if (!strcmp(a, "--json")) {
            o->json = 1;
        } else if (!strcmp(a, "--validation")) {
            o->validation = 1;
        } else if (!strcmp(a, "--verify")) {
            o->verify = 1;
        } else if (!strcmp(a, "--verbose")) {
            o->log.verbose = 1;
        } else if (!strcmp(a, "--quiet")) {
            o->log.quiet = 1;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (!next)
                return cli_usage_error("%s needs a file name", a);
            o->output = argv[++i];
        } else if (!strcmp(a, "--textures")) {
            if (!next)
                return cli_usage_error("%s needs a directory", a);
            o->textures = argv[++i];
        } else if (!strcmp(a, "--points")) {
            if (!next)
                return cli_usage_error("%s needs a points file (JSON)", a);
            o->points = argv[++i];
        } else if (!strcmp(a, "--quality")) {
            if (!next || !pb_bake_quality_find(next))
                return cli_usage_error("%s takes preview, production or reference", a);
            o->quality = argv[++i];
        } else if (!strcmp(a, "--guide") || !strcmp(a, "--probe-nee") || !strcmp(a, "--light-cells")) {
            if (!next || (strcmp(next, "on") && strcmp(next, "off")))
                return cli_usage_error("%s takes on or off", a);
            *(!strcmp(a, "--guide") ? &o->guide : !strcmp(a, "--probe-nee") ? &o->probe_nee : &o->light_cells) =
                argv[++i];
        } else if (!strcmp(a, "--direct")) {
            if (!next || (strcmp(next, "include") && strcmp(next, "exclude")))
                return cli_usage_error("%s takes include or exclude", a);
            o->direct = argv[++i];
        } else if (!strcmp(a, "--volume") || !strcmp(a, "--mode")) {
            if (!next)
                return cli_usage_error("%s needs a value", a);
            *(!strcmp(a, "--volume") ? &o->volume : &o->mode) = argv[++i];
        } else if (!strcmp(a, "--eye") || !strcmp(a, "--target") || !strcmp(a, "--up")) {
            float *dst = !strcmp(a, "--eye") ? o->eye : !strcmp(a, "--target") ? o->target : o->up;
            if (!next || !cli_parse_floats(next, 3, dst)) {
                fprintf(stderr, "probebake: error: %s '%s' is not three comma-separated finite numbers\n", a,
                        next ? next : "");
                return 2;
            }
            *(dst == o->eye ? &o->has_eye : dst == o->target ? &o->has_target : &o->has_up) = 1;
            ++i;
        } else if (!strcmp(a, "--fov") || !strcmp(a, "--exposure")) {
            int fov = !strcmp(a, "--fov");
            char *end = NULL;
            float v = next ? strtof(next, &end) : NAN;
            if (!fov && next && !strcmp(next, "auto")) {
                ++i;
                continue;
            }
            if (!next || *end || !isfinite(v) || (fov && !(v > 0.f && v < 180.f)) || (!fov && fabsf(v) > 64.f)) {
                fprintf(stderr, "probebake: error: %s '%s' is not %s\n", a, next ? next : "",
                        fov ? "a vertical field of view in degrees in (0, 180)" : "'auto' or an exposure in EV (-64..64)");
                return 2;
            }
            if (fov)
                o->fov_deg = v;
            else
                o->exposure = v, o->has_exposure = 1;
            ++i;
        } else if (!strcmp(a, "--size")) {
            unsigned w = 0, h = 0;
            char c = 0;
            if (!next || sscanf(next, "%ux%u%c", &w, &h, &c) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384) {
                fprintf(stderr, "probebake: error: --size '%s' is not WxH with each side 1..16384\n", next ? next : "");
                return 2;
            }
            o->width = w, o->height = h;
            ++i;
        } else if (!strcmp(a, "--camera") || !strcmp(a, "--spp")) {
            int cam = !strcmp(a, "--camera");
            if (!next || !parse_u32(next, cam ? 0 : 1, cam ? 1000000 : 65536, cam ? &o->camera : &o->spp)) {
                fprintf(stderr, "probebake: error: %s '%s' is not %s\n", a, next ? next : "",
                        cam ? "a camera index" : "an integer in [1, 65536]");
                return 2;
            }
            *(cam ? &o->has_camera : &o->has_spp) = 1;
            ++i;
        } else if (!strcmp(a, "--atlas") || !strcmp(a, "--sh-view")) {
            if (!next)
                return cli_usage_error("%s needs a PNG path", a);
            *(!strcmp(a, "--atlas") ? &o->atlas : &o->sh_view) = argv[++i];
        } else if (!strcmp(a, "--pfm")) {
            o->pfm = 1;
        } else if (!strcmp(a, "--show-probes")) {
            o->show_probes = 1;
        } else if (!strcmp(a, "--env")) {
            if (!next)
                return cli_usage_error("%s needs a .hdr file", a);
            o->env = argv[++i];
        } else if (!strcmp(a, "--max-lights-per-hit")) {
            if (!next || !parse_u32(next, 1, 1u << 20, &o->max_lights_per_hit)) {
                fprintf(stderr, "probebake: error: --max-lights-per-hit '%s' is not an integer in [1, 1048576]\n",
                        next ? next : "");
                return 2;
            }
            ++i;
        } else if (!strcmp(a, "--clamp-indirect")) {
            char *end = NULL;
            float v = next ? strtof(next, &end) : NAN;
            if (!next || *end || !(v > 0.f) || !isfinite(v)) {
                fprintf(stderr, "probebake: error: --clamp-indirect '%s' is not a positive radiance\n", next ? next : "");
                return 2;
            }
            o->indirect_clamp = v;
            ++i;
        } else if (!strcmp(a, "--sh-window")) {
            char kind[16] = {0};
            float w = 0.f;
            int got = next ? sscanf(next, "%15[a-z]:%f", kind, &w) : 0;
            o->sh_window = !strcmp(kind, "hanning") ? 1u : !strcmp(kind, "lanczos") ? 2u : 0u;
            if (got < 1 || (strcmp(kind, "none") && !o->sh_window) || (got == 2 && !(w > 0.f && w <= 1000.f))) {
                fprintf(stderr, "probebake: error: --sh-window '%s': use none, hanning[:W] or lanczos[:W] "
                                "with W in (0, 1000]\n", next ? next : "");
                return 2;
            }
            o->sh_window_width = got == 2 ? w : 0.f;
            ++i;
        } else if (!strcmp(a, "--indirect")) {
            if (!next || (strcmp(next, "path") && strcmp(next, "volume")))
                return cli_usage_error("%s takes path or volume", a);
            o->indirect_volume = !strcmp(next, "volume");
            ++i;
        } else if (!strcmp(a, "--env-intensity") || !strcmp(a, "--env-rotation")) {
            char *end = NULL;
            float v = next ? strtof(next, &end) : NAN;
            int intensity = !strcmp(a, "--env-intensity");
            if (!next || *end || !isfinite(v) || (intensity && v < 0.f) || (!intensity && fabsf(v) > 36000.f)) {
                fprintf(stderr, "probebake: error: %s '%s' is not %s\n", a, next ? next : "",
                        intensity ? "a finite scale >= 0" : "an angle in degrees");
                return 2;
            }
            *(intensity ? &o->env_intensity : &o->env_rotation) = v;
            ++i;
        } else if (!strcmp(a, "--target-error")) {
            char *end = NULL;
            o->target_error = next ? strtof(next, &end) : -1.f;
            if (!next || *end || !(o->target_error > 0.f && o->target_error < 1.f)) {
                fprintf(stderr, "probebake: error: --target-error '%s' is not a relative error in (0, 1)\n",
                        next ? next : "");
                return 2;
            }
            ++i;
        } else if (!strcmp(a, "--spacing")) {
            char *end = NULL;
            o->spacing = next ? strtof(next, &end) : 0.f;
            if (!next || *end || !(o->spacing > 0.f) || !isfinite(o->spacing)) {
                fprintf(stderr, "probebake: error: --spacing '%s' is not a positive length in metres\n",
                        next ? next : "");
                return 2;
            }
            o->has_spacing = 1;
            ++i;
        } else if (!strcmp(a, "--counts") || !strcmp(a, "--sky") || !strcmp(a, "--bounds")) {
            int want = !strcmp(a, "--bounds") ? 6 : 3, got = 0;
            double vals[6];
            const char *c = next;
            while (c && got < want) {
                char *end = NULL;
                vals[got] = strtod(c, &end);
                if (end == c || !isfinite(vals[got]))
                    break;
                ++got;
                c = *end == ',' ? end + 1 : (*end ? NULL : end);
                if (c && !*c)
                    break;
            }
            if (!next || got != want || (c && *c)) {
                fprintf(stderr, "probebake: error: %s needs %d comma-separated numbers, got '%s'\n", a, want,
                        next ? next : "");
                return 2;
            }
            if (!strcmp(a, "--counts")) {
                for (int k = 0; k < 3; ++k) {
                    if (!(vals[k] >= 1 && vals[k] <= 65536 && vals[k] == floor(vals[k]))) {
                        fprintf(stderr, "probebake: error: --counts '%s': each count must be an integer in 1..65536\n",
                                next);
                        return 2;
                    }
                    o->counts[k] = (uint32_t)vals[k];
                }
                o->has_counts = 1;
            } else if (!strcmp(a, "--sky")) {
                for (int k = 0; k < 3; ++k) {
                    if (!(vals[k] >= 0)) {
                        fprintf(stderr, "probebake: error: --sky '%s': radiance must be >= 0\n", next);
                        return 2;
                    }
                    o->sky[k] = (float)vals[k];
                }
                o->has_sky = 1;
            } else {
                for (int k = 0; k < 6; ++k)
                    o->bounds[k] = (float)vals[k];
                if (!(vals[3] > vals[0] && vals[4] > vals[1] && vals[5] > vals[2])) {
                    fprintf(stderr, "probebake: error: --bounds '%s': need x0,y0,z0,x1,y1,z1 with x1>x0, y1>y0, z1>z0\n",
                            next);
                    return 2;
                }
                o->has_bounds = 1;
            }
            ++i;
        } else if (!strcmp(a, "--passes") || !strcmp(a, "--bounces") || !strcmp(a, "--octmap-res")) {
            uint32_t *dst = !strcmp(a, "--passes") ? &o->passes : !strcmp(a, "--bounces") ? &o->bounces : &o->octmap_res;
            uint32_t lo = dst == &o->bounces ? 0 : 1, hi = dst == &o->passes ? 1000000 : 64;
            if (!next || !parse_u32(next, lo, hi, dst)) {
                fprintf(stderr, "probebake: error: %s '%s' is not an integer in [%u, %u]\n", a, next ? next : "", lo, hi);
                return 2;
            }
            o->has_bounces |= dst == &o->bounces; /* 0 is a valid bounce count */
            ++i;
        } else if (!strcmp(a, "--device")) {
            if (!next)
                return cli_usage_error("%s needs a value", a);
            o->device = argv[++i];
        } else if (!strcmp(a, "--probe")) {
            if (!next || !parse_u32(next, 0, UINT32_MAX - 1, &o->probe)) {
                fprintf(stderr, "probebake: error: --probe needs a probe index (see probebake --help)\n");
                return 2;
            }
            o->has_probe = 1;
            ++i;
        } else if (!strcmp(a, "--probes") || !strcmp(a, "--rays") || !strcmp(a, "--seed")) {
            if (!next)
                return cli_usage_error("%s needs a value", a);
            uint32_t *dst = !strcmp(a, "--probes") ? &o->probes : !strcmp(a, "--rays") ? &o->rays : &o->seed;
            uint32_t lo = dst == &o->seed ? 0 : 1, hi = dst == &o->rays ? 65536 : (dst == &o->probes ? 1u << 24 : UINT32_MAX);
            if (!parse_u32(next, lo, hi, dst)) {
                fprintf(stderr, "probebake: error: %s '%s' is not an integer in [%u, %u]\n", a, next, lo, hi);
                return 2;
            }
            o->has_rays |= dst == &o->rays;
            o->has_seed |= dst == &o->seed;
            ++i;
        } else if (a[0] == '-') {
            return cli_usage_error("unknown option '%s'", a);
        } else if (!o->command) {
            o->command = a;
        } else if (!o->scene) {
            o->scene = a;
        } else {
            return cli_usage_error("unexpected argument '%s'", a);
        }
    }
    if (!o->command) {
        print_help();
        return 2;
    }
    return 0;
}

static void json_string(const char *s)
{
    putchar('"');
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            printf("\\%c", c);
        else if (c < 0x20)
            printf("\\u%04x", c);
        else
            putchar(c);
    }
    putchar('"');
}

/* A JSON number: JSON has no NaN or Infinity, so those print as null.
 * Returned by value: J(x).s lives until the end of the printf using it. */
typedef struct json_num {
    char s[32];
} json_num;

static json_num J(double x)
{
    json_num j;
    if (isfinite(x))
        snprintf(j.s, sizeof j.s, "%.9g", x);
    else
        snprintf(j.s, sizeof j.s, "null");
    return j;
}

/* Full double precision (origins far from zero). */
static json_num J17(double x)
{
    json_num j = J(x);
    if (isfinite(x))
        snprintf(j.s, sizeof j.s, "%.17g", x);
    return j;
}

static int cmd_devices(const options *o)
{
    pb_device_info infos[16];
    uint32_t n = 0;
    pb_error err;
    if (pb_enumerate_devices(infos, 16, &n, &err) != PB_OK)
        return cli_fail(&err);
    if (n > 16)
        n = 16;
    if (o->json) {
        printf("[");
        for (uint32_t i = 0; i < n; ++i) {
            const pb_device_info *d = &infos[i];
            printf("%s\n  {\"index\": %u, \"name\": ", i ? "," : "", d->index);
            json_string(d->name);
            printf(", \"type\": \"%s\", \"driver\": ", pb_device_type_name(d->type));
            json_string(d->driver);
            printf(", \"vulkan\": \"%u.%u\", \"device_local_bytes\": %llu, \"subgroup_size\": %u, "
                   "\"max_storage_buffer_range\": %llu, \"max_memory_allocation\": %llu, \"shader_int64\": %s, "
                   "\"shader_float64\": %s, \"kernels\": \"%s\", \"usable\": %s}",
                   (d->api_version >> 22) & 0x7f, (d->api_version >> 12) & 0x3ff,
                   (unsigned long long)d->device_local_bytes, d->subgroup_size,
                   (unsigned long long)d->max_storage_buffer_range, (unsigned long long)d->max_memory_allocation,
                   d->shader_int64 ? "true" : "false", d->shader_float64 ? "true" : "false",
                   d->shader_int64 && d->shader_float64 ? "native64" : "portable", d->usable ? "true" : "false");
        }
        printf("\n]\n");
        return 0;
    }
    if (n == 0) {
        fprintf(stderr, "probebake: error: no Vulkan device found\n");
        return 1;
    }
    printf("%-5s %-40s %-15s %-32s %10s %8s %-8s\n", "index", "name", "type", "driver", "memory", "subgroup",
           "kernels");
    for (uint32_t i = 0; i < n; ++i) {
        const pb_device_info *d = &infos[i];
        printf("%-5u %-40.40s %-15s %-32.32s %7.1f GiB %8u %-8s%s%s\n", d->index, d->name,
               pb_device_type_name(d->type), d->driver, d->device_local_bytes / 1073741824.0, d->subgroup_size,
               d->shader_int64 && d->shader_float64 ? "native64" : "portable", d->usable ? "" : "  unusable: ",
               d->usable ? "" : d->unusable_reason);
    }
    return 0;
}

static const char *light_type(uint32_t t)
{
    return t == PB_LIGHT_DIRECTIONAL ? "directional" : t == PB_LIGHT_SPOT ? "spot" : "point";
}

/* "A, B" as a JSON array of strings ["A", "B"] (names hold no commas) */
static void json_name_list(const char *list)
{
    printf("[");
    for (const char *p = list; *p;) {
        const char *e = strstr(p, ", ");
        size_t n = e ? (size_t)(e - p) : strlen(p);
        char name[512];
        snprintf(name, sizeof name, "%.*s", (int)n, p);
        printf("%s", p == list ? "" : ", ");
        json_string(name);
        p += n + (e ? 2 : 0);
    }
    printf("]");
}

static int cmd_info(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a SCENE file", "info");
    pb_scene_desc sd = {{cli_log_to_stderr, (void *)&o->log}, 0};
    pb_scene *s;
    pb_error err;
    if (pb_scene_load(o->scene, &sd, &s, &err) != PB_OK)
        return cli_fail(&err);
    const pb_scene_stats *st = &s->stats;
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = s->bounds_min[k] + s->origin[k];
        hi[k] = s->bounds_max[k] + s->origin[k];
    }
    uint32_t emissive = 0, masked = 0, blended = 0;
    for (uint32_t m = 0; m < s->material_count; ++m) {
        const pb_material *mt = &s->materials[m];
        emissive += mt->emissive[0] > 0 || mt->emissive[1] > 0 || mt->emissive[2] > 0;
        masked += mt->alpha_mode == PB_ALPHA_MASK;
        blended += mt->alpha_mode == PB_ALPHA_BLEND;
    }
    if (o->json) {
        printf("{\n  \"file\": ");
        json_string(o->scene);
        printf(",\n  \"triangles\": %u,\n  \"triangles_in\": %llu,\n  \"dropped_degenerate\": %llu,\n"
               "  \"dropped_nonfinite\": %llu,\n  \"primitives\": %u,\n  \"primitives_skipped\": %u,\n"
               "  \"normals_generated\": %u,\n  \"nodes\": %u,\n",
               s->triangle_count, (unsigned long long)st->triangles_in, (unsigned long long)st->dropped_degenerate,
               (unsigned long long)st->dropped_nonfinite, st->primitives, st->primitives_skipped,
               st->normals_generated, st->nodes);
        printf("  \"materials\": %u,\n  \"emissive_materials\": %u,\n  \"masked_materials\": %u,\n"
               "  \"blended_materials\": %u,\n  \"textures\": %u,\n",
               s->material_count, emissive, masked, blended, s->texture_count);
        printf("  \"lights\": [");
        for (uint32_t i = 0; i < s->light_count; ++i) {
            const pb_light *l = &s->lights[i];
            printf("%s{\"type\": \"%s\", \"name\": ", i ? ", " : "", light_type(l->type));
            json_string(l->name);
            printf(", \"color\": [%s, %s, %s], \"intensity\": %s, \"range\": %s, \"position\": [%s, %s, %s]}",
                   J(l->color[0]).s, J(l->color[1]).s, J(l->color[2]).s, J(l->intensity).s, J(l->range).s,
                   J(l->position[0] + s->origin[0]).s, J(l->position[1] + s->origin[1]).s,
                   J(l->position[2] + s->origin[2]).s);
        }
        printf("],\n  \"cameras\": [");
        for (uint32_t i = 0; i < s->camera_count; ++i) {
            const pb_camera *c = &s->cameras[i];
            printf("%s{\"name\": ", i ? ", " : "");
            json_string(c->name);
            printf(", \"perspective\": %s, \"yfov\": %s, \"position\": [%s, %s, %s]}",
                   c->perspective ? "true" : "false", J(c->yfov).s, J(c->position[0] + s->origin[0]).s,
                   J(c->position[1] + s->origin[1]).s, J(c->position[2] + s->origin[2]).s);
        }
        printf("],\n  \"extensions_used\": ");
        json_name_list(st->extensions_used);
        printf(",\n  \"extensions_applied\": ");
        json_name_list(st->extensions_applied);
        printf(",\n  \"bounds_min\": [%s, %s, %s],\n  \"bounds_max\": [%s, %s, %s],\n"
               "  \"origin\": [%s, %s, %s]\n}\n",
               J(lo[0]).s, J(lo[1]).s, J(lo[2]).s, J(hi[0]).s, J(hi[1]).s, J(hi[2]).s, J17(s->origin[0]).s,
               J17(s->origin[1]).s, J17(s->origin[2]).s);
    } else {
        printf("scene       %s\n", o->scene);
        printf("triangles   %u kept of %llu (%llu degenerate, %llu NaN/Inf dropped)\n", s->triangle_count,
               (unsigned long long)st->triangles_in, (unsigned long long)st->dropped_degenerate,
               (unsigned long long)st->dropped_nonfinite);
        printf("primitives  %u (%u points/lines skipped, %u without normals: flat normals generated), %u nodes\n",
               st->primitives, st->primitives_skipped, st->normals_generated, st->nodes);
        printf("materials   %u (%u emissive, %u alpha-masked, %u blended)\n", s->material_count, emissive, masked,
               blended);
        printf("textures    %u\n", s->texture_count);
        printf("lights      %u", s->light_count);
        for (uint32_t i = 0; i < s->light_count; ++i)
            printf("%s%s '%s' %g", i ? ", " : ": ", light_type(s->lights[i].type), s->lights[i].name,
                   s->lights[i].intensity);
        printf("\ncameras     %u\n", s->camera_count);
        if (st->extensions_used[0])
            printf("extensions  used: %s; applied: %s\n", st->extensions_used,
                   st->extensions_applied[0] ? st->extensions_applied : "none");
        printf("bounds      (%.6g, %.6g, %.6g) .. (%.6g, %.6g, %.6g) m\n", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    }
    pb_scene_destroy(s);
    return 0;
}

static int cmd_trace(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a SCENE file", "trace");
    pb_log log = {cli_log_to_stderr, (void *)&o->log};
    pb_scene_desc sd = {log, 0};
    pb_scene *s = NULL;
    pb_bvh *bvh = NULL;
    pb_context *ctx = NULL;
    pb_gpu_scene *gs = NULL;
    pb_ray *rays = NULL;
    pb_hit *hits = NULL, *ref = NULL;
    pb_error err;
    int rc = 1;
    if (pb_scene_load(o->scene, &sd, &s, &err) != PB_OK || pb_bvh_build(s, NULL, &bvh, &err) != PB_OK)
        goto out;
    pb_context_desc cd = {o->device, (uint32_t)o->validation, 0, 0, log};
    if (pb_context_create(&cd, &ctx, &err) != PB_OK || pb_gpu_scene_create(ctx, s, bvh, &gs, &err) != PB_OK)
        goto out;
    pb_probe_grid grid;
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, o->probes, &grid);
    uint32_t probes = pb_probe_grid_count(&grid);
    uint64_t n64 = (uint64_t)probes * o->rays;
    if (n64 > (1u << 28)) {
        pb_error e2 = {PB_ERROR_INVALID_ARGUMENT, ""};
        snprintf(e2.message, sizeof e2.message, "%s: %llu rays requested; at most 2^28 per trace", o->scene,
                 (unsigned long long)n64);
        err = e2;
        goto out;
    }
    uint32_t n = (uint32_t)n64;
    rays = malloc((size_t)n * sizeof *rays);
    hits = malloc((size_t)n * sizeof *hits);
    if (!rays || !hits) {
        snprintf(err.message, sizeof err.message, "out of host memory for %u rays", n);
        goto out;
    }
    if (pb_probe_rays(&grid, 0, probes, o->rays, o->seed, rays) != PB_OK) {
        snprintf(err.message, sizeof err.message, "out of host memory generating rays");
        goto out;
    }
    pb_trace_stats ts;
    if (pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, &ts, &err) != PB_OK)
        goto out;
    uint64_t traversal = 0, total = pb_gpu_scene_bytes(gs, &traversal);
    uint32_t missed = 0, back = 0;
    for (uint32_t i = 0; i < n; ++i) {
        missed += hits[i].triangle == PB_NO_HIT;
        back += hits[i].triangle != PB_NO_HIT && hits[i].backface;
    }
    printf("scene      %s: %u triangles\n", o->scene, s->triangle_count);
    printf("bvh        %u nodes, %u leaves, depth %u, SAH %.2f, %.1f ms on %u threads\n", bvh->stats.nodes,
           bvh->stats.leaves, bvh->stats.depth, bvh->stats.sah_cost, bvh->stats.build_ms, bvh->stats.threads);
    printf("device     %s: %.1f MiB uploaded, %.1f bytes/triangle for traversal\n", pb_context_device(ctx)->name,
           total / 1048576.0, s->triangle_count ? (double)traversal / s->triangle_count : 0.0);
    printf("trace      %u probes x %u rays = %u rays in %u submits: kernel %.1f ms (%.2f Mrays/s), wall %.1f ms "
           "(%.2f Mrays/s)\n", probes, o->rays, n, ts.submits, ts.kernel_ms,
           ts.kernel_ms > 0 ? n / (ts.kernel_ms * 1e3) : 0.0, ts.wall_ms, n / (ts.wall_ms * 1e3));
    printf("hits       %.1f%% hit, %.1f%% of hits on back faces\n", 100.0 * (n - missed) / n,
           n - missed ? 100.0 * back / (n - missed) : 0.0);
    if (o->verify) {
        ref = malloc((size_t)n * sizeof *ref);
        if (!ref) {
            snprintf(err.message, sizeof err.message, "out of host memory for the CPU reference");
            goto out;
        }
        pb_trace_cpu(s, bvh, rays, n, PB_TRACE_CLOSEST, ref, 0);
        uint32_t mismatches = 0;
        for (uint32_t i = 0; i < n; ++i) {
            int same = hits[i].triangle == ref[i].triangle;
            float tol = 1e-5f * fmaxf(1.f, fabsf(ref[i].t));
            if (!same && hits[i].triangle != PB_NO_HIT && ref[i].triangle != PB_NO_HIT)
                same = fabsf(hits[i].t - ref[i].t) <= tol; /* a tie between two triangles */
            else if (same && hits[i].triangle != PB_NO_HIT)
                same = fabsf(hits[i].t - ref[i].t) <= tol;
            mismatches += !same;
        }
        printf("verify     GPU vs CPU reference: %u mismatches of %u rays\n", mismatches, n);
        if (mismatches) {
            snprintf(err.message, sizeof err.message, "%s: GPU and CPU traces differ on %u rays", o->scene,
                     mismatches);
            goto out;
        }
    }
    if (o->validation && pb_context_validation_messages(ctx)) {
        snprintf(err.message, sizeof err.message, "%u Vulkan validation messages", pb_context_validation_messages(ctx));
        goto out;
    }
    rc = 0;
out:
    free(rays), free(hits), free(ref);
    pb_gpu_scene_destroy(gs);
    pb_context_destroy(ctx);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    return rc ? cli_fail(&err) : 0;
}

static void print_flags(uint32_t f)
{
    static const char *const names[] = {"valid", "relocated", "dilated", "outside", "converged"};
    int first = 1;
    printf("[");
    for (int b = 0; b < 5; ++b)
        if (f & (1u << b)) {
            printf("%s\"%s\"", first ? "" : ", ", names[b]);
            first = 0;
        }
    printf("]");
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

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Paths and relative standard errors over the volume's probes (median, p95,
 * worst), where known. */
static void print_error_summary(FILE *out, const pb_volume *v)
{
    uint64_t paths = 0;
    uint32_t lo = UINT32_MAX, hi = 0, known = 0;
    float *e = malloc(v->probe_count * sizeof *e);
    for (uint32_t i = 0; i < v->probe_count; ++i) {
        paths += v->probe_paths[i];
        lo = v->probe_paths[i] < lo ? v->probe_paths[i] : lo;
        hi = v->probe_paths[i] > hi ? v->probe_paths[i] : hi;
        if (e && v->probe_std_error[i] != PB_STD_ERROR_UNKNOWN)
            e[known++] = v->probe_std_error[i];
    }
    fprintf(out, "paths       %llu in all, %u to %u per probe\n", (unsigned long long)paths, lo, hi);
    if (known) {
        qsort(e, known, sizeof *e, compare_floats);
        fprintf(out, "std error   irradiance, relative: median %.3g %%, p95 %.3g %%, worst %.3g %% (%u probes)\n",
               100.0 * e[known / 2], 100.0 * e[(size_t)(0.95 * (known - 1))], 100.0 * e[known - 1], known);
    } else {
        fprintf(out, "std error   unknown (%s)\n", v->file_version && v->file_version < 3 ? "file older than version 3" : "one pass per probe");
    }
    free(e);
}

static const char *window_name(uint32_t w)
{
    return w == 1 ? "hanning" : w == 2 ? "lanczos" : "none";
}

/* The file's techniques as JSON array items. */
static const char *technique_list(uint32_t t, char buf[64])
{
    static const char *names[3] = {"probe-nee", "guiding", "light-cells"};
    buf[0] = 0;
    for (int k = 0; k < 3; ++k)
        if (t & (1u << k))
            snprintf(buf + strlen(buf), 64 - strlen(buf), "%s\"%s\"", buf[0] ? ", " : "", names[k]);
    return buf;
}

static int cmd_inspect(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a VOLUME file", "inspect");
    pb_volume v;
    pb_error err;
    char techniques[64];
    if (pb_volume_read(o->scene, &v, &err) != PB_OK)
        return cli_fail(&err);
    if (o->has_probe && o->probe >= v.probe_count) {
        fprintf(stderr, "probebake: error: %s: probe %u does not exist (%u probes)\n", o->scene, o->probe,
                v.probe_count);
        pb_volume_free(&v);
        return 1;
    }
    const char *views[2] = {o->atlas, o->sh_view};
    for (int k = 0; k < 2; ++k) {
        if (!views[k])
            continue;
        const char *inputs[1] = {o->scene};
        if (pb_output_check(views[k], inputs, 1, &err) != PB_OK) {
            pb_volume_free(&v);
            return cli_fail(&err);
        }
        unsigned char *img = NULL;
        uint32_t w = 0, h = 0;
        pb_result r = k == 0 ? pb_volume_depth_atlas(&v, &img, &w, &h, &err) : pb_volume_sh_atlas(&v, 16, &img, &w, &h, &err);
        if (r == PB_OK)
            r = pb_write_png(views[k], img, w, h, &err);
        free(img);
        if (r != PB_OK) {
            pb_volume_free(&v);
            return cli_fail(&err);
        }
        if (!o->json)
            printf("wrote %s: %ux%u, %s of %u probes\n", views[k], w, h, k == 0 ? "depth atlas" : "SH irradiance view",
                   v.probe_count);
    }
    uint32_t counts[5] = {0};
    for (uint32_t i = 0; i < v.probe_count; ++i)
        for (int b = 0; b < 5; ++b)
            counts[b] += (v.probe_flags[i] >> b) & 1u;
    const pb_volume_settings *s = &v.settings;
    const char *kind = v.flags & PB_VOLUME_IRRADIANCE ? "irradiance" : "radiance";
    if (o->json) {
        printf("{\n  \"file\": ");
        json_string(o->scene);
        printf(",\n  \"version\": %u,\n  \"probes\": %u,\n  \"grid\": %s,\n  \"counts\": [%u, %u, %u],\n"
               "  \"origin\": [%s, %s, %s],\n  \"spacing\": [%s, %s, %s],\n  \"sh\": \"%s\",\n"
               "  \"direct\": %s,\n  \"octmap_res\": %u,\n  \"max_distance\": %s,\n  \"depth_unit\": %s,\n"
               "  \"seed\": %llu,\n"
               "  \"scene_hash\": \"%016llx\",\n  \"rays_per_probe\": %u,\n  \"passes\": %u,\n  \"bounces\": %u,\n"
               "  \"indirect\": \"%s\",\n  \"sh_window\": \"%s\",\n  \"sh_window_width\": %s,\n  \"indirect_clamp\": %s,\n"
               "  \"techniques\": [%s],\n  \"device\": ",
               v.file_version, v.probe_count, v.flags & PB_VOLUME_GRID ? "true" : "false", v.counts[0], v.counts[1],
               v.counts[2], J17(v.origin[0]).s, J17(v.origin[1]).s, J17(v.origin[2]).s, J(v.spacing[0]).s,
               J(v.spacing[1]).s, J(v.spacing[2]).s, kind, v.flags & PB_VOLUME_DIRECT ? "true" : "false", v.octmap_res,
               J(s->max_distance).s, J(v.depth_unit).s, (unsigned long long)s->seed,
               (unsigned long long)s->scene_hash, s->rays_per_probe, s->passes, s->bounces,
               s->indirect_mode ? "volume" : "path", window_name(s->sh_window), J(s->sh_window_width).s,
               J(s->indirect_clamp).s, technique_list(s->techniques, techniques));
        json_string(v.device);
        printf(",\n  \"valid\": %u, \"relocated\": %u, \"dilated\": %u, \"outside\": %u, \"converged\": %u,\n"
               "  \"probe_list\": [\n", counts[0], counts[1], counts[2], counts[3], counts[4]);
        if (o->has_probe)
            print_probe_json(&v, o->probe, 1);
        else
            for (uint32_t i = 0; i < v.probe_count; ++i)
                print_probe_json(&v, i, i + 1 == v.probe_count);
        printf("  ]\n}\n");
    } else if (o->has_probe) {
        double p[3];
        pb_volume_probe_position(&v, o->probe, p);
        printf("probe %u at (%.6g, %.6g, %.6g), offset (%g, %g, %g), flags ", o->probe, p[0], p[1], p[2],
               v.offset[3 * o->probe], v.offset[3 * o->probe + 1], v.offset[3 * o->probe + 2]);
        print_flags(v.probe_flags[o->probe]);
        float se = v.probe_std_error[o->probe];
        printf("\n%u paths, ", v.probe_paths[o->probe]);
        if (se == PB_STD_ERROR_UNKNOWN)
            printf("standard error unknown (%s)\n", v.file_version && v.file_version < 3 ? "file older than version 3" : "one pass, or passes around a zero mean");
        else
            printf("relative standard error of its irradiance %.3g %%\n", 100.0 * se);
        printf("%s SH (R G B per coefficient):\n", kind);
        for (int c = 0; c < 9; ++c)
            printf("  %d: %12.6g %12.6g %12.6g\n", c, v.sh[27 * (size_t)o->probe + 3 * c],
                   v.sh[27 * (size_t)o->probe + 3 * c + 1], v.sh[27 * (size_t)o->probe + 3 * c + 2]);
    } else {
        printf("volume      %s (format version %u)\n", o->scene, v.file_version);
        if (v.flags & PB_VOLUME_GRID)
            printf("probes      %u = %u x %u x %u, spacing (%g, %g, %g) m\n", v.probe_count, v.counts[0],
                   v.counts[1], v.counts[2], v.spacing[0], v.spacing[1], v.spacing[2]);
        else
            printf("probes      %u placed points\n", v.probe_count);
        printf("flags       %u valid, %u relocated, %u dilated, %u outside, %u converged\n", counts[0], counts[1],
               counts[2], counts[3], counts[4]);
        printf("content     %s SH L2, direct light %s; depth %ux%u (+1 border) per probe, misses at %g m\n", kind,
               v.flags & PB_VOLUME_DIRECT ? "included" : "excluded", v.octmap_res, v.octmap_res, s->max_distance);
        printf("bake        %u rays x %u passes, %u bounces (indirect %s), probe NEE %s, guiding %s, light cells %s, "
               "seed %llu, device %s\n", s->rays_per_probe, s->passes, s->bounces,
               s->indirect_mode ? "volume" : "path", s->techniques & PB_TECHNIQUE_PROBE_NEE ? "on" : "off",
               s->techniques & PB_TECHNIQUE_GUIDING ? "on" : "off",
               s->techniques & PB_TECHNIQUE_LIGHT_CELLS ? "on" : "off", (unsigned long long)s->seed,
               v.device[0] ? v.device : "?");
        if (s->sh_window || s->indirect_clamp > 0.f)
            printf("biased      SH window %s (W %g), indirect clamp %g\n", window_name(s->sh_window),
                   s->sh_window_width > 0.f ? s->sh_window_width : 3.f, s->indirect_clamp);
        print_error_summary(stdout, &v);
        printf("time        %.1f ms total\n", v.timings.total);
    }
    pb_volume_free(&v);
    return 0;
}

/* SIGINT and SIGTERM. Outside a deferred section nothing is being written,
 * so the handler exits at once (128 + signal, as shells report it). Inside
 * one (a bake or render and its final write) it only records the signal:
 * the progress callback and the writer's cancel check see it, the work
 * stops, the temporary file goes and the previous output stays. These two
 * flags are the only process state a signal handler may touch. */
static void on_signal(int sig)
{
    interrupted = sig;
    if (!deferring)
        _exit(128 + sig);
}

void cli_catch_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

void cli_defer_signals(void)
{
    deferring = 1;
}

int cli_interrupted(void *user)
{
    (void)user;
    return interrupted != 0;
}

int cli_progress(float fraction, const char *label, void *user)
{
    cli_progress_state *ps = user;
    if (ps->show) {
        double el = (cli_now_ms() - ps->start) / 1000.0;
        double eta = fraction > 0 ? el * (1 - fraction) / fraction : 0;
        fprintf(stderr, "\r%-14s %5.1f%%  %6.2f Mrays/s  ETA %5.0f s ", label, 100.0 * fraction,
                el > 0 ? fraction * (double)ps->rays_total / el / 1e6 : 0.0, eta);
        fflush(stderr);
    }
    return cli_interrupted(NULL);
}

static int cmd_bake(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a SCENE file", "bake");
    if (!o->output)
        return cli_usage_error("%s needs -o OUT.probes", "bake");
    if (o->has_spacing && o->has_counts)
        return cli_usage_error("%s: give --spacing or --counts, not both", "bake");
    if (o->points && (o->has_spacing || o->has_counts || o->has_bounds))
        return cli_usage_error("%s: --points replaces the grid; drop --spacing, --counts and --bounds", "bake");
    pb_log log = {cli_log_to_stderr, (void *)&o->log};
    pb_scene_desc sd = {log, 0};
    pb_scene *s = NULL;
    pb_bvh *bvh = NULL;
    pb_context *ctx = NULL;
    pb_gpu_scene *gs = NULL;
    pb_volume vol;
    memset(&vol, 0, sizeof vol);
    pb_points pts;
    memset(&pts, 0, sizeof pts);
    pb_environment env;
    memset(&env, 0, sizeof env);
    pb_error err;
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
    if (pb_scene_load(o->scene, &sd, &s, &err) != PB_OK ||
        pb_bake_check_light(s, o->sky, o->env ? &env : NULL, &err) != PB_OK)
        goto out;
    if (s->triangle_count == 0 && !o->has_bounds && !o->points) {
        snprintf(err.message, sizeof err.message, "%s: no triangles and no --bounds: nowhere to put probes", o->scene);
        goto out;
    }
    /* grid in the scene's local frame */
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = o->has_bounds ? (float)(o->bounds[k] - s->origin[k]) : s->bounds_min[k];
        hi[k] = o->has_bounds ? (float)(o->bounds[3 + k] - s->origin[k]) : s->bounds_max[k];
    }
    pb_bake_desc d;
    memset(&d, 0, sizeof d);
    if (o->has_counts) {
        for (int k = 0; k < 3; ++k) {
            d.grid.counts[k] = o->counts[k];
            d.grid.spacing[k] = (hi[k] - lo[k]) / (float)o->counts[k];
            d.grid.origin[k] = lo[k] + 0.5f * d.grid.spacing[k];
        }
    } else if (o->has_spacing) {
        for (int k = 0; k < 3; ++k) {
            double n = floor((hi[k] - lo[k]) / o->spacing);
            if (n > 65536) {
                snprintf(err.message, sizeof err.message, "--spacing %g gives %.0f probes along an axis; at most 65536",
                         o->spacing, n);
                goto out;
            }
            d.grid.counts[k] = n < 1 ? 1u : (uint32_t)n;
            d.grid.spacing[k] = o->spacing;
            d.grid.origin[k] = 0.5f * (lo[k] + hi[k]) - 0.5f * o->spacing * (float)(d.grid.counts[k] - 1);
        }
    } else {
        pb_probe_grid_fit(lo, hi, 2048, &d.grid); /* a room at roughly 0.3 m */
    }
    if (o->points) {
        d.points = &pts;
        memset(&d.grid, 0, sizeof d.grid);
    }
    /* a preset fills what the command line leaves out */
    const pb_bake_quality *q = pb_bake_quality_find(o->quality);
    d.rays_per_probe = o->has_rays ? o->rays : q ? q->rays_per_probe : 256;
    d.target_error = o->target_error > 0.f ? o->target_error : q ? q->target_error : 0.f;
    d.passes = o->passes ? o->passes : q ? q->passes : (d.target_error > 0.f ? 64 : 4);
    d.bounces = o->has_bounces ? o->bounces : 2;
    d.octmap_res = o->octmap_res ? o->octmap_res : 16;
    d.seed = o->has_seed ? o->seed : 1;
    d.exclude_direct = o->direct && !strcmp(o->direct, "exclude");
    d.probe_nee = o->probe_nee ? !strcmp(o->probe_nee, "on") : q ? q->probe_nee : 1u;
    d.guide_paths = o->guide ? (!strcmp(o->guide, "on") ? PB_GUIDE_DEFAULT_PATHS : 0u) : q ? q->guide_paths : 0u;
    d.light_cells = o->light_cells ? !strcmp(o->light_cells, "on") : q ? q->light_cells : 1u;
    memcpy(d.sky, o->sky, sizeof d.sky);
    d.environment = o->env ? &env : NULL;
    d.indirect_volume = (uint32_t)o->indirect_volume;
    d.sh_window = o->sh_window;
    d.indirect_clamp = o->indirect_clamp;
    d.max_lights_per_hit = o->max_lights_per_hit;
    d.sh_window_width = o->sh_window_width;
    char light[1200], clamp_text[32];
    if (o->env)
        snprintf(light, sizeof light, "environment %s (%ux%u, x%g, turned %g deg)", o->env, env.width, env.height,
                 o->env_intensity, o->env_rotation);
    else
        snprintf(light, sizeof light, "sky (%g, %g, %g)", d.sky[0], d.sky[1], d.sky[2]);
    uint64_t probes = o->points ? pts.count : (uint64_t)d.grid.counts[0] * d.grid.counts[1] * d.grid.counts[2];
    char where[160];
    if (o->points)
        snprintf(where, sizeof where, "%u points from %.100s", pts.count, o->points);
    else
        snprintf(where, sizeof where, "%u x %u x %u = %llu probes, spacing %.3g m", d.grid.counts[0], d.grid.counts[1],
                 d.grid.counts[2], (unsigned long long)probes, d.grid.spacing[0]);
    if (!o->log.quiet)
        fprintf(stderr,
                "probebake: baking %s%s%s: %s, %u rays x %s%u passes%s, %u bounces, "
                "%s, octmap %u, direct %s, indirect %s, probe NEE %s, guiding %s, light cells %s, seed %u\n",
                o->scene, q ? " at quality " : "", q ? q->name : "", where, d.rays_per_probe,
                d.target_error > 0.f ? "up to " : "", d.passes, d.target_error > 0.f ? " (until converged)" : "",
                d.bounces, light, d.octmap_res,
                d.exclude_direct ? "excluded" : "included", d.indirect_volume ? "volume" : "path",
                d.probe_nee ? "on" : "off",
                /* --indirect volume bakes one bounce at a time: no bounce rays to guide */
                d.guide_paths && d.bounces && !d.indirect_volume ? "on" : "off", d.light_cells ? "on" : "off",
                d.seed);
    if (!o->log.quiet && (d.indirect_clamp > 0.f || d.sh_window))
        fprintf(stderr, "probebake: biased on request:%s%s%s\n",
                d.indirect_clamp > 0.f ? " reflected light clamped per path to radiance " : "",
                d.indirect_clamp > 0.f ? (snprintf(clamp_text, sizeof clamp_text, "%g", d.indirect_clamp), clamp_text) : "",
                d.sh_window == 1 ? " SH Hanning window" : d.sh_window == 2 ? " SH Lanczos window" : "");
    if (pb_bvh_build(s, NULL, &bvh, &err) != PB_OK)
        goto out;
    pb_context_desc cd = {o->device, (uint32_t)o->validation, 0, 0, log};
    cli_fault_injection(&cd);
    if (pb_context_create(&cd, &ctx, &err) != PB_OK || pb_gpu_scene_create(ctx, s, bvh, &gs, &err) != PB_OK)
        goto out;
    cli_progress_state ps = {isatty(2) && !o->log.quiet, cli_now_ms(), probes * d.rays_per_probe * d.passes};
    d.progress = cli_progress;
    d.progress_user = &ps;
    cli_defer_signals(); /* from here a signal cancels the bake or the write */
    pb_result r = pb_bake(ctx, s, gs, &d, &vol, &err);
    if (ps.show)
        fprintf(stderr, "\n");
    if (r != PB_OK)
        goto out;
    if (o->validation && pb_context_validation_messages(ctx)) {
        snprintf(err.message, sizeof err.message, "%u Vulkan validation messages", pb_context_validation_messages(ctx));
        goto out;
    }
    vol.timings.load = 0;
    vol.timings.bvh = bvh->stats.build_ms;
    vol.timings.total = cli_now_ms() - t0;
    if (pb_volume_write_ex(o->output, &vol, cli_interrupted, NULL, &err) != PB_OK)
        goto out;
    FILE *report = strcmp(o->output, "-") ? stdout : stderr; /* stdout carries the volume for -o - */
    uint32_t valid = 0, outside = 0, relocated = 0, dilated = 0, converged = 0;
    for (uint32_t i = 0; i < vol.probe_count; ++i) {
        valid += (vol.probe_flags[i] & PB_PROBE_VALID) != 0;
        outside += (vol.probe_flags[i] & PB_PROBE_OUTSIDE) != 0;
        relocated += (vol.probe_flags[i] & PB_PROBE_RELOCATED) != 0;
        dilated += (vol.probe_flags[i] & PB_PROBE_DILATED) != 0;
        converged += (vol.probe_flags[i] & PB_PROBE_CONVERGED) != 0;
    }
    double rays = (double)vol.rays_traced;
    fprintf(report, "wrote %s: %llu probes (%u valid, %u relocated, %u invalid of which %u dilated, %u outside", o->output,
           (unsigned long long)probes, valid, relocated, vol.probe_count - valid, dilated, outside);
    if (d.target_error > 0.f)
        fprintf(report, ", %u converged before the last pass", converged);
    fprintf(report, "), %.3g probe rays in %s%u passes\n", rays, d.target_error > 0.f ? "up to " : "", vol.settings.passes);
    print_error_summary(report, &vol);
    fprintf(report, "time: bvh %.1f ms; GPU trace %.0f ms (%.2f M probe rays/s, %.2f M traversals/s), sh %.0f ms, depth %.0f ms; "
           "total %.0f ms wall\n",
           vol.timings.bvh, vol.timings.trace, vol.timings.trace > 0 ? rays / (vol.timings.trace * 1e3) : 0.0,
           vol.timings.trace > 0 ? (double)vol.traversals / (vol.timings.trace * 1e3) : 0.0, vol.timings.sh,
           vol.timings.octmap, vol.timings.total);
    rc = 0;
out:
    pb_volume_free(&vol);
    pb_points_free(&pts);
    pb_environment_free(&env);
    pb_gpu_scene_destroy(gs);
    pb_context_destroy(ctx);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    return rc ? cli_fail(&err) : 0;
}

int main(int argc, char **argv)
{
    cli_catch_signals();
    options o;
    int r = parse(argc, argv, &o);
    if (r)
        return r;
    if (!strcmp(o.command, "devices"))
        return cmd_devices(&o);
    if (!strcmp(o.command, "info"))
        return cmd_info(&o);
    if (!strcmp(o.command, "trace"))
        return cmd_trace(&o);
    if (!strcmp(o.command, "inspect"))
        return cmd_inspect(&o);
    if (!strcmp(o.command, "bake"))
        return cmd_bake(&o);
    if (!strcmp(o.command, "render"))
        return cmd_render(&o);
    if (!strcmp(o.command, "export"))
        return cmd_export(&o);
    return cli_usage_error("unknown command '%s'", o.command);
}
