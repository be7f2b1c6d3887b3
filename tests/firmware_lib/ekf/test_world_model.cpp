// The world model (docs/design.md, "The world model"): the motion test's false-alarm rate on white
// innovations is its option's (within the binomial interval); a mover at 5 cm/s is caught, taken by
// its track after, and not re-admitted while it stands for ten scans; a static map flags nothing;
// p_D learned per range bin falls with range; a landmark behind a nearer one is not expected; a miss
// below the detection floor changes nothing; float and double.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "firmware_lib/reloc/reloc_scene.hpp"
#include "geojcbb/ekf/detection.hpp"
#include "geojcbb/ekf/motion_test.hpp"
#include "geojcbb/node/slam_step.hpp"

using namespace geojcbb;
using geojcbb::test::observe_from;

namespace {

using B = DefaultBounds;
template <typename T>
using Rig = test::RelocRig<T, B>;

/// JCBB mapping as it goes, the motion test at 1e-5 per pairing.
template <typename T>
StepSettings<T> motion_settings() {
  StepSettings<T> s = test::reloc_settings<T>();
  s.augment = true;
  s.motion_false_alarm = 1e-5;
  return s;
}

/// A robot standing at x that has seen the map for 25 scans.
template <typename T>
std::unique_ptr<Rig<T>> standing_rig(const std::vector<Eigen::Vector2d>& map, const Pose2<double>& x,
                                     const StepSettings<T>& s) {
  auto rig = std::make_unique<Rig<T>>();
  REQUIRE(rig->step.configure(s) == Status::kOk);
  REQUIRE(rig->step.reset(Pose2<T>{T(x.x), T(x.y), T(x.theta)}, Vec3<T>(T(0.01), T(0.01), T(1e-4)).asDiagonal()) ==
          Status::kOk);
  for (int k = 0; k < 25; ++k) {
    observe_from(map, x, rig->obs);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
  }
  return rig;
}

/// The scan of `map` from x and one observation of the point p, last.
template <typename T>
void observe_with(const std::vector<Eigen::Vector2d>& map, const Pose2<double>& x, const Eigen::Vector2d& p,
                  Observations<T, B>& obs) {
  observe_from(map, x, obs);
  test::observe_point(x, p, obs, true);
}

}  // namespace

TEST_CASE_TEMPLATE("motion test: the false-alarm rate on white innovations is the option's", T, float, double) {
  // Landmarks of 200 pairings each, innovations drawn from their covariance: the statistic exceeds
  // -2 ln(p_FA) at a rate p_FA per pairing (chi-square, 2 dof, at every pairing).
  const double p_fa = 1e-3;
  const T threshold = ekf::motion_threshold<T>(p_fa);
  CHECK(std::abs(double(threshold) - 13.815510557964274) < 1e-4);
  std::mt19937_64 rng(42);
  std::normal_distribution<double> n01(0, 1);
  const int landmarks = 1000, pairings = 200;
  int fired = 0;
  for (int l = 0; l < landmarks; ++l) {
    ekf::MotionEvidence<T> m;
    m.clear();
    for (int k = 0; k < pairings; ++k) {
      // D = L L^T with a random shape each pairing (the geometry changes as the robot moves).
      const double a = 0.05 + 0.5 * std::abs(n01(rng)), b = 0.05 + 0.5 * std::abs(n01(rng)), c = 0.3 * n01(rng);
      const double e0 = n01(rng), e1 = n01(rng);
      const T d[2] = {T(a * e0), T(c * e0 + b * e1)};
      const T D[3] = {T(a * a), T(a * c), T(c * c + b * b)};
      fired += m.add(d, D) > threshold;
    }
  }
  const double N = double(landmarks) * pairings, mean = N * p_fa, sd = std::sqrt(N * p_fa * (1 - p_fa));
  MESSAGE("fired ", fired, " of ", N, " pairings (expected ", mean, ")");
  CHECK(std::abs(double(fired) - mean) <= 3.29 * sd + 1);  // the 99.9 % binomial interval
}

TEST_CASE_TEMPLATE("motion test: the world-frame innovation is G nu and G S G^T", T, float, double) {
  const Vec2<T> nu(T(0.2), T(-0.01));
  Mat2<T> S;
  S << T(0.04), T(0.001), T(0.001), T(4e-4);
  const T r = T(7), alpha = T(0.8);
  T d[2], D[3];
  REQUIRE(ekf::world_innovation(nu, S, r, alpha, d, D));
  Mat2<T> G;
  G << std::cos(alpha), -r * std::sin(alpha), std::sin(alpha), r * std::cos(alpha);
  const Vec2<T> dd = G * nu;
  const Mat2<T> DD = G * S * G.transpose();
  const T tol = sizeof(T) == 4 ? T(1e-5) : T(1e-12);
  CHECK(std::abs(d[0] - dd.x()) < tol);
  CHECK(std::abs(d[1] - dd.y()) < tol);
  CHECK(std::abs(D[0] - DD(0, 0)) < tol);
  CHECK(std::abs(D[1] - DD(0, 1)) < tol);
  CHECK(std::abs(D[2] - DD(1, 1)) < tol);
  CHECK(!ekf::world_innovation(nu, S, T(0), alpha, d, D));
}

TEST_CASE_TEMPLATE("motion test: a mover at 5 cm/s is caught, tracked, and not re-admitted when it stops", T, float,
                   double) {
  const auto map = test::reloc_map();
  const Pose2<double> x{0, 0, 0.3};
  auto rig = standing_rig<T>(map, x, motion_settings<T>());
  CHECK(rig->step.motion_movers().caught() == 0);  // a static map: nothing flagged
  const int mapped = rig->step.slam().landmarks();
  // Another robot 5 m ahead, one scan a second, walking at 5 cm/s across the view, then standing.
  const Eigen::Vector2d start(5 * std::cos(0.3), 5 * std::sin(0.3)), v(-0.05 * std::sin(0.3), 0.05 * std::cos(0.3));
  int caught_at = -1;
  Eigen::Vector2d at = start;
  for (int k = 0; k < 120; ++k) {
    const bool walking = caught_at < 0 || k < caught_at + 20;
    if (walking) at = start + v * k;
    observe_with(map, x, at, rig->obs);
    REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
    const int last = rig->obs.count - 1;
    if (caught_at < 0 && rig->out.review.movers > 0) {
      caught_at = k;
      CHECK(rig->out.outcome[last] == node::Outcome::kMover);
    } else if (caught_at >= 0 && k < caught_at + 30) {  // walking on, then standing for ten scans
      CHECK(rig->out.outcome[last] == node::Outcome::kMover);
      CHECK(rig->step.slam().landmarks() == mapped);
    }
    for (int i = 0; i < last; ++i) CHECK(rig->out.outcome[i] == node::Outcome::kPaired);  // the map is untouched
  }
  MESSAGE("mover caught after ", caught_at, " scans (", 0.05 * caught_at, " m moved)");
  CHECK(caught_at > 0);
  CHECK(caught_at < 60);
  CHECK(rig->step.motion_movers().caught() == 1);
}

TEST_CASE_TEMPLATE("detection: p_D learned per range bin falls with range; a miss below the floor is nothing", T, float,
                   double) {
  ekf::DetectionModel<T> m;
  m.reset(T(0.9), T(0.003), T(40));
  CHECK(std::abs(m.pd(T(5)) - T(0.9)) < T(1e-6));  // the prior before any sighting
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 3000; ++k) {  // near trees seen 80 % of the time, far ones 20 %
    m.sighting(T(7), u(rng) < 0.8);
    m.sighting(T(33), u(rng) < 0.2);
  }
  CHECK(m.pd(T(7)) > T(0.7));
  CHECK(m.pd(T(7)) < T(0.9));
  CHECK(m.pd(T(33)) < T(0.3));
  CHECK(m.bin(T(100)) == ekf::DetectionModel<T>::kDetectionBins - 1);

  // A landmark expected in view and missed: its log-odds falls with the floor at 0 and does not move
  // with the floor above p_D (0.9).
  const auto map = test::reloc_map();
  const Pose2<double> x{0, 0, 0.3};
  for (const float floor : {0.0f, 0.95f}) {
    StepSettings<T> s = motion_settings<T>();
    s.motion_false_alarm = 0;
    s.detection_floor = floor;
    auto rig = standing_rig<T>(map, x, s);
    std::vector<Eigen::Vector2d> less(map.begin() + 1, map.end());
    bool checked = false;
    for (int j = 0; j < rig->step.slam().landmarks() && !checked; ++j) {
      if ((rig->step.slam().landmark(j) - map[0].cast<T>()).norm() > T(0.01)) continue;
      const T before = rig->step.slam().existence(j);
      observe_from(less, x, rig->obs);
      REQUIRE(rig->step.step(rig->obs, rig->out) == Status::kOk);
      const int k = rig->step.slam().index_of(rig->step.slam().id(j));
      REQUIRE(k >= 0);
      if (floor > 0.9f) {
        CHECK(rig->step.slam().existence(k) == before);
      } else {
        CHECK(rig->step.slam().existence(k) < before);
      }
      checked = true;
    }
    if (!checked) MESSAGE("the first landmark is not in view from x: nothing to check");
  }
}

TEST_CASE_TEMPLATE("detection: a landmark behind a nearer one is not expected in view", T, float, double) {
  Prediction<T, B> pred;
  pred.count = 2;
  pred.id[0] = 0;
  pred.id[1] = 1;
  pred.h[0] = Vec2<T>(T(4), T(0.1));
  pred.h[1] = Vec2<T>(T(9), T(0.11));  // 0.01 rad behind the first
  ekf::Visibility<T> view;
  view.max_range_m = T(20);
  view.half_fov_rad = T(1.5);
  view.occlusion_rad = T(0.03);
  CHECK(ekf::in_view(pred, 0, view));
  CHECK(!ekf::in_view(pred, 1, view));
  view.occlusion_rad = T(0);
  CHECK(ekf::in_view(pred, 1, view));
}
