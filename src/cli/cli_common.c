#define _POSIX_C_SOURCE 200809L
/* What every command shares: logging to stderr, the monotonic clock, the
 * one-line error, usage errors, number lists, fault injection, the
 * environment options, and Ctrl-C handling with the progress line. */
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
    fprintf(stderr, "probebake: %s: ", names[level]);
    cli_fputs_printable(msg, stderr);
    fputc('\n', stderr);
}

void cli_fputs_printable(const char *s, FILE *f)
{
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s, next = (unsigned char)s[1];
        if (c < 0x20 || c == 0x7f)
            fprintf(f, "\\x%02x", c);
        else if (c == 0xc2 && next >= 0x80 && next <= 0x9f) /* U+0080..U+009F: C1 controls (CSI is U+009B) */
            fprintf(f, "\\u%04x", next), ++s;
        else
            fputc(c, f);
    }
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
    fputs("probebake: error: ", stderr);
    cli_fputs_printable(err->message[0] ? err->message : pb_result_name(err->code), stderr);
    fputc('\n', stderr);
    /* 128 + the signal, as shells report it (SIGINT 130, SIGTERM 143) */
    return err->code == PB_ERROR_CANCELLED ? 128 + (interrupted ? (int)interrupted : SIGINT) : 1;
}

int cli_parse_doubles(const char *s, int n, double *out)
{
    for (int k = 0; k < n; ++k) {
        char *end = NULL;
        double v = strtod(s, &end);
        if (end == s || !isfinite(v))
            return 0;
        out[k] = v;
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

pb_context_desc cli_context_desc(const options *o, const char *device, pb_log log)
{
    pb_context_desc cd = {device, (uint32_t)o->validation, 0, 0, log};
    cd.portable_kernels = (uint32_t)o->portable_kernels;
    cd.scene_loads = o->scene_loads;
    /* PB_INJECT_FAULT=allocation:N | submission:N | pipeline:N fails that call (test_cli's failure paths) */
    const char *f = getenv("PB_INJECT_FAULT");
    unsigned n = 0;
    if (f && sscanf(f, "allocation:%u", &n) == 1)
        cd.fail_allocation = n;
    else if (f && sscanf(f, "submission:%u", &n) == 1)
        cd.fail_submission = n;
    else if (f && sscanf(f, "pipeline:%u", &n) == 1)
        cd.fail_pipeline = n;
    return cd;
}

pb_result cli_context_create(const pb_context_desc *cd, const char *option, pb_context **ctx, pb_error *err)
{
    pb_result r = pb_context_create(cd, ctx, err);
    if (r == PB_ERROR_NO_DEVICE && cd->device && cd->device[0] && option) {
        char was[sizeof err->message];
        memcpy(was, err->message, sizeof was);
        /* the option first; a message too long for both loses its end */
        size_t at = (size_t)snprintf(err->message, sizeof err->message, "%.100s: ", option);
        snprintf(err->message + at, sizeof err->message - at, "%.*s", (int)(sizeof err->message - at - 1), was);
    }
    return r;
}

pb_result cli_environment(const options *o, pb_environment *env, pb_error *err)
{
    memset(env, 0, sizeof *env);
    if (o->env && o->has_sky) {
        snprintf(err->message, sizeof err->message, "--sky and --env both give the environment: choose one");
        return err->code = PB_ERROR_INVALID_ARGUMENT;
    }
    if (!o->env)
        return PB_OK;
    pb_result r = pb_environment_load(o->env, o->env_intensity, o->env_rotation, env, err);
    if (r == PB_OK && env->negative_values)
        fprintf(stderr, "probebake: warning: %s: %llu channel values below 0 (down to %g; lossy compression) read as 0\n",
                o->env, (unsigned long long)env->negative_values, env->most_negative);
    return r;
}

int cli_usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "probebake: error: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, " (see probebake --help)\n");
    return 2;
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
