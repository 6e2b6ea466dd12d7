#include "localizer/fusion/gps_odometry_localizer.hpp"

#include "localizer/match/bearing.hpp"

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
    : graph_(graph), config_(config), hmm_(graph, snapper, config.hmm), odometry_(graph, config.odometry, &snapper) {}

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

LocalizedPoint GpsOdometryLocalizer::on_gps(const GpsFix& fix) {
  if (fix.hdop && *fix.hdop > config_.max_gps_hdop) {
    // Not followed (the seed's switch), but a poor fix still tells the odometry's hypotheses apart
    // when they are streets apart.
    if (maps::is_valid_lat_lon(fix.position)) {
      odometry_.observe(graph_.projection().to_local(fix.position), *fix.hdop * config_.hmm.sigma_base_m);
    }
    return last_;
  }
  const MatchedPoint matched = hmm_.update(fix);
  if (!matched.matched) return last_;
  last_good_gps_s_ = fix.time_s;
  const double sigma = usable_hdop(fix, config_.hmm.default_hdop) * config_.hmm.sigma_base_m;
  const MatchedPoint m = along_road_mean(matched, sigma, fix.time_s);
  // Odometry always restarts from the latest good fix, so a hand-over continues from it. Its
  // heading is the receiver's last course while moving, turned by the odometry since (the online
  // match's direction can be wrong at the last fix, and a stopped vehicle has no course); without
  // one, it is the road's, and only loosely known.
  OdometryStart from;
  from.edge = m.edge;
  from.offset_m = m.offset_m;
  from.point = m.point;
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
  from.sigma_m = sigma;
  odometry_.start(from);
  LocalizedPoint p = output(PositionSource::gps, m, sigma);
  if (fix.speed_mps) p.speed_mps = last_.speed_mps = *fix.speed_mps;
  return p;
}

LocalizedPoint GpsOdometryLocalizer::on_odometry(const OdometryStep& step) {
  if (std::isfinite(step.distance_m)) odometry_m_ += std::max(0.0, step.distance_m);
  if (std::isfinite(step.time_s)) last_odometry_s_ = step.time_s;
  if (course_deg_ && std::isfinite(step.heading_change_deg) && std::isfinite(step.distance_m)) {
    course_deg_ = wrap180(*course_deg_ + step.heading_change_deg);
    driven_since_course_m_ += std::max(0.0, step.distance_m);
  }
  if (!odometry_.started()) return last_;
  // Recorded from the last good fix on (each fix restarts it), so that when GPS goes quiet the
  // odometry already holds every metre driven since; it is the output only after the timeout.
  if (step.time_s - last_good_gps_s_ <= config_.gps_timeout_s) {
    odometry_.record(step);
    return last_;
  }
  const MatchedPoint m = odometry_.advance(step);
  return output(PositionSource::odometry, m, odometry_.sigma_m());
}

}  // namespace corridor::localizer
