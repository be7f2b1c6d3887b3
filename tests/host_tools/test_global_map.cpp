// The host's global map (sequential map joining, docs/submaps.md): a duplicate between two maps is
// fused to the information-weighted mean; a landmark carried over with nothing learned about it
// leaves the global estimate as it was (its prior divided out, nothing counted twice); a landmark far
// from every global one is kept as new; a labelled run joins its maps with no wrong join.
#include <doctest/doctest.h>

#include <string>

#include <Eigen/Dense>

#include "geojcbb_host/global_map.hpp"
#include "geojcbb_host/slam_run.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {
// A local map with an exact last pose and independent landmarks (covariance var each).
Submap make_map(int index, const Eigen::Vector3d& end, const std::vector<Eigen::Vector2d>& l,
                const std::vector<FeatureId>& ids, double var) {
  Submap m;
  m.index = index;
  m.ids = ids;
  m.confirmed.assign(ids.size(), true);
  m.exist_nats.assign(ids.size(), 10.0);
  const int n = static_cast<int>(l.size());
  m.x.resize(3 + 2 * n);
  m.x.head<3>() = end;
  for (int k = 0; k < n; ++k) m.x.segment<2>(3 + 2 * k) = l[static_cast<std::size_t>(k)];
  m.P = Eigen::MatrixXd::Identity(3 + 2 * n, 3 + 2 * n) * var;
  m.P.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * 1e-12;
  return m;
}
}  // namespace

TEST_CASE("global map: duplicates between two maps fused to the information-weighted mean") {
  GlobalMap g(JoinOptions{});
  // Map 0 (the world's frame): two landmarks with variance 0.04; it ends at (10, 0, 0), exactly.
  const JoinResult first = g.join(make_map(0, {10, 0, 0}, {{12, 1}, {15, -2}}, {0, 1}, 0.04));
  CHECK(first.fused == 0);
  REQUIRE(g.landmarks() == 2);
  // Map 1 begins there and sees the same two (variance 0.01) 0.1 m off, and a third far away.
  const JoinResult j = g.join(make_map(1, {5, 0, 0}, {{2.1, 0.9}, {5.1, -2.1}, {30, 30}}, {2, 3, 4}, 0.01));
  CHECK(j.fused == 2);
  CHECK(j.pruned == 0);
  CHECK(!j.refused);
  REQUIRE(g.landmarks() == 3);  // the third is new
  CHECK(g.first_id(2) == 4);
  // Information 25 and 100: the mean (25 x + 100 x') / 125, the variance 1 / 125.
  CHECK(g.landmark(0).x() == doctest::Approx((25 * 12 + 100 * 12.1) / 125).epsilon(1e-4));
  CHECK(g.landmark(0).y() == doctest::Approx((25 * 1 + 100 * 0.9) / 125).epsilon(1e-4));
  CHECK(g.landmark(1).x() == doctest::Approx((25 * 15 + 100 * 15.1) / 125).epsilon(1e-4));
  CHECK(g.landmark_covariance(0)(0, 0) == doctest::Approx(1.0 / 125).epsilon(1e-3));
  // The base is map 1's last pose in the world: (10, 0, 0) + (5, 0, 0).
  CHECK(g.state()(0) == doctest::Approx(15).epsilon(1e-6));
  REQUIRE(j.pairs.size() == 2);
  CHECK(j.pairs[0].second == 0);
}

TEST_CASE("global map: a carried landmark the new map learned nothing about leaves the global one as it was") {
  GlobalMap g(JoinOptions{});
  Submap m0 = make_map(0, {10, 0, 0.3}, {{12, 1}, {15, -2}}, {0, 1}, 0.04);
  m0.P.topLeftCorner<3, 3>() = Eigen::Vector3d(0.02, 0.03, 0.001).asDiagonal();
  m0.P(0, 3) = m0.P(3, 0) = 0.01;  // the last pose correlated with landmark 0
  g.join(m0);
  const Eigen::Vector2d before = g.landmark(0);
  const Eigen::Matrix2d before_P = g.landmark_covariance(0);
  // Map 1 carries landmark 0 with the prior the device began it with (the previous map's, in its
  // last pose's frame) and sees nothing of it: its estimate and covariance are that prior.
  const double c = std::cos(0.3), s = std::sin(0.3);
  Eigen::Matrix2d Rt;
  Rt << c, s, -s, c;
  const Eigen::Vector2d d = Rt * (Eigen::Vector2d(12, 1) - Eigen::Vector2d(10, 0));
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2, 5);
  J.block<2, 2>(0, 0) = -Rt;
  J(0, 2) = d.y();
  J(1, 2) = -d.x();
  J.block<2, 2>(0, 3) = Rt;
  std::vector<int> rows = {0, 1, 2, 3, 4};
  const Eigen::Matrix2d prior = J * m0.P(rows, rows) * J.transpose();
  Submap m1 = make_map(1, {1, 0, 0}, {d, {40, 0}}, {0, 5}, 0.01);
  m1.P.block<2, 2>(3, 3) = prior;
  const JoinResult j = g.join(m1);
  CHECK(j.shared == 1);
  CHECK(j.fused == 0);
  CHECK((g.landmark(0) - before).norm() < 1e-9);
  CHECK((g.landmark_covariance(0) - before_P).norm() < 1e-9);
  CHECK(g.landmarks() == 3);
}

TEST_CASE("global map: the shared landmarks' update is measured: d2 = |shift|^2 / (prior - posterior variance)") {
  GlobalMap g(JoinOptions{});
  // Map 0 ends at (10, 0, 0) exactly; landmark 0 at (12, 1) with variance p = 0.04, carried over.
  Submap m0 = make_map(0, {10, 0, 0}, {{12, 1}, {15, -2}}, {0, 1}, 0.04);
  m0.carried = {true, false};
  g.join(m0);
  // Map 1 began with it at (2, 1) (variance p, as the global map holds it) and its scans moved it by
  // (0.3, 0) to variance q = 0.01: information 1/q - 1/p, a measurement at (2, 1) + p (0.3, 0) / (p - q)
  // with variance pq / (p - q); against the global (2, 1) with variance p, d2 = 0.3^2 / (p - q) = 3.
  const JoinResult j = g.join(make_map(1, {1, 0, 0}, {{2.3, 1}, {40, 0}}, {0, 5}, 0.01));
  CHECK(j.shared == 1);
  CHECK(j.shared_dof == 2);
  CHECK(j.shared_d2 == doctest::Approx(3.0).epsilon(1e-6));
  CHECK(j.seeded_dof == 0);  // nothing seeded
  CHECK(j.seeded_d2 == 0);
  // Fused with weight p / (p + pq / (p - q)) = 3/4, the measurement's 0.4 moves (12, 1) by 0.3: the map
  // began from the global estimate itself, so the global one becomes the map's posterior.
  CHECK(g.landmark(0).x() == doctest::Approx(12.3).epsilon(1e-6));
  CHECK(g.landmark_covariance(0)(0, 0) == doctest::Approx(0.01).epsilon(1e-6));
  CHECK(g.landmark(0).y() == doctest::Approx(1.0).epsilon(1e-6));
}

TEST_CASE("global map: a carried landmark the next map removed leaves the global map; one never carried stays") {
  JoinOptions o;
  o.remove_carried = true;
  GlobalMap g(o);
  // Map 0 ends at (10, 0, 0) with three landmarks; the next map begins with 0 and 1 (carried over).
  Submap m0 = make_map(0, {10, 0, 0}, {{12, 1}, {15, -2}, {-20, 3}}, {0, 1, 2}, 0.04);
  m0.carried = {true, true, false};
  g.join(m0);
  REQUIRE(g.landmarks() == 3);
  // Map 1 holds 0 and a new one far from all; 1 it removed by its evidence (missed in view); 2 it
  // never held (not carried: out of view at the restart).
  const JoinResult j = g.join(make_map(1, {1, 0, 0}, {{2, 1}, {40, 0}}, {0, 5}, 0.01));
  CHECK(j.shared == 1);
  CHECK(j.removed == 1);
  REQUIRE(g.landmarks() == 3);  // 0 and 2 kept, 1 removed, 5 new
  CHECK(g.first_id(0) == 0);
  CHECK(g.first_id(1) == 2);
  CHECK(g.first_id(2) == 5);
  // Without remove_carried (the default) the carried landmark the map removed stays.
  GlobalMap d(JoinOptions{});
  d.join(m0);
  CHECK(d.join(make_map(1, {1, 0, 0}, {{2, 1}, {40, 0}}, {0, 5}, 0.01)).removed == 0);
  CHECK(d.landmarks() == 4);
  // Map 1 named none carried (an empty list: not known): nothing is removed for want of it.
  const JoinResult k = g.join(make_map(2, {1, 0, 0}, {{50, 0}}, {6}, 0.01));
  CHECK(k.removed == 0);
  CHECK(g.landmarks() == 4);
}

TEST_CASE("global map: env1 in local maps of 30 landmarks, carried over and seeded: no wrong join, every map joined") {
  const Scenario s = load_scenario(std::string(GEOJCBB_SCENARIO_DIR) + "/env1.json");
  RunOptions single;
  single.step.strategy = Strategy::kPcjcbb;
  const RunResult one = run_slam(s, 3, single);
  int shared[2] = {0, 0};  // landmarks joined by their ids (carried over, seeded), unseeded and seeded
  for (const bool seed : {false, true}) {
    RunOptions o;
    o.step.strategy = Strategy::kPcjcbb;
    o.submaps = true;
    o.submap_seed = seed;
    o.step.submap_landmarks = 30;
    CAPTURE(seed);
    const RunResult r = run_slam(s, 3, o);
    CHECK(r.submaps.maps >= 5);
    CHECK(r.submaps.wrong == 0);
    CHECK(r.submaps.refused == 0);
    REQUIRE(r.submaps.joins.size() == static_cast<std::size_t>(r.submaps.maps));
    for (const JoinRecord& j : r.submaps.joins) {
      shared[seed] += j.shared;
      CHECK(j.shared_dof <= 2 * j.shared);
      CHECK(j.seeded_dof <= j.shared_dof);
      CHECK(j.shared_d2 >= 0);
      CHECK(j.seeded_d2 >= 0);
      if (!seed) CHECK(j.seeded_dof == 0);
    }
    // Unseeded, the loop is closed by the joins' association; seeded, in the local maps.
    if (!seed) CHECK(r.submaps.fused + r.submaps.declined + r.submaps.offered > 0);
    CHECK(r.score.f1() > 0.98);
    // The global map holds the landmarks the single map holds, not a copy per local map.
    CHECK(r.landmarks <= one.landmarks);
    CHECK(r.landmarks >= one.landmarks - 5);
  }
  CHECK(shared[1] > shared[0]);  // the seeds were re-observed and joined by their ids
}

TEST_CASE("global map: a seed is the region's landmarks the local map does not hold, each once, none ambiguous") {
  GlobalMap g(JoinOptions{});
  // Map 0 (the world's frame) ends at (10, 0, 0), exactly: two landmarks near, one far, and two
  // 0.1 m apart (either could be taken for the other: neither is given).
  g.join(make_map(0, {10, 0, 0}, {{12, 1}, {15, -2}, {40, 0}, {18, 5}, {18.1, 5}}, {0, 1, 2, 3, 4}, 0.04));
  REQUIRE(g.landmarks() == 5);
  const Eigen::Vector2d here(10, 0);
  const Seed s = g.seed(here, 20, 10, {});
  REQUIRE(s.first_ids.size() == 2);
  CHECK(s.first_ids[0] == 0);  // nearest first
  CHECK(s.first_ids[1] == 1);
  CHECK((s.x.segment<2>(0) - Eigen::Vector2d(2, 1)).norm() < 1e-12);  // in the base's frame
  CHECK((s.x.segment<2>(2) - Eigen::Vector2d(5, -2)).norm() < 1e-12);
  CHECK(s.P(0, 0) == doctest::Approx(0.04));
  CHECK(g.seed(here, 20, 1, {}).first_ids.size() == 1);  // at most max_count
  CHECK(s.P.block<2, 2>(0, 2).isZero());                 // uncorrelated, as SUBMAP_SEED carries them
  // Held: the local map holds landmark 0 (carried: its id is the global landmark's).
  CHECK(g.seed(here, 20, 10, {0}).first_ids == std::vector<FeatureId>{1});
  // The map refused landmark 1 (it holds one compatible with it): not offered again to this map;
  // one it had no room for is offered again.
  {
    GlobalMap h(JoinOptions{});
    h.join(make_map(0, {10, 0, 0}, {{12, 1}, {15, -2}}, {0, 1}, 0.04));
    const Seed t = h.seed(here, 20, 10, {});
    REQUIRE(t.first_ids.size() == 2);
    h.seeded(t, {kNewFeature, kUnmatched});
    CHECK(h.seed(here, 20, 10, {}).first_ids == std::vector<FeatureId>{0});
  }
  // Seeded at two scans: neither is given again, and each is the map's prior on its landmark: a map
  // that learned nothing about them leaves the global map as it was.
  const Seed a = g.seed(here, 20, 1, {});
  g.seeded(a, {100});
  const Seed b = g.seed(here, 20, 10, {});
  REQUIRE(b.first_ids == std::vector<FeatureId>{1});
  g.seeded(b, {101});
  CHECK(g.seed(here, 20, 10, {}).first_ids.empty());
  const Eigen::Vector2d l0 = g.landmark(0), l1 = g.landmark(1);
  Submap m1 = make_map(1, {1, 0, 0}, {a.x.segment<2>(0), b.x.segment<2>(0)}, {100, 101}, 0.01);
  m1.P.block<2, 2>(3, 3) = a.P;
  m1.P.block<2, 2>(5, 5) = b.P;
  const JoinResult j = g.join(m1);
  CHECK(j.shared == 2);
  CHECK(j.fused == 0);
  CHECK(g.landmarks() == 5);
  CHECK((g.landmark(0) - l0).norm() < 1e-9);
  CHECK((g.landmark(1) - l1).norm() < 1e-9);
}

TEST_CASE(
    "global map: landmarks exist by evidence; a seed carries the global log-odds, a seed the map removed leaves, "
    "an ambiguous landmark is neither fused nor added, a fused one sums two maps' evidence") {
  GlobalMap g(JoinOptions{});
  // Map 0 ends at (10, 0, 0): two landmarks near the robot and two 0.1 m apart (ambiguous).
  Submap m0 = make_map(0, {10, 0, 0}, {{12, 1}, {15, -2}, {18, 5}, {18.1, 5}}, {0, 1, 2, 3}, 0.04);
  m0.exist_nats = {7.0, 30.0, 12.0, 12.0};
  g.join(m0);
  REQUIRE(g.landmarks() == 4);
  CHECK(g.existence(0) == 7.0);
  CHECK(g.existence(1) == 30.0);
  const Seed s = g.seed(Eigen::Vector2d(10, 0), 20, 10, {});
  REQUIRE(s.first_ids == std::vector<FeatureId>{0, 1});
  CHECK(s.exist_nats == std::vector<double>{7.0, 30.0});  // as SUBMAP_SEED carries them
  g.seeded(s, {100, 101});
  // Map 1 removed seed 100 by its evidence (missed where it was expected) and kept 101 with less;
  // it made one landmark between the two close ones (either could be it) and one at global 1's
  // place... which it holds already as 101, so a new one near (25, 0) instead, paired with nothing.
  Submap m1 = make_map(1, {0, 0, 0}, {s.x.segment<2>(2), {8.05, 5}, {15, 0}}, {101, 102, 103}, 0.01);
  m1.P.block<2, 2>(3, 3) = s.P.block<2, 2>(2, 2);
  m1.exist_nats = {25.0, 9.0, 6.0};
  const JoinResult j = g.join(m1);
  CHECK(j.shared == 1);
  CHECK(j.removed == 1);
  CHECK(j.declined == 1);  // 102: within the gates of both close landmarks
  CHECK(j.fused == 0);
  CHECK(j.dropped == 1);
  REQUIRE(g.landmarks() == 4);  // 0 removed; 1, 2, 3 kept; 103 new; 102 left out
  CHECK(g.first_id(0) == 1);
  CHECK(g.existence(0) == 25.0);  // the last map's: it began from the global one
  CHECK(g.first_id(3) == 103);
  CHECK(g.existence(3) == 6.0);
  CHECK((g.landmark(3) - Eigen::Vector2d(25, 0)).norm() < 1e-6);
  // Map 2 makes 103 anew (a new id, not seeded): the join fuses it, and the evidence of both adds up.
  Submap m2 = make_map(2, {0, 0, 0}, {{15, 0}}, {200}, 0.01);
  m2.exist_nats = {5.5};
  const JoinResult k = g.join(m2);
  CHECK(k.fused == 1);
  REQUIRE(g.landmarks() == 4);
  CHECK(g.existence(3) == doctest::Approx(11.5));
}

TEST_CASE("global map: a wrong join within a landmark group is counted as wrong and, apart, as in the group") {
  // Fused pairs (local id, global first id); truths by id: 0 -> 0, 1 -> 1, 2 -> 2, 3 -> 3, 4 unknown.
  // Groups: {0, 1} (closer than the sensor separates), {2}, {3}.
  GlobalMap g(JoinOptions{});
  JoinResult j;
  j.pairs = {{0, 1}, {2, 3}, {1, 1}, {4, 0}};
  const std::vector<int> id_truth{0, 1, 2, 3, RunScorer::kUnknown};
  SubmapStats st;
  record_join(st, j, g, 1.0, id_truth, {0, 0, 1, 2}, 0.0);
  CHECK(st.wrong == 2);           // 0 with 1 and 2 with 3; 1 with 1 is right, an unknown truth is not counted
  CHECK(st.wrong_in_group == 1);  // 0 with 1
  SubmapStats none;
  record_join(none, j, g, 1.0, id_truth, {}, 0.0);  // no groups: each landmark its own
  CHECK(none.wrong == 2);
  CHECK(none.wrong_in_group == 0);
}
