#include <gtest/gtest.h>

#include "bake/street_map.h"
#include "core/status.h"
#include "graph/block_table.h"
#include "graph_test_util.h"

using namespace blvd;
using blvd::test::street;

namespace {
graph::StreetGraph smallGraph() {
  std::vector<bake::OsmStreet> s = {
      street(1, {1, 9, 2}, {{-100, 0}, {0, 0}, {100, 0}}),
      street(2, {3, 9, 4}, {{0, -100}, {0, 0}, {0, 100}}),
      street(3, {1, 3}, {{-100, 0}, {0, -100}}),
  };
  bake::StreetMap map(s);
  return map.graph();
}
}  // namespace

TEST(GraphSerialize, RoundTrip) {
  const graph::StreetGraph g = smallGraph();
  const auto gb = graph::serializeGraph(g), cb = graph::serializeCells(g);
  graph::StreetGraph r;
  graph::parseGraph(gb.data(), gb.size(), 0, r);
  graph::parseCells(cb.data(), cb.size(), 0, r);
  ASSERT_EQ(r.vertices.size(), g.vertices.size());
  ASSERT_EQ(r.halfedges.size(), g.halfedges.size());
  for (size_t i = 0; i < g.halfedges.size(); ++i) {
    EXPECT_EQ(r.halfedges[i].twin, g.halfedges[i].twin);
    EXPECT_EQ(r.halfedges[i].next, g.halfedges[i].next);
    EXPECT_EQ(r.halfedges[i].face, g.halfedges[i].face);
    EXPECT_EQ(r.halfedges[i].osm_way, g.halfedges[i].osm_way);
  }
  EXPECT_EQ(r.points, g.points);
  EXPECT_EQ(r.successors.items, g.successors.items);
  EXPECT_EQ(r.local_blocks.offsets, g.local_blocks.offsets);
  EXPECT_TRUE(graph::checkInvariants(r).empty());
}

TEST(GraphSerialize, EveryTruncationAndByteFlipIsCaught) {
  const graph::StreetGraph g = smallGraph();
  const auto gb = graph::serializeGraph(g);
  for (size_t n = 0; n < gb.size(); ++n) {
    graph::StreetGraph r;
    EXPECT_THROW(graph::parseGraph(gb.data(), n, 100, r), core::Error) << "length " << n;
  }
  // Flipping any byte either is caught or yields a graph whose indices are in range.
  for (size_t i = 0; i < gb.size(); ++i) {
    auto bad = gb;
    bad[i] ^= 0xff;
    graph::StreetGraph r;
    try {
      graph::parseGraph(bad.data(), bad.size(), 0, r);
      for (const auto& h : r.halfedges) {
        ASSERT_LT(h.twin, r.halfedges.size());
        ASSERT_LE(h.pts_begin + h.pts_count, r.points.size());
      }
    } catch (const core::Error& e) {
      EXPECT_EQ(e.status(), core::Status::Corrupt);
    }
  }
  const auto cb = graph::serializeCells(g);
  for (size_t n = 0; n < cb.size(); ++n) {
    graph::StreetGraph r = g;
    EXPECT_THROW(graph::parseCells(cb.data(), n, 0, r), core::Error);
  }
}

TEST(GraphSerialize, BlockTableChecksBlobIndex) {
  std::vector<graph::BlockRecord> blocks(3);
  blocks[1].blob = 0;
  blocks[2].blob = 7;
  const auto b = graph::serializeBlocks(blocks);
  std::vector<graph::BlockRecord> r;
  EXPECT_NO_THROW(graph::parseBlocks(b.data(), b.size(), 0, 8, r));
  EXPECT_EQ(r[2].blob, 7u);
  try {
    graph::parseBlocks(b.data(), b.size(), 512, 5, r);
    FAIL();
  } catch (const core::Error& e) {
    EXPECT_NE(std::string(e.what()).find("offset"), std::string::npos);
  }
}
