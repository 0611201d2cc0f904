#include "bake/tile.h"

#include <algorithm>
#include <limits>
#include <string>

#include <glm/common.hpp>

#include "core/status.h"
#include "package/glb.h"

namespace blvd::bake {
namespace {

constexpr uint32_t kNoBlob = 0xffffffffu;

uint32_t shifted(uint32_t index, uint64_t by) {
  if (index == graph::kNone) return index;
  const uint64_t v = uint64_t{index} + by;
  if (v >= graph::kNone) throw core::Error(core::Status::Internal, "tiled package: an index overflows 32 bits");
  return static_cast<uint32_t>(v);
}

void appendShifted(graph::Csr& out, const graph::Csr& in, uint64_t by) {
  for (size_t i = 0; i < in.size(); ++i) {
    std::vector<uint32_t> list;
    for (const uint32_t* p = in.begin(i); p != in.end(i); ++p) list.push_back(shifted(*p, by));
    out.push(list);
  }
}

// East/north extent of the city: its streets and its blocks' geometry.
void extent(const graph::StreetGraph& g, const std::vector<graph::BlockRecord>& blocks, glm::dvec2& lo,
            glm::dvec2& hi) {
  lo = glm::dvec2(std::numeric_limits<double>::max());
  hi = -lo;
  for (const glm::dvec2& p : g.points) lo = glm::min(lo, p), hi = glm::max(hi, p);
  for (const graph::BlockRecord& b : blocks) {
    if (b.lod_count == 0) continue;
    lo = glm::min(lo, glm::dvec2(b.bbox_min[0], -b.bbox_max[2]));  // glTF z is south
    hi = glm::max(hi, glm::dvec2(b.bbox_max[0], -b.bbox_min[2]));
  }
  if (lo.x > hi.x) lo = hi = glm::dvec2(0);
}

}  // namespace

TileLayout tileCity(graph::StreetGraph& g, std::vector<graph::BlockRecord>& blocks, graph::CellTables& tables,
                    package::PackageWriter& writer, const TileOptions& opt) {
  if (opt.nx == 0 || opt.ny == 0 || !(opt.gap_m >= 0))
    throw core::Error(core::Status::InvalidArg, "--tile needs at least 1x1 copies and a gap >= 0");
  TileLayout L;
  L.copies = opt.nx * opt.ny;
  L.cells = static_cast<uint32_t>(g.halfedges.size());
  L.blocks = static_cast<uint32_t>(g.faces.size());
  L.vertices = static_cast<uint32_t>(g.vertices.size());
  L.blobs = writer.blobCount();
  glm::dvec2 lo, hi;
  extent(g, blocks, lo, hi);
  // Whole metres: clean coordinates, and short node translations in the GLBs.
  L.step = glm::ceil(hi - lo + glm::dvec2(opt.gap_m));
  if (L.copies == 1) return L;

  const graph::StreetGraph src = g;
  const std::vector<graph::BlockRecord> src_blocks = blocks;
  const graph::CellTables src_tables = tables;
  const uint64_t P = src.points.size();
  for (uint32_t k = 1; k < L.copies; ++k) {
    const glm::dvec2 off(L.step.x * (k % opt.nx), L.step.y * (k / opt.nx));
    const float gltf_off[3] = {static_cast<float>(off.x), 0.f, static_cast<float>(-off.y)};
    const uint64_t dv = uint64_t{k} * L.vertices, dh = uint64_t{k} * L.cells, df = uint64_t{k} * L.blocks,
                   db = uint64_t{k} * L.blobs, dp = k * P;
    for (graph::Vertex v : src.vertices) {
      v.p += off;
      v.halfedge = shifted(v.halfedge, dh);
      g.vertices.push_back(v);
    }
    for (graph::HalfEdge e : src.halfedges) {
      e.origin = shifted(e.origin, dv);
      e.twin = shifted(e.twin, dh);
      e.next = shifted(e.next, dh);
      e.face = shifted(e.face, df);
      e.pts_begin = shifted(e.pts_begin, dp);
      g.halfedges.push_back(e);
    }
    for (graph::Face f : src.faces) {
      f.halfedge = shifted(f.halfedge, dh);
      g.faces.push_back(f);
    }
    for (const glm::dvec2& p : src.points) g.points.push_back(p + off);
    appendShifted(g.successors, src.successors, dh);
    appendShifted(g.predecessors, src.predecessors, dh);
    appendShifted(g.local_blocks, src.local_blocks, df);

    for (graph::BlockRecord b : src_blocks) {
      if (b.blob != kNoBlob) b.blob = shifted(b.blob, db);
      for (int a = 0; a < 3; ++a) b.bbox_min[a] += gltf_off[a], b.bbox_max[a] += gltf_off[a];
      blocks.push_back(b);
    }
    for (graph::CellVisibility v : src_tables.visibility) {
      for (uint32_t& b : v.blocks) b = shifted(b, df);
      tables.visibility.push_back(std::move(v));
    }
    for (graph::CellImpostors c : src_tables.impostors) {
      for (auto* list : {&c.layered, &c.single})
        for (graph::ImpostorLayer& l : *list) {
          l.blob = shifted(l.blob, db);
          for (uint32_t& b : l.blocks) b = shifted(b, df);
        }
      tables.impostors.push_back(std::move(c));
    }
    for (uint32_t i = 0; i < L.blobs; ++i) {
      const std::vector<uint8_t> glb = writer.blobContents(i);
      writer.addBlob(package::translateGlb(glb.data(), glb.size(), gltf_off));
    }
  }
  return L;
}

}  // namespace blvd::bake
