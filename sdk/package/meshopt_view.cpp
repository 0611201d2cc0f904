#include "package/meshopt_view.h"

#include <meshoptimizer.h>

#include "core/status.h"

namespace blvd::package {

using core::Status;

bool parseMeshoptMode(const std::string& name, MeshoptMode& out) {
  if (name == "ATTRIBUTES") out = MeshoptMode::Attributes;
  else if (name == "TRIANGLES") out = MeshoptMode::Triangles;
  else if (name == "INDICES") out = MeshoptMode::Indices;
  else return false;
  return true;
}

bool parseMeshoptFilter(const std::string& name, MeshoptFilter& out) {
  if (name == "NONE") out = MeshoptFilter::None;
  else if (name == "OCTAHEDRAL") out = MeshoptFilter::Octahedral;
  else if (name == "QUATERNION") out = MeshoptFilter::Quaternion;
  else if (name == "EXPONENTIAL") out = MeshoptFilter::Exponential;
  else return false;
  return true;
}

const char* meshoptModeName(MeshoptMode m) {
  switch (m) {
    case MeshoptMode::Attributes: return "ATTRIBUTES";
    case MeshoptMode::Triangles: return "TRIANGLES";
    case MeshoptMode::Indices: return "INDICES";
  }
  return "?";
}

const char* meshoptFilterName(MeshoptFilter f) {
  switch (f) {
    case MeshoptFilter::None: return "NONE";
    case MeshoptFilter::Octahedral: return "OCTAHEDRAL";
    case MeshoptFilter::Quaternion: return "QUATERNION";
    case MeshoptFilter::Exponential: return "EXPONENTIAL";
  }
  return "?";
}

namespace {

// The extension's validity rules ("JSON schema updates"), in its order.
const char* constraintBroken(const MeshoptView& v) {
  if (v.stride == 0) return "byteStride is 0";
  if (v.mode == MeshoptMode::Attributes && (v.stride % 4 || v.stride > 256))
    return "ATTRIBUTES needs a byteStride divisible by 4 and at most 256";
  if (v.mode == MeshoptMode::Triangles && v.count % 3) return "TRIANGLES needs a count divisible by 3";
  if (v.mode != MeshoptMode::Attributes && v.stride != 2 && v.stride != 4)
    return "TRIANGLES and INDICES need a byteStride of 2 or 4";
  if (v.mode != MeshoptMode::Attributes && v.filter != MeshoptFilter::None)
    return "TRIANGLES and INDICES take no filter";
  if (v.filter == MeshoptFilter::Octahedral && v.stride != 4 && v.stride != 8)
    return "OCTAHEDRAL needs a byteStride of 4 or 8";
  if (v.filter == MeshoptFilter::Quaternion && v.stride != 8) return "QUATERNION needs a byteStride of 8";
  if (v.filter == MeshoptFilter::Exponential && v.stride % 4) return "EXPONENTIAL needs a byteStride divisible by 4";
  return nullptr;
}

}  // namespace

Status decodeMeshoptView(const uint8_t* data, size_t size, const MeshoptView& v, std::vector<uint8_t>& out,
                         std::string& err) {
  out.clear();
  if (const char* why = constraintBroken(v)) {
    err = std::string(meshoptModeName(v.mode)) + "/" + meshoptFilterName(v.filter) + " with byteStride " +
          std::to_string(v.stride) + ", count " + std::to_string(v.count) + ": " + why;
    return Status::Corrupt;
  }
  // count <= 2^40 keeps count * stride (stride <= 256) far from overflow.
  const uint64_t bytes = v.count <= (uint64_t{1} << 40) ? v.count * v.stride : UINT64_MAX;
  if (bytes / kMeshoptMaxExpansion > size) {
    err = std::to_string(v.count) + " elements of " + std::to_string(v.stride) + " bytes from " + std::to_string(size) +
          " compressed bytes: more than the codecs' " + std::to_string(kMeshoptMaxExpansion) + "x expansion";
    return Status::Corrupt;
  }
  const auto n = static_cast<size_t>(v.count), stride = static_cast<size_t>(v.stride);
  // Filters run over whole groups of 4 elements in some meshoptimizer
  // versions; decoding into a buffer rounded up to 4 keeps them inside it.
  out.assign((n + 3) / 4 * 4 * stride, 0);
  int rc = 0;
  switch (v.mode) {
    case MeshoptMode::Attributes: rc = meshopt_decodeVertexBuffer(out.data(), n, stride, data, size); break;
    case MeshoptMode::Triangles: rc = meshopt_decodeIndexBuffer(out.data(), n, stride, data, size); break;
    case MeshoptMode::Indices: rc = meshopt_decodeIndexSequence(out.data(), n, stride, data, size); break;
  }
  if (rc != 0) {
    err = std::string(meshoptModeName(v.mode)) + " data (" + std::to_string(size) + " bytes for " + std::to_string(n) +
          " elements of " + std::to_string(stride) + " bytes) does not decode: meshoptimizer returned " +
          std::to_string(rc) + (rc == -1 ? " (unsupported version or bad header)" : " (malformed or truncated)");
    out.clear();
    return Status::Corrupt;
  }
  const size_t padded = out.size() / stride;
  switch (v.filter) {
    case MeshoptFilter::None: break;
    case MeshoptFilter::Octahedral: meshopt_decodeFilterOct(out.data(), padded, stride); break;
    case MeshoptFilter::Quaternion: meshopt_decodeFilterQuat(out.data(), padded, stride); break;
    case MeshoptFilter::Exponential: meshopt_decodeFilterExp(out.data(), padded, stride); break;
  }
  out.resize(n * stride);
  return Status::Ok;
}

std::vector<uint8_t> encodeMeshoptAttributes(const void* vertices, size_t count, size_t stride) {
  if (stride == 0 || stride % 4 || stride > 256)
    throw core::Error(Status::InvalidArg, "encodeMeshoptAttributes: stride " + std::to_string(stride) +
                                              " is not a multiple of 4 in 4..256");
  std::vector<uint8_t> out(meshopt_encodeVertexBufferBound(count, stride));
  out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), vertices, count, stride));
  if (out.empty()) throw core::Error(Status::Internal, "encodeMeshoptAttributes: the codec wrote nothing");
  return out;
}

std::vector<uint8_t> encodeMeshoptTriangles(const uint32_t* indices, size_t count, size_t vertex_count) {
  if (count % 3) throw core::Error(Status::InvalidArg, "encodeMeshoptTriangles: " + std::to_string(count) +
                                                           " indices are not whole triangles");
  std::vector<uint8_t> out(meshopt_encodeIndexBufferBound(count, vertex_count));
  out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(), indices, count));
  if (out.empty()) throw core::Error(Status::Internal, "encodeMeshoptTriangles: the codec wrote nothing");
  return out;
}

}  // namespace blvd::package
