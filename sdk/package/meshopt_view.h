// EXT_meshopt_compression bufferViews: the byte-level encode and decode of
// one compressed view (meshoptimizer's vertex and index codecs and its
// decode filters), with every constraint of the extension checked.
//
// Spec: github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Vendor/EXT_meshopt_compression
// ("JSON schema updates" for the constraints, Appendix B for the filters).
// Why a second codec beside Draco: decision 0009 (meshoptimizer's decoders
// take a twentieth of Draco's time on our block levels; with the GLB reader
// around them a block level costs 0.43x).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace blvd::package {

enum class MeshoptMode { Attributes, Triangles, Indices };
enum class MeshoptFilter { None, Octahedral, Quaternion, Exponential };

// The extension object of one bufferView, already read from the JSON.
struct MeshoptView {
  MeshoptMode mode = MeshoptMode::Attributes;
  MeshoptFilter filter = MeshoptFilter::None;
  uint64_t count = 0;   // elements
  uint64_t stride = 0;  // bytes per element
};

// The extension's names ("ATTRIBUTES", "OCTAHEDRAL", ...); false for an
// unknown name.
bool parseMeshoptMode(const std::string& name, MeshoptMode& out);
bool parseMeshoptFilter(const std::string& name, MeshoptFilter& out);
const char* meshoptModeName(MeshoptMode m);
const char* meshoptFilterName(MeshoptFilter f);

// The most bytes one view may decode to per compressed byte. The attribute
// codec's densest case is a 2-bit header per 16 zero deltas (64x), the index
// codec's is one byte per triangle (12x for 32-bit indices); a view claiming
// more is corrupt, and the cap keeps a few bytes of input from asking for
// gigabytes.
inline constexpr uint64_t kMeshoptMaxExpansion = 80;

// Decodes `size` compressed bytes as `view` says into `out` (resized to
// count * stride, then filtered in place). Checks the extension's
// constraints (stride per mode and filter, count % 3 for TRIANGLES) and the
// expansion cap first; returns Corrupt with `err` saying which failed, or
// what the codec reported. Never reads outside [data, data + size).
core::Status decodeMeshoptView(const uint8_t* data, size_t size, const MeshoptView& view, std::vector<uint8_t>& out,
                               std::string& err);

// The codecs, as a writer uses them: `vertices` holds count elements of
// `stride` bytes (stride % 4 == 0, <= 256); `indices` holds a triangle list
// (count % 3 == 0) of indices < vertex_count; one encoding decodes to 2- or
// 4-byte indices alike. Throws core::Error(InvalidArg) on arguments the
// codec cannot take.
std::vector<uint8_t> encodeMeshoptAttributes(const void* vertices, size_t count, size_t stride);
std::vector<uint8_t> encodeMeshoptTriangles(const uint32_t* indices, size_t count, size_t vertex_count);

}  // namespace blvd::package
