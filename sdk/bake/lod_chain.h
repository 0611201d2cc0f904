// A block's chain of levels of detail (DESIGN "Per block: LOD chain"; Marvie
// seed 004: each object offers levels whose polygon counts the frame budget
// chooses between). Level 0 is the full mesh; each further level aims at a
// share of level 0's triangles, simplified with meshoptimizer.
// docs/decisions/0004-lod-chain.md says why it is built this way.
#pragma once
#include <vector>

#include "geo/mesh.h"

namespace blvd::bake {

struct LodOptions {
  bool enabled = true;  // false: level 0 only (--lod none)
  // Target triangle shares of level 0, strictly decreasing, in (0, 1); at most
  // three (graph::kMaxBlockLods - 1).
  std::vector<double> ratios = {0.5, 0.25, 0.1};
};

enum class LodMethod { Full, Simplify, SimplifyUnlocked, Sloppy };

struct LodLevel {
  geo::MeshData mesh;     // compact: only the vertices its triangles use
  double error_m = 0;     // simplification error against level 0, metres (0 for level 0)
  LodMethod method = LodMethod::Full;
};

// Throws core::Error(InvalidArg) naming the bad ratio.
void checkLodOptions(const LodOptions& opt);

// Level 0 is `full` itself. Each further level simplifies the one before it
// (so errors add up and never decrease) towards ratio × level 0's triangles:
// meshopt_simplify with the topological border locked first (block borders are
// street edges shared with the neighbouring block, so they stay where they are
// and blocks at different levels still meet), then unlocked, then
// meshopt_simplifySloppy when neither reaches the target. A level is kept only
// when it has at most 90 % of the triangles of the level before it (and at
// least one), so 1..1+ratios.size() levels come back. Error in metres:
// meshopt's relative error × meshopt_simplifyScale(level 0's positions).
// Deterministic.
std::vector<LodLevel> buildLodChain(const geo::MeshData& full, const LodOptions& opt);

const char* lodMethodName(LodMethod m);

}  // namespace blvd::bake
