// Several robots' maps merged with their starts unknown (map_merge.hpp, docs/submaps.md): the starts
// are found from the maps alone, each landmark seen by several robots becomes one, no two different
// landmarks are fused; a map that aligns two ways equally well (a regular grid) is kept apart rather
// than guessed; a map with nothing in common is kept apart.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "geojcbb_host/map_merge.hpp"

using namespace geojcbb;
using namespace geojcbb::host;

namespace {
// The landmarks `which` of `world`, seen from a robot that started at `start`, in its own frame, with
// independent noise of std sigma on each coordinate (and that covariance).
RobotMap seen_from(const std::vector<Eigen::Vector2d>& world, const std::vector<int>& which, const Pose2<double>& start,
                   double sigma, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, sigma);
  RobotMap m;
  const double c = std::cos(start.theta), s = std::sin(start.theta);
  for (int i : which) {
    const Eigen::Vector2d d = world[static_cast<std::size_t>(i)] - Eigen::Vector2d(start.x, start.y);
    m.landmarks.emplace_back(c * d.x() + s * d.y() + n(rng), -s * d.x() + c * d.y() + n(rng));
    m.truth.push_back(i);
  }
  const int k = static_cast<int>(which.size());
  m.P = Eigen::MatrixXd::Identity(2 * k, 2 * k) * sigma * sigma;
  return m;
}

// n landmarks uniform in [-half, half]^2 (x drawn before y).
std::vector<Eigen::Vector2d> random_world(int n, double half, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-half, half);
  std::vector<Eigen::Vector2d> world(static_cast<std::size_t>(n));
  for (Eigen::Vector2d& w : world) {
    const double x = u(rng);
    w = Eigen::Vector2d(x, u(rng));
  }
  return world;
}

// 0, 1, ..., n - 1, each times step.
std::vector<int> indices(int n, int step = 1) {
  std::vector<int> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] = i * step;
  return v;
}
}  // namespace

TEST_CASE("merge: five robots' maps with unknown starts become one map, the starts found") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  std::vector<Eigen::Vector2d> world;
  world.reserve(15);
  for (int i = 0; i < 15; ++i) world.emplace_back(u(rng), u(rng));
  const std::vector<Pose2<double>> starts{{-4, -4, 0.3}, {3, -2, 2.0}, {0, 4, -1.2}, {-2, 1, 3.0}, {4, 4, -2.5}};
  std::vector<RobotMap> maps;
  std::uniform_int_distribution<int> drop(0, 14);
  for (const Pose2<double>& s : starts) {
    std::vector<int> which;
    const int a = drop(rng), b = drop(rng);  // each robot misses up to two landmarks
    for (int i = 0; i < 15; ++i)
      if (i != a && i != b) which.push_back(i);
    maps.push_back(seen_from(world, which, s, 0.03, rng));
  }
  const MergeResult m = merge_maps(maps);
  CHECK(m.landmarks.size() == 15);
  CHECK(m.wrong == 0);
  for (std::size_t k = 1; k < starts.size(); ++k) {
    CAPTURE(k);
    REQUIRE(m.aligned[k]);
    // Robot k's start in robot 0's frame.
    const Pose2<double>& a = starts[0];
    const Pose2<double>& b = starts[k];
    const double c = std::cos(a.theta), s = std::sin(a.theta);
    const double tx = c * (b.x - a.x) + s * (b.y - a.y), ty = -s * (b.x - a.x) + c * (b.y - a.y);
    CHECK(std::hypot(m.start[k].x - tx, m.start[k].y - ty) < 0.1);
    CHECK(std::abs(wrap_angle(m.start[k].theta - wrap_angle(b.theta - a.theta))) < 0.02);
    // The start's covariance says how far it may be: the error's NEES within chi2(0.999, 3).
    const Eigen::Vector3d err(m.start[k].x - tx, m.start[k].y - ty, wrap_angle(m.start[k].theta - (b.theta - a.theta)));
    const Eigen::Matrix3d& C = m.start_cov[k];
    REQUIRE(C.determinant() > 0);
    CAPTURE(err.transpose());
    CAPTURE(C);
    CHECK(err.dot(C.ldlt().solve(err)) < 16.27);
  }
  CHECK(m.start_cov[0].isZero());
  // Every merged landmark is one true landmark, near it.
  for (std::size_t j = 0; j < m.landmarks.size(); ++j) {
    const Eigen::Vector2d w = world[static_cast<std::size_t>(m.truth[j])];
    const double c = std::cos(starts[0].theta), s = std::sin(starts[0].theta);
    const Eigen::Vector2d d = w - Eigen::Vector2d(starts[0].x, starts[0].y);
    CHECK((m.landmarks[j] - Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y())).norm() < 0.1);
  }
}

TEST_CASE("merge: a map that fits two ways (a regular grid) or not at all is kept apart, not guessed") {
  std::mt19937 rng(3);
  std::vector<Eigen::Vector2d> grid;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) grid.emplace_back(3.0 * i, 3.0 * j);
  std::vector<int> all(16);
  for (int i = 0; i < 16; ++i) all[static_cast<std::size_t>(i)] = i;
  std::vector<RobotMap> maps{seen_from(grid, all, {0, 0, 0}, 0.02, rng),
                             seen_from(grid, {0, 1, 2, 4, 5, 6, 8, 9, 10}, {1, 1, 0.4}, 0.02, rng)};
  // Far away and unlike: nothing in common.
  std::vector<Eigen::Vector2d> other{{100, 100}, {104, 101}, {101, 107}, {109, 103}, {103, 110}, {108, 108}};
  maps.push_back(seen_from(other, {0, 1, 2, 3, 4, 5}, {100, 100, 0}, 0.02, rng));
  const MergeResult m = merge_maps(maps);
  CHECK_FALSE(m.aligned[1]);  // a 3x3 sub-grid fits the 4x4 grid in four places
  CHECK(m.why[1].find("ambiguous") != std::string::npos);
  CHECK_FALSE(m.aligned[2]);
  CHECK(m.wrong == 0);
  CHECK(m.landmarks.size() == 16);
}

TEST_CASE("merge: a map larger than the alignment's capacity is kept apart with the reason, and the rest merge") {
  std::mt19937 rng(5);
  const std::vector<Eigen::Vector2d> world = random_world(130, 15.0, rng);
  const std::vector<int> all = indices(130), some = indices(40, 3);
  std::vector<RobotMap> maps{seen_from(world, some, {0, 0, 0}, 0.01, rng),
                             seen_from(world, all, {1, 0.5, 0.3}, 0.01, rng),  // 130 > 127
                             seen_from(world, some, {2, 1, -0.2}, 0.01, rng)};
  const MergeResult m = merge_maps(maps);  // no exception
  REQUIRE(m.aligned.size() == 3);
  CHECK_FALSE(m.aligned[1]);
  CHECK(m.why[1].find("capacity") != std::string::npos);
  CHECK(m.aligned[2]);
  CHECK(m.wrong == 0);
  // Each pair passes its 0.99 gate: of 40, one or two may be kept as new landmarks.
  CHECK(m.pairs[2] >= 38);
  CHECK(m.landmarks.size() == static_cast<std::size_t>(40 + 40 - m.pairs[2]));
}

TEST_CASE("merge: a pair that another landmark could take under the alignment's uncertainty is refused, not guessed") {
  // Robot 0 maps 12 landmarks and a 13th 0.3 m from landmark 0; robot 1 sees the 12, not the 13th.
  std::mt19937 rng(11);
  std::vector<Eigen::Vector2d> world = random_world(12, 6.0, rng);
  world.emplace_back(world[0] + Eigen::Vector2d(0.3, 0.0));
  const std::vector<int> all = indices(13), shared = indices(12);
  const Pose2<double> s0{0, 0, 0}, s1{2, -1, 0.8};
  SUBCASE("maps precise enough to tell the two apart (2 cm): joined, landmark 0 with landmark 0") {
    const MergeResult m = merge_maps({seen_from(world, all, s0, 0.02, rng), seen_from(world, shared, s1, 0.02, rng)});
    REQUIRE(m.aligned[1]);
    CHECK(m.wrong == 0);
    CHECK(m.pairs[1] >= 11);
  }
  SUBCASE("maps too uncertain for 0.3 m (15 cm): kept apart as ambiguous") {
    const MergeResult m = merge_maps({seen_from(world, all, s0, 0.15, rng), seen_from(world, shared, s1, 0.15, rng)});
    CHECK_FALSE(m.aligned[1]);
    CAPTURE(m.why[1]);
    CHECK(m.why[1].find("ambiguous pairs") != std::string::npos);
    CHECK(m.wrong == 0);
    CHECK(m.landmarks.size() == 13);
  }
}
