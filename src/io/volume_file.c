/* Probe volume files (docs/format.md): explicit little-endian serialisation,
 * atomic writes (temporary file + fsync + rename), validating reads. */
#define _POSIX_C_SOURCE 200809L
#include "common/common.h"
#include "probebake/files.h"
#include "probebake/volume.h"

#include <errno.h>
#include <stddef.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define HEADER_BYTES 512u
#define MAGIC "PBVOLUME"
#define MAX_PROBES (1u << 28)
#define DEPTH_FORMAT_F16_METRES 1u /* version 1: float16 metres (overflows past 256 m) */
#define DEPTH_FORMAT_F16_UNITS 2u  /* version 2: float16 in depth units (a power of two) */
#define SH_FORMAT_F32 1u

/* ------------------------------------------------------------ sizes */

uint64_t pb_volume_tile_halves(uint32_t n)
{
    return (uint64_t)(n + 2) * (n + 2) * 2u;
}

static uint64_t align16(uint64_t x)
{
    return (x + 15u) & ~(uint64_t)15u;
}

typedef struct layout {
    uint64_t base, offset, flags, sh, depth, accounting, sparse, end;
} layout;

/* The sparse layout section (version 4, flag PB_VOLUME_SPARSE): a 32-byte
 * head (u32 levels, cells[3], brick count, chunk count, 2 reserved), then
 * per brick u32 coord[3], level; per brick 64 u32 probe indices; one u32
 * per cell (indirection); the chunk entries. */
#define SPARSE_HEAD 32u

static uint64_t sparse_bytes(uint64_t cells, uint64_t bricks, uint64_t chunks)
{
    return SPARSE_HEAD + bricks * 16u + bricks * PB_SPARSE_BRICK_PROBES * 4u + cells * 4u + chunks * 4u;
}

/* Sections of a file of `version`: the per-probe accounting (8 bytes per
 * probe: u32 paths, f32 relative standard error) exists from version 3. */
static layout layout_of(uint32_t probes, uint32_t n, uint32_t version)
{
    layout l;
    l.base = HEADER_BYTES;
    l.offset = align16(l.base + (uint64_t)probes * 12u);
    l.flags = align16(l.offset + (uint64_t)probes * 12u);
    l.sh = align16(l.flags + (uint64_t)probes * 4u);
    l.depth = align16(l.sh + (uint64_t)probes * 27u * 4u);
    l.end = l.depth + (uint64_t)probes * pb_volume_tile_halves(n) * 2u;
    l.accounting = 0;
    if (version >= 3) {
        l.accounting = align16(l.end);
        l.end = l.accounting + (uint64_t)probes * 8u;
    }
    l.sparse = 0;
    return l;
}

/* Appends the sparse section of sp (NULL: none) to l. */
static layout with_sparse(layout l, const pb_sparse_layout *sp)
{
    if (sp) {
        l.sparse = align16(l.end);
        uint64_t cells = (uint64_t)sp->cells[0] * sp->cells[1] * sp->cells[2];
        l.end = l.sparse + sparse_bytes(cells, sp->brick_count, sp->chunk_count);
    }
    return l;
}

uint64_t pb_volume_file_bytes(const pb_volume *v)
{
    return with_sparse(layout_of(v->probe_count, v->octmap_res, PB_VOLUME_VERSION),
                       (v->flags & PB_VOLUME_SPARSE) ? v->sparse : NULL)
        .end;
}

float pb_volume_depth_unit(float max_distance)
{
    if (!(max_distance > 0.f) || !isfinite(max_distance))
        return 1.f;
    int e;
    frexpf(max_distance / 128.f, &e); /* max_distance / 128 = m 2^e, m in [0.5, 1) */
    float u = ldexpf(1.f, e);         /* >= max_distance / 128, less than twice it */
    if (ldexpf(1.f, e - 1) >= max_distance / 128.f)
        u = ldexpf(1.f, e - 1);       /* an exact power of two already */
    return u;
}

/* ------------------------------------------------------------ memory */

pb_result pb_volume_alloc(pb_volume *v, pb_error *err)
{
    if (v->probe_count == 0 || v->probe_count > MAX_PROBES)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "a volume needs 1 to %u probes, not %u", MAX_PROBES,
                       v->probe_count);
    if (v->octmap_res < 1 || v->octmap_res > 256)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "octahedral map size %u is outside 1..256", v->octmap_res);
    if (v->depth_unit == 0.f) /* derived from the rays' reach unless the caller chose one */
        v->depth_unit = pb_volume_depth_unit(v->settings.max_distance);
    size_t n = v->probe_count;
    v->base = pb_calloc_large(n * 3, sizeof(float));
    v->offset = pb_calloc_large(n * 3, sizeof(float));
    v->probe_flags = pb_calloc_large(n, sizeof(uint32_t));
    v->sh = pb_calloc_large(n * 27, sizeof(float));
    v->depth = pb_calloc_large(n * (size_t)pb_volume_tile_halves(v->octmap_res), sizeof(uint16_t));
    v->probe_paths = pb_calloc_large(n, sizeof(uint32_t));
    v->probe_std_error = pb_malloc_large(n * sizeof(float));
    if (!v->base || !v->offset || !v->probe_flags || !v->sh || !v->depth || !v->probe_paths || !v->probe_std_error) {
        pb_volume_free(v);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for %u probes", v->probe_count);
    }
    for (size_t i = 0; i < n; ++i)
        v->probe_std_error[i] = PB_STD_ERROR_UNKNOWN;
    return PB_OK;
}

void pb_volume_free_probes(pb_volume *v)
{
    free(v->base);
    free(v->offset);
    free(v->probe_flags);
    free(v->sh);
    free(v->depth);
    free(v->probe_paths);
    free(v->probe_std_error);
    v->probe_paths = NULL;
    v->probe_std_error = NULL;
    v->base = v->offset = v->sh = NULL;
    v->probe_flags = NULL;
    v->depth = NULL;
}

void pb_volume_free(pb_volume *v)
{
    pb_volume_free_probes(v);
    if (v->sparse)
        pb_sparse_layout_free(v->sparse);
    free(v->sparse);
    v->sparse = NULL;
}

void pb_volume_probe_position(const pb_volume *v, uint32_t i, double out[3])
{
    for (int k = 0; k < 3; ++k)
        out[k] = v->origin[k] + (double)v->base[3 * (size_t)i + k] + (double)v->offset[3 * (size_t)i + k];
}

/* ------------------------------------------------------------ encoding */

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; ++i)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put_u64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; ++i)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put_f32(unsigned char *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(p, u);
}

static void put_f64(unsigned char *p, double f)
{
    uint64_t u;
    memcpy(&u, &f, 8);
    put_u64(p, u);
}

static uint32_t get_u32(const unsigned char *p)
{
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i)
        v = v << 8 | p[i];
    return v;
}

static uint64_t get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i)
        v = v << 8 | p[i];
    return v;
}

static float get_f32(const unsigned char *p)
{
    uint32_t u = get_u32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

static double get_f64(const unsigned char *p)
{
    uint64_t u = get_u64(p);
    double f;
    memcpy(&f, &u, 8);
    return f;
}

/* The 512-byte header of v, whose sections lie as l says. */
static void encode_header(const pb_volume *v, const layout *l, unsigned char *b)
{
    memset(b, 0, HEADER_BYTES);
    memcpy(b, MAGIC, 8);
    put_u32(b + 8, PB_VOLUME_VERSION);
    put_u32(b + 12, HEADER_BYTES);
    put_u32(b + 16, v->flags);
    put_u32(b + 20, v->probe_count);
    for (int k = 0; k < 3; ++k) {
        put_u32(b + 24 + 4 * k, v->counts[k]);
        put_f64(b + 40 + 8 * k, v->origin[k]);
        put_f64(b + 64 + 8 * k, v->spacing[k]);
    }
    put_u32(b + 36, v->octmap_res);
    const pb_volume_settings *s = &v->settings;
    put_u64(b + 88, s->seed);
    put_u64(b + 96, s->scene_hash);
    put_u32(b + 104, s->rays_per_probe);
    put_u32(b + 108, s->passes);
    put_u32(b + 112, s->bounces);
    put_u32(b + 116, s->indirect_mode);
    put_f32(b + 120, s->target_error);
    put_f32(b + 124, s->max_distance);
    put_u32(b + 128, DEPTH_FORMAT_F16_UNITS);
    put_u32(b + 132, SH_FORMAT_F32);
    put_u64(b + 136, l->base);
    put_u64(b + 144, l->offset);
    put_u64(b + 152, l->flags);
    put_u64(b + 160, l->sh);
    put_u64(b + 168, l->depth);
    put_u32(b + 176, v->octmap_res + 2);
    put_f32(b + 180, v->depth_unit);
    const pb_volume_timings *tm = &v->timings; /* in the file's order (docs/format.md) */
    const double t[8] = {tm->load, tm->bvh, tm->upload, tm->trace, tm->sh, tm->octmap, tm->relocate, tm->total};
    for (int i = 0; i < 8; ++i)
        put_f64(b + 184 + 8 * i, t[i]);
    memcpy(b + 248, v->device, strnlen(v->device, sizeof v->device - 1));
    put_u32(b + 376, s->sh_window);
    put_f32(b + 380, s->sh_window_width);
    put_f32(b + 384, s->indirect_clamp);
    put_u32(b + 388, s->techniques);
    put_u64(b + 392, l->accounting);
    put_u32(b + 448, s->relocation_rays);
    if (v->flags & PB_VOLUME_SHARD) {
        put_u32(b + 400, v->shard.index);
        put_u32(b + 404, v->shard.count);
        put_u32(b + 408, v->shard.first);
        put_u32(b + 412, v->shard.total);
        put_u32(b + 444, v->shard.step > 1 ? v->shard.step : 0u); /* 0: contiguous, as files before it */
    }
    if (l->sparse) {
        put_u64(b + 416, l->sparse);
        put_f32(b + 424, s->refine_error);
        put_u32(b + 428, s->refine_test);
        put_u32(b + 432, s->test_pass_scale);
        put_u32(b + 436, s->seam_rounds);
        put_f32(b + 440, s->seam_error);
    }
}

/* The file, written in order as it is encoded: a volume of a million probes
 * is 1.4 GB, which a whole-file buffer would hold twice. Values pass through
 * `buf` in the file's byte order (little-endian) whatever the host's. Errors
 * stick: after one, nothing more is written. */
#define WRITER_BYTES (1u << 20)
typedef struct writer {
    pb_output *out;
    pb_error *err;
    pb_result r;
    uint64_t at;  /* bytes handed to the output */
    uint32_t n;   /* bytes waiting in buf */
    unsigned char buf[WRITER_BYTES];
} writer;

static void w_flush(writer *w)
{
    if (w->r == PB_OK && w->n)
        w->r = pb_output_put(w->out, w->buf, w->n, w->err);
    w->at += w->n;
    w->n = 0;
}

static unsigned char *w_room(writer *w, uint32_t bytes)
{
    if (w->n + bytes > WRITER_BYTES)
        w_flush(w);
    unsigned char *p = w->buf + w->n;
    w->n += bytes;
    return p;
}

static void w_u32(writer *w, uint32_t v)
{
    put_u32(w_room(w, 4), v);
}

/* Zeros up to file offset `to` (a section's 16-byte alignment). */
static void w_pad(writer *w, uint64_t to)
{
    while (w->at + w->n < to)
        *w_room(w, 1) = 0;
}

/* count values of `width` bytes (2 or 4), each in the host's order, a
 * buffer at a time (on a little-endian host the loops are copies). */
static void w_array(writer *w, const void *values, uint64_t count, uint32_t width)
{
    const unsigned char *v = values;
    while (count) {
        if (w->n + width > WRITER_BYTES)
            w_flush(w);
        uint64_t k = (WRITER_BYTES - w->n) / width;
        k = k < count ? k : count;
        unsigned char *p = w->buf + w->n;
        for (uint64_t i = 0; i < k; ++i) {
            if (width == 2) {
                uint16_t h;
                memcpy(&h, v + 2 * i, 2);
                p[2 * i] = (unsigned char)h, p[2 * i + 1] = (unsigned char)(h >> 8);
            } else {
                uint32_t x;
                memcpy(&x, v + 4 * i, 4);
                put_u32(p + 4 * i, x);
            }
        }
        w->n += (uint32_t)(k * width);
        v += k * width;
        count -= k;
    }
}

/* Every section of v after the header, in the file's order (layout l). */
static void write_sections(writer *w, const pb_volume *v, const layout *l)
{
    size_t n = v->probe_count;
    w_pad(w, l->base);
    w_array(w, v->base, 3 * n, 4);
    w_pad(w, l->offset);
    w_array(w, v->offset, 3 * n, 4);
    w_pad(w, l->flags);
    w_array(w, v->probe_flags, n, 4);
    w_pad(w, l->sh);
    w_array(w, v->sh, 27 * n, 4);
    w_pad(w, l->depth);
    w_array(w, v->depth, n * pb_volume_tile_halves(v->octmap_res), 2);
    w_pad(w, l->accounting);
    for (size_t i = 0; i < n; ++i) {
        uint32_t e;
        memcpy(&e, &v->probe_std_error[i], 4);
        w_u32(w, v->probe_paths[i]);
        w_u32(w, e);
    }
    const pb_sparse_layout *sp = l->sparse ? v->sparse : NULL;
    if (sp) {
        w_pad(w, l->sparse);
        w_u32(w, sp->levels);
        for (int k = 0; k < 3; ++k)
            w_u32(w, sp->cells[k]);
        w_u32(w, sp->brick_count);
        w_u32(w, sp->chunk_count);
        w_pad(w, l->sparse + SPARSE_HEAD);
        for (uint32_t i = 0; i < sp->brick_count; ++i) {
            for (int k = 0; k < 3; ++k)
                w_u32(w, sp->bricks[i].coord[k]);
            w_u32(w, sp->bricks[i].level);
        }
        uint64_t cells = (uint64_t)sp->cells[0] * sp->cells[1] * sp->cells[2];
        w_array(w, sp->brick_probes, (uint64_t)sp->brick_count * PB_SPARSE_BRICK_PROBES, 4);
        w_array(w, sp->indirection, cells, 4);
        w_array(w, sp->chunks, sp->chunk_count, 4);
    }
    w_flush(w);
}

/* A relative standard error is >= 0 and finite, or exactly "unknown". */
static int std_error_ok(float e)
{
    return (e >= 0.f && isfinite(e)) || e == PB_STD_ERROR_UNKNOWN;
}

/* Whether all n floats (halves) are finite: an OR over their exponent
 * bits, no branch per value, so a million probes check in a few
 * milliseconds instead of a fifth of a second. */
static int floats_finite(const float *f, size_t n)
{
    uint32_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
        uint32_t u;
        memcpy(&u, &f[i], 4);
        bad |= (u & 0x7f800000u) == 0x7f800000u;
    }
    return !bad;
}

static int halves_finite(const uint16_t *h, uint64_t n)
{
    uint32_t bad = 0;
    for (uint64_t i = 0; i < n; ++i)
        bad |= (h[i] & 0x7c00u) == 0x7c00u;
    return !bad;
}

/* The first non-finite value of the volume, as a message; NULL if none.
 * *probe: the probe holding it, UINT32_MAX for header values. */
static const char *first_nonfinite(const pb_volume *v, uint32_t *probe)
{
    *probe = UINT32_MAX;
    for (int k = 0; k < 3; ++k)
        if (!isfinite(v->origin[k]) || !isfinite(v->spacing[k]))
            return "the grid origin or spacing";
    if (!(v->depth_unit > 0.f) || !isfinite(v->depth_unit))
        return "the depth unit";
    uint64_t halves = pb_volume_tile_halves(v->octmap_res);
    for (uint32_t p = 0; p < v->probe_count; ++p) {
        if (floats_finite(v->base + 3 * (size_t)p, 3) && floats_finite(v->offset + 3 * (size_t)p, 3) &&
            floats_finite(v->sh + 27 * (size_t)p, 27) && std_error_ok(v->probe_std_error[p]) &&
            halves_finite(v->depth + halves * p, halves))
            continue;
        *probe = p; /* which value, in the order messages have always named them */
        for (int k = 0; k < 3; ++k) {
            if (!isfinite(v->base[3 * (size_t)p + k]))
                return "its position";
            if (!isfinite(v->offset[3 * (size_t)p + k]))
                return "its relocation offset";
        }
        for (int c = 0; c < 27; ++c)
            if (!isfinite(v->sh[27 * (size_t)p + c]))
                return "an SH coefficient";
        if (!std_error_ok(v->probe_std_error[p]))
            return "its standard error (>= 0, or -1 for unknown)";
        return "a depth texel";
    }
    *probe = UINT32_MAX;
    return NULL;
}

pb_result pb_volume_write_ex(const char *path, const pb_volume *v, pb_cancel_fn cancel, void *user, pb_error *err)
{
    pb_error_clear(err);
    if (!v->base || !v->offset || !v->probe_flags || !v->sh || !v->depth || !v->probe_paths || !v->probe_std_error ||
        !v->probe_count)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: volume has no probe data to write", path);
    uint32_t bad_probe;
    const char *bad = first_nonfinite(v, &bad_probe);
    if ((v->flags & PB_VOLUME_SPARSE) && !v->sparse)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: sparse volume without its layout", path);
    if (v->flags & PB_VOLUME_SPARSE) {
        pb_error why;
        if (pb_sparse_layout_validate(v->sparse, v->probe_count, &why) != PB_OK)
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: not written: %s", path, why.message);
    }
    if (bad && bad_probe == UINT32_MAX) /* the grid origin or spacing, the depth unit */
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "%s: not written: %s is NaN or infinite (no volume file holds one)", path, bad);
    if (bad)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "%s: not written: probe %u has a NaN or infinite value in %s (no volume file holds one)", path,
                       bad_probe, bad);
    const pb_sparse_layout *sp = (v->flags & PB_VOLUME_SPARSE) ? v->sparse : NULL;
    layout l = with_sparse(layout_of(v->probe_count, v->octmap_res, PB_VOLUME_VERSION), sp);
    writer *w = malloc(sizeof *w);
    if (!w)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory encoding the volume", path);
    memset(w, 0, offsetof(writer, buf));
    pb_result r = pb_output_begin(path, cancel, user, &w->out, err);
    if (r == PB_OK) {
        w->err = err;
        encode_header(v, &l, w_room(w, HEADER_BYTES));
        write_sections(w, v, &l);
        r = w->r;
        if (r == PB_OK && w->at != l.end) /* the layout and the writer disagree: a bug, never a file */
            r = pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: encoded %llu bytes of a %llu-byte layout", path,
                        (unsigned long long)w->at, (unsigned long long)l.end);
        r = r == PB_OK ? pb_output_commit(w->out, err) : (pb_output_abort(w->out), r);
    }
    free(w);
    return r;
}

pb_result pb_volume_write(const char *path, const pb_volume *v, pb_error *err)
{
    return pb_volume_write_ex(path, v, NULL, NULL, err);
}

/* Version 1 stored metres; texels past 256 m overflowed to +Inf (the
 * squares first). Rays never see farther than max_distance, so an
 * overflowed or larger texel is max_distance (squared), and the rest is
 * re-expressed in the depth unit a version-2 writer would choose. */
static float v1_reach(const pb_volume *v)
{
    return v->settings.max_distance > 0.f && isfinite(v->settings.max_distance) ? v->settings.max_distance : 65504.f;
}

static void convert_v1_depth(pb_volume *v)
{
    float maxd = v1_reach(v);
    v->depth_unit = pb_volume_depth_unit(maxd);
    float u = v->depth_unit;
    uint64_t texels = (uint64_t)v->probe_count * pb_volume_tile_halves(v->octmap_res) / 2u;
    for (uint64_t t = 0; t < texels; ++t) {
        float m1 = pb_half_to_float(v->depth[2 * t]), m2 = pb_half_to_float(v->depth[2 * t + 1]);
        m1 = m1 >= 0.f && m1 <= maxd ? m1 : maxd;          /* NaN and +Inf too */
        m2 = m2 >= 0.f && m2 <= maxd * maxd ? m2 : maxd * maxd;
        v->depth[2 * t] = pb_half_from_float(m1 / u);
        v->depth[2 * t + 1] = pb_half_from_float(m2 / u / u);
    }
}

/* The sparse section at q (its size already checked against the file). */
static pb_result read_sparse(const unsigned char *q, pb_volume *v, pb_error *err)
{
    pb_sparse_layout *sp = calloc(1, sizeof *sp);
    if (!sp)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    v->sparse = sp;
    sp->levels = get_u32(q);
    for (int k = 0; k < 3; ++k)
        sp->cells[k] = get_u32(q + 4 + 4 * k);
    sp->brick_count = get_u32(q + 16);
    sp->chunk_count = get_u32(q + 20);
    uint64_t cells = (uint64_t)sp->cells[0] * sp->cells[1] * sp->cells[2];
    if (cells == 0 || cells > (1u << 24) || sp->brick_count == 0 || sp->brick_count > (1u << 22))
        return pb_fail(err, PB_ERROR_PARSE, "sparse layout with %llu cells and %u bricks", (unsigned long long)cells,
                       sp->brick_count);
    sp->bricks = malloc((size_t)sp->brick_count * sizeof *sp->bricks);
    sp->brick_probes = malloc((size_t)sp->brick_count * PB_SPARSE_BRICK_PROBES * sizeof(uint32_t));
    sp->indirection = malloc((size_t)cells * sizeof(uint32_t));
    sp->chunks = malloc((sp->chunk_count ? sp->chunk_count : 1) * sizeof(uint32_t));
    if (!sp->bricks || !sp->brick_probes || !sp->indirection || !sp->chunks)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the sparse layout");
    q += SPARSE_HEAD;
    for (uint32_t i = 0; i < sp->brick_count; ++i, q += 16) {
        for (int k = 0; k < 3; ++k)
            sp->bricks[i].coord[k] = get_u32(q + 4 * k);
        sp->bricks[i].level = get_u32(q + 12);
    }
    for (uint64_t i = 0; i < (uint64_t)sp->brick_count * PB_SPARSE_BRICK_PROBES; ++i, q += 4)
        sp->brick_probes[i] = get_u32(q);
    for (uint64_t i = 0; i < cells; ++i, q += 4)
        sp->indirection[i] = get_u32(q);
    for (uint32_t i = 0; i < sp->chunk_count; ++i, q += 4)
        sp->chunks[i] = get_u32(q);
    return pb_sparse_layout_validate(sp, v->probe_count, err);
}

/* The header's fields into v (the file's layout: docs/format.md). */
static void decode_header(const unsigned char *h, pb_volume *v)
{
    v->flags = get_u32(h + 16);
    v->probe_count = get_u32(h + 20);
    for (int k = 0; k < 3; ++k) {
        v->counts[k] = get_u32(h + 24 + 4 * k);
        v->origin[k] = get_f64(h + 40 + 8 * k);
        v->spacing[k] = get_f64(h + 64 + 8 * k);
    }
    v->octmap_res = get_u32(h + 36);
    v->settings.seed = get_u64(h + 88);
    v->settings.scene_hash = get_u64(h + 96);
    v->settings.rays_per_probe = get_u32(h + 104);
    v->settings.passes = get_u32(h + 108);
    v->settings.bounces = get_u32(h + 112);
    v->settings.indirect_mode = get_u32(h + 116);
    v->settings.target_error = get_f32(h + 120);
    v->settings.max_distance = get_f32(h + 124);
    pb_volume_timings *tm = &v->timings; /* in the file's order */
    double *t[8] = {&tm->load, &tm->bvh, &tm->upload, &tm->trace, &tm->sh, &tm->octmap, &tm->relocate, &tm->total};
    for (int i = 0; i < 8; ++i)
        *t[i] = get_f64(h + 184 + 8 * i);
    memcpy(v->device, h + 248, sizeof v->device - 1);
    v->device[sizeof v->device - 1] = '\0';
    /* zero in files written before these fields: none, default, off */
    v->settings.sh_window = get_u32(h + 376);
    v->settings.sh_window_width = get_f32(h + 380);
    v->settings.indirect_clamp = get_f32(h + 384);
    v->settings.techniques = get_u32(h + 388);
    int sparse = (v->flags & PB_VOLUME_SPARSE) != 0;
    v->settings.refine_error = sparse ? get_f32(h + 424) : 0.f;
    v->settings.refine_test = sparse ? get_u32(h + 428) : 0u;
    v->settings.test_pass_scale = sparse ? get_u32(h + 432) : 0u;
    v->settings.seam_rounds = sparse ? get_u32(h + 436) : 0u;
    v->settings.seam_error = sparse ? get_f32(h + 440) : 0.f;
    v->settings.relocation_rays = get_u32(h + 448);
    memset(&v->shard, 0, sizeof v->shard);
    if (v->flags & PB_VOLUME_SHARD)
        v->shard = (pb_volume_shard){get_u32(h + 400), get_u32(h + 404), get_u32(h + 408), get_u32(h + 412),
                                     get_u32(h + 444) ? get_u32(h + 444) : 1u};
}

/* What is wrong with a decoded header, before any section is read; NULL
 * when nothing is. */
static const char *header_problem(const unsigned char *h, const pb_volume *v, uint32_t version)
{
    uint64_t grid_probes = v->flags & PB_VOLUME_SHARD ? v->shard.total : v->probe_count;
    const pb_volume_shard *sd = &v->shard;
    if (get_u32(h + 12) != HEADER_BYTES)
        return "unexpected header size";
    if (v->probe_count == 0 || v->probe_count > MAX_PROBES)
        return "probe count out of range";
    if (v->octmap_res < 1 || v->octmap_res > 256 || get_u32(h + 176) != v->octmap_res + 2)
        return "octahedral map size out of range";
    if (get_u32(h + 128) != (version == 1 ? DEPTH_FORMAT_F16_METRES : DEPTH_FORMAT_F16_UNITS) ||
        get_u32(h + 132) != SH_FORMAT_F32)
        return "unknown SH or depth format";
    if (version >= 2 && (!(get_f32(h + 180) > 0.f) || !isfinite(get_f32(h + 180))))
        return "depth unit not a positive finite number";
    if ((v->flags & PB_VOLUME_SHARD) &&
        (sd->index >= sd->count || sd->total > MAX_PROBES ||
         ((v->flags & PB_VOLUME_SPARSE) ? sd->step > 1 || sd->first >= sd->total /* bricks */
          : sd->step <= 1 ? (uint64_t)sd->first + v->probe_count > sd->total
                          : sd->step != sd->count || sd->first != sd->index ||
                                v->probe_count != pb_shard_dealt_count(sd->total, sd->index, sd->count))))
        return "shard part out of range";
    if ((v->flags & PB_VOLUME_GRID) && (uint64_t)v->counts[0] * v->counts[1] * v->counts[2] != grid_probes)
        return "grid counts do not match the probe count";
    if ((v->flags & PB_VOLUME_SPARSE) && (version < 4 || (v->flags & PB_VOLUME_GRID)))
        return "sparse flag in a grid or a file older than version 4";
    return NULL;
}

/* The sections' offsets: from the header's counts, the sparse section's
 * size from its own head (read from f); what disagrees with the offsets the
 * header states goes to *bad. */
static layout sections_of(const unsigned char *h, const pb_volume *v, uint32_t version, FILE *f, uint64_t file_bytes,
                          const char **bad)
{
    layout l = layout_of(v->probe_count, v->octmap_res, version);
    unsigned char sh_head[SPARSE_HEAD];
    if (v->flags & PB_VOLUME_SPARSE) {
        uint64_t at = align16(l.end);
        if (get_u64(h + 416) != at)
            *bad = "section offsets do not match the sizes";
        else if (file_bytes < at + SPARSE_HEAD || fseek(f, (long)at, SEEK_SET) != 0 ||
                 fread(sh_head, 1, SPARSE_HEAD, f) != SPARSE_HEAD)
            *bad = "truncated sparse layout";
        else if (get_u32(sh_head + 4) >= (1u << 20) || get_u32(sh_head + 8) >= (1u << 20) ||
                 get_u32(sh_head + 12) >= (1u << 20))
            *bad = "sparse layout with too many cells";
        else {
            uint64_t cells = (uint64_t)get_u32(sh_head + 4) * get_u32(sh_head + 8) * get_u32(sh_head + 12);
            if ((v->flags & PB_VOLUME_SHARD) && v->shard.total != cells)
                *bad = "shard part out of range"; /* a sparse part counts coarsest bricks */
            l.sparse = at;
            l.end = at + sparse_bytes(cells, get_u32(sh_head + 16), get_u32(sh_head + 20));
        }
    } else if (version >= 4 && get_u64(h + 416) != 0) {
        *bad = "sparse layout offset in a volume without the sparse flag";
    }
    if (!*bad && (get_u64(h + 136) != l.base || get_u64(h + 144) != l.offset || get_u64(h + 152) != l.flags ||
                  get_u64(h + 160) != l.sh || get_u64(h + 168) != l.depth ||
                  (version >= 3 && get_u64(h + 392) != l.accounting)))
        *bad = "section offsets do not match the sizes";
    return l;
}

/* count values of `width` bytes (2 or 4), little-endian, from file offset
 * `at` into the host array `values`: read straight into it, a piece at a
 * time, each value's bytes then put in host order in place (nothing to do
 * on a little-endian host, the pass skipped where the compiler says so).
 * 0 on a short read. */
#define READER_PIECE_BYTES ((size_t)1 << 24)
static int read_array(FILE *f, uint64_t at, void *values, uint64_t count, uint32_t width)
{
    if (fseeko(f, (off_t)at, SEEK_SET) != 0)
        return 0;
    unsigned char *out = values;
    while (count) {
        size_t k = (size_t)(count < READER_PIECE_BYTES / width ? count : READER_PIECE_BYTES / width);
        if (fread(out, width, k, f) != k)
            return 0;
#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
        for (size_t i = 0; i < k; ++i) {
            if (width == 2) {
                uint16_t h = (uint16_t)(out[2 * i] | out[2 * i + 1] << 8);
                memcpy(out + 2 * i, &h, 2);
            } else {
                uint32_t x = get_u32(out + 4 * i);
                memcpy(out + 4 * i, &x, 4);
            }
        }
#endif
        out += k * width;
        count -= k;
    }
    return 1;
}

/* The grid sections of f into v (allocated), each read straight into its
 * array (the probes' accounting through one small buffer): no copy of the
 * whole file. Before version 3 a probe's paths are what the
 * header says every probe got (an upper bound under --target-error) and its
 * error is unknown. *bad_probe: the first probe whose standard error is
 * negative or not finite, or UINT32_MAX. 0 on a short read. */
#define READER_BYTES (1u << 20)
static int read_sections(FILE *f, const layout *l, uint32_t version, pb_volume *v, uint32_t *bad_probe)
{
    size_t n = v->probe_count;
    unsigned char *buf = malloc(READER_BYTES);
    int ok = buf && read_array(f, l->base, v->base, 3 * n, 4) && read_array(f, l->offset, v->offset, 3 * n, 4) &&
             read_array(f, l->flags, v->probe_flags, n, 4) && read_array(f, l->sh, v->sh, 27 * n, 4) &&
             read_array(f, l->depth, v->depth, n * pb_volume_tile_halves(v->octmap_res), 2);
    *bad_probe = UINT32_MAX;
    if (ok && version < 3) {
        uint64_t paths = (uint64_t)v->settings.passes * v->settings.rays_per_probe;
        for (size_t i = 0; i < n; ++i)
            v->probe_paths[i] = paths > UINT32_MAX ? UINT32_MAX : (uint32_t)paths;
    } else if (ok) { /* u32 paths and f32 error, interleaved */
        ok = fseeko(f, (off_t)l->accounting, SEEK_SET) == 0;
        for (size_t i = 0; ok && i < n; i += READER_BYTES / 8) {
            size_t k = n - i < READER_BYTES / 8 ? n - i : READER_BYTES / 8;
            ok = fread(buf, 8, k, f) == k;
            for (size_t j = 0; ok && j < k; ++j) {
                v->probe_paths[i + j] = get_u32(buf + 8 * j);
                v->probe_std_error[i + j] = get_f32(buf + 8 * j + 4);
                if (!std_error_ok(v->probe_std_error[i + j]) && *bad_probe == UINT32_MAX)
                    *bad_probe = (uint32_t)(i + j);
            }
        }
    }
    free(buf);
    return ok;
}

/* A volume file open for reading, its header checked. */
typedef struct checked_file {
    FILE *f;                       /* the caller closes it */
    layout l;                      /* its sections */
    uint32_t version;
    unsigned char h[HEADER_BYTES]; /* the header's bytes */
} checked_file;

/* Opens path and checks everything its header claims, down to the file's
 * exact size, before anything is allocated: *v gets the header's fields (no
 * arrays), *c the open file. */
static pb_result open_checked(const char *path, pb_volume *v, checked_file *c, pb_error *err)
{
    FILE **f = &c->f;
    layout *l = &c->l;
    uint32_t *version = &c->version;
    unsigned char *h = c->h;
    *l = (layout){0};
    *version = 0;
    pb_error_clear(err);
    memset(v, 0, sizeof *v);
    uint64_t file_bytes;
    pb_result opened = pb_input_open(path, UINT64_MAX, f, &file_bytes, err); /* regular files only */
    if (opened != PB_OK)
        return opened;
    size_t got = fread(h, 1, HEADER_BYTES, *f);
    const char *bad = NULL;
    pb_result r = PB_OK;
    if (got < 8 || memcmp(h, MAGIC, 8) != 0) {
        r = pb_fail(err, PB_ERROR_PARSE, "%s: not a probebake volume (bad magic)", path);
    } else if (got < HEADER_BYTES) {
        r = pb_fail(err, PB_ERROR_PARSE, "%s: truncated header (%zu of %u bytes)", path, got, HEADER_BYTES);
    } else if ((*version = get_u32(h + 8)) > PB_VOLUME_VERSION || *version == 0) {
        r = pb_fail(err, PB_ERROR_UNSUPPORTED, "%s: volume format version %u; this build reads versions 1 to %u", path,
                    *version, PB_VOLUME_VERSION);
    } else {
        decode_header(h, v);
        bad = header_problem(h, v, *version);
        if (!bad)
            *l = sections_of(h, v, *version, *f, file_bytes, &bad);
        if (bad)
            r = pb_fail(err, PB_ERROR_PARSE, "%s: %s", path, bad);
        else if (file_bytes != l->end)
            r = pb_fail(err, PB_ERROR_PARSE, "%s: file is %llu bytes, the header describes %llu (truncated?)", path,
                        (unsigned long long)file_bytes, (unsigned long long)l->end);
    }
    if (r != PB_OK) {
        fclose(*f);
        *f = NULL;
        memset(v, 0, sizeof *v);
    }
    return r;
}

/* The depth unit a file's texels are in once read: its own, or for version
 * 1 (metres) the one convert_v1_depth converts them to. */
static float depth_unit_read(const unsigned char *h, const pb_volume *v, uint32_t version)
{
    return version != 1 ? get_f32(h + 180) : pb_volume_depth_unit(v1_reach(v));
}

pb_result pb_volume_read_header(const char *path, pb_volume *v, pb_error *err)
{
    checked_file c;
    pb_result r = open_checked(path, v, &c, err);
    if (r != PB_OK)
        return r;
    fclose(c.f);
    v->file_version = c.version;
    v->depth_unit = depth_unit_read(c.h, v, c.version);
    return PB_OK;
}

pb_result pb_volume_read(const char *path, pb_volume *v, pb_error *err)
{
    checked_file c;
    pb_result opened = open_checked(path, v, &c, err);
    if (opened != PB_OK)
        return opened;
    FILE *f = c.f;
    const layout l = c.l;
    uint32_t version = c.version;
    const unsigned char *h = c.h;
    pb_result r = pb_volume_alloc(v, err);
    uint32_t bad_probe = UINT32_MAX;
    if (r == PB_OK && !read_sections(f, &l, version, v, &bad_probe))
        r = pb_fail(err, PB_ERROR_IO, "%s: read failed", path);
    unsigned char *sparse = NULL;
    if (r == PB_OK && l.sparse) { /* its errors come before a bad probe's, as they always did */
        sparse = malloc((size_t)(l.end - l.sparse));
        if (!sparse)
            r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of memory", path);
        else if (fseeko(f, (off_t)l.sparse, SEEK_SET) != 0 || fread(sparse, 1, (size_t)(l.end - l.sparse), f) !=
                                                                  l.end - l.sparse)
            r = pb_fail(err, PB_ERROR_IO, "%s: read failed", path);
        pb_error why;
        pb_result sr = r == PB_OK ? read_sparse(sparse, v, &why) : PB_OK;
        if (sr != PB_OK)
            r = pb_fail(err, sr == PB_ERROR_OUT_OF_HOST_MEMORY ? sr : PB_ERROR_PARSE, "%s: %s", path, why.message);
    }
    free(sparse);
    fclose(f);
    if (r != PB_OK) {
        pb_volume_free(v);
        return r;
    }
    v->file_version = version;
    if (bad_probe != UINT32_MAX) {
        pb_volume_free(v);
        return pb_fail(err, PB_ERROR_PARSE, "%s: probe %u has a negative or non-finite standard error", path,
                       bad_probe);
    }
    if (version == 1)
        convert_v1_depth(v);
    else
        v->depth_unit = depth_unit_read(h, v, version);
    /* what the writer refuses the reader refuses too (version 1's infinite
     * texels are converted above) */
    uint32_t nf_probe;
    const char *nf = first_nonfinite(v, &nf_probe);
    if (nf) {
        char what[160];
        if (nf_probe == UINT32_MAX)
            snprintf(what, sizeof what, "%s is NaN or infinite", nf);
        else
            snprintf(what, sizeof what, "probe %u has a NaN or infinite value in %s", nf_probe, nf);
        pb_volume_free(v);
        return pb_fail(err, PB_ERROR_PARSE, "%s: %s", path, what);
    }
    return PB_OK;
}
