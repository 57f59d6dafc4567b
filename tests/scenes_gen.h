/* Procedural test geometry and rays shared by the BVH and trace tests, plus
 * the hit comparison every kernel-vs-reference test uses. */
#ifndef PB_TEST_SCENES_GEN_H
#define PB_TEST_SCENES_GEN_H

#include "test_util.h"

/* n random triangles: centres uniform in [-1,1]^3, edges up to `size`. */
static inline pb_scene *random_soup(uint32_t n, float size, uint64_t seed, const double offset[3])
{
    test_rng r = {seed * 0x9E3779B97F4A7C15ull + 1};
    double *p = malloc((size_t)n * 9 * sizeof(double));
    for (uint32_t t = 0; t < n; ++t) {
        double c[3];
        for (int k = 0; k < 3; ++k)
            c[k] = 2.0 * rng_uniform(&r) - 1.0;
        for (int v = 0; v < 3; ++v)
            for (int k = 0; k < 3; ++k)
                p[9 * (size_t)t + 3 * v + k] = c[k] + size * (rng_uniform(&r) - 0.5) + (offset ? offset[k] : 0.0);
    }
    pb_scene *s = NULL;
    pb_error err;
    if (pb_scene_from_triangles(p, n, NULL, NULL, 0, &s, &err) != PB_OK)
        fprintf(stderr, "random_soup: %s\n", err.message);
    free(p);
    return s;
}

/* UV sphere of radius 1 around the origin, closed, outward CCW. Each vertex
 * position is computed once and shared exactly by its triangles. */
static inline pb_scene *closed_sphere(uint32_t rings, uint32_t segments, float **verts_out, uint32_t *nverts)
{
    uint32_t nv = 2 + (rings - 1) * segments;
    float *vp = malloc((size_t)nv * 3 * sizeof(float));
    vp[0] = 0, vp[1] = 1, vp[2] = 0;
    vp[3] = 0, vp[4] = -1, vp[5] = 0;
    for (uint32_t i = 1; i < rings; ++i)
        for (uint32_t j = 0; j < segments; ++j) {
            double th = 3.141592653589793 * i / rings, ph = 6.283185307179586 * j / segments;
            float *v = vp + 3 * (2 + (i - 1) * segments + j);
            v[0] = (float)(sin(th) * cos(ph));
            v[1] = (float)cos(th);
            v[2] = (float)(sin(th) * sin(ph));
        }
#define RV(i, j) (2 + ((i)-1) * segments + ((j) % segments))
    uint32_t nt = 2 * segments * (rings - 1);
    double *p = malloc((size_t)nt * 9 * sizeof(double));
    uint32_t t = 0;
    for (uint32_t j = 0; j < segments; ++j) {
        uint32_t tri[2][3] = {{0, RV(1, j + 1), RV(1, j)}, {1, RV(rings - 1, j), RV(rings - 1, j + 1)}};
        for (int q = 0; q < 2; ++q, ++t)
            for (int v = 0; v < 3; ++v)
                for (int k = 0; k < 3; ++k)
                    p[9 * (size_t)t + 3 * v + k] = vp[3 * tri[q][v] + k];
    }
    for (uint32_t i = 1; i + 1 < rings; ++i)
        for (uint32_t j = 0; j < segments; ++j) {
            uint32_t a = RV(i, j), b = RV(i, j + 1), c = RV(i + 1, j + 1), d = RV(i + 1, j);
            uint32_t tri[2][3] = {{a, b, c}, {a, c, d}};
            for (int q = 0; q < 2; ++q, ++t)
                for (int v = 0; v < 3; ++v)
                    for (int k = 0; k < 3; ++k)
                        p[9 * (size_t)t + 3 * v + k] = vp[3 * tri[q][v] + k];
        }
#undef RV
    pb_scene *s = NULL;
    pb_error err;
    /* the soup's AABB is centred on the origin, so rebasing does not move it */
    if (pb_scene_from_triangles(p, t, NULL, NULL, 0, &s, &err) != PB_OK)
        fprintf(stderr, "closed_sphere: %s\n", err.message);
    free(p);
    *verts_out = vp;
    *nverts = nv;
    return s;
}

/* Rays from inside the unit sphere aimed exactly at its vertices, at points on
 * its edges (midpoints and random fractions) and at its triangles' corners. */
static inline pb_ray *sphere_probe_rays(const pb_scene *s, uint32_t count, uint64_t seed)
{
    test_rng r = {seed};
    pb_ray *rays = malloc((size_t)count * sizeof *rays);
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t t = (uint32_t)(rng_uniform(&r) * s->triangle_count) % s->triangle_count;
        const float *p = s->positions + 9 * (size_t)t;
        float target[3];
        int kind = i % 3, e = (int)(rng_uniform(&r) * 3) % 3;
        const float *a = p + 3 * e, *b = p + 3 * ((e + 1) % 3);
        float f = kind == 0 ? 0.f : (kind == 1 ? 0.5f : (float)rng_uniform(&r));
        for (int k = 0; k < 3; ++k)
            target[k] = a[k] + f * (b[k] - a[k]);
        /* origins: the centre, and random points well inside */
        float o[3] = {0, 0, 0};
        if (i & 1) {
            float d[3];
            rng_direction(&r, d);
            float rad = 0.6f * (float)rng_uniform(&r);
            for (int k = 0; k < 3; ++k)
                o[k] = d[k] * rad;
        }
        for (int k = 0; k < 3; ++k) {
            rays[i].origin[k] = o[k];
            rays[i].direction[k] = target[k] - o[k];
        }
        rays[i].tmin = 0.f;
        rays[i].tmax = INFINITY;
    }
    return rays;
}

/* Random rays with origins in the box, some with a finite tmax or tmin > 0. */
static inline pb_ray *random_rays(const float lo[3], const float hi[3], uint32_t count, uint64_t seed)
{
    test_rng r = {seed * 7919 + 3};
    pb_ray *rays = malloc((size_t)count * sizeof *rays);
    for (uint32_t i = 0; i < count; ++i) {
        for (int k = 0; k < 3; ++k)
            rays[i].origin[k] = lo[k] + (hi[k] - lo[k]) * (float)rng_uniform(&r);
        rng_direction(&r, rays[i].direction);
        float ext = hi[0] - lo[0];
        rays[i].tmin = (i % 7 == 3) ? 0.05f * ext : 0.f;
        rays[i].tmax = (i % 5 == 1) ? 0.3f * ext : INFINITY;
    }
    return rays;
}

/* Counts disagreements between two hit lists: a hit against a miss, a
 * distance off by more than 1e-5 relative, or a different triangle at a
 * different distance (different triangles at the same distance are a tie:
 * both are the closest). Prints the first few. */
static inline uint32_t compare_hits(const char *what, const pb_ray *rays, const pb_hit *a, const pb_hit *b,
                                    uint32_t n, uint32_t *ties)
{
    uint32_t bad = 0, tie = 0;
    for (uint32_t i = 0; i < n; ++i) {
        int ha = a[i].triangle != PB_NO_HIT, hb = b[i].triangle != PB_NO_HIT;
        int ok = ha == hb;
        if (ok && ha) {
            float tol = 1e-5f * fmaxf(1.f, fabsf(b[i].t));
            ok = fabsf(a[i].t - b[i].t) <= tol;
            if (ok && a[i].triangle != b[i].triangle)
                ++tie;
            if (ok && a[i].triangle == b[i].triangle)
                ok = a[i].backface == b[i].backface && fabsf(a[i].u - b[i].u) <= 1e-4f &&
                     fabsf(a[i].v - b[i].v) <= 1e-4f;
        }
        if (!ok) {
            if (bad < 5)
                fprintf(stderr, "  %s: ray %u (o %g %g %g d %g %g %g): tri %u t %.9g vs tri %u t %.9g\n", what, i,
                        rays[i].origin[0], rays[i].origin[1], rays[i].origin[2], rays[i].direction[0],
                        rays[i].direction[1], rays[i].direction[2], a[i].triangle, a[i].t, b[i].triangle, b[i].t);
            ++bad;
        }
    }
    if (ties)
        *ties = tie;
    return bad;
}

/* Quads of an axis-aligned box [lo, hi] as 12 triangles, facing out (or in). */
static inline uint32_t box_tris(double *p, const double lo[3], const double hi[3], int inward)
{
    uint32_t t = 0;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            int u = (axis + 1) % 3, w = (axis + 2) % 3;
            double c[4][3];
            for (int q = 0; q < 4; ++q) {
                c[q][axis] = side ? hi[axis] : lo[axis];
                c[q][u] = (q == 1 || q == 2) ? hi[u] : lo[u];
                c[q][w] = (q >= 2) ? hi[w] : lo[w];
            }
            int order[2][3] = {{0, 1, 2}, {0, 2, 3}};
            int out = side ^ inward;
            for (int tri = 0; tri < 2; ++tri, ++t)
                for (int vtx = 0; vtx < 3; ++vtx) {
                    int q = order[tri][out ? vtx : 2 - vtx];
                    for (int k = 0; k < 3; ++k)
                        p[9 * t + 3 * vtx + k] = c[q][k];
                }
        }
    return t;
}


/* The bundled demo scene; NULL (and a failed check) if it does not load. */
static inline pb_scene *load_demo(void)
{
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_load(source_path("tests/scenes/demo.gltf"), NULL, &s, &err) == PB_OK, "%s", err.message);
    return s;
}

/* Bends every vertex normal of s away from its face normal by a smooth field
 * of the vertex's position (amount: its largest length against the unit face
 * normal), so the shading normal varies across each triangle and the scene
 * shades smooth (shading_normals.h). */
static inline void bend_normals(pb_scene *s, float amount)
{
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const float *p = s->positions + 9 * (size_t)t;
        float e1[3], e2[3], g[3];
        for (int k = 0; k < 3; ++k)
            e1[k] = p[3 + k] - p[k], e2[k] = p[6 + k] - p[k];
        g[0] = e1[1] * e2[2] - e1[2] * e2[1], g[1] = e1[2] * e2[0] - e1[0] * e2[2], g[2] = e1[0] * e2[1] - e1[1] * e2[0];
        float gl = sqrtf(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        for (int v = 0; v < 3; ++v) {
            const float *x = p + 3 * v;
            float b[3] = {sinf(1.7f * x[0] + 0.3f), sinf(2.3f * x[1] + 1.1f), sinf(1.3f * x[2] + 2.0f)}, n[3];
            for (int k = 0; k < 3; ++k)
                n[k] = g[k] / gl + amount / sqrtf(3.f) * b[k];
            float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int k = 0; k < 3; ++k)
                s->normals[9 * (size_t)t + 3 * v + k] = n[k] / l;
        }
    }
}

/* Gives every material of s a normal map (scale 1): a new size x size
 * texture (wrapping) of random tangent-space normals tilted up to max_tilt
 * radians from +Z, and every triangle texture coordinates from a fixed
 * linear map of its corners' positions, skewed so that no axis-aligned
 * plane (the demo's walls) maps to a line. A colour texture then reads them
 * too. 0 out of memory. */
static inline int give_normal_map(pb_scene *s, uint32_t size, float max_tilt, uint64_t seed)
{
    if (!s->texcoords)
        return 0;
    pb_texture *tx = realloc(s->textures, (s->texture_count + 1) * sizeof *tx);
    if (!tx)
        return 0;
    s->textures = tx;
    uint32_t *texels = realloc(s->texels, (size_t)(s->texel_count + (uint64_t)size * size) * sizeof *texels);
    if (!texels)
        return 0;
    s->texels = texels;
    tx[s->texture_count] = (pb_texture){size, size, s->texel_count, PB_WRAP_REPEAT, PB_WRAP_REPEAT, 0};
    test_rng r = {seed * 0x9E3779B97F4A7C15ull + 7};
    for (uint32_t i = 0; i < size * size; ++i) {
        double tilt = max_tilt * sqrt(rng_uniform(&r)), phi = 6.283185307179586 * rng_uniform(&r);
        double n[3] = {sin(tilt) * cos(phi), sin(tilt) * sin(phi), cos(tilt)};
        uint32_t w = 0xff000000u;
        for (int k = 0; k < 3; ++k)
            w |= (uint32_t)lround((n[k] + 1.0) * 127.5) << (8 * k);
        texels[s->texel_count + i] = w;
    }
    for (uint32_t m = 0; m < s->material_count; ++m)
        s->materials[m].normal_texture = (int32_t)s->texture_count, s->materials[m].normal_scale = 1.f;
    s->texel_count += (uint64_t)size * size;
    s->texture_count++;
    for (uint64_t c = 0; c < 3 * (uint64_t)s->triangle_count; ++c) {
        const float *x = s->positions + 3 * c;
        s->texcoords[2 * c] = 0.37f * x[0] + 0.13f * x[1] + 0.21f * x[2];
        s->texcoords[2 * c + 1] = -0.17f * x[0] + 0.31f * x[1] + 0.29f * x[2];
    }
    return 1;
}

/* Gives every triangle of s file tangents (pb_scene.tangents): at each
 * corner the unit n x (0.3, 0.9, 0.4) of its vertex normal n (or of the
 * face normal where n is parallel to that axis), handedness +1 on even
 * triangles and -1 on odd ones: another frame than the texture
 * coordinates'. 0 out of memory. */
static inline int give_tangents(pb_scene *s)
{
    free(s->tangents);
    s->tangents = malloc((size_t)s->triangle_count * 12 * sizeof(float));
    if (!s->tangents)
        return 0;
    const float axis[3] = {0.3f, 0.9f, 0.4f};
    for (uint32_t t = 0; t < s->triangle_count; ++t)
        for (int v = 0; v < 3; ++v) {
            const float *n = s->normals + 9 * (size_t)t + 3 * v;
            float c[3] = {n[1] * axis[2] - n[2] * axis[1], n[2] * axis[0] - n[0] * axis[2], n[0] * axis[1] - n[1] * axis[0]};
            float l = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            float *o = s->tangents + 12 * (size_t)t + 4 * v;
            for (int k = 0; k < 3; ++k)
                o[k] = l > 1e-3f ? c[k] / l : (k == 0 ? 1.f : 0.f);
            o[3] = t & 1 ? -1.f : 1.f;
        }
    return 1;
}

#endif
