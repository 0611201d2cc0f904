// GLB decoder (the runtime's; the encoder is glb_encode.cpp, for tools). glTF 2.0 spec: registry.khronos.org/glTF/specs/2.0;
// KHR_draco_mesh_compression: github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Khronos/KHR_draco_mesh_compression
// EXT_meshopt_compression: github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Vendor/EXT_meshopt_compression
// KHR_mesh_quantization: github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Khronos/KHR_mesh_quantization
//
// Why not tinygltf here: tinygltf 2.7.0 (Debian 12) is unsafe on untrusted
// input exactly where we need it. With TINYGLTF_ENABLE_DRACO its
// ParseDracoExtension indexes bufferViews/buffers/accessors without bounds
// checks and dereferences a null attribute for an unknown Draco unique id, and
// it drops a failed Draco decode silently; without it, its loader rejects every
// Draco primitive ("accessor[0] invalid bufferView"). It also forms
// &buffer.data[byteOffset] for images without checking the offset. So the
// decoder below reads the JSON with nlohmann::json (which tinygltf uses too)
// and checks every index, offset and count itself; tests/package checks our
// output against tinygltf+Draco as an independent reader.
#include "package/glb.h"
#include "package/glb_detail.h"

#include <draco/mesh/mesh.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <type_traits>

#include "package/meshopt_view.h"

namespace blvd::package {

namespace {

using nlohmann::json;
using core::Status;
using namespace glb_detail;

uint8_t linearToSrgbByte(float l) {
  if (!(l > 0)) return 0;  // also NaN
  if (l >= 1) return 255;
  const float s = l <= 0.0031308f ? l * 12.92f : 1.055f * std::pow(l, 1 / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(s * 255));
}

// linearToSrgbByte() without std::pow for the values unorm8 colours decode
// to (k / 255.0f, the decoder's own division), which is every colour we
// write; anything else (a float colour, a baseColorFactor) takes the formula.
uint8_t linearToSrgbByteFast(float l) {
  static const std::array<uint8_t, 256> lut = [] {
    std::array<uint8_t, 256> t{};
    for (int k = 0; k < 256; ++k) t[k] = linearToSrgbByte(static_cast<float>(k) / 255.0f);
    return t;
  }();
  if (l >= 0.0f && l <= 1.0f) {
    const auto k = static_cast<int>(l * 255.0f + 0.5f);
    if (static_cast<float>(k) / 255.0f == l) return lut[k];
  }
  return linearToSrgbByte(l);
}

// ---------------------------------------------------------------- decoder ---

// Thrown inside the decoder only; decodeGlb() turns it into status + text.
struct DecodeError {
  Status status;
  std::string message;
};

[[noreturn]] void fail(const std::string& msg, Status s = Status::Corrupt) { throw DecodeError{s, msg}; }

// One primitive's vertex streams before node transforms.
struct Primitive {
  std::vector<float> positions;  // xyz
  std::vector<float> normals;    // xyz or empty
  std::vector<float> colors;     // linear rgba or empty
  std::vector<float> texcoords;  // uv or empty
  std::vector<uint32_t> indices; // triangle list
  std::vector<float> shots;      // BLVD_projected_texcoords: each vertex's shot, or empty
};

struct Mat4 {
  double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // column-major, as glTF
  Mat4 operator*(const Mat4& b) const {
    Mat4 r;
    for (int c = 0; c < 4; ++c)
      for (int rr = 0; rr < 4; ++rr) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += m[k * 4 + rr] * b.m[c * 4 + k];
        r.m[c * 4 + rr] = s;
      }
    return r;
  }
};

class Decoder {
 public:
  Decoder(const json& doc, const uint8_t* bin, size_t bin_size, uint32_t level)
      : doc_(doc), bin_(bin), bin_size_(bin_size), level_(level) {}

  void run(geo::MeshData& out) {
    runGeometry(out);
    if (!out.texcoords.empty()) image(out);
  }

 private:
  void runGeometry(geo::MeshData& out) {
    checkRequiredExtensions();
    const json* scenes = arrayMember(doc_, "scenes", "");
    const json* nodes = arrayMember(doc_, "nodes", "");
    std::vector<size_t> roots;
    if (scenes && !scenes->empty()) {
      size_t scene = 0;
      if (doc_.contains("scene")) scene = index(doc_, "scene", "", scenes->size(), "scenes");
      const json& sc = object((*scenes)[scene], "scenes[" + std::to_string(scene) + "]");
      if (const json* list = arrayMember(sc, "nodes", "scenes[" + std::to_string(scene) + "]"))
        for (size_t i = 0; i < list->size(); ++i)
          roots.push_back(indexValue((*list)[i], "scenes[" + std::to_string(scene) + "].nodes[" + std::to_string(i) + "]",
                                     nodes ? nodes->size() : 0, "nodes"));
    } else if (nodes && !nodes->empty()) {
      // Roots are the nodes nobody refers to, as a child or as a level of detail.
      std::vector<bool> is_child(nodes->size(), false);
      for (size_t i = 0; i < nodes->size(); ++i) {
        const std::string where = "nodes[" + std::to_string(i) + "]";
        if (const json* ch = arrayMember(object((*nodes)[i], where), "children", where))
          for (size_t k = 0; k < ch->size(); ++k)
            is_child[indexValue((*ch)[k], where + ".children", nodes->size(), "nodes")] = true;
        if (const json* ids = lodIds((*nodes)[i], where))
          for (size_t k = 0; k < ids->size(); ++k)
            is_child[indexValue((*ids)[k], where + ".extensions.MSFT_lod.ids", nodes->size(), "nodes")] = true;
      }
      for (size_t i = 0; i < nodes->size(); ++i)
        if (!is_child[i]) roots.push_back(i);
    } else {
      if (level_ > 0) fail("level " + std::to_string(level_) + " requested but the GLB has no nodes", Status::NotFound);
      const json* meshes = arrayMember(doc_, "meshes", "");
      for (size_t i = 0; meshes && i < meshes->size(); ++i) emitMesh(i, Mat4{}, out);
      return;
    }
    struct Item {
      size_t node;
      Mat4 parent;
      int depth;
    };
    std::vector<Item> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, Mat4{}, 0});
    size_t visits = 0;
    while (!stack.empty()) {
      Item item = stack.back();
      stack.pop_back();
      std::string where = "nodes[" + std::to_string(item.node) + "]";
      // glTF nodes form a forest; a cycle or a DAG that fans out
      // exponentially is invalid, and these limits turn it into an error.
      if (item.depth > 64) fail(where + ": node hierarchy deeper than 64 (a cycle?)");
      if (++visits > 100000) fail(where + ": more than 100000 node visits (shared children?)");
      const json* node_ptr = &object((*nodes)[item.node], where);
      // MSFT_lod: the node stands for its whole level; its level node (with
      // that node's own transform, mesh and children) takes its place.
      if (level_ > 0) {
        if (const json* ids = lodIds(*node_ptr, where)) {
          if (level_ > ids->size())
            fail(where + ".extensions.MSFT_lod: " + std::to_string(ids->size()) + " lower levels, level " +
                     std::to_string(level_) + " requested",
                 Status::NotFound);
          const size_t sub = indexValue((*ids)[level_ - 1], where + ".extensions.MSFT_lod.ids", nodes->size(), "nodes");
          where = "nodes[" + std::to_string(sub) + "]";
          node_ptr = &object((*nodes)[sub], where);
          ++substituted_;
        }
      }
      const json& node = *node_ptr;
      const Mat4 world = item.parent * localMatrix(node, where);
      if (node.contains("mesh")) {
        const json* meshes = arrayMember(doc_, "meshes", "");
        emitMesh(index(node, "mesh", where, meshes ? meshes->size() : 0, "meshes"), world, out);
      }
      if (const json* ch = arrayMember(node, "children", where))
        for (size_t k = ch->size(); k-- > 0;)
          stack.push_back({indexValue((*ch)[k], where + ".children[" + std::to_string(k) + "]",
                                      nodes->size(), "nodes"),
                           world, item.depth + 1});
    }
    if (level_ > 0 && substituted_ == 0)
      fail("level " + std::to_string(level_) + " requested but the scene has no MSFT_lod node", Status::NotFound);
  }

  // The node's MSFT_lod level list, or null; a malformed one is an error.
  static const json* lodIds(const json& node, const std::string& where) {
    if (!node.is_object()) return nullptr;
    auto ext = node.find("extensions");
    if (ext == node.end() || !ext->is_object()) return nullptr;
    auto lod = ext->find("MSFT_lod");
    if (lod == ext->end()) return nullptr;
    const json* ids = arrayMember(object(*lod, where + ".extensions.MSFT_lod"), "ids", where + ".extensions.MSFT_lod");
    if (!ids) fail(where + ".extensions.MSFT_lod.ids: required but missing");
    return ids;
  }

 private:
  // ------------------------------------------------------- JSON helpers --
  static const json& object(const json& v, const std::string& where) {
    if (!v.is_object()) fail(where + ": expected a JSON object");
    return v;
  }
  static const json* arrayMember(const json& o, const char* key, const std::string& where) {
    if (!o.is_object()) fail((where.empty() ? std::string("root") : where) + ": expected a JSON object");
    auto it = o.find(key);
    if (it == o.end()) return nullptr;
    if (!it->is_array()) fail(prefix(where) + key + ": expected an array");
    return &*it;
  }
  static std::string prefix(const std::string& where) { return where.empty() ? "" : where + "."; }
  static uint64_t unsignedValue(const json& v, const std::string& where) {
    if (v.is_number_unsigned()) return v.get<uint64_t>();
    if (v.is_number_integer() && v.get<int64_t>() >= 0) return static_cast<uint64_t>(v.get<int64_t>());
    // Some exporters write integers as 24.0; accept exact small integers.
    if (v.is_number_float()) {
      const double d = v.get<double>();
      if (d >= 0 && d <= 9007199254740992.0 && std::floor(d) == d) return static_cast<uint64_t>(d);
    }
    fail(where + ": expected a non-negative integer");
  }
  static uint64_t unsignedMember(const json& o, const char* key, const std::string& where,
                                 std::optional<uint64_t> dflt = std::nullopt) {
    auto it = o.find(key);
    if (it == o.end()) {
      if (!dflt) fail(prefix(where) + key + ": required but missing");
      return *dflt;
    }
    return unsignedValue(*it, prefix(where) + key);
  }
  static size_t indexValue(const json& v, const std::string& where, size_t count, const char* array) {
    const uint64_t i = unsignedValue(v, where);
    if (i >= count)
      fail(where + ": index " + std::to_string(i) + " out of range (" + array + " has " + std::to_string(count) + ")");
    return static_cast<size_t>(i);
  }
  static size_t index(const json& o, const char* key, const std::string& where, size_t count, const char* array) {
    auto it = o.find(key);
    if (it == o.end()) fail(prefix(where) + key + ": required but missing");
    return indexValue(*it, prefix(where) + key, count, array);
  }
  static double number(const json& v, const std::string& where) {
    if (!v.is_number()) fail(where + ": expected a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(where + ": not finite");
    return d;
  }
  static std::vector<double> numbers(const json& o, const char* key, const std::string& where, size_t n) {
    auto it = o.find(key);
    if (it == o.end()) return {};
    if (!it->is_array() || it->size() != n)
      fail(prefix(where) + key + ": expected an array of " + std::to_string(n) + " numbers");
    std::vector<double> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = number((*it)[i], prefix(where) + key + "[" + std::to_string(i) + "]");
    return v;
  }
  const json& element(const char* array, size_t i) const {
    return object(doc_.at(array).at(i), std::string(array) + "[" + std::to_string(i) + "]");
  }
  size_t count(const char* array) const {
    const json* a = arrayMember(doc_, array, "");
    return a ? a->size() : 0;
  }

  void checkRequiredExtensions() const {
    const json* req = arrayMember(doc_, "extensionsRequired", "");
    if (!req) return;
    for (const json& e : *req) {
      if (!e.is_string()) fail("extensionsRequired: expected strings");
      const std::string name = e.get<std::string>();
      // The geometry extensions this decoder implements, and texture and
      // material ones, which do not change geometry (all it returns).
      const bool harmless = name == "KHR_draco_mesh_compression" || name == "KHR_mesh_quantization" ||
                            name == "EXT_meshopt_compression" || name == kProjectedTexcoords ||
                            name.rfind("KHR_materials_", 0) == 0 || name.rfind("KHR_texture_", 0) == 0 ||
                            name.rfind("EXT_texture_", 0) == 0;
      if (!harmless) fail("extensionsRequired: " + name + " is not supported", Status::Unsupported);
    }
  }

  // ------------------------------------------------------ buffers, views --
  struct Bytes {
    const uint8_t* data = nullptr;
    size_t size = 0;
  };

  Bytes buffer(size_t i) {
    auto cached = buffers_.find(i);
    if (cached != buffers_.end()) return {cached->second.data, cached->second.size};
    const std::string where = "buffers[" + std::to_string(i) + "]";
    const json& b = element("buffers", i);
    const uint64_t length = unsignedMember(b, "byteLength", where);
    Stored s;
    auto uri = b.find("uri");
    if (uri == b.end()) {
      if (i != 0 || !bin_) fail(where + ": no uri and no GLB BIN chunk to refer to");
      if (length > bin_size_)
        fail(where + ": byteLength " + std::to_string(length) + " exceeds the BIN chunk (" + std::to_string(bin_size_) + " bytes)");
      s.data = bin_;
    } else {
      if (!uri->is_string()) fail(where + ".uri: expected a string");
      s.owned = decodeDataUri(uri->get<std::string>(), where);
      if (s.owned.size() < length)
        fail(where + ": data uri holds " + std::to_string(s.owned.size()) + " bytes, byteLength says " + std::to_string(length));
      s.data = s.owned.data();
    }
    s.size = static_cast<size_t>(length);
    auto& stored = buffers_[i] = std::move(s);
    if (!stored.owned.empty()) stored.data = stored.owned.data();
    return {stored.data, stored.size};
  }

  static std::vector<uint8_t> decodeDataUri(const std::string& uri, const std::string& where) {
    if (uri.rfind("data:", 0) != 0) fail(where + ": external buffer \"" + uri.substr(0, 64) + "\" is not supported in a GLB", Status::Unsupported);
    const size_t comma = uri.find(',');
    if (comma == std::string::npos || uri.rfind(";base64", comma) == std::string::npos)
      fail(where + ": only base64 data: uris are supported", Status::Unsupported);
    std::vector<uint8_t> out;
    out.reserve((uri.size() - comma) / 4 * 3);
    uint32_t acc = 0;
    int bits = 0;
    for (size_t i = comma + 1; i < uri.size(); ++i) {
      const char c = uri[i];
      int v;
      if (c >= 'A' && c <= 'Z') v = c - 'A';
      else if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
      else if (c >= '0' && c <= '9') v = c - '0' + 52;
      else if (c == '+' || c == '-') v = 62;
      else if (c == '/' || c == '_') v = 63;
      else if (c == '=') break;
      else fail(where + ": invalid base64 character at uri position " + std::to_string(i));
      acc = (acc << 6) | static_cast<uint32_t>(v);
      bits += 6;
      if (bits >= 8) {
        bits -= 8;
        out.push_back(static_cast<uint8_t>((acc >> bits) & 0xFF));
      }
    }
    return out;
  }

  struct View {
    Bytes bytes;
    uint32_t stride = 0;  // 0 = tightly packed
  };

  // A bufferView's byteStride, 0 when absent (tightly packed).
  static uint32_t viewStride(const json& v, const std::string& where) {
    const uint64_t stride = unsignedMember(v, "byteStride", where, 0);
    if (stride != 0 && (stride < 4 || stride > 252 || stride % 4))
      fail(where + ".byteStride: " + std::to_string(stride) + " is not in 4..252 and a multiple of 4");
    return static_cast<uint32_t>(stride);
  }

  // The bytes an object's buffer / byteOffset / byteLength name (a
  // bufferView, or its EXT_meshopt_compression source), bounds-checked.
  Bytes bufferRange(const json& o, const std::string& where) {
    const size_t b = index(o, "buffer", where, count("buffers"), "buffers");
    const Bytes buf = buffer(b);
    const uint64_t off = unsignedMember(o, "byteOffset", where, 0);
    const uint64_t len = unsignedMember(o, "byteLength", where);
    if (len > buf.size || off > buf.size - len)
      fail(where + ": byteOffset " + std::to_string(off) + " + byteLength " + std::to_string(len) +
           " runs past buffers[" + std::to_string(b) + "] (" + std::to_string(buf.size) + " bytes)");
    return {buf.data + off, static_cast<size_t>(len)};
  }

  View bufferView(size_t i) {
    const std::string where = "bufferViews[" + std::to_string(i) + "]";
    const json& v = element("bufferViews", i);
    if (auto ext = v.find("extensions"); ext != v.end() && ext->is_object())
      if (auto mo = ext->find("EXT_meshopt_compression"); mo != ext->end())
        return meshoptView(i, v, object(*mo, where + ".extensions.EXT_meshopt_compression"), where);
    View view;
    view.bytes = bufferRange(v, where);
    view.stride = viewStride(v, where);
    return view;
  }

  // A compressed view decodes (once per decode call) into memory of its
  // own; the parent view's buffer (normally a fallback without data) is
  // never read. The extension's rules on the JSON are checked here, those
  // on the bitstream's layout in decodeMeshoptView().
  View meshoptView(size_t i, const json& v, const json& ext, const std::string& where) {
    const std::string ewhere = where + ".extensions.EXT_meshopt_compression";
    index(v, "buffer", where, count("buffers"), "buffers");
    const uint64_t stride = unsignedMember(ext, "byteStride", ewhere);
    const uint64_t n = unsignedMember(ext, "count", ewhere);
    const uint64_t parent_len = unsignedMember(v, "byteLength", where);
    const uint64_t parent_stride = viewStride(v, where);
    if (parent_stride != 0 && parent_stride != stride)
      fail(where + ".byteStride: " + std::to_string(parent_stride) + " differs from the extension's " +
           std::to_string(stride));
    if (n > 3 * kMaxDecodedVertices)
      fail(ewhere + ".count: " + std::to_string(n) + " elements exceed the decoder limit", Status::Unsupported);
    if (stride > 256 || parent_len != stride * n)
      fail(where + ".byteLength: " + std::to_string(parent_len) + " is not the extension's byteStride " +
           std::to_string(stride) + " x count " + std::to_string(n));
    auto cached = views_.find(i);
    if (cached == views_.end()) {
      MeshoptView mv;
      mv.count = n;
      mv.stride = stride;
      auto mode = ext.find("mode");
      if (mode == ext.end() || !mode->is_string() || !parseMeshoptMode(mode->get<std::string>(), mv.mode))
        fail(ewhere + ".mode: expected ATTRIBUTES, TRIANGLES or INDICES");
      if (auto f = ext.find("filter"); f != ext.end())
        if (!f->is_string() || !parseMeshoptFilter(f->get<std::string>(), mv.filter))
          fail(ewhere + ".filter: expected NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
      const Bytes src = bufferRange(ext, ewhere);
      std::vector<uint8_t> bytes;
      std::string err;
      if (decodeMeshoptView(src.data, src.size, mv, bytes, err) != Status::Ok)
        fail(ewhere + ": " + err);
      cached = views_.emplace(i, std::move(bytes)).first;
    }
    View view;
    view.bytes = {cached->second.data(), cached->second.size()};
    view.stride = static_cast<uint32_t>(parent_stride);
    return view;
  }

  // --------------------------------------------------------- accessors --
  static int componentBytes(int type) {
    switch (type) {
      case kByte: case kUnsignedByte: return 1;
      case kShort: case kUnsignedShort: return 2;
      case kUnsignedInt: case kFloat: return 4;
      default: return 0;
    }
  }
  static int typeComponents(const std::string& t) {
    if (t == "SCALAR") return 1;
    if (t == "VEC2") return 2;
    if (t == "VEC3") return 3;
    if (t == "VEC4") return 4;
    return 0;  // matrices are not vertex data we read
  }

  struct AccessorInfo {
    uint64_t count = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
  };

  AccessorInfo accessorInfo(size_t i) const {
    const std::string where = "accessors[" + std::to_string(i) + "]";
    const json& a = element("accessors", i);
    AccessorInfo info;
    info.count = unsignedMember(a, "count", where);
    const uint64_t ct = unsignedMember(a, "componentType", where);
    info.component_type = ct < 10000 ? static_cast<int>(ct) : 0;
    if (componentBytes(info.component_type) == 0) fail(where + ".componentType: " + std::to_string(ct) + " is not a glTF vertex component type");
    auto type = a.find("type");
    if (type == a.end() || !type->is_string() || typeComponents(type->get<std::string>()) == 0)
      fail(where + ".type: expected SCALAR, VEC2, VEC3 or VEC4");
    info.components = typeComponents(type->get<std::string>());
    auto norm = a.find("normalized");
    if (norm != a.end()) {
      if (!norm->is_boolean()) fail(where + ".normalized: expected a boolean");
      info.normalized = norm->get<bool>();
    }
    return info;
  }

  static float component(const uint8_t* p, int type, bool normalized) {
    switch (type) {
      case kFloat: { float v; std::memcpy(&v, p, 4); return v; }
      case kUnsignedByte: return normalized ? p[0] / 255.0f : p[0];
      case kByte: { const auto v = static_cast<int8_t>(p[0]); return normalized ? std::max(v / 127.0f, -1.0f) : v; }
      case kUnsignedShort: { uint16_t v; std::memcpy(&v, p, 2); return normalized ? v / 65535.0f : v; }
      case kShort: { int16_t v; std::memcpy(&v, p, 2); return normalized ? std::max(v / 32767.0f, -1.0f) : v; }
      case kUnsignedInt: { uint32_t v; std::memcpy(&v, p, 4); return static_cast<float>(v); }
    }
    return 0;
  }

  // Reads accessor `i` as `want` floats per element (missing components 0).
  std::vector<float> readFloats(size_t i, int want, const std::string& semantic) {
    const std::string where = "accessors[" + std::to_string(i) + "] (" + semantic + ")";
    const AccessorInfo info = accessorInfo(i);
    const json& a = element("accessors", i);
    if (a.contains("sparse")) fail(where + ": sparse accessors are not supported", Status::Unsupported);
    if (info.count > kMaxDecodedVertices)
      fail(where + ": " + std::to_string(info.count) + " elements exceed the decoder limit", Status::Unsupported);
    // Without a bufferView an accessor is all zeros, useful only as the base
    // of a sparse accessor; refusing it also stops a few bytes of JSON from
    // asking for millions of vertices.
    if (!a.contains("bufferView"))
      fail(where + ": no bufferView (zero-filled accessors are not supported)", Status::Unsupported);
    const auto n = static_cast<size_t>(info.count);
    std::vector<float> out(n * want, 0.0f);
    const View view = bufferView(index(a, "bufferView", where, count("bufferViews"), "bufferViews"));
    const uint64_t off = unsignedMember(a, "byteOffset", where, 0);
    const size_t cb = componentBytes(info.component_type);
    const size_t elem = cb * info.components;
    const size_t stride = view.stride ? view.stride : elem;
    if (stride < elem) fail(where + ": byteStride " + std::to_string(stride) + " is smaller than the element (" + std::to_string(elem) + " bytes)");
    if (n > 0) {
      const uint64_t need = off + uint64_t{stride} * (n - 1) + elem;  // n <= 2^24, stride <= 252: no overflow
      if (off > view.bytes.size || need > view.bytes.size)
        fail(where + ": " + std::to_string(n) + " elements of " + std::to_string(elem) + " bytes at offset " +
             std::to_string(off) + " run past the bufferView (" + std::to_string(view.bytes.size) + " bytes)");
    }
    const int take = std::min(want, info.components);
    for (size_t e = 0; e < n; ++e) {
      const uint8_t* p = view.bytes.data + off + e * stride;
      for (int k = 0; k < take; ++k) out[e * want + k] = component(p + k * cb, info.component_type, info.normalized);
    }
    return out;
  }

  std::vector<uint32_t> readIndices(size_t i) {
    const std::string where = "accessors[" + std::to_string(i) + "] (indices)";
    const AccessorInfo info = accessorInfo(i);
    if (info.components != 1 || !(info.component_type == kUnsignedByte || info.component_type == kUnsignedShort ||
                                  info.component_type == kUnsignedInt))
      fail(where + ": indices must be SCALAR unsigned byte/short/int");
    const json& a = element("accessors", i);
    if (a.contains("sparse")) fail(where + ": sparse accessors are not supported", Status::Unsupported);
    if (!a.contains("bufferView")) fail(where + ": indices without a bufferView");
    const View view = bufferView(index(a, "bufferView", where, count("bufferViews"), "bufferViews"));
    const uint64_t off = unsignedMember(a, "byteOffset", where, 0);
    const size_t cb = componentBytes(info.component_type);
    const size_t stride = view.stride ? view.stride : cb;
    if (info.count > 3 * kMaxDecodedVertices)
      fail(where + ": " + std::to_string(info.count) + " indices exceed the decoder limit", Status::Unsupported);
    const auto n = static_cast<size_t>(info.count);
    if (n > 0) {
      const uint64_t need = off + uint64_t{stride} * (n - 1) + cb;
      if (off > view.bytes.size || need > view.bytes.size)
        fail(where + ": " + std::to_string(n) + " indices at offset " + std::to_string(off) +
             " run past the bufferView (" + std::to_string(view.bytes.size) + " bytes)");
    }
    std::vector<uint32_t> out(n);
    for (size_t e = 0; e < n; ++e) {
      const uint8_t* p = view.bytes.data + off + e * stride;
      uint32_t v = 0;
      std::memcpy(&v, p, cb);  // little-endian host: low bytes first
      out[e] = v;
    }
    return out;
  }

  // -------------------------------------------------------- primitives --
  // Returns false for primitives that are not triangles (skipped).
  bool loadPrimitive(size_t mesh, size_t prim_index, const json& prim, Primitive& p) {
    const std::string where = "meshes[" + std::to_string(mesh) + "].primitives[" + std::to_string(prim_index) + "]";
    const uint64_t mode = unsignedMember(prim, "mode", where, kModeTriangles);
    if (mode != kModeTriangles && mode != kModeStrip && mode != kModeFan) return false;
    auto attrs = prim.find("attributes");
    if (attrs == prim.end() || !attrs->is_object()) fail(where + ".attributes: expected an object");
    const size_t n_acc = count("accessors");
    auto attr = [&](const char* name) -> std::optional<size_t> {
      auto it = attrs->find(name);
      if (it == attrs->end()) return std::nullopt;
      return indexValue(*it, where + ".attributes." + name, n_acc, "accessors");
    };
    const auto pos = attr("POSITION");
    if (!pos) fail(where + ": no POSITION attribute");
    const auto nrm = attr("NORMAL");
    const auto col = attr("COLOR_0");
    const auto tex = attr("TEXCOORD_0");
    const auto shot = attr(kShotAttribute);
    std::optional<size_t> idx;
    if (prim.contains("indices")) idx = index(prim, "indices", where, n_acc, "accessors");

    const json* draco = nullptr;
    const json* projected = nullptr;
    if (auto ext = prim.find("extensions"); ext != prim.end() && ext->is_object()) {
      auto d = ext->find("KHR_draco_mesh_compression");
      if (d != ext->end()) draco = &object(*d, where + ".extensions.KHR_draco_mesh_compression");
      auto pt = ext->find(kProjectedTexcoords);
      if (pt != ext->end()) projected = &object(*pt, where + ".extensions." + kProjectedTexcoords);
    }
    if (projected && tex) fail(where + ": TEXCOORD_0 and " + kProjectedTexcoords + " both");
    size_t vertex_count = 0;
    if (draco) {
      if (mode != kModeTriangles) fail(where + ": Draco primitive with mode " + std::to_string(mode) + " (only TRIANGLES)");
      loadDraco(*draco, where, *attrs, idx, {pos, nrm, col, tex, shot}, p);
      vertex_count = p.positions.size() / 3;
    } else {
      p.positions = readFloats(*pos, 3, "POSITION");
      vertex_count = p.positions.size() / 3;
      auto sameCount = [&](const std::vector<float>& v, int comps, const char* name) {
        if (v.size() != vertex_count * comps)
          fail(where + ": " + name + " has " + std::to_string(v.size() / comps) + " elements, POSITION " + std::to_string(vertex_count));
      };
      if (nrm) {
        p.normals = readFloats(*nrm, 3, "NORMAL");
        sameCount(p.normals, 3, "NORMAL");
      }
      if (col) {
        p.colors = readColors(*col);
        sameCount(p.colors, 4, "COLOR_0");
      }
      if (tex) {
        p.texcoords = readFloats(*tex, 2, "TEXCOORD_0");
        sameCount(p.texcoords, 2, "TEXCOORD_0");
      }
      if (shot) {
        p.shots = readFloats(*shot, 1, kShotAttribute);
        sameCount(p.shots, 1, kShotAttribute);
      }
      std::vector<uint32_t> raw;
      if (idx) {
        raw = readIndices(*idx);
      } else {
        raw.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) raw[i] = static_cast<uint32_t>(i);
      }
      p.indices = toTriangleList(raw, mode);
    }
    for (size_t i = 0; i < p.positions.size(); ++i)
      if (!std::isfinite(p.positions[i])) fail(where + ": POSITION element " + std::to_string(i / 3) + " is not finite");
    if (projected) projectTexcoords(*projected, where, p);
    for (size_t i = 0; i < p.texcoords.size(); ++i)
      if (!std::isfinite(p.texcoords[i])) fail(where + ": TEXCOORD_0 element " + std::to_string(i / 2) + " is not finite");
    for (size_t i = 0; i < p.indices.size(); ++i)
      if (p.indices[i] >= vertex_count)
        fail(where + ": index " + std::to_string(i) + " = " + std::to_string(p.indices[i]) + " >= vertex count " + std::to_string(vertex_count));
    return true;
  }

  std::vector<float> readColors(size_t i) {
    const AccessorInfo info = accessorInfo(i);
    if (info.components != 3 && info.components != 4) fail("accessors[" + std::to_string(i) + "] (COLOR_0): expected VEC3 or VEC4");
    std::vector<float> c = readFloats(i, 4, "COLOR_0");
    if (info.components == 3)
      for (size_t k = 3; k < c.size(); k += 4) c[k] = 1.0f;
    return c;
  }

  static std::vector<uint32_t> toTriangleList(const std::vector<uint32_t>& raw, uint64_t mode) {
    std::vector<uint32_t> tri;
    if (mode == kModeTriangles) {
      tri.assign(raw.begin(), raw.begin() + static_cast<ptrdiff_t>(raw.size() / 3 * 3));
    } else if (raw.size() >= 3) {
      tri.reserve((raw.size() - 2) * 3);
      for (size_t i = 0; i + 2 < raw.size(); ++i) {
        if (mode == kModeStrip) {  // every other triangle reversed to keep the winding
          if (i % 2 == 0) tri.insert(tri.end(), {raw[i], raw[i + 1], raw[i + 2]});
          else tri.insert(tri.end(), {raw[i + 1], raw[i], raw[i + 2]});
        } else {
          tri.insert(tri.end(), {raw[0], raw[i + 1], raw[i + 2]});
        }
      }
    }
    return tri;
  }

  // The accessors of a primitive's attributes, where it has them.
  struct Attributes {
    std::optional<size_t> pos, nrm, col, tex, shot;
  };

  // BLVD_projected_texcoords (glb.h, TexcoordProjection): each vertex's uv
  // from its position and its shot's projection, in the primitive's own
  // frame (before node transforms, as the bake wrote them).
  void projectTexcoords(const json& ext, const std::string& where, Primitive& p) {
    const std::string pwhere = where + ".extensions." + kProjectedTexcoords;
    const uint64_t shots = unsignedMember(ext, "count", pwhere);
    if (shots < 1 || shots > 256) fail(pwhere + ".count: " + std::to_string(shots) + " shots (1 to 256)");
    const View view = bufferView(index(ext, "bufferView", pwhere, count("bufferViews"), "bufferViews"));
    if (view.bytes.size != shots * kProjectionShotBytes)
      fail(pwhere + ": bufferView holds " + std::to_string(view.bytes.size) + " bytes, " + std::to_string(shots) +
           " shots take " + std::to_string(shots * kProjectionShotBytes));
    const size_t n = p.positions.size() / 3;
    if (shots > 1 && p.shots.size() != n) fail(pwhere + ": " + std::to_string(shots) + " shots but no _SHOT attribute");
    p.texcoords.resize(n * 2);
    for (size_t v = 0; v < n; ++v) {
      const float s = p.shots.empty() ? 0.0f : p.shots[v];
      if (!(s >= 0.0f && s < float(shots) && s == std::floor(s))) {
        char named[32];
        std::snprintf(named, sizeof named, "%g", double(s));
        fail(pwhere + ": vertex " + std::to_string(v) + " names shot " + named + " of " + std::to_string(shots));
      }
      float f[16];
      std::memcpy(f, view.bytes.data + size_t(s) * kProjectionShotBytes, sizeof f);
      if (!projectTexcoord(f, f + 12, &p.positions[3 * v], &p.texcoords[2 * v]))
        fail(pwhere + ": vertex " + std::to_string(v) + " is not in front of shot " + std::to_string(size_t(s)));
    }
    p.shots.clear();
  }

  void loadDraco(const json& ext, const std::string& where, const json& attrs, std::optional<size_t> idx,
                 const Attributes& a, Primitive& p) {
    const std::string dwhere = where + ".extensions.KHR_draco_mesh_compression";
    const View view = bufferView(index(ext, "bufferView", dwhere, count("bufferViews"), "bufferViews"));
    auto dattrs = ext.find("attributes");
    if (dattrs == ext.end() || !dattrs->is_object()) fail(dwhere + ".attributes: expected an object");
    std::unique_ptr<draco::Mesh> mesh;
    std::string err;
    const Status ds = decodeDracoBuffer(view.bytes.data, view.bytes.size, mesh, err);
    if (ds != Status::Ok) fail(dwhere + ": " + err, ds);
    const size_t points = mesh->num_points();
    const size_t faces = mesh->num_faces();
    if (points > kMaxDecodedVertices || faces > kMaxDecodedVertices)
      fail(dwhere + ": " + std::to_string(points) + " points / " + std::to_string(faces) + " faces exceed the decoder limit",
           Status::Unsupported);
    // The accessors promise counts; a decoder that disagrees means the blob
    // and its JSON do not belong together (tinygltf 2.7 would go on silently).
    if (idx) {
      const AccessorInfo ii = accessorInfo(*idx);
      if (ii.count != faces * 3)
        fail(dwhere + ": Draco data decodes to " + std::to_string(faces * 3) + " indices but accessors[" +
             std::to_string(*idx) + "].count is " + std::to_string(ii.count));
    }
    for (auto it = dattrs->begin(); it != dattrs->end(); ++it)
      if (!attrs.contains(it.key())) fail(dwhere + ".attributes." + it.key() + ": not among the primitive's attributes");

    // One attribute: from the Draco mesh when the extension maps it, else
    // from a plain accessor (the extension allows uncompressed attributes).
    auto load = [&](const char* semantic, std::optional<size_t> acc, int want) -> std::vector<float> {
      if (!acc) return {};
      const AccessorInfo ai = accessorInfo(*acc);
      if (ai.count != points)
        fail(dwhere + ": Draco data decodes to " + std::to_string(points) + " points but accessors[" +
             std::to_string(*acc) + "] (" + semantic + ").count is " + std::to_string(ai.count));
      auto d = dattrs->find(semantic);
      if (d == dattrs->end()) {
        std::vector<float> v = want == 4 ? readColors(*acc) : readFloats(*acc, want, semantic);
        return v;
      }
      const uint64_t uid = unsignedValue(*d, dwhere + ".attributes." + semantic);
      const draco::PointAttribute* pa =
          uid <= std::numeric_limits<uint32_t>::max() ? mesh->GetAttributeByUniqueId(static_cast<uint32_t>(uid)) : nullptr;
      if (!pa) fail(dwhere + ".attributes." + semantic + ": Draco data has no attribute with unique id " + std::to_string(uid));
      if (pa->num_components() < 1) fail(dwhere + ": Draco attribute " + semantic + " has no components");
      if (!pa->is_mapping_identity() && pa->indices_map_size() < points)
        fail(dwhere + ": Draco attribute " + semantic + " maps fewer points than the mesh has");
      const bool integral = pa->data_type() != draco::DT_FLOAT32 && pa->data_type() != draco::DT_FLOAT64;
      // Normalize integer data ourselves when glTF says so but the Draco
      // attribute does not carry the flag (older encoders).
      const float scale = (integral && ai.normalized && !pa->normalized()) ? 1.0f / maxOf(pa->data_type()) : 1.0f;
      std::vector<float> v(points * want, 0.0f);
      float tmp[4];
      for (uint32_t i = 0; i < points; ++i) {
        const draco::AttributeValueIndex avi = pa->mapped_index(draco::PointIndex(i));
        if (avi.value() >= pa->size() || !pa->ConvertValue<float>(avi, 4, tmp))
          fail(dwhere + ": Draco attribute " + semantic + " value for point " + std::to_string(i) + " is unreadable");
        for (int k = 0; k < want; ++k) v[i * want + k] = tmp[k] * scale;
      }
      if (want == 4 && pa->num_components() == 3)
        for (size_t k = 3; k < v.size(); k += 4) v[k] = 1.0f;
      return v;
    };
    p.positions = load("POSITION", a.pos, 3);
    p.normals = load("NORMAL", a.nrm, 3);
    p.colors = load("COLOR_0", a.col, 4);
    p.texcoords = load("TEXCOORD_0", a.tex, 2);
    p.shots = load(kShotAttribute, a.shot, 1);
    p.indices.resize(faces * 3);
    for (uint32_t f = 0; f < faces; ++f) {
      const draco::Mesh::Face& face = mesh->face(draco::FaceIndex(f));
      for (int k = 0; k < 3; ++k) p.indices[f * 3 + k] = face[k].value();
    }
  }

  static float maxOf(draco::DataType t) {
    switch (t) {
      case draco::DT_UINT8: return 255.0f;
      case draco::DT_INT8: return 127.0f;
      case draco::DT_UINT16: return 65535.0f;
      case draco::DT_INT16: return 32767.0f;
      case draco::DT_UINT32: return 4294967295.0f;
      case draco::DT_INT32: return 2147483647.0f;
      default: return 1.0f;
    }
  }

  // ---------------------------------------------------- nodes, output --
  static Mat4 localMatrix(const json& node, const std::string& where) {
    Mat4 m;
    const std::vector<double> mat = numbers(node, "matrix", where, 16);
    if (!mat.empty()) {
      std::copy(mat.begin(), mat.end(), m.m);
      return m;
    }
    const std::vector<double> t = numbers(node, "translation", where, 3);
    const std::vector<double> r = numbers(node, "rotation", where, 4);
    const std::vector<double> s = numbers(node, "scale", where, 3);
    double qx = 0, qy = 0, qz = 0, qw = 1;
    if (!r.empty()) {
      const double len = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
      if (len > 0) qx = r[0] / len, qy = r[1] / len, qz = r[2] / len, qw = r[3] / len;
    }
    const double sx = s.empty() ? 1 : s[0], sy = s.empty() ? 1 : s[1], sz = s.empty() ? 1 : s[2];
    // M = T * R * S, column-major.
    const double R[9] = {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy + qz * qw),     2 * (qx * qz - qy * qw),
                         2 * (qx * qy - qz * qw),     1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz + qx * qw),
                         2 * (qx * qz + qy * qw),     2 * (qy * qz - qx * qw),     1 - 2 * (qx * qx + qy * qy)};
    const double S[3] = {sx, sy, sz};
    for (int c = 0; c < 3; ++c)
      for (int rr = 0; rr < 3; ++rr) m.m[c * 4 + rr] = R[c * 3 + rr] * S[c];
    if (!t.empty()) m.m[12] = t[0], m.m[13] = t[1], m.m[14] = t[2];
    return m;
  }

  // The base colour texture of material 0, when it is an image stored in a
  // bufferView (impostor meshes carry their captured colour this way).
  void image(geo::MeshData& out) {
    if (count("materials") == 0 || count("textures") == 0 || count("images") == 0) return;
    const json& mat = element("materials", 0);
    auto pbr = mat.find("pbrMetallicRoughness");
    if (pbr == mat.end() || !pbr->is_object()) return;
    auto bct = pbr->find("baseColorTexture");
    if (bct == pbr->end()) return;
    const size_t ti = index(object(*bct, "materials[0].pbrMetallicRoughness.baseColorTexture"), "index",
                            "materials[0].pbrMetallicRoughness.baseColorTexture", count("textures"), "textures");
    const json& tex = element("textures", ti);
    const std::string tw = "textures[" + std::to_string(ti) + "]";
    // The image: EXT_texture_webp's source when there is one, else the texture's.
    const json* src = &tex;
    std::string sw = tw;
    if (const auto ext = tex.find("extensions"); ext != tex.end() && ext->is_object() && ext->contains("EXT_texture_webp")) {
      src = &object(ext->at("EXT_texture_webp"), tw + ".extensions.EXT_texture_webp");
      sw = tw + ".extensions.EXT_texture_webp";
    }
    if (!src->contains("source")) return;
    const size_t ii = index(*src, "source", sw, count("images"), "images");
    const json& img = element("images", ii);
    const std::string iw = "images[" + std::to_string(ii) + "]";
    if (!img.contains("bufferView")) return;  // uri images: dropped like other unusable ones below
    const View v = bufferView(index(img, "bufferView", iw, count("bufferViews"), "bufferViews"));
    // The bytes decide the type, not mimeType (it can lie); anything but PNG,
    // JPEG or WebP ("RIFF", size, "WEBP") is dropped, keeping the geometry usable.
    static const uint8_t kPng[4] = {0x89, 'P', 'N', 'G'}, kJpeg[3] = {0xFF, 0xD8, 0xFF};
    const uint8_t* d = v.bytes.data;
    if (v.bytes.size >= 4 && std::memcmp(d, kPng, 4) == 0) out.image_mime = "image/png";
    else if (v.bytes.size >= 3 && std::memcmp(d, kJpeg, 3) == 0) out.image_mime = "image/jpeg";
    else if (v.bytes.size >= 12 && std::memcmp(d, "RIFF", 4) == 0 && std::memcmp(d + 8, "WEBP", 4) == 0)
      out.image_mime = "image/webp";
    else return;
    out.image.assign(d, d + v.bytes.size);
  }

  void emitMesh(size_t mesh_index, const Mat4& world, geo::MeshData& out) {
    const std::string where = "meshes[" + std::to_string(mesh_index) + "]";
    const json& mesh = element("meshes", mesh_index);
    const json* prims = arrayMember(mesh, "primitives", where);
    if (!prims) fail(where + ".primitives: required but missing");
    for (size_t k = 0; k < prims->size(); ++k) {
      const json& prim = object((*prims)[k], where + ".primitives[" + std::to_string(k) + "]");
      // Instanced meshes are decoded (Draco included) once.
      auto key = std::make_pair(mesh_index, k);
      auto it = cache_.find(key);
      if (it == cache_.end()) {
        Primitive p;
        if (!loadPrimitive(mesh_index, k, prim, p)) p = Primitive{};
        it = cache_.emplace(key, std::move(p)).first;
      }
      const std::array<float, 4> factor = baseColor(prim, where + ".primitives[" + std::to_string(k) + "]");
      append(it->second, world, factor, out);
    }
  }

  std::array<float, 4> baseColor(const json& prim, const std::string& where) const {
    std::array<float, 4> f{1, 1, 1, 1};
    if (!prim.contains("material")) return f;
    const size_t mi = index(prim, "material", where, count("materials"), "materials");
    const json& mat = element("materials", mi);
    auto pbr = mat.find("pbrMetallicRoughness");
    if (pbr == mat.end()) return f;
    const std::vector<double> c = numbers(object(*pbr, "materials[" + std::to_string(mi) + "].pbrMetallicRoughness"),
                                          "baseColorFactor", "materials[" + std::to_string(mi) + "].pbrMetallicRoughness", 4);
    for (size_t i = 0; i < c.size(); ++i) f[i] = static_cast<float>(c[i]);
    return f;
  }

  static void append(const Primitive& p, const Mat4& M, const std::array<float, 4>& factor, geo::MeshData& out) {
    if (p.indices.empty()) return;
    const double* m = M.m;
    // Inverse transpose of the upper 3x3 for normals = cofactor / det.
    const double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    const double cof[9] = {e * i - f * h, -(d * i - f * g), d * h - e * g,
                           -(b * i - c * h), a * i - c * g, -(a * h - b * g),
                           b * f - c * e, -(a * f - c * d), a * e - b * d};  // row-major cofactor matrix
    const double det = a * cof[0] + b * cof[1] + c * cof[2];
    const bool mirrored = det < 0;
    const double sign = mirrored ? -1.0 : 1.0;
    auto xform = [&](const float* v, float* o) {
      for (int r = 0; r < 3; ++r) {
        o[r] = static_cast<float>(m[r] * v[0] + m[4 + r] * v[1] + m[8 + r] * v[2] + m[12 + r]);
        // Finite inputs can still overflow float under a huge node scale.
        if (!std::isfinite(o[r])) fail("a node transform moves a position out of float range");
      }
    };
    auto xformNormal = [&](const float* n, float* o) {
      double r[3];
      for (int k = 0; k < 3; ++k) r[k] = sign * (cof[k * 3] * n[0] + cof[k * 3 + 1] * n[1] + cof[k * 3 + 2] * n[2]);
      const double len = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      if (len > 1e-30 && std::isfinite(len)) {
        for (int k = 0; k < 3; ++k) o[k] = static_cast<float>(r[k] / len);
      } else {
        o[0] = 0, o[1] = 1, o[2] = 0;
      }
    };
    auto pushColor = [&](size_t v) {
      float rgba[4] = {1, 1, 1, 1};
      if (!p.colors.empty()) std::copy(&p.colors[v * 4], &p.colors[v * 4] + 4, rgba);
      for (int k = 0; k < 3; ++k) out.colors.push_back(linearToSrgbByteFast(rgba[k] * factor[k]));
      out.colors.push_back(unitToByte(rgba[3] * factor[3]));
    };
    // Texture coordinates are kept when every primitive so far has them.
    const bool uv = !p.texcoords.empty() && out.texcoords.size() == out.vertexCount() * 2;
    if (!uv) out.texcoords.clear();
    auto pushUv = [&](size_t v) {
      if (uv) out.texcoords.insert(out.texcoords.end(), &p.texcoords[v * 2], &p.texcoords[v * 2] + 2);
    };
    const bool flat = p.normals.empty();
    const size_t added_vertices = flat ? p.indices.size() : p.positions.size() / 3;
    if (out.vertexCount() + added_vertices > kMaxDecodedVertices || out.indices.size() + p.indices.size() > 3 * kMaxDecodedVertices)
      fail("decoded mesh exceeds " + std::to_string(kMaxDecodedVertices) + " vertices", Status::Unsupported);
    const auto base = static_cast<uint32_t>(out.vertexCount());
    if (base == 0) {  // the usual single primitive: one allocation per array
      out.positions.reserve(added_vertices * 3);
      out.normals.reserve(added_vertices * 3);
      out.colors.reserve(added_vertices * 4);
      if (uv) out.texcoords.reserve(added_vertices * 2);
      out.indices.reserve(p.indices.size());
    }
    if (!flat) {
      const size_t n = p.positions.size() / 3;
      for (size_t v = 0; v < n; ++v) {
        float o[3];
        xform(&p.positions[v * 3], o);
        out.positions.insert(out.positions.end(), o, o + 3);
        xformNormal(&p.normals[v * 3], o);
        out.normals.insert(out.normals.end(), o, o + 3);
        pushColor(v);
        pushUv(v);
      }
      for (size_t t = 0; t + 2 < p.indices.size(); t += 3) {
        const uint32_t i0 = p.indices[t], i1 = p.indices[t + 1], i2 = p.indices[t + 2];
        out.indices.insert(out.indices.end(), {base + i0, base + (mirrored ? i2 : i1), base + (mirrored ? i1 : i2)});
      }
      return;
    }
    // No normals: flat shading, so each triangle gets its own three vertices.
    for (size_t t = 0; t + 2 < p.indices.size(); t += 3) {
      uint32_t tri[3] = {p.indices[t], p.indices[t + 1], p.indices[t + 2]};
      if (mirrored) std::swap(tri[1], tri[2]);
      float q[3][3];
      for (int k = 0; k < 3; ++k) xform(&p.positions[tri[k] * 3], q[k]);
      const double u[3] = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
      const double w[3] = {q[2][0] - q[0][0], q[2][1] - q[0][1], q[2][2] - q[0][2]};
      double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
      const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
      float fn[3] = {0, 1, 0};
      if (len > 1e-30 && std::isfinite(len))
        for (int k = 0; k < 3; ++k) fn[k] = static_cast<float>(nrm[k] / len);
      const auto first = static_cast<uint32_t>(out.vertexCount());
      for (int k = 0; k < 3; ++k) {
        out.positions.insert(out.positions.end(), q[k], q[k] + 3);
        out.normals.insert(out.normals.end(), fn, fn + 3);
        pushColor(tri[k]);
        pushUv(tri[k]);
        out.indices.push_back(first + static_cast<uint32_t>(k));
      }
    }
  }

  struct Stored {
    const uint8_t* data = nullptr;
    size_t size = 0;
    std::vector<uint8_t> owned;
  };

  const json& doc_;
  const uint8_t* bin_;
  size_t bin_size_;
  std::map<size_t, Stored> buffers_;
  std::map<size_t, std::vector<uint8_t>> views_;  // decoded EXT_meshopt_compression views
  std::map<std::pair<size_t, size_t>, Primitive> cache_;
  uint32_t level_ = 0;
  size_t substituted_ = 0;  // nodes replaced by their MSFT_lod level
};

uint32_t readU32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

}  // namespace

namespace glb_detail {

core::Status splitChunks(const uint8_t* data, size_t size, Chunks& c, std::string& err) {
  if (data == nullptr || size < 12) {
    err = "GLB: " + std::to_string(size) + " bytes, shorter than the 12-byte header";
    return core::Status::Corrupt;
  }
  if (readU32(data) != kGlbMagic) {
    err = "GLB: not a glTF binary (bad magic)";
    return core::Status::Corrupt;
  }
  const uint32_t version = readU32(data + 4), length = readU32(data + 8);
  if (version != 2) {
    err = "GLB: container version " + std::to_string(version) + " (only 2 is supported)";
    return core::Status::Unsupported;
  }
  if (length > size || length < 20) {
    err = "GLB: header says " + std::to_string(length) + " bytes, " + std::to_string(size) + " available";
    return core::Status::Corrupt;
  }
  size_t pos = 12;
  for (int chunk = 0; pos < length; ++chunk) {
    if (length - pos < 8) {
      err = "GLB: chunk " + std::to_string(chunk) + " header at offset " + std::to_string(pos) + " is truncated";
      return core::Status::Corrupt;
    }
    const uint32_t clen = readU32(data + pos), ctype = readU32(data + pos + 4);
    if (clen > length - pos - 8) {
      err = "GLB: chunk " + std::to_string(chunk) + " at offset " + std::to_string(pos) + ": length " +
            std::to_string(clen) + " runs past the GLB (" + std::to_string(length) + " bytes)";
      return core::Status::Corrupt;
    }
    const uint8_t* body = data + pos + 8;
    if (chunk == 0) {
      if (ctype != kChunkJson) {
        err = "GLB: first chunk is not JSON";
        return core::Status::Corrupt;
      }
      c.json_data = body;
      c.json_size = clen;
    } else if (chunk == 1 && ctype == kChunkBin) {
      c.bin = body;
      c.bin_size = clen;
    }
    pos += 8 + size_t{clen};
    pos = (pos + 3) & ~size_t{3};  // chunks are 4-aligned; tolerate writers that forget the padding
  }
  if (!c.json_data) {
    err = "GLB: no JSON chunk";
    return core::Status::Corrupt;
  }
  return core::Status::Ok;
}
}  // namespace glb_detail

const char* glbCodecName(GlbCodec c) {
  switch (c) {
    case GlbCodec::Plain: return "plain";
    case GlbCodec::Draco: return "draco";
    case GlbCodec::Meshopt: return "meshopt";
  }
  return "?";
}

bool parseGlbCodec(const std::string& name, GlbCodec& out) {
  for (GlbCodec c : {GlbCodec::Plain, GlbCodec::Draco, GlbCodec::Meshopt})
    if (name == glbCodecName(c)) {
      out = c;
      return true;
    }
  return false;
}

Status decodeGlb(const uint8_t* data, size_t size, geo::MeshData& out, std::string& err) {
  return decodeGlbLevel(data, size, 0, out, err);
}

// Empties `j` leaves first. nlohmann's destructor of a non-empty array or
// object allocates (it moves the children onto a heap stack); emptied from
// the leaves up, nothing does, so closing a document cannot throw
// std::bad_alloc out of a destructor where memory has run out.
namespace {
void drainJson(json& j) noexcept {
  if (!j.is_array() && !j.is_object()) return;
  for (json& child : j) drainJson(child);
  if (j.is_array()) j.get_ref<json::array_t&>().clear();
  else j.get_ref<json::object_t&>().clear();
}
}  // namespace

struct GlbDocument::Impl {
  json doc;
  const uint8_t* bin = nullptr;
  size_t bin_size = 0;
  ~Impl() { drainJson(doc); }
};

GlbDocument::GlbDocument() = default;
GlbDocument::~GlbDocument() = default;
GlbDocument::GlbDocument(GlbDocument&&) noexcept = default;
GlbDocument& GlbDocument::operator=(GlbDocument&&) noexcept = default;

bool GlbDocument::isOpen() const { return impl_ != nullptr; }

Status GlbDocument::open(const uint8_t* data, size_t size, std::string& err) {
  impl_.reset();
  Chunks c;
  if (const Status st = splitChunks(data, size, c, err); st != Status::Ok) return st;
  try {
    auto impl = std::make_unique<Impl>();
    impl->doc = json::parse(c.json_data, c.json_data + c.json_size);
    if (!impl->doc.is_object()) {
      err = "GLB: JSON chunk is not an object";
      return Status::Corrupt;
    }
    impl->bin = c.bin;
    impl->bin_size = c.bin_size;
    impl_ = std::move(impl);
    return Status::Ok;
  } catch (const json::exception& e) {
    err = std::string("GLB: JSON: ") + e.what();
    return Status::Corrupt;
  } catch (const std::bad_alloc&) {
    err = "GLB: out of memory while parsing the JSON";
    return Status::NoMem;
  }
}

Status GlbDocument::decodeLevel(uint32_t level, geo::MeshData& out, std::string& err) const {
  out.clear();
  if (!impl_) {
    err = "GLB: document not open";
    return Status::Corrupt;
  }
  try {
    Decoder(impl_->doc, impl_->bin, impl_->bin_size, level).run(out);
    return Status::Ok;
  } catch (const DecodeError& e) {
    err = "GLB: " + e.message;
    out.clear();
    return e.status;
  } catch (const json::exception& e) {
    err = std::string("GLB: JSON: ") + e.what();
    out.clear();
    return Status::Corrupt;
  } catch (const std::bad_alloc&) {
    err = "GLB: out of memory while decoding";
    out.clear();
    return Status::NoMem;
  } catch (const std::exception& e) {
    err = std::string("GLB: ") + e.what();
    out.clear();
    return Status::Corrupt;
  }
}

Status decodeGlbLevel(const uint8_t* data, size_t size, uint32_t level, geo::MeshData& out, std::string& err) {
  out.clear();
  GlbDocument doc;
  if (const Status st = doc.open(data, size, err); st != Status::Ok) return st;
  return doc.decodeLevel(level, out, err);
}

}  // namespace blvd::package
