// A package that goes bad under a drive: a block blob of a cell on the route
// fails its checksum. Each cell with that block is drawn without it, the block
// is reported (blvd_stats.load_errors, the last error naming the file, blob and
// offset), and the drive goes on with whole frames; no frame fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>

#include "blvd/blvd.h"
#include "drive.h"
#include "package/reader.h"
#include "runtime_fixture.h"
#include "stream/city.h"

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

}  // namespace
