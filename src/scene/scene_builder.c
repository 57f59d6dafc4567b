#include "scene/scene_builder.h"
#include "common/common.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Grows *ptr (elements of `size` bytes) so that `need` fit. Returns 0 on OOM. */
static int grow(void **ptr, uint64_t *capacity, uint64_t need, size_t size)
{
    if (need <= *capacity)
        return 1;
    uint64_t cap = *capacity ? *capacity : 64;
    while (cap < need)
        cap *= 2;
    void *p = pb_realloc_large(*ptr, (size_t)(cap * size));
    if (!p)
        return 0;
    *ptr = p;
    *capacity = cap;
    return 1;
}

/* Gives back what *ptr holds beyond `count` elements (at least one stays);
 * where the system keeps the block, the block stays as it was. */
static void shrink(void **ptr, uint64_t count, size_t size)
{
    void *p = realloc(*ptr, (size_t)((count ? count : 1) * size));
    if (p)
        *ptr = p;
}

static int grow32(void **ptr, uint32_t *capacity, uint64_t need, size_t size)
{
    uint64_t cap = *capacity;
    if (need > UINT32_MAX)
        return 0;
    int ok = grow(ptr, &cap, need, size);
    *capacity = (uint32_t)cap;
    return ok;
}

void pb_sb_init(pb_scene_builder *b, pb_log log)
{
    memset(b, 0, sizeof *b);
    b->log = log;
}

void pb_sb_free(pb_scene_builder *b)
{
    free(b->pos);
    free(b->nrm);
    free(b->uv);
    free(b->rgba);
    free(b->tan);
    free(b->mat);
    free(b->materials);
    free(b->textures);
    free(b->texels);
    free(b->lights);
    free(b->light_world);
    free(b->cameras);
    free(b->camera_world);
    pb_log log = b->log;
    memset(b, 0, sizeof *b);
    b->log = log;
}

/* out = v / |v|; 0 when v has no direction (zero, or not finite). In
 * double: a float vector of length 1e-20 squares to a denormal, whose few
 * bits would leave it far from unit length (the fuzzer found one). */
static int normalize3f(const float v[3], float out[3])
{
    double x = v[0], y = v[1], z = v[2], l = sqrt(x * x + y * y + z * z);
    if (!(l > 0.0 && isfinite(l)))
        return 0;
    out[0] = (float)(x / l), out[1] = (float)(y / l), out[2] = (float)(z / l);
    return 1;
}

static int finite9(const double p[9])
{
    for (int i = 0; i < 9; ++i)
        if (!isfinite(p[i]))
            return 0;
    return 1;
}

int pb_sb_reserve(pb_scene_builder *b, uint64_t n, int colours, int tangents)
{
    if (b->count + n > b->capacity) {
        /* all the per-triangle arrays share one capacity and grow together */
        uint64_t cap = b->capacity;
        if (!grow((void **)&b->pos, &cap, b->count + n, 9 * sizeof(double))) {
            b->out_of_memory = 1;
            return 0;
        }
        float *nrm = pb_realloc_large(b->nrm, (size_t)(cap * 9 * sizeof(float)));
        if (nrm)
            b->nrm = nrm;
        float *uvs = nrm ? pb_realloc_large(b->uv, (size_t)(cap * 6 * sizeof(float))) : NULL;
        if (uvs)
            b->uv = uvs;
        uint32_t *mat = uvs ? pb_realloc_large(b->mat, (size_t)(cap * sizeof(uint32_t))) : NULL;
        if (mat)
            b->mat = mat;
        float *cols = b->rgba && mat ? pb_realloc_large(b->rgba, (size_t)(cap * 12 * sizeof(float))) : NULL;
        if (cols)
            b->rgba = cols;
        float *tans = b->tan && mat ? pb_realloc_large(b->tan, (size_t)(cap * 12 * sizeof(float))) : NULL;
        if (tans)
            b->tan = tans;
        if (!mat || (b->rgba && !cols) || (b->tan && !tans)) {
            b->out_of_memory = 1;
            return 0;
        }
        b->capacity = cap;
    }
    if (colours && !b->rgba) { /* the first coloured triangles: the ones before are white */
        b->rgba = pb_malloc_large((size_t)(b->capacity * 12 * sizeof(float)));
        if (!b->rgba) {
            b->out_of_memory = 1;
            return 0;
        }
        for (uint64_t k = 0; k < 12 * b->count; ++k)
            b->rgba[k] = 1.f;
        b->rgba_pending = 1;
    }
    if (tangents && !b->tan) { /* the first triangles with tangents: the ones before have none */
        b->tan = pb_malloc_large((size_t)(b->capacity * 12 * sizeof(float)));
        if (!b->tan) {
            b->out_of_memory = 1;
            return 0;
        }
        memset(b->tan, 0, (size_t)(12 * b->count * sizeof(float)));
        b->tan_pending = 1;
    }
    return 1;
}

int pb_sb_put_triangle(pb_scene_builder *b, uint64_t slot, const double p[9], const float *n, const float *uv,
                       const float *rgba, const float *tangent, uint32_t material)
{
    if (!finite9(p))
        return 0;
    uint64_t i = slot;
    memcpy(b->pos + 9 * i, p, 9 * sizeof(double));
    for (int k = 0; b->rgba && k < 12; ++k) /* glTF colours are in [0, 1] */
        b->rgba[12 * i + k] = !rgba ? 1.f : isfinite(rgba[k]) ? fminf(fmaxf(rgba[k], 0.f), 1.f) : 1.f;
    /* A vertex normal that cannot be normalized (absent, zero, not finite)
     * is the face normal: shading normals bend light. NaN marks it here;
     * pb_sb_finish takes the face normal of the triangle as stored (float,
     * rebased), so that it agrees with the triangle the kernels see. */
    float *dn = b->nrm + 9 * i;
    for (int v = 0; v < 3; ++v)
        if (!n || !normalize3f(n + 3 * v, dn + 3 * v))
            dn[3 * v] = dn[3 * v + 1] = dn[3 * v + 2] = NAN;
    for (int v = 0; b->tan && v < 3; ++v) { /* unit, w +-1; else none (0) */
        float *dt = b->tan + 12 * i + 4 * v;
        if (tangent && isfinite(tangent[4 * v + 3]) && normalize3f(tangent + 4 * v, dt))
            dt[3] = tangent[4 * v + 3] < 0.f ? -1.f : 1.f;
        else
            dt[0] = dt[1] = dt[2] = dt[3] = 0.f;
    }
    float *du = b->uv + 6 * i;
    for (int k = 0; k < 6; ++k)
        du[k] = (uv && isfinite(uv[k])) ? uv[k] : 0.f;
    b->mat[i] = material;
    return 1;
}

/* The kept slots of the batch moved down over the dropped ones, in order. */
static void compact(pb_scene_builder *b, uint64_t n, const unsigned char *keep)
{
    uint64_t kept = b->count;
    for (uint64_t k = 0; k < n; ++k) {
        uint64_t i = b->count + k;
        if (!keep[k]) {
            b->stats.dropped_nonfinite++;
            continue;
        }
        if (kept != i) { /* down over a dropped slot */
            memcpy(b->pos + 9 * kept, b->pos + 9 * i, 9 * sizeof(double));
            memcpy(b->nrm + 9 * kept, b->nrm + 9 * i, 9 * sizeof(float));
            memcpy(b->uv + 6 * kept, b->uv + 6 * i, 6 * sizeof(float));
            b->mat[kept] = b->mat[i];
            if (b->rgba)
                memcpy(b->rgba + 12 * kept, b->rgba + 12 * i, 12 * sizeof(float));
            if (b->tan)
                memcpy(b->tan + 12 * kept, b->tan + 12 * i, 12 * sizeof(float));
        }
        ++kept;
    }
    b->count = kept;
}

void pb_sb_commit(pb_scene_builder *b, uint64_t n, const unsigned char *keep)
{
    uint64_t first = b->count;
    b->stats.triangles_in += n;
    if (keep)
        compact(b, n, keep);
    else
        b->count += n;
    /* colours made for a batch that kept no triangle (empty, or all
     * non-finite): a scene has colours only once a coloured triangle stays */
    if (b->rgba_pending && b->count == first) {
        free(b->rgba);
        b->rgba = NULL;
    }
    if (b->tan_pending && b->count == first) { /* the same for tangents */
        free(b->tan);
        b->tan = NULL;
    }
    b->rgba_pending = 0;
    b->tan_pending = 0;
}

int pb_sb_add_triangle(pb_scene_builder *b, const double p[9], const float *n, const float *uv, const float *rgba,
                       uint32_t material)
{
    if (!finite9(p)) { /* dropped before it takes room */
        b->stats.triangles_in++;
        b->stats.dropped_nonfinite++;
        return 1;
    }
    if (!pb_sb_reserve(b, 1, rgba != NULL, 0))
        return 0;
    pb_sb_put_triangle(b, b->count, p, n, uv, rgba, NULL, material);
    pb_sb_commit(b, 1, NULL);
    return 1;
}

int32_t pb_sb_add_material(pb_scene_builder *b, const pb_material *m)
{
    if (!grow32((void **)&b->materials, &b->material_capacity, (uint64_t)b->material_count + 1, sizeof *m)) {
        b->out_of_memory = 1;
        return -1;
    }
    b->materials[b->material_count] = *m;
    return (int32_t)b->material_count++;
}

int32_t pb_sb_add_texture(pb_scene_builder *b, const void *texels, uint32_t width, uint32_t height,
                          uint32_t wrap_s, uint32_t wrap_t, uint32_t srgb)
{
    uint64_t n = (uint64_t)width * height;
    if (!grow32((void **)&b->textures, &b->texture_capacity, (uint64_t)b->texture_count + 1, sizeof(pb_texture)) ||
        !grow((void **)&b->texels, &b->texel_capacity, b->texel_count + n, sizeof(uint32_t))) {
        b->out_of_memory = 1;
        return -1;
    }
    pb_texture *t = &b->textures[b->texture_count];
    t->width = width;
    t->height = height;
    t->offset = b->texel_count;
    t->wrap_s = wrap_s;
    t->wrap_t = wrap_t;
    t->srgb = srgb;
    if (n)
        memcpy(b->texels + b->texel_count, texels, (size_t)n * sizeof(uint32_t));
    b->texel_count += n;
    return (int32_t)b->texture_count++;
}

int32_t pb_sb_add_light(pb_scene_builder *b, const pb_light *l, const double pos[3], const double dir[3])
{
    uint32_t cap = b->light_capacity;
    if (!grow32((void **)&b->lights, &b->light_capacity, (uint64_t)b->light_count + 1, sizeof(pb_light)) ||
        !grow32((void **)&b->light_world, &cap, (uint64_t)b->light_count + 1, 6 * sizeof(double))) {
        b->out_of_memory = 1;
        return -1;
    }
    b->lights[b->light_count] = *l;
    memcpy(b->light_world + 6 * b->light_count, pos, 3 * sizeof(double));
    memcpy(b->light_world + 6 * b->light_count + 3, dir, 3 * sizeof(double));
    return (int32_t)b->light_count++;
}

int32_t pb_sb_add_camera(pb_scene_builder *b, const pb_camera *c, const double pos[3], const double fwd[3],
                         const double up[3])
{
    uint32_t cap = b->camera_capacity;
    if (!grow32((void **)&b->cameras, &b->camera_capacity, (uint64_t)b->camera_count + 1, sizeof(pb_camera)) ||
        !grow32((void **)&b->camera_world, &cap, (uint64_t)b->camera_count + 1, 9 * sizeof(double))) {
        b->out_of_memory = 1;
        return -1;
    }
    b->cameras[b->camera_count] = *c;
    double *w = b->camera_world + 9 * b->camera_count;
    memcpy(w, pos, 3 * sizeof(double));
    memcpy(w + 3, fwd, 3 * sizeof(double));
    memcpy(w + 6, up, 3 * sizeof(double));
    return (int32_t)b->camera_count++;
}

static void unit3(const double in[3], float out[3])
{
    double l = sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2]);
    if (!(l > 0) || !isfinite(l)) {
        out[0] = 0.f, out[1] = 0.f, out[2] = -1.f;
        return;
    }
    for (int k = 0; k < 3; ++k)
        out[k] = (float)(in[k] / l);
}

#define FINISH_GRAIN 65536u /* triangles per block of the rebase */

enum { TRI_NONFINITE, TRI_DEGENERATE, TRI_KEPT };

typedef struct finish_part {
    double lo[3], hi[3]; /* the block's world bounds */
    float flo[3], fhi[3]; /* its kept triangles' rebased bounds */
} finish_part;

typedef struct finish_job {
    double *pos; /* the builder's: 9 doubles per triangle in, 9 floats at each slot's front out */
    float *nrm;
    uint32_t material_count;
    uint32_t *mat;
    double origin[3];
    finish_part *part; /* one per block, merged in block order */
    unsigned char *status; /* TRI_* per triangle */
} finish_job;

/* Minima and maxima keep the first of equal values (-0 before +0 or the
 * other way), so blocks merged in order give what one scan gives. */
static void bound_block(finish_job *j, uint64_t begin, uint64_t end)
{
    finish_part *q = &j->part[begin / FINISH_GRAIN];
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 3 * begin; i < 3 * end; ++i)
        for (int k = 0; k < 3; ++k) {
            double v = j->pos[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    memcpy(q->lo, lo, sizeof lo);
    memcpy(q->hi, hi, sizeof hi);
}

/* Rebases, rounds and tests each triangle of a block in its own slot: its
 * floats go over the front of its doubles, a missing vertex normal becomes
 * the face normal of the rounded triangle, a material past the end the
 * last one. Two loops, the tests reading the floats back from memory: in
 * one, GCC 12's SLP vectorizer at -O3 computed the edges from the doubles
 * before rounding (the face normals of 15 of the demo's 40 triangles an ulp
 * off, zero components as 5e-9; CMakeLists.txt now turns it off). */
static void rebase_block(finish_job *j, uint64_t begin, uint64_t end)
{
    for (uint64_t i = begin; i < end; ++i) {
        float p[9];
        for (int k = 0; k < 9; ++k)
            p[k] = (float)(j->pos[9 * i + k] - j->origin[k % 3]);
        memcpy(j->pos + 9 * i, p, sizeof p);
    }
    finish_part *q = &j->part[begin / FINISH_GRAIN];
    float flo[3] = {INFINITY, INFINITY, INFINITY}, fhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = begin; i < end; ++i) {
        float p[9];
        memcpy(p, j->pos + 9 * i, sizeof p);
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)p[3 + k] - p[k];
            e2[k] = (double)p[6 + k] - p[k];
        }
        double c0 = e1[1] * e2[2] - e1[2] * e2[1];
        double c1 = e1[2] * e2[0] - e1[0] * e2[2];
        double c2 = e1[0] * e2[1] - e1[1] * e2[0];
        int finite = 1;
        for (int k = 0; k < 9; ++k)
            finite &= isfinite(p[k]) != 0;
        if (!finite) {
            j->status[i] = TRI_NONFINITE;
            continue;
        }
        if (c0 == 0 && c1 == 0 && c2 == 0) {
            j->status[i] = TRI_DEGENERATE;
            continue;
        }
        j->status[i] = TRI_KEPT;
        for (int k = 0; k < 9; ++k) {
            flo[k % 3] = p[k] < flo[k % 3] ? p[k] : flo[k % 3];
            fhi[k % 3] = p[k] > fhi[k % 3] ? p[k] : fhi[k % 3];
        }
        float *dn = j->nrm + 9 * i;
        double cl = sqrt(c0 * c0 + c1 * c1 + c2 * c2);
        for (int v = 0; v < 3; ++v)
            if (isnan(dn[3 * v])) /* no normal of its own: the face's */
                dn[3 * v] = (float)(c0 / cl), dn[3 * v + 1] = (float)(c1 / cl), dn[3 * v + 2] = (float)(c2 / cl);
        uint32_t m = j->mat[i];
        j->mat[i] = m < j->material_count ? m : j->material_count - 1;
    }
    memcpy(q->flo, flo, sizeof flo);
    memcpy(q->fhi, fhi, sizeof fhi);
}

/* pb_parallel_for's ranges start at multiples of FINISH_GRAIN, and one
 * thread gets the whole range at once: block by block either way */
static void bound_range(void *user, uint64_t begin, uint64_t end)
{
    for (uint64_t q = begin; q < end; q += FINISH_GRAIN)
        bound_block(user, q, end - q < FINISH_GRAIN ? end : q + FINISH_GRAIN);
}

static void rebase_range(void *user, uint64_t begin, uint64_t end)
{
    for (uint64_t q = begin; q < end; q += FINISH_GRAIN)
        rebase_block(user, q, end - q < FINISH_GRAIN ? end : q + FINISH_GRAIN);
}

pb_result pb_sb_finish(pb_scene_builder *b, const char *path, pb_scene **out, pb_error *err)
{
    *out = NULL;
    if (b->out_of_memory)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory while loading", path);
    if (b->count > UINT32_MAX)
        return pb_fail(err, PB_ERROR_TOO_LARGE, "%s: %llu triangles, more than 2^32-1", path,
                       (unsigned long long)b->count);
    if (b->material_count == 0) {
        pb_material m = pb_material_default();
        snprintf(m.name, sizeof m.name, "default");
        if (pb_sb_add_material(b, &m) < 0)
            return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    }

    /* the rebase's work, in blocks on all host cores (below) */
    uint64_t blocks = (b->count + FINISH_GRAIN - 1) / FINISH_GRAIN;
    finish_job job = {b->pos, b->nrm, b->material_count, b->mat, {0, 0, 0}, NULL, NULL};
    job.part = calloc(blocks ? blocks : 1, sizeof *job.part);
    job.status = pb_malloc_large((size_t)(b->count ? b->count : 1));
    if (!job.part || !job.status) {
        free(job.part);
        free(job.status);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    }

    /* origin: centre of the world AABB of every finite triangle, in double */
    pb_parallel_for(b->count, FINISH_GRAIN, 0, bound_range, &job);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t q = 0; q < blocks; ++q) /* in order, as one scan would meet them (ties between -0 and +0) */
        for (int k = 0; k < 3; ++k) {
            lo[k] = job.part[q].lo[k] < lo[k] ? job.part[q].lo[k] : lo[k];
            hi[k] = job.part[q].hi[k] > hi[k] ? job.part[q].hi[k] : hi[k];
        }
    double origin[3] = {0, 0, 0};
    if (b->count)
        for (int k = 0; k < 3; ++k)
            origin[k] = 0.5 * (lo[k] + hi[k]);
    memcpy(job.origin, origin, sizeof origin);

    pb_scene *s = calloc(1, sizeof *s);
    if (!s) {
        free(job.part);
        free(job.status);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    }
    if (!b->capacity) { /* no triangle was added: one element each, as for any scene */
        b->pos = malloc(9 * sizeof(double)), b->nrm = malloc(9 * sizeof(float));
        b->uv = malloc(6 * sizeof(float)), b->mat = malloc(sizeof(uint32_t));
        b->capacity = 1;
    }
    if (!b->pos || !b->nrm || !b->uv || !b->mat) {
        pb_scene_destroy(s);
        free(job.part);
        free(job.status);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    }
    /* The per-triangle arrays are the builder's, compacted in place (a kept
     * triangle never moves up), so a large scene's load touches no new pages
     * for them. The float positions go over the double ones: first each
     * triangle's floats over the front of its own 72 bytes, then down to
     * their place in order (kept <= i, and a float triangle is 36 bytes). */
    s->positions = (float *)(void *)b->pos, s->normals = b->nrm, s->texcoords = b->uv, s->material = b->mat;
    s->colors = b->rgba, s->tangents = b->tan;
    const double *pos = b->pos;
    b->pos = NULL, b->nrm = NULL, b->uv = NULL, b->mat = NULL, b->rgba = NULL, b->tan = NULL;

    /* rebase, round to float, then drop what became (or was) zero area:
     * each triangle in its own slot on all cores, then the kept ones moved
     * down in order on one */
    pb_parallel_for(b->count, FINISH_GRAIN, 0, rebase_range, &job);
    float flo[3] = {INFINITY, INFINITY, INFINITY}, fhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t q = 0; q < blocks; ++q)
        for (int k = 0; k < 3; ++k) {
            flo[k] = job.part[q].flo[k] < flo[k] ? job.part[q].flo[k] : flo[k];
            fhi[k] = job.part[q].fhi[k] > fhi[k] ? job.part[q].fhi[k] : fhi[k];
        }
    uint32_t kept = 0;
    for (uint64_t i = 0; i < b->count; ++i) {
        if (job.status[i] != TRI_KEPT) {
            if (job.status[i] == TRI_NONFINITE)
                b->stats.dropped_nonfinite++;
            else
                b->stats.dropped_degenerate++;
            continue;
        }
        /* the floats at the front of the slot's 72 bytes, down to their place
         * (36 bytes at kept <= i: below the next slot's doubles) */
        if (i != 0)
            memmove(s->positions + 9 * (uint64_t)kept, pos + 9 * i, 9 * sizeof(float));
        if (kept != i) {
            memmove(s->normals + 9 * (uint64_t)kept, s->normals + 9 * i, 9 * sizeof(float));
            memmove(s->texcoords + 6 * (uint64_t)kept, s->texcoords + 6 * i, 6 * sizeof(float));
            if (s->colors)
                memmove(s->colors + 12 * (uint64_t)kept, s->colors + 12 * i, 12 * sizeof(float));
            if (s->tangents)
                memmove(s->tangents + 12 * (uint64_t)kept, s->tangents + 12 * i, 12 * sizeof(float));
            s->material[kept] = s->material[i];
        }
        ++kept;
    }
    free(job.part);
    free(job.status);
    s->triangle_count = kept;
    shrink((void **)&s->positions, kept, 9 * sizeof(float)); /* the builder's spare capacity back */
    shrink((void **)&s->normals, kept, 9 * sizeof(float));
    shrink((void **)&s->texcoords, kept, 6 * sizeof(float));
    shrink((void **)&s->material, kept, sizeof(uint32_t));
    if (s->colors)
        shrink((void **)&s->colors, kept, 12 * sizeof(float));
    if (s->tangents)
        shrink((void **)&s->tangents, kept, 12 * sizeof(float));
    for (int k = 0; k < 3; ++k) {
        s->origin[k] = origin[k];
        s->bounds_min[k] = kept ? flo[k] : 0.f;
        s->bounds_max[k] = kept ? fhi[k] : 0.f;
    }

    /* move the rest */
    s->material_count = b->material_count;
    s->materials = b->materials;
    s->texture_count = b->texture_count;
    s->textures = b->textures;
    s->texel_count = b->texel_count;
    s->texels = b->texels;
    b->materials = NULL, b->textures = NULL, b->texels = NULL;
    s->light_count = b->light_count;
    s->lights = b->lights;
    b->lights = NULL;
    for (uint32_t i = 0; i < s->light_count; ++i) {
        const double *w = b->light_world + 6 * i;
        for (int k = 0; k < 3; ++k)
            s->lights[i].position[k] = (float)(w[k] - origin[k]);
        unit3(w + 3, s->lights[i].direction);
    }
    s->camera_count = b->camera_count;
    s->cameras = b->cameras;
    b->cameras = NULL;
    for (uint32_t i = 0; i < s->camera_count; ++i) {
        const double *w = b->camera_world + 9 * i;
        for (int k = 0; k < 3; ++k)
            s->cameras[i].position[k] = (float)(w[k] - origin[k]);
        unit3(w + 3, s->cameras[i].forward);
        unit3(w + 6, s->cameras[i].up);
    }
    s->stats = b->stats;
    snprintf(s->path, sizeof s->path, "%s", path ? path : "");
    pb_sb_free(b);
    *out = s;
    return PB_OK;
}
