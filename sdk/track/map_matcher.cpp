#include "track/map_matcher.h"
#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace blvd::track {
namespace {
using core::kPi;
constexpr double kDeg = kPi / 180.0;
constexpr double kNegInf = -std::numeric_limits<double>::infinity();
constexpr uint8_t kNoBack = 0xff;
constexpr uint32_t kMaxK = 32;

double orDefault(double v, double d) { return v > 0 ? v : d; }

// Bearing of a direction vector, clockwise from north.
double bearing(double dx, double dy) {
  const double a = std::atan2(dx, dy);
  return a < 0 ? a + 2 * kPi : a;
}

// Bounds of the per-cell scratch: half-edges (one per twin pair) a candidate
// search may hold, and cells a route search may reach per heap entry. Both far
// above what a search within its radius and expansion cap meets in San
// Francisco's grid; past them a search counts what it dropped.
constexpr uint32_t kSeenCells = 2048;
constexpr uint32_t kReachedPerExpansion = 8;
}  // namespace

MatcherDesc matcherDefaults(const MatcherDesc& in) {
  MatcherDesc d = in;
  if (d.max_candidates == 0) d.max_candidates = 8;
  d.max_candidates = std::min(d.max_candidates, kMaxK);
  if (d.lag == 0) d.lag = 4;
  d.grid_cell_m = orDefault(d.grid_cell_m, 50);
  d.search_min_m = orDefault(d.search_min_m, 25);
  d.search_max_m = orDefault(d.search_max_m, 200);
  d.search_sigmas = orDefault(d.search_sigmas, 4);
  d.road_sigma_m = orDefault(d.road_sigma_m, 2.5);
  d.heading_sigma_deg = orDefault(d.heading_sigma_deg, 10);
  d.beta_m = orDefault(d.beta_m, 2);
  d.beta_sigma_factor = orDefault(d.beta_sigma_factor, 1);
  d.route_slack_m = orDefault(d.route_slack_m, 60);
  d.route_factor = orDefault(d.route_factor, 2);
  if (d.max_expansions == 0) d.max_expansions = 256;
  d.backward_tolerance_m = orDefault(d.backward_tolerance_m, 5);
  d.score_floor = orDefault(d.score_floor, 20);
  return d;
}

MapMatcher::MapMatcher(const graph::StreetGraph& g, const MatcherDesc& desc)
    : MapMatcher(std::make_unique<graph::MemoryGraph>(g, matcherDefaults(desc).grid_cell_m), desc) {}

MapMatcher::MapMatcher(const graph::GraphSource& g, const MatcherDesc& desc) : MapMatcher(nullptr, &g, desc) {}

MapMatcher::MapMatcher(std::unique_ptr<graph::MemoryGraph> owned, const MatcherDesc& desc)
    : MapMatcher(std::move(owned), nullptr, desc) {}

MapMatcher::MapMatcher(std::unique_ptr<graph::MemoryGraph> owned, const graph::GraphSource* g, const MatcherDesc& desc)
    : owned_(std::move(owned)),
      g_(owned_ ? *owned_ : *g),
      d_(matcherDefaults(desc)),
      seen_(kSeenCells),
      reached_(kReachedPerExpansion * d_.max_expansions),
      targets_(d_.max_candidates) {
  const size_t K = d_.max_candidates, W = d_.lag + 1;
  cols_.resize(W);
  cand_store_.resize(K * W);
  delta_store_.resize(K * W);
  alpha_store_.resize(K * W);
  back_store_.resize(K * W);
  dist_store_.resize(K * K);
  for (size_t w = 0; w < W; ++w) {
    cols_[w].cand = &cand_store_[w * K];
    cols_[w].delta = &delta_store_[w * K];
    cols_[w].alpha = &alpha_store_[w * K];
    cols_[w].back = &back_store_[w * K];
  }
  touched_.assign(seen_.capacity(), 0);
  heap_.resize(d_.max_expansions);
}

size_t MapMatcher::bytes() const {
  return indexBytes() + cols_.capacity() * sizeof(Column) + cand_store_.capacity() * sizeof(Candidate) +
         (delta_store_.capacity() + alpha_store_.capacity() + dist_store_.capacity()) * sizeof(double) +
         back_store_.capacity() + seen_.bytes() + touched_.capacity() * 4 + reached_.bytes() + targets_.bytes() +
         heap_.capacity() * sizeof(HeapItem);
}

uint32_t MapMatcher::candidateCount() const { return steps_ ? cols_[(steps_ - 1) % cols_.size()].count : 0; }
const CellPoint& MapMatcher::candidate(uint32_t i) const { return cols_[(steps_ - 1) % cols_.size()].cand[i].p; }
double MapMatcher::candidateEmission(uint32_t i) const { return cols_[(steps_ - 1) % cols_.size()].cand[i].log_e; }
double MapMatcher::candidateScore(uint32_t i) const { return cols_[(steps_ - 1) % cols_.size()].delta[i]; }
double MapMatcher::candidatePosterior(uint32_t i) const { return cols_[(steps_ - 1) % cols_.size()].alpha[i]; }

void MapMatcher::reset() {
  steps_ = 0;
  head_ = settled_ = CellPoint{};
  confidence_ = settled_t_ = 0;
}

CellPoint MapMatcher::project(uint32_t h, double e, double n) const {
  CellPoint best;
  if (h >= g_.cellCount()) return best;
  const graph::HalfEdge he = g_.halfedge(h);
  const glm::dvec2 p(e, n);
  double best_d2 = 1e300, along = 0;
  for (uint32_t i = 0; i + 1 < he.pts_count; ++i) {
    const glm::dvec2 a = g_.point(he.pts_begin + i), b = g_.point(he.pts_begin + i + 1);
    const glm::dvec2 d = b - a;
    const double len2 = d.x * d.x + d.y * d.y;
    const double len = std::sqrt(len2);
    if (len < 1e-9) continue;
    const double t = std::clamp(((p.x - a.x) * d.x + (p.y - a.y) * d.y) / len2, 0.0, 1.0);
    const glm::dvec2 q = a + d * t;
    const double d2 = (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y);
    if (d2 < best_d2) {
      best_d2 = d2;
      best.cell = h;
      best.arc_m = along + t * len;
      best.dist_m = std::sqrt(d2);
      best.lateral_m = ((p.x - q.x) * d.y - (p.y - q.y) * d.x) / len;  // right = (dy, -dx)
      best.heading_rad = bearing(d.x, d.y);
      best.e = q.x;
      best.n = q.y;
    }
    along += len;
  }
  return best;
}

// The nearest segment of every half-edge (one per twin pair) within r of
// (px, py) into seen_; the half-edges found, in order, into touched_.
size_t MapMatcher::nearestSegments(double px, double py, double r) {
  seen_.clear();
  size_t touched = 0;
  g_.forSegmentsNear(px, py, r, [&](const graph::SegmentGrid::Entry& en) {
    const glm::dvec2 a = g_.point(en.point), b = g_.point(en.point + 1);
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len2 = dx * dx + dy * dy;
    const double t = len2 > 1e-18 ? std::clamp(((px - a.x) * dx + (py - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
    const double qx = a.x + dx * t - px, qy = a.y + dy * t - py;
    const double dist = std::sqrt(qx * qx + qy * qy);
    if (dist > r) return;
    const uint32_t h = en.halfedge;
    bool fresh = false;
    Seen* s = seen_.insert(h, &fresh);
    if (!s) {
      ++stats_.candidates_dropped;
      return;
    }
    if (fresh) touched_[touched++] = h;
    else if (dist >= s->dist) return;
    *s = Seen{static_cast<float>(dist), en.point, static_cast<float>(t)};
  });
  return touched;
}

// Cell h with emission log-likelihood log_e into the column's `count`
// kept, the K best (sorted, ties to the lower cell id). The listed half-edge
// its segment came from, and whether h is its twin, are stashed in arc_m and
// lateral_m until placeCandidates.
void MapMatcher::keepCandidate(Column& col, uint32_t& count, uint32_t h, double log_e, uint32_t listed, bool reversed,
                               double heading) {
  const uint32_t K = d_.max_candidates;
  if (count == K && !(log_e > col.cand[K - 1].log_e || (log_e == col.cand[K - 1].log_e && h < col.cand[K - 1].p.cell)))
    return;
  uint32_t pos = count < K ? count++ : K - 1;
  while (pos > 0 && (col.cand[pos - 1].log_e < log_e || (col.cand[pos - 1].log_e == log_e && col.cand[pos - 1].p.cell > h))) {
    col.cand[pos] = col.cand[pos - 1];
    --pos;
  }
  Candidate& c = col.cand[pos];
  c.log_e = log_e;
  c.p.cell = h;
  c.p.heading_rad = heading;
  c.p.arc_m = listed;
  c.p.lateral_m = reversed ? -1 : 1;
}

// Emission log-likelihoods of both directions of each touched half-edge
// (one-way streets only the way they run); the K best kept in col.
uint32_t MapMatcher::scoreCandidates(const MatchObservation& obs, size_t touched, Column& col) {
  const double se = std::sqrt(obs.sigma_m * obs.sigma_m + d_.road_sigma_m * d_.road_sigma_m);
  const double inv_2se2 = 0.5 / (se * se);
  const double sa = std::max(0.5, obs.sigma_m);
  const double inv_2sa2 = 0.5 / (sa * sa);
  const bool use_heading = obs.heading_sigma_rad > 0;
  const double sh = obs.heading_sigma_rad * obs.heading_sigma_rad + (d_.heading_sigma_deg * kDeg) * (d_.heading_sigma_deg * kDeg);
  const double kappa = use_heading ? 1.0 / sh : 0.0;
  auto headingTerm = [&](double hd) { return use_heading ? kappa * (std::cos(hd - obs.heading_rad) - 1) : 0.0; };
  uint32_t count = 0;
  for (size_t k = 0; k < touched; ++k) {
    const uint32_t h = touched_[k];
    const Seen& s = *seen_.find(h);
    const glm::dvec2 a = g_.point(s.point), b = g_.point(s.point + 1);
    const double hd = bearing(b.x - a.x, b.y - a.y);
    const double dist = s.dist;
    const graph::HalfEdge he = g_.halfedge(h);
    // Past either end of the street, the distance has an along-street part
    // (the overshoot) that the lane offset does not explain: it is weighed with
    // the position's own sigma, so a position just past a junction belongs to
    // the next street rather than to the end of this one.
    double overshoot = 0;
    const float t = s.t;
    if ((t <= 0.0f && s.point == he.pts_begin) || (t >= 1.0f && s.point + 2 == he.pts_begin + he.pts_count)) {
      const glm::dvec2 d = b - a;
      const double len = glm::length(d);
      if (len > 1e-9)
        overshoot = std::min(dist, std::fabs(((obs.e - (t <= 0 ? a.x : b.x)) * d.x + (obs.n - (t <= 0 ? a.y : b.y)) * d.y) / len));
    }
    const double lateral2 = dist * dist - overshoot * overshoot;
    const double base = -lateral2 * inv_2se2 - overshoot * overshoot * inv_2sa2;
    if (!(he.flags & graph::kReverseOfOneway)) keepCandidate(col, count, h, base + headingTerm(hd), h, false, hd);
    const uint32_t tw = he.twin;
    if (tw < g_.cellCount() && !(g_.halfedge(tw).flags & graph::kReverseOfOneway)) {
      const double ht = hd >= kPi ? hd - kPi : hd + kPi;
      keepCandidate(col, count, tw, base + headingTerm(ht), h, true, ht);
    }
  }
  return count;
}

// Arc length, lateral offset and foot point of the first `count` candidates,
// from the segment each came from (keepCandidate's stash).
void MapMatcher::placeCandidates(const MatchObservation& obs, Column& col, uint32_t count) {
  for (uint32_t j = 0; j < count; ++j) {
    Candidate& c = col.cand[j];
    const uint32_t listed = static_cast<uint32_t>(c.p.arc_m);
    const bool reversed = c.p.lateral_m < 0;
    const graph::HalfEdge he = g_.halfedge(listed);
    double along = 0, total = 0;
    const Seen& s = *seen_.find(listed);
    const uint32_t seg = s.point;
    for (uint32_t i = he.pts_begin; i + 1 < he.pts_begin + he.pts_count; ++i) {
      const double l = glm::length(g_.point(i + 1) - g_.point(i));
      if (i < seg) along += l;
      else if (i == seg) along += l * s.t;
      total += l;
    }
    const glm::dvec2 a = g_.point(seg), b = g_.point(seg + 1);
    const glm::dvec2 q = a + (b - a) * static_cast<double>(s.t);
    const double len = glm::length(b - a);
    const double lat = len > 1e-9 ? ((obs.e - q.x) * (b.y - a.y) - (obs.n - q.y) * (b.x - a.x)) / len : 0.0;
    c.p.arc_m = reversed ? std::max(0.0, total - along) : along;
    c.p.lateral_m = reversed ? -lat : lat;
    c.p.dist_m = s.dist;
    c.p.e = q.x;
    c.p.n = q.y;
  }
}

void MapMatcher::findCandidates(const MatchObservation& obs, Column& col) {
  const double r = std::clamp(d_.search_sigmas * obs.sigma_m, d_.search_min_m, d_.search_max_m);
  const size_t touched = nearestSegments(obs.e, obs.n, r);
  const uint32_t count = scoreCandidates(obs, touched, col);
  placeCandidates(obs, col, count);
  // The raw fix's distance from each candidate: evidence independent from
  // step to step (MatchObservation::fix_e).
  if (obs.fix_sigma_m > 0) {
    const double sf2 = obs.fix_sigma_m * obs.fix_sigma_m + d_.road_sigma_m * d_.road_sigma_m;
    for (uint32_t j = 0; j < count; ++j) {
      const CellPoint f = project(col.cand[j].p.cell, obs.fix_e, obs.fix_n);
      col.cand[j].log_e -= 0.5 * f.dist_m * f.dist_m / sf2;
    }
  }
  col.count = count;
}

void MapMatcher::routeDistances(const Candidate& from, const Column& to, double cap, double* out) {
  ++stats_.route_searches;
  for (uint32_t j = 0; j < to.count; ++j) out[j] = -1;
  reached_.clear();
  targets_.clear();
  uint32_t remaining = 0;
  for (uint32_t j = 0; j < to.count; ++j) {
    bool fresh = false;
    *targets_.insert(to.cand[j].p.cell, &fresh) = static_cast<uint8_t>(j);
    ++remaining;
  }
  const uint32_t src = from.p.cell;
  if (const uint8_t* t = targets_.find(src)) {
    const uint32_t j = *t;
    const double da = to.cand[j].p.arc_m - from.p.arc_m;
    if (da >= -d_.backward_tolerance_m) {
      out[j] = std::max(0.0, da);
      --remaining;
    }
  }
  if (remaining == 0) return;
  // A min-heap on distance, ties to the lower cell id (deterministic).
  const auto heapGreater = [](const HeapItem& a, const HeapItem& b) { return a.d > b.d || (a.d == b.d && a.cell > b.cell); };
  size_t hs = 0;
  const size_t hcap = heap_.size();
  auto push = [&](uint32_t c, double d) {
    const Reached* r = reached_.find(c);
    if (r && (r->done || r->dist <= d)) return;
    bool fresh = false;
    Reached* w = hs == hcap ? nullptr : reached_.insert(c, &fresh);
    if (!w) {
      ++stats_.route_truncated;
      return;
    }
    *w = Reached{static_cast<float>(d), false};
    heap_[hs++] = HeapItem{static_cast<float>(d), c};
    std::push_heap(heap_.begin(), heap_.begin() + hs, heapGreater);
  };
  const double d0 = std::max(0.0, static_cast<double>(g_.halfedge(src).length) - from.p.arc_m);
  if (d0 <= cap)
    for (uint32_t s : g_.successors(src)) push(s, d0);
  while (hs > 0 && remaining > 0) {
    std::pop_heap(heap_.begin(), heap_.begin() + hs, heapGreater);
    const HeapItem it = heap_[--hs];
    Reached& r = *reached_.find(it.cell);
    if (r.done || it.d > r.dist) continue;
    r.done = true;
    ++stats_.route_expansions;
    if (const uint8_t* t = targets_.find(it.cell)) {
      const uint32_t j = *t;
      if (out[j] < 0) {
        out[j] = it.d + to.cand[j].p.arc_m;
        --remaining;
      }
    }
    const double nd = it.d + g_.halfedge(it.cell).length;
    if (nd > cap) continue;
    for (uint32_t s : g_.successors(it.cell)) push(s, nd);
  }
}

bool MapMatcher::step(const MatchObservation& obs) {
  ++stats_.steps;
  last_obs_ = obs;
  Column& cur = column(steps_);
  cur.t = obs.t;
  cur.e = obs.e;
  cur.n = obs.n;
  findCandidates(obs, cur);
  if (cur.count == 0) {
    ++stats_.empty_steps;
    reset();
    return false;
  }
  double max_le = kNegInf;
  for (uint32_t j = 0; j < cur.count; ++j) max_le = std::max(max_le, cur.cand[j].log_e);

  bool chained = false;
  if (steps_ > 0) {
    const Column& prev = column(steps_ - 1);
    const double d_obs = std::hypot(cur.e - prev.e, cur.n - prev.n);
    const double beta = d_.beta_m + d_.beta_sigma_factor * obs.sigma_m;
    const double cap = d_.route_factor * d_obs + d_.route_slack_m;
    const uint32_t K = d_.max_candidates;
    for (uint32_t i = 0; i < prev.count; ++i) routeDistances(prev.cand[i], cur, cap, &dist_store_[i * K]);
    double asum = 0;
    for (uint32_t j = 0; j < cur.count; ++j) {
      double best = kNegInf, fsum = 0;
      uint8_t bi = kNoBack;
      for (uint32_t i = 0; i < prev.count; ++i) {
        const double d = dist_store_[i * K + j];
        if (d < 0 || prev.delta[i] == kNegInf) continue;
        const double lt = -std::fabs(d_obs - d) / beta;
        const double v = prev.delta[i] + lt;
        if (v > best) best = v, bi = static_cast<uint8_t>(i);
        fsum += prev.alpha[i] * std::exp(lt);
      }
      cur.delta[j] = best == kNegInf ? kNegInf : best + cur.cand[j].log_e;
      cur.back[j] = bi;
      cur.alpha[j] = fsum * std::exp(cur.cand[j].log_e - max_le);
      asum += cur.alpha[j];
      if (bi != kNoBack) chained = true;
    }
    if (!chained) ++stats_.breaks;
    else if (!(asum > 0)) chained = false;  // the forward filter underflowed: restart it with the chain
    if (chained) {
      for (uint32_t j = 0; j < cur.count; ++j) cur.alpha[j] /= asum;
      double mx = kNegInf;
      for (uint32_t j = 0; j < cur.count; ++j) mx = std::max(mx, cur.delta[j]);
      // Scores are relative to the best; a floor bounds how much past evidence a
      // live alternative must overcome, so a wrong early choice is not forever.
      for (uint32_t j = 0; j < cur.count; ++j)
        if (cur.delta[j] != kNegInf) cur.delta[j] = std::max(cur.delta[j] - mx, -d_.score_floor);
    }
  }
  if (!chained) {
    // A chain start (N&K §5.1 break): emissions only.
    double asum = 0;
    for (uint32_t j = 0; j < cur.count; ++j) {
      cur.delta[j] = cur.cand[j].log_e - max_le;
      cur.back[j] = kNoBack;
      cur.alpha[j] = std::exp(cur.delta[j]);
      asum += cur.alpha[j];
    }
    for (uint32_t j = 0; j < cur.count; ++j) cur.alpha[j] /= asum;
  }

  uint32_t best = 0;
  for (uint32_t j = 1; j < cur.count; ++j)
    if (cur.delta[j] > cur.delta[best]) best = j;
  head_ = cur.cand[best].p;
  confidence_ = cur.alpha[best];

  // Fixed-lag decision: back along the best path to the step `lag` ago.
  settled_ = CellPoint{};
  settled_t_ = 0;
  if (steps_ >= d_.lag) {
    uint32_t idx = best;
    bool ok = true;
    for (uint64_t s = steps_; s > steps_ - d_.lag; --s) {
      const uint8_t b = column(s).back[idx];
      if (b == kNoBack) {
        ok = false;
        break;
      }
      idx = b;
    }
    if (ok) {
      const Column& old = column(steps_ - d_.lag);
      settled_ = old.cand[idx].p;
      settled_t_ = old.t;
    }
  }
  ++steps_;
  return true;
}

CellPoint MapMatcher::follow(const CellPoint& from, double e, double n, double heading_rad,
                             double heading_sigma_rad) const {
  if (from.cell >= g_.cellCount()) return from;
  const double s2 = d_.road_sigma_m * d_.road_sigma_m;
  const double kappa = heading_sigma_rad > 0 ? 1.0 / (heading_sigma_rad * heading_sigma_rad +
                                                       (d_.heading_sigma_deg * kDeg) * (d_.heading_sigma_deg * kDeg))
                                             : 0.0;
  auto cost = [&](const CellPoint& p) { return 0.5 * p.dist_m * p.dist_m / s2 + kappa * (1 - std::cos(p.heading_rad - heading_rad)); };
  CellPoint cur = project(from.cell, e, n);
  // Near the junction at the cell's end, within a lane and a half of it: on the
  // inside of a turn the vehicle cuts the corner and its projection on this cell
  // never reaches the end, so the street it is on is the one it is nearer to (the
  // bisector of the corner), as long as it lies along that street. The heading
  // picks which successor (cost); the switch itself is by distance alone, the
  // nearest-point rule that defines "on a cell" (a heading term moved the switch
  // off the bisector: the heading turns gradually through the corner).
  const double near_end_m = std::max(3.0, 1.5 * d_.road_sigma_m);
  for (int hop = 0; hop < 2; ++hop) {
    const double len = g_.halfedge(cur.cell).length;
    const bool past_end = cur.arc_m >= len - 0.01;
    if (!past_end && cur.arc_m < len - near_end_m) break;  // within the cell
    CellPoint best;
    double best_cost = 1e300;
    for (uint32_t s : g_.successors(cur.cell)) {
      const CellPoint p = project(s, e, n);
      const double c = cost(p);
      if (p.cell != graph::kNone && c < best_cost) best = p, best_cost = c;
    }
    if (best.cell == graph::kNone) break;
    if (past_end) {
      // Past the end: onto the successor that fits best when the position lies
      // along it or is no farther from it. A position beyond the end whose nearest
      // point on the successor is its start (the outside of a turn: every point
      // there is nearest to the junction vertex) is a tie; the vehicle has left the
      // cell, so the tie goes to the successor it is heading into.
      if (!(best.arc_m > 0.01 || best.dist_m <= cur.dist_m + 1e-9)) break;
    } else if (!(best.arc_m > 0.01 && best.dist_m < cur.dist_m)) {
      break;
    }
    cur = best;
  }
  // Just past a fork the branches have not drawn apart: the successor taken at
  // the junction (by heading, while the vehicle was still turning into one) is
  // weighed again against the junction's other branches while the position lies
  // within the first metres of it, so that the pose does not hold the wrong
  // branch until the next HMM step. Only with a precise heading (a yaw-rate
  // sensor's, within 2 degrees): by distance alone every street leaving the
  // junction is about as near as the one taken, and a GNSS course alone moved
  // GNSS-only drives onto the wrong branch more often than off it (bench track:
  // 1,235 -> 1,257 misses at sigma 5 m without this bound, 1,235 with it).
  constexpr double kForkWindowM = 8.0;  // about one HMM step (1 s) of urban driving
  constexpr double kForkHeadingSigma = 2 * kDeg;
  if (heading_sigma_rad > 0 && heading_sigma_rad < kForkHeadingSigma && cur.arc_m < kForkWindowM && cur.arc_m > 0.01) {
    CellPoint best = cur;
    double best_cost = cost(cur);
    const uint32_t twin = g_.halfedge(cur.cell).twin;
    for (uint32_t p : g_.predecessors(cur.cell)) {
      for (uint32_t s : g_.successors(p)) {
        if (s == cur.cell || s == twin) continue;
        const CellPoint q = project(s, e, n);
        const double c = cost(q);
        if (q.cell != graph::kNone && q.arc_m > 0.01 && c < best_cost) best = q, best_cost = c;
      }
    }
    cur = best;
  }
  return cur;
}

}  // namespace blvd::track
