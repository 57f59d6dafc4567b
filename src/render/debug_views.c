/* Debug images of a volume: its depth octmap atlas and its per-probe SH
 * irradiance, each probe a square tile (octahedral, +Z in the centre),
 * tiles row by row in probe order, a 1-pixel dark gap between them. In a
 * sparse volume each tile's top and left gap lines carry its finest level's
 * colour (level_colour below), bright or dim by the parity of the first
 * brick that names the probe, so levels and bricks show. */
#include "common/common.h"
#include "probebake/octahedral.h"
#include "probebake/render.h"
#include "probebake/sh.h"
#include "probebake/volume.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void pb_atlas_layout(uint32_t probes, uint32_t tile, uint32_t *columns, uint32_t *width, uint32_t *height)
{
    uint32_t c = (uint32_t)ceil(sqrt((double)probes));
    c = c < 1 ? 1 : c;
    uint32_t r = (probes + c - 1) / c;
    *columns = c;
    *width = c * (tile + 1) + 1;
    *height = r * (tile + 1) + 1;
}

static unsigned char *tile_px(unsigned char *rgb8, uint32_t width, uint32_t columns, uint32_t tile, uint32_t p,
                              uint32_t x, uint32_t y)
{
    uint32_t tx = p % columns, ty = p / columns;
    return rgb8 + 3 * ((size_t)(1 + ty * (tile + 1) + y) * width + 1 + tx * (tile + 1) + x);
}

/* Level colours of a sparse volume's tiles: level 0 (coarsest) blue, 1 green, 2 red. */
static const unsigned char level_colour[3][3] = {{40, 90, 255}, {40, 220, 60}, {255, 50, 40}};

static void mark_sparse(const pb_volume *v, unsigned char *rgb8, uint32_t width, uint32_t columns, uint32_t tile)
{
    const pb_sparse_layout *l = (v->flags & PB_VOLUME_SPARSE) ? v->sparse : NULL;
    if (!l)
        return;
    uint32_t P = v->probe_count;
    uint8_t *level = calloc(P ? P : 1, 1);
    uint32_t *first = malloc((P ? P : 1) * sizeof *first);
    if (!level || !first) {
        free(level), free(first);
        return;
    }
    pb_sparse_probe_levels(l, P, level, first);
    for (uint32_t p = 0; p < P; ++p) {
        const unsigned char *c = level_colour[level[p] < 3 ? level[p] : 2];
        int dim = first[p] % 2; /* neighbouring bricks alternate */
        for (uint32_t k = 0; k <= tile; ++k) {
            /* the gap pixels above and left of the tile: (k - 1, -1) and (-1, k - 1) */
            unsigned char *top = tile_px(rgb8, width, columns, tile, p, 0, 0) - 3 * (size_t)width - 3 + 3 * (size_t)k;
            unsigned char *left = tile_px(rgb8, width, columns, tile, p, 0, 0) - 3 * (size_t)width - 3 +
                                  3 * (size_t)k * width;
            for (int ch = 0; ch < 3; ++ch)
                top[ch] = left[ch] = (unsigned char)(dim ? c[ch] / 2 : c[ch]);
        }
    }
    free(level), free(first);
}

pb_result pb_volume_depth_atlas(const pb_volume *v, unsigned char **rgb8, uint32_t *width, uint32_t *height,
                                pb_error *err)
{
    uint32_t side = v->octmap_res + 2, columns;
    pb_atlas_layout(v->probe_count, side, &columns, width, height);
    *rgb8 = calloc((size_t)*width * *height, 3);
    if (!*rgb8)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the atlas");
    /* the tiles hold depth units: the reach in those units */
    float maxd = (v->settings.max_distance > 0.f ? v->settings.max_distance : 1.f) /
                 (v->depth_unit > 0.f ? v->depth_unit : 1.f);
    for (uint32_t p = 0; p < v->probe_count; ++p)
        for (uint32_t y = 0; y < side; ++y)
            for (uint32_t x = 0; x < side; ++x) {
                const uint16_t *t = v->depth + pb_volume_tile_halves(v->octmap_res) * p + 2 * (y * side + x);
                float mean = pb_half_to_float(t[0]), sd = sqrtf(fabsf(pb_half_to_float(t[1]) - mean * mean));
                /* grey: mean distance (near dark, far bright), red: its spread */
                float g = sqrtf(fminf(1.f, fmaxf(0.f, mean / maxd)));
                float r = fminf(1.f, sd / (0.1f * maxd));
                unsigned char *px = tile_px(*rgb8, *width, columns, side, p, x, y);
                px[0] = (unsigned char)(255.f * fmaxf(g, r) + 0.5f);
                px[1] = px[2] = (unsigned char)(255.f * g + 0.5f);
            }
    mark_sparse(v, *rgb8, *width, columns, side);
    return PB_OK;
}

pb_result pb_volume_sh_atlas(const pb_volume *v, uint32_t tile, unsigned char **rgb8, uint32_t *width,
                             uint32_t *height, pb_error *err)
{
    uint32_t columns;
    pb_atlas_layout(v->probe_count, tile, &columns, width, height);
    *rgb8 = calloc((size_t)*width * *height, 3);
    float *lin = malloc((size_t)v->probe_count * tile * tile * 4 * sizeof(float));
    if (!*rgb8 || !lin) {
        free(lin), free(*rgb8);
        *rgb8 = NULL;
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the SH view");
    }
    for (uint32_t p = 0; p < v->probe_count; ++p)
        for (uint32_t t = 0; t < tile * tile; ++t) {
            float d[3], e[3];
            pb_oct_texel_direction(t % tile, t / tile, tile, d);
            pb_sh_eval(v->sh + 27 * (size_t)p, d, e);
            float *o = lin + 4 * ((size_t)p * tile * tile + t);
            o[0] = e[0] / 3.14159265f, o[1] = e[1] / 3.14159265f, o[2] = e[2] / 3.14159265f, o[3] = 1.f;
        }
    /* one exposure for all tiles, so probes compare */
    float ev = pb_auto_exposure(lin, tile * tile, v->probe_count);
    unsigned char *tmp = malloc((size_t)v->probe_count * tile * tile * 3);
    if (!tmp) {
        free(lin), free(*rgb8);
        *rgb8 = NULL;
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for the SH view");
    }
    pb_tonemap_image(lin, tile * tile, v->probe_count, ev, tmp);
    for (uint32_t p = 0; p < v->probe_count; ++p)
        for (uint32_t t = 0; t < tile * tile; ++t)
            memcpy(tile_px(*rgb8, *width, columns, tile, p, t % tile, t / tile), tmp + 3 * ((size_t)p * tile * tile + t), 3);
    mark_sparse(v, *rgb8, *width, columns, tile);
    free(tmp), free(lin);
    return PB_OK;
}
