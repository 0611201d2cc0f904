#include "bake/impostor_bake.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "bake/capture.h"
#include "bake/capture_plan.h"
#include "bake/atlas.h"
#include "bake/depth_mesh.h"
#include "bake/layers.h"
#include "bake/rig_pool.h"
#include "bake/shard_plan.h"
#include "bake/street_points.h"
#include "bake/texture_encode.h"
#include "bake/visibility_bake.h"
#include "core/log.h"
#include "package/glb.h"
#include "render/camera.h"

namespace blvd::bake {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct BlockInfo {
  std::vector<glm::dvec2> hull;  // ground footprint (east, north)
  glm::dvec3 lo{0}, hi{0};       // glTF box
  double top = 0;
};

// Where a run of a cell's captures stand and which directions they must
// cover (capture_plan.h, docs/decisions/0010).
struct CellView {
  double s0 = 0, s1 = 0;      // the run: arc lengths along the cell
  glm::dvec2 P{0.0}, Q{0.0};  // its ends: D99's viewing segment
  glm::dvec3 eye_enu{0.0};    // the vantage point
  double heading_deg = 0;     // the reference direction: the run's chord
  double az_lo = 0, az_hi = 0;  // azimuths to cover, relative to heading_deg
};

double headingOf(glm::dvec2 d) { return glm::degrees(std::atan2(d.x, d.y)); }
double wrap180(double a) { return a - 360.0 * std::floor((a + 180.0) / 360.0); }
constexpr double kMaxNeighbourTurnDeg = 120.0;
constexpr int kAtlasGutter = 4;  // pixels around each capture in a layer's atlas

// Heading of a cell's first (or last) segment of non-zero length.
double edgeHeading(const graph::StreetGraph& g, uint32_t cell, bool first) {
  const graph::HalfEdge& e = g.halfedges[cell];
  for (uint32_t k = 1; k < e.pts_count; ++k) {
    const uint32_t i = first ? k : e.pts_count - k;
    const glm::dvec2 d = g.points[e.pts_begin + i] - g.points[e.pts_begin + i - 1];
    if (glm::length(d) > 1e-6) return headingOf(d);
  }
  return 0.0;
}

// Headings of the cell's segments that overlap [s0, s1], in order.
std::vector<double> runHeadings(const graph::StreetGraph& g, const graph::HalfEdge& e, double s0, double s1) {
  std::vector<double> out;
  double s = 0;
  for (uint32_t i = 1; i < e.pts_count; ++i) {
    const glm::dvec2 d = g.points[e.pts_begin + i] - g.points[e.pts_begin + i - 1];
    const double len = glm::length(d);
    if (len > 1e-6 && s + len > s0 && s < s1) out.push_back(headingOf(d));
    s += len;
  }
  return out;
}

}  // namespace

// The most the ground rises or falls along the cell (0 without a terrain),
// from heights every 5 m.
double cellClimb(const graph::StreetGraph& g, const graph::HalfEdge& e, const ImpostorOptions& opt) {
  if (!opt.ground) return 0.0;
  double lo = 1e300, hi = -1e300;
  const int steps = std::max(1, static_cast<int>(std::ceil(e.length / 5.0)));
  for (int k = 0; k <= steps; ++k) {
    const double h = opt.ground(pointAt(g, e, e.length * k / steps));
    lo = std::min(lo, h), hi = std::max(hi, h);
  }
  return hi - lo;
}

// The runs of a cell (S97 §4.2's vantage point, repeated): a cell longer
// than run_length_m, turning more than run_turn_deg or (on terrain) whose
// ground rises or falls more than run_climb_m gets several, equal in length,
// at most max_runs: a viewer above or below the vantage point sees roofs and
// ground the capture did not. Each run's impostors are drawn only while the
// viewer is on it, so each is captured from where its viewer stands.
std::vector<std::pair<double, double>> cellRuns(const graph::StreetGraph& g, const graph::HalfEdge& e,
                                                const ImpostorOptions& opt) {
  const std::vector<double> hd = runHeadings(g, e, 0.0, e.length);
  double turn = 0, lo = 0, hi = 0;
  for (size_t i = 1; i < hd.size(); ++i) turn += wrap180(hd[i] - hd[i - 1]), lo = std::min(lo, turn), hi = std::max(hi, turn);
  int want = std::max(static_cast<int>(std::ceil(e.length / opt.run_length_m - 1e-9)),
                      static_cast<int>(std::ceil((hi - lo) / opt.run_turn_deg - 1e-9)));
  if (opt.run_climb_m > 0)
    want = std::max(want, static_cast<int>(std::ceil(cellClimb(g, e, opt) / opt.run_climb_m - 1e-9)));
  const int n = std::clamp(want, 1, opt.max_runs);
  std::vector<std::pair<double, double>> runs;
  for (int k = 0; k < n; ++k) runs.emplace_back(e.length * k / n, e.length * (k + 1) / n);
  return runs;
}

namespace {

// The vantage point stands on the street at opt.vantage_at of the run (the
// middle by default: a viewer is never more than half a run from it, so what
// parallax uncovers and what the capture saw edge-on is half what a vantage
// point at the run's start leaves; docs/decisions/0025), but never inside a
// building. The azimuths: every heading the street takes along the run
// (unwrapped, so a hairpin's sweep is kept), widened by half the display's
// field and a margin: the captures cover every direction a viewer anywhere on
// the run looks (capture_plan.h), in front of the vantage point or behind it.
CellView cellView(const graph::StreetGraph& g, const graph::HalfEdge& e, double s0, double s1,
                  const ImpostorOptions& opt, CaptureRig& rig) {
  CellView v;
  v.s0 = s0, v.s1 = s1;
  v.P = pointAt(g, e, s0);
  v.Q = pointAt(g, e, s1);
  const std::vector<double> hd = runHeadings(g, e, s0, s1);
  glm::dvec2 fwd = v.Q - v.P;
  if (glm::length(fwd) < 1.0 && !hd.empty())
    fwd = {std::sin(glm::radians(hd[0])), std::cos(glm::radians(hd[0]))};
  fwd = glm::length(fwd) > 0 ? glm::normalize(fwd) : glm::dvec2(0, 1);
  v.heading_deg = headingOf(fwd);
  // Moved along the run where the eye would be inside a building (a street
  // under a building, a short cell ending at a corner): a capture from inside
  // sees only back faces.
  const double at = std::clamp(opt.vantage_at, 0.0, 1.0);
  for (double f : {at, 0.5, 0.25, 0.75, 0.0, 1.0}) {
    v.eye_enu = eyeAt(pointAt(g, e, s0 + f * (s1 - s0)), opt.ground);
    if (!rig.insideGeometry(v.eye_enu)) break;
  }
  double a = 0, lo = 0, hi = 0;
  for (size_t i = 0; i < hd.size(); ++i) {
    a = i == 0 ? wrap180(hd[0] - v.heading_deg) : a + wrap180(hd[i] - hd[i - 1]);
    lo = std::min(lo, a), hi = std::max(hi, a);
  }
  // A driver turns into the next street before the cell ends (and out of the
  // last one after it begins): the neighbours' headings at the shared ends,
  // U-turns aside, are looked along from the first and last runs too.
  const uint32_t h = uint32_t(&e - g.halfedges.data());
  auto turnTo = [&](double from, double to, double base) {
    const double t = wrap180(to - from);
    if (std::abs(t) <= kMaxNeighbourTurnDeg) lo = std::min(lo, base + t), hi = std::max(hi, base + t);
  };
  if (!hd.empty() && s1 >= e.length - 1e-6)
    for (const uint32_t* q = g.successors.begin(h); q != g.successors.end(h); ++q)
      turnTo(hd.back(), edgeHeading(g, *q, true), a);
  if (!hd.empty() && s0 <= 1e-6)
    for (const uint32_t* p = g.predecessors.begin(h); p != g.predecessors.end(h); ++p)
      turnTo(hd.front(), edgeHeading(g, *p, false), wrap180(hd.front() - v.heading_deg));
  const double half = 0.5 * displayFovX(opt) + opt.view_margin_deg;
  v.az_lo = lo - half, v.az_hi = hi + half;
  if (v.az_hi - v.az_lo >= 360.0) v.az_lo = -180.0, v.az_hi = 180.0;
  return v;
}

// What one cell adds to the bake's counters (ImpostorBakeResult's).
struct CellCounters {
  size_t capped_cells = 0;
  double capped_worst_px = 0;
  size_t budget_cells = 0;
  double budget_min_density = 1.0;
};

// D99 §4.2's layers of the far blocks for one run's viewing segment, capped
// at max_layers (the report says how much parallax error a merge admitted).
std::vector<std::vector<uint32_t>> layerBlocks(const CellView& view, const std::vector<uint32_t>& far,
                                               const std::vector<BlockInfo>& info, const ImpostorOptions& opt,
                                               double T, CellCounters& res) {
  std::vector<LayerObject> objs;
  for (uint32_t b : far)
    objs.push_back({b, info[b].hull, info[b].top >= opt.landmark_height_m ? opt.landmark_scale : 1.0});
  LayerAssignment la = assignLayers(view.P, view.Q, objs, T);
  if (la.layers.size() > size_t(opt.max_layers)) {
    ++res.capped_cells;
    res.capped_worst_px = std::max(res.capped_worst_px, capLayers(la, objs.size(), opt.max_layers) / T * opt.threshold_px);
  }
  std::vector<std::vector<uint32_t>> out;
  for (const auto& layer : la.layers) {
    std::vector<uint32_t> blocks;
    for (uint32_t i : layer) blocks.push_back(far[i]);
    std::sort(blocks.begin(), blocks.end());
    out.push_back(std::move(blocks));
  }
  return out;
}

// All of a cell's captures scaled to one density so that together they hold
// at most opt.cell_texels texels (where they would hold more at one texel
// per display pixel); counted in `res` for the bake report.
void fitTexelBudget(std::vector<std::vector<CaptureShot>>& plans, const ImpostorOptions& opt,
                    const CapturePlanOptions& popt, CellCounters& res) {
  uint64_t full = 0;
  for (const auto& p : plans)
    for (const CaptureShot& s : p) full += fullDensityTexels(s, popt);
  if (full == 0 || full <= uint64_t(opt.cell_texels)) return;
  const double density = std::sqrt(double(opt.cell_texels) / double(full));
  for (auto& p : plans)
    for (CaptureShot& s : p) sizeCapture(s, density, popt);
  ++res.budget_cells;
  res.budget_min_density = std::min(res.budget_min_density, density);
}

// Shrinks a layer's captures until their images pack into one atlas of at
// most texture_max on a side (each step 15 % fewer texels per side).
AtlasLayout layoutAtlas(std::vector<CaptureShot>& shots, const CapturePlanOptions& popt) {
  AtlasLayout layout;
  for (;;) {
    std::vector<std::pair<int, int>> sizes;
    for (const CaptureShot& s : shots) sizes.emplace_back(s.cam.width, s.cam.height);
    if (packAtlas(sizes, popt.texture_max, kAtlasGutter, layout)) return layout;
    bool smaller = false;
    for (CaptureShot& s : shots) {
      const int w = s.cam.width, h = s.cam.height;
      sizeCapture(s, 0.85 * s.density, popt);
      smaller |= s.cam.width < w || s.cam.height < h;
    }
    if (!smaller)  // each at its least size (capture_plan.h sizeCapture): a bug, not a loop
      throw core::Error(core::Status::Internal, "impostor captures at their least size do not fit one " +
                                                    std::to_string(popt.texture_max) + " texel atlas");
  }
}

// Where capture `pin`, placed at (x0, y0) in an atlas of `atlas_w` x
// `atlas_h` texels, sees a point, as a texcoord: the projective texture
// matrix of the depth mesh's vertices (S97 §4.2: a vertex is an image point
// at a depth), so the package need not store their uv (decision 0041). It
// inverts PinholeCamera::ray: u = (x0 + (sx + 1) w / 2) / W with sx = (d ·
// right) / (z tan_half_x), z = d · forward, d = p - eye; v likewise, down.
package::TexcoordProjection::Shot projectionOf(const PinholeCamera& pin, int x0, int y0, int atlas_w, int atlas_h) {
  const double W = atlas_w, H = atlas_h, w = pin.width, h = pin.height;
  const glm::dvec3 rows[3] = {
      pin.forward * ((x0 + 0.5 * w) / W) + pin.right * (w / (2.0 * pin.tan_half_x * W)),
      pin.forward * ((y0 + 0.5 * h) / H) - pin.up * (h / (2.0 * pin.tan_half_y * H)),
      pin.forward,
  };
  package::TexcoordProjection::Shot shot;
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) shot.matrix[4 * k + c] = static_cast<float>(rows[k][c]);
    shot.matrix[4 * k + 3] = static_cast<float>(-glm::dot(rows[k], pin.eye));
  }
  const float rect[4] = {float(x0 / W), float(y0 / H), float((x0 + w) / W), float((y0 + h) / H)};
  std::copy_n(rect, 4, shot.rect);
  return shot;
}

// A layer's captures made into one textured depth mesh blob `glb` (S97 §4.2):
// each capture's depth mesh, its texture coordinates moved into the atlas,
// and the atlas as the texture, less the triangles the capture saw edge-on
// and a viewer at either end of the run faces (dropEdgeOnTriangles). False when
// nothing survives (nothing covered, or Draco kept nothing).
bool captureLayer(CaptureRig& rig, std::vector<CaptureShot>& shots, const std::vector<uint32_t>& blocks,
                  const ImpostorOptions& opt, const CapturePlanOptions& popt, const glm::dvec3 (&ends)[2],
                  graph::ImpostorLayer& il, ImpostorRecord& rec, std::vector<uint8_t>& glb) {
  const auto tl = Clock::now();
  const AtlasLayout layout = layoutAtlas(shots, popt);
  CaptureImage atlas;
  atlas.width = layout.width, atlas.height = layout.height;
  atlas.rgba.assign(size_t(layout.width) * layout.height * 4, 0);
  atlas.mask.assign(size_t(layout.width) * layout.height, 0);
  geo::MeshData mesh;
  package::TexcoordProjection projection;
  rec.density = 1.0;
  for (size_t k = 0; k < shots.size(); ++k) {
    CaptureImage img;
    PinholeCamera pin;
    rig.capture(shots[k].cam, blocks, img, pin);
    DepthMeshOptions dopt;
    dopt.grid_spacing_px = opt.grid_px;
    hangSkirt(img, opt.skirt_px);
    geo::MeshData part;
    std::string why;
    if (!buildDepthMesh(img, pin, dopt, part, nullptr, why)) {
      BLVD_LOG_DEBUG("cell %u layer %u capture %zu: nothing (%s)", rec.cell, rec.layer, k, why.c_str());
      continue;
    }
    for (const glm::dvec3& end : ends) dropEdgeOnTriangles(part, pin.eye, end, opt.edge_on_cos);
    const auto [x0, y0] = layout.at[k];
    for (int y = 0; y < img.height; ++y) {
      const size_t src = size_t(y) * img.width, dst = size_t(y0 + y) * atlas.width + x0;
      std::copy_n(&img.rgba[src * 4], size_t(img.width) * 4, &atlas.rgba[dst * 4]);
      std::copy_n(&img.mask[src], size_t(img.width), &atlas.mask[dst]);
    }
    for (size_t t = 0; t + 1 < part.texcoords.size(); t += 2) {
      part.texcoords[t] = float((x0 + part.texcoords[t] * img.width) / atlas.width);
      part.texcoords[t + 1] = float((y0 + part.texcoords[t + 1] * img.height) / atlas.height);
    }
    projection.vertex_shot.insert(projection.vertex_shot.end(), part.vertexCount(),
                                  static_cast<uint8_t>(projection.shots.size()));
    projection.shots.push_back(projectionOf(pin, x0, y0, atlas.width, atlas.height));
    mesh.append(part);
    rec.density = std::min(rec.density, shots[k].density);
    ++rec.shot;
  }
  if (mesh.indices.empty()) return false;
  const bool webp = opt.texture_codec == TextureCodec::Webp;
  mesh.image = webp ? encodeTextureWebp(atlas, opt.texture_quality) : encodeTextureJpeg(atlas, opt.texture_quality);
  if (mesh.image.empty()) throw core::Error(core::Status::Internal, "impostor texture: the image encoder failed");
  mesh.image_mime = webp ? "image/webp" : "image/jpeg";
  package::GlbOptions glb_opt;
  glb_opt.normal_bits = 0;
  glb_opt.codec = opt.mesh_codec;
  glb_opt.position_bits = opt.mesh_position_bits;
  glb_opt.texcoord_bits = opt.mesh_texcoord_bits;
  if (projection.shots.size() <= 256) glb_opt.projection = &projection;  // else the uv are stored
  package::GlbMeshCounts counts;
  glb = package::encodeGlb(mesh, glb_opt, &counts);
  if (counts.triangles == 0) {
    BLVD_LOG_DEBUG("cell %u layer %u: no impostor (the mesh codec kept no triangle)", rec.cell, rec.layer);
    return false;
  }
  il.triangles = counts.triangles;
  il.vertices = counts.vertices;
  il.texture_width = static_cast<uint16_t>(atlas.width);
  il.texture_height = static_cast<uint16_t>(atlas.height);
  il.blocks = blocks;
  rec.triangles = il.triangles;
  rec.bytes = static_cast<uint32_t>(glb.size());
  rec.blocks = static_cast<uint32_t>(blocks.size());
  rec.texture_width = atlas.width;
  rec.texture_height = atlas.height;
  rec.jpeg = mesh.image;
  rec.seconds = since(tl);
  return true;
}

}  // namespace

double displayFovX(const ImpostorOptions& opt) {
  const double ty = std::tan(glm::radians(opt.display_fov_y_deg) * 0.5);
  return glm::degrees(2.0 * std::atan(ty * opt.display_width / opt.display_height));
}

namespace {

using Progress = std::function<void(const char*, double, double)>;

// Bounds, footprint hull and top of every block mesh, for the layer split.
std::vector<BlockInfo> blockInfo(const std::vector<geo::MeshData>& block_meshes) {
  std::vector<BlockInfo> info(block_meshes.size());
  for (size_t b = 0; b < block_meshes.size(); ++b) {
    const auto& m = block_meshes[b];
    if (m.empty()) continue;
    std::vector<glm::dvec2> pts;
    info[b].lo = info[b].hi = glm::dvec3(m.positions[0], m.positions[1], m.positions[2]);
    for (size_t v = 0; v < m.positions.size(); v += 3) {
      const glm::dvec3 p(m.positions[v], m.positions[v + 1], m.positions[v + 2]);
      info[b].lo = glm::min(info[b].lo, p);
      info[b].hi = glm::max(info[b].hi, p);
      pts.emplace_back(p.x, -p.z);
    }
    info[b].hull = convexHull(std::move(pts));
    info[b].top = info[b].hi.y;
  }
  return info;
}

// Points every kOutlineStepM along each block's footprint hull at its
// ground, for the capture plan where the scout misses a block.
constexpr double kOutlineStepM = 2.0;
BlockOutlines blockOutlines(const std::vector<BlockInfo>& info) {
  BlockOutlines out(info.size());
  for (size_t b = 0; b < info.size(); ++b) {
    const std::vector<glm::dvec2>& hull = info[b].hull;
    for (size_t i = 0; i < hull.size(); ++i) {
      const glm::dvec2 a = hull[i], c = hull[(i + 1) % hull.size()];
      const int n = std::max(1, static_cast<int>(std::ceil(glm::length(c - a) / kOutlineStepM)));
      for (int k = 0; k < n; ++k) {
        const glm::dvec2 p = a + (c - a) * (double(k) / n);
        out[b].emplace_back(p.x, p.y, info[b].lo.y);
      }
    }
  }
  return out;
}

// What the impostors of every cell share: the blocks, the options.
struct CellBake {
  const graph::StreetGraph& g;
  const std::vector<geo::MeshData>& block_meshes;
  const std::vector<BlockInfo>& info;
  const ImpostorOptions& opt;
  CapturePlanOptions popt;
  BlockOutlines outlines;
  double T = 0;  // the threshold angle, radians (Décoret 99 §4.2)
};

// One capture's blocks: a layer (D99 §4.2), or S97's single impostor, of one run.
struct CaptureJob {
  bool single;
  float run_from;
  std::vector<uint32_t> blocks;
  glm::dvec3 ends[2];  // the eye at the run's start and end, glTF axes
  glm::dvec3 eye_enu;  // the run's vantage point
};

// One cell's impostors as a worker makes them; committed in cell order.
struct CellImpostors {
  struct Layer {
    graph::ImpostorLayer il;  // its blob not yet in the package
    ImpostorRecord rec;
    std::vector<uint8_t> glb;
  };
  std::vector<Layer> layers;
  CellCounters counters;
};

// 2–4. One cell: per run (cellRuns), its layers and/or single impostor, each
// planned from the run's vantage point; every capture of the cell planned
// first, then sized to the cell's texel budget, then captured as textured
// depth meshes.
CellImpostors bakeCellImpostors(const CellBake& cb, CaptureRig& rig, uint32_t h, const std::vector<uint32_t>& far) {
  const graph::HalfEdge& e = cb.g.halfedges[h];
  const ImpostorOptions& opt = cb.opt;
  CellImpostors out;
  std::vector<CaptureJob> jobs;
  std::vector<std::vector<CaptureShot>> plans;
  for (const auto& [s0, s1] : cellRuns(cb.g, e, opt)) {
    const CellView view = cellView(cb.g, e, s0, s1, opt, rig);
    const glm::dvec3 start = render::enuToGltf(eyeAt(view.P, opt.ground));
    const glm::dvec3 end = render::enuToGltf(eyeAt(view.Q, opt.ground));
    std::vector<CaptureJob> run;
    if (opt.mode == ImpostorMode::Layered || opt.mode == ImpostorMode::Both)
      for (auto& blocks : layerBlocks(view, far, cb.info, opt, cb.T, out.counters))
        run.push_back({false, float(s0), blocks, {start, end}, view.eye_enu});
    if (opt.mode == ImpostorMode::Single || opt.mode == ImpostorMode::Both)
      run.push_back({true, float(s0), far, {start, end}, view.eye_enu});
    for (CaptureJob& j : run) {
      plans.push_back(
          planCaptures(rig, view.eye_enu, view.heading_deg, view.az_lo, view.az_hi, j.blocks, cb.popt, &cb.outlines));
      jobs.push_back(std::move(j));
    }
  }
  fitTexelBudget(plans, opt, cb.popt, out.counters);
  uint32_t layer_index = 0;
  for (size_t j = 0; j < jobs.size(); ++j) {
    if (plans[j].empty()) continue;
    CellImpostors::Layer l;
    l.rec.cell = h;
    l.rec.single = jobs[j].single;
    l.rec.layer = layer_index++;
    l.rec.run_from_m = jobs[j].run_from;
    l.rec.eye_enu = jobs[j].eye_enu;
    l.il.run_from_m = jobs[j].run_from;
    if (captureLayer(rig, plans[j], jobs[j].blocks, opt, cb.popt, jobs[j].ends, l.il, l.rec, l.glb))
      out.layers.push_back(std::move(l));
  }
  return out;
}

// A cell's impostors into the package and the result, and its counters.
void commitCell(uint32_t h, CellImpostors& c, package::PackageWriter& writer, ImpostorBakeResult& res) {
  for (CellImpostors::Layer& l : c.layers) {
    l.il.blob = writer.addBlob(std::move(l.glb));
    (l.rec.single ? res.tables.impostors[h].single : res.tables.impostors[h].layered).push_back(std::move(l.il));
    res.records.push_back(std::move(l.rec));
  }
  res.capped_cells += c.counters.capped_cells;
  res.capped_worst_px = std::max(res.capped_worst_px, c.counters.capped_worst_px);
  res.budget_cells += c.counters.budget_cells;
  res.budget_min_density = std::min(res.budget_min_density, c.counters.budget_min_density);
}

// The cell's potentially visible blocks that are not its local blocks.
std::vector<uint32_t> farBlocks(const CellBake& cb, uint32_t h, const graph::CellVisibility& vis) {
  std::vector<uint32_t> local(cb.g.local_blocks.begin(h), cb.g.local_blocks.end(h));
  std::vector<uint32_t> far;
  for (uint32_t b : vis.blocks)
    if (std::find(local.begin(), local.end(), b) == local.end() && !cb.block_meshes[b].empty()) far.push_back(b);
  return far;
}

// A shard's part of the bake: only its streets stay wanted (shard_plan.h).
void keepShard(const graph::StreetGraph& g, const ImpostorOptions& opt, std::vector<bool>& want,
               ImpostorBakeResult& res) {
  const ShardPlan plan = planShards(g, want, opt, opt.shard_count);
  res.shard_streets = plan.streets[opt.shard_index];
  res.shard_plan = plan.streets;
  res.shard_costs = plan.cost;
  std::vector<bool> mine(g.halfedges.size(), false);
  for (uint32_t h : res.shard_streets) mine[h] = mine[g.halfedges[h].twin] = true;
  for (size_t h = 0; h < want.size(); ++h) want[h] = want[h] && mine[h];
}

// Farthest a block can be from the eye and still be drawn: the far plane
// along the widest corner ray of any capture (spans up to 120 x 90 degrees
// put it at 1 / 0.447 of the far plane).
constexpr double kReachM = 3.0 * kViewDistanceM;

// The blocks a shard's rigs draw: those whose footprint box lies within
// kReachM of the box around its streets; the others are beyond every far
// plane, so the captures are the same without them.
std::vector<bool> blocksInReach(const graph::StreetGraph& g, const std::vector<BlockInfo>& info,
                                const std::vector<bool>& want) {
  glm::dvec2 lo(1e300), hi(-1e300);
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
    if (!want[h]) continue;
    const graph::HalfEdge& e = g.halfedges[h];
    for (uint32_t i = 0; i < e.pts_count; ++i) lo = glm::min(lo, g.points[e.pts_begin + i]), hi = glm::max(hi, g.points[e.pts_begin + i]);
  }
  std::vector<bool> draw(info.size(), false);
  for (size_t b = 0; b < info.size(); ++b) {
    const glm::dvec2 blo(info[b].lo.x, -info[b].hi.z), bhi(info[b].hi.x, -info[b].lo.z);  // glTF z is south
    const glm::dvec2 gap = glm::max(glm::max(blo - hi, lo - bhi), glm::dvec2(0.0));
    draw[b] = glm::length(gap) <= kReachM;
  }
  return draw;
}

}  // namespace

ImpostorBakeResult bakeImpostors(const graph::StreetGraph& g, const std::vector<geo::MeshData>& block_meshes,
                                 const ImpostorOptions& opt, package::PackageWriter& writer, const Progress& progress) {
  ImpostorBakeResult res;
  const size_t H = g.halfedges.size();
  CapturePlanOptions popt;
  popt.texture_max = opt.texture_max;
  popt.gutter_px = kAtlasGutter;
  popt.max_span_deg = opt.max_span_deg;
  popt.display_ppr = 0.5 * opt.display_height / std::tan(glm::radians(opt.display_fov_y_deg) * 0.5);
  const std::vector<BlockInfo> info = blockInfo(block_meshes);
  std::vector<bool> want(H, opt.only_cells.empty());
  for (uint32_t c : opt.only_cells)
    if (c < H) want[c] = true;
  std::vector<bool> draw;
  if (opt.shard_count > 0) {
    keepShard(g, opt, want, res);
    draw = blocksInReach(g, info, want);
    res.shard_blocks_drawn = size_t(std::count(draw.begin(), draw.end(), true));
  }
  // The largest view a rig draws: a capture, an item buffer or a scout view.
  const int side = std::max({opt.texture_max, opt.item_resolution, popt.scout_height});
  RigPool pool(block_meshes, side, opt.jobs, draw);
  BLVD_LOG_INFO("impostors: capturing on %s, %d workers", pool.backendName(), pool.workers());

  auto t0 = Clock::now();
  bakeVisibility(g, pool, opt, want, res, progress);
  res.pvs_seconds = since(t0);
  BLVD_LOG_INFO("impostors: %zu item-buffer samples in %.1f s", res.samples, res.pvs_seconds);

  t0 = Clock::now();
  res.tables.impostors.assign(H, {});
  res.tables.threshold_px = static_cast<float>(opt.threshold_px);
  res.tables.display_fov_y_deg = static_cast<float>(opt.display_fov_y_deg);
  res.tables.display_width = static_cast<uint16_t>(opt.display_width);
  res.tables.display_height = static_cast<uint16_t>(opt.display_height);
  if (opt.mode == ImpostorMode::None) return res;
  CellBake cb{g, block_meshes, info, opt, popt, blockOutlines(info), 0};
  cb.T = pixelsToRadians(opt.threshold_px, opt.display_width, displayFovX(opt));
  std::vector<uint32_t> cells;  // wanted cells with far blocks, in order
  std::vector<std::vector<uint32_t>> far(H);
  for (uint32_t h = 0; h < H; ++h)
    if (want[h] && !(far[h] = farBlocks(cb, h, res.tables.visibility[h])).empty()) cells.push_back(h);
  // Batches of a few cells per worker: their blobs wait in memory until
  // committed in cell order, so the package is the same with any workers.
  const size_t batch = size_t(4 * pool.workers());
  std::vector<CellImpostors> made(batch);
  size_t committed = 0;
  pool.runInBatches(
      cells.size(), batch,
      [&](CaptureRig& rig, size_t i) { made[i % batch] = bakeCellImpostors(cb, rig, cells[i], far[cells[i]]); },
      [&](size_t done) {
        for (; committed < done; ++committed) commitCell(cells[committed], made[committed % batch], writer, res);
        if (progress) progress("impostors (capture + depth mesh)", double(done), double(cells.size()));
      });
  res.impostor_seconds = since(t0);
  BLVD_LOG_INFO("impostors: %zu meshes in %.1f s", res.records.size(), res.impostor_seconds);
  return res;
}

}  // namespace blvd::bake
