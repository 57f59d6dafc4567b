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
