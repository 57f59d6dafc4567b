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

#define MANIFEST_VERSION 1
#define TEXELS_PER_ROW 2048u /* WebGL2 guarantees 2048 per side */

static pb_result write_ktx2(const char *dir, const char *name, uint32_t format, uint32_t w, uint32_t h,
                            const void *texels, pb_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    pb_ktx2_image img = {format, w, h, texels};
    uint64_t size = 0;
    unsigned char *bytes = pb_ktx2_encode(&img, &size);
    if (!bytes)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    pb_result r = pb_output_write(path, bytes, size, NULL, NULL, err);
    free(bytes);
    return r;
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
    if (stat(dir, &st) != 0) {
        if (errno != ENOENT || mkdir(dir, 0755) != 0)
            return pb_fail(err, PB_ERROR_IO, "%s: cannot make the directory: %s", dir, strerror(errno));
    } else if (!S_ISDIR(st.st_mode)) {
        return pb_fail(err, PB_ERROR_IO, "%s: exists and is not a directory", dir);
    }
    uint32_t P = v->probe_count, n = v->octmap_res, tile = n + 2;
    uint32_t *words = NULL, word_count = 0;
    if (sp && pb_sparse_layout_words(sp, &words, &word_count) != PB_OK)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for the sparse layout", dir);
    /* pb_probes, pb_sh (and pb_sparse) share the row width; the depth atlas is square in tiles */
    uint32_t W = 7u * P > word_count ? 7u * P : word_count;
    W = W < TEXELS_PER_ROW ? W : TEXELS_PER_ROW;
    uint32_t probe_rows = (P + W - 1) / W, sh_rows = (7u * P + W - 1) / W, sparse_rows = (word_count + W - 1) / W;
    if ((uint64_t)sparse_rows > TEXELS_PER_ROW * 8u) { /* past any WebGL2 device's largest texture */
        free(words);
        return pb_fail(err, PB_ERROR_TOO_LARGE, "%s: the sparse layout's %u words need %u rows of %u texels", dir,
                       word_count, sparse_rows, W);
    }
    uint32_t *sparse_tex = sp ? calloc((size_t)W * sparse_rows, sizeof(uint32_t)) : NULL;
    uint32_t T = (uint32_t)ceil(sqrt((double)P)), depth_rows = (P + T - 1) / T;
    float *probes = calloc((size_t)W * probe_rows * 4, sizeof(float));
    float *sh = calloc((size_t)W * sh_rows * 4, sizeof(float));
    uint16_t *depth = calloc((size_t)T * tile * depth_rows * tile * 2, sizeof(uint16_t));
    pb_result r = PB_OK;
    if (!probes || !sh || !depth || (sp && !sparse_tex)) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for %u probes' textures", dir, P);
        goto done;
    }
    for (uint32_t p = 0; p < P; ++p) {
        for (int k = 0; k < 3; ++k)
            probes[4 * p + k] = v->base[3 * p + k] + v->offset[3 * p + k];
        probes[4 * p + 3] = (float)v->probe_flags[p];
        memcpy(sh + 28 * (size_t)p, v->sh + 27 * (size_t)p, 27 * sizeof(float));
        const uint16_t *src = v->depth + pb_volume_tile_halves(n) * p;
        uint32_t tx = p % T * tile, ty = p / T * tile;
        for (uint32_t y = 0; y < tile; ++y)
            memcpy(depth + 2 * ((size_t)(ty + y) * T * tile + tx), src + 2 * (size_t)y * tile,
                   2 * tile * sizeof(uint16_t));
    }
    r = write_ktx2(dir, "probes.ktx2", PB_VK_FORMAT_R32G32B32A32_SFLOAT, W, probe_rows, probes, err);
    if (r == PB_OK)
        r = write_ktx2(dir, "sh.ktx2", PB_VK_FORMAT_R32G32B32A32_SFLOAT, W, sh_rows, sh, err);
    if (r == PB_OK)
        r = write_ktx2(dir, "depth.ktx2", PB_VK_FORMAT_R16G16_SFLOAT, T * tile, depth_rows * tile, depth, err);
    if (r == PB_OK && sp) {
        memcpy(sparse_tex, words, (size_t)word_count * sizeof(uint32_t));
        r = write_ktx2(dir, "sparse.ktx2", PB_VK_FORMAT_R32_UINT, W, sparse_rows, sparse_tex, err);
    }
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
    r = pb_output_write(path, text, (uint64_t)len, NULL, NULL, err);
done:
    free(probes), free(sh), free(depth), free(sparse_tex), free(words);
    return r;
}
