// EKF covariance engine (packed covariance): the packed covariance against a dense
// reference on random states. Every operation starts from the filter's own state (x, and P read
// through cov()), the reference applies the textbook dense formula in double, and the filter's
// result must match it:
//   predict  P <- F P F^T + G Q G^T (F the identity outside the pose rows)
//   update   one batch: S = H P H^T + R, K = P H^T S^-1, x <- x + K nu, P <- P - K S K^T
//   augment  [P, P Jp^T; Jp P, Jp P_rr Jp^T + Jz R Jz^T] (Jp on the pose columns)
//   review   removal keeps the kept rows and columns, exactly
// Tolerance: max |P - P_ref| <= tol * max |P_ref| with tol 1e-10 (double) and 2e-4 (float; the
// reference is computed in double from the float filter's own input state).
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "geojcbb_host/sim.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;
using namespace geojcbb::ekf;
using namespace geojcbb::test;

namespace {
using CB = Bounds<12, 16, 4, 1000, 30>;

struct Dense {
  Eigen::VectorXd x;
  Eigen::MatrixXd P;
};

template <typename T, class B>
Dense dense(const Slam<T, B>& s) {
  const int d = s.dim();
  Dense out{Eigen::VectorXd(d), Eigen::MatrixXd(d, d)};
  for (int r = 0; r < d; ++r) {
    out.x(r) = double(s.x(r));
    for (int c = 0; c < d; ++c) out.P(r, c) = double(s.cov(r, c));
  }
  return out;
}

template <typename T>
double tolerance() {
  return std::is_same<T, float>::value ? 2e-4 : 1e-10;
}

template <typename T, class B>
void check_close(const Slam<T, B>& s, const Dense& ref, const char* what) {
  CAPTURE(what);
  const Dense got = dense(s);
  REQUIRE(got.P.rows() == ref.P.rows());
  const double scale = ref.P.cwiseAbs().maxCoeff();
  CHECK((got.P - ref.P).cwiseAbs().maxCoeff() <= tolerance<T>() * scale);
  Eigen::VectorXd dx = got.x - ref.x;
  dx(2) = wrap_angle(dx(2));
  CHECK(dx.cwiseAbs().maxCoeff() <= tolerance<T>() * (1 + ref.x.cwiseAbs().maxCoeff()));
}

template <typename T>
struct Rig {
  Slam<T, CB> slam;
  ekf::SlamWorkspace<T, CB> ws;
  Observations<T, CB> obs;
  Association<T, CB> assoc;
  Prediction<T, CB> pred;
};

// A random state: a random pose prior, landmarks added by augment around the robot, some predicts
// and ground-truth updates so the covariance is dense and correlated.
template <typename T>
void random_state(Rig<T>& g, std::mt19937& rng, int landmarks, bool fej) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3<T> P0;
  const Eigen::Matrix3d A = Eigen::Matrix3d::Random() * 0.1;
  const Eigen::Matrix3d S = A * A.transpose() + Eigen::Matrix3d::Identity() * 0.01;
  P0 = S.cast<T>();
  REQUIRE(g.slam.reset(Pose2<T>{T(u(rng)), T(u(rng)), T(u(rng))}, P0, FilterOptions{fej}) == Status::kOk);
  for (int k = 0; k < landmarks; ++k) {
    FeatureId id;
    const Vec2<T> z(T(3 + 3 * (u(rng) + 1)), T(2.5 * u(rng)));
    REQUIRE(g.slam.augment(z, Mat2<T>(Vec2<T>(T(0.01), T(1e-4)).asDiagonal()), id) == Status::kOk);
    if (k % 3 == 2) {
      REQUIRE(g.slam.predict(Odometry<T>{T(0.5 + u(rng)), T(0.3 * u(rng)), T(0.2), T(0.1), T(0.05)}) == Status::kOk);
    }
  }
}

// Observations of `pairs` distinct random landmarks near their predicted measurements.
template <typename T>
void random_scan(Rig<T>& g, std::mt19937& rng, int pairs) {
  std::uniform_real_distribution<double> u(-1, 1);
  g.obs.clear();
  std::vector<int> idx(g.slam.landmarks());
  for (int j = 0; j < g.slam.landmarks(); ++j) idx[j] = j;
  std::shuffle(idx.begin(), idx.end(), rng);
  for (int i = 0; i < pairs; ++i) {
    const Vec2<T> h = observe(g.slam.pose(), g.slam.landmark(idx[i]));
    const Vec2<T> z(h.x() + T(0.1 * u(rng)), h.y() + T(0.02 * u(rng)));
    Mat2<T> R;
    R << T(0.01 + 0.01 * (u(rng) + 1)), T(1e-4 * u(rng)), T(0), T(2e-4);
    R(1, 0) = R(0, 1);
    REQUIRE(g.obs.push(z, R) == Status::kOk);
    g.assoc.feature[i] = g.slam.id(idx[i]);
  }
  g.assoc.count = g.obs.count;
}

template <typename T>
Dense reference_update(const Rig<T>& g) {
  Dense ref = dense(g.slam);
  const int d = g.slam.dim();
  const int m = 2 * g.obs.count;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, d), R = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd nu(m);
  const Pose2<double> xr{ref.x(0), ref.x(1), ref.x(2)};
  for (int i = 0; i < g.obs.count; ++i) {
    const int j = g.slam.index_of(g.assoc.feature[i]);
    const int l = Layout::landmark(j);
    Mat23<double> Hp;
    Mat2<double> Hl;
    const Vec2<double> h = observe(xr, Vec2<double>(ref.x(l), ref.x(l + 1)));
    observe(xr, Vec2<double>(g.slam.linearisation_point(j).template cast<double>()), &Hp, &Hl);
    H.block<2, 3>(2 * i, 0) = Hp;
    H.block<2, 2>(2 * i, l) = Hl;
    nu.segment<2>(2 * i) = innovation(Vec2<double>(g.obs.z[i].template cast<double>()), h);
    R.block<2, 2>(2 * i, 2 * i) = g.obs.R[i].template cast<double>();
  }
  const Eigen::MatrixXd S = H * ref.P * H.transpose() + R;
  const Eigen::MatrixXd K = ref.P * H.transpose() * S.inverse();
  ref.x += K * nu;
  ref.P -= K * S * K.transpose();
  ref.P = (0.5 * (ref.P + ref.P.transpose())).eval();
  return ref;
}
}  // namespace

TEST_CASE_TEMPLATE("packed covariance: accessors, symmetric by construction, the packed index a bijection", T, float,
                   double) {
  auto g = std::make_unique<Rig<T>>();
  std::mt19937 rng(11);
  random_state(*g, rng, CB::kMaxLandmarks, true);
  const int d = g->slam.dim();
  REQUIRE(d == Slam<T, CB>::kMaxState);
  std::vector<int> seen(Slam<T, CB>::kPackedSize, 0);
  for (int r = 0; r < d; ++r) {
    for (int c = 0; c < d; ++c) {
      CHECK(g->slam.cov(r, c) == g->slam.cov(c, r));
      CHECK(Slam<T, CB>::packed_index(r, c) == Slam<T, CB>::packed_index(c, r));
      if (r <= c) ++seen[Slam<T, CB>::packed_index(r, c)];
    }
  }
  for (int v : seen) CHECK(v == 1);  // every stored scalar is exactly one upper-triangle entry
  static_assert(sizeof(Slam<T, CB>{}) < sizeof(T) * Slam<T, CB>::kMaxState * Slam<T, CB>::kMaxState,
                "packed: less than the dense square");
}

TEST_CASE_TEMPLATE("packed covariance against a dense reference: predict, update, augment, removal", T, float, double) {
  for (int trial = 0; trial < 12; ++trial) {
    CAPTURE(trial);
    const bool fej = trial % 2 == 0;
    auto g = std::make_unique<Rig<T>>();
    std::mt19937 rng(100 + trial);
    random_state(*g, rng, 6 + trial, fej);
    // predict, after a predict (no FEJ correction pending): F only on the pose rows.
    {
      const Odometry<T> od{T(0.8), T(-0.2), T(0.1), T(0.2), T(0.05)};
      REQUIRE(g->slam.predict(od) == Status::kOk);
      Dense ref = dense(g->slam);
      Mat3<double> F;
      Mat32<double> G;
      const Pose2<double> next =
          move(Pose2<double>{ref.x(0), ref.x(1), ref.x(2)}, Odometry<double>{0.8, -0.2, 0.1, 0.2, 0.05}, &F, &G);
      Eigen::MatrixXd Fx = Eigen::MatrixXd::Identity(ref.P.rows(), ref.P.cols());
      Fx.topLeftCorner<3, 3>() = F;
      Eigen::MatrixXd GQG = Eigen::MatrixXd::Zero(ref.P.rows(), ref.P.cols());
      GQG.topLeftCorner<3, 3>() = G * Eigen::Vector2d(0.04, 0.0025).asDiagonal() * G.transpose();
      ref.P = Fx * ref.P * Fx.transpose() + GQG;
      ref.x.head<3>() = Eigen::Vector3d(next.x, next.y, next.theta);
      REQUIRE(g->slam.predict(od) == Status::kOk);
      check_close(g->slam, ref, "predict");
    }
    // update: every pair count from 1 to the capacity (odd counts leave a short last block).
    for (int pairs = 1; pairs <= std::min(g->slam.landmarks(), CB::kMaxObservations); pairs += 1 + trial % 3) {
      CAPTURE(pairs);
      random_scan(*g, rng, pairs);
      const Dense ref = reference_update(*g);
      REQUIRE(g->slam.update(g->obs, g->assoc, g->ws) == Status::kOk);
      CHECK(g->ws.rejected_blocks == 0);
      CHECK(g->ws.floored_variances == 0);
      check_close(g->slam, ref, "update");
    }
    // augment
    {
      Dense ref = dense(g->slam);
      const Vec2<T> z(T(4), T(0.3));
      const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.02), T(3e-4)).asDiagonal());
      Mat23<double> Jp;
      Mat2<double> Jz;
      const Vec2<double> l = inverse_observe(Pose2<double>{ref.x(0), ref.x(1), ref.x(2)},
                                             Vec2<double>(z.template cast<double>()), &Jp, &Jz);
      const int d = int(ref.x.size());
      Dense big{Eigen::VectorXd(d + 2), Eigen::MatrixXd::Zero(d + 2, d + 2)};
      big.x << ref.x, l;
      big.P.topLeftCorner(d, d) = ref.P;
      big.P.block(d, 0, 2, d) = Jp * ref.P.topRows(3);
      big.P.block(0, d, d, 2) = big.P.block(d, 0, 2, d).transpose();
      big.P.block<2, 2>(d, d) =
          Jp * ref.P.topLeftCorner<3, 3>() * Jp.transpose() + Jz * R.template cast<double>() * Jz.transpose();
      FeatureId id;
      REQUIRE(g->slam.augment(z, R, id) == Status::kOk);
      check_close(g->slam, big, "augment");
    }
    // removal (compaction): an unpaired tentative landmark in view is removed at delete_nats.
    {
      const Dense before = dense(g->slam);
      const int n = g->slam.landmarks();
      // Landmarks 0..n-2 are paired in a fake prediction; the newest (tentative) one is missed.
      g->pred.count = 0;
      LocalMapStats st;
      REQUIRE(g->slam.predict_local(T(1000), g->ws, g->pred, st) == Status::kOk);
      g->assoc.count = 0;
      for (int a = 0; a < g->pred.count && g->assoc.count < CB::kMaxObservations; ++a) {
        if (g->pred.id[a] == g->slam.id(n - 1)) continue;
        g->assoc.feature[g->assoc.count++] = g->pred.id[a];
      }
      // Drop by policy every landmark with one hit that was expected and not paired (the newest,
      // and any the capacity of pairings left out), so removals fall in the middle too.
      LandmarkPolicy pol;
      pol.delete_nats = -1.0f;  // one miss (-2.3 nats) removes a landmark that was never paired
      Visibility<T> view{T(0), T(1e6), T(4), T(0)};
      ReviewStats rs;
      g->obs.clear();
      for (int i = 0; i < g->assoc.count; ++i) {
        REQUIRE(g->obs.push(Vec2<T>(T(1), T(0)), Mat2<T>::Identity() * T(0.01)) == Status::kOk);  // z not read
      }
      REQUIRE(g->slam.review(g->obs, g->pred, g->assoc, view, pol, rs) == Status::kOk);
      REQUIRE(rs.removed >= 1);
      std::vector<int> rows = {0, 1, 2};
      // Map each survivor to its old index by its mean (unique per landmark; review() does not move it).
      for (int k = 0; k < g->slam.landmarks(); ++k) {
        int old = -1;
        for (int j = 0; j < n; ++j) {
          if (before.x(Layout::landmark(j)) == double(g->slam.x(Layout::landmark(k))) &&
              before.x(Layout::landmark(j) + 1) == double(g->slam.x(Layout::landmark(k) + 1))) {
            old = j;
          }
        }
        REQUIRE(old >= 0);
        rows.push_back(Layout::landmark(old));
        rows.push_back(Layout::landmark(old) + 1);
      }
      const Dense after = dense(g->slam);
      for (std::size_t r = 0; r < rows.size(); ++r)
        for (std::size_t c = 0; c < rows.size(); ++c) CHECK(after.P(r, c) == before.P(rows[r], rows[c]));
    }
  }
}

TEST_CASE_TEMPLATE("update and predict allocate nothing; an S not positive definite changes nothing", T, float,
                   double) {
  auto g = std::make_unique<Rig<T>>();
  std::mt19937 rng(5);
  random_state(*g, rng, 20, true);
  random_scan(*g, rng, CB::kMaxObservations);
  const std::uint64_t allocs = allocations_during([&] {
    REQUIRE(g->slam.update(g->obs, g->assoc, g->ws) == Status::kOk);
    REQUIRE(g->slam.predict(Odometry<T>{T(1), T(0.1), T(0.1), T(0.1), T(0.1)}) == Status::kOk);
  });
  CHECK(allocs == 0);
  // R positive definite but so negative-correlated with nothing else that S is not: impossible with
  // P PSD; instead, an R that is not positive definite is caught before any change.
  random_scan(*g, rng, 3);
  g->obs.R[2] = Mat2<T>::Identity() * T(-1);
  auto snapshot = std::make_unique<Slam<T, CB>>(g->slam);
  CHECK(g->slam.update(g->obs, g->assoc, g->ws) == Status::kNotPositiveDefinite);
  CHECK(std::memcmp(snapshot.get(), &g->slam, sizeof(g->slam)) == 0);
}

TEST_CASE("float SLAM over the whole env1 run: P symmetric and positive definite at every scan") {
  using LB = LargeControllerBounds;
  const host::Scenario sc = host::load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  host::Simulator sim(sc, 1);
  auto step = std::make_unique<node::SlamStep<float, LB>>();
  node::StepSettings<float> set;
  set.strategy = Strategy::kJcbb;
  set.local_radius_m = float(sc.max_range_m + 5.0);
  set.min_range_m = float(sc.min_range_m + 1);
  set.max_range_m = float(sc.max_range_m - 1);
  set.half_fov_rad = float(sc.fov_rad / 2);
  REQUIRE(step->configure(set) == Status::kOk);
  REQUIRE(step->reset(Pose2<float>{float(sc.waypoints[0].x()), float(sc.waypoints[0].y()), 0.0f},
                      Mat3<float>::Identity() * 1e-6f) == Status::kOk);
  auto obs = std::make_unique<Observations<float, LB>>();
  auto out = std::make_unique<node::StepResult<float, LB>>();
  host::SimStep s;
  int scans = 0, checked = 0, max_landmarks = 0;
  while (sim.step(s)) {  // <= the scenario's path
    REQUIRE(step->predict(ekf::Odometry<float>{float(s.v_mps), float(s.w_radps), float(sc.dt_s), float(sc.sigma_v_mps),
                                               float(sc.sigma_w_radps)}) == Status::kOk);
    if (!s.scan) continue;
    obs->clear();
    for (const auto& o : s.observations) {
      if (obs->count == LB::kMaxObservations) break;
      REQUIRE(obs->push(o.z.cast<float>(), o.R.cast<float>()) == Status::kOk);
    }
    REQUIRE(step->step(*obs, *out) == Status::kOk);
    ++scans;
    const auto& sl = step->slam();
    max_landmarks = std::max(max_landmarks, sl.landmarks());
    if (scans % 10 != 0) continue;  // the dense check is O(n^3): every tenth scan
    ++checked;
    const int d = sl.dim();
    Eigen::MatrixXf P(d, d);
    for (int r = 0; r < d; ++r)
      for (int c = 0; c < d; ++c) P(r, c) = sl.cov(r, c);
    CHECK(P == P.transpose());
    // Positive definite in float itself: its Cholesky factor exists.
    Eigen::LLT<Eigen::MatrixXf> llt(P);
    CHECK(llt.info() == Eigen::Success);
  }
  MESSAGE("env1 float: " << scans << " scans, " << checked << " dense checks, up to " << max_landmarks << " landmarks");
  CHECK(scans > 500);
  CHECK(max_landmarks > 50);
}
