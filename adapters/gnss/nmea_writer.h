// NMEA 0183 output: RMC, GGA and GST sentences from a Fix, with checksums, as
// a receiver writes them (for simulators, e.g. samples/sim_feed, and for
// round-trip tests of the parser in nmea.h).
//
//   std::string out;
//   blvd::gnss::NmeaWriterOptions opt;          // talker "GP", 6 decimals of minutes
//   blvd::gnss::appendEpoch(fix, opt, out);     // "$GPRMC,...*hh\r\n$GPGGA,...\r\n$GPGST,...\r\n"
//
// A fix without kFixHasLatLon (or mode kModeNoFix) is written as a receiver
// reports a lost fix: RMC status V, GGA quality 0 and GST with empty fields (the
// cycle stays RMC, GGA, GST, so a parser's epoch detection is not disturbed). Latitude and longitude are written as ddmm.mmmmmm (6 decimals of
// a minute: 2 mm), time as hhmmss.ss, speed in knots with 3 decimals, course
// with 2, the GST errors with 2 decimals of a metre.
//
// Contract: pure functions; append to the caller's string (which may allocate).
#pragma once

#include <string>

#include "gnss/fix.h"

namespace blvd::gnss {

struct NmeaWriterOptions {
  const char* talker = "GP";  // two letters: GP, GN, GL, ...
  int lat_lon_decimals = 6;   // decimals of the minutes, 1..8
  int sats_used = 10;         // GGA satellites, when the fix does not say (sats_used < 0)
};

// "$" + body + "*hh\r\n", hh the XOR of the body's bytes.
void appendSentence(const std::string& body, std::string& out);

void appendRmc(const Fix& f, const NmeaWriterOptions& opt, std::string& out);
void appendGga(const Fix& f, const NmeaWriterOptions& opt, std::string& out);
// GST: rms, error ellipse (semi-major = semi-minor = h_acc / sqrt 2, orientation 0),
// latitude, longitude and altitude errors; empty fields without kFixHasHAcc or a position.
void appendGst(const Fix& f, const NmeaWriterOptions& opt, std::string& out);

// RMC + GGA + GST of one epoch.
void appendEpoch(const Fix& f, const NmeaWriterOptions& opt, std::string& out);

}  // namespace blvd::gnss
