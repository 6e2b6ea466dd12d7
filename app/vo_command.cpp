#include "app/vo_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <opencv2/imgcodecs.hpp>

#include "app/cli_error.hpp"
#include "app/map_options.hpp"
#include "localizer/synth/sequence_writer.hpp"
#include "localizer/vo/errors.hpp"
#include "localizer/vo/stereo_odometry.hpp"
#include "localizer/vo/trajectory_metrics.hpp"
#include "localizer/vo/trajectory_plot.hpp"
#include "planner/experiments/scenario_generator.hpp"
#include "planner/one_to_one_search.hpp"

namespace corridor::app {
namespace {
namespace fs = std::filesystem;
using namespace corridor::localizer;

struct SynthOptions {
  MapOptions map;
  std::string out;
  double length_m = 1200.0;
  std::uint64_t seed = 1;
  double hz = 10.0;
  double speed_kmh = 36.0;
  double noise = 2.0;
  double blur = 0.0;
  double exposure = 0.05;
  double cars_per_km = 5.0;
  double min_turn_deg = 180.0;
};

// A real route through the map at least `length_m` long and with real turns, chosen by seed.
std::vector<maps::Point2> pick_drive(const maps::RoadGraph& graph, const SynthOptions& o) {
  planner::CostOverlay overlay(graph);
  const planner::TravelCost cost(graph, overlay, {50.0 / 3.6});
  planner::OneToOneSearch search;
  planner::Rng rng(planner::derive_seed(o.seed, "vo-synth-route"));
  // On the main component, where every pair of roads is joined.
  std::vector<EdgeId> main_edges;
  for (EdgeId e : graph.edges()) {
    if (graph.in_main_component(e)) main_edges.push_back(e);
  }
  const auto edges = static_cast<std::uint32_t>(main_edges.size());
  for (int attempt = 0; attempt < 400 && edges > 0; ++attempt) {
    const EdgeId a = main_edges[rng.below(edges)], b = main_edges[rng.below(edges)];
    const planner::Route route =
        search.run(planner::SearchSpace(cost, {{a, 0.0}}, {{b, graph.length_m(b)}}), true);
    if (!route.found || route.length_m < o.length_m + 30.0) continue;
    auto line = planner::route_polyline(graph, route);
    // Only the part that will be driven counts: the drive stops after --length-m.
    if (synth::total_turn_deg(line, synth::DriveOptions{}.corner_smoothing_m, o.length_m) < o.min_turn_deg) continue;
    spdlog::info("vo synth: route of {:.0f} m on attempt {}", route.length_m, attempt + 1);
    return line;
  }
  throw UsageError("no route of " + std::to_string(static_cast<int>(o.length_m)) +
                   " m with turns found on this map; try a shorter --length-m or another --seed");
}

void run_synth(const SynthOptions& o) {
  if (o.out.empty()) throw UsageError("--out is required");
  if (!(o.length_m >= 30 && o.length_m <= 20000)) throw UsageError("--length-m must be in [30, 20000]");
  if (!(o.hz >= 1 && o.hz <= 60)) throw UsageError("--hz must be in [1, 60]");
  if (!(o.speed_kmh > 1 && o.speed_kmh <= 130)) throw UsageError("--speed-kmh must be in (1, 130]");
  if (!(o.noise >= 0 && o.noise <= 50)) throw UsageError("--noise must be in [0, 50] grey levels");
  if (!(o.blur >= 0 && o.blur <= 1)) throw UsageError("--blur must be in [0, 1] (fraction of the frame interval)");
  if (!(o.exposure >= 0 && o.exposure <= 0.3)) throw UsageError("--exposure must be in [0, 0.3]");
  if (!(o.cars_per_km >= 0 && o.cars_per_km <= 100)) throw UsageError("--cars-per-km must be in [0, 100]");
  const maps::RoadGraph graph = load_map_from_options(o.map);
  const auto line = pick_drive(graph, o);
  synth::SynthSequenceOptions s;
  s.drive.frame_rate_hz = o.hz;
  s.drive.cruise_speed_mps = o.speed_kmh / 3.6;
  s.drive.max_length_m = o.length_m;
  s.scene.seed = o.seed;
  s.scene.cars_per_km = o.cars_per_km;
  s.imaging = {o.noise, o.blur, o.exposure, o.seed};
  const auto t0 = std::chrono::steady_clock::now();
  const auto summary = synth::write_synthetic_sequence(line, s, o.out);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json j{{"out", o.out},
                   {"frames", summary.frames},
                   {"length_m", summary.length_m},
                   {"duration_s", summary.duration_s},
                   {"total_turn_deg", summary.total_turn_deg},
                   {"width", s.render.width},
                   {"height", s.render.height},
                   {"focal_px", s.render.focal_px},
                   {"baseline_m", s.baseline_m},
                   {"frame_rate_hz", o.hz},
                   {"render_s", seconds}};
  std::cout << j.dump() << '\n';
}

struct RunOptions {
  std::string seq;
  bool eval = false;
  bool json = false;
  std::string out = "vo_poses.txt";
  std::string plot = "vo_trajectory.png";
  std::string frames_csv;
  std::string detector = "censure";
  std::string motion = "relative";
  bool no_ba = false;
  bool no_track_selection = false;
  int max_frames = 0;
  double max_depth_m = 40.0;
  int window = 6;
  bool ba_inline = false;
};

OdometryOptions odometry_options(const RunOptions& o) {
  OdometryOptions v;
  try {
    v.detector.kind = parse_detector_kind(o.detector);
    v.motion_model = parse_motion_model(o.motion);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  if (!(o.max_depth_m > 1 && o.max_depth_m <= 500)) throw UsageError("--max-depth-m must be in (1, 500]");
  v.stereo.max_depth_m = o.max_depth_m;
  if (!(o.window >= 3 && o.window <= 30)) throw UsageError("--ba-window must be in [3, 30] frames");
  v.window_frames = o.window;
  v.ba_in_background = !o.ba_inline;
  v.bundle_adjustment = !o.no_ba;
  v.ba.track_selection = !o.no_track_selection;
  return v;
}

struct RunResult {
  std::vector<Pose> poses;
  std::vector<FrameReport> frames;
  double seconds = 0.0;  // pipeline only, images already decoded
  std::vector<Pose> ground_truth;  // the frames run, when the sequence has ground truth
  std::optional<TrajectoryMetrics> metrics;
};

RunResult run_sequence(const StereoSequence& seq, const OdometryOptions& options, int max_frames) {
  StereoOdometry vo(seq.camera, options, seq.frame_rate_hz);
  RunResult r;
  const std::size_t n = max_frames > 0 ? std::min<std::size_t>(static_cast<std::size_t>(max_frames), seq.left.size())
                                       : seq.left.size();
  for (std::size_t i = 0; i < n; ++i) {
    const cv::Mat left = cv::imread(seq.left[i].string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(seq.right[i].string(), cv::IMREAD_GRAYSCALE);
    if (left.empty() || right.empty()) throw SequenceError("cannot read frame " + seq.left[i].string());
    if (left.size() != right.size()) throw SequenceError("left and right images differ in size at " + seq.left[i].string());
    const auto t0 = std::chrono::steady_clock::now();
    vo.process(left, right);
    r.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  const auto t0 = std::chrono::steady_clock::now();
  vo.flush();
  r.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.frames = vo.reports();
  r.poses = vo.trajectory();
  if (seq.ground_truth) {
    auto& gt = r.ground_truth;
    gt.assign(seq.ground_truth->begin(), seq.ground_truth->begin() + static_cast<std::ptrdiff_t>(n));
    // Drives shorter than KITTI's shortest segment are scored on 10…50 m segments instead.
    double len = 0;
    for (std::size_t i = 1; i < gt.size(); ++i) len += (gt[i].translation() - gt[i - 1].translation()).norm();
    r.metrics = evaluate_trajectory(r.poses, gt, len > 110 ? std::vector<double>{} : std::vector<double>{10, 20, 30, 40, 50});
  }
  return r;
}

nlohmann::json metrics_json(const RunResult& r) {
  nlohmann::json j;
  const auto& m = *r.metrics;
  j["t_err_pct"] = m.t_err_pct ? nlohmann::json(*m.t_err_pct) : nlohmann::json(nullptr);
  j["r_err_deg_per_100m"] = m.r_err_deg_per_100m ? nlohmann::json(*m.r_err_deg_per_100m) : nlohmann::json(nullptr);
  j["ate_rmse_m"] = m.ate_rmse_m;
  j["drift_pct"] = m.drift_pct;
  j["segment_lengths_m"] = m.segment_lengths_m;
  j["segments"] = m.segments;
  j["length_m"] = m.length_m;
  return j;
}

nlohmann::json summary_json(const RunResult& r, bool with_metrics) {
  nlohmann::json j = with_metrics && r.metrics ? metrics_json(r) : nlohmann::json::object();
  int bridged = 0;
  double inliers = 0, before = 0, after = 0;
  int ba_frames = 0;
  for (const auto& f : r.frames) {
    bridged += f.bridged ? 1 : 0;
    inliers += f.inliers;
    if (f.ba_iterations > 0) {
      before += f.reprojection_before_px;
      after += f.reprojection_after_px;
      ++ba_frames;
    }
  }
  j["fps"] = r.seconds > 0 ? static_cast<double>(r.frames.size()) / r.seconds : 0.0;
  j["frames"] = r.frames.size();
  j["bridged_frames"] = bridged;
  j["mean_inliers"] = r.frames.empty() ? 0.0 : inliers / static_cast<double>(r.frames.size());
  j["mean_ba_reprojection_before_px"] = ba_frames ? before / ba_frames : 0.0;
  j["mean_ba_reprojection_after_px"] = ba_frames ? after / ba_frames : 0.0;
  double stage[5] = {0, 0, 0, 0, 0};
  for (const auto& f : r.frames) {
    stage[0] += f.detect_ms;
    stage[1] += f.stereo_ms;
    stage[2] += f.temporal_ms;
    stage[3] += f.motion_ms;
    stage[4] += f.ba_ms;
  }
  const double n = std::max<double>(1.0, static_cast<double>(r.frames.size()));
  j["stage_ms"] = {{"detect", stage[0] / n}, {"stereo", stage[1] / n}, {"temporal", stage[2] / n},
                   {"motion", stage[3] / n}, {"ba", stage[4] / n}};
  return j;
}

void write_frames_csv(const fs::path& file, const std::vector<FrameReport>& frames) {
  std::ofstream out(file);
  if (!out) throw SequenceError("cannot write " + file.string());
  out << "frame,bridged,features,stereo_points,matches,inliers,motion_rms_px,ba_reprojection_before_px,"
         "ba_reprojection_after_px,ba_iterations,sigma_t_m,process_ms\n";
  for (const auto& f : frames) {
    const double sigma_t = std::sqrt(std::max(0.0, f.covariance.bottomRightCorner<3, 3>().trace()));
    out << f.index << ',' << (f.bridged ? 1 : 0) << ',' << f.features << ',' << f.stereo_points << ',' << f.matches
        << ',' << f.inliers << ',' << f.motion_rms_px << ',' << f.reprojection_before_px << ','
        << f.reprojection_after_px << ',' << f.ba_iterations << ',' << sigma_t << ',' << f.process_ms << '\n';
  }
}

StereoSequence open_or_usage(const std::string& dir) {
  if (dir.empty()) throw UsageError("--seq is required");
  return open_stereo_sequence(dir);
}

}  // namespace

std::vector<localizer::Pose> vo_poses(const std::filesystem::path& sequence, double* frame_rate_hz) {
  const localizer::StereoSequence seq = localizer::open_stereo_sequence(sequence);
  if (frame_rate_hz != nullptr) *frame_rate_hz = seq.frame_rate_hz;
  return run_sequence(seq, localizer::OdometryOptions{}, 0).poses;
}

namespace {

void run_vo(const RunOptions& o) {
  const auto options = odometry_options(o);
  if (o.max_frames < 0) throw UsageError("--max-frames must be ≥ 0");
  const StereoSequence seq = open_or_usage(o.seq);
  if (o.eval && !seq.ground_truth) {
    throw UsageError("--eval needs ground truth: " + o.seq + " has no poses.txt");
  }
  const RunResult r = run_sequence(seq, options, o.max_frames);
  write_kitti_poses(o.out, r.poses);
  if (!o.frames_csv.empty()) write_frames_csv(o.frames_csv, r.frames);
  if (!o.plot.empty()) write_trajectory_plot(o.plot, r.poses, r.ground_truth.empty() ? nullptr : &r.ground_truth);
  const nlohmann::json j = summary_json(r, o.eval);
  if (o.json) {
    std::cout << j.dump() << '\n';
    return;
  }
  std::cout << "frames            " << r.frames.size() << " (" << j["bridged_frames"] << " bridged)\n"
            << "fps               " << j["fps"].get<double>() << '\n'
            << "poses             " << o.out << '\n';
  if (o.eval) {
    auto show = [&](const char* key) { return j[key].is_null() ? std::string("n/a") : std::to_string(j[key].get<double>()); };
    std::cout << "t_err             " << show("t_err_pct") << " %\n"
              << "r_err             " << show("r_err_deg_per_100m") << " deg/100 m\n"
              << "ate_rmse          " << j["ate_rmse_m"].get<double>() << " m\n"
              << "drift             " << j["drift_pct"].get<double>() << " % of " << j["length_m"].get<double>() << " m\n"
              << "segments          " << j["segments"] << " of lengths " << j["segment_lengths_m"].dump() << " m\n";
  }
  if (!o.plot.empty()) std::cout << "plot              " << o.plot << '\n';
}

struct CompareOptions {
  std::string seq;
  std::string out;
  int max_frames = 0;
};

// The seed thesis's comparison: relative vs absolute orientation, with and without local BA, and
// track selection on and off.
void run_compare(const CompareOptions& o) {
  const StereoSequence seq = open_or_usage(o.seq);
  if (!seq.ground_truth) throw UsageError("compare needs ground truth: " + o.seq + " has no poses.txt");
  struct Variant {
    const char* name;
    MotionModel motion;
    bool ba;
    bool track_selection;
  };
  const Variant variants[] = {
      {"relative (P3P), BA, track selection", MotionModel::relative, true, true},
      {"relative (P3P), BA, all tracks refined", MotionModel::relative, true, false},
      {"relative (P3P), no BA", MotionModel::relative, false, true},
      {"absolute (Umeyama), BA, track selection", MotionModel::absolute, true, true},
      {"absolute (Umeyama), no BA", MotionModel::absolute, false, true},
  };
  std::ostringstream md;
  md << "| variant | t_err % | r_err deg/100 m | ATE RMSE m | drift % | fps | bridged |\n|---|---|---|---|---|---|---|\n";
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& v : variants) {
    OdometryOptions options;
    options.motion_model = v.motion;
    options.bundle_adjustment = v.ba;
    options.ba.track_selection = v.track_selection;
    const RunResult r = run_sequence(seq, options, o.max_frames);
    nlohmann::json j = summary_json(r, true);
    j["variant"] = v.name;
    rows.push_back(j);
    auto num = [&](const char* key, int digits) {
      if (j[key].is_null()) return std::string("n/a");
      std::ostringstream s;
      s.precision(digits);
      s << std::fixed << j[key].get<double>();
      return s.str();
    };
    md << "| " << v.name << " | " << num("t_err_pct", 2) << " | " << num("r_err_deg_per_100m", 3) << " | "
       << num("ate_rmse_m", 2) << " | " << num("drift_pct", 2) << " | " << num("fps", 1) << " | "
       << j["bridged_frames"] << " |\n";
    spdlog::info("vo compare: {} done", v.name);
  }
  if (!o.out.empty()) {
    std::ofstream f(o.out);
    if (!f) throw SequenceError("cannot write " + o.out);
    f << md.str();
  }
  std::cout << md.str();
}

}  // namespace

void register_vo_command(CLI::App& app) {
  auto* vo = app.add_subcommand("vo", "Stereo visual odometry: synthetic drives, runs and evaluation");
  vo->require_subcommand(1);

  auto so = std::make_shared<SynthOptions>();
  auto* synth_cmd = vo->add_subcommand("synth", "Render a synthetic stereo drive along a real route (KITTI layout)");
  add_map_options(*synth_cmd, so->map);
  synth_cmd->add_option("--out", so->out, "output directory")->required();
  synth_cmd->add_option("--length-m", so->length_m, "distance to drive")->capture_default_str();
  synth_cmd->add_option("--seed", so->seed, "route, scene and noise seed")->capture_default_str();
  synth_cmd->add_option("--hz", so->hz, "frame rate")->capture_default_str();
  synth_cmd->add_option("--speed-kmh", so->speed_kmh, "cruise speed (slower in bends)")->capture_default_str();
  synth_cmd->add_option("--noise", so->noise, "sensor noise sigma in grey levels")->capture_default_str();
  synth_cmd->add_option("--blur", so->blur, "motion blur: exposure as a fraction of the frame interval")
      ->capture_default_str();
  synth_cmd->add_option("--exposure", so->exposure, "auto-exposure gain jitter per frame")->capture_default_str();
  synth_cmd->add_option("--cars-per-km", so->cars_per_km, "oncoming cars crossing the view")->capture_default_str();
  synth_cmd->add_option("--min-turn-deg", so->min_turn_deg, "least total turning the route must have")
      ->capture_default_str();
  synth_cmd->callback([so] { run_synth(*so); });

  auto ro = std::make_shared<RunOptions>();
  auto* run_cmd = vo->add_subcommand("run", "Run the stereo odometry on a KITTI-layout sequence");
  run_cmd->add_option("--seq", ro->seq, "sequence directory (image_0/, image_1/, calib.txt[, poses.txt])")->required();
  run_cmd->add_flag("--eval", ro->eval, "score against the ground truth");
  run_cmd->add_flag("--json", ro->json, "print one JSON object");
  run_cmd->add_option("--out", ro->out, "estimated poses, KITTI format")->capture_default_str();
  run_cmd->add_option("--plot", ro->plot, "trajectory plot (PNG); empty for none")->capture_default_str();
  run_cmd->add_option("--frames-csv", ro->frames_csv, "per-frame report (inliers, BA reprojection, covariance)");
  run_cmd->add_option("--detector", ro->detector, "censure, fast or harris")->capture_default_str();
  run_cmd->add_option("--motion", ro->motion, "relative (P3P) or absolute")->capture_default_str();
  run_cmd->add_flag("--no-ba", ro->no_ba, "turn local bundle adjustment off");
  run_cmd->add_flag("--no-track-selection", ro->no_track_selection, "refine every point's structure in BA");
  run_cmd->add_option("--max-frames", ro->max_frames, "stop after this many frames (0: all)")->capture_default_str();
  run_cmd->add_option("--max-depth-m", ro->max_depth_m, "farthest stereo point used")->capture_default_str();
  run_cmd->add_option("--ba-window", ro->window, "keyframes in the local BA window")->capture_default_str();
  run_cmd->add_flag("--ba-inline", ro->ba_inline, "run local BA in line instead of on a second thread (same poses)");
  run_cmd->callback([ro] { run_vo(*ro); });

  auto co = std::make_shared<CompareOptions>();
  auto* cmp = vo->add_subcommand("compare", "Relative vs absolute orientation, BA on/off, track selection on/off");
  cmp->add_option("--seq", co->seq, "sequence directory with ground truth")->required();
  cmp->add_option("--out", co->out, "also write the Markdown table here");
  cmp->add_option("--max-frames", co->max_frames, "stop after this many frames (0: all)")->capture_default_str();
  cmp->callback([co] { run_compare(*co); });
}

}  // namespace corridor::app
