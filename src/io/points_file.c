/* Probe points files (--points): a small JSON document, read by a strict
 * little parser (the project has no JSON library on the C side):
 *
 *   { "spacing": 0.5,                       optional: relocation bound (45 % of it); 0 = none
 *     "points": [ [x, y, z], ...             positions in scene (glTF world) coordinates, or
 *                 { "id": 12, "position": [x, y, z] }, ... ] }
 *
 * Ids key each probe's random numbers (default: its index in the array), so
 * a subset of a grid's probes given with their grid indices as ids bakes to
 * the same values as in the whole grid. */
#include "common/common.h"
#include "probebake/bake.h"
#include "probebake/files.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct cursor {
    const char *s, *base, *path;
    pb_error *err;
    int failed;
} cursor;

static int compare_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static void ws(cursor *c)
{
    while (*c->s && isspace((unsigned char)*c->s))
        c->s++;
}

static int expect(cursor *c, char ch)
{
    ws(c);
    if (*c->s != ch) {
        if (!c->failed)
            pb_fail(c->err, PB_ERROR_PARSE, "%s: expected '%c' at byte %ld", c->path, ch, (long)(c->s - c->base));
        c->failed = 1;
        return 0;
    }
    c->s++;
    return 1;
}

static int number(cursor *c, double *out)
{
    ws(c);
    char *end = NULL;
    errno = 0;
    *out = strtod(c->s, &end);
    if (end == c->s || errno == ERANGE || !isfinite(*out)) {
        if (!c->failed)
            pb_fail(c->err, PB_ERROR_PARSE, "%s: expected a finite number near \"%.12s\"", c->path, c->s);
        c->failed = 1;
        return 0;
    }
    c->s = end;
    return 1;
}

static int key(cursor *c, char *buf, size_t size)
{
    if (!expect(c, '"'))
        return 0;
    size_t n = 0;
    while (*c->s && *c->s != '"' && n + 1 < size)
        buf[n++] = *c->s++;
    buf[n] = '\0';
    return expect(c, '"') && expect(c, ':');
}

/* After a member or element: 1 when a ',' announces another, 0 when the
 * container ends with `close` (or on an error, which sets c->failed). After
 * an earlier error it reads nothing: the next member's parse would replace
 * that error's message with its own (a bad "id" was reported as an unknown
 * key "position" at the top level). */
static int more(cursor *c, char close)
{
    if (c->failed)
        return 0;
    ws(c);
    if (*c->s == ',') {
        c->s++;
        return 1;
    }
    expect(c, close);
    return 0;
}

static int vec3(cursor *c, double v[3])
{
    return expect(c, '[') && number(c, &v[0]) && expect(c, ',') && number(c, &v[1]) && expect(c, ',') &&
           number(c, &v[2]) && expect(c, ']');
}

/* One element of "points": [x, y, z] or {"id": i, "position": [x, y, z]},
 * appended to out (growing it); its id defaults to its index. 0 on error. */
static int read_point(cursor *c, pb_points *out, uint32_t *cap)
{
    if (out->count == *cap) {
        *cap = *cap ? 2 * *cap : 64;
        double *pp = realloc(out->positions, (size_t)*cap * 3 * sizeof(double));
        uint32_t *ii = pp ? realloc(out->ids, (size_t)*cap * sizeof(uint32_t)) : NULL;
        if (pp)
            out->positions = pp;
        if (ii)
            out->ids = ii;
        if (!pp || !ii) {
            pb_fail(c->err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of memory", c->path);
            c->failed = 1;
            return 0;
        }
    }
    double *v = out->positions + 3 * (size_t)out->count;
    uint32_t id = out->count;
    ws(c);
    if (*c->s == '[') {
        vec3(c, v);
    } else if (expect(c, '{')) {
        int have_pos = 0;
        for (;;) {
            char pk[32];
            if (!key(c, pk, sizeof pk))
                break;
            if (!strcmp(pk, "id")) {
                double x;
                if (!number(c, &x))
                    break;
                if (!(x >= 0 && x < 4294967295.0 && x == floor(x))) {
                    pb_fail(c->err, PB_ERROR_PARSE, "%s: point %u: id must be a non-negative integer", c->path,
                            out->count);
                    c->failed = 1;
                    break;
                }
                id = (uint32_t)x;
            } else if (!strcmp(pk, "position")) {
                have_pos = vec3(c, v);
            } else {
                pb_fail(c->err, PB_ERROR_PARSE, "%s: point %u: unknown key \"%s\"", c->path, out->count, pk);
                c->failed = 1;
                break;
            }
            if (!more(c, '}'))
                break;
        }
        if (!c->failed && !have_pos) {
            pb_fail(c->err, PB_ERROR_PARSE, "%s: point %u has no position", c->path, out->count);
            c->failed = 1;
        }
    }
    for (int k = 0; k < 3 && !c->failed; ++k)
        if (!(fabs(v[k]) <= PB_MAX_COORDINATE)) {
            pb_fail(c->err, PB_ERROR_PARSE, "%s: point %u at (%g, %g, %g): coordinates must be within +-%g m",
                    c->path, out->count, v[0], v[1], v[2], PB_MAX_COORDINATE);
            c->failed = 1;
        }
    if (c->failed)
        return 0;
    out->ids[out->count++] = id;
    return 1;
}

pb_result pb_points_read(const char *path, pb_points *out, pb_error *err)
{
    pb_error_clear(err);
    memset(out, 0, sizeof *out);
    unsigned char *bytes;
    uint64_t size;
    pb_result rr = pb_input_read(path, 256u << 20, &bytes, &size, err); /* regular files only, at most 256 MiB */
    if (rr != PB_OK)
        return rr;
    char *text = (char *)bytes;
    cursor c = {text, text, path, err, 0};
    uint32_t cap = 0;
    int have_points = 0;
    if (expect(&c, '{')) {
        for (;;) {
            char k[32];
            if (!key(&c, k, sizeof k))
                break;
            if (!strcmp(k, "spacing")) {
                double sp;
                if (!number(&c, &sp))
                    break;
                if (!(sp >= 0)) {
                    pb_fail(err, PB_ERROR_PARSE, "%s: spacing must be >= 0", path);
                    c.failed = 1;
                    break;
                }
                out->spacing = sp;
            } else if (!strcmp(k, "points")) {
                have_points = 1;
                if (!expect(&c, '['))
                    break;
                ws(&c);
                if (*c.s == ']') /* an empty array: reported as "no points" below */
                    c.s++;
                else
                    while (read_point(&c, out, &cap) && more(&c, ']'))
                        ;
            } else {
                pb_fail(err, PB_ERROR_PARSE, "%s: unknown key \"%s\" (expected \"points\" or \"spacing\")", path, k);
                c.failed = 1;
                break;
            }
            if (!more(&c, '}'))
                break;
        }
    }
    free(text);
    if (!c.failed && (!have_points || out->count == 0))
        pb_fail(err, PB_ERROR_PARSE, "%s: no points", path), c.failed = 1;
    /* ids must be unique: they key the random numbers */
    if (!c.failed) {
        uint32_t *sorted = malloc((size_t)out->count * sizeof *sorted);
        if (sorted) {
            memcpy(sorted, out->ids, (size_t)out->count * sizeof *sorted);
            qsort(sorted, out->count, sizeof *sorted, compare_u32);
            for (uint32_t i = 1; i < out->count; ++i)
                if (sorted[i] == sorted[i - 1]) {
                    pb_fail(err, PB_ERROR_PARSE, "%s: two points share id %u", path, sorted[i]);
                    c.failed = 1;
                    break;
                }
            free(sorted);
        }
    }
    if (c.failed) {
        pb_points_free(out);
        return err ? err->code : PB_ERROR_PARSE;
    }
    return PB_OK;
}

void pb_points_free(pb_points *p)
{
    free(p->positions);
    free(p->ids);
    memset(p, 0, sizeof *p);
}
