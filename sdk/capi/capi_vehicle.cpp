// The CAN part of the C API: vehicle profiles (sdk/vehicle) behind an opaque
// handle, and blvd_feed_can_frame(), which decodes a frame through a profile
// and queues the odometry exactly as blvd_feed_odometry() does. Design:
// docs/decisions/0005-can-profiles-in-sdk.md.
#include <algorithm>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "capi/binding.h"
#include "core/sized.h"
#include "vehicle/dbc.h"
#include "vehicle/profile.h"

namespace vehicle = blvd::vehicle;

// One vehicle's CAN decoding state. Feeds may come from several threads (two
// buses' reader threads, say), and Profile::consume keeps the latest signal
// values, so every use takes the lock; nothing in it allocates.
struct blvd_can_profile {
  std::mutex mu;
  vehicle::Database dbc;    // must outlive `profile` (it points into it): declared first
  vehicle::Profile profile;
  std::vector<blvd_can_message_id> ids;  // what the profile reads, in id order: fixed at create
};

namespace {

static_assert(BLVD_ODO_SPEED == vehicle::kOdoSpeed && BLVD_ODO_YAW_RATE == vehicle::kOdoYawRate &&
                  BLVD_ODO_WHEEL_SPEEDS == vehicle::kOdoWheelSpeeds && BLVD_ODO_GEAR == vehicle::kOdoGear,
              "the profile's odometry bits are the C API's");
constexpr uint32_t kOdoBits = BLVD_ODO_SPEED | BLVD_ODO_YAW_RATE | BLVD_ODO_WHEEL_SPEEDS | BLVD_ODO_GEAR;

blvd_status fail(blvd_status st, std::string why) {
  blvd::capi::t_create_error = std::move(why);
  return st;
}

// The C frame as the profile's Frame. BLVD_ERR_INVALID_ARG for a length or id
// that no CAN bus can carry.
blvd_status toFrame(const blvd_can_frame& in, vehicle::Frame& f) {
  const blvd_can_frame c = blvd::core::sized(in);
  f.t = c.t;
  f.extended = (c.flags & BLVD_CAN_EXTENDED) != 0;
  f.rtr = (c.flags & BLVD_CAN_RTR) != 0;
  f.error = (c.flags & BLVD_CAN_ERROR) != 0;
  f.fd = (c.flags & BLVD_CAN_FD) != 0;
  if (c.len > vehicle::kMaxFdLen || (!f.fd && c.len > vehicle::kMaxClassicLen) || (f.fd && !vehicle::isFdLength(c.len)))
    return BLVD_ERR_INVALID_ARG;
  if (!f.error && c.id > (f.extended ? vehicle::kEffMask : vehicle::kSffMask)) return BLVD_ERR_INVALID_ARG;
  f.id = c.id;
  f.dlc = c.len;
  std::memcpy(f.data, c.data, c.len);
  return BLVD_OK;
}

blvd_status decodeLocked(blvd_can_profile* p, const blvd_can_frame& frame, blvd_odometry& odo) {
  vehicle::Frame f;
  if (const blvd_status st = toFrame(frame, f); st != BLVD_OK) return st;
  vehicle::Odometry o;
  {
    std::lock_guard<std::mutex> lock(p->mu);
    if (!p->profile.consume(f, o)) return BLVD_ERR_NOT_FOUND;
  }
  const uint32_t flags = o.updated & kOdoBits;
  if (!flags) return BLVD_ERR_NOT_FOUND;  // e.g. only the steering angle
  blvd_odometry r{};
  r.struct_size = odo.struct_size && odo.struct_size < sizeof r ? odo.struct_size : sizeof r;
  r.t = o.t;
  r.speed_mps = o.speed_mps;
  r.yaw_rate_dps = o.yaw_rate_dps;
  for (int i = 0; i < 4; ++i) r.wheel_speeds_mps[i] = o.wheel_speeds_mps[i];
  r.reverse = o.gear == vehicle::Gear::Reverse;
  r.flags = flags;
  std::memcpy(&odo, &r, r.struct_size);
  return BLVD_OK;
}

// The profile's messages as the C API lists them: extended after standard, each by id.
std::vector<blvd_can_message_id> messageIds(const vehicle::Profile& profile) {
  std::vector<blvd_can_message_id> ids;
  for (const auto& [id, extended] : profile.messageIds()) ids.push_back({id, extended ? BLVD_CAN_EXTENDED : 0u});
  std::sort(ids.begin(), ids.end(), [](const blvd_can_message_id& a, const blvd_can_message_id& b) {
    return a.flags != b.flags ? a.flags < b.flags : a.id < b.id;
  });
  return ids;
}

}  // namespace

extern "C" {

blvd_status blvd_vehicle_from_name(const char* name, blvd_vehicle* out) {
  if (!name || !out) return BLVD_ERR_INVALID_ARG;
  vehicle::Vehicle v;
  if (!vehicle::parseVehicle(name, v)) return BLVD_ERR_NOT_FOUND;
  *out = static_cast<blvd_vehicle>(v);
  return BLVD_OK;
}

static_assert(static_cast<int>(vehicle::Vehicle::Toyota) == BLVD_VEHICLE_TOYOTA &&
                  static_cast<int>(vehicle::Vehicle::VwMqb) == BLVD_VEHICLE_VW_MQB &&
                  static_cast<int>(vehicle::Vehicle::Hyundai) == BLVD_VEHICLE_HYUNDAI,
              "vehicle enums");
static_assert(static_cast<int>(vehicle::SpeedSource::Auto) == BLVD_CAN_SPEED_AUTO &&
                  static_cast<int>(vehicle::SpeedSource::WheelMean) == BLVD_CAN_SPEED_WHEELS &&
                  static_cast<int>(vehicle::SpeedSource::VehicleSignal) == BLVD_CAN_SPEED_VEHICLE,
              "speed source enums");

blvd_status blvd_can_profile_create(const blvd_can_profile_desc* desc, blvd_can_profile** out) {
  if (!out) return fail(BLVD_ERR_INVALID_ARG, "blvd_can_profile_create: out is NULL");
  *out = nullptr;
  if (!desc) return fail(BLVD_ERR_INVALID_ARG, "blvd_can_profile_create: desc is NULL");
  const blvd_can_profile_desc d = blvd::core::sized(*desc);
  if (!d.dbc_path || !*d.dbc_path) return fail(BLVD_ERR_INVALID_ARG, "blvd_can_profile_create: desc.dbc_path is required");
  using blvd::core::rawEnum;
  if (rawEnum(d.vehicle) < 0 || rawEnum(d.vehicle) > BLVD_VEHICLE_HYUNDAI)
    return fail(BLVD_ERR_INVALID_ARG, "blvd_can_profile_create: unknown vehicle " + std::to_string(rawEnum(d.vehicle)));
  if (rawEnum(d.speed) < 0 || rawEnum(d.speed) > BLVD_CAN_SPEED_VEHICLE)
    return fail(BLVD_ERR_INVALID_ARG,
                "blvd_can_profile_create: unknown speed source " + std::to_string(rawEnum(d.speed)));
  if (!(d.wheel_stale_s >= 0 && d.wheel_stale_s < 3600))
    return fail(BLVD_ERR_INVALID_ARG, "blvd_can_profile_create: wheel_stale_s out of range");
  if (d.flags & ~BLVD_CAN_PROFILE_STRICT_DBC)
    return fail(BLVD_ERR_INVALID_ARG, "blvd_can_profile_create: unknown flags " + std::to_string(d.flags));
  try {
    auto p = std::make_unique<blvd_can_profile>();  // freed on every error, bad_alloc included
    std::string err;
    vehicle::DbcOptions dbc_opt;
    dbc_opt.strict = (d.flags & BLVD_CAN_PROFILE_STRICT_DBC) != 0;
    blvd::core::Status st = p->dbc.load(d.dbc_path, err, dbc_opt);
    if (st == blvd::core::Status::Ok) {
      vehicle::ProfileDesc pd;
      pd.vehicle = static_cast<vehicle::Vehicle>(d.vehicle);
      pd.speed = static_cast<vehicle::SpeedSource>(d.speed);
      pd.wheel_stale_s = d.wheel_stale_s;
      st = p->profile.create(pd, p->dbc, err);
    }
    if (st == blvd::core::Status::Ok) p->ids = messageIds(p->profile);
    if (st != blvd::core::Status::Ok) return fail(blvd::capi::toStatus(st), "blvd_can_profile_create: " + err);
    *out = p.release();
    blvd::capi::t_create_error.clear();
    return BLVD_OK;
  } catch (const std::bad_alloc&) {
    return fail(BLVD_ERR_NOMEM, "out of memory");
  } catch (...) {
    return fail(BLVD_ERR_INTERNAL, "internal error in blvd_can_profile_create");
  }
}

void blvd_can_profile_destroy(blvd_can_profile* profile) { delete profile; }

const char* blvd_can_profile_warning(const blvd_can_profile* profile, uint32_t index) {
  if (!profile || index >= profile->dbc.diagnostics().size()) return nullptr;
  return profile->dbc.diagnostics()[index].c_str();
}

blvd_status blvd_can_profile_decode(blvd_can_profile* profile, const blvd_can_frame* frame, blvd_odometry* odo) {
  if (!profile) return BLVD_ERR_MISUSE;
  if (!frame || !odo) return BLVD_ERR_INVALID_ARG;
  return decodeLocked(profile, *frame, *odo);
}

blvd_status blvd_can_profile_message_ids(const blvd_can_profile* profile, blvd_can_message_id* ids, uint32_t capacity,
                                         uint32_t* count) {
  if (!profile) return BLVD_ERR_MISUSE;
  if (!count || (!ids && capacity)) return BLVD_ERR_INVALID_ARG;
  const auto n = static_cast<uint32_t>(profile->ids.size());
  std::copy_n(profile->ids.begin(), std::min(n, capacity), ids);
  *count = n;
  return BLVD_OK;
}

blvd_status blvd_feed_can_frame(blvd_runtime* rt, blvd_can_profile* profile, const blvd_can_frame* frame) {
  if (!rt || !profile) return BLVD_ERR_MISUSE;  // no last error: feeds may run on any thread
  if (!frame) return BLVD_ERR_INVALID_ARG;
  blvd_odometry odo{};
  odo.struct_size = sizeof odo;
  const blvd_status st = decodeLocked(profile, *frame, odo);
  if (st == BLVD_ERR_NOT_FOUND) return BLVD_OK;  // nothing for the profile on this frame
  if (st != BLVD_OK) return st;
  return blvd_feed_odometry(rt, &odo);
}

}  // extern "C"
