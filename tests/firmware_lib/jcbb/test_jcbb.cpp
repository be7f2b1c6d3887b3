// JCBB and ICNN behaviour: node budget respected and flagged (anytime answer still jointly
// compatible); mutual exclusion holds when on; two observations may share a feature when off;
// the incremental joint d2 equals a from-scratch computation.
#include <doctest/doctest.h>

#include <random>

#include "geojcbb_host/scene.hpp"
#include "support/helpers.hpp"
#include "support/oracle.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {
host::SceneParams dense_params(int m, int n) {
  host::SceneParams p;
  p.observations = m;
  p.landmarks = n;
  p.max_range_m = 6.0;
  p.sigma_pose_xy_m = 0.5;
  p.sigma_pose_theta_rad = 0.05;
  return p;
}
}  // namespace

TEST_CASE_TEMPLATE("the node budget is respected and flagged - the answer is still jointly compatible", T, float,
                   double) {
  using B = DefaultBounds;
  int hits = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const host::Scene scene = host::make_scene(dense_params(24, 32), seed);
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(scene, p->obs, p->pred));
    for (int budget : {1, 7, 50, 400}) {
      auto cfg = make_config<T, B>(SearchMethod::kJcbb, true, true);
      cfg.node_budget = budget;
      REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
      CHECK(p->out.diag.jcbb_nodes <= static_cast<std::uint32_t>(budget));
      CHECK(p->out.jointly_compatible);
      if (p->out.diag.node_budget_hit) {
        ++hits;
        CHECK(p->out.diag.jcbb_nodes == static_cast<std::uint32_t>(budget));
      }
    }
  }
  CHECK(hits > 0);  // the dense scenes do exhaust small budgets
}

TEST_CASE_TEMPLATE("with a budget that suffices, the answer equals the unbudgeted one", T, float, double) {
  using B = DefaultBounds;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const host::Scene scene = host::make_scene(dense_params(12, 20), seed);
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(scene, p->obs, p->pred));
    auto cfg = make_config<T, B>(SearchMethod::kJcbb, true, true);
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    REQUIRE_FALSE(p->out.diag.node_budget_hit);
    const auto full = p->out;
    cfg.node_budget = full.diag.jcbb_nodes;
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    CHECK_FALSE(p->out.diag.node_budget_hit);
    CHECK(p->out.pairings == full.pairings);
    CHECK(p->out.joint_d2 == full.joint_d2);
  }
}

TEST_CASE_TEMPLATE("node budget 0 is the capacity, as the option table says", T, float, double) {
  using B = DefaultBounds;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const host::Scene scene = host::make_scene(dense_params(24, 32), seed);
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(scene, p->obs, p->pred));
    auto cfg = make_config<T, B>(SearchMethod::kJcbb, true, true);
    cfg.node_budget = B::kMaxJcbbNodes;
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    const auto capacity = p->out;
    cfg.node_budget = 0;
    CHECK(cfg.search_nodes() == static_cast<NodeCount>(B::kMaxJcbbNodes));
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    CHECK(p->out.diag.jcbb_nodes == capacity.diag.jcbb_nodes);
    CHECK(p->out.diag.node_budget_hit == capacity.diag.node_budget_hit);
    CHECK(p->out.pairings == capacity.pairings);
    CHECK(p->out.joint_d2 == capacity.joint_d2);
  }
}

TEST_CASE_TEMPLATE("mutual exclusion: on, a feature takes one observation - off, two may share it", T, float, double) {
  using B = DefaultBounds;
  auto p = make_problem<T, B>();
  // Two returns from one post (e.g. its two edges) and a single mapped feature.
  p->obs.count = 2;
  p->obs.z[0] = Vec2<T>(T(5.02), T(0.005));
  p->obs.z[1] = Vec2<T>(T(4.98), T(-0.005));
  p->obs.R[0] = p->obs.R[1] = Mat2<T>(Vec2<T>(T(0.01), T(0.0003)).asDiagonal());
  p->pred.count = 1;
  p->pred.id[0] = 42;
  p->pred.h[0] = Vec2<T>(T(5), T(0));
  REQUIRE(p->pred.C.resize(1) == Status::kOk);
  p->pred.C.set_block(0, 0, Mat2<T>(Vec2<T>(T(0.01), T(0.0003)).asDiagonal()));
  for (auto search : {SearchMethod::kJcbb, SearchMethod::kIcnn}) {
    CAPTURE(static_cast<int>(search));
    auto off = make_config<T, B>(search, false, false);
    REQUIRE(associate(p->obs, p->pred, off, p->ws, p->out) == Status::kOk);
    CHECK(p->out.feature[0] == 42);
    CHECK(p->out.feature[1] == 42);
    CHECK(p->out.pairings == 2);
    auto on = make_config<T, B>(search, true, true);
    REQUIRE(associate(p->obs, p->pred, on, p->ws, p->out) == Status::kOk);
    CHECK(p->out.pairings == 1);
    CHECK((p->out.feature[0] == 42) != (p->out.feature[1] == 42));
  }
}

TEST_CASE_TEMPLATE("ICNN takes each observation's nearest compatible candidate", T, float, double) {
  using B = DefaultBounds;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    const host::Scene scene = host::make_scene(dense_params(10, 16), seed);
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(scene, p->obs, p->pred));
    auto cfg = make_config<T, B>(SearchMethod::kIcnn, false, false);
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    Oracle<T, B> o(p->obs, p->pred, cfg, 0, false);
    for (int i = 0; i < p->obs.count; ++i) {
      long double best = std::numeric_limits<long double>::infinity();
      int arg = -1;
      for (int j = 0; j < p->pred.count; ++j) {
        const long double d2 = o.individual_d2(i, j);
        if (d2 <= cfg.gate.individual && d2 < best) {
          best = d2;
          arg = j;
        }
      }
      CHECK(p->out.candidate[i] == arg);
    }
  }
}

TEST_CASE_TEMPLATE("incremental joint d2 equals a from-scratch solve, for any pairing order", T, float, double) {
  using B = DefaultBounds;
  std::mt19937_64 rng(5);
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    const host::Scene scene = host::make_scene(dense_params(16, 24), seed);
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(scene, p->obs, p->pred));
    auto cfg = make_config<T, B>(SearchMethod::kJcbb, false, false);
    Oracle<T, B> o(p->obs, p->pred, cfg, 0, false);
    // A random hypothesis (pairs may be incompatible: the algebra must hold regardless).
    std::vector<std::pair<int, int>> pairs;
    IncrementalJoint<T, B::kMaxObservations> joint;
    for (int i = 0; i < p->obs.count; ++i) {
      if (rng() % 4 == 0) continue;
      const int j = static_cast<int>(rng() % p->pred.count);
      pairs.emplace_back(i, j);
      T d2 = 0;
      REQUIRE(joint.try_push(p->pred.C, j, p->obs.R[i], innovation(p->obs.z[i], p->pred.h[j]), d2) == Status::kOk);
      joint.commit();
      const long double want = o.joint_d2(pairs);
      CHECK(static_cast<long double>(d2) ==
            doctest::Approx(static_cast<double>(want)).epsilon(std::is_same<T, float>::value ? 2e-3 : 1e-9));
    }
    // Popping returns to the earlier joint d2 exactly.
    if (pairs.size() >= 2) {
      joint.pop();
      pairs.pop_back();
      CHECK(
          static_cast<long double>(joint.d2()) ==
          doctest::Approx(static_cast<double>(o.joint_d2(pairs))).epsilon(std::is_same<T, float>::value ? 2e-3 : 1e-9));
    }
  }
}
