#include "sim/sim_feed.h"
#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>

#include "can/candump.h"

namespace blvd::sim {
namespace {

using blvd::core::kPi;

// The odometry a car's sensors report for one simulated sample: the wheel
// speeds split by the yaw rate across the track, the steering wheel angle from
// a bicycle model, gear D.
vehicle::Odometry carOdometry(const track::Odometry& o, const FeedDesc& d) {
  vehicle::Odometry c;
  const double w = o.yaw_rate_dps * kPi / 180.0;  // positive to the left: the right wheels run faster
  const double half = 0.5 * d.track_width_m * w;
  c.speed_mps = o.speed_mps;
  c.vehicle_speed_mps = o.speed_mps;
  c.yaw_rate_dps = o.yaw_rate_dps;
  c.wheel_speeds_mps[0] = std::max(0.0, o.speed_mps - half);  // FL
  c.wheel_speeds_mps[1] = std::max(0.0, o.speed_mps + half);  // FR
  c.wheel_speeds_mps[2] = std::max(0.0, o.speed_mps - half);  // RL
  c.wheel_speeds_mps[3] = std::max(0.0, o.speed_mps + half);  // RR
  const double road_wheel = o.speed_mps > 1 ? std::atan(d.wheelbase_m * w / o.speed_mps) : 0;
  c.steering_deg = std::clamp(road_wheel * 180.0 / kPi * d.steering_ratio, -500.0, 500.0);
  c.gear = vehicle::Gear::Drive;
  c.valid = vehicle::kOdoSpeed | vehicle::kOdoVehicleSpeed | vehicle::kOdoYawRate | vehicle::kOdoSteering |
            vehicle::kOdoWheelSpeeds | vehicle::kOdoGear;
  return c;
}

}  // namespace

blvd_status makeFeed(const graph::StreetGraph& g, const geo::LocalFrame& frame, const vehicle::Profile& profile,
                     const FeedDesc& desc, Feed& out, std::string& err) {
  out = Feed{};
  const track::SimTrace trace = track::simulateDrive(g, frame, desc.drive);
  if (trace.epochs.empty()) {
    err = "sim: no drivable route in the graph for seed " + std::to_string(desc.drive.seed);
    return BLVD_ERR_NOT_FOUND;
  }
  const double t0 = desc.start_unix;
  out.route = trace.route;
  out.start_unix = t0;
  out.duration_s = trace.duration_s;
  out.distance_m = trace.distance_m;
  out.end_cell = trace.end_cell;
  out.end_arc_m = trace.end_arc_m;
  out.end_e = trace.end_e;
  out.end_n = trace.end_n;
  out.end_heading_deg = trace.end_heading_deg;
  out.outage_begin = t0 + trace.outage_begin;
  out.outage_end = t0 + trace.outage_end;

  // NMEA: one epoch per truth sample; the kept fixes are those with a fix, in order.
  size_t next_fix = 0;
  for (size_t e = 0; e < trace.epochs.size(); ++e) {
    const track::SimSample& s = trace.epochs[e];
    TruthRow row;
    row.t = t0 + s.t;
    row.e = s.e;
    row.n = s.n;
    double h = 0;
    frame.reverse(geo::Enu{s.e, s.n, 0}, row.lat, row.lon, h);
    row.heading_deg = s.heading_deg;
    row.speed_mps = s.speed_mps;
    row.cell = s.cell;
    row.arc_m = s.arc_m;
    row.fix = trace.epoch_has_fix[e] != 0;
    out.truth.push_back(row);

    gnss::Fix f = gnss::Fix::empty();
    f.t_unix = row.t;
    f.flags = gnss::kFixHasTime;
    f.mode = gnss::kModeNoFix;
    if (row.fix && next_fix < trace.fixes.size()) {
      const track::GnssFix& k = trace.fixes[next_fix++];
      f.lat = k.lat;
      f.lon = k.lon;
      f.alt = k.alt;
      f.speed_mps = k.speed_mps;
      f.track_deg = k.track_deg;
      f.hdop = k.hdop;
      f.h_acc_m = k.h_acc_m;
      f.mode = gnss::kMode3D;
      f.flags |= gnss::kFixHasLatLon | gnss::kFixHasAlt | gnss::kFixHasSpeed | gnss::kFixHasTrack |
                 gnss::kFixHasHdop | gnss::kFixHasHAcc;
    }
    out.nmea_epoch_begin.push_back(out.nmea.size());
    gnss::appendEpoch(f, desc.nmea, out.nmea);
  }

  // CAN: every message of the profile per odometry sample.
  for (const track::Odometry& o : trace.odometry)
    if (const core::Status st = profile.encode(carOdometry(o, desc), t0 + o.t, out.frames, err); st != core::Status::Ok)
      return static_cast<blvd_status>(st);  // the same values (core/status.h)
  return BLVD_OK;
}

std::string candumpText(const Feed& feed, const std::string& iface) {
  std::string s;
  s.reserve(feed.frames.size() * 48);
  for (const vehicle::Frame& f : feed.frames) {
    s += can::formatLine(f, iface);
    s += '\n';
  }
  return s;
}

void writeTruthCsv(const Feed& feed, std::ostream& out) {
  out << "t,e,n,lat,lon,heading_deg,speed_mps,cell,arc_m,fix\n";
  char buf[256];
  for (const TruthRow& r : feed.truth) {
    std::snprintf(buf, sizeof buf, "%.3f,%.3f,%.3f,%.9f,%.9f,%.2f,%.3f,%u,%.3f,%d\n", r.t, r.e, r.n, r.lat, r.lon,
                  r.heading_deg, r.speed_mps, r.cell, r.arc_m, r.fix ? 1 : 0);
    out << buf;
  }
}

void writeTruthJson(const Feed& feed, std::ostream& out) {
  char buf[320];
  std::snprintf(buf, sizeof buf, "{\"start_unix\":%.3f,\"duration_s\":%.3f,\"distance_m\":%.3f,\"outage\":[%.3f,%.3f],",
                feed.start_unix, feed.duration_s, feed.distance_m, feed.outage_begin, feed.outage_end);
  out << buf << "\"route\":[";
  for (size_t i = 0; i < feed.route.size(); ++i) out << (i ? "," : "") << feed.route[i];
  out << "],\"cells\":[";  // the cell sequence the truth visits, each cell once per visit
  bool first = true;
  for (size_t i = 0; i < feed.truth.size(); ++i)
    if (i == 0 || feed.truth[i].cell != feed.truth[i - 1].cell) {
      out << (first ? "" : ",") << feed.truth[i].cell;
      first = false;
    }
  out << "],\"epochs\":[";
  for (size_t i = 0; i < feed.truth.size(); ++i) {
    const TruthRow& r = feed.truth[i];
    std::snprintf(buf, sizeof buf,
                  "%s{\"t\":%.3f,\"e\":%.3f,\"n\":%.3f,\"lat\":%.9f,\"lon\":%.9f,\"heading_deg\":%.2f,\"speed_mps\":%.3f,"
                  "\"cell\":%u,\"arc_m\":%.3f,\"fix\":%s}",
                  i ? "," : "", r.t, r.e, r.n, r.lat, r.lon, r.heading_deg, r.speed_mps, r.cell, r.arc_m,
                  r.fix ? "true" : "false");
    out << buf;
  }
  out << "]}\n";
}

}  // namespace blvd::sim
