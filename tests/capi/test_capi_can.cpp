// blvd_can_profile_* and blvd_feed_can_frame: frames encoded with the Toyota
// DBC decode to the odometry they were encoded from, bad frames and bad
// descriptors are refused with clear errors, and feeds from several threads at
// once reach the tracker (run under TSan/ASan in CI like the other feeds).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "blvd/blvd.h"
#include "common/test_runtime.h"
#include "vehicle/dbc.h"

namespace {

const std::string kToyotaDbc = std::string(BLVD_TEST_DATA_DIR) + "/can/dbc/toyota_new_mc_pt_generated.dbc";

struct ProfileHandle {
  blvd_can_profile* p = nullptr;
  ~ProfileHandle() { blvd_can_profile_destroy(p); }
};

blvd_can_frame encodeToyota(const blvd::vehicle::Database& db, const char* message,
                            const std::vector<std::pair<std::string, double>>& values, double t) {
  const blvd::vehicle::Message* m = db.findByName(message);
  EXPECT_NE(m, nullptr) << message;
  blvd::vehicle::Frame f;
  std::string err;
  EXPECT_EQ(blvd::vehicle::encode(*m, values, f, err), blvd::core::Status::Ok) << err;
  blvd_can_frame c{};
  c.struct_size = sizeof c;
  c.t = t;
  c.id = f.id;
  c.len = f.dlc;
  for (int i = 0; i < f.dlc; ++i) c.data[i] = f.data[i];
  return c;
}

blvd::vehicle::Database loadToyota() {
  blvd::vehicle::Database db;
  std::string err;
  EXPECT_EQ(db.load(kToyotaDbc, err), blvd::core::Status::Ok) << err;
  return db;
}

TEST(CapiCan, DecodesToyotaFramesIntoOdometry) {
  blvd_can_profile_desc d{};
  d.struct_size = sizeof d;
  d.dbc_path = kToyotaDbc.c_str();
  ProfileHandle h;
  ASSERT_EQ(blvd_can_profile_create(&d, &h.p), BLVD_OK) << blvd_last_error(nullptr);
  const auto db = loadToyota();

  blvd_odometry odo{};
  odo.struct_size = sizeof odo;
  // Wheel speeds in km/h: 36.00 on every wheel but a faster right side (a left turn).
  blvd_can_frame f = encodeToyota(db, "WHEEL_SPEEDS",
                                  {{"WHEEL_SPEED_FL", 36.0}, {"WHEEL_SPEED_RL", 36.0}, {"WHEEL_SPEED_FR", 37.8},
                                   {"WHEEL_SPEED_RR", 37.8}},
                                  10.0);
  ASSERT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_OK);
  EXPECT_EQ(odo.flags, BLVD_ODO_SPEED | BLVD_ODO_WHEEL_SPEEDS);
  EXPECT_DOUBLE_EQ(odo.t, 10.0);
  EXPECT_NEAR(odo.wheel_speeds_mps[0], 10.0, 1e-3);
  EXPECT_NEAR(odo.wheel_speeds_mps[1], 10.5, 1e-3);
  EXPECT_NEAR(odo.speed_mps, 10.25, 1e-3);

  f = encodeToyota(db, "KINEMATICS", {{"YAW_RATE", 12.2}}, 10.01);
  ASSERT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_OK);
  EXPECT_EQ(odo.flags, BLVD_ODO_YAW_RATE);
  EXPECT_NEAR(odo.yaw_rate_dps, 12.2, 0.122);  // one step of the 0.244 deg/s factor

  f = encodeToyota(db, "GEAR_PACKET", {{"GEAR", 16}}, 10.02);  // R
  ASSERT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_OK);
  EXPECT_EQ(odo.flags, BLVD_ODO_GEAR);
  EXPECT_EQ(odo.reverse, 1);

  // Only the steering angle: nothing blvd_odometry holds.
  f = encodeToyota(db, "STEER_ANGLE_SENSOR", {{"STEER_ANGLE", 30}}, 10.03);
  odo.t = -1;
  EXPECT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_ERR_NOT_FOUND);
  EXPECT_EQ(odo.t, -1);
  // An id the profile does not read; error and RTR frames.
  blvd_can_frame other{};
  other.id = 0x123;
  other.len = 8;
  EXPECT_EQ(blvd_can_profile_decode(h.p, &other, &odo), BLVD_ERR_NOT_FOUND);
  f = encodeToyota(db, "KINEMATICS", {{"YAW_RATE", 1}}, 11);
  f.flags = BLVD_CAN_RTR;
  EXPECT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_ERR_NOT_FOUND);
}

TEST(CapiCan, RefusesBadFramesAndDescriptors) {
  blvd_can_profile* p = nullptr;
  blvd_can_profile_desc d{};
  EXPECT_EQ(blvd_can_profile_create(&d, &p), BLVD_ERR_INVALID_ARG);
  EXPECT_EQ(p, nullptr);
  EXPECT_NE(std::string(blvd_last_error(nullptr)).find("dbc_path"), std::string::npos);
  d.dbc_path = "/nonexistent/toyota.dbc";
  EXPECT_EQ(blvd_can_profile_create(&d, &p), BLVD_ERR_IO);
  EXPECT_NE(std::string(blvd_last_error(nullptr)).find("/nonexistent/toyota.dbc"), std::string::npos);
  // The Toyota DBC has none of the VW messages: each missing one is named.
  d.dbc_path = kToyotaDbc.c_str();
  d.vehicle = BLVD_VEHICLE_VW_MQB;
  EXPECT_EQ(blvd_can_profile_create(&d, &p), BLVD_ERR_NOT_FOUND);
  EXPECT_NE(std::string(blvd_last_error(nullptr)).find("ESP_19"), std::string::npos) << blvd_last_error(nullptr);
  d.vehicle = static_cast<blvd_vehicle>(7);
  EXPECT_EQ(blvd_can_profile_create(&d, &p), BLVD_ERR_INVALID_ARG);
  EXPECT_EQ(blvd_can_profile_create(nullptr, &p), BLVD_ERR_INVALID_ARG);
  blvd_can_profile_destroy(nullptr);  // no-op

  blvd_vehicle v;
  EXPECT_EQ(blvd_vehicle_from_name("hyundai", &v), BLVD_OK);
  EXPECT_EQ(v, BLVD_VEHICLE_HYUNDAI);
  EXPECT_EQ(blvd_vehicle_from_name("tesla", &v), BLVD_ERR_NOT_FOUND);

  d.vehicle = BLVD_VEHICLE_TOYOTA;
  ProfileHandle h;
  ASSERT_EQ(blvd_can_profile_create(&d, &h.p), BLVD_OK) << blvd_last_error(nullptr);
  blvd_odometry odo{};
  blvd_can_frame f{};
  f.id = 0xAA;
  f.len = 12;  // classic CAN carries at most 8
  EXPECT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_ERR_INVALID_ARG);
  f.flags = BLVD_CAN_FD;
  f.len = 13;  // not a CAN FD length
  EXPECT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_ERR_INVALID_ARG);
  f.flags = 0;
  f.len = 8;
  f.id = 0x800;  // not an 11-bit id
  EXPECT_EQ(blvd_can_profile_decode(h.p, &f, &odo), BLVD_ERR_INVALID_ARG);
  EXPECT_EQ(blvd_can_profile_decode(h.p, nullptr, &odo), BLVD_ERR_INVALID_ARG);
  EXPECT_EQ(blvd_feed_can_frame(nullptr, h.p, &f), BLVD_ERR_MISUSE);
}

// A DBC as projects ship it (the Toyota file plus a message above 0x7FF without
// the extended bit): the profile loads and says what it skipped; strict refuses it.
TEST(CapiCan, ADbcWithAMessageItCannotUseLoadsUnlessStrict) {
  const std::string path = std::string(BLVD_BINARY_DIR) + "/test_capi_can_field.dbc";
  std::string text;
  {
    std::ifstream in(kToyotaDbc, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const size_t line = size_t(std::count(text.begin(), text.end(), '\n')) + 2;
  std::ofstream(path, std::ios::binary) << text << "\nBO_ 13274 LKAS_HUD_A: 5 ADAS\n SG_ X : 7|8@0+ (1,0) [0|255] \"\" XXX\n";
  blvd_can_profile_desc d{};
  d.struct_size = sizeof d;
  d.dbc_path = path.c_str();
  ProfileHandle h;
  ASSERT_EQ(blvd_can_profile_create(&d, &h.p), BLVD_OK) << blvd_last_error(nullptr);
  ASSERT_NE(blvd_can_profile_warning(h.p, 0), nullptr);
  EXPECT_EQ(std::string(blvd_can_profile_warning(h.p, 0)),
            path + ":" + std::to_string(line) + ": message LKAS_HUD_A skipped: id 13274 exceeds 0x7FF (extended ids set bit 31)");
  EXPECT_EQ(blvd_can_profile_warning(h.p, 1), nullptr);
  EXPECT_EQ(blvd_can_profile_warning(nullptr, 0), nullptr);
  d.flags = BLVD_CAN_PROFILE_STRICT_DBC;
  blvd_can_profile* p = nullptr;
  EXPECT_EQ(blvd_can_profile_create(&d, &p), BLVD_ERR_CORRUPT);
  EXPECT_EQ(p, nullptr);
  EXPECT_NE(std::string(blvd_last_error(nullptr)).find(path + ":" + std::to_string(line) + ": message LKAS_HUD_A"),
            std::string::npos)
      << blvd_last_error(nullptr);
  d.flags = 0x80;
  EXPECT_EQ(blvd_can_profile_create(&d, &p), BLVD_ERR_INVALID_ARG);
  // Strict on a clean file loads as before.
  d.dbc_path = kToyotaDbc.c_str();
  d.flags = BLVD_CAN_PROFILE_STRICT_DBC;
  ProfileHandle clean;
  EXPECT_EQ(blvd_can_profile_create(&d, &clean.p), BLVD_OK) << blvd_last_error(nullptr);
}

// The ids a host filters its socket on: every message the Toyota profile
// decodes is listed, in id order, and a short array gets the first ones.
TEST(CapiCan, ListsTheMessagesTheProfileReads) {
  blvd_can_profile_desc d{};
  d.dbc_path = kToyotaDbc.c_str();
  ProfileHandle h;
  ASSERT_EQ(blvd_can_profile_create(&d, &h.p), BLVD_OK) << blvd_last_error(nullptr);
  uint32_t n = 0;
  ASSERT_EQ(blvd_can_profile_message_ids(h.p, nullptr, 0, &n), BLVD_OK);
  std::vector<blvd_can_message_id> ids(n + 2, blvd_can_message_id{~0u, ~0u});
  uint32_t again = 0;
  ASSERT_EQ(blvd_can_profile_message_ids(h.p, ids.data(), n + 2, &again), BLVD_OK);
  EXPECT_EQ(again, n);
  EXPECT_EQ(ids[n].id, ~0u) << "wrote past the count";
  const auto db = loadToyota();
  for (const char* name : {"WHEEL_SPEEDS", "KINEMATICS", "GEAR_PACKET", "STEER_ANGLE_SENSOR"}) {
    const blvd::vehicle::Message* m = db.findByName(name);
    ASSERT_NE(m, nullptr) << name;
    const bool listed = std::any_of(ids.begin(), ids.begin() + n, [&](const blvd_can_message_id& x) {
      return x.id == m->id && x.flags == (m->extended ? BLVD_CAN_EXTENDED : 0u);
    });
    EXPECT_TRUE(listed) << name;
  }
  for (uint32_t i = 1; i < n; ++i) EXPECT_LT(ids[i - 1].id, ids[i].id);
  std::vector<blvd_can_message_id> two(2);
  ASSERT_EQ(blvd_can_profile_message_ids(h.p, two.data(), 2, &again), BLVD_OK);
  EXPECT_EQ(again, n);
  EXPECT_EQ(two[1].id, ids[1].id);
  EXPECT_EQ(blvd_can_profile_message_ids(nullptr, nullptr, 0, &n), BLVD_ERR_MISUSE);
  EXPECT_EQ(blvd_can_profile_message_ids(h.p, nullptr, 0, nullptr), BLVD_ERR_INVALID_ARG);
  EXPECT_EQ(blvd_can_profile_message_ids(h.p, nullptr, 3, &n), BLVD_ERR_INVALID_ARG);
}

// Four threads feed the same runtime through one profile (two buses' worth of
// wheel speeds and yaw rates); the tracker dead-reckons from them: driving
// north-ish at 10 m/s for 2 s moves the pose about 20 m.
TEST(CapiCan, FeedsFromManyThreadsReachTheTracker) {
  blvd_runtime* rt = blvd::test::createTrackingRuntime();
  ASSERT_NE(rt, nullptr);
  blvd_can_profile_desc d{};
  d.dbc_path = kToyotaDbc.c_str();
  ProfileHandle h;
  ASSERT_EQ(blvd_can_profile_create(&d, &h.p), BLVD_OK) << blvd_last_error(nullptr);
  const auto db = loadToyota();
  blvd_runtime_info info{};
  info.struct_size = sizeof info;
  ASSERT_EQ(blvd_runtime_get_info(rt, &info), BLVD_OK);

  // A GNSS fix at the origin with a course, then CAN only.
  blvd_gnss_fix fix{};
  fix.struct_size = sizeof fix;
  fix.t = 0;
  fix.lat = info.origin_lat;
  fix.lon = info.origin_lon;
  fix.speed_mps = 10;
  fix.track_deg = 0;
  fix.h_acc_m = 1;
  fix.mode = BLVD_GNSS_MODE_3D;
  fix.flags = BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_SPEED | BLVD_GNSS_HAS_TRACK | BLVD_GNSS_HAS_HACC;
  ASSERT_EQ(blvd_feed_gnss(rt, &fix), BLVD_OK);
  blvd_pose p0{};
  p0.struct_size = sizeof p0;
  ASSERT_EQ(blvd_get_pose(rt, 0, &p0), BLVD_OK);

  std::vector<blvd_can_frame> frames;
  for (int k = 1; k <= 100; ++k) {
    const double t = k * 0.02;
    frames.push_back(encodeToyota(db, "WHEEL_SPEEDS",
                                  {{"WHEEL_SPEED_FL", 36}, {"WHEEL_SPEED_FR", 36}, {"WHEEL_SPEED_RL", 36},
                                   {"WHEEL_SPEED_RR", 36}},
                                  t));
    frames.push_back(encodeToyota(db, "KINEMATICS", {{"YAW_RATE", 0}}, t));
  }
  std::vector<std::thread> threads;
  std::atomic<int> bad{0};
  for (int th = 0; th < 4; ++th)
    threads.emplace_back([&, th] {
      for (size_t i = static_cast<size_t>(th); i < frames.size(); i += 4)
        if (blvd_feed_can_frame(rt, h.p, &frames[i]) != BLVD_OK) ++bad;
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(bad.load(), 0);
  blvd_pose p{};
  p.struct_size = sizeof p;
  ASSERT_EQ(blvd_get_pose(rt, 2.0, &p), BLVD_OK);
  ASSERT_TRUE(p.flags & BLVD_POSE_VALID);
  EXPECT_NEAR(p.speed_mps, 10, 0.5);
  EXPECT_NEAR(std::hypot(p.x - p0.x, p.y - p0.y), 20, 3);
  blvd_runtime_destroy(rt);
}

}  // namespace
