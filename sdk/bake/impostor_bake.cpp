#include "bake/impostor_bake.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "bake/capture.h"
#include "bake/depth_mesh.h"
#include "bake/layers.h"
#include "bake/texture_encode.h"
#include "core/log.h"
#include "package/glb.h"

namespace blvd::bake {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr double kEyeHeight = 1.5;

// Sparse per-sample pixel counts: (block, pixels).
using Counts = std::vector<std::pair<uint32_t, uint32_t>>;

glm::dvec2 pointAt(const graph::StreetGraph& g, const graph::HalfEdge& e, double s) {
  const glm::dvec2* p = &g.points[e.pts_begin];
  for (uint32_t i = 1; i < e.pts_count; ++i) {
    const double l = glm::length(p[i] - p[i - 1]);
    if (s <= l || i + 1 == e.pts_count) return l > 0 ? p[i - 1] + (p[i] - p[i - 1]) * std::min(1.0, s / l) : p[i];
    s -= l;
  }
  return p[e.pts_count - 1];
}

// D99 §5.3: "full 360° views ... recording the visible objects into an item
// buffer"; Marvie's ACH: the same buffers in 6 directions (4 around, up, down).
Counts sampleAt(CaptureRig& rig, glm::dvec2 p, int res, std::vector<uint32_t>& scratch) {
  std::fill(scratch.begin(), scratch.end(), 0u);
  render::Camera cam;
  cam.eye_enu = {p.x, p.y, kEyeHeight};
  cam.fov_y_deg = 90.0;
  cam.width = cam.height = res;
  cam.near_m = 0.3;
  cam.far_m = 6000.0;
  static const double dirs[6][2] = {{0, 0}, {90, 0}, {180, 0}, {270, 0}, {0, 89.9}, {0, -89.9}};
  for (const auto& d : dirs) {
    cam.heading_deg = d[0];
    cam.pitch_deg = d[1];
    rig.itemBuffer(cam, scratch);
  }
  Counts c;
  for (uint32_t b = 0; b < scratch.size(); ++b)
    if (scratch[b]) c.emplace_back(b, scratch[b]);
  return c;
}

struct BlockInfo {
  std::vector<glm::dvec2> hull;  // ground footprint (east, north)
  glm::dvec3 lo{0}, hi{0};       // glTF box
  double top = 0;
};

}  // namespace

double displayFovX(const ImpostorOptions& opt) {
  const double ty = std::tan(glm::radians(opt.display_fov_y_deg) * 0.5);
  return glm::degrees(2.0 * std::atan(ty * opt.display_width / opt.display_height));
}

ImpostorBakeResult bakeImpostors(const graph::StreetGraph& g, const std::vector<geo::MeshData>& block_meshes,
                                 const ImpostorOptions& opt, package::PackageWriter& writer,
                                 const std::function<void(const char*, double, double)>& progress) {
  ImpostorBakeResult res;
  const size_t H = g.halfedges.size(), B = block_meshes.size();
  const double fov_x_display = displayFovX(opt);
  const double ppr = 0.5 * opt.display_height / std::tan(glm::radians(opt.display_fov_y_deg) * 0.5);
  // Largest capture the cell frustum rule can ask for.
  CaptureRig rig(block_meshes, std::max(opt.texture_max, opt.item_resolution),
                 std::max(opt.texture_max, opt.item_resolution));
  BLVD_LOG_INFO("impostors: capturing on %s", rig.backendName());

  std::vector<BlockInfo> info(B);
  for (size_t b = 0; b < B; ++b) {
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

  // 1. PVS + ACH from item buffers at samples along every street.
  auto t0 = Clock::now();
  std::vector<bool> want(H, opt.only_cells.empty());
  for (uint32_t c : opt.only_cells)
    if (c < H) want[c] = true;
  res.tables.visibility.assign(H, {});
  std::unordered_map<uint32_t, Counts> vertex_samples;  // shared by every street at a junction
  std::vector<uint32_t> scratch(B);
  size_t done = 0;
  for (uint32_t h = 0; h < H; ++h) {
    const graph::HalfEdge& e = g.halfedges[h];
    if (h > e.twin) continue;  // both directions share the samples
    if (!want[h] && !want[e.twin]) continue;
    std::vector<const Counts*> samples;
    std::vector<Counts> interior;
    for (uint32_t v : {e.origin, g.endVertex(h)}) {
      auto it = vertex_samples.find(v);
      if (it == vertex_samples.end()) {
        it = vertex_samples.emplace(v, sampleAt(rig, g.vertices[v].p, opt.item_resolution, scratch)).first;
        ++res.samples;
      }
      samples.push_back(&it->second);
    }
    // Marvie's ACH: 8 positions along the cell (its two ends, shared with
    // the neighbouring streets, and 6 between) × 6 directions.
    const int n_in = std::max(0, opt.positions_per_cell - 2);
    interior.reserve(n_in);
    for (int i = 1; i <= n_in; ++i) {
      const double s = e.length * i / (n_in + 1);
      interior.push_back(sampleAt(rig, pointAt(g, e, s), opt.item_resolution, scratch));
      ++res.samples;
    }
    for (const Counts& c : interior) samples.push_back(&c);
    std::map<uint32_t, double> acc;
    for (const Counts* c : samples)
      for (const auto& [b, px] : *c) acc[b] += px;
    for (uint32_t l = g.local_blocks.offsets[h]; l < g.local_blocks.offsets[h + 1]; ++l)
      acc.emplace(g.local_blocks.items[l], 0.0);
    const double norm = 1.0 / (double(samples.size()) * 6.0 * opt.item_resolution * opt.item_resolution);
    graph::CellVisibility vis;
    for (const auto& [b, px] : acc) {
      vis.blocks.push_back(b);
      vis.ach.push_back(static_cast<float>(px * norm));
    }
    res.tables.visibility[h] = vis;
    res.tables.visibility[e.twin] = vis;
    if (progress) progress("visibility (item buffers)", double(++done), double(H / 2));
  }
  res.pvs_seconds = since(t0);
  BLVD_LOG_INFO("impostors: %zu item-buffer samples in %.1f s", res.samples, res.pvs_seconds);

  // 2–4. Per cell: frustum, layers, textured depth meshes.
  t0 = Clock::now();
  res.tables.impostors.assign(H, {});
  res.tables.threshold_px = static_cast<float>(opt.threshold_px);
  res.tables.display_fov_y_deg = static_cast<float>(opt.display_fov_y_deg);
  res.tables.display_width = static_cast<uint16_t>(opt.display_width);
  res.tables.display_height = static_cast<uint16_t>(opt.display_height);
  if (opt.mode == ImpostorMode::None) return res;
  const double T = pixelsToRadians(opt.threshold_px, opt.display_width, fov_x_display);
  package::GlbOptions glb_opt;
  glb_opt.normal_bits = 0;
  done = 0;
  size_t todo = 0;
  for (uint32_t h = 0; h < H; ++h) todo += want[h];
  for (uint32_t h = 0; h < H; ++h) {
    if (!want[h]) continue;
    const graph::HalfEdge& e = g.halfedges[h];
    std::vector<uint32_t> local(g.local_blocks.begin(h), g.local_blocks.end(h));
    std::vector<uint32_t> far;
    for (uint32_t b : res.tables.visibility[h].blocks)
      if (std::find(local.begin(), local.end(), b) == local.end() && !block_meshes[b].empty()) far.push_back(b);
    if (progress) progress("impostors (capture + depth mesh)", double(++done), double(todo));
    if (far.empty()) continue;

    // Vantage point and frustum (K06 §4.4.4, S97 §4.2). The camera sits at the
    // cell's start looking along its chord, pulled back so a viewer anywhere
    // across the carriageway stays inside the captured cone. Its horizontal
    // field covers the display's plus twice the largest heading change along
    // the cell, plus 10° of slack; its vertical field and pitch span every far
    // block's top and bottom as seen from the eye, so tall far geometry is
    // never clipped.
    const glm::dvec2 P = g.points[e.pts_begin], Q = g.points[e.pts_begin + e.pts_count - 1];
    glm::dvec2 fwd = Q - P;
    if (glm::length(fwd) < 1.0) fwd = g.points[e.pts_begin + 1] - P;
    fwd = glm::normalize(fwd);
    double turn = 0;
    for (uint32_t i = 1; i < e.pts_count; ++i) {
      const glm::dvec2 d = g.points[e.pts_begin + i] - g.points[e.pts_begin + i - 1];
      if (glm::length(d) < 1e-6) continue;
      turn = std::max(turn, std::acos(std::clamp(glm::dot(glm::normalize(d), fwd), -1.0, 1.0)));
    }
    const double fov_x = std::min(140.0, fov_x_display + 2.0 * glm::degrees(turn) + 10.0);
    const glm::dvec2 eye2 = P - fwd * opt.pullback_m;
    const glm::dvec3 eye_gl(eye2.x, kEyeHeight, -eye2.y);
    double el_lo = 0, el_hi = 0;
    for (uint32_t b : far) {
      for (int k = 0; k < 8; ++k) {
        const glm::dvec3 c((k & 1) ? info[b].hi.x : info[b].lo.x, (k & 2) ? info[b].hi.y : info[b].lo.y,
                           (k & 4) ? info[b].hi.z : info[b].lo.z);
        const glm::dvec2 rel(c.x - eye_gl.x, -c.z - eye2.y);
        const double ahead = glm::dot(rel, fwd);
        if (ahead < 1.0) continue;
        const double el = glm::degrees(std::atan2(c.y - eye_gl.y, glm::length(rel)));
        el_lo = std::min(el_lo, el);
        el_hi = std::max(el_hi, el);
      }
    }
    el_lo = std::max(el_lo - 2.0, -50.0);
    el_hi = std::min(el_hi + 2.0, 70.0);
    render::Camera cam;
    cam.eye_enu = {eye2.x, eye2.y, kEyeHeight};
    cam.heading_deg = glm::degrees(std::atan2(fwd.x, fwd.y));
    cam.pitch_deg = 0.5 * (el_hi + el_lo);
    cam.fov_y_deg = std::max(10.0, el_hi - el_lo);
    cam.near_m = 0.5;
    cam.far_m = 6000.0;
    const double tx = std::tan(glm::radians(fov_x) * 0.5), ty = std::tan(glm::radians(cam.fov_y_deg) * 0.5);
    double W = 2 * tx * ppr, Hh = 2 * ty * ppr;
    const double scale = std::min(1.0, opt.texture_max / std::max(W, Hh));
    cam.width = std::max(16, static_cast<int>(W * scale) / 4 * 4);
    cam.height = std::max(16, static_cast<int>(Hh * scale) / 4 * 4);

    // Layers (D99 §4.2), or one layer for S97's single impostor.
    std::vector<LayerObject> objs;
    for (uint32_t b : far)
      objs.push_back({b, info[b].hull, info[b].top >= opt.landmark_height_m ? opt.landmark_scale : 1.0});
    std::vector<std::pair<bool, std::vector<uint32_t>>> jobs;  // (single?, blocks)
    if (opt.mode == ImpostorMode::Layered || opt.mode == ImpostorMode::Both) {
      LayerAssignment la = assignLayers(P, Q, objs, T);
      if (la.layers.size() > size_t(opt.max_layers)) {
        // Each layer costs a texture and a capture; past max_layers the
        // extra layers merge where they add the least parallax error, and
        // the report says how much that was.
        ++res.capped_cells;
        res.capped_worst_px = std::max(res.capped_worst_px, capLayers(la, objs.size(), opt.max_layers) / T * opt.threshold_px);
      }
      for (const auto& layer : la.layers) {
        std::vector<uint32_t> blocks;
        for (uint32_t i : layer) blocks.push_back(far[i]);
        std::sort(blocks.begin(), blocks.end());
        jobs.emplace_back(false, blocks);
      }
    }
    if (opt.mode == ImpostorMode::Single || opt.mode == ImpostorMode::Both) jobs.emplace_back(true, far);

    uint32_t layer_index = 0;
    for (const auto& [single, blocks] : jobs) {
      const auto tl = Clock::now();
      CaptureImage img;
      PinholeCamera pin;
      rig.capture(cam, blocks, img, pin);
      DepthMeshOptions dopt;
      dopt.grid_spacing_px = opt.grid_px;
      geo::MeshData mesh;
      DepthMeshStats st;
      std::string why;
      if (!buildDepthMesh(img, pin, dopt, mesh, &st, why)) {
        BLVD_LOG_DEBUG("cell %u layer %u: no impostor (%s)", h, layer_index, why.c_str());
        continue;
      }
      mesh.image = encodeTextureJpeg(img, opt.jpeg_quality);
      mesh.image_mime = "image/jpeg";
      package::GlbMeshCounts counts;
      std::vector<uint8_t> glb = package::encodeGlb(mesh, glb_opt, &counts);
      if (counts.triangles == 0) {
        BLVD_LOG_DEBUG("cell %u layer %u: no impostor (Draco kept no triangle)", h, layer_index);
        continue;
      }
      graph::ImpostorLayer il;
      il.triangles = counts.triangles;
      il.vertices = counts.vertices;
      il.texture_width = static_cast<uint16_t>(img.width);
      il.texture_height = static_cast<uint16_t>(img.height);
      il.blocks = blocks;
      ImpostorRecord rec;
      rec.cell = h;
      rec.single = single;
      rec.layer = layer_index++;
      rec.triangles = il.triangles;
      rec.bytes = static_cast<uint32_t>(glb.size());
      rec.blocks = static_cast<uint32_t>(blocks.size());
      rec.texture_width = img.width;
      rec.texture_height = img.height;
      rec.jpeg = mesh.image;
      il.blob = writer.addBlob(std::move(glb));
      rec.seconds = since(tl);
      (single ? res.tables.impostors[h].single : res.tables.impostors[h].layered).push_back(std::move(il));
      res.records.push_back(std::move(rec));
    }
  }
  res.impostor_seconds = since(t0);
  BLVD_LOG_INFO("impostors: %zu meshes in %.1f s", res.records.size(), res.impostor_seconds);
  return res;
}

}  // namespace blvd::bake
