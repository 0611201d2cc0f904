#include "bake/lod_chain.h"

#include <meshoptimizer.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/status.h"
#include "graph/block_table.h"

namespace blvd::bake {
namespace {

// The mesh made of `indices` (into full's vertices), with only the vertices
// they use, in order of first use.
geo::MeshData compact(const geo::MeshData& full, const std::vector<uint32_t>& indices) {
  geo::MeshData m;
  std::vector<uint32_t> remap(full.vertexCount(), 0xffffffffu);
  m.indices.reserve(indices.size());
  for (uint32_t i : indices) {
    if (remap[i] == 0xffffffffu) {
      remap[i] = static_cast<uint32_t>(m.vertexCount());
      m.positions.insert(m.positions.end(), &full.positions[i * 3], &full.positions[i * 3] + 3);
      if (!full.normals.empty()) m.normals.insert(m.normals.end(), &full.normals[i * 3], &full.normals[i * 3] + 3);
      if (!full.colors.empty()) m.colors.insert(m.colors.end(), &full.colors[i * 4], &full.colors[i * 4] + 4);
      if (!full.texcoords.empty())
        m.texcoords.insert(m.texcoords.end(), &full.texcoords[i * 2], &full.texcoords[i * 2] + 2);
    }
    m.indices.push_back(remap[i]);
  }
  return m;
}

}  // namespace

void checkLodOptions(const LodOptions& opt) {
  if (opt.ratios.size() > graph::kMaxBlockLods - 1)
    throw core::Error(core::Status::InvalidArg, "LOD ratios: at most " + std::to_string(graph::kMaxBlockLods - 1) +
                                                    " levels below the full mesh, got " +
                                                    std::to_string(opt.ratios.size()));
  for (size_t i = 0; i < opt.ratios.size(); ++i) {
    const double r = opt.ratios[i];
    if (!(r > 0 && r < 1) || (i > 0 && r >= opt.ratios[i - 1]))
      throw core::Error(core::Status::InvalidArg, "LOD ratio " + std::to_string(r) +
                                                      ": ratios must be in (0, 1) and strictly decreasing");
  }
}

std::vector<LodLevel> buildLodChain(const geo::MeshData& full, const LodOptions& opt) {
  checkLodOptions(opt);
  std::vector<LodLevel> levels(1);
  levels[0].mesh = full;
  if (!opt.enabled || full.indices.empty()) return levels;

  const size_t n = full.vertexCount();
  const float* pos = full.positions.data();
  const double scale = meshopt_simplifyScale(pos, n, 12);
  const size_t tri0 = full.triangleCount();
  // A level must drop at least this share of its predecessor's triangles to
  // be worth its memory and a decode.
  constexpr double kMinStep = 0.9;
  // The simplifiers stop at the target or when they cannot go on; "reached"
  // allows 5 % (at least one triangle) of slack for the last collapses.
  auto reached = [](size_t tris, size_t target) { return tris <= target + std::max<size_t>(1, target / 20); };

  std::vector<uint32_t> prev = full.indices, out(full.indices.size());
  double prev_error = 0;
  for (double ratio : opt.ratios) {
    const size_t target_tris = std::max<size_t>(1, static_cast<size_t>(std::floor(ratio * double(tri0))));
    if (prev.size() / 3 <= target_tris) continue;  // the level before already got there
    const size_t target = target_tris * 3;
    float err = 0;
    // No error cap: the budget controller picks levels by triangle count and
    // the error is recorded, so the simplifier may go as far as the target.
    const float no_cap = std::numeric_limits<float>::max();
    size_t got = meshopt_simplify(out.data(), prev.data(), prev.size(), pos, n, 12, target, no_cap,
                                  meshopt_SimplifyLockBorder, &err);
    LodMethod method = LodMethod::Simplify;
    if (!reached(got / 3, target_tris)) {
      got = meshopt_simplify(out.data(), prev.data(), prev.size(), pos, n, 12, target, no_cap, 0, &err);
      method = LodMethod::SimplifyUnlocked;
    }
    if (!reached(got / 3, target_tris)) {
      got = meshopt_simplifySloppy(out.data(), prev.data(), prev.size(), pos, n, 12, target, no_cap, &err);
      method = LodMethod::Sloppy;
    }
    if (got == 0 || double(got) > kMinStep * double(prev.size())) continue;
    std::vector<uint32_t> indices(out.begin(), out.begin() + static_cast<ptrdiff_t>(got));
    LodLevel level;
    level.mesh = compact(full, indices);
    level.error_m = prev_error + double(err) * scale;
    level.method = method;
    prev_error = level.error_m;
    prev = std::move(indices);
    levels.push_back(std::move(level));
  }
  return levels;
}

const char* lodMethodName(LodMethod m) {
  switch (m) {
    case LodMethod::Full: return "full";
    case LodMethod::Simplify: return "simplify";
    case LodMethod::SimplifyUnlocked: return "simplify-unlocked";
    case LodMethod::Sloppy: return "sloppy";
  }
  return "full";
}

}  // namespace blvd::bake
