// How a bake's streets are cut into shards (bake/shard.h): ordered along a
// Hilbert curve over the city's bounds, as PMTiles orders its tiles, so that
// a shard's streets lie near each other and its captures see the same
// blocks; then cut into contiguous ranges of about equal estimated cost.
//
// A street is the unit (both directions of it): its two cells share their
// item-buffer samples (visibility_bake.h), so they are baked together.
#pragma once
#include <cstdint>
#include <vector>

#include "graph/street_graph.h"

namespace blvd::bake {

struct ImpostorOptions;

// Index of cell (x, y) along the Hilbert curve that fills a grid of
// side × side cells (side a power of two; x, y < side). Consecutive indices
// are neighbouring cells.
uint64_t hilbertIndex(uint32_t side, uint32_t x, uint32_t y);

struct ShardPlan {
  // Per shard, its streets (each by its lower half-edge), ascending.
  std::vector<std::vector<uint32_t>> streets;
  // Per shard, the estimated cost of its streets (streetCost's units).
  std::vector<double> cost;
};

// The estimated cost of baking street h (its lower half-edge) whose
// directions `want` says are baked: its interior item-buffer samples, its
// share of the junction samples, and its impostor runs times the captures a
// run takes (bake/impostor_bake.h), in item-buffer samples.
double streetCost(const graph::StreetGraph& g, uint32_t h, bool want_h, bool want_twin,
                  const ImpostorOptions& opt);

// Cuts the streets with a wanted direction (want: per half-edge) into
// `count` shards (count >= 1): Hilbert order of each street's midpoint,
// then shard k takes the streets whose cost midpoint lies in the k-th
// count-th of the total. A shard may be empty (more shards than streets).
ShardPlan planShards(const graph::StreetGraph& g, const std::vector<bool>& want, const ImpostorOptions& opt,
                     uint32_t count);

}  // namespace blvd::bake
