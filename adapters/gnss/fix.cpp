#include "gnss/fix.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>

namespace blvd::gnss {

Fix Fix::empty() {
  constexpr double dn = std::numeric_limits<double>::quiet_NaN();
  constexpr float fn = std::numeric_limits<float>::quiet_NaN();
  Fix f;
  f.struct_size = sizeof(Fix);
  f.t_unix = dn;
  f.lat = f.lon = f.alt = dn;
  f.speed_mps = f.track_deg = f.hdop = f.h_acc_m = f.v_acc_m = fn;
  f.lat_err_m = f.lon_err_m = f.heading_deg = f.geoid_sep_m = f.pdop = f.vdop = fn;
  f.mode = kModeUnknown;
  f.status = kStatusUnknown;
  f.sats_used = -1;
  f.flags = 0;
  return f;
}

// Howard Hinnant's days_from_civil / civil_from_days (public domain algorithms,
// "chrono-Compatible Low-Level Date Algorithms").
int64_t daysFromCivil(int year, unsigned month, unsigned day) {
  const int64_t y = static_cast<int64_t>(year) - (month <= 2 ? 1 : 0);
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const int64_t yoe = y - era * 400;
  const int64_t mp = (static_cast<int64_t>(month) + 9) % 12;
  const int64_t doy = (153 * mp + 2) / 5 + static_cast<int64_t>(day) - 1;
  const int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

namespace {

void civilFromDays(int64_t z, int64_t* year, unsigned* month, unsigned* day) {
  z += 719468;
  const int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const int64_t doe = z - era * 146097;
  const int64_t yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const int64_t doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const int64_t mp = (5 * doy + 2) / 153;
  const int64_t d = doy - (153 * mp + 2) / 5 + 1;
  const int64_t m = mp < 10 ? mp + 3 : mp - 9;
  *year = yoe + era * 400 + (m <= 2 ? 1 : 0);
  *month = static_cast<unsigned>(m);
  *day = static_cast<unsigned>(d);
}

// Appends printf output at out+*len, never past cap-1.
__attribute__((format(printf, 4, 5))) void append(char* out, size_t cap, size_t* len, const char* fmt, ...) {
  if (*len + 1 >= cap) return;
  va_list ap;
  va_start(ap, fmt);
  const int n = std::vsnprintf(out + *len, cap - *len, fmt, ap);
  va_end(ap);
  if (n < 0) return;
  *len += static_cast<size_t>(n);
  if (*len >= cap) *len = cap - 1;
}

}  // namespace

size_t formatIso8601(double t_unix, char* out, size_t cap) {
  if (cap == 0) return 0;
  out[0] = '\0';
  if (!std::isfinite(t_unix)) return 0;
  // Milliseconds, rounded like gpsd's timespec_to_iso8601 (which rounds to the
  // requested precision).
  const int64_t ms = static_cast<int64_t>(std::llround(t_unix * 1000.0));
  int64_t secs = ms / 1000;
  int64_t frac = ms % 1000;
  if (frac < 0) {
    frac += 1000;
    secs -= 1;
  }
  int64_t days = secs / 86400;
  int64_t sod = secs % 86400;
  if (sod < 0) {
    sod += 86400;
    days -= 1;
  }
  int64_t y;
  unsigned m, d;
  civilFromDays(days, &y, &m, &d);
  const int n = std::snprintf(out, cap, "%04lld-%02u-%02uT%02d:%02d:%02d.%03dZ", static_cast<long long>(y), m, d,
                              static_cast<int>(sod / 3600), static_cast<int>(sod / 60 % 60), static_cast<int>(sod % 60),
                              static_cast<int>(frac));
  if (n < 0) return 0;
  return static_cast<size_t>(n) < cap ? static_cast<size_t>(n) : cap - 1;
}

bool parseIso8601(const char* s, size_t len, double* t_unix) {
  // YYYY-MM-DDThh:mm:ss[.f+]Z
  auto digits = [&](size_t at, size_t n, int* v) {
    if (at + n > len) return false;
    int x = 0;
    for (size_t i = 0; i < n; ++i) {
      const char c = s[at + i];
      if (c < '0' || c > '9') return false;
      x = x * 10 + (c - '0');
    }
    *v = x;
    return true;
  };
  int Y, M, D, h, mi, sec;
  if (!digits(0, 4, &Y) || len < 20 || s[4] != '-' || !digits(5, 2, &M) || s[7] != '-' || !digits(8, 2, &D) ||
      s[10] != 'T' || !digits(11, 2, &h) || s[13] != ':' || !digits(14, 2, &mi) || s[16] != ':' ||
      !digits(17, 2, &sec))
    return false;
  if (M < 1 || M > 12 || D < 1 || D > 31 || h > 23 || mi > 59 || sec > 60) return false;
  size_t i = 19;
  double frac = 0.0, scale = 0.1;
  if (i < len && s[i] == '.') {
    ++i;
    if (i >= len || s[i] < '0' || s[i] > '9') return false;
    while (i < len && s[i] >= '0' && s[i] <= '9') {
      frac += (s[i] - '0') * scale;
      scale /= 10.0;
      ++i;
    }
  }
  if (i + 1 != len || s[i] != 'Z') return false;
  const int64_t days = daysFromCivil(Y, static_cast<unsigned>(M), static_cast<unsigned>(D));
  *t_unix = static_cast<double>(days * 86400 + h * 3600 + mi * 60 + sec) + frac;
  return true;
}

size_t formatTpvJson(const Fix& fix, char* out, size_t cap) {
  if (cap == 0) return 0;
  out[0] = '\0';
  size_t len = 0;
  append(out, cap, &len, "{\"class\":\"TPV\",\"mode\":%d", fix.mode);
  if (fix.flags & kFixHasTime) {
    char t[40];
    if (formatIso8601(fix.t_unix, t, sizeof t) > 0) append(out, cap, &len, ",\"time\":\"%s\"", t);
  }
  if (fix.flags & kFixHasLatLon) append(out, cap, &len, ",\"lat\":%.9f,\"lon\":%.9f", fix.lat, fix.lon);
  if (fix.flags & kFixHasAlt) append(out, cap, &len, ",\"alt\":%.4f", fix.alt);
  if (fix.flags & kFixHasSpeed) append(out, cap, &len, ",\"speed\":%.3f", static_cast<double>(fix.speed_mps));
  if (fix.flags & kFixHasTrack) append(out, cap, &len, ",\"track\":%.4f", static_cast<double>(fix.track_deg));
  append(out, cap, &len, "}");
  return len;
}

}  // namespace blvd::gnss
