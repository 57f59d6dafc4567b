/* Scene loader: hierarchy transforms, primitive modes, file forms, attribute
 * encodings, dropped triangles, and every malformed-file error; and the
 * environment maps a scene is lit by (.hdr and OpenEXR). CPU only. */
#define _DEFAULT_SOURCE /* mknod, makedev */
#define _GNU_SOURCE     /* sched_setaffinity */
#include "bake/shading_normals.h"
#include "bvh/alpha.h"
#include "compressed_variants.h"
#include "exr_pattern.h"
#include "fuzz/scene_exercise.h"
#include "io/environment_exr.h"
#include "io/ktx2_layout.h"
#include "scene/basis_uastc.h"
#include "scene/ktx2_read.h"
#include "test_util.h"

#include <sched.h>
#include <sys/sysmacros.h>

#include <stb_image_write.h>

/* ------------------------------------------------------------ helpers */

/* Writes `json` with each "@BUF@" replaced by a data URI of `bin`. */
static const char *write_gltf(const char *name, const char *json, const void *bin, size_t bin_size)
{
    char *b64 = base64(bin, bin_size);
    size_t need = strlen(json) + 8 * (strlen(b64) + 64);
    char *out = malloc(need), *o = out;
    for (const char *p = json; *p;) {
        if (!strncmp(p, "@BUF@", 5)) {
            o += sprintf(o, "data:application/octet-stream;base64,%s", b64);
            p += 5;
        } else {
            *o++ = *p++;
        }
    }
    *o = '\0';
    const char *path = write_file(name, out, strlen(out));
    free(out);
    free(b64);
    return path;
}

static pb_scene *load_ok(const char *path)
{
    pb_scene *s = NULL;
    pb_error err;
    pb_result r = pb_scene_load(path, NULL, &s, &err);
    CHECKF(r == PB_OK, "%s: %s", path, err.message);
    return s;
}

/* Loads, expects failure with `code`, and a message naming the file. */
static void load_fails(const char *path, pb_result code, const char *needle)
{
    pb_scene *s = (pb_scene *)1;
    pb_error err;
    pb_result r = pb_scene_load(path, NULL, &s, &err);
    CHECKF(r == code, "%s: got %s (%s), want %s", path, pb_result_name(r), err.message, pb_result_name(code));
    CHECK(s == NULL);
    CHECKF(strstr(err.message, path) != NULL, "message does not name the file: %s", err.message);
    if (needle)
        CHECKF(strstr(err.message, needle) != NULL, "message '%s' lacks '%s'", err.message, needle);
    CHECK(strchr(err.message, '\n') == NULL);
}

/* Warnings holding any of `needles` (NULL-terminated), counted through a
 * pb_scene_desc's log: {{count_warnings, &counter}, ...}. */
typedef struct warning_counter {
    const char *needles[3];
    int count;
} warning_counter;

static void count_warnings(pb_log_level level, const char *msg, void *user)
{
    warning_counter *w = user;
    int hit = 0;
    for (int i = 0; i < 3 && w->needles[i]; ++i)
        hit |= strstr(msg, w->needles[i]) != NULL;
    w->count += level == PB_LOG_WARN && hit;
}

/* World position of vertex v of triangle t. */
static void world(const pb_scene *s, uint32_t t, int v, double out[3])
{
    for (int k = 0; k < 3; ++k)
        out[k] = s->positions[9 * (size_t)t + 3 * v + k] + s->origin[k];
}

static int near3(const double a[3], double x, double y, double z, double tol)
{
    return fabs(a[0] - x) <= tol && fabs(a[1] - y) <= tol && fabs(a[2] - z) <= tol;
}

/* Geometric normal direction (unnormalised) of triangle t. */
static void geo_normal(const pb_scene *s, uint32_t t, double n[3])
{
    const float *p = s->positions + 9 * (size_t)t;
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)p[3 + k] - p[k];
        e2[k] = (double)p[6 + k] - p[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

/* One triangle (0,0,0) (1,0,0) (0,1,0), normals +Z, as bytes. */
static const float tri_pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};

static const char *one_triangle_json =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],%s"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
    "\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}";

static const char *one_triangle(const char *name, const char *nodes)
{
    char json[4096];
    snprintf(json, sizeof json, one_triangle_json, nodes);
    return write_gltf(name, json, tri_pos, sizeof tri_pos);
}

/* One triangle whose material's colour is texture 0: `extensions` opens the
 * JSON (extensionsUsed and the like, "" for none), `textures` gives its
 * "textures" and "images" members, and `views` any bufferViews after the
 * positions' (each ",{...}"). */
static const char *textured_triangle(const char *name, const char *extensions, const char *textures,
                                     const char *views)
{
    char json[4096];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},%s\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}],"
             "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],%s,"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}%s],"
             "\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}",
             extensions, textures, views);
    return write_gltf(name, json, tri_pos, 36);
}

/* `count` triangles with TEXCOORD_0, the i-th drawn with material i, and
 * `parts` in the file: its materials, textures and images (and any
 * extensionsUsed), each followed by a comma. */
static const char *uv_triangles(const char *name, int count, const char *parts)
{
    unsigned char bin[36 + 24];
    const float uv[6] = {0, 0, 1, 0, 0, 1};
    memcpy(bin, tri_pos, 36);
    memcpy(bin + 36, uv, 24);
    char ids[256] = "", nodes[512] = "", meshes[2048] = "";
    size_t a = 0, b = 0, c = 0;
    for (int i = 0; i < count; ++i) {
        a += (size_t)snprintf(ids + a, sizeof ids - a, "%s%d", i ? "," : "", i);
        b += (size_t)snprintf(nodes + b, sizeof nodes - b, "%s{\"mesh\":%d}", i ? "," : "", i);
        c += (size_t)snprintf(meshes + c, sizeof meshes - c,
                              "%s{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"material\":%d}]}",
                              i ? "," : "", i);
    }
    char json[8192];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[%s]}],\"nodes\":[%s],%s\"meshes\":[%s],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":24}],"
             "\"buffers\":[{\"byteLength\":60,\"uri\":\"@BUF@\"}]}",
             ids, nodes, parts, meshes);
    return write_gltf(name, json, bin, sizeof bin);
}

/* ------------------------------------------------------------ tests */

/* glTF cameras of both kinds, on nodes that move and turn them: an
 * orthographic camera keeps its extents and clip planes (the renderer draws it
 * in perspective at 0.8 rad, pb_camera_from_scene), a perspective one its
 * field of view and aspect; both look down their node's -Z. */
static void cameras_of_both_kinds(void)
{
    const char *path = write_gltf(
        "cameras.gltf",
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1,2]}],"
        "\"nodes\":[{\"mesh\":0},{\"camera\":0,\"translation\":[1,2,3]},"
        "{\"camera\":1,\"rotation\":[0,0.70710678,0,0.70710678]}],"
        "\"cameras\":[{\"type\":\"orthographic\",\"orthographic\":{\"xmag\":2,\"ymag\":1.5,\"znear\":0.1,\"zfar\":50}},"
        "{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.6,\"aspectRatio\":1.5,\"znear\":0.01}}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}",
        tri_pos, 36);
    pb_scene *s = load_ok(path);
    if (!s)
        return;
    CHECK(s->camera_count == 2);
    if (s->camera_count == 2) {
        const pb_camera *o = &s->cameras[0], *p = &s->cameras[1];
        double at[3] = {o->position[0] + s->origin[0], o->position[1] + s->origin[1], o->position[2] + s->origin[2]};
        CHECK(!o->perspective && o->xmag == 2.f && o->ymag == 1.5f && o->znear == 0.1f && o->zfar == 50.f);
        CHECK(near3(at, 1, 2, 3, 1e-6) && fabsf(o->forward[2] + 1.f) < 1e-6f && fabsf(o->up[1] - 1.f) < 1e-6f);
        CHECK(p->perspective && p->yfov == 0.6f && p->aspect == 1.5f && p->znear == 0.01f && p->zfar == 0.f);
        /* turned 90 degrees about +Y: -Z goes to -X */
        CHECK(fabsf(p->forward[0] + 1.f) < 1e-6f && fabsf(p->forward[2]) < 1e-6f);
        pb_camera_view v;
        pb_camera_from_scene(o, &v);
        CHECK(v.yfov == 0.8f);
        pb_camera_from_scene(p, &v);
        CHECK(v.yfov == 0.6f);
    }
    pb_scene_destroy(s);
}

static void demo_scene_loads_everything(void)
{
    pb_scene *s = load_ok(source_path("tests/scenes/demo.gltf"));
    if (!s)
        return;
    CHECK(s->triangle_count == 40);
    CHECK(s->stats.dropped_degenerate == 0 && s->stats.dropped_nonfinite == 0);
    CHECK(s->light_count == 1 && s->lights[0].type == PB_LIGHT_POINT && s->lights[0].intensity == 15.f);
    double lp[3] = {s->lights[0].position[0] + s->origin[0], s->lights[0].position[1] + s->origin[1],
                    s->lights[0].position[2] + s->origin[2]};
    CHECK(near3(lp, 0.6, 2.4, 1.2, 1e-6));
    CHECK(s->camera_count == 1 && s->cameras[0].perspective && fabsf(s->cameras[0].yfov - 1.f) < 1e-6f);
    CHECK(fabsf(s->cameras[0].forward[2] + 1.f) < 1e-6f); /* looks down -Z */
    CHECK(s->texture_count == 1 && s->textures[0].width == 16 && s->textures[0].height == 16);
    int light = -1, lattice = -1;
    for (uint32_t m = 0; m < s->material_count; ++m) {
        if (!strcmp(s->materials[m].name, "light"))
            light = (int)m;
        if (!strcmp(s->materials[m].name, "lattice"))
            lattice = (int)m;
    }
    CHECK(light >= 0 && fabsf(s->materials[light].emissive[0] - 8.f) < 1e-5f); /* emissive strength applied */
    CHECK(lattice >= 0 && s->materials[lattice].alpha_mode == PB_ALPHA_MASK && s->materials[lattice].double_sided);
    CHECK(lattice >= 0 && s->materials[lattice].base_color_texture == 0);
    double lo[3] = {s->bounds_min[0] + s->origin[0], s->bounds_min[1] + s->origin[1], s->bounds_min[2] + s->origin[2]};
    double hi[3] = {s->bounds_max[0] + s->origin[0], s->bounds_max[1] + s->origin[1], s->bounds_max[2] + s->origin[2]};
    CHECK(near3(lo, -2, 0, -2.5, 1e-6) && near3(hi, 2, 3, 2.5, 1e-6));
    CHECK(near3(s->origin, 0, 1.5, 0, 0));
    /* texels decoded: the lattice has transparent holes and opaque bars */
    uint32_t opaque = 0;
    for (uint32_t i = 0; i < 256; ++i)
        opaque += (s->texels[i] >> 24) == 255;
    CHECK(opaque > 0 && opaque < 256);
    pb_scene_destroy(s);
}

static void hierarchy_composes_matrix_and_trs(void)
{
    /* parent: matrix = translate (10,0,0) * scale 2; child: TRS, 90 deg about Y, then +1 in Y */
    const char *nodes =
        "\"nodes\":[{\"matrix\":[2,0,0,0, 0,2,0,0, 0,0,2,0, 10,0,0,1],\"children\":[1]},"
        "{\"mesh\":0,\"rotation\":[0,0.7071067811865476,0,0.7071067811865476],\"translation\":[0,1,0]}],";
    pb_scene *s = load_ok(one_triangle("hierarchy.gltf", nodes));
    if (!s)
        return;
    CHECK(s->triangle_count == 1);
    double v[3];
    world(s, 0, 0, v);
    CHECKF(near3(v, 10, 2, 0, 1e-6), "v0 = %g %g %g", v[0], v[1], v[2]);
    world(s, 0, 1, v);
    CHECKF(near3(v, 10, 2, -2, 1e-6), "v1 = %g %g %g", v[0], v[1], v[2]);
    world(s, 0, 2, v);
    CHECKF(near3(v, 10, 4, 0, 1e-6), "v2 = %g %g %g", v[0], v[1], v[2]);
    /* flat normal generated (no NORMAL): rotated +Z -> +X */
    CHECK(s->stats.normals_generated == 1);
    CHECK(fabsf(s->normals[0] - 1.f) < 1e-6f);
    pb_scene_destroy(s);
}

static void mirrored_transform_keeps_front_faces(void)
{
    pb_scene *s = load_ok(one_triangle("mirror.gltf", "\"nodes\":[{\"mesh\":0,\"scale\":[-1,1,1]}],"));
    if (!s)
        return;
    double n[3];
    geo_normal(s, 0, n);
    CHECKF(n[2] > 0, "winding not reversed under a mirror: n.z = %g", n[2]);
    pb_scene_destroy(s);
}

static void strips_fans_and_unindexed(void)
{
    /* 5 vertices in the z=0 plane, all primitives should face +Z */
    float pos[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 2, 0};
    float fan[15] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0.5f, 1.5f, 0, 0, 1, 0};
    unsigned char bin[15 * 4 * 2 + 8];
    memcpy(bin, pos, 60);
    memcpy(bin + 60, fan, 60);
    uint16_t idx[4] = {0, 1, 2, 3};
    memcpy(bin + 120, idx, 8);
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":["
        "{\"attributes\":{\"POSITION\":0},\"mode\":5},"               /* strip, 5 verts: 3 tris */
        "{\"attributes\":{\"POSITION\":1},\"mode\":6},"               /* fan, 5 verts: 3 tris */
        "{\"attributes\":{\"POSITION\":0},\"mode\":5,\"indices\":2}," /* indexed strip: 2 tris */
        "{\"attributes\":{\"POSITION\":0},\"mode\":4},"               /* unindexed triangles: 1 tri (5/3) */
        "{\"attributes\":{\"POSITION\":0},\"mode\":1}]}],"            /* lines: skipped */
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":5,\"type\":\"VEC3\"},"
        "{\"bufferView\":0,\"byteOffset\":60,\"componentType\":5126,\"count\":5,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":4,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":120},{\"buffer\":0,\"byteOffset\":120,\"byteLength\":8}],"
        "\"buffers\":[{\"byteLength\":128,\"uri\":\"@BUF@\"}]}";
    pb_scene *s = load_ok(write_gltf("modes.gltf", json, bin, 128));
    if (!s)
        return;
    CHECKF(s->triangle_count == 9, "%u triangles", s->triangle_count);
    CHECK(s->stats.primitives_skipped == 1);
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        double n[3];
        geo_normal(s, t, n);
        CHECKF(n[2] > 0, "triangle %u faces -Z (winding)", t);
    }
    pb_scene_destroy(s);
}

/* A .glb of `json` and a BIN chunk of `bin`. */
static const char *write_glb_bin(const char *name, const char *json, const void *bin, uint32_t bin_size)
{
    uint32_t jlen = (uint32_t)((strlen(json) + 3) & ~3u), blen = (bin_size + 3) & ~3u;
    uint32_t total = 12 + 8 + jlen + 8 + blen;
    unsigned char *glb = calloc(1, total);
    uint32_t hdr[3] = {0x46546C67u, 2, total}, jc[2] = {jlen, 0x4E4F534Au}, bc[2] = {blen, 0x004E4942u};
    memcpy(glb, hdr, 12);
    memcpy(glb + 12, jc, 8);
    memset(glb + 20, ' ', jlen);
    memcpy(glb + 20, json, strlen(json));
    memcpy(glb + 20 + jlen, bc, 8);
    memcpy(glb + 28 + jlen, bin, bin_size);
    const char *path = write_file(name, glb, total);
    free(glb);
    return path;
}

/* Primitives far larger than a block of the loader's threads (16,384
 * triangles as they are assembled, 65,536 as they are rebased), with
 * non-finite and degenerate triangles spread over the blocks, a mirrored
 * node, vertex normals (some zero) and colours (some out of range or NaN)
 * on the second primitive only: every array as the rules say, in order,
 * computed here again from the file's floats. The face normals are
 * compared bit for bit with the rounded triangle's: GCC 12's -O3 once
 * computed them from the doubles before rounding. */
static void large_primitives_assembled_in_blocks(void)
{
    enum { NA = 50000, NB = 40000 };
    size_t na = 9 * (size_t)NA, nb = 9 * (size_t)NB, ncol = 12 * (size_t)NB;
    size_t bytes = 4 * (na + nb + nb + ncol);
    float *bin = malloc(bytes);
    float *pa = bin, *pbv = pa + na, *nbv = pbv + nb, *cb = nbv + nb;
    uint64_t st = 12345;
    for (size_t i = 0; i < na + nb; ++i) {
        st = st * 6364136223846793005ull + 1442695040888963407ull;
        float x = (float)((st >> 40) / 16777216.0) * 40.f - 20.f; /* 24 random bits */
        pa[i] = i % 3 == 1 ? x * 0.25f : x;
    }
    for (uint32_t t = 0; t < NA + NB; ++t) { /* small triangles: corners near the first */
        float *v = t < NA ? pa + 9 * (size_t)t : pbv + 9 * (size_t)(t - NA);
        for (int k = 3; k < 9; ++k)
            v[k] = v[k % 3] + (v[k] - v[k % 3]) * 1e-3f;
        if (t % 997 == 5)
            v[4 + t % 3] = t % 2 ? NAN : INFINITY;
        else if (t % 1009 == 7)
            memcpy(v + 6, v, 12); /* degenerate */
    }
    for (size_t i = 0; i < nb; ++i)
        nbv[i] = i % 301 < 3 ? 0.f : (float)((i * 7919) % 200) / 100.f - 1.f;
    for (size_t i = 0; i < ncol; ++i)
        cb[i] = i % 97 == 0 ? NAN : (float)((i * 104729) % 300) / 200.f - 0.25f;
    char json[2048];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1]}],"
             "\"nodes\":[{\"mesh\":0},{\"mesh\":1,\"scale\":[1,-1,1],\"translation\":[3,0,-2]}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]},"
             "{\"primitives\":[{\"attributes\":{\"POSITION\":1,\"NORMAL\":2,\"COLOR_0\":3}}]}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"},"
             "{\"bufferView\":2,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"},"
             "{\"bufferView\":3,\"componentType\":5126,\"count\":%u,\"type\":\"VEC4\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu},{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu},"
             "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu},{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}],"
             "\"buffers\":[{\"byteLength\":%zu}]}",
             3 * NA, 3 * NB, 3 * NB, 3 * NB, 4 * na, 4 * na, 4 * nb, 4 * (na + nb), 4 * nb, 4 * (na + 2 * nb),
             4 * ncol, bytes);
    pb_scene *s = load_ok(write_glb_bin("blocks.glb", json, bin, (uint32_t)bytes));
    if (!s) {
        free(bin);
        return;
    }
    /* the world triangles in order (the mirror reverses the winding), the
     * non-finite ones dropped as they come, the origin their box's centre */
    double *w = malloc(sizeof(double) * 9 * (NA + NB));
    uint32_t *src = malloc(sizeof(uint32_t) * (NA + NB));
    uint32_t n = 0, nonfinite = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t t = 0; t < NA + NB; ++t) {
        double *o = w + 9 * (size_t)n;
        int finite = 1;
        for (int c = 0; c < 3; ++c) {
            int from = t < NA ? c : (c ? 3 - c : 0);
            const float *v = t < NA ? pa + 9 * (size_t)t + 3 * from : pbv + 9 * (size_t)(t - NA) + 3 * from;
            double x = v[0], y = v[1], z = v[2];
            if (t >= NA)
                x += 3, y = -y, z -= 2;
            o[3 * c] = x, o[3 * c + 1] = y, o[3 * c + 2] = z;
        }
        for (int k = 0; k < 9; ++k)
            finite &= isfinite(o[k]) != 0;
        if (!finite) {
            nonfinite++;
            continue;
        }
        for (int k = 0; k < 9; ++k) {
            lo[k % 3] = fmin(lo[k % 3], o[k]);
            hi[k % 3] = fmax(hi[k % 3], o[k]);
        }
        src[n++] = t;
    }
    uint32_t kept = 0, degenerate = 0, bad_pos = 0, bad_face = 0, bad_vertex = 0, bad_col = 0;
    for (int k = 0; k < 3; ++k)
        CHECKF(s->origin[k] == 0.5 * (lo[k] + hi[k]), "origin %d: %.17g, want %.17g", k, s->origin[k],
               0.5 * (lo[k] + hi[k]));
    for (uint32_t i = 0; i < n; ++i) {
        float p[9];
        for (int k = 0; k < 9; ++k)
            p[k] = (float)(w[9 * (size_t)i + k] - 0.5 * (lo[k % 3] + hi[k % 3]));
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k)
            e1[k] = (double)p[3 + k] - p[k], e2[k] = (double)p[6 + k] - p[k];
        double g[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        if (g[0] == 0 && g[1] == 0 && g[2] == 0) {
            degenerate++;
            continue;
        }
        if (kept >= s->triangle_count)
            break;
        const float *sp = s->positions + 9 * (size_t)kept, *sn = s->normals + 9 * (size_t)kept;
        bad_pos += memcmp(sp, p, sizeof p) != 0;
        uint32_t t = src[i];
        double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        for (int c = 0; c < 3; ++c) {
            float want[3] = {(float)(g[0] / gl), (float)(g[1] / gl), (float)(g[2] / gl)};
            if (t >= NA) { /* the file's normal: cofactors of diag(1,-1,1) negated by the mirror, unit */
                const float *fn = nbv + 9 * (size_t)(t - NA) + 3 * (c ? 3 - c : 0);
                double v[3] = {fn[0], -(double)fn[1], fn[2]};
                double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                if (l > 0)
                    for (int k = 0; k < 3; ++k)
                        want[k] = (float)((double)(float)v[k] / sqrt((double)(float)v[0] * (float)v[0] +
                                                                     (double)(float)v[1] * (float)v[1] +
                                                                     (double)(float)v[2] * (float)v[2]));
                bad_vertex += sn[3 * c] != want[0] || sn[3 * c + 1] != want[1] || sn[3 * c + 2] != want[2];
            } else {
                bad_face += sn[3 * c] != want[0] || sn[3 * c + 1] != want[1] || sn[3 * c + 2] != want[2];
            }
            for (int k = 0; k < 4; ++k) { /* white before the first coloured primitive, [0, 1] after */
                float x = t < NA ? 1.f : cb[12 * (size_t)(t - NA) + 4 * (c ? 3 - c : 0) + k];
                x = isfinite(x) ? fminf(fmaxf(x, 0.f), 1.f) : 1.f;
                bad_col += !s->colors || s->colors[12 * (size_t)kept + 4 * c + k] != x;
            }
        }
        kept++;
    }
    fprintf(stderr, "  %u + %u triangles: %u kept, %u non-finite, %u degenerate (loader: %u, %llu, %llu)\n", NA, NB,
            kept, nonfinite, degenerate, s->triangle_count, (unsigned long long)s->stats.dropped_nonfinite,
            (unsigned long long)s->stats.dropped_degenerate);
    CHECK(s->triangle_count == kept && kept == n - degenerate);
    CHECK(s->stats.dropped_nonfinite == nonfinite && s->stats.dropped_degenerate == degenerate);
    CHECK(nonfinite > 50 && degenerate > 50);
    CHECKF(bad_pos == 0 && bad_face == 0 && bad_vertex == 0 && bad_col == 0,
           "%u positions, %u face normals, %u vertex normals, %u colours differ", bad_pos, bad_face, bad_vertex,
           bad_col);
    free(w);
    free(src);
    free(bin);
    pb_scene_destroy(s);
}

/* Vertex colours exist once a coloured triangle stays: a coloured
 * primitive whose triangles are all dropped (non-finite) leaves the scene
 * without colours, as before its triangles were written in batches. */
static void colours_only_from_kept_triangles(void)
{
    enum { N = 20000 }; /* more than one block of the loader's threads */
    size_t np = 9 * (size_t)N, nc = 12 * (size_t)N;
    size_t bytes = 4 * (9 + np + nc);
    float *bin = calloc(1, bytes);
    memcpy(bin, tri_pos, 36); /* the first primitive: one plain triangle */
    for (size_t i = 0; i < np; ++i)
        bin[9 + i] = i % 9 == 4 ? NAN : (float)(i % 7);
    for (size_t i = 0; i < nc; ++i)
        bin[9 + np + i] = 0.25f;
    for (int finite_one = 0; finite_one < 2; ++finite_one) {
        if (finite_one) /* the second primitive's last triangle kept */
            for (int k = 0; k < 9; ++k)
                bin[9 + np - 9 + k] = tri_pos[k] + 2.f;
        char json[1536];
        snprintf(json, sizeof json,
                 "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                 "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}},"
                 "{\"attributes\":{\"POSITION\":1,\"COLOR_0\":2}}]}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
                 "{\"bufferView\":1,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"},"
                 "{\"bufferView\":2,\"componentType\":5126,\"count\":%u,\"type\":\"VEC4\"}],"
                 "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":%zu},"
                 "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}],\"buffers\":[{\"byteLength\":%zu}]}",
                 3 * N, 3 * N, 4 * np, 36 + 4 * np, 4 * nc, bytes);
        pb_scene *s = load_ok(write_glb_bin("colours.glb", json, bin, (uint32_t)bytes));
        if (!s)
            continue;
        CHECKF(s->triangle_count == 1u + (uint32_t)finite_one && s->stats.dropped_nonfinite == N - (uint32_t)finite_one,
               "%u triangles, %llu non-finite", s->triangle_count, (unsigned long long)s->stats.dropped_nonfinite);
        if (!finite_one) {
            CHECKF(s->colors == NULL, "colours with no coloured triangle kept");
        } else if (s->colors) { /* the plain triangle white, the kept coloured one its colour */
            CHECK(s->colors[0] == 1.f && s->colors[11] == 1.f && s->colors[12] == 0.25f && s->colors[23] == 0.25f);
        } else {
            CHECKF(0, "no colours with a coloured triangle kept");
        }
        pb_scene_destroy(s);
    }
    free(bin);
}

/* A .glb: header, JSON chunk (space padded), BIN chunk of the triangle. */
static const char *write_glb(const char *name, const char *json)
{
    uint32_t jlen = (uint32_t)((strlen(json) + 3) & ~3u);
    uint32_t total = 12 + 8 + jlen + 8 + 36;
    unsigned char *glb = calloc(1, total);
    uint32_t hdr[3] = {0x46546C67u, 2, total};
    memcpy(glb, hdr, 12);
    uint32_t jc[2] = {jlen, 0x4E4F534Au};
    memcpy(glb + 12, jc, 8);
    memset(glb + 20, ' ', jlen);
    memcpy(glb + 20, json, strlen(json));
    uint32_t bc[2] = {36, 0x004E4942u};
    memcpy(glb + 20 + jlen, bc, 8);
    memcpy(glb + 28 + jlen, tri_pos, 36);
    const char *path = write_file(name, glb, total);
    free(glb);
    return path;
}

/* The triangle as a .glb whose POSITION accessor claims `count` elements. */
static const char *glb_with_count(const char *name, const char *count)
{
    char json[1024];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%s,\"type\":\"VEC3\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"buffers\":[{\"byteLength\":36}]}", count);
    return write_glb(name, json);
}

static void glb_and_external_buffers(void)
{
    pb_scene *s = load_ok(glb_with_count("tri.glb", "3"));
    CHECK(s && s->triangle_count == 1);
    pb_scene_destroy(s);

    /* .gltf with an external .bin beside it */
    write_file("tri.bin", tri_pos, 36);
    const char *ext = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                      "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                      "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                      "\"buffers\":[{\"byteLength\":36,\"uri\":\"tri.bin\"}]}";
    s = load_ok(write_file("external.gltf", ext, strlen(ext)));
    CHECK(s && s->triangle_count == 1);
    pb_scene_destroy(s);
}

static void normalized_integer_texcoords(void)
{
    unsigned char bin[36 + 8];
    memcpy(bin, tri_pos, 36);
    unsigned char uv[8] = {0, 0, 255, 0, 0, 51, 0, 0}; /* 3 x (u8,u8) padded to 4-byte stride */
    memcpy(bin + 36, uv, 8);
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1}}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5121,\"normalized\":true,\"count\":3,\"type\":\"VEC2\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
        "\"buffers\":[{\"byteLength\":44,\"uri\":\"@BUF@\"}]}";
    pb_scene *s = load_ok(write_gltf("uv8.gltf", json, bin, 44));
    if (!s)
        return;
    CHECK(s->texcoords[0] == 0.f && s->texcoords[2] == 1.f && fabsf(s->texcoords[5] - 0.2f) < 1e-6f);
    pb_scene_destroy(s);
}

/* COLOR_0 (glTF: multiplies the base colour, alpha included): normalized
 * UNSIGNED_BYTE RGBA and float RGB read exactly, a primitive without it is
 * white beside one with it, the interpolated alpha takes part in the alpha
 * test, and a scene without any has no colour array. */
static void vertex_colours_loaded(void)
{
    /* two primitives over the same triangle: ubyte RGBA colours, then none;
     * a third with float RGB (alpha 1) */
    unsigned char bin[36 + 12 + 36];
    memcpy(bin, tri_pos, 36);
    unsigned char rgba[12] = {255, 0, 51, 255, 0, 255, 0, 0, 255, 255, 255, 0};
    memcpy(bin + 36, rgba, 12);
    float rgb[9] = {0.5f, 0.25f, 1.f, 0.f, 0.75f, 0.125f, 1.f, 1.f, 1.f};
    memcpy(bin + 48, rgb, 36);
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"materials\":[{\"alphaMode\":\"MASK\",\"alphaCutoff\":0.5}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"COLOR_0\":1},\"material\":0},"
        "{\"attributes\":{\"POSITION\":0}},{\"attributes\":{\"POSITION\":0,\"COLOR_0\":2}}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5121,\"normalized\":true,\"count\":3,\"type\":\"VEC4\"},"
        "{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":12},"
        "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":36}],"
        "\"buffers\":[{\"byteLength\":84,\"uri\":\"@BUF@\"}]}";
    pb_scene *s = load_ok(write_gltf("color0.gltf", json, bin, sizeof bin));
    if (!s)
        return;
    CHECK(s->triangle_count == 3 && s->colors != NULL);
    if (s->triangle_count == 3 && s->colors) {
        int ok = 1;
        for (int k = 0; k < 12; ++k) {
            ok &= s->colors[k] == rgba[k] / 255.f || fabsf(s->colors[k] - rgba[k] / 255.f) < 1e-7f;
            ok &= s->colors[12 + k] == 1.f;
            ok &= s->colors[24 + k] == (k % 4 == 3 ? 1.f : rgb[3 * (k / 4) + k % 4]);
        }
        CHECKF(ok, "colours read wrong");
        /* alpha: corners 1, 0, 0: opaque near corner 0 only (cutoff 0.5) */
        CHECK(pb_alpha_opaque(s, 0, 0.1f, 0.1f) && !pb_alpha_opaque(s, 0, 0.45f, 0.45f));
        float c[4];
        pb_vertex_color(s, 0, 0.25f, 0.5f, c); /* 0.25 of corner 1, 0.5 of corner 2 */
        CHECK(fabsf(c[0] - 0.75f) < 1e-6f && fabsf(c[1] - 0.75f) < 1e-6f && fabsf(c[3] - 0.25f) < 1e-6f);
    }
    pb_scene_destroy(s);
    s = load_ok(PB_SOURCE_DIR "/tests/scenes/demo.gltf");
    CHECK(s && s->colors == NULL);
    pb_scene_destroy(s);
}

/* Sparse accessors (core glTF 2.0): substitutions over a base bufferView
 * and over an accessor with no bufferView (zeros), and the malformed kinds
 * (an index past the end, indices that do not increase, values past their
 * view) refused naming the accessor. Two triangles; the sparse part moves
 * vertex 1 of the first and builds the second from zeros. */
static void sparse_accessors(void)
{
    /* bytes: 0 base positions (6 vertices, 72 B); 72 indices u16 [1, 4, 5] (6 B, padded to 8);
     * 80 values (3 x vec3 = 36 B); 116 indices u8 [3, 4, 5] (3 B, padded to 4); 120 values (36 B) */
    unsigned char bin[156];
    memset(bin, 0, sizeof bin);
    float base[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 5, 5, 5, 5, 5, 5};
    memcpy(bin, base, 72);
    uint16_t i16[3] = {1, 4, 5};
    memcpy(bin + 72, i16, 6);
    float v1[9] = {2, 0, 0, 1, 0, 3, 0, 1, 3};
    memcpy(bin + 80, v1, 36);
    uint8_t i8[3] = {3, 4, 5};
    memcpy(bin + 116, i8, 3);
    float v2[9] = {0, 0, 7, 1, 0, 7, 0, 1, 7};
    memcpy(bin + 120, v2, 36);
    const char *fmt =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}},{\"attributes\":{\"POSITION\":1}}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":6,\"type\":\"VEC3\","
        "\"sparse\":{\"count\":3,\"indices\":{\"bufferView\":1,\"componentType\":5123},"
        "\"values\":{\"bufferView\":2}}},"
        "{\"componentType\":5126,\"count\":6,\"type\":\"VEC3\","
        "\"sparse\":{\"count\":3,\"indices\":{\"bufferView\":3,\"componentType\":5121},"
        "\"values\":{\"bufferView\":%d}}}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":72},{\"buffer\":0,\"byteOffset\":72,\"byteLength\":6},"
        "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":116,\"byteLength\":3},"
        "{\"buffer\":0,\"byteOffset\":120,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":120,\"byteLength\":30}],"
        "\"buffers\":[{\"byteLength\":156,\"uri\":\"@BUF@\"}]}";
    char json[4096];
    snprintf(json, sizeof json, fmt, 4);
    pb_scene *s = load_ok(write_gltf("sparse.gltf", json, bin, sizeof bin));
    if (s) {
        /* accessor 0 as triangles (0,1,2) (3,4,5): vertex 1 moved to (2,0,0); 4 and 5 to z = 3;
         * accessor 1: zeros but 3, 4, 5 -> one triangle at z = 7 (its first, all-zero, is degenerate) */
        double p[3];
        CHECK(s->triangle_count == 3);
        world(s, 0, 1, p);
        CHECK(near3(p, 2, 0, 0, 1e-6));
        world(s, 1, 1, p);
        CHECK(near3(p, 1, 0, 3, 1e-6));
        world(s, 2, 2, p);
        CHECK(near3(p, 0, 1, 7, 1e-6));
        pb_scene_destroy(s);
    }
    snprintf(json, sizeof json, fmt, 5); /* values view 6 bytes short */
    load_fails(write_gltf("sparse-short.gltf", json, bin, sizeof bin), PB_ERROR_PARSE, "sparse values");
    bin[116 + 2] = 9; /* index 9 of 6 */
    snprintf(json, sizeof json, fmt, 4);
    load_fails(write_gltf("sparse-past.gltf", json, bin, sizeof bin), PB_ERROR_PARSE, "past the accessor's end");
    bin[116 + 2] = 4; /* 3, 4, 4 */
    load_fails(write_gltf("sparse-order.gltf", json, bin, sizeof bin), PB_ERROR_PARSE, "does not increase");
}

/* Materials of extensions a bake must read: KHR_materials_pbrSpecularGlossiness
 * (the diffuse factor is the albedo, metallic 0) and KHR_materials_unlit
 * (it emits its base colour and reflects nothing), both accepted when
 * required. */
static void spec_gloss_and_unlit_materials(void)
{
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"extensionsUsed\":[\"KHR_materials_pbrSpecularGlossiness\",\"KHR_materials_unlit\"],"
        "\"extensionsRequired\":[\"KHR_materials_pbrSpecularGlossiness\",\"KHR_materials_unlit\"],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"metallicFactor\":1.0},\"extensions\":{"
        "\"KHR_materials_pbrSpecularGlossiness\":{\"diffuseFactor\":[0.2,0.4,0.6,1.0],"
        "\"specularFactor\":[1,1,1],\"glossinessFactor\":0.9}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.25,1.0,1.0]},\"extensions\":{\"KHR_materials_unlit\":{}}}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
        "{\"attributes\":{\"POSITION\":0},\"material\":1}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
        "\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}";
    pb_scene *s = load_ok(write_gltf("specgloss.gltf", json, tri_pos, sizeof tri_pos));
    if (!s)
        return;
    CHECK(s->material_count >= 2);
    const pb_material *sg = &s->materials[0], *ul = &s->materials[1];
    fprintf(stderr, "  spec-gloss albedo (%g, %g, %g) metallic %g; unlit emits (%g, %g, %g), base (%g, %g, %g)\n",
            sg->base_color[0], sg->base_color[1], sg->base_color[2], sg->metallic, ul->emissive[0], ul->emissive[1],
            ul->emissive[2], ul->base_color[0], ul->base_color[1], ul->base_color[2]);
    CHECK(sg->base_color[0] == 0.2f && sg->base_color[1] == 0.4f && sg->base_color[2] == 0.6f && sg->metallic == 0.f);
    CHECK(ul->emissive[0] == 0.5f && ul->emissive[1] == 0.25f && ul->emissive[2] == 1.f);
    CHECK(ul->base_color[0] == 0.f && ul->base_color[1] == 0.f && ul->base_color[2] == 0.f);
    pb_scene_destroy(s);
}

/* KHR_texture_transform on the base colour texture: the UVs the scene keeps
 * are offset + R(rotation) x scale x uv with u' = cos u + sin v,
 * v' = -sin u + cos v (the direction the Khronos sample TextureTransformTest
 * marks correct); checked at the three vertices (uv (0,0), (1,0), (0,1))
 * with offset (0.5, 0.25), scale (2, 3) and a quarter turn: (0.5, 0.25),
 * (0.5, -1.75), (3.5, 0.25). */
static void texture_transform_applied(void)
{
    unsigned char bin[36 + 24];
    memcpy(bin, tri_pos, 36);
    float uv[6] = {0, 0, 1, 0, 0, 1};
    memcpy(bin + 36, uv, 24);
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"extensionsUsed\":[\"KHR_texture_transform\"],\"extensionsRequired\":[\"KHR_texture_transform\"],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0,\"extensions\":{"
        "\"KHR_texture_transform\":{\"offset\":[0.5,0.25],\"scale\":[2,3],\"rotation\":1.5707963267948966}}}}}],"
        "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"data:image/png;base64,"
        "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==\"}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"material\":0}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":24}],"
        "\"buffers\":[{\"byteLength\":60,\"uri\":\"@BUF@\"}]}";
    pb_scene *s = load_ok(write_gltf("texture-transform.gltf", json, bin, sizeof bin));
    if (!s)
        return;
    const float want[6] = {0.5f, 0.25f, 0.5f, -1.75f, 3.5f, 0.25f};
    float worst = 0.f;
    for (int k = 0; k < 6; ++k)
        worst = fmaxf(worst, fabsf(s->texcoords[k] - want[k]));
    fprintf(stderr, "  uv (%g, %g) (%g, %g) (%g, %g), worst difference %.1e\n", s->texcoords[0], s->texcoords[1],
            s->texcoords[2], s->texcoords[3], s->texcoords[4], s->texcoords[5], worst);
    CHECK(s->triangle_count == 1 && worst < 1e-6f);
    pb_scene_destroy(s);
}

static void bad_triangles_dropped_and_counted(void)
{
    float pos[27] = {0, 0, 0, 1, 0, 0, 0, 1, 0,        /* good */
                     0, 0, 0, 1, 1, 1, 2, 2, 2,        /* collinear: zero area */
                     0, 0, 0, NAN, 0, 0, 0, 1, 0};     /* NaN */
    const char *json = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                       "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                       "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":9,\"type\":\"VEC3\"}],"
                       "\"bufferViews\":[{\"buffer\":0,\"byteLength\":108}],"
                       "\"buffers\":[{\"byteLength\":108,\"uri\":\"@BUF@\"}]}";
    pb_scene *s = load_ok(write_gltf("bad.gltf", json, pos, sizeof pos));
    if (!s)
        return;
    CHECK(s->triangle_count == 1);
    CHECK(s->stats.triangles_in == 3);
    CHECK(s->stats.dropped_degenerate == 1);
    CHECK(s->stats.dropped_nonfinite == 1);
    pb_scene_destroy(s);

    /* Inf in a node transform poisons every triangle below it */
    s = load_ok(one_triangle("inf.gltf", "\"nodes\":[{\"mesh\":0,\"translation\":[1e308,1e308,0],"
                                         "\"scale\":[1e308,1,1]}],"));
    CHECK(s && s->triangle_count == 0 && s->stats.dropped_nonfinite == 1);
    pb_scene_destroy(s);
}

/* A triangle kept after a dropped one moves down with all it carries: the
 * loader compacts positions, normals, texture coordinates and materials in
 * place (scene_builder.c), so each must land beside its own triangle. */
static void kept_triangles_keep_their_attributes(void)
{
    float bin[9 * 3 + 9 * 3 + 9 * 2] = {
        0, 0, 0,  1, 0, 0,  0, 1, 0,           /* A: kept */
        0, 0, 0,  1, 1, 1,  2, 2, 2,           /* D: collinear, dropped */
        0, 0, 2,  1, 0, 2,  0, 1, 2,           /* B: kept, second primitive, material 1 */
        0, 0, 1,  0, 0, 1,  0, 0, 1,           /* normals */
        0, 0, 1,  0, 0, 1,  0, 0, 1,
        0, 0.6f, 0.8f,  0, 0.8f, 0.6f,  0.6f, 0, 0.8f,
        0, 0,  1, 0,  0, 1,                    /* texture coordinates */
        0.9f, 0.9f,  0.8f, 0.8f,  0.7f, 0.7f,
        0.5f, 0.5f,  0.25f, 0.75f,  0.125f, 0.875f};
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"materials\":[{\"name\":\"a\"},{\"name\":\"b\"}],"
        "\"meshes\":[{\"primitives\":["
        "{\"attributes\":{\"POSITION\":0,\"NORMAL\":2,\"TEXCOORD_0\":4},\"material\":0},"
        "{\"attributes\":{\"POSITION\":1,\"NORMAL\":3,\"TEXCOORD_0\":5},\"material\":1}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":6,\"type\":\"VEC3\"},"
        "{\"bufferView\":0,\"byteOffset\":72,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5126,\"count\":6,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"byteOffset\":72,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":2,\"componentType\":5126,\"count\":6,\"type\":\"VEC2\"},"
        "{\"bufferView\":2,\"byteOffset\":48,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":108},{\"buffer\":0,\"byteOffset\":108,\"byteLength\":108},"
        "{\"buffer\":0,\"byteOffset\":216,\"byteLength\":72}],"
        "\"buffers\":[{\"byteLength\":288,\"uri\":\"@BUF@\"}]}";
    pb_scene *s = load_ok(write_gltf("kept-attributes.gltf", json, bin, sizeof bin));
    if (!s)
        return;
    CHECKF(s->triangle_count == 2 && s->stats.dropped_degenerate == 1, "%u triangles, %llu dropped",
           s->triangle_count, (unsigned long long)s->stats.dropped_degenerate);
    if (s->triangle_count != 2) {
        pb_scene_destroy(s);
        return;
    }
    float worst = 0.f;
    for (int k = 0; k < 9; ++k) {
        worst = fmaxf(worst, fabsf(s->positions[k] + (float)s->origin[k % 3] - bin[k]));
        worst = fmaxf(worst, fabsf(s->positions[9 + k] + (float)s->origin[k % 3] - bin[18 + k]));
        worst = fmaxf(worst, fabsf(s->normals[k] - bin[27 + k]));
        worst = fmaxf(worst, fabsf(s->normals[9 + k] - bin[27 + 18 + k]));
    }
    for (int k = 0; k < 6; ++k) {
        worst = fmaxf(worst, fabsf(s->texcoords[k] - bin[54 + k]));
        worst = fmaxf(worst, fabsf(s->texcoords[6 + k] - bin[54 + 12 + k]));
    }
    fprintf(stderr, "  worst attribute difference %.1e, materials %u %u\n", worst, s->material[0], s->material[1]);
    CHECK(worst < 1e-6f);
    CHECK(s->material[0] == 0 && s->material[1] == 1);
    pb_scene_destroy(s);
}

/* Vertex normals are read for shading: normalized, a zero one replaced by
 * the face normal (it used to become +Y), a bent one kept; packed for the
 * kernels within 1e-4 radians; interpolated, turned to the side a ray
 * arrives from, and the face normal where they cancel. */
/* The count over many blocks of triangles (it runs on all host cores): every
 * seventh of 300,000 triangles has one corner's normal tilted 2 degrees,
 * every eleventh a corner's normal turned to the back (not bent), the rest
 * the face normal; triangles in 100 orientations. */
static void bent_triangles_counted_over_blocks(void)
{
    const uint32_t n = 300000;
    pb_scene s;
    memset(&s, 0, sizeof s);
    s.triangle_count = n;
    s.positions = malloc((size_t)n * 36);
    s.normals = malloc((size_t)n * 36);
    if (!s.positions || !s.normals) {
        free(s.positions), free(s.normals);
        CHECK(0);
        return;
    }
    uint64_t want = 0;
    for (uint32_t t = 0; t < n; ++t) {
        double a = 0.0628 * (t % 100), c = cos(a), sn = sin(a); /* the triangle turned about X */
        const float p[9] = {0, 0, 0, 1, 0, 0, 0, (float)c, (float)sn};
        float nz[3] = {0, (float)-sn, (float)c}; /* its face normal */
        memcpy(s.positions + 9 * (size_t)t, p, 36);
        for (int v = 0; v < 3; ++v)
            memcpy(s.normals + 9 * (size_t)t + 3 * v, nz, 12);
        float *n0 = s.normals + 9 * (size_t)t;
        if (t % 7 == 0) { /* 2 degrees toward +X */
            const float tilt = 0.0349f;
            n0[0] = sinf(tilt), n0[1] = nz[1] * cosf(tilt), n0[2] = nz[2] * cosf(tilt);
            ++want;
        } else if (t % 11 == 0) {
            n0[1] = -nz[1], n0[2] = -nz[2];
        }
    }
    uint64_t got = pb_scene_bent_triangles(&s);
    CHECKF(got == want, "%llu bent, want %llu", (unsigned long long)got, (unsigned long long)want);
    free(s.positions), free(s.normals);
}

static void vertex_normals_read_for_shading(void)
{
    float data[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0,   /* positions: counter-clockwise seen from +Z */
                      0, 0, 0, 0, 0, 2, 1, 0, 1};  /* normals: zero, +Z twice as long, 45 degrees toward +X */
    const char *json = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                       "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1}}]}],"
                       "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
                       "{\"bufferView\":0,\"byteOffset\":36,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                       "\"bufferViews\":[{\"buffer\":0,\"byteLength\":72}],"
                       "\"buffers\":[{\"byteLength\":72,\"uri\":\"@BUF@\"}]}";
    char path[512];
    snprintf(path, sizeof path, "%s", write_gltf("normals.gltf", json, data, sizeof data));
    pb_scene *s = load_ok(path);
    if (!s)
        return;
    const float r = 0.70710678f, want[9] = {0, 0, 1, 0, 0, 1, r, 0, r};
    float worst = 0;
    for (int k = 0; k < 9; ++k)
        worst = fmaxf(worst, fabsf(s->normals[k] - want[k]));
    CHECKF(s->triangle_count == 1 && worst < 1e-6f, "normals off by %g", worst);
    CHECK(pb_scene_bent_triangles(s) == 1);
    /* at the corners the vertex normals, within the packing; from behind, turned to the back */
    float up[3] = {0, 0, 1}, down[3] = {0, 0, -1}, ns[3];
    pb_shading_normal_cpu(s, 0, 0.f, 1.f, up, ns);
    CHECKF(fabsf(ns[0] - r) < 1e-4f && fabsf(ns[2] - r) < 1e-4f, "(%g %g %g)", ns[0], ns[1], ns[2]);
    pb_shading_normal_cpu(s, 0, 0.f, 1.f, down, ns);
    CHECKF(fabsf(ns[0] + r) < 1e-4f && fabsf(ns[2] + r) < 1e-4f, "(%g %g %g)", ns[0], ns[1], ns[2]);
    /* opposite vertex normals cancel half way: the face normal */
    s->normals[3] = 0, s->normals[5] = -1, s->normals[6] = 0, s->normals[8] = 1;
    pb_shading_normal_cpu(s, 0, 0.5f, 0.5f, up, ns);
    CHECKF(ns[0] == 0.f && ns[1] == 0.f && ns[2] == 1.f, "(%g %g %g)", ns[0], ns[1], ns[2]);
    pb_scene_destroy(s);
    /* pb_scene_desc.face_normals (--shading-normals face): the face normals, flat shading */
    pb_scene_desc fd = {0};
    fd.face_normals = 1;
    pb_error err;
    CHECK(pb_scene_load(path, &fd, &s, &err) == PB_OK && pb_scene_bent_triangles(s) == 0 &&
          s->normals[6] == 0.f && s->normals[8] == 1.f);
    /* the scene hash (merge's check) tells them apart: the bent normals shade */
    pb_scene *vertex = load_ok(path);
    CHECK(vertex && s && pb_scene_hash(vertex) != pb_scene_hash(s));
    pb_scene_destroy(vertex);
    pb_scene_destroy(s);

    /* the packing: random directions, the axes and the octahedron's edges */
    uint64_t state = 7;
    double max_angle = 0;
    for (int i = 0; i < 200000; ++i) {
        float n[3], back[3];
        if (i < 6) {
            n[0] = n[1] = n[2] = 0.f;
            n[i / 2] = i % 2 ? -1.f : 1.f;
        } else if (i < 1006) { /* z = 0: the fold's seam */
            float a = 6.2831853f * (float)(i - 6) / 1000.f;
            n[0] = cosf(a), n[1] = sinf(a), n[2] = 0.f;
        } else {
            float z = 2.f * (float)((state = state * 6364136223846793005ull + 1442695040888963407ull) >> 40) /
                      16777216.f - 1.f;
            float a = 6.2831853f * (float)((state = state * 6364136223846793005ull + 1442695040888963407ull) >> 40) /
                      16777216.f;
            float rr = sqrtf(fmaxf(0.f, 1.f - z * z));
            n[0] = rr * cosf(a), n[1] = rr * sinf(a), n[2] = z;
        }
        uint32_t w = pb_normal_pack(n);
        pb_normal_unpack(w, back);
        /* the angle from the cross product: acos of a float dot product cannot resolve 1e-4 */
        double c[3] = {(double)n[1] * back[2] - (double)n[2] * back[1], (double)n[2] * back[0] - (double)n[0] * back[2],
                       (double)n[0] * back[1] - (double)n[1] * back[0]};
        double d = (double)n[0] * back[0] + (double)n[1] * back[1] + (double)n[2] * back[2];
        max_angle = fmax(max_angle, atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), d));
    }
    fprintf(stderr, "  packed normals: worst angle %.2e rad over 200000 directions\n", max_angle);
    CHECK(max_angle < 1e-4);

    /* the shared scenes: the demo is flat, the duck and the helmet smooth */
    /* a flat scene's hash is the same either way (and what it was before normals shaded) */
    pb_scene *demo = load_ok(source_path("tests/scenes/demo.gltf")), *demo_face = NULL;
    CHECK(demo && pb_scene_bent_triangles(demo) == 0);
    CHECK(pb_scene_load(source_path("tests/scenes/demo.gltf"), &fd, &demo_face, &err) == PB_OK && demo &&
          pb_scene_hash(demo) == pb_scene_hash(demo_face));
    pb_scene_destroy(demo);
    pb_scene_destroy(demo_face);
    const char *smooth[2] = {"samples/Duck/Duck.gltf", "samples/DamagedHelmet/DamagedHelmet.gltf"};
    for (int i = 0; i < 2; ++i) {
        char path[1024];
        snprintf(path, sizeof path, "%s/../shared/scenes/%s", PB_SOURCE_DIR, smooth[i]);
        if (!file_exists(path))
            continue;
        pb_scene *m = load_ok(path);
        uint64_t bent = m ? pb_scene_bent_triangles(m) : 0;
        fprintf(stderr, "  %s: %llu of %u triangles shade smooth\n", smooth[i], (unsigned long long)bent,
                m ? m->triangle_count : 0);
        CHECK(m && bent > m->triangle_count / 4);
        pb_scene_destroy(m);
    }
}

static void far_from_origin_is_rebased(void)
{
    pb_scene *near = load_ok(one_triangle("near.gltf", "\"nodes\":[{\"mesh\":0}],"));
    pb_scene *far = load_ok(one_triangle("far.gltf", "\"nodes\":[{\"mesh\":0,\"translation\":[1e7,-3e6,1e6]}],"));
    if (!near || !far)
        return;
    CHECK(far->origin[0] == 1e7 + 0.5 && far->origin[1] == -3e6 + 0.5);
    /* local coordinates are the same floats: no precision lost to the offset */
    CHECK(memcmp(near->positions, far->positions, 9 * sizeof(float)) == 0);
    pb_scene_destroy(near);
    pb_scene_destroy(far);
}

static void malformed_files_get_clear_errors(void)
{
    load_fails("/nonexistent/scene.gltf", PB_ERROR_IO, "cannot open");
    const char *garbage = "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [";
    load_fails(write_file("garbage.gltf", garbage, strlen(garbage)), PB_ERROR_PARSE, NULL);
    load_fails(write_file("empty.gltf", "", 0), PB_ERROR_PARSE, NULL);
    load_fails(write_file("notglb.glb", "glTF\x02\0\0\0\x10\0\0\0", 12), PB_ERROR_PARSE, NULL);

    const char *missing_bin = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                              "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                              "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                              "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                              "\"buffers\":[{\"byteLength\":36,\"uri\":\"missing.bin\"}]}";
    load_fails(write_file("missingbin.gltf", missing_bin, strlen(missing_bin)), PB_ERROR_IO, "missing.bin");

    /* the buffer holds 24 bytes, the view and accessor claim 36 */
    const char *trunc = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                        "\"buffers\":[{\"byteLength\":24,\"uri\":\"@BUF@\"}]}";
    load_fails(write_gltf("truncated.gltf", trunc, tri_pos, 24), PB_ERROR_PARSE, NULL);

    /* accessor reads past its view */
    const char *past = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                       "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                       "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":30,\"type\":\"VEC3\"}],"
                       "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                       "\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}";
    load_fails(write_gltf("pastview.gltf", past, tri_pos, 36), PB_ERROR_PARSE, "accessor 0");

    /* accessor index that does not exist */
    const char *noacc = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":7}}]}],"
                        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                        "\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}";
    load_fails(write_gltf("noaccessor.gltf", noacc, tri_pos, 36), PB_ERROR_PARSE, NULL);

    /* vertex index out of range */
    unsigned char bin[42];
    memcpy(bin, tri_pos, 36);
    uint16_t idx[3] = {0, 1, 9};
    memcpy(bin + 36, idx, 6);
    const char *badidx = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                         "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
                         "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
                         "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],"
                         "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},"
                         "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
                         "\"buffers\":[{\"byteLength\":42,\"uri\":\"@BUF@\"}]}";
    load_fails(write_gltf("badindex.gltf", badidx, bin, 42), PB_ERROR_PARSE, "out of range");

    /* a required extension we do not implement */
    const char *req = "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_materials_volume\"],"
                      "\"extensionsRequired\":[\"KHR_materials_volume\"],\"scenes\":[{\"nodes\":[]}]}";
    load_fails(write_file("volume.gltf", req, strlen(req)), PB_ERROR_UNSUPPORTED, "KHR_materials_volume");

    /* a cycle in the node graph */
    load_fails(one_triangle("cycle.gltf", "\"nodes\":[{\"mesh\":0,\"children\":[1]},{\"children\":[0]}],"),
               PB_ERROR_PARSE, NULL);

    /* a node naming a mesh that does not exist */
    load_fails(one_triangle("nomesh.gltf", "\"nodes\":[{\"mesh\":3}],"), PB_ERROR_PARSE, "mesh 3");
}

/* Hostile inputs (issue 10): what is not a regular file is named as such
 * without blocking, accessor counts are checked against the buffer before
 * anything is sized from them, and JSON nesting is bounded before the
 * parser recurses. Each is a one-line error naming the file, never a crash
 * (this runs under ASan/UBSan in CI, where a 2^32 x 24-byte allocation
 * would abort). */
static void hostile_inputs_refused(void)
{
    char dir[600], fifo[600], dev[600];
    snprintf(dir, sizeof dir, "%s/a-directory.gltf", temp_dir());
    mkdir(dir, 0755);
    load_fails(dir, PB_ERROR_IO, "is a directory");
    snprintf(fifo, sizeof fifo, "%s/fifo.gltf", temp_dir());
    unlink(fifo);
    CHECK(mkfifo(fifo, 0644) == 0);
    load_fails(fifo, PB_ERROR_IO, "is not a regular file (a FIFO)"); /* no writer: must not hang */
    if (geteuid() == 0) { /* a null device of our own, never the machine's /dev */
        snprintf(dev, sizeof dev, "%s/zero.gltf", temp_dir());
        unlink(dev);
        CHECK(mknod(dev, S_IFCHR | 0644, makedev(1, 5)) == 0);
        load_fails(dev, PB_ERROR_IO, "is not a regular file (a character device)");
        unlink(dev);
    }
    load_fails(glb_with_count("count-2e32.glb", "4294967295"), PB_ERROR_PARSE, "reads past the end of bufferView");
    load_fails(glb_with_count("count-2e61.glb", "2305843009213693952"), PB_ERROR_PARSE, "reads past the end");
    load_fails(glb_with_count("count-2e8.glb", "200000000"), PB_ERROR_PARSE, "reads past the end");
    const char *noview = "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                         "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                         "\"accessors\":[{\"componentType\":5126,\"count\":4294967295,\"type\":\"VEC3\"}]}";
    load_fails(write_file("count-no-view.gltf", noview, strlen(noview)), PB_ERROR_PARSE, "no bufferView");
    /* 20,000 levels overflowed the parser's stack; 500 still load */
    for (int deep = 0; deep < 2; ++deep) {
        int levels = deep ? 20000 : 500;
        size_t n = 64 + 2 * (size_t)levels;
        char *json = malloc(n), *o = json;
        o += sprintf(o, "{\"asset\":{\"version\":\"2.0\"},\"extras\":");
        memset(o, '[', (size_t)levels - 2), o += levels - 2;
        memset(o, ']', (size_t)levels - 2), o += levels - 2;
        o += sprintf(o, "}");
        const char *path = write_file(deep ? "nested-20000.gltf" : "nested-500.gltf", json, (size_t)(o - json));
        if (deep) {
            load_fails(path, PB_ERROR_PARSE, "JSON nested deeper than 512 levels");
        } else {
            pb_scene *s = load_ok(path);
            pb_scene_destroy(s);
        }
        free(json);
    }
    /* an external buffer that is a directory */
    const char *ext = "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":36,\"uri\":\"a-directory.gltf\"}]}";
    pb_scene *s = (pb_scene *)1;
    pb_error err;
    pb_result r = pb_scene_load(write_file("buffer-dir.gltf", ext, strlen(ext)), NULL, &s, &err);
    CHECKF(r != PB_OK && s == NULL && strstr(err.message, "buffer-dir.gltf"), "%s: %s", pb_result_name(r), err.message);
}

static void corrupt_texture_is_a_warning(void)
{
    pb_scene *s = load_ok(textured_triangle(
        "badpng.gltf", "", "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"data:image/png;base64,AAAAAAAA\"}]",
        ""));
    CHECK(s && s->triangle_count == 1 && s->materials[0].base_color_texture == -1);
    pb_scene_destroy(s);
    /* a WebP header over no image data, the only source of a texture
     * (EXT_texture_webp required): the factor again */
    s = load_ok(textured_triangle(
        "badwebp.gltf", "\"extensionsUsed\":[\"EXT_texture_webp\"],\"extensionsRequired\":[\"EXT_texture_webp\"],",
        "\"textures\":[{\"extensions\":{\"EXT_texture_webp\":{\"source\":0}}}],"
        "\"images\":[{\"uri\":\"data:image/webp;base64,UklGRgwAAABXRUJQVlA4IAAAAAA=\"}]",
        ""));
    CHECK(s && s->triangle_count == 1 && s->materials[0].base_color_texture == -1);
    pb_scene_destroy(s);
    /* KHR_texture_basisu used, not required, its image not a KTX2 file
     * (the identifier's first byte wrong): the core PNG is read, quietly */
    const char *ktx2 = textured_triangle(
        "ktx2.gltf", "\"extensionsUsed\":[\"KHR_texture_basisu\"],",
        "\"textures\":[{\"source\":1,\"extensions\":{\"KHR_texture_basisu\":{\"source\":0}}}],"
        "\"images\":[{\"uri\":\"data:image/ktx2;base64,Q0tUWCAyMLsNChoKAAAAAAAAAAAAAAAAAAAAAAAAAAA=\"},"
        "{\"uri\":\"data:image/png;base64,"
        "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==\"}]",
        "");
    warning_counter any = {{": ", NULL}, 0}; /* every warning names the file */
    pb_scene_desc d = {{count_warnings, &any}, 0, 0, 0};
    pb_error err;
    s = NULL;
    CHECKF(pb_scene_load(ktx2, &d, &s, &err) == PB_OK, "%s", err.message);
    CHECK(s && s->materials[0].base_color_texture == 0 && s->texture_count == 1 && s->textures[0].width == 1 &&
          any.count == 0);
    pb_scene_destroy(s);
}

/* KHR_texture_basisu. The files in tests/data/ktx2 were written by Basis
 * Universal's own encoder (scripts/make_ktx2_fixtures.sh). ETC1S: an alpha
 * slice, 8 mip levels, the encoder's lowest and highest quality (codebooks
 * of a few entries and of hundreds), grey endpoints, one flat colour, sizes
 * that are not multiples of 4. UASTC: Zstandard supercompressed and stored
 * as it is, with alpha, rate-distortion optimised, the slower effort's
 * partitions, and 1,024 random blocks the transcoder accepts (every mode,
 * every pattern table, trit and quint codes past their range). Each loads,
 * as a glTF's only source for its texture, to the texels Binomial's
 * transcoder decodes from it (the .rgba beside it) byte for byte, with no
 * warning. */
static void ktx2_textures_decoded_as_basis_transcodes_them(void)
{
    static const char *const files[] = {
        "etc1s_gradient_alpha", "etc1s_noise_mips",   "etc1s_noise_low",    "etc1s_grey",
        "etc1s_contrast",       "demo_lattice",       "etc1s_flat",         "uastc_gradient",
        "uastc_noise_mips",     "uastc_gradient_rdo", "uastc_contrast_slow", "uastc_random_blocks",
        "demo_lattice_uastc"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[512], name[64], textures[256];
        size_t n = 0, m = 0;
        snprintf(path, sizeof path, "%s/%s.ktx2", source_path("tests/data/ktx2"), files[i]);
        unsigned char *ktx = read_bytes(path, &n);
        snprintf(path, sizeof path, "%s/%s.rgba", source_path("tests/data/ktx2"), files[i]);
        unsigned char *ref = read_bytes(path, &m);
        CHECKF(ktx && ref, "%s: missing", files[i]);
        if (!ktx || !ref) {
            free(ktx);
            free(ref);
            continue;
        }
        snprintf(name, sizeof name, "%s.ktx2", files[i]);
        write_file(name, ktx, n);
        snprintf(textures, sizeof textures,
                 "\"textures\":[{\"extensions\":{\"KHR_texture_basisu\":{\"source\":0}}}],"
                 "\"images\":[{\"uri\":\"%s\",\"mimeType\":\"image/ktx2\"}]",
                 name);
        snprintf(name, sizeof name, "%s.gltf", files[i]);
        warning_counter any = {{": ", NULL}, 0};
        pb_scene_desc d = {{count_warnings, &any}, 0, 0, 0};
        pb_scene *s = NULL;
        pb_error err;
        const char *gltf = textured_triangle(
            name, "\"extensionsUsed\":[\"KHR_texture_basisu\"],\"extensionsRequired\":[\"KHR_texture_basisu\"],",
            textures, "");
        CHECKF(pb_scene_load(gltf, &d, &s, &err) == PB_OK, "%s", err.message);
        if (s) {
            const pb_texture *t = s->texture_count ? &s->textures[0] : NULL;
            CHECKF(t && s->materials[0].base_color_texture == 0 && (size_t)t->width * t->height * 4 == m,
                   "%s: %u textures", files[i], s->texture_count);
            size_t differ = 0;
            for (size_t k = 0; t && (size_t)t->width * t->height * 4 == m && k < m; ++k)
                differ += ((const unsigned char *)(s->texels + t->offset))[k] != ref[k];
            CHECKF(differ == 0, "%s: %zu of %zu bytes differ from Basis Universal's transcoder", files[i], differ, m);
            CHECKF(any.count == 0, "%s: %d warnings", files[i], any.count);
            CHECK(strstr(s->stats.extensions_applied, "KHR_texture_basisu") != NULL);
        }
        pb_scene_destroy(s);
        free(ktx);
        free(ref);
    }
}

/* tests/data/ktx2/uastc_random_blocks.ktx2 (128 x 128 texels: 1,024 blocks
 * stored as they are), and where its base level's blocks start; NULL (a
 * failed check) where it cannot be read. */
static unsigned char *random_uastc_file(size_t *size, size_t *blocks_at)
{
    char path[512];
    snprintf(path, sizeof path, "%s/uastc_random_blocks.ktx2", source_path("tests/data/ktx2"));
    unsigned char *ktx = read_bytes(path, size);
    uint64_t at = 0;
    for (int i = 7; ktx && *size >= PB_KTX2_LEVELS_AT + 8 && i >= 0; --i)
        at = at << 8 | ktx[PB_KTX2_LEVELS_AT + i];
    CHECKF(ktx && at <= *size && *size - at >= 16 * 1024, "%s: missing or cut short", path);
    if (ktx && !(at <= *size && *size - at >= 16 * 1024)) {
        free(ktx);
        ktx = NULL;
    }
    *blocks_at = (size_t)at;
    return ktx;
}

/* The specification's own 64 example blocks (tests/data/uastc_spec_examples.txt)
 * decode to the texels it prints, and the three it marks invalid are refused.
 * An oracle beside the transcoder's, from the format's author: 16 of the 19
 * modes (all but 7, 16 and 17), and invalid blocks of modes 2 and 9 (a
 * pattern index past its table). */
static void uastc_specification_examples_decode_as_printed(void)
{
    char path[512];
    snprintf(path, sizeof path, "%s/uastc_spec_examples.txt", source_path("tests/data"));
    char *text = read_text(path);
    CHECKF(text != NULL, "%s missing", path);
    if (!text)
        return;
    int examples = 0, decoded = 0, refused = 0;
    const char *p = text;
    while (*p) {
        if (*p == '#' || *p == '\n') { /* comment or blank line */
            p = strchr(p, '\n');
            p = p ? p + 1 : "";
            continue;
        }
        uint8_t block[16];
        uint32_t want[16];
        int ok = 1;
        for (int i = 0; i < 16 && ok; ++i) {
            char *end;
            unsigned long v = strtoul(p, &end, 16);
            ok = end != p && v <= 0xff;
            block[i] = (uint8_t)v;
            p = end;
        }
        for (int i = 0; i < 16 && ok; ++i) {
            char *end;
            unsigned long v = strtoul(p, &end, 16);
            ok = end != p && v <= 0xffffffffu;
            want[i] = (uint32_t)v;
            p = end;
        }
        CHECKF(ok, "%s: example %d is not 16 bytes and 16 words", path, examples);
        if (!ok)
            break;
        while (*p == ' ' || *p == '\n')
            ++p;
        int invalid = 1;
        for (int i = 0; i < 16; ++i)
            invalid &= want[i] == 0xffff00ffu;
        uint8_t rgba[64];
        int rc = pb_uastc_block_decode(block, rgba);
        if (invalid) {
            CHECKF(rc == -1, "example %d: the specification marks it invalid, decoded", examples);
            refused += rc == -1;
        } else {
            int same = rc == 0;
            for (int i = 0; i < 16 && same; ++i) {
                uint32_t got = (uint32_t)rgba[4 * i] | (uint32_t)rgba[4 * i + 1] << 8 |
                               (uint32_t)rgba[4 * i + 2] << 16 | (uint32_t)rgba[4 * i + 3] << 24;
                same = got == want[i];
            }
            CHECKF(same, "example %d (first byte %02x): %s", examples, block[0],
                   rc ? "refused" : "texels differ from the specification's");
            decoded += same;
        }
        ++examples;
    }
    CHECKF(examples == 64 && decoded == 61 && refused == 3, "%s: %d examples, %d decoded as printed, %d refused", path,
           examples, decoded, refused);
    free(text);
}

/* A UASTC block no mode describes, as Binomial's transcoder refuses it: the
 * reserved mode (prefix code 1000101), or a pattern index past its table
 * (mode 2's, 5 bits at bit 20, of 30 patterns). The image does not decode,
 * with that reason; in a glTF it is a warning naming the image, and the
 * texture falls back to its core image, or without one the material keeps
 * its factor. */
static void invalid_uastc_blocks_are_refused(void)
{
    size_t n = 0, blocks_at = 0;
    unsigned char *ktx = random_uastc_file(&n, &blocks_at);
    if (!ktx)
        return;
    size_t block = blocks_at + 16 * 77; /* the level's 78th block */
    uint8_t *rgba = malloc(128 * 128 * 4);
    const char *why = NULL;
    CHECK(n > block + 16 && pb_ktx2_decode(ktx, n, rgba, &why) == 0);
    uint8_t original[16];
    memcpy(original, ktx + block, 16);

    ktx[block] = (uint8_t)((ktx[block] & 0x80) | 0x45); /* the reserved mode */
    why = NULL;
    CHECKF(pb_ktx2_decode(ktx, n, rgba, &why) == -1 && why && strstr(why, "invalid UASTC block"), "reserved mode: %s",
           why ? why : "decoded");
    memcpy(ktx + block, original, 16);
    ktx[block] = (uint8_t)((ktx[block] & 0xe0) | 0x1d); /* mode 2 ... */
    ktx[block + 2] |= 0xf0;                             /* ... pattern 31 (bits 20-24) */
    ktx[block + 3] |= 0x01;
    why = NULL;
    CHECKF(pb_ktx2_decode(ktx, n, rgba, &why) == -1 && why && strstr(why, "invalid UASTC block"), "pattern 31: %s",
           why ? why : "decoded");
    ktx[block + 2] = (uint8_t)((ktx[block + 2] & 0x0f) | 0xd0); /* pattern 29, the last: valid */
    ktx[block + 3] &= 0xfe;
    why = NULL;
    CHECKF(pb_ktx2_decode(ktx, n, rgba, &why) == 0, "pattern 29: %s", why ? why : "");
    ktx[block + 2] |= 0xf0; /* pattern 31 again, for the loader */
    ktx[block + 3] |= 0x01;
    write_file("uastc-invalid.ktx2", ktx, n);
    free(rgba);
    free(ktx);

    static const char *const png1x1 =
        "{\"uri\":\"data:image/png;base64,"
        "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==\"}";
    for (int fallback = 0; fallback < 2; ++fallback) {
        char textures[512];
        snprintf(textures, sizeof textures,
                 "\"textures\":[{%s\"extensions\":{\"KHR_texture_basisu\":{\"source\":0}}}],"
                 "\"images\":[{\"uri\":\"uastc-invalid.ktx2\",\"mimeType\":\"image/ktx2\"}%s%s]",
                 fallback ? "\"source\":1," : "", fallback ? "," : "", fallback ? png1x1 : "");
        const char *gltf = textured_triangle(
            fallback ? "uastc-invalid-fallback.gltf" : "uastc-invalid.gltf",
            fallback ? "\"extensionsUsed\":[\"KHR_texture_basisu\"],"
                     : "\"extensionsUsed\":[\"KHR_texture_basisu\"],\"extensionsRequired\":[\"KHR_texture_basisu\"],",
            textures, "");
        warning_counter named = {{"image 0 (KTX2) could not be decoded: an invalid UASTC block", NULL}, 0};
        pb_scene_desc d = {{count_warnings, &named}, 0, 0, 0};
        pb_scene *s = NULL;
        pb_error err;
        CHECKF(pb_scene_load(gltf, &d, &s, &err) == PB_OK, "%s", err.message);
        CHECKF(s && s->materials[0].base_color_texture == (fallback ? 0 : -1) &&
                   s->texture_count == (fallback ? 1u : 0u) && (!fallback || s->textures[0].width == 1),
               "invalid UASTC, fallback %d: texture %d", fallback, s ? s->materials[0].base_color_texture : -2);
        CHECKF(named.count == 1, "invalid UASTC, fallback %d: %d warnings naming the block", fallback, named.count);
        pb_scene_destroy(s);
    }
}

/* A UASTC image large enough to be split over the host's threads (1,000 x
 * 520 texels: 32,500 blocks, the fixture's 1,024 random ones repeated, the
 * last column and row of blocks cut) decodes to the bytes each block gives
 * alone; and one invalid block anywhere fails it. */
static void uastc_images_decode_on_all_cores_as_block_by_block(void)
{
    size_t n = 0, blocks_at = 0;
    unsigned char *ktx = random_uastc_file(&n, &blocks_at);
    if (!ktx)
        return;
    const uint8_t *random = ktx + blocks_at;
    enum { W = 1000, H = 520, BW = (W + 3) / 4, BH = (H + 3) / 4 };
    uint8_t *blocks = malloc((size_t)BW * BH * 16), *rgba = malloc((size_t)W * H * 4), *ref = malloc((size_t)W * H * 4);
    for (size_t b = 0; b < (size_t)BW * BH; ++b)
        memcpy(blocks + 16 * b, random + 16 * ((b * 7) % 1024), 16);
    for (size_t by = 0; by < BH; ++by)
        for (size_t bx = 0; bx < BW; ++bx) {
            uint8_t texels[64];
            CHECK(pb_uastc_block_decode(blocks + 16 * (by * BW + bx), texels) == 0);
            for (size_t y = 0; y < 4 && by * 4 + y < H; ++y)
                for (size_t x = 0; x < 4 && bx * 4 + x < W; ++x)
                    memcpy(ref + 4 * ((by * 4 + y) * W + bx * 4 + x), texels + 4 * (4 * y + x), 4);
        }
    const char *why = NULL;
    memset(rgba, 0, (size_t)W * H * 4);
    CHECKF(pb_uastc_image_decode(blocks, (size_t)BW * BH * 16, W, H, rgba, &why) == 0, "%s", why ? why : "");
    CHECK(memcmp(rgba, ref, (size_t)W * H * 4) == 0);
    for (size_t at = 0; at < (size_t)BW * BH; at += 4093) { /* the reserved mode in one block at a time */
        uint8_t keep = blocks[16 * at];
        blocks[16 * at] = (uint8_t)((keep & 0x80) | 0x45);
        why = NULL;
        CHECKF(pb_uastc_image_decode(blocks, (size_t)BW * BH * 16, W, H, rgba, &why) == -1 && why &&
                   strstr(why, "invalid UASTC block"),
               "block %zu: %s", at, why ? why : "decoded");
        blocks[16 * at] = keep;
    }
    why = NULL;
    CHECK(pb_uastc_image_decode(blocks, (size_t)BW * BH * 16 - 1, W, H, rgba, &why) == -1 && why);
    free(blocks);
    free(rgba);
    free(ref);
    free(ktx);
}


/* Images decoded ahead of the material pass on the host's threads
 * (prefetch_images) make the scene and the messages that decoding each in
 * turn makes: the same textures, texels and material indices, the same
 * warnings in the same order. Nine PNG images of noise (4 MB of them: more
 * than the 1 MiB under which nothing is decoded ahead) behind seven materials
 * (base colour, emissive, transmission, metallic and normal textures; one
 * image read by two textures, one unlit material, one whose metallic factor
 * is 0), with a
 * corrupt image, one past the per-image limit, and a file budget that the
 * sixth image to decode exceeds. Loaded with the process on all cores, then
 * on one (where nothing is decoded ahead), then on one with decode_ahead
 * PB_DECODE_AHEAD_ALWAYS (the same cache, no threads). */
static void images_decoded_ahead_load_as_in_turn(void)
{
    static const int sizes[9][2] = {{512, 256}, {256, 256}, {64, 64},   {0, 0},    {1024, 512},
                                    {32, 32},   {512, 512}, {128, 128}, {128, 64}};
    uint32_t noise = 12345;
    for (int i = 0; i < 9; ++i) {
        char path[600];
        snprintf(path, sizeof path, "%s/ahead%d.png", temp_dir(), i);
        if (sizes[i][0] == 0) { /* not a PNG */
            write_file("ahead3.png", "\x89PNG\r\n\x1a\n-not-really", 19);
            continue;
        }
        size_t n = (size_t)sizes[i][0] * sizes[i][1];
        unsigned char *px = malloc(4 * n);
        for (size_t k = 0; k < 4 * n; ++k)
            px[k] = (unsigned char)((noise = noise * 1664525u + 1013904223u) >> 24);
        CHECK(stbi_write_png(path, sizes[i][0], sizes[i][1], 4, px, 4 * sizes[i][0]) != 0);
        free(px);
    }
    const char *path = uv_triangles("ahead.gltf", 7,
        "\"extensionsUsed\":[\"KHR_materials_unlit\",\"KHR_materials_transmission\"],"
        "\"materials\":["
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicRoughnessTexture\":{\"index\":1}},"
        "\"normalTexture\":{\"index\":2}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":3}},\"emissiveTexture\":{\"index\":4},"
        "\"emissiveFactor\":[1,1,1]},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":5},\"metallicRoughnessTexture\":{\"index\":6},"
        "\"metallicFactor\":0}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":7}},\"normalTexture\":{\"index\":2},"
        "\"extensions\":{\"KHR_materials_unlit\":{}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":8}},\"normalTexture\":{\"index\":9}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}},\"emissiveTexture\":{\"index\":10}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.5,"
        "\"transmissionTexture\":{\"index\":11}}}}],"
        "\"textures\":[{\"source\":0},{\"source\":1},{\"source\":2},{\"source\":3},{\"source\":4},{\"source\":5},"
        "{\"source\":6},{\"source\":7},{\"source\":1},{\"source\":6},{\"source\":5},{\"source\":8}],"
        "\"images\":[{\"uri\":\"ahead0.png\"},{\"uri\":\"ahead1.png\"},{\"uri\":\"ahead2.png\"},{\"uri\":\"ahead3.png\"},"
        "{\"uri\":\"ahead4.png\"},{\"uri\":\"ahead5.png\"},{\"uri\":\"ahead6.png\"},{\"uri\":\"ahead7.png\"},"
        "{\"uri\":\"ahead8.png\"}],");
    cpu_set_t all, one;
    CHECK(sched_getaffinity(0, sizeof all, &all) == 0);
    if (CPU_COUNT(&all) < 2) {
        fprintf(stderr, "  skipped: one core, so nothing is decoded ahead\n");
        return;
    }
    CPU_ZERO(&one);
    for (int c = 0; c < CPU_SETSIZE; ++c)
        if (CPU_ISSET(c, &all)) {
            CPU_SET(c, &one);
            break;
        }
    /* 0: all cores, decoded ahead; 1: one core, nothing ahead (the
     * reference); 2: one core, decoded ahead all the same (PB_DECODE_AHEAD_ALWAYS,
     * on the calling thread) */
    pb_scene *s[3] = {NULL, NULL, NULL};
    static pb_fuzz_log logs[3]; /* the fuzz harness's message log (fuzz/scene_exercise.h) */
    for (int run = 0; run < 3; ++run) {
        memset(&logs[run], 0, sizeof logs[run]);
        /* 512 x 512 pixels an image; 400,000 for the file: ahead4 (1024 x 512)
         * is past the first, and ahead6 (512 x 512, after 218,112 pixels) past
         * the second; ahead8, read last (transmission), fits */
        pb_scene_desc d = {{pb_fuzz_keep, &logs[run]}, 0, 512 * 512, 400000, 0, 0};
        d.decode_ahead = run == 2 ? PB_DECODE_AHEAD_ALWAYS : PB_DECODE_AHEAD_AUTO;
        if (run == 1)
            CHECK(sched_setaffinity(0, sizeof one, &one) == 0);
        pb_error err;
        CHECKF(pb_scene_load(path, &d, &s[run], &err) == PB_OK, "%s", err.message);
        if (run == 2)
            CHECK(sched_setaffinity(0, sizeof all, &all) == 0);
    }
    CHECKF(strstr(logs[1].text, "image 3 could not be decoded") &&
               strstr(logs[1].text, "image 4 is 1024 x 512 pixels") && strstr(logs[1].text, "image 6 is 512 x 512 pixels"),
           "%s", logs[1].text);
    for (int run = 0; run < 3; run += 2) {
        const pb_scene *x = s[run], *y = s[1];
        CHECKF(strcmp(logs[run].text, logs[1].text) == 0, "run %d: messages differ:\n%s---\n%s", run, logs[run].text,
               logs[1].text);
        if (!x || !y)
            continue;
        CHECKF(x->texture_count == y->texture_count && x->material_count == y->material_count && x->texture_count >= 4,
               "run %d: %u / %u textures", run, x->texture_count, y->texture_count);
        CHECKF(pb_fuzz_same_textures(x, y), "run %d: textures or texels differ", run);
        for (uint32_t m = 0; m < x->material_count && m < y->material_count; ++m) {
            const pb_material *a = &x->materials[m], *b = &y->materials[m];
            CHECKF(a->base_color_texture == b->base_color_texture && a->emissive_texture == b->emissive_texture &&
                       a->normal_texture == b->normal_texture && a->metallic == b->metallic &&
                       a->transmission == b->transmission && a->transmission_in_alpha == b->transmission_in_alpha &&
                       !memcmp(a->base_color, b->base_color, sizeof a->base_color) &&
                       !memcmp(a->emissive, b->emissive, sizeof a->emissive),
                   "run %d: material %u", run, m);
        }
        CHECKF(x->material_count > 6 && x->materials[6].transmission_in_alpha == 1,
               "run %d: the transmission texture was not read", run);
    }
    for (int run = 0; run < 3; ++run)
        pb_scene_destroy(s[run]);
    /* a value the option does not have is refused, naming it */
    pb_scene_desc bad = {{0}, 0};
    bad.decode_ahead = 3;
    pb_scene *none = NULL;
    pb_error err;
    CHECKF(pb_scene_load(path, &bad, &none, &err) == PB_ERROR_INVALID_ARGUMENT && !none &&
               strstr(err.message, "decode_ahead 3"),
           "%s", err.message);
}

/* Every KTX2 fixture cut short at every length, and with every byte in turn
 * flipped: each decode succeeds or fails with a reason, and never reads or
 * writes outside its buffers (ASan in CI's sanitizer build). A corrupt
 * stream is caught by the container's bounds, the prefix codes' checks or
 * the codebook indices' ranges. */
static void ktx2_corruption_is_an_error(void)
{
    static const char *const files[] = {"etc1s_gradient_alpha", "etc1s_noise_low",    "etc1s_grey",
                                        "etc1s_contrast",       "etc1s_flat",         "etc1s_noise_mips",
                                        "uastc_gradient",       "uastc_gradient_rdo", "uastc_contrast_slow"};
    size_t variants = 0, decodes = 0, refused = 0;
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        char path[512];
        size_t n = 0;
        snprintf(path, sizeof path, "%s/%s.ktx2", source_path("tests/data/ktx2"), files[i]);
        unsigned char *ktx = read_bytes(path, &n);
        CHECK(ktx != NULL);
        if (!ktx)
            continue;
        pb_ktx2_info info;
        const char *why = NULL;
        CHECKF(pb_ktx2_peek(ktx, n, &info, &why) == 0, "%s: %s", files[i], why);
        size_t pixels = (size_t)info.width * info.height * 4;
        size_t step = n > 2000 ? 7 : 1; /* the large file at every 7th byte */
        for (size_t k = 0; k < 2 * n; k += step) {
            unsigned char *copy = malloc(n);
            memcpy(copy, ktx, n);
            size_t size = n;
            if (k < n)
                size = k; /* cut short at k */
            else
                copy[k - n] ^= (unsigned char)(0x5a + k); /* byte k - n changed */
            pb_ktx2_info ci;
            why = NULL;
            variants++;
            if (pb_ktx2_peek(copy, size, &ci, &why) == 0 && (size_t)ci.width * ci.height * 4 <= 4 * pixels) {
                /* an exactly sized buffer of its own, so ASan sees any write past it */
                unsigned char *out = malloc((size_t)ci.width * ci.height * 4);
                why = NULL;
                int r = pb_ktx2_decode(copy, size, out, &why);
                decodes++;
                refused += r != 0;
                CHECKF(r == 0 || (why && *why), "%s: a failure with no reason", files[i]);
                free(out);
            } else
                refused++;
            free(copy);
        }
        free(ktx);
    }
    fprintf(stderr, "  %zu corrupt KTX2 files: %zu refused, %zu decoded to some picture\n", variants, refused,
            variants - refused);
    CHECK(refused > 0);
}

/* An image in a bufferView that reaches past its buffer (4,000 bytes into a
 * 36-byte one). tinygltf hands such bytes to the image decoder unchecked, and
 * the fuzzer's WebP seed led the decoder to read past the buffer
 * (tests/fuzz/corpus/image-view-outside-buffer.glb). The view is now checked
 * first: a warning, and the material keeps its factor. */
static void image_view_outside_its_buffer_is_a_warning(void)
{
    const char *path = textured_triangle(
        "image-view-outside.gltf", "", "\"textures\":[{\"source\":0}],\"images\":[{\"bufferView\":1,\"mimeType\":\"image/png\"}]",
        ",{\"buffer\":0,\"byteOffset\":4000,\"byteLength\":52}");
    warning_counter views = {{"lies outside its buffer", NULL}, 0};
    pb_scene_desc d = {{count_warnings, &views}, 0, 0, 0};
    pb_scene *s = NULL;
    pb_error err;
    CHECKF(pb_scene_load(path, &d, &s, &err) == PB_OK, "%s", err.message);
    CHECK(s && s->triangle_count == 1 && s->materials[0].base_color_texture == -1 && views.count == 1);
    pb_scene_destroy(s);
}

/* A baseline greyscale JPEG of w x h pixels in 144 bytes: one Huffman code
 * (DC difference 0, then end of block) that stb reads from the zero bits it
 * substitutes past the data's end, so it decodes to uniform grey of any size. */
static size_t tiny_jpeg(uint32_t w, uint32_t h, unsigned char out[160])
{
    static const unsigned char head[] = {0xff, 0xd8, 0xff, 0xdb, 0x00, 0x43, 0x00};
    unsigned char *o = out;
    memcpy(o, head, sizeof head), o += sizeof head;
    memset(o, 1, 64), o += 64; /* quantisation table 0 */
    const unsigned char sof[] = {0xff, 0xc0, 0x00, 0x0b, 0x08, (unsigned char)(h >> 8), (unsigned char)h,
                                 (unsigned char)(w >> 8), (unsigned char)w, 0x01, 0x01, 0x11, 0x00};
    memcpy(o, sof, sizeof sof), o += sizeof sof;
    for (int ac = 0; ac < 2; ++ac) { /* one 1-bit code for symbol 0 */
        const unsigned char dht[] = {0xff, 0xc4, 0x00, 0x14, (unsigned char)(ac ? 0x10 : 0x00), 0x01};
        memcpy(o, dht, sizeof dht), o += sizeof dht;
        memset(o, 0, 16), o += 16; /* 15 empty code lengths, then the symbol */
    }
    const unsigned char sos[] = {0xff, 0xda, 0x00, 0x08, 0x01, 0x01, 0x00, 0x00, 0x3f, 0x00,
                                 0x00, 0x00, 0x00, 0x00, 0xff, 0xd9};
    memcpy(o, sos, sizeof sos), o += sizeof sos;
    return (size_t)(o - out);
}

static int warned_pixels;
static void count_pixel_warnings(pb_log_level level, const char *msg, void *user)
{
    (void)user;
    if (level == PB_LOG_WARN && strstr(msg, "pixels") && strstr(msg, "its factor is used"))
        warned_pixels++;
}

/* An image is refused from its header when it claims more pixels than an
 * image (or the file's images together) may decode to: the fuzzer's 144-byte
 * JPEG of 11000 x 11000 took 1.5 GB. The material keeps its factor. */
static void oversized_texture_refused_unread(void)
{
    unsigned char jpg[160];
    write_file("grey-16x8.jpg", jpg, tiny_jpeg(16, 8, jpg));
    write_file("grey-11000.jpg", jpg, tiny_jpeg(11000, 11000, jpg));
    const char *fmt =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
        "{\"attributes\":{\"POSITION\":0},\"material\":1}]}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":1}}}],"
        "\"textures\":[{\"source\":0},{\"source\":1}],\"images\":[{\"uri\":\"grey-16x8.jpg\"},{\"uri\":\"%s\"}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
        "\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}";
    char json[2048];
    struct {
        const char *second;
        uint64_t per_image, total;
        int tex0, tex1, warnings;
    } cases[] = {
        {"grey-16x8.jpg", 0, 0, 0, 1, 0},        /* both load under the defaults */
        {"grey-11000.jpg", 0, 0, 0, -1, 1},      /* 121 M pixels > 8192^2 */
        {"grey-16x8.jpg", 127, 0, -1, -1, 2},    /* 128 pixels each > 127 */
        {"grey-16x8.jpg", 128, 128, 0, -1, 1},   /* the second exceeds what is left */
        {"grey-16x8.jpg", 128, 256, 0, 1, 0},    /* exactly enough */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        snprintf(json, sizeof json, fmt, cases[i].second);
        const char *path = write_gltf("textures-limited.gltf", json, tri_pos, 36);
        warned_pixels = 0;
        pb_scene_desc d = {{count_pixel_warnings, NULL}, 0, cases[i].per_image, cases[i].total};
        pb_scene *s = NULL;
        pb_error err;
        pb_result r = pb_scene_load(path, &d, &s, &err);
        CHECKF(r == PB_OK, "case %zu: %s", i, err.message);
        if (r != PB_OK)
            continue;
        CHECKF(s->materials[0].base_color_texture == cases[i].tex0 &&
                   s->materials[1].base_color_texture == cases[i].tex1 && warned_pixels == cases[i].warnings,
               "case %zu: textures %d %d, %d warnings; want %d %d, %d", i, s->materials[0].base_color_texture,
               s->materials[1].base_color_texture, warned_pixels, cases[i].tex0, cases[i].tex1, cases[i].warnings);
        if (cases[i].tex0 == 0)
            CHECK(s->textures[0].width == 16 && s->textures[0].height == 8);
        pb_scene_destroy(s);
    }
}

/* Only the textures the bake reads are decoded: base colour, emissive,
 * metallic-roughness where a metallic factor > 0 folds it, transmission,
 * normal maps unless --normal-maps off (pb_scene_desc.no_normal_maps).
 * Here the normal and occlusion maps are corrupt and 121 M pixels, past a
 * budget the colour texture fills exactly: the occlusion map is neither
 * warned about nor counted, the normal map only where normal maps are read.
 * With a metallic factor the corrupt metallic texture is read, and warned
 * about, while the occlusion map still is not. */
static void unread_maps_not_decoded(void)
{
    unsigned char jpg[160];
    write_file("grey-16x8.jpg", jpg, tiny_jpeg(16, 8, jpg));
    write_file("grey-11000.jpg", jpg, tiny_jpeg(11000, 11000, jpg));
    write_file("corrupt.png", "\x89PNG\r\n\x1a\n-not-a-png", 19);
    const char *fmt =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":%s,"
        "\"metallicRoughnessTexture\":{\"index\":3}},\"normalTexture\":{\"index\":1},"
        "\"occlusionTexture\":{\"index\":2}}],"
        "\"textures\":[{\"source\":0},{\"source\":1},{\"source\":2},{\"source\":3},{\"source\":2}],"
        "\"images\":[{\"uri\":\"grey-16x8.jpg\"},{\"uri\":\"corrupt.png\"},{\"uri\":\"grey-11000.jpg\"},"
        "{\"uri\":\"corrupt.png\"}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
        "\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}";
    for (int v = 0; v < 4; ++v) {
        int metal = v & 1, normals = v >> 1;
        char json[2048];
        snprintf(json, sizeof json, fmt, metal ? "1.0" : "0.0");
        const char *path = write_gltf("unread-maps.gltf", json, tri_pos, 36);
        warning_counter any = {{": ", NULL}, 0}, corrupt = {{"could not be decoded", NULL}, 0};
        pb_scene_desc d = {{count_warnings, &any}, 0, 0, 16 * 8};
        d.no_normal_maps = !normals;
        pb_scene *s = NULL;
        pb_error err;
        pb_result r = pb_scene_load(path, &d, &s, &err);
        CHECKF(r == PB_OK, "metallic %d, normal maps %d: %s", metal, normals, err.message);
        if (r != PB_OK)
            continue;
        CHECKF(s->texture_count == 1 && s->materials[0].base_color_texture == 0 && s->textures[0].width == 16 &&
                   s->materials[0].normal_texture == -1,
               "metallic %d, normal maps %d: %u textures, colour texture %d", metal, normals, s->texture_count,
               s->materials[0].base_color_texture);
        CHECKF(any.count == metal + normals, "metallic %d, normal maps %d: %d warnings, want %d", metal, normals,
               any.count, metal + normals);
        /* 5 textures: 2 and 4 (occlusion, no material's) never read, 1 (normal) only with normal maps, 3
         * (metallic) only under a factor */
        CHECKF(s->stats.textures_in == 5 && s->stats.textures_unread == 4u - (uint32_t)metal - (uint32_t)normals,
               "metallic %d, normal maps %d: %u textures in the file, %u unread", metal, normals, s->stats.textures_in,
               s->stats.textures_unread);
        pb_scene_destroy(s);
        /* the warnings are the corrupt metallic and normal textures' */
        d.log.user_data = &corrupt;
        CHECK(pb_scene_load(path, &d, &s, &err) == PB_OK && corrupt.count == metal + normals);
        pb_scene_destroy(s);
    }
}

static void shared_scenes_load(void)
{
    struct {
        const char *path;
        uint32_t triangles;
    } cases[] = {
        {"samples/Box/Box.gltf", 12},
        {"samples/Duck/Duck.gltf", 4212},
        {"samples/DamagedHelmet/DamagedHelmet.gltf", 15452},
        {"samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf", 61},
        {"samples/TextureTransformTest/TextureTransformTest.gltf", 24},
        {"samples/atteneder-glTF-test-models-embedded/Empty/Empty.gltf", 0},
        {"samples/atteneder-glTF-test-models-embedded/OnlyAccessors/OnlyAccessors.gltf", 0},
        {"samples/atteneder-glTF-test-models-embedded/FormatVariants/glTF-Embedded/FormatVariants.gltf", 12},
        {"cornell/cornellBox.gltf", 16272},
        {"openarena/oacmpdm1.glb", 59082},
        {"bunny/bunny.gltf", 3674},
    };
    int found = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char path[1024];
        snprintf(path, sizeof path, "%s/../shared/scenes/%s", PB_SOURCE_DIR, cases[i].path);
        if (!file_exists(path))
            continue;
        ++found;
        pb_scene *s = load_ok(path);
        CHECKF(s && s->triangle_count == cases[i].triangles, "%s: %u triangles, want %u", cases[i].path,
               s ? s->triangle_count : 0, cases[i].triangles);
        if (s && !strcmp(cases[i].path, "samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf")) {
            uint32_t masked = 0;
            for (uint32_t m = 0; m < s->material_count; ++m)
                masked += s->materials[m].alpha_mode == PB_ALPHA_MASK;
            CHECK(masked == 3);
        }
        /* of its 5 textures the bake reads 4 (colour, metallic-roughness,
         * emissive, normal; the occlusion map is not decoded), and its
         * metallic texture folded into the colour is a 5th */
        if (s && !strcmp(cases[i].path, "samples/DamagedHelmet/DamagedHelmet.gltf"))
            CHECKF(s->materials[0].emissive_texture >= 0 && s->texture_count == 5 && s->materials[0].metallic == 0.f &&
                       s->materials[0].base_color_texture == 3 && s->materials[0].normal_texture == 4 &&
                       !s->textures[4].srgb,
                   "DamagedHelmet: %u textures, colour %d, emissive %d, normal %d, metallic %g", s->texture_count,
                   s->materials[0].base_color_texture, s->materials[0].emissive_texture,
                   s->materials[0].normal_texture, s->materials[0].metallic);
        if (s && !strcmp(cases[i].path, "samples/DamagedHelmet/DamagedHelmet.gltf"))
            CHECK(s->stats.textures_in == 5 && s->stats.textures_unread == 1);
        pb_scene_destroy(s);
    }
    char bad[1024];
    snprintf(bad, sizeof bad, "%s/../shared/scenes/samples/atteneder-glTF-test-models-embedded/EmbedBufferInvalid/"
                              "EmbedBufferInvalid.gltf", PB_SOURCE_DIR);
    if (file_exists(bad)) {
        ++found;
        load_fails(bad, PB_ERROR_PARSE, NULL);
    }
    if (!found)
        skip("../shared/scenes not present");
}

/* ------------------------------------------------- compressed geometry */

/* One triangle in world space, for matching across two loads of a scene. */
typedef struct tri_rec {
    double v[3][3], n[3][3], uv[3][2];
    double cx; /* centroid x: the sort key */
    uint32_t material;
} tri_rec;

static int by_cx(const void *a, const void *b)
{
    double x = ((const tri_rec *)a)->cx, y = ((const tri_rec *)b)->cx;
    return x < y ? -1 : x > y;
}

static tri_rec *tri_records(const pb_scene *s)
{
    tri_rec *r = calloc(s->triangle_count ? s->triangle_count : 1, sizeof *r);
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        for (int k = 0; k < 3; ++k) {
            world(s, t, k, r[t].v[k]);
            for (int c = 0; c < 3; ++c)
                r[t].n[k][c] = s->normals[9 * (size_t)t + 3 * k + c];
            for (int c = 0; c < 2; ++c)
                r[t].uv[k][c] = s->texcoords[6 * (size_t)t + 2 * k + c];
        }
        r[t].cx = (r[t].v[0][0] + r[t].v[1][0] + r[t].v[2][0]) / 3;
        r[t].material = s->material[t];
    }
    qsort(r, s->triangle_count, sizeof *r, by_cx);
    return r;
}

/* Largest per-axis distance between a's corners and b's, b's corners
 * rotated by `rot` (Draco may start a triangle at another corner). */
static double corner_distance(const tri_rec *a, const tri_rec *b, int rot)
{
    double d = 0;
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c)
            d = fmax(d, fabs(a->v[k][c] - b->v[(k + rot) % 3][c]));
    return d;
}

/* Twice the area over the longest edge: the triangle's height. A triangle
 * lower than twice the position bound may be an encoding's sliver (or lose
 * its area to it), so it need not have a partner. */
static double tri_height(const tri_rec *t)
{
    double e1[3], e2[3], cr[3], longest = 0;
    for (int c = 0; c < 3; ++c)
        e1[c] = t->v[1][c] - t->v[0][c], e2[c] = t->v[2][c] - t->v[0][c];
    cr[0] = e1[1] * e2[2] - e1[2] * e2[1], cr[1] = e1[2] * e2[0] - e1[0] * e2[2], cr[2] = e1[0] * e2[1] - e1[1] * e2[0];
    for (int k = 0; k < 3; ++k) {
        double l = 0;
        for (int c = 0; c < 3; ++c)
            l += pow(t->v[(k + 1) % 3][c] - t->v[k][c], 2);
        longest = fmax(longest, sqrt(l));
    }
    return longest > 0 ? sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) / longest : 0;
}

/* Triangles of `a` (sorted) with no partner in `b` (sorted): same material,
 * corners within `bound` per axis; partners' normals within `nbound` and
 * texcoords within `uvbound`, else counted in *attr_bad. */
static uint32_t unmatched(const tri_rec *a, uint32_t na, const tri_rec *b, uint32_t nb, double bound, double nbound,
                          double uvbound, uint32_t *attr_bad)
{
    uint32_t missing = 0;
    for (uint32_t i = 0; i < na; ++i) {
        uint32_t lo = 0, hi = nb; /* first b with cx >= a.cx - bound */
        while (lo < hi) {
            uint32_t mid = (lo + hi) / 2;
            if (b[mid].cx < a[i].cx - bound)
                lo = mid + 1;
            else
                hi = mid;
        }
        int found = 0;
        for (uint32_t j = lo; j < nb && b[j].cx <= a[i].cx + bound && !found; ++j)
            for (int rot = 0; rot < 3 && !found; ++rot) {
                if (b[j].material != a[i].material || corner_distance(&a[i], &b[j], rot) > bound)
                    continue;
                found = 1;
                double dn = 0, duv = 0;
                for (int k = 0; k < 3; ++k) {
                    for (int c = 0; c < 3; ++c)
                        dn = fmax(dn, fabs(a[i].n[k][c] - b[j].n[(k + rot) % 3][c]));
                    for (int c = 0; c < 2; ++c)
                        duv = fmax(duv, fabs(a[i].uv[k][c] - b[j].uv[(k + rot) % 3][c]));
                }
                *attr_bad += dn > nbound || duv > uvbound;
            }
        missing += !found && tri_height(&a[i]) > 2 * bound;
    }
    return missing;
}

/* Draco, meshopt and quantized variants of the demo scene and the shared
 * Cornell box load to the original's geometry: lossless ones bit for bit,
 * lossy ones within the bound of their quantization (compressed_variants.h),
 * triangle by triangle both ways, normals within 0.01 and texcoords within
 * their own grid's half step. Under ASan in CI, this runs both decoders. */
static void compressed_variants_match_originals(void)
{
    for (int si = 0; si < PB_VARIANT_SOURCES; ++si) {
        const char *src, *tag;
        pb_scene *o = variant_original(si, &src, &tag);
        if (!o)
            continue;
        double diag = 0, rmax = 0, uvmax = 0;
        for (int c = 0; c < 3; ++c)
            diag += pow(o->bounds_max[c] - o->bounds_min[c], 2);
        diag = sqrt(diag);
        for (size_t i = 0; i < 6 * (size_t)o->triangle_count; ++i)
            uvmax = fmax(uvmax, fabs(o->texcoords[i]));
        tri_rec *ra = tri_records(o);
        for (uint32_t t = 0; t < o->triangle_count; ++t)
            for (int k = 0; k < 3; ++k)
                rmax = fmax(rmax, sqrt(pow(ra[t].v[k][0], 2) + pow(ra[t].v[k][1], 2) + pow(ra[t].v[k][2], 2)));
        for (size_t vi = 0; vi < PB_VARIANT_COUNT; ++vi) {
            const pb_variant *v = &pb_variants[vi];
            const char *path;
            pb_scene *c = variant_scene(src, tag, v, &path);
            if (!c)
                continue;
            if (v->lossless) { /* the same triangles in the same order, bit for bit; meshopt's
                                 * index codec may start a triangle at another corner */
                size_t n = o->triangle_count;
                uint32_t differ = c->triangle_count != n || memcmp(c->origin, o->origin, sizeof o->origin);
                for (size_t t = 0; t < n && !differ; ++t) {
                    int same = 0;
                    for (int rot = 0; rot < 3 && !same; ++rot) {
                        same = c->material[t] == o->material[t];
                        for (int k = 0; k < 3; ++k) {
                            size_t a = 3 * t + k, b = 3 * t + (k + rot) % 3;
                            same = same && !memcmp(c->positions + 3 * b, o->positions + 3 * a, 12) &&
                                   !memcmp(c->normals + 3 * b, o->normals + 3 * a, 12) &&
                                   !memcmp(c->texcoords + 2 * b, o->texcoords + 2 * a, 8);
                        }
                    }
                    differ += !same;
                }
                CHECKF(!differ, "%s: not identical to %s", path, src);
                pb_scene_destroy(c);
                continue;
            }
            double bound = variant_position_bound(v, diag, rmax);
            /* texcoords: Draco 12 bits over their range, quantize USHORT in
             * [0,1] (else kept as float), meshopt-exp 16-bit mantissas */
            double uvb = !strcmp(v->mode, "draco") ? 2 * uvmax / 4095.0 / 2 + 1e-6
                         : !strcmp(v->mode, "quantize") ? 1 / 65535.0 / 2 + 1e-6 : uvmax * ldexp(1.0, -15) + 1e-6;
            tri_rec *rb = tri_records(c);
            uint32_t bad_ab = 0, bad_ba = 0;
            uint32_t miss_ab = unmatched(ra, o->triangle_count, rb, c->triangle_count, bound, 0.01, uvb, &bad_ab);
            uint32_t miss_ba = unmatched(rb, c->triangle_count, ra, o->triangle_count, bound, 0.01, uvb, &bad_ba);
            CHECKF(miss_ab == 0 && miss_ba == 0 && bad_ab == 0 && bad_ba == 0,
                   "%s: %u/%u triangles of the original/variant without a partner within %.3g m, %u/%u partners with "
                   "normals or texcoords out of bound", path, miss_ab, miss_ba, bound, bad_ab, bad_ba);
            printf("  %-11s %-4s %s: %u triangles (original %u), position bound %.3g m\n", v->mode, v->ext, tag,
                   c->triangle_count, o->triangle_count, bound);
            free(rb);
            pb_scene_destroy(c);
        }
        free(ra);
        pb_scene_destroy(o);
    }
}

/* Corrupt compressed data is a one-line error naming the file, whichever
 * codec meets it. */
static void corrupt_compressed_data_refused(void)
{
    const char *demo = PB_SOURCE_DIR "/tests/scenes/demo.gltf";
    for (size_t vi = 0; vi < PB_VARIANT_COUNT; ++vi) {
        const pb_variant *v = &pb_variants[vi];
        if (strcmp(v->ext, "gltf") != 0)
            continue;
        const char *path = compressed_variant(demo, "corrupt", v);
        if (!path)
            continue;
        /* scramble the external buffer, where the compressed streams are */
        char bin[600];
        snprintf(bin, sizeof bin, "%s.bin", path);
        FILE *f = fopen(bin, "r+b");
        CHECK(f != NULL);
        if (!f)
            continue;
        fseek(f, 0, SEEK_END);
        long n = ftell(f);
        for (long i = 0; i < n; i += 3) {
            fseek(f, i, SEEK_SET);
            fputc((int)((i * 131) & 0xff), f);
        }
        fclose(f);
        pb_scene *s = (pb_scene *)1;
        pb_error err;
        pb_result r = pb_scene_load(path, NULL, &s, &err);
        /* a scrambled stream may still decode to something; if it does not,
         * the error is the loader's one line */
        if (r != PB_OK) {
            CHECK(s == NULL);
            CHECKF(strstr(err.message, path) && !strchr(err.message, '\n'), "%s", err.message);
            printf("  %s: %s\n", v->mode, err.message + strlen(path));
        } else {
            pb_scene_destroy(s);
        }
    }
    /* truncated: the compressed ranges no longer fit their buffer */
    const char *path = compressed_variant(demo, "short", &pb_variants[0]);
    if (path) {
        char bin[600];
        snprintf(bin, sizeof bin, "%s.bin", path);
        CHECK(truncate(bin, 40) == 0);
        load_fails(path, PB_ERROR_PARSE, "size mismatch");
    }
}

/* ------------------------------------------------------------ instancing */

/* EXT_mesh_gpu_instancing (what glTF-Transform's instance writes, required):
 * a node at x = 10 draws its one-triangle mesh three times, at TRANSLATION x
 * ROTATION x SCALE of each instance, the rotation as normalized SHORTs (a
 * quarter turn about +Z for the second): the three world triangles below.
 * Accessors of different counts, no attribute at all, and 2^24 instances of
 * a 17-triangle mesh (zero-filled translations: past 2^28 triangles, refused
 * before anything is read) are one-line errors naming the file. */
static void gpu_instancing_draws_each_instance(void)
{
    unsigned char bin[36 + 36 + 24 + 36 + 204] = {0}; /* the last: 51 zero indices */
    const float t[9] = {0, 0, 0, 2, 0, 0, 0, 3, 0}, s[9] = {1, 1, 1, 1, 1, 1, 2, 2, 2};
    const int16_t q[12] = {0, 0, 0, 32767, 0, 0, 23170, 23170, 0, 0, 0, 32767};
    memcpy(bin, tri_pos, 36);
    memcpy(bin + 36, t, 36);
    memcpy(bin + 72, q, 24);
    memcpy(bin + 96, s, 36);
    const char *fmt =
        "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"EXT_mesh_gpu_instancing\"],"
        "\"extensionsRequired\":[\"EXT_mesh_gpu_instancing\"],\"scenes\":[{\"nodes\":[0]}],"
        "\"nodes\":[{\"mesh\":0,\"translation\":[10,0,0],\"extensions\":{\"EXT_mesh_gpu_instancing\":"
        "{\"attributes\":{%s}}}}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}%s}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":2,\"componentType\":5122,\"normalized\":true,\"count\":3,\"type\":\"VEC4\"},"
        "{\"bufferView\":3,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"},"
        "{\"componentType\":5126,\"count\":16777216,\"type\":\"VEC3\"},"
        "{\"bufferView\":4,\"componentType\":5125,\"count\":51,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":36},"
        "{\"buffer\":0,\"byteOffset\":72,\"byteLength\":24},{\"buffer\":0,\"byteOffset\":96,\"byteLength\":36},"
        "{\"buffer\":0,\"byteOffset\":132,\"byteLength\":204}],"
        "\"buffers\":[{\"byteLength\":336,\"uri\":\"@BUF@\"}]}";
    char json[4096];
    snprintf(json, sizeof json, fmt, "\"TRANSLATION\":1,\"ROTATION\":2,\"SCALE\":3", "");
    pb_scene *sc = load_ok(write_gltf("instanced.gltf", json, bin, sizeof bin));
    if (sc) {
        const double want[3][9] = {{10, 0, 0, 11, 0, 0, 10, 1, 0},
                                   {12, 0, 0, 12, 1, 0, 11, 0, 0},
                                   {10, 3, 0, 12, 3, 0, 10, 5, 0}};
        int found[3] = {0, 0, 0};
        for (uint32_t tr = 0; tr < sc->triangle_count; ++tr)
            for (int i = 0; i < 3; ++i) {
                double a[3], b[3], c[3];
                world(sc, tr, 0, a), world(sc, tr, 1, b), world(sc, tr, 2, c);
                found[i] += near3(a, want[i][0], want[i][1], want[i][2], 1e-5) &&
                            near3(b, want[i][3], want[i][4], want[i][5], 1e-5) &&
                            near3(c, want[i][6], want[i][7], want[i][8], 1e-5);
            }
        CHECKF(sc->triangle_count == 3 && found[0] == 1 && found[1] == 1 && found[2] == 1,
               "%u triangles; instances found %d %d %d", sc->triangle_count, found[0], found[1], found[2]);
        CHECK(strstr(sc->stats.extensions_applied, "EXT_mesh_gpu_instancing") != NULL);
    }
    pb_scene_destroy(sc);
    snprintf(json, sizeof json, fmt, "\"TRANSLATION\":1,\"SCALE\":4", "");
    load_fails(write_gltf("instanced-counts.gltf", json, bin, sizeof bin), PB_ERROR_PARSE, "accessors differ in count");
    snprintf(json, sizeof json, fmt, "", "");
    load_fails(write_gltf("instanced-none.gltf", json, bin, sizeof bin), PB_ERROR_PARSE,
               "has no TRANSLATION, ROTATION or SCALE");
    snprintf(json, sizeof json, fmt, "\"TRANSLATION\":5", ",\"indices\":6");
    load_fails(write_gltf("instanced-huge.gltf", json, bin, sizeof bin), PB_ERROR_PARSE,
               "16777216 instances of 17 triangles");
}

/* ------------------------------------------------------------ transmission */

/* The head of a glTF file of `count` primitives, each POSITION accessor 0
 * (one triangle) with material i, and those materials (JSON objects), into
 * json: up to and with `"materials":[...],`; extensions_used: its
 * extensionsUsed array's JSON, or NULL. Returns the characters written. */
static int gltf_one_triangle_per_material(char *json, size_t size, const char *extensions_used,
                                          const char *const *mats, int count)
{
    int n = snprintf(json, size, "{\"asset\":{\"version\":\"2.0\"},%s%s%s\"scenes\":[{\"nodes\":[0]}],"
                     "\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[",
                     extensions_used ? "\"extensionsUsed\":" : "", extensions_used ? extensions_used : "",
                     extensions_used ? "," : "");
    for (int i = 0; i < count; ++i)
        n += snprintf(json + n, size - (size_t)n, "%s{\"attributes\":{\"POSITION\":0},\"material\":%d}",
                      i ? "," : "", i);
    n += snprintf(json + n, size - (size_t)n, "]}],\"materials\":[");
    for (int i = 0; i < count; ++i)
        n += snprintf(json + n, size - (size_t)n, "%s%s", i ? "," : "", mats[i]);
    return n + snprintf(json + n, size - (size_t)n, "],");
}

/* glTF normalTexture: the texture is made linear (its bytes as they stand),
 * its scale read (default 1); read with other UVs than the material's
 * colour (TEXCOORD_1, another KHR_texture_transform) it is a warning and not
 * applied, on an unlit material silently not; where it is the material's
 * only texture, the material's UVs take its transform (the triangle's
 * coordinates 0 become its offset); pb_scene_desc.no_normal_maps
 * (--normal-maps off) reads none, leaves the texture undecoded and gives
 * the scene the hash it has without normalTexture in the file. */
static void normal_maps_read(void)
{
    unsigned char px[2 * 4] = {128, 200, 255, 255, 10, 128, 250, 255};
    char png[600];
    snprintf(png, sizeof png, "%s/normal-map.png", temp_dir());
    CHECK(stbi_write_png(png, 2, 1, 4, px, 8) != 0);
    const char *mats[6] = {
        "{\"normalTexture\":{\"index\":0}}",
        "{\"normalTexture\":{\"index\":0,\"scale\":0.5}}",
        "{\"normalTexture\":{\"index\":0,\"texCoord\":1}}",
        ("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":1}},"
         "\"normalTexture\":{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0]}}}}"),
        "{\"normalTexture\":{\"index\":0},\"extensions\":{\"KHR_materials_unlit\":{}}}",
        "{\"normalTexture\":{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0.25]}}}}"};
    /* the file without normal maps: the same materials less their normalTexture */
    const char *plain[6] = {"{}", "{}", "{}", "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":1}}}",
                            "{\"extensions\":{\"KHR_materials_unlit\":{}}}", "{}"};
    pb_scene *sc[3] = {NULL, NULL, NULL};
    for (int variant = 0; variant < 3; ++variant) { /* with maps, --normal-maps off, a file without them */
        char json[4096];
        int n = gltf_one_triangle_per_material(json, sizeof json, NULL, variant == 2 ? plain : mats, 6);
        snprintf(json + n, sizeof json - (size_t)n,
                 "\"textures\":[{\"source\":0},{\"source\":0}],\"images\":[{\"uri\":\"normal-map.png\"}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                 "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}");
        warning_counter warned = {{"normalTexture is read with other UVs", NULL}, 0};
        pb_scene_desc d = {{count_warnings, &warned}, 0, 0, 0};
        d.no_normal_maps = variant == 1;
        pb_error err;
        const char *path = write_gltf(variant == 2 ? "normal-map-none.gltf" : "normal-map.gltf", json, tri_pos, 36);
        CHECKF(pb_scene_load(path, &d, &sc[variant], &err) == PB_OK, "%s", err.message);
        if (!sc[variant] || sc[variant]->material_count < 6 || sc[variant]->triangle_count != 6)
            break;
        const pb_scene *s = sc[variant];
        const pb_material *m = s->materials;
        if (variant == 0) {
            CHECKF(warned.count == 2, "%d warnings", warned.count);
            CHECK(pb_scene_normal_mapped(s) == 3 && s->texture_count == 2 && s->stats.textures_in == 2 &&
                  s->stats.textures_unread == 0);
            CHECK(m[0].normal_texture == 0 && m[0].normal_scale == 1.f);
            CHECK(m[1].normal_texture == 0 && m[1].normal_scale == 0.5f);
            CHECK(m[2].normal_texture == -1 && m[3].normal_texture == -1 && m[4].normal_texture == -1);
            CHECK(m[3].base_color_texture == 1 && m[5].normal_texture == 0);
            CHECKF(s->texcoords[30] == 0.5f && s->texcoords[31] == 0.25f && s->texcoords[0] == 0.f,
                   "uv %g %g", s->texcoords[30], s->texcoords[31]);
            if (s->texture_count == 2) { /* linear: the bytes as the file has them */
                const pb_texture *tx = &s->textures[0];
                CHECK(tx->srgb == 0 && tx->width == 2 && tx->height == 1);
                CHECKF(s->texels[tx->offset] == 0xffffc880u && s->texels[tx->offset + 1] == 0xfffa800au,
                       "texels %08x %08x", s->texels[tx->offset], s->texels[tx->offset + 1]);
            }
        } else {
            CHECKF(warned.count == 0, "%d warnings", warned.count);
            CHECK(pb_scene_normal_mapped(s) == 0 && s->texture_count == 1 && s->textures[0].srgb == 1);
            CHECK(s->texcoords[30] == 0.f && s->texcoords[31] == 0.f); /* no normal map: no transform */
            CHECK(s->stats.textures_in == 2 && s->stats.textures_unread == 1);
        }
    }
    if (sc[0] && sc[1] && sc[2]) {
        CHECK(pb_scene_hash(sc[0]) != pb_scene_hash(sc[1]));
        CHECK(pb_scene_hash(sc[1]) == pb_scene_hash(sc[2]));
    }
    for (int i = 0; i < 3; ++i)
        pb_scene_destroy(sc[i]);
}

/* glTF TANGENT of a normal-mapped primitive: read into pb_scene.tangents in
 * world space through its node (a turn of 90 degrees about +Y takes +X to
 * -Z), the handedness turned by a mirrored node (scale -1 in x: +X to -X,
 * w -1); a primitive whose material has no normal map keeps none (zeros),
 * and without normal maps (--normal-maps off) the scene has none. A TANGENT
 * accessor of another count than POSITION is a one-line error. */
static void tangents_read(void)
{
    float bin[27] = {0, 0, 0, 1, 0, 0, 0, 1, 0,           /* positions */
                     0, 0, 1, 0, 0, 1,                    /* texture coordinates */
                     1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}; /* tangents */
    const char *fmt =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1,2,3]}],"
        "\"nodes\":[{\"mesh\":0},{\"mesh\":0,\"rotation\":[0,0.70710678,0,0.70710678]},{\"mesh\":0,\"scale\":[-1,1,1]},"
        "{\"mesh\":1,\"translation\":[0,0,2]}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1,\"TANGENT\":%d},\"material\":0}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1,\"TANGENT\":2},\"material\":1}]}],"
        "\"materials\":[{\"normalTexture\":{\"index\":0}},{}],"
        "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"normal-map.png\"}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"},"
        "{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC4\"},"
        "{\"bufferView\":2,\"componentType\":5126,\"count\":2,\"type\":\"VEC4\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":24},"
        "{\"buffer\":0,\"byteOffset\":60,\"byteLength\":48}],\"buffers\":[{\"byteLength\":108,\"uri\":\"@BUF@\"}]}";
    unsigned char px[4] = {128, 128, 255, 255};
    char png[600], json[4096];
    snprintf(png, sizeof png, "%s/normal-map.png", temp_dir());
    CHECK(stbi_write_png(png, 1, 1, 4, px, 4) != 0);
    snprintf(json, sizeof json, fmt, 2);
    const char *path = write_gltf("tangents.gltf", json, bin, sizeof bin);
    for (int off = 0; off < 2; ++off) {
        pb_scene_desc d = {0};
        d.no_normal_maps = (uint32_t)off;
        pb_scene *s = NULL;
        pb_error err;
        CHECKF(pb_scene_load(path, &d, &s, &err) == PB_OK, "%s", err.message);
        if (!s || s->triangle_count != 4) {
            pb_scene_destroy(s);
            return;
        }
        if (off) {
            CHECK(s->tangents == NULL && pb_scene_tangent_triangles(s) == 0);
        } else if (s->tangents) {
            const float want[4][4] = {{1, 0, 0, 1}, {0, 0, -1, 1}, {-1, 0, 0, -1}, {0, 0, 0, 0}};
            float worst = 0;
            for (int t = 0; t < 4; ++t)
                for (int v = 0; v < 3; ++v)
                    for (int k = 0; k < 4; ++k)
                        worst = fmaxf(worst, fabsf(s->tangents[12 * t + 4 * v + k] - want[t][k]));
            CHECKF(worst < 1e-6f, "tangents %g from the expected", worst);
            CHECK(pb_scene_tangent_triangles(s) == 3);
        } else {
            CHECK(s->tangents != NULL);
        }
        pb_scene_destroy(s);
    }
    snprintf(json, sizeof json, fmt, 3); /* 2 tangents for 3 positions */
    path = write_gltf("tangents-count.gltf", json, bin, sizeof bin);
    pb_scene *s = NULL;
    pb_error err;
    CHECK(pb_scene_load(path, NULL, &s, &err) == PB_ERROR_PARSE && strstr(err.message, "TANGENT and POSITION") &&
          !strchr(err.message, '\n') && s == NULL);
}

/* KHR_materials_transmission (thin): the material becomes alpha-blended
 * glass, its alpha the coverage (1 for an opaque material), its
 * transmission t (1 - metallic) (test_bake's thin_glass_tints_light bakes
 * what passes): factor 0.75 on an opaque material gives coverage 1 and
 * transmission 0.75, and the traversal meets it as opaque (the ray's owner
 * decides); 0.5 on a blended alpha of 0.5 keeps alpha 0.5; an all-metal
 * material lets nothing through and stays opaque; an alpha mask is left as
 * it is (a warning); an opaque material's texture alpha stops counting (its
 * copy is opaque). A transmissionTexture (red 200 and 100) under factor 0.5
 * on an opaque material goes into the colour texture's alpha as it stands
 * (200, 100), the scale of transmission 0.5 (transmission_in_alpha, tinted
 * as without a texture); on a blended one, whose alpha is coverage, it is
 * read beside the colour texture as it stands (transmission_texture, its
 * texels the file's), transmission 0.5; read through another transform it is
 * a warning and the factor stands. */
static void transmission_is_coverage(void)
{
    unsigned char px[2 * 4] = {200, 200, 200, 0, 100, 100, 100, 0}; /* alpha 0: ignored while opaque */
    char png[600];
    snprintf(png, sizeof png, "%s/transmission-base.png", temp_dir());
    CHECK(stbi_write_png(png, 2, 1, 4, px, 8) != 0);
    const char *mats[8] = {
        "{\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.75}}}",
        "{\"alphaMode\":\"BLEND\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,0.5],\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.5}}}",
        "{\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":1}}}",
        "{\"alphaMode\":\"MASK\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":1}}}",
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0},"
        "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.5}}}",
        "{\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"extensions\":{\"KHR_materials_transmission\":"
        "{\"transmissionFactor\":0.5,\"transmissionTexture\":{\"index\":0}}}}",
        "{\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"extensions\":{\"KHR_materials_transmission\":"
        "{\"transmissionFactor\":0.5,\"transmissionTexture\":{\"index\":0,\"extensions\":{"
        "\"KHR_texture_transform\":{\"offset\":[0.5,0]}}}}}}",
        "{\"alphaMode\":\"BLEND\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"extensions\":{"
        "\"KHR_materials_transmission\":{\"transmissionFactor\":0.5,\"transmissionTexture\":{\"index\":0}}}}"};
    char json[4096];
    int n = gltf_one_triangle_per_material(json, sizeof json, "[\"KHR_materials_transmission\"]", mats, 8);
    snprintf(json + n, sizeof json - (size_t)n,
             "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"transmission-base.png\"}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"buffers\":[{\"byteLength\":36,\"uri\":\"@BUF@\"}]}");
    warning_counter warned = {{"transmissionTexture is read with other UVs", "transmission on an alpha-masked material",
                               NULL},
                              0};
    pb_scene_desc d = {{count_warnings, &warned}, 0, 0, 0};
    pb_scene *s = NULL;
    pb_error err;
    const char *path = write_gltf("transmission.gltf", json, tri_pos, 36);
    CHECKF(pb_scene_load(path, &d, &s, &err) == PB_OK, "%s", err.message);
    if (!s || s->material_count < 8)
        return;
    const pb_material *m = s->materials;
    CHECK(m[0].alpha_mode == PB_ALPHA_BLEND && m[0].base_color[3] == 1.f && m[0].transmission == 0.75f);
    CHECK(m[1].alpha_mode == PB_ALPHA_BLEND && m[1].base_color[3] == 0.5f && m[1].transmission == 0.5f);
    CHECK(m[2].alpha_mode == PB_ALPHA_OPAQUE && m[2].base_color[3] == 1.f && m[2].transmission == 0.f); /* metal */
    CHECK(m[3].alpha_mode == PB_ALPHA_MASK && m[3].base_color[3] == 1.f && m[3].transmission == 0.f);
    CHECK(m[4].alpha_mode == PB_ALPHA_BLEND && m[4].base_color[3] == 1.f && m[4].transmission == 0.5f &&
          m[4].base_color_texture >= 1);
    if (m[4].base_color_texture >= 1) {
        const pb_texture *tx = &s->textures[m[4].base_color_texture];
        CHECK(tx->width == 2 && (s->texels[tx->offset] >> 24) == 255 && (s->texels[tx->offset + 1] >> 24) == 255 &&
              (s->texels[tx->offset] & 0xffffffu) == 0xc8c8c8u);
    }
    CHECK(m[5].alpha_mode == PB_ALPHA_BLEND && m[5].base_color[3] == 1.f && m[5].base_color_texture >= 1 &&
          m[5].transmission == 0.5f && m[5].transmission_in_alpha == 1);
    if (m[5].base_color_texture >= 1) {
        const pb_texture *tx = &s->textures[m[5].base_color_texture];
        CHECKF(tx->width == 2 && (s->texels[tx->offset] >> 24) == 200 && (s->texels[tx->offset + 1] >> 24) == 100 &&
                   (s->texels[tx->offset] & 0xffffffu) == 0xffffffu,
               "transmission texture as alpha %u %u", s->texels[tx->offset] >> 24, s->texels[tx->offset + 1] >> 24);
    }
    CHECK(m[7].alpha_mode == PB_ALPHA_BLEND && m[7].base_color[3] == 1.f && m[7].base_color_texture == -1 &&
          m[7].transmission == 0.5f && m[7].transmission_in_alpha == 0 && m[7].transmission_texture >= 0);
    if (m[7].transmission_texture >= 0) {
        const pb_texture *tx = &s->textures[m[7].transmission_texture];
        CHECKF(tx->width == 2 && (s->texels[tx->offset] & 0xffu) == 200 && (s->texels[tx->offset + 1] & 0xffu) == 100,
               "transmission texture %u %u", s->texels[tx->offset] & 0xffu, s->texels[tx->offset + 1] & 0xffu);
    }
    for (int i = 0; i < 7; ++i)
        CHECK(m[i].transmission_texture == -1);
    CHECK(m[6].alpha_mode == PB_ALPHA_BLEND && m[6].base_color[3] == 1.f && m[6].transmission == 0.5f);
    CHECKF(warned.count == 2, "%d warnings", warned.count);
    /* material 0's triangle (the first) is glass: opaque to the traversal everywhere */
    uint32_t kept = 0, N = 1000;
    test_rng r = {21};
    for (uint32_t i = 0; i < N; ++i) {
        float u = (float)rng_uniform(&r), v = (float)rng_uniform(&r);
        if (u + v > 1.f)
            u = 1.f - u, v = 1.f - v;
        kept += (uint32_t)pb_alpha_opaque(s, 0, u, v);
    }
    CHECK(s->material[0] == 0 && kept == N);
    pb_scene_destroy(s);
}

/* ------------------------------------------------------------ metallic textures */

static double srgb_dec(double c)
{
    return c > 0.04045 ? pow((c + 0.055) / 1.055, 2.4) : c / 12.92;
}

static double srgb_enc(double l)
{
    return l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1.0 / 2.4) - 0.055;
}

/* glTF's metallic is metallicFactor x the metallicRoughness texture's blue
 * channel; the bake reflects base colour x (1 - metallic), and a metallic
 * texture is folded into the colour texture (texture_fold.h). Known texels:
 * a 2 x 1 base colour texture and a 4 x 2 metallic one (blue 0, 255, 128, 0 /
 * 255, 0, 64, 255; red and green set, and ignored). Each folded texel is the
 * nearest base texel's linear colour x (1 - factor x blue / 255), within one
 * sRGB step of the double-precision value (exact where blue is 0 or 255),
 * with the base's alpha. A material without a colour texture gets a grey one;
 * a metallic texture read through another transform is a warning and the
 * factor alone; two materials with the same pair share one folded texture;
 * factor 0 folds nothing. */
static void metallic_texture_folded_into_the_colour(void)
{
    const unsigned char base[2][4] = {{200, 100, 50, 255}, {10, 20, 30, 128}};
    const unsigned char blue[8] = {0, 255, 128, 0, 255, 0, 64, 255};
    unsigned char mr[8][4];
    for (int i = 0; i < 8; ++i)
        mr[i][0] = 77, mr[i][1] = 200, mr[i][2] = blue[i], mr[i][3] = 255;
    char path[600];
    snprintf(path, sizeof path, "%s/fold-base.png", temp_dir());
    CHECK(stbi_write_png(path, 2, 1, 4, base, 8) != 0);
    snprintf(path, sizeof path, "%s/fold-mr.png", temp_dir());
    CHECK(stbi_write_png(path, 4, 2, 4, mr, 16) != 0);
    pb_scene *s = load_ok(uv_triangles("metallic-fold.gltf", 6,
        "\"extensionsUsed\":[\"KHR_texture_transform\"],"
        "\"materials\":["
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicRoughnessTexture\":{\"index\":1}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicRoughnessTexture\":{\"index\":1},"
        "\"metallicFactor\":0.5}},"
        "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1],\"metallicRoughnessTexture\":{\"index\":1}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicRoughnessTexture\":{\"index\":1,"
        "\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0]}}}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicRoughnessTexture\":{\"index\":1}}},"
        "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicRoughnessTexture\":{\"index\":1},"
        "\"metallicFactor\":0}}],"
        "\"textures\":[{\"source\":0},{\"source\":1}],"
        "\"images\":[{\"uri\":\"fold-base.png\"},{\"uri\":\"fold-mr.png\"}],"));
    if (!s)
        return;
    const pb_material *m = s->materials;
    CHECKF(s->material_count == 7 && s->texture_count == 5, "%u materials, %u textures", s->material_count,
           s->texture_count);
    if (s->material_count != 7 || s->texture_count != 5) {
        pb_scene_destroy(s);
        return;
    }
    /* folded: 0 (factor 1), 1 (0.5), 2 (no colour texture, grey); 3 and 5 as loaded; 4 shares 0's */
    CHECK(m[0].metallic == 0.f && m[1].metallic == 0.f && m[2].metallic == 0.f && m[4].metallic == 0.f);
    CHECK(m[3].metallic == 1.f && m[3].base_color_texture == 0 && m[5].metallic == 0.f && m[5].base_color_texture == 0);
    CHECK(m[4].base_color_texture == m[0].base_color_texture && m[2].base_color[0] == 0.5f);
    const int mats[3] = {0, 1, 2};
    const double factor[3] = {1.0, 0.5, 1.0};
    int worst = 0, exact = 1, alpha = 1;
    for (int i = 0; i < 3; ++i) {
        int32_t id = m[mats[i]].base_color_texture;
        CHECKF(id >= 2 && s->textures[id].width == 4 && s->textures[id].height == 2 && s->textures[id].srgb == 1,
               "material %d: texture %d", mats[i], id);
        if (id < 2 || s->textures[id].width != 4 || s->textures[id].height != 2)
            continue;
        for (int t = 0; t < 8; ++t) {
            uint32_t texel = s->texels[s->textures[id].offset + (uint32_t)t];
            const unsigned char *c = i == 2 ? (const unsigned char[4]){255, 255, 255, 255} : base[(t % 4) / 2];
            double keep = 1.0 - factor[i] * blue[t] / 255.0;
            for (int k = 0; k < 3; ++k) {
                int want = (int)lround(srgb_enc(srgb_dec(c[k] / 255.0) * keep) * 255.0);
                int got = (int)((texel >> (8 * k)) & 0xffu);
                worst = abs(got - want) > worst ? abs(got - want) : worst;
                if (blue[t] == 0 || (blue[t] == 255 && factor[i] == 1.0))
                    exact &= got == want;
            }
            alpha &= (texel >> 24) == c[3];
        }
    }
    fprintf(stderr, "  folded texels within %d sRGB step of the double-precision product\n", worst);
    CHECK(worst <= 1 && exact && alpha);
    pb_scene_destroy(s);
}

/* ------------------------------------------------------------ WebP textures */

/* Every material's texture indices, and every texture's size, wrap modes,
 * colour space and texels, equal in a and b. */
static void same_textures(const pb_scene *a, const pb_scene *b, const char *what)
{
    CHECKF(a->texture_count == b->texture_count && a->material_count == b->material_count,
           "%s: %u textures, %u materials against %u, %u", what, b->texture_count, b->material_count,
           a->texture_count, a->material_count);
    if (a->texture_count != b->texture_count || a->material_count != b->material_count)
        return;
    uint32_t differ = 0;
    for (uint32_t m = 0; m < a->material_count; ++m)
        differ += a->materials[m].base_color_texture != b->materials[m].base_color_texture ||
                  a->materials[m].emissive_texture != b->materials[m].emissive_texture;
    for (uint32_t t = 0; t < a->texture_count; ++t) {
        const pb_texture *x = &a->textures[t], *y = &b->textures[t];
        differ += x->width != y->width || x->height != y->height || x->wrap_s != y->wrap_s ||
                  x->wrap_t != y->wrap_t || x->srgb != y->srgb ||
                  (x->width == y->width && x->height == y->height &&
                   memcmp(a->texels + x->offset, b->texels + y->offset, (size_t)x->width * x->height * 4) != 0);
    }
    CHECKF(differ == 0, "%s: %u materials or textures differ from the original's", what, differ);
}

/* EXT_texture_webp and EXT_texture_avif: each sample's images as lossless
 * WebP (libwebp) or AVIF (libavif with libaom, 4:4:4, identity matrix), written
 * by tests/gltf_compress and reachable only through the extension, load to
 * the original's texels bit for bit (alpha and the colour under alpha 0
 * included: AlphaBlendModeTest). With every such image cut in half and the
 * core images kept as fallbacks (the -broken variants), each is a warning
 * and the textures read their fallbacks, again bit for bit. */
static void webp_and_avif_textures_read_as_their_originals(void)
{
    static const char *const sources[] = {
        "tests/scenes/demo.gltf", "../shared/scenes/samples/Duck/Duck.gltf",
        "../shared/scenes/samples/TextureTransformTest/TextureTransformTest.gltf",
        "../shared/scenes/samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf"};
    static const char *const codecs[2] = {"webp", "avif"};
    static const char *const names[2] = {"WebP", "AVIF"}, *const ext[2] = {"EXT_texture_webp", "EXT_texture_avif"};
    for (size_t ci = 0; ci < 2; ++ci)
    for (size_t i = 0; i < sizeof sources / sizeof sources[0]; ++i) {
        const char *path = source_path(sources[i]);
        if (!file_exists(path)) {
            skip("%s absent", path);
            continue;
        }
        char tag[32], needle[32];
        snprintf(tag, sizeof tag, "coded%zu", i);
        snprintf(needle, sizeof needle, "corrupt %s", names[ci]);
        pb_scene *orig = load_ok(path);
        const char *wb = NULL, *w = compressed_image_variants(path, tag, codecs[ci], &wb);
        if (!orig || !w) {
            pb_scene_destroy(orig);
            continue;
        }
        CHECKF(orig->texture_count > 0, "%s has no texture to test", path);
        pb_scene *s = load_ok(w);
        if (s) {
            same_textures(orig, s, w);
            CHECK(strstr(s->stats.extensions_applied, ext[ci]) != NULL);
        }
        pb_scene_destroy(s);
        warning_counter cut = {{needle, NULL}, 0};
        pb_scene_desc d = {{count_warnings, &cut}, 0, 0, 0};
        s = NULL;
        pb_error err;
        CHECKF(pb_scene_load(wb, &d, &s, &err) == PB_OK, "%s: %s", wb, err.message);
        if (s)
            same_textures(orig, s, wb);
        CHECKF(cut.count > 0, "%s: %d warnings about corrupt %s images", wb, cut.count, names[ci]);
        fprintf(stderr, "  %s: %u textures read from %s as from the original; %d cut images fell back\n",
                sources[i], orig->texture_count, names[ci], cut.count);
        pb_scene_destroy(s);
        pb_scene_destroy(orig);
    }
}

/* ------------------------------------------------------------ environment maps */

/* An EXR file of `kind` (tests/exr_write.cpp). */
static const char *exr_file(const char *kind)
{
    static char paths[4][512];
    static int slot;
    char *out = paths[slot++ & 3], cmd[1200];
    snprintf(out, 512, "%s/env_%s.exr", temp_dir(), kind);
    snprintf(cmd, sizeof cmd, "'%s' %s '%s'", PB_EXR_WRITE, kind, out);
    int rc = system(cmd);
    CHECKF(rc == 0, "%s failed (%d)", cmd, rc);
    return out;
}

/* Expects failure with `code` and a one-line message naming the file and
 * holding `needle`, with nothing left allocated. */
static void environment_fails(const char *path, pb_result code, const char *needle)
{
    pb_environment env;
    pb_error err;
    pb_result r = pb_environment_load(path, 1.f, 0.f, &env, &err);
    CHECKF(r == code, "%s: got %s (%s), want %s", path, pb_result_name(r), err.message, pb_result_name(code));
    CHECK(env.rgb == NULL);
    CHECKF(strstr(err.message, path) != NULL, "message does not name the file: %s", err.message);
    CHECKF(strstr(err.message, needle) != NULL, "message '%s' lacks '%s'", err.message, needle);
    CHECK(strchr(err.message, '\n') == NULL);
    pb_environment_free(&env);
}

/* OpenEXR maps, written by the OpenEXR library and read back exactly: float
 * and half channels, scanline (ZIP) and tiled (PIZ) files, a grey Y channel,
 * and a data window that is not the display window (the display window is
 * the map; texels only it covers are 0). Intensity 2 scales every texel. A
 * negative value reads as 0 and is counted. NaN, luminance-chroma and
 * colourless files, an oversized window, truncated files and a file of
 * neither format get one-line errors naming the file. */
static void exr_environment_maps_read_exactly(void)
{
    static const struct {
        const char *kind;
        int grey, window, negative;
    } ok[] = {{"float", 0, 0, 0}, {"half-tiled", 0, 0, 0}, {"grey", 1, 0, 0}, {"window", 0, 1, 0}, {"negative", 0, 0, 1}};
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; ++i) {
        const char *path = exr_file(ok[i].kind);
        pb_environment env;
        pb_error err;
        pb_result r = pb_environment_load(path, 2.f, 0.f, &env, &err);
        CHECKF(r == PB_OK, "%s: %s", ok[i].kind, err.message);
        if (r != PB_OK)
            continue;
        CHECKF(env.width == EXR_PATTERN_W && env.height == EXR_PATTERN_H, "%s: %ux%u", ok[i].kind, env.width,
               env.height);
        uint32_t wrong = 0;
        for (int y = 0; y < EXR_PATTERN_H && env.width == EXR_PATTERN_W; ++y)
            for (int x = 0; x < EXR_PATTERN_W; ++x)
                for (int c = 0; c < 3; ++c) {
                    /* the window case's data window covers display texels x 2..7, y 1..2 */
                    int outside = ok[i].window && (x < 2 || y < 1 || y > 2);
                    int clamped = ok[i].negative && x == 3 && y == 1 && c == 1;
                    float want = outside || clamped ? 0.f : 2.f * exr_pattern(x, y, ok[i].grey ? 0 : c);
                    wrong += env.rgb[3 * (y * EXR_PATTERN_W + x) + c] != want;
                }
        CHECKF(wrong == 0, "%s: %u values differ from the pattern", ok[i].kind, wrong);
        CHECKF(env.negative_values == (uint64_t)ok[i].negative, "%s: %llu negative values counted", ok[i].kind,
               (unsigned long long)env.negative_values);
        CHECK(env.most_negative == (ok[i].negative ? -0.5f : 0.f));
        pb_environment_free(&env);
    }
    environment_fails(exr_file("nan"), PB_ERROR_INVALID_ARGUMENT, "texel 21 is NaN");
    environment_fails(exr_file("chroma"), PB_ERROR_UNSUPPORTED, "luminance-chroma");
    environment_fails(exr_file("no-colour"), PB_ERROR_PARSE, "no R, G, B or Y channel");
    environment_fails(exr_file("huge"), PB_ERROR_PARSE, "EXR windows of 1048576x1048576 (display)");
    /* cut inside the header, the offset table and the last chunk */
    char *whole = read_text(exr_file("float"));
    struct stat st;
    stat(exr_file("float"), &st);
    const size_t cuts[3] = {40, (size_t)st.st_size / 2, (size_t)st.st_size - 8};
    for (int k = 0; k < 3; ++k) {
        char name[64];
        snprintf(name, sizeof name, "env_cut%d.exr", k);
        environment_fails(write_file(name, whole, cuts[k]), PB_ERROR_PARSE, "cannot decode the EXR file");
    }
    free(whole);
    environment_fails(source_path("tests/scenes/demo.gltf"), PB_ERROR_PARSE,
                      "neither a Radiance .hdr nor an OpenEXR file");
}

/* The shared folder's courtyard map as DWAB-compressed EXR and as the .hdr
 * oiiotool made of it agree to RGBE's precision: a texel's largest channel
 * in [2^(e-1), 2^e) is stored in steps of 2^(e-8), so every channel is
 * within 2^-7 of the texel's largest. Texels where the EXR holds a negative
 * value (DWA's near-black noise) are left out, since RGBE cannot store one;
 * the loader reads exactly those values as 0, and counts them. */
static void exr_and_hdr_of_one_map_agree(void)
{
    const char *exr = source_path("../shared/scenes/env/courtyard.exr"), *hdr = source_path("../shared/scenes/env/courtyard.hdr");
    if (!file_exists(exr) || !file_exists(hdr)) {
        skip("%s or %s absent", exr, hdr);
        return;
    }
    float *raw = NULL;
    uint32_t w = 0, h = 0;
    pb_environment from_exr, from_hdr;
    pb_error err;
    CHECKF(pb_exr_read_rgb(exr, 1u << 28, &raw, &w, &h, &err) == PB_OK, "%s", err.message);
    CHECKF(pb_environment_load(exr, 1.f, 0.f, &from_exr, &err) == PB_OK, "%s", err.message);
    CHECKF(pb_environment_load(hdr, 1.f, 0.f, &from_hdr, &err) == PB_OK, "%s", err.message);
    if (!raw || !from_exr.rgb || !from_hdr.rgb) {
        free(raw);
        pb_environment_free(&from_exr), pb_environment_free(&from_hdr);
        return;
    }
    CHECK(w == 1024 && h == 512 && from_hdr.width == w && from_hdr.height == h && from_exr.width == w);
    uint64_t negatives = 0, compared = 0, far = 0, exr_differs = 0;
    double worst = 0.0;
    for (size_t t = 0; t < (size_t)w * h && from_hdr.width == w && from_exr.width == w; ++t) {
        const float *e = raw + 3 * t, *d = from_hdr.rgb + 3 * t, *l = from_exr.rgb + 3 * t;
        int neg = 0;
        float top = 0.f;
        for (int c = 0; c < 3; ++c) {
            neg += e[c] < 0.f;
            top = fmaxf(top, e[c]);
            exr_differs += l[c] != (e[c] < 0.f ? 0.f : e[c]);
        }
        negatives += (uint64_t)neg;
        if (neg)
            continue;
        for (int c = 0; c < 3; ++c) {
            double diff = fabs((double)e[c] - d[c]);
            far += diff > top * 0x1p-7;
            worst = fmax(worst, top > 0.f ? diff / top : diff);
        }
        ++compared;
    }
    fprintf(stderr, "  %llu texels compared, %llu negative values: worst difference %.3f x 2^-7 of the largest channel\n",
            (unsigned long long)compared, (unsigned long long)negatives, worst * 128.0);
    CHECKF(far == 0, "%llu values further from the .hdr than RGBE's step", (unsigned long long)far);
    CHECKF(exr_differs == 0, "%llu loaded values differ from the file's (negatives as 0)", (unsigned long long)exr_differs);
    CHECK(from_exr.negative_values == negatives && negatives > 0 && from_hdr.negative_values == 0);
    CHECK(compared > (uint64_t)w * h * 99 / 100);
    free(raw);
    pb_environment_free(&from_exr);
    pb_environment_free(&from_hdr);
}

int main(void)
{
    RUN(demo_scene_loads_everything);
    RUN(bent_triangles_counted_over_blocks);
    RUN(cameras_of_both_kinds);
    RUN(hierarchy_composes_matrix_and_trs);
    RUN(mirrored_transform_keeps_front_faces);
    RUN(strips_fans_and_unindexed);
    RUN(large_primitives_assembled_in_blocks);
    RUN(colours_only_from_kept_triangles);
    RUN(glb_and_external_buffers);
    RUN(normalized_integer_texcoords);
    RUN(vertex_colours_loaded);
    RUN(sparse_accessors);
    RUN(spec_gloss_and_unlit_materials);
    RUN(texture_transform_applied);
    RUN(bad_triangles_dropped_and_counted);
    RUN(kept_triangles_keep_their_attributes);
    RUN(vertex_normals_read_for_shading);
    RUN(far_from_origin_is_rebased);
    RUN(malformed_files_get_clear_errors);
    RUN(hostile_inputs_refused);
    RUN(corrupt_texture_is_a_warning);
    RUN(image_view_outside_its_buffer_is_a_warning);
    RUN(ktx2_textures_decoded_as_basis_transcodes_them);
    RUN(uastc_specification_examples_decode_as_printed);
    RUN(invalid_uastc_blocks_are_refused);
    RUN(uastc_images_decode_on_all_cores_as_block_by_block);
    RUN(images_decoded_ahead_load_as_in_turn);
    RUN(ktx2_corruption_is_an_error);
    RUN(oversized_texture_refused_unread);
    RUN(unread_maps_not_decoded);
    RUN(shared_scenes_load);
    RUN(compressed_variants_match_originals);
    RUN(corrupt_compressed_data_refused);
    RUN(gpu_instancing_draws_each_instance);
    RUN(transmission_is_coverage);
    RUN(normal_maps_read);
    RUN(tangents_read);
    RUN(metallic_texture_folded_into_the_colour);
    RUN(webp_and_avif_textures_read_as_their_originals);
    RUN(exr_environment_maps_read_exactly);
    RUN(exr_and_hdr_of_one_map_agree);
    return test_summary();
}
