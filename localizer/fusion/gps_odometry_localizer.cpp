#include "localizer/fusion/gps_odometry_localizer.hpp"

#include "localizer/match/bearing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace corridor::localizer {

const char* to_string(PositionSource s) {
  switch (s) {
    case PositionSource::none: return "none";
    case PositionSource::gps: return "gps";
    case PositionSource::odometry: return "vo";
  }
  return "none";
}

GpsOdometryLocalizer::GpsOdometryLocalizer(const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper,
                                           LocalizerConfig config)
    : graph_(graph),
      config_(config),
      hmm_(graph, snapper, config.hmm),
      odometry_(graph, config.odometry, &snapper),
      scale_(config.odometry_scale),
      takeover_s_(config.gps_timeout_s) {}

double GpsOdometryLocalizer::road_heading_deg(EdgeId e, double offset_m) const {
  return road_bearing_deg(graph_, e, offset_m, 3.0);
}

LocalizedPoint GpsOdometryLocalizer::output(PositionSource source, const MatchedPoint& m, double sigma_m) {
  LocalizedPoint p;
  p.source = m.matched ? source : PositionSource::none;
  p.match = m;
  if (m.matched) {
    p.position = graph_.projection().to_lat_lon(m.point);
    p.heading_deg = road_heading_deg(m.edge, m.offset_m);
  }
  p.sigma_m = sigma_m;
  p.speed_mps = last_.speed_mps;
  last_ = p;
  return p;
}

MatchedPoint GpsOdometryLocalizer::along_road_mean(const MatchedPoint& m, double sigma_m, double time_s) {
  // The GPS/odometry fusion along the road: each recent fix on this edge (either way), or on the
  // edge just before it, is carried forward by the odometry driven since, and the estimates are averaged
  // with weights for the fix's σ and the odometry's drift. Across the road, the match stands.
  // Only what the odometry carried: without it (a GPS-only trace, a VO dropout), or after a gap
  // in the fixes, the older fixes would hold a moving vehicle back.
  const bool carried_by_odometry = time_s - last_odometry_s_ <= config_.gps_timeout_s;
  if (!carried_by_odometry || (!recent_.empty() && time_s - recent_.back().time_s > config_.gps_timeout_s)) recent_.clear();
  recent_.push_back({m.edge, m.offset_m, odometry_m_, sigma_m, time_s});
  while (recent_.size() > config_.along_fixes) recent_.pop_front();
  EdgeId before;  // the edge that leads into m.edge, if a recent fix was on it
  for (const RecentFix& r : recent_) {
    if (r.edge != m.edge && graph_.head(r.edge) == graph_.tail(m.edge) && r.edge != graph_.twin(m.edge)) before = r.edge;
  }
  const double before_len = before.valid() ? graph_.length_m(before) : 0.0;
  double sum = 0.0, weights = 0.0;
  for (const RecentFix& r : recent_) {
    double u;  // along [before, m.edge], from m.edge's tail
    if (r.edge == m.edge) {
      u = r.offset_m;
    } else if (r.edge == graph_.twin(m.edge)) {
      u = graph_.twin_offset_m(r.edge, r.offset_m);  // a stopped vehicle's match may face either way
    } else if (before.valid() && r.edge == before) {
      u = r.offset_m - before_len;
    } else {
      continue;
    }
    const double carried = odometry_m_ - r.odometry_m;
    if (carried > config_.along_max_carry_m) continue;
    const double estimate = u + carried;
    const double var = std::max(0.25, r.sigma_m * r.sigma_m + std::pow(config_.along_drift_per_m * carried, 2.0));
    // A fix far from this one along the road (a multipath jump the matcher followed) is left out.
    if (std::abs(estimate - m.offset_m) > 3.0 * std::max(sigma_m, r.sigma_m)) continue;
    sum += estimate / var;
    weights += 1.0 / var;
  }
  const double u = weights > 0.0 ? sum / weights : m.offset_m;
  if (!std::isfinite(u)) return m;
  MatchedPoint out = m;
  if (u >= 0.0 || !before.valid()) {
    out.offset_m = std::clamp(u, 0.0, graph_.length_m(m.edge));
  } else {
    out.edge = before;
    out.offset_m = std::clamp(before_len + u, 0.0, before_len);
  }
  out.point = graph_.point_along(out.edge, out.offset_m);
  out.distance_m = m.distance_m + maps::distance_m(out.point, m.point);
  return out;
}

GpsOdometryLocalizer::FixMean GpsOdometryLocalizer::carried_to_now(const CarriedFix& f) const {
  FixMean out;
  // Without a course, only a fix the vehicle has not moved from can be carried.
  if (!f.course_known && f.driven_m > 0.0) return out;
  const double drift = config_.along_drift_per_m * f.driven_m, across = config_.carry_course_per_m * f.driven_m;
  out.valid = true;
  out.point = {f.point.x_m + f.moved.x_m, f.point.y_m + f.moved.y_m};
  out.sigma_m = std::sqrt(f.sigma_m * f.sigma_m + drift * drift + across * across);
  return out;
}

GpsOdometryLocalizer::FixMean GpsOdometryLocalizer::fix_mean() const {
  double x = 0.0, y = 0.0, weights = 0.0;
  int counted = 0;
  for (const CarriedFix& f : carried_) {
    const FixMean c = carried_to_now(f);
    if (!c.valid) continue;
    ++counted;
    const double w = 1.0 / std::max(0.25, c.sigma_m * c.sigma_m);
    x += w * c.point.x_m, y += w * c.point.y_m, weights += w;
  }
  FixMean out;
  if (!(weights > 0.0) || counted < 2) return out;
  out.valid = true;
  out.point = {x / weights, y / weights};
  out.sigma_m = 1.0 / std::sqrt(weights);
  return out;
}

bool GpsOdometryLocalizer::agrees(const FixMean& mean, maps::Point2 fix, double sigma_m) const {
  const double sigma = std::sqrt(sigma_m * sigma_m + mean.sigma_m * mean.sigma_m);
  return maps::distance_m(fix, mean.point) <= config_.restart_gate_sigmas * sigma;
}

void GpsOdometryLocalizer::dead_reckon(CarriedFix& f, double distance_m, std::optional<double> course_deg) {
  if (distance_m <= 0.0) return;
  f.driven_m += distance_m;
  if (!course_deg) {
    f.course_known = false;
    return;
  }
  const double rad = *course_deg * std::numbers::pi / 180.0;  // clockwise from north; x east, y north
  f.moved.x_m += distance_m * std::sin(rad);
  f.moved.y_m += distance_m * std::cos(rad);
}

LocalizedPoint GpsOdometryLocalizer::on_gps(const GpsFix& fix) {
  // The receiver's interval, from every fix it gives, whatever its quality.
  const double previous_fix_s = last_fix_s_;
  if (std::isfinite(fix.time_s) && fix.time_s > last_fix_s_) {
    if (const double gap = fix.time_s - last_fix_s_; gap <= config_.gps_timeout_s) {
      fix_gaps_.push_back(gap);
      if (fix_gaps_.size() > 5) fix_gaps_.pop_front();
      takeover_s_ = takeover_s();  // read at every odometry step, so worked out once per fix
    }
    last_fix_s_ = fix.time_s;
  }
  if (fix.hdop && *fix.hdop > config_.max_gps_hdop) {
    // Not followed (the seed's switch), but a poor fix still tells the odometry's hypotheses apart
    // when they are streets apart.
    if (maps::is_valid_lat_lon(fix.position)) {
      odometry_.observe(graph_.projection().to_local(fix.position), *fix.hdop * config_.hmm.sigma_base_m);
    }
    return last_;
  }
  // Only a good fix's speed calibrates the odometry's scale; it is the odometry as reported,
  // before the correction, that is measured against it.
  scale_.on_fix(fix.time_s, fix.speed_mps, raw_odometry_m_);
  const MatchedPoint matched = hmm_.update(fix);
  if (!matched.matched) return last_;
  const double sigma = usable_hdop(fix, config_.hmm.default_hdop) * config_.hmm.sigma_base_m;
  // The fixes are carried only by the odometry: on a GPS-only trace, or after a gap in the fixes,
  // the mean starts again (and with one fix, the restart is the matched point). Gated fixes are
  // no gap: the mean's 1σ grows with the metres carried, and with it the gate.
  const bool carried_by_odometry = fix.time_s - last_odometry_s_ <= config_.gps_timeout_s;
  if (!carried_by_odometry || fix.time_s - previous_fix_s > config_.gps_timeout_s) carried_.clear();
  CarriedFix now;
  now.point = graph_.projection().to_local(fix.position);
  now.sigma_m = sigma;
  if (const FixMean before = fix_mean(); before.valid && !agrees(before, now.point, sigma)) {
    const FixMean gated = gated_ ? carried_to_now(*gated_) : FixMean{};
    if (!gated.valid || !agrees(gated, now.point, sigma)) {
      // Shown, as GPS is followed, with its distance from the mean as its 1σ, but the odometry
      // keeps its restart and its record since, and takes over from there if no agreeing fix
      // comes.
      gated_ = now;
      // Once the odometry has taken over (gated fixes only, for 1.5 intervals), it stays the
      // output: a position flipping between it and each gated fix would help no one.
      if (last_.source == PositionSource::odometry) return last_;
      LocalizedPoint p = output(PositionSource::gps, matched, std::max(sigma, maps::distance_m(now.point, before.point)));
      if (fix.speed_mps) p.speed_mps = last_.speed_mps = *fix.speed_mps;
      return p;
    }
    carried_.assign(1, *gated_);
  }
  gated_.reset();
  // A repeated or older time is not a new fix of the present: it would count twice.
  if (fix.time_s > last_good_gps_s_) {
    carried_.push_back(now);
    while (carried_.size() > config_.restart_fixes) carried_.pop_front();
  }
  last_good_gps_s_ = std::max(last_good_gps_s_, fix.time_s);
  const MatchedPoint m = along_road_mean(matched, sigma, fix.time_s);
  // Odometry restarts at every good fix, so a hand-over continues from the latest. Its heading is
  // the receiver's last course while moving, turned by the odometry since (the online match's
  // direction can be wrong at the last fix, and a stopped vehicle has no course); without one, it
  // is the road's, and only loosely known.
  OdometryStart from;
  from.edge = m.edge;
  from.offset_m = m.offset_m;
  // The dead reckoning's origin is the fixes' mean; every road near it, the matched one too,
  // pays for its distance from it.
  const FixMean mean = fix_mean();
  from.point = mean.valid ? mean.point : m.point;
  if (fix.heading_deg && std::isfinite(*fix.heading_deg) && fix.speed_mps && *fix.speed_mps > 3.0) {
    course_deg_ = *fix.heading_deg;
    driven_since_course_m_ = 0.0;
  }
  from.heading_deg = road_heading_deg(m.edge, m.offset_m);
  from.heading_sigma_deg = 45.0;  // the road alone: a vehicle that stood may face either way
  if (course_deg_ && driven_since_course_m_ <= config_.course_memory_m) {
    // The receiver measured the heading; a road's bearing at one point can be off by a bend.
    from.heading_deg = *course_deg_;
    from.heading_sigma_deg = 20.0;
  }
  from.time_s = fix.time_s;
  // The start's 1σ stays the fix's: the mean's own (a few metres) would pin the dead reckoning
  // to a point that a course error over the carried metres can shift as far (measured: Monaco
  // lost 1.5 points of the outage at σ 10–15 m with it).
  from.sigma_m = sigma;
  odometry_.start(from);
  LocalizedPoint p = output(PositionSource::gps, m, sigma);
  if (fix.speed_mps) p.speed_mps = last_.speed_mps = *fix.speed_mps;
  return p;
}

double GpsOdometryLocalizer::takeover_s() const {
  if (fix_gaps_.size() < 3) return config_.gps_timeout_s;
  // The median: a missed fix or a burst at lock does not move it.
  std::array<double, 5> gaps{};
  std::copy(fix_gaps_.begin(), fix_gaps_.end(), gaps.begin());
  const auto mid = gaps.begin() + static_cast<std::ptrdiff_t>(fix_gaps_.size() / 2);
  std::nth_element(gaps.begin(), mid, gaps.begin() + static_cast<std::ptrdiff_t>(fix_gaps_.size()));
  return std::clamp(config_.gps_overdue_intervals * *mid, config_.gps_min_takeover_s, config_.gps_timeout_s);
}

LocalizedPoint GpsOdometryLocalizer::on_odometry(const OdometryStep& reported) {
  if (std::isfinite(reported.distance_m)) raw_odometry_m_ += std::max(0.0, reported.distance_m);
  OdometryStep step = reported;
  step.distance_m *= scale_.factor();
  if (std::isfinite(step.distance_m)) odometry_m_ += std::max(0.0, step.distance_m);
  if (std::isfinite(step.time_s)) last_odometry_s_ = step.time_s;
  if (std::isfinite(step.distance_m)) {
    // The fixes are carried along the course at the step's middle (a 45° step at 8 m/s would put
    // them 3 m aside with the heading at either end); a course older than course_memory_m is none.
    std::optional<double> course;
    if (course_deg_ && driven_since_course_m_ <= config_.course_memory_m) {
      course = wrap180(*course_deg_ + 0.5 * (std::isfinite(step.heading_change_deg) ? step.heading_change_deg : 0.0));
    }
    for (CarriedFix& f : carried_) dead_reckon(f, std::max(0.0, step.distance_m), course);
    if (gated_) dead_reckon(*gated_, std::max(0.0, step.distance_m), course);
  }
  if (course_deg_ && std::isfinite(step.heading_change_deg) && std::isfinite(step.distance_m)) {
    course_deg_ = wrap180(*course_deg_ + step.heading_change_deg);
    driven_since_course_m_ += std::max(0.0, step.distance_m);
  }
  if (!odometry_.started()) return last_;
  // Driven from the last good fix on (each fix restarts it), so that when GPS goes quiet the
  // odometry already holds every metre driven since; it is the output on its own after the timeout.
  if (step.time_s - last_good_gps_s_ <= takeover_s_) {
    // Between two fixes the last one is carried on by the odometry (the hypotheses it started
    // from that fix), not held: a 1 Hz receiver's fix is up to a second old, 30 m at 30 m/s. It
    // is still GPS's position, dead-reckoned for less than the takeover time. The odometry's best
    // hypothesis is taken even off the fix's road and its exits: holding the fix's own match to
    // its road instead (against a parallel street leading for a moment) stuck it at the road's
    // end on short streets and lost 0.3 points of a GPS outage on Monaco.
    const MatchedPoint m = odometry_.advance(step);
    if (!m.matched || !(step.time_s > last_good_gps_s_) || last_.source != PositionSource::gps) return last_;
    return output(PositionSource::gps, m, std::max(last_.sigma_m, odometry_.sigma_m()));
  }
  const MatchedPoint m = odometry_.advance(step);
  return output(PositionSource::odometry, m, odometry_.sigma_m());
}

}  // namespace corridor::localizer
