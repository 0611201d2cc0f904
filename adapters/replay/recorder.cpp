#include "replay/recorder.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ostream>

namespace blvd::replay {
namespace {

constexpr double kKnotMps = 1852.0 / 3600.0;

// Civil date of a day count since 1970-01-01 (H. Hinnant, "chrono-compatible low-level date algorithms").
void civilFromDays(int64_t z, int& y, unsigned& m, unsigned& d) {
  z += 719468;
  const int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y = static_cast<int>(yoe + era * 400 + (m <= 2));
}

// "ddmm.mmmmmmm,N" (or dddmm for longitude), rounded once in units of 1e-7 minute.
std::string angle(double deg, bool is_lat) {
  const char hemi = is_lat ? (deg < 0 ? 'S' : 'N') : (deg < 0 ? 'W' : 'E');
  const long long units = std::llround(std::fabs(deg) * 60.0 * 1e7);
  const long long per_deg = 60LL * 10000000LL;
  const long long whole = units / per_deg;
  const long long rem = units % per_deg;
  char buf[48];
  std::snprintf(buf, sizeof buf, is_lat ? "%02lld%02lld.%07lld,%c" : "%03lld%02lld.%07lld,%c", whole,
                rem / 10000000LL, rem % 10000000LL, hemi);
  return buf;
}

// GST latitude/longitude error e = h_acc / sqrt 2 (an even split: blvd_gnss_fix
// has h_acc alone), with the fewest decimals (3 to 12) from which a reader's
// hypot(e, e), as a float, is h_acc again (adapters/gnss reads h_acc so).
std::string axisError(float h_acc) {
  char buf[48] = "";
  for (int d = 3; d <= 12; ++d) {
    std::snprintf(buf, sizeof buf, "%.*f", d, static_cast<double>(h_acc) / std::sqrt(2.0));
    const double e = std::strtod(buf, nullptr);
    if (static_cast<float>(std::sqrt(e * e + e * e)) == h_acc) break;
  }
  return buf;
}

}  // namespace

uint8_t nmeaChecksum(std::string_view body) {
  uint8_t x = 0;
  for (char c : body) x = static_cast<uint8_t>(x ^ static_cast<uint8_t>(c));
  return x;
}

std::string nmeaSentence(std::string_view body) {
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\r\n", nmeaChecksum(body));
  std::string s;
  s.reserve(body.size() + 6);
  s += '$';
  s += body;
  s += tail;
  return s;
}

std::string formatFix(const blvd_gnss_fix& fix, std::string_view talker) {
  const std::string tk(talker.substr(0, 2));
  std::string time, date;
  if ((fix.flags & BLVD_GNSS_HAS_TIME) && std::isfinite(fix.t)) {
    const long long ms = std::llround(fix.t * 1000.0);
    long long days = ms / 86400000LL;
    long long tod = ms % 86400000LL;
    if (tod < 0) {
      tod += 86400000LL;
      --days;
    }
    int y;
    unsigned mo, d;
    civilFromDays(days, y, mo, d);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%02lld%02lld%02lld.%03lld", tod / 3600000LL, tod / 60000LL % 60,
                  tod / 1000LL % 60, tod % 1000LL);
    time = buf;
    std::snprintf(buf, sizeof buf, "%02u%02u%02d", d, mo, ((y % 100) + 100) % 100);
    date = buf;
  }
  const bool pos = (fix.flags & BLVD_GNSS_HAS_LATLON) && std::isfinite(fix.lat) && std::isfinite(fix.lon);
  const bool valid = pos && fix.mode != 1;
  const std::string lat = pos ? angle(fix.lat, true) : std::string(",");
  const std::string lon = pos ? angle(fix.lon, false) : std::string(",");
  auto num = [](bool has, double v, int decimals) {
    if (!has || !std::isfinite(v)) return std::string();
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return std::string(buf);
  };
  const std::string sog = num(fix.flags & BLVD_GNSS_HAS_SPEED, fix.speed_mps / kKnotMps, 4);
  const std::string cog = num(fix.flags & BLVD_GNSS_HAS_TRACK, fix.track_deg, 3);
  const std::string hdop = num(fix.flags & BLVD_GNSS_HAS_HDOP, fix.hdop, 2);
  const std::string alt = num(fix.flags & BLVD_GNSS_HAS_ALT, fix.alt, 3);

  std::string out;
  // RMC (NMEA 2.3): time, status, lat, lon, SOG knots, COG, date, magvar, E/W, mode.
  out += nmeaSentence(tk + "RMC," + time + "," + (valid ? "A" : "V") + "," + lat + "," + lon + "," + sog + "," +
                      cog + "," + date + ",,," + (valid ? "A" : "N"));
  // GGA: time, lat, lon, quality, satellites (not in blvd_gnss_fix), HDOP, altitude, geoid separation, age, station.
  out += nmeaSentence(tk + "GGA," + time + "," + lat + "," + lon + "," + (valid ? "1" : "0") + ",," + hdop + "," +
                      alt + ",M,,M,,");
  // GSA and GST in every epoch, as a receiver keeps its cycle: with no fix it
  // still sends GSA (fix type 1) and GST (empty fields). A cycle that varied
  // with the fix would move the epoch's last sentence, which a reader may use
  // to tell when an epoch is complete.
  // GSA: auto, fix type (1 without a fix; empty when a fix's mode is unknown),
  // 12 satellite slots, PDOP, HDOP, VDOP.
  const std::string fix_type = !valid ? "1" : fix.mode == 2 || fix.mode == 3 ? std::to_string(fix.mode) : "";
  out += nmeaSentence(tk + "GSA,A," + fix_type + ",,,,,,,,,,,,," + hdop + ",");
  // GST: time, rms, semi-major, semi-minor, orientation, lat error, lon error, alt error.
  const bool hacc = valid && (fix.flags & BLVD_GNSS_HAS_HACC) && std::isfinite(fix.h_acc_m);
  const std::string e = hacc ? axisError(fix.h_acc_m) : std::string();
  out += nmeaSentence(tk + "GST," + time + ",,,,," + e + "," + e + ",");
  return out;
}

blvd_status Recorder::openNmea(const std::string& path, std::string& err) {
  auto f = std::make_unique<std::ofstream>(path, std::ios::binary | std::ios::trunc);
  if (!*f) {
    err = path + ": cannot create";
    return BLVD_ERR_IO;
  }
  nmea_file_ = std::move(f);
  nmea_ = nmea_file_.get();
  return BLVD_OK;
}

blvd_status Recorder::openCandump(const std::string& path, std::string& err) {
  candump_ = can::CandumpWriter();
  const blvd_status s = candump_.open(path, err);
  has_candump_ = s == BLVD_OK;
  return s;
}

bool Recorder::record(const blvd_gnss_fix& fix) {
  if (!nmea_) return false;
  const std::string s = formatFix(fix, talker);
  nmea_->write(s.data(), static_cast<std::streamsize>(s.size()));
  if (!*nmea_) return false;
  ++fixes_;
  return true;
}

bool Recorder::record(const can::Frame& frame) {
  if (!has_candump_ || !candump_.write(frame)) return false;
  ++frames_;
  return true;
}

bool Recorder::flush() {
  bool ok = true;
  if (nmea_) ok = static_cast<bool>(nmea_->flush()) && ok;
  if (has_candump_) ok = candump_.flush() && ok;
  return ok;
}

}  // namespace blvd::replay
