// --nmea: GNSS fixes from an NMEA log, fed in step with the CAN bus.
//
// The log's fix times (UTC, Unix seconds; fixes before the first RMC/ZDA have
// no date and are skipped) are taken to be on the CAN trace's clock, plus
// `offset_s`. CAN frames arrive on the receiving clock (kernel timestamps on a
// live bus, the log's own times from a candump file); main.cpp maps them onto
// the trace clock, and feedUntil(trace_t, to_rx) feeds every fix up to trace_t,
// stamped on the receiving clock, so the tracker sees both inputs on one clock.
// Read in chunks as the bus time advances: memory stays bounded.
#pragma once

#include <cstdint>
#include <deque>
#include <fstream>
#include <string>

#include "gnss/nmea.h"
#include "tracking.h"

namespace vcan_drive {

class GnssFeed {
 public:
  blvd_status open(const std::string& path, double offset_s, std::string& err);
  bool isOpen() const { return in_.is_open(); }

  // The first dated fix (time on the trace clock); false when the log has none.
  bool first(blvd_gnss_fix& out);
  // Feeds the fixes with trace time <= trace_t, each at its trace time + to_rx.
  void feedUntil(double trace_t, double to_rx, Tracking& tracking);

  uint64_t fed() const { return fed_; }
  uint64_t untimed() const { return untimed_; }
  uint64_t diagnostics() const { return diagnostics_; }

 private:
  struct Out;
  bool readMore();  // decodes the next chunk; false at the end of the log

  std::ifstream in_;
  std::string path_;
  double offset_s_ = 0;
  blvd::gnss::NmeaDecoder decoder_;
  std::deque<blvd_gnss_fix> pending_;
  bool eof_ = false;
  uint64_t fed_ = 0, untimed_ = 0, diagnostics_ = 0;
};

}  // namespace vcan_drive
