// Vehicle profiles on frames encoded with the shared opendbc files: units,
// signs (VW's separate sign bits), gears, speed source selection, interface
// filter, and a clear error for a DBC that lacks a profile's signals.
#include <gtest/gtest.h>

#include <algorithm>

#include "can/candump.h"
#include "vehicle/dbc.h"
#include "vehicle/profile.h"
#include "can_test_util.h"

namespace blvd::can {
namespace {

// The DBC subset and the profiles are the SDK's sdk/vehicle module; the candump
// reader that feeds these tests is the adapter's.
using namespace blvd::vehicle;

Database loadDbc(const char* file) {
  Database db;
  std::string err;
  EXPECT_EQ(db.load(test::dataPath(std::string("dbc/") + file), err), blvd::core::Status::Ok) << err;
  return db;
}

Frame encoded(const Database& db, const char* message, const std::vector<std::pair<std::string, double>>& values,
              double t, const char* iface = "can0") {
  const Message* m = db.findByName(message);
  EXPECT_NE(m, nullptr) << message;
  Frame f;
  f.t = t;
  f.iface = iface;
  std::string err;
  if (m) {
    EXPECT_EQ(encode(*m, values, f, err), blvd::core::Status::Ok) << err;
  }
  return f;
}

Odometry feed(Profile& p, const Frame& f) {
  Odometry o;
  EXPECT_TRUE(p.consume(f, o));
  return o;
}

TEST(Profile, Toyota) {
  const Database db = loadDbc("toyota_new_mc_pt_generated.dbc");
  Profile p;
  std::string err;
  ASSERT_EQ(p.create(ProfileDesc{}, db, err), blvd::core::Status::Ok) << err;
  EXPECT_EQ(p.messageIds().size(), 5u);  // 0xAA 0xB4 0x24 0x25 0x3BC

  // Only the dashboard speed so far: Auto uses it.
  Odometry o = feed(p, encoded(db, "SPEED", {{"SPEED", 36.0}}, 1.0));
  EXPECT_EQ(o.updated, kOdoVehicleSpeed | kOdoSpeed);
  EXPECT_NEAR(o.speed_mps, 10.0, 1e-9);
  // Wheel speeds arrive: Auto switches to their mean.
  o = feed(p, encoded(db, "WHEEL_SPEEDS",
                      {{"WHEEL_SPEED_FL", 36.0}, {"WHEEL_SPEED_FR", 36.36}, {"WHEEL_SPEED_RL", 35.64},
                       {"WHEEL_SPEED_RR", 36.0}},
                      1.01));
  EXPECT_EQ(o.updated, kOdoWheelSpeeds | kOdoSpeed);
  EXPECT_NEAR(o.wheel_speeds_mps[0], 10.0, 1e-9);
  EXPECT_NEAR(o.wheel_speeds_mps[1], 10.1, 1e-9);
  EXPECT_NEAR(o.wheel_speeds_mps[2], 9.9, 1e-9);
  EXPECT_NEAR(o.speed_mps, 10.0, 1e-9);
  // A dashboard update while wheel speeds are fresh does not override them...
  o = feed(p, encoded(db, "SPEED", {{"SPEED", 37.0}}, 1.02));
  EXPECT_EQ(o.updated, kOdoVehicleSpeed);
  EXPECT_NEAR(o.speed_mps, 10.0, 1e-9);
  // ...but after 0.5 s without wheel speeds it does.
  o = feed(p, encoded(db, "SPEED", {{"SPEED", 37.8}}, 1.6));
  EXPECT_EQ(o.updated, kOdoVehicleSpeed | kOdoSpeed);
  EXPECT_NEAR(o.speed_mps, 10.5, 1e-9);

  // Steering: STEER_ANGLE (1.5 deg steps) + STEER_FRACTION; positive to the left.
  o = feed(p, encoded(db, "STEER_ANGLE_SENSOR", {{"STEER_ANGLE", -4.5}, {"STEER_FRACTION", -0.3}}, 1.7));
  EXPECT_EQ(o.updated, kOdoSteering);
  EXPECT_NEAR(o.steering_deg, -4.8, 1e-9);
  o = feed(p, encoded(db, "KINEMATICS", {{"YAW_RATE", 2.2}}, 1.8));
  EXPECT_EQ(o.updated, kOdoYawRate);
  EXPECT_NEAR(o.yaw_rate_dps, 2.2, 0.244 / 2);  // 0.244 deg/s steps, offset -125
  o = feed(p, encoded(db, "GEAR_PACKET", {{"GEAR", 16}}, 1.9));
  EXPECT_EQ(o.gear, Gear::Reverse);
  o = feed(p, encoded(db, "GEAR_PACKET", {{"GEAR", 32}}, 2.0));
  EXPECT_EQ(o.gear, Gear::Park);
  EXPECT_EQ(o.valid, kOdoSpeed | kOdoVehicleSpeed | kOdoYawRate | kOdoSteering | kOdoWheelSpeeds | kOdoGear);
  EXPECT_EQ(o.t, 2.0);

  // Frames the profile does not map, and remote/error frames, are not updates.
  Frame other;
  other.id = 0x123;
  other.dlc = 8;
  Odometry unchanged;
  EXPECT_FALSE(p.consume(other, unchanged));
  Frame rtr = encoded(db, "SPEED", {{"SPEED", 1}}, 3);
  rtr.rtr = true;
  EXPECT_FALSE(p.consume(rtr, unchanged));
  // A frame too short to hold the signals is not an update either.
  Frame shorty = encoded(db, "SPEED", {{"SPEED", 1}}, 3);
  shorty.dlc = 4;
  EXPECT_FALSE(p.consume(shorty, unchanged));
  p.reset();
  EXPECT_EQ(p.state().valid, 0u);
}

TEST(Profile, ToyotaSpeedSourcesAndInterfaceFilter) {
  const Database db = loadDbc("toyota_new_mc_pt_generated.dbc");
  ProfileDesc desc;
  desc.speed = SpeedSource::VehicleSignal;
  desc.iface = "can0";
  Profile p;
  std::string err;
  ASSERT_EQ(p.create(desc, db, err), blvd::core::Status::Ok) << err;
  Odometry o;
  EXPECT_FALSE(p.consume(encoded(db, "SPEED", {{"SPEED", 36.0}}, 1.0, "can1"), o));  // other bus
  o = feed(p, encoded(db, "SPEED", {{"SPEED", 36.0}}, 1.0));
  EXPECT_NEAR(o.speed_mps, 10.0, 1e-9);
  o = feed(p, encoded(db, "WHEEL_SPEEDS",
                      {{"WHEEL_SPEED_FL", 72}, {"WHEEL_SPEED_FR", 72}, {"WHEEL_SPEED_RL", 72}, {"WHEEL_SPEED_RR", 72}},
                      1.01));
  EXPECT_NEAR(o.speed_mps, 10.0, 1e-9);  // still the vehicle signal
  EXPECT_FALSE(o.updated & kOdoSpeed);

  desc.speed = SpeedSource::WheelMean;
  desc.iface.clear();
  ASSERT_EQ(p.create(desc, db, err), blvd::core::Status::Ok);
  o = feed(p, encoded(db, "SPEED", {{"SPEED", 36.0}}, 1.0, "can7"));
  EXPECT_FALSE(o.valid & kOdoSpeed);  // never from the vehicle signal
}

TEST(Profile, VwMqbSignBits) {
  const Database db = loadDbc("vw_mqb.dbc");
  ProfileDesc desc;
  desc.vehicle = Vehicle::VwMqb;
  Profile p;
  std::string err;
  ASSERT_EQ(p.create(desc, db, err), blvd::core::Status::Ok) << err;
  Odometry o = feed(p, encoded(db, "ESP_19",
                               {{"ESP_VL_Radgeschw_02", 54.0}, {"ESP_VR_Radgeschw_02", 54.0},
                                {"ESP_HL_Radgeschw_02", 53.1}, {"ESP_HR_Radgeschw_02", 54.9}},
                               1.0));
  EXPECT_NEAR(o.wheel_speeds_mps[0], 15.0, 1e-9);  // VL: vorne links, front left
  EXPECT_NEAR(o.wheel_speeds_mps[2], 14.75, 1e-9);  // HL: hinten links, rear left
  EXPECT_NEAR(o.wheel_speeds_mps[3], 15.25, 1e-9);
  EXPECT_NEAR(o.speed_mps, 15.0, 1e-9);
  o = feed(p, encoded(db, "ESP_21", {{"ESP_v_Signal", 54.72}}, 1.01));
  EXPECT_NEAR(o.vehicle_speed_mps, 15.2, 1e-9);
  o = feed(p, encoded(db, "ESP_02", {{"ESP_Gierrate", 12.34}, {"ESP_VZ_Gierrate", 0}}, 1.02));
  EXPECT_NEAR(o.yaw_rate_dps, 12.34, 1e-9);
  o = feed(p, encoded(db, "ESP_02", {{"ESP_Gierrate", 12.34}, {"ESP_VZ_Gierrate", 1}}, 1.03));
  EXPECT_NEAR(o.yaw_rate_dps, -12.34, 1e-9);
  o = feed(p, encoded(db, "LWI_01", {{"LWI_Lenkradwinkel", 90.5}, {"LWI_VZ_Lenkradwinkel", 1}}, 1.04));
  EXPECT_NEAR(o.steering_deg, -90.5, 1e-9);
  o = feed(p, encoded(db, "LWI_01", {{"LWI_Lenkradwinkel", 3.2}, {"LWI_VZ_Lenkradwinkel", 0}}, 1.05));
  EXPECT_NEAR(o.steering_deg, 3.2, 1e-9);
  o = feed(p, encoded(db, "Getriebe_11", {{"GE_Fahrstufe", 6}}, 1.06));
  EXPECT_EQ(o.gear, Gear::Reverse);
  o = feed(p, encoded(db, "Getriebe_11", {{"GE_Fahrstufe", 8}}, 1.07));
  EXPECT_EQ(o.gear, Gear::Drive);
}

TEST(Profile, Hyundai) {
  const Database db = loadDbc("hyundai_2015_ccan.dbc");
  ProfileDesc desc;
  desc.vehicle = Vehicle::Hyundai;
  Profile p;
  std::string err;
  ASSERT_EQ(p.create(desc, db, err), blvd::core::Status::Ok) << err;
  Odometry o = feed(p, encoded(db, "WHL_SPD11",
                               {{"WHL_SPD_FL", 36.0}, {"WHL_SPD_FR", 36.0}, {"WHL_SPD_RL", 36.0}, {"WHL_SPD_RR", 37.125}},
                               1.0));
  EXPECT_NEAR(o.wheel_speeds_mps[3], 37.125 / 3.6, 1e-9);
  EXPECT_NEAR(o.speed_mps, (36.0 * 3 + 37.125) / 4 / 3.6, 1e-9);
  o = feed(p, encoded(db, "ESP12", {{"YAW_RATE", -3.5}}, 1.01));
  EXPECT_NEAR(o.yaw_rate_dps, -3.5, 1e-9);
  o = feed(p, encoded(db, "SAS11", {{"SAS_Angle", -123.4}}, 1.02));
  EXPECT_NEAR(o.steering_deg, -123.4, 1e-9);
  o = feed(p, encoded(db, "CLU15",
                      {{"CF_Clu_InhibitP", 0}, {"CF_Clu_InhibitR", 1}, {"CF_Clu_InhibitN", 0}, {"CF_Clu_InhibitD", 0}},
                      1.03));
  EXPECT_EQ(o.gear, Gear::Reverse);
  o = feed(p, encoded(db, "CLU15",
                      {{"CF_Clu_InhibitP", 1}, {"CF_Clu_InhibitR", 1}, {"CF_Clu_InhibitN", 0}, {"CF_Clu_InhibitD", 0}},
                      1.04));
  EXPECT_EQ(o.gear, Gear::Unknown);  // contradictory bits
  EXPECT_FALSE(o.valid & kOdoVehicleSpeed);  // no vehicle speed signal on this profile
}

// A second, independent Toyota log (GPL-3.0: read in place from ../shared/data
// when present, never copied). It has no WHEEL_SPEEDS frames, so Auto falls back
// to the SPEED signal. SOURCES.md: SPEED 0..18.49 km/h, STEER_ANGLE -111..-75 deg.
TEST(Profile, ToyotaOnTheScionLogIfPresent) {
  const std::string path = test::sharedDataPath("can/scion_xb_mphlog.log");
  if (!test::exists(path)) GTEST_SKIP() << path << " not present";
  const Database db = loadDbc("toyota_new_mc_pt_generated.dbc");
  Profile p;
  std::string err;
  ASSERT_EQ(p.create(ProfileDesc{}, db, err), blvd::core::Status::Ok) << err;
  CandumpReader reader;
  ASSERT_EQ(reader.open(path), BLVD_OK) << reader.error();
  Record r;
  Odometry o;
  double vmax = 0, smin = 1e9, smax = -1e9;
  size_t updates = 0;
  while (reader.next(r) == CandumpReader::Result::Frame) {
    if (!p.consume(r.frame, o)) continue;
    ++updates;
    if (o.updated & kOdoSpeed) vmax = std::max(vmax, o.speed_mps);
    if (o.updated & kOdoSteering) smin = std::min(smin, o.steering_deg), smax = std::max(smax, o.steering_deg);
  }
  EXPECT_EQ(reader.badLineCount(), 0u);
  EXPECT_FALSE(o.valid & kOdoWheelSpeeds);
  EXPECT_NEAR(vmax * 3.6, 18.49, 0.005);
  EXPECT_GT(smin, -112);
  EXPECT_LT(smax, -74);
  std::printf("Scion xB: %zu updates, top speed %.2f km/h, steering %.1f..%.1f deg\n", updates, vmax * 3.6, smin,
              smax);
}

TEST(Profile, MissingSignalsAreNamed) {
  Database db;
  std::string err;
  ASSERT_EQ(db.parse("BO_ 170 WHEEL_SPEEDS: 8 X\n SG_ WHEEL_SPEED_FR : 7|16@0+ (0.01,-67.67) [0|250] \"km/h\" X\n",
                     "partial.dbc", err),
            blvd::core::Status::Ok);
  Profile p;
  EXPECT_EQ(p.create(ProfileDesc{}, db, err), blvd::core::Status::NotFound);
  EXPECT_EQ(err,
            "profile toyota: partial.dbc lacks WHEEL_SPEEDS.WHEEL_SPEED_FL, WHEEL_SPEEDS.WHEEL_SPEED_RL, "
            "WHEEL_SPEEDS.WHEEL_SPEED_RR, SPEED, KINEMATICS, STEER_ANGLE_SENSOR");
  // A DBC for another make is refused, not silently half-used.
  const Database vw = loadDbc("vw_mqb.dbc");
  EXPECT_EQ(p.create(ProfileDesc{}, vw, err), blvd::core::Status::NotFound);
  EXPECT_EQ(err, "profile toyota: " + test::dataPath("dbc/vw_mqb.dbc") +
                     " lacks WHEEL_SPEEDS, SPEED, KINEMATICS, STEER_ANGLE_SENSOR");
  Vehicle v;
  EXPECT_TRUE(parseVehicle("vw_mqb", v));
  EXPECT_EQ(v, Vehicle::VwMqb);
  EXPECT_FALSE(parseVehicle("tesla", v));
}

// encode() is consume()'s inverse on every profile: the frames it writes decode
// to the odometry it was given (to the DBC's resolution), for both signs of the
// yaw rate and steering, each gear, and a Toyota checksum opendbc accepts.
TEST(Profile, EncodeRoundTripsEveryVehicle) {
  const struct {
    Vehicle v;
    const char* dbc;
    double yaw_step, steer_step;
  } cases[] = {{Vehicle::Toyota, "toyota_new_mc_pt_generated.dbc", 0.244, 0.1},
               {Vehicle::VwMqb, "vw_mqb.dbc", 0.01, 0.1},
               {Vehicle::Hyundai, "hyundai_2015_ccan.dbc", 0.01, 0.1}};
  for (const auto& c : cases) {
    SCOPED_TRACE(vehicleName(c.v));
    const Database db = loadDbc(c.dbc);
    ProfileDesc pd;
    pd.vehicle = c.v;
    pd.speed = SpeedSource::WheelMean;
    Profile enc, dec;
    std::string err;
    ASSERT_EQ(enc.create(pd, db, err), blvd::core::Status::Ok) << err;
    ASSERT_EQ(dec.create(pd, db, err), blvd::core::Status::Ok) << err;
    for (const double sign : {1.0, -1.0})
      for (const Gear g : {Gear::Drive, Gear::Reverse, Gear::Park, Gear::Neutral}) {
        Odometry o;
        o.vehicle_speed_mps = 12.3;
        o.yaw_rate_dps = sign * 17.3;
        o.steering_deg = sign * 95.3;
        o.wheel_speeds_mps[0] = 12.0, o.wheel_speeds_mps[1] = 12.6, o.wheel_speeds_mps[2] = 12.1,
        o.wheel_speeds_mps[3] = 12.5;
        o.gear = g;
        o.valid = kOdoVehicleSpeed | kOdoYawRate | kOdoSteering | kOdoWheelSpeeds | kOdoGear;
        std::vector<Frame> frames;
        ASSERT_EQ(enc.encode(o, 4.5, frames, err), blvd::core::Status::Ok) << err;
        ASSERT_EQ(frames.size(), enc.messageIds().size());
        Odometry got;
        for (const Frame& f : frames) {
          EXPECT_EQ(f.t, 4.5);
          dec.consume(f, got);
          if (c.v == Vehicle::Toyota && f.id == 0xB4) {  // SPEED: opendbc's toyota_checksum in the last byte
            unsigned sum = 0xB4 + 0 + f.dlc;
            for (int i = 0; i + 1 < f.dlc; ++i) sum += f.data[i];
            EXPECT_EQ(f.data[f.dlc - 1], sum & 0xFF);
          }
        }
        const Odometry& s = dec.state();
        for (int w = 0; w < 4; ++w) EXPECT_NEAR(s.wheel_speeds_mps[w], o.wheel_speeds_mps[w], 0.02) << w;
        EXPECT_NEAR(s.yaw_rate_dps, o.yaw_rate_dps, c.yaw_step);
        EXPECT_NEAR(s.steering_deg, o.steering_deg, c.steer_step + 1e-9);
        if (c.v != Vehicle::Hyundai) {
          EXPECT_NEAR(s.vehicle_speed_mps, o.vehicle_speed_mps, 0.02);
        }
        EXPECT_EQ(s.gear, g);
      }
  }
}

}  // namespace
}  // namespace blvd::can
