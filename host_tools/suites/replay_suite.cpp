// host_tools/suites: the own-log replay's runs and their report (replay_suite.hpp).
#include "geojcbb_host/replay_suite.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/batch.hpp"
#include "geojcbb_host/gps.hpp"
#include "geojcbb_host/world_model_report.hpp"
#include "geojcbb_host/report.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/svg_plot.hpp"

namespace geojcbb::host {
namespace fs = std::filesystem;

namespace {

// A landmark ever observed within this range [m] (made or paired): on Victoria Park, where a
// smoother's graph (iSAM/GTSAM's 151 trees) keeps only measurements at 4.6-20.7 m, the landmarks of
// the map that graph could hold.
constexpr double kNearRange_m = 20;

// The GPS table of a replay whose log has gps lines: per strategy the error of the estimated antenna
// track at the screened fixes, the landmarks mapped (and of them those ever observed within
// kNearRange_m), the mean NIS per pairing against its 95 % bounds, and the replay's time.
nlohmann::json gps_table(const std::vector<Method>& strategies, const std::vector<RunAggregate>& agg,
                         const std::vector<GpsScore>& gps) {
  nlohmann::json rows = nlohmann::json::array();
  std::printf("\nGPS (the antenna's estimated track at each kept fix; %d fixes, %d rejected after a gap, %d jumps)\n",
              gps.empty() ? 0 : gps[0].fixes, gps.empty() ? 0 : gps[0].after_gap, gps.empty() ? 0 : gps[0].jumps);
  std::printf(
      "| strategy | fixes used | RMSE [m] | max [m] (at t s) | landmarks | within %.0f m | pairings | mean NIS [95 %% "
      "bounds] | time [s] |\n",
      kNearRange_m);
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!agg[k].have_first) {
      std::printf("| %s | failed: %s | | | | | | | |\n", strategies[k].name().c_str(), agg[k].error.c_str());
      rows.push_back({{"strategy", strategies[k].name()}, {"error", agg[k].error}});
      continue;
    }
    const RunResult& r = agg[k].first;
    const GpsScore& g = gps[k];
    const double n = static_cast<double>(r.nis_pairings);
    const double nis = n > 0 ? r.nis_sum / n : NAN, half = n > 0 ? 1.96 * 2 / std::sqrt(n) : NAN;  // mean of chi2(2)
    const auto near =
        std::count_if(r.map.begin(), r.map.end(), [](const MapLandmark& l) { return l.closest_m <= kNearRange_m; });
    std::printf("| %s | %d | %.2f | %.2f (%.0f) | %d | %ld | %ld | %.2f [%.2f, %.2f] | %.2f |\n",
                strategies[k].name().c_str(), g.used, g.rmse_m, g.max_m, g.max_at_s, r.landmarks,
                static_cast<long>(near), r.nis_pairings, nis, 2 - half, 2 + half, agg[k].run_s);
    rows.push_back({{"strategy", strategies[k].name()},
                    {"fixes_used", g.used},
                    {"fixes_unmatched", g.unmatched},
                    {"rmse_m", g.rmse_m},
                    {"max_m", g.max_m},
                    {"max_at_s", g.max_at_s},
                    {"landmarks", r.landmarks},
                    {"landmarks_within_20_m", near},
                    {"not_augmented", r.not_augmented},
                    {"pairings", r.nis_pairings},
                    {"mean_nis", nis},
                    {"nis_bounds", {2 - half, 2 + half}},
                    {"time_s", agg[k].run_s}});
  }
  return rows;
}

// The path and map figure of a replay scored by GPS: the estimated antenna track over the kept fixes.
svg::Panel gps_panel(const std::string& title, const RunResult& r, const std::vector<replay::GpsEvent>& fixes,
                     const GpsOptions& o) {
  svg::Panel p;
  p.title = title;
  p.xlabel = "x (east) [m]";
  p.ylabel = "y (north) [m]";
  p.equal_aspect = true;
  GpsScore counts;
  svg::Series g{"GPS fixes kept", {}, {}, svg::Style::kMarkersDot, "#000000"};
  for (const replay::GpsEvent& f : screen_gps(fixes, o, counts)) {
    g.x.push_back(f.x);
    g.y.push_back(f.y);
  }
  svg::Series est{"estimated antenna track", {}, {}, svg::Style::kLine, "#D55E00"};
  const std::size_t step = std::max<std::size_t>(1, r.trace.size() / svg::kMaxLinePoints);
  for (std::size_t k = 0; k < r.trace.size(); k += step) {
    const Eigen::Vector2d at = antenna_at(r.trace[k].pose, o);
    est.x.push_back(at.x());
    est.y.push_back(at.y());
  }
  svg::Series map{"landmarks mapped", {}, {}, svg::Style::kMarkersCircle, "#009E73"};
  for (const MapLandmark& m : r.map) {
    map.x.push_back(m.x);
    map.y.push_back(m.y);
  }
  p.series = {g, est, map};
  return p;
}

// replay.csv's columns of run_csv that a log cannot give: without labels (or streamed to a device)
// the association scores and the map's spurious and duplicate landmarks; without truth lines the pose
// error and ANEES; a log has no kidnap, so no relocalisation score. Left empty, never 0.
std::set<std::string> unmeasured_columns(bool scored, bool have_truth) {
  std::set<std::string> u{"relocalised_at_scan", "fp_mover", "movers_in_map"};  // no simulated movers either
  if (!scored) {
    u.insert({"tp", "tn", "fp", "fn", "precision", "recall", "f1", "spurious_in_map", "duplicates", "fp_clutter",
              "group_f1"});
  }
  if (!have_truth) u.insert({"mean_abs_x_m", "mean_abs_y_m", "anees"});
  return u;
}

// replay.csv's GPS columns (the GPS table's figures) and the mean NIS per pairing; empty where not
// measured (no fixes in the log, a device run, no pairing).
constexpr const char* kGpsColumns[] = {"gps_fixes_used", "gps_rmse_m", "gps_max_m", "gps_max_at_s", "mean_nis"};
std::string gps_csv(const GpsScore* g, const RunResult& r) {
  std::ostringstream o;  // run_csv's precision
  if (g != nullptr && g->used > 0) {
    o << ',' << g->used << ',' << g->rmse_m << ',' << g->max_m << ',' << g->max_at_s;
  } else {
    o << ",,,,";
  }
  o << ',';
  if (r.nis_pairings > 0) o << r.nis_sum / static_cast<double>(r.nis_pairings);
  return o.str();
}

// The noise from the innovations (docs/replay.md, "Noise from the innovations"): `rounds` rounds of
// innovation_round with `m`, each printed (with the GPS RMSE when the log has fixes: a column of
// the table, never an input).
struct InnovationEstimate {
  NoiseScales scales;
  nlohmann::json rounds = nlohmann::json::array();
};
InnovationEstimate noise_from_innovations(const replay::LogSource& source, const RunOptions& base, const Method& m,
                                          int rounds, const std::vector<replay::GpsEvent>& gps,
                                          const GpsOptions& gps_opt) {
  InnovationEstimate e;
  NoiseScales& s = e.scales;
  std::printf("noise from the innovations (%s, %d rounds):\n", m.name().c_str(), rounds);
  std::printf(
      "| round | R range x | R bearing x | odometry x | pairings | mean NIS | NIS range | NIS bearing | R's share of S range "
      "| bearing | landmarks | GPS RMSE [m] |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (int round = 0; round < rounds; ++round) {
    RunOptions ro = base;
    m.apply(ro);
    ro.record_trace = !gps.empty();
    const NoiseScales at = s;
    const RunResult r = innovation_round(source, ro, s);
    const double rmse = gps.empty() ? NAN : score_gps(r.trace, gps, gps_opt).rmse_m;
    const InnovationSums& in = r.innovations;
    const double n = static_cast<double>(in.n);
    const double nis = r.nis_sum / static_cast<double>(std::max(1L, r.nis_pairings));
    std::printf("| %d | %.4g | %.4g | %.4g | %ld | %.3f | %.3f | %.3f | %.2f | %.2f | %d | %.2f |\n", round + 1,
                at.range, at.bearing, at.odometry, in.n, nis, in.nis[0] / n, in.nis[1] / n, in.r_share[0] / n,
                in.r_share[1] / n, r.landmarks, rmse);
    e.rounds.push_back({{"round", round + 1},
                        {"scales", {at.range, at.bearing, at.odometry}},
                        {"pairings", in.n},
                        {"mean_nis", nis},
                        {"nis", {in.nis[0] / n, in.nis[1] / n}},
                        {"r_share", {in.r_share[0] / n, in.r_share[1] / n}},
                        {"landmarks", r.landmarks},
                        {"gps_rmse_m", gps.empty() ? nlohmann::json() : nlohmann::json(rmse)}});
  }
  std::printf("scales: R range x %.4g, R bearing x %.4g, odometry x %.4g (variances)\n", s.range, s.bearing,
              s.odometry);
  return e;
}

// The batch reference (host_tools/mapping, batch.hpp): per strategy, every pose and landmark solved
// at once with the pairings its steps made, beside the filter: the GPS RMSE of both where the log
// has fixes, the mean position error of both where it has truth lines; with labels, one more row
// solved with the labels as the association (from TRUTH's run when it ran). Printed and written to
// batch.csv.
void batch_table(const std::vector<Method>& strategies, const std::vector<RunAggregate>& agg,
                 const std::vector<BatchRecorder>& recorders, const replay::LogSource& source, const RunOptions& base,
                 const replay::EventLog& log, const GpsOptions& gps_opt, bool labelled, const BatchOptions& bo,
                 const std::string& out_dir) {
  replay::LogSource src = source;
  const StepSettings<double> ss = step_settings(base, src.sensor);
  const Mount<double> mount{ss.sensor_x_m, ss.sensor_y_m, ss.sensor_theta_rad};
  std::printf(
      "\nBatch reference (every pose and landmark at once, Ceres' sparse Cholesky; %s; the association "
      "each strategy's steps made)\n",
      bo.huber > 0 ? ("Huber loss at " + std::to_string(bo.huber).substr(0, 4) + " sigma").c_str()
                   : "plain least squares");
  std::printf(
      "| association | filter GPS RMSE [m] | batch GPS RMSE [m] | filter position error [m] | batch position "
      "error [m] | poses | landmarks | observations | iterations | cost (start -> end) | converged | time [s] "
      "|\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  std::ofstream csv(out_dir + "/batch.csv");
  csv << "association,filter_gps_rmse_m,batch_gps_rmse_m,filter_position_error_m,batch_position_error_m,poses,landmarks,"
         "observations,iterations,initial_cost,final_cost,converged,solve_s\n";
  auto row = [&](const std::string& name, const BatchProblem& p, const RunResult& filter) {
    const BatchResult b = solve_batch(p, bo);
    const double f = log.gps.empty() ? NAN : score_gps(filter.trace, log.gps, gps_opt).rmse_m;
    const double g = log.gps.empty() ? NAN : score_gps(b.trace, log.gps, gps_opt).rmse_m;
    const double fe = mean_position_error(p, p.initial), be = mean_position_error(p, b.poses);
    std::printf("| %s | %.2f | %.2f | %.3f | %.3f | %zu | %zu | %zu | %d | %.4g -> %.4g | %s | %.1f |\n", name.c_str(),
                f, g, fe, be, p.initial.size(), p.landmark_initial.size(), p.obs.size(), b.iterations, b.initial_cost,
                b.final_cost, b.converged ? "yes" : "no", b.solve_s);
    csv << name << ',' << f << ',' << g << ',' << fe << ',' << be << ',' << p.initial.size() << ','
        << p.landmark_initial.size() << ',' << p.obs.size() << ',' << b.iterations << ',' << b.initial_cost << ','
        << b.final_cost << ',' << (b.converged ? 1 : 0) << ',' << b.solve_s << '\n';
  };
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!agg[k].have_first) continue;
    row(strategies[k].name(), batch_problem(src, recorders[k], agg[k].first.trace, mount, false), agg[k].first);
  }
  // The labels' batch starts from the best run there is: TRUTH's (the filter with the labels as its
  // association) when it ran, else the first strategy's.
  std::size_t start = strategies.size();
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (agg[k].have_first && (start == strategies.size() || strategies[k].oracle)) start = k;
  }
  if (labelled && start < strategies.size()) {
    row("labels", batch_problem(src, recorders[start], agg[start].first.trace, mount, true), agg[start].first);
  }
  if (!csv) throw std::runtime_error("cannot write " + out_dir + "/batch.csv");
}

// One replay's state, step by step: the log, the noise the filter assumes where a line gives none
// (and where it came from), the run options every strategy starts from, the GPS screening, the
// strategies; then what their replays gave.
struct ReplayRun {
  replay::EventLog log;
  bool labelled = false;
  replay::LogNoise noise;
  std::string noise_from = "the command line and the log's lines";
  std::vector<Eigen::Vector2d> positions;  ///< the landmark lines' (empty without them)
  RunOptions base;
  GpsOptions gps_opt;
  std::vector<Method> strategies;
  InnovationEstimate estimate;  ///< --noise-from-innovations
  int scans = 0, with_truth = 0;
  // The replays, per strategy.
  std::vector<RunAggregate> agg;
  std::vector<WorldModelSums> world;
  std::vector<BatchRecorder> recorders;  ///< --batch: what each strategy's steps made
  double wall_s = 0;
  std::vector<ReportRow> rows, group_rows;
  int failures = 0;
  std::vector<GpsScore> gps;
  nlohmann::json gps_rows;
};

// The log read, and the noise where a line gives none: from the data (--noise-from-data), the
// --sigma-* given, and for --noise-from-innovations a generic start where nothing gives it.
ReplayRun read_replay(const ReplayOptions& o) {
  ReplayRun r;
  r.log = replay::read_event_log(o.log);
  r.labelled = r.log.labelled();
  if (o.flags.oracle && !r.labelled) throw std::runtime_error("TRUTH (--truth) needs every measurement labelled");
  replay::LogNoise& noise = r.noise;
  if (o.noise_from_data) {
    noise = replay::estimate_noise(r.log, o.noise_inflation);
    r.noise_from = "the labelled data (robust spreads x " + std::to_string(o.noise_inflation).substr(0, 4) + ")";
  }
  if (o.noise.sigma_range_m > 0) noise.sigma_range_m = o.noise.sigma_range_m;
  if (o.noise.sigma_bearing_rad > 0) noise.sigma_bearing_rad = o.noise.sigma_bearing_rad;
  if (o.noise.sigma_v_mps > 0) noise.sigma_v_mps = o.noise.sigma_v_mps;
  if (o.noise.sigma_w_radps > 0) noise.sigma_w_radps = o.noise.sigma_w_radps;
  if (o.innovations) {  // a generic start where nothing gives the noise: the rounds scale it
    if (noise.sigma_range_m <= 0) noise.sigma_range_m = 0.1;
    if (noise.sigma_bearing_rad <= 0) noise.sigma_bearing_rad = 0.05;
    if (noise.sigma_v_mps <= 0) noise.sigma_v_mps = 0.1;
    if (noise.sigma_w_radps <= 0) noise.sigma_w_radps = 0.1;
  }
  return r;
}

// The run options every strategy starts from (the trace, the groups, the known map), the GPS
// antenna from the log's meta, the strategies.
void set_up_runs(const ReplayOptions& o, ReplayRun& r) {
  r.positions = replay::landmark_positions(r.log);
  r.base = o.run;
  r.base.record_trace = !r.log.gps.empty() || o.write_path || o.batch;
  r.gps_opt = o.gps;
  if (r.log.meta.count("gps_x_m")) r.gps_opt.antenna_x_m = r.log.meta.at("gps_x_m");
  if (r.log.meta.count("gps_y_m")) r.gps_opt.antenna_y_m = r.log.meta.at("gps_y_m");
  if (o.group_radius_m > 0) {
    if (r.positions.empty()) throw std::runtime_error("--group-radius needs the landmark positions (landmark lines)");
    r.base.landmark_group = replay::landmark_groups(r.positions, o.group_radius_m);
  }
  if (o.known_map) {
    if (r.positions.empty()) throw std::runtime_error("--known-map needs the landmark positions (landmark lines)");
    r.base.known_map = r.positions;
  }
  r.strategies = select_methods(o.flags.strategies, true, o.flags.oracle);
}

// --noise-from-innovations: the rounds with the first strategy besides TRUTH, and the source's
// noise (and what is printed as the noise where a line gives none) scaled by what they found.
void scale_from_innovations(const ReplayOptions& o, ReplayRun& r, replay::LogSource& source) {
  const auto learner =
      std::find_if(r.strategies.begin(), r.strategies.end(), [](const Method& m) { return !m.oracle; });
  if (learner == r.strategies.end())
    throw std::runtime_error("--noise-from-innovations needs a strategy besides TRUTH");
  r.estimate = noise_from_innovations(source, r.base, *learner, o.innovation_rounds,
                                      o.runner ? std::vector<replay::GpsEvent>() : r.log.gps, r.gps_opt);
  const NoiseScales& scales = r.estimate.scales;
  source.scale_noise(scales.range, scales.bearing, scales.odometry);
  r.noise_from += ", then scaled from the innovations (a line's own noise too)";
  r.noise.sigma_range_m *= std::sqrt(scales.range);  // what the replays below use where a line gives none
  r.noise.sigma_bearing_rad *= std::sqrt(scales.bearing);
  r.noise.sigma_v_mps *= std::sqrt(scales.odometry);
  r.noise.sigma_w_radps *= std::sqrt(scales.odometry);
}

// What the log holds and the noise the replays assume, printed; the scans counted.
void print_inputs(const ReplayOptions& o, ReplayRun& r, const replay::LogSource& source) {
  const replay::EventLog& log = r.log;
  if (o.runner && !log.gps.empty()) {
    std::printf(
        "GPS: the device reports its pose after every scan; between scans the host moves it by the odometry it "
        "sent (the filter's mean moves by the motion model alone)\n");
  }
  fs::create_directories(o.flags.out_dir);
  int predictions = 0;
  for (const RunInput& in : source.inputs()) {
    r.scans += in.scan;
    predictions += !in.scan;
    r.with_truth += in.scan && in.have_truth;
  }
  std::printf(
      "== %s: %zu odom, %zu odom_delta, %zu meas, %zu truth, %zu gps, %zu landmark lines; %d scans (%d with a true "
      "pose), %d predictions\n",
      o.log.c_str(), log.odometry.size(), log.increments.size(), log.measurements.size(), log.truth.size(),
      log.gps.size(), log.landmarks.size(), r.scans, r.with_truth, predictions);
  auto g = [](double v, const char* unit) {
    char b[48] = "not given";
    if (v > 0) std::snprintf(b, sizeof b, "%.4g %s", v, unit);
    return std::string(b);
  };
  std::printf(
      "noise where a line gives none (from %s): sigma_range %s, sigma_bearing %s, sigma_v %s, sigma_w %s "
      "(1-s means)\n",
      r.noise_from.c_str(), g(r.noise.sigma_range_m, "m").c_str(), g(r.noise.sigma_bearing_rad, "rad").c_str(),
      g(r.noise.sigma_v_mps, "m/s").c_str(), g(r.noise.sigma_w_radps, "rad/s").c_str());
  if (!r.labelled) std::printf("measurements not labelled: no association scores (Table 2), timing and pose only\n");
  if (r.with_truth == 0) std::printf("no truth lines at the scans: no pose error or NEES\n");
}

// Every strategy replayed (in process or through the runner), each from its own copy of the source.
void run_strategies(const ReplayOptions& o, ReplayRun& r, const replay::LogSource& source) {
  const std::size_t n = r.strategies.size();
  r.agg.assign(n, RunAggregate{});
  r.world.assign(n, WorldModelSums{});
  r.recorders.assign(n, BatchRecorder{});
  r.wall_s = run_parallel(n, o.runner ? 1 : o.flags.jobs, o.flags.progress, [&](std::size_t k) {
    RunOptions ro = r.base;
    r.strategies[k].apply(ro);
    if (o.batch) ro.on_scan = [&rec = r.recorders[k]](const ScanOutcome& sc) { rec.on_scan(sc); };
    replay::LogSource src = source;  // each thread its own position
    src.rewind();
    const auto a = std::chrono::steady_clock::now();
    try {
      RunResult res = o.runner ? o.runner(src, ro) : run_inputs(src, ro);
      r.agg[k].add(res, std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
      r.world[k].add(res);
      r.agg[k].first = std::move(res);
      r.agg[k].have_first = true;
    } catch (const std::exception& e) {
      r.agg[k].fail(e.what());
    }
  });
}

// The rows (pose scores left out without truth), Tables 1 and 2, the submaps and the world model.
void print_replay_tables(const ReplayOptions& o, ReplayRun& r, const replay::LogSource& source) {
  for (std::size_t k = 0; k < r.strategies.size(); ++k) {
    ReportRow row = r.agg[k].row(r.strategies[k].name(), false, r.labelled && !o.runner);
    if (r.with_truth == 0) row.abs_x = row.abs_y = row.anees = NAN;
    r.rows.push_back(row);
    r.group_rows.push_back(r.agg[k].group_row(r.strategies[k].name()));
    r.failures += r.agg[k].failed;
  }
  print_tables(r.rows, stdout, r.labelled);
  print_submaps(r.strategies, r.agg, stdout);
  std::vector<std::string> names;
  names.reserve(r.strategies.size());
  for (const Method& m : r.strategies) names.push_back(m.name());
  DetectionTable table;
  replay::LogSource src = source;
  if (r.labelled && r.with_truth > 0 && !r.positions.empty())
    table = labelled_detection(src, r.positions, step_settings(r.base, src.sensor));
  print_world_model(names, r.world, table.expected.empty() ? nullptr : &table, stdout);
}

// The GPS score per strategy: its table and gps_error.csv (per strategy and kept fix).
void report_gps(const ReplayOptions& o, ReplayRun& r) {
  for (std::size_t k = 0; k < r.strategies.size(); ++k)
    if (r.agg[k].have_first) r.gps[k] = score_gps(r.agg[k].first.trace, r.log.gps, r.gps_opt);
  r.gps_rows = gps_table(r.strategies, r.agg, r.gps);
  std::ofstream e(o.flags.out_dir + "/gps_error.csv");  // per strategy and kept fix: time and error
  e << "strategy,t_s,error_m\n";
  for (std::size_t k = 0; k < r.strategies.size(); ++k)
    for (std::size_t i = 0; i < r.gps[k].t.size(); ++i)
      e << r.strategies[k].name() << ',' << r.gps[k].t[i] << ',' << r.gps[k].error_m[i] << '\n';
  if (!e) throw std::runtime_error("cannot write " + o.flags.out_dir + "/gps_error.csv");
}

// --write-path: path.csv, the pose each strategy reported after each input, and map.csv, its final
// (global) map's landmarks.
void write_path_and_map(const std::string& out_dir, const std::vector<Method>& strategies,
                        const std::vector<RunAggregate>& agg) {
  std::ofstream p(out_dir + "/path.csv");
  p << "strategy,t_s,x_m,y_m,theta_rad\n";
  p.precision(10);
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!agg[k].have_first) continue;
    for (const TracePoint& q : agg[k].first.trace)
      p << strategies[k].name() << ',' << q.t_s << ',' << q.pose.x << ',' << q.pose.y << ',' << q.pose.theta << '\n';
  }
  if (!p) throw std::runtime_error("cannot write " + out_dir + "/path.csv");
  std::ofstream m(out_dir + "/map.csv");  // per strategy: the final (global) map's landmarks
  m << "strategy,x_m,y_m,sd_x_m,sd_y_m\n";
  m.precision(10);
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!agg[k].have_first) continue;
    const RunResult& r = agg[k].first;
    const bool cov = r.map_cov.rows() == static_cast<Eigen::Index>(2 * r.map.size());
    for (std::size_t i = 0; i < r.map.size(); ++i) {
      const auto d = static_cast<Eigen::Index>(2 * i);
      m << strategies[k].name() << ',' << r.map[i].x << ',' << r.map[i].y << ','
        << (cov ? std::sqrt(r.map_cov(d, d)) : std::nan("")) << ','
        << (cov ? std::sqrt(r.map_cov(d + 1, d + 1)) : std::nan("")) << '\n';
    }
  }
  if (!m) throw std::runtime_error("cannot write " + out_dir + "/map.csv");
}

// joins.csv, when a strategy joined local maps: per strategy and local map, what its join did
// (docs/submaps.md).
void write_joins(const std::string& out_dir, const std::vector<Method>& strategies,
                 const std::vector<RunAggregate>& agg) {
  bool any_join = false;
  for (std::size_t k = 0; k < strategies.size(); ++k)
    any_join = any_join || (agg[k].have_first && !agg[k].first.submaps.joins.empty());
  if (!any_join) return;
  std::ofstream j(out_dir + "/joins.csv");
  j << "strategy,map,t_s,landmarks,shared,offered,fused,declined,pruned,dropped,removed,refused,joint_d2,shared_d2,"
       "shared_dof,seeded_d2,seeded_dof,global_landmarks,base_x_m,base_y_m,base_theta_rad,base_sd_x_m,base_sd_y_m,base_sd_theta_rad\n";
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!agg[k].have_first) continue;
    const std::vector<JoinRecord>& js = agg[k].first.submaps.joins;
    for (std::size_t m = 0; m < js.size(); ++m) {
      const JoinRecord& r = js[m];
      j << strategies[k].name() << ',' << m << ',' << r.t_s << ',' << r.landmarks << ',' << r.shared << ',' << r.offered
        << ',' << r.fused << ',' << r.declined << ',' << r.pruned << ',' << r.dropped << ',' << r.removed << ','
        << r.refused << ',' << r.joint_d2 << ',' << r.shared_d2 << ',' << r.shared_dof << ',' << r.seeded_d2 << ','
        << r.seeded_dof << ',' << r.global << ',' << r.base[0] << ',' << r.base[1] << ',' << r.base[2] << ','
        << r.base_sd[0] << ',' << r.base_sd[1] << ',' << r.base_sd[2] << '\n';
    }
  }
  if (!j) throw std::runtime_error("cannot write " + out_dir + "/joins.csv");
}

// replay.csv: one row per strategy, a column the log cannot give left empty. False: not written.
bool write_replay_csv(const ReplayOptions& o, const ReplayRun& r) {
  std::ofstream csv(o.flags.out_dir + "/replay.csv");
  const std::set<std::string> unmeasured = unmeasured_columns(r.labelled && !o.runner, r.with_truth > 0);
  const bool scored_gps = !r.log.gps.empty();
  csv << "log,strategy";
  for (const std::string& c : run_csv_columns()) csv << ',' << c;
  for (const char* c : kGpsColumns) csv << ',' << c;
  csv << ",error\n";
  for (std::size_t k = 0; k < r.strategies.size(); ++k) {
    const RunAggregate& agg = r.agg[k];
    csv << csv_escape(o.log) << ',' << r.strategies[k].name();
    if (agg.have_first) {
      for (const std::string& c : run_csv_columns()) {
        csv << ',' << (unmeasured.count(c) != 0 ? std::string() : run_csv(agg.first, agg.run_s, {c}));
      }
      csv << gps_csv(scored_gps ? &r.gps[k] : nullptr, agg.first) << ",\n";
    } else {
      csv << std::string(run_csv_columns().size() + std::size(kGpsColumns), ',') << ',' << csv_escape(agg.error)
          << '\n';
    }
  }
  return static_cast<bool>(csv);
}

// replay.json: the log, the noise, the rows (a score the log cannot give null, never 0), the
// group-level rows and the GPS table.
void write_replay_json(const ReplayOptions& o, const ReplayRun& r) {
  nlohmann::json js;
  js["log"] = o.log;
  js["labelled"] = r.labelled;
  js["scans"] = r.scans;
  js["scans_with_truth"] = r.with_truth;
  js["noise"] = {{"from", r.noise_from},
                 {"sigma_range_m", r.noise.sigma_range_m},
                 {"sigma_bearing_rad", r.noise.sigma_bearing_rad},
                 {"sigma_v_mps", r.noise.sigma_v_mps},
                 {"sigma_w_radps", r.noise.sigma_w_radps}};
  if (o.innovations) {
    const NoiseScales& scales = r.estimate.scales;
    js["noise"]["innovation_scales"] = {
        {"range_var", scales.range}, {"bearing_var", scales.bearing}, {"odometry_var", scales.odometry}};
    js["noise"]["innovation_rounds"] = r.estimate.rounds;
  }
  js["wall_s"] = r.wall_s;
  js["strategies"] = rows_json(r.rows);
  // As in replay.csv, a score the log cannot give is null, never 0.
  static const char* const kLabelScores[] = {"accuracy",
                                             "f1",
                                             "precision",
                                             "recall",
                                             "tp",
                                             "tn",
                                             "fp",
                                             "fn",
                                             "false_pairs_in_group",
                                             "false_pairs_other_group",
                                             "false_pairs_to_duplicate",
                                             "false_pairs_to_original",
                                             "spurious_in_map",
                                             "runs_over_5_false_pairs",
                                             "false_relocalisations",
                                             "false_pairs_to_clutter"};
  for (nlohmann::json& row : js["strategies"]) {
    if (!(r.labelled && !o.runner)) {
      for (const char* key : kLabelScores) {
        if (row.contains(key)) row[key] = nullptr;
      }
    }
    if (r.with_truth == 0) {
      for (const char* key : {"nees_inside", "pose_error_after_kidnap_m"}) {
        if (row.contains(key)) row[key] = nullptr;
      }
    }
  }
  if (o.group_radius_m > 0) js["group_level"] = rows_json(r.group_rows);
  if (!r.log.gps.empty()) {
    const GpsOptions& g = r.gps_opt;
    js["gps"] = {{"fixes", r.gps[0].fixes},          {"rejected_after_gap", r.gps[0].after_gap},
                 {"rejected_jumps", r.gps[0].jumps}, {"max_gap_s", g.max_gap_s},
                 {"max_jump_m", g.max_jump_m},       {"antenna", {g.antenna_x_m, g.antenna_y_m}},
                 {"strategies", r.gps_rows}};
  }
  std::ofstream(o.flags.out_dir + "/replay.json") << js.dump(2) << '\n';
}

// replay_path.svg: per strategy its path and map, or with GPS fixes its antenna track over them.
void write_replay_figure(const ReplayOptions& o, const ReplayRun& r) {
  svg::Figure path;
  path.title = "Path and map, " + fs::path(o.log).filename().string();
  path.cols = std::min<int>(3, static_cast<int>(r.strategies.size()));
  for (std::size_t k = 0; k < r.strategies.size(); ++k) {
    if (!r.agg[k].have_first) continue;
    if (r.log.gps.empty()) {
      path.panels.push_back(path_map_panel(r.strategies[k].name(), r.agg[k].first, r.positions));
    } else {
      char t[96];
      std::snprintf(t, sizeof t, "%s: GPS RMSE %.2f m, %d landmarks", r.strategies[k].name().c_str(), r.gps[k].rmse_m,
                    r.agg[k].first.landmarks);
      path.panels.push_back(gps_panel(t, r.agg[k].first, r.log.gps, r.gps_opt));
    }
  }
  svg::write(path, o.flags.out_dir + "/replay_path.svg");
}

}  // namespace

int run_replay(const ReplayOptions& o) {
  ReplayRun r = read_replay(o);
  replay::LogSource source(r.log, r.noise);  // throws when a line has no noise from anywhere
  set_up_runs(o, r);
  if (o.innovations) scale_from_innovations(o, r, source);
  print_inputs(o, r, source);
  run_strategies(o, r, source);
  print_replay_tables(o, r, source);
  r.gps.assign(r.strategies.size(), GpsScore{});
  if (!r.log.gps.empty()) report_gps(o, r);
  if (o.batch) {
    if (o.runner) throw std::runtime_error("--batch: in process only (a device does not report its steps' pairings)");
    batch_table(r.strategies, r.agg, r.recorders, source, r.base, r.log, r.gps_opt, r.labelled, o.batch_options,
                o.flags.out_dir);
  }
  if (o.write_path) write_path_and_map(o.flags.out_dir, r.strategies, r.agg);
  write_joins(o.flags.out_dir, r.strategies, r.agg);
  if (r.labelled) {
    print_summary(r.rows, r.group_rows, stdout, "run");
    if (o.group_radius_m > 0) {
      std::printf("Table 2 at landmark-group level (landmarks within %.2f m form a group)\n", o.group_radius_m);
      print_accuracy(r.group_rows, stdout);
    }
  }
  // Files: one CSV row per strategy, the summary, the path and map figure.
  const bool csv_written = write_replay_csv(o, r);
  write_replay_json(o, r);
  if (!csv_written) throw std::runtime_error("cannot write " + o.flags.out_dir + "/replay.csv");
  if (o.flags.svg) write_replay_figure(o, r);
  std::printf("\n%zu replays in %.1f s; per-strategy rows: %s/replay.csv, summary: %s/replay.json%s\n",
              r.strategies.size(), r.wall_s, o.flags.out_dir.c_str(), o.flags.out_dir.c_str(),
              o.flags.svg ? (", figure: " + o.flags.out_dir + "/replay_path.svg").c_str() : "");
  if (r.failures > 0) std::fprintf(stderr, "%d replays failed (see the tables)\n", r.failures);
  return r.failures > 0 ? 1 : 0;
}

}  // namespace geojcbb::host
