// Compressed glTF geometry, decoded by the libraries that define the codecs
// (meshoptimizer for EXT_meshopt_compression, Draco for
// KHR_draco_mesh_compression); nothing here parses glTF. Each function takes
// bytes the loader has already bounds-checked, checks every size it hands a
// codec (their asserts are compiled out in Debian's builds), and returns ""
// or a one-phrase reason for the loader's one-line error.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pb_gltf {

// Largest decoded size the loader accepts per compressed byte of an
// EXT_meshopt_compression view. meshoptimizer 0.18's densest streams stay
// well below it (measured, 2^20 elements encoded by the library: an
// all-zero 16-byte vertex stream 64x, a 32-bit triangle list 6x, an index
// sequence 4x); a view claiming more is corrupt, and is refused before the
// claim is allocated. (Draco streams size themselves inside libdraco.)
constexpr size_t max_expansion = 256;

// EXT_meshopt_compression bufferView: `count` elements of `stride` bytes
// decoded from `src` with mode ATTRIBUTES / TRIANGLES / INDICES and filter
// NONE / OCTAHEDRAL / QUATERNION / EXPONENTIAL.
std::string meshopt_decode(const unsigned char *src, size_t src_len, size_t count, size_t stride,
                           const std::string &mode, const std::string &filter, std::vector<unsigned char> &out);

// A decoded Draco mesh, handed back as the plain arrays an uncompressed
// file would hold: a triangle list and, per attribute unique id, its values
// tightly packed in the glTF component type of the accessor that names it
// (the accessor, normalized flag included, then reads them as usual).
struct draco_mesh;
struct draco_mesh_deleter {
    void operator()(draco_mesh *) const;
};
using draco_mesh_ptr = std::unique_ptr<draco_mesh, draco_mesh_deleter>;

std::string draco_decode(const unsigned char *src, size_t src_len, draco_mesh_ptr &out);
// the triangle list as `component_type` (5121 / 5123 / 5125) indices
std::string draco_indices(const draco_mesh &m, int component_type, std::vector<unsigned char> &out, size_t *count);
// attribute `unique_id`, `components` per point, as `component_type`
std::string draco_attribute(const draco_mesh &m, int unique_id, int component_type, int components,
                            std::vector<unsigned char> &out, size_t *count);

} // namespace pb_gltf
