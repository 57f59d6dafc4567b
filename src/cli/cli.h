/* The probebake command line: options shared by the commands, and the
 * helpers every command uses (one-line errors, logging, time). */
#ifndef PB_CLI_H
#define PB_CLI_H

#include "probebake/probebake.h"

#include <stdio.h>

typedef struct cli_log {
    int verbose;
    int quiet;
} cli_log;

typedef struct options {
    const char *command;
    const char *scene;
    const char *device;
    const char *output;
    const char *direct;
    const char *probe_nee;      /* "on" | "off"; NULL: the preset's, else on */
    const char *quality;        /* a pb_bake_quality name; NULL: none (the defaults below) */
    const char *guide;          /* "on" | "off"; NULL: the preset's, else off */
    const char *light_cells;    /* "on" | "off"; NULL: the preset's, else on */
    const char *skip_inside;    /* "on" | "off"; NULL: on */
    const char *points;
    const char *env;
    const char *textures;       /* export: the output directory */
    float spacing, sky[3], target_error, env_intensity, env_rotation;
    double bounds[6]; /* world coordinates: double, as a scene's origin is (1e7 m offsets) */
    int has_sky, indirect_volume;
    uint32_t sh_window;
    float sh_window_width, indirect_clamp;
    uint32_t max_lights_per_hit;
    uint32_t relocation_rays;   /* --relocation-rays; 0: the library's default */
    uint32_t counts[3], passes, bounces, octmap_res;
    int has_spacing, has_counts, has_bounds, has_rays, has_seed, has_bounces;
    int json, validation, verify, has_probe;
    int portable_kernels;       /* --portable-kernels: pb_context_desc.portable_kernels */
    uint32_t scene_loads;       /* --scene-loads: pb_context_desc.scene_loads (pb_scene_loads) */
    int face_normals;           /* --shading-normals face: pb_scene_desc.face_normals */
    int no_normal_maps;         /* --normal-maps off: pb_scene_desc.no_normal_maps */
    int emitters_by_area;       /* --emitter-sampling area: pb_bake_desc.emitters_by_area */
    uint32_t schedule;          /* --schedule: pb_bake_desc.schedule (pb_bake_schedule) */
    uint32_t paths_per_lane;    /* --schedule restart:K (0: the default) */
    uint32_t probes, rays, seed, probe;
    cli_log log;
    /* render */
    const char *volume, *mode, *atlas, *sh_view, *reference;
    const char *seams_of;   /* render --mode diff: seam metrics on another (sparse) volume's seams */
    double eye[3], target[3], up[3]; /* world coordinates: double, as bounds */
    float fov_deg, exposure;
    int has_eye, has_target, has_up, has_camera, has_exposure, pfm, show_probes;
    uint32_t camera, width, height, spp;
    int has_spp;
    /* bake on several machines or devices */
    uint32_t shard_index, shard_count; /* --shard I/N; count 0: the whole bake */
    const char *devices;               /* --devices all|LIST */
    /* --layout sparse (docs/sparse.md) */
    int sparse;
    uint32_t max_level;                /* finest level, 0-2 (default 2) */
    int has_max_level;
    float refine_error;                /* 0: the default */
    uint32_t refine_test;              /* pb_refine_test */
    int has_refine_test;
    uint32_t refine_seams;             /* rounds of the sparse seam test */
    int has_refine_seams;
    float seam_error;                  /* the seam test's threshold (0: the refine error) */
    /* merge: OUT is `scene`, the parts follow */
    char **parts;
    uint32_t part_count;
} options;

/* "probebake: error: MESSAGE" on stderr; returns the exit code (1, or 130
 * for a cancelled run). */
int cli_fail(const pb_error *err);

/* fputs, with control characters written as \xNN (C1 controls, UTF-8's
 * U+0080..U+009F, as \uNNNN): names and messages that
 * come from a file (a light's name, an extension, a volume's device) may
 * hold escape sequences or line breaks, which a terminal would act on. */
void cli_fputs_printable(const char *s, FILE *f);
/* A usage error: exit code 2. */
int cli_usage_error(const char *fmt, const char *arg);
void cli_log_to_stderr(pb_log_level level, const char *msg, void *user);
double cli_now_ms(void);
/* Parses "a,b,c" into n floats; 1 on success. */
int cli_parse_doubles(const char *s, int n, double *out);

/* Parses argv into o (defaults first); prints --help / --version and exits
 * 0 for them. Returns 0, or the exit code of a usage error (2) after its
 * one-line message. */
int cli_parse(int argc, char **argv, options *o);
void cli_print_help(void);
void cli_options_free(options *o);

/* The commands, one file each (src/cli/cmd_*.c); each returns the exit code. */
int cmd_devices(const options *o);
int cmd_info(const options *o);
int cmd_trace(const options *o);
int cmd_inspect(const options *o);
int cmd_bake(const options *o);
int cmd_render(const options *o);
int cmd_export(const options *o);
int cmd_merge(const options *o);

/* JSON output (json.c): a quoted, escaped string on stdout, and numbers
 * (NaN and infinities as null, which JSON lacks). Returned by value: J(x).s
 * lives until the end of the printf using it; J17 keeps full double
 * precision (origins far from zero). */
typedef struct json_num {
    char s[32];
} json_num;
void json_string(const char *s);
json_num J(double x);
json_num J17(double x);

/* "s" after a count other than one: "1 probe", "2 probes" in messages */
static inline const char *cli_plural(uint64_t n)
{
    return n == 1 ? "" : "s";
}

/* Paths and relative standard errors over a volume's probes (median, p95,
 * worst), where known (volume_report.c). */
void cli_print_error_summary(FILE *out, const pb_volume *v);

/* Progress line on stderr (when show) for pb_progress_fn; returns nonzero
 * once Ctrl-C was pressed while cli_catch_sigint(1) was in force. */
typedef struct cli_progress_state {
    int show;
    double start;
    uint64_t rays_total;
} cli_progress_state;
int cli_progress(float fraction, const char *label, void *user);
/* SIGINT / SIGTERM: installed once by main; until cli_defer_signals() a
 * signal exits at once (nothing is being written), after it the signal only
 * cancels (cli_progress, cli_interrupted as the writer's pb_cancel_fn). */
void cli_catch_signals(void);
void cli_defer_signals(void);
int cli_interrupted(void *user);

/* The context a command asks for: `device`, --validation and
 * --portable-kernels; and PB_INJECT_FAULT=allocation:N or submission:N
 * (tests of the error paths): the Nth device allocation or submission fails
 * as out of memory / device lost. */
pb_context_desc cli_context_desc(const options *o, const char *device, pb_log log);
/* pb_context_create, with a device that matches nothing (or cannot run the
 * kernels) named by the option that asked for it: "--device: no Vulkan
 * device matches 'x'". */
pb_result cli_context_create(const pb_context_desc *cd, const char *option, pb_context **ctx, pb_error *err);

/* --sky / --env: refuses both at once; loads the map when --env is given
 * (env zeroed otherwise). */
pb_result cli_environment(const options *o, pb_environment *env, pb_error *err);

#endif
