// Google Benchmark of the tracker's update cost (median <= 20 us per
// update). Drives on the fixture package (sdk/track/sim.h, 1 Hz fixes at
// sigma 5 m, 50 Hz odometry) are tracked once to record the map matcher's
// observations; then
//   BM_MatcherStep   one HMM step (MapMatcher::step), the "update" the target bounds
//                    (`blvd bench track` reports the same as update_us_p50);
//   BM_TrackerSecond one second of input: a fix, 50 odometry samples and
//                    Tracker::update (EKF + HMM + pose).
// Each runs 5 repetitions of a mean over many steps; the median of those means
// (CPU time) is checked. Usage:
//   bench_tracker PACKAGE [--max-step-us US] [benchmark flags]
// exits 1 when BM_MatcherStep's median exceeds --max-step-us (default 20; 0: no check)
// or when there is no such median to check.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "stream/city.h"
#include "track/map_matcher.h"
#include "track/sim.h"
#include "track/tracker.h"

namespace {

using namespace blvd;

struct Drive {
  track::SimTrace trace;
  std::vector<track::MatchObservation> observations;
};

stream::City g_city;
std::vector<Drive> g_drives;

void prepare(const std::string& package) {
  std::string err;
  if (g_city.open(package, err) != core::Status::Ok) {
    std::fprintf(stderr, "bench_tracker: %s\n", err.c_str());
    std::exit(2);
  }
  for (uint64_t seed = 2000; seed < 2010; ++seed) {
    track::SimDesc sd;
    sd.seed = seed;
    sd.route_cells = 60;
    Drive d;
    d.trace = track::simulateDrive(g_city.graph(), g_city.frame(), sd);
    if (d.trace.epochs.empty()) continue;
    track::Tracker tr(g_city.frame(), &g_city.graph(), track::TrackerDesc{});
    size_t o = 0;
    uint64_t steps = 0;
    for (const track::GnssFix& f : d.trace.fixes) {
      for (; o < d.trace.odometry.size() && d.trace.odometry[o].t <= f.t; ++o) tr.feedOdometry(d.trace.odometry[o]);
      tr.feedGnss(f);
      tr.update(f.t);
      if (tr.matcher()->stats().steps != steps) {
        steps = tr.matcher()->stats().steps;
        d.observations.push_back(tr.matcher()->lastObservation());
      }
    }
    g_drives.push_back(std::move(d));
  }
}

void BM_MatcherStep(benchmark::State& state) {
  track::MapMatcher m(g_city.graph());
  size_t d = 0, i = 0;
  for (auto _ : state) {
    if (i == g_drives[d].observations.size()) {
      state.PauseTiming();
      d = (d + 1) % g_drives.size();
      i = 0;
      m.reset();
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(m.step(g_drives[d].observations[i++]));
  }
}
BENCHMARK(BM_MatcherStep)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);

void BM_TrackerSecond(benchmark::State& state) {
  size_t d = 0, f = 0, o = 0;
  auto tracker = std::make_unique<track::Tracker>(g_city.frame(), &g_city.graph(), track::TrackerDesc{});
  for (auto _ : state) {
    const track::SimTrace& tr = g_drives[d].trace;
    if (f == tr.fixes.size()) {
      state.PauseTiming();
      d = (d + 1) % g_drives.size();
      f = o = 0;
      tracker = std::make_unique<track::Tracker>(g_city.frame(), &g_city.graph(), track::TrackerDesc{});
      state.ResumeTiming();
      continue;
    }
    const track::GnssFix& fix = tr.fixes[f++];
    for (; o < tr.odometry.size() && tr.odometry[o].t <= fix.t; ++o) tracker->feedOdometry(tr.odometry[o]);
    tracker->feedGnss(fix);
    benchmark::DoNotOptimize(tracker->update(fix.t));
  }
}
BENCHMARK(BM_TrackerSecond)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);

// Remembers the median of each benchmark while printing as usual.
class MedianReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs)
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name == "median")
        medians[r.run_name.function_name] = r.GetAdjustedCPUTime();
    ConsoleReporter::ReportRuns(runs);
  }
  // CPU microseconds: wall time on a shared machine counts the other processes too.
  std::map<std::string, double> medians;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: %s PACKAGE [--max-step-us US] [benchmark flags]\n", argv[0]);
    return 2;
  }
  double max_step_us = 20;
  std::vector<char*> args{argv[0]};
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--max-step-us") == 0 && i + 1 < argc) max_step_us = std::atof(argv[++i]);
    else args.push_back(argv[i]);
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 2;
  prepare(argv[1]);
  if (g_drives.empty()) {
    std::fprintf(stderr, "bench_tracker: no drivable route in %s\n", argv[1]);
    return 2;
  }
  MedianReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  benchmark::Shutdown();
  if (max_step_us <= 0) return 0;
  // A filter or a renamed benchmark that leaves no median fails too: the
  // check must have something to check.
  const auto it = rep.medians.find("BM_MatcherStep");
  if (it == rep.medians.end()) {
    std::fprintf(stderr, "FAIL: no median of BM_MatcherStep (was it filtered out or renamed?)\n");
    return 1;
  }
  if (it->second > max_step_us) {
    std::fprintf(stderr, "FAIL: BM_MatcherStep median %.2f us > %.2f us\n", it->second, max_step_us);
    return 1;
  }
  std::printf("BM_MatcherStep median %.2f us <= %.2f us\n", it->second, max_step_us);
  return 0;
}
