// jcbb/rjc.hpp inside associate(): reproducible from its seed; a jointly compatible answer; small
// scans searched by plain JCBB; its options validated; no allocation.
#include <doctest/doctest.h>

#include "support/alloc_counter.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {

host::SceneParams large_scan(int m, int n) {
  host::SceneParams sp;
  sp.observations = m;
  sp.landmarks = n;
  sp.max_range_m = 10;
  return sp;
}

template <typename T, class B>
AssociationConfig<T, B> rjc_config(std::uint64_t seed) {
  auto cfg = make_config<T, B>(SearchMethod::kJcbb, true, true);
  cfg.rjc = true;
  cfg.rjc_tries = 6;
  cfg.rjc_subset = 6;
  cfg.rjc_seed = seed;
  return cfg;
}

}  // namespace

TEST_CASE_TEMPLATE("RJC: the same seed gives the same answer; the answer is jointly compatible", T, float, double) {
  using B = HostBounds;
  int differing = 0;
  for (std::uint64_t scene = 1; scene <= 10; ++scene) {
    auto a = scene_problem<T, B>(large_scan(24, 40), scene);
    auto b = scene_problem<T, B>(large_scan(24, 40), scene);
    auto c = scene_problem<T, B>(large_scan(24, 40), scene);
    REQUIRE(associate(a->obs, a->pred, rjc_config<T, B>(11), a->ws, a->out) == Status::kOk);
    REQUIRE(associate(b->obs, b->pred, rjc_config<T, B>(11), b->ws, b->out) == Status::kOk);
    REQUIRE(associate(c->obs, c->pred, rjc_config<T, B>(12), c->ws, c->out) == Status::kOk);
    CAPTURE(scene);
    CHECK(a->out.diag.rjc_used);
    for (int i = 0; i < a->obs.count; ++i) CHECK(a->out.candidate[i] == b->out.candidate[i]);
    CHECK(a->out.joint_d2 == b->out.joint_d2);
    CHECK(a->out.diag.jcbb_nodes == b->out.diag.jcbb_nodes);
    CHECK(a->out.jointly_compatible);
    CHECK(c->out.jointly_compatible);
    // Exclusion holds in the completion too.
    for (int i = 0; i < a->obs.count; ++i)
      for (int k = i + 1; k < a->obs.count; ++k)
        if (a->out.candidate[i] >= 0) CHECK(a->out.candidate[i] != a->out.candidate[k]);
    differing += a->out.diag.jcbb_nodes != c->out.diag.jcbb_nodes;
    // Every try's JCBB shares the budget.
    CHECK(a->out.diag.jcbb_nodes <= (a->obs.count == 0 ? NodeCount{0} : B::kMaxJcbbNodes));
  }
  CHECK(differing > 0);  // another seed draws other subsets
}

TEST_CASE_TEMPLATE("RJC: a scan no larger than the subset is searched by plain JCBB", T, float, double) {
  using B = DefaultBounds;
  for (std::uint64_t scene = 1; scene <= 10; ++scene) {
    auto a = scene_problem<T, B>(large_scan(5, 12), scene);
    auto b = scene_problem<T, B>(large_scan(5, 12), scene);
    REQUIRE(associate(a->obs, a->pred, rjc_config<T, B>(3), a->ws, a->out) == Status::kOk);
    REQUIRE(associate(b->obs, b->pred, make_config<T, B>(SearchMethod::kJcbb, true, true), b->ws, b->out) ==
            Status::kOk);
    CHECK_FALSE(a->out.diag.rjc_used);
    for (int i = 0; i < a->obs.count; ++i) CHECK(a->out.candidate[i] == b->out.candidate[i]);
  }
}

TEST_CASE_TEMPLATE("RJC: bad options give kInvalidInput; the calls allocate nothing", T, float, double) {
  using B = DefaultBounds;
  auto p = scene_problem<T, B>(large_scan(20, 30), 4);
  auto bad = [&](auto mutate) {
    auto cfg = rjc_config<T, B>(1);
    mutate(cfg);
    p->out.count = 99;
    CHECK(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kInvalidInput);
    CHECK(p->out.count == 99);
  };
  bad([](auto& c) { c.rjc_tries = 0; });
  bad([](auto& c) { c.rjc_tries = kMaxRjcTries + 1; });
  bad([](auto& c) { c.rjc_subset = 0; });
  bad([](auto& c) { c.rjc_subset = B::kMaxObservations + 1; });
  bad([](auto& c) { c.node_budget = 3; });  // fewer nodes than tries
  bad([](auto& c) { c.grouping = Grouping::kKMeans; });
  bad([](auto& c) { c.search = SearchMethod::kIcnn; });
  bad([](auto& c) { c.ambiguity_margin = T(1); });
  const auto cfg = rjc_config<T, B>(5);
  Status s = Status::kNoConvergence;
  CHECK(allocations_during([&] { s = associate(p->obs, p->pred, cfg, p->ws, p->out); }) == 0);
  CHECK(s == Status::kOk);
  CHECK(p->out.diag.rjc_used);
}
