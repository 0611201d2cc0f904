#include "runtime/terrain_set.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/math.h"
#include "core/status.h"
#include "render/prepared_mesh.h"

namespace blvd::runtime {
namespace {

constexpr uint32_t kNoTile = 0xffffffffu;
constexpr uint32_t kFailedKept = 64;

uint32_t tileVertices(uint32_t g) { return g * g + 4 * g; }              // grid and skirts
uint32_t tileIndices(uint32_t g) { return 6 * (g - 1) * (g - 1) + 24 * (g - 1); }

}  // namespace

TerrainPlan TerrainSet::plan(const stream::City& city) {
  TerrainPlan p;
  const stream::TerrainPages* t = city.terrain();
  if (!t) return p;
  const uint32_t g = t->layout().grid;
  p.slots = uint32_t(std::min<uint64_t>(kMaxSlots, t->layout().tiles()));
  p.slab.vertex_bytes = uint64_t(tileVertices(g)) * render::kVertexBytes;
  p.slab.index_bytes = uint64_t(tileIndices(g)) * 2 + 4;
  p.slab.meshes = 1;
  p.gpu_bytes = p.slots * render::slabGpuBytes(p.slab);
  const uint64_t v = tileVertices(g), i = tileIndices(g);
  p.cpu_bytes = render::preparedBytes(v, i, 0, 0) + v * (12 + 12 + 4) + i * 4 + uint64_t(g) * g * (4 + 2) +
                uint64_t(p.slots) * (sizeof(render::SlabHandle) + sizeof(render::MeshHandle) + 4 + 8) +
                uint64_t(p.slots) * (4 + 8 + 4 + 4) + kFailedKept * 4;
  return p;
}

TerrainSet::TerrainSet(const stream::City& city, render::Renderer& renderer, const TerrainPlan& plan, float error_px)
    : city_(city), renderer_(renderer), plan_(plan), error_px_(std::max(error_px, 0.1f)) {
  if (!plan.slots) return;
  layout_ = city.terrain()->layout();
  for (int k = 0; k < 3; ++k) colour_[k] = uint8_t(std::lround(std::clamp(renderer.look().ground[k], 0.f, 1.f) * 255));
  for (uint32_t s = 0; s < plan.slots; ++s) {
    slab_.push_back(renderer.createSlab(plan.slab));
    if (!slab_.back().id)
      throw core::Error(renderer.outOfMemory() ? core::Status::NoMem : core::Status::Internal,
                        "terrain slot " + std::to_string(s) + ": " + renderer.lastError());
  }
  if (!renderer.reserveMeshes(plan.slots)) throw core::Error(core::Status::Internal, renderer.lastError());
  mesh_.assign(plan.slots, render::MeshHandle{});
  tile_.assign(plan.slots, kNoTile);
  used_.assign(plan.slots, 0);
  tree_.reserve(plan.slots);
  tree_px_.reserve(plan.slots);
  first_child_.reserve(plan.slots);
  stack_.reserve(plan.slots);
  failed_.reserve(kFailedKept);
  uncached_.reserve(plan.slots);
  const uint32_t g = layout_.grid, v = tileVertices(g), i = tileIndices(g);
  heights_.resize(size_t(g) * g);
  blob_.reserve(size_t(g) * g * 2);
  mesh_data_.positions.reserve(3 * v);
  mesh_data_.normals.reserve(3 * v);
  mesh_data_.colors.reserve(4 * v);
  mesh_data_.indices.reserve(i);
  arena_bytes_.resize(render::preparedBytes(v, i, 0, 0));
}

uint32_t TerrainSet::frame(const render::Camera& cam, render::MeshHandle* out) {
  if (!plan_.slots) return 0;
  ++tick_;
  choose(cam);
  loadMissing(kLoadsPerFrame);
  return draw(out);
}

void TerrainSet::settle(const render::Camera& cam) {
  if (!plan_.slots) return;
  ++tick_;
  choose(cam);
  loadMissing(plan_.slots);
}

// 3D Tiles' screen-space error: the tile's error over its distance from the
// eye (to its box), in pixels of the view's height.
// A tile whose record cannot be read (a table page over the link not there,
// a record that breaks the rules) is not refined: 0.
double TerrainSet::screenError(uint32_t tile, const render::Camera& cam) {
  graph::TerrainRecord r;
  try {
    r = city_.terrain()->record(tile);
  } catch (const core::Error& e) {
    last_error_ = e.what();
    return 0;
  }
  const graph::TerrainTile t = graph::terrainTileAt(tile);
  const double ts = layout_.tileSize(t.level), x0 = layout_.west + t.x * ts, y0 = layout_.south + t.y * ts;
  const glm::dvec3 lo(x0, y0, r.min_m), hi(x0 + ts, y0 + ts, r.max_m);
  const double d = std::max(glm::length(glm::clamp(cam.eye_enu, lo, hi) - cam.eye_enu), cam.near_m);
  return r.error_m * cam.height / (2 * d * std::tan(0.5 * cam.fov_y_deg * core::kDegToRad));
}

void TerrainSet::choose(const render::Camera& cam) {
  tree_.clear();
  tree_px_.clear();
  first_child_.clear();
  tree_.push_back(0);
  tree_px_.push_back(screenError(0, cam));
  first_child_.push_back(0);
  while (tree_.size() + 4 <= plan_.slots) {
    size_t best = tree_.size();
    for (size_t k = 0; k < tree_.size(); ++k)
      if (!first_child_[k] && tree_px_[k] > error_px_ && graph::terrainTileAt(tree_[k]).level + 1 < layout_.levels &&
          (best == tree_.size() || tree_px_[k] > tree_px_[best]))
        best = k;
    if (best == tree_.size()) break;
    first_child_[best] = uint32_t(tree_.size());
    for (uint32_t c = 0; c < 4; ++c) {
      const uint32_t child = graph::terrainChild(tree_[best], c);
      tree_.push_back(child);
      tree_px_.push_back(screenError(child, cam));
      first_child_.push_back(0);
    }
  }
  chosen_ = uint32_t(tree_.size());
  for (uint32_t t : tree_)
    if (const uint32_t s = residentSlot(t); s != kNoTile) used_[s] = tick_;
}

void TerrainSet::loadMissing(uint32_t max_loads) {
  uint32_t loaded = 0;
  uncached_.clear();
  for (size_t k = 0; k < tree_.size() && loaded < max_loads; ++k) {
    const uint32_t t = tree_[k];
    if (residentSlot(t) != kNoTile || std::find(failed_.begin(), failed_.end(), t) != failed_.end()) continue;
    const uint32_t s = victim();
    if (s == kNoTile) break;
    const core::Status st = load(t, s);
    if (st == core::Status::Unavailable) continue;  // recorded in uncached_ by load()
    ++loaded;
    if (st == core::Status::Ok) continue;
    ++load_errors_;
    if (failed_.size() < kFailedKept) failed_.push_back(t);
  }
}

// A free slot, or the deepest (then least recently used) tile outside the tree.
uint32_t TerrainSet::victim() const {
  uint32_t best = kNoTile, best_level = 0;
  for (uint32_t s = 0; s < plan_.slots; ++s) {
    if (tile_[s] == kNoTile) return s;
    if (inTree(tile_[s])) continue;
    const uint32_t level = graph::terrainTileAt(tile_[s]).level;
    if (best == kNoTile || level > best_level || (level == best_level && used_[s] < used_[best])) best = s, best_level = level;
  }
  return best;
}

core::Status TerrainSet::load(uint32_t tile, uint32_t slot) {
  try {
    const graph::TerrainRecord r = city_.terrain()->record(tile);
    if (!city_.terrainCached(r)) {  // the link prefetch brings it; asked for again next frame
      if (uncached_.size() < uncached_.capacity()) uncached_.push_back(r.blob);
      return core::Status::Unavailable;
    }
    std::string err;
    if (const core::Status st = city_.terrainHeights(r, blob_, heights_.data(), err); st != core::Status::Ok) {
      last_error_ = err;
      return st == core::Status::Unavailable ? core::Status::Io : st;  // evicted meanwhile: an error like any read
    }
    tileMesh(layout_, tile, heights_.data(), colour_, true, mesh_data_);
    render::StagingArena arena{arena_bytes_.data(), arena_bytes_.size(), 0};
    render::PreparedMesh prepared;
    if (!render::prepareMesh(mesh_data_, arena, prepared, err)) {
      last_error_ = "terrain tile " + std::to_string(tile) + ": " + err;
      return core::Status::Internal;
    }
    renderer_.resetSlab(slab_[slot]);
    tile_[slot] = kNoTile;
    mesh_[slot] = renderer_.uploadToSlab(slab_[slot], prepared);
    if (!mesh_[slot].id) {
      last_error_ = "terrain tile " + std::to_string(tile) + ": " + renderer_.lastError();
      return core::Status::Internal;
    }
  } catch (const core::Error& e) {  // a record that breaks the rules, a read that failed
    last_error_ = e.what();
    return e.status();  // Unavailable: a table page over the link, asked for again next frame
  }
  tile_[slot] = tile;
  used_[slot] = tick_;
  ++loads_;
  return core::Status::Ok;
}

uint32_t TerrainSet::residentSlot(uint32_t tile) const {
  for (uint32_t s = 0; s < plan_.slots; ++s)
    if (tile_[s] == tile) return s;
  return kNoTile;
}

bool TerrainSet::inTree(uint32_t tile) const { return std::find(tree_.begin(), tree_.end(), tile) != tree_.end(); }

uint32_t TerrainSet::draw(render::MeshHandle* out) {
  uint32_t n = 0;
  stack_.clear();
  stack_.push_back(0);
  while (!stack_.empty()) {
    const uint32_t k = stack_.back();
    stack_.pop_back();
    const uint32_t fc = first_child_[k];
    bool children = fc != 0;
    for (uint32_t c = 0; children && c < 4; ++c) children = residentSlot(tree_[fc + c]) != kNoTile;
    if (children) {
      for (uint32_t c = 0; c < 4; ++c) stack_.push_back(fc + c);
      continue;
    }
    if (const uint32_t s = residentSlot(tree_[k]); s != kNoTile) out[n++] = mesh_[s];
  }
  return n;
}

void TerrainSet::tileMesh(const graph::TerrainLayout& l, uint32_t tile, const float* h, const uint8_t rgba[4],
                          bool skirts, geo::MeshData& out) {
  out.clear();
  const graph::TerrainTile t = graph::terrainTileAt(tile);
  const uint32_t g = l.grid, last = (1u << t.level) - 1;
  const double ts = l.tileSize(t.level), step = ts / (g - 1), x0 = l.west + t.x * ts, y0 = l.south + t.y * ts;
  const double skirt = l.level_error_m[t.level] + 2.0 * l.level_error_m[0] + 1.0;
  auto at = [&](int i, int j) { return double(h[size_t(std::clamp(j, 0, int(g) - 1)) * g + size_t(std::clamp(i, 0, int(g) - 1))]); };
  auto vertex = [&](uint32_t i, uint32_t j, double drop) {
    const double e = x0 + i * step, n = y0 + j * step;
    const double de = (at(int(i) + 1, int(j)) - at(int(i) - 1, int(j))) / (step * ((i > 0) + (i + 1 < g)));
    const double dn = (at(int(i), int(j) + 1) - at(int(i), int(j) - 1)) / (step * ((j > 0) + (j + 1 < g)));
    const glm::dvec3 nrm = glm::normalize(glm::dvec3(-de, 1.0, dn));  // glTF: x east, y up, z south
    out.positions.insert(out.positions.end(), {float(e), float(at(int(i), int(j)) - drop), float(-n)});
    out.normals.insert(out.normals.end(), {float(nrm.x), float(nrm.y), float(nrm.z)});
    out.colors.insert(out.colors.end(), {rgba[0], rgba[1], rgba[2], rgba[3]});
  };
  for (uint32_t j = 0; j < g; ++j)
    for (uint32_t i = 0; i < g; ++i) vertex(i, j, 0);
  auto id = [g](uint32_t i, uint32_t j) { return j * g + i; };
  for (uint32_t j = 0; j + 1 < g; ++j)
    for (uint32_t i = 0; i + 1 < g; ++i)  // counter-clockwise from above, split south-west to north-east
      out.indices.insert(out.indices.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
  if (!skirts) return;
  // Each inner side walked with the outside on its right: south west to east,
  // east south to north, north east to west, west north to south.
  auto side = [&](bool inner, auto border) {
    if (!inner) return;
    const auto first = uint32_t(out.vertexCount());
    for (uint32_t k = 0; k < g; ++k) {
      uint32_t i, j;
      border(k, i, j);
      vertex(i, j, skirt);
    }
    for (uint32_t k = 0; k + 1 < g; ++k) {
      uint32_t i, j, i2, j2;
      border(k, i, j);
      border(k + 1, i2, j2);
      const uint32_t a = id(i, j), b = id(i2, j2), sa = first + k, sb = first + k + 1;
      out.indices.insert(out.indices.end(), {a, sa, b, b, sa, sb});
    }
  };
  side(t.y > 0, [](uint32_t k, uint32_t& i, uint32_t& j) { i = k, j = 0; });
  side(t.x < last, [g](uint32_t k, uint32_t& i, uint32_t& j) { i = g - 1, j = k; });
  side(t.y < last, [g](uint32_t k, uint32_t& i, uint32_t& j) { i = g - 1 - k, j = g - 1; });
  side(t.x > 0, [g](uint32_t k, uint32_t& i, uint32_t& j) { i = 0, j = g - 1 - k; });
}

}  // namespace blvd::runtime
