// The evaluation's scoring on a hand-computed case (eq. 15: every observation
// exactly once), the chi-square quantile used for the time-averaged NEES
// bounds, and the MRCLAM replay on real data.
#include <doctest/doctest.h>

#include <set>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb_host/eval_report.hpp"
#include "geojcbb_host/event_log.hpp"
#include "geojcbb_host/mrclam_replay.hpp"
#include "geojcbb_host/slam_run.hpp"
#include "support/data.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

TEST_CASE("scoring: TP, TN, FP, FN on a hand-computed sequence of scans") {
  // A robot standing at the origin. True landmarks 0 and 1 stand at the same
  // spot (10, 0), so geometry cannot tell them apart; with both in one group
  // the group score calls their mix-up right.
  RunOptions o;
  o.step.strategy = Strategy::kJcbb;
  o.landmark_group = {0, 0, 2};
  const SensorModel sensor{0.5, 30.0, 2 * kPi<double>, 0.001};
  SlamSession s(o, sensor, 3, Pose2<double>{0, 0, 0}, Eigen::Matrix3d::Identity() * 1e-9);
  const Eigen::Matrix2d R = Eigen::Vector2d(0.01 * 0.01, 0.001 * 0.001).asDiagonal();
  const Pose2<double> truth{0, 0, 0};
  // Scan 1: landmark 0, map empty -> TN, and it becomes feature 0.
  s.scan({{Eigen::Vector2d(10, 0), 0, R}}, 1, &truth);
  // Scan 2: landmark 1 at landmark 0's spot -> paired with feature 0: FP
  // (group: TP). Landmark 0 measured far from where it is (0.5 rad off) -> left
  // unpaired while mapped: FN. Clutter far from everything -> TN.
  s.scan({{Eigen::Vector2d(10, 0), 1, R}, {Eigen::Vector2d(10, 0.5), 0, R}, {Eigen::Vector2d(5, -1), -1, R}}, 2,
         &truth);
  // Scan 3: landmark 0 where it is -> TP.
  s.scan({{Eigen::Vector2d(10, 0), 0, R}}, 3, &truth);
  const RunResult r = s.finish();
  CHECK(r.scans == 3);
  CHECK(r.observations == 5);
  CHECK(r.score.tp == 1);
  CHECK(r.score.fp == 1);
  CHECK(r.score.fn == 1);
  CHECK(r.score.tn == 2);
  CHECK(r.group_score.tp == 2);
  CHECK(r.group_score.fp == 0);
  CHECK(r.group_score.fn == 1);
  CHECK(r.group_score.tn == 2);
  CHECK(r.score.precision() == doctest::Approx(0.5));
  CHECK(r.score.recall() == doctest::Approx(0.5));
  CHECK(accuracy(r.score) == doctest::Approx(3.0 / 5.0));
  CHECK(r.steps.size() == 3);
  CHECK(r.mean_abs_x_m < 1e-6);
  CHECK(r.spurious_landmarks == 1);  // the clutter passed the second gate and was mapped (tentative)
}

TEST_CASE(
    "the NEES bound quantile (Wilson-Hilferty) agrees with chi2_inv "
    "where both exist") {
  // The evaluation uses it at 3 x runs x scans dof (tens of thousands); from
  // 200 dof up its relative error is below 1e-5 in the centre and 1e-4 in the
  // tails (at 60 dof it is 2e-4).
  for (int dof : {200, 1000, 4000}) {
    for (double p : {0.025, 0.5, 0.975}) {
      double exact = 0;
      REQUIRE(chi2_inv(p, dof, exact) == Status::kOk);
      CAPTURE(dof);
      CAPTURE(p);
      CHECK(chi2_quantile_wh(p, dof) == doctest::Approx(exact).epsilon(1e-4));
    }
  }
}

TEST_CASE("MRCLAM replay: landmark groups, and every measurement scored once") {
  if (!geojcbb::test::have_mrclam()) return;
  const mrclam::Dataset ds = mrclam::load_dataset(mrclam::dataset_dir(6));
  const std::vector<int> g = replay::landmark_groups(geojcbb::test::landmark_xy(ds), kLandmarkGroupRadius_m);
  REQUIRE(g.size() == 15);
  CHECK(std::set<int>(g.begin(), g.end()).size() == 6);  // six clusters of two or three landmarks
  const std::vector<mrclam::RobotLog> logs{mrclam::load_robot(ds, 1)};
  const MrclamNoise noise = MrclamNoise::from_data(ds, logs, 1.5);
  CHECK(noise.sigma_range_m > 0.05);
  CHECK(noise.sigma_bearing_rad > 0.005);
  RunOptions o;
  o.landmark_group = g;
  MrclamModel model;
  model.noise = noise;
  const RunResult r = replay_robot(ds, logs[0], o, model);
  std::size_t measurements = 0;
  for (const mrclam::Scan& s : logs[0].scans) measurements += s.z.size();
  const Score& a = r.score;
  CHECK(a.tp + a.tn + a.fp + a.fn == r.observations);
  CHECK(r.observations <= static_cast<int>(measurements));
  CHECK(r.observations > static_cast<int>(measurements) * 9 / 10);  // only scans before the start are skipped
  // A pair correct at landmark level is correct at group level.
  CHECK(r.group_score.tp >= a.tp);
  CHECK(r.group_score.tp + r.group_score.fp == a.tp + a.fp);
  CHECK(r.steps.size() > 1000);
}

// The MRCLAM bound on real data, asserted on measured behaviour: association by ground truth on
// robot 3 of each dataset, with the model and landmark rules the report uses (camera and drive
// calibrated on the same robot in the other dataset), is consistent (time-averaged pose NEES <= 6,
// 3 if perfect) and maps no landmark twice.
TEST_CASE("MRCLAM: TRUTH on one robot of each dataset is consistent and maps no duplicate") {
  if (!geojcbb::test::have_mrclam()) return;
  for (const int number : {6, 7}) {
    const mrclam::Dataset ds = mrclam::load_dataset(mrclam::dataset_dir(number));
    const mrclam::Dataset other = mrclam::load_dataset(mrclam::dataset_dir(number == 6 ? 7 : 6));
    std::vector<mrclam::RobotLog> logs;
    for (int r = 1; r <= mrclam::kRobots; ++r) logs.push_back(mrclam::load_robot(ds, r));
    const mrclam::RobotLog& log = logs[2];
    const MrclamModel model = mrclam_model(MrclamNoise::from_data(ds, logs, 1.5),
                                           mrclam::calibrate_robot(other, mrclam::load_robot(other, log.robot)));
    RunOptions o = mrclam_run_defaults();
    o.oracle = true;
    const RunResult r = replay_robot(ds, log, o, model);
    REQUIRE(r.steps.size() > 1000);
    double nees = 0;
    for (const StepRecord& s : r.steps) nees += s.pose_nees;
    const double anees = nees / static_cast<double>(r.steps.size());
    std::vector<int> per_truth(ds.landmarks.size(), 0);
    int duplicates = 0;
    for (const MapLandmark& l : r.map)
      if (l.truth >= 0 && per_truth[static_cast<std::size_t>(l.truth)]++ > 0) ++duplicates;
    CAPTURE(number);
    MESSAGE("dataset " << number << " robot 3, TRUTH: ANEES " << anees << ", " << r.landmarks << " landmarks, "
                       << duplicates << " duplicates, F1 " << r.score.f1());
    CHECK(anees <= 6.0);
    CHECK(duplicates == 0);
    CHECK(r.score.fp == 0);
  }
}
