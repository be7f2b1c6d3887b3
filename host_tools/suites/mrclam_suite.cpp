// host_tools/suites: the MRCLAM replay's report (mrclam_suite.hpp): every strategy on every robot
// of every data set, replayed through the own-log format, scored, printed and written.
#include "geojcbb_host/mrclam_suite.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/map_merge.hpp"
#include "geojcbb_host/mover_motion.hpp"
#include "geojcbb_host/report.hpp"
#include "geojcbb_host/world_model_report.hpp"

namespace geojcbb::host {

namespace {
// mrclam.csv's columns between dataset, robot, strategy and error (report.hpp: run_csv).
const std::vector<std::string> kMrclamCsvColumns{
    "scans", "observations",  "tp",    "tn",           "fp",           "fn",        "precision",       "recall",
    "f1",    "association_s", "run_s", "mean_abs_x_m", "mean_abs_y_m", "landmarks", "spurious_in_map", "fp_clutter"};

/// The mover split's observer of one replay: the subjects of the observations it is fed (the log
/// says "clutter" for a robot; MrclamSource knows which), the robots' ground truth.
MoverMotion mover_motion(const mrclam::Dataset& ds, const mrclam::RobotLog& log, const MrclamModel& model,
                         bool drop_other_robots, const std::vector<std::vector<mrclam::PoseSample>>& tracks) {
  MoverMotion m(tracks, log.robot);
  const MrclamSource src(ds, log, model, drop_other_robots);
  std::size_t k = 0;
  for (const RunInput& in : src.inputs()) {
    if (in.scan) m.add_subjects(in.t_s, in.observations, src.scan_subjects[k++]);
  }
  return m;
}

/// The other robots' false pairs by how far the robot moved since its landmark was made
/// (mover_motion.hpp), per strategy; their total is the FP of clutter less the false detections.
void print_movers(const std::vector<Method>& strategies, const std::vector<MoverCounts>& movers,
                  const std::vector<ReportRow>& rows) {
  std::printf(
      "False pairs with other robots, by how far the robot moved since the landmark was made from it "
      "(sigma: docs/mrclam.md)\n  %-9s %9s %9s %9s %26s %7s %13s\n",
      "strategy", mover_bucket_title(MoverBucket::kUnder1Sigma), mover_bucket_title(MoverBucket::k1To3Sigma),
      mover_bucket_title(MoverBucket::kOver3Sigma), mover_bucket_title(MoverBucket::kOtherLandmark), "total",
      "FP of clutter");
  for (std::size_t s = 0; s < strategies.size(); ++s) {
    const MoverCounts& c = movers[s];
    std::printf("  %-9s %9d %9d %9d %26d %7d %13d\n", strategies[s].name().c_str(), c.bucket[0], c.bucket[1],
                c.bucket[2], c.bucket[3], c.total(), rows[s].fp_clutter);
    if (c.false_detections > 0 || c.unmatched > 0 || c.truth_gaps > 0)
      std::printf(
          "  %-9s (clutter not a robot paired: %d; observations without a subject: %d; positions from the "
          "nearest truth sample: %d)\n",
          "", c.false_detections, c.unmatched, c.truth_gaps);
  }
}

nlohmann::json movers_json(const MoverCounts& c) {
  nlohmann::json j;
  for (int k = 0; k < kMoverBuckets; ++k)
    j[mover_bucket_key(static_cast<MoverBucket>(k))] = c.bucket[static_cast<std::size_t>(k)];
  j["false_detections"] = c.false_detections;
  return j;
}

void write_trace(const std::string& path, const RunResult& res) {
  {
    std::ofstream m(path.substr(0, path.size() - 4) + "_map.csv");
    m.precision(10);
    m << "x_m,y_m,truth\n";
    for (const MapLandmark& l : res.map) m << l.x << ',' << l.y << ',' << l.truth << '\n';
  }
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write");
  f.precision(10);
  f << "t_s,ex_m,ey_m,etheta_rad,var_x,var_y,var_theta,nees,paired,nis_sum\n";
  for (const StepRecord& s : res.steps) {
    f << s.t_s << ',' << s.estimate.x - s.truth.x << ',' << s.estimate.y - s.truth.y << ','
      << wrap_angle(s.estimate.theta - s.truth.theta) << ',' << s.var_x << ',' << s.var_y << ',' << s.var_theta << ','
      << s.pose_nees << ',' << s.paired << ',' << s.nis_sum << '\n';
  }
}
}  // namespace

namespace {

/// A robot's final map in its own frame: the run's map (in the world frame, as it started at its true
/// pose) moved by the inverse of its start. EKF-SLAM commutes with a rigid change of the start (the
/// models are invariant), so this is the map it would have built from an origin of its own.
RobotMap own_frame(const RunResult& r, const Pose2<double>& x0) {
  RobotMap m;
  const double c = std::cos(x0.theta), sn = std::sin(x0.theta);
  Eigen::Matrix2d Rt;
  Rt << c, sn, -sn, c;
  const int n = static_cast<int>(r.map.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  for (int i = 0; i < n; ++i) {
    const MapLandmark& l = r.map[static_cast<std::size_t>(i)];
    m.landmarks.push_back(Rt * Eigen::Vector2d(l.x - x0.x, l.y - x0.y));
    m.truth.push_back(l.truth);
    J.block<2, 2>(2 * i, 2 * i) = Rt;
  }
  m.P = J * r.map_cov * J.transpose();
  return m;
}

/// b in a's frame: a^-1 (+) b.
Pose2<double> relative(const Pose2<double>& a, const Pose2<double>& b) {
  const double c = std::cos(a.theta), sn = std::sin(a.theta), dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + sn * dy, -sn * dx + c * dy, wrap_angle(b.theta - a.theta)};
}

/// The heading standard deviation at the run's first scan with a pairing [rad] (-1: none): the
/// floor on its map's rotation about its start, since only the odometry before that scan ties the two
/// (docs/submaps.md, "What the logs allow").
double first_pairing_heading_sd(const RunResult& r) {
  for (const StepRecord& st : r.steps) {
    if (st.paired > 0) return std::sqrt(std::max(st.var_theta, 0.0));
  }
  return -1;
}

struct MergedRobot {
  int robot;
  Pose2<double> x0;  ///< its true start: only for the score
  const RunResult* res;
};

/// mrclam --merge: the robots' maps merged with their starts unknown, the starts found scored.
void print_merge(int dataset, const std::string& strategy, const std::vector<MergedRobot>& robots, double f1,
                 const MergeOptions& mo, nlohmann::json& js) {
  if (robots.empty()) return;
  std::vector<RobotMap> maps;
  maps.reserve(robots.size());
  for (const MergedRobot& r : robots) maps.push_back(own_frame(*r.res, r.x0));
  const MergeResult m = merge_maps(maps, mo);
  int alone = 0;
  for (bool a : m.aligned) alone += !a;
  std::printf("Merged, %s (the robots' maps in their own frames, starts unknown; docs/submaps.md)\n", strategy.c_str());
  std::printf(
      "  global map: %zu landmarks\n  wrong joins: %d\n  fused %d pairs; %d map(s) kept apart; F1 over all "
      "robots %.3f\n",
      m.landmarks.size(), m.wrong, m.fused, alone, f1);
  nlohmann::json starts = nlohmann::json::array();
  const double sd0 = first_pairing_heading_sd(*robots[0].res);
  for (std::size_t k = 1; k < robots.size(); ++k) {
    const Pose2<double> truth = relative(robots[0].x0, robots[k].x0);
    const double sdk = first_pairing_heading_sd(*robots[k].res);
    const double floor_deg = sd0 >= 0 && sdk >= 0 ? std::hypot(sd0, sdk) * 180 / kPi<double> : -1;
    std::printf(
        "  robot %d: the logs' floor on its start's heading: %.2f deg (both robots' heading standard "
        "deviations at their first paired scan)\n",
        robots[k].robot, floor_deg);
    if (!m.aligned[k]) {
      std::printf("  robot %d: not joined: %s (its true start (%.2f, %.2f, %.2f))\n", robots[k].robot, m.why[k].c_str(),
                  truth.x, truth.y, truth.theta);
      starts.push_back({{"robot", robots[k].robot}, {"found", false}, {"why", m.why[k]}, {"floor_deg", floor_deg}});
      continue;
    }
    const Pose2<double>& f = m.start[k];
    const double e = std::hypot(f.x - truth.x, f.y - truth.y), a = std::abs(wrap_angle(f.theta - truth.theta));
    const Eigen::Matrix3d& C = m.start_cov[k];
    const double sd_x = std::sqrt(C(0, 0)), sd_y = std::sqrt(C(1, 1)), sd_deg = std::sqrt(C(2, 2)) * 180 / kPi<double>;
    std::printf(
        "  robot %d's start in robot %d's frame: found (%.3f, %.3f, %.2f deg), standard deviations (%.3f, %.3f, "
        "%.2f deg); true (%.3f, %.3f, %.2f deg): error %.3f m, %.2f deg; %d landmarks fused\n",
        robots[k].robot, robots[0].robot, f.x, f.y, f.theta * 180 / kPi<double>, sd_x, sd_y, sd_deg, truth.x, truth.y,
        truth.theta * 180 / kPi<double>, e, a * 180 / kPi<double>, m.pairs[k]);
    starts.push_back({{"robot", robots[k].robot},
                      {"found", true},
                      {"error_m", e},
                      {"error_deg", a * 180 / kPi<double>},
                      {"sd_m", {sd_x, sd_y}},
                      {"sd_deg", sd_deg},
                      {"floor_deg", floor_deg}});
  }
  js["merged"].push_back({{"dataset", dataset},
                          {"strategy", strategy},
                          {"landmarks", m.landmarks.size()},
                          {"wrong_joins", m.wrong},
                          {"fused", m.fused},
                          {"f1", f1},
                          {"starts", starts}});
}

// A data set as the report replays it: its robots' logs, the noise from the data, each robot's
// calibration, and every robot's ground truth (the mover split).
struct DatasetData {
  int number;
  mrclam::Dataset ds;
  std::vector<mrclam::RobotLog> logs;
  MrclamNoise noise;
  std::vector<mrclam::RobotCalibration> calibration;    ///< per log
  std::vector<std::vector<mrclam::PoseSample>> tracks;  ///< robot -> its ground truth (the mover split)
};

// One replay: a robot of a data set with a strategy, and what it gave.
struct Job {
  std::size_t d, r, s;
  Pose2<double> x0{};  ///< the start (the ground truth's): the robot's own frame for --merge
  RunResult res;
  MoverCounts movers;       ///< in process only (a device's runner does not report its steps' outcomes)
  DetectionTable labelled;  ///< p_D from the labels (the first strategy's job of each robot)
  double run_s = 0;
  std::string error;
  std::array<double, 3> batch{NAN, NAN, NAN};  ///< --batch: the trace's, own pairings', labels' error [m]
};

const Job& find_job(const std::vector<Job>& jobs, std::size_t d, std::size_t r, std::size_t s) {
  return *std::find_if(jobs.begin(), jobs.end(), [&](const Job& x) { return x.d == d && x.r == r && x.s == s; });
}

// The data sets loaded, with the noise (the data's, or as given) and the calibrations.
std::vector<DatasetData> load_datasets(const MrclamOptions& o, const std::string& root) {
  std::vector<DatasetData> data;
  for (int n : o.datasets) {
    DatasetData d;
    d.number = n;
    d.ds = mrclam::load_dataset(mrclam::dataset_dir(n, root));
    for (int r : o.robots) d.logs.push_back(mrclam::load_robot(d.ds, r));
    d.tracks.resize(mrclam::kRobots + 1);
    for (int k = 1; k <= mrclam::kRobots; ++k) {  // every robot can be seen, replayed or not
      const auto it = std::find_if(d.logs.begin(), d.logs.end(), [&](const auto& l) { return l.robot == k; });
      d.tracks[static_cast<std::size_t>(k)] = it != d.logs.end() ? it->truth : mrclam::load_robot(d.ds, k).truth;
    }
    d.noise = MrclamNoise::from_data(d.ds, d.logs, o.noise_inflation);
    if (o.sigma_range_m > 0) d.noise.sigma_range_m = o.sigma_range_m;
    if (o.sigma_bearing_rad > 0) d.noise.sigma_bearing_rad = o.sigma_bearing_rad;
    if (o.sigma_v_mps > 0) d.noise.sigma_v_mps = o.sigma_v_mps;
    if (o.sigma_w_radps > 0) d.noise.sigma_w_radps = o.sigma_w_radps;
    if (o.camera || o.drive) {
      // "cross": the same robot of the other dataset (the robots and cameras are the same in 6 and 7).
      const int other = n == 6 ? 7 : 6;
      mrclam::Dataset cds;
      if (o.calibration == "cross") cds = mrclam::load_dataset(mrclam::dataset_dir(other, root));
      for (std::size_t r = 0; r < d.logs.size(); ++r) {
        if (o.calibration == "same") {
          d.calibration.push_back(mrclam::calibrate_robot(d.ds, d.logs[r], o.calibration_options));
        } else {
          d.calibration.push_back(
              mrclam::calibrate_robot(cds, mrclam::load_robot(cds, d.logs[r].robot), o.calibration_options));
        }
      }
    }
    data.push_back(std::move(d));
  }
  return data;
}

// One replay: the robot converted to the own-log format (what convert-mrclam writes) and replayed
// as any log (docs/replay.md); its landmark lines give the groups and the known map. An exception
// is the job's error.
void replay_job(const MrclamOptions& o, const std::vector<DatasetData>& data, Job& jb) {
  RunOptions ro = o.run;
  o.strategies[jb.s].apply(ro);
  const auto a = std::chrono::steady_clock::now();
  try {
    const MrclamModel model = mrclam_model(
        data[jb.d].noise, data[jb.d].calibration.empty() ? mrclam::RobotCalibration{} : data[jb.d].calibration[jb.r],
        o.camera, o.drive, o.model_inflation);
    const mrclam::RobotLog& full = data[jb.d].logs[jb.r];
    mrclam::RobotLog cut;
    if (o.seconds > 0) cut = replay::truncate(full, o.seconds);
    const mrclam::RobotLog& used = o.seconds > 0 ? cut : full;
    const replay::EventLog log = replay::mrclam_to_log(data[jb.d].ds, used, model, o.drop_other_robots);
    MoverMotion movers = mover_motion(data[jb.d].ds, used, model, o.drop_other_robots, data[jb.d].tracks);
    ScanRecorder rec;
    if (o.batch) ro.record_trace = true;
    ro.on_scan = [&movers, &rec, &o](const ScanOutcome& sc) {
      movers.on_scan(sc);
      if (o.batch) rec.on_scan(sc);
    };
    const std::vector<Eigen::Vector2d> positions = replay::landmark_positions(log);
    ro.landmark_group = replay::landmark_groups(positions, kLandmarkGroupRadius_m);
    if (o.known_map) ro.known_map = positions;
    replay::LogSource src(log, replay::LogNoise{});
    if (jb.s == 0) jb.labelled = labelled_detection(src, positions, step_settings(ro, src.sensor));
    jb.x0 = src.x0;
    jb.res = o.runner ? o.runner(src, ro) : run_inputs(src, ro);
    jb.movers = movers.counts();
    if (o.batch) jb.batch = o.batch(src, rec, jb.res, ro);
  } catch (const std::exception& e) {
    jb.error = e.what();
  }
  jb.run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

// A data set's sums over its robots, per strategy.
struct DatasetSums {
  std::vector<RunAggregate> agg;
  std::vector<MoverCounts> movers;
  std::vector<WorldModelSums> world;
  DetectionTable labelled;
  explicit DatasetSums(std::size_t strategies) : agg(strategies), movers(strategies), world(strategies) {}
};

// F1 per robot and strategy (landmark / group) with each robot's winner; every replay summed into
// sums, its mrclam.csv row written and its trace (--trace). Returns the failed replays.
int robot_table(const MrclamOptions& o, const DatasetData& dd, std::size_t d, const std::vector<Job>& jobs,
                DatasetSums& sums, std::ofstream& csv) {
  int failures = 0;
  std::printf(
      "F1 per robot (landmark / landmark group: landmarks within "
      "%.2f m form a group)\n  %-6s",
      kLandmarkGroupRadius_m, "robot");
  for (const Method& s : o.strategies) std::printf(" %11s", s.name().c_str());
  std::printf("   winner\n");
  for (std::size_t r = 0; r < dd.logs.size(); ++r) {
    std::printf("  %-6d", dd.logs[r].robot);
    double best = -1;
    std::string winner;
    for (std::size_t s = 0; s < o.strategies.size(); ++s) {
      const Job& jb = find_job(jobs, d, r, s);
      const std::string line =
          std::to_string(dd.number) + ',' + std::to_string(dd.logs[r].robot) + ',' + o.strategies[s].name() + ',';
      if (!jb.error.empty()) {
        ++failures;
        sums.agg[s].fail(jb.error);
        std::printf(" %11s", "failed");
        csv << line << std::string(kMrclamCsvColumns.size() + kMoverBuckets, ',') << csv_escape(jb.error) << '\n';
        continue;
      }
      const RunResult& res = jb.res;
      if (!o.trace_dir.empty())
        write_trace(o.trace_dir + "/trace_" + std::to_string(dd.number) + "_" + std::to_string(dd.logs[r].robot) + "_" +
                        o.strategies[s].name() + ".csv",
                    res);
      const double f1 = res.score.f1();
      std::printf("   %.3f/%.3f", f1, res.group_score.f1());
      if (o.strategies[s].oracle) {
        // not a contender
      } else if (f1 > best + 1e-12) {
        best = f1;
        winner = o.strategies[s].name();
      } else if (std::abs(f1 - best) <= 1e-12) {
        winner += "=" + std::string(o.strategies[s].name());
      }
      sums.agg[s].add(res, jb.run_s);
      sums.movers[s] += jb.movers;
      sums.world[s].add(res);
      sums.labelled += jb.labelled;
      csv << line << run_csv(res, jb.run_s, kMrclamCsvColumns);
      for (int k : jb.movers.bucket) {  // empty through a device: it does not report the outcomes
        csv << ',';
        if (!o.runner) csv << k;
      }
      csv << ",\n";
    }
    std::printf("   %s\n", winner.c_str());
  }
  return failures;
}

// The path and map figure (report.hpp, as the simulation's and the own-log replay's): one panel per
// robot, for GEOJCBB (else the first strategy listed).
void write_path_figure(const MrclamOptions& o, const DatasetData& dd, std::size_t d, const std::vector<Job>& jobs,
                       const std::string& out_dir) {
  std::size_t shown = 0;
  for (std::size_t s = 0; s < o.strategies.size(); ++s)
    if (!o.strategies[s].oracle && !o.strategies[s].verify && o.strategies[s].strategy == Strategy::kGeojcbb) shown = s;
  std::vector<Eigen::Vector2d> truth_map;
  for (const mrclam::Landmark& l : dd.ds.landmarks) truth_map.emplace_back(l.x, l.y);
  svg::Figure path;
  path.title = "Path and map, MRCLAM_Dataset" + std::to_string(dd.number) + ", " + o.strategies[shown].name();
  path.cols = std::min<int>(3, static_cast<int>(dd.logs.size()));
  for (std::size_t r = 0; r < dd.logs.size(); ++r) {
    const Job& jb = find_job(jobs, d, r, shown);
    if (jb.error.empty())
      path.panels.push_back(path_map_panel("robot " + std::to_string(dd.logs[r].robot), jb.res, truth_map));
  }
  const std::string fig = out_dir + "/mrclam" + std::to_string(dd.number) + "_path.svg";
  svg::write(path, fig);
  std::printf("figure: %s\n", fig.c_str());
}

// A data set's report: its noise, the robots' table, the tables over all its robots, the movers,
// the world model, the group-level table, --merge, the figure, its summary in js. Returns the
// failed replays.
int report_dataset(const MrclamOptions& o, const DatasetData& dd, std::size_t d, const std::vector<Job>& jobs,
                   const std::string& out_dir, std::ofstream& csv, nlohmann::json& js) {
  std::printf(
      "\n== MRCLAM_Dataset%d: R from the data: sigma_range %.4f m, "
      "sigma_bearing %.4f rad; odometry "
      "sigma_v %.4f m/s, sigma_w %.4f rad/s (1-s means)\n",
      dd.number, dd.noise.sigma_range_m, dd.noise.sigma_bearing_rad, dd.noise.sigma_v_mps, dd.noise.sigma_w_radps);
  DatasetSums sums(o.strategies.size());
  const int failures = robot_table(o, dd, d, jobs, sums, csv);
  // The mean over robots of each replay's time-averaged NEES (no Monte Carlo bounds); a device
  // does not report its map.
  std::vector<ReportRow> rows, group_rows;
  for (std::size_t s = 0; s < o.strategies.size(); ++s) {
    rows.push_back(sums.agg[s].row(o.strategies[s].name(), false, !o.runner));
    group_rows.push_back(sums.agg[s].group_row(o.strategies[s].name()));
  }
  std::printf(
      "All robots of the dataset (ANEES: mean over robots of the "
      "time-averaged pose NEES; 3 if consistent)\n");
  print_tables(rows, stdout);
  print_summary(rows, group_rows, stdout);
  print_submaps(o.strategies, sums.agg, stdout);
  if (!o.runner) print_movers(o.strategies, sums.movers, rows);
  std::vector<std::string> names;
  names.reserve(o.strategies.size());
  for (const Method& m : o.strategies) names.push_back(m.name());
  print_world_model(names, sums.world, &sums.labelled, stdout);
  std::printf(
      "Table 2 at landmark-group level (a pair is correct when its "
      "feature's landmark is in the observed "
      "landmark's group)\n");
  print_accuracy(group_rows, stdout);
  if (o.merge) {
    for (std::size_t s = 0; s < o.strategies.size(); ++s) {
      std::vector<MergedRobot> robots;
      for (std::size_t r = 0; r < dd.logs.size(); ++r) {
        const Job& jb = find_job(jobs, d, r, s);
        if (jb.error.empty()) robots.push_back({dd.logs[r].robot, jb.x0, &jb.res});
      }
      print_merge(dd.number, o.strategies[s].name(), robots, sums.agg[s].score.f1(), o.merge_options, js);
    }
  }
  write_path_figure(o, dd, d, jobs, out_dir);
  nlohmann::json strategies_json = rows_json(rows);
  for (std::size_t s = 0; s < o.strategies.size() && !o.runner; ++s)
    strategies_json[s]["false_pairs_to_robots_by_motion"] = movers_json(sums.movers[s]);
  js["datasets"].push_back({{"dataset", dd.number},
                            {"sigma_range_m", dd.noise.sigma_range_m},
                            {"sigma_bearing_rad", dd.noise.sigma_bearing_rad},
                            {"sigma_v_mps", dd.noise.sigma_v_mps},
                            {"sigma_w_radps", dd.noise.sigma_w_radps},
                            {"strategies", strategies_json},
                            {"group_level", rows_json(group_rows)}});
  return failures;
}

// --batch: the batch reference per robot (docs/mapping.md).
void print_batch_references(const MrclamOptions& o, const std::vector<DatasetData>& data,
                            const std::vector<Job>& jobs) {
  std::printf(
      "\n== the batch reference: mean position error [m] of the replay's trace, of every pose and landmark solved "
      "at once with its own pairings, and with the labels\n| data set | robot | strategy | trace | own pairings | "
      "labels |\n| --- | --- | --- | --- | --- | --- |\n");
  for (const Job& jb : jobs) {
    if (!jb.error.empty()) continue;
    std::printf("| %d | %d | %s | %.2f | %.2f | %.2f |\n", data[jb.d].number, data[jb.d].logs[jb.r].robot,
                o.strategies[jb.s].name().c_str(), jb.batch[0], jb.batch[1], jb.batch[2]);
  }
}

}  // namespace

int run_mrclam_report(const MrclamOptions& o, const std::string& out_dir, bool progress) {
  if (!o.trace_dir.empty()) std::filesystem::create_directories(o.trace_dir);
  const std::string root = o.data_dir.empty() ? mrclam::default_data_dir() : o.data_dir;
  std::filesystem::create_directories(out_dir);
  if (o.calibration != "cross" && o.calibration != "same") {
    throw std::runtime_error("calibration: 'cross' or 'same' expected, not '" + o.calibration + "'");
  }
  const std::vector<DatasetData> data = load_datasets(o, root);
  std::vector<Job> jobs;
  for (std::size_t d = 0; d < data.size(); ++d)
    for (std::size_t r = 0; r < data[d].logs.size(); ++r)
      for (std::size_t s = 0; s < o.strategies.size(); ++s)
        jobs.push_back({d, r, s, Pose2<double>{}, RunResult{}, MoverCounts{}, DetectionTable{}, 0, std::string{}, {}});
  const int threads = o.jobs > 0 ? o.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const double wall_s =
      run_parallel(jobs.size(), threads, progress, [&](std::size_t j) { replay_job(o, data, jobs[j]); });

  nlohmann::json js;
  int failures = 0;
  std::ofstream csv(out_dir + "/mrclam.csv");
  csv << "dataset,robot,strategy";
  for (const std::string& c : kMrclamCsvColumns) csv << ',' << c;
  for (int k = 0; k < kMoverBuckets; ++k) csv << ",fp_robot_" << mover_bucket_key(static_cast<MoverBucket>(k));
  csv << ",error\n";
  for (std::size_t d = 0; d < data.size(); ++d) failures += report_dataset(o, data[d], d, jobs, out_dir, csv, js);
  js["wall_s"] = wall_s;
  std::ofstream(out_dir + "/mrclam.json") << js.dump(2) << '\n';
  if (o.batch) print_batch_references(o, data, jobs);
  std::printf(
      "\n%zu replays in %.1f s on %d threads; per-robot rows: "
      "%s/mrclam.csv, summary: %s/mrclam.json\n",
      jobs.size(), wall_s, threads, out_dir.c_str(), out_dir.c_str());
  return failures > 0 ? 1 : 0;
}

}  // namespace geojcbb::host
