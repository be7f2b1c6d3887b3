// host_tools/suites: the simulation's runs and their report (sim_suite.hpp).
#include "geojcbb_host/sim_suite.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "geojcbb_host/batch.hpp"
#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/report.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "geojcbb_host/svg_plot.hpp"
#include "geojcbb_host/worlds.hpp"
#include "geojcbb_host/worlds_table.hpp"

namespace geojcbb::host {
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
                                              "anees",
                                              "ambiguous_scans",
                                              "fp_clutter",
                                              "fp_mover",
                                              "movers_in_map",
                                              "movers_caught"};

// The batch reference per run (--batch): the mean position error of the run's trace at its scans
// (the filter's, or with local maps on the solver the joined map's smoothed one) and of every pose
// and landmark solved at once (batch.hpp) with the run's own pairings (with local maps: the ids the
// local maps gave, not the joins' fusions, so a loop closed between maps is not closed there) and
// with the labels (the true association), from the run's trace.
struct BatchRow {
  bool have = false;
  double filter_m = 0, batch_m = 0, labels_m = 0;  ///< labels_m: the batch with the labels' pairings
};

// The batch table: per scenario (a world's family) and strategy, the medians over its runs.
void print_batch_table(const std::vector<Scenario>& scenarios, const std::vector<std::string>& family,
                       const std::vector<Method>& strategies, const std::vector<std::array<int, 3>>& job_of,
                       const std::vector<BatchRow>& rows, const std::string& out_dir) {
  std::map<std::pair<std::string, int>, std::vector<std::size_t>> groups;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    if (!rows[j].have) continue;
    const auto sc = static_cast<std::size_t>(job_of[j][0]);
    groups[{family[sc].empty() ? scenarios[sc].name : family[sc], job_of[j][1]}].push_back(j);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? NAN : v[v.size() / 2];
  };
  std::printf(
      "\n== the batch reference (every pose and landmark solved at once with each run's own pairings; "
      "docs/mapping.md)\n| scenario | strategy | runs | trace's mean position error, median [m] | batch's, median "
      "[m] | labels' batch, median [m] | trace / labels' batch (median of the runs' ratios) |\n| --- | --- | --- | --- "
      "| --- | --- | --- |\n");
  std::ofstream csv(out_dir + "/batch.csv");
  csv << "scenario,strategy,run,trace_position_error_m,batch_position_error_m,labels_batch_position_error_m\n";
  for (const auto& [key, js] : groups) {
    std::vector<double> f, b, l, ratio;
    for (std::size_t j : js) {
      f.push_back(rows[j].filter_m);
      b.push_back(rows[j].batch_m);
      l.push_back(rows[j].labels_m);
      ratio.push_back(rows[j].filter_m / rows[j].labels_m);
      csv << csv_escape(key.first) << ',' << strategies[static_cast<std::size_t>(key.second)].name() << ','
          << job_of[j][2] << ',' << rows[j].filter_m << ',' << rows[j].batch_m << ',' << rows[j].labels_m << '\n';
    }
    std::printf("| %s | %s | %zu | %.2f | %.2f | %.2f | %.2f |\n", key.first.c_str(),
                strategies[static_cast<std::size_t>(key.second)].name().c_str(), js.size(), median(f), median(b),
                median(l), median(ratio));
  }
  if (!csv) throw std::runtime_error("cannot write " + out_dir + "/batch.csv");
}

// The first run of each (scenario, strategy): what the worlds' table compares.
struct FirstRun {
  bool have = false;
  double err = 0, f1 = 0, anees = 0;
};

double mean_nees(const RunResult& r) {
  double nees = 0;
  for (const StepRecord& k : r.steps) nees += k.pose_nees;
  return r.steps.empty() ? 0.0 : nees / static_cast<double>(r.steps.size());
}

// The non-inferiority table over the generated worlds, when both presets ran (worlds_table.hpp).
void report_worlds(const SimOptions& o, const std::vector<Method>& strategies,
                   const std::vector<std::vector<FirstRun>>& first) {
  int base = -1, robust = -1, truth = -1;
  for (std::size_t st = 0; st < strategies.size(); ++st) {
    const std::string n = strategies[st].name();
    if (n == "PCJCBB") base = static_cast<int>(st);
    if (n == "PCJCBB+RL") robust = static_cast<int>(st);
    if (n == "TRUTH") truth = static_cast<int>(st);
  }
  if (base < 0 || robust < 0) return;
  std::vector<WorldOutcome> worlds;
  std::ofstream csv(o.flags.out_dir + "/worlds.csv");
  csv << "family,file,err_pcjcbb_m,err_robust_m,err_truth_m,f1_pcjcbb,f1_robust,anees_pcjcbb,anees_robust,worse,"
         "recovered\n";
  for (std::size_t sc = 0; sc < o.scenarios.size(); ++sc) {
    if (o.world_family[sc].empty()) continue;
    const FirstRun& b = first[sc][static_cast<std::size_t>(base)];
    const FirstRun& r = first[sc][static_cast<std::size_t>(robust)];
    if (!b.have || !r.have) continue;
    WorldOutcome w{o.world_family[sc], o.scenarios[sc], b.err, r.err, b.f1, r.f1, b.anees, r.anees, -1};
    if (truth >= 0 && first[sc][static_cast<std::size_t>(truth)].have) {
      w.err_truth = first[sc][static_cast<std::size_t>(truth)].err;
    }
    csv << w.family << ',' << csv_escape(w.file) << ',' << w.err_base << ',' << w.err_robust << ',' << w.err_truth
        << ',' << w.f1_base << ',' << w.f1_robust << ',' << w.anees_base << ',' << w.anees_robust << ','
        << robust_worse(w) << ',' << robust_recovered(w) << '\n';
    worlds.push_back(std::move(w));
  }
  if (worlds.empty()) return;
  std::printf("\n== generated worlds (first seed %llu, run seed %llu): %s/worlds.csv\n%s",
              static_cast<unsigned long long>(o.world_seed), static_cast<unsigned long long>(o.seed),
              o.flags.out_dir.c_str(), non_inferiority_markdown(worlds).c_str());
}

// Every strategy on the generated worlds, per family (worlds_table.hpp): F1, pose error and the
// false pairs of clutter and movers, with the movers left in the map.
void report_world_strategies(const SimOptions& o, const std::vector<Method>& strategies,
                             const std::vector<std::vector<Cell>>& cells) {
  std::vector<WorldStrategyOutcome> ws;
  for (std::size_t sc = 0; sc < o.scenarios.size(); ++sc) {
    if (o.world_family[sc].empty()) continue;
    for (std::size_t st = 0; st < strategies.size(); ++st) {
      const Cell& c = cells[sc][st];
      if (c.runs == 0) continue;
      WorldStrategyOutcome w;
      w.family = o.world_family[sc];
      w.strategy = strategies[st].name();
      w.err = std::hypot(c.abs_x / c.runs, c.abs_y / c.runs);
      w.f1 = c.score.f1();
      w.tp = c.score.tp;
      w.fp = c.score.fp;
      w.fn = c.score.fn;
      w.fp_clutter = c.fp_clutter;
      w.fp_mover = c.fp_mover;
      w.movers_in_map = c.movers_in_map;
      ws.push_back(std::move(w));
    }
  }
  if (ws.empty()) return;
  std::printf("\n== generated worlds per strategy (first seed %llu, run seed %llu)\n%s",
              static_cast<unsigned long long>(o.world_seed), static_cast<unsigned long long>(o.seed),
              strategies_markdown(ws).c_str());
}

// One simulation's runs and what they gave: the jobs (scenario, strategy, run; seed-major), per
// (scenario, strategy) the sums and the first run, per job its runs.csv row and batch reference.
struct SimRuns {
  std::vector<Method> strategies;
  std::vector<Scenario> scenarios;
  struct Job {
    int sc, st, run;
  };
  std::vector<Job> jobs;
  std::vector<std::vector<Cell>> cells;
  std::vector<std::string> csv_rows;
  std::vector<std::vector<FirstRun>> first;
  std::vector<BatchRow> batch_rows;
  std::vector<std::array<int, 3>> job_of;
  int threads = 1;
  double wall_s = 0;
};

// The strategies, the scenarios loaded, the jobs and the threads; the output folder made.
SimRuns plan_runs(const SimOptions& o) {
  SimRuns s;
  s.strategies = select_methods(o.flags.strategies, true, o.flags.oracle);
  for (const std::string& p : o.scenarios) s.scenarios.push_back(load_scenario(p));
  fs::create_directories(o.flags.out_dir);
  const int most_runs = std::max(o.runs, o.worlds > 0 ? o.world_runs : 0);
  for (int run = 0; run < most_runs; ++run)  // seed-major: a partial result is still balanced
    for (std::size_t sc = 0; sc < s.scenarios.size(); ++sc) {
      if (run >= (o.world_family[sc].empty() ? o.runs : o.world_runs)) continue;
      for (std::size_t st = 0; st < s.strategies.size(); ++st) s.jobs.push_back({int(sc), int(st), run});
    }
  s.cells.assign(s.scenarios.size(), std::vector<Cell>(s.strategies.size()));
  s.csv_rows.resize(s.jobs.size());
  s.first.assign(s.scenarios.size(), std::vector<FirstRun>(s.strategies.size()));
  s.threads = o.runner           ? 1  // one device, one run at a time
              : o.flags.jobs > 0 ? o.flags.jobs
                                 : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (o.batch && o.runner) throw std::runtime_error("--batch: in process only (a device does not report its pairings)");
  s.batch_rows.resize(s.jobs.size());
  s.job_of.resize(s.jobs.size());
  for (std::size_t j = 0; j < s.jobs.size(); ++j) s.job_of[j] = {s.jobs[j].sc, s.jobs[j].st, s.jobs[j].run};
  return s;
}

// Job j: its run (in process or through the runner), with the batch reference when asked, added
// to its cell (under mu) with its runs.csv row; the first run of a cell is kept for the figures.
void run_job(const SimOptions& o, SimRuns& s, std::size_t j, std::mutex& mu) {
  const SimRuns::Job& jb = s.jobs[j];
  RunOptions ro = o.run;
  s.strategies[jb.st].apply(ro);
  ScanRecorder rec;
  if (o.batch) {
    ro.record_trace = true;
    ro.on_scan = [&rec](const ScanOutcome& sc) { rec.on_scan(sc); };
  }
  const std::uint64_t seed = o.seed + static_cast<std::uint64_t>(jb.run);
  const auto a = std::chrono::steady_clock::now();
  RunResult r;
  std::string err;
  try {
    SimSource src(s.scenarios[jb.sc], seed, ro.max_steps);
    r = o.runner ? o.runner(src, ro) : run_inputs(src, ro);
    if (o.batch) {
      const std::array<double, 3> e = batch_errors(src, rec, r, ro);
      s.batch_rows[j] = {true, e[0], e[1], e[2]};
    }
  } catch (const std::exception& e) {
    err = e.what();
  }
  const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
  std::lock_guard<std::mutex> lock(mu);
  Cell& c = s.cells[jb.sc][jb.st];
  if (!err.empty()) {
    c.fail(err);
    return;
  }
  const double kidnap = s.scenarios[jb.sc].kidnap_t_s;
  c.add(r, run_s, kidnap);
  s.csv_rows[j] = csv_escape(s.scenarios[jb.sc].name) + ',' + s.strategies[jb.st].name() + ',' + std::to_string(seed) +
                  ',' + run_csv(r, run_s, kSimCsvColumns, kidnap);
  if (jb.run == 0) {
    s.first[jb.sc][jb.st] = {true, std::hypot(r.mean_abs_x_m, r.mean_abs_y_m), r.score.f1(), mean_nees(r)};
    c.first = std::move(r);
    c.have_first = true;
  }
}

// The NEES's 95 % bounds for 3 x runs dof (have: chi2_inv gave both).
struct NeesBounds {
  bool have = false;
  double lo = 0, hi = 0;
};

// A scenario's figures: the first run's path and map per strategy, the mean absolute x and y error
// over time, the mean NEES over time with its bounds.
void write_scenario_figures(const SimOptions& o, const SimRuns& s, std::size_t sc, const NeesBounds& b) {
  const Scenario& sn = s.scenarios[sc];
  const std::string stem = o.flags.out_dir + "/" + fs::path(o.scenarios[sc]).stem().string();
  svg::Figure path;
  path.title = "Path fitting, " + sn.name + " (seed " + std::to_string(o.seed) + ")";
  path.cols = std::min<int>(3, static_cast<int>(s.strategies.size()));
  svg::Figure err;
  err.title = "Mean absolute pose error over " + std::to_string(o.runs) + " runs, " + sn.name;
  err.cols = 1;
  err.panel_w = 900;
  err.share_x = true;
  err.panels.resize(2);
  err.panels[0] = {"x error", "", "|x error| [m]", {}, false, {}, {}};
  err.panels[1] = {"y error", "time [s]", "|y error| [m]", {}, false, {}, {}};
  svg::Figure nees;
  nees.title = "Pose NEES, mean over " + std::to_string(o.runs) + " runs: " + sn.name;
  nees.panel_w = 900;
  nees.panels.resize(1);
  nees.panels[0] = {"", "time [s]", "NEES (3 dof)", {}, false, {}, {}};
  for (std::size_t st = 0; st < s.strategies.size(); ++st) {
    const Cell& c = s.cells[sc][st];
    if (!c.have_first) continue;
    std::vector<Eigen::Vector2d> truth_map(sn.landmarks.begin(), sn.landmarks.end());
    const svg::Panel p = path_map_panel(s.strategies[st].name(), c.first, truth_map);
    path.panels.push_back(p);
    const std::string name = s.strategies[st].name();
    svg::Series sx{name, c.t, {}, svg::Style::kLine, ""}, sy{name, c.t, {}, svg::Style::kLine, ""};
    svg::Series snees{name, c.t, {}, svg::Style::kLine, ""};
    for (std::size_t k = 0; k < c.t.size(); ++k) {
      sx.y.push_back(c.ex_sum[k] / c.runs);
      sy.y.push_back(c.ey_sum[k] / c.runs);
      snees.y.push_back(c.nees_sum[k] / c.runs);
    }
    err.panels[0].series.push_back(sx);
    err.panels[1].series.push_back(sy);
    nees.panels[0].series.push_back(snees);
  }
  if (b.have && !s.cells[sc][0].t.empty()) {
    const auto& t = s.cells[sc][0].t;
    nees.panels[0].series.push_back(
        {"95 % bounds", t, std::vector<double>(t.size(), b.lo / o.runs), svg::Style::kDashed, "#000000"});
    nees.panels[0].series.push_back(
        {"", t, std::vector<double>(t.size(), b.hi / o.runs), svg::Style::kDashed, "#000000"});
  }
  svg::write(path, stem + "_path.svg");
  svg::write(err, stem + "_error.svg");
  svg::write(nees, stem + "_nees.svg");
  std::printf("figures: %s_path.svg, %s_error.svg, %s_nees.svg\n", stem.c_str(), stem.c_str(), stem.c_str());
}

// Per scenario: its rows into summary.json and, for a --scenario file, its tables and figures on
// stdout and in out_dir; f1[strategy][scenario] filled. Returns the failed runs.
int report_scenarios(const SimOptions& o, const SimRuns& s, nlohmann::json& js, std::vector<std::vector<double>>& f1) {
  int failures = 0;
  NeesBounds b;
  b.have = chi2_inv(0.025, 3 * o.runs, b.lo) == Status::kOk && chi2_inv(0.975, 3 * o.runs, b.hi) == Status::kOk;
  f1.assign(s.strategies.size(), std::vector<double>(s.scenarios.size(), NAN));
  for (std::size_t sc = 0; sc < s.scenarios.size(); ++sc) {
    const Scenario& sn = s.scenarios[sc];
    std::vector<ReportRow> rows;
    for (std::size_t st = 0; st < s.strategies.size(); ++st) {
      const Cell& c = s.cells[sc][st];
      failures += c.failed;
      const ReportRow row = c.row(s.strategies[st].name(), true, !o.runner);
      f1[st][sc] = c.score.f1();
      rows.push_back(row);
    }
    const int scans = s.cells[sc][0].runs ? s.cells[sc][0].scans / s.cells[sc][0].runs : 0;
    const bool world = !o.world_family[sc].empty();  // a generated world: in summary.json and the worlds' table
    if (world) {
      js["scenarios"].push_back({{"name", sn.name}, {"file", o.scenarios[sc]}, {"strategies", rows_json(rows)}});
      continue;
    }
    std::printf("\n== %s: %d runs per strategy (seeds %llu..%llu), %d scans per run\n", sn.name.c_str(), o.runs,
                static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed + o.runs - 1), scans);
    print_tables(rows, stdout);
    print_submaps(s.strategies, s.cells[sc], stdout);
    js["scenarios"].push_back({{"name", sn.name}, {"file", o.scenarios[sc]}, {"strategies", rows_json(rows)}});
    if (o.flags.svg) write_scenario_figures(o, s, sc, b);
  }
  return failures;
}

// f1.svg: F1 per strategy, grouped by scenario.
void write_f1_chart(const SimOptions& o, const SimRuns& s, const std::vector<std::vector<double>>& f1) {
  svg::BarChart bars;
  bars.title = "F1 per strategy (" + std::to_string(o.runs) + " runs each)";
  bars.ylabel = "F1";
  for (const Method& st : s.strategies) bars.categories.push_back(st.name());
  for (const Scenario& sn : s.scenarios) bars.groups.push_back(sn.name.substr(0, sn.name.find(':')));
  bars.values.assign(s.scenarios.size(), std::vector<double>(s.strategies.size(), NAN));
  double fmin = 1.0;
  for (std::size_t st = 0; st < s.strategies.size(); ++st)
    for (std::size_t sc = 0; sc < s.scenarios.size(); ++sc) {
      bars.values[sc][st] = f1[st][sc];
      if (std::isfinite(f1[st][sc])) fmin = std::min(fmin, f1[st][sc]);
    }
  bars.y_range = svg::Range{std::floor(fmin * 50 - 1) / 50, 1.0};
  bars.value_decimals = 4;
  svg::write(bars, o.flags.out_dir + "/f1.svg");
  std::printf("figure: %s/f1.svg\n", o.flags.out_dir.c_str());
}

// runs.csv (one row per run that did not fail) and summary.json.
void write_runs_files(const SimOptions& o, const SimRuns& s, const nlohmann::json& js) {
  std::ofstream csv(o.flags.out_dir + "/runs.csv");
  csv << "scenario,strategy,seed";
  for (const std::string& col : kSimCsvColumns) csv << ',' << col;
  csv << '\n';
  for (const std::string& r : s.csv_rows)
    if (!r.empty()) csv << r << '\n';
  std::ofstream(o.flags.out_dir + "/summary.json") << js.dump(2) << '\n';
  if (!csv) throw std::runtime_error("cannot write " + o.flags.out_dir + "/runs.csv");
}

}  // namespace

int run_sim(const SimOptions& o) {
  SimRuns s = plan_runs(o);
  std::mutex mu;
  s.wall_s = run_parallel(s.jobs.size(), s.threads, o.flags.progress, [&](std::size_t j) { run_job(o, s, j, mu); });

  // Report.
  nlohmann::json js;
  js["runs_per_strategy"] = o.runs;
  js["first_seed"] = o.seed;
  js["threads"] = s.threads;
  js["wall_s"] = s.wall_s;
  if (!o.device_info.empty()) js["device"] = o.device_info;
  std::vector<std::vector<double>> f1;
  const int failures = report_scenarios(o, s, js, f1);
  if (o.flags.svg && o.worlds == 0) write_f1_chart(o, s, f1);  // with worlds, their table instead
  write_runs_files(o, s, js);
  if (o.worlds > 0) {
    report_world_strategies(o, s.strategies, s.cells);
    report_worlds(o, s.strategies, s.first);
  }
  if (o.batch) print_batch_table(s.scenarios, o.world_family, s.strategies, s.job_of, s.batch_rows, o.flags.out_dir);
  std::printf(
      "\n%zu runs in %.1f s on %d threads; per-run rows: %s/runs.csv, "
      "summary: %s/summary.json\n",
      s.jobs.size(), s.wall_s, s.threads, o.flags.out_dir.c_str(), o.flags.out_dir.c_str());
  if (failures > 0) std::fprintf(stderr, "%d runs failed (see the tables)\n", failures);
  return failures > 0 ? 1 : 0;
}

void add_generated_worlds(SimOptions& o) {
  o.world_family.assign(o.scenarios.size(), "");
  if (o.worlds <= 0) return;
  const std::string dir = o.flags.out_dir + "/worlds";
  fs::create_directories(dir);
  const std::vector<WorldFamily>& fams = world_families();
  for (int k = 0; k < o.worlds; ++k) {
    const std::string fam = o.family.empty() ? fams[static_cast<std::size_t>(k) % fams.size()].name : o.family;
    const std::uint64_t seed = o.world_seed + static_cast<std::uint64_t>(k);
    std::string path = dir + "/";
    path += fam;
    path += '_';
    path += std::to_string(seed);
    path += ".json";
    save_scenario(draw_world(fam, seed), path);
    o.scenarios.push_back(path);
    o.world_family.push_back(fam);
  }
}

}  // namespace geojcbb::host
