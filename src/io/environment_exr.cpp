// OpenEXR environment maps (environment_exr.h). The library does the
// decoding; this file picks the channels, places the data window inside the
// display window and turns the library's exceptions into one-line errors.
#include "io/environment_exr.h"

extern "C" {
#include "common/common.h"
}

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfPartType.h>
#include <ImathBox.h>

#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace {

// The library's messages can span lines; ours are one line.
std::string one_line(const char *what)
{
    std::string s = what ? what : "unknown error";
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    return s.size() > 400 ? s.substr(0, 400) + "..." : s;
}

// Texels of a window, or 0 when it is empty or larger than `max`.
uint64_t window_texels(const Imath::Box2i &b, uint64_t max)
{
    int64_t w = (int64_t)b.max.x - b.min.x + 1, h = (int64_t)b.max.y - b.min.y + 1;
    if (w < 1 || h < 1 || w > (int64_t)max || h > (int64_t)max || (uint64_t)w * (uint64_t)h > max)
        return 0;
    return (uint64_t)w * (uint64_t)h;
}

} // namespace

extern "C" int pb_exr_magic(const unsigned char b[4])
{
    return b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01;
}

extern "C" pb_result pb_exr_read_rgb(const char *path, uint64_t max_texels, float **rgb, uint32_t *width,
                                     uint32_t *height, pb_error *err)
{
    *rgb = nullptr;
    *width = *height = 0;
    float *out = nullptr;
    try {
        Imf::InputFile file(path);
        const Imf::Header &hd = file.header();
        if (hd.hasType() && Imf::isDeepData(hd.type()))
            return pb_fail(err, PB_ERROR_UNSUPPORTED, "%s: deep EXR data is not an environment map", path);
        const Imf::ChannelList &ch = hd.channels();
        if (ch.findChannel("RY") || ch.findChannel("BY"))
            return pb_fail(err, PB_ERROR_UNSUPPORTED,
                           "%s: luminance-chroma (RY, BY) EXR is not read: save the map as R, G, B", path);
        const char *names[3] = {"R", "G", "B"};
        int has_rgb = ch.findChannel("R") || ch.findChannel("G") || ch.findChannel("B");
        if (!has_rgb && !ch.findChannel("Y"))
            return pb_fail(err, PB_ERROR_PARSE, "%s: no R, G, B or Y channel in the EXR file", path);
        const Imath::Box2i disp = hd.displayWindow(), data = hd.dataWindow();
        uint64_t n = window_texels(disp, max_texels), nd = window_texels(data, max_texels);
        if (!n || !nd)
            return pb_fail(err, PB_ERROR_PARSE, "%s: EXR windows of %lldx%lld (display) and %lldx%lld (data) texels",
                           path, (long long)disp.max.x - disp.min.x + 1, (long long)disp.max.y - disp.min.y + 1,
                           (long long)data.max.x - data.min.x + 1, (long long)data.max.y - data.min.y + 1);
        const int64_t W = (int64_t)disp.max.x - disp.min.x + 1, H = (int64_t)disp.max.y - disp.min.y + 1;
        const int64_t DW = (int64_t)data.max.x - data.min.x + 1, DH = (int64_t)data.max.y - data.min.y + 1;
        // the data window as the file stores it, then its overlap with the display window
        std::vector<float> px(3 * nd, 0.f);
        Imf::FrameBuffer fb;
        for (int c = 0; c < (has_rgb ? 3 : 1); ++c)
            fb.insert(has_rgb ? names[c] : "Y",
                      Imf::Slice::Make(Imf::FLOAT, px.data() + c, data.min, DW, DH, 3 * sizeof(float),
                                       3 * sizeof(float) * (size_t)DW));
        file.setFrameBuffer(fb);
        file.readPixels(data.min.y, data.max.y);
        if (!has_rgb) // grey: Y in every channel
            for (uint64_t i = 0; i < nd; ++i)
                px[3 * i + 1] = px[3 * i + 2] = px[3 * i];
        out = (float *)calloc(3 * n, sizeof(float));
        if (!out)
            return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for the environment map", path);
        for (int64_t y = 0; y < H; ++y) {
            int64_t sy = y + disp.min.y - data.min.y;
            if (sy < 0 || sy >= DH)
                continue;
            for (int64_t x = 0; x < W; ++x) {
                int64_t sx = x + disp.min.x - data.min.x;
                if (sx >= 0 && sx < DW)
                    memcpy(out + 3 * (y * W + x), px.data() + 3 * (sy * DW + sx), 3 * sizeof(float));
            }
        }
        *rgb = out;
        *width = (uint32_t)W;
        *height = (uint32_t)H;
        return PB_OK;
    } catch (const std::bad_alloc &) {
        free(out);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory reading the EXR file", path);
    } catch (const std::exception &e) {
        free(out);
        return pb_fail(err, PB_ERROR_PARSE, "%s: cannot decode the EXR file (%s)", path, one_line(e.what()).c_str());
    }
}
