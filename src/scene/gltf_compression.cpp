// Decoders for compressed glTF geometry: thin, checked calls into
// meshoptimizer and Draco (see gltf_compression.h).
#include "scene/gltf_compression.h"

#include <meshoptimizer.h>

#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>

#include <cstring>

namespace pb_gltf {

namespace {

// glTF component types (the numbers of the spec; tinygltf is not included here)
enum : int {
    GL_BYTE = 5120, GL_UNSIGNED_BYTE = 5121, GL_SHORT = 5122, GL_UNSIGNED_SHORT = 5123,
    GL_UNSIGNED_INT = 5125, GL_FLOAT = 5126
};

size_t component_size(int type)
{
    switch (type) {
    case GL_BYTE: case GL_UNSIGNED_BYTE: return 1;
    case GL_SHORT: case GL_UNSIGNED_SHORT: return 2;
    case GL_UNSIGNED_INT: case GL_FLOAT: return 4;
    default: return 0;
    }
}

bool expands_too_far(size_t src_len, size_t count, size_t stride)
{
    return count > (SIZE_MAX / 2) / (stride ? stride : 1) || count * stride > max_expansion * src_len + 4096;
}

} // namespace

std::string meshopt_decode(const unsigned char *src, size_t src_len, size_t count, size_t stride,
                           const std::string &mode, const std::string &filter, std::vector<unsigned char> &out)
{
    if (expands_too_far(src_len, count, stride))
        return "claims " + std::to_string(count) + " elements of " + std::to_string(stride) + " bytes from " +
               std::to_string(src_len) + " compressed bytes";
    out.assign(count * stride, 0);
    if (count == 0)
        return "";
    int rc;
    if (mode == "ATTRIBUTES") {
        if (stride == 0 || stride > 256 || stride % 4 != 0)
            return "ATTRIBUTES need a byteStride that is a multiple of 4 up to 256, not " + std::to_string(stride);
        rc = meshopt_decodeVertexBuffer(out.data(), count, stride, src, src_len);
    } else if (mode == "TRIANGLES" || mode == "INDICES") {
        if (stride != 2 && stride != 4)
            return mode + " need a byteStride of 2 or 4, not " + std::to_string(stride);
        if (mode == "TRIANGLES" && count % 3 != 0)
            return "TRIANGLES need a count that is a multiple of 3, not " + std::to_string(count);
        rc = mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(out.data(), count, stride, src, src_len)
                                 : meshopt_decodeIndexSequence(out.data(), count, stride, src, src_len);
    } else {
        return "unknown mode '" + mode + "'";
    }
    if (rc != 0)
        return "malformed " + mode + " data (meshoptimizer error " + std::to_string(rc) + ")";
    if (filter == "NONE" || filter.empty())
        return "";
    if (mode != "ATTRIBUTES")
        return "filter " + filter + " on " + mode + " data";
    if (filter == "OCTAHEDRAL" && (stride == 4 || stride == 8))
        meshopt_decodeFilterOct(out.data(), count, stride);
    else if (filter == "QUATERNION" && stride == 8)
        meshopt_decodeFilterQuat(out.data(), count, stride);
    else if (filter == "EXPONENTIAL")
        meshopt_decodeFilterExp(out.data(), count, stride);
    else
        return "filter '" + filter + "' with byteStride " + std::to_string(stride);
    return "";
}

struct draco_mesh {
    std::unique_ptr<draco::Mesh> mesh;
};

void draco_mesh_deleter::operator()(draco_mesh *m) const
{
    delete m;
}

std::string draco_decode(const unsigned char *src, size_t src_len, draco_mesh_ptr &out)
{
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char *>(src), src_len);
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok())
        return "Draco: " + std::string(decoded.status().error_msg());
    out.reset(new draco_mesh{std::move(decoded).value()});
    if (!out->mesh)
        return "Draco: no mesh";
    return "";
}

namespace {

template <typename T> void put(unsigned char *dst, T v)
{
    memcpy(dst, &v, sizeof v);
}

// One value of `comps` components of attribute `a` at point `p`, converted
// by Draco to T, packed at dst. false when Draco cannot represent it as T.
template <typename T>
bool convert(const draco::PointAttribute *a, draco::PointIndex p, int comps, unsigned char *dst)
{
    T v[4] = {};
    if (!a->ConvertValue<T>(a->mapped_index(p), (int8_t)comps, v))
        return false;
    memcpy(dst, v, sizeof(T) * comps);
    return true;
}

} // namespace

std::string draco_indices(const draco_mesh &m, int component_type, std::vector<unsigned char> &out, size_t *count)
{
    size_t isize = component_size(component_type);
    if (component_type != GL_UNSIGNED_BYTE && component_type != GL_UNSIGNED_SHORT && component_type != GL_UNSIGNED_INT)
        return "Draco indices need an unsigned integer accessor";
    const draco::Mesh &mesh = *m.mesh;
    uint64_t limit = isize == 1 ? 0xffu : isize == 2 ? 0xffffu : 0xffffffffu;
    if (mesh.num_points() > 0 && (uint64_t)mesh.num_points() - 1 > limit)
        return "Draco mesh has " + std::to_string(mesh.num_points()) + " points, more than its index accessor holds";
    *count = (size_t)mesh.num_faces() * 3;
    out.assign(*count * isize, 0);
    for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f)
        for (int k = 0; k < 3; ++k) {
            uint32_t v = mesh.face(f)[k].value();
            unsigned char *dst = out.data() + ((size_t)f.value() * 3 + k) * isize;
            if (isize == 1)
                put<uint8_t>(dst, (uint8_t)v);
            else if (isize == 2)
                put<uint16_t>(dst, (uint16_t)v);
            else
                put<uint32_t>(dst, v);
        }
    return "";
}

std::string draco_attribute(const draco_mesh &m, int unique_id, int component_type, int components,
                            std::vector<unsigned char> &out, size_t *count)
{
    const draco::Mesh &mesh = *m.mesh;
    if (unique_id < 0)
        return "Draco attribute id " + std::to_string(unique_id) + " is negative";
    const draco::PointAttribute *a = mesh.GetAttributeByUniqueId((uint32_t)unique_id);
    if (!a)
        return "Draco attribute " + std::to_string(unique_id) + " does not exist";
    size_t csize = component_size(component_type);
    if (csize == 0 || components < 1 || components > 4)
        return "Draco attribute " + std::to_string(unique_id) + " has an accessor of unsupported type";
    if (a->num_components() != components)
        return "Draco attribute " + std::to_string(unique_id) + " has " + std::to_string(a->num_components()) +
               " components, its accessor " + std::to_string(components);
    *count = mesh.num_points();
    size_t elem = csize * (size_t)components;
    out.assign(*count * elem, 0);
    for (draco::PointIndex p(0); p < mesh.num_points(); ++p) {
        unsigned char *dst = out.data() + (size_t)p.value() * elem;
        bool ok;
        switch (component_type) {
        case GL_BYTE: ok = convert<int8_t>(a, p, components, dst); break;
        case GL_UNSIGNED_BYTE: ok = convert<uint8_t>(a, p, components, dst); break;
        case GL_SHORT: ok = convert<int16_t>(a, p, components, dst); break;
        case GL_UNSIGNED_SHORT: ok = convert<uint16_t>(a, p, components, dst); break;
        case GL_UNSIGNED_INT: ok = convert<uint32_t>(a, p, components, dst); break;
        default: ok = convert<float>(a, p, components, dst); break;
        }
        if (!ok)
            return "Draco attribute " + std::to_string(unique_id) + " does not convert to its accessor's type";
    }
    return "";
}

} // namespace pb_gltf
