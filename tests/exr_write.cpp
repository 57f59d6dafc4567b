// OpenEXR files for the environment loader's tests (test_scene.c), written by
// the library that reads them, one per case the loader must tell apart:
//
//   exr_write KIND OUT.exr
//
//   float       R, G, B float, ZIP scanlines: the pattern (exr_pattern.h)
//   half-tiled  R, G, B half, PIZ, 4 x 4 tiles: the pattern
//   grey        Y only, half: the pattern's channel 0, to be read as grey
//   window      display window (10, 20)-(17, 23), data window (12, 21)-(19, 22):
//               the pattern where both windows hold a texel, nothing elsewhere
//   negative    float, channel G of texel (3, 1) is -0.5
//   nan         float, channel B of texel (5, 2) is NaN
//   chroma      Y, RY, BY (luminance-chroma)
//   no-colour   one channel, Z
//   huge        a display window of 2^20 x 2^20 over an 8 x 4 data window
#include "exr_pattern.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>
#include <ImfTileDescriptionAttribute.h>
#include <ImathBox.h>
#include <half.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace {

// Writes channels `names` of the data window from `px` (per texel, one value
// per channel, float or half as `type` says, data window order).
template <typename T>
void write(const std::string &path, Imf::Header hd, const std::vector<std::string> &names, Imf::PixelType type,
           std::vector<T> &px, bool tiled)
{
    const Imath::Box2i dw = hd.dataWindow();
    const int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    const size_t n = names.size();
    for (const std::string &c : names)
        hd.channels().insert(c.c_str(), Imf::Channel(type));
    Imf::FrameBuffer fb;
    for (size_t c = 0; c < n; ++c)
        fb.insert(names[c].c_str(),
                  Imf::Slice::Make(type, px.data() + c, dw.min, w, h, n * sizeof(T), n * sizeof(T) * (size_t)w));
    if (tiled) {
        hd.setTileDescription(Imf::TileDescription(4, 4, Imf::ONE_LEVEL));
        Imf::TiledOutputFile f(path.c_str(), hd);
        f.setFrameBuffer(fb);
        f.writeTiles(0, f.numXTiles() - 1, 0, f.numYTiles() - 1);
    } else {
        Imf::OutputFile f(path.c_str(), hd);
        f.setFrameBuffer(fb);
        f.writePixels((int)h);
    }
}

// The pattern over a data window, at display-relative coordinates.
template <typename T>
std::vector<T> pattern(const Imath::Box2i &disp, const Imath::Box2i &dw, int channels)
{
    std::vector<T> px;
    for (int y = dw.min.y; y <= dw.max.y; ++y)
        for (int x = dw.min.x; x <= dw.max.x; ++x)
            for (int c = 0; c < channels; ++c)
                px.push_back(T(exr_pattern(x - disp.min.x, y - disp.min.y, c)));
    return px;
}

} // namespace

int main(int argc, char **argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: exr_write KIND OUT.exr\n");
        return 2;
    }
    const std::string kind = argv[1], out = argv[2];
    const Imath::Box2i base(Imath::V2i(0, 0), Imath::V2i(EXR_PATTERN_W - 1, EXR_PATTERN_H - 1));
    try {
        Imf::Header hd(base, base, 1.f, Imath::V2f(0, 0), 1.f, Imf::INCREASING_Y, Imf::ZIP_COMPRESSION);
        if (kind == "float" || kind == "negative" || kind == "nan") {
            std::vector<float> px = pattern<float>(base, base, 3);
            if (kind == "negative")
                px[3 * (1 * EXR_PATTERN_W + 3) + 1] = -0.5f;
            if (kind == "nan")
                px[3 * (2 * EXR_PATTERN_W + 5) + 2] = std::nanf("");
            write(out, hd, {"R", "G", "B"}, Imf::FLOAT, px, false);
        } else if (kind == "half-tiled") {
            hd.compression() = Imf::PIZ_COMPRESSION;
            std::vector<half> px = pattern<half>(base, base, 3);
            write(out, hd, {"R", "G", "B"}, Imf::HALF, px, true);
        } else if (kind == "grey") {
            std::vector<half> px = pattern<half>(base, base, 1);
            write(out, hd, {"Y"}, Imf::HALF, px, false);
        } else if (kind == "window") {
            Imath::Box2i disp(Imath::V2i(10, 20), Imath::V2i(17, 23)), dw(Imath::V2i(12, 21), Imath::V2i(19, 22));
            Imf::Header h2(disp, dw, 1.f, Imath::V2f(0, 0), 1.f, Imf::INCREASING_Y, Imf::ZIP_COMPRESSION);
            std::vector<float> px = pattern<float>(disp, dw, 3);
            write(out, h2, {"R", "G", "B"}, Imf::FLOAT, px, false);
        } else if (kind == "chroma") {
            std::vector<half> px = pattern<half>(base, base, 3);
            write(out, hd, {"Y", "RY", "BY"}, Imf::HALF, px, false);
        } else if (kind == "no-colour") {
            std::vector<float> px = pattern<float>(base, base, 1);
            write(out, hd, {"Z"}, Imf::FLOAT, px, false);
        } else if (kind == "huge") {
            Imath::Box2i disp(Imath::V2i(0, 0), Imath::V2i((1 << 20) - 1, (1 << 20) - 1));
            Imf::Header h2(disp, base, 1.f, Imath::V2f(0, 0), 1.f, Imf::INCREASING_Y, Imf::ZIP_COMPRESSION);
            std::vector<float> px = pattern<float>(disp, base, 3);
            write(out, h2, {"R", "G", "B"}, Imf::FLOAT, px, false);
        } else {
            std::fprintf(stderr, "exr_write: unknown kind %s\n", kind.c_str());
            return 2;
        }
    } catch (const std::exception &e) {
        std::fprintf(stderr, "exr_write: %s: %s\n", out.c_str(), e.what());
        return 1;
    }
    return 0;
}
