#include "vehicle/profile.h"

#include <algorithm>
#include <cmath>

namespace blvd::vehicle {
namespace {

constexpr double kKmh = 3.6;  // km/h per m/s

// One mapped value in a profile's table.
struct Spec {
  Profile::Target target;
  const char* message;
  const char* signal;
  const char* add;      // or nullptr
  const char* sign;     // or nullptr
  double divisor;
  bool required;
};

using T = Profile::Target;

const Spec kToyota[] = {
    {T::WheelFL, "WHEEL_SPEEDS", "WHEEL_SPEED_FL", nullptr, nullptr, kKmh, true},
    {T::WheelFR, "WHEEL_SPEEDS", "WHEEL_SPEED_FR", nullptr, nullptr, kKmh, true},
    {T::WheelRL, "WHEEL_SPEEDS", "WHEEL_SPEED_RL", nullptr, nullptr, kKmh, true},
    {T::WheelRR, "WHEEL_SPEEDS", "WHEEL_SPEED_RR", nullptr, nullptr, kKmh, true},
    {T::VehicleSpeed, "SPEED", "SPEED", nullptr, nullptr, kKmh, true},
    {T::YawRate, "KINEMATICS", "YAW_RATE", nullptr, nullptr, 1, true},
    {T::Steering, "STEER_ANGLE_SENSOR", "STEER_ANGLE", "STEER_FRACTION", nullptr, 1, true},
    {T::GearCode, "GEAR_PACKET", "GEAR", nullptr, nullptr, 1, false},
};

const Spec kVwMqb[] = {
    {T::WheelFL, "ESP_19", "ESP_VL_Radgeschw_02", nullptr, nullptr, kKmh, true},
    {T::WheelFR, "ESP_19", "ESP_VR_Radgeschw_02", nullptr, nullptr, kKmh, true},
    {T::WheelRL, "ESP_19", "ESP_HL_Radgeschw_02", nullptr, nullptr, kKmh, true},
    {T::WheelRR, "ESP_19", "ESP_HR_Radgeschw_02", nullptr, nullptr, kKmh, true},
    {T::VehicleSpeed, "ESP_21", "ESP_v_Signal", nullptr, nullptr, kKmh, true},
    {T::YawRate, "ESP_02", "ESP_Gierrate", nullptr, "ESP_VZ_Gierrate", 1, true},
    {T::Steering, "LWI_01", "LWI_Lenkradwinkel", nullptr, "LWI_VZ_Lenkradwinkel", 1, true},
    {T::GearCode, "Getriebe_11", "GE_Fahrstufe", nullptr, nullptr, 1, false},
};

const Spec kHyundai[] = {
    {T::WheelFL, "WHL_SPD11", "WHL_SPD_FL", nullptr, nullptr, kKmh, true},
    {T::WheelFR, "WHL_SPD11", "WHL_SPD_FR", nullptr, nullptr, kKmh, true},
    {T::WheelRL, "WHL_SPD11", "WHL_SPD_RL", nullptr, nullptr, kKmh, true},
    {T::WheelRR, "WHL_SPD11", "WHL_SPD_RR", nullptr, nullptr, kKmh, true},
    {T::YawRate, "ESP12", "YAW_RATE", nullptr, nullptr, 1, true},
    {T::Steering, "SAS11", "SAS_Angle", nullptr, nullptr, 1, true},
    {T::GearP, "CLU15", "CF_Clu_InhibitP", nullptr, nullptr, 1, false},
    {T::GearR, "CLU15", "CF_Clu_InhibitR", nullptr, nullptr, 1, false},
    {T::GearN, "CLU15", "CF_Clu_InhibitN", nullptr, nullptr, 1, false},
    {T::GearD, "CLU15", "CF_Clu_InhibitD", nullptr, nullptr, 1, false},
};

uint32_t key(uint32_t id, bool extended) { return id | (extended ? 0x80000000u : 0u); }

Gear toyotaGear(int64_t v) {
  switch (v) {  // VAL_ 956 GEAR 0 "D" 1 "S" 8 "N" 16 "R" 32 "P"
    case 0: return Gear::Drive;
    case 1: return Gear::Sport;
    case 8: return Gear::Neutral;
    case 16: return Gear::Reverse;
    case 32: return Gear::Park;
    default: return Gear::Unknown;
  }
}

Gear vwGear(int64_t v) {
  switch (v) {  // VAL_ 173 GE_Fahrstufe 5 "P" 6 "R" 7 "N" 8 "D" 9 "S" 10 "E" 13 "T" 14 "T"
    case 5: return Gear::Park;
    case 6: return Gear::Reverse;
    case 7: return Gear::Neutral;
    case 8: return Gear::Drive;
    case 9: return Gear::Sport;
    case 10:  // E: eco drive
    case 13:  // T: tiptronic (manual gate), forward
    case 14: return Gear::Drive;
    default: return Gear::Unknown;
  }
}

int toyotaGearCode(Gear g) {
  switch (g) {
    case Gear::Drive: return 0;
    case Gear::Sport: return 1;
    case Gear::Neutral: return 8;
    case Gear::Reverse: return 16;
    case Gear::Park: return 32;
    default: return -1;
  }
}

int vwGearCode(Gear g) {
  switch (g) {
    case Gear::Park: return 5;
    case Gear::Reverse: return 6;
    case Gear::Neutral: return 7;
    case Gear::Drive: return 8;
    case Gear::Sport: return 9;
    default: return -1;
  }
}

// opendbc's toyota_checksum: the id's bytes, the length and every payload byte
// but the last, summed modulo 256.
uint8_t toyotaChecksum(const Frame& f) {
  unsigned sum = (f.id & 0xFFu) + ((f.id >> 8) & 0xFFu) + f.dlc;
  for (unsigned i = 0; i + 1 < f.dlc; ++i) sum += f.data[i];
  return static_cast<uint8_t>(sum & 0xFFu);
}

}  // namespace

const char* gearName(Gear g) {
  switch (g) {
    case Gear::Park: return "P";
    case Gear::Reverse: return "R";
    case Gear::Neutral: return "N";
    case Gear::Drive: return "D";
    case Gear::Sport: return "S";
    default: return "unknown";
  }
}

const char* vehicleName(Vehicle v) {
  switch (v) {
    case Vehicle::Toyota: return "toyota";
    case Vehicle::VwMqb: return "vw_mqb";
    case Vehicle::Hyundai: return "hyundai";
  }
  return "unknown";
}

bool parseVehicle(std::string_view name, Vehicle& out) {
  for (Vehicle v : {Vehicle::Toyota, Vehicle::VwMqb, Vehicle::Hyundai})
    if (name == vehicleName(v)) {
      out = v;
      return true;
    }
  return false;
}

core::Status Profile::create(const ProfileDesc& desc, const Database& dbc, std::string& err) {
  desc_ = desc;
  if (!(desc_.wheel_stale_s > 0)) desc_.wheel_stale_s = 0.5;
  bound_.clear();
  reset();
  const Spec* begin = nullptr;
  size_t n = 0;
  switch (desc.vehicle) {
    case Vehicle::Toyota: begin = kToyota, n = std::size(kToyota); break;
    case Vehicle::VwMqb: begin = kVwMqb, n = std::size(kVwMqb); break;
    case Vehicle::Hyundai: begin = kHyundai, n = std::size(kHyundai); break;
  }
  std::vector<std::string> missing;  // each named once
  const auto noteMissing = [&](std::string what) {
    if (std::find(missing.begin(), missing.end(), what) == missing.end()) missing.push_back(std::move(what));
  };
  const auto lookup = [&](const Message* m, const char* name, bool required) -> const Signal* {
    if (!name || !m) return nullptr;
    const Signal* s = m->signal(name);
    const bool usable = s && s->supported && s->multiplex_value < 0;  // a profile reads plain signals
    if (!usable && required)
      noteMissing(m->name + "." + name + (!s ? "" : s->supported ? " (multiplexed)" : " (unsupported)"));
    return usable ? s : nullptr;
  };
  for (const Spec* s = begin; s != begin + n; ++s) {
    const Message* m = dbc.findByName(s->message);
    if (!m) {
      if (s->required) noteMissing(s->message);
      continue;
    }
    Item it{s->target, lookup(m, s->signal, s->required), lookup(m, s->add, s->required),
            lookup(m, s->sign, s->required), s->divisor};
    if (!it.signal || (s->add && !it.add) || (s->sign && !it.sign)) continue;
    Bound& b = bound_[key(m->id, m->extended)];
    b.message = m;
    b.items.push_back(it);
  }
  if (!missing.empty()) {
    err = std::string("profile ") + vehicleName(desc.vehicle) + ": " + dbc.source() + " lacks ";
    for (size_t i = 0; i < missing.size(); ++i) err += (i ? ", " : "") + missing[i];
    bound_.clear();
    return core::Status::NotFound;
  }
  return core::Status::Ok;
}

void Profile::reset() {
  state_ = Odometry{};
  wheel_t_ = 0;
}

std::vector<std::pair<uint32_t, bool>> Profile::messageIds() const {
  std::vector<std::pair<uint32_t, bool>> ids;
  for (const auto& [k, b] : bound_) ids.emplace_back(b.message->id, b.message->extended);
  return ids;
}

core::Status Profile::encode(const Odometry& o, double t, std::vector<Frame>& out, std::string& err) const {
  std::vector<const Bound*> msgs;
  for (const auto& [k, b] : bound_) msgs.push_back(&b);
  std::sort(msgs.begin(), msgs.end(), [](const Bound* a, const Bound* b) {
    return std::make_pair(a->message->extended, a->message->id) < std::make_pair(b->message->extended, b->message->id);
  });
  const auto put = [&](const Signal& s, double value, Frame& f) {
    uint64_t raw = 0;
    if (!toRaw(s, value, raw)) {
      err = "profile " + std::string(vehicleName(desc_.vehicle)) + ": signal " + s.name + ": value " +
            std::to_string(value) + " does not fit";
      return false;
    }
    insertRaw(s, raw, f.data);
    return true;
  };
  const auto has = [&](uint32_t bit) { return (o.valid & bit) != 0; };
  for (const Bound* b : msgs) {
    Frame f;
    f.t = t;
    f.id = b->message->id;
    f.extended = b->message->extended;
    f.dlc = static_cast<uint8_t>(std::min<uint32_t>(b->message->size, kMaxFdLen));
    f.fd = f.dlc > kMaxClassicLen;
    for (const Item& it : b->items) {
      double v = 0;
      bool gear_code = false;
      switch (it.target) {
        case VehicleSpeed: v = has(kOdoVehicleSpeed) ? o.vehicle_speed_mps : 0; break;
        case YawRate: v = has(kOdoYawRate) ? o.yaw_rate_dps : 0; break;
        case Steering: v = has(kOdoSteering) ? o.steering_deg : 0; break;
        case WheelFL:
        case WheelFR:
        case WheelRL:
        case WheelRR: v = has(kOdoWheelSpeeds) ? o.wheel_speeds_mps[it.target - WheelFL] : 0; break;
        case GearCode: {
          const int code = desc_.vehicle == Vehicle::VwMqb ? vwGearCode(o.gear) : toyotaGearCode(o.gear);
          if (!has(kOdoGear) || code < 0) continue;  // no value to send: the bits stay 0
          v = code;
          gear_code = true;
          break;
        }
        case GearP: v = has(kOdoGear) && o.gear == Gear::Park; break;
        case GearR: v = has(kOdoGear) && o.gear == Gear::Reverse; break;
        case GearN: v = has(kOdoGear) && o.gear == Gear::Neutral; break;
        case GearD: v = has(kOdoGear) && (o.gear == Gear::Drive || o.gear == Gear::Sport); break;
      }
      if (!gear_code) v *= it.divisor;
      if (it.sign) {  // magnitude plus a sign bit (VW)
        if (!put(*it.sign, v < 0 ? 1 : 0, f)) return core::Status::InvalidArg;
        v = std::fabs(v);
      }
      if (it.add) {  // coarse signal plus a fine one (Toyota STEER_ANGLE + STEER_FRACTION)
        uint64_t raw = 0;
        if (!toRaw(*it.signal, v, raw)) return put(*it.signal, v, f), core::Status::InvalidArg;
        insertRaw(*it.signal, raw, f.data);
        const double rest = v - toPhysical(*it.signal, raw);
        if (!put(*it.add, rest, f)) return core::Status::InvalidArg;
        continue;
      }
      if (!put(*it.signal, v, f)) return core::Status::InvalidArg;
    }
    if (desc_.vehicle == Vehicle::Toyota)
      if (const Signal* cs = b->message->signal("CHECKSUM"); cs && cs->supported && cs->bytes_needed <= f.dlc)
        insertRaw(*cs, toyotaChecksum(f), f.data);
    out.push_back(f);
  }
  return core::Status::Ok;
}

bool Profile::consume(const Frame& f, Odometry& out) {
  if (f.error || f.rtr) return false;
  if (!desc_.iface.empty() && f.iface != desc_.iface) return false;
  const auto found = bound_.find(key(f.id, f.extended));
  if (found == bound_.end()) return false;
  Odometry& s = state_;
  s.updated = 0;
  double wheels[4];
  int wheel_count = 0;
  int gear_bits[4] = {-1, -1, -1, -1};  // P R N D (Hyundai)
  for (const Item& it : found->second.items) {
    if (it.signal->bytes_needed > f.dlc || (it.add && it.add->bytes_needed > f.dlc) ||
        (it.sign && it.sign->bytes_needed > f.dlc))
      continue;  // a short frame: this signal is not in it
    const uint64_t raw = extractRaw(*it.signal, f.data);
    double v = toPhysical(*it.signal, raw);
    if (it.add) v += toPhysical(*it.add, extractRaw(*it.add, f.data));
    if (it.sign && extractRaw(*it.sign, f.data) != 0) v = -v;
    v /= it.divisor;
    switch (it.target) {
      case VehicleSpeed:
        s.vehicle_speed_mps = v;
        s.updated |= kOdoVehicleSpeed;
        break;
      case YawRate:
        s.yaw_rate_dps = v;
        s.updated |= kOdoYawRate;
        break;
      case Steering:
        s.steering_deg = v;
        s.updated |= kOdoSteering;
        break;
      case WheelFL:
      case WheelFR:
      case WheelRL:
      case WheelRR:
        wheels[it.target - WheelFL] = v;
        ++wheel_count;
        break;
      case GearCode: {
        const int64_t code = static_cast<int64_t>(raw);
        const Gear g = desc_.vehicle == Vehicle::VwMqb ? vwGear(code) : toyotaGear(code);
        s.gear = g;
        s.updated |= kOdoGear;
        break;
      }
      case GearP:
      case GearR:
      case GearN:
      case GearD: gear_bits[it.target - GearP] = raw != 0; break;
    }
  }
  if (wheel_count == 4) {  // all four come in one message on every profile
    for (int i = 0; i < 4; ++i) s.wheel_speeds_mps[i] = wheels[i];
    s.updated |= kOdoWheelSpeeds;
    wheel_t_ = f.t;
  }
  if (gear_bits[0] >= 0 && gear_bits[1] >= 0 && gear_bits[2] >= 0 && gear_bits[3] >= 0) {
    const int set = gear_bits[0] + gear_bits[1] + gear_bits[2] + gear_bits[3];
    static constexpr Gear kPrnd[] = {Gear::Park, Gear::Reverse, Gear::Neutral, Gear::Drive};
    Gear g = Gear::Unknown;
    if (set == 1)
      for (int i = 0; i < 4; ++i)
        if (gear_bits[i]) g = kPrnd[i];
    s.gear = g;
    s.updated |= kOdoGear;
  }
  s.valid |= s.updated;

  // Ground speed from the selected source.
  const bool wheels_fresh = (s.valid & kOdoWheelSpeeds) && f.t - wheel_t_ <= desc_.wheel_stale_s;
  const bool use_wheels = desc_.speed == SpeedSource::WheelMean ||
                          (desc_.speed == SpeedSource::Auto && (wheels_fresh || !(s.valid & kOdoVehicleSpeed)));
  if (use_wheels && (s.updated & kOdoWheelSpeeds)) {
    s.speed_mps = (s.wheel_speeds_mps[0] + s.wheel_speeds_mps[1] + s.wheel_speeds_mps[2] + s.wheel_speeds_mps[3]) / 4;
    s.updated |= kOdoSpeed;
  } else if (!use_wheels && (s.updated & kOdoVehicleSpeed)) {
    s.speed_mps = s.vehicle_speed_mps;
    s.updated |= kOdoSpeed;
  }
  s.valid |= s.updated;
  if (!s.updated) return false;
  s.t = f.t;
  out = s;
  return true;
}

}  // namespace blvd::vehicle
