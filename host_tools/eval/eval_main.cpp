// geojcbb_eval: the evaluation that reproduces the papers' tables and figures.
//   sim     Monte Carlo EKF-SLAM runs over simulated scenarios (default: env1
//   and env2, 20 runs each,
//           every strategy on the same seeds): Table 1 (association time),
//           Table 2 (TP/TN/FP/FN, precision, recall, F1, accuracy), x/y pose
//           error, NEES with its 95 % bounds; CSV, JSON and SVG figures (path
//           fitting, x/y error over time, F1 per strategy, NEES over time).
//   mrclam  the same filter and metrics on the UTIAS MRCLAM real data (every
//   strategy, every robot).
//   replay  the same on a user's own log (docs/replay.md); convert-mrclam writes a MRCLAM robot as
//           such a log. All three report through report.hpp (tables, CSV, JSON, path figure).
// With --port (or --device, which starts a device program on a pty) every run is streamed to a
// device over the serial link instead of running in process (host_tools/link: stream_run, one run
// at a time, reconnecting as LinkSession does), and the device's replies are scored the same way.
// Timing never decides anything here; it is reported.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/link_cli.hpp"
#include "geojcbb_host/mrclam_replay.hpp"
#include "geojcbb_host/report.hpp"
#include "geojcbb_host/run_cli.hpp"
#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/gps.hpp"
#include "geojcbb_host/victoria_park.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/stream.hpp"
#include "geojcbb_host/svg_plot.hpp"
#include "geojcbb_host/guarded_main.hpp"

using namespace geojcbb;
using namespace geojcbb::host;
namespace fs = std::filesystem;

namespace {

// Per (scenario, strategy): sums over the runs (report.hpp, the reporting path shared with the
// MRCLAM replay and the own-log replay).
using Cell = RunAggregate;

// runs.csv's columns after scenario, strategy, seed (report.hpp: run_csv).
const std::vector<std::string> kSimCsvColumns{"scans",
                                              "observations",
                                              "tp",
                                              "tn",
                                              "fp",
                                              "fn",
                                              "f1",
                                              "association_s",
                                              "run_s",
                                              "mean_abs_x_m",
                                              "mean_abs_y_m",
                                              "landmarks",
                                              "spurious_in_map",
                                              "budget_hits",
                                              "relocalised_at_scan",
                                              "anees"};

struct SimOptions {
  std::vector<std::string> scenarios;
  int runs = 20;
  std::uint64_t seed = 1;
  std::vector<std::string> strategies;
  int jobs = 0;
  std::string out_dir = "build/results/eval";
  bool svg = true;
  bool progress = true;
  bool oracle = false;
  RunOptions run;
  RunInputsFn runner;       ///< empty: in process
  std::string device_info;  ///< the device the runs were streamed to (empty: in process)
};

int run_sim(const SimOptions& o) {
  const std::vector<Method> strategies = select_methods(o.strategies, true, o.oracle);
  std::vector<Scenario> scenarios;
  for (const std::string& p : o.scenarios) scenarios.push_back(load_scenario(p));
  fs::create_directories(o.out_dir);

  struct Job {
    int sc, st, run;
  };
  std::vector<Job> jobs;
  for (int run = 0; run < o.runs; ++run)  // seed-major: a partial result is still balanced
    for (std::size_t sc = 0; sc < scenarios.size(); ++sc)
      for (std::size_t st = 0; st < strategies.size(); ++st) jobs.push_back({int(sc), int(st), run});
  std::vector<std::vector<Cell>> cells(scenarios.size(), std::vector<Cell>(strategies.size()));
  struct RunRow {
    int sc, st, run;
    RunResult r;
    double run_s;
  };
  std::vector<std::string> csv_rows(jobs.size());
  std::mutex mu;
  const int threads = o.runner     ? 1  // one device, one run at a time
                      : o.jobs > 0 ? o.jobs
                                   : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const double wall_s = run_parallel(jobs.size(), threads, o.progress, [&](std::size_t j) {
    const Job& jb = jobs[j];
    RunOptions ro = o.run;
    strategies[jb.st].apply(ro);
    const std::uint64_t seed = o.seed + static_cast<std::uint64_t>(jb.run);
    const auto a = std::chrono::steady_clock::now();
    RunResult r;
    std::string err;
    try {
      SimSource src(scenarios[jb.sc], seed, ro.max_steps);
      r = o.runner ? o.runner(src, ro) : run_inputs(src, ro);
    } catch (const std::exception& e) {
      err = e.what();
    }
    const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
    std::lock_guard<std::mutex> lock(mu);
    Cell& c = cells[jb.sc][jb.st];
    if (!err.empty()) {
      c.fail(err);
    } else {
      const double kidnap = scenarios[jb.sc].kidnap_t_s;
      c.add(r, run_s, kidnap);
      csv_rows[j] = csv_escape(scenarios[jb.sc].name) + ',' + strategies[jb.st].name() + ',' + std::to_string(seed) +
                    ',' + run_csv(r, run_s, kSimCsvColumns, kidnap);
      if (jb.run == 0) {
        c.first = std::move(r);
        c.have_first = true;
      }
    }
  });

  // Report.
  nlohmann::json js;
  js["runs_per_strategy"] = o.runs;
  js["first_seed"] = o.seed;
  js["threads"] = threads;
  js["wall_s"] = wall_s;
  if (!o.device_info.empty()) js["device"] = o.device_info;
  int failures = 0;
  double lo = 0, hi = 0;
  const bool have_bounds =
      chi2_inv(0.025, 3 * o.runs, lo) == Status::kOk && chi2_inv(0.975, 3 * o.runs, hi) == Status::kOk;
  std::vector<std::vector<double>> f1(strategies.size(), std::vector<double>(scenarios.size(), NAN));
  for (std::size_t sc = 0; sc < scenarios.size(); ++sc) {
    const Scenario& s = scenarios[sc];
    std::vector<ReportRow> rows;
    for (std::size_t st = 0; st < strategies.size(); ++st) {
      const Cell& c = cells[sc][st];
      failures += c.failed;
      const ReportRow row = c.row(strategies[st].name(), true, !o.runner);
      f1[st][sc] = c.score.f1();
      rows.push_back(row);
    }
    const int scans = cells[sc][0].runs ? cells[sc][0].scans / cells[sc][0].runs : 0;
    std::printf("\n== %s: %d runs per strategy (seeds %llu..%llu), %d scans per run\n", s.name.c_str(), o.runs,
                static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed + o.runs - 1), scans);
    print_tables(rows, stdout);
    js["scenarios"].push_back({{"name", s.name}, {"file", o.scenarios[sc]}, {"strategies", rows_json(rows)}});

    if (o.svg) {
      const std::string stem = o.out_dir + "/" + fs::path(o.scenarios[sc]).stem().string();
      svg::Figure path;
      path.title = "Path fitting, " + s.name + " (seed " + std::to_string(o.seed) + ")";
      path.cols = std::min<int>(3, static_cast<int>(strategies.size()));
      svg::Figure err;
      err.title = "Mean absolute pose error over " + std::to_string(o.runs) + " runs, " + s.name;
      err.cols = 1;
      err.panel_w = 900;
      err.share_x = true;
      err.panels.resize(2);
      err.panels[0] = {"x error", "", "|x error| [m]", {}, false, {}, {}};
      err.panels[1] = {"y error", "time [s]", "|y error| [m]", {}, false, {}, {}};
      svg::Figure nees;
      nees.title = "Pose NEES, mean over " + std::to_string(o.runs) + " runs: " + s.name;
      nees.panel_w = 900;
      nees.panels.resize(1);
      nees.panels[0] = {"", "time [s]", "NEES (3 dof)", {}, false, {}, {}};
      for (std::size_t st = 0; st < strategies.size(); ++st) {
        const Cell& c = cells[sc][st];
        if (!c.have_first) continue;
        std::vector<Eigen::Vector2d> truth_map(s.landmarks.begin(), s.landmarks.end());
        const svg::Panel p = path_map_panel(strategies[st].name(), c.first, truth_map);
        path.panels.push_back(p);
        const std::string name = strategies[st].name();
        svg::Series sx{name, c.t, {}, svg::Style::kLine, ""}, sy{name, c.t, {}, svg::Style::kLine, ""};
        svg::Series sn{name, c.t, {}, svg::Style::kLine, ""};
        for (std::size_t k = 0; k < c.t.size(); ++k) {
          sx.y.push_back(c.ex_sum[k] / c.runs);
          sy.y.push_back(c.ey_sum[k] / c.runs);
          sn.y.push_back(c.nees_sum[k] / c.runs);
        }
        err.panels[0].series.push_back(sx);
        err.panels[1].series.push_back(sy);
        nees.panels[0].series.push_back(sn);
      }
      if (have_bounds && !cells[sc][0].t.empty()) {
        const auto& t = cells[sc][0].t;
        nees.panels[0].series.push_back(
            {"95 % bounds", t, std::vector<double>(t.size(), lo / o.runs), svg::Style::kDashed, "#000000"});
        nees.panels[0].series.push_back(
            {"", t, std::vector<double>(t.size(), hi / o.runs), svg::Style::kDashed, "#000000"});
      }
      svg::write(path, stem + "_path.svg");
      svg::write(err, stem + "_error.svg");
      svg::write(nees, stem + "_nees.svg");
      std::printf("figures: %s_path.svg, %s_error.svg, %s_nees.svg\n", stem.c_str(), stem.c_str(), stem.c_str());
    }
  }
  if (o.svg) {
    svg::BarChart bars;
    bars.title = "F1 per strategy (" + std::to_string(o.runs) + " runs each)";
    bars.ylabel = "F1";
    for (const Method& st : strategies) bars.categories.push_back(st.name());
    for (const Scenario& s : scenarios) bars.groups.push_back(s.name.substr(0, s.name.find(':')));
    bars.values.assign(scenarios.size(), std::vector<double>(strategies.size(), NAN));
    double fmin = 1.0;
    for (std::size_t st = 0; st < strategies.size(); ++st)
      for (std::size_t sc = 0; sc < scenarios.size(); ++sc) {
        bars.values[sc][st] = f1[st][sc];
        if (std::isfinite(f1[st][sc])) fmin = std::min(fmin, f1[st][sc]);
      }
    bars.y_range = svg::Range{std::floor(fmin * 50 - 1) / 50, 1.0};
    bars.value_decimals = 4;
    svg::write(bars, o.out_dir + "/f1.svg");
    std::printf("figure: %s/f1.svg\n", o.out_dir.c_str());
  }
  {
    std::ofstream csv(o.out_dir + "/runs.csv");
    csv << "scenario,strategy,seed";
    for (const std::string& col : kSimCsvColumns) csv << ',' << col;
    csv << '\n';
    for (const std::string& r : csv_rows)
      if (!r.empty()) csv << r << '\n';
    std::ofstream(o.out_dir + "/summary.json") << js.dump(2) << '\n';
    if (!csv) throw std::runtime_error("cannot write " + o.out_dir + "/runs.csv");
  }
  std::printf(
      "\n%zu runs in %.1f s on %d threads; per-run rows: %s/runs.csv, "
      "summary: %s/summary.json\n",
      jobs.size(), wall_s, threads, o.out_dir.c_str(), o.out_dir.c_str());
  if (failures > 0) std::fprintf(stderr, "%d runs failed (see the tables)\n", failures);
  return failures > 0 ? 1 : 0;
}

// The own-log replay (docs/replay.md): every chosen strategy on one log, reported as the
// simulation and the MRCLAM replay are (report.hpp): Tables 1 and 2 (Table 2 and the summary only
// when every measurement is labelled), pose and map, replay.csv, replay.json, replay_path.svg.
struct ReplayOptions {
  std::string log;
  std::vector<std::string> strategies;
  bool oracle = false;
  std::string out_dir = "build/results/replay";
  replay::LogNoise noise;  ///< 0: from the lines, or from the data
  bool noise_from_data = false;
  double noise_inflation = 1.5;
  double group_radius_m = 0;  ///< > 0: landmark groups for the group-level score
  bool known_map = false;
  bool svg = true;
  bool progress = true;
  int jobs = 0;
  RunOptions run;
  GpsOptions gps;      ///< the screening (the antenna from the log's meta)
  RunInputsFn runner;  ///< empty: in process; else each replay streamed to a device
};

// The GPS table of a replay whose log has gps lines: per strategy the error of the estimated antenna
// track at the screened fixes, the landmarks mapped, the mean NIS per pairing against its 95 %
// bounds, and the replay's time.
nlohmann::json gps_table(const std::vector<Method>& strategies, const std::vector<RunAggregate>& agg,
                         const std::vector<GpsScore>& gps) {
  nlohmann::json rows = nlohmann::json::array();
  std::printf("\nGPS (the antenna's estimated track at each kept fix; %d fixes, %d rejected after a gap, %d jumps)\n",
              gps.empty() ? 0 : gps[0].fixes, gps.empty() ? 0 : gps[0].after_gap, gps.empty() ? 0 : gps[0].jumps);
  std::printf(
      "| strategy | fixes used | RMSE [m] | max [m] (at t s) | landmarks | pairings | mean NIS [95 %% bounds] | time [s] |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!agg[k].have_first) {
      std::printf("| %s | failed: %s | | | | | | |\n", strategies[k].name().c_str(), agg[k].error.c_str());
      rows.push_back({{"strategy", strategies[k].name()}, {"error", agg[k].error}});
      continue;
    }
    const RunResult& r = agg[k].first;
    const GpsScore& g = gps[k];
    const double n = static_cast<double>(r.nis_pairings);
    const double nis = n > 0 ? r.nis_sum / n : NAN, half = n > 0 ? 1.96 * 2 / std::sqrt(n) : NAN;  // mean of chi2(2)
    std::printf("| %s | %d | %.2f | %.2f (%.0f) | %d | %ld | %.2f [%.2f, %.2f] | %.2f |\n",
                strategies[k].name().c_str(), g.used, g.rmse_m, g.max_m, g.max_at_s, r.landmarks, r.nis_pairings, nis,
                2 - half, 2 + half, agg[k].run_s);
    rows.push_back({{"strategy", strategies[k].name()},
                    {"fixes_used", g.used},
                    {"fixes_unmatched", g.unmatched},
                    {"rmse_m", g.rmse_m},
                    {"max_m", g.max_m},
                    {"max_at_s", g.max_at_s},
                    {"landmarks", r.landmarks},
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

int run_replay(const ReplayOptions& o) {
  const replay::EventLog log = replay::read_event_log(o.log);
  const bool labelled = log.labelled();
  if (o.oracle && !labelled) throw std::runtime_error("TRUTH (--truth) needs every measurement labelled");
  replay::LogNoise noise;
  std::string noise_from = "the command line and the log's lines";
  if (o.noise_from_data) {
    noise = replay::estimate_noise(log, o.noise_inflation);
    noise_from = "the labelled data (robust spreads x " + std::to_string(o.noise_inflation).substr(0, 4) + ")";
  }
  if (o.noise.sigma_range_m > 0) noise.sigma_range_m = o.noise.sigma_range_m;
  if (o.noise.sigma_bearing_rad > 0) noise.sigma_bearing_rad = o.noise.sigma_bearing_rad;
  if (o.noise.sigma_v_mps > 0) noise.sigma_v_mps = o.noise.sigma_v_mps;
  if (o.noise.sigma_w_radps > 0) noise.sigma_w_radps = o.noise.sigma_w_radps;
  const replay::LogSource source(log, noise);  // throws when a line has no noise from anywhere
  const std::vector<Eigen::Vector2d> positions = replay::landmark_positions(log);
  RunOptions base = o.run;
  base.record_trace = !log.gps.empty();
  GpsOptions gps_opt = o.gps;
  if (log.meta.count("gps_x_m")) gps_opt.antenna_x_m = log.meta.at("gps_x_m");
  if (log.meta.count("gps_y_m")) gps_opt.antenna_y_m = log.meta.at("gps_y_m");
  if (o.group_radius_m > 0) {
    if (positions.empty()) throw std::runtime_error("--group-radius needs the landmark positions (landmark lines)");
    base.landmark_group = replay::landmark_groups(positions, o.group_radius_m);
  }
  if (o.known_map) {
    if (positions.empty()) throw std::runtime_error("--known-map needs the landmark positions (landmark lines)");
    base.known_map = positions;
  }
  const std::vector<Method> strategies = select_methods(o.strategies, true, o.oracle);
  if (o.runner && !log.gps.empty()) {
    std::printf("GPS scoring needs the pose after every input, which a device does not report: not scored\n");
  }
  base.record_trace = base.record_trace && !o.runner;
  fs::create_directories(o.out_dir);
  int scans = 0, predictions = 0, with_truth = 0;
  for (const RunInput& in : source.inputs()) {
    scans += in.scan;
    predictions += !in.scan;
    with_truth += in.scan && in.have_truth;
  }
  std::printf(
      "== %s: %zu odom, %zu odom_delta, %zu meas, %zu truth, %zu gps, %zu landmark lines; %d scans (%d with a true "
      "pose), %d predictions\n",
      o.log.c_str(), log.odometry.size(), log.increments.size(), log.measurements.size(), log.truth.size(),
      log.gps.size(), log.landmarks.size(), scans, with_truth, predictions);
  {
    auto g = [](double v, const char* unit) {
      char b[48] = "not given";
      if (v > 0) std::snprintf(b, sizeof b, "%.4g %s", v, unit);
      return std::string(b);
    };
    std::printf(
        "noise where a line gives none (from %s): sigma_range %s, sigma_bearing %s, sigma_v %s, sigma_w %s "
        "(1-s means)\n",
        noise_from.c_str(), g(noise.sigma_range_m, "m").c_str(), g(noise.sigma_bearing_rad, "rad").c_str(),
        g(noise.sigma_v_mps, "m/s").c_str(), g(noise.sigma_w_radps, "rad/s").c_str());
  }
  if (!labelled) std::printf("measurements not labelled: no association scores (Table 2), timing and pose only\n");
  if (with_truth == 0) std::printf("no truth lines at the scans: no pose error or NEES\n");

  std::vector<RunAggregate> agg(strategies.size());
  const double wall_s = run_parallel(strategies.size(), o.runner ? 1 : o.jobs, o.progress, [&](std::size_t k) {
    RunOptions ro = base;
    strategies[k].apply(ro);
    replay::LogSource src = source;  // each thread its own position
    src.rewind();
    const auto a = std::chrono::steady_clock::now();
    try {
      RunResult r = o.runner ? o.runner(src, ro) : run_inputs(src, ro);
      agg[k].add(r, std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
      agg[k].first = std::move(r);
      agg[k].have_first = true;
    } catch (const std::exception& e) {
      agg[k].fail(e.what());
    }
  });
  std::vector<ReportRow> rows, group_rows;
  int failures = 0;
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    ReportRow row = agg[k].row(strategies[k].name(), false, labelled && !o.runner);
    if (with_truth == 0) row.abs_x = row.abs_y = row.anees = NAN;
    rows.push_back(row);
    group_rows.push_back(agg[k].group_row(strategies[k].name()));
    failures += agg[k].failed;
  }
  print_tables(rows, stdout, labelled);
  std::vector<GpsScore> gps(strategies.size());
  nlohmann::json gps_rows;
  if (!log.gps.empty() && !o.runner) {
    for (std::size_t k = 0; k < strategies.size(); ++k)
      if (agg[k].have_first) gps[k] = score_gps(agg[k].first.trace, log.gps, gps_opt);
    gps_rows = gps_table(strategies, agg, gps);
    std::ofstream e(o.out_dir + "/gps_error.csv");  // per strategy and kept fix: time and error
    e << "strategy,t_s,error_m\n";
    for (std::size_t k = 0; k < strategies.size(); ++k)
      for (std::size_t i = 0; i < gps[k].t.size(); ++i)
        e << strategies[k].name() << ',' << gps[k].t[i] << ',' << gps[k].error_m[i] << '\n';
    if (!e) throw std::runtime_error("cannot write " + o.out_dir + "/gps_error.csv");
  }
  if (labelled) {
    print_summary(rows, group_rows, stdout, "run");
    if (o.group_radius_m > 0) {
      std::printf("Table 2 at landmark-group level (landmarks within %.2f m form a group)\n", o.group_radius_m);
      print_accuracy(group_rows, stdout);
    }
  }
  // Files: one CSV row per strategy, the summary, the path and map figure.
  {
    std::ofstream csv(o.out_dir + "/replay.csv");
    csv << "log,strategy";
    for (const std::string& c : run_csv_columns()) csv << ',' << c;
    csv << ",error\n";
    for (std::size_t k = 0; k < strategies.size(); ++k) {
      csv << csv_escape(o.log) << ',' << strategies[k].name() << ',';
      if (agg[k].have_first) {
        csv << run_csv(agg[k].first, agg[k].run_s, run_csv_columns()) << ",\n";
      } else {
        csv << std::string(run_csv_columns().size(), ',') << csv_escape(agg[k].error) << '\n';
      }
    }
    nlohmann::json js;
    js["log"] = o.log;
    js["labelled"] = labelled;
    js["scans"] = scans;
    js["scans_with_truth"] = with_truth;
    js["noise"] = {{"from", noise_from},
                   {"sigma_range_m", noise.sigma_range_m},
                   {"sigma_bearing_rad", noise.sigma_bearing_rad},
                   {"sigma_v_mps", noise.sigma_v_mps},
                   {"sigma_w_radps", noise.sigma_w_radps}};
    js["wall_s"] = wall_s;
    js["strategies"] = rows_json(rows);
    if (o.group_radius_m > 0) js["group_level"] = rows_json(group_rows);
    if (!log.gps.empty() && !o.runner) {
      js["gps"] = {{"fixes", gps[0].fixes},
                   {"rejected_after_gap", gps[0].after_gap},
                   {"rejected_jumps", gps[0].jumps},
                   {"max_gap_s", gps_opt.max_gap_s},
                   {"max_jump_m", gps_opt.max_jump_m},
                   {"antenna", {gps_opt.antenna_x_m, gps_opt.antenna_y_m}},
                   {"strategies", gps_rows}};
    }
    std::ofstream(o.out_dir + "/replay.json") << js.dump(2) << '\n';
    if (!csv) throw std::runtime_error("cannot write " + o.out_dir + "/replay.csv");
  }
  if (o.svg) {
    svg::Figure path;
    path.title = "Path and map, " + fs::path(o.log).filename().string();
    path.cols = std::min<int>(3, static_cast<int>(strategies.size()));
    for (std::size_t k = 0; k < strategies.size(); ++k) {
      if (!agg[k].have_first) continue;
      if (log.gps.empty() || o.runner) {
        path.panels.push_back(path_map_panel(strategies[k].name(), agg[k].first, positions));
      } else {
        char t[96];
        std::snprintf(t, sizeof t, "%s: GPS RMSE %.2f m, %d landmarks", strategies[k].name().c_str(), gps[k].rmse_m,
                      agg[k].first.landmarks);
        path.panels.push_back(gps_panel(t, agg[k].first, log.gps, gps_opt));
      }
    }
    svg::write(path, o.out_dir + "/replay_path.svg");
  }
  std::printf("\n%zu replays in %.1f s; per-strategy rows: %s/replay.csv, summary: %s/replay.json%s\n",
              strategies.size(), wall_s, o.out_dir.c_str(), o.out_dir.c_str(),
              o.svg ? (", figure: " + o.out_dir + "/replay_path.svg").c_str() : "");
  if (failures > 0) std::fprintf(stderr, "%d replays failed (see the tables)\n", failures);
  return failures > 0 ? 1 : 0;
}

// A MRCLAM robot as a log (docs/replay.md): with its model (what MrclamSource feeds the filter,
// as `geojcbb_eval mrclam --datasets D --robots R` builds it) or raw.
struct ConvertOptions {
  std::string data_dir, out;
  int dataset = 6, robot = 1;
  double seconds = 0;  ///< > 0: only the first seconds
  bool raw = false;
  MrclamOptions model;  ///< the model switches, as for `mrclam`
};

int run_convert(const ConvertOptions& c) {
  const std::string root = c.data_dir.empty() ? mrclam::default_data_dir() : c.data_dir;
  const mrclam::Dataset ds = mrclam::load_dataset(mrclam::dataset_dir(c.dataset, root));
  const mrclam::RobotLog full = mrclam::load_robot(ds, c.robot);
  const mrclam::RobotLog log = c.seconds > 0 ? replay::truncate(full, c.seconds) : full;
  replay::EventLog out;
  std::string what;
  if (c.raw) {
    out = replay::mrclam_raw_log(ds, log);
    what = "raw: commands and measurements as logged, no noise";
  } else {
    const MrclamOptions& m = c.model;
    MrclamNoise noise = MrclamNoise::from_data(ds, {full}, m.noise_inflation);
    if (m.sigma_range_m > 0) noise.sigma_range_m = m.sigma_range_m;
    if (m.sigma_bearing_rad > 0) noise.sigma_bearing_rad = m.sigma_bearing_rad;
    if (m.sigma_v_mps > 0) noise.sigma_v_mps = m.sigma_v_mps;
    if (m.sigma_w_radps > 0) noise.sigma_w_radps = m.sigma_w_radps;
    mrclam::RobotCalibration cal;
    if (m.camera || m.drive) {
      if (m.calibration == "same") {
        cal = mrclam::calibrate_robot(ds, full, m.calibration_options);
      } else {
        const mrclam::Dataset cds = mrclam::load_dataset(mrclam::dataset_dir(c.dataset == 6 ? 7 : 6, root));
        cal = mrclam::calibrate_robot(cds, mrclam::load_robot(cds, c.robot), m.calibration_options);
      }
    }
    out = replay::mrclam_to_log(ds, log, mrclam_model(noise, cal, m.camera, m.drive, m.model_inflation),
                                m.drop_other_robots);
    what = std::string("the replay's model: camera ") + (m.camera ? "calibrated" : "constant R") + ", drive " +
           (m.drive ? "calibrated (latency, scale, process noise)" : "commands with constant noise") +
           ", calibration " + m.calibration + (m.drop_other_robots ? ", other robots dropped" : "");
  }
  if (fs::path(c.out).has_parent_path()) fs::create_directories(fs::path(c.out).parent_path());
  std::ofstream f(c.out);
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  replay::write_event_log(out, f,
                          "MRCLAM_Dataset" + std::to_string(c.dataset) + " robot " + std::to_string(c.robot) +
                              (c.seconds > 0 ? ", first " + std::to_string(c.seconds) + " s" : std::string()) + "\n" +
                              what);
  f.close();
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  std::printf("%s: %zu odom, %zu meas, %zu empty scans, %zu truth, %zu landmark lines (%s)\n", c.out.c_str(),
              out.odometry.size(), out.measurements.size(), out.empty_scans.size(), out.truth.size(),
              out.landmarks.size(), what.c_str());
  return 0;
}

// Victoria Park as a log (docs/victoria_park.md): the rear axle's increments, the laser's mount,
// the detections kept, GPS.
struct VictoriaOptions {
  std::string data_dir, out;
  victoria_park::ConvertOptions model;
};

int run_convert_victoria(const VictoriaOptions& c) {
  const std::string dir = c.data_dir.empty() ? victoria_park::default_data_dir() : c.data_dir;
  const victoria_park::Data data = victoria_park::read(dir);
  const replay::EventLog out = victoria_park::to_log(data, c.model);
  if (fs::path(c.out).has_parent_path()) fs::create_directories(fs::path(c.out).parent_path());
  std::ofstream f(c.out);
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  const victoria_park::ConvertOptions& m = c.model;
  char what[512];
  std::snprintf(what, sizeof what,
                "Victoria Park (ACFR; Guivant and Nebot 2001) from %s\n"
                "reference point: the rear axle's centre; odometry noise per 40 Hz sample: speed %.3g m/s, steering "
                "%.3g rad\ndetections kept: %.3g to %.3g m, |bearing| <= %.3g rad; R = diag(%.3g m, %.3g rad)^2",
                dir.c_str(), m.sigma_speed_mps, m.sigma_steer_rad, m.min_range_m, m.max_range_m, m.max_bearing_rad,
                m.sigma_range_m, m.sigma_bearing_rad);
  replay::write_event_log(out, f, what);
  f.close();
  if (!f) throw std::runtime_error(c.out + ": cannot write");
  std::printf("%s: %zu odom_delta, %zu meas, %zu empty scans, %zu gps lines\n", c.out.c_str(), out.increments.size(),
              out.measurements.size(), out.empty_scans.size(), out.gps.size());
  return 0;
}

// Runs `run` in process (no --port/--device), or with every run streamed to the device: prints the
// device and where its capacity differs from the in-process filter's, and at the end shuts down a
// device it started. Returns run's exit code (1 when a started device did not exit cleanly).
template <class Run>
int with_device(const LinkCli& lc, bool oracle, bool known_map, Run&& run) {
  if (lc.port.empty() && lc.device.empty()) return run(RunInputsFn{}, std::string{});
  if (!lc.port.empty() && !lc.device.empty()) throw std::runtime_error("give --port or --device, not both");
  if (oracle) throw std::runtime_error("the TRUTH row (--truth) runs in process only: drop it with --port/--device");
  if (known_map) {  // link_config refuses it too, per run; here before a device is started
    throw std::runtime_error(
        "known_map (--known-map): CONFIG carries no landmarks, so a device would map instead of localise; run it in "
        "process");
  }
  DeviceLink dl(lc, !lc.device.empty());
  const std::string info = dl.describe();
  std::printf("%s; %d scan(s) in flight, reply timeout %d ms\n", info.c_str(), lc.window, lc.timeout_ms);
  const proto::Capabilities& caps = dl.session().capabilities();
  const int obs = std::min<int>(caps.max_observations, static_cast<int>(kLinkMaxObs));
  if (obs < kEvalMaxObservations) {
    std::printf(
        "  the device takes at most %d observations per scan (in process: %d): each scan's nearest %d are "
        "sent, the rest dropped and not scored\n",
        obs, kEvalMaxObservations, obs);
  }
  if (caps.max_landmarks < kEvalMaxLandmarks) {
    std::printf(
        "  the device's map holds %u landmarks (in process: %d): past that, new landmarks are not added "
        "(noted per run)\n",
        caps.max_landmarks, kEvalMaxLandmarks);
  }
  std::mutex mu;
  std::set<std::string> said;
  StreamOptions st;
  st.window = lc.window;
  st.note = [&](const std::string& n) {
    std::lock_guard<std::mutex> lock(mu);
    if (said.insert(n).second) std::printf("  %s\n", n.c_str());
  };
  const RunInputsFn runner = [&](RunSource& src, const RunOptions& ro) {
    return stream_run(dl.session(), src, ro, st);
  };
  int rc = run(runner, info);
  if (dl.session().reconnections() > 0) {
    std::printf("link: %d reconnection(s), %d run restart(s)\n", dl.session().reconnections(), dl.session().restarts());
  }
  if (dl.started_device()) {
    const int code = dl.shut_down();
    if (code != 0) {
      std::fprintf(stderr, "geojcbb_eval: the device did not exit cleanly after SHUTDOWN (exit code %d)\n", code);
      if (rc == 0) rc = 1;
    }
  }
  return rc;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "geojcbb evaluation: EKF-SLAM with every association strategy, scored "
      "against ground truth, "
      "on simulated scenarios (sim), the UTIAS MRCLAM real data (mrclam) or your own log (replay; convert-mrclam "
      "writes a MRCLAM robot as such a log)."};
  app.require_subcommand(1);
  SimOptions so;
  auto* sim = app.add_subcommand("sim",
                                 "Monte Carlo runs over simulated scenarios: "
                                 "Tables 1 and 2, pose error, NEES, figures");
  sim->add_option("--scenario", so.scenarios,
                  "scenario JSON file(s) (default: env1 and env2 from "
                  "host_tools/scenarios)");
  sim->add_option("--runs", so.runs,
                  "Monte Carlo runs per scenario and strategy (seeds seed .. "
                  "seed+runs-1)")
      ->default_val(20)
      ->check(CLI::Range(1, 100000));
  sim->add_option("--seed", so.seed, "first seed")->default_val(1);
  sim->add_option("--strategies", so.strategies,
                  std::string("strategies to run, comma separated (") + kPresetsHelp + "; default the seven presets)")
      ->delimiter(',');
  sim->add_option("--jobs", so.jobs,
                  "worker threads (default: the number of cores; 1 gives the "
                  "cleanest timing)")
      ->check(CLI::Range(0, 256));
  sim->add_option("--out-dir", so.out_dir, "directory for runs.csv, summary.json and the SVG figures")
      ->default_val(so.out_dir);
  sim->add_flag("!--no-svg", so.svg, "do not write the figures");
  sim->add_flag("!--no-progress", so.progress, "no progress bar on stderr");
  sim->add_flag("--truth", so.oracle,
                "add a row TRUTH: association by ground truth (gated at chi2(0.999, 2)), the filter's own accuracy "
                "with perfect association");
  sim->add_option("--max-steps", so.run.max_steps,
                  "stop each run after this many control intervals (0: the whole path)")
      ->default_val(0);
  add_run_options(*sim, so.run);
  LinkCli sim_link;
  add_link_options(*sim, sim_link,
                   "stream every run to the device on this serial port or pty instead of running it in process",
                   "start this device program with --pty (e.g. geojcbb_device) and stream every run to it");

  MrclamOptions mo;
  std::string mo_out = "build/results/mrclam";
  std::vector<std::string> mo_strategies;
  bool mo_progress = true;
  bool mo_oracle = false;
  auto* mr = app.add_subcommand("mrclam",
                                "replay the UTIAS MRCLAM datasets: every strategy on every "
                                "robot, scored with the barcodes' ground truth");
  mr->add_option("--data", mo.data_dir,
                 "folder holding MRCLAM_Dataset6 and MRCLAM_Dataset7 (default: "
                 "$GEOJCBB_MRCLAM_DIR, else ../shared/data/mrclam beside the repository)");
  mr->add_option("--datasets", mo.datasets, "dataset numbers")->delimiter(',')->default_str("6,7");
  mr->add_option("--robots", mo.robots, "robot numbers")->delimiter(',')->default_str("1,2,3,4,5");
  mr->add_option("--strategies", mo_strategies,
                 std::string("strategies, comma separated (") + kPresetsHelp + "; default the seven presets)")
      ->delimiter(',');
  mr->add_option("--out-dir", mo_out, "directory for mrclam.csv and mrclam.json")->default_val(mo_out);
  mr->add_flag("!--no-progress", mo_progress, "no progress bar on stderr");
  mr->add_option("--sigma-range", mo.sigma_range_m,
                 "range noise for R [m] (default: from the data, see docs/mrclam.md)");
  mr->add_option("--sigma-bearing", mo.sigma_bearing_rad, "bearing noise for R [rad] (default: from the data)");
  mr->add_option("--sigma-v", mo.sigma_v_mps,
                 "odometry v noise, std of a 1-second mean [m/s] (default: "
                 "from the data)");
  mr->add_option("--sigma-w", mo.sigma_w_radps,
                 "odometry w noise, std of a 1-second mean [rad/s] (default: "
                 "from the data)");
  mr->add_option("--noise-inflation", mo.noise_inflation, "factor on the data's robust noise spreads")
      ->default_val(mo.noise_inflation)
      ->check(CLI::Range(0.1, 100.0));
  mr->add_flag(
      "--truth", mo_oracle,
      "add a row TRUTH: association by ground truth (gated), the filter's own accuracy with perfect association");
  mr->add_flag("--known-map", mo.known_map,
               "localisation only: the surveyed landmark positions are the map from the start (std 1 cm), nothing "
               "is added or removed; separates association from mapping");
  mr->add_flag("--drop-other-robots", mo.drop_other_robots,
               "remove measurements of the other robots instead of feeding "
               "them as clutter");
  mr->add_option("--jobs", mo.jobs, "worker threads (default: the number of cores)")->check(CLI::Range(0, 256));
  mr->add_option("--trace", mo.trace_dir,
                 "write one CSV per replay into this folder: per scan the pose error, variances, NEES, pairings, NIS");
  bool mo_legacy = false;
  mr->add_flag("--legacy-model", mo_legacy,
               "the constant noise model of before (no calibration): R and the odometry noise from --sigma-* or "
               "the data's robust spreads x --noise-inflation; the same as --no-camera --no-drive");
  mr->add_flag("!--no-camera", mo.camera,
               "do not use the calibrated camera (range and bearing bias, range-proportional R)");
  mr->add_flag("!--no-drive", mo.drive,
               "do not use the calibrated drive (command latency and scale, motion-dependent process noise)");
  mr->add_option("--calibration", mo.calibration,
                 "fit each robot's camera and drive on: cross (the same robot in the other dataset) or same")
      ->default_val(mo.calibration)
      ->check(CLI::IsMember({"cross", "same"}));
  mr->add_option("--model-inflation", mo.model_inflation, "factor on the calibrated standard deviations")
      ->default_val(mo.model_inflation)
      ->check(CLI::Range(0.1, 100.0));
  mr->add_option("--fit-window", mo.calibration_options.fit_window_s,
                 "window over which the drive's scale and noise are fitted [s]")
      ->default_val(mo.calibration_options.fit_window_s)
      ->check(CLI::Range(0.1, 30.0));
  add_run_options(*mr, mo.run);
  LinkCli mr_link;
  add_link_options(*mr, mr_link,
                   "stream every replay to the device on this serial port or pty instead of running it in process",
                   "start this device program with --pty (e.g. geojcbb_device) and stream every replay to it");

  ReplayOptions ro;
  auto* rp = app.add_subcommand("replay",
                                "replay your own log (docs/replay.md): every strategy, scored when the measurements "
                                "are labelled; tables, replay.csv, replay.json and the path/map figure");
  rp->add_option("--log", ro.log, "the log file (CSV, docs/replay.md)")->required();
  rp->add_option("--strategies", ro.strategies,
                 std::string("strategies, comma separated (") + kPresetsHelp + "; default the seven presets)")
      ->delimiter(',');
  rp->add_flag("--truth", ro.oracle, "add a row TRUTH: association by the labels (needs labelled measurements)");
  rp->add_option("--out-dir", ro.out_dir, "directory for replay.csv, replay.json and replay_path.svg")
      ->default_val(ro.out_dir);
  rp->add_option("--sigma-range", ro.noise.sigma_range_m, "range std for R where a line gives none [m]");
  rp->add_option("--sigma-bearing", ro.noise.sigma_bearing_rad, "bearing std for R where a line gives none [rad]");
  rp->add_option("--sigma-v", ro.noise.sigma_v_mps,
                 "odometry v noise where a line gives none: std of a 1-second mean [m/s]");
  rp->add_option("--sigma-w", ro.noise.sigma_w_radps,
                 "odometry w noise where a line gives none: std of a 1-second mean [rad/s]");
  rp->add_flag("--noise-from-data", ro.noise_from_data,
               "estimate the noise from the labelled measurements, truth and landmark lines (robust spreads; a "
               "--sigma-* given overrides its part)");
  rp->add_option("--noise-inflation", ro.noise_inflation, "factor on the data's robust spreads")
      ->default_val(ro.noise_inflation)
      ->check(CLI::Range(0.1, 100.0));
  rp->add_option("--group-radius", ro.group_radius_m,
                 "landmarks within this distance [m] form a group, for a group-level score (0: none)")
      ->default_val(0.0)
      ->check(CLI::Range(0.0, 1000.0));
  rp->add_flag("--known-map", ro.known_map, "localisation only: the landmark lines are the map (std 1 cm, fixed)");
  bool rp_mrclam_rules = false;
  rp->add_flag("--mrclam-rules", rp_mrclam_rules,
               "the MRCLAM replay's landmark rules (miss probability 1e-5, static gate 0.95, new if taken, occlusion "
               "0.03 rad) where not given");
  rp->add_option("--jobs", ro.jobs, "worker threads (default: the number of cores)")->check(CLI::Range(0, 256));
  rp->add_flag("!--no-svg", ro.svg, "do not write the figure");
  rp->add_flag("!--no-progress", ro.progress, "no progress bar on stderr");
  add_run_options(*rp, ro.run);
  LinkCli rp_link;
  add_link_options(*rp, rp_link,
                   "stream every replay to the device on this serial port or pty instead of running it in process "
                   "(settings the device cannot run are refused)",
                   "start this device program with --pty (e.g. geojcbb_device) and stream every replay to it");

  ConvertOptions co;
  auto* cv = app.add_subcommand("convert-mrclam",
                                "write a MRCLAM robot as a log of docs/replay.md's format: with the replay's model "
                                "(replays to the same results as `mrclam --datasets D --robots R`) or --raw");
  cv->add_option("--data", co.data_dir, "folder holding MRCLAM_Dataset6 and 7 (default as for mrclam)");
  cv->add_option("--dataset", co.dataset, "dataset number")->default_val(6)->check(CLI::IsMember({6, 7}));
  cv->add_option("--robot", co.robot, "robot number")->default_val(1)->check(CLI::Range(1, 5));
  cv->add_option("--out", co.out, "the log file to write")->required();
  cv->add_option("--seconds", co.seconds, "only the first seconds of the robot's log (0: all)")
      ->default_val(0.0)
      ->check(CLI::Range(0.0, 1e6));
  cv->add_flag("--raw", co.raw,
               "the data as logged (commands, measurements, labels, truth, landmarks), no model or noise: replay "
               "it with --noise-from-data or --sigma-*");
  cv->add_option("--noise-inflation", co.model.noise_inflation, "as for mrclam")->default_val(co.model.noise_inflation);
  cv->add_flag("!--no-camera", co.model.camera, "as for mrclam");
  cv->add_flag("!--no-drive", co.model.drive, "as for mrclam");
  cv->add_option("--calibration", co.model.calibration, "as for mrclam: cross or same")
      ->default_val(co.model.calibration)
      ->check(CLI::IsMember({"cross", "same"}));
  cv->add_option("--model-inflation", co.model.model_inflation, "as for mrclam")->default_val(co.model.model_inflation);
  cv->add_flag("--drop-other-robots", co.model.drop_other_robots, "as for mrclam");

  VictoriaOptions vo;
  auto* vp =
      app.add_subcommand("convert-victoria-park",
                         "write ACFR's Victoria Park as a log of docs/replay.md's format (docs/victoria_park.md): "
                         "pose increments of the rear axle, the laser's mount, detections, GPS; replay it with "
                         "`replay --log`");
  {
    victoria_park::ConvertOptions& m = vo.model;
    vp->add_option("--data", vo.data_dir,
                   "the folder of the four CSV files (default $GEOJCBB_VICTORIA_PARK_DIR, else "
                   "../shared/data/victoria_park beside the repository)");
    vp->add_option("--out", vo.out, "the log file to write")->required();
    vp->add_option("--sigma-speed", m.sigma_speed_mps, "speed noise per 40 Hz odometry sample [m/s]")
        ->default_val(m.sigma_speed_mps)
        ->check(CLI::Range(0.0, 100.0));
    vp->add_option("--sigma-steer", m.sigma_steer_rad, "steering noise per sample [rad]")
        ->default_val(m.sigma_steer_rad)
        ->check(CLI::Range(0.0, 1.0));
    vp->add_option("--sigma-range", m.sigma_range_m, "range noise of a detection [m]")
        ->default_val(m.sigma_range_m)
        ->check(CLI::Range(1e-6, 100.0));
    vp->add_option("--sigma-bearing", m.sigma_bearing_rad, "bearing noise of a detection [rad]")
        ->default_val(m.sigma_bearing_rad)
        ->check(CLI::Range(1e-6, 1.0));
    vp->add_option("--min-range", m.min_range_m, "detections nearer are dropped [m]")
        ->default_val(m.min_range_m)
        ->check(CLI::Range(0.0, 100.0));
    vp->add_option("--max-range", m.max_range_m, "detections farther are dropped [m]")
        ->default_val(m.max_range_m)
        ->check(CLI::Range(1.0, 100.0));
    vp->add_option("--max-bearing", m.max_bearing_rad, "detections wider are dropped [rad]")
        ->default_val(m.max_bearing_rad)
        ->check(CLI::Range(0.01, 1.5708));
    vp->add_option("--start-theta", m.start_theta_rad, "the start heading [rad]")->default_val(m.start_theta_rad);
    vp->add_option("--seconds", m.seconds, "only the first seconds of the run (0: all)")
        ->default_val(m.seconds)
        ->check(CLI::Range(0.0, 1e6));
  }
  rp->add_option("--gps-max-gap", ro.gps.max_gap_s, "a GPS fix after a longer dropout is not scored [s]")
      ->default_val(ro.gps.max_gap_s)
      ->check(CLI::Range(0.0, 1e6));
  rp->add_option("--gps-max-jump", ro.gps.max_jump_m, "a GPS fix farther from the previous one is not scored [m]")
      ->default_val(ro.gps.max_jump_m)
      ->check(CLI::Range(0.0, 1e6));

  CLI11_PARSE(app, argc, argv);
  try {
    if (vp->parsed()) return run_convert_victoria(vo);
    if (rp->parsed()) {
      if (rp_mrclam_rules) {
        const RunOptions m = mrclam_run_defaults();
        if (rp->count("--miss-probability") == 0) ro.run.step.miss_probability = m.step.miss_probability;
        if (rp->count("--static-gate-level") == 0) ro.run.step.static_gate_level = m.step.static_gate_level;
        if (rp->count("--new-if-taken") == 0) ro.run.step.new_if_candidates_taken = m.step.new_if_candidates_taken;
        if (rp->count("--occlusion") == 0) ro.run.step.occlusion_rad = m.step.occlusion_rad;
      }
      ro.progress = ro.progress && isatty(STDERR_FILENO);
      return with_device(rp_link, ro.oracle, ro.known_map, [&](const RunInputsFn& runner, const std::string&) {
        ro.runner = runner;
        return run_replay(ro);
      });
    }
    if (cv->parsed()) return run_convert(co);
    if (sim->parsed()) {
      if (so.scenarios.empty()) {
        so.scenarios = {std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json",
                        std::string(GEOJCBB_SCENARIO_DIR) + "/env2.json"};
      }
      so.progress = so.progress && isatty(STDERR_FILENO);
      return with_device(sim_link, so.oracle, false, [&](const RunInputsFn& runner, const std::string& info) {
        so.runner = runner;
        so.device_info = info;
        return run_sim(so);
      });
    }
    mo.strategies = select_methods(mo_strategies, true, mo_oracle);
    if (mo_legacy) mo.camera = mo.drive = false;
    return with_device(mr_link, mo_oracle, mo.known_map, [&](const RunInputsFn& runner, const std::string&) {
      mo.runner = runner;
      if (runner) mo.jobs = 1;  // one device, one replay at a time
      return run_mrclam_report(mo, mo_out, mo_progress && isatty(STDERR_FILENO));
    });
  } catch (const std::exception& e) {
    std::fprintf(stderr, "geojcbb_eval: %s\n", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) { return geojcbb::host::guarded_main(run, argc, argv); }
