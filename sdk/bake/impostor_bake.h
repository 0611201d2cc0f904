// Per-cell visibility and impostors (the heart of the method):
//  1. PVS and coverage: item buffers all around from sample points along each
//     street (Décoret 99 §5.3), with every block's pixel share kept as its
//     Average Coverage Hint (Marvie: positions along the cell × 6 directions).
//  2. Vantage point per cell and the captures' frusta fitted to what each
//     layer covers (Kmoch 06 §4.4.4, Sillion 97 §4.2; capture_plan.h).
//  3. Far blocks grouped into layers by visibility events (Décoret 99 §4.1–4.2).
//  4. One textured depth mesh per layer and capture (Sillion 97 §4.2).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "geo/mesh.h"
#include "graph/cell_tables.h"
#include "graph/street_graph.h"
#include "package/glb.h"
#include "package/writer.h"

namespace blvd::bake {

enum class ImpostorMode { None, Single, Layered, Both };

enum class TextureCodec : uint8_t { Jpeg, Webp };

struct ImpostorOptions {
  ImpostorMode mode = ImpostorMode::Layered;
  // The ground's height under a street point (bake/terrain.h); unset: flat at
  // 0. The eye of every item-buffer sample and capture is kEyeHeight above it.
  std::function<double(glm::dvec2)> ground;
  int texture_max = 512;          // largest texture side, pixels
  double threshold_px = 10.0;     // D99's T, pixels at the display below
  int max_layers = 4;             // layers beyond this merge (capLayers); counted in the result
  int display_width = 800, display_height = 480;
  double display_fov_y_deg = 45.0;
  int grid_px = 24;               // S97 grid spacing inside the contour, texture pixels
  int skirt_px = 1;               // rows hung under far geometry's lower edge (depth_mesh.h hangSkirt)
  double edge_on_cos = 0.2;       // depth-mesh triangles seen this edge-on are dropped (depth_mesh.h dropEdgeOnTriangles; 0: none)
  int positions_per_cell = 8;     // item-buffer positions along a street, ends included (Marvie: 8 × 6 directions)
  int item_resolution = 128;      // item buffer size per direction (square, 90°)
  double vantage_at = 0.5;        // where along its run a run's vantage point stands: 0 its start, 1 its end
  double max_span_deg = 45.0;     // widest azimuth one capture holds (capture_plan.h)
  double view_margin_deg = 10.0;  // azimuths covered past half the display's field, each side
  int cell_texels = 655360;       // texel budget of a cell's captures together (capture_plan.h)
  double run_length_m = 35.0;     // a longer cell gets several runs (vantage points) ...
  double run_turn_deg = 90.0;     // ... and so does one turning more than this
  double run_climb_m = 3.0;       // ... or whose ground rises or falls more than this (on terrain; 0: off)
  int max_runs = 16;
  double landmark_height_m = 60.0;  // blocks with a building at least this tall ...
  double landmark_scale = 2.0;      // ... get their D99 weights scaled by this
  // How the atlases are stored: lossy WebP (EXT_texture_webp), or JPEG, at
  // this quality (0..100; decision 0010 chose 75 for JPEG). The defaults
  // above and this one: decision 0015 (WebP pays for twice the texels).
  // 60 rather than 75: the 2016 route's far metrics are the same (far_bad
  // p50 6.3 %, p95 23.3 against 23.2 %) for 12 % fewer image bytes
  // (docs/decisions/0027).
  TextureCodec texture_codec = TextureCodec::Webp;
  int texture_quality = 60;
  // How the depth meshes are stored (package/glb.h), and Draco's
  // quantization of their positions (over the mesh's box: 15 bits keep a
  // vertex within 3 cm on a box of 2 km, half a display pixel at 35 m) and
  // texture coordinates (11 bits: an eighth of a texel on a 512-texel atlas).
  // Decision 0027 measured what each costs.
  package::GlbCodec mesh_codec = package::GlbCodec::Draco;
  int mesh_position_bits = 15;
  int mesh_texcoord_bits = 11;
  std::vector<uint32_t> only_cells; // bake impostors only for these cells (empty: all)
  // Capture workers, each with its own GL context (0: one per CPU). The
  // package is the same with any number (bake/rig_pool.h).
  int jobs = 0;
  // One shard of the bake (bake/shard.h): only the streets of shard
  // shard_index of shard_count (shard_plan.h) are baked, and its rigs draw
  // only the blocks within reach of them. 0 shards: the whole bake.
  uint32_t shard_index = 0, shard_count = 0;
};

// One impostor as the bake report shows it.
struct ImpostorRecord {
  uint32_t cell = 0;
  bool single = false;
  uint32_t layer = 0;
  float run_from_m = 0.f;         // the run of the cell it serves (arc length of its start)
  glm::dvec3 eye_enu{0.0};        // its vantage point (east, north, up)
  uint32_t shot = 0;              // captures in the layer's atlas (capture_plan.h: one per piece of azimuth)
  double density = 1.0;           // lowest texels per display pixel of its captures (< 1: a cap bit)
  uint32_t triangles = 0, bytes = 0, blocks = 0;
  int texture_width = 0, texture_height = 0;
  double seconds = 0;
  std::vector<uint8_t> jpeg;  // the texture, for thumbnails
};

struct ImpostorBakeResult {
  graph::CellTables tables;
  std::vector<ImpostorRecord> records;
  double pvs_seconds = 0, impostor_seconds = 0;
  size_t samples = 0;
  size_t capped_cells = 0;          // cells whose D99 layering needed more than max_layers
  double capped_worst_px = 0;       // largest weight a merge admitted, in display pixels
  size_t budget_cells = 0;          // cells whose captures the texel budget scaled down
  double budget_min_density = 1.0;  // the lowest density it left (texels per display pixel)
  // A shard's streets (lower half-edges, ascending), the estimated cost of
  // each shard (shard_plan.h) and the blocks its rigs drew.
  std::vector<uint32_t> shard_streets;
  std::vector<std::vector<uint32_t>> shard_plan;  // every shard's streets
  std::vector<double> shard_costs;
  size_t shard_blocks_drawn = 0;
};

// block_meshes: per block (face) its full geometry, glTF axes. Blobs go into
// `writer`. `progress(stage, done, total)` reports. Deterministic: the same
// inputs give the same blobs.
ImpostorBakeResult bakeImpostors(const graph::StreetGraph& g, const std::vector<geo::MeshData>& block_meshes,
                                 const ImpostorOptions& opt, package::PackageWriter& writer,
                                 const std::function<void(const char*, double, double)>& progress = {});

// Horizontal field of view of the display (degrees).
double displayFovX(const ImpostorOptions& opt);
// The runs of cell `e` ([from, to) arc lengths): their rule is in impostor_bake.cpp.
std::vector<std::pair<double, double>> cellRuns(const graph::StreetGraph& g, const graph::HalfEdge& e,
                                                const ImpostorOptions& opt);
// The most the ground (opt.ground) rises or falls along cell `e`; 0 without one.
double cellClimb(const graph::StreetGraph& g, const graph::HalfEdge& e, const ImpostorOptions& opt);

}  // namespace blvd::bake
