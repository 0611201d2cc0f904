#include "gnss/gpsd_client.h"

#include <cmath>

#include <nlohmann/json.hpp>

namespace blvd::gnss {

namespace {

using nlohmann::json;

// A number within [lo, hi]; anything else (a string, out of range, a value no
// receiver gives, which a float could not even hold) counts as absent.
bool number(const json& j, const char* key, double* out, double lo, double hi) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return false;
  const double v = it->get<double>();
  if (!(v >= lo && v <= hi)) return false;
  *out = v;
  return true;
}

// Ranges: the globe, altitudes from the Dead Sea to low orbit, speeds below
// any vehicle's, dilutions and 1-sigma errors as gpsd prints them.
constexpr double kMaxAltM = 1e6, kMaxSpeedMps = 1e4, kMaxDop = 1e4, kMaxErrM = 1e7;

// gpsd's TPV "status" (gps.h STATUS_*) to FixStatus.
int statusFromGpsd(int s) {
  switch (s) {
    case 1: return kStatusGps;
    case 2: return kStatusDgps;
    case 3: return kStatusRtkFixed;
    case 4: return kStatusRtkFloat;
    case 5: return kStatusDeadReckoning;
    case 6: return kStatusDeadReckoning;  // GNSS + dead reckoning
    case 7: return kStatusManual;         // time only / surveyed
    case 8: return kStatusSimulated;
    case 9: return kStatusPps;            // P(Y)
    default: return kStatusUnknown;
  }
}

bool parseTpvObject(const json& j, Fix* out) {
  Fix f = Fix::empty();
  const auto mode = j.find("mode");
  f.mode = (mode != j.end() && mode->is_number_integer()) ? mode->get<int>() : kModeUnknown;
  if (f.mode < kModeUnknown || f.mode > kMode3D) f.mode = kModeUnknown;
  const auto t = j.find("time");
  if (t != j.end() && t->is_string()) {
    const std::string& s = t->get_ref<const std::string&>();
    if (parseIso8601(s.data(), s.size(), &f.t_unix)) f.flags |= kFixHasTime;
  }
  if (number(j, "lat", &f.lat, -90, 90) && number(j, "lon", &f.lon, -180, 180))
    f.flags |= kFixHasLatLon;
  else
    f.lat = f.lon = Fix::empty().lat;
  if (number(j, "altMSL", &f.alt, -kMaxAltM, kMaxAltM) || number(j, "alt", &f.alt, -kMaxAltM, kMaxAltM))
    f.flags |= kFixHasAlt;
  double v;
  if (number(j, "speed", &v, 0, kMaxSpeedMps)) {
    f.speed_mps = static_cast<float>(v);
    f.flags |= kFixHasSpeed;
  }
  if (number(j, "track", &v, 0, 360)) {
    f.track_deg = static_cast<float>(v);
    f.flags |= kFixHasTrack;
  }
  if (number(j, "geoidSep", &v, -kMaxAltM, kMaxAltM)) {
    f.geoid_sep_m = static_cast<float>(v);
    f.flags |= kFixHasGeoidSep;
  }
  const auto st = j.find("status");
  if (st != j.end() && st->is_number_integer()) f.status = statusFromGpsd(st->get<int>());
  else if (f.mode >= kMode2D) f.status = kStatusGps;
  *out = f;
  return true;
}

}  // namespace

bool parseGpsdTpv(std::string_view text, Fix* out, std::string* err) {
  const json j = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) {
    if (err) *err = "not a JSON object";
    return false;
  }
  const auto cls = j.find("class");
  if (cls == j.end() || !cls->is_string() || cls->get_ref<const std::string&>() != "TPV") {
    if (err) *err = "not a TPV report";
    return false;
  }
  return parseTpvObject(j, out);
}

bool GpsdClient::open(const Options& opt, std::string* err) {
  buf_.clear();
  version_.clear();
  have_sky_ = have_gst_ = false;
  if (!src_.connect(opt.host, opt.port, opt.timeout_ms, err)) return false;
  json watch = {{"enable", true}, {"json", true}};
  if (!opt.device.empty()) watch["device"] = opt.device;
  const std::string cmd = "?WATCH=" + watch.dump() + ";\n";
  if (!src_.writeAll(cmd.data(), cmd.size(), opt.timeout_ms)) {
    if (err) *err = "gpsd " + opt.host + ":" + std::to_string(opt.port) + ": " + src_.error();
    src_.close();
    return false;
  }
  return true;
}

ReadStatus GpsdClient::poll(Handler& h, int timeout_ms) {
  char chunk[4096];
  const ReadResult r = src_.read(chunk, sizeof chunk, timeout_ms);
  if (r.status != ReadStatus::Data) return r.status;
  consume(std::string_view(chunk, r.bytes), h);
  return ReadStatus::Data;
}

void GpsdClient::consume(std::string_view bytes, Handler& h) {
  buf_.append(bytes.data(), bytes.size());
  size_t start = 0;
  while (true) {
    const size_t nl = buf_.find('\n', start);
    if (nl == std::string::npos) break;
    std::string_view line(buf_.data() + start, nl - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (!line.empty()) handleLine(line, h);
    start = nl + 1;
  }
  buf_.erase(0, start);
  // gpsd's reports are at most a few kB (SKY with 100+ satellites); more
  // without a newline means we are not talking to gpsd.
  if (buf_.size() > (1u << 20)) {
    h.onError("gpsd: over 1 MiB without a line end; input discarded");
    buf_.clear();
  }
}

void GpsdClient::handleLine(std::string_view line, Handler& h) {
  const json j = json::parse(line.begin(), line.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) {
    h.onError("gpsd: not a JSON object: " + std::string(line.substr(0, 80)));
    return;
  }
  const auto cls_it = j.find("class");
  if (cls_it == j.end() || !cls_it->is_string()) {
    h.onError("gpsd: report without a class: " + std::string(line.substr(0, 80)));
    return;
  }
  const std::string& cls = cls_it->get_ref<const std::string&>();
  h.onReport(cls, line);
  if (cls == "VERSION") {
    const auto rel = j.find("release");
    if (rel != j.end() && rel->is_string()) version_ = rel->get<std::string>();
  } else if (cls == "ERROR") {
    const auto msg = j.find("message");
    h.onError("gpsd: " + (msg != j.end() && msg->is_string() ? msg->get<std::string>() : std::string(line)));
  } else if (cls == "SKY") {
    double v;
    if (number(j, "hdop", &v, 0, kMaxDop)) {
      hdop_ = v;
      have_sky_ = true;
    }
    if (number(j, "pdop", &v, 0, kMaxDop)) pdop_ = v;
    if (number(j, "vdop", &v, 0, kMaxDop)) vdop_ = v;
    const auto u = j.find("uSat");
    if (u != j.end() && u->is_number_unsigned() && u->get<uint64_t>() <= 1000) used_ = u->get<int>();
  } else if (cls == "GST") {
    const auto t = j.find("time");
    double tt;
    if (t != j.end() && t->is_string() &&
        parseIso8601(t->get_ref<const std::string&>().data(), t->get_ref<const std::string&>().size(), &tt) &&
        number(j, "lat", &gst_lat_, 0, kMaxErrM) && number(j, "lon", &gst_lon_, 0, kMaxErrM)) {
      gst_time_ = tt;
      if (!number(j, "alt", &gst_alt_, 0, kMaxErrM)) gst_alt_ = Fix::empty().alt;
      have_gst_ = true;
    }
  } else if (cls == "TPV") {
    Fix f;
    if (!parseTpvObject(j, &f)) return;
    if (have_sky_) {
      f.hdop = static_cast<float>(hdop_);
      f.flags |= kFixHasHdop;
      if (pdop_ > 0) {
        f.pdop = static_cast<float>(pdop_);
        f.vdop = static_cast<float>(vdop_);
        f.flags |= kFixHasPdop;
      }
    }
    if (used_ >= 0) f.sats_used = used_;
    if (have_gst_ && (f.flags & kFixHasTime) && std::fabs(gst_time_ - f.t_unix) < 0.0005) {
      f.lat_err_m = static_cast<float>(gst_lat_);
      f.lon_err_m = static_cast<float>(gst_lon_);
      f.h_acc_m = static_cast<float>(std::hypot(gst_lat_, gst_lon_));
      f.flags |= kFixHasHAcc;
      if (std::isfinite(gst_alt_)) {
        f.v_acc_m = static_cast<float>(gst_alt_);
        f.flags |= kFixHasVAcc;
      }
    }
    h.onFix(f);
  }
}

}  // namespace blvd::gnss
