// Online map matching onto the street graph's cells (half-edges): a hidden
// Markov model after Newson & Krumm 2009 ("Hidden Markov Map Matching Through
// Noise and Sparseness", ACM GIS '09), solved with a fixed-lag Viterbi.
//
// - States: candidate half-edges near the observation (N&K §4.1), from a
//   uniform grid over the segments (graph/segment_grid.h), at most K per step, the
//   K most likely by emission.
// - Emission (N&K §4.2, eq. 1): Gaussian in the distance from the observation to
//   the half-edge, sigma = sqrt(sigma_obs^2 + road_sigma^2); times a von Mises
//   term in the angle between the observed heading and the half-edge's
//   direction, so of two twin half-edges the one going the vehicle's way wins
//   (an extension of N&K, who match undirected roads).
// - Transition (N&K §4.3, eq. 2): exponential in |d_obs - d_route|, where d_obs
//   is the straight ("great circle", N&K) distance between consecutive
//   observations and d_route the driving distance between the two candidates'
//   matched points, found by a Dijkstra over successors bounded by a distance
//   cap and an expansion cap (N&K §4.3 also bound the route search). beta grows
//   with the observation sigma (N&K fit beta from data; here the positions come
//   from a filter whose sigma is known).
// - Breaks (N&K §5.1): a step with no reachable candidate restarts the chain
//   from its emissions.
// - Decoding: Viterbi over a window of `lag` steps. The head (the best state of
//   the newest step) is the online answer; backtracking `lag` steps from it gives
//   the settled answer for the step `lag` steps ago (fixed-lag decoding, e.g.
//   Goh et al. 2012, "Online map-matching based on Hidden Markov model for
//   real-time traffic sensing applications", §IV). The confidence is the
//   forward filter's posterior probability of the head state.
//
// Memory: everything is sized at construction (K candidates x (lag + 1) steps,
// the route-search heap, per-cell scratch tables sized by the search bounds,
// not by the city); step() never allocates.
// Contract: one thread; deterministic (fixed hashing, no unordered iteration).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "graph/graph_source.h"
#include "graph/street_graph.h"
#include "track/cell_scratch.h"

namespace blvd::track {

// Zero means "default" for every field (see matcherDefaults()).
struct MatcherDesc {
  uint32_t max_candidates = 0;   // K, states per step; default 8 (at most 32)
  uint32_t lag = 0;              // fixed-lag window in steps; default 4
  double grid_cell_m = 0;        // spatial index cell; default 50
  double search_min_m = 0;       // candidate radius is clamp(search_sigmas x sigma, min, max); default 25
  double search_max_m = 0;       // default 200
  double search_sigmas = 0;      // default 4
  double road_sigma_m = 0;       // lane offset / road width in the emission; default 2.5
  double heading_sigma_deg = 0;  // road direction vs vehicle heading, added to the observed sigma; default 10
  double beta_m = 0;             // transition scale: beta = beta_m + beta_sigma_factor x sigma_obs; default 2
  double beta_sigma_factor = 0;  // default 1
  double route_slack_m = 0;      // route search cap = route_factor x d_obs + route_slack_m; default 60
  double route_factor = 0;       // default 2
  uint32_t max_expansions = 0;   // route search heap capacity per source; default 256
  double backward_tolerance_m = 0;  // a small step back on the same cell counts as standing still; default 5
  double score_floor = 0;        // Viterbi scores are kept within this many nats of the best; default 20
};

MatcherDesc matcherDefaults(const MatcherDesc& desc);

struct MatchObservation {
  double t = 0;
  double e = 0, n = 0;        // local frame metres
  double sigma_m = 5;         // 1-sigma position error
  double heading_rad = 0;     // clockwise from north
  double heading_sigma_rad = 0;  // <= 0: no heading (standing still, not yet known)
  // The raw GNSS fix of this step, when there is one (fix_sigma_m > 0). The
  // filtered position above is precise but its errors are correlated from step
  // to step (and pulled toward the matched street by the map aid); the fixes'
  // errors are independent, so their distances add evidence that accumulates
  // honestly, e.g. between two parallel streets.
  double fix_e = 0, fix_n = 0;
  double fix_sigma_m = 0;
};

// A point on a cell.
struct CellPoint {
  uint32_t cell = graph::kNone;
  double arc_m = 0;        // along the cell's polyline
  double lateral_m = 0;    // observation's offset, positive right of the cell's direction
  double dist_m = 0;       // |lateral| (distance to the polyline)
  double heading_rad = 0;  // direction of the cell at arc_m, clockwise from north
  double e = 0, n = 0;     // the point on the polyline
};

struct MatchStats {
  uint64_t steps = 0;
  uint64_t breaks = 0;          // chain restarts (no candidate reachable)
  uint64_t empty_steps = 0;     // no candidate within the search radius
  uint64_t route_searches = 0;
  uint64_t route_expansions = 0;
  uint64_t route_truncated = 0;  // searches stopped by the expansion cap (or the cells they may hold)
  uint64_t candidates_dropped = 0;  // street segments past the half-edges a candidate search may hold
};

class MapMatcher {
 public:
  // Builds the spatial index and allocates every buffer. The graph must outlive the matcher.
  MapMatcher(const graph::StreetGraph& g, const MatcherDesc& desc = MatcherDesc{});
  // Over any graph source (a package's paged graph), with its own spatial
  // index (desc.grid_cell_m is then unused). The source must outlive the matcher.
  MapMatcher(const graph::GraphSource& g, const MatcherDesc& desc = MatcherDesc{});

  // Forgets the chain (a new trip).
  void reset();

  // One HMM step. False when no candidate was found (the head is then invalid).
  bool step(const MatchObservation& obs);

  // The online answer of the last step; cell == kNone when there is none.
  const CellPoint& head() const { return head_; }
  // Posterior probability of the head state under the forward filter, [0, 1].
  double confidence() const { return confidence_; }
  // The fixed-lag decision: the state of the step `lag` steps before the last,
  // on the best path through the window; cell == kNone until there are lag + 1 steps.
  const CellPoint& settled() const { return settled_; }
  double settledTime() const { return settled_t_; }

  // Moves a matched point along the graph to a new position: re-projects on its
  // cell and, past the cell's end, onto the successor that fits best (distance
  // and heading; up to two junctions). For the pose between HMM steps.
  CellPoint follow(const CellPoint& from, double e, double n, double heading_rad, double heading_sigma_rad) const;

  // Projects (e, n) on cell h.
  CellPoint project(uint32_t h, double e, double n) const;

  // The candidates of the last step: point, emission log-likelihood, Viterbi
  // score (0 for the best, -inf when unreachable) and forward posterior.
  uint32_t candidateCount() const;
  const CellPoint& candidate(uint32_t i) const;
  double candidateEmission(uint32_t i) const;
  double candidateScore(uint32_t i) const;
  double candidatePosterior(uint32_t i) const;

  // The observation of the last step (to replay a drive through another matcher).
  const MatchObservation& lastObservation() const { return last_obs_; }

  const MatcherDesc& desc() const { return d_; }
  const MatchStats& stats() const { return stats_; }
  const graph::GraphSource& graph() const { return g_; }
  // Bytes of the spatial index the matcher built for itself (0 over a source
  // it was given: the source owns its index).
  size_t indexBytes() const { return owned_ ? owned_->bytes() : 0; }
  size_t bytes() const;

 private:
  struct Candidate {
    CellPoint p;
    double log_e = 0;
  };
  struct Column {
    double t = 0, e = 0, n = 0;
    uint32_t count = 0;
    Candidate* cand = nullptr;  // K entries
    double* delta = nullptr;    // Viterbi log score
    double* alpha = nullptr;    // forward probability (normalised)
    uint8_t* back = nullptr;    // best predecessor in the previous column, 0xff: chain start
  };
  struct HeapItem {
    float d;
    uint32_t cell;
  };

  void findCandidates(const MatchObservation& obs, Column& col);
  size_t nearestSegments(double px, double py, double r);
  uint32_t scoreCandidates(const MatchObservation& obs, size_t touched, Column& col);
  void keepCandidate(Column& col, uint32_t& count, uint32_t h, double log_e, uint32_t listed, bool reversed,
                     double heading);
  void placeCandidates(const MatchObservation& obs, Column& col, uint32_t count);
  // Route distances from candidate `from` of the previous column to every
  // candidate of `to` (out[j], < 0 when unreachable within the cap).
  void routeDistances(const Candidate& from, const Column& to, double cap, double* out);
  Column& column(uint64_t step) { return cols_[step % cols_.size()]; }

  MapMatcher(std::unique_ptr<graph::MemoryGraph> owned, const MatcherDesc& desc);
  MapMatcher(std::unique_ptr<graph::MemoryGraph> owned, const graph::GraphSource* g, const MatcherDesc& desc);

  std::unique_ptr<graph::MemoryGraph> owned_;  // when built over a StreetGraph
  const graph::GraphSource& g_;
  MatcherDesc d_;
  std::vector<Column> cols_;
  std::vector<Candidate> cand_store_;
  std::vector<double> delta_store_, alpha_store_, dist_store_;
  std::vector<uint8_t> back_store_;
  struct Seen {  // the nearest segment of a half-edge (one per twin pair) in the search radius
    float dist;
    uint32_t point;
    float t;
  };
  struct Reached {  // a cell the route search pushed
    float dist;
    bool done;
  };
  // Scratch of the bounded searches, sized by their bounds, not by the city.
  CellScratch<Seen> seen_;
  std::vector<uint32_t> touched_;  // the half-edges seen_ holds, in the order found
  CellScratch<Reached> reached_;
  CellScratch<uint8_t> targets_;   // candidate cell -> its index in the column
  std::vector<HeapItem> heap_;

  uint64_t steps_ = 0;  // steps in the current chain window (column index of the next step)
  MatchObservation last_obs_;
  CellPoint head_, settled_;
  double confidence_ = 0, settled_t_ = 0;
  MatchStats stats_;
};

}  // namespace blvd::track
