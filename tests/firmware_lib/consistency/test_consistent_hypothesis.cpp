// The pose-free hypothesis (consistency/consistent_hypothesis.hpp): invariant to a rigid motion of the
// world; right where the predicted pose is badly wrong and nearest neighbour is not; a pairwise
// consistent hypothesis within the budget; bad input gives a status and touches nothing; no
// allocation; float and double agree on well-conditioned scenes.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "geojcbb/consistency/consistent_hypothesis.hpp"
#include "support/alloc_counter.hpp"
#include "support/consistency_scene.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {

using B = DefaultBounds;

template <typename T>
struct Run {
  Observations<T, B> obs;
  Prediction<T, B> pred;
  ConsistencyOptions<T> opt;
  ConsistencyWorkspace<T, B> ws;
  ConsistencyResult<B> out;
};

template <typename T>
std::unique_ptr<Run<T>> make_run(const host::Scene& s, PairingGate gate) {
  auto r = std::make_unique<Run<T>>();
  REQUIRE(host::to_inputs(s, r->obs, r->pred));
  REQUIRE(r->opt.set_confidence(0.99999, 0.999) == Status::kOk);
  r->opt.pairing_gate = gate;
  return r;
}

template <typename T>
Status solve(Run<T>& r) {
  return consistent_hypothesis(r.obs, r.pred, r.opt, r.ws, r.out);
}

/// The hypothesis is a matching (one candidate per observation, one observation per candidate), its
/// pairings are graph nodes and pairwise adjacent, and its size is the reported clique.
template <typename T>
void check_hypothesis_is_clique(const Run<T>& r) {
  const auto& out = r.out;
  REQUIRE(out.count == r.obs.count);
  int paired = 0;
  std::vector<int> node_of(out.count, -1);
  for (int i = 0; i < out.count; ++i) {
    if (out.candidate[i] < 0) continue;
    ++paired;
    for (int k = 0; k < i; ++k) CHECK(out.candidate[k] != out.candidate[i]);
    for (int x = 0; x < r.ws.pairings.count; ++x) {
      if (r.ws.pairings.node[x].obs == i && r.ws.pairings.node[x].cand == out.candidate[i]) node_of[i] = x;
    }
    REQUIRE(node_of[i] >= 0);
  }
  CHECK(paired == out.pairings);
  CHECK(out.diag.clique_size == out.pairings);
  for (int i = 0; i < out.count; ++i) {
    for (int k = i + 1; k < out.count; ++k) {
      if (node_of[i] >= 0 && node_of[k] >= 0) CHECK(r.ws.graph.has_edge(node_of[i], node_of[k]));
    }
  }
}

}  // namespace

TEST_CASE_TEMPLATE("consistency: the hypothesis is invariant to a rigid motion of the world", T, float, double) {
  int compared = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(10, 14, 1.0, 0.3), seed);
    for (const PairingGate gate : {PairingGate::kWide, PairingGate::kEveryCandidate}) {
      auto r0 = make_run<T>(s, gate);
      REQUIRE(solve(*r0) == Status::kOk);
      check_hypothesis_is_clique(*r0);
      for (const double phi : {0.7, -2.5, 3.0}) {
        const host::Scene moved = rigidly_moved(s, phi, Eigen::Vector2d(40.0 * phi, -25.0));
        auto r1 = make_run<T>(moved, gate);
        REQUIRE(solve(*r1) == Status::kOk);
        CAPTURE(seed);
        CAPTURE(phi);
        REQUIRE(r1->ws.pairings.count == r0->ws.pairings.count);
        for (int x = 0; x < r0->ws.pairings.count; ++x) {
          CHECK(r1->ws.pairings.node[x].obs == r0->ws.pairings.node[x].obs);
          CHECK(r1->ws.pairings.node[x].cand == r0->ws.pairings.node[x].cand);
        }
        CHECK(r1->ws.graph.count == r0->ws.graph.count);
        for (int x = 0; x < r0->ws.graph.count; ++x) CHECK(r1->ws.graph.adj[x] == r0->ws.graph.adj[x]);
        for (int i = 0; i < r0->obs.count; ++i) CHECK(r1->out.candidate[i] == r0->out.candidate[i]);
        CHECK(r1->out.diag.search_nodes == r0->out.diag.search_nodes);
        ++compared;
      }
    }
  }
  CHECK(compared == 120);
}

TEST_CASE_TEMPLATE("consistency: a badly wrong pose, where nearest neighbour fails, gets the true pairing", T, float,
                   double) {
  const host::Scene s = wrong_pose_scene();
  // Precondition of the construction: no two landmark pairs are equally far apart (the 21 distances
  // differ by at least 0.15 m, the most seven points in this area allowed in a random search), so a
  // wrong pairing can agree with a few distances but not with all of them.
  for (int a = 0; a < 7; ++a) {
    for (int b = a + 1; b < 7; ++b) {
      for (int c = 0; c < 7; ++c) {
        for (int d = c + 1; d < 7; ++d) {
          if (a == c && b == d) continue;
          const double dab = (s.true_landmarks[a] - s.true_landmarks[b]).norm();
          const double dcd = (s.true_landmarks[c] - s.true_landmarks[d]).norm();
          REQUIRE(std::abs(dab - dcd) > 0.15);
        }
      }
    }
  }
  // The same scene with an overconfident filter (the pose covariance 10 times too small in standard
  // deviation, as after a long drift): the graph must not change, it does not read the pose's share.
  host::Scene overconfident = s;
  overconfident.P.topLeftCorner<3, 3>() = Eigen::Vector3d(0.25 * 0.25, 0.25 * 0.25, 0.01).asDiagonal();
  host::predict_measurements(overconfident);
  auto honest = make_run<T>(s, PairingGate::kEveryCandidate);
  REQUIRE(solve(*honest) == Status::kOk);
  for (const host::Scene* scene : {&s, static_cast<const host::Scene*>(&overconfident)}) {
    auto r = make_run<T>(*scene, PairingGate::kEveryCandidate);
    // Nearest neighbour by individual d2 is wrong for most observations.
    int nn_wrong = 0;
    for (int i = 0; i < r->obs.count; ++i) {
      int best = -1;
      T best_d2 = std::numeric_limits<T>::infinity();
      for (int a = 0; a < r->pred.count; ++a) {
        const Mat2<T> S = r->pred.C.block(a, a) + r->obs.R[i];
        const T d2 = mahalanobis2(innovation(r->obs.z[i], r->pred.h[a]), S);
        if (d2 < best_d2) best_d2 = d2, best = a;
      }
      if (s.truth[i] >= 0 && best != s.truth[i]) ++nn_wrong;
    }
    CHECK(nn_wrong >= 4);
    REQUIRE(solve(*r) == Status::kOk);
    check_hypothesis_is_clique(*r);
    CHECK(r->out.pairings == 7);
    for (int i = 0; i < r->obs.count; ++i) CHECK(r->out.candidate[i] == s.truth[i]);
    CHECK_FALSE(r->out.diag.budget_hit);
    CHECK_FALSE(r->out.diag.nodes_truncated);
    CHECK(r->out.diag.graph_nodes == 56);
    for (int x = 0; x < 56; ++x) CHECK(r->ws.graph.adj[x] == honest->ws.graph.adj[x]);
    // JCBB trusts the predicted pose and its covariance (for information; not this stage's subject).
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(*scene, p->obs, p->pred));
    const auto cfg = make_config<T, B>(SearchMethod::kJcbb, true, true);
    REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
    int jcbb_right = 0;
    for (int i = 0; i < p->obs.count; ++i) jcbb_right += s.truth[i] >= 0 && p->out.candidate[i] == s.truth[i];
    if (scene != &s) CHECK(jcbb_right < 7);  // the motivation: JCBB misses what the clique finds
    MESSAGE(std::string(scene == &s ? "honest" : "overconfident")
            << " covariance: nearest neighbour wrong for " << nn_wrong << " of 7; JCBB " << p->out.pairings
            << " pairings, " << jcbb_right << " right; clique " << r->out.pairings << " of 7 right; graph "
            << r->out.diag.graph_nodes << " nodes, " << r->out.diag.graph_edges << " edges, "
            << r->out.diag.search_nodes << " search nodes");
  }
}

TEST_CASE_TEMPLATE("consistency: the budget is respected and flagged; the best so far is consistent", T, float,
                   double) {
  int flagged = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(16, 20, 2.0, 0.5), seed);
    auto r = make_run<T>(s, PairingGate::kEveryCandidate);
    REQUIRE(solve(*r) == Status::kOk);
    const std::uint32_t full = r->out.diag.search_nodes;
    const int full_size = r->out.pairings;
    REQUIRE_FALSE(r->out.diag.budget_hit);
    for (const std::uint32_t budget : {0u, 1u, full / 2, full}) {
      r->opt.node_budget = budget;
      REQUIRE(solve(*r) == Status::kOk);
      CHECK(r->out.diag.search_nodes == std::min(budget, full));
      CHECK(r->out.diag.budget_hit == (budget < full));
      CHECK(r->out.pairings <= full_size);
      CHECK(r->out.pairings >= 1);
      check_hypothesis_is_clique(*r);
      flagged += r->out.diag.budget_hit;
    }
  }
  CHECK(flagged >= 20);
}

TEST_CASE_TEMPLATE("consistency: bad input returns a status and leaves the result untouched", T, float, double) {
  const host::Scene s = host::make_scene(consistency_scene_params(8, 10, 0.5, 0.05), 3);
  auto r = make_run<T>(s, PairingGate::kWide);
  auto expect = [&](Status want) {
    ConsistencyResult<B> sentinel;
    sentinel.count = 99;
    sentinel.pairings = 77;
    for (auto& c : sentinel.candidate) c = 55;
    sentinel.diag.search_nodes = 1234;
    r->out = sentinel;
    CHECK(solve(*r) == want);
    CHECK(r->out.count == 99);
    CHECK(r->out.pairings == 77);
    CHECK(r->out.diag.search_nodes == 1234);
    for (const auto c : r->out.candidate) CHECK(c == 55);
  };
  const T nan = std::numeric_limits<T>::quiet_NaN(), inf = std::numeric_limits<T>::infinity();
  auto fresh = [&] { r = make_run<T>(s, PairingGate::kWide); };

  r->obs.z[2].x() = nan;
  expect(Status::kNonFinite);
  fresh();
  r->obs.R[1](0, 0) = inf;
  expect(Status::kNonFinite);
  fresh();
  r->pred.h[4].y() = inf;
  expect(Status::kNonFinite);
  fresh();
  r->pred.C(3, 5) = nan;  // and C(5, 3): one entry in the packed C
  expect(Status::kNonFinite);
  fresh();
  r->obs.R[0](1, 1) = T(-1e-4);  // not positive definite
  expect(Status::kNotPositiveDefinite);
  fresh();
  r->obs.R[0](0, 1) = T(1e-3);  // not symmetric
  expect(Status::kNotSymmetric);
  fresh();
  r->obs.z[0].x() = T(-1);
  expect(Status::kInvalidInput);
  fresh();
  r->obs.count = B::kMaxObservations + 1;
  expect(Status::kCapacityExceeded);
  fresh();
  r->pred.count = B::kMaxCandidates + 1;
  expect(Status::kCapacityExceeded);
  fresh();
  r->obs.count = -1;
  expect(Status::kInvalidInput);
  fresh();
  r->pred.count -= 1;  // C now mis-sized
  expect(Status::kInvalidInput);
  fresh();
  r->opt.pair_d2 = nan;
  expect(Status::kInvalidInput);
  fresh();
  r->opt.wide_d2 = T(0);
  expect(Status::kInvalidInput);
  fresh();
  r->opt.node_budget = kMaxCliqueSearchNodes + 1;
  expect(Status::kInvalidInput);
  fresh();
  r->opt.local_region = true;
  r->opt.local_radius_m = T(-2);
  expect(Status::kInvalidInput);
  fresh();
  // C's off-diagonal blocks making a distance variance negative: C not PSD.
  r->opt.pairing_gate = PairingGate::kEveryCandidate;
  r->pred.C.set_block(0, 1, T(50) * Mat2<T>::Identity());  // and block (1, 0): C is symmetric by storage
  expect(Status::kNotPositiveDefinite);
  // The options' thresholds: nothing written on failure.
  ConsistencyOptions<T> opt;
  opt.pair_d2 = T(3);
  CHECK(opt.set_confidence(1.5, 0.99) == Status::kInvalidInput);
  CHECK(opt.pair_d2 == T(3));
}

TEST_CASE_TEMPLATE("consistency: an empty scan and an empty map give an empty hypothesis", T, float, double) {
  const host::Scene s = host::make_scene(consistency_scene_params(8, 10, 0.5, 0.05), 4);
  auto r = make_run<T>(s, PairingGate::kWide);
  r->obs.count = 0;
  REQUIRE(solve(*r) == Status::kOk);
  CHECK(r->out.count == 0);
  CHECK(r->out.pairings == 0);
  r = make_run<T>(s, PairingGate::kWide);
  r->pred.count = 0;
  REQUIRE(r->pred.C.resize(0) == Status::kOk);
  REQUIRE(solve(*r) == Status::kOk);
  CHECK(r->out.count == 8);
  CHECK(r->out.pairings == 0);
  for (int i = 0; i < 8; ++i) CHECK(r->out.candidate[i] == -1);
}

TEST_CASE_TEMPLATE("consistent_hypothesis() allocates nothing", T, float, double) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(20, 30, 1.0, 0.2), seed);
    for (const PairingGate gate : {PairingGate::kWide, PairingGate::kEveryCandidate}) {
      auto r = make_run<T>(s, gate);
      r->opt.local_region = seed % 2 == 0;
      r->opt.local_radius_m = T(8);
      Status st = Status::kInvalidInput;
      CHECK(allocations_during([&] { st = solve(*r); }) == 0);
      CHECK(st == Status::kOk);
      r->obs.z[0].x() = T(-1);  // the error path allocates nothing either
      CHECK(allocations_during([&] { st = solve(*r); }) == 0);
      CHECK(st == Status::kInvalidInput);
      ConsistencyOptions<T> opt;
      CHECK(allocations_during([&] { st = opt.set_confidence(0.9999, 0.999); }) == 0);
      CHECK(st == Status::kOk);
    }
  }
}

TEST_CASE("consistency: float and double agree on well-conditioned scenes") {
  // A scene is well conditioned when no gate value (individual d2 against the wide gate, pairwise d2
  // against its gate) lies within 1e-3 of its threshold, computed in double.
  int compared = 0, skipped = 0, truncated = 0;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    const host::Scene s = host::make_scene(consistency_scene_params(8, 8, 1.0, 0.2), seed);  // <= 64 pairings
    for (const PairingGate gate : {PairingGate::kWide, PairingGate::kEveryCandidate}) {
      auto rd = make_run<double>(s, gate);
      auto rf = make_run<float>(s, gate);
      REQUIRE(solve(*rd) == Status::kOk);
      REQUIRE(solve(*rf) == Status::kOk);
      bool borderline = false;
      const auto& list = rd->ws.pairings;
      for (int i = 0; i < rd->obs.count && gate == PairingGate::kWide; ++i) {
        for (int a = 0; a < rd->pred.count; ++a) {
          const Mat2<double> S = rd->pred.C.block(a, a) + rd->obs.R[i];
          const double d2 = mahalanobis2(innovation(rd->obs.z[i], rd->pred.h[a]), S);
          borderline = borderline || std::abs(d2 - rd->opt.wide_d2) <= 1e-3 * rd->opt.wide_d2;
        }
      }
      for (int x = 0; x < list.count; ++x) {
        for (int y = x + 1; y < list.count; ++y) {
          const auto& p = list.node[x];
          const auto& q = list.node[y];
          if (p.obs == q.obs || p.cand == q.cand) continue;
          PairStatistic<double> st;
          REQUIRE(pair_statistic(rd->ws.geometry, rd->pred, p.obs, p.cand, q.obs, q.cand, st) == Status::kOk);
          borderline = borderline || std::abs(st.d2() - rd->opt.pair_d2) <= 1e-3 * rd->opt.pair_d2;
        }
      }
      if (borderline || list.truncated) {
        ++skipped;
        truncated += list.truncated;
        continue;
      }
      CAPTURE(seed);
      REQUIRE(rf->ws.graph.count == rd->ws.graph.count);
      for (int x = 0; x < rd->ws.graph.count; ++x) CHECK(rf->ws.graph.adj[x] == rd->ws.graph.adj[x]);
      for (int i = 0; i < rd->obs.count; ++i) CHECK(rf->out.candidate[i] == rd->out.candidate[i]);
      CHECK(rf->out.diag.search_nodes == rd->out.diag.search_nodes);
      ++compared;
    }
  }
  MESSAGE("float = double on " << compared << " scenes; " << skipped << " skipped (" << truncated << " truncated)");
  CHECK(compared >= 90);
}

TEST_CASE("consistency: graph and search sizes on generated scenes (reported for docs/consistency.md)") {
  MESSAGE("sizeof ConsistencyWorkspace<float, DefaultBounds> = "
          << sizeof(ConsistencyWorkspace<float, B>) << " B (graph " << sizeof(BitsetGraph<64>) << " B, search "
          << sizeof(ConsistencyWorkspace<float, B>::search) << " B)");
  struct Setting {
    const char* name;
    int m, n;
  };
  for (const Setting& st :
       {Setting{"8 observations, 8 candidates", 8, 8}, Setting{"12 observations, 16 candidates", 12, 16},
        Setting{"16 observations, 24 candidates", 16, 24}}) {
    for (const PairingGate gate : {PairingGate::kWide, PairingGate::kEveryCandidate}) {
      std::vector<int> nodes, edges, search, wrong, size, true_pairs;
      int truncated = 0, with_wrong = 0, smaller = 0;
      for (std::uint64_t seed = 1; seed <= 300; ++seed) {
        // Large pose error (loop closure, relocalisation): 2 m and 0.5 rad, with a covariance that
        // admits it.
        const host::Scene s = host::make_scene(consistency_scene_params(st.m, st.n, 2.0, 0.5), seed);
        auto r = make_run<float>(s, gate);
        REQUIRE(solve(*r) == Status::kOk);
        REQUIRE_FALSE(r->out.diag.budget_hit);
        check_hypothesis_is_clique(*r);
        nodes.push_back(r->out.diag.graph_nodes);
        edges.push_back(r->out.diag.graph_edges);
        search.push_back(static_cast<int>(r->out.diag.search_nodes));
        size.push_back(r->out.pairings);
        int ok = 0, real = 0;
        for (int i = 0; i < r->obs.count; ++i) {
          ok += r->out.candidate[i] >= 0 && r->out.candidate[i] == s.truth[i];
          real += s.truth[i] >= 0;
        }
        wrong.push_back(r->out.pairings - ok);
        true_pairs.push_back(real);
        with_wrong += r->out.pairings > ok;
        smaller += ok < real;
        truncated += r->out.diag.nodes_truncated;
      }
      auto med = [](std::vector<int> v) {
        std::sort(v.begin(), v.end());
        return std::to_string(v[v.size() / 2]) + " (max " + std::to_string(v.back()) + ")";
      };
      MESSAGE(std::string(st.name) << ", " << std::string(gate == PairingGate::kWide ? "wide gate" : "every candidate")
                                   << ", 300 scenes: graph nodes " << med(nodes) << ", truncated " << truncated
                                   << "; edges " << med(edges) << "; search nodes " << med(search) << "; clique "
                                   << med(size) << " for true pairings " << med(true_pairs)
                                   << "; scenes with a wrong pairing " << with_wrong << ", missing a true one "
                                   << smaller);
    }
  }
}
