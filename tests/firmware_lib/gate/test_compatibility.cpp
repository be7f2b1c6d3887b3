// Individual gate and local region: the gate boundary, bearing wrap across +-pi, eq. 5's strict <;
// an S that is not positive definite gates nothing.
#include <doctest/doctest.h>

#include <limits>

#include "geojcbb/gate/compatibility.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {
// One observation, n candidates with independent unit-ish covariances.
template <typename T, class B>
void one_obs(Problem<T, B>& p, Vec2<T> z, std::initializer_list<Vec2<T>> hs) {
  p.obs.count = 1;
  p.obs.z[0] = z;
  p.obs.R[0] = Mat2<T>::Identity() * T(0.01);
  p.pred.count = static_cast<int>(hs.size());
  p.pred.C.set_identity(p.pred.count, T(0));
  int j = 0;
  for (const auto& h : hs) {
    p.pred.id[j] = 100 + j;
    p.pred.h[j] = h;
    p.pred.C.set_block(j, j, Mat2<T>::Identity() * T(0.01));
    ++j;
  }
}
}  // namespace

TEST_CASE_TEMPLATE("a landmark at +179.5 deg observed at -179.5 deg is compatible", T, float, double) {
  auto p = make_problem<T, DefaultBounds>();
  const T deg = kPi<T> / T(180);
  one_obs<T, DefaultBounds>(*p, Vec2<T>(T(5), T(-179.5) * deg), {Vec2<T>(T(5), T(179.5) * deg)});
  auto cfg = make_config<T, DefaultBounds>(SearchMethod::kJcbb, false, false);
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == 100);
  // innovation 1 deg, S = 0.02 rad^2 on the bearing: d2 = (pi/180)^2 / 0.02
  CHECK(p->out.d2[0] == doctest::Approx(deg * deg / T(0.02)).epsilon(1e-3));
}

TEST_CASE_TEMPLATE("the individual gate accepts d2 at the threshold and rejects just above", T, float, double) {
  auto p = make_problem<T, DefaultBounds>();
  auto cfg = make_config<T, DefaultBounds>(SearchMethod::kIcnn, false, false);
  // Range innovation e with S_rr = 0.02: d2 = e^2 / 0.02. Put d2 at the threshold and 0.1 % over.
  const T e_at = std::sqrt(cfg.gate.individual * T(0.02));
  one_obs<T, DefaultBounds>(*p, Vec2<T>(T(5) + e_at * T(0.9995), T(0)), {Vec2<T>(T(5), T(0))});
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == 100);
  one_obs<T, DefaultBounds>(*p, Vec2<T>(T(5) + e_at * T(1.001), T(0)), {Vec2<T>(T(5), T(0))});
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == kNewFeature);
  CHECK(p->out.d2[0] > cfg.gate.individual);
}

TEST_CASE_TEMPLATE("local region keeps candidates with predicted range < r + d only (eq. 5)", T, float, double) {
  auto p = make_problem<T, DefaultBounds>();
  one_obs<T, DefaultBounds>(*p, Vec2<T>(T(9.9), T(0)),
                            {Vec2<T>(T(9.9), T(0)), Vec2<T>(T(10), T(0.5)), Vec2<T>(T(3), T(0))});
  auto cfg = make_config<T, DefaultBounds>(SearchMethod::kJcbb, false, false);
  cfg.local_region = true;
  cfg.local_radius_m = T(10);
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.diag.candidates_in_region == 2);  // 10.0 is not < 10
  CHECK(p->out.feature[0] == 100);
  cfg.local_radius_m = T(9.5);
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.diag.candidates_in_region == 1);
  CHECK(p->out.feature[0] == kNewFeature);  // its only match is outside the region
}

TEST_CASE_TEMPLATE("new vs unmatched: no compatible candidate is new - compatible but left out is unmatched", T, float,
                   double) {
  auto p = make_problem<T, DefaultBounds>();
  // Two observations at the same spot, one candidate, mutual exclusion: one pairs, the other is
  // compatible but unpaired (unmatched); a third far away is new.
  p->obs.count = 3;
  p->obs.z[0] = Vec2<T>(T(5), T(0));
  p->obs.z[1] = Vec2<T>(T(5.01), T(0));
  p->obs.z[2] = Vec2<T>(T(2), T(1));
  for (int i = 0; i < 3; ++i) p->obs.R[i] = Mat2<T>::Identity() * T(0.01);
  p->pred.count = 1;
  p->pred.id[0] = 7;
  p->pred.h[0] = Vec2<T>(T(5), T(0));
  p->pred.C.set_identity(1, T(0.01));
  auto cfg = make_config<T, DefaultBounds>(SearchMethod::kJcbb, true, true);
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == 7);
  CHECK(p->out.feature[1] == kUnmatched);
  CHECK(p->out.feature[2] == kNewFeature);
  CHECK(p->out.pairings == 1);
}

TEST_CASE_TEMPLATE("new if candidates taken: an observation whose only compatible feature is taken is new", T, float,
                   double) {
  auto p = make_problem<T, DefaultBounds>();
  // As above, with the option: observation 1 could only be feature 7, which observation 0 holds.
  p->obs.count = 3;
  p->obs.z[0] = Vec2<T>(T(5), T(0));
  p->obs.z[1] = Vec2<T>(T(5.01), T(0));
  p->obs.z[2] = Vec2<T>(T(2), T(1));
  for (int i = 0; i < 3; ++i) p->obs.R[i] = Mat2<T>::Identity() * T(0.01);
  p->pred.count = 2;
  p->pred.id[0] = 7;
  p->pred.h[0] = Vec2<T>(T(5), T(0));
  p->pred.id[1] = 8;
  p->pred.h[1] = Vec2<T>(T(9), T(1));  // far from everything
  p->pred.C.set_identity(2, T(0.01));
  auto cfg = make_config<T, DefaultBounds>(SearchMethod::kJcbb, true, true);
  cfg.new_if_candidates_taken = true;
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == 7);
  CHECK(p->out.feature[1] == kNewFeature);
  // Its d2 for the augmentation gate is the nearest over the features it could be: feature 8 only.
  const Mat2<T> S = Mat2<T>::Identity() * T(0.02);
  CHECK(p->out.d2[1] == doctest::Approx(double(mahalanobis2(innovation(p->obs.z[1], p->pred.h[1]), S))));
  CHECK(p->out.feature[2] == kNewFeature);
  // Without mutual exclusion the option does nothing: both pair with 7.
  cfg.mutual_exclusion = false;
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[1] == 7);
}

TEST_CASE_TEMPLATE("decline: an observation between two features is left unmatched; a clear one is paired", T, float,
                   double) {
  for (const SearchMethod search : {SearchMethod::kJcbb, SearchMethod::kIcnn}) {
    auto p = make_problem<T, DefaultBounds>();
    // Observation 0 lies midway between features 100 and 101 (equal d2); observation 1 sits on
    // feature 102, far from the others.
    p->obs.count = 2;
    p->obs.z[0] = Vec2<T>(T(5), T(0.01));
    p->obs.z[1] = Vec2<T>(T(3), T(-0.6));
    for (int i = 0; i < 2; ++i) p->obs.R[i] = Mat2<T>::Identity() * T(1e-5);
    p->pred.count = 3;
    p->pred.C.set_identity(3, T(1e-5));  // S: 0.0045 rad
    const Vec2<T> h[3] = {Vec2<T>(T(5), T(0)), Vec2<T>(T(5), T(0.02)), Vec2<T>(T(3), T(-0.6))};
    for (int j = 0; j < 3; ++j) {
      p->pred.id[j] = 100 + j;
      p->pred.h[j] = h[j];
    }
    auto cfg = make_config<T, DefaultBounds>(search, true, true);
    CAPTURE(static_cast<int>(search));
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    CHECK(p->out.feature[0] >= 100);  // off: a guess
    CHECK(p->out.diag.declined == 0);
    cfg.ambiguity_margin = T(1);
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    CHECK(p->out.feature[0] == kUnmatched);  // on: declined, neither paired nor new
    CHECK(p->out.feature[1] == 102);
    CHECK(p->out.pairings == 1);
    CHECK(p->out.diag.declined == 1);
    // The reported joint d2 is the kept hypothesis's: observation 1 alone, on its feature.
    CHECK(p->out.joint_d2 == doctest::Approx(0.0).epsilon(1e-6));
    // Move observation 0 next to feature 100: feature 101 is out of its gate, so it is paired.
    p->obs.z[0] = Vec2<T>(T(5), T(-0.002));
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    CHECK(p->out.feature[0] == 100);
    CHECK(p->out.diag.declined == 0);
  }
}

// Found by tests/fuzz/fuzz_node: C's blocks are checked positive semidefinite only within rounding,
// so C + R is indefinite for a tiny R; the closed-form d2 was then negative and passed the gate, and
// the device's ASSOC_RESULT (d2 must be >= 0 or +inf) could not be encoded. A pair whose S is not
// positive definite is now incompatible, and d2 is never negative.
TEST_CASE_TEMPLATE("an S that rounding left indefinite gates nothing; d2 is never negative", T, float, double) {
  const T eps = std::numeric_limits<T>::epsilon();
  Mat2<T> S;
  S << T(1), T(1) + T(100) * eps, T(1) + T(100) * eps, T(1);
  CHECK(mahalanobis2(Vec2<T>(T(1), T(-1)), S) == std::numeric_limits<T>::infinity());
  S << T(1), T(0), T(0), T(-1);
  CHECK(mahalanobis2(Vec2<T>(T(0.1), T(0.1)), S) == std::numeric_limits<T>::infinity());
  S << T(1), T(0.5), T(0.5), T(1);
  CHECK(mahalanobis2(Vec2<T>(T(0), T(0)), S) == T(0));
  CHECK(mahalanobis2(Vec2<T>(T(1), T(0)), S) == doctest::Approx(T(4) / T(3)));

  auto p = make_problem<T, DefaultBounds>();
  one_obs<T, DefaultBounds>(*p, Vec2<T>(T(6), T(-0.5)), {Vec2<T>(T(5), T(0.5))});
  // C's block is PSD within rounding (det = -200 eps, inside is_psd's 1024 eps), R = eps I.
  Mat2<T> C;
  C << T(1), T(1) + T(100) * eps, T(1) + T(100) * eps, T(1);
  p->pred.C.set_block(0, 0, C);
  p->obs.R[0] = Mat2<T>::Identity() * eps;
  auto cfg = make_config<T, DefaultBounds>(SearchMethod::kJcbb, false, false);
  REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] != 100);
  CHECK(!(p->out.d2[0] < T(0)));
}
