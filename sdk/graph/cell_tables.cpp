#include "graph/cell_tables.h"

#include <cmath>

#include "core/bytes.h"
#include "core/status.h"

namespace blvd::graph {
namespace {
// 2 since package format 2.0: layers carry their vertex count; 3 since 3.0:
// and the run of the cell they serve (run_from_m).
constexpr uint32_t kImpostorTableVersion = 3;

void putLayers(core::ByteWriter& w, const std::vector<ImpostorLayer>& layers) {
  w.put<uint32_t>(static_cast<uint32_t>(layers.size()));
  for (const ImpostorLayer& l : layers) {
    w.put(l.blob);
    w.put(l.triangles);
    w.put(l.vertices);
    w.put(l.texture_width);
    w.put(l.texture_height);
    w.put(l.run_from_m);
    w.put<uint32_t>(static_cast<uint32_t>(l.blocks.size()));
    for (uint32_t b : l.blocks) w.put(b);
  }
}

// `length`: the cell's length; runs start inside it, in order.
void getLayers(core::ByteReader& r, std::vector<ImpostorLayer>& layers, uint32_t blocks, uint32_t blobs, float length) {
  layers.resize(r.getCount(24));
  float last_run = 0.f;
  for (ImpostorLayer& l : layers) {
    const size_t at = r.pos();
    l.blob = r.get<uint32_t>();
    l.triangles = r.get<uint32_t>();
    l.vertices = r.get<uint32_t>();
    l.texture_width = r.get<uint16_t>();
    l.texture_height = r.get<uint16_t>();
    l.run_from_m = r.get<float>();
    if (!(l.run_from_m >= last_run && l.run_from_m <= length))
      r.fail("impostor run start " + std::to_string(l.run_from_m) + " m is not in order within the cell's " +
                 std::to_string(length) + " m",
             at);
    last_run = l.run_from_m;
    if (l.blob >= blobs) r.fail("impostor blob index out of range", at);
    if (l.triangles == 0 || l.vertices == 0 || l.triangles > (1u << 24) || l.vertices > (1u << 24))
      r.fail("impostor layer counts outside 1..2^24", at);
    l.blocks.resize(r.getCount(4));
    for (uint32_t& b : l.blocks) {
      b = r.get<uint32_t>();
      if (b >= blocks) r.fail("impostor block index out of range");
    }
  }
}
}  // namespace

std::vector<uint8_t> serializeVisibility(const CellTables& t, std::vector<uint64_t>* offsets) {
  core::ByteWriter w;
  w.put<uint32_t>(1);
  w.put<uint32_t>(static_cast<uint32_t>(t.visibility.size()));
  for (const CellVisibility& v : t.visibility) {
    if (offsets) offsets->push_back(w.bytes().size());
    w.put<uint32_t>(static_cast<uint32_t>(v.blocks.size()));
    for (size_t i = 0; i < v.blocks.size(); ++i) {
      w.put(v.blocks[i]);
      w.put(v.ach[i]);
    }
  }
  return std::move(w.bytes());
}

std::vector<uint8_t> serializeImpostors(const CellTables& t, std::vector<uint64_t>* offsets) {
  core::ByteWriter w;
  w.put<uint32_t>(kImpostorTableVersion);
  w.put(t.threshold_px);
  w.put(t.display_fov_y_deg);
  w.put(t.display_width);
  w.put(t.display_height);
  w.put<uint32_t>(static_cast<uint32_t>(t.impostors.size()));
  for (const CellImpostors& c : t.impostors) {
    if (offsets) offsets->push_back(w.bytes().size());
    putLayers(w, c.layered);
    putLayers(w, c.single);
  }
  return std::move(w.bytes());
}

void parseVisibilityHeader(core::ByteReader& r, uint32_t cells) {
  if (r.get<uint32_t>() != 1) r.fail("unknown visibility version");
  const uint32_t n = r.get<uint32_t>();
  if (n != cells) r.fail("visibility lists " + std::to_string(n) + " cells, the graph has " + std::to_string(cells));
}

void parseCellVisibility(core::ByteReader& r, uint32_t blocks, CellVisibility& v) {
  const uint32_t k = r.getCount(8);
  v.blocks.resize(k);
  v.ach.resize(k);
  for (uint32_t i = 0; i < k; ++i) {
    v.blocks[i] = r.get<uint32_t>();
    v.ach[i] = r.get<float>();
    if (v.blocks[i] >= blocks) r.fail("visible block index out of range");
    if (!(v.ach[i] >= 0.f && v.ach[i] <= 1.f)) r.fail("coverage hint outside [0, 1]");
    if (i > 0 && v.blocks[i] <= v.blocks[i - 1]) r.fail("visible blocks not ascending");
  }
}

void parseVisibility(const uint8_t* data, size_t size, uint64_t file_offset, uint32_t cells, uint32_t blocks,
                     CellTables& t) {
  core::ByteReader r(data, size, "visibility section PVSA", file_offset);
  parseVisibilityHeader(r, cells);
  t.visibility.resize(cells);
  for (CellVisibility& v : t.visibility) parseCellVisibility(r, blocks, v);
}

void parseImpostorsHeader(core::ByteReader& r, uint32_t cells, CellTables& t) {
  if (const uint32_t v = r.get<uint32_t>(); v != kImpostorTableVersion)
    r.fail("impostor table version " + std::to_string(v) + ", this build reads " + std::to_string(kImpostorTableVersion),
           0);
  t.threshold_px = r.get<float>();
  t.display_fov_y_deg = r.get<float>();
  t.display_width = r.get<uint16_t>();
  t.display_height = r.get<uint16_t>();
  const uint32_t n = r.get<uint32_t>();
  if (n != cells) r.fail("impostors list " + std::to_string(n) + " cells, the graph has " + std::to_string(cells));
}

void parseCellImpostors(core::ByteReader& r, uint32_t blocks, uint32_t blobs, float length, CellImpostors& c) {
  getLayers(r, c.layered, blocks, blobs, length);
  getLayers(r, c.single, blocks, blobs, length);
}

void parseImpostors(const uint8_t* data, size_t size, uint64_t file_offset, const std::vector<float>& lengths,
                    uint32_t blocks, uint32_t blobs, CellTables& t) {
  const uint32_t cells = static_cast<uint32_t>(lengths.size());
  core::ByteReader r(data, size, "impostor section IMPO", file_offset);
  parseImpostorsHeader(r, cells, t);
  t.impostors.resize(cells);
  for (size_t c = 0; c < t.impostors.size(); ++c) parseCellImpostors(r, blocks, blobs, lengths[c], t.impostors[c]);
}

std::vector<uint8_t> serializeCellTableIndex(const std::vector<uint64_t>& visibility,
                                             const std::vector<uint64_t>& impostors) {
  if (visibility.size() != impostors.size())
    throw core::Error(core::Status::InvalidArg, "cell table index: visibility and impostor offsets differ in count");
  core::ByteWriter w;
  w.put<uint32_t>(kCellTableIndexVersion);
  w.put<uint32_t>(static_cast<uint32_t>(visibility.size()));
  for (size_t c = 0; c < visibility.size(); ++c) {
    w.put(visibility[c]);
    w.put(impostors[c]);
  }
  return std::move(w.bytes());
}

}  // namespace blvd::graph
