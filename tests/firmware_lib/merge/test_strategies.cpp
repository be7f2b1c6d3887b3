// The six strategies on random scenes: every answer is a valid hypothesis (exclusion holds where on;
// the union passes the joint test where the re-check is on); one group gives exactly plain JCBB;
// float and double agree on well-conditioned scenes; the re-check repairs unions that fail.
#include <doctest/doctest.h>

#include <random>

#include "geojcbb_host/scene.hpp"
#include "support/helpers.hpp"

using namespace geojcbb;
using namespace geojcbb::test;

namespace {
constexpr Strategy kAll[] = {Strategy::kIcnn,   Strategy::kJcbb,    Strategy::kKjcbb,
                             Strategy::kDfjcbb, Strategy::kGemjcbb, Strategy::kGeojcbb};

host::SceneParams random_scene(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  host::SceneParams p;
  p.observations = 5 + static_cast<int>(rng() % 16);
  p.landmarks = 10 + static_cast<int>(rng() % 21);
  p.max_range_m = 4 + 8 * u(rng);
  p.sigma_pose_xy_m = 0.1 + 0.4 * u(rng);
  p.sigma_pose_theta_rad = 0.01 + 0.04 * u(rng);
  return p;
}

// Dense scenes with a large heading error, which moves every group the same way: groups searched
// apart can each pass alone and fail together.
host::SceneParams heading_error_scene() {
  host::SceneParams sp;
  sp.observations = 20;
  sp.landmarks = 30;
  sp.max_range_m = 8;
  sp.sigma_pose_xy_m = 0.1;
  sp.sigma_pose_theta_rad = 0.08;
  sp.sigma_landmark_m = 0.05;
  return sp;
}

template <typename T, class B>
AssociationConfig<T, B> strategy(Strategy s, bool recheck = true) {
  StepSettings<T> p;
  p.local_radius_m = T(10);
  p.joint_recheck = recheck;
  AssociationConfig<T, B> cfg;
  REQUIRE(make_strategy(s, p, cfg) == Status::kOk);
  return cfg;
}
}  // namespace

TEST_CASE_TEMPLATE("every strategy gives a valid hypothesis on random scenes", T, float, double) {
  using B = DefaultBounds;
  std::mt19937_64 rng(77);
  int repaired = 0;
  for (int k = 0; k < 300; ++k) {
    const std::uint64_t seed = rng();
    CAPTURE(seed);
    const host::Scene scene = host::make_scene(random_scene(rng), seed);
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(scene, p->obs, p->pred));
    for (Strategy s : kAll) {
      CAPTURE(to_string(s));
      const auto cfg = strategy<T, B>(s);
      REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
      CHECK(p->out.count == p->obs.count);
      if (cfg.mutual_exclusion) {
        for (int a = 0; a < p->obs.count; ++a)
          for (int b = a + 1; b < p->obs.count; ++b)
            CHECK((p->out.candidate[a] < 0 || p->out.candidate[a] != p->out.candidate[b]));
      }
      if (cfg.search == SearchMethod::kJcbb && cfg.joint_recheck) CHECK(p->out.jointly_compatible);
      if (cfg.local_region) {
        for (int i = 0; i < p->obs.count; ++i) {
          if (p->out.candidate[i] >= 0) CHECK(p->pred.h[p->out.candidate[i]].x() < cfg.local_radius_m);
        }
      }
      CHECK(p->out.diag.groups <= B::kMaxGroups);
      repaired += p->out.diag.recheck_failed;
    }
  }
  MESSAGE("unions repaired by the re-check: " << repaired);
}

TEST_CASE_TEMPLATE("one group gives exactly the plain JCBB answer", T, float, double) {
  using B = DefaultBounds;
  std::mt19937_64 rng(78);
  for (int k = 0; k < 200; ++k) {
    const host::Scene scene = host::make_scene(random_scene(rng), rng());
    auto p = make_problem<T, B>();
    REQUIRE(host::to_inputs(scene, p->obs, p->pred));
    for (bool geo : {false, true}) {
      auto plain = strategy<T, B>(geo ? Strategy::kGeojcbb : Strategy::kJcbb);
      plain.grouping = Grouping::kNone;
      REQUIRE(associate(p->obs, p->pred, plain, p->ws, p->out) == Status::kOk);
      const auto want = p->out;
      for (Grouping g : {Grouping::kKMeans, Grouping::kGmmEm}) {
        auto one = plain;
        one.grouping = g;
        one.groups = 1;
        REQUIRE(associate(p->obs, p->pred, one, p->ws, p->out) == Status::kOk);
        CHECK(p->out.diag.groups == (p->obs.count > 0 ? 1 : 0));
        CHECK(p->out.pairings == want.pairings);
        CHECK(p->out.joint_d2 == want.joint_d2);
        for (int i = 0; i < p->obs.count; ++i) CHECK(p->out.candidate[i] == want.candidate[i]);
      }
      // DBSCAN with a radius covering every point: one group too.
      auto db = plain;
      db.grouping = Grouping::kDbscan;
      db.dbscan_eps_m = T(1000);
      REQUIRE(associate(p->obs, p->pred, db, p->ws, p->out) == Status::kOk);
      for (int i = 0; i < p->obs.count; ++i) CHECK(p->out.candidate[i] == want.candidate[i]);
    }
  }
}

TEST_CASE("float and double agree on well-conditioned scenes, for every strategy") {
  using B = DefaultBounds;
  std::mt19937_64 rng(79);
  for (int k = 0; k < 150; ++k) {
    host::SceneParams sp;
    sp.observations = 5 + static_cast<int>(rng() % 16);
    sp.landmarks = 10 + static_cast<int>(rng() % 15);
    sp.max_range_m = 12;
    sp.min_separation_m = 2.5;  // features far apart relative to the uncertainty
    sp.sigma_pose_xy_m = 0.05;
    sp.sigma_pose_theta_rad = 0.005;
    sp.sigma_common_xy_m = 0.02;
    sp.sigma_common_theta_rad = 0.002;
    sp.sigma_landmark_m = 0.05;
    sp.clutter_fraction = 0;
    const host::Scene scene = host::make_scene(sp, rng());
    auto pf = make_problem<float, B>();
    auto pd = make_problem<double, B>();
    REQUIRE(host::to_inputs(scene, pf->obs, pf->pred));
    REQUIRE(host::to_inputs(scene, pd->obs, pd->pred));
    for (Strategy s : kAll) {
      CAPTURE(to_string(s));
      REQUIRE(associate(pf->obs, pf->pred, strategy<float, B>(s), pf->ws, pf->out) == Status::kOk);
      REQUIRE(associate(pd->obs, pd->pred, strategy<double, B>(s), pd->ws, pd->out) == Status::kOk);
      CHECK(pf->out.diag.groups == pd->out.diag.groups);
      for (int i = 0; i < pd->obs.count; ++i) CHECK(pf->out.feature[i] == pd->out.feature[i]);
      CHECK(pf->out.joint_d2 == doctest::Approx(pd->out.joint_d2).epsilon(1e-3));
    }
  }
}

TEST_CASE_TEMPLATE("the re-check repairs unions that fail the joint test", T, float, double) {
  // Dense scenes with a common pose error: groups searched apart can each pass alone and fail
  // together. Without the re-check such unions come out; with it, never.
  using B = DefaultBounds;
  std::mt19937_64 rng(80);
  int failing_without = 0, repaired = 0;
  for (int k = 0; k < 200; ++k) {
    auto p = scene_problem<T, B>(heading_error_scene(), rng());
    for (Strategy s : {Strategy::kKjcbb, Strategy::kGemjcbb, Strategy::kGeojcbb}) {
      auto off = strategy<T, B>(s, false);
      off.groups = 5;
      REQUIRE(associate(p->obs, p->pred, off, p->ws, p->out) == Status::kOk);
      failing_without += !p->out.jointly_compatible;
      auto on = off;
      on.joint_recheck = true;
      REQUIRE(associate(p->obs, p->pred, on, p->ws, p->out) == Status::kOk);
      CHECK(p->out.jointly_compatible);
      repaired += p->out.diag.recheck_failed;
    }
  }
  MESSAGE("unions failing without the re-check: " << failing_without << ", repaired with it: " << repaired);
  CHECK(failing_without > 0);  // the scenes do exercise the repair
  CHECK(repaired == failing_without);
}

TEST_CASE_TEMPLATE("conditioned groups: the union is jointly compatible by construction, exclusion holds", T, float,
                   double) {
  using B = DefaultBounds;
  std::mt19937_64 rng(81);
  for (int k = 0; k < 200; ++k) {
    auto p = scene_problem<T, B>(heading_error_scene(), rng());
    for (Strategy s : {Strategy::kKjcbb, Strategy::kDfjcbb, Strategy::kGemjcbb, Strategy::kGeojcbb}) {
      auto cfg = strategy<T, B>(s, false);  // no re-check: nothing repairs the union afterwards
      cfg.condition_groups = true;
      cfg.groups = 5;
      REQUIRE(associate(p->obs, p->pred, cfg, p->ws, p->out) == Status::kOk);
      CHECK(p->out.jointly_compatible);
      CHECK(p->out.diag.merge_conflicts == 0);
      if (cfg.mutual_exclusion) {
        for (int a = 0; a < p->obs.count; ++a)
          for (int b = a + 1; b < p->obs.count; ++b)
            CHECK((p->out.candidate[a] < 0 || p->out.candidate[a] != p->out.candidate[b]));
      }
    }
  }
}
