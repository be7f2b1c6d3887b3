// EKF landmark life cycle and filter options (MRCLAM): an object that moves is removed by the
// static gate; existence by evidence: a landmark that is gone is removed after the misses its
// saturated log-odds allows, one seen at half the scans is kept, a new one missed twice goes, a
// known one never; two landmarks 0.15 m apart, the second first seen from
// near, become two landmarks, not one and not three; known landmarks; first-estimates Jacobians;
// the sensor and drive models; bad input changes no state; no allocation.
#include <doctest/doctest.h>

#include <cstring>
#include <memory>
#include <vector>

#include "geojcbb/ekf/sensor_model.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/slam_step.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;
using namespace geojcbb::ekf;

namespace {
using LB = Bounds<8, 16, 3, 2000, 16>;

template <typename T>
struct Rig {
  Slam<T, LB> slam;
  ekf::SlamWorkspace<T, LB> ws;
  Observations<T, LB> obs;
  Association<T, LB> assoc;
  Prediction<T, LB> pred;
};

// One scan of a single observation z of landmark `id` (or unpaired when id < 0) from the current
// pose: update when paired, then review with the given policy.
template <typename T>
ReviewStats scan(Rig<T>& r, const Vec2<T>& z, FeatureId id, const LandmarkPolicy& policy) {
  LocalMapStats st;
  REQUIRE(r.slam.predict_local(T(30), r.ws, r.pred, st) == Status::kOk);
  r.obs.clear();
  REQUIRE(r.obs.push(z, Mat2<T>(Vec2<T>(T(0.02 * 0.02), T(0.005 * 0.005)).asDiagonal())) == Status::kOk);
  r.assoc.count = 1;
  r.assoc.feature[0] = id;
  if (id >= 0) REQUIRE(r.slam.update(r.obs, r.assoc, r.ws) == Status::kOk);
  ReviewStats rs;
  REQUIRE(r.slam.review(r.obs, r.pred, r.assoc, Visibility<T>{T(0.5), T(20), T(1.2)}, policy, rs) == Status::kOk);
  return rs;
}
}  // namespace

TEST_CASE_TEMPLATE("static gate: a landmark that follows a moving object is removed; a static one stays", T, float,
                   double) {
  for (const bool moving : {true, false}) {
    auto r = std::make_unique<Rig<T>>();
    REQUIRE(r->slam.reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
    FeatureId id = -1;
    const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.02 * 0.02), T(0.005 * 0.005)).asDiagonal());
    REQUIRE(r->slam.augment(Vec2<T>(T(4), T(0)), R, id) == Status::kOk);
    LandmarkPolicy policy;
    policy.static_gate_d2 = 13.8f;  // chi2(0.999, 2)
    int removed_at = -1;
    for (int k = 1; k <= 40 && removed_at < 0; ++k) {
      // The object drives away across the view at 6 cm per scan (another robot); a static landmark
      // is seen where it is.
      const T y = moving ? T(0.06) * T(k) : T(0);
      const Vec2<T> z(std::sqrt(T(16) + y * y), std::atan2(y, T(4)));
      const ReviewStats rs = scan(*r, z, id, policy);
      if (rs.removed_moved > 0) removed_at = k;
    }
    CAPTURE(moving);
    if (moving) {
      CHECK(removed_at > 0);
      CHECK(removed_at <= 10);
      CHECK(r->slam.landmarks() == 0);
      CHECK(r->slam.index_of(id) == -1);
    } else {
      CHECK(removed_at == -1);
      CHECK(r->slam.landmarks() == 1);
    }
  }
}

TEST_CASE_TEMPLATE("existence: gone is removed after the misses its log-odds allows; seen at half the scans stays", T,
                   float, double) {
  // The default policy: p_D 0.9, 0.003 clutter per m^2. Here p_FA ~ 4e-5 (a 2 cm x 0.3 deg gate at 4 m), so
  // a pairing adds ~10 nats (the log-odds saturates at 4.6 + 4.6 nats) and a miss -2.30: from 9.2, six
  // misses in a row reach -4.6 <= delete_nats (-4), five (-2.3) do not.
  for (const bool gone : {true, false}) {
    auto r = std::make_unique<Rig<T>>();
    REQUIRE(r->slam.reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
    FeatureId id = -1, other = -1, known = -1;
    const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.02 * 0.02), T(0.005 * 0.005)).asDiagonal());
    REQUIRE(r->slam.augment(Vec2<T>(T(4), T(0)), R, id) == Status::kOk);
    REQUIRE(r->slam.augment(Vec2<T>(T(5), T(0.3)), R, other) == Status::kOk);
    REQUIRE(r->slam.add_known_landmark(Vec2<T>(T(6), T(-1)), Mat2<T>::Identity() * T(1e-4), known) == Status::kOk);
    LandmarkPolicy policy;
    policy.reserve_nats = 4.6f;  // MRCLAM's rules (the default, 1000, keeps a confirmed landmark)
    const Vec2<T> z(T(4), T(0));
    // The landmark never paired (clutter): in view and missed on the first two reviews, removed.
    ReviewStats rs = scan(*r, z, id, policy);
    CHECK(rs.confirmed == 1);  // id: one re-sighting confirms
    CHECK(r->slam.confirmed(r->slam.index_of(id)));
    CHECK(r->slam.existence(r->slam.index_of(id)) ==
          doctest::Approx(double(policy.confirm_nats + policy.reserve_nats)));
    CHECK(r->slam.index_of(other) >= 0);
    CHECK(r->slam.existence(r->slam.index_of(other)) == doctest::Approx(-2.3026).epsilon(1e-3));
    rs = scan(*r, z, -1, policy);
    CHECK(r->slam.index_of(other) == -1);
    CHECK(rs.removed == 1);
    CHECK(rs.removed_missed == 0);  // it was tentative
    // Seen in every second scan for 40 scans: a detection rate of 0.5 (the log-odds 9.2, 6.9, 9.2, ...).
    for (int k = 2; k < 40; ++k) (void)scan(*r, z, k % 2 == 0 ? id : -1, policy);
    REQUIRE(r->slam.index_of(id) >= 0);
    // Then: gone (never seen again), or seen at its rate. The last scan above was a miss (6.9).
    int removed_at = -1;
    for (int k = 0; k < 60 && removed_at < 0; ++k) {
      rs = scan(*r, z, !gone && k % 2 == 0 ? id : -1, policy);
      if (rs.removed_missed > 0) removed_at = k + 1;
    }
    CAPTURE(gone);
    if (gone) {
      CHECK(removed_at == 5);
      CHECK(r->slam.index_of(id) == -1);
    } else {
      CHECK(removed_at == -1);
      CHECK(r->slam.index_of(id) >= 0);
    }
    // The known landmark, in view and never paired for 40 + reviews: kept, confirmed.
    const int jk = r->slam.index_of(known);
    REQUIRE(jk >= 0);
    CHECK(r->slam.confirmed(jk));
    CHECK(r->slam.existence(jk) < T(-50));
  }
}

TEST_CASE_TEMPLATE("existence: removal marginalises the landmark and P stays positive definite", T, float, double) {
  // Eight landmarks around the robot, paired on three scans; then half of them are never seen again.
  // Each removal drops the landmark's rows and columns (exact marginalisation for an EKF; that the
  // compaction keeps every other entry is test_covariance's "removal"): P stays positive definite.
  auto r = std::make_unique<Rig<T>>();
  REQUIRE(r->slam.reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-4)) == Status::kOk);
  const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.05 * 0.05), T(0.01 * 0.01)).asDiagonal());
  std::vector<Vec2<T>> zs;
  for (int k = 0; k < 8; ++k) {
    const Vec2<T> z(T(3) + T(0.5) * T(k), T(-1) + T(0.25) * T(k));
    FeatureId id = -1;
    REQUIRE(r->slam.augment(z, R, id) == Status::kOk);
    zs.push_back(z);
  }
  const Visibility<T> view{T(0.5), T(20), T(1.2)};
  auto one_scan = [&](bool all) {
    LocalMapStats st;
    REQUIRE(r->slam.predict_local(T(30), r->ws, r->pred, st) == Status::kOk);
    r->obs.clear();
    r->assoc.count = 0;
    for (int j = 0; j < r->slam.landmarks(); ++j) {
      const FeatureId id = r->slam.id(j);
      if (!all && id % 2 == 1) continue;
      REQUIRE(r->obs.push(zs[static_cast<std::size_t>(id)], R) == Status::kOk);
      r->assoc.feature[r->assoc.count++] = id;
    }
    REQUIRE(r->slam.update(r->obs, r->assoc, r->ws) == Status::kOk);
    ReviewStats rs;
    LandmarkPolicy policy;
    policy.reserve_nats = 4.6f;  // MRCLAM's rules: six misses in a row remove a landmark seen long
    REQUIRE(r->slam.review(r->obs, r->pred, r->assoc, view, policy, rs) == Status::kOk);
    return rs;
  };
  for (int k = 0; k < 3; ++k) (void)one_scan(true);
  int removed = 0;
  for (int k = 0; k < 10 && r->slam.landmarks() > 4; ++k) {
    const ReviewStats rs = one_scan(false);
    removed += rs.removed;
    const int m = r->slam.dim();
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic> Pm(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) Pm(a, b) = double(r->slam.cov(a, b));
    CHECK(Pm.llt().info() == Eigen::Success);
  }
  CHECK(removed == 4);
  REQUIRE(r->slam.landmarks() == 4);
  for (int j = 0; j < 4; ++j) CHECK(r->slam.id(j) % 2 == 0);
}

TEST_CASE_TEMPLATE("two landmarks 0.15 m apart, the second first seen from near: two landmarks, not one or three", T,
                   float, double) {
  using SB = Bounds<8, 16, 3, 2000, 16>;
  auto step = std::make_unique<node::SlamStep<T, SB>>();
  node::StepSettings<T> s;
  s.strategy = Strategy::kGeojcbb;
  s.local_radius_m = T(20);
  s.new_if_candidates_taken = true;
  s.min_range_m = T(0.3);
  s.max_range_m = T(15);
  s.half_fov_rad = T(1.0);
  REQUIRE(step->configure(s) == Status::kOk);
  REQUIRE(step->reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
  const Vec2<double> A(8, 0), Bp(8, 0.15);
  const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.02 * 0.02), T(0.005 * 0.005)).asDiagonal());
  auto obs = std::make_unique<Observations<T, SB>>();
  auto res = std::make_unique<node::StepResult<T, SB>>();
  FeatureId id_a = -1, id_b = -1;
  for (int k = 0; k < 30; ++k) {
    const double x = 0.2 * k;  // drives from 8 m to 2 m away
    if (k > 0) REQUIRE(step->predict(ekf::Odometry<T>{T(0.2), T(0), T(1), T(0.002), T(0.0005)}) == Status::kOk);
    obs->clear();
    auto push = [&](const Vec2<double>& l) {
      const Vec2<double> z = observe(Pose2<double>{x, 0, 0}, l);
      REQUIRE(obs->push(z.cast<T>(), R) == Status::kOk);
    };
    push(A);
    const bool near = k >= 20;  // from 4 m on, B is seen too (it was hidden behind A before)
    if (near) push(Bp);
    REQUIRE(step->step(*obs, *res) == Status::kOk);
    if (k == 0) {
      REQUIRE(res->outcome[0] == node::Outcome::kNewLandmark);
      id_a = res->feature[0];
    } else {
      CHECK(res->outcome[0] == node::Outcome::kPaired);
      CHECK(res->feature[0] == id_a);
    }
    if (k == 20) {
      CHECK(res->outcome[1] == node::Outcome::kNewLandmark);
      id_b = res->feature[1];
    } else if (near) {
      CHECK(res->outcome[1] == node::Outcome::kPaired);
      CHECK(res->feature[1] == id_b);
    }
  }
  CHECK(step->slam().landmarks() == 2);
  CHECK(id_b != id_a);
  const int ja = step->slam().index_of(id_a), jb = step->slam().index_of(id_b);
  REQUIRE(ja >= 0);
  REQUIRE(jb >= 0);
  CHECK((step->slam().landmark(ja).template cast<double>() - A).norm() < 0.05);
  CHECK((step->slam().landmark(jb).template cast<double>() - Bp).norm() < 0.05);
}

TEST_CASE_TEMPLATE("known landmarks: added uncorrelated with their covariance; bad input changes nothing", T, float,
                   double) {
  auto r = std::make_unique<Rig<T>>();
  REQUIRE(r->slam.reset(Pose2<T>{}, Mat3<T>::Identity() * T(0.01)) == Status::kOk);
  FeatureId id = -1;
  const Mat2<T> Pll = Mat2<T>::Identity() * T(1e-4);
  REQUIRE(r->slam.add_known_landmark(Vec2<T>(T(3), T(1)), Pll, id) == Status::kOk);
  CHECK(id == 0);
  CHECK(r->slam.landmarks() == 1);
  for (int c = 0; c < 3; ++c) CHECK(r->slam.cov(3, c) == T(0));
  CHECK(r->slam.cov(3, 3) == Pll(0, 0));
  // Snapshots are byte copies (padding included): a copy-constructed object need not copy padding.
  const auto bytes_of = [](const Slam<T, LB>& s) {
    std::vector<unsigned char> b(sizeof(Slam<T, LB>));
    std::memcpy(b.data(), static_cast<const void*>(&s), b.size());
    return b;
  };
  const std::vector<unsigned char> before = bytes_of(r->slam);
  const T nan = std::numeric_limits<T>::quiet_NaN();
  CHECK(r->slam.add_known_landmark(Vec2<T>(nan, T(1)), Pll, id) == Status::kNonFinite);
  CHECK(r->slam.add_known_landmark(Vec2<T>(T(1), T(1)), Mat2<T>::Zero(), id) == Status::kNotPositiveDefinite);
  CHECK(bytes_of(r->slam) == before);
  for (int k = 1; k < LB::kMaxLandmarks; ++k)
    REQUIRE(r->slam.add_known_landmark(Vec2<T>(T(k), T(2)), Pll, id) == Status::kOk);
  CHECK(r->slam.add_known_landmark(Vec2<T>(T(1), T(1)), Pll, id) == Status::kCapacityExceeded);
  // A bad policy (the new rules' fields out of range) is refused before anything changes.
  LocalMapStats st;
  REQUIRE(r->slam.predict_local(T(30), r->ws, r->pred, st) == Status::kOk);
  const std::vector<unsigned char> full = bytes_of(r->slam);
  LandmarkPolicy bad;
  bad.reserve_nats = -1.0f;
  r->assoc.count = 0;
  r->obs.clear();
  ReviewStats rs;
  const Visibility<T> view{T(0.5), T(20), T(1.2)};
  CHECK(r->slam.review(r->obs, r->pred, r->assoc, view, bad, rs) == Status::kInvalidInput);
  bad = LandmarkPolicy{};
  bad.static_gate_d2 = -1.0f;
  CHECK(r->slam.review(r->obs, r->pred, r->assoc, view, bad, rs) == Status::kInvalidInput);
  bad = LandmarkPolicy{};
  bad.delete_nats = 0.5f;  // must be below the start (0)
  CHECK(r->slam.review(r->obs, r->pred, r->assoc, view, bad, rs) == Status::kInvalidInput);
  bad = LandmarkPolicy{};
  bad.p_detect = 1.0f;
  CHECK(r->slam.review(r->obs, r->pred, r->assoc, view, bad, rs) == Status::kInvalidInput);
  r->assoc.count = 1;  // one pairing, no observation
  r->assoc.feature[0] = 0;
  CHECK(r->slam.review(r->obs, r->pred, r->assoc, view, LandmarkPolicy{}, rs) == Status::kInvalidInput);
  CHECK(bytes_of(r->slam) == full);
}

TEST_CASE_TEMPLATE("first-estimates Jacobians: a landmark's Jacobians stay at its first estimate; off, at the current",
                   T, float, double) {
  for (const bool fej : {true, false}) {
    auto r = std::make_unique<Rig<T>>();
    FilterOptions o;
    o.first_estimates_jacobians = fej;
    REQUIRE(r->slam.reset(Pose2<T>{}, Mat3<T>::Identity() * T(0.01), o) == Status::kOk);
    FeatureId id = -1;
    REQUIRE(r->slam.augment(Vec2<T>(T(4), T(0)), Mat2<T>::Identity() * T(0.01), id) == Status::kOk);
    const Vec2<T> first = r->slam.landmark(0);
    (void)scan(*r, Vec2<T>(T(4.3), T(0.05)), id, LandmarkPolicy{});
    CAPTURE(fej);
    CHECK(r->slam.landmark(0) != first);  // the update moved it
    CHECK(r->slam.linearisation_point(0) == (fej ? first : r->slam.landmark(0)));
  }
}

TEST_CASE_TEMPLATE("sensor and drive models: corrections, covariances and bad input", T, float, double) {
  RangeBearingModel<T> m;
  m.range_rel_bias0 = T(0.03);
  m.range_rel_bias2_per_rad2 = T(-0.5);
  m.bearing_bias_rad = T(-0.01);
  m.sigma_range_m = T(0.01);
  m.sigma_range_rel = T(0.01);
  m.sigma_bearing_rad = T(0.008);
  Vec2<T> z(T(9), T(9));
  Mat2<T> R = Mat2<T>::Zero();
  REQUIRE(m.correct(Vec2<T>(T(4), T(0.29)), z, R) == Status::kOk);
  const T b = T(0.3);
  CHECK(z.y() == doctest::Approx(double(b)));
  CHECK(z.x() == doctest::Approx(4.0 / (1.03 - 0.5 * 0.09)).epsilon(1e-5));
  CHECK(R(0, 0) == doctest::Approx(1e-4 + 1e-4 * double(z.x() * z.x())).epsilon(1e-4));
  CHECK(R(1, 1) == doctest::Approx(0.008 * 0.008).epsilon(1e-5));
  CHECK(R(0, 1) == T(0));
  const Vec2<T> z0 = z;
  CHECK(m.correct(Vec2<T>(T(-1), T(0)), z, R) == Status::kInvalidInput);
  CHECK(m.correct(Vec2<T>(std::numeric_limits<T>::infinity(), T(0)), z, R) == Status::kNonFinite);
  m.sigma_bearing_rad = T(0);
  CHECK(m.correct(Vec2<T>(T(4), T(0)), z, R) == Status::kInvalidInput);
  CHECK(z == z0);

  OdometryModel<T> d;
  d.scale_v = T(0.9);
  d.scale_w = T(0.8);
  d.alpha_v_sqrt_s = T(0.1);
  d.q_w_rad2ps = T(1e-4);
  Odometry<T> u;
  REQUIRE(d.odometry(T(0.1), T(0.5), T(0.25), u) == Status::kOk);
  CHECK(u.v_mps == doctest::Approx(0.09));
  CHECK(u.w_radps == doctest::Approx(0.4));
  // var(v dt) = alpha_v^2 v^2 dt: sigma_v = alpha_v v / sqrt(dt).
  CHECK(u.sigma_v_mps == doctest::Approx(0.1 * 0.09 / 0.5).epsilon(1e-5));
  CHECK(u.sigma_w_radps == doctest::Approx(std::sqrt(1e-4 / 0.25)).epsilon(1e-5));
  const Odometry<T> u0 = u;
  CHECK(d.odometry(T(0.1), T(0.5), T(-1), u) == Status::kInvalidInput);
  d.scale_v = T(-1);
  CHECK(d.odometry(T(0.1), T(0.5), T(0.25), u) == Status::kInvalidInput);
  CHECK(u.v_mps == u0.v_mps);
}

TEST_CASE_TEMPLATE("the landmark rules and known landmarks allocate nothing", T, float, double) {
  auto r = std::make_unique<Rig<T>>();
  REQUIRE(r->slam.reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
  FeatureId id = -1;
  LandmarkPolicy policy;
  policy.static_gate_d2 = 13.8f;
  test::AllocationGuard guard;
  REQUIRE(r->slam.add_known_landmark(Vec2<T>(T(4), T(0)), Mat2<T>::Identity() * T(1e-4), id) == Status::kOk);
  for (int k = 0; k < 30; ++k) (void)scan(*r, Vec2<T>(T(4), T(0.001) * T(k % 2)), k % 3 == 0 ? id : -1, policy);
  CHECK(r->slam.index_of(id) == 0);
  CHECK(guard.allocations() == 0);
}

TEST_CASE_TEMPLATE(
    "a full map: new landmarks refused, or with evict_when_full the least-seen far one evicted, ids stable", T, float,
    double) {
  // Four landmarks fit. At the origin L0 is seen on four scans and L1 (new at the third) on two;
  // 30 m on, L2 and L3 fill the map, and L4 needs room. Off: L4 is refused and counted. On: L1 goes
  // (beyond r + d = 10 m and the least seen), every other landmark keeps its id and estimate, and
  // L4 gets the next id. Near the origin, with every landmark within r + d, nothing can go.
  using SB = Bounds<8, 4, 3, 2000, 4>;
  for (const bool evict : {false, true}) {
    CAPTURE(evict);
    auto step = std::make_unique<node::SlamStep<T, SB>>();
    node::StepSettings<T> s;
    s.strategy = Strategy::kJcbb;
    s.local_radius_m = T(10);
    s.min_range_m = T(0.3);
    s.max_range_m = T(8);
    s.half_fov_rad = T(1.5);
    s.evict_when_full = evict;
    REQUIRE(step->configure(s) == Status::kOk);
    REQUIRE(step->reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
    const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.02 * 0.02), T(0.005 * 0.005)).asDiagonal());
    auto obs = std::make_unique<Observations<T, SB>>();
    auto res = std::make_unique<node::StepResult<T, SB>>();
    double x = 0;
    auto scan = [&](std::initializer_list<Vec2<double>> ls) {
      obs->clear();
      for (const Vec2<double>& l : ls)
        REQUIRE(obs->push(observe(Pose2<double>{x, 0, 0}, l).cast<T>(), R) == Status::kOk);
      REQUIRE(step->step(*obs, *res) == Status::kOk);
    };
    const Vec2<double> L0(3, 0.5), L1(4, -1), L2(33, 1), L3(34, -1), L4(35, 2), L5(2, 2);
    scan({L0});
    scan({L0});
    scan({L0, L1});
    scan({L0, L1});
    const FeatureId id0 = step->slam().index_of(0) >= 0 ? 0 : -1, id1 = 1;
    REQUIRE(id0 == 0);
    REQUIRE(step->slam().hits(step->slam().index_of(id0)) > step->slam().hits(step->slam().index_of(id1)));
    for (int k = 0; k < 30; ++k) {  // 30 m along x
      REQUIRE(step->predict(ekf::Odometry<T>{T(1), T(0), T(1), T(0.001), T(0.0001)}) == Status::kOk);
      x += 1;
    }
    scan({L2, L3});
    REQUIRE(step->slam().landmarks() == 4);
    const Vec2<T> l0_before = step->slam().landmark(step->slam().index_of(id0));
    scan({L2, L3, L4});
    CHECK(res->outcome[0] == node::Outcome::kPaired);
    CHECK(res->outcome[1] == node::Outcome::kPaired);
    CHECK(step->slam().landmarks() == 4);
    if (!evict) {
      CHECK(res->outcome[2] == node::Outcome::kNotAugmented);
      CHECK(res->review.evicted == 0);
      CHECK(step->slam().index_of(id1) >= 0);
      continue;
    }
    REQUIRE(res->outcome[2] == node::Outcome::kNewLandmark);
    CHECK(res->feature[2] == 4);  // the next id
    CHECK(res->review.evicted == 1);
    CHECK(step->slam().index_of(id1) == -1);  // L1: beyond r + d and the least seen
    for (const FeatureId id : {0, 2, 3, 4}) CHECK(step->slam().index_of(id) >= 0);
    CHECK(step->slam().landmark(step->slam().index_of(id0)) == l0_before);
    // Every landmark within r + d (a map filled where the robot is): nothing can go, the new one
    // is refused.
    auto near = std::make_unique<node::SlamStep<T, SB>>();
    REQUIRE(near->configure(s) == Status::kOk);
    REQUIRE(near->reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
    obs->clear();
    for (const Vec2<double>& l : {L0, L1, L5, Vec2<double>(5, 0), Vec2<double>(6, -2)})
      REQUIRE(obs->push(observe(Pose2<double>{0, 0, 0}, l).cast<T>(), R) == Status::kOk);
    REQUIRE(near->step(*obs, *res) == Status::kOk);
    CHECK(near->slam().landmarks() == 4);
    CHECK(res->review.evicted == 0);
    int refused = 0;
    for (int i = 0; i < res->count; ++i) refused += res->outcome[i] == node::Outcome::kNotAugmented;
    CHECK(refused == 1);
  }
}

TEST_CASE_TEMPLATE("removed landmarks are named: the first 8 ids in order, all counted, until cleared", T, float,
                   double) {
  // What a device's POSE reports (the host's seed leaves out what the local map still holds).
  auto r = std::make_unique<Rig<T>>();
  REQUIRE(r->slam.reset(Pose2<T>{}, Mat3<T>::Identity() * T(1e-6)) == Status::kOk);
  const Mat2<T> R = Mat2<T>(Vec2<T>(T(0.02 * 0.02), T(0.005 * 0.005)).asDiagonal());
  FeatureId ids[12];
  for (int k = 0; k < 12; ++k) {
    REQUIRE(r->slam.augment(Vec2<T>(T(4) + T(0.5) * T(k), T(0.05) * T(k)), R, ids[k]) == Status::kOk);
  }
  CHECK(r->slam.removed().count == 0);
  // A restart keeps landmarks 3 and 7: ten removed, the first eight named in order.
  std::int16_t keep[LB::kMaxLandmarks] = {3, 7};
  REQUIRE(r->slam.restart(Mat3<T>::Identity() * T(1e-6), keep, 2) == Status::kOk);
  const RemovedIds& gone = r->slam.removed();
  CHECK(gone.count == 10);
  const FeatureId named[RemovedIds::kMaxIds] = {ids[0], ids[1], ids[2], ids[4], ids[5], ids[6], ids[8], ids[9]};
  for (int k = 0; k < RemovedIds::kMaxIds; ++k) CHECK(gone.ids[static_cast<std::size_t>(k)] == named[k]);
  r->slam.clear_removed();
  CHECK(r->slam.removed().count == 0);
  // Another rule, the same report: an eviction names the landmark it removes.
  FeatureId evicted = -1;
  REQUIRE(r->slam.evict(T(1), evicted) == Status::kOk);
  CHECK(r->slam.removed().count == 1);
  CHECK(r->slam.removed().ids[0] == evicted);
  CHECK((evicted == ids[3] || evicted == ids[7]));
  CHECK(r->slam.landmarks() == 1);
}
