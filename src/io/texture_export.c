/* The sampler's textures as KTX2 files and a JSON manifest
 * (pb_volume_export_textures in volume.h; the contract is docs/format.md,
 * "Texture contract"). */
#define _POSIX_C_SOURCE 200809L
#include "common/common.h"
#include "io/ktx2.h"
#include "probebake/files.h"
#include "probebake/sparse.h"
#include "probebake/volume.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MANIFEST_VERSION 1
#define TEXELS_PER_ROW 2048u /* WebGL2 guarantees 2048 per side */

/* The textures' rows, made from the volume as the KTX2 writer asks for
 * them (no texture is ever whole in memory: a million probes' depth atlas
 * alone is 1.3 GB). Texels past the last probe are zero. */
typedef struct atlas {
    const pb_volume *v;
    uint32_t W;                /* texels per row of pb_probes, pb_sh and pb_sparse */
    uint32_t T, tile;          /* pb_depth: tiles per row, texels per tile side */
    const uint32_t *words;     /* the sparse layout's words */
    uint32_t word_count;
} atlas;

/* pb_probes: texel p = probe p's position (base + offset) and its flags. */
static void fill_probes(void *user, uint32_t y0, uint32_t count, void *out)
{
    const atlas *a = user;
    float *o = out;
    for (uint64_t i = 0; i < (uint64_t)count * a->W; ++i) {
        uint64_t p = (uint64_t)y0 * a->W + i;
        for (int k = 0; k < 3; ++k)
            o[4 * i + k] = p < a->v->probe_count ? a->v->base[3 * p + k] + a->v->offset[3 * p + k] : 0.f;
        o[4 * i + 3] = p < a->v->probe_count ? (float)a->v->probe_flags[p] : 0.f;
    }
}

/* pb_sh: seven texels a probe, its 27 coefficients and a zero. */
static void fill_sh(void *user, uint32_t y0, uint32_t count, void *out)
{
    const atlas *a = user;
    float *o = out;
    for (uint64_t i = 0; i < (uint64_t)count * a->W * 4; ++i) {
        uint64_t c = (uint64_t)y0 * a->W * 4 + i, p = c / 28, k = c % 28;
        o[i] = p < a->v->probe_count && k < 27 ? a->v->sh[27 * p + k] : 0.f;
    }
}

/* pb_depth: probe p's tile at tile column p % T, tile row p / T. */
static void fill_depth(void *user, uint32_t y0, uint32_t count, void *out)
{
    const atlas *a = user;
    uint32_t tile = a->tile, w = a->T * tile;
    uint64_t halves = pb_volume_tile_halves(a->v->octmap_res);
    uint16_t *o = out;
    for (uint32_t r = 0; r < count; ++r) {
        uint32_t y = y0 + r, ty = y / tile, in = y % tile;
        for (uint32_t tx = 0; tx < a->T; ++tx) {
            uint64_t p = (uint64_t)ty * a->T + tx;
            uint16_t *dst = o + 2 * ((size_t)r * w + (size_t)tx * tile);
            if (p < a->v->probe_count)
                memcpy(dst, a->v->depth + halves * p + 2 * (size_t)in * tile, 2 * tile * sizeof *dst);
            else
                memset(dst, 0, 2 * tile * sizeof *dst);
        }
    }
}

/* pb_sparse: the layout's words in order. */
static void fill_sparse(void *user, uint32_t y0, uint32_t count, void *out)
{
    const atlas *a = user;
    uint32_t *o = out;
    for (uint64_t i = 0; i < (uint64_t)count * a->W; ++i) {
        uint64_t k = (uint64_t)y0 * a->W + i;
        o[i] = k < a->word_count ? a->words[k] : 0u;
    }
}

static pb_result stage_ktx2(const char *dir, const char *name, uint32_t format, uint32_t w, uint32_t h,
                            pb_ktx2_rows_fn rows, atlas *a, pb_output **staged, pb_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return pb_ktx2_stage(path, format, w, h, rows, a, staged, err);
}

pb_result pb_volume_export_textures(const pb_volume *v, const char *dir, pb_error *err)
{
    pb_error_clear(err);
    if (v->flags & PB_VOLUME_SHARD)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "%s: the volume is part %u of %u of a sharded bake: probebake merge joins the parts first", dir,
                       v->shard.index, v->shard.count);
    const pb_sparse_layout *sp = (v->flags & PB_VOLUME_SPARSE) ? v->sparse : NULL;
    if (!(v->flags & PB_VOLUME_GRID) && !sp)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT,
                       "%s: the textures are for a grid or sparse volume (the sampler interpolates a grid); this "
                       "one has %u placed points", dir, v->probe_count);
    struct stat st;
    int made_dir = 0; /* removed again if the export fails */
    if (stat(dir, &st) != 0) {
        if (errno != ENOENT || mkdir(dir, 0755) != 0)
            return pb_fail(err, PB_ERROR_IO, "%s: cannot make the directory: %s", dir, strerror(errno));
        made_dir = 1;
    } else if (!S_ISDIR(st.st_mode)) {
        return pb_fail(err, PB_ERROR_IO, "%s: exists and is not a directory", dir);
    }
    uint32_t P = v->probe_count, n = v->octmap_res, tile = n + 2;
    uint32_t *words = NULL, word_count = 0;
    pb_output *staged[5] = {NULL}; /* the KTX2 files and the manifest, committed together at the end */
    pb_result r = PB_OK;
    if (sp && pb_sparse_layout_words(sp, &words, &word_count) != PB_OK) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for the sparse layout", dir);
        goto done;
    }
    /* pb_probes, pb_sh (and pb_sparse) share the row width; the depth atlas is square in tiles */
    uint32_t W = 7u * P > word_count ? 7u * P : word_count;
    W = W < TEXELS_PER_ROW ? W : TEXELS_PER_ROW;
    uint32_t probe_rows = (P + W - 1) / W, sh_rows = (7u * P + W - 1) / W, sparse_rows = (word_count + W - 1) / W;
    if ((uint64_t)sparse_rows > TEXELS_PER_ROW * 8u) { /* past any WebGL2 device's largest texture */
        r = pb_fail(err, PB_ERROR_TOO_LARGE, "%s: the sparse layout's %u words need %u rows of %u texels", dir,
                    word_count, sparse_rows, W);
        goto done;
    }
    uint32_t T = (uint32_t)ceil(sqrt((double)P)), depth_rows = (P + T - 1) / T;
    atlas at = {v, W, T, tile, words, word_count};
    r = stage_ktx2(dir, "probes.ktx2", PB_VK_FORMAT_R32G32B32A32_SFLOAT, W, probe_rows, fill_probes, &at, &staged[0],
                   err);
    if (r == PB_OK)
        r = stage_ktx2(dir, "sh.ktx2", PB_VK_FORMAT_R32G32B32A32_SFLOAT, W, sh_rows, fill_sh, &at, &staged[1], err);
    if (r == PB_OK)
        r = stage_ktx2(dir, "depth.ktx2", PB_VK_FORMAT_R16G16_SFLOAT, T * tile, depth_rows * tile, fill_depth, &at,
                       &staged[2], err);
    if (r == PB_OK && sp)
        r = stage_ktx2(dir, "sparse.ktx2", PB_VK_FORMAT_R32_UINT, W, sparse_rows, fill_sparse, &at, &staged[3], err);
    if (r != PB_OK)
        goto done;
    uint32_t largest = W > T * tile ? W : T * tile;
    largest = largest > depth_rows * tile ? largest : depth_rows * tile;
    largest = largest > sparse_rows ? largest : sparse_rows;
    /* a sparse volume: the sampler compiled with PB_SPARSE, its layout texture,
     * its levels, and the coarsest cells per axis where a grid has its counts */
    char sparse_uniform[64] = "", sparse_texture[160] = "", define[64] = "";
    const uint32_t *counts = v->counts;
    if (sp) {
        snprintf(sparse_uniform, sizeof sparse_uniform, ",\n    \"pb_levels\": %u", sp->levels);
        snprintf(sparse_texture, sizeof sparse_texture,
                 ",\n    \"pb_sparse\": {\"file\": \"sparse.ktx2\", \"format\": \"R32UI\", \"width\": %u, "
                 "\"height\": %u}", W, sparse_rows);
        snprintf(define, sizeof define, "  \"define\": \"PB_SPARSE\",\n");
        counts = sp->cells;
    }
    char text[8192];
    int len = snprintf(
        text, sizeof text,
        "{\n  \"format\": \"probebake-textures\",\n  \"version\": %d,\n  \"volume_version\": %u,\n"
        "  \"sh\": \"%s\",\n  \"direct\": %s,\n"
        "%s  \"frame_origin\": [%.17g, %.17g, %.17g],\n"
        "  \"uniforms\": {\n    \"pb_grid_origin\": [0, 0, 0],\n    \"pb_grid_spacing\": [%.9g, %.9g, %.9g],\n"
        "    \"pb_grid_counts\": [%u, %u, %u],\n    \"pb_octmap_res\": %u,\n    \"pb_depth_unit\": %.9g,\n"
        "    \"pb_tex_width\": %u,\n    \"pb_depth_tiles_per_row\": %u,\n    \"pb_normal_bias\": 0.1,\n"
        "    \"pb_view_bias\": 0.1%s\n  },\n"
        "  \"textures\": {\n"
        "    \"pb_probes\": {\"file\": \"probes.ktx2\", \"format\": \"RGBA32F\", \"width\": %u, \"height\": %u},\n"
        "    \"pb_sh\": {\"file\": \"sh.ktx2\", \"format\": \"RGBA32F\", \"width\": %u, \"height\": %u},\n"
        "    \"pb_depth\": {\"file\": \"depth.ktx2\", \"format\": \"RG16F\", \"width\": %u, \"height\": %u}%s\n  },\n"
        "  \"max_texture_size\": %u,\n  \"probes\": %u\n}\n",
        MANIFEST_VERSION, v->file_version ? v->file_version : 3u,
        v->flags & PB_VOLUME_IRRADIANCE ? "irradiance" : "radiance", v->flags & PB_VOLUME_DIRECT ? "true" : "false",
        define, v->origin[0], v->origin[1], v->origin[2], v->spacing[0], v->spacing[1], v->spacing[2], counts[0],
        counts[1], counts[2], n, v->depth_unit, W, T, sparse_uniform, W, probe_rows, W, sh_rows, T * tile,
        depth_rows * tile, sparse_texture, largest, P);
    char path[4096];
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    r = pb_output_begin(path, NULL, NULL, &staged[4], err);
    if (r == PB_OK)
        r = pb_output_put(staged[4], text, (uint64_t)len, err);
    /* every file written: in place together, the manifest last (a failure
     * before here leaves none of them, and no folder this call made) */
    for (int i = 0; i < 5 && r == PB_OK; ++i)
        if (staged[i]) {
            r = pb_output_commit(staged[i], err);
            staged[i] = NULL;
        }
done:
    for (int i = 0; i < 5; ++i)
        pb_output_abort(staged[i]);
    if (r != PB_OK && made_dir)
        rmdir(dir); /* empty unless a commit failed part way */
    free(words);
    return r;
}
