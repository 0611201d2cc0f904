// Time-synchronised replay of an NMEA log and/or a candump log on a virtual clock.
//
//   blvd::replay::ReplayDesc d;
//   d.nmea_path = "drive.nmea";
//   d.candump_path = "drive.log"; d.dbc_path = "toyota.dbc"; d.vehicle = "toyota";
//   d.pace = blvd::replay::Pace::RealTime; d.speed = 2.0;
//   blvd::replay::Replayer r;
//   std::string err;
//   if (r.open(d, err) != BLVD_OK) die(err);
//   blvd::replay::RuntimeSink sink(rt);          // blvd_feed_gnss / blvd_feed_odometry
//   if (r.run(sink, err) != BLVD_OK) die(err);
//
// Clock: the replay clock is the NMEA one (UTC, Unix seconds). candump times are
// mapped onto it with `t + offset_s`; by default the offset aligns the first event
// of the candump stream with the first fix of the NMEA stream (0 with only one
// stream). Events are merged by time; on a tie the GNSS fix goes first.
//
// Contract:
// - Streaming: both logs are read in bounded chunks, never loaded whole; memory
//   stays bounded by the fixes of one read chunk plus one pending event per stream.
// - Threads: one thread per instance; stop() may be called from any thread.
// - Errors: nothing throws. A log that cannot be opened fails open(). A bad line
//   is skipped and counted; its message ("file:line: reason") is kept in
//   warnings() (the first kMaxWarnings) - unless ReplayDesc::strict, where the
//   first bad line stops the replay with that message.
// - Fixes without a date (no RMC/ZDA seen yet) have no place on the clock and are
//   skipped (counted in Stats::gnss_untimed).
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "can/candump.h"
#include "vehicle/dbc.h"
#include "vehicle/profile.h"
#include "gnss/fix.h"
#include "gnss/nmea.h"
#include "gnss/to_blvd.h"

namespace blvd::replay {

enum class EventType : uint8_t { Gnss, Odometry };

struct Event {
  EventType type = EventType::Gnss;
  double t = 0;               // replay clock (UTC seconds); equals gnss.t or odometry.t
  blvd_gnss_fix gnss{};       // when type == Gnss
  blvd_odometry odometry{};   // when type == Odometry
  uint64_t line = 0;          // line of its log that completed the event (1-based)
};

// Where replayed events go. Called on the thread that runs the replay.
class Sink {
 public:
  virtual ~Sink() = default;
  virtual void onEvent(const Event& e) = 0;
};

// The default sink: feeds a runtime through the public C API.
class RuntimeSink final : public Sink {
 public:
  explicit RuntimeSink(blvd_runtime* rt) : rt_(rt) {}
  void onEvent(const Event& e) override;
  uint64_t failures() const { return failures_; }  // feeds that did not return BLVD_OK
  blvd_status lastStatus() const { return last_; }

 private:
  blvd_runtime* rt_;
  uint64_t failures_ = 0;
  blvd_status last_ = BLVD_OK;
};

enum class Pace : uint8_t {
  AsFastAsPossible,  // no sleeping: the virtual clock jumps from event to event
  RealTime,          // sleeps on a steady clock so that events keep their spacing / speed
};

struct ReplayDesc {
  // NMEA log: a path, or a stream the caller keeps alive (then nmea_path only names it).
  std::string nmea_path;
  std::istream* nmea_stream = nullptr;
  // candump -l log (same rules), decoded with a DBC and a vehicle profile.
  std::string candump_path;
  std::istream* candump_stream = nullptr;
  std::string dbc_path;             // required with a candump log
  std::string vehicle = "toyota";   // "toyota", "vw_mqb", "hyundai"; overrides profile.vehicle
  vehicle::ProfileDesc profile;         // speed source, wheel staleness, interface filter
  // candump clock -> replay clock: t_replay = t_candump + offset_s.
  bool has_offset = false;          // false: align the first events of both streams
  double offset_s = 0;
  Pace pace = Pace::AsFastAsPossible;
  double speed = 1;                 // RealTime: virtual seconds per wall second; <= 0 means 1
  bool strict = false;              // stop at the first bad line instead of skipping it
};

class Replayer {
 public:
  static constexpr size_t kMaxWarnings = 64;
  static constexpr size_t kChunk = 4096;  // NMEA bytes read per refill

  struct Stats {
    uint64_t gnss = 0;          // fixes delivered
    uint64_t gnss_untimed = 0;  // fixes skipped: no date/time
    uint64_t odometry = 0;      // odometry events delivered
    uint64_t frames = 0;        // candump frames read
    uint64_t bad_lines = 0;     // NMEA diagnostics + bad candump lines
  };

  enum class Step { Event, End, Error };

  Replayer();
  ~Replayer();
  Replayer(const Replayer&) = delete;
  Replayer& operator=(const Replayer&) = delete;

  // Opens the logs and the DBC, binds the profile. BLVD_ERR_INVALID_ARG without any
  // log; BLVD_ERR_IO / BLVD_ERR_NOT_FOUND / ... with `err` naming the file.
  blvd_status open(const ReplayDesc& desc, std::string& err);

  // The next event in time order, without pacing. Error: error() says why.
  Step next(Event& out);

  // Delivers every remaining event to `sink`, paced as the descriptor says.
  // BLVD_OK at the end of both logs (or after stop()); else `err` is set.
  blvd_status run(Sink& sink, std::string& err);

  // Makes run() return after the event in progress. Any thread.
  void stop() { stop_.store(true); }

  // The candump -> replay clock offset in use (known once both streams have an event).
  double offset() const { return offset_; }
  const Stats& stats() const { return stats_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  const std::string& error() const { return error_; }

 private:
  struct NmeaOut;
  bool pullGnss();       // fills gnss_head_ if possible
  bool pullOdometry();   // fills odo_head_ if possible
  void warn(std::string msg);
  bool prime();

  ReplayDesc desc_;
  // NMEA stream.
  std::unique_ptr<std::istream> nmea_file_;
  std::istream* nmea_in_ = nullptr;
  gnss::NmeaDecoder decoder_;
  std::unique_ptr<NmeaOut> nmea_out_;
  std::deque<Event> gnss_queue_;
  bool nmea_done_ = true;
  // candump stream.
  can::CandumpReader candump_;
  vehicle::Database dbc_;
  vehicle::Profile profile_;
  bool can_done_ = true;
  // Heads of both streams (odo_head_.t on the candump clock).
  bool have_gnss_ = false, have_odo_ = false;
  Event gnss_head_, odo_head_;
  bool primed_ = false;
  double offset_ = 0;

  std::atomic<bool> stop_{false};
  Stats stats_;
  std::vector<std::string> warnings_;
  std::string error_;
  bool io_error_ = false;
};

// Conversions used by the replayer (also handy for a host's own loop).
using gnss::toBlvd;  // adapters/gnss/to_blvd.h
blvd_odometry toBlvd(const vehicle::Odometry& o);

}  // namespace blvd::replay
