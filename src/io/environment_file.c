/* Environment maps from files: Radiance .hdr through stb_image (Debian
 * libstb), OpenEXR through the OpenEXR library (environment_exr.h), told
 * apart by their first bytes. Then validation and a box filter down to at
 * most PB_ENVIRONMENT_MAX_WIDTH texels across. */
#include "common/common.h"
#include "io/environment_exr.h"
#include "probebake/environment.h"
#include "probebake/files.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>

#define MAX_TEXELS (1ull << 28)

/* Reads either kind into *px, 3 floats per texel (free with free_texels). */
static pb_result read_texels(const char *path, float **px, int *is_exr, uint32_t *w, uint32_t *h, pb_error *err)
{
    *px = NULL;
    FILE *f;
    pb_result opened = pb_input_open(path, 1ull << 31, &f, NULL, err); /* regular files only, at most 2 GiB */
    if (opened != PB_OK)
        return opened;
    unsigned char magic[4] = {0, 0, 0, 0};
    *is_exr = fread(magic, 1, 4, f) == 4 && pb_exr_magic(magic);
    rewind(f);
    if (*is_exr) {
        fclose(f);
        return pb_exr_read_rgb(path, MAX_TEXELS, px, w, h, err);
    }
    if (!stbi_is_hdr_from_file(f)) {
        fclose(f);
        return pb_fail(err, PB_ERROR_PARSE, "%s: neither a Radiance .hdr nor an OpenEXR file", path);
    }
    int iw = 0, ih = 0, c = 0;
    *px = stbi_loadf_from_file(f, &iw, &ih, &c, 3);
    fclose(f);
    if (!*px)
        return pb_fail(err, PB_ERROR_PARSE, "%s: cannot decode the .hdr file (%s)", path,
                       stbi_failure_reason() ? stbi_failure_reason() : "unknown");
    if (iw < 1 || ih < 1 || (uint64_t)iw * ih > MAX_TEXELS) {
        stbi_image_free(*px);
        *px = NULL;
        return pb_fail(err, PB_ERROR_PARSE, "%s: environment map of %dx%d texels", path, iw, ih);
    }
    *w = (uint32_t)iw, *h = (uint32_t)ih;
    return PB_OK;
}

static void free_texels(float *px, int is_exr)
{
    if (is_exr)
        free(px);
    else
        stbi_image_free(px);
}

pb_result pb_environment_load(const char *path, float intensity, float rotation_deg, pb_environment *out,
                              pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (!(intensity >= 0.f) || !isfinite(intensity))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: environment intensity %g must be finite and >= 0", path,
                       intensity);
    if (!isfinite(rotation_deg))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: environment rotation must be finite", path);
    float *px;
    int is_exr = 0;
    uint32_t w = 0, h = 0;
    pb_result r = read_texels(path, &px, &is_exr, &w, &h, err);
    if (r != PB_OK)
        return r;
    /* Lossy EXR compression (DWA, B44) leaves small negative values where a
     * map is near black: they read as 0, as a conversion to .hdr would make
     * them, and are counted for a warning. NaN and infinity are refused. */
    for (uint64_t i = 0; i < 3ull * w * h; ++i) {
        if (!isfinite(px[i])) {
            const char *what = isnan(px[i]) ? "NaN" : "infinite";
            free_texels(px, is_exr);
            memset(out, 0, sizeof *out);
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: texel %llu is %s", path, (unsigned long long)(i / 3),
                           what);
        }
        if (px[i] < 0.f) {
            out->negative_values++;
            out->most_negative = fminf(out->most_negative, px[i]);
            px[i] = 0.f;
        }
    }
    uint32_t factor = (w + PB_ENVIRONMENT_MAX_WIDTH - 1) / PB_ENVIRONMENT_MAX_WIDTH;
    uint32_t W = (w + factor - 1) / factor, H = (h + factor - 1) / factor;
    out->rgb = calloc(3ull * W * H, sizeof(float));
    if (!out->rgb) {
        free_texels(px, is_exr);
        memset(out, 0, sizeof *out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for the environment map", path);
    }
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
            double sum[3] = {0, 0, 0};
            uint32_t k = 0;
            for (uint32_t yy = y * factor; yy < (y + 1) * factor && yy < h; ++yy)
                for (uint32_t xx = x * factor; xx < (x + 1) * factor && xx < w; ++xx, ++k)
                    for (int ch = 0; ch < 3; ++ch)
                        sum[ch] += px[3 * ((size_t)yy * w + xx) + ch];
            for (int ch = 0; ch < 3; ++ch)
                out->rgb[3 * ((size_t)y * W + x) + ch] = (float)(sum[ch] / k * intensity);
        }
    free_texels(px, is_exr);
    out->width = W, out->height = H;
    out->rotation_deg = rotation_deg;
    snprintf(out->path, sizeof out->path, "%s", path);
    return PB_OK;
}
