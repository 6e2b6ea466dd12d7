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
    : graph_(graph), config_(config), hmm_(graph, snapper, config.hmm), odometry_(graph, config.odometry) {}

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

LocalizedPoint GpsOdometryLocalizer::on_gps(const GpsFix& fix) {
  if (fix.hdop && *fix.hdop > config_.max_gps_hdop) return last_;  // odometry keeps going
  const MatchedPoint m = hmm_.update(fix);
  if (!m.matched) return last_;
  last_good_gps_s_ = fix.time_s;
  const double sigma = fix.hdop.value_or(config_.hmm.default_hdop) * config_.hmm.sigma_base_m;
  // Odometry always restarts from the latest good fix, so a hand-over continues from it.
  odometry_.start(m.edge, m.offset_m, road_heading_deg(m.edge, m.offset_m), fix.time_s, sigma);
  LocalizedPoint p = output(PositionSource::gps, m, sigma);
  if (fix.speed_mps) p.speed_mps = last_.speed_mps = *fix.speed_mps;
  return p;
}

LocalizedPoint GpsOdometryLocalizer::on_odometry(const OdometryStep& step) {
  if (!odometry_.started()) return last_;
  // Integrated from the last good fix on (each fix restarts it), so that when GPS goes quiet the
  // odometry already holds every metre driven since; it is the output only after the timeout.
  const MatchedPoint m = odometry_.advance(step);
  if (step.time_s - last_good_gps_s_ <= config_.gps_timeout_s) return last_;
  return output(PositionSource::odometry, m, odometry_.sigma_m());
}

}  // namespace corridor::localizer
