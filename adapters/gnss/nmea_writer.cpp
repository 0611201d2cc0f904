#include "gnss/nmea_writer.h"

#include <cmath>
#include <cstdio>

namespace blvd::gnss {
namespace {

bool hasPosition(const Fix& f) { return (f.flags & kFixHasLatLon) && f.mode != kModeNoFix; }

// "hhmmss.ss" and, for RMC, "ddmmyy", from Unix seconds (UTC, no leap seconds).
void timeFields(double t_unix, std::string& hms, std::string& dmy) {
  // Centiseconds, rounded once, so 59.999 s does not print as "60.00".
  const int64_t cs = static_cast<int64_t>(std::llround(t_unix * 100.0));
  int64_t days = cs / 8640000;
  int64_t rem = cs % 8640000;
  if (rem < 0) rem += 8640000, --days;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%02d%02d%02d.%02d", static_cast<int>(rem / 360000), static_cast<int>(rem / 6000 % 60),
                static_cast<int>(rem / 100 % 60), static_cast<int>(rem % 100));
  hms = buf;
  // civil_from_days (H. Hinnant), the inverse of daysFromCivil.
  const int64_t z = days + 719468;
  const int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned d = doy - (153 * mp + 2) / 5 + 1;
  const unsigned m = mp < 10 ? mp + 3 : mp - 9;
  const int64_t y = static_cast<int64_t>(yoe) + era * 400 + (m <= 2);
  std::snprintf(buf, sizeof buf, "%02u%02u%02d", d, m, static_cast<int>(((y % 100) + 100) % 100));
  dmy = buf;
}

// ddmm.mmmmmm,N / dddmm.mmmmmm,E
std::string angle(double deg, bool lat, int decimals) {
  const char hemi = lat ? (deg < 0 ? 'S' : 'N') : (deg < 0 ? 'W' : 'E');
  double a = std::fabs(deg);
  const double scale = std::pow(10.0, decimals);
  // Round the minutes once, then carry into the degrees.
  int64_t units = static_cast<int64_t>(std::llround(a * 60.0 * scale));
  const int64_t per_deg = static_cast<int64_t>(std::llround(60.0 * scale));
  const int64_t d = units / per_deg;
  units -= d * per_deg;
  char buf[48];
  std::snprintf(buf, sizeof buf, lat ? "%02lld%0*.*f,%c" : "%03lld%0*.*f,%c", static_cast<long long>(d),
                decimals + 3, decimals, static_cast<double>(units) / scale, hemi);
  return buf;
}

std::string num(double v, int decimals) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

void appendSentence(const std::string& body, std::string& out) {
  unsigned char cs = 0;
  for (char c : body) cs ^= static_cast<unsigned char>(c);
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\r\n", cs);
  out += '$';
  out += body;
  out += tail;
}

void appendRmc(const Fix& f, const NmeaWriterOptions& opt, std::string& out) {
  std::string hms, dmy;
  timeFields(f.t_unix, hms, dmy);
  const bool pos = hasPosition(f);
  std::string b = std::string(opt.talker) + "RMC," + hms + (pos ? ",A," : ",V,");
  b += pos ? angle(f.lat, true, opt.lat_lon_decimals) + "," + angle(f.lon, false, opt.lat_lon_decimals) : ",,,";
  b += ",";
  b += (f.flags & kFixHasSpeed) && pos ? num(f.speed_mps / 0.514444, 3) : "";
  b += ",";
  b += (f.flags & kFixHasTrack) && pos ? num(f.track_deg, 2) : "";
  b += "," + dmy + ",,," + (pos ? "A" : "N");
  appendSentence(b, out);
}

void appendGga(const Fix& f, const NmeaWriterOptions& opt, std::string& out) {
  std::string hms, dmy;
  timeFields(f.t_unix, hms, dmy);
  const bool pos = hasPosition(f);
  std::string b = std::string(opt.talker) + "GGA," + hms + ",";
  if (!pos) {
    b += ",,,,0,00,,,M,,M,,";
  } else {
    b += angle(f.lat, true, opt.lat_lon_decimals) + "," + angle(f.lon, false, opt.lat_lon_decimals) + ",1,";
    char sats[8];
    std::snprintf(sats, sizeof sats, "%02d", f.sats_used >= 0 ? f.sats_used : opt.sats_used);
    b += sats;
    b += "," + ((f.flags & kFixHasHdop) ? num(f.hdop, 1) : std::string()) + ",";
    b += ((f.flags & kFixHasAlt) ? num(f.alt, 2) : std::string()) + ",M,";
    b += ((f.flags & kFixHasGeoidSep) ? num(f.geoid_sep_m, 1) : std::string()) + ",M,,";
  }
  appendSentence(b, out);
}

void appendGst(const Fix& f, const NmeaWriterOptions& opt, std::string& out) {
  std::string hms, dmy;
  timeFields(f.t_unix, hms, dmy);
  if (!(f.flags & kFixHasHAcc) || !hasPosition(f)) {
    // Receivers keep their sentence cycle without a fix (u-blox sends GST with
    // empty fields), which lets a parser learn which sentence ends an epoch.
    appendSentence(std::string(opt.talker) + "GST," + hms + ",,,,,,,", out);
    return;
  }
  const double axis = f.h_acc_m / std::sqrt(2.0);
  const double lat_err = std::isfinite(f.lat_err_m) ? f.lat_err_m : axis;
  const double lon_err = std::isfinite(f.lon_err_m) ? f.lon_err_m : axis;
  const double alt_err = (f.flags & kFixHasVAcc) ? f.v_acc_m : 1.5 * axis;
  std::string b = std::string(opt.talker) + "GST," + hms + "," + num(f.h_acc_m, 2) + "," + num(axis, 2) + "," +
                  num(axis, 2) + ",0.0," + num(lat_err, 2) + "," + num(lon_err, 2) + "," + num(alt_err, 2);
  appendSentence(b, out);
}

void appendEpoch(const Fix& f, const NmeaWriterOptions& opt, std::string& out) {
  appendRmc(f, opt, out);
  appendGga(f, opt, out);
  appendGst(f, opt, out);
}

}  // namespace blvd::gnss
