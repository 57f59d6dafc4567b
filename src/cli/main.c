#define _POSIX_C_SOURCE 200809L
/* probebake: one command per file (src/cli/cmd_*.c) over the options of
 * options.c. Every failure prints one line "probebake: error: FILE: problem"
 * to stderr and exits non-zero. */
#include "cli/cli.h"

#include <string.h>

int main(int argc, char **argv)
{
    cli_catch_signals();
    options o;
    int r = cli_parse(argc, argv, &o);
    if (r) {
        cli_options_free(&o);
        return r;
    }
    static const struct {
        const char *name;
        int (*run)(const options *);
    } commands[] = {{"devices", cmd_devices}, {"info", cmd_info},     {"trace", cmd_trace},
                    {"inspect", cmd_inspect}, {"bake", cmd_bake},     {"render", cmd_render},
                    {"export", cmd_export},   {"merge", cmd_merge}};
    r = -1;
    for (size_t i = 0; i < sizeof commands / sizeof commands[0] && r < 0; ++i)
        if (!strcmp(o.command, commands[i].name))
            r = commands[i].run(&o);
    if (r < 0)
        r = cli_usage_error("unknown command '%s'", o.command);
    cli_options_free(&o);
    return r;
}
