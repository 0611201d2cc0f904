#include "stream/city.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "package/blob_codec.h"
#include "package/glb.h"

namespace blvd::stream {
namespace {
// The cell tables' cache: a cell's records are a few hundred bytes to a few KiB.
constexpr uint32_t kCellTablePages = 64, kCellTablePageBytes = 2048;
// The block table's: 88-byte records, a cell's local blocks a few pages.
constexpr uint32_t kBlockPages = 32, kBlockPageBytes = 2048;
// ELEV's: 4 bytes a point, a street's points on one or two pages.
constexpr uint32_t kGroundPages = 8, kGroundPageBytes = 2048;

thread_local bool t_no_link_wait = false;

std::vector<float> cellLengths(const graph::GraphSource& g) {
  std::vector<float> v(g.cellCount());
  for (uint32_t h = 0; h < g.cellCount(); ++h) v[h] = g.halfedge(h).length;
  return v;
}
}  // namespace


core::Status City::open(const std::string& path, std::string& err, Tables tables, GraphTables graph,
                        const PagedGraphDesc& paging) {
  graph_ = graph::StreetGraph{};
  blocks_.clear();
  tables_ = graph::CellTables{};
  whole_.reset();
  paged_.reset();
  cell_pages_.reset();
  block_pages_.reset();
  max_cell_layers_ = 0;
  streets_ = nullptr;
  ground_.reset();
  ground_points_ = 0;
  terrain_.reset();
  // Read, not mapped: a package file cut short under the runtime, even while
  // it is being opened, is a read error, never a SIGBUS (package/reader.h).
  core::Status st = package::PackageReader::open(path, reader_, err, package::PackageReader::Access::Read);
  if (st != core::Status::Ok) return st;
  if (reader_.hasSection(package::kSectionShard)) {
    err = path + ": a shard of a bake, not a package: merge the shards with `blvd pack merge`";
    reader_.close();
    return core::Status::Unsupported;
  }
  st = graph == GraphTables::Paged ? openPaged(paging, err) : openWhole(err);
  if (st != core::Status::Ok) return st;
  if (tables == Tables::All && (st = openRenderTables(err)) != core::Status::Ok) return st;
  if ((st = openElevation(err)) != core::Status::Ok) return st;
  if (tables == Tables::All && (st = openTerrain(err)) != core::Status::Ok) return st;
  const auto& h = reader_.header();
  frame_ = geo::LocalFrame(h.origin_lat, h.origin_lon, h.origin_h);
  return core::Status::Ok;
}

bool City::isUrl(const std::string& path) {
  return path.rfind("http://", 0) == 0 || path.rfind("https://", 0) == 0;
}

core::Status City::openUrl(const std::string& url, const remote::RemoteOptions& remote, std::string& err,
                           Tables tables, GraphTables graph, const PagedGraphDesc& paging) {
  if (remote.cache_path.empty()) return err = url + ": a package on a server needs a cache folder", core::Status::InvalidArg;
  for (int attempt = 0;; ++attempt) {
    remote_ = std::make_unique<remote::RemotePackage>();
    link_pages_.remote = remote_.get();
    core::Status st = remote_->open(url, remote, err);
    if (st == core::Status::Ok) st = open(remote_->mirrorPath(), err, tables, graph, paging);
    if (st == core::Status::Ok) return st;
    // A mirror a killed process or a bad disk left wrong: fetched again, once.
    const bool refetch = st == core::Status::Corrupt && attempt == 0 && !remote_->mirrorPath().empty() &&
                         remote_->mode() != remote::LinkMode::Offline && !remote_->stats().offline_start;
    reader_.close();
    if (!refetch) {
      remote_.reset();
      return st;
    }
    std::remove(remote_->mirrorPath().c_str());
  }
}

void City::cellBlobs(uint32_t cell, const uint32_t* skip, uint32_t skip_count, std::vector<uint32_t>& out) const {
  out.clear();
  for (const uint32_t b : streets().localBlocks(cell)) {
    if (std::find(skip, skip + skip_count, b) != skip + skip_count) continue;
    const graph::BlockRecord rec = block(b);
    if (rec.lod_count > 0 && rec.blob != 0xffffffffu) out.push_back(rec.blob);
  }
  std::vector<LayerInfo> layers(std::max<uint32_t>(1, max_cell_layers_));
  uint32_t layered = 0, single = 0;
  cellLayers(cell, layers.data(), uint32_t(layers.size()), &layered, &single);
  for (uint32_t j = 0; j < layered + single; ++j) out.push_back(layers[j].blob);
}

bool City::cellCached(uint32_t cell, std::vector<uint32_t>& scratch) const {
  if (!remote_) return true;
  try {
    cellBlobs(cell, nullptr, 0, scratch);
  } catch (const core::Error&) {
    return false;  // its table pages are not there and the link cannot bring them
  }
  return std::all_of(scratch.begin(), scratch.end(), [&](uint32_t b) { return remote_->cached(b); });
}

core::Status City::blobBytes(uint32_t i, package::Span& s, std::vector<uint8_t>& hold, std::string& err) const {
  if (!remote_) return reader_.readBlobContents(i, hold, s, err);  // pread: a file cut short is Io, not SIGBUS
  if (i >= remote_->blobCount()) return remote_->blob(i, hold, err);  // NotFound, naming the count
  std::vector<uint8_t>& into = package::storedBuffer(remote_->blobInfo(i), hold);
  const core::Status st = remote_->blob(i, into, err);
  if (st != core::Status::Ok) return st;
  return package::unpackBlob(remote_->blobInfo(i), i, into.data(), hold, s, reader_.name(), err);
}

City::NoLinkWait::NoLinkWait() : was_(t_no_link_wait) { t_no_link_wait = true; }
City::NoLinkWait::~NoLinkWait() { t_no_link_wait = was_; }

void City::LinkPages::ensure(uint64_t offset, uint64_t size) const {
  std::string err;
  const core::Status st = remote->ensureTables(offset, size, err, !t_no_link_wait);
  if (st != core::Status::Ok) throw core::Error(st, err);
}

core::Status City::ensureSection(uint32_t tag, std::string& err) const {
  const package::Span s = reader_.section(tag);
  if (!source() || !s.data) return core::Status::Ok;
  return remote_->ensureTables(s.offset, s.size, err);
}

core::Status City::openWhole(std::string& err) {
  try {
    package::Span s;
    std::vector<uint8_t> hold;
    for (uint32_t tag : {package::kSectionGraph, package::kSectionCells}) {
      const core::Status st = requiredSection(tag, hold, s, err);
      if (st != core::Status::Ok) return st;
      if (tag == package::kSectionGraph) graph::parseGraph(s.data, s.size, s.offset, graph_);
      else graph::parseCells(s.data, s.size, s.offset, graph_);
    }
  } catch (const core::Error& e) {
    err = reader_.name() + ": " + e.what();
    return e.status();
  }
  whole_ = std::make_unique<graph::MemoryGraph>(graph_);
  streets_ = whole_.get();
  return core::Status::Ok;
}

core::Status City::openPaged(const PagedGraphDesc& paging, std::string& err) {
  paged_ = std::make_unique<PagedGraph>();
  const core::Status st = paged_->open(reader_, err, paging, source());
  if (st != core::Status::Ok) return st;
  streets_ = paged_.get();
  return core::Status::Ok;
}

core::Status City::requiredSection(uint32_t tag, std::vector<uint8_t>& hold, package::Span& s,
                                   std::string& err) const {
  core::Status st = ensureSection(tag, err);
  if (st != core::Status::Ok) return st;
  st = reader_.checkedCopy(tag, hold, s, err);
  if (st == core::Status::NotFound) {
    err = reader_.name() + ": missing section " + package::tagToString(tag);
    return core::Status::Corrupt;
  }
  return st;
}

// ELEV through a page cache (4 bytes a point: a region's would be
// megabytes), every height checked here unless its pages come over the link
// (then each as it is read).
core::Status City::openElevation(std::string& err) {
  ground_.reset();
  ground_points_ = 0;
  if (!reader_.hasSection(package::kSectionElevation)) return core::Status::Ok;
  package::Span s;
  core::Status st = tableSection(reader_, source(), package::kSectionElevation, s, err);
  if (st != core::Status::Ok) return st;
  const uint64_t points = streets_->pointCount();
  uint32_t head[2] = {0, 0};
  try {
    if (source()) link_pages_.ensure(s.offset, std::min<uint64_t>(s.size, 8));
  } catch (const core::Error& e) {
    err = e.what();
    return e.status();
  }
  if (s.size >= 8 && (st = reader_.read(s.offset, 8, reinterpret_cast<uint8_t*>(head), err)) != core::Status::Ok)
    return st;
  if (s.size < 8 || head[0] != 1 || head[1] != points || s.size != 8 + 4 * points) {
    err = reader_.name() + ": elevation section ELEV at offset " + std::to_string(s.offset) + ": version " +
          std::to_string(head[0]) + ", " + std::to_string(head[1]) + " heights in " + std::to_string(s.size) +
          " bytes; a version 1 section for the graph's " + std::to_string(points) + " points has " +
          std::to_string(8 + 4 * points);
    return core::Status::Corrupt;
  }
  ground_ = std::make_unique<PageCache>(reader_, kGroundPages, kGroundPageBytes, source());
  ground_table_ = ground_->addTable(s.data + 8, points, 4);
  ground_offset_ = s.offset + 8;
  ground_points_ = points;
  if (source()) return core::Status::Ok;
  try {
    for (uint64_t i = 0; i < points; ++i) (void)groundOf(i);
  } catch (const core::Error& e) {
    err = e.what();
    ground_.reset();
    ground_points_ = 0;
    return e.status();
  }
  return core::Status::Ok;
}

float City::groundOf(uint64_t point) const {
  float h = 0;
  ground_->read(ground_table_, uint32_t(point), &h);
  if (!std::isfinite(h) || std::abs(h) > 1e4f)
    throw core::Error(core::Status::Corrupt, reader_.name() + ": elevation section ELEV at offset " +
                                                 std::to_string(ground_offset_ + 4 * point) + ": point " +
                                                 std::to_string(point) + " has no plausible height");
  return h;
}

core::Status City::openTerrain(std::string& err) {
  if (!reader_.hasSection(package::kSectionTerrain)) return core::Status::Ok;
  terrain_ = std::make_unique<TerrainPages>();
  const core::Status st = terrain_->open(reader_, err, source());
  if (st != core::Status::Ok) terrain_.reset();
  return st;
}

bool City::terrainCached(const graph::TerrainRecord& r) const { return !remote_ || remote_->cached(r.blob); }

core::Status City::terrainHeights(const graph::TerrainRecord& r, std::vector<uint8_t>& hold, float* out,
                                  std::string& err) const {
  if (remote_ && !remote_->cached(r.blob)) {
    err = reader_.name() + ": terrain blob " + std::to_string(r.blob) + " is not in the cache";
    return core::Status::Unavailable;
  }
  package::Span s;
  const core::Status st = blobBytes(r.blob, s, hold, err);
  if (st != core::Status::Ok) return st;
  const uint32_t grid = terrain_->layout().grid;
  if (graph::decodeTerrainHeights(s.data, s.size, terrain_->layout(), out)) return core::Status::Ok;
  err = reader_.name() + ": terrain blob " + std::to_string(r.blob) + " at offset " + std::to_string(s.offset) +
        ": " + std::to_string(s.size) + " bytes, a tile of " + std::to_string(grid) + "² heights has " +
        std::to_string(2 * grid * grid);
  return core::Status::Corrupt;
}

// False too where a height cannot be read (its page not over the link yet,
// a file cut short): the camera then keeps the pose's height for the frame.
bool City::groundSegment(uint32_t cell, double arc_m, GroundSegment& out) const try {
  if (!ground_ || cell >= streets_->cellCount()) return false;
  const graph::HalfEdge e = streets_->halfedge(cell);
  if (e.pts_count == 0 || uint64_t(e.pts_begin) + e.pts_count > ground_points_) return false;
  double h0 = groundOf(e.pts_begin);
  out = GroundSegment{h0, h0, 0, 0};
  glm::dvec2 a = streets_->point(e.pts_begin);
  for (uint32_t i = 1; i < e.pts_count; ++i) {
    const glm::dvec2 b = streets_->point(e.pts_begin + i);
    const double h1 = groundOf(e.pts_begin + i);
    out = GroundSegment{h0, h1, glm::length(b - a), arc_m};
    h0 = h1;
    if (arc_m <= out.length) break;
    arc_m -= out.length;
    a = b;
  }
  return true;
} catch (const core::Error&) {
  return false;
}

double City::groundHeight(uint32_t cell, double arc_m) const {
  double height = 0, grade = 0;
  groundAt(cell, arc_m, height, grade);
  return height;
}

bool City::groundAt(uint32_t cell, double arc_m, double& height, double& grade) const {
  GroundSegment s;
  height = grade = 0;
  if (!groundSegment(cell, arc_m, s)) return false;
  const double t = s.length > 0 ? std::clamp(s.at_m / s.length, 0.0, 1.0) : 1.0;
  height = s.h0 * (1 - t) + s.h1 * t;
  grade = s.length < 0.5 ? 0.0 : (s.h1 - s.h0) / s.length;  // a segment too short to say
  return true;
}

bool City::cameraOnRoad(uint32_t cell, double arc_m, double eye_height_m, double& eye_u, double& pitch_deg) const {
  double ground, grade;
  if (!groundAt(cell, arc_m, ground, grade)) return false;
  eye_u = ground + eye_height_m;
  pitch_deg = std::clamp(pitch_deg + std::atan(grade) * 180.0 / M_PI, -89.0, 89.0);
  return true;
}

// Blocks, then (present when the bake made impostors) visibility and impostors.
core::Status City::openRenderTables(std::string& err) {
  const uint32_t cells = streets_->cellCount();
  const uint32_t faces = paged_ ? paged_->faceCount() : static_cast<uint32_t>(graph_.faces.size());
  try {
    package::Span s;
    std::vector<uint8_t> hold;
    core::Status st = core::Status::Ok;
    if (paged_) {
      block_pages_ = std::make_unique<BlockPages>();
      st = block_pages_->open(reader_, kBlockPages, kBlockPageBytes, err, source());
      if (st == core::Status::NotFound) err = reader_.name() + ": missing section BLCK", st = core::Status::Corrupt;
    } else if ((st = requiredSection(package::kSectionBlocks, hold, s, err)) == core::Status::Ok) {
      graph::parseBlocks(s.data, s.size, s.offset, reader_.blobCount(), blocks_);
    }
    if (st != core::Status::Ok) return st;
    const uint32_t nblocks = blockCount();
    if (nblocks != faces) {
      err = reader_.name() + ": block table has " + std::to_string(nblocks) + " blocks but the graph " +
            std::to_string(faces) + " faces";
      return core::Status::Corrupt;
    }
    if (paged_ && reader_.hasSection(package::kSectionCellTableIndex)) {
      cell_pages_ = std::make_unique<CellTablePages>();
      st = cell_pages_->open(reader_, *streets_, nblocks, kCellTablePages, kCellTablePageBytes, err, source(),
                             header().max_cell_impostor_layers);
      if (st != core::Status::Ok) return st;
      max_cell_layers_ = cell_pages_->maxLayers();
      return core::Status::Ok;
    }
    for (uint32_t tag : {package::kSectionVisibility, package::kSectionImpostors}) {
      if (!reader_.hasSection(tag)) continue;
      if ((st = requiredSection(tag, hold, s, err)) != core::Status::Ok) return st;
      if (tag == package::kSectionVisibility) graph::parseVisibility(s.data, s.size, s.offset, cells, nblocks, tables_);
      else graph::parseImpostors(s.data, s.size, s.offset, cellLengths(*streets_), nblocks, reader_.blobCount(), tables_);
    }
    for (const graph::CellImpostors& ci : tables_.impostors)
      max_cell_layers_ = std::max<uint32_t>(max_cell_layers_, static_cast<uint32_t>(ci.layered.size() + ci.single.size()));
  } catch (const core::Error& e) {
    err = reader_.name() + ": " + e.what();
    return e.status();
  }
  return core::Status::Ok;
}

void City::cellLayers(uint32_t cell, LayerInfo* out, uint32_t cap, uint32_t* layered, uint32_t* single) const {
  *layered = *single = 0;
  if (cell_pages_) return cell_pages_->layers(cell, out, cap, layered, single);
  if (cell >= tables_.impostors.size()) return;
  uint32_t written = 0;
  const graph::CellImpostors& ci = tables_.impostors[cell];
  for (auto [list, count] : {std::pair{&ci.layered, layered}, std::pair{&ci.single, single}})
    for (const graph::ImpostorLayer& l : *list) {
      if (written == cap) break;
      out[written++] = LayerInfo{l.blob, l.triangles, l.vertices, l.texture_width, l.texture_height, l.run_from_m};
      ++*count;
    }
}

float City::coverage(uint32_t cell, uint32_t block) const {
  if (cell_pages_) return cell_pages_->coverage(cell, block);
  if (cell >= tables_.visibility.size()) return 0.f;
  const graph::CellVisibility& v = tables_.visibility[cell];
  const auto it = std::lower_bound(v.blocks.begin(), v.blocks.end(), block);
  if (it == v.blocks.end() || *it != block) return 0.f;
  const size_t i = size_t(it - v.blocks.begin());
  return i < v.ach.size() ? v.ach[i] : 0.f;
}

namespace {
template <typename T>
uint64_t bytesOf(const std::vector<T>& v) {
  return uint64_t(v.capacity()) * sizeof(T);
}
uint64_t bytesOf(const graph::Csr& c) { return bytesOf(c.offsets) + bytesOf(c.items); }
}  // namespace

uint64_t City::tableBytes() const {
  uint64_t n = bytesOf(graph_.vertices) + bytesOf(graph_.halfedges) + bytesOf(graph_.faces) +
               bytesOf(graph_.points) + bytesOf(graph_.successors) + bytesOf(graph_.predecessors) +
               bytesOf(graph_.local_blocks) + bytesOf(blocks_) + bytesOf(tables_.visibility) +
               bytesOf(tables_.impostors) + (whole_ ? whole_->bytes() : 0) + (paged_ ? paged_->bytes() : 0) +
               (cell_pages_ ? cell_pages_->bytes() : 0) +
               (block_pages_ ? block_pages_->bytes() : 0) + (ground_ ? ground_->bytes() : 0) + (terrain_ ? terrain_->bytes() : 0);
  for (const auto& v : tables_.visibility) n += bytesOf(v.blocks) + bytesOf(v.ach);
  for (const auto& c : tables_.impostors) {
    n += bytesOf(c.layered) + bytesOf(c.single);
    for (const auto& l : c.layered) n += bytesOf(l.blocks);
    for (const auto& l : c.single) n += bytesOf(l.blocks);
  }
  return n;
}

core::Status City::decodeBlock(uint32_t b, geo::MeshData& out, std::string& err) const {
  out.clear();
  if (b < blockCount() && block(b).blob == 0xffffffffu) return core::Status::Ok;  // empty block, no levels
  return decodeBlock(b, 0, out, err);
}

core::Status City::levelMissing(uint32_t b, uint32_t lod, std::string& err) const {
  err = "block " + std::to_string(b) + " has " + std::to_string(block(b).lod_count) + " levels, level " +
        std::to_string(lod) + " requested";
  return core::Status::NotFound;
}

core::Status City::decodeBlock(uint32_t b, uint32_t lod, geo::MeshData& out, std::string& err) const {
  out.clear();
  // Checked before the open, so a missing level costs no parse.
  if (b < blockCount() && lod >= block(b).lod_count) return levelMissing(b, lod, err);
  BlockBlob blob;
  const core::Status st = openBlock(b, blob, err);
  if (st != core::Status::Ok) return st;
  return decodeBlockLevel(blob, lod, out, err);
}

void City::BlockBlob::close() {
  span_ = {};
  glb_ = package::GlbDocument{};
  block_ = 0xffffffffu;
}

core::Status City::openBlock(uint32_t b, BlockBlob& blob, std::string& err) const {
  blob.close();
  if (b >= blockCount()) {
    err = "block " + std::to_string(b) + " does not exist";
    return core::Status::NotFound;
  }
  const graph::BlockRecord rec = block(b);
  if (rec.lod_count == 0 || rec.blob == 0xffffffffu) {
    err = "block " + std::to_string(b) + " is empty (no levels)";
    return core::Status::NotFound;
  }
  package::Span s;
  core::Status st = blobBytes(rec.blob, s, blob.bytes_, err);
  if (st != core::Status::Ok) return st;
  blob.span_ = s;
  st = blob.glb_.open(s.data, s.size, err);
  if (st != core::Status::Ok) {
    err = reader_.name() + ": block " + std::to_string(b) + " at offset " + std::to_string(s.offset) + ": " + err;
    blob.close();
    return st;
  }
  blob.block_ = b;
  return core::Status::Ok;
}

core::Status City::decodeBlockLevel(const BlockBlob& blob, uint32_t lod, geo::MeshData& out, std::string& err) const {
  out.clear();
  const uint32_t b = blob.block_;
  if (b >= blockCount() || !blob.glb_.isOpen()) {
    err = "block blob not open";
    return core::Status::Misuse;
  }
  const graph::BlockRecord rec = block(b);
  if (lod >= rec.lod_count) return levelMissing(b, lod, err);
  core::Status st = blob.glb_.decodeLevel(lod, out, err);
  if (st == core::Status::NotFound) st = core::Status::Corrupt;  // BLCK promised the level
  auto where = [&] {
    return reader_.name() + ": block " + std::to_string(b) + " level " + std::to_string(lod) + " at offset " +
           std::to_string(blob.span_.offset) + ": ";
  };
  if (st != core::Status::Ok) {
    err = where() + err;
    return st;
  }
  // Pools are sized from the record; a GLB that decodes to more would overrun them.
  if (out.vertexCount() != rec.vertices[lod] || out.triangleCount() != rec.triangles[lod]) {
    err = where() + "decodes to " + std::to_string(out.vertexCount()) + " vertices and " +
          std::to_string(out.triangleCount()) + " triangles, BLCK records " + std::to_string(rec.vertices[lod]) +
          " and " + std::to_string(rec.triangles[lod]);
    out.clear();
    return core::Status::Corrupt;
  }
  return core::Status::Ok;
}

core::Status City::decodeImpostorBlob(uint32_t blob, geo::MeshData& out, std::string& err,
                                      std::vector<uint8_t>* hold) const {
  package::Span s;
  std::vector<uint8_t> own;
  core::Status st = blobBytes(blob, s, hold ? *hold : own, err);
  if (st != core::Status::Ok) return st;
  st = package::decodeGlb(s.data, s.size, out, err);
  if (st != core::Status::Ok)
    err = reader_.name() + ": impostor blob " + std::to_string(blob) + " at offset " + std::to_string(s.offset) +
          ": " + err;
  return st;
}

namespace {
// The cost of being on a half-edge's directed segment a→a+d: metres from p
// to the segment plus a penalty for facing the wrong way, 5 m × (1 − cos),
// with `cos_fwd` the cosine between d and the heading. Shared by
// nearestCell and cellCost so the two compare like with like.
constexpr double kHeadingPenaltyM = 5.0;
double headingPenalty(double cos_fwd) { return kHeadingPenaltyM * (1.0 - cos_fwd); }
glm::dvec2 headingDir(double heading_deg) {
  return {std::sin(glm::radians(heading_deg)), std::cos(glm::radians(heading_deg))};
}
}  // namespace

double City::cellCost(uint32_t cell, glm::dvec2 p, double heading_deg, double* arc_m, bool* at_end) const {
  const glm::dvec2 dir = headingDir(heading_deg);
  const graph::HalfEdge e = streets_->halfedge(cell);
  double best = 1e300, before = 0, best_arc = 0;
  for (uint32_t i = e.pts_begin; i + 1 < e.pts_begin + e.pts_count; ++i) {
    const glm::dvec2 a = streets_->point(i), d = streets_->point(i + 1) - a;
    const double len = glm::length(d);
    if (len < 1e-9) continue;
    const double t = glm::clamp(glm::dot(p - a, d) / (len * len), 0.0, 1.0);
    const double cost = glm::length(a + d * t - p) + headingPenalty(glm::dot(d / len, dir));
    if (cost < best) best = cost, best_arc = before + t * len;
    before += len;
  }
  if (arc_m) *arc_m = best_arc;
  if (at_end) *at_end = best_arc >= before - 1e-6;  // `before` is now the whole length
  return best;
}

void City::warmCell(uint32_t cell) const {
  const graph::HalfEdge e = streets_->halfedge(cell);
  double arc = 0;
  for (uint32_t i = e.pts_begin; i + 1 < e.pts_begin + e.pts_count; ++i) {
    const glm::dvec2 a = streets_->point(i), b = streets_->point(i + 1);
    const double len = glm::length(b - a);
    const double heading = glm::degrees(std::atan2(b.x - a.x, b.y - a.y));
    for (double t = 0; t < len; t += 10.0)
      for (const double h : {heading, heading + 180.0}) nearestCell(a + (b - a) * (t / len), h, &arc);
  }
  const glm::dvec2 end = streets_->point(e.pts_begin + e.pts_count - 1);
  bool at_end = false;
  for (const uint32_t s : streets_->successors(cell)) cellCost(s, end, 0.0, &arc, &at_end);
}

uint32_t City::nearestCell(glm::dvec2 p, double heading_deg, double* arc_m, double* cost_out) const {
  const glm::dvec2 dir = headingDir(heading_deg);
  double best = 1e300;
  uint32_t best_h = graph::kNone;
  // Distance plus a penalty for facing the wrong way, so of two twin
  // half-edges the one going our way wins. The grid lists one half-edge of
  // each pair; its twin runs the same segment backwards.
  auto consider = [&](uint32_t h, uint32_t point) {
    const graph::HalfEdge e = streets_->halfedge(h);
    const glm::dvec2 a = streets_->point(point), b = streets_->point(point + 1);
    const glm::dvec2 d = b - a;
    const double len = glm::length(d);
    if (len < 1e-9) return;
    const double t = glm::clamp(glm::dot(p - a, d) / (len * len), 0.0, 1.0);
    const double dist = glm::length(a + d * t - p);
    const double cos_fwd = glm::dot(d / len, dir);
    for (int back = 0; back < 2; ++back) {
      const uint32_t c = back ? e.twin : h;
      if (c == graph::kNone) continue;
      const double cost = dist + headingPenalty(back ? -cos_fwd : cos_fwd);
      if (!(cost < best || (cost == best && c < best_h))) continue;
      best = cost;
      best_h = c;
      if (!arc_m) continue;
      // Metres of h's polyline before this segment, and in all (only for a
      // new best: most segments the grid offers are not).
      double before = 0, total = 0;
      for (uint32_t i = e.pts_begin; i + 1 < e.pts_begin + e.pts_count; ++i) {
        const double l = glm::length(streets_->point(i + 1) - streets_->point(i));
        if (i < point) before += l;
        total += l;
      }
      *arc_m = back ? total - (before + t * len) : before + t * len;
    }
  };
  // Growing squares: a segment farther than r cannot beat a cost <= r (the
  // heading penalty is never negative). Past the grid's extent, every
  // segment has been seen.
  const graph::GridShape grid = streets_->gridShape();
  const double extent = grid.cell * std::max(grid.nx, grid.ny);
  for (double r = grid.cell; streets_->gridEntryCount() > 0; r *= 2) {
    streets_->forSegmentsNear(p.x, p.y, r, [&](const graph::SegmentGrid::Entry& en) { consider(en.halfedge, en.point); });
    if (best <= r || r > 2 * extent + glm::length(p)) break;
  }
  if (cost_out) *cost_out = best;
  return best_h;
}

}  // namespace blvd::stream
