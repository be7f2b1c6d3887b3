// Zero allocations: operator new and malloc are counted around every pipeline call, for every search
// option, in float and double, at two capacity configurations (Eigen's run-time no-malloc switch is
// off inside the guard too).
#include <doctest/doctest.h>

#include "geojcbb_host/scene.hpp"
#include "support/alloc_counter.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {
host::SceneParams scene_params(int m, int n, double max_range_m) {
  host::SceneParams sp;
  sp.observations = m;
  sp.landmarks = n;
  sp.max_range_m = max_range_m;
  return sp;
}

template <typename T, class B>
void check_no_alloc(int m, int n) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    auto p = scene_problem<T, B>(scene_params(m, n, 6), seed);
    const Vec2<T> z0 = p->obs.z[0];
    for (int combo = 0; combo < 8; ++combo) {
      auto cfg = make_config<T, B>((combo & 4) ? SearchMethod::kIcnn : SearchMethod::kJcbb, combo & 1, combo & 2);
      cfg.local_region = combo & 1;
      cfg.local_radius_m = T(5);
      Status s = Status::kNoConvergence;
      CHECK(allocations_during([&] { s = associate(p->obs, p->pred, cfg, p->ws, p->out); }) == 0);
      CHECK(s == Status::kOk);
      // Error paths allocate nothing either.
      p->obs.z[0].x() = -1;
      CHECK(allocations_during([&] { s = associate(p->obs, p->pred, cfg, p->ws, p->out); }) == 0);
      CHECK(s == Status::kInvalidInput);
      p->obs.z[0] = z0;
      // So does computing thresholds.
      CHECK(allocations_during(
                [&] { s = GateThresholds<T, B::kMaxObservations>::from_confidence(0.95, 0.99, cfg.gate); }) == 0);
      CHECK(s == Status::kOk);
    }
  }
}
}  // namespace

TEST_CASE("the allocation counter sees allocations (self-test)") {
  AllocationGuard guard;
  auto* v = new int(3);
  CHECK(guard.allocations() >= 1);
  delete v;
  if (counts_malloc()) {
    const auto before = guard.allocations();
    void* volatile q = std::malloc(16);  // volatile: the pair must not be elided
    CHECK(guard.allocations() == before + 1);
    std::free(q);
  }
}

namespace {
template <typename T, class B>
void check_no_alloc_strategies(int m, int n) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    auto p = scene_problem<T, B>(scene_params(m, n, 8), seed);
    for (int s = 0; s < kStrategyCount; ++s) {
      for (int k : {0, 3, -3}) {  // GMM-EM by BIC and fixed K; -3: K = 3 with the verification
        StepSettings<T> sp;
        sp.local_radius_m = T(6);
        sp.groups = k < 0 ? -k : k;
        sp.verify = k < 0;
        sp.seed_min_position_var_m2 = T(1e-3);  // PCJCBB: the seed tried on every scene
        sp.full_covariance_check = k == 0;      // packed covariance: the full check and the papers' EM stop
        sp.papers_em = k == 0;                  // too (k = 3, -3: C checked where read)
        AssociationConfig<T, B> cfg;
        REQUIRE(make_strategy(static_cast<Strategy>(s), sp, cfg) == Status::kOk);
        Status st = Status::kNoConvergence;
        CHECK(allocations_during([&] { st = associate(p->obs, p->pred, cfg, p->ws, p->out); }) == 0);
        CHECK(st == Status::kOk);
      }
    }
  }
}
}  // namespace

TEST_CASE_TEMPLATE("every strategy allocates nothing (small and default bounds)", T, float, double) {
  check_no_alloc_strategies<T, SmallBounds>(7, 10);
  check_no_alloc_strategies<T, DefaultBounds>(20, 30);
}

TEST_CASE_TEMPLATE("associate() allocates nothing (small bounds)", T, float, double) {
  check_no_alloc<T, SmallBounds>(7, 10);
}
TEST_CASE_TEMPLATE("associate() allocates nothing (default bounds)", T, float, double) {
  check_no_alloc<T, DefaultBounds>(20, 30);
}
