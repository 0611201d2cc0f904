// The grid city the tracking tests drive on, and feeding a simulated drive
// (track/sim.h) to a Tracker in time order.
#pragma once
#include <cstddef>

#include "track/sim.h"
#include "track/tracker.h"
#include "track_test_util.h"

namespace blvd_test {

// A 9 x 9 grid of 70 m blocks, placed in Monaco.
inline const blvd::geo::LocalFrame& gridFrame() {
  static const blvd::geo::LocalFrame f(43.7384, 7.4246, 0);
  return f;
}
inline const blvd::graph::StreetGraph& gridCity() {
  static const blvd::graph::StreetGraph g = makeGrid(9, 70);
  return g;
}

// Feeds the trace's odometry, and its fixes stamped at or after `fixes_from`,
// in time order, updating at every GNSS epoch (and every 50 odometry samples);
// calls fn(epoch index, pose) at each epoch.
template <class Fn>
void replaySim(blvd::track::Tracker& tr, const blvd::track::SimTrace& trace, double fixes_from, Fn&& fn) {
  size_t fi = 0, oi = 0;
  while (fi < trace.fixes.size() && trace.fixes[fi].t < fixes_from) ++fi;
  for (size_t e = 0; e < trace.epochs.size(); ++e) {
    const double t = trace.epochs[e].t;
    for (;;) {
      const bool f = fi < trace.fixes.size() && trace.fixes[fi].t <= t;
      const bool o = oi < trace.odometry.size() && trace.odometry[oi].t <= t;
      if (!f && !o) break;
      if (f && (!o || trace.fixes[fi].t <= trace.odometry[oi].t)) {
        tr.feedGnss(trace.fixes[fi++]);
      } else {
        tr.feedOdometry(trace.odometry[oi++]);
        if (oi % 50 == 0) tr.update(trace.odometry[oi - 1].t);
      }
    }
    fn(e, tr.update(t));
  }
}

}  // namespace blvd_test
