// Wraps tinygltf (its images are decoded in gltf_images.cpp, materials and
// textures read in gltf_materials.cpp, compressed geometry decoded in
// gltf_compression.cpp). Parses the file, checks every index and
// byte range before touching data, walks the default scene's node hierarchy
// composing transforms in double, assembles triangles from triangles / strips
// / fans with or without indices, and hands world-space data to the C scene
// builder. Nothing here outlives the call.
#include "scene/gltf_compression.h"
#include "scene/gltf_images.h"
#include "scene/gltf_materials.h"
#include "scene/gltf_reader.h"
#include "scene/scene_builder.h"

extern "C" {
#include "common/common.h"
#include "probebake/files.h"
}

#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace pb_gltf {

pb_result fail(reader &r, pb_result code, const std::string &what)
{
    return pb_fail(r.err, code, "%s: %s", r.path, what.c_str());
}

} // namespace pb_gltf

namespace {

// tinygltf lets a std::bad_alloc reach one of its noexcept functions, where
// C++ calls std::terminate: that load cannot fail the usual way (found by
// failing each allocation in turn, tests/test_out_of_memory.sh). While
// tinygltf reads, a terminate handler says why on one line naming the file
// and exits 1, instead of an abort without a word. The file being read is
// kept here for it: the handler takes no argument.
thread_local const char *tinygltf_reading;

[[noreturn]] void tinygltf_terminated()
{
    /* the handler is the process's while any thread reads: a terminate on a
     * thread that is not reading a file ends as C++'s default one does */
    if (!tinygltf_reading)
        std::abort();
    const char *why = "an exception tinygltf could not pass on";
    try {
        if (std::exception_ptr e = std::current_exception())
            std::rethrow_exception(e);
    } catch (const std::bad_alloc &) {
        why = "out of host memory";
    } catch (...) {
    }
    fprintf(stderr, "probebake: error: %s: %s while tinygltf read it\n", tinygltf_reading, why);
    _exit(1);
}

// The allocator of the loader's per-vertex and per-index arrays: a large
// scene's are hundreds of MB, filled right after they are made, so they ask
// for huge pages (pb_malloc_large; bench/RESULTS.md, "Huge pages for large
// arrays").
template <class T> struct large_allocator {
    using value_type = T;
    large_allocator() = default;
    template <class U> large_allocator(const large_allocator<U> &) {}
    T *allocate(size_t n)
    {
        if (n > SIZE_MAX / sizeof(T))
            throw std::bad_alloc();
        void *p = pb_malloc_large(n * sizeof(T));
        if (!p)
            throw std::bad_alloc();
        return static_cast<T *>(p);
    }
    void deallocate(T *p, size_t) { free(p); }
    template <class U> bool operator==(const large_allocator<U> &) const { return true; }
    template <class U> bool operator!=(const large_allocator<U> &) const { return false; }
};
using double_array = std::vector<double, large_allocator<double>>;
using index_array = std::vector<uint32_t, large_allocator<uint32_t>>;

using pb_gltf::mat4;
using pb_gltf::reader;
using pb_gltf::fail;
using pb_gltf::read_materials;
using pb_gltf::read_textures;

void mat_identity(mat4 o)
{
    for (int i = 0; i < 16; ++i)
        o[i] = (i % 5) == 0 ? 1.0 : 0.0;
}

void mat_mul(const mat4 a, const mat4 b, mat4 o)
{
    mat4 r;
    for (int c = 0; c < 4; ++c)
        for (int rr = 0; rr < 4; ++rr) {
            double s = 0;
            for (int k = 0; k < 4; ++k)
                s += a[k * 4 + rr] * b[c * 4 + k];
            r[c * 4 + rr] = s;
        }
    memcpy(o, r, sizeof r);
}

// T x R x S, the quaternion normalised
void trs_matrix(const double t[3], const double q_in[4], const double s[3], mat4 o)
{
    double q[4] = {q_in[0], q_in[1], q_in[2], q_in[3]};
    double ql = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (ql > 0)
        for (double &c : q)
            c /= ql;
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                   2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)}; // columns
    mat_identity(o);
    for (int c = 0; c < 3; ++c)
        for (int rr = 0; rr < 3; ++rr)
            o[c * 4 + rr] = r[c * 3 + rr] * s[c];
    o[12] = t[0], o[13] = t[1], o[14] = t[2];
}

void node_local(const tinygltf::Node &n, mat4 o)
{
    if (n.matrix.size() == 16) {
        for (int i = 0; i < 16; ++i)
            o[i] = n.matrix[i];
        return;
    }
    double t[3] = {0, 0, 0}, s[3] = {1, 1, 1}, q[4] = {0, 0, 0, 1};
    if (n.translation.size() == 3)
        for (int i = 0; i < 3; ++i)
            t[i] = n.translation[i];
    if (n.scale.size() == 3)
        for (int i = 0; i < 3; ++i)
            s[i] = n.scale[i];
    if (n.rotation.size() == 4)
        for (int i = 0; i < 4; ++i)
            q[i] = n.rotation[i];
    trs_matrix(t, q, s, o);
}

void xform_point(const mat4 m, const double p[3], double o[3])
{
    for (int r = 0; r < 3; ++r)
        o[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
}

void xform_dir(const mat4 m, const double d[3], double o[3])
{
    for (int r = 0; r < 3; ++r)
        o[r] = m[r] * d[0] + m[4 + r] * d[1] + m[8 + r] * d[2];
}

// Inverse-transpose of the upper 3x3 (cofactor matrix; the scale does not
// matter because normals are renormalised). Returns the determinant.
double normal_matrix(const mat4 m, double n[9])
{
    double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    // cofactors, stored column-major for xform: n maps object normal -> world
    double c00 = e * i - f * h, c01 = -(d * i - f * g), c02 = d * h - e * g;
    double c10 = -(b * i - c * h), c11 = a * i - c * g, c12 = -(a * h - b * g);
    double c20 = b * f - c * e, c21 = -(a * f - c * d), c22 = a * e - b * d;
    // world normal row r = sum_k cof[r][k] * n_k
    n[0] = c00, n[3] = c01, n[6] = c02;
    n[1] = c10, n[4] = c11, n[7] = c12;
    n[2] = c20, n[5] = c21, n[8] = c22;
    return a * c00 + b * c01 + c * c02;
}

// An accessor without a bufferView reads as zeros of any count; larger ones
// are refused rather than allocated.
const size_t PB_GLTF_MAX_ZERO_ELEMENTS = size_t(1) << 24;

// JSON deeper than this is refused before the parser (which recurses once
// per level: 20,000 levels overflowed an 8 MiB stack) sees it. Real glTF
// nests about ten levels; 512 leaves room for deep extras.
const int PB_GLTF_MAX_NESTING = 512;

// One component of type `type` at p as a double (normalized integers to
// [0, 1] or [-1, 1], glTF's rule). false for an unknown component type.
bool component(const unsigned char *p, int type, bool normalized, double *x)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; memcpy(&f, p, 4); *x = f; return true; }
    case TINYGLTF_COMPONENT_TYPE_DOUBLE: { double f; memcpy(&f, p, 8); *x = f; return true; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: *x = normalized ? p[0] / 255.0 : p[0]; return true;
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t s; memcpy(&s, p, 1); *x = normalized ? std::fmax(s / 127.0, -1.0) : s; return true; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t s; memcpy(&s, p, 2); *x = normalized ? s / 65535.0 : s; return true; }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t s; memcpy(&s, p, 2); *x = normalized ? std::fmax(s / 32767.0, -1.0) : s; return true; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t s; memcpy(&s, p, 4); *x = normalized ? s / 4294967295.0 : s; return true; }
    case TINYGLTF_COMPONENT_TYPE_INT: { int32_t s; memcpy(&s, p, 4); *x = s; return true; }
    default: return false;
    }
}

// The bytes of bufferView `view` from `offset` that `count` elements of
// `elem` bytes at `stride` need, checked against the view and its buffer.
pb_result view_span(reader &r, int view, size_t offset, size_t count, size_t elem, size_t stride,
                    const std::string &name, const unsigned char **out)
{
    const tinygltf::Model &m = r.m;
    if (view < 0 || view >= (int)m.bufferViews.size())
        return fail(r, PB_ERROR_PARSE, name + " refers to missing bufferView " + std::to_string(view));
    const tinygltf::BufferView &v = m.bufferViews[view];
    const unsigned char *data;
    size_t length;
    if (view < (int)r.view_decoded.size() && r.view_decoded[view]) { // decompressed: its own bytes
        data = r.view_data[view].data(), length = r.view_data[view].size();
    } else {
        if (v.buffer < 0 || v.buffer >= (int)m.buffers.size())
            return fail(r, PB_ERROR_PARSE, "bufferView " + std::to_string(view) + " refers to missing buffer " +
                                               std::to_string(v.buffer));
        const std::vector<unsigned char> &buf = m.buffers[v.buffer].data;
        // the view must sit in the buffer, and the elements in the view
        if (v.byteOffset > buf.size() || v.byteLength > buf.size() - v.byteOffset)
            return fail(r, PB_ERROR_PARSE, "bufferView " + std::to_string(view) + " (offset " +
                                               std::to_string(v.byteOffset) + ", length " + std::to_string(v.byteLength) +
                                               ") exceeds buffer " + std::to_string(v.buffer) + " of " +
                                               std::to_string(buf.size()) + " bytes (truncated or missing buffer?)");
        data = buf.data() + v.byteOffset, length = v.byteLength;
    }
    size_t need = offset + stride * (count - 1) + elem;
    if (count > SIZE_MAX / stride || need < offset || need > length)
        return fail(r, PB_ERROR_PARSE, name + " (" + std::to_string(count) + " elements) reads past the end of bufferView " +
                                           std::to_string(view));
    *out = data + offset;
    return PB_OK;
}

// Reads `count` elements of accessor `index` as `ncomp` doubles each, after
// checking every byte it touches lies inside its buffer view and buffer;
// a sparse accessor's substitutions (core glTF 2.0) are applied over its
// base (its bufferView, or zeros).
pb_result read_accessor(reader &r, int index, int ncomp, double_array &out, const char *what)
{
    const tinygltf::Model &m = r.m;
    if (index < 0 || index >= (int)m.accessors.size())
        return fail(r, PB_ERROR_PARSE, std::string(what) + " accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor &a = m.accessors[index];
    std::string name = std::string(what) + " accessor " + std::to_string(index);
    int comps = tinygltf::GetNumComponentsInType((uint32_t)a.type);
    int csize = tinygltf::GetComponentSizeInBytes((uint32_t)a.componentType);
    if (comps <= 0 || csize <= 0)
        return fail(r, PB_ERROR_PARSE, name + " has an invalid type or component type");
    if (comps < ncomp)
        return fail(r, PB_ERROR_PARSE, name + " has " + std::to_string(comps) + " components, needs " +
                                           std::to_string(ncomp));
    auto decoded = r.draco_accessors.find(index);
    if (decoded != r.draco_accessors.end()) { // Draco: packed in the accessor's type, never sparse
        size_t elem = (size_t)comps * csize, n = decoded->second.count;
        if (decoded->second.bytes.size() != n * elem)
            return fail(r, PB_ERROR_PARSE, name + " does not match its Draco attribute");
        out.assign(n * ncomp, 0.0);
        for (size_t i = 0; i < n; ++i)
            for (int c = 0; c < ncomp; ++c)
                component(decoded->second.bytes.data() + i * elem + (size_t)c * csize, a.componentType, a.normalized,
                          &out[i * ncomp + c]);
        return PB_OK;
    }
    // every size is checked before anything is allocated from it
    if (a.count == 0) {
        out.clear();
        return PB_OK;
    }
    size_t elem = (size_t)comps * csize;
    if (a.bufferView < 0) { // glTF: all zeros; no buffer bounds the count, so a fixed limit does
        if (a.count > PB_GLTF_MAX_ZERO_ELEMENTS)
            return fail(r, PB_ERROR_PARSE, name + " has " + std::to_string(a.count) +
                                               " elements and no bufferView: at most " +
                                               std::to_string(PB_GLTF_MAX_ZERO_ELEMENTS));
        out.assign((size_t)a.count * ncomp, 0.0);
    } else {
        size_t stride = a.bufferView < (int)m.bufferViews.size() && m.bufferViews[a.bufferView].byteStride
                            ? m.bufferViews[a.bufferView].byteStride
                            : elem;
        if (stride < elem)
            return fail(r, PB_ERROR_PARSE, name + ": byteStride smaller than an element");
        const unsigned char *base;
        pb_result res = view_span(r, a.bufferView, a.byteOffset, a.count, elem, stride, name, &base);
        if (res != PB_OK)
            return res;
        out.assign((size_t)a.count * ncomp, 0.0); // bounded: count x stride fits in the view
        for (size_t i = 0; i < a.count; ++i)
            for (int c = 0; c < ncomp; ++c)
                if (!component(base + i * stride + (size_t)c * csize, a.componentType, a.normalized,
                               &out[i * ncomp + c]))
                    return fail(r, PB_ERROR_PARSE, name + " has an invalid component type");
    }
    if (!a.sparse.isSparse)
        return PB_OK;
    // sparse: `count` (index, value) pairs, indices strictly increasing and
    // inside the accessor, values tightly packed in the accessor's type
    size_t n = (size_t)a.sparse.count;
    if (a.sparse.count < 1 || n > a.count)
        return fail(r, PB_ERROR_PARSE, name + " has a sparse count of " + std::to_string(a.sparse.count) + " for " +
                                           std::to_string(a.count) + " elements");
    int itype = a.sparse.indices.componentType;
    int isize = tinygltf::GetComponentSizeInBytes((uint32_t)itype);
    if (itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        return fail(r, PB_ERROR_PARSE, name + ": sparse indices must be unsigned byte, short or int");
    const unsigned char *ip, *vp;
    pb_result res = view_span(r, a.sparse.indices.bufferView, (size_t)a.sparse.indices.byteOffset, n, (size_t)isize,
                              (size_t)isize, name + " sparse indices", &ip);
    if (res == PB_OK)
        res = view_span(r, a.sparse.values.bufferView, (size_t)a.sparse.values.byteOffset, n, elem, elem,
                        name + " sparse values", &vp);
    if (res != PB_OK)
        return res;
    double prev = -1;
    for (size_t k = 0; k < n; ++k) {
        double idx;
        component(ip + k * isize, itype, false, &idx);
        if (!(idx > prev) || idx >= (double)a.count)
            return fail(r, PB_ERROR_PARSE, name + ": sparse index " + std::to_string((uint64_t)idx) +
                                               (idx >= (double)a.count ? " is past the accessor's end"
                                                                        : " does not increase"));
        prev = idx;
        for (int c = 0; c < ncomp; ++c)
            component(vp + k * elem + (size_t)c * csize, a.componentType, a.normalized, &out[(size_t)idx * ncomp + c]);
    }
    return PB_OK;
}

// A non-negative integer member of an extension object (`dflt` when absent;
// a negative default makes the member required).
bool ext_uint(const tinygltf::Value &e, const char *key, double dflt, size_t *out)
{
    double x = dflt;
    if (e.Has(key)) {
        if (!e.Get(key).IsNumber())
            return false;
        x = e.Get(key).GetNumberAsDouble();
    }
    if (!(x >= 0 && x <= 9007199254740992.0) || x != std::floor(x))
        return false;
    *out = (size_t)x;
    return true;
}

std::string ext_string(const tinygltf::Value &e, const char *key, const char *dflt)
{
    return e.Has(key) && e.Get(key).IsString() ? e.Get(key).Get<std::string>() : std::string(dflt);
}

// EXT_meshopt_compression: each compressed bufferView is decoded once, up
// front, from the source range its extension names; from then on its
// accessors read the decoded bytes (view_span), never the fallback buffer.
pb_result decode_meshopt_views(reader &r)
{
    const tinygltf::Model &m = r.m;
    r.view_data.assign(m.bufferViews.size(), {});
    r.view_decoded.assign(m.bufferViews.size(), 0);
    for (size_t i = 0; i < m.bufferViews.size(); ++i) {
        auto it = m.bufferViews[i].extensions.find("EXT_meshopt_compression");
        if (it == m.bufferViews[i].extensions.end())
            continue;
        const tinygltf::Value &e = it->second;
        std::string name = "bufferView " + std::to_string(i) + " (EXT_meshopt_compression)";
        size_t buffer, offset, length, stride, count;
        if (!e.IsObject() || !ext_uint(e, "buffer", -1, &buffer) || !ext_uint(e, "byteOffset", 0, &offset) ||
            !ext_uint(e, "byteLength", -1, &length) || !ext_uint(e, "byteStride", -1, &stride) ||
            !ext_uint(e, "count", -1, &count))
            return fail(r, PB_ERROR_PARSE, name + " lacks a valid buffer, byteLength, byteStride or count");
        if (buffer >= m.buffers.size())
            return fail(r, PB_ERROR_PARSE, name + " refers to missing buffer " + std::to_string(buffer));
        const std::vector<unsigned char> &buf = m.buffers[buffer].data;
        if (offset > buf.size() || length > buf.size() - offset)
            return fail(r, PB_ERROR_PARSE, name + ": its compressed bytes (offset " + std::to_string(offset) +
                                               ", length " + std::to_string(length) + ") exceed buffer " +
                                               std::to_string(buffer) + " of " + std::to_string(buf.size()) + " bytes");
        if (stride == 0 || count > SIZE_MAX / stride || count * stride != m.bufferViews[i].byteLength)
            return fail(r, PB_ERROR_PARSE, name + " decodes to " + std::to_string(count) + " x " + std::to_string(stride) +
                                               " bytes, not the bufferView's " +
                                               std::to_string(m.bufferViews[i].byteLength));
        std::string why = pb_gltf::meshopt_decode(buf.data() + offset, length, count, stride,
                                                  ext_string(e, "mode", ""), ext_string(e, "filter", "NONE"),
                                                  r.view_data[i]);
        if (!why.empty())
            return fail(r, PB_ERROR_PARSE, name + ": " + why);
        r.view_decoded[i] = 1;
    }
    return PB_OK;
}

// KHR_draco_mesh_compression on a primitive: decodes its bufferView and
// stands the decoded indices and attributes in for the accessors that name
// them (read_accessor reads them from there), so the rest of the loader does
// not know the mesh was compressed. Its indices accessor: *indices (moved
// there by patch_for_tinygltf).
pb_result decode_draco(reader &r, const tinygltf::Primitive &prim, const tinygltf::Value &e, const char *mesh_name,
                       int *indices_out)
{
    const tinygltf::Model &m = r.m;
    std::string name = "mesh '" + std::string(mesh_name) + "' (KHR_draco_mesh_compression)";
    if (!e.IsObject() || !e.Has("bufferView") || !e.Get("bufferView").IsInt() || !e.Has("attributes") ||
        !e.Get("attributes").IsObject())
        return fail(r, PB_ERROR_PARSE, name + " lacks a bufferView or attributes");
    int view = e.Get("bufferView").GetNumberAsInt();
    if (view < 0 || view >= (int)m.bufferViews.size() || m.bufferViews[view].byteLength == 0)
        return fail(r, PB_ERROR_PARSE, name + " refers to missing or empty bufferView " + std::to_string(view));
    int indices = e.Has("pb_indices") && e.Get("pb_indices").IsInt() ? e.Get("pb_indices").GetNumberAsInt() : -1;
    if (indices < 0 || indices >= (int)m.accessors.size())
        return fail(r, PB_ERROR_PARSE, name + " needs an indices accessor");
    size_t len = m.bufferViews[view].byteLength;
    const unsigned char *src;
    pb_result res = view_span(r, view, 0, 1, len, len, name, &src);
    if (res != PB_OK)
        return res;
    pb_gltf::draco_mesh_ptr mesh;
    std::string why = pb_gltf::draco_decode(src, len, mesh);
    reader::decoded_accessor d;
    if (why.empty())
        why = pb_gltf::draco_indices(*mesh, m.accessors[indices].componentType, d.bytes, &d.count);
    if (!why.empty())
        return fail(r, PB_ERROR_PARSE, name + ": " + why);
    r.draco_accessors[indices] = std::move(d);
    *indices_out = indices;
    const tinygltf::Value &attrs = e.Get("attributes");
    for (const std::string &key : attrs.Keys()) {
        auto pa = prim.attributes.find(key);
        if (!attrs.Get(key).IsInt() || pa == prim.attributes.end() || pa->second < 0 ||
            pa->second >= (int)m.accessors.size())
            return fail(r, PB_ERROR_PARSE, name + ": attribute " + key + " has no accessor in the primitive");
        const tinygltf::Accessor &a = m.accessors[pa->second];
        why = pb_gltf::draco_attribute(*mesh, attrs.Get(key).GetNumberAsInt(), a.componentType,
                                       tinygltf::GetNumComponentsInType((uint32_t)a.type), d.bytes, &d.count);
        if (!why.empty())
            return fail(r, PB_ERROR_PARSE, name + ": " + key + ": " + why);
        r.draco_accessors[pa->second] = std::move(d);
    }
    return PB_OK;
}

// Vertex indices of accessor `index` (unsigned integers: the caller checked),
// each below `nv`. The plain case (a SCALAR in a bufferView, neither sparse
// nor normalized nor from Draco) is read straight into `order`, so a large
// scene's indices never pass through doubles (8 fresh bytes each); every
// other case goes through read_accessor. Either way, the same errors.
pb_result read_indices(reader &r, int index, size_t nv, index_array &order)
{
    const tinygltf::Model &m = r.m;
    const tinygltf::Accessor *a = index >= 0 && index < (int)m.accessors.size() ? &m.accessors[index] : nullptr;
    bool plain = a && a->type == TINYGLTF_TYPE_SCALAR && !a->normalized && !a->sparse.isSparse &&
                 a->bufferView >= 0 && a->count > 0 && r.draco_accessors.find(index) == r.draco_accessors.end();
    size_t elem = a ? (size_t)tinygltf::GetComponentSizeInBytes((uint32_t)a->componentType) : 0;
    size_t stride = plain && a->bufferView < (int)m.bufferViews.size() && m.bufferViews[a->bufferView].byteStride
                        ? m.bufferViews[a->bufferView].byteStride
                        : elem;
    std::string range_error = " in accessor " + std::to_string(index) + " is out of range (" + std::to_string(nv) +
                              " vertices)";
    if (plain && (elem == 1 || elem == 2 || elem == 4) && stride >= elem) {
        const unsigned char *base;
        pb_result res = view_span(r, a->bufferView, a->byteOffset, a->count, elem, stride,
                                  "index accessor " + std::to_string(index), &base);
        if (res != PB_OK)
            return res;
        order.resize(a->count);
        for (size_t i = 0; i < a->count; ++i) {
            const unsigned char *p = base + i * stride;
            uint16_t s;
            uint32_t v;
            if (elem == 1)
                v = p[0];
            else if (elem == 2)
                memcpy(&s, p, 2), v = s;
            else
                memcpy(&v, p, 4);
            if (v >= nv)
                return fail(r, PB_ERROR_PARSE, "index " + std::to_string(v) + range_error);
            order[i] = v;
        }
        return PB_OK;
    }
    double_array idx;
    pb_result res = read_accessor(r, index, 1, idx, "index");
    if (res != PB_OK)
        return res;
    order.resize(idx.size());
    for (size_t i = 0; i < idx.size(); ++i) {
        if (idx[i] >= (double)nv)
            return fail(r, PB_ERROR_PARSE, "index " + std::to_string((uint64_t)idx[i]) + range_error);
        order[i] = (uint32_t)idx[i];
    }
    return PB_OK;
}

// A primitive's triangles, assembled on all host cores: each writes its own
// slot of the scene builder (pb_sb_put_triangle), and pb_sb_commit drops
// the non-finite ones in order afterwards, so the arrays do not depend on
// the threads. On a large mesh most of this is the first touch of the
// builder's fresh pages, which the kernel clears on the touching core.
struct triangle_job {
    pb_scene_builder *b;
    const double *world; // mat4, column-major
    double nm[9];        // normal matrix (cofactors), column-major
    double det;
    const uint32_t *tris; // vertex-index triples
    const double *pos, *nrm, *uv, *col, *tan; // nrm, uv, col, tan: NULL when absent
    int col_n;
    const double *uv_transform; // 6: the material's texture transform
    uint32_t material;
    bool vertex_normals;
    uint64_t first; // the builder's slot of triangle 0
    unsigned char *keep; // what pb_sb_put_triangle returned for each
};

const uint64_t TRIANGLE_GRAIN = 16384;

void put_triangles(void *user, uint64_t begin, uint64_t end)
{
    triangle_job &j = *static_cast<triangle_job *>(user);
    bool flip = j.det < 0; // mirrored transform: glTF says reverse the winding
    const double *nm = j.nm, *x = j.uv_transform;
    for (uint64_t t = begin; t < end; ++t) {
        double p[9];
        float n[9], tc[6], rgba[12], tn[12];
        for (int k = 0; k < 3; ++k) {
            uint32_t v = j.tris[3 * t + (flip && k ? 3 - k : k)];
            xform_point(j.world, &j.pos[3 * v], &p[3 * k]);
            if (j.nrm) {
                const double *vn = &j.nrm[3 * v];
                double wn[3];
                wn[0] = nm[0] * vn[0] + nm[3] * vn[1] + nm[6] * vn[2];
                wn[1] = nm[1] * vn[0] + nm[4] * vn[1] + nm[7] * vn[2];
                wn[2] = nm[2] * vn[0] + nm[5] * vn[1] + nm[8] * vn[2];
                if (flip)
                    wn[0] = -wn[0], wn[1] = -wn[1], wn[2] = -wn[2]; // cofactors of a mirror point inward
                for (int c = 0; c < 3; ++c)
                    n[3 * k + c] = (float)wn[c];
            }
            double u0 = j.uv ? j.uv[2 * v] : 0.0, v0 = j.uv ? j.uv[2 * v + 1] : 0.0;
            tc[2 * k] = (float)(x[0] * u0 + x[1] * v0 + x[2]);
            tc[2 * k + 1] = (float)(x[3] * u0 + x[4] * v0 + x[5]);
            for (int c = 0; c < 4 && j.col_n; ++c)
                rgba[4 * k + c] = c < j.col_n ? (float)j.col[(size_t)j.col_n * v + c] : 1.f;
            if (j.tan) { // a direction along the surface: the world matrix itself; a mirror turns the handedness
                const double *vt = &j.tan[4 * v], *w = j.world;
                for (int c = 0; c < 3; ++c)
                    tn[4 * k + c] = (float)(w[c] * vt[0] + w[4 + c] * vt[1] + w[8 + c] * vt[2]);
                tn[4 * k + 3] = (float)(flip ? -vt[3] : vt[3]);
            }
        }
        j.keep[t] = (unsigned char)pb_sb_put_triangle(j.b, j.first + t, p, j.vertex_normals ? n : nullptr, tc,
                                                      j.col_n ? rgba : nullptr, j.tan ? tn : nullptr, j.material);
    }
}

pb_result read_primitive(reader &r, const tinygltf::Primitive &prim, const mat4 world, const char *mesh_name)
{
    // the builder refused something already (the default material's index
    // is then -1): nothing more to read
    if (r.b->out_of_memory)
        return fail(r, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    r.b->stats.primitives++;
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        prim.mode != TINYGLTF_MODE_TRIANGLE_FAN && prim.mode != -1) {
        r.b->stats.primitives_skipped++;
        return PB_OK;
    }
    r.draco_accessors.clear();
    int indices = prim.indices;
    auto draco = prim.extensions.find("KHR_draco_mesh_compression");
    if (draco != prim.extensions.end()) {
        pb_result res = decode_draco(r, prim, draco->second, mesh_name, &indices);
        if (res != PB_OK)
            return res;
    }
    auto pos_it = prim.attributes.find("POSITION");
    if (pos_it == prim.attributes.end()) {
        pb_logf(&r.b->log, PB_LOG_WARN, "%s: a primitive of mesh '%s' has no POSITION; skipped", r.path, mesh_name);
        r.b->stats.primitives_skipped++;
        return PB_OK;
    }
    double_array pos, nrm, uv;
    pb_result res = read_accessor(r, pos_it->second, 3, pos, "POSITION");
    if (res != PB_OK)
        return res;
    size_t nv = pos.size() / 3;
    auto nit = prim.attributes.find("NORMAL");
    bool have_n = nit != prim.attributes.end();
    if (have_n && (res = read_accessor(r, nit->second, 3, nrm, "NORMAL")) != PB_OK)
        return res;
    if (have_n && nrm.size() != pos.size())
        return fail(r, PB_ERROR_PARSE, "NORMAL and POSITION accessors of mesh '" + std::string(mesh_name) + "' differ in count");
    if (!have_n)
        r.b->stats.normals_generated++;
    auto tit = prim.attributes.find("TEXCOORD_0");
    bool have_uv = tit != prim.attributes.end();
    if (have_uv && (res = read_accessor(r, tit->second, 2, uv, "TEXCOORD_0")) != PB_OK)
        return res;
    if (have_uv && uv.size() / 2 != nv)
        return fail(r, PB_ERROR_PARSE, "TEXCOORD_0 and POSITION accessors of mesh '" + std::string(mesh_name) + "' differ in count");
    // COLOR_0 (linear RGB or RGBA) multiplies the base colour, glTF's rule
    double_array col;
    int col_n = 0;
    auto cit = prim.attributes.find("COLOR_0");
    if (cit != prim.attributes.end()) {
        col_n = cit->second >= 0 && cit->second < (int)r.m.accessors.size() &&
                        r.m.accessors[cit->second].type == TINYGLTF_TYPE_VEC4 ? 4 : 3;
        if ((res = read_accessor(r, cit->second, col_n, col, "COLOR_0")) != PB_OK)
            return res;
        if (col.size() / col_n != nv)
            return fail(r, PB_ERROR_PARSE, "COLOR_0 and POSITION accessors of mesh '" + std::string(mesh_name) +
                                               "' differ in count");
    }
    index_array order; // vertex indices, before triangle assembly
    if (indices >= 0) {
        const tinygltf::Accessor *ia = indices < (int)r.m.accessors.size() ? &r.m.accessors[indices] : nullptr;
        if (ia && ia->componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            ia->componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            ia->componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            return fail(r, PB_ERROR_PARSE, "index accessor " + std::to_string(indices) + " is not unsigned integer");
        if ((res = read_indices(r, indices, nv, order)) != PB_OK)
            return res;
    } else {
        order.resize(nv);
        for (size_t i = 0; i < nv; ++i)
            order[i] = (uint32_t)i;
    }
    // assemble triangles as vertex-index triples
    index_array tris;
    int mode = prim.mode == -1 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
    if (mode == TINYGLTF_MODE_TRIANGLES) {
        order.resize((order.size() / 3) * 3);
        tris.swap(order);
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t i = 0; i + 2 < order.size(); ++i) { // odd triangles swap to keep the winding
            bool odd = i & 1;
            tris.insert(tris.end(), {order[i], order[odd ? i + 2 : i + 1], order[odd ? i + 1 : i + 2]});
        }
    } else {
        for (size_t i = 1; i + 1 < order.size(); ++i)
            tris.insert(tris.end(), {order[i], order[i + 1], order[0]});
    }
    uint32_t material = r.default_material;
    if (prim.material >= 0) {
        if (prim.material >= (int)r.m.materials.size())
            return fail(r, PB_ERROR_PARSE, "mesh '" + std::string(mesh_name) + "' refers to missing material " +
                                               std::to_string(prim.material));
        material = (uint32_t)prim.material;
    }
    // TANGENT, where the material's normal map reads it (else its frame comes
    // from the texture coordinates: docs/bake.md, "Normal maps")
    double_array tan;
    auto ait = prim.attributes.find("TANGENT");
    bool have_t = ait != prim.attributes.end() && material < r.b->material_count &&
                  r.b->materials[material].normal_texture >= 0;
    if (have_t && (res = read_accessor(r, ait->second, 4, tan, "TANGENT")) != PB_OK)
        return res;
    if (have_t && tan.size() / 4 != nv)
        return fail(r, PB_ERROR_PARSE, "TANGENT and POSITION accessors of mesh '" + std::string(mesh_name) +
                                           "' differ in count");
    triangle_job job;
    job.b = r.b;
    job.world = world;
    job.det = normal_matrix(world, job.nm);
    job.tris = tris.data();
    job.pos = pos.data(), job.nrm = have_n ? nrm.data() : nullptr, job.uv = have_uv ? uv.data() : nullptr;
    job.col = col_n ? col.data() : nullptr;
    job.tan = have_t ? tan.data() : nullptr;
    job.col_n = col_n;
    job.uv_transform = r.uv_transform[material].data();
    job.material = material;
    job.vertex_normals = have_n && !r.face_normals;
    uint64_t n = tris.size() / 3;
    std::unique_ptr<unsigned char[]> keep(new (std::nothrow) unsigned char[n ? n : 1]);
    if (!keep || !pb_sb_reserve(r.b, n, col_n != 0, have_t))
        return fail(r, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    job.first = r.b->count;
    job.keep = keep.get();
    pb_parallel_for(n, TRIANGLE_GRAIN, 0, put_triangles, &job);
    pb_sb_commit(r.b, n, keep.get());
    return PB_OK;
}

// More triangles than this after instancing (nodes or EXT_mesh_gpu_instancing)
// is refused: a small file can instance a large mesh millions of times.
const uint64_t PB_GLTF_MAX_TRIANGLES = uint64_t(1) << 28;

pb_result triangles_bounded(reader &r)
{
    if (r.b->stats.triangles_in <= PB_GLTF_MAX_TRIANGLES)
        return PB_OK;
    return fail(r, PB_ERROR_PARSE, "more than " + std::to_string(PB_GLTF_MAX_TRIANGLES) +
                                       " triangles after instancing: refused");
}

// Every primitive of a mesh at `world`, the triangle bound checked after each.
pb_result read_mesh(reader &r, const tinygltf::Mesh &mesh, const mat4 world)
{
    for (const tinygltf::Primitive &p : mesh.primitives) {
        pb_result res = read_primitive(r, p, world, mesh.name.c_str());
        if (res == PB_OK)
            res = triangles_bounded(r);
        if (res != PB_OK)
            return res;
    }
    return PB_OK;
}

// EXT_mesh_gpu_instancing: the node's mesh once per instance, at the node's
// world transform x the instance's TRANSLATION x ROTATION x SCALE (each
// optional; float, or normalized integers for ROTATION as the extension
// allows). The node's children are not instanced.
pb_result read_instances(reader &r, int node_index, const tinygltf::Value &ext, const mat4 world,
                         const tinygltf::Mesh &mesh)
{
    std::string where = "node " + std::to_string(node_index) + " (EXT_mesh_gpu_instancing)";
    if (!ext.IsObject() || !ext.Has("attributes") || !ext.Get("attributes").IsObject())
        return fail(r, PB_ERROR_PARSE, where + " has no TRANSLATION, ROTATION or SCALE");
    const tinygltf::Value &at = ext.Get("attributes");
    static const char *const names[3] = {"TRANSLATION", "ROTATION", "SCALE"};
    const int comps[3] = {3, 4, 3};
    int acc[3] = {-1, -1, -1};
    size_t count = 0;
    bool any = false;
    for (int k = 0; k < 3; ++k) {
        if (!at.Has(names[k]))
            continue;
        acc[k] = at.Get(names[k]).IsInt() ? at.Get(names[k]).GetNumberAsInt() : -1;
        if (acc[k] < 0 || acc[k] >= (int)r.m.accessors.size())
            return fail(r, PB_ERROR_PARSE, where + ": " + names[k] + " is not an accessor");
        size_t n = r.m.accessors[(size_t)acc[k]].count;
        if (any && n != count)
            return fail(r, PB_ERROR_PARSE, where + ": its accessors differ in count");
        count = n, any = true;
    }
    if (!any)
        return fail(r, PB_ERROR_PARSE, where + " has no TRANSLATION, ROTATION or SCALE");
    // the triangles the instances would add, from the accessors' declared
    // counts, before anything is read or allocated
    uint64_t per = 0;
    for (const tinygltf::Primitive &p : mesh.primitives) {
        auto pos = p.attributes.find("POSITION");
        int a = p.indices >= 0 ? p.indices : pos != p.attributes.end() ? pos->second : -1;
        uint64_t n = a >= 0 && a < (int)r.m.accessors.size() ? r.m.accessors[(size_t)a].count : 0;
        per += p.mode == TINYGLTF_MODE_TRIANGLE_STRIP || p.mode == TINYGLTF_MODE_TRIANGLE_FAN ? (n > 2 ? n - 2 : 0)
                                                                                               : n / 3;
    }
    if (per && (uint64_t)count > (PB_GLTF_MAX_TRIANGLES - r.b->stats.triangles_in) / per)
        return fail(r, PB_ERROR_PARSE, where + ": " + std::to_string(count) + " instances of " + std::to_string(per) +
                                           " triangles: more than " + std::to_string(PB_GLTF_MAX_TRIANGLES) +
                                           " triangles in all, refused");
    double_array v[3];
    for (int k = 0; k < 3; ++k)
        if (acc[k] >= 0) {
            pb_result res = read_accessor(r, acc[k], comps[k], v[k], names[k]);
            if (res != PB_OK)
                return res;
        }
    for (size_t i = 0; i < count; ++i) {
        double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
        for (int c = 0; c < 3 && !v[0].empty(); ++c)
            t[c] = v[0][3 * i + c];
        for (int c = 0; c < 4 && !v[1].empty(); ++c)
            q[c] = v[1][4 * i + c];
        for (int c = 0; c < 3 && !v[2].empty(); ++c)
            s[c] = v[2][3 * i + c];
        mat4 inst, w;
        trs_matrix(t, q, s, inst);
        mat_mul(world, inst, w);
        pb_result res = read_mesh(r, mesh, w);
        if (res != PB_OK)
            return res;
    }
    return PB_OK;
}

pb_result visit(reader &r, int node_index, const mat4 parent, int depth)
{
    const tinygltf::Model &m = r.m;
    if (node_index < 0 || node_index >= (int)m.nodes.size())
        return fail(r, PB_ERROR_PARSE, "node " + std::to_string(node_index) + " does not exist");
    if (depth > 1024 || r.b->stats.nodes > 16u * (uint32_t)m.nodes.size() + 16u)
        return fail(r, PB_ERROR_PARSE, "node hierarchy is cyclic or deeper than 1024 levels (at node " +
                                           std::to_string(node_index) + ")");
    r.b->stats.nodes++;
    const tinygltf::Node &n = m.nodes[node_index];
    mat4 local, world;
    node_local(n, local);
    mat_mul(parent, local, world);
    if (n.mesh >= 0) {
        if (n.mesh >= (int)m.meshes.size())
            return fail(r, PB_ERROR_PARSE, "node " + std::to_string(node_index) + " refers to missing mesh " +
                                               std::to_string(n.mesh));
        const tinygltf::Mesh &mesh = m.meshes[n.mesh];
        auto inst = n.extensions.find("EXT_mesh_gpu_instancing");
        if (inst != n.extensions.end()) {
            pb_result res = read_instances(r, node_index, inst->second, world, mesh);
            if (res != PB_OK)
                return res;
        } else {
            pb_result res = read_mesh(r, mesh, world);
            if (res != PB_OK)
                return res;
        }
    }
    const double origin[3] = {0, 0, 0}, neg_z[3] = {0, 0, -1}, pos_y[3] = {0, 1, 0};
    double wp[3], wf[3], wu[3];
    xform_point(world, origin, wp);
    xform_dir(world, neg_z, wf);
    xform_dir(world, pos_y, wu);
    if (n.camera >= 0 && n.camera < (int)m.cameras.size()) {
        const tinygltf::Camera &c = m.cameras[n.camera];
        pb_camera pc;
        memset(&pc, 0, sizeof pc);
        snprintf(pc.name, sizeof pc.name, "%s", c.name.c_str());
        pc.perspective = c.type != "orthographic";
        if (pc.perspective) {
            pc.yfov = (float)c.perspective.yfov;
            pc.aspect = (float)c.perspective.aspectRatio;
            pc.znear = (float)c.perspective.znear;
            pc.zfar = (float)c.perspective.zfar;
        } else {
            pc.xmag = (float)c.orthographic.xmag;
            pc.ymag = (float)c.orthographic.ymag;
            pc.znear = (float)c.orthographic.znear;
            pc.zfar = (float)c.orthographic.zfar;
        }
        pb_sb_add_camera(r.b, &pc, wp, wf, wu);
    }
    auto le = n.extensions.find("KHR_lights_punctual");
    if (le != n.extensions.end() && le->second.Has("light")) {
        int li = le->second.Get("light").GetNumberAsInt();
        if (li < 0 || li >= (int)m.lights.size())
            return fail(r, PB_ERROR_PARSE, "node " + std::to_string(node_index) + " refers to missing light " +
                                               std::to_string(li));
        const tinygltf::Light &l = m.lights[li];
        pb_light pl;
        memset(&pl, 0, sizeof pl);
        snprintf(pl.name, sizeof pl.name, "%s", l.name.c_str());
        pl.type = l.type == "directional" ? PB_LIGHT_DIRECTIONAL : l.type == "spot" ? PB_LIGHT_SPOT : PB_LIGHT_POINT;
        if (l.type != "directional" && l.type != "spot" && l.type != "point")
            return fail(r, PB_ERROR_PARSE, "light " + std::to_string(li) + " has unknown type '" + l.type + "'");
        for (int k = 0; k < 3; ++k)
            pl.color[k] = k < (int)l.color.size() ? (float)l.color[k] : 1.f;
        pl.intensity = (float)l.intensity;
        pl.range = (float)l.range;
        pl.inner_cone = (float)l.spot.innerConeAngle;
        pl.outer_cone = (float)l.spot.outerConeAngle;
        pb_sb_add_light(r.b, &pl, wp, wf);
    }
    for (int c : n.children) {
        pb_result res = visit(r, c, world, depth + 1);
        if (res != PB_OK)
            return res;
    }
    return PB_OK;
}

std::string first_line(const std::string &s)
{
    std::string t = s.substr(0, s.find('\n'));
    while (!t.empty() && (t.back() == ' ' || t.back() == '\r'))
        t.pop_back();
    return t;
}


// Deepest nesting of [ and { in JSON text (strings skipped), stopping early
// once past `limit`.
int json_nesting(const unsigned char *s, size_t n, int limit)
{
    int depth = 0, deepest = 0;
    bool in_string = false;
    for (size_t i = 0; i < n && deepest <= limit; ++i) {
        unsigned char c = s[i];
        if (in_string) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            deepest = ++depth > deepest ? depth : deepest;
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
    return deepest;
}

// The JSON of a file: all of a .gltf, the first chunk of a .glb (when its
// header says so; tinygltf judges the rest).
void json_part(const unsigned char *bytes, size_t n, bool glb, size_t *begin, size_t *len)
{
    *begin = 0, *len = n;
    if (glb && n >= 20) {
        uint32_t chunk;
        memcpy(&chunk, bytes + 12, 4);
        *begin = 20;
        *len = chunk <= n - 20 ? chunk : n - 20;
    }
}

// The extension object of `o` named `name`, or null.
nlohmann::json *extension(nlohmann::json &o, const char *name)
{
    if (!o.is_object() || !o.contains("extensions") || !o["extensions"].is_object() ||
        !o["extensions"].contains(name) || !o["extensions"][name].is_object())
        return nullptr;
    return &o["extensions"][name];
}

// Compressed files that tinygltf 2.7 (built without Draco) would refuse,
// edited in their JSON before it parses them (false: nothing to edit):
// - EXT_meshopt_compression may mark a buffer `fallback`: it has no bytes
//   (no uri, or more than a GLB's BIN chunk holds) and is read only through
//   decoded views. tinygltf would refuse it or hand it the BIN chunk, so it
//   becomes a 1-byte data URI; view_span refuses any uncompressed view that
//   still points into it.
// - A KHR_draco_mesh_compression primitive's indices accessor has no
//   bufferView, which tinygltf refuses; `indices` moves into the extension
//   object (as "pb_indices"), where decode_draco finds it.
bool patch_for_tinygltf(const unsigned char *bytes, size_t n, bool glb, std::vector<unsigned char> &out)
{
    size_t jb, jl;
    json_part(bytes, n, glb, &jb, &jl);
    std::string text((const char *)bytes + jb, jl);
    if (text.find("\"fallback\"") == std::string::npos && text.find("KHR_draco_mesh_compression") == std::string::npos)
        return false;
    nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object())
        return false; // tinygltf reports what is wrong
    bool changed = false;
    if (j.contains("buffers") && j["buffers"].is_array())
        for (nlohmann::json &buf : j["buffers"]) {
            nlohmann::json *mo = extension(buf, "EXT_meshopt_compression");
            if (!mo || buf.contains("uri") || mo->value("fallback", false) != true)
                continue;
            buf["uri"] = "data:application/octet-stream;base64,AA==";
            buf["byteLength"] = 1;
            changed = true;
        }
    if (j.contains("meshes") && j["meshes"].is_array())
        for (nlohmann::json &mesh : j["meshes"]) {
            if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
                continue;
            for (nlohmann::json &prim : mesh["primitives"]) {
                nlohmann::json *dr = extension(prim, "KHR_draco_mesh_compression");
                if (!dr || !prim.contains("indices"))
                    continue;
                (*dr)["pb_indices"] = prim["indices"];
                prim.erase("indices");
                changed = true;
            }
        }
    if (!changed)
        return false;
    std::string json = j.dump();
    if (!glb) {
        out.assign(json.begin(), json.end());
        return true;
    }
    while (json.size() % 4) // GLB chunks are 4-byte aligned, JSON padded with spaces
        json += ' ';
    size_t rest = jb + jl; // the chunks after JSON (BIN), unchanged
    uint32_t total = (uint32_t)(12 + 8 + json.size() + (n - rest)), chunk = (uint32_t)json.size(), type = 0x4E4F534Au;
    out.assign(bytes, bytes + 8); // magic and version
    out.insert(out.end(), (unsigned char *)&total, (unsigned char *)&total + 4);
    out.insert(out.end(), (unsigned char *)&chunk, (unsigned char *)&chunk + 4);
    out.insert(out.end(), (unsigned char *)&type, (unsigned char *)&type + 4);
    out.insert(out.end(), json.begin(), json.end());
    out.insert(out.end(), bytes + rest, bytes + n);
    return true;
}

// tinygltf's file access for external buffers and images: regular files only
// (a FIFO would hang, a directory reads as LONG_MAX bytes), sizes bounded.
bool fs_exists(const std::string &path, void *)
{
    struct stat st;
    return stat(path.c_str(), &st) == 0;
}

std::string fs_expand(const std::string &path, void *)
{
    return path; // no shell expansion of names found in files
}

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *)
{
    unsigned char *bytes = nullptr;
    uint64_t size = 0;
    pb_error e;
    if (pb_input_read(path.c_str(), UINT32_MAX, &bytes, &size, &e) != PB_OK) {
        if (err)
            *err += std::string(e.message) + "\n";
        return false;
    }
    out->clear();
    out->reserve((size_t)size); /* fresh storage, advised before the copy touches it */
    pb_advise_huge(out->data(), out->capacity());
    out->assign(bytes, bytes + size);
    free(bytes);
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    if (err)
        *err += "probebake never writes glTF files\n";
    return false;
}

pb_result gltf_read(const char *path, const pb_scene_desc *desc, pb_scene_builder *b, pb_error *err)
{
    unsigned char *bytes = nullptr;
    uint64_t size = 0;
    // regular files only; tinygltf takes 32-bit lengths
    pb_result res = pb_input_read(path, UINT32_MAX, &bytes, &size, err);
    if (res != PB_OK)
        return res;
    std::unique_ptr<unsigned char, void (*)(void *)> owned(bytes, free);
    if (size == 0)
        return pb_fail(err, PB_ERROR_PARSE, "%s: file is empty", path);
    bool glb = size >= 4 && memcmp(bytes, "glTF", 4) == 0;
    size_t jb, jl;
    json_part(bytes, (size_t)size, glb, &jb, &jl);
    if (json_nesting(bytes + jb, jl, PB_GLTF_MAX_NESTING) > PB_GLTF_MAX_NESTING)
        return pb_fail(err, PB_ERROR_PARSE, "%s: JSON nested deeper than %d levels", path, PB_GLTF_MAX_NESTING);

    tinygltf::TinyGLTF loader;
    tinygltf::Model model;
    pb_gltf::image_ctx ictx = {path, b->log, desc->skip_textures ? 1 : 0, desc->max_texture_pixels,
                      desc->max_texture_total_pixels, &model, {}, {}, desc->decode_ahead};
    loader.SetImageLoader(pb_gltf::load_image, &ictx);
    tinygltf::FsCallbacks fs = {fs_exists, fs_expand, fs_read, fs_write, nullptr};
    loader.SetFsCallbacks(fs);
    std::string p(path), base = p.find('/') == std::string::npos ? std::string(".") : p.substr(0, p.rfind('/'));
    if (base.empty())
        base = "/";
    std::vector<unsigned char> patched;
    if (patch_for_tinygltf(bytes, (size_t)size, glb, patched)) {
        if (patched.size() > UINT32_MAX)
            return pb_fail(err, PB_ERROR_PARSE, "%s: file too large", path);
        bytes = patched.data(), size = patched.size();
    }
    std::string gerr, gwarn;
    bool ok = false;
    const char *thrown = nullptr; /* what escaped tinygltf, if anything */
    bool no_memory = false;
    std::terminate_handler before = std::set_terminate(tinygltf_terminated);
    tinygltf_reading = path;
    try {
        ok = glb ? loader.LoadBinaryFromMemory(&model, &gerr, &gwarn, bytes, (unsigned)size, base)
                 : loader.LoadASCIIFromString(&model, &gerr, &gwarn, (const char *)bytes, (unsigned)size, base);
    } catch (const std::bad_alloc &) {
        no_memory = true;
    } catch (const std::exception &e) { // nlohmann throws on some malformed input
        gerr = e.what(), thrown = gerr.c_str();
    }
    tinygltf_reading = nullptr;
    std::set_terminate(before);
    /* tinygltf catches some exceptions itself and returns their what() as its error */
    if (no_memory || (!ok && !thrown && gerr.find("bad_alloc") != std::string::npos))
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory while tinygltf read it", path);
    if (thrown)
        return pb_fail(err, PB_ERROR_PARSE, "%s: malformed glTF: %s", path, thrown);
    if (!ok) {
        std::string msg = first_line(gerr.empty() ? gwarn : gerr);
        pb_result code = PB_ERROR_PARSE;
        bool data_uri = msg.find("data:") != std::string::npos;
        if (!data_uri &&
            (msg.find("File not found") != std::string::npos || msg.find("Failed to load external") != std::string::npos))
            code = PB_ERROR_IO;
        if (data_uri)
            msg = "invalid embedded (data URI) buffer or image: " + msg;
        return pb_fail(err, code, "%s: %s", path, msg.empty() ? "not a valid glTF file" : msg.c_str());
    }
    if (!gwarn.empty())
        pb_logf(&b->log, PB_LOG_DEBUG, "%s: tinygltf: %s", path, first_line(gwarn).c_str());

    static const char *const supported[] = {"EXT_mesh_gpu_instancing", "EXT_meshopt_compression", "EXT_texture_avif",
                                            "EXT_texture_webp",
                                            "KHR_draco_mesh_compression", "KHR_materials_transmission",
                                            "KHR_lights_punctual", "KHR_materials_emissive_strength",
                                            "KHR_materials_pbrSpecularGlossiness", "KHR_materials_unlit",
                                            "KHR_mesh_quantization", "KHR_texture_basisu", "KHR_texture_transform"};
    for (const std::string &ext : model.extensionsRequired) {
        bool known = false;
        for (const char *s : supported)
            known |= ext == s;
        if (!known)
            return pb_fail(err, PB_ERROR_UNSUPPORTED, "%s: requires extension %s, which probebake does not support",
                           path, ext.c_str());
    }
    std::string used, applied;
    for (const std::string &ext : model.extensionsUsed) {
        bool known = false;
        for (const char *s : supported)
            known |= ext == s;
        if (!known)
            pb_logf(&b->log, PB_LOG_INFO, "%s: extension %s is used but not supported; ignored", path, ext.c_str());
        used += (used.empty() ? "" : ", ") + ext;
        if (known)
            applied += (applied.empty() ? "" : ", ") + ext;
    }
    snprintf(b->stats.extensions_used, sizeof b->stats.extensions_used, "%s", used.c_str());
    snprintf(b->stats.extensions_applied, sizeof b->stats.extensions_applied, "%s", applied.c_str());

    reader r{model, path, b, err, {}, 0, {}, {}, {}, {}, {}, desc->face_normals != 0, &ictx};
    r.no_normal_maps = desc->no_normal_maps != 0;
    res = decode_meshopt_views(r);
    if (res != PB_OK)
        return res;
    res = read_textures(r, desc->skip_textures);
    if (res != PB_OK)
        return res;
    read_materials(r);
    pb_gltf::release_images(&ictx); // the scene holds what the bake reads: free the rest before the meshes
    if (model.scenes.empty()) {
        if (!model.nodes.empty())
            pb_logf(&b->log, PB_LOG_WARN, "%s: no scene defined; nothing to load", path);
        return b->out_of_memory ? pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path) : PB_OK;
    }
    int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
    if (scene >= (int)model.scenes.size())
        return pb_fail(err, PB_ERROR_PARSE, "%s: default scene %d does not exist", path, scene);
    mat4 id;
    mat_identity(id);
    for (int n : model.scenes[scene].nodes) {
        res = visit(r, n, id, 0);
        if (res != PB_OK)
            return res;
    }
    if (b->out_of_memory)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    return PB_OK;
}

} // namespace

// No exception leaves this file: each becomes the one-line error.
extern "C" pb_result pb_gltf_read(const char *path, const pb_scene_desc *desc, pb_scene_builder *b, pb_error *err)
{
    try {
        return gltf_read(path, desc, b, err);
    } catch (const std::bad_alloc &) {
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory reading the file", path);
    } catch (const std::exception &e) {
        return pb_fail(err, PB_ERROR_PARSE, "%s: malformed glTF: %s", path, e.what());
    } catch (...) {
        return pb_fail(err, PB_ERROR_PARSE, "%s: malformed glTF", path);
    }
}
