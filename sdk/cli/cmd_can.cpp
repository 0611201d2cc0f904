// `blvd can ...`: inspect candump logs with a DBC.
//
//   blvd can decode LOG --dbc DBC [--json] [--strict] [--iface can0] [-o FILE]
//     one line per frame whose id the DBC knows; with --json one object per line:
//     {"t":46408.584959,"id":37,"iface":"can0","name":"STEER_ANGLE_SENSOR","signals":{"STEER_ANGLE":0,...},
//      "named":{"GEAR":"P"}}
//     ("extended":true follows "id" for 29-bit ids; t is the log's timestamp text, exactly; "named" holds
//     the VAL_ description of each signal whose value has one, and is left out when none has)
//   blvd can odometry LOG --dbc DBC --vehicle toyota|vw_mqb|hyundai [--json] [--strict] [--iface can0] [-o FILE]
//     one line per Odometry update of the vehicle profile.
//
// A DBC message the decoder cannot use is skipped with a warning on stderr
// ("DBC:LINE: message X skipped: reason"); --strict makes it fail the command.
//
// Frames with ids the DBC lacks are skipped and counted; the counts go to stderr
// at the end. Bad log lines are reported as "LOG:LINE: reason" on stderr and
// skipped; the exit status is then 1 (2 when the DBC or the log cannot be read).
// This file uses only the adapter and the CLI hook, like any host program could.
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "can/candump.h"
#include "vehicle/dbc.h"
#include "vehicle/profile.h"
#include "cli/commands.h"

namespace blvd::cli {
namespace {

struct CanOptions {
  std::string log, dbc, iface, output, vehicle = "toyota", speed = "auto";
  bool json = false, strict = false;
};

// Buffered output to stdout or a file.
class Out {
 public:
  bool open(const std::string& path) {
    if (path.empty() || path == "-") return true;
    f_ = std::fopen(path.c_str(), "wb");
    return f_ != nullptr;
  }
  ~Out() {
    if (f_ && f_ != stdout) std::fclose(f_);
  }
  void put(const std::string& s) { std::fwrite(s.data(), 1, s.size(), f_); }
  bool finish() { return std::fflush(f_) == 0 && !std::ferror(f_); }

 private:
  std::FILE* f_ = stdout;
};

// Shortest text that reads back as the same double; JSON has no NaN or infinity.
void putNumber(std::string& s, double v, bool json) {
  if (!std::isfinite(v)) {
    s += json ? "null" : (std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf"));
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s.append(buf, r.ptr);
}

void putJsonString(std::string& s, const std::string& v) {
  s.push_back('"');
  for (const char ch : v) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      s.push_back('\\');
      s.push_back(ch);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      s += buf;
    } else {
      s.push_back(ch);
    }
  }
  s.push_back('"');
}

// ,"named":{"SIGNAL":"description",...} for the signals whose raw value VAL_ describes; nothing when none.
void putNamed(std::string& s, const std::vector<vehicle::DecodedSignal>& sig) {
  bool any = false;
  for (const auto& d : sig) {
    const std::string* text = d.signal->describe(static_cast<int64_t>(d.raw));
    if (!text) continue;
    s += any ? "," : ",\"named\":{";
    any = true;
    putJsonString(s, d.signal->name);
    s.push_back(':');
    putJsonString(s, *text);
  }
  if (any) s.push_back('}');
}

// The timestamp exactly as the log wrote it.
void putTime(std::string& s, const can::Record& r) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%" PRId64 ".%0*u", r.sec, static_cast<int>(r.frac_digits), r.frac);
  s += buf;
}

bool openInputs(const CanOptions& o, vehicle::Database& db, can::CandumpReader& reader, Out& out, int& code) {
  std::string err;
  vehicle::DbcOptions opt;
  opt.strict = o.strict;
  if (db.load(o.dbc, err, opt) != core::Status::Ok) {
    std::fprintf(stderr, "blvd can: %s\n", err.c_str());
    code = 2;
    return false;
  }
  for (const auto& d : db.diagnostics()) std::fprintf(stderr, "blvd can: warning: %s\n", d.c_str());
  if (o.log == "-") {
    reader.attach(std::cin, "<stdin>");
  } else if (reader.open(o.log) != BLVD_OK) {
    std::fprintf(stderr, "blvd can: %s\n", reader.error().c_str());
    code = 2;
    return false;
  }
  if (!out.open(o.output)) {
    std::fprintf(stderr, "blvd can: %s: cannot create\n", o.output.c_str());
    code = 2;
    return false;
  }
  return true;
}

int decodeLog(const CanOptions& o) {
  vehicle::Database db;
  can::CandumpReader reader;
  Out out;
  int code = 0;
  if (!openInputs(o, db, reader, out, code)) return code;
  can::Record rec;
  std::vector<vehicle::DecodedSignal> sig;
  uint64_t decoded = 0, unknown = 0, other_iface = 0, special = 0;
  std::string line;
  for (;;) {
    const auto r = reader.next(rec);
    if (r == can::CandumpReader::Result::End) break;
    if (r == can::CandumpReader::Result::IoError) {
      std::fprintf(stderr, "blvd can: %s\n", reader.error().c_str());
      return 2;
    }
    if (r == can::CandumpReader::Result::BadLine) {
      std::fprintf(stderr, "blvd can: %s\n", reader.error().c_str());
      continue;
    }
    const can::Frame& f = rec.frame;
    if (!o.iface.empty() && f.iface != o.iface) {
      ++other_iface;
      continue;
    }
    if (f.error || f.rtr) {
      ++special;
      continue;
    }
    const vehicle::Message* m = db.find(f);
    if (!m) {
      ++unknown;
      continue;
    }
    vehicle::decode(*m, f, sig);
    ++decoded;
    line.clear();
    if (o.json) {
      line += "{\"t\":";
      putTime(line, rec);
      line += ",\"id\":" + std::to_string(f.id);
      if (f.extended) line += ",\"extended\":true";
      line += ",\"iface\":";
      putJsonString(line, f.iface);
      line += ",\"name\":";
      putJsonString(line, m->name);
      line += ",\"signals\":{";
      for (size_t i = 0; i < sig.size(); ++i) {
        if (i) line.push_back(',');
        putJsonString(line, sig[i].signal->name);
        line.push_back(':');
        putNumber(line, sig[i].value, true);
      }
      line.push_back('}');
      putNamed(line, sig);
      line += "}\n";
    } else {
      putTime(line, rec);
      line += " " + f.iface + " " + can::formatFrame(f) + " " + m->name;
      for (const auto& s : sig) {
        line += " " + s.signal->name + "=";
        putNumber(line, s.value, false);
        if (!s.signal->unit.empty()) line += " " + s.signal->unit;
        if (const std::string* d = s.signal->describe(static_cast<int64_t>(s.raw))) line += " (" + *d + ")";
      }
      line.push_back('\n');
    }
    out.put(line);
  }
  if (!out.finish()) {
    std::fprintf(stderr, "blvd can: write error\n");
    return 2;
  }
  std::fprintf(stderr,
               "blvd can decode: %" PRIu64 " frames read, %" PRIu64 " decoded, %" PRIu64
               " skipped (id not in %s), %" PRIu64 " error/remote frames, %" PRIu64 " on other interfaces, %" PRIu64
               " bad lines\n",
               reader.frameCount(), decoded, unknown, o.dbc.c_str(), special, other_iface, reader.badLineCount());
  return reader.badLineCount() ? 1 : 0;
}

int odometryLog(const CanOptions& o) {
  vehicle::ProfileDesc desc;
  if (!vehicle::parseVehicle(o.vehicle, desc.vehicle)) {
    std::fprintf(stderr, "blvd can odometry: unknown vehicle '%s' (toyota, vw_mqb, hyundai)\n", o.vehicle.c_str());
    return 2;
  }
  desc.speed = o.speed == "wheels" ? vehicle::SpeedSource::WheelMean
               : o.speed == "vehicle" ? vehicle::SpeedSource::VehicleSignal
                                      : vehicle::SpeedSource::Auto;
  desc.iface = o.iface;
  vehicle::Database db;
  can::CandumpReader reader;
  Out out;
  int code = 0;
  if (!openInputs(o, db, reader, out, code)) return code;
  vehicle::Profile profile;
  std::string err;
  if (profile.create(desc, db, err) != core::Status::Ok) {
    std::fprintf(stderr, "blvd can odometry: %s\n", err.c_str());
    return 2;
  }
  can::Record rec;
  vehicle::Odometry odo;
  uint64_t updates = 0;
  std::string line;
  for (;;) {
    const auto r = reader.next(rec);
    if (r == can::CandumpReader::Result::End) break;
    if (r != can::CandumpReader::Result::Frame) {
      std::fprintf(stderr, "blvd can: %s\n", reader.error().c_str());
      if (r == can::CandumpReader::Result::IoError) return 2;
      continue;
    }
    if (!profile.consume(rec.frame, odo)) continue;
    ++updates;
    line.clear();
    const bool j = o.json;
    const auto field = [&](const char* name, double v, uint32_t bit) {
      if (!(odo.valid & bit)) return;
      line += j ? ",\"" : " ";
      line += name;
      line += j ? "\":" : "=";
      putNumber(line, v, j);
    };
    line += j ? "{\"t\":" : "";
    putTime(line, rec);
    field("speed_mps", odo.speed_mps, vehicle::kOdoSpeed);
    field("vehicle_speed_mps", odo.vehicle_speed_mps, vehicle::kOdoVehicleSpeed);
    field("yaw_rate_dps", odo.yaw_rate_dps, vehicle::kOdoYawRate);
    field("steering_deg", odo.steering_deg, vehicle::kOdoSteering);
    if (odo.valid & vehicle::kOdoWheelSpeeds) {
      line += j ? ",\"wheel_speeds_mps\":[" : " wheel_speeds_mps=";
      for (int i = 0; i < 4; ++i) {
        if (i) line.push_back(',');
        putNumber(line, odo.wheel_speeds_mps[i], j);
      }
      if (j) line.push_back(']');
    }
    if (odo.valid & vehicle::kOdoGear) {
      line += j ? ",\"gear\":\"" : " gear=";
      line += vehicle::gearName(odo.gear);
      if (j) line.push_back('"');
    }
    line += j ? "}\n" : "\n";
    out.put(line);
  }
  if (!out.finish()) {
    std::fprintf(stderr, "blvd can: write error\n");
    return 2;
  }
  std::fprintf(stderr, "blvd can odometry: %" PRIu64 " frames read, %" PRIu64 " updates, %" PRIu64 " bad lines\n",
               reader.frameCount(), updates, reader.badLineCount());
  return reader.badLineCount() ? 1 : 0;
}

}  // namespace

void addCan(CLI::App& app, Runner& run) {
  auto* can = app.add_subcommand("can", "decode candump logs with a DBC, or turn them into odometry");
  can->require_subcommand(1);
  auto o = std::make_shared<CanOptions>();

  auto* dec = can->add_subcommand("decode", "print the DBC signals of every frame whose id the DBC knows");
  dec->add_option("log", o->log, "candump -l log ('-' for stdin)")->required();
  dec->add_option("--dbc", o->dbc, "DBC file")->required();
  dec->add_flag("--json", o->json, "one JSON object per line: t, id, iface, name, signals, named");
  dec->add_flag("--strict", o->strict, "fail on a DBC message the decoder cannot use instead of skipping it");
  dec->add_option("--iface", o->iface, "only frames from this interface (e.g. can0)");
  dec->add_option("-o,--output", o->output, "write to this file instead of stdout");
  dec->callback([&run, o] { run = [o] { return decodeLog(*o); }; });

  auto* odo = can->add_subcommand("odometry", "print the vehicle profile's odometry updates");
  odo->add_option("log", o->log, "candump -l log ('-' for stdin)")->required();
  odo->add_option("--dbc", o->dbc, "DBC file")->required();
  odo->add_option("--vehicle", o->vehicle, "toyota, vw_mqb or hyundai")->capture_default_str();
  odo->add_option("--speed", o->speed, "speed source: auto, wheels or vehicle")->capture_default_str();
  odo->add_flag("--json", o->json, "one JSON object per line");
  odo->add_flag("--strict", o->strict, "fail on a DBC message the decoder cannot use instead of skipping it");
  odo->add_option("--iface", o->iface, "only frames from this interface (e.g. can0)");
  odo->add_option("-o,--output", o->output, "write to this file instead of stdout");
  odo->callback([&run, o] { run = [o] { return odometryLog(*o); }; });
}

}  // namespace blvd::cli
