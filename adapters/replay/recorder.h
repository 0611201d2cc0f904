// Records a live session to the formats the Replayer reads: GNSS fixes as NMEA
// 0183 and CAN frames as candump -l lines (adapters/can's CandumpWriter).
//
// Per fix, one epoch of sentences sharing its time, the same four every time as
// a receiver keeps its cycle: RMC, GGA, GSA (the 2D/3D fix type, which RMC/GGA
// cannot carry; 1 without a fix) and GST (empty fields without a fix or an
// accuracy). A cycle that changed with the fix would move the epoch's last
// sentence, which NMEA readers use to tell an epoch is complete. Only what
// blvd_gnss_fix holds is written; fields without their BLVD_GNSS_HAS_* bit are
// left empty. Latitude/longitude are written with 7 decimals of minutes
// (~0.2 mm), so a replay gives them back to 1e-8 degrees; h_acc_m (as GST
// latitude and longitude errors of h_acc / sqrt 2) with as many decimals (3..12)
// as a reader needs to get the same float back. fix.t is taken as UTC Unix
// seconds (the replay clock), rounded to milliseconds; time and date come from
// the rounded value, so they roll over together at midnight. A fix without a
// position (or with mode 1) is written as a receiver reports no fix: RMC status
// V, GGA quality 0. Fixes decoded from NMEA (as the Replayer gives them) are
// written so that decoding the recording gives them back bit for bit
// (tests/trace/test_trace_determinism.cpp).
//
// Contract: one thread per instance; nothing throws; write calls return false once
// their stream has failed. Files are created (truncated) by open*().
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iosfwd>
#include <memory>
#include <string>
#include <string_view>

#include "blvd/blvd.h"
#include "can/candump.h"
#include "can/frame.h"

namespace blvd::replay {

// XOR of the bytes between '$' and '*' (pass them without either).
uint8_t nmeaChecksum(std::string_view body);

// "$" body "*hh\r\n".
std::string nmeaSentence(std::string_view body);

// The sentences of one fix (see above), each ending in CR LF. `talker` is two letters ("GP", "GN").
std::string formatFix(const blvd_gnss_fix& fix, std::string_view talker = "GP");

class Recorder {
 public:
  // NMEA output: a file it creates, or a stream the caller keeps alive.
  blvd_status openNmea(const std::string& path, std::string& err);
  void attachNmea(std::ostream& out) { nmea_ = &out; }
  // candump output.
  blvd_status openCandump(const std::string& path, std::string& err);
  void attachCandump(std::ostream& out) { candump_ = can::CandumpWriter(out); has_candump_ = true; }

  bool record(const blvd_gnss_fix& fix);
  bool record(const can::Frame& frame);
  bool flush();

  std::string talker = "GP";
  uint64_t fixes() const { return fixes_; }
  uint64_t frames() const { return frames_; }

 private:
  std::unique_ptr<std::ofstream> nmea_file_;
  std::ostream* nmea_ = nullptr;
  can::CandumpWriter candump_;
  bool has_candump_ = false;
  uint64_t fixes_ = 0, frames_ = 0;
};

}  // namespace blvd::replay
