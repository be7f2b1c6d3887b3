// The batch reference (host_tools/mapping, batch.hpp): noise-free odometry and observations from a
// perturbed start solve to the truth; a kidnap's broken chain is still solved (the landmarks place
// the pose); on a simulated run with the true association, the batch's pose error is below the
// filter's (it uses every scan for every pose).
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb_host/batch.hpp"
#include "geojcbb_host/sim.hpp"
#include "geojcbb_host/slam_run.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {

/// Poses on an arc, landmarks around it, the odometry and every observation exact; the start of
/// every pose but the first and of every landmark off by up to `off`.
BatchProblem exact_problem(double off) {
  BatchProblem p;
  p.mount = Mount<double>{0.3, 0.1, 0.05};
  std::vector<Pose2<double>> truth;
  truth.reserve(12);
  for (int k = 0; k < 12; ++k) truth.push_back({2.0 * k, 0.2 * k * k, 0.1 * k});
  const std::vector<Eigen::Vector2d> map{{5, 8}, {12, -4}, {18, 20}, {25, 5}, {8, -6}};
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const double s = k == 0 ? 0 : off * std::sin(3.0 * static_cast<double>(k));
    p.t_s.push_back(static_cast<double>(k));
    p.initial.push_back({truth[k].x + s, truth[k].y - s, truth[k].theta + 0.1 * s});
    if (k > 0) {
      const Pose2<double>& a = truth[k - 1];
      const Pose2<double>& b = truth[k];
      const double c = std::cos(a.theta), sn = std::sin(a.theta);
      p.relative.push_back(
          {c * (b.x - a.x) + sn * (b.y - a.y), -sn * (b.x - a.x) + c * (b.y - a.y), wrap_angle(b.theta - a.theta)});
      p.relative_cov.push_back(Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal());
      p.chained.push_back(1);
    }
    for (std::size_t j = 0; j < map.size(); ++j) {
      const Vec2<double> z = observe(truth[k], p.mount, Vec2<double>(map[j]));
      p.obs.push_back({static_cast<int>(k), static_cast<int>(j), Eigen::Vector2d(z.x(), z.y()),
                       Eigen::Vector2d(0.01, 1e-4).asDiagonal()});
    }
  }
  for (std::size_t j = 0; j < map.size(); ++j) p.landmark_initial.push_back(map[j] + Eigen::Vector2d(off, -off));
  return p;
}

}  // namespace

TEST_CASE("batch: exact odometry and observations from a perturbed start solve to the truth") {
  const BatchProblem p = exact_problem(0.5);
  const BatchResult r = solve_batch(p, BatchOptions{});
  CHECK(r.converged);
  CHECK(r.final_cost < 1e-12);
  const BatchProblem truth = exact_problem(0);
  REQUIRE(r.poses.size() == truth.initial.size());
  for (std::size_t k = 0; k < r.poses.size(); ++k) {
    CHECK(r.poses[k].x == doctest::Approx(truth.initial[k].x).epsilon(1e-6));
    CHECK(r.poses[k].y == doctest::Approx(truth.initial[k].y).epsilon(1e-6));
    CHECK(std::abs(wrap_angle(r.poses[k].theta - truth.initial[k].theta)) < 1e-7);
  }
  for (std::size_t j = 0; j < r.landmarks.size(); ++j) {
    CHECK((r.landmarks[j] - truth.landmark_initial[j]).norm() < 1e-6);
  }
}

TEST_CASE("batch: a kidnap's broken odometry chain is solved by the landmarks") {
  BatchProblem p = exact_problem(0.3);
  p.chained[5] = 0;  // no factor between poses 5 and 6
  const BatchResult r = solve_batch(p, BatchOptions{});
  CHECK(r.converged);
  const BatchProblem truth = exact_problem(0);
  // Placed by its five landmarks to within what the weak anchor (10 m) pulls towards its start.
  CHECK(std::hypot(r.poses[6].x - truth.initial[6].x, r.poses[6].y - truth.initial[6].y) < 1e-2);
  CHECK(std::hypot(r.poses[11].x - truth.initial[11].x, r.poses[11].y - truth.initial[11].y) < 1e-2);
  BatchProblem empty;
  CHECK_THROWS_AS(solve_batch(empty, BatchOptions{}), std::invalid_argument);
}

TEST_CASE("batch: with the true association on a simulated run, the batch's position error is below the filter's") {
  const Scenario sc = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  SimSource src(sc, 1, 600);
  RunOptions ro;
  ro.oracle = true;
  ro.record_trace = true;
  BatchRecorder rec;
  ro.on_scan = [&rec](const ScanOutcome& s) { rec.on_scan(s); };
  std::vector<Pose2<double>> truth_at;  // the true pose at each scan
  {
    RunInput in;
    while (src.next(in)) {
      if (in.scan && in.have_truth) {
        truth_at.push_back(in.true_pose);
      }
    }
    src.rewind();
  }
  const RunResult res = run_inputs(src, ro);
  const BatchProblem p = batch_problem(src, rec, res.trace, Mount<double>{}, true);
  REQUIRE(p.initial.size() == truth_at.size());
  CHECK(p.obs.size() > 100);  // the pairings were recorded
  const BatchResult b = solve_batch(p, BatchOptions{});
  CHECK(b.converged);
  double filter_err = 0, batch_err = 0;
  for (std::size_t k = 0; k < truth_at.size(); ++k) {
    filter_err += std::hypot(p.initial[k].x - truth_at[k].x, p.initial[k].y - truth_at[k].y);
    batch_err += std::hypot(b.poses[k].x - truth_at[k].x, b.poses[k].y - truth_at[k].y);
  }
  const auto n = static_cast<double>(truth_at.size());
  MESSAGE("mean position error: filter ", filter_err / n, " m, batch ", batch_err / n, " m");
  CHECK(batch_err < filter_err);
}
