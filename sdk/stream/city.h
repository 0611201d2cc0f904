// A city opened from a package: the validated header, street graph, cells and
// block table, plus decoding of a block's geometry on request. This is the
// read side every runtime path shares; residency (which blocks are decoded and
// uploaded, in fixed pools) builds on it.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "geo/local_frame.h"
#include "geo/mesh.h"
#include "graph/block_table.h"
#include "graph/cell_tables.h"
#include "graph/segment_grid.h"
#include "graph/street_graph.h"
#include "package/glb.h"
#include "stream/block_pages.h"
#include "stream/cell_table_pages.h"
#include "stream/paged_graph.h"
#include "stream/terrain_pages.h"
#include "package/reader.h"
#include "remote/remote_package.h"

namespace blvd::stream {

class City {
 public:
  City() = default;
  City(const City&) = delete;  // the graph sources point into it
  City& operator=(const City&) = delete;

  // Opens and validates `path`: the package container, then the GRPH, CELL and
  // BLCK sections (CRC-checked and parsed with bounds checks). Returns
  // Io/Corrupt/Unsupported with a message naming the file and offset.
  // Tables::Graph reads the graph and cells only (tracking without render
  // data): blocks() and cellTables() stay empty.
  enum class Tables { All, Graph };
  // GraphTables::Whole parses the graph into memory (graph() is the whole
  // StreetGraph: the bake, tools, tests); Paged reads it through a fixed page
  // cache (stream/paged_graph.h: what the runtime and the tracker hold does
  // not grow with the city) and graph() stays empty. streets() reads either.
  enum class GraphTables { Whole, Paged };
  core::Status open(const std::string& path, std::string& err, Tables tables = Tables::All,
                    GraphTables graph = GraphTables::Whole, const PagedGraphDesc& paging = {});
  // The same for a package on a server (`url`: http:// or https://): its
  // tables are mirrored in remote.cache_path (required) and read from there
  // as from a local package; blobs come through the disk cache
  // (remote/remote_package.h). A mirror that fails its checks is fetched
  // again, once (never offline). Unavailable offline without a mirror.
  // A package with table page CRCs (3.2) mirrors its tables a page at a
  // time as they are read: a read of the tables may then wait for the link,
  // and throws core::Error (Unavailable offline, Corrupt for a bad record)
  // where a local package's cannot fail; open reads their headers only.
  core::Status openUrl(const std::string& url, const remote::RemoteOptions& remote, std::string& err,
                       Tables tables = Tables::All, GraphTables graph = GraphTables::Paged,
                       const PagedGraphDesc& paging = {});
  static bool isUrl(const std::string& path);
  // While one lives on a thread, that thread's reads of tables arriving over
  // the link never wait for it: a missing page is asked for (the link
  // prefetch's thread fetches it) and the read throws core::Error
  // (Unavailable). The render thread, whose frame draws what is resident instead.
  class NoLinkWait {
   public:
    NoLinkWait();
    ~NoLinkWait();
    NoLinkWait(const NoLinkWait&) = delete;
    NoLinkWait& operator=(const NoLinkWait&) = delete;

   private:
    bool was_;
  };
  // The package on a server, or nullptr for a local one.
  remote::RemotePackage* remote() const { return remote_.get(); }
  // Blobs cell `cell` draws (its non-empty local blocks but skip[0 ..
  // skip_count), its impostor layers) into out (cleared first).
  void cellBlobs(uint32_t cell, const uint32_t* skip, uint32_t skip_count, std::vector<uint32_t>& out) const;
  // Whether every blob `cell` draws is in the disk cache (always, for a
  // local package; never when its table pages cannot be read). `scratch`
  // holds its blobs after.
  bool cellCached(uint32_t cell, std::vector<uint32_t>& scratch) const;

  const package::PackageReader& package() const { return reader_; }
  const package::PackageHeader& header() const { return reader_.header(); }
  const graph::StreetGraph& graph() const { return graph_; }  // empty when paged
  const graph::GraphSource& streets() const { return *streets_; }
  bool paged() const { return paged_ != nullptr; }
  // Reads what a frame at any pose along `cell` reads of the tables to choose
  // its cell (the nearest cell every 10 m along it, heading both ways, and
  // the cost of each successor): for a package on a server, the link
  // prefetch's thread brings those pages before the vehicle gets there, so
  // the frames there do not ask for them. Throws as the reads do.
  void warmCell(uint32_t cell) const;
  // Whether a table page that is not here may still arrive: the package is
  // on a server, online or metered, the link up and the package unchanged.
  bool linkMayBringTables() const {
    return remote_ && remote_->mode() != remote::LinkMode::Offline && !remote_->linkDown() && !remote_->changed();
  }
  // Whether the tables arrive a page at a time over the link (their records
  // are checked as read, not at open).
  bool tablesOverLink() const { return source() != nullptr; }
  // The page cache's counts (zero when the graph is whole).
  PageCacheStats graphPageStats() const { return paged_ ? paged_->stats() : PageCacheStats{}; }
  uint64_t graphCacheBytes() const { return paged_ ? paged_->bytes() : 0; }
  PageCacheStats cellTablePageStats() const { return cell_pages_ ? cell_pages_->stats() : PageCacheStats{}; }
  PageCacheStats blockPageStats() const { return block_pages_ ? block_pages_->stats() : PageCacheStats{}; }
  // Whole tables only (empty when paged: the runtime reads block(), which serves both).
  const std::vector<graph::BlockRecord>& blocks() const { return blocks_; }
  uint32_t blockCount() const { return block_pages_ ? block_pages_->count() : static_cast<uint32_t>(blocks_.size()); }
  graph::BlockRecord block(uint32_t b) const { return block_pages_ ? block_pages_->record(b) : blocks_[b]; }
  // Visibility and impostors per cell; empty tables for a package baked with
  // --impostor none.
  // Whole tables only: empty when paged (the runtime reads cellLayers() and
  // coverage(), which serve both).
  const graph::CellTables& cellTables() const { return tables_; }
  bool hasImpostors() const { return cell_pages_ || !tables_.impostors.empty(); }
  // Layers of the cell with the most impostor layers (layered and single).
  uint32_t maxCellLayers() const { return max_cell_layers_; }
  // A cell's layered impostor layers into out[0 .. *layered), then its single
  // ones (at most `cap` in all: maxCellLayers() suffices). No allocation.
  void cellLayers(uint32_t cell, LayerInfo* out, uint32_t cap, uint32_t* layered, uint32_t* single) const;
  // The coverage hint (ACH) of `block` seen from `cell`; 0 when not in its PVS
  // or when the package has no visibility. No allocation.
  float coverage(uint32_t cell, uint32_t block) const;
  // Decodes one impostor layer's GLB (textured depth mesh with its image).
  core::Status decodeImpostor(const graph::ImpostorLayer& layer, geo::MeshData& out, std::string& err) const {
    return decodeImpostorBlob(layer.blob, out, err);
  }
  // `hold` (optional) receives the blob's bytes, so a loader that keeps it
  // reads every blob without an allocation once it has the largest.
  core::Status decodeImpostorBlob(uint32_t blob, geo::MeshData& out, std::string& err,
                                  std::vector<uint8_t>* hold = nullptr) const;
  const geo::LocalFrame& frame() const { return frame_; }
  // Terrain (the ELEV section, docs/package-format.md): whether the package
  // has the ground's height under its streets, and that height at arc length
  // `arc_m` along cell `cell` (linear between its polyline's points), metres
  // above the frame's origin height; 0 without ELEV. No allocation.
  bool hasGround() const { return ground_ != nullptr; }
  double groundHeight(uint32_t cell, double arc_m) const;
  // The same height and the road's grade there along the cell's direction
  // (rise over run of the polyline segment holding arc_m; 0 on a segment under
  // half a metre), in one walk of the polyline. False without ELEV.
  bool groundAt(uint32_t cell, double arc_m, double& height, double& grade) const;
  // A car's camera on the road there: the eye `eye_height_m` above the road,
  // the road's grade added to `pitch_deg` (within ±89°). False, and nothing
  // changed, without ELEV. What the runtime's frame and both trackers' poses use.
  bool cameraOnRoad(uint32_t cell, double arc_m, double eye_height_m, double& eye_u, double& pitch_deg) const;
  // Terrain tiles (the TERR section, stream/terrain_pages.h): null when the
  // package has none.
  const TerrainPages* terrain() const { return terrain_.get(); }
  // Tile `tile`'s heights (record r, read by the caller) into out[grid²];
  // `hold` keeps the blob's bytes between calls. Corrupt for a bad blob,
  // Io for a file cut short; Unavailable for a package on a server whose
  // cache does not hold the tile (a frame never waits for the link).
  core::Status terrainHeights(const graph::TerrainRecord& r, std::vector<uint8_t>& hold, float* out,
                              std::string& err) const;
  // Whether terrainHeights(r) can read its blob without the link (always for
  // a local package); allocates nothing.
  bool terrainCached(const graph::TerrainRecord& r) const;
  // Heap bytes of the tables above (graph, cells, blocks, visibility,
  // impostor lists): what holding the city costs besides the mapped file.
  uint64_t tableBytes() const;

  // Decodes block `b`'s GLB into `out` (cleared first). An empty block gives an
  // empty mesh and Ok. Corrupt if the blob's CRC or the GLB is bad.
  core::Status decodeBlock(uint32_t b, geo::MeshData& out, std::string& err) const;
  // Decodes level `lod` (0 = full) of block `b`: exactly blocks()[b].vertices[lod]
  // vertices and .triangles[lod] triangles. NotFound when lod >= lod_count (an
  // empty block has none); Corrupt, naming the file, block and offset, when the
  // blob or GLB is bad or its level disagrees with the BLCK record.
  core::Status decodeBlock(uint32_t b, uint32_t lod, geo::MeshData& out, std::string& err) const;

  // A block blob opened for decoding its levels one after another (the
  // loader's order): the blob's CRC is checked and its GLB's JSON parsed
  // once, not once per level, and its file pages are dropped once, when it
  // closes (or goes away). decodeBlock(b, lod) is open + decode + close.
  class BlockBlob {
   public:
    BlockBlob() = default;
    ~BlockBlob() { close(); }
    BlockBlob(const BlockBlob&) = delete;
    BlockBlob& operator=(const BlockBlob&) = delete;
    void close();
    uint32_t block() const { return block_; }

   private:
    friend class City;
    uint32_t block_ = 0xffffffffu;
    package::Span span_{};
    std::vector<uint8_t> bytes_;  // the blob, read from the file or the link; kept between opens
    package::GlbDocument glb_;
  };
  // NotFound for a block that does not exist or has no levels (empty);
  // Corrupt, naming the file, block and offset, for a bad blob or GLB.
  core::Status openBlock(uint32_t b, BlockBlob& blob, std::string& err) const;
  // As decodeBlock(blob.block(), lod): the same checks against the record.
  core::Status decodeBlockLevel(const BlockBlob& blob, uint32_t lod, geo::MeshData& out, std::string& err) const;

  // The cell nearest to local point p whose direction best matches heading_deg
  // (clockwise from north); kNone for an empty graph. Also returns the arc
  // length along the cell of the closest point. Searches the segment grid in
  // growing squares, so a frame's cost does not grow with the city; no
  // allocation.
  // `cost_out` (optional) receives the winner's cost: metres from p plus the
  // heading penalty, 5 m × (1 − cos of the angle to the cell's direction).
  uint32_t nearestCell(glm::dvec2 p, double heading_deg, double* arc_m = nullptr, double* cost_out = nullptr) const;
  // The same cost for one given cell (its nearest segment), the arc length of
  // the closest point and whether that point is the cell's end (p lies past
  // it). No allocation.
  double cellCost(uint32_t cell, glm::dvec2 p, double heading_deg, double* arc_m, bool* at_end) const;

 private:
  core::Status levelMissing(uint32_t b, uint32_t lod, std::string& err) const;  // NotFound, naming both
  core::Status openWhole(std::string& err);
  core::Status openPaged(const PagedGraphDesc& paging, std::string& err);
  core::Status openRenderTables(std::string& err);
  core::Status openElevation(std::string& err);  // ELEV, when the package has one
  core::Status openTerrain(std::string& err);    // TERR, when the package has one
  // The polyline segment of `cell` holding arc_m: its ends' heights, its
  // length and arc_m's place along it.
  struct GroundSegment {
    double h0 = 0, h1 = 0, length = 0, at_m = 0;
  };
  bool groundSegment(uint32_t cell, double arc_m, GroundSegment& out) const;
  // The section read whole into `hold` and CRC-checked (`s` points at the
  // copy); Corrupt when absent.
  core::Status requiredSection(uint32_t tag, std::vector<uint8_t>& hold, package::Span& s, std::string& err) const;
  // A section's pages all fetched (a whole-table parse of a package on a server).
  core::Status ensureSection(uint32_t tag, std::string& err) const;
  // Table pages over the link, for a package on a server with table page CRCs.
  struct LinkPages final : PageSource {
    remote::RemotePackage* remote = nullptr;
    void ensure(uint64_t offset, uint64_t size) const override;
  };
  const PageSource* source() const { return remote_ && remote_->lazyTables() ? &link_pages_ : nullptr; }
  LinkPages link_pages_;
  // Blob i's bytes: a span of the mapping, or of `hold` fetched through remote_.
  core::Status blobBytes(uint32_t i, package::Span& s, std::vector<uint8_t>& hold, std::string& err) const;
  std::unique_ptr<remote::RemotePackage> remote_;
  package::PackageReader reader_;
  graph::StreetGraph graph_;
  std::vector<graph::BlockRecord> blocks_;
  graph::CellTables tables_;
  std::unique_ptr<graph::MemoryGraph> whole_;  // over graph_, with its segment grid
  std::unique_ptr<PagedGraph> paged_;
  std::unique_ptr<CellTablePages> cell_pages_;
  std::unique_ptr<BlockPages> block_pages_;  // paged  // paged, for a package with a cell table index
  uint32_t max_cell_layers_ = 0;
  const graph::GraphSource* streets_ = nullptr;  // whole_ or paged_
  std::unique_ptr<TerrainPages> terrain_;
  // ELEV: the ground's height at each graph point, through a page cache.
  std::unique_ptr<PageCache> ground_;
  uint32_t ground_table_ = 0;
  uint64_t ground_points_ = 0, ground_offset_ = 0;
  float groundOf(uint64_t point) const;  // throws core::Error(Corrupt) for an implausible height
  geo::LocalFrame frame_{0, 0, 0};
};

}  // namespace blvd::stream
