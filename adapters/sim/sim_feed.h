// A simulated vehicle's device output: the drive of sdk/track/sim.h (a route
// through the street graph, vehicle model, GNSS noise, dropped fixes, one
// outage, odometry with scale, bias and noise) written as the bytes a real car
// produces: NMEA 0183 text (RMC + GGA + GST per epoch) and CAN frames encoded
// with a vehicle profile's DBC (Toyota by default), plus the ground truth.
//
// samples/sim_feed writes these to files, a pty, TCP or SocketCAN; `blvd bench
// track` and the trace tests parse them back through the adapters, so what is
// measured is the whole path a host uses.
//
//   blvd::sim::FeedDesc d;  d.drive.seed = 7;  d.drive.gnss_sigma_m = 5;
//   blvd::sim::Feed feed;
//   if (blvd::sim::makeFeed(graph, frame, profile, d, feed, err) != BLVD_OK) die(err);
//   std::string nmea = blvd::sim::nmeaText(feed), can = blvd::sim::candumpText(feed, "can0");
//
// Clock: every time is UTC Unix seconds, start_unix + the drive's time, on both
// streams and the truth (so a candump offset of 0 aligns them).
// Contract: pure function of its inputs; deterministic for a seed.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "blvd/blvd.h"
#include "geo/local_frame.h"
#include "gnss/nmea_writer.h"
#include "graph/street_graph.h"
#include "track/sim.h"
#include "vehicle/profile.h"

namespace blvd::sim {

struct FeedDesc {
  track::SimDesc drive;               // route, vehicle model, GNSS and odometry rates and noise
  double start_unix = 1767268800.0;   // 2026-01-01T12:00:00Z
  double track_width_m = 1.6;         // wheel speeds differ by yaw rate x track width
  double wheelbase_m = 2.7;           // steering wheel angle from the yaw rate (bicycle model)
  double steering_ratio = 15;
  gnss::NmeaWriterOptions nmea;
};

// The truth at one GNSS epoch (dropped and outage epochs included).
struct TruthRow {
  double t = 0;                  // UTC Unix seconds
  double e = 0, n = 0;           // local frame metres
  double lat = 0, lon = 0;
  double heading_deg = 0, speed_mps = 0;
  uint32_t cell = 0xffffffffu;   // the route's cell (graph half-edge)
  double arc_m = 0;              // along it
  bool fix = false;              // the receiver reported a fix at this epoch
};

struct Feed {
  std::vector<uint32_t> route;
  std::string nmea;                       // the whole NMEA stream, in time order
  std::vector<size_t> nmea_epoch_begin;   // byte offset in `nmea` where each truth epoch's sentences start
  std::vector<vehicle::Frame> frames;     // CAN frames in time order
  std::vector<TruthRow> truth;
  double start_unix = 0, duration_s = 0, distance_m = 0;
  double outage_begin = 0, outage_end = 0;  // UTC; equal when there is no outage
  // Where the car stopped (track::SimTrace): a chained drive starts there.
  uint32_t end_cell = 0xffffffffu;
  double end_arc_m = 0, end_e = 0, end_n = 0, end_heading_deg = 0;
};

// Simulates the drive and encodes it. BLVD_ERR_NOT_FOUND when the graph has no
// route for the seed; BLVD_ERR_INVALID_ARG (err names the signal) when a value
// does not fit the DBC.
blvd_status makeFeed(const graph::StreetGraph& g, const geo::LocalFrame& frame, const vehicle::Profile& profile,
                     const FeedDesc& desc, Feed& out, std::string& err);

// What makeFeed() needs, as files: a host or a sample gives paths and the
// vehicle's name (blvd_vehicle_from_name) and never touches the SDK's types.
struct FeedFiles {
  std::string package_path;                  // the .blvd whose street graph is driven (nothing else is read)
  std::string dbc_path;                      // the vehicle's DBC, for the CAN frames
  blvd_vehicle vehicle = BLVD_VEHICLE_TOYOTA;
};

// makeFeed() on the package's graph and frame with the DBC's profile. Also
// BLVD_ERR_IO / BLVD_ERR_CORRUPT / BLVD_ERR_NOT_FOUND (err names the file)
// when a file cannot be read or lacks what the drive needs.
blvd_status makeFeed(const FeedFiles& files, const FeedDesc& desc, Feed& out, std::string& err);

// The frames as a candump -l log (one "(t) iface ID#DATA" line each).
std::string candumpText(const Feed& feed, const std::string& iface);

// Ground truth as CSV: t,e,n,lat,lon,heading_deg,speed_mps,cell,arc_m,fix.
void writeTruthCsv(const Feed& feed, std::ostream& out);
// Ground truth as JSON: {"start_unix":..,"route":[cells],"epochs":[{t,e,n,...}], "cells":[run-length cell sequence]}.
void writeTruthJson(const Feed& feed, std::ostream& out);

}  // namespace blvd::sim
