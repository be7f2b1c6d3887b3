// EKF-SLAM: motion Jacobians (velocity model, pose increment) against finite differences; the
// increment model against the velocity model it can express; predict_local's C against an explicit dense
// H P H^T; a noise-free run stays on the truth; NEES within its 95 % bounds over a seeded Monte Carlo
// run; bad input and capacity change no state; no allocation; a duplicate merged.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <type_traits>
#include <vector>

#include <Eigen/Dense>

#include "geojcbb/core/chi_square.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "support/alloc_counter.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::ekf;
using namespace geojcbb::test;

namespace {
using EB = Bounds<16, 24, 5, 1000, 40>;

template <typename T>
struct Fixture {
  Slam<T, EB> slam;
  ekf::SlamWorkspace<T, EB> ws;
  Observations<T, EB> obs;
  Association<T, EB> assoc;
  Prediction<T, EB> pred;
};

// A ring of landmarks, and a robot driving a circle inside it.
std::vector<Eigen::Vector2d> ring(int n, double radius) {
  std::vector<Eigen::Vector2d> l;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * kPi<double> * k / n;
    l.emplace_back(radius * std::cos(a), radius * std::sin(a));
  }
  return l;
}

struct RunResult {
  double pose_nees = 0;  ///< at the last step
  double max_pose_error = 0;
  bool ok = true;
};

// Drives `steps` odometry intervals; every step observes the landmarks within 7 m and +-90 deg,
// associates by ground truth, updates, and augments the first sightings.
template <typename T>
RunResult run(Fixture<T>& f, const std::vector<Eigen::Vector2d>& world, int steps, double noise_scale,
              std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  const double sv = 0.05, sw = 0.02, sr = 0.05, sb = 0.01;
  Pose2<double> truth{0, -4, 0};
  REQUIRE(f.slam.reset(Pose2<T>{T(truth.x), T(truth.y), T(truth.theta)}, Mat3<T>::Identity() * T(1e-9)) == Status::kOk);
  std::vector<int> id_of(world.size(), -1);
  RunResult res;
  for (int k = 0; k < steps; ++k) {
    Odometry<double> u{1.0, 0.25, 0.1, sv, sw};
    truth = move(truth, u);
    Odometry<T> un{T(u.v_mps + noise_scale * sv * g(rng)), T(u.w_radps + noise_scale * sw * g(rng)), T(u.dt_s), T(sv),
                   T(sw)};
    REQUIRE(f.slam.predict(un) == Status::kOk);
    f.obs.clear();
    std::vector<int> seen;
    for (std::size_t j = 0; j < world.size(); ++j) {
      Vec2<double> z = observe(truth, Vec2<double>(world[j]));
      if (z.x() > 7 || std::abs(z.y()) > kPi<double> / 2 || f.obs.count == EB::kMaxObservations) continue;
      z += Vec2<double>(noise_scale * sr * g(rng), noise_scale * sb * g(rng));
      REQUIRE(f.obs.push(z.cast<T>(), Mat2<T>(Vec2<T>(T(sr * sr), T(sb * sb)).asDiagonal())) == Status::kOk);
      seen.push_back(static_cast<int>(j));
    }
    f.assoc.count = f.obs.count;
    for (int i = 0; i < f.obs.count; ++i) f.assoc.feature[i] = id_of[seen[i]] >= 0 ? id_of[seen[i]] : kNewFeature;
    REQUIRE(f.slam.update(f.obs, f.assoc, f.ws) == Status::kOk);
    for (int i = 0; i < f.obs.count; ++i) {
      if (f.assoc.feature[i] != kNewFeature) continue;
      FeatureId id = -1;
      REQUIRE(f.slam.augment(f.obs.z[i], f.obs.R[i], id) == Status::kOk);
      id_of[seen[i]] = id;
    }
    const Pose2<T> e = f.slam.pose();
    const Eigen::Vector3d err(static_cast<double>(e.x) - truth.x, static_cast<double>(e.y) - truth.y,
                              wrap_angle(static_cast<double>(e.theta) - truth.theta));
    res.max_pose_error = std::max(res.max_pose_error, err.head<2>().norm());
    Eigen::Matrix3d P;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) P(r, c) = static_cast<double>(f.slam.cov(r, c));
    res.pose_nees = err.dot(P.ldlt().solve(err));
  }
  return res;
}
}  // namespace

TEST_CASE("motion model: Jacobians equal central finite differences") {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-2, 2);
  const double h = 1e-6;
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2<double> x{u(rng), u(rng), wrap_angle(u(rng))};
    const Odometry<double> od{u(rng), u(rng), 0.05 + std::abs(u(rng)) * 0.1, 0.1, 0.1};
    Mat3<double> Jx;
    Mat32<double> Ju;
    move(x, od, &Jx, &Ju);
    auto diff = [&](const Pose2<double>& a, const Pose2<double>& b) {
      return Vec3<double>((a.x - b.x) / (2 * h), (a.y - b.y) / (2 * h), wrap_angle(a.theta - b.theta) / (2 * h));
    };
    for (int k = 0; k < 3; ++k) {
      Pose2<double> a = x, b = x;
      (k == 0 ? a.x : k == 1 ? a.y : a.theta) += h;
      (k == 0 ? b.x : k == 1 ? b.y : b.theta) -= h;
      CHECK((diff(move(a, od), move(b, od)) - Jx.col(k)).norm() < 1e-6);
    }
    for (int k = 0; k < 2; ++k) {
      Odometry<double> a = od, b = od;
      (k == 0 ? a.v_mps : a.w_radps) += h;
      (k == 0 ? b.v_mps : b.w_radps) -= h;
      CHECK((diff(move(x, a), move(x, b)) - Ju.col(k)).norm() < 1e-6);
    }
  }
}

TEST_CASE_TEMPLATE("predict_local: C equals an explicit dense H P H^T; the region keeps the nearest", T, float,
                   double) {
  auto f = std::make_unique<Fixture<T>>();
  const auto world = ring(30, 6.0);
  run(*f, world, 40, 1.0, 3);
  LocalMapStats st;
  REQUIRE(f->slam.predict_local(T(100), f->ws, f->pred, st) == Status::kOk);
  const int n = f->pred.count;
  REQUIRE(n == std::min(f->slam.landmarks(), EB::kMaxCandidates));
  CHECK(st.truncated == (f->slam.landmarks() > EB::kMaxCandidates));
  const int d = f->slam.dim();
  Eigen::MatrixXd P(d, d), H = Eigen::MatrixXd::Zero(2 * n, d);
  for (int r = 0; r < d; ++r)
    for (int c = 0; c < d; ++c) P(r, c) = static_cast<double>(f->slam.cov(r, c));
  const Pose2<T> x = f->slam.pose();
  const Pose2<double> xd{double(x.x), double(x.y), double(x.theta)};
  double prev = 0;
  for (int a = 0; a < n; ++a) {
    Mat23<double> Jp;
    Mat2<double> Jl;
    const int j = f->slam.index_of(f->pred.id[a]);
    const Vec2<double> h = observe(xd, Vec2<double>(f->slam.landmark(j).template cast<double>()));
    // H at the filter's linearisation point (the first estimate with FEJ, the default).
    observe(xd, Vec2<double>(f->slam.linearisation_point(j).template cast<double>()), &Jp, &Jl);
    CHECK(h.x() >= prev);  // nearest first
    prev = h.x();
    H.block<2, 3>(2 * a, 0) = Jp;
    H.block<2, 2>(2 * a, Layout::landmark(f->pred.id[a])) = Jl;
    CHECK((f->pred.h[a].template cast<double>() - h).norm() < 1e-4);
  }
  const Eigen::MatrixXd C = H * P * H.transpose();
  const double tol = std::is_same<T, float>::value ? 1e-4 : 1e-10;
  Eigen::MatrixXd packed(C.rows(), C.cols());
  REQUIRE(f->pred.C.rows() == C.rows());
  for (int r = 0; r < C.rows(); ++r)
    for (int c = 0; c < C.cols(); ++c) packed(r, c) = static_cast<double>(f->pred.C(r, c));
  CHECK((packed - C).norm() <= tol * (1 + C.norm()));
  REQUIRE(f->slam.predict_local(T(3), f->ws, f->pred, st) == Status::kOk);
  for (int a = 0; a < f->pred.count; ++a) CHECK(f->pred.h[a].x() < T(3));
}

TEST_CASE_TEMPLATE(
    "predict_local: a region over the candidates keeps those the sensor can see; behind ones make room first", T, float,
    double) {
  using CB = Bounds<5, 4, 5, 1000, 21>;  // 4 candidates
  auto s = std::make_unique<Slam<T, CB>>();
  auto ws = std::make_unique<SlamWorkspace<T, CB>>();
  auto pred = std::make_unique<Prediction<T, CB>>();
  REQUIRE(s->reset(Pose2<T>{0, 0, 0}, Mat3<T>::Identity() * T(1e-4)) == Status::kOk);
  // Facing +x: three behind (nearest), one abeam, four ahead.
  const T pts[8][2] = {{-2, 0}, {-2, 1}, {-2, -1}, {0, 3}, {5, 0}, {5, 2}, {6, -1}, {7, 0}};
  FeatureId id[8];
  for (int k = 0; k < 8; ++k)
    REQUIRE(s->add_known_landmark(Vec2<T>(pts[k][0], pts[k][1]), Mat2<T>::Identity() * T(0.01), id[k]) == Status::kOk);
  LocalMapStats st;
  auto ids = [&]() { return std::vector<FeatureId>(pred->id.begin(), pred->id.begin() + pred->count); };
  // A sensor that sees all round (the default): the nearest four.
  REQUIRE(s->predict_local(T(30), *ws, *pred, st) == Status::kOk);
  CHECK(st.truncated);
  CHECK(ids() == std::vector<FeatureId>{id[0], id[1], id[2], id[3]});
  // A 180-degree sensor: a landmark nearer the back than the edge of view (|bearing| > 135 deg) makes
  // room for the nearest in view; the kept ones nearest first.
  REQUIRE(s->predict_local(T(30), *ws, *pred, st, false, T(kPi<double> / 2)) == Status::kOk);
  CHECK(ids() == std::vector<FeatureId>{id[3], id[4], id[5], id[6]});
  // Not over the candidates: every landmark of the region, nearest first, behind ones included.
  REQUIRE(s->predict_local(T(4), *ws, *pred, st, false, T(kPi<double> / 2)) == Status::kOk);
  CHECK(!st.truncated);
  CHECK(ids() == std::vector<FeatureId>{id[0], id[1], id[2], id[3]});
  CHECK(pred->h[0].x() == doctest::Approx(2.0));
  // A half field of view outside (0, pi] is refused.
  CHECK(s->predict_local(T(30), *ws, *pred, st, false, T(0)) == Status::kInvalidInput);
  CHECK(s->predict_local(T(30), *ws, *pred, st, false, T(4)) == Status::kInvalidInput);
  CHECK(s->predict_local(T(30), *ws, *pred, st, false, std::numeric_limits<T>::quiet_NaN()) == Status::kInvalidInput);
}

TEST_CASE_TEMPLATE("a noise-free run stays on the truth; P stays symmetric", T, float, double) {
  auto f = std::make_unique<Fixture<T>>();
  const RunResult r = run(*f, ring(24, 6.0), 260, 0.0, 1);  // more than one lap: loop closure
  CHECK(r.max_pose_error < (std::is_same<T, float>::value ? 1e-3 : 1e-9));
  const int d = f->slam.dim();
  for (int i = 0; i < d; ++i) {
    CHECK(f->slam.cov(i, i) > T(0));
    for (int j = 0; j < i; ++j) CHECK(f->slam.cov(i, j) == f->slam.cov(j, i));
  }
}

// Diagnostic (skipped; run with --no-skip -tc="probe*"): EKF-SLAM's known inconsistency grows with
// time (heading information gained through Jacobians at estimates). Measured, 200 runs each:
// 5 steps 3.10, 20 steps 2.97, 80 steps 3.14, 160 steps 3.30 (3 is consistent).
TEST_CASE("probe: NEES against run length" * doctest::skip(true)) {
  for (int steps : {5, 10, 20, 40, 80, 160}) {
    double sum = 0;
    for (int k = 0; k < 200; ++k) {
      auto f = std::make_unique<Fixture<double>>();
      sum += run(*f, ring(24, 6.0), steps, 1.0, 100 + k).pose_nees;
    }
    MESSAGE("steps " << steps << ": mean pose NEES " << sum / 200);
  }
}

TEST_CASE("NEES of the pose over a seeded Monte Carlo run lies within its 95 % bounds") {
  // 200 runs of 80 steps with true association: the NEES at the last step averaged over runs, whose
  // sum is chi-square with 3 x 200 degrees of freedom for a consistent filter.
  constexpr int kRuns = 200;
  double sum = 0;
  for (int k = 0; k < kRuns; ++k) {
    auto f = std::make_unique<Fixture<double>>();
    sum += run(*f, ring(24, 6.0), 80, 1.0, 100 + k).pose_nees;
  }
  double lo = 0, hi = 0;
  REQUIRE(chi2_inv(0.025, 3 * kRuns, lo) == Status::kOk);
  REQUIRE(chi2_inv(0.975, 3 * kRuns, hi) == Status::kOk);
  const double mean = sum / kRuns;
  MESSAGE("mean pose NEES " << mean << ", 95 % bounds [" << lo / kRuns << ", " << hi / kRuns << "]");
  CHECK(mean >= lo / kRuns);
  CHECK(mean <= hi / kRuns);
}

TEST_CASE_TEMPLATE("bad input and a full map change no state", T, float, double) {
  auto f = std::make_unique<Fixture<T>>();
  run(*f, ring(24, 6.0), 30, 1.0, 9);
  auto snapshot = std::make_unique<Slam<T, EB>>(f->slam);
  auto same = [&] { return std::memcmp(snapshot.get(), &f->slam, sizeof(f->slam)) == 0; };
  const T nan = std::numeric_limits<T>::quiet_NaN();
  CHECK(f->slam.predict(Odometry<T>{nan, T(0), T(0.1), T(0.1), T(0.1)}) == Status::kNonFinite);
  CHECK(f->slam.predict(Odometry<T>{T(1), T(0), T(-0.1), T(0.1), T(0.1)}) == Status::kInvalidInput);
  FeatureId id = 99;
  CHECK(f->slam.augment(Vec2<T>(nan, T(0)), Mat2<T>::Identity(), id) == Status::kNonFinite);
  CHECK(f->slam.augment(Vec2<T>(T(1), T(0)), Mat2<T>::Zero(), id) == Status::kNotPositiveDefinite);
  CHECK(id == 99);
  f->obs.clear();
  REQUIRE(f->obs.push(Vec2<T>(T(3), T(0.1)), Mat2<T>::Identity() * T(0.01)) == Status::kOk);
  f->assoc.count = 1;
  f->assoc.feature[0] = f->slam.landmarks();  // no such landmark
  CHECK(f->slam.update(f->obs, f->assoc, f->ws) == Status::kInvalidInput);
  f->assoc.feature[0] = 0;
  f->obs.R[0](0, 0) = -1;
  CHECK(f->slam.update(f->obs, f->assoc, f->ws) == Status::kNotPositiveDefinite);
  f->assoc.count = 2;
  CHECK(f->slam.update(f->obs, f->assoc, f->ws) == Status::kInvalidInput);
  CHECK(f->slam.predict_local(T(-1), f->ws, f->pred, *std::make_unique<LocalMapStats>()) == Status::kInvalidInput);
  CHECK(same());
  // Fill the map, then one more.
  while (f->slam.landmarks() < EB::kMaxLandmarks) {
    REQUIRE(f->slam.augment(Vec2<T>(T(2), T(0.3)), Mat2<T>::Identity() * T(0.01), id) == Status::kOk);
  }
  CHECK(id == EB::kMaxLandmarks - 1);
  *snapshot = f->slam;
  CHECK(f->slam.augment(Vec2<T>(T(2), T(0.3)), Mat2<T>::Identity() * T(0.01), id) == Status::kCapacityExceeded);
  CHECK(same());
}

TEST_CASE_TEMPLATE("the filter allocates nothing", T, float, double) {
  auto f = std::make_unique<Fixture<T>>();
  run(*f, ring(24, 6.0), 20, 1.0, 4);
  LocalMapStats st;
  FeatureId id;
  f->assoc.count = f->obs.count;
  for (int i = 0; i < f->obs.count; ++i) f->assoc.feature[i] = i < f->slam.landmarks() ? i : kNewFeature;
  Status s1, s2, s3, s4, s5;
  ReviewStats rs;
  const Visibility<T> view{T(0.5), T(7), T(1.5)};
  LandmarkPolicy strict;
  strict.delete_nats = -1.0f;  // one miss removes a new landmark
  CHECK(allocations_during([&] {
          s1 = f->slam.predict(Odometry<T>{T(1), T(0.1), T(0.1), T(0.05), T(0.02)});
          s2 = f->slam.predict_local(T(8), f->ws, f->pred, st);
          s3 = f->slam.update(f->obs, f->assoc, f->ws);
          s4 = f->slam.augment(Vec2<T>(T(2), T(0.3)), Mat2<T>::Identity() * T(0.01), id);
          s5 = f->slam.review(f->obs, f->pred, f->assoc, view, strict, rs);
        }) == 0);
  CHECK(s1 == Status::kOk);
  CHECK(s2 == Status::kOk);
  CHECK(s3 == Status::kOk);
  CHECK(s4 == Status::kOk);
  CHECK(s5 == Status::kOk);
}

// One landmark mapped twice: first from a sure pose, then again after the pose drifted (the filter
// believes odometry that was wrong, with an honest covariance). Merged, the constraint carries the
// correction to the pose through the duplicate's correlation with it.
TEST_CASE_TEMPLATE("merge: a duplicate fused into the landmark it repeats; ids stable, P definite, pose corrected", T,
                   float, double) {
  auto f = std::make_unique<Fixture<T>>();
  REQUIRE(f->slam.reset(Pose2<T>{T(0), T(0), T(0)}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
  const Eigen::Vector2d world[3] = {{6, 1}, {4, -3}, {9, 4}};  // landmark 0 is mapped twice
  Mat2<T> R;
  R << T(0.0025), T(0), T(0), T(1e-4);
  auto z_from = [](const Pose2<double>& x, const Eigen::Vector2d& l) -> Vec2<T> {
    const Vec2<double> z = observe(x, Vec2<double>(l));
    return z.cast<T>();
  };
  FeatureId id = -1;
  const Pose2<double> start{0, 0, 0};
  for (int j = 0; j < 3; ++j) {
    REQUIRE(f->slam.augment(z_from(start, world[j]), R, id) == Status::kOk);
    REQUIRE(id == j);
  }
  // The robot drives 2 m straight; the odometry says 2.4 m (the filter's pose is 0.4 m off, and unsure).
  for (int k = 0; k < 10; ++k) {
    REQUIRE(f->slam.predict(Odometry<T>{T(2.4), T(0), T(0.1), T(1), T(0.01)}) == Status::kOk);
  }
  const Pose2<double> truth{2, 0, 0};
  REQUIRE(f->slam.augment(z_from(truth, world[0]), R, id) == Status::kOk);  // the duplicate, id 3
  REQUIRE(id == 3);
  auto pose_error = [&] {
    const Pose2<T> e = f->slam.pose();
    return std::hypot(double(e.x) - truth.x, double(e.y) - truth.y);
  };
  const double error_before = pose_error();
  REQUIRE(error_before > 0.3);
  // Duplicates are close in their own uncertainty, distinct landmarks are not.
  CHECK(f->slam.duplicate_d2(0, 3) < T(9.21));
  CHECK(f->slam.duplicate_d2(0, 1) > T(100));
  CHECK(f->slam.duplicate_d2(1, 3) > T(100));
  CHECK(std::isinf(f->slam.duplicate_d2(0, 0)));
  CHECK(std::isinf(f->slam.duplicate_d2(0, 4)));
  // Bad input changes nothing.
  auto snapshot = std::make_unique<Slam<T, EB>>(f->slam);
  auto same = [&] { return std::memcmp(snapshot.get(), &f->slam, sizeof(f->slam)) == 0; };
  CHECK(f->slam.merge(0, 0, f->ws) == Status::kInvalidInput);
  CHECK(f->slam.merge(-1, 3, f->ws) == Status::kInvalidInput);
  CHECK(f->slam.merge(0, 4, f->ws) == Status::kInvalidInput);
  CHECK(same());
  Status st = Status::kNoConvergence;
  CHECK(allocations_during([&] { st = f->slam.merge(0, 3, f->ws); }) == 0);
  REQUIRE(st == Status::kOk);
  REQUIRE(f->slam.landmarks() == 3);
  for (int j = 0; j < 3; ++j) CHECK(f->slam.id(j) == j);
  CHECK(f->slam.index_of(3) == -1);
  CHECK(f->slam.hits(0) == 2);  // its sightings and the duplicate's
  CHECK((f->slam.landmark(0).template cast<double>() - world[0]).norm() < 0.05);
  CHECK(pose_error() < 0.25 * error_before);
  Eigen::MatrixXd P(f->slam.dim(), f->slam.dim());
  for (int r = 0; r < f->slam.dim(); ++r)
    for (int c = 0; c < f->slam.dim(); ++c) P(r, c) = double(f->slam.cov(r, c));
  CHECK(P.isApprox(P.transpose()));
  CHECK(Eigen::LLT<Eigen::MatrixXd>(P).info() == Eigen::Success);
  // A new landmark still gets a fresh id, never the merged one.
  REQUIRE(f->slam.augment(z_from(truth, world[1]), R, id) == Status::kOk);
  CHECK(id == 4);
}

// Landmark bookkeeping: five landmarks ahead of the robot; the association pairs some of them.
TEST_CASE_TEMPLATE("review removes tentative landmarks that are missed, and keeps ids stable", T, float, double) {
  auto f = std::make_unique<Fixture<T>>();
  REQUIRE(f->slam.reset(Pose2<T>{T(0), T(0), T(0)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  FeatureId id = -1;
  for (int k = 0; k < 5; ++k) {
    REQUIRE(f->slam.augment(Vec2<T>(T(2 + k), T(0.2) * T(k - 2)), Mat2<T>::Identity() * T(0.01), id) == Status::kOk);
    CHECK(id == k);
  }
  LocalMapStats st;
  REQUIRE(f->slam.predict_local(T(20), f->ws, f->pred, st) == Status::kOk);
  REQUIRE(f->pred.count == 5);
  const Visibility<T> view{T(0.5), T(10), T(1.5)};
  LandmarkPolicy policy;  // the default: a pairing confirms, two misses remove a new landmark
  // Scan 1: landmarks 0, 2 and 4 paired (confirmed); 1 and 3 missed once.
  const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.05 * 0.05), T(0.01 * 0.01)).asDiagonal());
  f->obs.clear();
  for (int i = 0; i < 3; ++i) REQUIRE(f->obs.push(Vec2<T>(T(3), T(0)), R) == Status::kOk);  // z is not read
  f->assoc.count = 3;
  f->assoc.feature[0] = 4;
  f->assoc.feature[1] = 0;
  f->assoc.feature[2] = 2;
  ReviewStats rs;
  REQUIRE(f->slam.review(f->obs, f->pred, f->assoc, view, policy, rs) == Status::kOk);
  CHECK(rs.expected == 5);
  CHECK(rs.paired == 3);
  CHECK(rs.confirmed == 3);
  CHECK(rs.removed == 0);
  CHECK(f->slam.landmarks() == 5);
  // Scan 2: nothing paired: 1 and 3 reach two misses and go; 0, 2, 4 are confirmed and stay.
  auto before = std::make_unique<Slam<T, EB>>(f->slam);
  f->assoc.count = 0;
  f->obs.clear();
  REQUIRE(f->slam.review(f->obs, f->pred, f->assoc, view, policy, rs) == Status::kOk);
  CHECK(rs.removed == 2);
  REQUIRE(f->slam.landmarks() == 3);
  const int kept[3] = {0, 2, 4};
  for (int k = 0; k < 3; ++k) {
    CHECK(f->slam.id(k) == kept[k]);
    CHECK(f->slam.index_of(kept[k]) == k);
    CHECK(f->slam.landmark(k) == before->landmark(kept[k]));
  }
  CHECK(f->slam.index_of(1) == -1);
  CHECK(f->slam.index_of(3) == -1);
  CHECK(f->slam.index_of(5) == -1);
  // The covariance is the old one with the removed rows and columns deleted, exactly.
  auto old_row = [](int r) { return r < 3 ? r : Layout::landmark(2 * ((r - 3) / 2)) + (r - 3) % 2; };
  for (int r = 0; r < f->slam.dim(); ++r) {
    CHECK(f->slam.x(r) == before->x(old_row(r)));
    for (int c = 0; c < f->slam.dim(); ++c) CHECK(f->slam.cov(r, c) == before->cov(old_row(r), old_row(c)));
  }
  // A new landmark gets a fresh id, never a removed one; update() speaks ids.
  REQUIRE(f->slam.augment(Vec2<T>(T(3), T(0.1)), Mat2<T>::Identity() * T(0.01), id) == Status::kOk);
  CHECK(id == 5);
  CHECK(f->slam.index_of(5) == 3);
  f->obs.clear();
  REQUIRE(f->obs.push(Vec2<T>(T(6), T(0.4)), Mat2<T>::Identity() * T(0.01)) == Status::kOk);
  f->assoc.count = 1;
  f->assoc.feature[0] = 3;  // removed
  CHECK(f->slam.update(f->obs, f->assoc, f->ws) == Status::kInvalidInput);
  f->assoc.feature[0] = 4;
  CHECK(f->slam.update(f->obs, f->assoc, f->ws) == Status::kOk);
}

TEST_CASE_TEMPLATE("review: out of view is no miss; unconfirmed for too long is removed; bad input changes nothing", T,
                   float, double) {
  auto f = std::make_unique<Fixture<T>>();
  REQUIRE(f->slam.reset(Pose2<T>{T(0), T(0), T(0)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  FeatureId id = -1;
  REQUIRE(f->slam.augment(Vec2<T>(T(4), T(0)), Mat2<T>::Identity() * T(0.01), id) == Status::kOk);    // ahead
  REQUIRE(f->slam.augment(Vec2<T>(T(4), T(2.5)), Mat2<T>::Identity() * T(0.01), id) == Status::kOk);  // behind
  LocalMapStats st;
  REQUIRE(f->slam.predict_local(T(20), f->ws, f->pred, st) == Status::kOk);
  const Visibility<T> view{T(0.5), T(10), T(1.5)};
  LandmarkPolicy policy;
  policy.max_tentative_reviews = 4;
  f->obs.clear();
  REQUIRE(f->obs.push(Vec2<T>(T(4), T(0)), Mat2<T>(Vec2<T>(T(0.05 * 0.05), T(0.01 * 0.01)).asDiagonal())) ==
          Status::kOk);
  f->assoc.count = 1;
  f->assoc.feature[0] = 0;  // the one ahead is paired: confirmed
  ReviewStats rs;
  for (int k = 0; k < 3; ++k) {
    REQUIRE(f->slam.review(f->obs, f->pred, f->assoc, view, policy, rs) == Status::kOk);
    CHECK(rs.expected == 1);
    CHECK(f->slam.landmarks() == 2);  // out of view: no misses, not yet too old
  }
  REQUIRE(f->slam.review(f->obs, f->pred, f->assoc, view, policy, rs) == Status::kOk);
  CHECK(rs.removed == 1);  // fourth review: tentative for too long
  REQUIRE(f->slam.landmarks() == 1);
  CHECK(f->slam.id(0) == 0);
  // Bad input: nothing changes.
  auto snapshot = std::make_unique<Slam<T, EB>>(f->slam);
  auto same = [&] { return std::memcmp(snapshot.get(), &f->slam, sizeof(f->slam)) == 0; };
  LandmarkPolicy bad;
  bad.confirm_nats = 0.0f;
  CHECK(f->slam.review(f->obs, f->pred, f->assoc, view, bad, rs) == Status::kInvalidInput);
  CHECK(f->slam.review(f->obs, f->pred, f->assoc, Visibility<T>{T(5), T(1), T(1)}, policy, rs) ==
        Status::kInvalidInput);
  CHECK(f->slam.review(f->obs, f->pred, f->assoc, Visibility<T>{T(0), std::numeric_limits<T>::infinity(), T(1)}, policy,
                       rs) == Status::kInvalidInput);
  f->assoc.count = EB::kMaxObservations + 1;
  CHECK(f->slam.review(f->obs, f->pred, f->assoc, view, policy, rs) == Status::kInvalidInput);
  CHECK(same());
}

// The SLAM step the device loop and the evaluation share: refuses to run unconfigured or with a bad
// configuration (no state change), reports what became of each observation, allocates nothing.
TEST_CASE_TEMPLATE("SlamStep: configuration, outcomes, no allocation", T, float, double) {
  using SB = Bounds<16, 24, 5, 1000, 40>;
  auto s = std::make_unique<node::SlamStep<T, SB>>();
  Observations<T, SB> obs;
  auto res = std::make_unique<node::StepResult<T, SB>>();
  REQUIRE(obs.push(Vec2<T>(T(4), T(0.1)), Mat2<T>(Vec2<T>(T(0.01), T(0.0003)).asDiagonal())) == Status::kOk);
  CHECK(s->step(obs, *res) == Status::kInvalidInput);  // not configured
  node::StepSettings<T> bad;
  bad.local_radius_m = T(0);
  CHECK(s->configure(bad) == Status::kInvalidInput);
  CHECK(!s->configured());
  node::StepSettings<T> ok;
  ok.local_radius_m = T(15);
  ok.min_range_m = T(0.5);
  ok.max_range_m = T(10);
  ok.half_fov_rad = T(1.4);
  REQUIRE(s->configure(ok) == Status::kOk);
  REQUIRE(s->reset(Pose2<T>{T(0), T(0), T(0)}, Mat3<T>::Identity() * T(1e-4)) == Status::kOk);
  // First scan: the map is empty, so the observation becomes landmark 0; the second scan pairs it.
  REQUIRE(s->step(obs, *res) == Status::kOk);
  CHECK(res->outcome[0] == node::Outcome::kNewLandmark);
  CHECK(res->feature[0] == 0);
  Status st = Status::kNoConvergence;
  CHECK(allocations_during([&] { st = s->step(obs, *res); }) == 0);
  CHECK(st == Status::kOk);
  CHECK(res->outcome[0] == node::Outcome::kPaired);
  CHECK(res->feature[0] == 0);
  CHECK(s->slam().landmarks() == 1);
  CHECK(s->slam().hits(0) == 2);  // confirmed by the second pairing
}

// Found by tests/fuzz/fuzz_associate: a finite range near the scalar's max overflowed the new
// landmark's covariance, and augment() returned kOk with Inf in P.
TEST_CASE_TEMPLATE("augment: a range that would overflow the state is refused, nothing changed", T, float, double) {
  auto s = std::make_unique<Slam<T, EB>>();
  Mat3<T> P0 = Mat3<T>::Identity() * T(0.01);
  REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.3)}, P0) == Status::kOk);
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  FeatureId id = 77;
  REQUIRE(s->augment(Vec2<T>(T(3), T(0.4)), R, id) == Status::kOk);
  std::vector<unsigned char> before(sizeof(*s));  // bytes, padding included
  std::memcpy(before.data(), static_cast<const void*>(s.get()), sizeof(*s));
  id = 77;
  CHECK(s->augment(Vec2<T>(std::numeric_limits<T>::max() / T(4), T(0.4)), R, id) == Status::kNonFinite);
  CHECK(id == 77);
  CHECK(std::memcmp(static_cast<const void*>(s.get()), before.data(), sizeof(*s)) == 0);
  CHECK(s->landmarks() == 1);
  for (int r = 0; r < s->dim(); ++r)
    for (int c = 0; c < s->dim(); ++c) CHECK(std::isfinite(s->cov(r, c)));
}

// Found by tests/fuzz/fuzz_associate: finite odometry whose sigma squared overflows gave an Inf
// pose covariance, and predict() returned kOk.
TEST_CASE("pose increment: compose's Jacobians equal central finite differences") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2, 2);
  const double h = 1e-6;
  auto diff = [&](const Pose2<double>& a, const Pose2<double>& b) {
    return Vec3<double>((a.x - b.x) / (2 * h), (a.y - b.y) / (2 * h), wrap_angle(a.theta - b.theta) / (2 * h));
  };
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2<double> x{u(rng), u(rng), wrap_angle(u(rng))};
    PoseIncrement<double> d;
    d.dx_m = u(rng);
    d.dy_m = 0.3 * u(rng);
    d.dtheta_rad = 0.5 * u(rng);
    Mat3<double> Jx, Ju;
    compose(x, d, &Jx, &Ju);
    for (int k = 0; k < 3; ++k) {
      Pose2<double> a = x, b = x;
      (k == 0 ? a.x : k == 1 ? a.y : a.theta) += h;
      (k == 0 ? b.x : k == 1 ? b.y : b.theta) -= h;
      CHECK((diff(compose(a, d), compose(b, d)) - Jx.col(k)).norm() < 1e-6);
      PoseIncrement<double> p = d, q = d;
      (k == 0 ? p.dx_m : k == 1 ? p.dy_m : p.dtheta_rad) += h;
      (k == 0 ? q.dx_m : k == 1 ? q.dy_m : q.dtheta_rad) -= h;
      CHECK((diff(compose(x, p), compose(x, q)) - Ju.col(k)).norm() < 1e-6);
    }
  }
}

TEST_CASE_TEMPLATE("predict: a pose increment equal to the velocity model's gives its pose and covariance", T, float,
                   double) {
  // The velocity model's interval as an increment in the robot's frame: d = v dt along the midpoint
  // heading, its covariance G Q G^T rotated into the robot's frame.
  auto a = std::make_unique<Slam<T, EB>>();
  auto b = std::make_unique<Slam<T, EB>>();
  Mat3<T> P0;
  P0 << T(0.04), T(0.01), T(0.002), T(0.01), T(0.09), T(-0.003), T(0.002), T(-0.003), T(0.01);
  for (auto* s : {a.get(), b.get()}) {
    REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.3)}, P0) == Status::kOk);
    Mat2<T> R;
    R << T(0.01), T(0), T(0), T(3e-4);
    FeatureId id = 0;
    REQUIRE(s->augment(Vec2<T>(T(3), T(0.4)), R, id) == Status::kOk);
  }
  const Odometry<T> od{T(0.8), T(0.3), T(0.5), T(0.05), T(0.02)};
  Mat3<T> F;
  Mat32<T> G;
  const Pose2<T> x = a->pose();
  move(x, od, &F, &G);
  const Mat2<T> Q = Vec2<T>(od.sigma_v_mps * od.sigma_v_mps, od.sigma_w_radps * od.sigma_w_radps).asDiagonal();
  Mat3<T> Rt = Mat3<T>::Identity();  // world -> robot frame at the start
  Rt.template topLeftCorner<2, 2>() << std::cos(x.theta), std::sin(x.theta), -std::sin(x.theta), std::cos(x.theta);
  PoseIncrement<T> d;
  const T half = T(0.5) * od.w_radps * od.dt_s, dist = od.v_mps * od.dt_s;
  d.dx_m = dist * std::cos(half);
  d.dy_m = dist * std::sin(half);
  d.dtheta_rad = od.w_radps * od.dt_s;
  d.cov = Rt * G * Q * G.transpose() * Rt.transpose();
  d.cov = T(0.5) * (d.cov + d.cov.transpose());
  REQUIRE(a->predict(od) == Status::kOk);
  REQUIRE(b->predict(d) == Status::kOk);
  const T tol = std::is_same<T, float>::value ? T(2e-6) : T(1e-12);
  CHECK(std::abs(a->pose().x - b->pose().x) < tol);
  CHECK(std::abs(a->pose().y - b->pose().y) < tol);
  CHECK(std::abs(a->pose().theta - b->pose().theta) < tol);
  for (int r = 0; r < a->dim(); ++r) {
    for (int c = 0; c < a->dim(); ++c) CHECK(std::abs(a->cov(r, c) - b->cov(r, c)) < tol);
  }
}

TEST_CASE_TEMPLATE("predict: a bad pose increment is refused, nothing changed; none allocates", T, float, double) {
  auto s = std::make_unique<Slam<T, EB>>();
  REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.3)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  std::vector<unsigned char> before(sizeof(*s));
  std::memcpy(before.data(), static_cast<const void*>(s.get()), sizeof(*s));
  PoseIncrement<T> d;
  d.dx_m = T(0.5);
  d.cov = Vec3<T>(T(1e-4), T(1e-4), T(1e-5)).asDiagonal();
  PoseIncrement<T> bad = d;
  bad.dy_m = std::numeric_limits<T>::quiet_NaN();
  CHECK(s->predict(bad) == Status::kNonFinite);
  bad = d;
  bad.cov(0, 1) = T(1e-3);  // not symmetric
  CHECK(s->predict(bad) == Status::kNotPositiveDefinite);
  bad.cov(1, 0) = T(1e-3);  // symmetric, but |correlation| 10: indefinite
  CHECK(s->predict(bad) == Status::kNotPositiveDefinite);
  bad = d;
  bad.cov(2, 2) = T(-1e-6);
  CHECK(s->predict(bad) == Status::kNotPositiveDefinite);
  bad = d;
  bad.cov(0, 0) = std::numeric_limits<T>::infinity();
  CHECK(s->predict(bad) == Status::kNonFinite);
  CHECK(std::memcmp(static_cast<const void*>(s.get()), before.data(), sizeof(*s)) == 0);
  PoseIncrement<T> exact;  // a zero covariance: an exact increment
  exact.dx_m = T(0.1);
  Status st = Status::kNoConvergence;
  CHECK(allocations_during([&] { st = s->predict(d); }) == 0);
  CHECK(st == Status::kOk);
  CHECK(s->predict(exact) == Status::kOk);
  CHECK(std::abs(double(s->pose().x) - (1 + 0.6 * std::cos(0.3))) < 1e-5);
}

TEST_CASE_TEMPLATE("predict: odometry that would overflow the covariance is refused, nothing changed", T, float,
                   double) {
  auto s = std::make_unique<Slam<T, EB>>();
  REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.3)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  FeatureId id = 0;
  REQUIRE(s->augment(Vec2<T>(T(3), T(0.4)), R, id) == Status::kOk);
  std::vector<unsigned char> before(sizeof(*s));  // bytes, padding included
  std::memcpy(before.data(), static_cast<const void*>(s.get()), sizeof(*s));
  const T huge = std::numeric_limits<T>::max() / T(4);
  CHECK(s->predict(Odometry<T>{T(0.5), T(0.1), T(0.1), huge, T(0.01)}) == Status::kNonFinite);
  CHECK(s->predict(Odometry<T>{huge, T(0.1), T(1), T(0.05), T(0.01)}) == Status::kNonFinite);
  CHECK(std::memcmp(static_cast<const void*>(s.get()), before.data(), sizeof(*s)) == 0);
  CHECK(s->predict(Odometry<T>{T(0.5), T(0.1), T(0.1), T(0.05), T(0.01)}) == Status::kOk);
}

// Found by tests/fuzz/fuzz_associate: a finite sigma whose square is finite (1e17 in float: 1e34)
// swamps the pose's own covariance; x and y, both driven by the one sigma_v, become fully
// correlated by rounding, and predict() returned kOk with a pose block that is not positive
// definite. The check is scale-free (the correlation matrix), so it cannot overflow either.
TEST_CASE_TEMPLATE("predict: odometry that would leave the pose block singular is refused, nothing changed", T, float,
                   double) {
  auto s = std::make_unique<Slam<T, EB>>();
  REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.7)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  std::vector<unsigned char> before(sizeof(*s));  // bytes, padding included
  std::memcpy(before.data(), static_cast<const void*>(s.get()), sizeof(*s));
  // sigma_v such that sigma_v^2 * 1 is 1e18 times the prior's 0.01 in float, 1e34 in double: both
  // lose the prior's variance entirely next to it.
  const T sigma_v = std::is_same<T, float>::value ? T(1e8) : T(1e17);
  CHECK(s->predict(Odometry<T>{T(0.5), T(0), T(1), sigma_v, T(0)}) == Status::kNotPositiveDefinite);
  CHECK(std::memcmp(static_cast<const void*>(s.get()), before.data(), sizeof(*s)) == 0);
  // A large but representable noise is taken: the pose block stays positive definite.
  CHECK(s->predict(Odometry<T>{T(0.5), T(0), T(1), T(10), T(0.01)}) == Status::kOk);
  Mat3<T> P;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) P(r, c) = s->cov(r, c);
  CHECK(is_spd_scaled(P));
}

// Found by tests/fuzz/fuzz_node: RESET with a finite variance above half the scalar's max (2e38 in
// float) was accepted and then symmetrised as (P + P^T) / 2, whose sum overflowed: P became
// infinite. The symmetric part is now taken without overflow, the prior's definiteness is tested on
// its correlation matrix (Sylvester's raw minors overflowed too), and a pair like 3e38 / -3e38 is
// no longer "nearly equal".
TEST_CASE_TEMPLATE("reset and relocalise: a huge but finite prior stays finite; overflowing checks refuse", T, float,
                   double) {
  const T big = std::numeric_limits<T>::max() / T(1.5);  // above max / 2: P + P^T overflows
  Mat3<T> P0;
  P0 << big, T(0.001), T(0.001), T(0.001), T(0.01), T(0.001), T(0.001), T(0.001), big;
  auto s = std::make_unique<Slam<T, EB>>();
  REQUIRE(s->reset(Pose2<T>{T(0), T(0), T(0)}, P0) == Status::kOk);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) CHECK(s->cov(r, c) == P0(r, c));
  REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.3)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  FeatureId id = 0;
  REQUIRE(s->augment(Vec2<T>(T(3), T(0.4)), Mat2<T>::Identity() * T(0.01), id) == Status::kOk);
  REQUIRE(s->relocalise(Pose2<T>{T(5), T(-1), T(1)}, P0) == Status::kOk);
  for (int r = 0; r < s->dim(); ++r)
    for (int c = 0; c < s->dim(); ++c) CHECK(std::isfinite(s->cov(r, c)));
  CHECK(s->cov(0, 0) == big);

  std::vector<unsigned char> before(sizeof(*s));  // bytes, padding included
  std::memcpy(before.data(), static_cast<const void*>(s.get()), sizeof(*s));
  // Opposite off-diagonals at the scalar's edge: |a - b| overflowed, and inf <= inf called them equal.
  Mat3<T> asym = Mat3<T>::Identity() * big;
  asym(0, 1) = big;
  asym(1, 0) = -big;
  CHECK(s->reset(Pose2<T>{T(0), T(0), T(0)}, asym) == Status::kNotSymmetric);
  // Indefinite, with entries whose raw 2x2 and 3x3 minors overflow: correlation of x and y above 1.
  Mat3<T> indefinite = Mat3<T>::Identity() * big;
  indefinite(0, 1) = indefinite(1, 0) = big;
  indefinite(1, 1) = big / T(4);
  CHECK(s->reset(Pose2<T>{T(0), T(0), T(0)}, indefinite) == Status::kNotPositiveDefinite);
  CHECK(s->relocalise(Pose2<T>{T(0), T(0), T(0)}, indefinite) == Status::kNotPositiveDefinite);
  CHECK(std::memcmp(static_cast<const void*>(s.get()), before.data(), sizeof(*s)) == 0);
}

TEST_CASE_TEMPLATE("symmetric_part equals (M + M^T) / 2 for normal numbers and stays finite at the edge", T, float,
                   double) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  for (int k = 0; k < 200; ++k) {  // bit for bit against the textbook form
    Mat3<T> m;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m(r, c) = T(u(rng));
    const Mat3<T> a = symmetric_part(m);
    const Mat3<T> b = T(0.5) * (m + m.transpose());
    CHECK(std::memcmp(a.data(), b.data(), sizeof a) == 0);
  }
  const T big = std::numeric_limits<T>::max();
  Mat2<T> e;
  e << big, big, big / T(2), big;
  const Mat2<T> s = symmetric_part(e);
  CHECK(s.allFinite());
  CHECK(s(0, 0) == big);
  CHECK(s(0, 1) == s(1, 0));
  CHECK(s(0, 1) == T(0.75) * big);
}

// Found by tests/fuzz/fuzz_node: odometry with a large (valid) sigma left the pose variances near
// 1e6 next to a landmark's 1e-2; the next update's S was positive definite, but P - V V^T lost
// every digit in float and left the pose block indefinite. update() now computes the pose block and
// every landmark block as the downdate will write them and refuses (first block: nothing changed)
// or skips (later blocks) an update that would leave one of them not positive definite.
TEST_CASE_TEMPLATE("update: a downdate that rounding would leave indefinite is refused, nothing changed", T, float,
                   double) {
  int refused = 0, taken = 0;
  for (double sigma = 1.0; sigma <= 1e5; sigma *= 1.5) {  // <= 29 steps
    CAPTURE(sigma);
    auto f = std::make_unique<Fixture<T>>();
    Mat3<T> P0 = Mat3<T>::Zero();
    P0.diagonal() << T(0.01), T(0.01), T(0.001);
    REQUIRE(f->slam.reset(Pose2<T>{T(0), T(0), T(0)}, P0) == Status::kOk);
    Mat2<T> R;
    R << T(0.01), T(0), T(0), T(3e-4);
    FeatureId id = 0;
    REQUIRE(f->slam.augment(Vec2<T>(T(2.0), T(0.3)), R, id) == Status::kOk);
    REQUIRE(f->slam.augment(Vec2<T>(T(3.0), T(-0.4)), R, id) == Status::kOk);
    if (f->slam.predict(Odometry<T>{T(0.5), T(0.1), T(0.1), T(sigma), T(sigma)}) != Status::kOk) continue;
    f->obs.clear();
    for (int j = 0; j < 2; ++j) {
      const Vec2<T> z = observe(f->slam.pose(), f->slam.landmark(j)) + Vec2<T>(T(0.05), T(-0.01));
      REQUIRE(f->obs.push(z, R) == Status::kOk);
    }
    f->assoc.count = 2;
    f->assoc.feature[0] = f->slam.id(0);
    f->assoc.feature[1] = f->slam.id(1);
    std::vector<unsigned char> before(sizeof(f->slam));  // bytes, padding included
    std::memcpy(before.data(), static_cast<const void*>(&f->slam), sizeof(f->slam));
    const Status st = f->slam.update(f->obs, f->assoc, f->ws);
    REQUIRE((st == Status::kOk || st == Status::kNotPositiveDefinite));
    if (st == Status::kNotPositiveDefinite) {
      ++refused;
      CHECK(std::memcmp(static_cast<const void*>(&f->slam), before.data(), sizeof(f->slam)) == 0);
      continue;
    }
    ++taken;
    Mat3<T> Prr;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Prr(r, c) = f->slam.cov(r, c);
    CHECK(is_spd_scaled(Prr));
    for (int j = 0; j < 2; ++j) {
      const int l = Layout::landmark(j);
      CHECK(is_spd_scaled(f->slam.cov(l, l), f->slam.cov(l, l + 1), f->slam.cov(l + 1, l + 1)));
    }
  }
  CHECK(taken > 0);
  if (std::is_same<T, float>::value) CHECK(refused > 0);  // float cannot take the largest of these
}

// Found by tests/fuzz/fuzz_associate: a finite range near the scalar's max paired with a landmark
// gives a finite innovation, but L^-1 nu overflows and update() returned kOk with a mean of Inf and
// NaN. The new mean is now checked before anything is written.
TEST_CASE_TEMPLATE("update: an innovation that would overflow the mean is refused, nothing changed", T, float, double) {
  auto f = std::make_unique<Fixture<T>>();
  REQUIRE(f->slam.reset(Pose2<T>{T(0), T(0), T(0)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  FeatureId id = 0;
  REQUIRE(f->slam.add_known_landmark(Vec2<T>(T(3), T(0.4)), R, id) == Status::kOk);
  f->obs.clear();
  REQUIRE(f->obs.push(Vec2<T>(std::numeric_limits<T>::max() / T(4), T(0.1)), R) == Status::kOk);
  f->assoc.count = 1;
  f->assoc.feature[0] = id;
  std::vector<unsigned char> before(sizeof(f->slam));  // bytes, padding included
  std::memcpy(before.data(), static_cast<const void*>(&f->slam), sizeof(f->slam));
  CHECK(f->slam.update(f->obs, f->assoc, f->ws) == Status::kNonFinite);
  CHECK(std::memcmp(static_cast<const void*>(&f->slam), before.data(), sizeof(f->slam)) == 0);
  // A sane observation of the same landmark is then taken.
  f->obs.clear();
  REQUIRE(f->obs.push(observe(f->slam.pose(), f->slam.landmark(0)), R) == Status::kOk);
  CHECK(f->slam.update(f->obs, f->assoc, f->ws) == Status::kOk);
  for (int i = 0; i < f->slam.dim(); ++i) CHECK(std::isfinite(f->slam.x(i)));
}

// Found by tests/fuzz/fuzz_associate: augment with a range variance near 1e123 (double) gave a new
// block so elongated that it is singular in T, yet its raw determinant rounded positive and it was
// accepted. The new block is now tested on its correlation (is_spd_scaled), as the pose block is.
TEST_CASE_TEMPLATE("augment and add_known_landmark: a new block singular in T is refused, nothing changed", T, float,
                   double) {
  const double top = std::is_same<T, float>::value ? 1e36 : 1e300;
  int refused = 0;
  for (double var = 1e-2; var <= top; var *= 1e4) {  // <= 76 steps
    CAPTURE(var);
    auto s = std::make_unique<Slam<T, EB>>();
    REQUIRE(s->reset(Pose2<T>{T(1), T(2), T(0.3)}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
    Mat2<T> R;
    R << T(var), T(0), T(0), T(3e-4);
    std::vector<unsigned char> before(sizeof(*s));  // bytes, padding included
    std::memcpy(before.data(), static_cast<const void*>(s.get()), sizeof(*s));
    FeatureId id = 77;
    const Status st = s->augment(Vec2<T>(T(1.75), T(-0.9)), R, id);
    Mat2<T> Pll;  // the same block, surveyed
    Pll << T(var), T(var) * T(0.999999), T(var) * T(0.999999), T(var);
    FeatureId id2 = 78;
    auto t = std::make_unique<Slam<T, EB>>(*s);
    const Status st2 = t->add_known_landmark(Vec2<T>(T(1), T(1)), Pll, id2);
    auto check_one = [&refused](const Slam<T, EB>& slam, Status status, FeatureId got, FeatureId untouched) {
      if (status == Status::kOk) {
        const int l = Layout::landmark(slam.landmarks() - 1);
        CHECK(is_spd_scaled(slam.cov(l, l), slam.cov(l, l + 1), slam.cov(l + 1, l + 1)));
      } else {
        CHECK((status == Status::kNotPositiveDefinite || status == Status::kNonFinite));
        CHECK(got == untouched);
        ++refused;
      }
    };
    check_one(*s, st, id, 77);
    check_one(*t, st2, id2, 78);
    if (st != Status::kOk) CHECK(std::memcmp(static_cast<const void*>(s.get()), before.data(), sizeof(*s)) == 0);
  }
  CHECK(refused > 0);
}

TEST_CASE_TEMPLATE("a sensor mount: landmarks placed and predicted from the sensor's pose; bad mounts refused", T,
                   float, double) {
  // Victoria Park's laser on its ute: 3.78 m ahead of the rear axle, 0.50 m left (and a small yaw).
  const Mount<T> m{T(3.78), T(0.5), T(0.05)};
  auto f = std::make_unique<Fixture<T>>();
  REQUIRE(f->slam.reset(Pose2<T>{T(1), T(2), T(0.6)}, Vec3<T>(T(0.01), T(0.01), T(1e-3)).asDiagonal()) == Status::kOk);
  CHECK(f->slam.set_mount(Mount<T>{std::numeric_limits<T>::quiet_NaN(), T(0), T(0)}) == Status::kNonFinite);
  CHECK(f->slam.mount().at_origin());  // unchanged
  REQUIRE(f->slam.set_mount(m) == Status::kOk);
  // A landmark from a measurement sits where the sensor saw it; its predicted measurement is that
  // measurement; a noise-free update of it moves nothing.
  const Vec2<T> z(T(7), T(-0.4));
  Mat2<T> R;
  R << T(0.01), T(0), T(0), T(3e-4);
  FeatureId id = 0;
  REQUIRE(f->slam.augment(z, R, id) == Status::kOk);
  const Pose2<T> xs = sensor_pose(f->slam.pose(), m);
  const Vec2<T> l = f->slam.landmark(0);
  const T tol = std::is_same<T, float>::value ? T(2e-5) : T(1e-12);
  CHECK((l - inverse_observe(xs, z)).norm() < tol);
  CHECK((l - Vec2<T>(xs.x, xs.y)).norm() == doctest::Approx(double(z.x())).epsilon(1e-5));
  LocalMapStats st;
  REQUIRE(f->slam.predict_local(T(100), f->ws, f->pred, st) == Status::kOk);
  REQUIRE(f->pred.count == 1);
  CHECK((f->pred.h[0] - z).norm() < tol);
  // The landmark's block: J_l_pose P J_l_pose^T + J_l_z R J_l_z^T with the mount's pose Jacobian.
  Mat23<T> Jp;
  Mat2<T> Jz;
  (void)inverse_observe(Pose2<T>{T(1), T(2), T(0.6)}, m, z, &Jp, &Jz);
  const Mat2<T> expected =
      Jp * Mat3<T>(Vec3<T>(T(0.01), T(0.01), T(1e-3)).asDiagonal()) * Jp.transpose() + Jz * R * Jz.transpose();
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) CHECK(std::abs(f->slam.cov(3 + r, 3 + c) - expected(r, c)) < T(10) * tol);
  f->obs.clear();
  REQUIRE(f->obs.push(z, R) == Status::kOk);
  f->assoc.count = 1;
  f->assoc.feature[0] = id;
  f->assoc.candidate[0] = 0;
  f->assoc.pairings = 1;
  const Pose2<T> before = f->slam.pose();
  REQUIRE(f->slam.update(f->obs, f->assoc, f->ws) == Status::kOk);
  CHECK(std::abs(f->slam.pose().x - before.x) < tol);
  CHECK(std::abs(f->slam.pose().y - before.y) < tol);
  CHECK(std::abs(f->slam.pose().theta - before.theta) < tol);
}
