// Step 1 of the impostor bake: each street's potentially visible set and
// coverage hints from item buffers (Décoret 99 §5.3: "full 360° views ...
// recording the visible objects into an item buffer"; Marvie's ACH: the same
// buffers in 6 directions, 4 around, up and down, at 8 positions along the
// street). Samples at junctions are shared by every street ending there, and
// both directions of a street share its samples.
#pragma once
#include <cstddef>
#include <functional>
#include <vector>

#include "bake/impostor_bake.h"
#include "bake/rig_pool.h"

namespace blvd::bake {

// Fills res.tables.visibility (every half-edge; empty where neither
// direction is wanted) and res.samples, the item-buffer samples taken. The
// samples run on the pool's workers; the result does not depend on how many.
void bakeVisibility(const graph::StreetGraph& g, RigPool& pool, const ImpostorOptions& opt,
                    const std::vector<bool>& want, ImpostorBakeResult& res,
                    const std::function<void(const char*, double, double)>& progress);

}  // namespace blvd::bake
