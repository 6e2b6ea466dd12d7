#include "localizer/study/localization_study.hpp"

#include "localizer/match/bearing.hpp"
#include "planner/bounded_search.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <unordered_set>

namespace corridor::localizer {
namespace {

// Among `candidates`, the nearest directed edge that `keep` accepts and whose bearing agrees with
// the heading within max_deg, no farther than limit_m; with its distance.
template <class Keep>
std::pair<EdgeId, double> nearest_agreeing(const maps::RoadGraph& g, const std::vector<maps::SnapResult>& candidates,
                                           double heading_deg, double max_deg, double limit_m, Keep keep) {
  std::pair<EdgeId, double> best{EdgeId{}, limit_m};
  for (const maps::SnapResult& r : candidates) {
    for (auto [e, off] : {std::pair{r.edge, r.offset_m}, std::pair{r.twin, r.twin_offset_m}}) {
      if (!e.valid() || !keep(e) || angle_between_deg(road_bearing_deg(g, e, off, 3.0), heading_deg) > max_deg) continue;
      if (r.distance_m <= best.second && (!best.first.valid() || r.distance_m < best.second)) best = {e, r.distance_m};
    }
  }
  return best;
}

constexpr auto kAnyEdge = [](EdgeId) { return true; };

// Whether p lies more than margin_m beyond edge e's head or before its tail, along the road (its
// nearest point on the edge is an end, and p lies past it along the end piece), rather than beside it.
bool beyond_ends(const maps::RoadGraph& g, EdgeId e, maps::Point2 p, double margin_m) {
  const auto pts = g.geometry(e);
  if (pts.size() < 2) return false;
  const maps::RoadGraph::EdgePoint nearest = g.nearest_point(e, p);
  const bool at_tail = nearest.offset_m <= 1e-6, at_head = nearest.offset_m >= g.length_m(e) - 1e-6;
  if (!at_tail && !at_head) return false;
  // The end piece's direction, from the first point before the end that is not the end itself.
  const maps::Point2 end = at_head ? pts[pts.size() - 1] : pts[0];
  for (std::size_t k = 1; k < pts.size(); ++k) {
    const maps::Point2 inner = at_head ? pts[pts.size() - 1 - k] : pts[k];
    const double dx = end.x_m - inner.x_m, dy = end.y_m - inner.y_m, len = std::hypot(dx, dy);
    if (len > 1e-6) return ((p.x_m - end.x_m) * dx + (p.y_m - end.y_m) * dy) / len > margin_m;
  }
  return false;
}

// The farthest apart that SUMO's junction joining puts OSM nodes of one junction
// (netconvert --junctions.join-dist is 10 m; clusters chain a few of them), beyond the distance
// the vehicle drove through it.
constexpr double kJunctionSpanM = 60.0;

// The distance a vehicle drove between two samples along its path, as its odometry sees it. SUMO's
// ballistic update moves a vehicle along its lane by the mean of its two speeds over the step (on
// straight lanes that equals the samples' straight-line distance to 0.01 %); in a bend the
// straight line between 1 Hz samples is a chord, 1.5 % shorter than the lane on Monaco's curves,
// where a 10 Hz odometry follows the lane. A lane change is a sideways jump in SUMO, which only
// the straight line sees, so the longer of the two counts; a step that ends at a stop does not use
// the speeds (the vehicle stopped somewhere inside it). This assumes the ballistic update, which
// scripts/sumo_fcd_drives.py uses by default: under the Euler one (--step-method euler) a braking
// step moves by its new speed, and the mean of the two overstates it.
double driven_m(const TruthSample& a, const TruthSample& b, maps::Point2 pa, maps::Point2 pb) {
  const double chord = maps::distance_m(pa, pb);
  if (!(a.speed_mps > 0.0) || !(b.speed_mps > 0.0) || !(b.time_s > a.time_s)) return chord;
  return std::max(chord, 0.5 * (a.speed_mps + b.speed_mps) * (b.time_s - a.time_s));
}

}  // namespace

EdgeId true_edge(const maps::RoadGraph& g, const maps::EdgeSnapper& snapper, maps::Point2 p, double heading_deg,
                 double radius_m) {
  return nearest_agreeing(g, snapper.candidates_local(p, radius_m, 8), heading_deg, 60.0, radius_m, kAnyEdge).first;
}

std::optional<std::int64_t> sumo_lane_osm_way(const std::string& lane) {
  // "[-]<digits>[#<digits>]_<digits>": netconvert's name for a part of an OSM way, one direction.
  std::size_t i = lane.size() > 0 && lane[0] == '-' ? 1 : 0;
  const std::size_t digits = i;
  while (i < lane.size() && std::isdigit(static_cast<unsigned char>(lane[i])) != 0) ++i;
  if (i == digits || i - digits > 18) return std::nullopt;
  const std::int64_t way = std::stoll(lane.substr(digits, i - digits));
  if (i < lane.size() && lane[i] == '#') {
    const std::size_t part = ++i;
    while (i < lane.size() && std::isdigit(static_cast<unsigned char>(lane[i])) != 0) ++i;
    if (i == part) return std::nullopt;
  }
  if (i >= lane.size() || lane[i] != '_') return std::nullopt;
  const std::size_t index = ++i;
  while (i < lane.size() && std::isdigit(static_cast<unsigned char>(lane[i])) != 0) ++i;
  if (i == index || i != lane.size()) return std::nullopt;
  return way;
}

std::vector<TrueEdges> true_edges(const maps::RoadGraph& g, const maps::EdgeSnapper& snapper,
                                  const std::vector<TruthSample>& samples, double radius_m) {
  std::vector<TrueEdges> out(samples.size());
  std::vector<std::uint8_t> in_junction(samples.size(), 0);
  std::unordered_set<std::int64_t> graph_ways;
  for (EdgeId e : g.edges()) graph_ways.insert(g.osm_way(e).v);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const TruthSample& s = samples[i];
    const maps::Point2 p = g.projection().to_local(s.position);
    const auto candidates = snapper.candidates_local(p, radius_m, 16);
    // The nearest road going the vehicle's way (true_edge's rule), kept for comparison...
    const auto [nearest, nearest_d] = nearest_agreeing(g, candidates, s.heading_deg, 60.0, radius_m, kAnyEdge);
    out[i].nearest = nearest;
    if (!s.lane.empty() && s.lane[0] == ':') {
      in_junction[i] = 1;
      continue;
    }
    const auto way = sumo_lane_osm_way(s.lane);
    // A lane on a way the graph does not have (SUMO drives some ways our importer leaves out, such
    // as a street closed to motor vehicles) is off our roads: no edge of the graph is the truth.
    if (way && !graph_ways.contains(*way)) continue;
    out[i].edge = nearest;
    // ...unless the lane's way has an edge here: its nearest, if not well beyond that road.
    // netconvert joins consecutive ways into one edge (--geometry.remove), and its lane then
    // names only the way where that edge starts.
    // A vehicle beyond the ends of every edge of the way along the road has driven on past where
    // the way ends: onto the way netconvert joined to it, whose edge is then the nearest road.
    if (way) {
      const auto on_way = nearest_agreeing(g, candidates, s.heading_deg, 90.0, nearest_d + 4.0,
                                           [&](EdgeId e) { return g.osm_way(e).v == *way && !beyond_ends(g, e, p, 1.0); });
      if (on_way.first.valid()) out[i].edge = on_way.first, out[i].from_lane = true;
    }
  }
  // Inside a junction: the edge the vehicle came by, the one it leaves by, or one between them.
  // SUMO joins OSM nodes a few metres apart into one junction (a divided road's crossing); the
  // OSM edges between those nodes lie inside it.
  planner::BoundedDistances between(g.node_count());
  EdgeId before;
  for (std::size_t i = 0; i < samples.size();) {
    if (in_junction[i] == 0) {
      before = out[i++].edge;
      continue;
    }
    std::size_t j = i;
    while (j < samples.size() && in_junction[j] != 0) ++j;
    const EdgeId after = j < samples.size() ? out[j].edge : EdgeId{};
    std::vector<EdgeId> through;
    if (before.valid() && after.valid() && before != after && g.head(before) != g.tail(after)) {
      const NodeId to = g.tail(after);
      // A joined cluster on a fast road is crossed in several samples (Porto's span 80 m and more):
      // the roads between may be as long as the vehicle drove from the sample before it to the one
      // after.
      double driven = 0.0;
      for (std::size_t k = i > 0 ? i - 1 : i; k + 1 <= j && k + 1 < samples.size(); ++k) {
        driven += maps::distance_m(g.projection().to_local(samples[k].position), g.projection().to_local(samples[k + 1].position));
      }
      between.run(g, g.head(before), kJunctionSpanM + driven, std::array<NodeId, 1>{to});
      through = between.path_to(g, to);
    }
    for (; i < j; ++i) {
      out[i].edge = before.valid() ? before : after;
      out[i].alt = after;
      out[i].through = through;
    }
  }
  return out;
}

StudyResult run_localization_study(const maps::RoadGraph& g, const maps::EdgeSnapper& snapper,
                                   const std::map<std::string, std::vector<TruthSample>>& drives, const StudyConfig& config,
                                   const std::string& plot_id, DrivePlot* plot) {
  StudyResult out;
  out.total.id = "all";
  std::uint64_t drive_seed = config.seed;
  for (const auto& [id, samples] : drives) {
    if (samples.size() < 10) continue;
    std::mt19937_64 rng(drive_seed++);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    DriveResult d;
    d.id = id;
    d.samples = samples.size();
    const double t0 = samples.front().time_s, t1 = samples.back().time_s;
    const double outage_begin = t0 + config.outage_at * (t1 - t0);
    const double outage_end = config.outage_s > 0.0 ? outage_begin + config.outage_s : outage_begin;
    SimulatedOdometry odometry(config.odometry, drive_seed * 7919 + 11);

    // Truth in the local frame, the GPS trace (outage dropped), and the odometry increments.
    std::vector<maps::Point2> truth(samples.size());
    std::vector<GpsFix> gps;
    std::vector<std::size_t> gps_sample;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      truth[i] = g.projection().to_local(samples[i].position);
      const double t = samples[i].time_s;
      if (t >= outage_begin && t < outage_end) continue;
      maps::Point2 q{truth[i].x_m + config.noise_sigma_m * gauss(rng), truth[i].y_m + config.noise_sigma_m * gauss(rng)};
      if (unit(rng) < config.outlier_share) {
        const double a = unit(rng) * 2.0 * std::numbers::pi, r = 40.0 + 60.0 * unit(rng);
        q = {q.x_m + r * std::cos(a), q.y_m + r * std::sin(a)};
      }
      GpsFix f;
      f.time_s = t;
      f.position = g.projection().to_lat_lon(q);
      f.hdop = config.noise_sigma_m / config.localizer.hmm.sigma_base_m;
      // A receiver's course over ground is noisy at low speed; give it only when moving.
      if (samples[i].speed_mps > 3.0) f.heading_deg = std::fmod(samples[i].heading_deg + 5.0 * gauss(rng) + 360.0, 360.0);
      f.speed_mps = std::max(0.0, samples[i].speed_mps + 0.3 * gauss(rng));
      gps.push_back(f);
      gps_sample.push_back(i);
    }

    // HMM over the GPS alone (batch), and the nearest road.
    HmmMatcher batch(g, snapper, config.localizer.hmm);
    const std::vector<MatchedPoint> hmm = batch.match(gps);
    std::vector<MatchedPoint> hmm_at(samples.size());
    for (std::size_t k = 0; k < gps.size(); ++k) hmm_at[gps_sample[k]] = hmm[k];

    // The fusion, online, fed in time order: odometry each step, then the fix if there is one.
    GpsOdometryLocalizer fusion(g, snapper, config.localizer);
    std::vector<LocalizedPoint> fused(samples.size());
    std::size_t next_fix = 0;
    bool was_out = false;
    maps::Point2 before_handback{};
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (i > 0) {
        fusion.on_odometry(odometry.step(samples[i].time_s, truth[i - 1], samples[i - 1].heading_deg, truth[i],
                                         samples[i].heading_deg, driven_m(samples[i - 1], samples[i], truth[i - 1], truth[i])));
      }
      const bool out_now = samples[i].time_s >= outage_begin && samples[i].time_s < outage_end;
      if (out_now && !was_out) {
        d.scale_sq_raw = std::pow(odometry.scale() - 1.0, 2);
        d.scale_sq_calibrated = std::pow(odometry.scale() * fusion.odometry_scale() - 1.0, 2);
        d.scale_n = 1;
      }
      if (was_out && !out_now) before_handback = fusion.last().match.point;
      if (next_fix < gps.size() && gps_sample[next_fix] == i) fusion.on_gps(gps[next_fix++]);
      fused[i] = fusion.last();
      if (was_out && !out_now && fused[i].match.matched) d.handback_jump_m = maps::distance_m(before_handback, fused[i].match.point);
      was_out = out_now;
    }

    // Scores.
    const std::vector<TrueEdges> truths = true_edges(g, snapper, samples, config.truth_radius_m);
    std::vector<std::uint8_t> on_track(samples.size(), 0);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const double step_m = i > 0 ? maps::distance_m(truth[i - 1], truth[i]) : 0.0;
      d.length_m += step_m;
      const bool out_now = samples[i].time_s >= outage_begin && samples[i].time_s < outage_end;
      const TrueEdges& t = truths[i];
      const EdgeId nearest_oracle = t.nearest;
      auto on_road = [&](EdgeId e) { return t.contains(e) || (e.valid() && t.contains(g.twin(e))); };
      if (!out_now) {
        const maps::Point2 raw = g.projection().to_local(gps[std::lower_bound(gps_sample.begin(), gps_sample.end(), i) - gps_sample.begin()].position);
        d.sq_raw += std::pow(maps::distance_m(raw, truth[i]), 2);
        ++d.n_raw;
        const maps::SnapResult near = snapper.snap_local(raw, {500.0});
        d.sq_nearest += std::pow(maps::distance_m(near.point, truth[i]), 2);
        if (hmm_at[i].matched) {
          const double sq = std::pow(maps::distance_m(hmm_at[i].point, truth[i]), 2);
          d.sq_hmm += sq;
          ++d.n_hmm;
          if (t.valid()) {
            d.sq_hmm_on_graph += sq;
            ++d.n_hmm_on_graph;
          }
        }
        if (t.valid()) {
          ++d.with_truth;
          d.length_with_truth += step_m;
          d.correct_nearest_road += on_road(near.edge) ? 1 : 0;
          if (hmm_at[i].matched && t.contains(hmm_at[i].edge)) {
            ++d.correct_hmm;
            d.length_correct_hmm += step_m;
          }
          d.correct_hmm_road += hmm_at[i].matched && on_road(hmm_at[i].edge) ? 1 : 0;
        }
        if (nearest_oracle.valid()) {
          ++d.with_truth_nearest_oracle;
          d.correct_hmm_nearest_oracle += hmm_at[i].matched && hmm_at[i].edge == nearest_oracle ? 1 : 0;
        }
      }
      if (fused[i].match.matched) {
        d.sq_fused += std::pow(maps::distance_m(fused[i].match.point, truth[i]), 2);
        ++d.n_fused;
      }
      const bool fused_correct = fused[i].match.matched && t.contains(fused[i].match.edge);
      if (t.valid() && !out_now) d.correct_fused += fused_correct ? 1 : 0;
      d.truth_from_lane += t.from_lane ? 1 : 0;
      if (out_now && nearest_oracle.valid()) {
        ++d.outage_samples_nearest_oracle;
        d.outage_correct_nearest_oracle += fused[i].match.matched && fused[i].match.edge == nearest_oracle ? 1 : 0;
      }
      if (out_now && t.valid()) {
        ++d.outage_samples;
        d.outage_correct += fused_correct ? 1 : 0;
        if (fused[i].match.matched) d.outage_sq += std::pow(maps::distance_m(fused[i].match.point, truth[i]), 2);
      }
      on_track[i] = fused_correct && maps::distance_m(fused[i].match.point, truth[i]) < 15.0 ? 1 : 0;
    }
    // Recovery: from the outage's end until the fusion is back on the true edge, near the truth.
    // A sample off our roads (no true edge) says nothing either way.
    if (config.outage_s > 0.0) {
      for (std::size_t i = 0; i < samples.size(); ++i) {
        if (samples[i].time_s < outage_end || !truths[i].valid()) continue;
        if (on_track[i] != 0) break;
        d.recovery_s = samples[i].time_s - outage_end + 1.0;
      }
    }
    if (plot != nullptr && id == plot_id) {
      for (std::size_t i = 0; i < samples.size(); ++i) {
        plot->truth.push_back(truth[i]);
        plot->fused.push_back(fused[i].match.matched ? fused[i].match.point : truth[i]);
        plot->hmm.push_back(hmm_at[i].matched ? hmm_at[i].point : maps::Point2{NAN, NAN});
        plot->in_outage.push_back(samples[i].time_s >= outage_begin && samples[i].time_s < outage_end ? 1 : 0);
      }
      for (const GpsFix& f : gps) plot->gps.push_back(g.projection().to_local(f.position));
    }
    out.drives.push_back(d);
    DriveResult& t = out.total;
    t.samples += d.samples;
    t.length_m += d.length_m;
    t.sq_raw += d.sq_raw, t.sq_nearest += d.sq_nearest, t.sq_hmm += d.sq_hmm, t.sq_fused += d.sq_fused;
    t.n_raw += d.n_raw, t.n_hmm += d.n_hmm, t.n_fused += d.n_fused;
    t.sq_hmm_on_graph += d.sq_hmm_on_graph, t.n_hmm_on_graph += d.n_hmm_on_graph;
    t.with_truth += d.with_truth;
    t.correct_nearest_road += d.correct_nearest_road, t.correct_hmm += d.correct_hmm;
    t.correct_hmm_road += d.correct_hmm_road, t.correct_fused += d.correct_fused;
    t.length_with_truth += d.length_with_truth, t.length_correct_hmm += d.length_correct_hmm;
    t.outage_samples += d.outage_samples, t.outage_correct += d.outage_correct, t.outage_sq += d.outage_sq;
    t.with_truth_nearest_oracle += d.with_truth_nearest_oracle, t.correct_hmm_nearest_oracle += d.correct_hmm_nearest_oracle;
    t.outage_samples_nearest_oracle += d.outage_samples_nearest_oracle;
    t.outage_correct_nearest_oracle += d.outage_correct_nearest_oracle;
    t.truth_from_lane += d.truth_from_lane;
    t.recovery_s = std::max(t.recovery_s, d.recovery_s);
    t.handback_jump_m = std::max(t.handback_jump_m, d.handback_jump_m);
    t.scale_sq_raw += d.scale_sq_raw, t.scale_sq_calibrated += d.scale_sq_calibrated, t.scale_n += d.scale_n;
  }
  return out;
}

std::string drive_plot_svg(const maps::RoadGraph& g, const DrivePlot& plot, const std::string& title) {
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (const auto& p : plot.truth) {
    x0 = std::min(x0, p.x_m), y0 = std::min(y0, p.y_m), x1 = std::max(x1, p.x_m), y1 = std::max(y1, p.y_m);
  }
  x0 -= 60, y0 -= 60, x1 += 60, y1 += 60;
  const double w = 900.0, scale = w / std::max(1.0, x1 - x0), h = (y1 - y0) * scale;
  auto X = [&](double x) { return (x - x0) * scale; };
  auto Y = [&](double y) { return (y1 - y) * scale; };
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h + 40
    << "' font-family='sans-serif' font-size='13'>\n<rect width='100%' height='100%' fill='white'/>\n";
  s << "<g stroke='#ccc' stroke-width='2' fill='none'>\n";
  for (EdgeId e : g.edges()) {
    if (g.twin(e).valid() && g.twin(e) < e) continue;
    const auto pts = g.geometry(e);
    // Drawn when its bounding box meets the plot's: a long straight road has no point inside.
    double ex0 = 1e18, ey0 = 1e18, ex1 = -1e18, ey1 = -1e18;
    for (const auto& p : pts) ex0 = std::min(ex0, p.x_m), ey0 = std::min(ey0, p.y_m), ex1 = std::max(ex1, p.x_m), ey1 = std::max(ey1, p.y_m);
    if (ex1 < x0 || ex0 > x1 || ey1 < y0 || ey0 > y1) continue;
    s << "<polyline points='";
    for (const auto& p : pts) s << X(p.x_m) << ',' << Y(p.y_m) << ' ';
    s << "'/>\n";
  }
  s << "</g>\n";
  auto line = [&](const std::vector<maps::Point2>& pts, const char* colour, double width, const char* dash) {
    s << "<polyline fill='none' stroke='" << colour << "' stroke-width='" << width << "' stroke-dasharray='" << dash << "' points='";
    for (const auto& p : pts) {
      if (std::isfinite(p.x_m)) s << X(p.x_m) << ',' << Y(p.y_m) << ' ';
    }
    s << "'/>\n";
  };
  for (const auto& p : plot.gps) s << "<circle cx='" << X(p.x_m) << "' cy='" << Y(p.y_m) << "' r='2' fill='#e8a33d'/>\n";
  line(plot.truth, "#222", 2.0, "none");
  line(plot.hmm, "#2b7bd6", 2.0, "6 3");
  std::vector<maps::Point2> outage;
  for (std::size_t i = 0; i < plot.fused.size(); ++i) {
    if (plot.in_outage[i] != 0) outage.push_back(plot.fused[i]);
  }
  line(outage, "#d62b4c", 3.0, "none");
  s << "<text x='10' y='" << h + 18 << "'>" << title
    << ": truth (black), raw GPS (orange dots), HMM matched (blue, dashed), odometry on the map through the outage (red)</text>\n";
  s << "</svg>\n";
  return s.str();
}

}  // namespace corridor::localizer
