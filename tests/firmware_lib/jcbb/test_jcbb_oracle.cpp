// JCBB against the exhaustive oracle on thousands of random small problems (<= 7 observations,
// <= 8 candidates, clutter, dense landmarks for ambiguity), in float and double, for every
// combination of mutual exclusion, optimal criterion and ordering.
#include <doctest/doctest.h>

#include <cstdio>
#include <random>

#include "geojcbb_host/scene.hpp"
#include "support/helpers.hpp"
#include "support/oracle.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {

constexpr int kProblems = 1500;  // per (Scalar, option combination)

host::SceneParams random_params(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> m(1, 7), n(1, 8);
  std::uniform_real_distribution<double> u(0, 1);
  host::SceneParams p;
  p.observations = m(rng);
  p.landmarks = n(rng);
  p.clutter_fraction = 0.3 * u(rng);
  p.max_range_m = 2.0 + 4.0 * u(rng);  // dense: several landmarks inside one gate
  p.sigma_pose_xy_m = 0.1 + 0.4 * u(rng);
  p.sigma_pose_theta_rad = 0.01 + 0.05 * u(rng);
  p.sigma_common_xy_m = 0.2 * u(rng);
  p.sigma_landmark_m = 0.05 + 0.2 * u(rng);
  return p;
}

template <typename T>
constexpr long double kMargin = std::is_same<T, float>::value ? 1e-3L : 1e-9L;

}  // namespace

TEST_CASE_TEMPLATE("JCBB equals the exhaustive oracle: max pairings, joint test, min d2", T, float, double) {
  using B = SmallBounds;
  std::uint64_t borderline = 0, more_as_whole = 0, whole_checked = 0, nodes = 0;
  for (int combo = 0; combo < 8; ++combo) {
    const bool exclusion = combo & 1, optimal = combo & 2, fewest_first = combo & 4;
    CAPTURE(exclusion);
    CAPTURE(optimal);
    CAPTURE(fewest_first);
    auto cfg = make_config<T, B>(SearchMethod::kJcbb, exclusion, optimal);
    cfg.order_fewest_candidates_first = fewest_first;
    std::mt19937_64 rng(1000 + combo);
    for (int k = 0; k < kProblems; ++k) {
      const std::uint64_t seed = rng();
      CAPTURE(seed);
      const host::Scene scene = host::make_scene(random_params(rng), seed);
      auto p = make_problem<T, B>();
      REQUIRE(host::to_inputs(scene, p->obs, p->pred));
      REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
      REQUIRE_FALSE(p->out.diag.node_budget_hit);
      nodes += p->out.diag.jcbb_nodes;

      Oracle<T, B> strict(p->obs, p->pred, cfg, kMargin<T>, false);
      Oracle<T, B> loose(p->obs, p->pred, cfg, kMargin<T>, true);
      const OracleResult rs = strict.run(200000);
      const OracleResult rl = loose.run(0);
      // JCBB's own hypothesis is in its space and passes the joint test as a whole.
      std::array<std::int16_t, B::kMaxObservations> hyp{};
      for (int i = 0; i < p->obs.count; ++i) hyp[i] = p->out.candidate[i];
      CHECK(loose.prefixes_pass(hyp));
      CHECK(p->out.jointly_compatible);
      if (exclusion) {
        for (int a = 0; a < p->obs.count; ++a)
          for (int b = a + 1; b < p->obs.count; ++b) CHECK((hyp[a] < 0 || hyp[a] != hyp[b]));
      }
      const bool exact = !strict.saw_borderline() && !loose.saw_borderline();
      if (exact) {
        CHECK(p->out.pairings == rs.max_pairings);
        if (optimal) {
          CHECK(static_cast<long double>(p->out.joint_d2) == doctest::Approx(static_cast<double>(rs.min_d2))
                                                                 .epsilon(static_cast<double>(kMargin<T> * 10))
                                                                 .scale(1e-6));
        }
      } else {
        ++borderline;
        CHECK(p->out.pairings >= rs.max_pairings);
        CHECK(p->out.pairings <= rl.max_pairings);
      }
      if (rs.max_pairings_whole >= 0) {
        ++whole_checked;
        if (rs.max_pairings_whole > rs.max_pairings) ++more_as_whole;
      }
    }
  }
  std::printf(
      "[jcbb oracle, %s] %d problems: %llu borderline (a test value within %.0Le of its threshold), "
      "%llu/%llu with a hypothesis of more pairings that passes only as a whole, %.1f nodes/problem\n",
      std::is_same<T, float>::value ? "float" : "double", 8 * kProblems, static_cast<unsigned long long>(borderline),
      kMargin<T>, static_cast<unsigned long long>(more_as_whole), static_cast<unsigned long long>(whole_checked),
      static_cast<double>(nodes) / (8 * kProblems));
}
