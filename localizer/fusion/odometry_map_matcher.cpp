#include "localizer/fusion/odometry_map_matcher.hpp"

#include "localizer/match/corner_cut.hpp"

#include "localizer/match/bearing.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace corridor::localizer {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr int kMaxJunctionsPerStep = 24;  // a long step over very short edges must not branch forever
constexpr std::size_t kMaxBranches = 4096;  // per hypothesis and step
constexpr std::size_t kMaxHistory = 512;   // heading samples kept, whatever the odometry's rate

}  // namespace

OdometryMapMatcher::OdometryMapMatcher(const maps::RoadGraph& graph, OdometryMatchConfig config,
                                       const maps::EdgeSnapper* snapper)
    : graph_(graph), config_(config), snapper_(snapper) {}

double OdometryMapMatcher::road_bearing_deg(EdgeId e, double offset_m) const {
  return localizer::road_bearing_deg(graph_, e, offset_m, 3.0);
}

void OdometryMapMatcher::start(const OdometryStart& from) {
  start_ = from;
  if (start_.edge.valid()) {
    // Whatever a caller passes, the hypotheses start from finite numbers on the road.
    const double len = graph_.length_m(start_.edge);
    start_.offset_m = std::isfinite(start_.offset_m) ? std::clamp(start_.offset_m, 0.0, len) : 0.0;
    if (!std::isfinite(start_.point.x_m) || !std::isfinite(start_.point.y_m)) start_.point = graph_.point_along(start_.edge, start_.offset_m);
    if (!std::isfinite(start_.heading_deg)) {
      start_.heading_deg = road_bearing_deg(start_.edge, start_.offset_m);
      start_.heading_sigma_deg = 45.0;
    }
    if (!(start_.heading_sigma_deg > 0.0) || !std::isfinite(start_.heading_sigma_deg)) start_.heading_sigma_deg = 45.0;
    if (!(start_.sigma_m > 0.0) || !std::isfinite(start_.sigma_m)) start_.sigma_m = config_.base_sigma_m;
    if (!std::isfinite(start_.time_s)) start_.time_s = 0.0;
  }
  pending_.clear();
  hyps_.clear();
  seeded_ = false;
}

void OdometryMapMatcher::start(EdgeId edge, double offset_m, double heading_deg, double time_s, double sigma_m) {
  OdometryStart s;
  s.edge = edge;
  s.offset_m = offset_m;
  if (edge.valid()) s.point = graph_.point_along(edge, std::clamp(offset_m, 0.0, graph_.length_m(edge)));
  s.heading_deg = heading_deg;
  s.time_s = time_s;
  s.sigma_m = sigma_m;
  start(s);
}

void OdometryMapMatcher::seed() {
  seeded_ = true;
  hyps_.clear();
  heading_deg_ = start_.heading_deg;
  driven_m_ = 0.0;
  siblings_at_m_ = 0.0;
  headings_.assign(1, {start_.time_s, heading_deg_});
  track_.assign(1, {0.0, heading_deg_});
  const double sigma = std::max(start_.sigma_m, config_.base_sigma_m);
  const double heading_sigma = std::max(1.0, start_.heading_sigma_deg);
  // §IV's confidence region around the last good fix: the matched edge, its other direction, and
  // every road within reach, each costed by its distance and by how far its bearing turns the
  // odometry from the fix's heading.
  auto add = [&](EdgeId e, double offset_m, double distance_m) {
    if (!e.valid()) return;
    Hypothesis h;
    h.edge = e;
    h.offset_m = std::clamp(offset_m, 0.0, graph_.length_m(e));
    h.sigma_m = sigma;
    // A road's bearing at one point is no measure of the vehicle's heading (a bend, a kink at the
    // junction), so the odometry keeps the fix's heading, or turns it round on a road that runs
    // against it: the vehicle may face the other way when the heading came from a road alone.
    const double against = wrap180(road_bearing_deg(e, h.offset_m) - heading_deg_);
    h.heading_bias_deg = std::abs(against) > 135.0 ? 180.0 : 0.0;
    // Every hypothesis reckons from the fix itself, so a parallel road pays for its distance
    // from the curve the vehicle drove.
    h.reckoned = start_.point;
    h.cost = 0.5 * std::pow(distance_m / sigma, 2.0) + 0.5 * std::pow(against / heading_sigma, 2.0);
    hyps_.push_back(h);
  };
  // The matched edge pays for its distance from the origin too, along the road as well: charging
  // only the distance across (where the origin's foot on the road is) was no better (measured:
  // docs/experiments/localization.md).
  const double matched_off = maps::distance_m(graph_.point_along(start_.edge, start_.offset_m), start_.point);
  add(start_.edge, start_.offset_m, matched_off);
  if (const EdgeId twin = graph_.twin(start_.edge); twin.valid()) add(twin, graph_.twin_offset_m(start_.edge, start_.offset_m), matched_off);
  // The other exits of the node behind the match, as far past it: a fast vehicle a second past a
  // fork whose branches part slowly may have its fixes' mean nearer the branch the online match
  // did not take, yet further than the region's radius from the one it did (traced on Andorra: a
  // whole outage driven down the wrong branch at 28 m/s).
  for (EdgeId e : graph_.out_edges(graph_.tail(start_.edge))) {
    if (e == start_.edge) continue;
    const double off = std::min(start_.offset_m, graph_.length_m(e));
    add(e, off, maps::distance_m(graph_.point_along(e, off), start_.point));
  }
  if (snapper_ != nullptr) {
    const double radius = std::max(config_.start_radius_m, 2.0 * sigma);
    for (const maps::SnapResult& c : snapper_->candidates_local(start_.point, radius, 8)) {
      add(c.edge, c.offset_m, c.distance_m);
      add(c.twin, c.twin_offset_m, c.distance_m);
    }
  }
  prune();
}

void OdometryMapMatcher::move(Hypothesis h, double left_m, std::vector<Hypothesis>& out) const {
  // Depth-first along the road; every junction branches into its exits (no U-turn, except at a
  // dead end, as the single-hypothesis rule had it).
  struct Frame {
    Hypothesis h;
    double left;
    int junctions;
  };
  std::vector<Frame> stack{{h, left_m, 0}};
  const std::size_t out_before = out.size();
  while (!stack.empty()) {
    Frame f = stack.back();
    stack.pop_back();
    const double len = graph_.length_m(f.h.edge);
    if (f.left <= len - f.h.offset_m || f.junctions >= kMaxJunctionsPerStep ||
        out.size() - out_before + stack.size() >= kMaxBranches) {
      f.h.offset_m = std::min(len, f.h.offset_m + f.left);
      out.push_back(f.h);
      continue;
    }
    const double rest = f.left - (len - f.h.offset_m);
    if (slow_ && rest < config_.junction_commit_m) {  // slow, and not yet clearly past the node
      f.h.offset_m = len;
      f.h.past_node_m = rest;
      out.push_back(f.h);
      continue;
    }
    f.h.past_node_m = 0.0;
    const NodeId junction = graph_.head(f.h.edge);
    const EdgeId back = graph_.twin(f.h.edge);
    const double bearing_in = road_bearing_deg(f.h.edge, len);
    const auto in_pts = graph_.geometry(f.h.edge);
    const maps::Point2 in_a = in_pts[in_pts.size() - 2], in_b = in_pts.back();
    bool any = false;
    for (int pass = 0; pass < 2 && !any; ++pass) {
      for (EdgeId e : graph_.out_edges(junction)) {
        if (pass == 0 && e == back) continue;
        Hypothesis next = f.h;
        next.edge = e;
        next.offset_m = 0.0;
        next.junction_s = driven_m_ - rest;
        // The odometry measures the arc the vehicle drove round the corner, on its side of the
        // road; the hypothesis moves along the centre lines, which are longer through a turn
        // towards that side (corner_cut.hpp).
        const auto out_pts = graph_.geometry(e);
        const double theta = turn_towards_traffic_side_rad(graph_, in_b.x_m - in_a.x_m, in_b.y_m - in_a.y_m,
                                                           out_pts[1].x_m - out_pts[0].x_m, out_pts[1].y_m - out_pts[0].y_m);
        const double offset = 0.5 * ((back.valid() ? config_.corner.lane_offset_m : 0.0) +
                                     (graph_.twin(e).valid() ? config_.corner.lane_offset_m : 0.0));
        const double saving = e == back ? 0.0
                                        : corner_cut(theta, maps::distance_m(in_a, in_b), maps::distance_m(out_pts[0], out_pts[1]),
                                                     config_.corner.radius_m, offset).saving_m;
        const double road_turn = wrap180(road_bearing_deg(e, 0.0) - bearing_in);
        if (std::abs(road_turn) > config_.reset_turn_deg) {
          next.sharp_s = next.junction_s;
          next.sharp_turn_deg = road_turn;
          next.sharp_pending = true;
        }
        stack.push_back({next, std::max(0.0, rest + saving), f.junctions + 1});
        any = true;
      }
    }
    if (!any) {  // a sink: stay at its end
      f.h.offset_m = len;
      out.push_back(f.h);
    }
  }
}

void OdometryMapMatcher::drive(double distance_m, double turn_deg) {
  scratch_.clear();
  for (Hypothesis h : hyps_) {
    // Dead reckoning at the step's mean heading, in this hypothesis's frame (x east, y north).
    const double mid = (heading_deg_ - turn_deg / 2.0 + h.heading_bias_deg) * kDegToRad;
    h.reckoned = {h.reckoned.x_m + distance_m * std::sin(mid), h.reckoned.y_m + distance_m * std::cos(mid)};
    const double left = distance_m + h.past_node_m;
    h.past_node_m = 0.0;
    move(h, left, scratch_);
  }
  hyps_.swap(scratch_);
}

void OdometryMapMatcher::score(double distance_m) {
  const double per = distance_m / 10.0;  // the costs are per 10 m driven
  for (Hypothesis& h : hyps_) {
    h.sigma_m += config_.drift_per_m * distance_m;
    const double heading = heading_deg_ + h.heading_bias_deg;
    const double road = road_bearing_deg(h.edge, h.offset_m);
    const double ang = std::min(angle_between_deg(road, heading), config_.heading_cap_deg);
    h.cost += per * 0.5 * std::pow(ang / config_.heading_sigma_deg, 2.0);
    const double base = h.resets == 0 ? config_.position_base_m + 0.5 * start_.sigma_m : config_.position_base_m;
    const double position_sigma = base + config_.position_drift_per_m * (driven_m_ - h.reckoned_from_m);
    const maps::Point2 on_road = graph_.point_along(h.edge, h.offset_m);
    const double off = maps::distance_m(on_road, h.reckoned);
    h.cost += per * std::min(config_.position_cap, 0.5 * std::pow(off / position_sigma, 2.0));
    // Align with the road where it runs straight, away from a junction's kinks; a larger
    // difference is a wrong road, not a misaligned odometry.
    const bool straight = angle_between_deg(road, road_bearing_deg(h.edge, std::max(0.0, h.offset_m - 10.0))) < 5.0;
    const double misaligned = wrap180(road - heading);
    if (straight && driven_m_ - h.junction_s > 15.0 && std::abs(misaligned) < 30.0) {
      h.heading_bias_deg = wrap180(h.heading_bias_deg + std::min(1.0, distance_m / config_.heading_align_m) * misaligned);
    }
    const double pull = std::min(1.0, distance_m / config_.position_align_m);
    h.reckoned = {h.reckoned.x_m + pull * (on_road.x_m - h.reckoned.x_m), h.reckoned.y_m + pull * (on_road.y_m - h.reckoned.y_m)};
  }
}

double OdometryMapMatcher::heading_at(double s) const {
  double h = track_.front().second;
  for (const auto& [d, heading] : track_) {
    if (d > s) break;
    h = heading;
  }
  return h;
}

void OdometryMapMatcher::reset_at_turns() {
  // A sharp turn of the road at a junction that the odometry also made (§IV's distinctive
  // feature): the junction is where the odometry's turn was half done. Move the hypothesis along
  // its road by the difference, and restart its along-road uncertainty.
  const double half = config_.turn_window_m / 2.0;
  for (Hypothesis& h : hyps_) {
    if (!h.sharp_pending || driven_m_ - h.sharp_s < half) continue;
    h.sharp_pending = false;
    const double before = heading_at(h.sharp_s - config_.turn_window_m);
    // (Turns are differences, so this hypothesis's heading offset cancels out.)
    const double turn = wrap180(heading_deg_ - before);
    if (std::abs(turn) <= config_.reset_turn_deg || angle_between_deg(turn, h.sharp_turn_deg) > 30.0) continue;
    double s_mid = h.sharp_s;
    for (const auto& [d, heading] : track_) {
      if (d < h.sharp_s - config_.turn_window_m) continue;
      if (std::abs(wrap180(heading - before)) >= std::abs(turn) / 2.0) {
        s_mid = d;
        break;
      }
    }
    const double moved = h.offset_m + (h.sharp_s - s_mid);
    if (!(moved >= 0.0 && moved <= graph_.length_m(h.edge))) continue;
    h.offset_m = moved;
    h.sigma_m = config_.base_sigma_m;
    ++h.resets;
    // The drift is gone here: the dead reckoning restarts from the road, and a small heading
    // drift is taken out by aligning the odometry with the road it now follows.
    h.reckoned = graph_.point_along(h.edge, h.offset_m);
    h.reckoned_from_m = driven_m_;
    const double realign = wrap180(road_bearing_deg(h.edge, h.offset_m) - (heading_deg_ + h.heading_bias_deg));
    if (std::abs(realign) < 15.0) h.heading_bias_deg = wrap180(h.heading_bias_deg + realign);
  }
}

void OdometryMapMatcher::heading_check(double time_s) {
  // §IV: the road and the odometry disagree over the window (a junction just passed is the turn,
  // not a disagreement).
  for (Hypothesis& h : hyps_) {
    if (time_s - h.last_raise_s < 1.0 || driven_m_ - h.junction_s < config_.turn_window_m) continue;
    const double road = road_bearing_deg(h.edge, h.offset_m);
    double mean = 0.0;
    for (const auto& [t, heading] : headings_) mean += angle_between_deg(road, heading + h.heading_bias_deg);
    mean /= static_cast<double>(std::max<std::size_t>(1, headings_.size()));
    if (mean > config_.disagreement_deg) {
      h.sigma_m *= config_.disagreement_raise;
      h.last_raise_s = time_s;
    }
  }
}

void OdometryMapMatcher::prune() {
  std::sort(hyps_.begin(), hyps_.end(), [](const Hypothesis& a, const Hypothesis& b) { return a.cost < b.cost; });
  if (hyps_.empty()) return;
  const double best = hyps_.front().cost;
  scratch_.clear();
  for (const Hypothesis& h : hyps_) {
    if (h.cost > best + config_.prune_margin || scratch_.size() >= config_.max_hypotheses) break;
    const bool same_place = std::any_of(scratch_.begin(), scratch_.end(), [&](const Hypothesis& k) {
      return k.edge == h.edge && std::abs(k.offset_m - h.offset_m) < config_.merge_m;
    });
    if (same_place) continue;
    scratch_.push_back(h);
    scratch_.back().cost -= best;  // costs stay small over a long outage
  }
  hyps_.swap(scratch_);
}

bool OdometryMapMatcher::add_siblings() {
  if (driven_m_ - siblings_at_m_ < config_.sibling_every_m) return false;
  siblings_at_m_ = driven_m_;
  const std::size_t parents = std::min(config_.sibling_parents, hyps_.size());
  for (std::size_t i = 0; i < parents; ++i) {
    for (const double shift : {-config_.sibling_step_m, config_.sibling_step_m}) {
      Hypothesis h = hyps_[i];
      h.offset_m += shift;
      h.past_node_m = 0.0;
      if (h.offset_m < 0.0 || h.offset_m > graph_.length_m(h.edge)) continue;
      h.cost += config_.sibling_cost;
      hyps_.push_back(h);
    }
  }
  return parents > 0;
}

void OdometryMapMatcher::observe(maps::Point2 fix, double sigma_m) {
  if (!started() || !(sigma_m > 0.0) || !std::isfinite(fix.x_m) || !std::isfinite(fix.y_m)) return;
  if (!seeded_) {
    pending_.push_back({OdometryStep{start_.time_s, 0.0, 0.0}, fix, sigma_m});
    return;
  }
  for (Hypothesis& h : hyps_) {
    const double off = maps::distance_m(graph_.point_along(h.edge, h.offset_m), fix);
    h.cost += std::min(config_.position_cap, 0.5 * std::pow(off / sigma_m, 2.0));
  }
  prune();
}

void OdometryMapMatcher::record(const OdometryStep& step) {
  if (!started()) return;
  if (seeded_) {
    advance(step);
    return;
  }
  pending_.push_back({step, std::nullopt, 0.0});
}

MatchedPoint OdometryMapMatcher::advance(const OdometryStep& step) {
  if (!started()) return {};
  if (!seeded_) {
    seed();
    std::vector<Pending> replay;
    replay.swap(pending_);
    for (const Pending& p : replay) {
      if (p.fix) {
        observe(*p.fix, p.fix_sigma_m);
      } else {
        advance(p.step);
      }
    }
  }
  const double dist = std::isfinite(step.distance_m) ? std::max(0.0, step.distance_m) : 0.0;
  const double turn = std::isfinite(step.heading_change_deg) ? step.heading_change_deg : 0.0;
  heading_deg_ = wrap180(heading_deg_ + turn);
  driven_m_ += dist;
  const double time_s = std::isfinite(step.time_s) ? step.time_s : headings_.back().first;
  const double dt = headings_.empty() ? 0.0 : time_s - headings_.back().first;
  slow_ = dt > 0.0 && dist < config_.slow_speed_mps * dt;
  headings_.emplace_back(time_s, heading_deg_);
  while (headings_.size() > kMaxHistory || (headings_.size() > 1 && headings_.front().first < time_s - config_.heading_window_s)) {
    headings_.pop_front();
  }
  // Standing still adds nothing to the curve: the last sample takes the new heading.
  if (dist > 0.0 || track_.size() < 2) {
    track_.emplace_back(driven_m_, heading_deg_);
  } else {
    track_.back().second = heading_deg_;
  }
  while (track_.size() > kMaxHistory || (track_.size() > 2 && track_[1].first < driven_m_ - 3.0 * config_.turn_window_m)) track_.pop_front();

  if (dist > 0.0) {
    drive(dist, turn);
    score(dist);
    reset_at_turns();
  }
  heading_check(time_s);
  prune();
  if (add_siblings()) prune();  // they join behind their parents, and may merge with others
  return current();
}

MatchedPoint OdometryMapMatcher::current() const {
  MatchedPoint m;
  if (hyps_.empty()) return m;
  const Hypothesis& best = hyps_.front();
  m.matched = true;
  m.edge = best.edge;
  m.offset_m = best.offset_m;
  m.point = graph_.point_along(best.edge, best.offset_m);
  // The best hypothesis's share, times how far its drift has grown from a fresh reset.
  double total = 0.0;
  for (const Hypothesis& h : hyps_) total += std::exp(-h.cost);  // costs are relative to the best
  m.confidence = std::clamp(config_.base_sigma_m / best.sigma_m, 0.0, 1.0) / std::max(1.0, total);
  return m;
}

double OdometryMapMatcher::sigma_m() const { return hyps_.empty() ? 0.0 : hyps_.front().sigma_m; }

std::size_t OdometryMapMatcher::resets() const { return hyps_.empty() ? 0 : hyps_.front().resets; }

}  // namespace corridor::localizer
