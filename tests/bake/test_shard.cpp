// Shards of a bake: the Hilbert order, the cost-balanced plan on a grid
// city, the --shard spec (explicit, Slurm, Kubernetes) and the manifest.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>

#include <glm/common.hpp>

#include "../graph/graph_test_util.h"
#include "bake/impostor_bake.h"
#include "bake/shard.h"
#include "bake/shard_plan.h"
#include "bake/street_map.h"
#include "core/status.h"

using namespace blvd;

TEST(Hilbert, VisitsEveryCellOnceStepByStep) {
  const uint32_t side = 16;
  std::map<uint64_t, std::pair<int, int>> at;
  for (uint32_t y = 0; y < side; ++y)
    for (uint32_t x = 0; x < side; ++x) at[bake::hilbertIndex(side, x, y)] = {int(x), int(y)};
  ASSERT_EQ(at.size(), size_t(side) * side);
  EXPECT_EQ(at.begin()->first, 0u);
  EXPECT_EQ(at.rbegin()->first, uint64_t(side) * side - 1);
  for (auto it = std::next(at.begin()); it != at.end(); ++it) {
    const auto [x0, y0] = std::prev(it)->second;
    const auto [x1, y1] = it->second;
    EXPECT_EQ(std::abs(x1 - x0) + std::abs(y1 - y0), 1) << "step to index " << it->first;
  }
}

namespace {
// An n x n lattice of two-way streets, `spacing` metres apart.
std::vector<bake::OsmStreet> lattice(int n, double spacing) {
  std::vector<bake::OsmStreet> s;
  for (int j = 0; j < n; ++j) {
    std::vector<int64_t> row, col;
    std::vector<glm::dvec2> prow, pcol;
    for (int i = 0; i < n; ++i) {
      row.push_back(1000 + i * 100 + j), prow.emplace_back(i * spacing, j * spacing);
      col.push_back(1000 + j * 100 + i), pcol.emplace_back(j * spacing, i * spacing);
    }
    s.push_back(test::street(10 + j, row, prow));
    s.push_back(test::street(100 + j, col, pcol));
  }
  return s;
}
}  // namespace

TEST(ShardPlan, EveryStreetInOneShardBalancedAndCompact) {
  bake::StreetMap map(lattice(9, 80.0));
  const graph::StreetGraph& g = map.graph();
  bake::ImpostorOptions opt;
  opt.mode = bake::ImpostorMode::Both;
  const std::vector<bool> want(g.halfedges.size(), true);
  const uint32_t n = 4;
  const bake::ShardPlan plan = bake::planShards(g, want, opt, n);
  ASSERT_EQ(plan.streets.size(), n);
  std::set<uint32_t> seen;
  double total = 0, worst = 0, biggest = 0;
  for (uint32_t k = 0; k < n; ++k) {
    EXPECT_TRUE(std::is_sorted(plan.streets[k].begin(), plan.streets[k].end()));
    for (uint32_t h : plan.streets[k]) {
      EXPECT_LT(h, g.halfedges[h].twin) << "a street is named by its lower half-edge";
      EXPECT_TRUE(seen.insert(h).second) << "street " << h << " in two shards";
      biggest = std::max(biggest, bake::streetCost(g, h, true, true, opt));
    }
    total += plan.cost[k];
    worst = std::max(worst, plan.cost[k]);
  }
  EXPECT_EQ(seen.size(), g.halfedges.size() / 2);
  // Cut at cost midpoints: no shard exceeds its share by more than one street.
  EXPECT_LE(worst, total / n + biggest);
  // Hilbert ranges are compact: each shard's streets lie in about a quarter of
  // the city (a quadrant of the 640 m square), not strewn across it.
  for (uint32_t k = 0; k < n; ++k) {
    glm::dvec2 lo(1e9), hi(-1e9);
    for (uint32_t h : plan.streets[k])
      for (uint32_t i = 0; i < g.halfedges[h].pts_count; ++i)
        lo = glm::min(lo, g.points[g.halfedges[h].pts_begin + i]), hi = glm::max(hi, g.points[g.halfedges[h].pts_begin + i]);
    EXPECT_LE((hi.x - lo.x) * (hi.y - lo.y), 0.5 * 640.0 * 640.0) << "shard " << k;
  }
}

TEST(ShardPlan, OnlyWantedStreetsAndEmptyShardsWhenThereAreFew) {
  bake::StreetMap map(lattice(3, 100.0));
  const graph::StreetGraph& g = map.graph();
  std::vector<bool> want(g.halfedges.size(), false);
  want[g.halfedges[0].twin] = true;  // one direction of one street
  const bake::ShardPlan plan = bake::planShards(g, want, bake::ImpostorOptions{}, 3);
  size_t streets = 0;
  for (const auto& s : plan.streets) streets += s.size();
  EXPECT_EQ(streets, 1u);
  EXPECT_EQ(std::count_if(plan.streets.begin(), plan.streets.end(), [](const auto& s) { return s.empty(); }), 2);
}

namespace {
std::map<std::string, std::string> g_env;
const char* fakeEnv(const char* k) {
  const auto it = g_env.find(k);
  return it == g_env.end() ? nullptr : it->second.c_str();
}
std::string specError(const std::string& spec, uint32_t shards) {
  try {
    bake::parseShardSpec(spec, shards, fakeEnv);
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), core::Status::InvalidArg);
    return e.what();
  }
  return "(accepted)";
}
}  // namespace

TEST(ShardSpec, ExplicitSlurmAndKubernetes) {
  g_env.clear();
  bake::ShardSpec s = bake::parseShardSpec("2/4", 0, fakeEnv);
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 4u);
  s = bake::parseShardSpec("1", 3, fakeEnv);
  EXPECT_EQ(s.index, 1u);
  EXPECT_EQ(s.count, 3u);
  g_env = {{"SLURM_ARRAY_TASK_ID", "3"}, {"SLURM_ARRAY_TASK_COUNT", "4"}};
  s = bake::parseShardSpec("env", 0, fakeEnv);
  EXPECT_EQ(s.index, 3u);
  EXPECT_EQ(s.count, 4u);
  // A resubmitted task runs in an array of one: --shards keeps the bake's count.
  g_env = {{"SLURM_ARRAY_TASK_ID", "2"}, {"SLURM_ARRAY_TASK_COUNT", "1"}};
  s = bake::parseShardSpec("env", 4, fakeEnv);
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 4u);
  g_env = {{"JOB_COMPLETION_INDEX", "5"}};
  s = bake::parseShardSpec("env", 8, fakeEnv);
  EXPECT_EQ(s.index, 5u);
  EXPECT_EQ(s.count, 8u);
}

TEST(ShardSpec, RefusesWhatCannotBeAShard) {
  g_env.clear();
  EXPECT_NE(specError("4/4", 0).find("index 4 is out of range for 4 shards"), std::string::npos);
  EXPECT_NE(specError("x/4", 0).find("'x' is not a whole number"), std::string::npos);
  EXPECT_NE(specError("-1/4", 0).find("not a whole number"), std::string::npos);
  EXPECT_NE(specError("0/0", 0).find("at least 1"), std::string::npos);
  EXPECT_NE(specError("2", 0).find("give the number of shards"), std::string::npos);
  EXPECT_NE(specError("1/4", 3).find("disagree"), std::string::npos);
  EXPECT_NE(specError("env", 4).find("neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX"), std::string::npos);
  g_env = {{"JOB_COMPLETION_INDEX", "1"}};
  EXPECT_NE(specError("env", 0).find("--shards N"), std::string::npos);
  g_env = {{"SLURM_ARRAY_TASK_ID", "7"}, {"SLURM_ARRAY_TASK_COUNT", "4"}};
  EXPECT_NE(specError("env", 0).find("index 7 is out of range"), std::string::npos);
}

TEST(ShardManifest, RoundTripsAndNamesWhatIsWrong) {
  bake::ShardManifest m;
  m.index = 1, m.count = 3;
  m.input_name = "city.osm.pbf", m.input_bytes = 123, m.input_sha256 = std::string(64, 'a');
  m.options_sha256 = std::string(64, 'b'), m.generator = "blvd bake 0.1.0", m.block_blobs = 9;
  m.streets = {2, 4, 8}, m.plan_streets = 10, m.plan_sha256 = std::string(64, 'c'), m.plan_costs = {1.5, 2.5, 3};
  m.blocks_drawn = 7, m.seconds = 1.25, m.cpu_seconds = 2.5;
  const bake::ShardManifest r = bake::parseManifest(bake::manifestJson(m), "s1");
  EXPECT_EQ(bake::manifestJson(r), bake::manifestJson(m));

  auto error = [](const std::string& json) -> std::string {
    try {
      bake::parseManifest(json, "shard.blvdshard");
    } catch (const core::Error& e) {
      EXPECT_EQ(e.status(), core::Status::Corrupt);
      return e.what();
    }
    return "(accepted)";
  };
  std::string j = bake::manifestJson(m);
  EXPECT_NE(error("not json").find("shard.blvdshard: shard manifest: not a JSON object"), std::string::npos);
  EXPECT_NE(error(R"({"format":"x"})").find("format is not blvd-shard"), std::string::npos);
  std::string no_streets = j;
  no_streets.replace(no_streets.find("\"streets\""), 9, "\"street_\"");
  EXPECT_NE(error(no_streets).find("streets"), std::string::npos);
  bake::ShardManifest unsorted = m;
  unsorted.streets = {4, 2};
  EXPECT_NE(error(bake::manifestJson(unsorted)).find("ascending"), std::string::npos);
  bake::ShardManifest outside = m;
  outside.index = 3;
  EXPECT_NE(error(bake::manifestJson(outside)).find("shard 3 of 3"), std::string::npos);
}

TEST(ShardManifest, PlanDigestTellsPlansApart) {
  EXPECT_EQ(bake::planDigest({{1, 2}, {3}}), bake::planDigest({{1, 2}, {3}}));
  EXPECT_NE(bake::planDigest({{1, 2}, {3}}), bake::planDigest({{1}, {2, 3}}));
  EXPECT_NE(bake::planDigest({{1, 2}, {3}}), bake::planDigest({{1, 2, 3}, {}}));
}
