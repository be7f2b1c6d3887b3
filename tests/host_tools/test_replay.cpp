// The own-log replay (host_tools/datasets/event_log.hpp, docs/replay.md): the converted MRCLAM log
// replays to the MRCLAM replay's results exactly, the reader names the file, line and reason of
// every malformed line, and a log round-trips through the writer bit for bit.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/mrclam_calibration.hpp"
#include "geojcbb_host/mrclam_replay.hpp"
#include "support/data.hpp"

using namespace geojcbb;
using namespace geojcbb::host;
namespace fs = std::filesystem;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("geojcbb_test_replay_" + std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

double anees(const RunResult& r) {
  double s = 0;
  for (const StepRecord& k : r.steps) s += k.pose_nees;
  return r.steps.empty() ? 0.0 : s / static_cast<double>(r.steps.size());
}

void check_same(const RunResult& a, const RunResult& b) {
  CHECK(a.scans == b.scans);
  CHECK(a.observations == b.observations);
  CHECK(a.score.tp == b.score.tp);
  CHECK(a.score.tn == b.score.tn);
  CHECK(a.score.fp == b.score.fp);
  CHECK(a.score.fn == b.score.fn);
  CHECK(a.group_score.tp == b.group_score.tp);
  CHECK(a.group_score.fp == b.group_score.fp);
  CHECK(a.score.f1() == b.score.f1());
  CHECK(a.landmarks == b.landmarks);
  CHECK(a.spurious_in_map == b.spurious_in_map);
  CHECK(a.fp_clutter == b.fp_clutter);
  CHECK(a.steps.size() == b.steps.size());
  // R is written as standard deviations and squared on reading, which can move it by an ulp:
  // every decision and count above is equal, the continuous outputs agree to 1e-12.
  CHECK(anees(a) == doctest::Approx(anees(b)).epsilon(1e-12));
  CHECK(a.mean_abs_x_m == doctest::Approx(b.mean_abs_x_m).epsilon(1e-12));
  CHECK(a.mean_abs_y_m == doctest::Approx(b.mean_abs_y_m).epsilon(1e-12));
}

std::string error_of(const std::string& text) {
  std::istringstream in(text);
  try {
    (void)replay::read_event_log(in, "log.csv");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("replay: a converted MRCLAM robot replays to the MRCLAM replay's results") {
  if (!geojcbb::test::have_mrclam()) return;
  // 150 s of dataset 6 robot 1 with the report's model (cross calibration from dataset 7, the
  // data's noise for what the model leaves constant) and its run options.
  const mrclam::Dataset ds = mrclam::load_dataset(mrclam::dataset_dir(6));
  const mrclam::Dataset other = mrclam::load_dataset(mrclam::dataset_dir(7));
  const mrclam::RobotLog full = mrclam::load_robot(ds, 1);
  const mrclam::RobotLog log = replay::truncate(full, 150.0);
  REQUIRE(log.scans.size() > 50);
  const MrclamNoise noise = MrclamNoise::from_data(ds, {full}, 1.5);
  const mrclam::RobotCalibration cal = mrclam::calibrate_robot(other, mrclam::load_robot(other, 1));
  for (bool drop : {false, true}) {
    for (bool calibrated : {true, false}) {
      CAPTURE(drop);
      CAPTURE(calibrated);
      const MrclamModel model = mrclam_model(noise, cal, calibrated, calibrated, 1.2);
      TempDir dir;
      const std::string path = (dir.path / "robot1.csv").string();
      {
        std::ofstream f(path);
        replay::write_event_log(replay::mrclam_to_log(ds, log, model, drop), f);
      }
      const replay::EventLog read = replay::read_event_log(path);
      CHECK(read.labelled());
      replay::LogSource from_log(read, replay::LogNoise{});
      MrclamSource from_mrclam(ds, log, model, drop);
      // The inputs themselves, bit for bit.
      REQUIRE(from_log.inputs().size() == from_mrclam.inputs().size());
      CHECK(from_log.true_landmarks == from_mrclam.true_landmarks);
      CHECK(from_log.x0.x == from_mrclam.x0.x);
      CHECK(from_log.x0.theta == from_mrclam.x0.theta);
      CHECK(from_log.sensor.max_range_m == from_mrclam.sensor.max_range_m);
      int different = 0;
      for (std::size_t k = 0; k < from_log.inputs().size(); ++k) {
        const RunInput& a = from_log.inputs()[k];
        const RunInput& b = from_mrclam.inputs()[k];
        bool same = a.scan == b.scan && a.t_s == b.t_s && a.have_truth == b.have_truth;
        if (same && !a.scan) {
          same = a.v_mps == b.v_mps && a.w_radps == b.w_radps && a.dt_s == b.dt_s && a.sigma_v_mps == b.sigma_v_mps &&
                 a.sigma_w_radps == b.sigma_w_radps;
        } else if (same) {
          same = a.observations.size() == b.observations.size() && a.true_pose.x == b.true_pose.x &&
                 a.true_pose.theta == b.true_pose.theta;
          for (std::size_t i = 0; same && i < a.observations.size(); ++i) {
            same = a.observations[i].z == b.observations[i].z && a.observations[i].truth == b.observations[i].truth &&
                   (a.observations[i].R - b.observations[i].R).norm() <= 1e-15 * b.observations[i].R.norm();
          }
        }
        different += !same;
      }
      CHECK(different == 0);
      // And the runs: every count, F1 and ANEES equal.
      for (const Method m :
           {Method{Strategy::kGeojcbb, false}, Method{Strategy::kJcbb, false}, Method{Strategy::kJcbb, true}}) {
        CAPTURE(m.name());
        RunOptions o = mrclam_run_defaults();
        m.apply(o);
        o.landmark_group = replay::landmark_groups(geojcbb::test::landmark_xy(ds), kLandmarkGroupRadius_m);
        const RunResult a = replay_robot(ds, log, o, model, drop);
        from_log.rewind();
        const RunResult b = run_inputs(from_log, o);
        CHECK(a.scans > 50);
        check_same(a, b);
      }
    }
  }
}

TEST_CASE("replay: the raw MRCLAM log gives the noise from its labelled data") {
  if (!geojcbb::test::have_mrclam()) return;
  const mrclam::Dataset ds = mrclam::load_dataset(mrclam::dataset_dir(6));
  const mrclam::RobotLog log = replay::truncate(mrclam::load_robot(ds, 2), 300.0);
  const replay::EventLog raw = replay::mrclam_raw_log(ds, log);
  CHECK(raw.labelled());
  CHECK(raw.landmark_labels().size() == 15);
  const replay::LogNoise n = replay::estimate_noise(raw, 1.5);
  // The same estimators as MrclamNoise::from_data on the same stretch.
  const MrclamNoise m = MrclamNoise::from_data(ds, {log}, 1.5);
  CHECK(n.sigma_range_m == doctest::Approx(m.sigma_range_m));
  CHECK(n.sigma_bearing_rad == doctest::Approx(m.sigma_bearing_rad));
  CHECK(n.sigma_v_mps == doctest::Approx(m.sigma_v_mps));
  CHECK(n.sigma_w_radps == doctest::Approx(m.sigma_w_radps));
  replay::LogSource src(raw, n);
  RunOptions o;
  o.step.strategy = Strategy::kGeojcbb;
  const RunResult r = run_inputs(src, o);
  CHECK(r.scans > 100);
  CHECK(r.observations == r.score.tp + r.score.tn + r.score.fp + r.score.fn);
  CHECK(r.steps.size() == static_cast<std::size_t>(r.scans));
}

TEST_CASE("replay: a hand-made log, its labels, noise and start") {
  // A robot drives along x at 1 m/s and sees landmark A at (5, 1) and clutter, never twice in one
  // place.
  std::ostringstream s;
  s << "# a test log\ngeojcbb_log,1\nmeta,max_range_m,20\nlandmark,A,5,1\nlandmark,B,9,-2\n";
  for (int k = 0; k <= 20; ++k) {
    const double t = 0.1 * k;
    s << "truth," << t << ',' << t << ",0,0\n";
    s << "odom," << t << ",1,0\n";
    if (k % 2 == 0 && k > 0) {
      const double half = 0.5 * k;  // k even: a whole number
      s << "meas," << t << ',' << std::hypot(5 - t, 1.0) << ',' << std::atan2(1.0, 5 - t) << ",A\n";
      s << "meas," << t << ",3," << 0.3 * half - 1.5 << ",robot7\n";
    }
  }
  std::istringstream in(s.str());
  const replay::EventLog log = replay::read_event_log(in, "hand");
  CHECK(log.labelled());
  CHECK(log.truth_index("A") == 0);
  CHECK(log.truth_index("B") == 1);
  CHECK(log.truth_index("robot7") == -1);  // not a landmark line: clutter
  CHECK(log.truth_index("clutter") == -1);
  CHECK_THROWS_WITH_AS(replay::LogSource(log, replay::LogNoise{}), doctest::Contains("has no sigma_v, sigma_w"),
                       std::runtime_error);
  replay::LogNoise n;
  n.sigma_range_m = 0.05;
  n.sigma_bearing_rad = 0.01;
  n.sigma_v_mps = 0.05;
  n.sigma_w_radps = 0.02;
  replay::LogSource src(log, n);
  CHECK(src.true_landmarks == 2);
  CHECK(src.x0.x == 0.0);
  CHECK(src.sensor.max_range_m == 20.0);
  RunOptions o;
  o.step.strategy = Strategy::kJcbb;
  const RunResult r = run_inputs(src, o);
  CHECK(r.scans == 10);
  CHECK(r.observations == 20);
  CHECK(r.score.fp == 0);
  CHECK(r.score.tp == 9);  // A: new on the first scan (TN), paired on the nine after
  CHECK(r.mean_abs_x_m < 0.05);
  CHECK_THROWS_WITH_AS(replay::estimate_noise(log, 1.5), doctest::Contains("fewer than"), std::runtime_error);
}

TEST_CASE("replay: a log round-trips through the writer bit for bit") {
  replay::EventLog log;
  log.meta["fov_rad"] = 1.2;
  log.landmarks.push_back({"7", 0.1, 1.0 / 3.0});
  log.odometry.push_back({1.0 / 7.0, 0.2, -0.3, 0.01, 0.02});
  log.odometry.push_back({0.5, 0.1, 0.0});
  log.measurements.push_back({0.3, 2.0 / 3.0, -0.25, "7", 0.1, 0.01});
  log.empty_scans.push_back(0.4);
  log.truth.push_back({0.0, 1.0 / 9.0, 2.0, 3.0});
  std::ostringstream out;
  replay::write_event_log(log, out, "two lines\nof comment");
  std::istringstream in(out.str());
  const replay::EventLog r = replay::read_event_log(in, "mem");
  CHECK(r.meta.at("fov_rad") == 1.2);
  REQUIRE(r.odometry.size() == 2);
  CHECK(r.odometry[0].t == 1.0 / 7.0);
  CHECK(r.odometry[0].sigma_w == 0.02);
  CHECK(r.odometry[1].sigma_v < 0);
  REQUIRE(r.measurements.size() == 1);
  CHECK(r.measurements[0].range == 2.0 / 3.0);
  CHECK(r.measurements[0].label == "7");
  CHECK(r.measurements[0].sigma_bearing == 0.01);
  CHECK(r.empty_scans == std::vector<double>{0.4});
  REQUIRE(r.truth.size() == 1);
  CHECK(r.truth[0].x == 1.0 / 9.0);
  CHECK(r.landmarks[0].y == 1.0 / 3.0);
}

TEST_CASE("replay: every malformed line is an error naming the file, the line and the reason") {
  struct Case {
    const char* text;
    const char* message;
  };
  const Case cases[] = {
      {"odom,0,1\n", "log.csv:1: 'odom' takes t,v,w[,sigma_v,sigma_w] (2 fields given)"},
      {"# c\n\nodom,0,1,x\n", "log.csv:3: w: 'x' is not a number"},
      {"odom,0,1,0,0.1\n", "log.csv:1: 'odom' gives both sigma_v and sigma_w, or neither"},
      {"odom,0,1,0,0.1,-2\n", "log.csv:1: sigma_w: a standard deviation must be non-negative, not -2"},
      {"meas,0,1,0,A,0,0.1\n", "log.csv:1: sigma_range: a standard deviation must be positive, not 0"},
      {"odom,0,1,nan\n", "log.csv:1: w: 'nan' is not finite"},
      {"odom,0,1,1e999\n", "log.csv:1: w: '1e999' is not finite"},
      {"odom,1,1,0\nodom,0.5,1,0\n", "log.csv:2: time goes back in the odom lines"},
      {"odom,,1,0\n", "log.csv:1: t: empty field, a number expected"},
      {"meas,0,-1,0\n", "log.csv:1: range: must be positive, not -1"},
      {"meas,0,1,7\n", "log.csv:1: bearing: must be in [-pi, pi] rad, not 7"},
      {"meas,0,1,0,A,0.1\n", "log.csv:1: 'meas' gives both sigma_range and sigma_bearing, or neither"},
      {"meas,0,1,0,A,0.1,0.1,0,9\n",
       "log.csv:1: 'meas' takes t,range,bearing[,label[,sigma_range,sigma_bearing[,rho]]] (8 "
       "fields given)"},
      {"meas,0,1,0,A,0.1,0.1,1\n", "log.csv:1: rho: a correlation in (-1, 1) expected (R positive definite), not 1"},
      {"odom_delta,0,1,0\n", "log.csv:1: 'odom_delta' takes t,dx,dy,dtheta[,cxx,cxy,cxt,cyy,cyt,ctt] (3 fields given)"},
      {"odom_delta,0,1,0,0,1,0,0\n", "log.csv:1: 'odom_delta' gives all 6 covariance terms, or none"},
      {"odom_delta,0,1,0,0,1,2,0,1,0,1\n", "log.csv:1: odom_delta: the covariance is not positive semi-definite"},
      {"odom_delta,0,1,0,4\n", "log.csv:1: dtheta: must be in [-pi, pi] rad, not 4"},
      {"odom_delta,1,1,0,0\nodom_delta,0.5,1,0,0\n", "log.csv:2: time goes back in the odom_delta lines"},
      {"odom,0,1,0\nodom_delta,1,1,0,0\n",
       "log.csv:2: odom_delta line in a log of odom lines (line 1): one or the other"},
      {"odom_delta,0,1,0,0\nodom,1,1,0\n",
       "log.csv:2: odom line in a log of odom_delta lines (line 1): one or the other"},
      {"gps,0,1\n", "log.csv:1: 'gps' takes t,x,y (2 fields given)"},
      {"gps,1,1,2\ngps,0,1,2\n", "log.csv:2: time goes back in the gps lines"},
      {"meas,0,1,0,A\nmeas,1,1,0\n",
       "log.csv:2: a measurement without a label, while line 1 has one: label every measurement (clutter: "
       "'clutter') or none"},
      {"meas,1,1,0\nscan,0.5\n", "log.csv:2: time goes back in the meas and scan lines"},
      {"truth,0,1,2\n", "log.csv:1: 'truth' takes t,x,y,theta (3 fields given)"},
      {"landmark,A,1,2\nlandmark,A,3,4\n", "log.csv:2: landmark 'A' given twice"},
      {"landmark,clutter,1,2\n", "log.csv:1: landmark: a label other than '' and 'clutter' expected"},
      {"meta,max_range,9\n", "log.csv:1: unknown meta key 'max_range'"},
      {"geojcbb_log,2\n", "log.csv:1: format version 2 not supported (1 expected)"},
      {"odometry,0,1,0\n",
       "log.csv:1: unknown line kind 'odometry' (odom, odom_delta, meas, scan, truth, gps, landmark, meta expected)"},
      {"odom;0;1;0\n",
       "log.csv:1: unknown line kind 'odom;0;1;0' (odom, odom_delta, meas, scan, truth, gps, landmark, meta expected)"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.text);
    const std::string e = error_of(c.text);
    CHECK(e.rfind(c.message, 0) == 0);
    if (e.rfind(c.message, 0) != 0) MESSAGE(e);
  }
  // Binary garbage is an unknown kind, not a crash.
  CHECK(error_of(std::string("\xff\xfe\0,\n", 5)).rfind("log.csv:1: unknown line kind", 0) == 0);
  // Comments, blank lines, blanks around fields and CRLF are accepted.
  CHECK(error_of("# x\r\n\r\n odom , 0 , 1 , 0 \r\n") == "");
  // A missing file names it.
  CHECK_THROWS_WITH_AS(replay::read_event_log("/nonexistent/geojcbb.csv"), "/nonexistent/geojcbb.csv: cannot open",
                       std::runtime_error);
}

TEST_CASE("replay: mutated logs are read, replayed or refused, never a crash") {
  // A small valid log, then 3000 copies with 1-4 random byte edits each (a digit, a comma, a
  // sign, a letter, a newline, or a byte removed): each is read and, when read, replayed; every
  // outcome is a result or a std::exception with a message.
  const std::string valid =
      "geojcbb_log,1\nmeta,max_range_m,20\nmeta,fov_rad,3\nlandmark,A,5,1\nlandmark,B,4,-2\n"
      "truth,0,0,0,0\ntruth,1,1,0,0\ntruth,2,2,0,0.1\n"
      "odom,0,1,0\nmeas,0.5,4.6,0.22,A\nmeas,0.5,4.9,-0.45,B\nodom,1,1,0.1,0.05,0.02\n"
      "meas,1.5,3.7,0.27,A,0.1,0.02\nmeas,1.5,3.1,-0.6,clutter\nscan,1.8\nodom,2,0,0\n";
  std::mt19937 rng(7);
  const std::string alphabet = "0123456789,.-+eE\nAx #";
  replay::LogNoise n;
  n.sigma_range_m = 0.1;
  n.sigma_bearing_rad = 0.02;
  n.sigma_v_mps = 0.05;
  n.sigma_w_radps = 0.02;
  int read = 0, replayed = 0, refused = 0;
  for (int k = 0; k < 3000; ++k) {
    std::string text = valid;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const std::size_t at = rng() % text.size();
      if (rng() % 4 == 0) {
        text.erase(at, 1);
      } else {
        text[at] = alphabet[rng() % alphabet.size()];
      }
    }
    try {
      std::istringstream in(text);
      const replay::EventLog log = replay::read_event_log(in, "mutated");
      ++read;
      replay::LogSource src(log, n);
      RunOptions o;
      o.step.strategy = k % 2 ? Strategy::kGeojcbb : Strategy::kJcbb;
      const RunResult r = run_inputs(src, o);
      CHECK(r.observations == r.score.tp + r.score.tn + r.score.fp + r.score.fn);
      ++replayed;
    } catch (const std::exception& e) {
      CHECK(std::string(e.what()).size() > 0);
      ++refused;
    }
  }
  CHECK(read + refused >= 3000);
  CHECK(replayed > 100);  // the mutations also leave valid logs, which replay
  CHECK(refused > 100);
}
