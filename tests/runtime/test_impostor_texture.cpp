// Cell slots whose impostor atlas is ETC2 (blvd_runtime_desc.impostor_texture):
// the plan carves an eighth of the atlas's texel bytes (on the coarser grid
// ETC2 places need), blvd_memory_required says so, the frames of a drive draw
// the far city within the codec's error of RGBA8 slots, and an unknown value
// is refused at create.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "drive.h"
#include "render/slab_atlas.h"
#include "runtime/memory_plan.h"
#include "runtime_fixture.h"
#include "stream/city.h"

namespace {

using blvd_test::baseDesc;
using blvd_test::Runtime;

blvd_runtime_desc textureDesc(uint32_t texture) {
  blvd_runtime_desc d = baseDesc();
  d.width = 320;
  d.height = 192;
  d.mode = BLVD_MODE_BLVD;
  d.prefetch_priority = BLVD_PREFETCH_LOW;
  d.impostor_texture = texture;
  return d;
}

uint64_t atlasPart(const blvd::runtime::MemoryPlan& p) {
  return blvd::render::atlasBytes(p.slab.atlas_width, p.slab.atlas_height, p.slab.atlas_format);
}

TEST(ImpostorTexture, Etc2SlotsHoldAnEighthOfTheAtlasBytes) {
  blvd::stream::City city;
  std::string err;
  ASSERT_EQ(city.open(BLVD_TEST_PACKAGE, err), blvd::core::Status::Ok) << err;
  const blvd_runtime_desc r0 = textureDesc(BLVD_TEXTURE_RGBA8), e0 = textureDesc(BLVD_TEXTURE_ETC2);
  const blvd_runtime_desc rd = blvd_runtime_desc_defaults(&r0), ed = blvd_runtime_desc_defaults(&e0);
  const blvd::runtime::MemoryPlan rgba = blvd::runtime::planMemory(rd, city), etc2 = blvd::runtime::planMemory(ed, city);
  ASSERT_GT(rgba.slab.atlas_height, 0) << "the test package has no impostors";
  EXPECT_EQ(etc2.slab.atlas_format, blvd::render::AtlasFormat::Etc2);
  EXPECT_EQ(etc2.slab.atlas_width % blvd::render::kEtc2AtlasAlign, 0);
  EXPECT_EQ(etc2.slab.atlas_height % blvd::render::kEtc2AtlasAlign, 0);
  // The same texels on a coarser grid: at most a grid step more each way.
  EXPECT_GE(etc2.slab.atlas_width, rgba.slab.atlas_width);
  const double area = double(etc2.slab.atlas_width) * etc2.slab.atlas_height;
  const double rgba_area = double(rgba.slab.atlas_width) * rgba.slab.atlas_height;
  // Half a byte a texel at every level (each a whole number of blocks).
  EXPECT_EQ(atlasPart(etc2) * 8, blvd::render::atlasBytes(etc2.slab.atlas_width, etc2.slab.atlas_height));
  EXPECT_LE(area, rgba_area * 1.5) << "the 32-texel grid should cost little of the atlas";
  EXPECT_LT(atlasPart(etc2) * 5, atlasPart(rgba));
  EXPECT_EQ(rgba.gpu_bytes - etc2.gpu_bytes, uint64_t(rgba.resident_cells) * (atlasPart(rgba) - atlasPart(etc2)));
  // Staging holds the ETC2 levels beside the RGBA8 ones.
  EXPECT_GT(etc2.staging_arena_bytes, rgba.staging_arena_bytes);
  // blvd_memory_required says the same (it opens the tables paged: compared
  // against the RGBA8 figure, where the table bytes cancel).
  uint64_t cpu = 0, gpu = 0, rgba_cpu = 0, rgba_gpu = 0;
  ASSERT_EQ(blvd_memory_required(&ed, nullptr, &cpu, &gpu), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_memory_required(&rd, nullptr, &rgba_cpu, &rgba_gpu), BLVD_OK) << blvd_last_error(nullptr);
  EXPECT_EQ(gpu, etc2.gpu_bytes);
  EXPECT_EQ(rgba_gpu, rgba.gpu_bytes);
  EXPECT_EQ(cpu - rgba_cpu, etc2.cpu_bytes - rgba.cpu_bytes);
}

// Along a drive through cells with impostors: where the RGBA8 runtime's blvd
// frame differs from its local-model frame (the impostors' pixels), the ETC2
// runtime's frame is within 30 dB PSNR of it; everything else is the same.
TEST(ImpostorTexture, Etc2FramesDrawTheFarCityWithinTheCodecsError) {
  const blvd_test::Drive dr = blvd_test::impostorDrive(8, 12.0);
  ASSERT_GE(dr.poses.size(), 8u);
  const blvd_runtime_desc rd = textureDesc(BLVD_TEXTURE_RGBA8), ed = textureDesc(BLVD_TEXTURE_ETC2);
  Runtime a, b;
  ASSERT_EQ(blvd_runtime_create(&rd, &a.rt), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_EQ(blvd_runtime_create(&ed, &b.rt), BLVD_OK) << blvd_last_error(nullptr);
  for (blvd_runtime* rt : {a.rt, b.rt}) ASSERT_EQ(blvd_set_route(rt, dr.cells.data(), dr.cells.size()), BLVD_OK);
  uint64_t impostor_px = 0;
  for (size_t i = 0; i < dr.poses.size(); ++i) {
    const blvd_test::DrivePose& p = dr.poses[i];
    auto frame = [&](blvd_runtime* rt) {
      return blvd_test::wholeFrame(rt, p.x, p.y, p.heading_deg, rd.width, rd.height, 30000);
    };
    ASSERT_EQ(blvd_set_render_mode(a.rt, BLVD_MODE_LOCAL, 0), BLVD_OK);
    const std::vector<uint8_t> local = frame(a.rt);
    ASSERT_EQ(blvd_set_render_mode(a.rt, BLVD_MODE_BLVD, 0), BLVD_OK);
    const std::vector<uint8_t> fa = frame(a.rt), fb = frame(b.rt);
    double se = 0;
    uint64_t n = 0, elsewhere = 0;
    for (size_t k = 0; k < fa.size(); k += 4) {
      const bool impostor = fa[k] != local[k] || fa[k + 1] != local[k + 1] || fa[k + 2] != local[k + 2];
      for (int c = 0; c < 3; ++c) {
        const double d = double(fa[k + c]) - fb[k + c];
        if (impostor) se += d * d;
        else elsewhere += d != 0;
      }
      n += impostor;
    }
    impostor_px += n;
    if (n == 0) continue;
    const double psnr = 10 * std::log10(255.0 * 255.0 / std::max(1e-9, se / (3.0 * double(n))));
    EXPECT_GE(psnr, 30.0) << "pose " << i << " (cell " << p.cell << "), " << n << " impostor pixels";
    // An impostor pixel of one frame may show the local model in the other
    // (the codec moves a colour, not a depth), but only a few.
    EXPECT_LE(elsewhere, fa.size() / 400) << "pose " << i;
  }
  EXPECT_GT(impostor_px, uint64_t(rd.width) * rd.height) << "the drive shows too few impostor pixels to compare";
}

TEST(ImpostorTexture, AnUnknownFormatIsRefused) {
  blvd_runtime_desc d = textureDesc(7);
  Runtime r;
  EXPECT_EQ(blvd_runtime_create(&d, &r.rt), BLVD_ERR_INVALID_ARG);
  EXPECT_NE(std::string(blvd_last_error(nullptr)).find("impostor_texture"), std::string::npos) << blvd_last_error(nullptr);
  uint64_t cpu = 0;
  EXPECT_EQ(blvd_memory_required(&d, nullptr, &cpu, nullptr), BLVD_ERR_INVALID_ARG);
}

}  // namespace
