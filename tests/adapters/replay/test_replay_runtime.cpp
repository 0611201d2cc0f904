// Replay into a real runtime: a synthetic NMEA trace along a Monaco street
// (recorded with the Recorder) through RuntimeSink, then blvd_get_pose.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "blvd/blvd.h"
#include "replay/recorder.h"
#include "replay/replayer.h"

namespace blvd::replay {
namespace {

TEST(ReplayRuntime, SyntheticTraceGivesValidPose) {
  if (!std::ifstream(BLVD_TEST_PACKAGE).good()) GTEST_SKIP() << BLVD_TEST_PACKAGE << " missing (fixture monaco_package)";
  blvd_runtime_desc desc{};
  desc.struct_size = sizeof desc;
  desc.package_path = BLVD_TEST_PACKAGE;
  desc.width = 320;
  desc.height = 192;
  blvd_runtime* rt = nullptr;
  ASSERT_EQ(blvd_runtime_create(&desc, &rt), BLVD_OK) << blvd_last_error(nullptr);

  const double lat0 = 43.73537, lon0 = 7.41729, hdg = 211.0 * M_PI / 180.0, t0 = 1717243200.0;
  std::ostringstream nmea;
  Recorder rec;
  rec.attachNmea(nmea);
  for (int k = 0; k < 10; ++k) {
    const double d = 10.0 * k;
    blvd_gnss_fix f{};
    f.struct_size = sizeof f;
    f.t = t0 + k;
    f.lat = lat0 + d * std::cos(hdg) / 111132.0;
    f.lon = lon0 + d * std::sin(hdg) / (111320.0 * std::cos(lat0 * M_PI / 180.0));
    f.speed_mps = 10.0f;
    f.track_deg = 211.0f;
    f.hdop = 1.0f;
    f.mode = BLVD_GNSS_MODE_3D;
    f.flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_SPEED | BLVD_GNSS_HAS_TRACK |
              BLVD_GNSS_HAS_HDOP;
    ASSERT_TRUE(rec.record(f));
  }
  std::istringstream in(nmea.str());
  ReplayDesc d;
  d.nmea_stream = &in;
  Replayer r;
  std::string err;
  ASSERT_EQ(r.open(d, err), BLVD_OK) << err;
  RuntimeSink sink(rt);
  ASSERT_EQ(r.run(sink, err), BLVD_OK) << err;
  EXPECT_EQ(r.stats().gnss, 10u);
  EXPECT_EQ(sink.failures(), 0u);

  blvd_pose pose{};
  pose.struct_size = sizeof pose;
  EXPECT_EQ(blvd_get_pose(rt, t0 + 9.0, &pose), BLVD_OK) << blvd_last_error(rt);
  EXPECT_TRUE(pose.flags & BLVD_POSE_VALID);
  EXPECT_NEAR(pose.lat, lat0 + 90.0 * std::cos(hdg) / 111132.0, 30.0 / 111132.0);
  blvd_runtime_destroy(rt);
}

}  // namespace
}  // namespace blvd::replay
