// Bad input: every class gets its specific status, and the output is left exactly as it was.
#include <doctest/doctest.h>

#include <cstring>
#include <functional>

#include "geojcbb_host/scene.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {
/// The packed C as a dense matrix (every entry through the accessor).
template <typename T, class B>
Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> dense_of(const JointCovariance<T, B>& C) {
  Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> D(C.rows(), C.cols());
  for (int r = 0; r < C.rows(); ++r)
    for (int c = 0; c < C.cols(); ++c) D(r, c) = C(r, c);
  return D;
}
/// Same candidates and every entry bit for bit (the blocks past the count are not C's).
template <typename T, class B>
bool same_C(const JointCovariance<T, B>& x, const JointCovariance<T, B>& y) {
  if (x.rows() != y.rows()) return false;
  for (int r = 0; r < x.rows(); ++r) {
    for (int c = 0; c < x.cols(); ++c) {
      const T a = x(r, c), b = y(r, c);
      if (std::memcmp(&a, &b, sizeof(T)) != 0) return false;
    }
  }
  return true;
}
}  // namespace

TEST_CASE_TEMPLATE("bad input gets a specific status and leaves the output untouched", T, float, double) {
  using B = DefaultBounds;
  host::SceneParams sp;
  sp.observations = 6;
  sp.landmarks = 8;
  const host::Scene scene = host::make_scene(sp, 1234);
  auto base = make_problem<T, B>();
  REQUIRE(host::to_inputs(scene, base->obs, base->pred));
  const auto cfg0 = make_config<T, B>(SearchMethod::kJcbb, true, true);
  const T nan = std::numeric_limits<T>::quiet_NaN();
  const T inf = std::numeric_limits<T>::infinity();

  struct Case {
    const char* name;
    Status want;
    std::function<void(Problem<T, B>&, AssociationConfig<T, B>&)> corrupt;
    /// With C checked where read (packed covariance), when it differs from `want`: kOk
    /// for an entry no test of this scene reads, whose answer must then be the clean input's.
    bool unread_where_read = false;
  };
  const Case cases[] = {
      {"NaN range", Status::kNonFinite, [&](auto& p, auto&) { p.obs.z[2].x() = nan; }},
      {"Inf bearing", Status::kNonFinite, [&](auto& p, auto&) { p.obs.z[0].y() = inf; }},
      {"NaN in R", Status::kNonFinite, [&](auto& p, auto&) { p.obs.R[1](1, 1) = nan; }},
      {"Inf in h", Status::kNonFinite, [&](auto& p, auto&) { p.pred.h[3].x() = inf; }},
      {"NaN in C off-diagonal", Status::kNonFinite, [&](auto& p, auto&) { p.pred.C(7, 2) = nan; }},
      {"negative range", Status::kInvalidInput, [&](auto& p, auto&) { p.obs.z[0].x() = T(-0.1); }},
      {"bearing beyond pi", Status::kInvalidInput, [&](auto& p, auto&) { p.obs.z[0].y() = T(3.2); }},
      {"R not symmetric", Status::kNotSymmetric, [&](auto& p, auto&) { p.obs.R[0](0, 1) = T(1e-3); }},
      {"R not positive definite", Status::kNotPositiveDefinite,
       [&](auto& p, auto&) { p.obs.R[4] << T(0.01), T(0.02), T(0.02), T(0.01); }},
      {"R zero", Status::kNotPositiveDefinite, [&](auto& p, auto&) { p.obs.R[4].setZero(); }},
      // A cross block cannot be asymmetric in the packed C (packed covariance): that is
      // checked where a dense C comes in (the test "a dense C's asymmetric cross block is refused
      // where it comes in" below). A diagonal block is stored whole and is still validate()'s to
      // check, in both modes.
      {"C diagonal block not symmetric", Status::kNotSymmetric, [&](auto& p, auto&) { p.pred.C(5, 4) += T(0.5); }},
      {"C block indefinite", Status::kNotPositiveDefinite, [&](auto& p, auto&) { p.pred.C(2, 2) = T(-1); }},
      {"C wrong size", Status::kInvalidInput,
       [&](auto& p, auto&) { CHECK(p.pred.C.resize(p.pred.count - 1) == Status::kOk); }},
      {"observations over capacity", Status::kCapacityExceeded,
       [&](auto& p, auto&) { p.obs.count = B::kMaxObservations + 1; }},
      {"candidates over capacity", Status::kCapacityExceeded,
       [&](auto& p, auto&) { p.pred.count = B::kMaxCandidates + 1; }},
      {"negative count", Status::kInvalidInput, [&](auto& p, auto&) { p.obs.count = -1; }},
      {"negative feature id", Status::kInvalidInput, [&](auto& p, auto&) { p.pred.id[1] = -3; }},
      {"node budget over capacity", Status::kInvalidInput,
       [&](auto&, auto& c) { c.node_budget = B::kMaxJcbbNodes + 1; }},
      {"thresholds not set", Status::kInvalidInput,
       [&](auto&, auto& c) { c.gate = GateThresholds<T, B::kMaxObservations>{}; }},
      {"local radius NaN", Status::kInvalidInput,
       [&](auto&, auto& c) {
         c.local_region = true;
         c.local_radius_m = nan;
       }},
  };
  auto clean = std::make_unique<Problem<T, B>>(*base);
  std::memset(static_cast<void*>(&clean->out), 0x5A, sizeof(clean->out));
  REQUIRE(associate(clean->obs, clean->pred, cfg0, clean->ws, clean->out) == Status::kOk);
  for (CovarianceCheck check : {CovarianceCheck::kFull, CovarianceCheck::kWhereRead}) {
    for (const Case& c : cases) {
      CAPTURE(c.name);
      CAPTURE(static_cast<int>(check));
      auto p = std::make_unique<Problem<T, B>>(*base);
      auto cfg = cfg0;
      cfg.covariance_check = check;
      c.corrupt(*p, cfg);
      // Sentinel output: every byte set, so any write shows.
      std::memset(static_cast<void*>(&p->out), 0x5A, sizeof(p->out));
      Association<T, B> before;
      std::memcpy(static_cast<void*>(&before), &p->out, sizeof(before));
      if (check == CovarianceCheck::kWhereRead && c.unread_where_read) {
        CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
        CHECK(std::memcmp(&clean->out, &p->out, sizeof(p->out)) == 0);  // the clean answer
        continue;
      }
      CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == c.want);
      CHECK(std::memcmp(&before, &p->out, sizeof(before)) == 0);
    }
  }
}

TEST_CASE_TEMPLATE("an indefinite C found in the joint test is reported, output untouched", T, float, double) {
  using B = DefaultBounds;
  auto p = make_problem<T, B>();
  // Two candidates whose 2x2 blocks are fine but whose cross block makes C indefinite, and R tiny.
  p->obs.count = 2;
  p->obs.z[0] = Vec2<T>(T(5), T(0));
  p->obs.z[1] = Vec2<T>(T(6), T(0.5));
  p->obs.R[0] = p->obs.R[1] = Mat2<T>::Identity() * T(1e-6);
  p->pred.count = 2;
  p->pred.id[0] = 0;
  p->pred.id[1] = 1;
  p->pred.h[0] = p->obs.z[0];
  p->pred.h[1] = p->obs.z[1];
  p->pred.C.set_identity(2);
  p->pred.C(2, 0) = T(3);  // and C(0, 2): |correlation| > 1
  auto cfg = make_config<T, B>(SearchMethod::kJcbb, false, false);
  std::memset(static_cast<void*>(&p->out), 0x5A, sizeof(p->out));
  Association<T, B> before;
  std::memcpy(static_cast<void*>(&before), &p->out, sizeof(before));
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kNotPositiveDefinite);
  CHECK(std::memcmp(&before, &p->out, sizeof(before)) == 0);
}

TEST_CASE_TEMPLATE("empty input is not an error: an empty answer", T, float, double) {
  using B = DefaultBounds;
  auto p = make_problem<T, B>();
  REQUIRE(p->pred.C.resize(0) == Status::kOk);
  for (auto search : {SearchMethod::kIcnn, SearchMethod::kJcbb}) {
    auto cfg = make_config<T, B>(search, true, true);
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    CHECK(p->out.count == 0);
    CHECK(p->out.pairings == 0);
    // Observations but no candidates: all new.
    p->obs.count = 2;
    p->obs.z[0] = p->obs.z[1] = Vec2<T>(T(1), T(0));
    p->obs.R[0] = p->obs.R[1] = Mat2<T>::Identity();
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    CHECK(p->out.feature[0] == kNewFeature);
    CHECK(p->out.feature[1] == kNewFeature);
    p->obs.count = 0;
  }
}

TEST_CASE_TEMPLATE("with the local region on, C is validated where it is read: inside the region", T, float, double) {
  using B = DefaultBounds;
  auto p = make_problem<T, B>();
  p->obs.count = 1;
  p->obs.z[0] = Vec2<T>(T(4), T(0));
  p->obs.R[0] = Mat2<T>::Identity() * T(0.01);
  p->pred.count = 3;
  const T ranges[] = {T(4), T(6), T(30)};  // the last is outside r + d = 10 m
  p->pred.C.set_identity(3, T(0.01));
  for (int j = 0; j < 3; ++j) {
    p->pred.id[j] = j;
    p->pred.h[j] = Vec2<T>(ranges[j], T(0));
  }
  auto cfg = make_config<T, B>(SearchMethod::kJcbb, true, true);
  cfg.local_region = true;
  cfg.local_radius_m = T(10);
  p->pred.C(5, 1) = std::numeric_limits<T>::quiet_NaN();  // cross term of candidate 2 (outside)
  p->pred.C(4, 4) = T(-1);                                // its own block, indefinite
  // The full check (CovarianceCheck::kFull: every block between candidates in the region, up front).
  cfg.covariance_check = CovarianceCheck::kFull;
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == 0);
  cfg.local_region = false;  // now every candidate is read
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kNonFinite);
  cfg.local_region = true;
  p->pred.C(3, 0) = std::numeric_limits<T>::quiet_NaN();  // cross term between two candidates inside
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kNonFinite);
  // The check where read (the default, packed covariance): diagonal blocks in the region
  // at gating, cross blocks when a joint test reads them. One observation: no joint test holds two
  // candidates, so the NaN cross term C(3, 0) inside the region is never read and cannot change the
  // answer.
  cfg.covariance_check = CovarianceCheck::kWhereRead;
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == 0);
  cfg.local_region = false;  // candidate 2's own block is now read by the gate: indefinite
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kNotPositiveDefinite);
  p->pred.C(4, 4) = T(0.01);  // its block fine again: its NaN cross term C(5, 1) is never read
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
  CHECK(p->out.feature[0] == 0);
  p->pred.C(4, 5) = std::numeric_limits<T>::quiet_NaN();  // inside candidate 2's own block: read
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kNonFinite);
}

// Packed covariance: C's cross blocks are checked where a joint (or pairwise) test reads
// them. A bad entry a test reads gets the same status as the full check's, output untouched; one
// that no test reads leaves the answer exactly as on the clean input. The full check
// (CovarianceCheck::kFull) still rejects both.
TEST_CASE_TEMPLATE("C's cross blocks are validated where the joint test reads them", T, float, double) {
  using B = DefaultBounds;
  const T nan = std::numeric_limits<T>::quiet_NaN();
  const T inf = std::numeric_limits<T>::infinity();
  int read_cases = 0;
  int unread_cases = 0;
  int refused_cases = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    host::SceneParams sp;
    sp.observations = 8;
    sp.landmarks = 14;
    sp.max_range_m = 8;
    auto base = scene_problem<T, B>(sp, seed);
    for (int preset = 0; preset < kStrategyCount; ++preset) {
      CAPTURE(seed);
      CAPTURE(preset);
      StepSettings<T> params;
      params.local_radius_m = T(100);             // every candidate in the region
      params.seed_min_position_var_m2 = T(1e-3);  // PCJCBB: the seed (pairwise tests) on every scene
      AssociationConfig<T, B> cfg;
      REQUIRE(make_strategy(static_cast<Strategy>(preset), params, cfg) == Status::kOk);
      auto clean = std::make_unique<Problem<T, B>>(*base);
      REQUIRE(associate(clean->obs, clean->pred, cfg, clean->ws, clean->out) == Status::kOk);
      // Two paired candidates: their cross block is read when the second joins the first.
      int c1 = -1, c2 = -1;
      for (int i = 0; i < clean->out.count; ++i) {
        if (clean->out.candidate[i] < 0) continue;
        (c1 < 0 ? c1 : c2) = clean->out.candidate[i];
        if (c2 >= 0) break;
      }
      // A candidate no observation is individually compatible with (never in any hypothesis), and
      // for the pose-free seed and verification not within their wide gate either: never read.
      int unread = -1;
      for (int j = 0; j < base->pred.count && unread < 0; ++j) {
        bool near = false;
        for (int i = 0; i < base->obs.count; ++i) {
          const Mat2<T> S = base->pred.C.block(j, j) + base->obs.R[i];
          near = near || mahalanobis2(innovation(base->obs.z[i], base->pred.h[j]), S) <= cfg.consistency_wide_d2;
        }
        if (!near) unread = j;
      }
      struct Bad {
        T value;
        bool mirror_only;  // corrupt one side only (asymmetry) or both (NaN / Inf on both sides)
        Status want;
      };
      // A one-sided change goes in through a dense C (BlockCovariance::assign_dense): a non-finite side
      // is kept for the stages to find; an asymmetry cannot be held by the packed C and is refused
      // there, whether or not a test would read it, with the prediction unchanged.
      const Bad bads[] = {
          {nan, false, Status::kNonFinite}, {inf, true, Status::kNonFinite}, {T(0.37), true, Status::kNotSymmetric}};
      const auto dense = dense_of<T, B>(base->pred.C);
      for (const Bad& bad : bads) {
        for (int which = 0; which < 2; ++which) {
          const int a = which == 0 ? c1 : unread;
          const int b = which == 0 ? c2 : (unread == 0 ? 1 : 0);
          if (a < 0 || b < 0 || a == b) continue;
          for (int entry = 0; entry < 4; ++entry) {
            auto p = std::make_unique<Problem<T, B>>(*base);
            const int r = 2 * a + entry / 2, c = 2 * b + entry % 2;
            auto D = dense;
            D(r, c) = bad.mirror_only ? D(r, c) + bad.value : bad.value;
            if (!bad.mirror_only) D(c, r) = bad.value;
            const Status loaded = p->pred.C.assign_dense(D);
            if (bad.want == Status::kNotSymmetric) {
              ++refused_cases;
              CHECK(loaded == Status::kNotSymmetric);
              CHECK(same_C<T, B>(p->pred.C, base->pred.C));
              continue;
            }
            REQUIRE(loaded == Status::kOk);
            std::memset(static_cast<void*>(&p->out), 0x5A, sizeof(p->out));
            Association<T, B> before;
            std::memcpy(static_cast<void*>(&before), &p->out, sizeof(before));
            if (which == 0) {
              ++read_cases;
              CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == bad.want);
              CHECK(std::memcmp(&before, &p->out, sizeof(before)) == 0);
            } else {
              ++unread_cases;
              std::memcpy(static_cast<void*>(&p->out), &clean->out, sizeof(p->out));  // same padding
              p->out.count = -1;
              REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
              CHECK(std::memcmp(&clean->out, &p->out, sizeof(p->out)) == 0);
            }
            auto full = cfg;
            full.covariance_check = CovarianceCheck::kFull;
            std::memcpy(static_cast<void*>(&p->out), &before, sizeof(before));
            CHECK(associate(p->obs, p->pred, full, p->ws, p->out) == bad.want);
            CHECK(std::memcmp(&before, &p->out, sizeof(before)) == 0);
          }
        }
      }
    }
  }
  CHECK(read_cases > 100);
  CHECK(unread_cases > 100);
  CHECK(refused_cases > 100);
}

// Packed covariance: the prediction holds C's lower block triangle, so an asymmetric
// cross block can only come in through a dense C (the C API, the Python binding,
// BlockCovariance::assign_dense). It is refused there with kNotSymmetric (within validate()'s
// tolerance it is accepted, the lower entry kept), and the prediction is left as it was; a
// non-finite entry on either side is kept for the stages.
TEST_CASE_TEMPLATE("a dense C's asymmetric cross block is refused where it comes in", T, float, double) {
  using B = DefaultBounds;
  host::SceneParams sp;
  sp.observations = 6;
  sp.landmarks = 8;
  const host::Scene scene = host::make_scene(sp, 1234);
  auto base = make_problem<T, B>();
  REQUIRE(host::to_inputs(scene, base->obs, base->pred));
  const auto dense = dense_of<T, B>(base->pred.C);
  REQUIRE(dense.rows() == 2 * base->pred.count);
  CHECK((dense - dense.transpose()).cwiseAbs().maxCoeff() == T(0));
  auto p = std::make_unique<Problem<T, B>>(*base);
  auto D = dense;
  D(5, 0) += T(0.5);  // cross block of candidates 2 and 0
  CHECK(p->pred.C.assign_dense(D) == Status::kNotSymmetric);
  CHECK(same_C<T, B>(p->pred.C, base->pred.C));
  D = dense;
  D(0, 5) *= T(1) + T(2) * std::numeric_limits<T>::epsilon();  // within rounding: accepted, lower kept
  REQUIRE(p->pred.C.assign_dense(D) == Status::kOk);
  CHECK(p->pred.C(0, 5) == dense(5, 0));
  CHECK(same_C<T, B>(p->pred.C, base->pred.C));
  D = dense;
  D(0, 5) = std::numeric_limits<T>::quiet_NaN();  // upper side non-finite: kept, found where read
  REQUIRE(p->pred.C.assign_dense(D) == Status::kOk);
  CHECK(std::isnan(p->pred.C(5, 0)));
  D = dense;
  D(4, 5) += T(0.5);  // inside candidate 2's diagonal block: stored whole, validate()'s to refuse
  REQUIRE(p->pred.C.assign_dense(D) == Status::kOk);
  CHECK(p->pred.C(4, 5) != p->pred.C(5, 4));
  auto cfg = make_config<T, B>(SearchMethod::kJcbb, true, true);
  CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kNotSymmetric);
  D.resize(2 * base->pred.count, 2 * base->pred.count - 1);  // not square
  CHECK(p->pred.C.assign_dense(D) == Status::kInvalidInput);
  D.resize(2 * B::kMaxCandidates + 2, 2 * B::kMaxCandidates + 2);
  CHECK(p->pred.C.assign_dense(D) == Status::kCapacityExceeded);
}

TEST_CASE_TEMPLATE("the full covariance check and the check where read give the same answers", T, float, double) {
  using B = DefaultBounds;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    host::SceneParams sp;
    sp.observations = 10;
    sp.landmarks = 20;
    sp.max_range_m = 8;
    auto p = scene_problem<T, B>(sp, seed);
    auto q = std::make_unique<Problem<T, B>>(*p);
    for (int preset = 0; preset < kStrategyCount; ++preset) {
      CAPTURE(seed);
      CAPTURE(preset);
      StepSettings<T> params;
      params.local_radius_m = T(7);
      AssociationConfig<T, B> lazy, full;
      REQUIRE(make_strategy(static_cast<Strategy>(preset), params, lazy) == Status::kOk);
      params.full_covariance_check = true;
      REQUIRE(make_strategy(static_cast<Strategy>(preset), params, full) == Status::kOk);
      CHECK(full.covariance_check == CovarianceCheck::kFull);
      REQUIRE(associate(p->obs, p->pred, lazy, p->ws, p->out) == Status::kOk);
      REQUIRE(associate(q->obs, q->pred, full, q->ws, q->out) == Status::kOk);
      CHECK(std::memcmp(&p->out, &q->out, sizeof(p->out)) == 0);
    }
  }
}
