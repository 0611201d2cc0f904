// GLB encoder (tools: the bake, `blvd pack`; not in libblvd). glTF 2.0 spec:
// registry.khronos.org/glTF/specs/2.0; the extensions it writes are listed in
// glb_decode.cpp, which reads them.
#include "package/glb.h"
#include "package/glb_detail.h"

#include <draco/compression/encode.h>
#include <draco/core/encoder_buffer.h>
#include <draco/mesh/mesh.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
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

const std::array<uint8_t, 256>& srgbToLinearBytes() {
  static const std::array<uint8_t, 256> lut = [] {
    std::array<uint8_t, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = unitToByte(srgbToLinear(i / 255.0f));
    return t;
  }();
  return lut;
}

// ---------------------------------------------------------------- encoder ---

int componentForIndices(size_t vertex_count) {
  return vertex_count <= 0xFFFF ? kUnsignedShort : kUnsignedInt;
}

void validateMesh(const geo::MeshData& m, const GlbOptions& opt, const std::string& where) {
  auto bad = [&](const std::string& why) {
    throw core::Error(Status::InvalidArg, "encodeGlb: " + where + why);
  };
  if (m.positions.size() % 3) bad("positions.size() is not a multiple of 3");
  const size_t n = m.vertexCount();
  if (n > std::numeric_limits<uint32_t>::max()) bad("more than 2^32 vertices");
  if (!m.normals.empty() && m.normals.size() != m.positions.size())
    bad("normals.size() " + std::to_string(m.normals.size()) + " != positions.size() " +
        std::to_string(m.positions.size()));
  if (!m.colors.empty() && m.colors.size() != n * 4)
    bad("colors.size() " + std::to_string(m.colors.size()) + " != 4 * vertex count " +
        std::to_string(n));
  if (!m.texcoords.empty() && m.texcoords.size() != n * 2)
    bad("texcoords.size() " + std::to_string(m.texcoords.size()) + " != 2 * vertex count " + std::to_string(n));
  for (size_t i = 0; i < m.texcoords.size(); ++i)
    if (!std::isfinite(m.texcoords[i])) bad("texcoord component " + std::to_string(i) + " is not finite");
  if (!m.image.empty() && m.texcoords.empty()) bad("an image without texcoords");
  if (!m.image.empty() && m.image_mime != "image/png" && m.image_mime != "image/jpeg" && m.image_mime != "image/webp")
    bad("image_mime must be image/png, image/jpeg or image/webp, is '" + m.image_mime + "'");
  if (m.indices.size() % 3) bad("indices.size() is not a multiple of 3");
  for (size_t i = 0; i < m.indices.size(); ++i)
    if (m.indices[i] >= n)
      bad("index " + std::to_string(i) + " = " + std::to_string(m.indices[i]) +
          " >= vertex count " + std::to_string(n));
  for (size_t i = 0; i < m.positions.size(); ++i)
    if (!std::isfinite(m.positions[i])) bad("position component " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < m.normals.size(); ++i)
    if (!std::isfinite(m.normals[i])) bad("normal component " + std::to_string(i) + " is not finite");
  auto bits = [&](int b, const char* what) {
    if (b < 0 || b > 30) bad(std::string(what) + " must be 0..30, is " + std::to_string(b));
  };
  bits(opt.position_bits, "position_bits");
  bits(opt.normal_bits, "normal_bits");
  bits(opt.color_bits, "color_bits");
  bits(opt.texcoord_bits, "texcoord_bits");
  if (opt.meshopt_position_bits < 0 || opt.meshopt_position_bits > 24)
    bad("meshopt_position_bits must be 0..24, is " + std::to_string(opt.meshopt_position_bits));
  if (opt.compression_level < 0 || opt.compression_level > 10)
    bad("compression_level must be 0..10, is " + std::to_string(opt.compression_level));
}

// A projection that does not give the mesh's own texcoords would move the
// texture: refused before the texcoords are dropped.
void validateProjection(const geo::MeshData& m, const TexcoordProjection& proj) {
  auto bad = [&](const std::string& why) {
    throw core::Error(Status::InvalidArg, "encodeGlb: texcoord projection: " + why);
  };
  if (proj.shots.empty() || proj.shots.size() > 256) bad(std::to_string(proj.shots.size()) + " shots (1 to 256)");
  if (m.texcoords.empty()) bad("the mesh has no texcoords to project");
  if (proj.vertex_shot.size() != m.vertexCount())
    bad(std::to_string(proj.vertex_shot.size()) + " vertex shots for " + std::to_string(m.vertexCount()) + " vertices");
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    const uint8_t k = proj.vertex_shot[v];
    if (k >= proj.shots.size()) bad("vertex " + std::to_string(v) + " names shot " + std::to_string(k));
    float uv[2] = {0.0f, 0.0f};
    const bool ok = projectTexcoord(proj.shots[k].matrix, proj.shots[k].rect, &m.positions[3 * v], uv);
    if (!ok || std::fabs(uv[0] - m.texcoords[2 * v]) > kProjectedTexcoordTolerance ||
        std::fabs(uv[1] - m.texcoords[2 * v + 1]) > kProjectedTexcoordTolerance)
      bad("vertex " + std::to_string(v) + " projects to (" + std::to_string(uv[0]) + ", " + std::to_string(uv[1]) +
          "), its texcoord is (" + std::to_string(m.texcoords[2 * v]) + ", " + std::to_string(m.texcoords[2 * v + 1]) +
          ")");
  }
}

std::vector<uint8_t> assembleGlb(const json& doc, const std::vector<uint8_t>& bin) {
  std::string text = doc.dump();
  while (text.size() % 4) text.push_back(' ');  // JSON chunk pads with spaces (spec)
  const size_t bin_padded = (bin.size() + 3) / 4 * 4;
  const size_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin_padded);
  if (total > std::numeric_limits<uint32_t>::max())
    throw core::Error(Status::InvalidArg, "encodeGlb: GLB would exceed 4 GiB");
  std::vector<uint8_t> out;
  out.reserve(total);
  auto u32 = [&](uint32_t v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    out.insert(out.end(), p, p + 4);
  };
  u32(kGlbMagic);
  u32(2);
  u32(static_cast<uint32_t>(total));
  u32(static_cast<uint32_t>(text.size()));
  u32(kChunkJson);
  out.insert(out.end(), text.begin(), text.end());
  if (!bin.empty()) {
    u32(static_cast<uint32_t>(bin_padded));
    u32(kChunkBin);
    out.insert(out.end(), bin.begin(), bin.end());
    out.resize(total, 0);
  }
  return out;
}

json baseDocument() {
  json doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", "blvd"}};
  doc["scene"] = 0;
  return doc;
}

json material() {
  // White factor so COLOR_0 is the colour; rough dielectric, as buildings are.
  return json{{"pbrMetallicRoughness",
               {{"baseColorFactor", {1.0, 1.0, 1.0, 1.0}}, {"metallicFactor", 0.0},
                {"roughnessFactor", 1.0}}},
              {"doubleSided", false}};
}

void minMax(const float* p, size_t n, std::array<float, 3>& lo, std::array<float, 3>& hi) {
  lo = {0, 0, 0};
  hi = {0, 0, 0};
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const float v = p[i * 3 + k];
      if (i == 0 || v < lo[k]) lo[k] = v;
      if (i == 0 || v > hi[k]) hi[k] = v;
    }
}

std::vector<uint8_t> linearColors(const geo::MeshData& mesh) {
  const auto& lut = srgbToLinearBytes();
  std::vector<uint8_t> c(mesh.colors.size());
  for (size_t i = 0; i < c.size(); ++i) c[i] = (i % 4 == 3) ? mesh.colors[i] : lut[mesh.colors[i]];
  return c;
}

// The buffers, views and accessors of a GLB under construction; each level
// of detail adds one primitive to them.
struct Parts {
  std::vector<uint8_t> bin;
  json views = json::array(), accessors = json::array();
  // EXT_meshopt_compression: the decoded views' layout in buffer 1, a
  // fallback buffer without data (the extension's "Fallback buffers").
  size_t fallback_bytes = 0;
  bool quantized = false;  // a view uses KHR_mesh_quantization's types

  // One compressed view: its bytes in the BIN chunk, its decoded layout
  // (count x stride) in the fallback buffer. Vertex views state byteStride,
  // index views must not (glTF 2.0: byteStride is for vertex attributes only).
  size_t addMeshoptView(const std::vector<uint8_t>& compressed, size_t count, size_t stride, MeshoptMode mode,
                        MeshoptFilter filter, int target) {
    while (bin.size() % 4) bin.push_back(0);
    const size_t off = bin.size();
    bin.insert(bin.end(), compressed.begin(), compressed.end());
    fallback_bytes = (fallback_bytes + 3) / 4 * 4;
    json ext = {{"buffer", 0}, {"byteOffset", off}, {"byteLength", compressed.size()}, {"byteStride", stride},
                {"count", count}, {"mode", meshoptModeName(mode)}};
    if (filter != MeshoptFilter::None) ext["filter"] = meshoptFilterName(filter);
    json v = {{"buffer", 1}, {"byteOffset", fallback_bytes}, {"byteLength", count * stride}, {"target", target}};
    if (mode == MeshoptMode::Attributes) v["byteStride"] = stride;
    v["extensions"] = {{"EXT_meshopt_compression", ext}};
    fallback_bytes += count * stride;
    views.push_back(v);
    return views.size() - 1;
  }

  size_t addView(const void* p, size_t bytes, std::optional<int> target) {
    while (bin.size() % 4) bin.push_back(0);
    const size_t off = bin.size();
    bin.insert(bin.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + bytes);
    json v = {{"buffer", 0}, {"byteOffset", off}, {"byteLength", bytes}};
    if (target) v["target"] = *target;
    views.push_back(v);
    return views.size() - 1;
  }
};

// Puts the mesh's image (if any) at the end of the BIN data as its own
// bufferView and makes it material 0's unlit base colour texture.
void addImage(const geo::MeshData& mesh, json& doc, Parts& parts) {
  if (mesh.image.empty()) return;
  const size_t view = parts.addView(mesh.image.data(), mesh.image.size(), std::nullopt);
  doc["images"] = json::array({{{"bufferView", view}, {"mimeType", mesh.image_mime}}});
  // 9729 LINEAR, 9987 LINEAR_MIPMAP_LINEAR, 33071 CLAMP_TO_EDGE.
  doc["samplers"] = json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 33071}, {"wrapT", 33071}}});
  // A WebP image is the texture's source through EXT_texture_webp (required:
  // there is no PNG/JPEG fallback), as that extension's specification says.
  if (mesh.image_mime == "image/webp")
    doc["textures"] = json::array({{{"sampler", 0}, {"extensions", {{"EXT_texture_webp", {{"source", 0}}}}}}});
  else
    doc["textures"] = json::array({{{"source", 0}, {"sampler", 0}}});
  json& mat = doc["materials"][0];
  mat["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  mat["extensions"] = {{"KHR_materials_unlit", json::object()}};
}

// What the decoder makes of `points` vertices and `faces` triangles: a mesh
// without normals is unwelded into flat-shaded triangles.
GlbMeshCounts decodedCounts(const geo::MeshData& mesh, size_t points, size_t faces) {
  GlbMeshCounts c;
  c.triangles = static_cast<uint32_t>(faces);
  c.vertices = static_cast<uint32_t>(mesh.normals.empty() ? faces * 3 : points);
  return c;
}

// Plain buffers: POSITION/NORMAL float32, COLOR_0 unorm8 RGBA, indices u16/u32.
json addPlainPrimitive(const geo::MeshData& mesh, Parts& parts, GlbMeshCounts& counts) {
  const size_t n = mesh.vertexCount();
  json& accessors = parts.accessors;
  json attributes = json::object();
  std::array<float, 3> lo, hi;
  minMax(mesh.positions.data(), n, lo, hi);
  attributes["POSITION"] = accessors.size();
  accessors.push_back({{"bufferView", parts.addView(mesh.positions.data(), n * 12, kArrayBuffer)},
                       {"componentType", kFloat}, {"count", n}, {"type", "VEC3"},
                       {"min", lo}, {"max", hi}});
  if (!mesh.normals.empty()) {
    attributes["NORMAL"] = accessors.size();
    accessors.push_back({{"bufferView", parts.addView(mesh.normals.data(), n * 12, kArrayBuffer)},
                         {"componentType", kFloat}, {"count", n}, {"type", "VEC3"}});
  }
  if (!mesh.colors.empty()) {
    const std::vector<uint8_t> lin = linearColors(mesh);
    attributes["COLOR_0"] = accessors.size();
    accessors.push_back({{"bufferView", parts.addView(lin.data(), lin.size(), kArrayBuffer)},
                         {"componentType", kUnsignedByte}, {"normalized", true},
                         {"count", n}, {"type", "VEC4"}});
  }
  if (!mesh.texcoords.empty()) {
    attributes["TEXCOORD_0"] = accessors.size();
    accessors.push_back({{"bufferView", parts.addView(mesh.texcoords.data(), n * 8, kArrayBuffer)},
                         {"componentType", kFloat}, {"count", n}, {"type", "VEC2"}});
  }
  const int ictype = componentForIndices(n);
  size_t iview;
  if (ictype == kUnsignedShort) {
    std::vector<uint16_t> idx(mesh.indices.begin(), mesh.indices.end());
    iview = parts.addView(idx.data(), idx.size() * 2, kElementArrayBuffer);
  } else {
    iview = parts.addView(mesh.indices.data(), mesh.indices.size() * 4, kElementArrayBuffer);
  }
  const size_t iacc = accessors.size();
  accessors.push_back({{"bufferView", iview}, {"componentType", ictype},
                       {"count", mesh.indices.size()}, {"type", "SCALAR"}});
  counts = decodedCounts(mesh, n, mesh.triangleCount());
  return {{"attributes", attributes}, {"indices", iacc}, {"material", 0}, {"mode", kModeTriangles}};
}

// The unique ids of a Draco mesh's attributes (those present).
struct DracoIds {
  uint32_t pos = 0;
  std::optional<uint32_t> nrm, col, tex, shot;
};

// `mesh` as a Draco mesh: positions as GENERIC, then normals, linear
// colours (`lin` keeps their bytes), uv unless projected, and the shot
// index of a projection with several captures.
DracoIds dracoMeshOf(const geo::MeshData& mesh, const TexcoordProjection* proj, draco::Mesh& dm,
                     std::vector<uint8_t>& lin) {
  const size_t n = mesh.vertexCount();
  dm.set_num_points(static_cast<uint32_t>(n));
  auto addAttribute = [&](draco::GeometryAttribute::Type type, int comps, draco::DataType dt,
                          bool normalized, size_t elem_bytes, const void* src) {
    draco::GeometryAttribute ga;
    ga.Init(type, nullptr, static_cast<uint8_t>(comps), dt, normalized,
            static_cast<int64_t>(elem_bytes), 0);
    const int id = dm.AddAttribute(ga, true, static_cast<uint32_t>(n));
    draco::PointAttribute* pa = dm.attribute(id);
    const auto* p = static_cast<const uint8_t*>(src);
    for (size_t i = 0; i < n; ++i)
      pa->SetAttributeValue(draco::AttributeValueIndex(static_cast<uint32_t>(i)), p + i * elem_bytes);
    return pa->unique_id();
  };
  DracoIds ids;
  // Positions as GENERIC, not POSITION: a Draco stream with a POSITION
  // attribute is refused by our decoder (draco_decode.cpp says why). Without
  // one, Draco's edgebreaker must split the mesh on attribute seams
  // (split_mesh_on_seams, encodeDraco): its per-attribute connectivity is
  // built around the POSITION attribute.
  ids.pos = addAttribute(draco::GeometryAttribute::GENERIC, 3, draco::DT_FLOAT32, false, 12, mesh.positions.data());
  if (!mesh.normals.empty())
    ids.nrm = addAttribute(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32, false, 12, mesh.normals.data());
  if (!mesh.colors.empty()) {
    lin = linearColors(mesh);
    ids.col = addAttribute(draco::GeometryAttribute::COLOR, 4, draco::DT_UINT8, true, 4, lin.data());
  }
  if (!mesh.texcoords.empty() && !proj)
    ids.tex = addAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32, false, 8, mesh.texcoords.data());
  if (proj && proj->shots.size() > 1)  // an integer attribute: Draco quantizes only floats
    ids.shot = addAttribute(draco::GeometryAttribute::GENERIC, 1, draco::DT_UINT8, false, 1, proj->vertex_shot.data());
  dm.SetNumFaces(mesh.triangleCount());
  for (size_t f = 0; f < mesh.triangleCount(); ++f) {
    draco::Mesh::Face face;
    for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(mesh.indices[f * 3 + k]);
    dm.SetFace(draco::FaceIndex(static_cast<uint32_t>(f)), face);
  }
  return ids;
}

void encodeDraco(draco::Mesh& dm, const GlbOptions& opt, draco::EncoderBuffer& eb) {
  draco::Encoder enc;
  if (opt.position_bits > 0) enc.SetAttributeQuantization(draco::GeometryAttribute::GENERIC, opt.position_bits);
  if (opt.normal_bits > 0) enc.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, opt.normal_bits);
  if (opt.color_bits > 0) enc.SetAttributeQuantization(draco::GeometryAttribute::COLOR, opt.color_bits);
  if (opt.texcoord_bits > 0) enc.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, opt.texcoord_bits);
  const int speed = 10 - opt.compression_level;
  enc.SetSpeedOptions(speed, speed);
  enc.options().SetGlobalBool("split_mesh_on_seams", true);
  const draco::Status st = enc.EncodeMeshToBuffer(dm, &eb);
  if (!st.ok()) throw core::Error(Status::Internal, std::string("encodeGlb: Draco encoder: ") + st.error_msg());
}

// The bounds of the positions `back` decoded to (attribute `pos_id`).
void decodedBounds(const draco::Mesh& back, uint32_t pos_id, std::array<float, 3>& lo, std::array<float, 3>& hi) {
  const draco::PointAttribute* bpos = back.GetAttributeByUniqueId(pos_id);
  if (!bpos) throw core::Error(Status::Internal, "encodeGlb: Draco lost the position attribute");
  lo = hi = {0, 0, 0};
  for (draco::PointIndex i(0); i < back.num_points(); ++i) {
    float v[3] = {0, 0, 0};
    if (!bpos->ConvertValue<float>(bpos->mapped_index(i), 3, v))
      throw core::Error(Status::Internal, "encodeGlb: Draco's decoded POSITION is not 3 floats");
    for (int k = 0; k < 3; ++k) {
      if (i.value() == 0 || v[k] < lo[k]) lo[k] = v[k];
      if (i.value() == 0 || v[k] > hi[k]) hi[k] = v[k];
    }
  }
}

json addDracoPrimitive(const geo::MeshData& mesh, const GlbOptions& opt, Parts& parts, GlbMeshCounts& counts) {
  const TexcoordProjection* proj = opt.projection;
  draco::Mesh dm;
  std::vector<uint8_t> lin;
  const DracoIds ids = dracoMeshOf(mesh, proj, dm, lin);
  draco::EncoderBuffer eb;
  encodeDraco(dm, opt, eb);

  // The accessors must state what a client will decode: Draco may drop
  // degenerate faces and unreferenced points, or split non-manifold vertices,
  // so counts and the quantized bounds come from decoding our own output (it
  // also proves the blob decodes before it goes into a package).
  const auto* bytes = reinterpret_cast<const uint8_t*>(eb.data());
  std::unique_ptr<draco::Mesh> back;
  std::string err;
  if (decodeDracoBuffer(bytes, eb.size(), back, err) != Status::Ok)
    throw core::Error(Status::Internal, "encodeGlb: own Draco output does not decode: " + err);
  const size_t points = back->num_points();
  std::array<float, 3> lo, hi;
  decodedBounds(*back, ids.pos, lo, hi);

  const size_t view = parts.addView(bytes, eb.size(), std::nullopt);
  json& accessors = parts.accessors;
  json attributes = json::object(), draco_attrs = json::object();
  const int ictype = componentForIndices(points);
  const size_t iacc = accessors.size();
  accessors.push_back({{"componentType", ictype}, {"count", back->num_faces() * 3}, {"type", "SCALAR"}});
  auto accessor = [&](const char* name, uint32_t id, json acc) {
    attributes[name] = accessors.size();
    draco_attrs[name] = id;
    acc["count"] = points;
    accessors.push_back(std::move(acc));
  };
  accessor("POSITION", ids.pos, {{"componentType", kFloat}, {"type", "VEC3"}, {"min", lo}, {"max", hi}});
  if (ids.nrm) accessor("NORMAL", *ids.nrm, {{"componentType", kFloat}, {"type", "VEC3"}});
  if (ids.col) accessor("COLOR_0", *ids.col, {{"componentType", kUnsignedByte}, {"normalized", true}, {"type", "VEC4"}});
  if (ids.tex) accessor("TEXCOORD_0", *ids.tex, {{"componentType", kFloat}, {"type", "VEC2"}});
  if (ids.shot) accessor(kShotAttribute, *ids.shot, {{"componentType", kUnsignedByte}, {"type", "SCALAR"}});
  counts = decodedCounts(mesh, points, back->num_faces());
  json ext = {{"KHR_draco_mesh_compression", {{"bufferView", view}, {"attributes", draco_attrs}}}};
  if (proj) {
    static_assert(sizeof(TexcoordProjection::Shot) == kProjectionShotBytes, "16 floats a shot");
    const size_t shots = parts.addView(proj->shots.data(), proj->shots.size() * kProjectionShotBytes, std::nullopt);
    ext[kProjectedTexcoords] = {{"bufferView", shots}, {"count", proj->shots.size()}};
  }
  return {{"attributes", attributes}, {"indices", iacc}, {"material", 0}, {"mode", kModeTriangles},
          {"extensions", ext}};
}

// One vertex attribute's elements as its meshopt view holds them.
struct RawAttribute {
  std::vector<uint8_t> bytes;
  size_t stride = 12;
  MeshoptFilter filter = MeshoptFilter::None;
  int ctype = kFloat;
};

// POSITION: float32, exponential filter (one exponent per vertex).
RawAttribute rawPositions(const std::vector<float>& pos, size_t n, const GlbOptions& opt) {
  RawAttribute r;
  r.bytes.resize(n * 12);
  if (opt.meshopt_position_bits > 0) {
    meshopt_encodeFilterExp(r.bytes.data(), n, 12, opt.meshopt_position_bits, pos.data());
    r.filter = MeshoptFilter::Exponential;
  } else {
    std::memcpy(r.bytes.data(), pos.data(), r.bytes.size());
  }
  return r;
}

// NORMAL: octahedral filter into snorm8 (bits <= 8) or snorm16 (4 or 8
// bytes per vertex, the 4th component unused), or float32.
RawAttribute rawNormals(const std::vector<float>& nrm, size_t n, const GlbOptions& opt, Parts& parts) {
  RawAttribute r;
  if (opt.normal_bits <= 0) {
    r.bytes.resize(n * 12);
    std::memcpy(r.bytes.data(), nrm.data(), r.bytes.size());
    return r;
  }
  const int bits = std::min(opt.normal_bits, 16);
  r.stride = bits <= 8 ? 4 : 8;
  r.ctype = bits <= 8 ? kByte : kShort;
  r.filter = MeshoptFilter::Octahedral;
  std::vector<float> v4(n * 4, 0.0f);
  for (size_t v = 0; v < n; ++v) {
    const float* p = &nrm[v * 3];
    const float len = std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]);
    if (len > 0) std::copy(p, p + 3, &v4[v * 4]);
    else v4[v * 4 + 2] = 1.0f;  // the filter divides by the L1 length
  }
  r.bytes.resize(n * r.stride);
  meshopt_encodeFilterOct(r.bytes.data(), n, r.stride, bits, v4.data());
  parts.quantized = true;
  return r;
}

// TEXCOORD_0: unorm16 when every uv is in [0, 1] (impostor uvs are), else float32.
RawAttribute rawTexcoords(const std::vector<float>& uv, const GlbOptions& opt, Parts& parts) {
  RawAttribute r;
  r.stride = 8;
  const bool unit =
      opt.texcoord_bits > 0 && std::all_of(uv.begin(), uv.end(), [](float t) { return t >= 0.0f && t <= 1.0f; });
  if (!unit) {
    r.bytes.resize(uv.size() * 4);
    std::memcpy(r.bytes.data(), uv.data(), r.bytes.size());
    return r;
  }
  r.stride = 4;
  r.ctype = kUnsignedShort;
  std::vector<uint16_t> q(uv.size());
  for (size_t i = 0; i < uv.size(); ++i) q[i] = static_cast<uint16_t>(meshopt_quantizeUnorm(uv[i], 16));
  r.bytes.resize(q.size() * 2);
  std::memcpy(r.bytes.data(), q.data(), r.bytes.size());
  parts.quantized = true;
  return r;
}

std::vector<uint8_t> ownMeshoptDecode(const std::vector<uint8_t>& c, size_t count, size_t stride, MeshoptMode mode,
                                      MeshoptFilter f) {
  std::vector<uint8_t> back;
  std::string err;
  if (decodeMeshoptView(c.data(), c.size(), {mode, f, count, stride}, back, err) != Status::Ok)
    throw core::Error(Status::Internal, "encodeGlb: own meshopt output does not decode: " + err);
  return back;
}

// The index codec keeps the triangles and their winding but may rotate a
// triangle's corners: `back` (decoded, isize bytes an index) must hold
// `idx`'s triangles so.
void checkOwnTriangles(const std::vector<uint8_t>& back, const std::vector<uint32_t>& idx, size_t isize) {
  for (size_t t = 0; t < idx.size(); t += 3) {
    uint32_t v[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) std::memcpy(&v[k], &back[(t + k) * isize], isize);
    bool same = false;
    for (int r = 0; r < 3 && !same; ++r)
      same = v[r] == idx[t] && v[(r + 1) % 3] == idx[t + 1] && v[(r + 2) % 3] == idx[t + 2];
    if (!same) throw core::Error(Status::Internal, "encodeGlb: own meshopt triangle " + std::to_string(t / 3) +
                                                       " decodes to other corners");
  }
}

// EXT_meshopt_compression over KHR_mesh_quantization types, as the
// extension's "Compressing geometry data" advises: triangles in vertex-cache
// order, vertices in the order the triangles first use them (so the codecs'
// deltas are small), then each attribute and the indices as one compressed
// view. Like Draco this reorders vertices and triangles, and it drops
// vertices no triangle uses. The accessors' counts and POSITION bounds come
// from decoding our own views, which also proves they decode.
json addMeshoptPrimitive(const geo::MeshData& mesh, const GlbOptions& opt, Parts& parts, GlbMeshCounts& counts) {
  const size_t n0 = mesh.vertexCount(), ni = mesh.indices.size();
  std::vector<uint32_t> idx(ni), remap(n0);
  meshopt_optimizeVertexCache(idx.data(), mesh.indices.data(), ni, n0);
  const size_t n = meshopt_optimizeVertexFetchRemap(remap.data(), idx.data(), ni, n0);
  meshopt_remapIndexBuffer(idx.data(), idx.data(), ni, remap.data());
  auto reordered = [&](const auto& src, size_t comps) {
    std::remove_cv_t<std::remove_reference_t<decltype(src)>> out(n * comps);
    if (!src.empty())
      meshopt_remapVertexBuffer(out.data(), src.data(), n0, comps * sizeof(src[0]), remap.data());
    return out;
  };
  json& accessors = parts.accessors;
  json attributes = json::object();
  // One vertex attribute: its raw elements compressed into a view, and its accessor.
  auto attribute = [&](const char* name, const RawAttribute& r, const char* type) {
    const std::vector<uint8_t> c = encodeMeshoptAttributes(r.bytes.data(), n, r.stride);
    json acc = {{"bufferView", parts.addMeshoptView(c, n, r.stride, MeshoptMode::Attributes, r.filter, kArrayBuffer)},
                {"componentType", r.ctype}, {"count", n}, {"type", type}};
    if (r.ctype != kFloat) acc["normalized"] = true;
    attributes[name] = accessors.size();
    accessors.push_back(acc);
    return c;
  };
  {
    const RawAttribute pos = rawPositions(reordered(mesh.positions, 3), n, opt);
    const std::vector<uint8_t> back =
        ownMeshoptDecode(attribute("POSITION", pos, "VEC3"), n, 12, MeshoptMode::Attributes, pos.filter);
    std::array<float, 3> lo, hi;
    minMax(reinterpret_cast<const float*>(back.data()), n, lo, hi);
    accessors.back()["min"] = lo;
    accessors.back()["max"] = hi;
  }
  if (!mesh.normals.empty()) attribute("NORMAL", rawNormals(reordered(mesh.normals, 3), n, opt, parts), "VEC3");
  if (!mesh.colors.empty()) {
    RawAttribute col;
    col.bytes = reordered(linearColors(mesh), 4);
    col.stride = 4;
    col.ctype = kUnsignedByte;
    attribute("COLOR_0", col, "VEC4");
  }
  if (!mesh.texcoords.empty()) attribute("TEXCOORD_0", rawTexcoords(reordered(mesh.texcoords, 2), opt, parts), "VEC2");
  const int ictype = componentForIndices(n);
  const size_t isize = ictype == kUnsignedShort ? 2 : 4;
  const std::vector<uint8_t> ic = encodeMeshoptTriangles(idx.data(), ni, n);
  checkOwnTriangles(ownMeshoptDecode(ic, ni, isize, MeshoptMode::Triangles, MeshoptFilter::None), idx, isize);
  const size_t iacc = accessors.size();
  accessors.push_back({{"bufferView", parts.addMeshoptView(ic, ni, isize, MeshoptMode::Triangles, MeshoptFilter::None,
                                                           kElementArrayBuffer)},
                       {"componentType", ictype}, {"count", ni}, {"type", "SCALAR"}});
  counts = decodedCounts(mesh, n, ni / 3);
  return {{"attributes", attributes}, {"indices", iacc}, {"material", 0}, {"mode", kModeTriangles}};
}

}  // namespace

std::vector<uint8_t> encodeGlb(const geo::MeshData& mesh, const GlbOptions& opt, GlbMeshCounts* counts) {
  std::vector<GlbMeshCounts> c;
  std::vector<uint8_t> glb = encodeGlbLevels({mesh}, opt, counts ? &c : nullptr);
  if (counts) *counts = c.at(0);
  return glb;
}

std::vector<uint8_t> encodeGlbLevels(const std::vector<geo::MeshData>& levels, const GlbOptions& opt,
                                     std::vector<GlbMeshCounts>* counts) {
  if (levels.empty()) throw core::Error(Status::InvalidArg, "encodeGlb: no levels");
  for (size_t k = 0; k < levels.size(); ++k) {
    const std::string where = levels.size() > 1 ? "level " + std::to_string(k) + ": " : "";
    validateMesh(levels[k], opt, where);
    if (k == 0) continue;
    const geo::MeshData &m = levels[k], &m0 = levels[0];
    if (m.indices.empty()) throw core::Error(Status::InvalidArg, "encodeGlb: " + where + "empty (only level 0 may be)");
    if (m.normals.empty() != m0.normals.empty() || m.colors.empty() != m0.colors.empty() ||
        m.texcoords.empty() != m0.texcoords.empty())
      throw core::Error(Status::InvalidArg, "encodeGlb: " + where + "attributes differ from level 0's");
    if (!m.image.empty()) throw core::Error(Status::InvalidArg, "encodeGlb: " + where + "only level 0 may carry an image");
  }
  GlbOptions o = opt;
  if (opt.codec != GlbCodec::Draco) o.projection = nullptr;
  if (o.projection) {
    if (levels.size() != 1) throw core::Error(Status::InvalidArg, "encodeGlb: a texcoord projection needs one level");
    validateProjection(levels[0], *o.projection);
  }
  if (counts) counts->assign(levels.size(), GlbMeshCounts{});
  json doc = baseDocument();
  if (levels[0].indices.empty()) {
    doc["scenes"] = json::array({json::object()});
    return assembleGlb(doc, {});
  }
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  doc["materials"] = json::array({material()});
  Parts parts;
  json meshes = json::array(), nodes = json::array(), used = json::array();
  for (size_t k = 0; k < levels.size(); ++k) {
    GlbMeshCounts c;
    json prim = opt.codec == GlbCodec::Draco     ? addDracoPrimitive(levels[k], o, parts, c)
                : opt.codec == GlbCodec::Meshopt ? addMeshoptPrimitive(levels[k], opt, parts, c)
                                                 : addPlainPrimitive(levels[k], parts, c);
    if (counts) (*counts)[k] = c;
    meshes.push_back({{"primitives", json::array({prim})}});
    nodes.push_back({{"mesh", k}});
  }
  if (levels.size() > 1) {
    json ids = json::array();
    for (size_t k = 1; k < levels.size(); ++k) ids.push_back(k);
    nodes[0]["extensions"] = {{"MSFT_lod", {{"ids", ids}}}};
  }
  addImage(levels[0], doc, parts);
  json required = json::array();
  if (opt.codec == GlbCodec::Draco) required.push_back("KHR_draco_mesh_compression");
  if (opt.codec == GlbCodec::Meshopt) required.push_back("EXT_meshopt_compression");
  if (parts.quantized) required.push_back("KHR_mesh_quantization");
  if (o.projection) required.push_back(kProjectedTexcoords);
  if (levels[0].image_mime == "image/webp" && !levels[0].image.empty()) required.push_back("EXT_texture_webp");
  used = required;
  if (levels.size() > 1) used.push_back("MSFT_lod");
  if (!levels[0].image.empty()) used.push_back("KHR_materials_unlit");
  if (!used.empty()) doc["extensionsUsed"] = used;
  if (!required.empty()) doc["extensionsRequired"] = required;
  doc["buffers"] = json::array({{{"byteLength", parts.bin.size()}}});
  if (parts.fallback_bytes > 0)
    doc["buffers"].push_back(
        {{"byteLength", parts.fallback_bytes}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
  doc["bufferViews"] = parts.views;
  doc["accessors"] = parts.accessors;
  doc["meshes"] = meshes;
  doc["nodes"] = nodes;
  return assembleGlb(doc, parts.bin);
}

namespace {
[[noreturn]] void bad(const std::string& why) { throw core::Error(Status::InvalidArg, "translateGlb: " + why); }
}  // namespace

std::vector<uint8_t> translateGlb(const uint8_t* data, size_t size, const float offset[3]) {
  Chunks c;
  std::string err;
  if (splitChunks(data, size, c, err) != Status::Ok) bad(err);
  try {
    json doc = json::parse(c.json_data, c.json_data + c.json_size, nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) bad("the JSON chunk does not parse");
    // The nodes that place the geometry: the scene's roots and their MSFT_lod
    // level nodes (which sit outside the scene).
    std::vector<size_t> movers;
    json empty = json::array();
    json& nodes = doc.contains("nodes") ? doc["nodes"] : empty;
    {
      if (!nodes.is_array()) bad("nodes is not an array");
      auto add = [&](const json& v) {
        if (!v.is_number_unsigned() || v.get<size_t>() >= nodes.size()) bad("a node index is out of range");
        if (std::find(movers.begin(), movers.end(), v.get<size_t>()) == movers.end()) movers.push_back(v.get<size_t>());
      };
      for (const json& sc : doc.value("scenes", json::array()))
        for (const json& n : sc.value("nodes", json::array())) add(n);
      for (size_t i = 0; i < movers.size(); ++i) {
        const json& node = nodes[movers[i]];
        if (!node.is_object()) bad("a node is not an object");
        const json ids = node.value("/extensions/MSFT_lod/ids"_json_pointer, json::array());
        if (!ids.is_array()) bad("MSFT_lod.ids is not an array");
        for (const json& n : ids) add(n);
      }
    }
    for (size_t n : movers) {
      json& node = nodes[n];
      if (node.contains("matrix")) bad("nodes[" + std::to_string(n) + "] has a matrix");
      json t = node.value("translation", json::array({0.0, 0.0, 0.0}));
      if (!t.is_array() || t.size() != 3) bad("nodes[" + std::to_string(n) + "].translation is not 3 numbers");
      for (int k = 0; k < 3; ++k) {
        if (!t[k].is_number()) bad("nodes[" + std::to_string(n) + "].translation is not 3 numbers");
        t[k] = t[k].get<double>() + double(offset[k]);
      }
      node["translation"] = t;
    }
    return assembleGlb(doc, std::vector<uint8_t>(c.bin, c.bin + c.bin_size));
  } catch (const json::exception& e) {
    bad(std::string("JSON: ") + e.what());
  }
}

}  // namespace blvd::package
