// The street graph read through a page cache (stream::PagedGraph), against the
// same package parsed whole: every half-edge, point and cell list, every grid
// query, the nearest cell, with a cache far smaller than the graph so that
// pages are evicted and read again; a record out of range under a valid CRC
// refused with its offset; a package without the stored grid (format 3.0);
// the per-cell visibility and impostor tables read a cell at a time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>
#include <string>
#include <vector>

#include "common/monaco_city.h"
#include "package/format.h"
#include "package/format_detail.h"
#include "package_test_util.h"
#include "graph/cell_tables.h"
#include "stream/paged_graph.h"

namespace blvd {
namespace {

using package::testutil::readFile;
using package::testutil::resealChecksums;
using package::testutil::writeFile;

const stream::City& whole() { return test::monacoCity(); }

constexpr stream::PagedGraphDesc kSmallCache{16, 1024};  // 16 KiB: a fraction of Monaco's graph

core::Status openPaged(stream::City& city, const std::string& path, stream::City::Tables tables, std::string& err) {
  return city.open(path, err, tables, stream::City::GraphTables::Paged, kSmallCache);
}

std::set<std::pair<uint32_t, uint32_t>> near(const graph::GraphSource& g, double x, double y, double r) {
  std::set<std::pair<uint32_t, uint32_t>> out;
  g.forSegmentsNear(x, y, r, [&](const graph::SegmentGrid::Entry& e) { out.insert({e.halfedge, e.point}); });
  return out;
}

void expectSameGraph(const graph::GraphSource& a, const graph::StreetGraph& g) {
  ASSERT_EQ(a.cellCount(), g.halfedges.size());
  ASSERT_EQ(a.pointCount(), g.points.size());
  for (uint32_t h = 0; h < g.halfedges.size(); ++h) {
    const graph::HalfEdge e = a.halfedge(h), &w = g.halfedges[h];
    ASSERT_TRUE(e.origin == w.origin && e.twin == w.twin && e.next == w.next && e.face == w.face &&
                e.pts_begin == w.pts_begin && e.pts_count == w.pts_count && e.length == w.length &&
                e.width == w.width && e.road_class == w.road_class && e.flags == w.flags && e.layer == w.layer &&
                e.osm_way == w.osm_way)
        << "half-edge " << h;
    const graph::Csr* csr[3] = {&g.successors, &g.predecessors, &g.local_blocks};
    const graph::GraphSource::List lists[3] = {a.successors(h), a.predecessors(h), a.localBlocks(h)};
    for (int l = 0; l < 3; ++l)
      ASSERT_EQ(std::vector<uint32_t>(lists[l].begin(), lists[l].end()),
                std::vector<uint32_t>(csr[l]->begin(h), csr[l]->end(h)))
          << "list " << l << " of cell " << h;
  }
  for (uint32_t i = 0; i < g.points.size(); ++i) ASSERT_EQ(a.point(i), g.points[i]) << "point " << i;
}

TEST(PagedGraph, ReadsWhatTheWholeGraphHolds) {
  stream::PagedGraph paged;
  std::string err;
  ASSERT_EQ(paged.open(whole().package(), err, kSmallCache), core::Status::Ok) << err;
  expectSameGraph(paged, whole().graph());
  EXPECT_EQ(paged.faceCount(), whole().graph().faces.size());
  // The grid the bake stored answers as the one built in memory.
  const graph::GridShape gs = whole().streets().gridShape(), ps = paged.gridShape();
  EXPECT_TRUE(gs.ox == ps.ox && gs.oy == ps.oy && gs.cell == ps.cell && gs.nx == ps.nx && gs.ny == ps.ny);
  EXPECT_EQ(paged.gridEntryCount(), whole().streets().gridEntryCount());
  for (int k = 0; k < 200; ++k) {
    const double x = gs.ox + (k * 37 % 101) / 100.0 * gs.nx * gs.cell, y = gs.oy + (k * 53 % 103) / 102.0 * gs.ny * gs.cell;
    ASSERT_EQ(near(paged, x, y, 20 + k % 7 * 30), near(whole().streets(), x, y, 20 + k % 7 * 30)) << "query " << k;
  }
  // The cache stayed its size while everything passed through it.
  const stream::PageCacheStats st = paged.stats();
  EXPECT_GT(st.misses, 1000u);
  EXPECT_LT(paged.bytes(), 24u * 1024);
}

// The runtime's nearest cell, through the paged graph and the whole one.
TEST(PagedGraph, NearestCellAsTheWholeGraph) {
  stream::City city;
  std::string err;
  ASSERT_EQ(openPaged(city, BLVD_TEST_PACKAGE, stream::City::Tables::Graph, err), core::Status::Ok) << err;
  ASSERT_TRUE(city.paged());
  EXPECT_TRUE(city.graph().halfedges.empty());  // nothing of the graph held whole
  const graph::GridShape gs = city.streets().gridShape();
  for (int k = 0; k < 300; ++k) {
    const glm::dvec2 p(gs.ox + (k * 71 % 113) / 112.0 * gs.nx * gs.cell, gs.oy + (k * 29 % 127) / 126.0 * gs.ny * gs.cell);
    const double heading = k * 47 % 360;
    double arc_a = -1, arc_b = -1, cost_a = 0, cost_b = 0;
    const uint32_t a = city.nearestCell(p, heading, &arc_a, &cost_a);
    const uint32_t b = whole().nearestCell(p, heading, &arc_b, &cost_b);
    ASSERT_EQ(a, b) << "point " << k;
    EXPECT_EQ(arc_a, arc_b);
    EXPECT_EQ(cost_a, cost_b);
  }
}

// A byte offset of the GRPH section's first half-edge record, and the section.
size_t firstHalfEdge(const std::vector<uint8_t>& b, size_t* entry) {
  using package::detail::get;
  *entry = package::testutil::dirEntryOffset(b, package::kSectionGraph);
  const size_t at = get<uint64_t>(b.data() + *entry + package::detail::dir::kOffset);
  const uint32_t vertices = get<uint32_t>(b.data() + at + 4);
  return at + 8 + size_t(vertices) * 24 + 4;
}

void resealSection(std::vector<uint8_t>& b, size_t entry) {
  using package::detail::get;
  using package::detail::put;
  const size_t at = get<uint64_t>(b.data() + entry + package::detail::dir::kOffset);
  const size_t size = get<uint64_t>(b.data() + entry + package::detail::dir::kSize);
  put<uint32_t>(b.data() + entry + package::detail::dir::kCrc, package::crc32c(b.data() + at, size));
  resealChecksums(b);
}

TEST(PagedGraph, RefusesAHalfEdgeOutOfRangeNamingItsOffset) {
  std::vector<uint8_t> b = readFile(BLVD_TEST_PACKAGE);
  size_t entry = 0;
  const size_t rec = firstHalfEdge(b, &entry) + 5 * 44;  // half-edge 5
  package::detail::put<uint32_t>(b.data() + rec + 4, 0x7fffffffu);  // its twin
  resealSection(b, entry);
  const std::string path = ::testing::TempDir() + "/paged_bad_twin.blvd";
  writeFile(path, b);
  stream::City city;
  std::string err;
  EXPECT_EQ(openPaged(city, path, stream::City::Tables::Graph, err), core::Status::Corrupt);
  EXPECT_NE(err.find("GRPH"), std::string::npos) << err;
  EXPECT_NE(err.find("record 5 at file offset " + std::to_string(rec)), std::string::npos) << err;
}

// Tables that arrive a page at a time (a PageSource): open reads the counts
// only, each page is asked of the source before it is read, and a bad record
// is refused when read, with its offset, as open refuses it otherwise.
TEST(PagedGraph, OverASourceChecksEachRecordAsItIsRead) {
  std::vector<uint8_t> b = readFile(BLVD_TEST_PACKAGE);
  size_t entry = 0;
  const size_t rec = firstHalfEdge(b, &entry) + 5 * 44;
  package::detail::put<uint32_t>(b.data() + rec + 4, 0x7fffffffu);  // half-edge 5's twin
  resealSection(b, entry);
  const std::string path = ::testing::TempDir() + "/paged_lazy_bad_twin.blvd";
  writeFile(path, b);
  struct Asked final : stream::PageSource {
    mutable std::vector<std::pair<uint64_t, uint64_t>> ranges;
    void ensure(uint64_t offset, uint64_t size) const override { ranges.emplace_back(offset, size); }
  } asked;
  package::PackageReader reader;
  std::string err;
  ASSERT_EQ(package::PackageReader::open(path, reader, err), core::Status::Ok) << err;
  stream::PagedGraph g;
  ASSERT_EQ(g.open(reader, err, kSmallCache, &asked), core::Status::Ok) << err;
  const uint64_t at_open = asked.ranges.size();
  EXPECT_LE(at_open, 16u);  // the tables' counts, not their records
  EXPECT_EQ(g.halfedge(4).twin, whole().streets().halfedge(4).twin);
  ASSERT_GT(asked.ranges.size(), at_open);
  const auto [offset, size] = asked.ranges.back();
  EXPECT_LE(offset, uint64_t(rec));  // the page holding half-edge 4 (and 5)
  EXPECT_GT(offset + size, uint64_t(rec));
  try {
    g.halfedge(5);
    ADD_FAILURE() << "half-edge 5 read";
  } catch (const core::Error& e) {
    EXPECT_EQ(e.status(), core::Status::Corrupt);
    EXPECT_NE(std::string(e.what()).find("record 5 at file offset " + std::to_string(rec)), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(g.halfedge(g.cellCount()), core::Error);  // past the table
}

// A 3.0 package has no SIDX: the paged graph builds the grid from its pages.
TEST(PagedGraph, BuildsTheGridForAPackageWithoutOne) {
  std::vector<uint8_t> b = readFile(BLVD_TEST_PACKAGE);
  for (uint32_t tag : {package::kSectionSpatialIndex, package::kSectionTablePages}) {  // 3.0 had neither
    const size_t entry = package::testutil::dirEntryOffset(b, tag);
    package::detail::put<uint32_t>(b.data() + entry + package::detail::dir::kTag, package::fourcc('X', 'X', 'X', char('0' + (tag & 7))));
  }
  resealChecksums(b);
  const std::string path = ::testing::TempDir() + "/paged_no_sidx.blvd";
  writeFile(path, b);
  stream::City city;
  std::string err;
  ASSERT_EQ(openPaged(city, path, stream::City::Tables::Graph, err), core::Status::Ok) << err;
  EXPECT_EQ(city.streets().gridEntryCount(), whole().streets().gridEntryCount());
  const graph::GridShape gs = whole().streets().gridShape();
  for (int k = 0; k < 100; ++k) {
    const glm::dvec2 p(gs.ox + (k * 71 % 113) / 112.0 * gs.nx * gs.cell, gs.oy + (k * 29 % 127) / 126.0 * gs.ny * gs.cell);
    ASSERT_EQ(city.nearestCell(p, k * 13 % 360), whole().nearestCell(p, k * 13 % 360)) << "point " << k;
  }
}

// The per-cell tables a cell at a time through the cell table index, against
// the whole parse: every cell's layers and every coverage hint, and a block
// outside a cell's PVS.
TEST(PagedCellTables, ReadWhatTheWholeTablesHold) {
  stream::City city;
  std::string err;
  ASSERT_EQ(openPaged(city, BLVD_TEST_PACKAGE, stream::City::Tables::All, err), core::Status::Ok) << err;
  ASSERT_TRUE(city.hasImpostors());
  EXPECT_TRUE(city.cellTables().impostors.empty() && city.cellTables().visibility.empty());  // nothing held whole
  EXPECT_EQ(city.maxCellLayers(), whole().maxCellLayers());
  const graph::CellTables& t = whole().cellTables();
  std::vector<stream::LayerInfo> a(city.maxCellLayers()), b(city.maxCellLayers());
  uint32_t with_layers = 0;
  for (uint32_t c = 0; c < t.impostors.size(); ++c) {
    uint32_t la = 0, sa = 0, lb = 0, sb = 0;
    city.cellLayers(c, a.data(), static_cast<uint32_t>(a.size()), &la, &sa);
    whole().cellLayers(c, b.data(), static_cast<uint32_t>(b.size()), &lb, &sb);
    ASSERT_EQ(la, t.impostors[c].layered.size()) << "cell " << c;
    ASSERT_EQ(sa, t.impostors[c].single.size()) << "cell " << c;
    ASSERT_TRUE(la == lb && sa == sb);
    with_layers += la + sa > 0;
    for (uint32_t i = 0; i < la + sa; ++i) {
      const graph::ImpostorLayer& w = i < la ? t.impostors[c].layered[i] : t.impostors[c].single[i - la];
      EXPECT_TRUE(a[i].blob == w.blob && a[i].triangles == w.triangles && a[i].vertices == w.vertices &&
                  a[i].texture_width == w.texture_width && a[i].texture_height == w.texture_height &&
                  a[i].run_from_m == w.run_from_m)
          << "cell " << c << " layer " << i;
    }
    const graph::CellVisibility& v = t.visibility[c];
    for (size_t i = 0; i < v.blocks.size(); ++i) ASSERT_EQ(city.coverage(c, v.blocks[i]), v.ach[i]) << "cell " << c;
    uint32_t outside = 0;  // the lowest block id not in the list
    while (std::binary_search(v.blocks.begin(), v.blocks.end(), outside)) ++outside;
    EXPECT_EQ(city.coverage(c, outside), 0.f);
  }
  EXPECT_GT(with_layers, 0u);
}

TEST(PagedCellTables, RefuseAnIndexEntryThatPointsElsewhere) {
  std::vector<uint8_t> b = readFile(BLVD_TEST_PACKAGE);
  const size_t entry = package::testutil::dirEntryOffset(b, package::kSectionCellTableIndex);
  const size_t at = package::detail::get<uint64_t>(b.data() + entry + package::detail::dir::kOffset);
  const size_t cell3 = at + graph::kCellTableIndexHeader + 3 * graph::kCellTableIndexEntry;
  package::detail::put<uint64_t>(b.data() + cell3 + 8, package::detail::get<uint64_t>(b.data() + cell3 + 8) + 4);
  resealSection(b, entry);
  const std::string path = ::testing::TempDir() + "/paged_bad_ctix.blvd";
  writeFile(path, b);
  stream::City city;
  std::string err;
  EXPECT_EQ(openPaged(city, path, stream::City::Tables::All, err), core::Status::Corrupt);
  EXPECT_NE(err.find("CTIX at offset " + std::to_string(cell3)), std::string::npos) << err;
  EXPECT_NE(err.find("cell 3 "), std::string::npos) << err;
}

}  // namespace
}  // namespace blvd
