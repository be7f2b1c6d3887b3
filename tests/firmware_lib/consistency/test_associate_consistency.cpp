// The consistency stage inside associate() (pose-free consistency): verify drops the
// pairings of JCBB's answer that are not pairwise consistent (a constructed loop closure where JCBB
// alone takes a wrong hypothesis); seed uses the pose-free clique when the pose is uncertain (a
// constructed relocalisation) and is not tried otherwise; the PCJCBB preset; bad options give a
// status and leave the output untouched.
#include <doctest/doctest.h>

#include <limits>
#include <memory>

#include "support/consistency_scene.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {

using B = DefaultBounds;

template <typename T>
std::unique_ptr<Problem<T, B>> problem_of(const host::Scene& s) {
  auto p = make_problem<T, B>();
  REQUIRE(host::to_inputs(s, p->obs, p->pred));
  return p;
}

/// Plain JCBB (the paper's: no exclusion, no optimal criterion), optionally verified.
template <typename T>
AssociationConfig<T, B> jcbb_config(bool verify) {
  auto cfg = make_config<T, B>(SearchMethod::kJcbb, false, false);
  ConsistencyOptions<T> levels;
  REQUIRE(levels.set_confidence(0.99999, 0.999) == Status::kOk);
  cfg.consistency_wide_d2 = levels.wide_d2;
  cfg.consistency_pair_d2 = levels.pair_d2;
  cfg.verify = verify;
  return cfg;
}

template <typename T>
AssociationConfig<T, B> pcjcbb_config() {
  AssociationConfig<T, B> cfg;
  REQUIRE(make_strategy(Strategy::kPcjcbb, StepSettings<T>{}, cfg) == Status::kOk);
  return cfg;
}

/// A constructed loop closure: the robot back among eight old landmarks, its estimate 0.64 m and
/// 0.02 rad off with a pose covariance that admits it (1 m, 0.05 rad), the landmarks known to 0.2 m.
/// A ninth old landmark (6, 0) is not seen, but a clutter return lies 1.2 m beyond it. Individually
/// the return is compatible with it (the pose's share of C dominates); jointly the eight true
/// pairings pin the pose and the extra pairing adds about 26 to the joint d2, still under
/// chi2(0.99, 18) = 34.8 because one bad pairing is diluted over 18 dof. JCBB maximises pairings and
/// takes it. Its distances to the landmarks in line with the offset are 1.2 m off, with a standard
/// deviation of about 0.3 m: not pairwise consistent. Noise-free measurements.
host::Scene loop_closure_scene() {
  host::Scene s;
  s.true_pose = {0, 0, 0};
  s.est_pose = {0.5, -0.4, 0.02};
  s.true_landmarks = {{2.5, 0.6},  {3.2, -1.1}, {9.6, 0.9}, {10.4, -0.7}, {5.0, 4.5},
                      {7.5, -4.2}, {4.0, -3.0}, {8.5, 3.5}, {6.0, 0.0}};
  const int n = static_cast<int>(s.true_landmarks.size());
  s.est_landmarks = s.true_landmarks;
  s.P = Eigen::MatrixXd::Zero(3 + 2 * n, 3 + 2 * n);
  s.P.topLeftCorner<3, 3>() = Eigen::Vector3d(1.0, 1.0, 0.05 * 0.05).asDiagonal();
  s.P.bottomRightCorner(2 * n, 2 * n).diagonal().setConstant(0.2 * 0.2);
  host::predict_measurements(s);
  s.R = Eigen::Vector2d(0.1 * 0.1, 0.01 * 0.01).asDiagonal();
  for (int j = 0; j < n - 1; ++j) {  // landmark 8 missed
    s.z.push_back(observe(s.true_pose, Vec2<double>(s.true_landmarks[j])));
    s.truth.push_back(j);
  }
  s.z.push_back(observe(s.true_pose, Vec2<double>(6.0 + 1.2, 0.0)));  // the clutter return
  s.truth.push_back(-1);
  return s;
}

int right_pairings(const host::Scene& s, const std::array<std::int16_t, B::kMaxObservations>& c, int m) {
  int n = 0;
  for (int i = 0; i < m; ++i) n += s.truth[i] >= 0 && c[i] == s.truth[i];
  return n;
}
int wrong_pairings(const host::Scene& s, const std::array<std::int16_t, B::kMaxObservations>& c, int m) {
  int n = 0;
  for (int i = 0; i < m; ++i) n += c[i] >= 0 && c[i] != s.truth[i];
  return n;
}

}  // namespace

TEST_CASE_TEMPLATE("verify: at a constructed loop closure JCBB pairs wrongly and verification drops it", T, float,
                   double) {
  const host::Scene s = loop_closure_scene();
  auto plain = problem_of<T>(s);
  REQUIRE(associate(plain->obs, plain->pred, jcbb_config<T>(false), plain->ws, plain->out) == Status::kOk);
  const int m = plain->obs.count;
  // Precondition of the construction: JCBB alone takes a jointly compatible wrong hypothesis.
  REQUIRE(wrong_pairings(s, plain->out.candidate, m) > 0);
  CHECK(plain->out.jointly_compatible);
  CHECK(plain->out.diag.verify_dropped == 0);

  auto verified = problem_of<T>(s);
  REQUIRE(associate(verified->obs, verified->pred, jcbb_config<T>(true), verified->ws, verified->out) == Status::kOk);
  MESSAGE("JCBB: " << plain->out.pairings << " pairings, " << wrong_pairings(s, plain->out.candidate, m)
                   << " wrong; verified: " << verified->out.pairings << " pairings, "
                   << wrong_pairings(s, verified->out.candidate, m) << " wrong, " << verified->out.diag.verify_dropped
                   << " dropped");
  // Verification only removes pairings, and it removes every wrong one here.
  CHECK(verified->out.diag.verify_dropped > 0);
  CHECK(verified->out.pairings == plain->out.pairings - verified->out.diag.verify_dropped);
  CHECK(wrong_pairings(s, verified->out.candidate, m) == 0);
  for (int i = 0; i < m; ++i) {
    if (verified->out.candidate[i] >= 0) CHECK(verified->out.candidate[i] == plain->out.candidate[i]);
    // A dropped pairing leaves its observation neither paired nor new.
    if (plain->out.candidate[i] >= 0 && verified->out.candidate[i] < 0) CHECK(verified->out.feature[i] == kUnmatched);
  }
  CHECK(verified->out.diag.clique_graph_nodes == plain->out.pairings);
  CHECK_FALSE(verified->out.diag.clique_budget_hit);
  CHECK_FALSE(verified->out.diag.seed_tried);
}

TEST_CASE_TEMPLATE("verify: a consistent answer is kept whole", T, float, double) {
  // Generated scenes with a small, admitted pose error: where JCBB's answer is all correct, the
  // verified answer is the same.
  int compared = 0;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(10, 14, 0.3, 0.03), seed);
    auto a = problem_of<T>(s);
    auto b = problem_of<T>(s);
    REQUIRE(associate(a->obs, a->pred, jcbb_config<T>(false), a->ws, a->out) == Status::kOk);
    if (wrong_pairings(s, a->out.candidate, a->obs.count) > 0) continue;
    REQUIRE(associate(b->obs, b->pred, jcbb_config<T>(true), b->ws, b->out) == Status::kOk);
    CAPTURE(seed);
    CHECK(b->out.diag.verify_dropped == 0);
    for (int i = 0; i < a->obs.count; ++i) CHECK(b->out.candidate[i] == a->out.candidate[i]);
    CHECK(b->out.joint_d2 == a->out.joint_d2);
    ++compared;
  }
  CHECK(compared >= 20);
}

TEST_CASE_TEMPLATE("seed: a constructed relocalisation is found from the pose-free clique", T, float, double) {
  const host::Scene s = wrong_pose_scene();  // pose 2.5 m, 0.8 rad off; its covariance admits it
  auto p = problem_of<T>(s);
  const auto cfg = pcjcbb_config<T>();
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.diag.seed_tried);
  CHECK(p->out.diag.seed_used);
  CHECK(p->out.diag.seed_pairings == 7);
  CHECK(p->out.jointly_compatible);
  for (int i = 0; i < p->obs.count; ++i) CHECK(p->out.candidate[i] == s.truth[i]);
  // JCBB with the same switches but no seed (for information).
  auto q = problem_of<T>(s);
  auto unseeded = cfg;
  unseeded.seed = false;
  REQUIRE(associate(q->obs, q->pred, unseeded, q->ws, q->out) == Status::kOk);
  MESSAGE("unseeded: " << right_pairings(s, q->out.candidate, q->obs.count) << " of 7 right, "
                       << wrong_pairings(s, q->out.candidate, q->obs.count) << " wrong");
}

TEST_CASE_TEMPLATE("seed: not tried when the pose is certain; PCJCBB is then JCBB + exclusion + optimal + verify", T,
                   float, double) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(10, 14, 0.3, 0.03), seed);
    auto a = problem_of<T>(s);
    auto b = problem_of<T>(s);
    const auto cfg = pcjcbb_config<T>();
    auto plain = make_config<T, B>(SearchMethod::kJcbb, true, true);
    plain.verify = true;
    plain.consistency_wide_d2 = cfg.consistency_wide_d2;
    plain.consistency_pair_d2 = cfg.consistency_pair_d2;
    REQUIRE(associate(a->obs, a->pred, cfg, a->ws, a->out) == Status::kOk);
    REQUIRE(associate(b->obs, b->pred, plain, b->ws, b->out) == Status::kOk);
    CAPTURE(seed);
    CHECK_FALSE(a->out.diag.seed_tried);
    for (int i = 0; i < a->obs.count; ++i) CHECK(a->out.candidate[i] == b->out.candidate[i]);
  }
}

TEST_CASE_TEMPLATE("seed and verify: bad options and input give a status and leave the output untouched", T, float,
                   double) {
  const host::Scene s = wrong_pose_scene();
  auto p = problem_of<T>(s);
  auto expect = [&](const AssociationConfig<T, B>& cfg, Status want) {
    p->out.count = 99;
    p->out.pairings = 77;
    p->out.diag.verify_dropped = 55;
    CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == want);
    CHECK(p->out.count == 99);
    CHECK(p->out.pairings == 77);
    CHECK(p->out.diag.verify_dropped == 55);
  };
  const T nan = std::numeric_limits<T>::quiet_NaN();
  {
    auto cfg = jcbb_config<T>(true);
    cfg.consistency_pair_d2 = nan;  // verify needs the pairwise gate
    expect(cfg, Status::kInvalidInput);
    cfg.verify = false;  // unused options are not checked
    CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  }
  {
    auto cfg = pcjcbb_config<T>();
    cfg.consistency_wide_d2 = nan;       // the seed needs the wide gate (the clique budget is the stage's
    expect(cfg, Status::kInvalidInput);  // constant: a budget over its cap, test_consistent_hypothesis)
  }
  {
    auto cfg = pcjcbb_config<T>();
    cfg.seed_min_position_var_m2 = T(0);
    expect(cfg, Status::kInvalidInput);
    cfg.seed_min_position_var_m2 = nan;
    expect(cfg, Status::kInvalidInput);
  }
  {
    auto cfg = pcjcbb_config<T>();
    cfg.seed_min_pairings = 1;
    expect(cfg, Status::kInvalidInput);
  }
  {
    auto cfg = pcjcbb_config<T>();
    cfg.search = SearchMethod::kIcnn;  // the seed extends a JCBB search
    expect(cfg, Status::kInvalidInput);
  }
  {
    StepSettings<T> sp;
    sp.seed_min_position_var_m2 = T(-1);
    AssociationConfig<T, B> cfg;
    CHECK(make_strategy(Strategy::kPcjcbb, sp, cfg) == Status::kInvalidInput);
    sp = StepSettings<T>{};
    sp.consistency_pair_d2 = T(-1);
    CHECK(make_strategy(Strategy::kPcjcbb, sp, cfg) == Status::kInvalidInput);
    sp = StepSettings<T>{};
    sp.consistency_wide_d2 = nan;
    CHECK(make_strategy(Strategy::kPcjcbb, sp, cfg) == Status::kInvalidInput);
  }
  {
    const auto cfg = pcjcbb_config<T>();
    p->obs.z[1].y() = nan;
    expect(cfg, Status::kNonFinite);
  }
}

TEST_CASE("PCJCBB: its name and its switches") {
  CHECK(std::string(to_string(Strategy::kPcjcbb)) == "PCJCBB");
  AssociationConfig<double, B> cfg;
  REQUIRE(make_strategy(Strategy::kPcjcbb, StepSettings<double>{}, cfg) == Status::kOk);
  CHECK(cfg.search == SearchMethod::kJcbb);
  CHECK(cfg.grouping == Grouping::kNone);
  CHECK(cfg.mutual_exclusion);
  CHECK(cfg.optimal_criterion);
  CHECK(cfg.verify);
  CHECK(cfg.seed);
  CHECK_FALSE(cfg.local_region);
  // The preset's consistency thresholds are the chi-square quantiles they stand for.
  ConsistencyOptions<double> ref;
  REQUIRE(ref.set_confidence(0.99999, 0.999) == Status::kOk);
  CHECK(consistency_options(cfg).wide_d2 == doctest::Approx(ref.wide_d2).epsilon(1e-6));
  CHECK(consistency_options(cfg).pair_d2 == doctest::Approx(ref.pair_d2).epsilon(1e-6));
  // The papers' presets are unchanged unless the verification is asked for.
  for (int k = 0; k < kPaperStrategyCount; ++k) {
    StepSettings<double> sp;
    sp.local_radius_m = 10;
    REQUIRE(make_strategy(static_cast<Strategy>(k), sp, cfg) == Status::kOk);
    CHECK_FALSE(cfg.verify);
    CHECK_FALSE(cfg.seed);
    sp.verify = true;
    REQUIRE(make_strategy(static_cast<Strategy>(k), sp, cfg) == Status::kOk);
    CHECK(cfg.verify);
    CHECK_FALSE(cfg.seed);
  }
}
