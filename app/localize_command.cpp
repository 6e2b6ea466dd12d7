#include "app/localize_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "app/cli_error.hpp"
#include "app/map_options.hpp"
#include "app/vo_command.hpp"
#include "gnss/gpsd_source.hpp"
#include "gnss/nmea_replay.hpp"
#include "localizer/fusion/gps_odometry_localizer.hpp"
#include "localizer/fusion/simulated_odometry.hpp"
#include "localizer/match/trace_io.hpp"
#include "localizer/study/localization_study.hpp"
#include "maps/text_id.hpp"
#include "sim/corridor_client.hpp"

namespace corridor::app {
namespace {

using nlohmann::json;

struct LocalizeOptions {
  MapOptions map;
  std::string gps;
  std::string gpsd;  // HOST:PORT
  std::string nmea;
  std::string seq;
  std::string truth;
  bool json = false;
  std::string out;
  // Simulated GPS from the truth, when no --gps is given.
  double gps_noise_m = 5.0;
  double gps_rate_hz = 1.0;
  std::vector<std::string> gps_outages;
  std::uint64_t seed = 1;
  // Live feed.
  std::string server;
  std::string vehicle;
  std::string token;
  double speedup = 1.0;
  double gpsd_idle_s = 10.0;
};

struct TruthRow {
  double time_s;
  maps::Point2 position;
  double heading_deg;  // clockwise from north
  double arc_m;        // driven since the start
};

// The speed at row k: the distance driven over the rows either side of it.
double truth_speed_mps(const std::vector<TruthRow>& rows, std::size_t k) {
  const std::size_t a = k > 0 ? k - 1 : k, b = std::min(k + 1, rows.size() - 1);
  const double dt = rows[b].time_s - rows[a].time_s;
  return dt > 0.0 ? std::max(0.0, (rows[b].arc_m - rows[a].arc_m) / dt) : 0.0;
}

// drive.csv from `corridor vo synth`: frame,time_s,x_m,y_m,heading_rad,arc_m (map frame).
std::vector<TruthRow> read_drive_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UsageError("truth file not found: '" + path + "'");
  std::string line;
  std::getline(in, line);
  if (line.rfind("frame,time_s,x_m,y_m,heading_rad", 0) != 0) {
    throw UsageError("'" + path + "' is not a drive.csv (frame,time_s,x_m,y_m,heading_rad,arc_m)");
  }
  std::vector<TruthRow> rows;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string f;
    std::vector<double> v;
    while (std::getline(ss, f, ',')) v.push_back(std::stod(f));
    if (v.size() < 6) throw UsageError("'" + path + "': short line");
    // heading_rad is counter-clockwise from east; the map's headings are clockwise from north.
    rows.push_back({v[1], {v[2], v[3]}, std::fmod(90.0 - v[4] * 180.0 / std::numbers::pi + 720.0, 360.0), v[5]});
  }
  if (rows.size() < 2) throw UsageError("'" + path + "' has no drive");
  return rows;
}

std::vector<std::pair<double, double>> parse_outages(const std::vector<std::string>& specs) {
  std::vector<std::pair<double, double>> out;
  for (const std::string& s : specs) {
    const auto colon = s.find(':');
    try {
      if (colon == std::string::npos) throw std::invalid_argument(s);
      const double start = std::stod(s.substr(0, colon)), dur = std::stod(s.substr(colon + 1));
      if (!(start >= 0.0) || !(dur > 0.0)) throw std::invalid_argument(s);
      out.emplace_back(start, start + dur);
    } catch (const std::exception&) {
      throw UsageError("--gps-outage expects START:DURATION in seconds, got '" + s + "'");
    }
  }
  return out;
}

// What became of a receiver's reports: how many, how many became fixes, and why the others did not.
struct ReceiverTally {
  std::size_t reports = 0;
  std::size_t fixes = 0;
  std::map<std::string, std::size_t> refused;
  std::size_t duplicates = 0;
  std::size_t bad_checksums = 0;  // an NMEA log's, found before gpsd
  std::string ended;              // a live receiver: why its stream ended
  [[nodiscard]] json to_json() const {
    json j{{"reports", reports}, {"fixes", fixes}, {"refused", refused}, {"duplicate_epochs", duplicates}};
    if (bad_checksums > 0) j["bad_checksums"] = bad_checksums;
    if (!ended.empty()) j["ended"] = ended;
    return j;
  }
};

// Every epoch of a recorded NMEA log, through gpsd, as fixes (those with a 2D/3D fix).
std::vector<localizer::GpsFix> read_nmea(const std::string& file, ReceiverTally& tally) {
  gnss::NmeaReplay replay(file);
  tally.bad_checksums = replay.check().bad_checksums;
  std::vector<localizer::GpsFix> fixes;
  while (const auto r = replay.next()) {
    ++tally.reports;
    std::string why;
    if (const auto f = gnss::to_fix(*r, &why)) {
      if (!fixes.empty() && f->time_s <= fixes.back().time_s) continue;  // an epoch gpsd gave twice
      fixes.push_back(*f);
      ++tally.fixes;
    } else {
      ++tally.refused[why];
    }
  }
  if (fixes.empty()) throw UsageError("'" + file + "': gpsd found no 2D/3D fix in the log");
  return fixes;
}

// A live receiver through gpsd: each fix localized and posted as it comes, until the receiver's
// stream ends (idle, or its gpsd gone and not back).
void run_live_gpsd(const LocalizeOptions& o, const maps::RoadGraph& graph, const maps::EdgeSnapper& snapper) {
  const auto colon = o.gpsd.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == o.gpsd.size()) {
    throw UsageError("--gpsd expects HOST:PORT (gpsd listens on 2947), got '" + o.gpsd + "'");
  }
  gnss::GpsdSourceOptions options;
  options.idle_timeout_s = o.gpsd_idle_s;
  std::unique_ptr<gnss::GpsdSource> source;
  try {
    source = std::make_unique<gnss::GpsdSource>(o.gpsd.substr(0, colon), o.gpsd.substr(colon + 1), options);
  } catch (const gnss::GnssError& e) {
    throw std::runtime_error(e.what());
  }
  localizer::GpsOdometryLocalizer fusion(graph, snapper);
  std::unique_ptr<sim::CorridorClient> client;
  if (!o.server.empty()) client = std::make_unique<sim::CorridorClient>(o.server, o.token);
  ReceiverTally tally;
  json points = json::array();
  std::size_t posted = 0;
  double last_time = -1e18;
  while (const auto r = source->next()) {
    ++tally.reports;
    std::string why;
    const auto fix = gnss::to_fix(*r, &why);
    if (!fix) {
      ++tally.refused[why];
      continue;
    }
    if (fix->time_s <= last_time) continue;
    last_time = fix->time_s;
    ++tally.fixes;
    fusion.on_gps(*fix);
    const localizer::LocalizedPoint& p = fusion.last();
    if (p.source == localizer::PositionSource::none) continue;
    json j{{"time_s", fix->time_s}, {"lat", p.position.lat_deg}, {"lon", p.position.lon_deg}, {"heading_deg", p.heading_deg},
           {"edge", p.match.edge.v}, {"name", graph.name(p.match.edge)}, {"sigma_m", p.sigma_m}, {"source", localizer::to_string(p.source)}};
    if (client) {
      // The receiver's own time: a live fix is now.
      json body{{"lat", p.position.lat_deg}, {"lon", p.position.lon_deg}, {"heading_deg", p.heading_deg}, {"timestamp", fix->time_s},
                {"source", "gps"}};
      if (fix->hdop) body["hdop"] = *fix->hdop;
      if (fix->speed_mps) body["speed_mps"] = *fix->speed_mps;
      (void)client->post("/v1/vehicles/" + sim::path_segment(o.vehicle) + "/position", body);
      ++posted;
    }
    if (o.json) std::cout << j.dump() << std::endl;  // a stream: one line per position
    points.push_back(std::move(j));
  }
  tally.duplicates = source->duplicates();
  tally.ended = source->ended();
  if (tally.ended == "disconnected") spdlog::warn("event=gpsd_lost detail=\"the receiver's gpsd went away and did not come back\"");
  json summary{{"positions", points.size()}, {"receiver", tally.to_json()}, {"reconnects", source->reconnects()}};
  if (client) summary["posted_gps"] = posted;
  if (!o.out.empty()) {
    std::ofstream out(o.out);
    if (!out) throw UsageError("cannot write --out '" + o.out + "'");
    out << points.dump() << '\n';
  }
  std::cout << (o.json ? json{{"summary", summary}}.dump() : summary.dump(2)) << '\n';
}

void run_localize(const LocalizeOptions& o) {
  const int sources = (o.gps.empty() ? 0 : 1) + (o.gpsd.empty() ? 0 : 1) + (o.nmea.empty() ? 0 : 1);
  if (sources > 1) throw UsageError("give one GPS source: --gps, --gpsd or --nmea");
  if (!(o.gpsd_idle_s > 0.0 && o.gpsd_idle_s <= 3600.0)) throw UsageError("--gpsd-idle-s must be in (0, 3600]");
  if (!o.server.empty() && (o.vehicle.empty() || o.token.empty())) throw UsageError("--server needs --vehicle and --token");
  if (!o.vehicle.empty()) {
    if (const auto problem = maps::id_problem(o.vehicle)) throw UsageError("--vehicle: the id " + *problem);
  }
  if (!o.gpsd.empty()) {
    if (!o.seq.empty() || !o.truth.empty()) throw UsageError("--gpsd is a live receiver: it takes no --seq or --truth");
    const maps::RoadGraph graph = load_map_from_options(o.map);
    const maps::EdgeSnapper snapper(graph);
    run_live_gpsd(o, graph, snapper);
    return;
  }
  if (sources == 0 && o.truth.empty()) throw UsageError("give --gps, --gpsd or --nmea, or --truth to simulate GPS from");
  const bool gps_only = o.seq.empty() && o.truth.empty();
  if (gps_only && o.nmea.empty()) throw UsageError("give --seq (stereo odometry), or --truth to simulate odometry from");
  if (!(o.gps_rate_hz > 0.0 && o.gps_rate_hz <= 50.0) || !(o.gps_noise_m >= 0.0) || !(o.speedup > 0.0)) {
    throw UsageError("--gps-rate-hz must be in (0, 50], --gps-noise-m >= 0 and --speedup > 0");
  }
  if (!o.server.empty() && (o.vehicle.empty() || o.token.empty())) throw UsageError("--server needs --vehicle and --token");
  const auto outages = parse_outages(o.gps_outages);
  const maps::RoadGraph graph = load_map_from_options(o.map);
  const maps::EdgeSnapper snapper(graph);
  const std::vector<TruthRow> truth = o.truth.empty() ? std::vector<TruthRow>{} : read_drive_csv(o.truth);

  // GPS: from the file, or from the truth with noise, dropped inside the outages.
  std::vector<localizer::GpsFix> gps;
  ReceiverTally tally;
  if (!o.gps.empty()) {
    gps = localizer::read_trace(o.gps);
  } else if (!o.nmea.empty()) {
    try {
      gps = read_nmea(o.nmea, tally);
    } catch (const gnss::GnssError& e) {
      throw UsageError(e.what());
    }
  } else {
    std::mt19937_64 rng(o.seed);
    std::normal_distribution<double> noise(0.0, o.gps_noise_m), unit(0.0, 1.0);
    std::size_t k = 0;
    for (double t = truth.front().time_s; t <= truth.back().time_s; t += 1.0 / o.gps_rate_hz) {
      while (k + 1 < truth.size() && truth[k + 1].time_s <= t) ++k;
      const bool out = std::any_of(outages.begin(), outages.end(), [&](const auto& w) { return t >= w.first && t < w.second; });
      if (out) continue;
      localizer::GpsFix f;
      f.time_s = t;
      f.position = graph.projection().to_lat_lon({truth[k].position.x_m + noise(rng), truth[k].position.y_m + noise(rng)});
      f.hdop = std::max(1.0, o.gps_noise_m / 4.0);
      // A receiver's Doppler speed (±0.3 m/s) and, while moving, its course over ground (±5°), as
      // every NMEA receiver gives them (RMC) and as the localization study simulates them.
      const double v = truth_speed_mps(truth, k);
      f.speed_mps = std::max(0.0, v + 0.3 * unit(rng));
      if (v > 3.0) f.heading_deg = std::fmod(truth[k].heading_deg + 5.0 * unit(rng) + 360.0, 360.0);
      gps.push_back(f);
    }
  }

  // Odometry: the stereo VO's poses, or the truth with the VO's measured drift.
  std::vector<localizer::OdometryStep> odometry;
  if (!o.seq.empty()) {
    double rate = 10.0;
    const auto poses = vo_poses(o.seq, &rate);
    for (std::size_t i = 1; i < poses.size(); ++i) {
      const Eigen::Isometry3d step = poses[i - 1].inverse() * poses[i];
      const Eigen::Matrix3d r = step.rotation();
      // KITTI camera frame: x right, y down, z forward; a right turn swings z towards x.
      const double yaw_deg = std::atan2(r(0, 2), r(2, 2)) * 180.0 / std::numbers::pi;
      odometry.push_back({static_cast<double>(i) / rate, step.translation().norm(), yaw_deg});
    }
  } else {
    localizer::SimulatedOdometry simulated({}, o.seed + 1);
    for (std::size_t i = 1; i < truth.size(); ++i) {
      odometry.push_back(simulated.step(truth[i].time_s, truth[i - 1].position, truth[i - 1].heading_deg,
                                        truth[i].position, truth[i].heading_deg, truth[i].arc_m - truth[i - 1].arc_m));
    }
  }

  // Fuse in time order; one output per GPS period.
  localizer::GpsOdometryLocalizer fusion(graph, snapper);
  const double t_begin = std::min(gps.empty() ? 1e18 : gps.front().time_s, odometry.empty() ? 1e18 : odometry.front().time_s);
  const double t_end = std::max(gps.empty() ? -1e18 : gps.back().time_s, odometry.empty() ? -1e18 : odometry.back().time_s);
  std::size_t gi = 0, oi = 0;
  std::unique_ptr<sim::CorridorClient> client;
  if (!o.server.empty()) client = std::make_unique<sim::CorridorClient>(o.server, o.token);
  // The sequence's times as Unix seconds, keeping its intervals (the tracker reads speeds from them).
  // Posted `speedup` times faster than real time, they would run ahead of the wall clock, and the
  // server refuses positions from further ahead than its clock skew allows: so the sequence is
  // placed early enough that its last report is due when it is sent.
  const double epoch = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count() -
                       std::max(0.0, t_end - t_begin) * std::max(0.0, 1.0 - 1.0 / o.speedup);
  const auto wall_start = std::chrono::steady_clock::now();
  json points = json::array();
  std::size_t posted_gps = 0, posted_vo = 0, completed_at = 0;
  bool completed = false;
  double sq = 0.0;
  std::size_t scored = 0, on_edge = 0, outage_scored = 0, outage_on_edge = 0;
  std::size_t tk = 0;
  for (double t = t_begin; t <= t_end + 1e-9; t += 1.0 / o.gps_rate_hz) {
    while (oi < odometry.size() && odometry[oi].time_s <= t + 1e-9) fusion.on_odometry(odometry[oi++]);
    std::optional<double> hdop;
    while (gi < gps.size() && gps[gi].time_s <= t + 1e-9) {
      hdop = gps[gi].hdop;
      fusion.on_gps(gps[gi++]);
    }
    const localizer::LocalizedPoint& p = fusion.last();
    if (p.source == localizer::PositionSource::none) continue;
    json j{{"time_s", t},
           {"lat", p.position.lat_deg},
           {"lon", p.position.lon_deg},
           {"heading_deg", p.heading_deg},
           {"edge", p.match.edge.v},
           {"osm_way_id", graph.osm_way(p.match.edge).v},
           {"name", graph.name(p.match.edge)},
           {"offset_m", p.match.offset_m},
           {"sigma_m", p.sigma_m},
           {"source", localizer::to_string(p.source)}};
    if (!truth.empty()) {
      while (tk + 1 < truth.size() && truth[tk + 1].time_s <= t) ++tk;
      const double err = maps::distance_m(p.match.point, truth[tk].position);
      const EdgeId te = localizer::true_edge(graph, snapper, truth[tk].position, truth[tk].heading_deg, 20.0);
      const bool right = te.valid() && te == p.match.edge;
      sq += err * err;
      ++scored;
      on_edge += right ? 1 : 0;
      const bool out = std::any_of(outages.begin(), outages.end(), [&](const auto& w) { return t >= w.first && t < w.second; });
      if (out && te.valid()) {
        ++outage_scored;
        outage_on_edge += right ? 1 : 0;
      }
      j["error_m"] = err;
    }
    if (client) {
      // At the sequence's pace (or faster), with the source and HDOP as they were.
      const auto due = wall_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        std::chrono::duration<double>((t - t_begin) / o.speedup));
      std::this_thread::sleep_until(due);
      json body{{"lat", p.position.lat_deg}, {"lon", p.position.lon_deg}, {"heading_deg", p.heading_deg},
                {"timestamp", epoch + (t - t_begin)}, {"source", p.source == localizer::PositionSource::gps ? "gps" : "vo"}};
      if (p.source == localizer::PositionSource::gps && hdop) body["hdop"] = *hdop;
      const json answer = client->post("/v1/vehicles/" + sim::path_segment(o.vehicle) + "/position", body);
      (p.source == localizer::PositionSource::gps ? posted_gps : posted_vo) += 1;
      if (!completed && answer.value("completed", false)) {
        completed = true;
        completed_at = points.size();
      }
    }
    points.push_back(std::move(j));
  }
  if (points.empty()) throw UsageError("nothing could be localized: no GPS fix matched the map");
  json summary{{"positions", points.size()}, {"gps_fixes", gps.size()}, {"odometry_steps", odometry.size()}};
  if (!o.nmea.empty()) summary["receiver"] = tally.to_json();
  if (!truth.empty()) {
    summary["rmse_m"] = std::sqrt(sq / static_cast<double>(std::max<std::size_t>(1, scored)));
    summary["correct_edge_share"] = scored > 0 ? static_cast<double>(on_edge) / static_cast<double>(scored) : 0.0;
    summary["outage_correct_edge_share"] =
        outage_scored > 0 ? json(static_cast<double>(outage_on_edge) / static_cast<double>(outage_scored)) : json(nullptr);
  }
  if (client) {
    summary["posted_gps"] = posted_gps;
    summary["posted_vo"] = posted_vo;
    summary["mission_completed"] = completed;
    summary["completed_at_position"] = completed ? json(completed_at) : json(nullptr);
  }
  if (!o.out.empty()) {
    std::ofstream out(o.out);
    if (!out) throw UsageError("cannot write --out '" + o.out + "'");
    out << points.dump() << '\n';
  }
  if (o.json) {
    std::cout << json{{"summary", summary}, {"points", points}}.dump() << '\n';
  } else {
    std::cout << summary.dump(2) << '\n';
  }
}

}  // namespace

void register_localize_command(CLI::App& app) {
  auto o = std::make_shared<LocalizeOptions>();
  auto* cmd = app.add_subcommand("localize", "Fuse GPS and stereo odometry on a map; optionally feed a live server");
  add_map_options(*cmd, o->map);
  cmd->add_option("--gps", o->gps, "GPS trace (GPX or CSV time,lat,lon[,hdop,heading_deg,speed_mps]); else simulated from --truth");
  cmd->add_option("--gpsd", o->gpsd,
                  "a live receiver: gpsd at HOST:PORT (its reports through libgps; fixes without a 2D/3D mode are refused); "
                  "each position is printed (--json: a line each) and posted (--server) as it comes");
  cmd->add_option("--nmea", o->nmea, "a recorded NMEA 0183 log, decoded by a private gpsd as a receiver's would be");
  cmd->add_option("--gpsd-idle-s", o->gpsd_idle_s, "with --gpsd: no report for this long ends the run (receiver gone)")
      ->capture_default_str();
  cmd->add_option("--seq", o->seq, "KITTI-layout stereo sequence for the odometry; else simulated from --truth");
  cmd->add_option("--truth", o->truth, "drive.csv from corridor vo synth: scores the output and feeds the simulations");
  cmd->add_flag("--json", o->json, "print the summary and every position as JSON");
  cmd->add_option("--out", o->out, "write the positions as a JSON array");
  cmd->add_option("--gps-noise-m", o->gps_noise_m,
                  "simulated GPS noise σ (the simulated receiver also gives its speed, ±0.3 m/s, and course, ±5°)")
      ->capture_default_str();
  cmd->add_option("--gps-rate-hz", o->gps_rate_hz, "simulated GPS rate, and the output rate")->capture_default_str();
  cmd->add_option("--gps-outage", o->gps_outages, "START:DURATION seconds without simulated GPS (repeatable)");
  cmd->add_option("--seed", o->seed, "simulation seed")->capture_default_str();
  cmd->add_option("--server", o->server, "post each position to this corridor serve (http://host:port)");
  cmd->add_option("--vehicle", o->vehicle, "with --server: the vehicle id");
  cmd->add_option("--token", o->token, "with --server: a token with the vehicle or dispatcher role");
  cmd->add_option("--speedup", o->speedup, "with --server: post this many times faster than real time")->capture_default_str();
  cmd->callback([o] { run_localize(*o); });
}

}  // namespace corridor::app
