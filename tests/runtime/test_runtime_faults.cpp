// A package that goes bad under a drive. A block blob of a cell on the route
// fails its checksum: each cell with that block is drawn without it, the block
// is reported (blvd_stats.load_errors, the last error naming the file, blob and
// offset), and the drive goes on with whole frames; no frame fails. The file
// is cut short under the running runtime: the blobs past the cut are read
// errors naming the offset (a mapped reader would die of SIGBUS), the drive
// goes on; cut to nothing, a street whose table pages are not cached is a
// refused call naming the file; cut while the tables are being parsed at
// open, a read error too. The GPU is reset under the drive (the
// driver's GetError says GL_CONTEXT_LOST): every frame from then on is
// BLVD_ERR_BACKEND saying to create the runtime again, and a new one draws.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "blvd/blvd.h"
#include "capi/binding.h"
#include "drive.h"
#include "package/reader.h"
#include "render/gl_api.h"
#include "render/renderer.h"
#include "runtime_fixture.h"
#include "stream/block_pages.h"
#include "stream/cell_table_pages.h"
#include "stream/city.h"
#include "stream/paged_graph.h"

namespace {

using blvd_test::baseDesc;
using blvd_test::Runtime;
using blvd_test::statsOf;

// A copy of the test package with one byte flipped in the middle of the blob
// of `cell`'s first local block; returns that block's blob offset.
uint64_t corruptFirstBlock(const std::string& path, uint32_t cell) {
  std::filesystem::copy_file(BLVD_TEST_PACKAGE, path, std::filesystem::copy_options::overwrite_existing);
  blvd::stream::City city;
  std::string err;
  EXPECT_EQ(city.open(path, err), blvd::core::Status::Ok) << err;
  const auto blocks = city.streets().localBlocks(cell);
  EXPECT_GT(blocks.size(), 0u);
  const uint32_t blob = city.block(*blocks.begin()).blob;
  blvd::package::PackageReader r;
  EXPECT_EQ(blvd::package::PackageReader::open(path, r, err), blvd::core::Status::Ok) << err;
  const blvd::package::BlobInfo info = r.blobInfo(blob);
  r.close();
  std::FILE* f = std::fopen(path.c_str(), "r+b");
  EXPECT_NE(f, nullptr);
  const long at = static_cast<long>(info.offset + info.size / 2);
  std::fseek(f, at, SEEK_SET);
  const int c = std::fgetc(f);
  std::fseek(f, at, SEEK_SET);
  std::fputc(c ^ 0x5A, f);
  std::fclose(f);
  return info.offset;
}

TEST(RuntimeFaults, ABlobFailingItsChecksumMidDriveLeavesItsBlockOut) {
  const blvd_test::Drive dr = blvd_test::impostorDrive(6, 8.0);
  ASSERT_GE(dr.cells.size(), 4u);
  const uint32_t bad = dr.cells[2];
  const std::string path = (std::filesystem::temp_directory_path() / "blvd_test_bad_blob.blvd").string();
  const uint64_t offset = corruptFirstBlock(path, bad);
  blvd_runtime_desc d = baseDesc();
  d.package_path = path.c_str();
  Runtime r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);  // blobs are checked as loaded
  size_t whole = 0, frames_in_bad = 0;
  std::string error;
  for (const auto& p : dr.poses) {
    ASSERT_EQ(blvd_set_pose_local(r.rt, p.x, p.y, float(p.heading_deg), 0.f), BLVD_OK);
    blvd_frame_stats fs{};
    fs.struct_size = sizeof fs;
    ASSERT_EQ(blvd_render(r.rt, &fs), BLVD_OK) << blvd_last_error(r.rt);
    if (fs.flags & BLVD_FRAME_DEGRADED) {
      ASSERT_EQ(blvd_wait_resident(r.rt, 60000), BLVD_OK) << blvd_last_error(r.rt);
      ASSERT_EQ(blvd_render(r.rt, &fs), BLVD_OK) << blvd_last_error(r.rt);
    }
    if (statsOf(r.rt).load_errors > 0 && error.empty()) error = blvd_last_error(r.rt);
    frames_in_bad += p.cell == bad;
    whole += !(fs.flags & BLVD_FRAME_DEGRADED) && fs.blocks_drawn > 0;
  }
  ASSERT_GT(frames_in_bad, 1u);
  const blvd_stats s = statsOf(r.rt);
  EXPECT_GE(s.load_errors, 1u);
  EXPECT_LE(s.load_errors, s.loads);  // at most once per load of a cell with the block
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("block left out"), std::string::npos) << error;
  EXPECT_NE(error.find(std::to_string(offset)), std::string::npos) << error;
  EXPECT_EQ(whole, dr.poses.size());  // every frame whole, the bad cell's too (without its block)
  std::filesystem::remove(path);
}

// The smallest blob offset of `cells`' local blocks and impostor layers.
uint64_t firstBlobOf(const std::string& path, const std::vector<uint32_t>& cells) {
  blvd::stream::City city;
  std::string err;
  EXPECT_EQ(city.open(path, err), blvd::core::Status::Ok) << err;
  uint64_t first = ~0ull;
  std::vector<uint32_t> blobs;
  for (const uint32_t c : cells) {
    city.cellBlobs(c, nullptr, 0, blobs);
    for (const uint32_t b : blobs) first = std::min(first, city.package().blobInfo(b).offset);
  }
  return first;
}

// Drives `poses`; every frame must be drawn (BLVD_OK). Returns the first
// error the runtime reported with load_errors > 0.
std::string driveThrough(blvd_runtime* rt, const std::vector<blvd_test::DrivePose>& poses) {
  std::string error;
  for (const auto& p : poses) {
    EXPECT_EQ(blvd_set_pose_local(rt, p.x, p.y, float(p.heading_deg), 0.f), BLVD_OK);
    blvd_frame_stats fs{};
    fs.struct_size = sizeof fs;
    EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
    if (fs.flags & BLVD_FRAME_DEGRADED) {
      (void)blvd_wait_resident(rt, 60000);  // a cell whose impostors are past the cut fails: reported below
      EXPECT_EQ(blvd_render(rt, &fs), BLVD_OK) << blvd_last_error(rt);
    }
    if (statsOf(rt).load_errors > 0 && error.empty()) error = blvd_last_error(rt);
  }
  return error;
}

TEST(RuntimeFaults, APackageCutShortMidDriveGivesReadErrorsNotASigbus) {
  const blvd_test::Drive dr = blvd_test::impostorDrive(12, 8.0);
  ASSERT_GE(dr.cells.size(), 8u);
  const std::string path = (std::filesystem::temp_directory_path() / "blvd_test_cut_short.blvd").string();
  std::filesystem::copy_file(BLVD_TEST_PACKAGE, path, std::filesystem::copy_options::overwrite_existing);
  // The poses follow dr.cells: the first six cells before the cut, the rest
  // after it (a drive may come back to a cell: those count as before).
  const std::vector<uint32_t> first(dr.cells.begin(), dr.cells.begin() + 6);
  std::vector<uint32_t> later;
  for (auto c = dr.cells.begin() + 6; c != dr.cells.end(); ++c)
    if (std::find(first.begin(), first.end(), *c) == first.end()) later.push_back(*c);
  ASSERT_FALSE(later.empty());
  const uint64_t cut = firstBlobOf(path, later);
  ASSERT_LT(cut, std::filesystem::file_size(path));
  blvd_runtime_desc d = baseDesc();
  d.package_path = path.c_str();
  Runtime r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  std::vector<blvd_test::DrivePose> before, after;
  const size_t split = size_t(std::find_if(dr.poses.begin(), dr.poses.end(),
                                            [&](const blvd_test::DrivePose& p) { return p.cell == dr.cells[6]; }) -
                               dr.poses.begin());
  before.assign(dr.poses.begin(), dr.poses.begin() + split);
  after.assign(dr.poses.begin() + split, dr.poses.end());
  ASSERT_FALSE(before.empty());
  ASSERT_FALSE(after.empty());
  EXPECT_EQ(driveThrough(r.rt, before), "");
  ASSERT_EQ(statsOf(r.rt).load_errors, 0u);
  ASSERT_EQ(::truncate(path.c_str(), static_cast<off_t>(cut)), 0);  // under the running runtime
  const std::string error = driveThrough(r.rt, after);
  const blvd_stats s = statsOf(r.rt);
  EXPECT_GE(s.load_errors, 1u);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("the file ends at offset " + std::to_string(cut)), std::string::npos) << error;
  EXPECT_NE(error.find("(truncated)"), std::string::npos) << error;
  // And back to where the drive began: those cells draw as before.
  EXPECT_NO_FATAL_FAILURE(driveThrough(r.rt, before));
  // Cut to nothing: the tables' pages the caches let go can no longer be read.
  ASSERT_EQ(::truncate(path.c_str(), 0), 0);
  blvd_test::Drive elsewhere;
  {
    blvd::stream::City city;
    std::string err;
    ASSERT_EQ(city.open(BLVD_TEST_PACKAGE, err), blvd::core::Status::Ok) << err;
    elsewhere = blvd_test::makeDrive(city.graph(), city.graph().cellCount() / 2, 8, 8.0);
  }
  size_t failed = 0, drawn = 0;
  for (const auto& p : elsewhere.poses) {
    const blvd_status st = blvd_set_pose_local(r.rt, p.x, p.y, float(p.heading_deg), 0.f);
    blvd_frame_stats fs{};
    fs.struct_size = sizeof fs;
    const blvd_status rs = st == BLVD_OK ? blvd_render(r.rt, &fs) : st;
    if (rs == BLVD_OK) {
      ++drawn;
      continue;
    }
    ++failed;
    const std::string why = blvd_last_error(r.rt);
    EXPECT_NE(why.find(path + ": cannot read"), std::string::npos) << why;
  }
  std::printf("file cut to 0 bytes: %zu frames drawn, %zu refused with a read error\n", drawn, failed);
  EXPECT_GT(failed, 0u);  // a new street's table pages were not cached: the cut shows, named
  std::filesystem::remove(path);
}

// What City::open parses after its reader opened the file: the street
// graph, the block table and the cell tables.
blvd::core::Status openTables(const blvd::package::PackageReader& r, std::string& err) {
  blvd::stream::PagedGraph graph;
  blvd::core::Status st = graph.open(r, err);
  if (st != blvd::core::Status::Ok) return st;
  blvd::stream::BlockPages blocks;
  if ((st = blocks.open(r, 32, 2048, err)) != blvd::core::Status::Ok) return st;
  blvd::stream::CellTablePages cells;
  return cells.open(r, graph, blocks.count(), 64, 2048, err, nullptr, r.header().max_cell_impostor_layers);
}

// The window a mapped reader left: the file cut short after the reader opened
// it and before the tables were parsed, at the start and in the middle of
// each section. A cut before the end of a table is a read error naming the
// file and saying it was truncated; a cut past them all opens; no signal
// either way, since the runtime's reader maps nothing (Access::Read).
TEST(RuntimeFaults, APackageCutShortWhileItIsBeingOpenedGivesReadErrorsNotASigbus) {
  using blvd::package::PackageReader;
  const std::string path = (std::filesystem::temp_directory_path() / "blvd_test_cut_opening.blvd").string();
  std::string err;
  std::vector<uint64_t> cuts;
  uint64_t tables_end = 0;
  {
    PackageReader r;
    ASSERT_EQ(PackageReader::open(BLVD_TEST_PACKAGE, r, err), blvd::core::Status::Ok) << err;
    for (const blvd::package::SectionInfo& s : r.sections()) {
      cuts.push_back(s.offset);
      cuts.push_back(s.offset + s.size / 2);
      for (uint32_t tag : {blvd::package::kSectionGraph, blvd::package::kSectionCells,
                           blvd::package::kSectionSpatialIndex, blvd::package::kSectionBlocks,
                           blvd::package::kSectionVisibility, blvd::package::kSectionImpostors,
                           blvd::package::kSectionCellTableIndex})
        if (s.tag == tag) tables_end = std::max(tables_end, s.offset + s.size);
    }
    ASSERT_TRUE(r.hasSection(blvd::package::kSectionCellTableIndex));
  }
  size_t refused = 0;
  for (const uint64_t cut : cuts) {
    std::filesystem::copy_file(BLVD_TEST_PACKAGE, path, std::filesystem::copy_options::overwrite_existing);
    PackageReader r;
    ASSERT_EQ(PackageReader::open(path, r, err, PackageReader::Access::Read), blvd::core::Status::Ok) << err;
    blvd::package::Span unused;
    ASSERT_EQ(r.blob(0, unused, err), blvd::core::Status::Misuse);  // nothing mapped to touch
    ASSERT_EQ(::truncate(path.c_str(), static_cast<off_t>(cut)), 0);
    std::string why;
    const blvd::core::Status st = openTables(r, why);
    if (cut >= tables_end) {
      EXPECT_EQ(st, blvd::core::Status::Ok) << "cut at " << cut << ": " << why;
      continue;
    }
    ++refused;
    EXPECT_EQ(st, blvd::core::Status::Io) << "cut at " << cut << ": " << why;
    EXPECT_NE(why.find(path + ": cannot read"), std::string::npos) << why;
    EXPECT_NE(why.find("the file ends at offset " + std::to_string(cut)), std::string::npos) << why;
  }
  std::printf("%zu cuts, %zu refused with a read error\n", cuts.size(), refused);
  EXPECT_GT(refused, 0u);
  std::filesystem::remove(path);
}

GLenum GL_APIENTRY contextLost() { return 0x0507; }  // GL_CONTEXT_LOST, for ever after

TEST(RuntimeFaults, AGpuResetMidDriveFailsEveryFrameUntilTheRuntimeIsCreatedAgain) {
  const blvd_test::Drive dr = blvd_test::impostorDrive(2, 8.0);
  blvd_runtime_desc d = baseDesc();
  Runtime r;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  const auto& p = dr.poses.front();
  ASSERT_EQ(blvd_set_pose_local(r.rt, p.x, p.y, float(p.heading_deg), 0.f), BLVD_OK);
  ASSERT_EQ(blvd_wait_resident(r.rt, 60000), BLVD_OK) << blvd_last_error(r.rt);
  blvd_frame_stats fs{};
  fs.struct_size = sizeof fs;
  ASSERT_EQ(blvd_render(r.rt, &fs), BLVD_OK) << blvd_last_error(r.rt);
  r.rt->impl->renderer().api().GetError = contextLost;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(blvd_render(r.rt, &fs), BLVD_ERR_BACKEND);
    EXPECT_NE(std::string(blvd_last_error(r.rt)).find("GL context lost"), std::string::npos) << blvd_last_error(r.rt);
  }
  EXPECT_NE(std::string(blvd_last_error(r.rt)).find("create it again"), std::string::npos) << blvd_last_error(r.rt);
  blvd_runtime_destroy(r.rt);
  r.rt = nullptr;
  ASSERT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_set_pose_local(r.rt, p.x, p.y, float(p.heading_deg), 0.f), BLVD_OK);
  ASSERT_EQ(blvd_wait_resident(r.rt, 60000), BLVD_OK) << blvd_last_error(r.rt);
  EXPECT_EQ(blvd_render(r.rt, &fs), BLVD_OK) << blvd_last_error(r.rt);
  EXPECT_GT(fs.blocks_drawn, 0u);
}

}  // namespace
