// One GNSS position fix, as the NMEA parser and the gpsd client produce it.
//
// The layout is the proposal for the C API's future `blvd_gnss_fix` (fed to
// `blvd_feed_gnss()` by the tracking module): the same fields in the same
// order, plain types only, so the tracking module can copy it member by member
// (or memcpy it once the C struct exists). Unknown floating-point values are
// NaN and their bit in `flags` is clear; check either.
#pragma once

#include <cstddef>
#include <cstdint>

namespace blvd::gnss {

// gpsd's TPV "mode": what kind of solution the receiver reports.
enum FixMode : int {
  kModeUnknown = 0,  // nothing said about the fix yet
  kModeNoFix = 1,    // the receiver says it has no valid position
  kMode2D = 2,       // latitude/longitude valid, altitude not (or held)
  kMode3D = 3,       // latitude/longitude and altitude valid
};

// How the solution was obtained (GGA quality, RMC/GNS/GLL FAA mode letter).
enum FixStatus : int {
  kStatusUnknown = 0,
  kStatusGps = 1,        // autonomous
  kStatusDgps = 2,       // differential (SBAS, DGPS, "precise")
  kStatusRtkFixed = 3,   // RTK, integer ambiguities fixed
  kStatusRtkFloat = 4,   // RTK, float solution
  kStatusDeadReckoning = 5,
  kStatusManual = 6,     // surveyed / manual input
  kStatusSimulated = 7,
  kStatusPps = 8,        // GGA quality 3 (PPS / precise positioning service)
};

// Bits of Fix::flags. The first group says which fields hold values.
enum FixFlag : uint32_t {
  kFixHasTime = 1u << 0,      // t_unix (the date was known: RMC or ZDA)
  kFixHasLatLon = 1u << 1,    // lat, lon
  kFixHasAlt = 1u << 2,       // alt (metres above mean sea level)
  kFixHasSpeed = 1u << 3,     // speed_mps (over ground)
  kFixHasTrack = 1u << 4,     // track_deg (course over ground, true)
  kFixHasHdop = 1u << 5,      // hdop
  kFixHasHAcc = 1u << 6,      // h_acc_m, lat_err_m, lon_err_m (GST)
  kFixHasVAcc = 1u << 7,      // v_acc_m (GST)
  kFixHasHeading = 1u << 8,   // heading_deg (true heading: HDT/THS)
  kFixHasGeoidSep = 1u << 9,  // geoid_sep_m (GGA/GNS)
  kFixHasPdop = 1u << 10,     // pdop, vdop (GSA)
  // Provenance.
  kFixNoChecksum = 1u << 16,  // a sentence merged into this fix had no checksum
  kFixUpdate = 1u << 17,      // supersedes the fix emitted just before it: same epoch, completed late (nmea.h)
};

struct Fix {
  uint32_t struct_size = sizeof(Fix);  // for the future C struct: it only grows at the end
  double t_unix;       // UTC, seconds since 1970-01-01 (fractional)
  double lat, lon;     // degrees, WGS 84, north / east positive
  double alt;          // metres above mean sea level (GGA/GNS altitude)
  float speed_mps;     // speed over ground
  float track_deg;     // course over ground, degrees true, [0, 360)
  float hdop;          // horizontal dilution of precision
  float h_acc_m;       // 1-sigma horizontal error, sqrt(lat_err^2 + lon_err^2), from GST
  float v_acc_m;       // 1-sigma altitude error, from GST
  float lat_err_m;     // 1-sigma latitude error (GST)
  float lon_err_m;     // 1-sigma longitude error (GST)
  float heading_deg;   // true heading of the antenna baseline/vehicle (HDT/THS), not the track
  float geoid_sep_m;   // geoid height above the WGS 84 ellipsoid; alt + geoid_sep_m = ellipsoidal height
  float pdop, vdop;    // GSA
  int mode;            // FixMode
  int status;          // FixStatus
  int sats_used;       // satellites used in the solution, -1 if unknown
  uint32_t flags;      // FixFlag bits

  // An empty fix: every value unknown.
  static Fix empty();
};

// gpsd-style ISO 8601 UTC time with milliseconds, e.g. "2019-04-07T12:34:56.000Z".
// Writes at most `cap` bytes including the NUL; returns the length (0 if t is not finite).
size_t formatIso8601(double t_unix, char* out, size_t cap);

// Parses the ISO 8601 UTC form gpsd writes ("YYYY-MM-DDThh:mm:ss[.fff]Z").
// Returns false (and leaves *t_unix alone) if the text is not such a time.
bool parseIso8601(const char* text, size_t len, double* t_unix);

// One gpsd-style TPV object on one line, without a newline:
// {"class":"TPV","mode":3,"time":"...","lat":..,"lon":..,"alt":..,"speed":..,"track":..}
// Fields without a value are left out; numbers use gpsd's precision (lat/lon 9
// decimals, alt 4, speed 3, track 4). Returns the length written (truncated to cap-1).
size_t formatTpvJson(const Fix& fix, char* out, size_t cap);

// Days since 1970-01-01 of a proleptic Gregorian date (no range checks).
int64_t daysFromCivil(int year, unsigned month, unsigned day);

}  // namespace blvd::gnss
