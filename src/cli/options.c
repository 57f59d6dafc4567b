#define _POSIX_C_SOURCE 200809L
/* The options every command shares, parsed with getopt_long, and --help. */
#include "cli/cli.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cli_print_help(void)
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
           "  probebake merge OUT PART...             join the parts of a sharded bake (bake --shard) into\n"
           "                                          the file one process writes\n"
           "  probebake --help | --version\n\n"
           "options:\n"
           "  --device INDEX|NAME     pick a device (default: discrete > integrated > virtual > CPU)\n"
           "  --validation            enable the Vulkan validation layer (fail on any message)\n"
           "  --portable-kernels      run the kernels built for devices without shaderInt64 and\n"
           "                          shaderFloat64 on any device (same results; to check them)\n"
           "  --scene-loads auto|address|texel  how kernels read the BVH (same results): texel loads\n"
           "                          are faster on lavapipe; auto: texels on CPU devices only\n"
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
           "  --relocation-rays N            rays per probe in each of the 3 iterations that move probes out of\n"
           "                                 walls (first hits only; default 64, at most --rays)\n"
           "  --skip-inside on|off           probes relocation still finds inside geometry (more than 35 %% back\n"
           "                                 faces where they end up) are flagged and not traced (default on)\n"
           "  --sky R,G,B                    uniform sky radiance (default black)\n"
           "  --env FILE.hdr|FILE.exr        equirectangular environment map (Radiance or OpenEXR) instead of --sky\n"
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
           "  --emitter-sampling solid-angle|area   light samples on an emissive triangle: uniform in the\n"
           "                                 solid angle it spans where that is 0.01 sr or more (default),\n"
           "                                 or a uniform point on it (noisier near it; both unbiased)\n"
           "  --schedule megakernel|wavefront|restart[:K]   each path traced by one invocation (default),\n"
           "                                 as a wavefront, one kind of ray per dispatch, or K paths per\n"
           "                                 invocation, the next begun when one ends (K 1-64, default 8);\n"
           "                                 the same volume, bit for bit (docs/bake.md, \"Schedules\")\n"
           "  --shading-normals vertex|face  reflect with the file's vertex normals interpolated (default)\n"
           "                                 or each triangle's face normal (flat); render too, info counts\n"
           "  --normal-maps on|off           bend the shading normals by the materials' glTF normal maps\n"
           "                                 (default on); render too, info counts\n"
           "  --sh-window none|hanning[:W]|lanczos[:W]   taper SH bands against ringing (default none; W 3)\n"
           "  --max-lights-per-hit N         above N punctual lights, each hit draws one by power (default 8)\n"
           "  --clamp-indirect X             clamp each reflected-light path contribution to radiance X\n"
           "                                 (against fireflies; biased, off by default)\n"
           "  --indirect path|volume         indirect light path traced (default, unbiased) or, per bounce, from\n"
           "                                 the previous bounce's volume through the run-time sampler (fast, biased)\n"
           "  --shard I/N                    bake part I (from 0) of N only: a range of the probes, joined by\n"
           "                                 probebake merge (scripts/slurm/submit.sh queues it on Slurm)\n"
           "  --devices all|LIST             bake on several devices at once (indices or names, comma-separated;\n"
           "                                 a part each, merged in memory)\n"
           "  --layout grid|sparse           sparse: 4x4x4-probe bricks at up to 3 spacings (the grid's spacing\n"
           "                                 is the finest), refined where interpolation errs (docs/sparse.md)\n"
           "  --max-level L                  sparse: finest level 0-2 (default 2: spacings 9x, 3x, 1x)\n"
           "  --refine-error E               sparse: subdivide where the coarser level mispredicts the test's\n"
           "                                 probes by more than E of their irradiance (default 0.1; < 1 for surface)\n"
           "  --refine-test surface|probe    sparse: test probes at points on the surfaces in a cell, along\n"
           "                                 their normals (default), or one probe inside it, six axes\n"
           "  --refine-seams N               sparse: N rounds (0-8, default 0) of the seam test: also refine a\n"
           "                                 coarser cell where a finer brick's probe on its face sees it err\n"
           "  --seam-error E                 sparse: the seam test refines where that miss exceeds E (default:\n"
           "                                 the refine error; larger refines only the worst seams)\n"
           "render options:\n"
           "  --mode probes|reference|direct|indirect|diff   (default probes with --volume, else reference)\n"
           "  --camera I | --eye x,y,z --target x,y,z [--up x,y,z] [--fov DEG]   (default: glTF camera 0; a\n"
           "                                 scene without one is seen from in front of its bounds, or from\n"
           "                                 inside them where outside shows only walls' backs: a level;\n"
           "                                 --up defaults to +Y, or -Z looking straight up or down)\n"
           "  --size WxH (default 640x480)  --spp N  --bounces N (reference, default 8)  --seed S\n"
           "  --exposure EV|auto (default auto)  --pfm (linear image beside the PNG)  --json (metrics)\n"
           "  --show-probes   draw the volume's probes: spheres lit by their SH, invalid red, grid homes grey\n"
           "  --reference REF.pfm   diff: compare with this image (a converged `--mode reference --pfm` of the\n"
           "                  same camera and size) instead of tracing a 16x-spp reference\n"
           "  --seams-of SPARSE.probes   diff: the seam and per-level metrics on the pixels where that sparse\n"
           "                  volume's levels meet (e.g. a grid's error where a sparse volume has its seams)\n"
           "  --sky R,G,B | --env FILE.hdr|.exr [...]   the environment, as for bake\n"
           "  --emitter-sampling solid-angle|area   reference, direct: light samples on emitters, as for bake\n",
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

/* A float strictly inside (lo, hi), the whole string. */
static int parse_open_range(const char *s, float lo, float hi, float *out)
{
    char *end = NULL;
    float v = strtof(s, &end);
    if (!s[0] || *end || !(v > lo && v < hi))
        return 0;
    *out = v;
    return 1;
}

/* Every long option: its code, name and whether it takes a value. The
 * short forms are -h (--help) and -o (--output). Every command accepts
 * every option (a command ignores those it has no use for). */
#define CLI_LONG_OPTIONS(X) \
    X(OPT_HELP, "help", no_argument) \
    X(OPT_VERSION, "version", no_argument) \
    X(OPT_JSON, "json", no_argument) \
    X(OPT_VALIDATION, "validation", no_argument) \
    X(OPT_VERIFY, "verify", no_argument) \
    X(OPT_PORTABLE_KERNELS, "portable-kernels", no_argument) \
    X(OPT_VERBOSE, "verbose", no_argument) \
    X(OPT_QUIET, "quiet", no_argument) \
    X(OPT_PFM, "pfm", no_argument) \
    X(OPT_SHOW_PROBES, "show-probes", no_argument) \
    X(OPT_OUTPUT, "output", required_argument) \
    X(OPT_TEXTURES, "textures", required_argument) \
    X(OPT_POINTS, "points", required_argument) \
    X(OPT_QUALITY, "quality", required_argument) \
    X(OPT_GUIDE, "guide", required_argument) \
    X(OPT_PROBE_NEE, "probe-nee", required_argument) \
    X(OPT_LIGHT_CELLS, "light-cells", required_argument) \
    X(OPT_DIRECT, "direct", required_argument) \
    X(OPT_VOLUME, "volume", required_argument) \
    X(OPT_REFERENCE, "reference", required_argument) \
    X(OPT_SEAMS_OF, "seams-of", required_argument) \
    X(OPT_MODE, "mode", required_argument) \
    X(OPT_EYE, "eye", required_argument) \
    X(OPT_TARGET, "target", required_argument) \
    X(OPT_UP, "up", required_argument) \
    X(OPT_FOV, "fov", required_argument) \
    X(OPT_EXPOSURE, "exposure", required_argument) \
    X(OPT_SIZE, "size", required_argument) \
    X(OPT_CAMERA, "camera", required_argument) \
    X(OPT_SPP, "spp", required_argument) \
    X(OPT_ATLAS, "atlas", required_argument) \
    X(OPT_SH_VIEW, "sh-view", required_argument) \
    X(OPT_ENV, "env", required_argument) \
    X(OPT_MAX_LIGHTS, "max-lights-per-hit", required_argument) \
    X(OPT_CLAMP_INDIRECT, "clamp-indirect", required_argument) \
    X(OPT_SH_WINDOW, "sh-window", required_argument) \
    X(OPT_INDIRECT, "indirect", required_argument) \
    X(OPT_ENV_INTENSITY, "env-intensity", required_argument) \
    X(OPT_ENV_ROTATION, "env-rotation", required_argument) \
    X(OPT_TARGET_ERROR, "target-error", required_argument) \
    X(OPT_SPACING, "spacing", required_argument) \
    X(OPT_COUNTS, "counts", required_argument) \
    X(OPT_SKY, "sky", required_argument) \
    X(OPT_BOUNDS, "bounds", required_argument) \
    X(OPT_PASSES, "passes", required_argument) \
    X(OPT_BOUNCES, "bounces", required_argument) \
    X(OPT_OCTMAP_RES, "octmap-res", required_argument) \
    X(OPT_DEVICE, "device", required_argument) \
    X(OPT_PROBE, "probe", required_argument) \
    X(OPT_PROBES, "probes", required_argument) \
    X(OPT_RAYS, "rays", required_argument) \
    X(OPT_RELOCATION_RAYS, "relocation-rays", required_argument) \
    X(OPT_SKIP_INSIDE, "skip-inside", required_argument) \
    X(OPT_SEED, "seed", required_argument) \
    X(OPT_SHARD, "shard", required_argument) \
    X(OPT_DEVICES, "devices", required_argument) \
    X(OPT_LAYOUT, "layout", required_argument) \
    X(OPT_MAX_LEVEL, "max-level", required_argument) \
    X(OPT_REFINE_ERROR, "refine-error", required_argument) \
    X(OPT_REFINE_TEST, "refine-test", required_argument) \
    X(OPT_REFINE_SEAMS, "refine-seams", required_argument) \
    X(OPT_SEAM_ERROR, "seam-error", required_argument) \
    X(OPT_SCENE_LOADS, "scene-loads", required_argument) \
    X(OPT_SHADING_NORMALS, "shading-normals", required_argument) \
    X(OPT_NORMAL_MAPS, "normal-maps", required_argument) \
    X(OPT_EMITTER_SAMPLING, "emitter-sampling", required_argument) \
    X(OPT_SCHEDULE, "schedule", required_argument)

enum {
    OPT_FIRST = 256,
#define X_ENUM(code, name, arg) code,
    CLI_LONG_OPTIONS(X_ENUM)
#undef X_ENUM
};

static const struct option long_options[] = {
#define X_OPTION(code, name, arg) {name, arg, NULL, code},
    CLI_LONG_OPTIONS(X_OPTION)
#undef X_OPTION
    {NULL, 0, NULL, 0},
};

static const char *const option_names[] = {
#define X_NAME(code, name, arg) "--" name,
    CLI_LONG_OPTIONS(X_NAME)
#undef X_NAME
};

/* Applies option `a` (its name, as the messages print it) with value
 * `next` (NULL when it takes none, or when the value is missing: each
 * option's own message says what it needs). Returns 0 or the exit code. */
static int apply(options *o, const char *a, const char *next)
{
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
        cli_print_help();
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
    } else if (!strcmp(a, "--portable-kernels")) {
        o->portable_kernels = 1;
    } else if (!strcmp(a, "--verbose")) {
        o->log.verbose = 1;
    } else if (!strcmp(a, "--quiet")) {
        o->log.quiet = 1;
    } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
        if (!next)
            return cli_usage_error("%s needs a file name", a);
        o->output = next;
    } else if (!strcmp(a, "--textures")) {
        if (!next)
            return cli_usage_error("%s needs a directory", a);
        o->textures = next;
    } else if (!strcmp(a, "--points")) {
        if (!next)
            return cli_usage_error("%s needs a points file (JSON)", a);
        o->points = next;
    } else if (!strcmp(a, "--quality")) {
        if (!next || !pb_bake_quality_find(next))
            return cli_usage_error("%s takes preview, production or reference", a);
        o->quality = next;
    } else if (!strcmp(a, "--guide") || !strcmp(a, "--probe-nee") || !strcmp(a, "--light-cells") ||
               !strcmp(a, "--skip-inside")) {
        if (!next || (strcmp(next, "on") && strcmp(next, "off")))
            return cli_usage_error("%s takes on or off", a);
        *(!strcmp(a, "--guide")         ? &o->guide
          : !strcmp(a, "--probe-nee")   ? &o->probe_nee
          : !strcmp(a, "--light-cells") ? &o->light_cells
                                        : &o->skip_inside) = next;
    } else if (!strcmp(a, "--direct")) {
        if (!next || (strcmp(next, "include") && strcmp(next, "exclude")))
            return cli_usage_error("%s takes include or exclude", a);
        o->direct = next;
    } else if (!strcmp(a, "--volume") || !strcmp(a, "--mode") || !strcmp(a, "--reference") ||
               !strcmp(a, "--seams-of")) {
        if (!next)
            return cli_usage_error("%s needs a value", a);
        *(!strcmp(a, "--volume")      ? &o->volume
          : !strcmp(a, "--mode")      ? &o->mode
          : !strcmp(a, "--reference") ? &o->reference
                                      : &o->seams_of) = next;
    } else if (!strcmp(a, "--eye") || !strcmp(a, "--target") || !strcmp(a, "--up")) {
        double *dst = !strcmp(a, "--eye") ? o->eye : !strcmp(a, "--target") ? o->target : o->up;
        if (!next || !cli_parse_doubles(next, 3, dst)) {
            fprintf(stderr, "probebake: error: %s '%s' is not three comma-separated finite numbers\n", a,
                    next ? next : "");
            return 2;
        }
        *(dst == o->eye ? &o->has_eye : dst == o->target ? &o->has_target : &o->has_up) = 1;
    } else if (!strcmp(a, "--fov") || !strcmp(a, "--exposure")) {
        int fov = !strcmp(a, "--fov");
        char *end = NULL;
        float v = next ? strtof(next, &end) : NAN;
        if (!fov && next && !strcmp(next, "auto"))
            return 0;
        if (!next || *end || !isfinite(v) || (fov && !(v > 0.f && v < 180.f)) || (!fov && fabsf(v) > 64.f)) {
            fprintf(stderr, "probebake: error: %s '%s' is not %s\n", a, next ? next : "",
                    fov ? "a vertical field of view in degrees in (0, 180)" : "'auto' or an exposure in EV (-64..64)");
            return 2;
        }
        if (fov)
            o->fov_deg = v;
        else
            o->exposure = v, o->has_exposure = 1;
    } else if (!strcmp(a, "--size")) {
        unsigned w = 0, h = 0;
        char c = 0;
        if (!next || sscanf(next, "%ux%u%c", &w, &h, &c) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384) {
            fprintf(stderr, "probebake: error: --size '%s' is not WxH with each side 1..16384\n", next ? next : "");
            return 2;
        }
        o->width = w, o->height = h;
    } else if (!strcmp(a, "--camera") || !strcmp(a, "--spp")) {
        int cam = !strcmp(a, "--camera");
        if (!next || !parse_u32(next, cam ? 0 : 1, cam ? 1000000 : 65536, cam ? &o->camera : &o->spp)) {
            fprintf(stderr, "probebake: error: %s '%s' is not %s\n", a, next ? next : "",
                    cam ? "a camera index" : "an integer in [1, 65536]");
            return 2;
        }
        *(cam ? &o->has_camera : &o->has_spp) = 1;
    } else if (!strcmp(a, "--atlas") || !strcmp(a, "--sh-view")) {
        if (!next)
            return cli_usage_error("%s needs a PNG path", a);
        *(!strcmp(a, "--atlas") ? &o->atlas : &o->sh_view) = next;
    } else if (!strcmp(a, "--pfm")) {
        o->pfm = 1;
    } else if (!strcmp(a, "--show-probes")) {
        o->show_probes = 1;
    } else if (!strcmp(a, "--env")) {
        if (!next)
            return cli_usage_error("%s needs a .hdr or .exr file", a);
        o->env = next;
    } else if (!strcmp(a, "--relocation-rays")) {
        if (!next || !parse_u32(next, 1, 65536, &o->relocation_rays)) {
            fprintf(stderr, "probebake: error: --relocation-rays '%s' is not an integer in [1, 65536]\n",
                    next ? next : "");
            return 2;
        }
    } else if (!strcmp(a, "--max-lights-per-hit")) {
        if (!next || !parse_u32(next, 1, 1u << 20, &o->max_lights_per_hit)) {
            fprintf(stderr, "probebake: error: --max-lights-per-hit '%s' is not an integer in [1, 1048576]\n",
                    next ? next : "");
            return 2;
        }
    } else if (!strcmp(a, "--clamp-indirect")) {
        char *end = NULL;
        float v = next ? strtof(next, &end) : NAN;
        if (!next || *end || !(v > 0.f) || !isfinite(v)) {
            fprintf(stderr, "probebake: error: --clamp-indirect '%s' is not a positive radiance\n", next ? next : "");
            return 2;
        }
        o->indirect_clamp = v;
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
    } else if (!strcmp(a, "--scene-loads")) {
        if (!next || (strcmp(next, "auto") && strcmp(next, "address") && strcmp(next, "texel")))
            return cli_usage_error("%s takes auto, address or texel", a);
        o->scene_loads = !strcmp(next, "address") ? PB_SCENE_LOADS_ADDRESS
                         : !strcmp(next, "texel") ? PB_SCENE_LOADS_TEXEL : PB_SCENE_LOADS_AUTO;
    } else if (!strcmp(a, "--schedule")) {
        if (!pb_bake_schedule_parse(next, &o->schedule, &o->paths_per_lane)) {
            char k_range[80];
            snprintf(k_range, sizeof k_range, "%%s restart:K takes K from 1 to %u paths per lane",
                     PB_MAX_PATHS_PER_LANE);
            int bad_k = next && !strncmp(next, "restart:", 8);
            return cli_usage_error(bad_k ? k_range : "%s takes megakernel, wavefront or restart[:K]", a);
        }
    } else if (!strcmp(a, "--emitter-sampling")) {
        if (!next || (strcmp(next, "solid-angle") && strcmp(next, "area")))
            return cli_usage_error("%s takes solid-angle or area", a);
        o->emitters_by_area = !strcmp(next, "area");
    } else if (!strcmp(a, "--shading-normals")) {
        if (!next || (strcmp(next, "vertex") && strcmp(next, "face")))
            return cli_usage_error("%s takes vertex or face", a);
        o->face_normals = !strcmp(next, "face");
    } else if (!strcmp(a, "--normal-maps")) {
        if (!next || (strcmp(next, "on") && strcmp(next, "off")))
            return cli_usage_error("%s takes on or off", a);
        o->no_normal_maps = !strcmp(next, "off");
    } else if (!strcmp(a, "--indirect")) {
        if (!next || (strcmp(next, "path") && strcmp(next, "volume")))
            return cli_usage_error("%s takes path or volume", a);
        o->indirect_volume = !strcmp(next, "volume");
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
    } else if (!strcmp(a, "--target-error") || !strcmp(a, "--refine-error") || !strcmp(a, "--seam-error")) {
        /* relative errors: a fraction for the stopping target, up to 100x for the sparse tests */
        float hi = !strcmp(a, "--target-error") ? 1.f : 100.f;
        float *dst = hi == 1.f ? &o->target_error : !strcmp(a, "--refine-error") ? &o->refine_error : &o->seam_error;
        if (!next || !parse_open_range(next, 0.f, hi, dst)) {
            fprintf(stderr, "probebake: error: %s '%s' is not a relative error in (0, %g)\n", a, next ? next : "",
                    (double)hi);
            return 2;
        }
    } else if (!strcmp(a, "--spacing")) {
        char *end = NULL;
        o->spacing = next ? strtof(next, &end) : 0.f;
        if (!next || *end || !(o->spacing > 0.f) || !isfinite(o->spacing)) {
            fprintf(stderr, "probebake: error: --spacing '%s' is not a positive length in metres\n",
                    next ? next : "");
            return 2;
        }
        o->has_spacing = 1;
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
            fprintf(stderr, "probebake: error: %s needs %d comma-separated finite numbers, got '%s'\n", a, want,
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
                o->bounds[k] = vals[k];
            if (!(vals[3] > vals[0] && vals[4] > vals[1] && vals[5] > vals[2])) {
                fprintf(stderr, "probebake: error: --bounds '%s': need x0,y0,z0,x1,y1,z1 with x1>x0, y1>y0, z1>z0\n",
                        next);
                return 2;
            }
            o->has_bounds = 1;
        }
    } else if (!strcmp(a, "--passes") || !strcmp(a, "--bounces") || !strcmp(a, "--octmap-res")) {
        uint32_t *dst = !strcmp(a, "--passes") ? &o->passes : !strcmp(a, "--bounces") ? &o->bounces : &o->octmap_res;
        uint32_t lo = dst == &o->bounces ? 0 : 1, hi = dst == &o->passes ? 1000000 : 64;
        if (!next || !parse_u32(next, lo, hi, dst)) {
            fprintf(stderr, "probebake: error: %s '%s' is not an integer in [%u, %u]\n", a, next ? next : "", lo, hi);
            return 2;
        }
        o->has_bounces |= dst == &o->bounces; /* 0 is a valid bounce count */
    } else if (!strcmp(a, "--shard")) {
        unsigned i = 0, n = 0;
        char c = 0;
        if (!next || sscanf(next, "%u/%u%c", &i, &n, &c) != 2 || n < 1 || i >= n || n > (1u << 24)) {
            fprintf(stderr, "probebake: error: --shard '%s' is not I/N with 0 <= I < N (part I of N, from 0)\n",
                    next ? next : "");
            return 2;
        }
        o->shard_index = i, o->shard_count = n;
    } else if (!strcmp(a, "--layout")) {
        if (!next || (strcmp(next, "grid") && strcmp(next, "sparse")))
            return cli_usage_error("--layout '%s' is not grid or sparse", next ? next : "");
        o->sparse = !strcmp(next, "sparse");
    } else if (!strcmp(a, "--max-level")) {
        if (!next || !parse_u32(next, 0, PB_SPARSE_MAX_LEVELS - 1, &o->max_level)) {
            fprintf(stderr, "probebake: error: --max-level '%s' is not an integer in [0, %u]\n", next ? next : "",
                    PB_SPARSE_MAX_LEVELS - 1);
            return 2;
        }
        o->has_max_level = 1;
    } else if (!strcmp(a, "--refine-test")) {
        if (!next || (strcmp(next, "surface") && strcmp(next, "probe")))
            return cli_usage_error("--refine-test '%s' is not surface or probe", next ? next : "");
        o->refine_test = !strcmp(next, "probe") ? PB_REFINE_TEST_PROBE : PB_REFINE_TEST_SURFACE;
        o->has_refine_test = 1;
    } else if (!strcmp(a, "--refine-seams")) {
        if (!next || !parse_u32(next, 0, 8, &o->refine_seams))
            return cli_usage_error("--refine-seams '%s' is not a number of rounds from 0 to 8", next ? next : "");
        o->has_refine_seams = 1;
    } else if (!strcmp(a, "--devices")) {
        if (!next)
            return cli_usage_error("%s needs all or a comma-separated list of device indices or names", a);
        o->devices = next;
    } else if (!strcmp(a, "--device")) {
        if (!next)
            return cli_usage_error("%s needs a value", a);
        o->device = next;
    } else if (!strcmp(a, "--probe")) {
        if (!next || !parse_u32(next, 0, UINT32_MAX - 1, &o->probe)) {
            fprintf(stderr, "probebake: error: --probe needs a probe index (see probebake --help)\n");
            return 2;
        }
        o->has_probe = 1;
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
    }
    return 0;
}

int cli_parse(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->probes = 4096;
    o->rays = 256;
    o->seed = 1;
    o->env_intensity = 1.f;
    /* "-": operands come back in order as code 1 (so the command and its
     * SCENE may sit anywhere among the options, POSIXLY_CORRECT or not);
     * ":": a missing value comes back as ':' with optopt, unprinted */
    o->parts = calloc((size_t)argc, sizeof *o->parts); /* at most every argument; freed by cli_options_free */
    if (!o->parts) {
        fprintf(stderr, "probebake: error: out of memory\n");
        return 1;
    }
    opterr = 0;
    optind = 0; /* glibc: a full reinitialisation */
    for (;;) {
        const char *typed = optind > 0 && optind < argc ? argv[optind] : optind == 0 && argc > 1 ? argv[1] : NULL;
        int code = getopt_long(argc, argv, "-:ho:", long_options, NULL);
        if (code == -1)
            break;
        if (code == 1) { /* an operand */
            if (!o->command)
                o->command = optarg;
            else if (!o->scene)
                o->scene = optarg;
            else if (!strcmp(o->command, "merge")) /* merge OUT PART... */
                o->parts[o->part_count++] = optarg;
            else
                return cli_usage_error("unexpected argument '%s'", optarg);
            continue;
        }
        int which = code == ':' ? optopt : code;
        const char *name = which == 'h' ? "-h" : which == 'o' ? "-o"
                           : which > OPT_FIRST && code != '?' ? option_names[which - OPT_FIRST - 1] : NULL;
        if (!name)
            return cli_usage_error("unknown option '%s'", typed ? typed : "?");
        int r = apply(o, name, code == ':' ? NULL : optarg);
        if (r)
            return r;
    }
    if (!o->command) {
        cli_print_help();
        return 2;
    }
    return 0;
}

void cli_options_free(options *o)
{
    free(o->parts);
    o->parts = NULL;
}
