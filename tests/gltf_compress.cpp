// Test helper: writes compressed variants of a glTF file with the libraries
// Debian packages (no glTF-level encoder is packaged: draco_encoder reads
// OBJ/PLY, gltfpack is not in Debian). Usage:
//   gltf_compress draco|meshopt|meshopt-exp|quantize|webp|avif IN OUT.gltf|OUT.glb [BROKEN_OUT]
// draco        every triangle primitive as KHR_draco_mesh_compression
//              (positions 14 bits, normals 10, texcoords 12, colours 10)
// meshopt      vertex and index views as EXT_meshopt_compression, no filter
//              (lossless), with a fallback buffer that holds no bytes
// meshopt-exp  as meshopt, float attribute views through the EXPONENTIAL
//              filter with 16-bit mantissas (lossy)
// quantize     KHR_mesh_quantization: positions as normalized SHORT with a
//              dequantizing node, normals as normalized BYTE, texcoords in
//              [0,1] as normalized USHORT
// webp         every image as lossless WebP (libwebp) read through
//              EXT_texture_webp, required: no texture keeps a core source;
//              with BROKEN_OUT, also that file from the same encoding, each
//              WebP image cut to half its bytes and every texture keeping its
//              core source as the fallback (not required)
// avif         the same with lossless AVIF (libavif, libaom; 4:4:4, identity
//              matrix) through EXT_texture_avif
// Every bufferView of IN is copied into one new buffer (external .bin for
// .gltf, the BIN chunk for .glb); the JSON is IN's, edited.
#include <tiny_gltf.h>

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>
#include <avif/avif.h>
#include <webp/encode.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using json = nlohmann::json;

namespace {

[[noreturn]] void die(const std::string &msg)
{
    fprintf(stderr, "gltf_compress: %s\n", msg.c_str());
    exit(1);
}

struct out_file {
    json j;
    std::vector<unsigned char> bin;

    // appends bytes to buffer 0, 4-byte aligned; returns their offset
    size_t append(const void *p, size_t n)
    {
        while (bin.size() % 4)
            bin.push_back(0);
        size_t at = bin.size();
        bin.insert(bin.end(), (const unsigned char *)p, (const unsigned char *)p + n);
        return at;
    }
    // ... as a new bufferView
    int add_view(const void *p, size_t n, int stride = 0)
    {
        json v = {{"buffer", 0}, {"byteOffset", append(p, n)}, {"byteLength", n}};
        if (stride)
            v["byteStride"] = stride;
        j["bufferViews"].push_back(v);
        return (int)j["bufferViews"].size() - 1;
    }
    void use(const char *ext, bool required)
    {
        for (const char *key : {"extensionsUsed", "extensionsRequired"}) {
            if (key[9] == 'R' && !required)
                continue;
            if (!j.contains(key))
                j[key] = json::array();
            if (std::find(j[key].begin(), j[key].end(), ext) == j[key].end())
                j[key].push_back(ext);
        }
    }
};

// accessor `a` as floats (normalized integers per glTF), `comps` per element
std::vector<float> floats(const tinygltf::Model &m, int a, int *comps)
{
    const tinygltf::Accessor &acc = m.accessors[a];
    const tinygltf::BufferView &v = m.bufferViews[acc.bufferView];
    int nc = tinygltf::GetNumComponentsInType(acc.type), cs = tinygltf::GetComponentSizeInBytes(acc.componentType);
    size_t stride = v.byteStride ? v.byteStride : (size_t)nc * cs;
    const unsigned char *base = m.buffers[v.buffer].data.data() + v.byteOffset + acc.byteOffset;
    std::vector<float> out(acc.count * nc);
    for (size_t i = 0; i < acc.count; ++i)
        for (int c = 0; c < nc; ++c) {
            const unsigned char *p = base + i * stride + c * cs;
            float x;
            switch (acc.componentType) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: memcpy(&x, p, 4); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: x = acc.normalized ? p[0] / 255.f : p[0]; break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                uint16_t s; memcpy(&s, p, 2); x = acc.normalized ? s / 65535.f : s; break; }
            default: die("accessor " + std::to_string(a) + ": component type not handled by this helper");
            }
            out[i * nc + c] = x;
        }
    *comps = nc;
    return out;
}

std::vector<uint32_t> indices(const tinygltf::Model &m, int a)
{
    const tinygltf::Accessor &acc = m.accessors[a];
    const tinygltf::BufferView &v = m.bufferViews[acc.bufferView];
    int cs = tinygltf::GetComponentSizeInBytes(acc.componentType);
    const unsigned char *base = m.buffers[v.buffer].data.data() + v.byteOffset + acc.byteOffset;
    std::vector<uint32_t> out(acc.count);
    for (size_t i = 0; i < acc.count; ++i) {
        uint32_t x = 0;
        memcpy(&x, base + i * cs, cs); // little-endian
        out[i] = x;
    }
    return out;
}

// IN's bufferViews, copied into buffer 0 at their old indices
void copy_views(const tinygltf::Model &m, out_file &o)
{
    json views = json::array();
    for (size_t i = 0; i < m.bufferViews.size(); ++i) {
        const tinygltf::BufferView &v = m.bufferViews[i];
        json ov = o.j["bufferViews"][i];
        ov["buffer"] = 0;
        ov["byteOffset"] = o.append(m.buffers[v.buffer].data.data() + v.byteOffset, v.byteLength);
        views.push_back(ov);
    }
    o.j["bufferViews"] = views;
}

void to_draco(const tinygltf::Model &m, out_file &o)
{
    for (size_t mi = 0; mi < m.meshes.size(); ++mi)
        for (size_t pi = 0; pi < m.meshes[mi].primitives.size(); ++pi) {
            const tinygltf::Primitive &p = m.meshes[mi].primitives[pi];
            if ((p.mode != TINYGLTF_MODE_TRIANGLES && p.mode != -1) || p.indices < 0)
                continue;
            std::vector<uint32_t> idx = indices(m, p.indices);
            draco::Mesh mesh;
            size_t nv = m.accessors[p.attributes.at("POSITION")].count;
            mesh.set_num_points((uint32_t)nv);
            for (size_t t = 0; t + 2 < idx.size(); t += 3)
                mesh.AddFace({draco::PointIndex(idx[t]), draco::PointIndex(idx[t + 1]), draco::PointIndex(idx[t + 2])});
            std::map<std::string, int> ids;
            for (const auto &kv : p.attributes) {
                draco::GeometryAttribute::Type type =
                    kv.first == "POSITION"     ? draco::GeometryAttribute::POSITION
                    : kv.first == "NORMAL"     ? draco::GeometryAttribute::NORMAL
                    : kv.first == "TEXCOORD_0" ? draco::GeometryAttribute::TEX_COORD
                    : kv.first == "COLOR_0"    ? draco::GeometryAttribute::COLOR
                                               : draco::GeometryAttribute::GENERIC;
                int nc;
                std::vector<float> v = floats(m, kv.second, &nc);
                draco::GeometryAttribute ga;
                ga.Init(type, nullptr, (int8_t)nc, draco::DT_FLOAT32, false, sizeof(float) * nc, 0);
                int id = mesh.AddAttribute(ga, true, (uint32_t)nv);
                for (size_t i = 0; i < nv; ++i)
                    mesh.attribute(id)->SetAttributeValue(draco::AttributeValueIndex((uint32_t)i), &v[i * nc]);
                ids[kv.first] = (int)mesh.attribute(id)->unique_id();
            }
            draco::Encoder enc;
            enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
            enc.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, 10);
            enc.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, 12);
            enc.SetAttributeQuantization(draco::GeometryAttribute::COLOR, 10);
            draco::EncoderBuffer buf;
            if (!enc.EncodeMeshToBuffer(mesh, &buf).ok())
                die("Draco could not encode mesh " + std::to_string(mi));
            // the decoded point count is what the accessors must say
            draco::DecoderBuffer db;
            db.Init(buf.data(), buf.size());
            draco::Decoder dec;
            auto decoded = dec.DecodeMeshFromBuffer(&db);
            if (!decoded.ok())
                die("Draco could not decode its own output");
            int view = o.add_view(buf.data(), buf.size());
            json &jp = o.j["meshes"][mi]["primitives"][pi];
            jp["extensions"]["KHR_draco_mesh_compression"] = {{"bufferView", view}, {"attributes", ids}};
            for (const auto &kv : p.attributes) {
                json &a = o.j["accessors"][kv.second];
                a.erase("bufferView"), a.erase("byteOffset");
                a["count"] = decoded.value()->num_points();
            }
            json &ia = o.j["accessors"][p.indices];
            ia.erase("bufferView"), ia.erase("byteOffset");
            ia["count"] = decoded.value()->num_faces() * 3;
            ia["componentType"] = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        }
    o.use("KHR_draco_mesh_compression", true);
}

void to_meshopt(const tinygltf::Model &m, out_file &o, bool exp_filter)
{
    // which views hold vertex attributes / triangle indices of the meshes
    std::map<int, int> attr_views, index_views; // view -> element size
    std::set<int> float_views;
    for (const tinygltf::Mesh &mesh : m.meshes)
        for (const tinygltf::Primitive &p : mesh.primitives) {
            for (const auto &kv : p.attributes) {
                const tinygltf::Accessor &a = m.accessors[kv.second];
                int es = tinygltf::GetNumComponentsInType(a.type) * tinygltf::GetComponentSizeInBytes(a.componentType);
                attr_views[a.bufferView] = m.bufferViews[a.bufferView].byteStride ? (int)m.bufferViews[a.bufferView].byteStride : es;
                if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
                    float_views.insert(a.bufferView);
            }
            if (p.indices >= 0)
                index_views[m.accessors[p.indices].bufferView] = tinygltf::GetComponentSizeInBytes(m.accessors[p.indices].componentType);
        }
    json views = o.j["bufferViews"];
    size_t fallback = 0; // bytes of the fallback buffer (buffer 1), which holds none
    for (size_t i = 0; i < m.bufferViews.size(); ++i) {
        const tinygltf::BufferView &v = m.bufferViews[i];
        const unsigned char *src = m.buffers[v.buffer].data.data() + v.byteOffset;
        json ext;
        std::vector<unsigned char> enc;
        auto av = attr_views.find((int)i);
        auto iv = index_views.find((int)i);
        if (av != attr_views.end() && av->second % 4 == 0 && v.byteLength % av->second == 0) {
            size_t count = v.byteLength / av->second, stride = av->second;
            std::vector<unsigned char> data(src, src + v.byteLength);
            std::string filter = "NONE";
            if (exp_filter && float_views.count((int)i)) {
                meshopt_encodeFilterExp(data.data(), count, stride, 16, (const float *)(const void *)src);
                filter = "EXPONENTIAL";
            }
            enc.resize(meshopt_encodeVertexBufferBound(count, stride));
            enc.resize(meshopt_encodeVertexBuffer(enc.data(), enc.size(), data.data(), count, stride));
            ext = {{"byteStride", stride}, {"count", count}, {"mode", "ATTRIBUTES"}, {"filter", filter}};
        } else if (iv != index_views.end() && (iv->second == 2 || iv->second == 4) && (v.byteLength / iv->second) % 3 == 0) {
            size_t count = v.byteLength / iv->second;
            std::vector<uint32_t> idx(count);
            for (size_t k = 0; k < count; ++k) {
                uint32_t x = 0;
                memcpy(&x, src + k * iv->second, iv->second);
                idx[k] = x;
            }
            enc.resize(meshopt_encodeIndexBufferBound(count, *std::max_element(idx.begin(), idx.end()) + 1));
            enc.resize(meshopt_encodeIndexBuffer(enc.data(), enc.size(), idx.data(), count));
            ext = {{"byteStride", iv->second}, {"count", count}, {"mode", "TRIANGLES"}};
        } else {
            views[i]["buffer"] = 0, views[i]["byteOffset"] = o.append(src, v.byteLength);
            continue;
        }
        ext["buffer"] = 0;
        ext["byteOffset"] = o.append(enc.data(), enc.size());
        ext["byteLength"] = enc.size();
        while (fallback % 4)
            ++fallback;
        views[i] = {{"buffer", 1}, {"byteOffset", fallback}, {"byteLength", v.byteLength},
                    {"extensions", {{"EXT_meshopt_compression", ext}}}};
        if (av != attr_views.end())
            views[i]["byteStride"] = av->second;
        fallback += v.byteLength;
    }
    o.j["bufferViews"] = views;
    o.j["buffers"].push_back({{"byteLength", fallback ? fallback : 4},
                              {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
    o.use("EXT_meshopt_compression", true);
}

void to_quantized(const tinygltf::Model &m, out_file &o)
{
    copy_views(m, o);
    std::map<int, std::array<double, 6>> dequant; // mesh -> min, extent
    std::set<int> done;
    for (size_t mi = 0; mi < m.meshes.size(); ++mi) {
        double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
        for (const tinygltf::Primitive &p : m.meshes[mi].primitives) {
            int nc;
            std::vector<float> v = floats(m, p.attributes.at("POSITION"), &nc);
            for (size_t i = 0; i < v.size(); ++i)
                lo[i % 3] = std::min(lo[i % 3], (double)v[i]), hi[i % 3] = std::max(hi[i % 3], (double)v[i]);
        }
        std::array<double, 6> d = {lo[0], lo[1], lo[2], std::max(hi[0] - lo[0], 1e-6), std::max(hi[1] - lo[1], 1e-6),
                                   std::max(hi[2] - lo[2], 1e-6)};
        dequant[(int)mi] = d;
        for (const tinygltf::Primitive &p : m.meshes[mi].primitives)
            for (const auto &kv : p.attributes) {
                if (done.count(kv.second))
                    continue;
                done.insert(kv.second);
                int nc;
                std::vector<float> v = floats(m, kv.second, &nc);
                size_t n = v.size() / nc;
                json &a = o.j["accessors"][kv.second];
                a.erase("byteOffset");
                if (kv.first == "POSITION") { // [0, 32767] of each axis's range, 8-byte stride
                    std::vector<int16_t> q(n * 4, 0);
                    for (size_t i = 0; i < n; ++i)
                        for (int c = 0; c < 3; ++c)
                            q[i * 4 + c] = (int16_t)std::lround((v[i * 3 + c] - d[c]) / d[3 + c] * 32767.0);
                    a["bufferView"] = o.add_view(q.data(), q.size() * 2, 8);
                    a["componentType"] = TINYGLTF_COMPONENT_TYPE_SHORT;
                    a["normalized"] = true;
                    a["min"] = {0, 0, 0}, a["max"] = {1, 1, 1};
                    for (int c = 0; c < 3; ++c) { // exact bounds of the stored values
                        int16_t lo16 = 32767, hi16 = 0;
                        for (size_t i = 0; i < n; ++i)
                            lo16 = std::min(lo16, q[i * 4 + c]), hi16 = std::max(hi16, q[i * 4 + c]);
                        a["min"][c] = lo16 / 32767.0, a["max"][c] = hi16 / 32767.0;
                    }
                } else if (kv.first == "NORMAL") {
                    std::vector<int8_t> q(n * 4, 0);
                    for (size_t i = 0; i < n; ++i)
                        for (int c = 0; c < 3; ++c)
                            q[i * 4 + c] = (int8_t)std::lround(std::max(-1.f, std::min(1.f, v[i * 3 + c])) * 127.0);
                    a["bufferView"] = o.add_view(q.data(), q.size(), 4);
                    a["componentType"] = TINYGLTF_COMPONENT_TYPE_BYTE;
                    a["normalized"] = true;
                } else if (kv.first == "TEXCOORD_0" &&
                           *std::min_element(v.begin(), v.end()) >= 0.f && *std::max_element(v.begin(), v.end()) <= 1.f) {
                    std::vector<uint16_t> q(n * 2);
                    for (size_t i = 0; i < v.size(); ++i)
                        q[i] = (uint16_t)std::lround(v[i] * 65535.0);
                    a["bufferView"] = o.add_view(q.data(), q.size() * 2, 4);
                    a["componentType"] = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
                    a["normalized"] = true;
                }
            }
    }
    // the mesh moves to a child node whose transform dequantizes
    size_t nodes = o.j["nodes"].size();
    for (size_t ni = 0; ni < nodes; ++ni) {
        json &n = o.j["nodes"][ni];
        if (!n.contains("mesh"))
            continue;
        const std::array<double, 6> &d = dequant[n["mesh"].get<int>()];
        json child = {{"mesh", n["mesh"]}, {"translation", {d[0], d[1], d[2]}}, {"scale", {d[3], d[4], d[5]}}};
        n.erase("mesh");
        o.j["nodes"].push_back(child);
        o.j["nodes"][ni]["children"].push_back(o.j["nodes"].size() - 1);
    }
    o.use("KHR_mesh_quantization", true);
}

// RGBA8 as lossless and exact WebP (libwebp): the colour under alpha 0 is
// kept too (the simple WebPEncodeLosslessRGBA of libwebp 1.2 zeroes it)
std::vector<uint8_t> encode_webp(const std::vector<uint8_t> &rgba, int w, int h)
{
    WebPConfig config;
    WebPPicture pic;
    WebPMemoryWriter mem;
    if (!WebPConfigInit(&config) || !WebPPictureInit(&pic))
        die("libwebp version mismatch");
    config.lossless = 1;
    config.exact = 1;
    config.method = 0; // the fastest: these are test files
    config.quality = 0.f;
    pic.use_argb = 1;
    pic.width = w;
    pic.height = h;
    WebPMemoryWriterInit(&mem);
    pic.writer = WebPMemoryWrite;
    pic.custom_ptr = &mem;
    bool ok = WebPPictureImportRGBA(&pic, rgba.data(), w * 4) && WebPEncode(&config, &pic);
    WebPPictureFree(&pic);
    std::vector<uint8_t> out(mem.mem, mem.mem + (ok ? mem.size : 0));
    WebPMemoryWriterClear(&mem);
    if (!ok)
        die("libwebp could not encode an image");
    return out;
}

// RGBA8 as lossless AVIF (libavif with libaom): 4:4:4, the identity matrix
// (G, B, R as the planes), full range, quantizer 0 for colour and alpha
std::vector<uint8_t> encode_avif(const std::vector<uint8_t> &rgba, int w, int h)
{
    avifImage *img = avifImageCreate((uint32_t)w, (uint32_t)h, 8, AVIF_PIXEL_FORMAT_YUV444);
    avifEncoder *enc = avifEncoderCreate();
    if (!img || !enc)
        die("libavif: out of memory");
    img->matrixCoefficients = AVIF_MATRIX_COEFFICIENTS_IDENTITY;
    img->yuvRange = AVIF_RANGE_FULL;
    avifRGBImage rgb;
    avifRGBImageSetDefaults(&rgb, img);
    rgb.format = AVIF_RGB_FORMAT_RGBA;
    rgb.depth = 8;
    rgb.pixels = const_cast<uint8_t *>(rgba.data());
    rgb.rowBytes = (uint32_t)w * 4;
    enc->codecChoice = AVIF_CODEC_CHOICE_AOM;
    enc->minQuantizer = enc->maxQuantizer = AVIF_QUANTIZER_LOSSLESS;
    enc->minQuantizerAlpha = enc->maxQuantizerAlpha = AVIF_QUANTIZER_LOSSLESS;
    enc->speed = AVIF_SPEED_FASTEST;
    avifRWData out = AVIF_DATA_EMPTY;
    bool ok = avifImageRGBToYUV(img, &rgb) == AVIF_RESULT_OK && avifEncoderWrite(enc, img, &out) == AVIF_RESULT_OK;
    std::vector<uint8_t> bytes(out.data, out.data + (ok ? out.size : 0));
    avifRWDataFree(&out);
    avifEncoderDestroy(enc);
    avifImageDestroy(img);
    if (!ok)
        die("libavif could not encode an image");
    return bytes;
}

// Every image of m as lossless `codec` ("webp" or "avif"), in order.
std::vector<std::vector<uint8_t>> encode_images(const tinygltf::Model &m, const std::string &codec)
{
    std::vector<std::vector<uint8_t>> coded;
    for (size_t i = 0; i < m.images.size(); ++i) {
        const tinygltf::Image &img = m.images[i];
        int w = img.width, h = img.height, c = img.component;
        if (w <= 0 || h <= 0 || img.bits != 8 || (c != 3 && c != 4) || img.image.size() != (size_t)w * h * c)
            die("image " + std::to_string(i) + " is not 8-bit RGB or RGBA");
        std::vector<uint8_t> rgba((size_t)w * h * 4, 255);
        for (size_t p = 0; p < (size_t)w * h; ++p)
            memcpy(&rgba[4 * p], &img.image[c * p], (size_t)c);
        coded.push_back(codec == "avif" ? encode_avif(rgba, w, h) : encode_webp(rgba, w, h));
    }
    return coded;
}

// m with its images `coded` (encode_images) through EXT_texture_<codec>
void to_images(const tinygltf::Model &m, out_file &o, const std::string &codec,
               const std::vector<std::vector<uint8_t>> &coded, bool broken, const std::string &in_dir)
{
    const std::string ext = "EXT_texture_" + codec;
    copy_views(m, o);
    // the core images from external files go into the buffer, so that OUT stands alone
    for (size_t i = 0; i < m.images.size(); ++i) {
        const std::string &uri = m.images[i].uri;
        if (uri.empty() || uri.compare(0, 5, "data:") == 0)
            continue;
        std::ifstream f(in_dir + "/" + uri, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        if (!f.good() && !f.eof())
            die("cannot read image " + uri);
        json &ji = o.j["images"][i];
        ji.erase("uri");
        ji["bufferView"] = o.add_view(bytes.data(), bytes.size());
        ji["mimeType"] = uri.size() > 4 && (uri.substr(uri.size() - 4) == ".jpg" || uri.substr(uri.size() - 5) == ".jpeg")
                             ? "image/jpeg"
                             : "image/png";
    }
    std::vector<int> coded_of(m.images.size(), -1);
    for (size_t i = 0; i < m.images.size(); ++i) {
        const std::vector<uint8_t> &bytes = coded[i];
        int view = o.add_view(bytes.data(), broken ? bytes.size() / 2 : bytes.size());
        o.j["images"].push_back({{"bufferView", view}, {"mimeType", "image/" + codec}});
        coded_of[i] = (int)o.j["images"].size() - 1;
    }
    for (size_t t = 0; t < m.textures.size(); ++t) {
        json &jt = o.j["textures"][t];
        int src = m.textures[t].source;
        if (src < 0 || coded_of[src] < 0)
            continue;
        jt["extensions"][ext] = {{"source", coded_of[src]}};
        if (!broken)
            jt.erase("source");
    }
    if (!m.images.empty())
        o.use(ext.c_str(), !broken);
}

void write(out_file &o, const std::string &path)
{
    bool glb = path.size() > 4 && path.substr(path.size() - 4) == ".glb";
    while (o.bin.size() % 4)
        o.bin.push_back(0);
    o.j["buffers"][0] = {{"byteLength", o.bin.size()}};
    std::string bin_name = path.substr(path.rfind('/') + 1) + ".bin";
    if (!glb)
        o.j["buffers"][0]["uri"] = bin_name;
    std::string text = o.j.dump();
    std::ofstream f(path, std::ios::binary);
    if (!glb) {
        f << text;
        std::ofstream b(path + ".bin", std::ios::binary);
        b.write((const char *)o.bin.data(), (std::streamsize)o.bin.size());
    } else {
        while (text.size() % 4)
            text += ' ';
        uint32_t hdr[5] = {0x46546C67u, 2, (uint32_t)(12 + 8 + text.size() + 8 + o.bin.size()), (uint32_t)text.size(),
                           0x4E4F534Au};
        uint32_t bin_hdr[2] = {(uint32_t)o.bin.size(), 0x004E4942u};
        f.write((const char *)hdr, sizeof hdr);
        f << text;
        f.write((const char *)bin_hdr, sizeof bin_hdr);
        f.write((const char *)o.bin.data(), (std::streamsize)o.bin.size());
    }
    if (!f)
        die("could not write " + path);
}

} // namespace

int main(int argc, char **argv)
{
    if (argc != 4 && argc != 5)
        die("usage: gltf_compress draco|meshopt|meshopt-exp|quantize|webp|avif IN OUT.gltf|OUT.glb "
            "[BROKEN_OUT: webp and avif only]");
    std::string mode = argv[1], in = argv[2], out = argv[3];
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    bool ok = in.size() > 4 && in.substr(in.size() - 4) == ".glb" ? loader.LoadBinaryFromFile(&m, &err, &warn, in)
                                                                  : loader.LoadASCIIFromFile(&m, &err, &warn, in);
    if (!ok)
        die(in + ": " + err);
    // the JSON as written, to edit (GLB: its JSON chunk)
    std::ifstream f(in, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (bytes.compare(0, 4, "glTF") == 0) {
        uint32_t len;
        memcpy(&len, bytes.data() + 12, 4);
        bytes = bytes.substr(20, len);
    }
    auto fresh = [&]() {
        out_file o;
        o.j = json::parse(bytes);
        o.j["buffers"] = json::array({json::object()});
        return o;
    };
    bool image_mode = mode == "webp" || mode == "avif";
    if (argc == 5 && !image_mode)
        die("BROKEN_OUT is for webp and avif only");
    out_file o = fresh();
    if (mode == "draco") {
        copy_views(m, o);
        to_draco(m, o);
    } else if (mode == "meshopt" || mode == "meshopt-exp") {
        to_meshopt(m, o, mode == "meshopt-exp");
    } else if (mode == "quantize") {
        to_quantized(m, o);
    } else if (image_mode) {
        // encoding is most of the time (libaom, libwebp's best compression),
        // so a second variant reuses it
        std::string dir = in.find('/') == std::string::npos ? "." : in.substr(0, in.rfind('/'));
        std::vector<std::vector<uint8_t>> coded = encode_images(m, mode);
        to_images(m, o, mode, coded, false, dir);
        if (argc == 5) {
            out_file b = fresh();
            to_images(m, b, mode, coded, true, dir);
            write(b, argv[4]);
        }
    } else {
        die("unknown mode " + mode);
    }
    write(o, out);
    return 0;
}
