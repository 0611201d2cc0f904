// Item-buffer visibility of the streets; the contract is in visibility_bake.h.
#include "bake/visibility_bake.h"

#include <algorithm>
#include <map>

#include "bake/street_points.h"

namespace blvd::bake {
namespace {

// Sparse per-sample pixel counts: (block, pixels).
using Counts = std::vector<std::pair<uint32_t, uint32_t>>;

// One position's counts: of the blocks' surfaces, and of the outlines of
// those no pixel centre fell on (CaptureRig::itemBuffer), when drawn.
struct Sample {
  Counts px, outline;
};

constexpr size_t kBatch = 64;  // tasks between progress reports

Counts sparse(const std::vector<uint32_t>& counts) {
  Counts c;
  for (uint32_t b = 0; b < counts.size(); ++b)
    if (counts[b]) c.emplace_back(b, counts[b]);
  return c;
}

// D99 §5.3's item buffer at one point: 6 views of 90°, each block's pixels;
// with `outlines`, also the outline pixels of what no pixel centre fell on.
Sample sampleAt(CaptureRig& rig, glm::dvec2 p, const ImpostorOptions& opt, bool outlines) {
  const int res = opt.item_resolution;
  std::vector<uint32_t> counts(rig.blockCount(), 0u), lines(outlines ? rig.blockCount() : 0, 0u);
  render::Camera cam;
  cam.eye_enu = eyeAt(p, opt.ground);
  cam.fov_y_deg = 90.0;
  cam.width = cam.height = res;
  cam.near_m = 0.3;
  cam.far_m = kViewDistanceM;
  static const double dirs[6][2] = {{0, 0}, {90, 0}, {180, 0}, {270, 0}, {0, 89.9}, {0, -89.9}};
  for (const auto& d : dirs) {
    cam.heading_deg = d[0];
    cam.pitch_deg = d[1];
    rig.itemBuffer(cam, counts, outlines ? &lines : nullptr);
  }
  return Sample{sparse(counts), sparse(lines)};
}

// The samples of a bake: one per junction (shared), and interior ones per street.
struct Samples {
  std::vector<uint32_t> vertices;  // sorted graph vertices of the wanted streets' ends
  std::vector<Sample> at_vertex;   // their samples
  const Sample& atVertex(uint32_t v) const {
    return at_vertex[size_t(std::lower_bound(vertices.begin(), vertices.end(), v) - vertices.begin())];
  }
};

// Street h's PVS and ACH: its two end samples, n_in interior ones (taken
// here), every block any of them saw, and the cell's local blocks at 0.
// The ends and the middle sample also draw outlines: a strip thinner than a
// pixel stays so along the street, and three of eight positions find it at a
// fraction of the cost of all eight (docs/decisions/0036). A block only an
// outline showed is in the PVS with its outline's pixels as its ACH; the
// others' ACH is their surfaces' pixels alone, as the papers estimate it.
graph::CellVisibility streetVisibility(const graph::StreetGraph& g, uint32_t h, CaptureRig& rig,
                                       const ImpostorOptions& opt, const Samples& ends) {
  const graph::HalfEdge& e = g.halfedges[h];
  std::vector<const Sample*> samples = {&ends.atVertex(e.origin), &ends.atVertex(g.endVertex(h))};
  const int n_in = std::max(0, opt.positions_per_cell - 2);
  std::vector<Sample> interior;
  interior.reserve(size_t(n_in));
  for (int i = 1; i <= n_in; ++i)
    interior.push_back(sampleAt(rig, pointAt(g, e, e.length * i / (n_in + 1)), opt, i == (n_in + 1) / 2));
  for (const Sample& c : interior) samples.push_back(&c);
  std::map<uint32_t, double> acc, by_outline;
  for (const Sample* c : samples) {
    for (const auto& [b, px] : c->px) acc[b] += px;
    for (const auto& [b, px] : c->outline) by_outline[b] += px;
  }
  for (const auto& [b, px] : by_outline) acc.emplace(b, px);  // only where no surface showed
  for (uint32_t l = g.local_blocks.offsets[h]; l < g.local_blocks.offsets[h + 1]; ++l)
    acc.emplace(g.local_blocks.items[l], 0.0);
  const double norm = 1.0 / (double(samples.size()) * 6.0 * opt.item_resolution * opt.item_resolution);
  graph::CellVisibility vis;
  for (const auto& [b, px] : acc) {
    vis.blocks.push_back(b);
    vis.ach.push_back(static_cast<float>(px * norm));
  }
  return vis;
}

}  // namespace

void bakeVisibility(const graph::StreetGraph& g, RigPool& pool, const ImpostorOptions& opt,
                    const std::vector<bool>& want, ImpostorBakeResult& res,
                    const std::function<void(const char*, double, double)>& progress) {
  const size_t H = g.halfedges.size();
  res.tables.visibility.assign(H, {});
  std::vector<uint32_t> streets;  // one half-edge of each wanted street
  Samples ends;
  for (uint32_t h = 0; h < H; ++h) {
    const graph::HalfEdge& e = g.halfedges[h];
    if (h > e.twin || (!want[h] && !want[e.twin])) continue;  // both directions share the samples
    streets.push_back(h);
    ends.vertices.push_back(e.origin);
    ends.vertices.push_back(g.endVertex(h));
  }
  std::sort(ends.vertices.begin(), ends.vertices.end());
  ends.vertices.erase(std::unique(ends.vertices.begin(), ends.vertices.end()), ends.vertices.end());
  ends.at_vertex.resize(ends.vertices.size());
  const size_t nv = ends.vertices.size(), total = nv + streets.size();
  auto report = [&](size_t done) {
    if (progress) progress("visibility (item buffers)", double(done), double(total));
  };
  pool.runInBatches(
      nv, kBatch,
      [&](CaptureRig& rig, size_t i) {
        ends.at_vertex[i] = sampleAt(rig, g.vertices[ends.vertices[i]].p, opt, true);
      },
      report);
  pool.runInBatches(
      streets.size(), kBatch,
      [&](CaptureRig& rig, size_t i) {
        res.tables.visibility[streets[i]] = streetVisibility(g, streets[i], rig, opt, ends);
      },
      [&](size_t done) { report(nv + done); });
  for (uint32_t h : streets) res.tables.visibility[g.halfedges[h].twin] = res.tables.visibility[h];
  res.samples = nv + streets.size() * size_t(std::max(0, opt.positions_per_cell - 2));
}

}  // namespace blvd::bake
