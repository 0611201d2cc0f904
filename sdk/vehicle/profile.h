// Vehicle profiles: which DBC signals carry speed, yaw rate, steering angle,
// wheel speeds and gear on a given make, and how to turn them into one
// Odometry in SI units and one sign convention.
//
//   Toyota (opendbc toyota_new_mc_pt_generated.dbc; RAV4 2016-18, checked on comma2k19)
//     WHEEL_SPEEDS 0xAA  WHEEL_SPEED_FL/FR/RL/RR km/h
//     SPEED        0xB4  SPEED km/h (dashboard speed; reads ~2% high)
//     KINEMATICS   0x24  YAW_RATE deg/s, positive to the left (checked against the comma2k19 gyro)
//     STEER_ANGLE_SENSOR 0x25  STEER_ANGLE + STEER_FRACTION deg, positive to the left
//     GEAR_PACKET  0x3BC GEAR (0 D, 1 S, 8 N, 16 R, 32 P; optional)
//   VW MQB (opendbc vw_mqb.dbc; no log to check against)
//     ESP_19  0xB2  ESP_VL/VR/HL/HR_Radgeschw_02 km/h (VL = front left, HL = rear left)
//     ESP_21  0xFD  ESP_v_Signal km/h
//     ESP_02  0x101 ESP_Gierrate deg/s, negated when ESP_VZ_Gierrate is 1
//     LWI_01  0x86  LWI_Lenkradwinkel deg, negated when LWI_VZ_Lenkradwinkel is 1
//     Getriebe_11 0xAD GE_Fahrstufe (5 P, 6 R, 7 N, 8 D, 9 S, 10 E, 13/14 T; optional)
//   Hyundai / Kia (opendbc hyundai_2015_ccan.dbc; no log to check against)
//     WHL_SPD11 0x386 WHL_SPD_FL/FR/RL/RR km/h
//     ESP12     0x220 YAW_RATE deg/s
//     SAS11     0x2B0 SAS_Angle deg
//     CLU15     0x52A CF_Clu_InhibitP/R/N/D (gear lever position bits; optional)
//     (no vehicle speed signal is mapped: speed is the mean of the wheel speeds)
//
// The VW sign bits and the Hyundai signs follow openpilot's car ports (steering
// and yaw positive to the left); they have not been checked against a recording.
//
// Conventions of Odometry: speeds in m/s and never signed by direction (use
// gear == Reverse); yaw rate in deg/s, positive counterclockwise seen from above
// (a left turn; ISO 8855, z up), so a compass heading changes at -yaw_rate_dps;
// steering wheel angle in degrees, positive to the left.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/status.h"
#include "vehicle/dbc.h"
#include "vehicle/frame.h"

namespace blvd::vehicle {

enum class Gear : uint8_t { Unknown = 0, Park, Reverse, Neutral, Drive, Sport };
const char* gearName(Gear g);

// Bits of Odometry::valid and Odometry::updated.
enum OdometryField : uint32_t {
  kOdoSpeed = 1u << 0,         // speed_mps
  kOdoVehicleSpeed = 1u << 1,  // vehicle_speed_mps
  kOdoYawRate = 1u << 2,
  kOdoSteering = 1u << 3,
  kOdoWheelSpeeds = 1u << 4,   // all four
  kOdoGear = 1u << 5,
};

struct Odometry {
  double t = 0;                      // time of the frame that produced this state
  double speed_mps = 0;              // ground speed from the source ProfileDesc::speed selects
  double vehicle_speed_mps = 0;      // the car's own speed signal, when the profile has one
  double yaw_rate_dps = 0;           // positive to the left (counterclockwise from above)
  double steering_deg = 0;           // steering wheel angle, positive to the left
  double wheel_speeds_mps[4] = {};   // front left, front right, rear left, rear right
  Gear gear = Gear::Unknown;
  uint32_t valid = 0;    // OdometryField bits received at least once since create()/reset()
  uint32_t updated = 0;  // OdometryField bits the last consumed frame changed
};

enum class Vehicle : uint8_t { Toyota, VwMqb, Hyundai };
const char* vehicleName(Vehicle v);                     // "toyota", "vw_mqb", "hyundai"
bool parseVehicle(std::string_view name, Vehicle& out);  // accepts those names

enum class SpeedSource : uint8_t {
  Auto,           // the mean of the four wheel speeds while they are fresh, else the vehicle speed signal
  WheelMean,      // only the wheel speeds (what openpilot uses as vEgoRaw)
  VehicleSignal,  // only the vehicle speed signal
};

// Zero-initialised (value-initialised) means: Toyota, Auto, 0.5 s, every interface.
struct ProfileDesc {
  Vehicle vehicle = Vehicle::Toyota;
  SpeedSource speed = SpeedSource::Auto;
  double wheel_stale_s = 0;  // Auto falls back to the vehicle speed after this long without wheel speeds; 0: 0.5 s
  std::string iface;         // only frames from this interface (e.g. the powertrain bus); empty: all
};

class Profile {
 public:
  // Binds the profile's signals in `dbc`, which must outlive the profile.
  // core::Status::NotFound with `err` naming each missing message/signal when a
  // required one is absent (the gear signals are optional).
  core::Status create(const ProfileDesc& desc, const Database& dbc, std::string& err);

  // Feeds one frame. Returns true when it carried a mapped signal; `out` is then
  // the whole state after it, with `updated` saying what changed. Not thread-safe.
  bool consume(const Frame& f, Odometry& out);

  const Odometry& state() const { return state_; }
  // Forgets every value (valid = 0), keeping the bindings.
  void reset();
  // The inverse of consume(), for simulators and tests: writes `o` (the fields
  // set in o.valid; the others as zero) into one frame per message the profile
  // reads, in id order, stamped `t`. consume() of those frames gives `o` back to
  // the DBC's resolution. Toyota messages with a CHECKSUM signal get Toyota's
  // checksum. core::Status::InvalidArg with `err` naming the signal when a value does
  // not fit it.
  core::Status encode(const Odometry& o, double t, std::vector<Frame>& out, std::string& err) const;
  // (id, extended) of every message the profile reads, e.g. for SocketCAN filters.
  std::vector<std::pair<uint32_t, bool>> messageIds() const;

 // What a mapped signal feeds (used by the profile tables in profile.cpp).
  enum Target : uint8_t { VehicleSpeed, YawRate, Steering, WheelFL, WheelFR, WheelRL, WheelRR, GearCode, GearP, GearR,
                          GearN, GearD };

 private:
  struct Item {
    Target target;
    const Signal* signal;
    const Signal* add;   // added to the value (Toyota STEER_FRACTION)
    const Signal* sign;  // negates the value when its raw bits are non-zero (VW ..._VZ_...)
    double divisor;      // km/h -> m/s: 3.6
  };
  struct Bound {
    const Message* message;
    std::vector<Item> items;
  };

  ProfileDesc desc_;
  std::unordered_map<uint32_t, Bound> bound_;
  Odometry state_;
  double wheel_t_ = 0;
};

}  // namespace blvd::vehicle
