#include "replay/replayer.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>
#include <utility>

namespace blvd::replay {

blvd_odometry toBlvd(const vehicle::Odometry& o) {
  blvd_odometry out{};
  out.struct_size = sizeof out;
  out.t = o.t;
  out.speed_mps = o.speed_mps;
  out.yaw_rate_dps = o.yaw_rate_dps;
  for (int i = 0; i < 4; ++i) out.wheel_speeds_mps[i] = o.wheel_speeds_mps[i];
  out.heading_deg = 0;
  out.reverse = o.gear == vehicle::Gear::Reverse ? 1 : 0;
  // Only what this frame changed: the tracker takes every flagged field as a new
  // measurement, so re-sending the last speed with each yaw-rate frame would count
  // one wheel-speed reading several times. (The profile's ground speed is
  // kOdoSpeed; a vehicle speed signal that is not the selected source is not.)
  if (o.updated & vehicle::kOdoSpeed) out.flags |= BLVD_ODO_SPEED;
  if (o.updated & vehicle::kOdoYawRate) out.flags |= BLVD_ODO_YAW_RATE;
  if (o.updated & vehicle::kOdoWheelSpeeds) out.flags |= BLVD_ODO_WHEEL_SPEEDS;
  if (o.updated & vehicle::kOdoGear) out.flags |= BLVD_ODO_GEAR;
  return out;
}

void RuntimeSink::onEvent(const Event& e) {
  const blvd_status s =
      e.type == EventType::Gnss ? blvd_feed_gnss(rt_, &e.gnss) : blvd_feed_odometry(rt_, &e.odometry);
  if (s != BLVD_OK) {
    ++failures_;
    last_ = s;
  }
}

// Collects the decoder's fixes and diagnostics for the replayer.
struct Replayer::NmeaOut final : gnss::NmeaDecoder::Handler {
  Replayer* r = nullptr;
  uint64_t last_line = 0;
  void onSentence(const gnss::Sentence& s, const gnss::NmeaRecord*) override { last_line = s.line; }
  void onFix(const gnss::Fix& f) override {
    if (!(f.flags & gnss::kFixHasTime) || !std::isfinite(f.t_unix)) {
      ++r->stats_.gnss_untimed;
      return;
    }
    Event e;
    e.type = EventType::Gnss;
    e.gnss = toBlvd(f);
    e.t = e.gnss.t;
    e.line = last_line;
    r->gnss_queue_.push_back(e);
  }
  void onDiagnostic(const gnss::NmeaDiagnostic& d) override {
    // d.message starts "line N, byte B: ..."; name the file in front, as "file:N: ...".
    r->warn(r->desc_.nmea_path + ":" + std::to_string(d.line) + ": " + d.message);
  }
};

Replayer::Replayer() : nmea_out_(std::make_unique<NmeaOut>()) { nmea_out_->r = this; }
Replayer::~Replayer() = default;

void Replayer::warn(std::string msg) {
  ++stats_.bad_lines;
  if (desc_.strict && error_.empty()) error_ = msg;
  if (warnings_.size() < kMaxWarnings) warnings_.push_back(std::move(msg));
}

blvd_status Replayer::open(const ReplayDesc& desc, std::string& err) {
  desc_ = desc;
  if (!(desc_.speed > 0) || !std::isfinite(desc_.speed)) desc_.speed = 1;
  stats_ = Stats{};
  warnings_.clear();
  error_.clear();
  io_error_ = false;
  gnss_queue_.clear();
  have_gnss_ = have_odo_ = primed_ = false;
  offset_ = desc_.has_offset ? desc_.offset_s : 0;
  stop_.store(false);
  decoder_.reset();

  const bool nmea = desc_.nmea_stream || !desc_.nmea_path.empty();
  const bool can = desc_.candump_stream || !desc_.candump_path.empty();
  if (!nmea && !can) {
    err = "replay: no NMEA and no candump log given";
    return BLVD_ERR_INVALID_ARG;
  }
  nmea_done_ = !nmea;
  can_done_ = !can;
  if (nmea) {
    if (desc_.nmea_stream) {
      nmea_in_ = desc_.nmea_stream;
      if (desc_.nmea_path.empty()) desc_.nmea_path = "<nmea>";
    } else {
      auto f = std::make_unique<std::ifstream>(desc_.nmea_path, std::ios::binary);
      if (!*f) {
        err = desc_.nmea_path + ": cannot open";
        return BLVD_ERR_IO;
      }
      nmea_file_ = std::move(f);
      nmea_in_ = nmea_file_.get();
    }
  }
  if (can) {
    if (desc_.dbc_path.empty()) {
      err = "replay: a candump log needs a DBC (dbc_path)";
      return BLVD_ERR_INVALID_ARG;
    }
    // The vehicle module's statuses are the C API's values (core/status.h).
    if (const core::Status v = dbc_.load(desc_.dbc_path, err); v != core::Status::Ok) return static_cast<blvd_status>(v);
    vehicle::ProfileDesc pd = desc_.profile;
    if (!desc_.vehicle.empty() && !vehicle::parseVehicle(desc_.vehicle, pd.vehicle)) {
      err = "replay: unknown vehicle profile \"" + desc_.vehicle + "\" (toyota, vw_mqb, hyundai)";
      return BLVD_ERR_INVALID_ARG;
    }
    if (const core::Status v = profile_.create(pd, dbc_, err); v != core::Status::Ok) return static_cast<blvd_status>(v);
    if (desc_.candump_stream) {
      candump_.attach(*desc_.candump_stream, desc_.candump_path.empty() ? "<candump>" : desc_.candump_path);
    } else {
      const blvd_status s = candump_.open(desc_.candump_path);
      if (s != BLVD_OK) {
        err = candump_.error();
        return s;
      }
    }
  }
  return BLVD_OK;
}

bool Replayer::pullGnss() {
  while (!have_gnss_) {
    if (!gnss_queue_.empty()) {
      gnss_head_ = gnss_queue_.front();
      gnss_queue_.pop_front();
      have_gnss_ = true;
      break;
    }
    if (nmea_done_ || !error_.empty()) break;
    char buf[kChunk];
    nmea_in_->read(buf, sizeof buf);
    const std::streamsize n = nmea_in_->gcount();
    if (n > 0) decoder_.feed(buf, static_cast<size_t>(n), *nmea_out_);
    if (!*nmea_in_) {
      if (nmea_in_->bad()) {
        error_ = desc_.nmea_path + ": read error";
        io_error_ = true;
        return false;
      }
      decoder_.finish(*nmea_out_);
      nmea_done_ = true;
    }
  }
  return have_gnss_;
}

bool Replayer::pullOdometry() {
  can::Record rec;
  vehicle::Odometry odo;
  while (!have_odo_ && !can_done_ && error_.empty()) {
    switch (candump_.next(rec)) {
      case can::CandumpReader::Result::Frame:
        ++stats_.frames;
        // A frame that changed nothing blvd_odometry carries (the steering angle, a
        // vehicle speed that is not the selected source) makes no event.
        if (profile_.consume(rec.frame, odo) && toBlvd(odo).flags != 0) {
          odo_head_ = Event{};
          odo_head_.type = EventType::Odometry;
          odo_head_.odometry = toBlvd(odo);
          odo_head_.t = odo.t;  // candump clock until delivered
          odo_head_.line = rec.line;
          have_odo_ = true;
        }
        break;
      case can::CandumpReader::Result::BadLine:
        warn(candump_.error());
        break;
      case can::CandumpReader::Result::End:
        can_done_ = true;
        break;
      case can::CandumpReader::Result::IoError:
        error_ = candump_.error();
        io_error_ = true;
        can_done_ = true;
        break;
    }
  }
  return have_odo_;
}

bool Replayer::prime() {
  pullGnss();
  pullOdometry();
  if (!error_.empty()) return false;
  if (!desc_.has_offset && have_gnss_ && have_odo_) offset_ = gnss_head_.t - odo_head_.t;
  primed_ = true;
  return true;
}

Replayer::Step Replayer::next(Event& out) {
  if (!error_.empty()) return Step::Error;
  if (!primed_ && !prime()) return Step::Error;
  pullGnss();
  pullOdometry();
  if (!error_.empty()) return Step::Error;
  if (!have_gnss_ && !have_odo_) return Step::End;
  const bool gnss_first = have_gnss_ && (!have_odo_ || gnss_head_.t <= odo_head_.t + offset_);
  if (gnss_first) {
    out = gnss_head_;
    have_gnss_ = false;
    ++stats_.gnss;
  } else {
    out = odo_head_;
    out.t += offset_;
    out.odometry.t = out.t;
    have_odo_ = false;
    ++stats_.odometry;
  }
  return Step::Event;
}

blvd_status Replayer::run(Sink& sink, std::string& err) {
  using Clock = std::chrono::steady_clock;
  bool started = false;
  double t0 = 0;
  Clock::time_point wall0;
  Event e;
  while (!stop_.load()) {
    const Step s = next(e);
    if (s == Step::End) break;
    if (s == Step::Error) {
      err = error_;
      return io_error_ ? BLVD_ERR_IO : BLVD_ERR_CORRUPT;
    }
    if (desc_.pace == Pace::RealTime) {
      if (!started) {
        started = true;
        t0 = e.t;
        wall0 = Clock::now();
      } else if (e.t > t0) {
        const auto due = wall0 + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>((e.t - t0) / desc_.speed));
        std::this_thread::sleep_until(due);
      }
    }
    sink.onEvent(e);
  }
  return BLVD_OK;
}

}  // namespace blvd::replay
