#define _POSIX_C_SOURCE 200809L
/* JSON output helpers of the commands' --json modes. */
#include "cli/cli.h"

#include <math.h>
#include <stdio.h>

void json_string(const char *s)
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

json_num J(double x)
{
    json_num j;
    if (isfinite(x))
        snprintf(j.s, sizeof j.s, "%.9g", x);
    else
        snprintf(j.s, sizeof j.s, "null");
    return j;
}

/* Full double precision (origins far from zero). */
json_num J17(double x)
{
    json_num j = J(x);
    if (isfinite(x))
        snprintf(j.s, sizeof j.s, "%.17g", x);
    return j;
}
