#include "localizer/match/hmm_matcher.hpp"

#include "localizer/match/bearing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace corridor::localizer {
namespace {

constexpr double kNoScore = -std::numeric_limits<double>::infinity();
constexpr std::int32_t kRestart = -2;  // a parent in Links: the path starts afresh there

}  // namespace

void HmmConfig::validate() const {
  if (!(sigma_base_m > 0.0) || !(default_hdop > 0.0) || !(beta_m > 0.0) || !(min_radius_m > 0.0) ||
      !(max_radius_m >= min_radius_m) || !(max_speed_mps > 0.0) || !(gap_s > 0.0) || !(speed_gap_s >= 0.0) || !(backward_tolerance_m >= 0.0) || !(backward_sigmas >= 0.0) ||
      !(uturn_penalty >= 0.0) || !(service_entry_penalty >= 0.0) || !(outlier_penalty >= 0.0) || !(restart_penalty > 0.0) || !(heading_sigma_deg > 0.0) ||
      !std::isfinite(heading_sigma_deg) || !(heading_wide_sigma_deg > 0.0) || !std::isfinite(heading_wide_sigma_deg) ||
      !(heading_wide_share >= 0.0 && heading_wide_share <= 1.0) ||
      max_candidates == 0 || window == 0 || max_skipped > 16) {
    throw std::invalid_argument(
        "map matcher configuration needs positive scales, radii, speed, gap, window and restart penalty, "
        "non-negative other penalties and speed gap, finite heading sigmas, a wide heading share between 0 and 1, "
        "and at most 16 fixes set aside in a row");
  }
}

HmmMatcher::HmmMatcher(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper, HmmConfig config,
                       SearchArrays arrays)
    : graph_(graph),
      snapper_(snapper),
      config_(config),
      distances_(arrays == SearchArrays::owned ? std::make_unique<planner::BoundedDistances>(graph.node_count()) : nullptr) {
  config_.validate();
  heading_log_narrow_ = std::log((1.0 - config_.heading_wide_share) / config_.heading_sigma_deg);
  heading_log_wide_ = std::log(config_.heading_wide_share / config_.heading_wide_sigma_deg);
  heading_log_at_zero_ = heading_log_likelihood(0.0);  // with the member still 0: the raw density
}

void HmmMatcher::reset() {
  window_.clear();
  reported_chain_ = 0;
}

double HmmMatcher::heading_log_likelihood(double angle_deg) const {
  // The mixture's log density, summed in the log domain (a σ of a few degrees would underflow
  // exp() at 180°), over its value at 0°: a course right along the road costs nothing, as with one
  // Gaussian before. Both σ are finite (validate), so one part is always finite.
  const double narrow = angle_deg / config_.heading_sigma_deg, wide = angle_deg / config_.heading_wide_sigma_deg;
  const double ln = heading_log_narrow_ - 0.5 * narrow * narrow;
  const double lw = heading_log_wide_ - 0.5 * wide * wide;
  const double top = std::max(ln, lw);
  return top + std::log(std::exp(ln - top) + std::exp(lw - top)) - heading_log_at_zero_;
}

std::vector<HmmMatcher::Candidate> HmmMatcher::candidates_for(const GpsFix& fix, maps::Point2 raw) const {
  const double hdop = usable_hdop(fix, config_.default_hdop);
  const double sigma = hdop * config_.sigma_base_m;
  const double radius = std::clamp(config_.radius_sigmas * sigma, config_.min_radius_m, config_.max_radius_m);
  const bool use_heading = fix.heading_deg && std::isfinite(*fix.heading_deg) &&
                           (!fix.speed_mps || *fix.speed_mps >= config_.heading_min_speed_mps);
  std::vector<Candidate> out;
  for (const maps::SnapResult& road : snapper_.candidates_local(raw, radius, config_.max_candidates)) {
    // Newson & Krumm's emission: a zero-mean Gaussian in the distance from the fix to the road.
    const double emission = -0.5 * (road.distance_m / sigma) * (road.distance_m / sigma);
    auto add = [&](EdgeId e, double offset) {
      double score = emission;
      if (use_heading) {
        score += heading_log_likelihood(angle_between_deg(road_bearing_deg(graph_, e, offset), *fix.heading_deg));
      }
      out.push_back({e, offset, road.point, road.distance_m, score, -1});
    };
    add(road.edge, road.offset_m);
    if (road.twin.valid()) add(road.twin, road.twin_offset_m);
  }
  return out;
}

HmmMatcher::Links::Links(const maps::RoadGraph& graph, const std::vector<Candidate>& next)
    : best(next.size(), kNoScore), parent(next.size(), -1), back(next.size(), 1) {
  for (const Candidate& c : next) targets.push_back(graph.tail(c.edge));
  std::sort(targets.begin(), targets.end());
  targets.erase(std::unique(targets.begin(), targets.end()), targets.end());
}

void HmmMatcher::relax(const Step& prev, const Step& next, const GpsFix& fix, double penalty, std::uint8_t back,
                       double base, planner::BoundedDistances& distances, Links& links) const {
  const double dt = next.time_s - prev.time_s;
  if (dt > config_.gap_s || dt < 0.0) return;
  const double straight = maps::distance_m(prev.raw, next.raw);
  // No route can be longer than the fastest vehicle drives meanwhile; a generous detour budget
  // keeps the searches small where fixes are dense.
  const double bound = std::min(config_.max_speed_mps * std::max(dt, 1.0), 2.0 * straight + 300.0);
  const bool use_speed = fix.speed_mps && std::isfinite(*fix.speed_mps) && dt > 0.0 && dt <= config_.speed_gap_s;
  // Both distances come from noisy fixes (projected onto the road, or straight between them), so
  // their difference spreads with the GPS noise: the scale grows with σ, never below beta_m.
  const double hdop = usable_hdop(fix, config_.default_hdop);
  const double beta = std::max(config_.beta_m, config_.beta_per_sigma * hdop * config_.sigma_base_m);
  const double backward = std::max(config_.backward_tolerance_m, config_.backward_sigmas * hdop * config_.sigma_base_m);

  for (std::size_t i = 0; i < prev.candidates.size(); ++i) {
    const Candidate& p = prev.candidates[i];
    if (p.score == kNoScore) continue;
    const double to_end = graph_.length_m(p.edge) - p.offset_m;
    // A move onto a service road pays to enter it, not to go on along it.
    const double service_entry = graph_.road_class(p.edge) == maps::RoadClass::service ? 0.0 : config_.service_entry_penalty;
    bool searched = false;
    for (std::size_t j = 0; j < next.candidates.size(); ++j) {
      const Candidate& c = next.candidates[j];
      double route;
      if (c.edge == p.edge && c.offset_m >= p.offset_m - backward) {
        route = std::max(0.0, c.offset_m - p.offset_m);
      } else {
        if (!searched) {
          distances.run(graph_, graph_.head(p.edge), std::max(0.0, bound - to_end), links.targets);
          searched = true;
        }
        const double between = distances.length_m(graph_.tail(c.edge));
        if (between == planner::kInfCost) continue;
        route = to_end + between + c.offset_m;
      }
      if (route > bound || (dt > 0.0 && route / dt > config_.max_speed_mps)) continue;
      // Newson & Krumm's transition: exponential in |route − straight line|.
      // Where the fix has a speed (Doppler, good to a fraction of a m/s), speed × time measures the
      // distance driven far better than the straight line between two noisy fixes does (its noise
      // is σ√2 a side, and all of it at a stop), so the speed term gets the tighter scale.
      double transition = use_speed ? -std::abs(route - straight) / (2.0 * beta) - std::abs(route - *fix.speed_mps * dt) / beta
                                     : -std::abs(route - straight) / beta;
      if (c.edge == graph_.twin(p.edge)) transition -= config_.uturn_penalty;
      if (graph_.road_class(c.edge) == maps::RoadClass::service) transition -= service_entry;
      const double score = p.score + (prev.norm - base) + transition - penalty;
      if (score > links.best[j]) {
        links.best[j] = score;
        links.parent[j] = static_cast<std::int32_t>(i);
        links.back[j] = back;
      }
    }
  }
}

void HmmMatcher::allow_restarts(Links& links) const {
  // Afresh, from the last step's best candidate (scored 0 on the scale of the last step), where
  // that beats every way in; only once something links, so that a fix nothing reaches is still set
  // aside or breaks the chain as before.
  if (std::none_of(links.best.begin(), links.best.end(), [](double b) { return b != kNoScore; })) return;
  for (std::size_t j = 0; j < links.best.size(); ++j) {
    if (links.best[j] < -config_.restart_penalty) {
      links.best[j] = -config_.restart_penalty;
      links.parent[j] = kRestart;
      links.back[j] = 1;
    }
  }
}

bool HmmMatcher::apply(Step& next, const Links& links, double base) {
  if (std::all_of(links.best.begin(), links.best.end(), [](double b) { return b == kNoScore; })) return false;
  for (std::size_t j = 0; j < next.candidates.size(); ++j) {
    Candidate& c = next.candidates[j];
    c.restart = links.parent[j] == kRestart;
    c.parent = c.restart ? -1 : links.parent[j];
    c.back = links.back[j];
    c.score = links.best[j] == kNoScore ? kNoScore : c.score + links.best[j];
  }
  // Keep the scores near zero: only their differences matter.
  const double top = next.candidates[HmmMatcher::best(next)].score;
  for (Candidate& c : next.candidates) {
    if (c.score != kNoScore) c.score -= top;
  }
  next.norm = base + top;
  return true;
}

bool HmmMatcher::link(const Step& prev, Step& next, const GpsFix& fix, planner::BoundedDistances& distances) {
  Links links(graph_, next.candidates);
  relax(prev, next, fix, 0.0, 1, prev.norm, distances, links);
  allow_restarts(links);
  return apply(next, links, prev.norm);
}

std::size_t HmmMatcher::best(const Step& step) {
  std::size_t b = 0;
  for (std::size_t i = 1; i < step.candidates.size(); ++i) {
    if (step.candidates[i].score > step.candidates[b].score) b = i;
  }
  return b;
}

MatchedPoint HmmMatcher::point_of(const Step& step, std::size_t index) const {
  MatchedPoint m;
  if (step.candidates.empty() || step.candidates[index].score == kNoScore) return m;
  const Candidate& c = step.candidates[index];
  m.matched = true;
  m.edge = c.edge;
  m.offset_m = c.offset_m;
  m.point = c.point;
  m.distance_m = c.distance_m;
  m.chain_start = step.chain_start || c.restart;
  double total = 0.0;
  for (const Candidate& o : step.candidates) {
    if (o.score != kNoScore) total += std::exp(o.score - c.score);
  }
  m.confidence = total > 0.0 ? 1.0 / total : 0.0;
  return m;
}

MatchedPoint HmmMatcher::update(const GpsFix& fix, planner::BoundedDistances* lent) {
  if (!maps::is_valid_lat_lon(fix.position) || !std::isfinite(fix.time_s)) {
    throw std::invalid_argument("a fix needs a finite time and a valid coordinate");
  }
  planner::BoundedDistances* distances = lent != nullptr ? lent : distances_.get();
  if (distances == nullptr) throw std::logic_error("a matcher with lent search arrays was given none");
  if (distances->node_count() != graph_.node_count()) throw std::logic_error("lent search arrays are for another graph");
  Step step;
  step.time_s = fix.time_s;
  step.raw = graph_.projection().to_local(fix.position);
  step.candidates = candidates_for(fix, step.raw);
  if (step.candidates.empty()) {
    window_.clear();
    MatchedPoint none;
    none.distance_m = 0.0;
    return none;
  }
  if (window_.empty() || !link(window_.back(), step, fix, *distances)) {
    // A new chain: its first step is scored by the emission alone.
    step.chain_start = true;
    window_.clear();
    const std::uint32_t chain = next_chain_++;
    for (Candidate& c : step.candidates) c.chain = chain;
  } else {
    const Step& prev = window_.back();
    for (Candidate& c : step.candidates) {
      if (c.restart) {
        c.chain = next_chain_++;
      } else if (c.parent >= 0) {
        c.chain = prev.candidates[static_cast<std::size_t>(c.parent)].chain;
      }
    }
  }
  window_.push_back(std::move(step));
  while (window_.size() > config_.window) window_.pop_front();
  const Step& now = window_.back();
  const std::size_t at = best(now);
  MatchedPoint m = point_of(now, at);
  // A restart that wins only some fixes later is still a jump from the path reported before.
  if (m.matched) {
    m.chain_start = m.chain_start || now.candidates[at].chain != reported_chain_;
    reported_chain_ = now.candidates[at].chain;
  }
  return m;
}

std::vector<MatchedPoint> HmmMatcher::match(std::span<const GpsFix> trace) {
  std::unique_ptr<planner::BoundedDistances> own;
  if (!distances_) own = std::make_unique<planner::BoundedDistances>(graph_.node_count());
  planner::BoundedDistances& distances = distances_ ? *distances_ : *own;
  for (std::size_t i = 0; i < trace.size(); ++i) {
    if (!maps::is_valid_lat_lon(trace[i].position) || !std::isfinite(trace[i].time_s)) {
      throw std::invalid_argument("fix " + std::to_string(i + 1) + " needs a finite time and a valid coordinate");
    }
    if (i > 0 && trace[i].time_s < trace[i - 1].time_s) {
      throw std::invalid_argument("fix " + std::to_string(i + 1) + " is earlier than the one before it: sort the trace by time");
    }
  }
  std::vector<MatchedPoint> out(trace.size());
  std::vector<Step> steps;
  std::vector<std::size_t> fix_of;  // steps[k] came from trace[fix_of[k]]
  // Smooths the part of a chain from steps[first] to steps[last] (its points already set).
  auto smooth_part = [&](std::size_t first, std::size_t last) {
    const std::size_t from = fix_of[first], to = fix_of[last];
    for (std::size_t i = from; i <= to; ++i) out[i].outlier = !out[i].matched;
    if (config_.along_path != HmmConfig::AlongPath::smoothed) return;
    std::vector<MatchedPoint> chain_points(out.begin() + static_cast<std::ptrdiff_t>(from),
                                           out.begin() + static_cast<std::ptrdiff_t>(to + 1));
    SmootherConfig smoother;
    smoother.sigma_base_m = config_.sigma_base_m;
    smoother.default_hdop = config_.default_hdop;
    smoother.speed_gap_s = config_.speed_gap_s;
    const auto smoothed = smooth_along_path(graph_, distances, trace.subspan(from, to + 1 - from), chain_points, smoother);
    for (std::size_t i = from; i <= to; ++i) {
      MatchedPoint& m = out[i];
      const bool outlier = m.outlier;
      m = smoothed[i - from];
      m.outlier = outlier;
      if (m.matched) m.distance_m = maps::distance_m(graph_.projection().to_local(trace[i].position), m.point);
    }
  };
  // Backtracks the chain steps[first..steps.size()) from its best last candidate; the fixes
  // between its steps that the path leaves out are outliers. Where the path starts afresh
  // (restart_penalty), the part before it ends at its own best candidate, and each part is
  // smoothed alone.
  auto finish_chain = [&](std::size_t first) {
    if (steps.size() <= first) return;
    std::size_t k = steps.size() - 1;
    std::size_t part_last = k;
    std::int32_t at = static_cast<std::int32_t>(best(steps[k]));
    while (true) {
      out[fix_of[k]] = point_of(steps[k], static_cast<std::size_t>(at));
      if (k == first) break;
      const Candidate& c = steps[k].candidates[static_cast<std::size_t>(at)];
      if (c.restart) {
        // Fixes set aside between the two parts stay unmatched and unflagged, as before a break.
        smooth_part(k, part_last);
        part_last = --k;
        at = static_cast<std::int32_t>(best(steps[k]));
        continue;
      }
      if (c.parent < 0 || c.back > k - first) break;  // cannot happen inside a chain; stop rather than misread
      k -= c.back;
      at = c.parent;
    }
    smooth_part(first, part_last);
  };
  std::size_t chain_first = 0;
  std::size_t skipped = 0;  // fixes in a row set aside because nothing in the chain reaches them
  for (std::size_t i = 0; i < trace.size(); ++i) {
    Step step;
    step.time_s = trace[i].time_s;
    step.raw = graph_.projection().to_local(trace[i].position);
    step.candidates = candidates_for(trace[i], step.raw);
    const bool in_chain = steps.size() > chain_first;
    bool linked = false;
    if (in_chain && !step.candidates.empty()) {
      // From the last step, or over up to max_skipped steps before it, each left out as an outlier.
      // Fixes already set aside since a step count towards the limit on outliers in a row.
      Links links(graph_, step.candidates);
      const double base = steps.back().norm;
      for (std::size_t back = 1; back <= config_.max_skipped + 1 && steps.size() >= chain_first + back; ++back) {
        const std::size_t from = steps.size() - back;
        if (i - fix_of[from] - 1 > config_.max_skipped) break;
        relax(steps[from], step, trace[i], static_cast<double>(back - 1) * config_.outlier_penalty,
              static_cast<std::uint8_t>(back), base, distances, links);
      }
      allow_restarts(links);
      linked = apply(step, links, base);
    }
    // A fix nothing in the chain can reach, or with no road near, between fixes that fit it, is an
    // outlier (multipath): set aside rather than breaking the chain, at most max_skipped in a row.
    if (!linked && in_chain && skipped < config_.max_skipped && trace[i].time_s - steps.back().time_s <= config_.gap_s) {
      ++skipped;
      continue;
    }
    skipped = 0;
    if (!linked) {
      finish_chain(chain_first);
      chain_first = steps.size();
      if (step.candidates.empty()) continue;  // out[i] stays unmatched
      step.chain_start = true;  // scored by the emission alone
    }
    steps.push_back(std::move(step));
    fix_of.push_back(i);
  }
  finish_chain(chain_first);
  return out;
}

}  // namespace corridor::localizer
