/* Radiance .hdr environment maps through stb_image (Debian libstb): RGBE
 * decoding, then validation and a box filter down to at most
 * PB_ENVIRONMENT_MAX_WIDTH texels across. */
#include "common/common.h"
#include "probebake/environment.h"
#include "probebake/files.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>

pb_result pb_environment_load(const char *path, float intensity, float rotation_deg, pb_environment *out,
                              pb_error *err)
{
    memset(out, 0, sizeof *out);
    if (!(intensity >= 0.f) || !isfinite(intensity))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: environment intensity %g must be finite and >= 0", path,
                       intensity);
    if (!isfinite(rotation_deg))
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: environment rotation must be finite", path);
    FILE *f;
    pb_result opened = pb_input_open(path, 1ull << 31, &f, NULL, err); /* regular files only, at most 2 GiB */
    if (opened != PB_OK)
        return opened;
    if (!stbi_is_hdr_from_file(f)) {
        fclose(f);
        return pb_fail(err, PB_ERROR_PARSE, "%s: not a Radiance .hdr file", path);
    }
    int w = 0, h = 0, c = 0;
    float *px = stbi_loadf_from_file(f, &w, &h, &c, 3);
    fclose(f);
    if (!px)
        return pb_fail(err, PB_ERROR_PARSE, "%s: cannot decode the .hdr file (%s)", path,
                       stbi_failure_reason() ? stbi_failure_reason() : "unknown");
    if (w < 1 || h < 1 || (uint64_t)w * h > (1ull << 28)) {
        stbi_image_free(px);
        return pb_fail(err, PB_ERROR_PARSE, "%s: environment map of %dx%d texels", path, w, h);
    }
    for (uint64_t i = 0; i < 3ull * w * h; ++i)
        if (!(px[i] >= 0.f) || !isfinite(px[i])) {
            stbi_image_free(px);
            return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: texel %llu is %s", path,
                           (unsigned long long)(i / 3), isnan(px[i]) ? "NaN" : px[i] < 0 ? "negative" : "infinite");
        }
    uint32_t factor = ((uint32_t)w + PB_ENVIRONMENT_MAX_WIDTH - 1) / PB_ENVIRONMENT_MAX_WIDTH;
    uint32_t W = ((uint32_t)w + factor - 1) / factor, H = ((uint32_t)h + factor - 1) / factor;
    out->rgb = calloc(3ull * W * H, sizeof(float));
    if (!out->rgb) {
        stbi_image_free(px);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for the environment map", path);
    }
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
            double sum[3] = {0, 0, 0};
            uint32_t k = 0;
            for (uint32_t yy = y * factor; yy < (y + 1) * factor && yy < (uint32_t)h; ++yy)
                for (uint32_t xx = x * factor; xx < (x + 1) * factor && xx < (uint32_t)w; ++xx, ++k)
                    for (int ch = 0; ch < 3; ++ch)
                        sum[ch] += px[3 * ((size_t)yy * w + xx) + ch];
            for (int ch = 0; ch < 3; ++ch)
                out->rgb[3 * ((size_t)y * W + x) + ch] = (float)(sum[ch] / k * intensity);
        }
    stbi_image_free(px);
    out->width = W, out->height = H;
    out->rotation_deg = rotation_deg;
    snprintf(out->path, sizeof out->path, "%s", path);
    return PB_OK;
}
