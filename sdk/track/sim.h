// A deterministic drive simulator on the street graph, for the map-matching
// benchmark and tests (and, later, samples/sim_feed): a vehicle follows a
// seeded route with a pure-pursuit controller and a curvature-limited speed
// profile; it emits GNSS fixes (Gaussian noise, dropped fixes, one outage) and
// odometry (speed and yaw rate with scale, bias and noise), with the truth at
// every GNSS epoch.
//
// The route is graph/route.h's seededRoute with no cell driven twice (the
// truth is a cell sequence); the noise draws from core/rng.h, so the same seed
// gives the same drive with every standard library.
//
// Contract: pure function of (graph, frame, desc); allocates its outputs.
#pragma once
#include <cstdint>
#include <vector>

#include "geo/local_frame.h"
#include "graph/street_graph.h"
#include "track/types.h"

namespace blvd::track {

struct SimDesc {
  uint64_t seed = 1;
  uint32_t route_cells = 40;     // cells in the route
  // Where the drive begins. By default a seeded street (simRoute); a chained
  // drive instead begins where an earlier one ended (SimTrace::end_cell and
  // end_arc_m): its route starts with that cell and the car pulls away from
  // that arc at start_speed_mps, as a car parked at the end of one trip starts
  // the next.
  uint32_t first_cell = kNoCell;
  double start_arc_m = 0;        // along first_cell (with first_cell only)
  double start_speed_mps = -1;   // negative: the speed profile's (0.6 x cruise at most)
  // The car parks halfway along the route's last cell instead of driving on
  // to its end (a junction, often at the edge of the map): where a chained
  // drive starts, as cars park along streets.
  bool park_mid_last_cell = false;
  double dt = 0.01;              // integration step, seconds
  double lateral_m = 1.8;        // two-way streets: driving this far right of the centre line
                                 // (one-way streets: the centre; lane.h)
  // Lane keeping: the car wanders about its lane's centre line, a first-order
  // Gauss-Markov process in the distance driven with this standard deviation
  // (SDLP, "standard deviation of lateral position", 0.2-0.3 m for attentive
  // drivers in driving studies) and correlation length. 0: on the line.
  double lane_wander_m = 0.25;
  double lane_wander_length_m = 40;
  double cruise_mps = 12;        // top speed
  double min_speed_mps = 3;      // slowest (tight hairpins)
  double lat_accel = 2.0;        // m/s^2, sets the speed through curves
  double accel = 1.5, decel = 2.5;  // m/s^2
  // GNSS
  double gnss_rate_hz = 1;
  double gnss_sigma_m = 5;       // per axis
  double gnss_speed_sigma = 0.3; // per axis of the velocity, m/s
  double drop_fraction = 0.1;    // fixes lost at random
  double outage_s = 20;          // one outage of this length (0: none)
  double outage_at = 0.4;        // its start, as a fraction of the drive
  // Odometry
  double odo_rate_hz = 50;
  double speed_scale = 1.01;     // wheel radius error
  double speed_noise = 0.05;     // m/s
  double yaw_bias_dps = 0.2;
  double yaw_noise_dps = 0.3;
};

struct SimSample {
  double t = 0;
  double e = 0, n = 0;      // true position
  double heading_deg = 0;   // true heading
  double speed_mps = 0;
  uint32_t cell = kNoCell;  // the route's cell at the vehicle's progress
  double arc_m = 0;         // along that cell
};

struct SimTrace {
  std::vector<uint32_t> route;
  std::vector<GnssFix> fixes;          // in time order; dropped ones and the outage left out
  std::vector<Odometry> odometry;      // in time order
  std::vector<SimSample> epochs;       // the truth at every GNSS epoch, dropped ones included
  std::vector<uint8_t> epoch_has_fix;  // per epoch
  double outage_begin = 0, outage_end = 0;
  double duration_s = 0, distance_m = 0;
  double start_e = 0, start_n = 0, start_heading_deg = 0;  // where the car was at t = 0
  // Where the car stopped: its cell and the arc along it (the next chained
  // drive's SimDesc::first_cell / start_arc_m), its position and heading.
  uint32_t end_cell = kNoCell;
  double end_arc_m = 0;
  double end_e = 0, end_n = 0, end_heading_deg = 0;
};

// A route of `cells` connected cells, no cell twice, from a seeded start or
// from `first` when it is a cell of the graph (graph::seededRoute).
std::vector<uint32_t> simRoute(const graph::StreetGraph& g, uint32_t cells, uint64_t seed, uint32_t first = kNoCell);

// Drives the route for `desc`; an empty trace when the graph has no usable route.
SimTrace simulateDrive(const graph::StreetGraph& g, const geo::LocalFrame& frame, const SimDesc& desc);

}  // namespace blvd::track
