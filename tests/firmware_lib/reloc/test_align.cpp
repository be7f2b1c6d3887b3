// The pose-free relocaliser's alignment (reloc/align.hpp): the true pose found on random maps whenever a
// base pair is clean, against an exhaustive search over every observed and map pair; a mirrored
// constellation rejected; a map that repeats itself (two copies) not accepted (no unique pose); the
// fit's covariance against the spread of the answers over noise draws; bad input a Status with the
// output untouched; no allocation; float and double agree.
#include <doctest/doctest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <Eigen/LU>

#include "geojcbb/reloc/align.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;
using namespace geojcbb::reloc;

namespace {

using B = DefaultBounds;

struct World {
  std::vector<Eigen::Vector2d> map;  ///< landmark positions
  std::vector<int> truth;            ///< per observation: landmark index or -1 (clutter)
  std::vector<Eigen::Vector2d> z;    ///< (range, bearing)
  Pose2<double> pose{};              ///< where the robot is
};

constexpr double kSigmaR = 0.1, kSigmaB = 0.0175;  // 0.1 m, 1 degree

/// n landmarks at least 3 m apart in a 60 m square; a pose inside it; the landmarks within 20 m in
/// the half plane ahead observed with noise (scale 0: exact), plus `clutter` false returns.
World make_world(std::uint64_t seed, int n, int clutter, double noise) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-30, 30);
  std::normal_distribution<double> g(0, 1);
  World w;
  for (int tries = 0; static_cast<int>(w.map.size()) < n && tries < 100000; ++tries) {
    const Eigen::Vector2d p(u(rng), u(rng));
    bool ok = true;
    for (const auto& q : w.map) ok = ok && (p - q).norm() >= 3;
    if (ok) w.map.push_back(p);
  }
  w.pose = {0.5 * u(rng), 0.5 * u(rng), std::uniform_real_distribution<double>(-3.1, 3.1)(rng)};
  for (int j = 0; j < static_cast<int>(w.map.size()); ++j) {
    const Eigen::Vector2d d = w.map[j] - Eigen::Vector2d(w.pose.x, w.pose.y);
    const double r = d.norm(), b = wrap_angle(std::atan2(d.y(), d.x()) - w.pose.theta);
    if (r > 20 || r < 0.5 || std::abs(b) > kPi<double> / 2) continue;
    w.z.emplace_back(r + noise * kSigmaR * g(rng), b + noise * kSigmaB * g(rng));
    w.truth.push_back(j);
  }
  for (int c = 0; c < clutter; ++c) {
    w.z.emplace_back(1 + 19 * std::uniform_real_distribution<double>(0, 1)(rng),
                     std::uniform_real_distribution<double>(-1.5, 1.5)(rng));
    w.truth.push_back(-1);
  }
  return w;
}

template <typename T>
struct Problem {
  Observations<T, B> obs;
  AlignWorkspace<T, B> ws;
  AlignResult<T, B> out;
};

template <typename T>
std::unique_ptr<Problem<T>> load(const World& w, const std::vector<Eigen::Vector2d>& map, double map_sigma = 0.05) {
  auto p = std::make_unique<Problem<T>>();
  Mat2<T> R;
  R << T(kSigmaR * kSigmaR), T(0), T(0), T(kSigmaB * kSigmaB);
  for (std::size_t i = 0; i < w.z.size() && static_cast<int>(i) < B::kMaxObservations; ++i) {
    REQUIRE(p->obs.push(w.z[i].cast<T>(), R) == Status::kOk);
  }
  p->ws.clear_map();
  for (const auto& m : map) {
    REQUIRE(p->ws.push_landmark(m.cast<T>(), Mat2<T>::Identity() * T(map_sigma * map_sigma)) == Status::kOk);
  }
  return p;
}

/// The options with the test's sensor: 20 m, 180 degrees.
template <typename T>
AlignOptions<T> align_options() {
  AlignOptions<T> o;
  o.max_range_m = T(20);
  o.half_fov_rad = kPi<T> / 2;
  return o;
}

double pose_error_m(const Pose2<double>& a, const Pose2<double>& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double heading_error_rad(const Pose2<double>& a, const Pose2<double>& b) {
  return std::abs(wrap_angle(a.theta - b.theta));
}
template <typename T>
Pose2<double> to_double(const Pose2<T>& x) {
  return {static_cast<double>(x.x), static_cast<double>(x.y), static_cast<double>(x.theta)};
}

/// The most inliers any two-point hypothesis reaches (every observed pair, every map pair, both
/// assignments), with exact geometry: the oracle of what the search could find.
int exhaustive_best_inliers(const World& w, double gate_m) {
  int best = 0;
  const int m = static_cast<int>(w.z.size());
  auto point = [&](int i) {
    return Eigen::Vector2d(w.z[i].x() * std::cos(w.z[i].y()), w.z[i].x() * std::sin(w.z[i].y()));
  };
  for (int a = 0; a < m; ++a)
    for (int b = a + 1; b < m; ++b)
      for (std::size_t j = 0; j < w.map.size(); ++j)
        for (std::size_t k = 0; k < w.map.size(); ++k) {
          if (j == k) continue;
          const Eigen::Vector2d u = point(b) - point(a), v = w.map[k] - w.map[j];
          if (std::abs(u.norm() - v.norm()) > 0.3 || u.norm() < 2) continue;
          const double th = std::atan2(v.y(), v.x()) - std::atan2(u.y(), u.x());
          Eigen::Matrix2d Rm;
          Rm << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
          const Eigen::Vector2d t = w.map[j] - Rm * point(a);
          int in = 0;
          for (int i = 0; i < m; ++i) {
            const Eigen::Vector2d p = Rm * point(i) + t;
            bool hit = false;
            for (const auto& l : w.map) hit = hit || (p - l).norm() < gate_m;
            in += hit;
          }
          best = std::max(best, in);
        }
  return best;
}

}  // namespace

TEST_CASE_TEMPLATE("reloc: the true pose is found on random maps whenever a base pair is clean", T, float, double) {
  int clean_runs = 0, found = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const World w = make_world(seed, 60, 2, 1.0);
    if (w.z.size() < 6) continue;
    auto p = load<T>(w, w.map);
    const AlignOptions<T> opt = align_options<T>();
    REQUIRE(align(p->obs, opt, p->ws, p->out) == Status::kOk);
    bool clean = false;
    for (int b = 0; b < opt.base_pairs; ++b) {
      const int a = p->ws.base[2 * b], c = p->ws.base[2 * b + 1];
      clean = clean || (w.truth[a] >= 0 && w.truth[c] >= 0);
    }
    if (!clean) continue;
    ++clean_runs;
    CAPTURE(seed);
    REQUIRE(p->out.accepted);
    ++found;
    const Pose2<double> x = to_double(p->out.pose);
    CHECK(pose_error_m(x, w.pose) < 0.3);
    CHECK(heading_error_rad(x, w.pose) < 0.02);
    // Every inlier is a true pairing (or a false return that fell next to a landmark).
    for (int i = 0; i < p->obs.count; ++i) {
      const int j = p->out.landmark[i];
      if (j < 0) continue;
      if (w.truth[i] >= 0) {
        CHECK(j == w.truth[i]);
      } else {
        const Eigen::Vector2d at(w.pose.x + w.z[i].x() * std::cos(w.pose.theta + w.z[i].y()),
                                 w.pose.y + w.z[i].x() * std::sin(w.pose.theta + w.z[i].y()));
        CHECK((at - w.map[static_cast<std::size_t>(j)]).norm() < 1.0);
      }
    }
    // The refined answer has as many inliers as the best two-point hypothesis of any pair has within
    // a 1 m gate, less those a gate in sigmas turns away at the far ranges.
    CHECK(p->out.inliers + 2 >= exhaustive_best_inliers(w, 1.0));
    CHECK(p->out.score >= p->out.rival_score + opt.margin_nats);  // unique by the margin (a rival at -inf: none)
  }
  CHECK(clean_runs >= 30);
  CHECK(found == clean_runs);
}

// The evidence test against "not of the map" (AlignOptions::test_unmapped, the relocaliser's): a
// scan of ground the map has never seen is left unaligned, however many look-alike poses a dense map
// offers; the true pose of a mapped scan still passes, pose-free and under a reset's wide prior.
TEST_CASE_TEMPLATE("reloc: a scan of unmapped ground is not aligned; a mapped one still is", T, float, double) {
  int coincidences = 0, mapped = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const World w = make_world(seed, 60, 0, 1.0);
    if (w.z.size() < 6) continue;
    // A map of other landmarks, half as dense again and loosely known (0.7 m): the scan's own
    // landmarks are not in it, but coincidences within the landmarks' uncertainty are many.
    const World other = make_world(seed + 1000, 90, 0, 0.0);
    AlignOptions<T> o = align_options<T>();
    o.free_log_volume = T(std::log(60.0 * 60.0 * 2 * kPi<double>));
    auto p = load<T>(w, other.map, 0.7);
    REQUIRE(align(p->obs, o, p->ws, p->out) == Status::kOk);
    coincidences += p->out.accepted;
    o.test_unmapped = true;
    REQUIRE(align(p->obs, o, p->ws, p->out) == Status::kOk);
    CAPTURE(seed);
    CHECK(!p->out.accepted);
    auto q = load<T>(w, w.map);
    REQUIRE(align(q->obs, o, q->ws, q->out) == Status::kOk);
    const bool pose_free = q->out.accepted && pose_error_m(to_double(q->out.pose), w.pose) < 0.3;
    // A reset: 15 m and pi rad of sigma around an estimate 8 m off.
    const Pose2<T> guess{T(w.pose.x + 6), T(w.pose.y - 5), T(wrap_angle(w.pose.theta + 1.0))};
    REQUIRE(set_prior(guess, Mat3<T>(Vec3<T>(T(225), T(225), T(9.87)).asDiagonal()), o));
    REQUIRE(align(q->obs, o, q->ws, q->out) == Status::kOk);
    const bool with_prior = q->out.accepted && pose_error_m(to_double(q->out.pose), w.pose) < 0.3;
    mapped += pose_free && with_prior;
  }
  CHECK(coincidences > 0);  // without the test, the dense map offers poses that pass
  CHECK(mapped >= 30);
}

TEST_CASE_TEMPLATE("reloc: a mirrored constellation is not accepted", T, float, double) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const World w = make_world(seed, 60, 0, 0.0);
    if (w.z.size() < 6) continue;
    // The map mirrored about the robot's own heading line: every distance between landmarks is kept,
    // so each base pair finds its match, but no rotation lines up the rest.
    std::vector<Eigen::Vector2d> mirrored;
    const Eigen::Vector2d o(w.pose.x, w.pose.y), h(std::cos(w.pose.theta), std::sin(w.pose.theta));
    for (const auto& l : w.map) {
      const Eigen::Vector2d d = l - o;
      mirrored.push_back(o + 2 * d.dot(h) * h - d);
    }
    auto p = load<T>(w, mirrored);
    REQUIRE(align(p->obs, align_options<T>(), p->ws, p->out) == Status::kOk);
    CAPTURE(seed);
    CHECK(!p->out.accepted);
  }
}

TEST_CASE_TEMPLATE("reloc: a map with two copies of the scene has no unique pose", T, float, double) {
  const World w = make_world(3, 30, 0, 1.0);
  REQUIRE(w.z.size() >= 6);
  std::vector<Eigen::Vector2d> twice = w.map;
  for (const auto& l : w.map) twice.push_back(l + Eigen::Vector2d(200, 0));
  auto p = load<T>(w, twice);
  REQUIRE(align(p->obs, align_options<T>(), p->ws, p->out) == Status::kOk);
  CHECK(!p->out.accepted);
  CHECK(p->out.inliers == p->out.rival_inliers);
}

// The prior (the filter's pose and covariance) decides between look-alike places the scan alone
// cannot: a copy of the scene 200 m away is no rival to an estimate with a 5 m sigma, and an
// estimate at the copy finds the copy. Pose-free, the same scan is ambiguous (docs/design.md, "Decisions with the prior").
TEST_CASE_TEMPLATE("reloc: with the pose prior, a look-alike place far from the estimate is no rival", T, float,
                   double) {
  const World w = make_world(3, 30, 0, 1.0);
  REQUIRE(w.z.size() >= 6);
  std::vector<Eigen::Vector2d> twice = w.map;
  for (const auto& l : w.map) twice.push_back(l + Eigen::Vector2d(200, 0));
  const Mat3<T> P = Vec3<T>(T(25), T(25), T(0.25)).asDiagonal();  // 5 m, 0.5 rad
  for (const double shift : {0.0, 200.0}) {
    CAPTURE(shift);
    auto p = load<T>(w, twice);
    AlignOptions<T> o = align_options<T>();
    // An estimate 3 m and 0.2 rad off the true pose (or off its copy).
    const Pose2<T> guess{T(w.pose.x + shift + 3), T(w.pose.y - 2), T(wrap_angle(w.pose.theta + 0.2))};
    REQUIRE(set_prior(guess, P, o));
    REQUIRE(align(p->obs, o, p->ws, p->out) == Status::kOk);
    CHECK(p->out.accepted);
    CHECK(!p->out.ambiguous);
    Pose2<double> want = w.pose;
    want.x += shift;
    CHECK(pose_error_m(to_double(p->out.pose), want) < 0.5);
    CHECK(heading_error_rad(to_double(p->out.pose), want) < 0.05);
  }
  auto p = load<T>(w, twice);
  REQUIRE(align(p->obs, align_options<T>(), p->ws, p->out) == Status::kOk);
  CHECK(!p->out.accepted);
  CHECK(p->out.ambiguous);
  CHECK(p->out.score - p->out.rival_score < T(10));
  // A prior that is not a covariance is refused: the search stays pose-free.
  AlignOptions<T> o = align_options<T>();
  CHECK(!set_prior(Pose2<T>{}, Mat3<T>(-Mat3<T>::Identity()), o));
  CHECK(!o.has_prior);
}

TEST_CASE("reloc: the fit's covariance is the spread of its answers over noise draws") {
  // One map and pose; 200 noise draws of the scan; the NEES of the answers against the fit's covariance
  // averages about 3 (3 dof) when the covariance is right.
  const World base = make_world(7, 60, 0, 0.0);
  REQUIRE(base.z.size() >= 8);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0, 1);
  double nees = 0;
  int n = 0;
  for (int draw = 0; draw < 200; ++draw) {
    World w = base;
    for (auto& z : w.z) z += Eigen::Vector2d(kSigmaR * g(rng), kSigmaB * g(rng));
    auto p = load<double>(w, w.map, 1e-3);
    REQUIRE(align(p->obs, align_options<double>(), p->ws, p->out) == Status::kOk);
    REQUIRE(p->out.accepted);
    const Eigen::Vector3d e(p->out.pose.x - w.pose.x, p->out.pose.y - w.pose.y,
                            wrap_angle(p->out.pose.theta - w.pose.theta));
    nees += e.dot(p->out.cov.inverse() * e);
    ++n;
  }
  const double mean = nees / n;
  CHECK(mean > 2.0);  // 200 draws: the mean of chi2(3) / 200 has a standard deviation of 0.17
  CHECK(mean < 4.0);
}

TEST_CASE_TEMPLATE("reloc: bad input is a Status and the output is untouched", T, float, double) {
  const World w = make_world(1, 60, 0, 1.0);
  auto p = load<T>(w, w.map);
  p->out.inliers = 77;
  AlignOptions<T> bad;
  bad.base_pairs = kMaxBasePairs + 1;
  CHECK(align(p->obs, bad, p->ws, p->out) == Status::kInvalidInput);
  bad = align_options<T>();
  bad.min_inliers = 2;
  CHECK(align(p->obs, bad, p->ws, p->out) == Status::kInvalidInput);
  p->obs.z[0].x() = std::numeric_limits<T>::quiet_NaN();
  CHECK(align(p->obs, align_options<T>(), p->ws, p->out) == Status::kNonFinite);
  CHECK(p->out.inliers == 77);
  // The map's own checks.
  CHECK(p->ws.push_landmark(Vec2<T>(std::numeric_limits<T>::infinity(), 0), Mat2<T>::Identity()) == Status::kNonFinite);
  CHECK(p->ws.push_landmark(Vec2<T>(0, 0), -Mat2<T>::Identity()) == Status::kNotPositiveDefinite);
  const int n = p->ws.n;
  while (p->ws.n < B::kMaxLandmarks) REQUIRE(p->ws.push_landmark(Vec2<T>(0, 0), Mat2<T>::Identity()) == Status::kOk);
  CHECK(p->ws.push_landmark(Vec2<T>(0, 0), Mat2<T>::Identity()) == Status::kCapacityExceeded);
  CHECK(n == static_cast<int>(w.map.size()));
}

TEST_CASE_TEMPLATE("reloc: align allocates nothing", T, float, double) {
  const World w = make_world(2, 96, 3, 1.0);
  auto p = load<T>(w, w.map);
  Status s = Status::kNoConvergence;
  CHECK(test::allocations_during([&] { s = align(p->obs, align_options<T>(), p->ws, p->out); }) == 0);
  CHECK(s == Status::kOk);
}

TEST_CASE("reloc: float and double agree on a well-conditioned scene") {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const World w = make_world(seed, 60, 1, 1.0);
    if (w.z.size() < 6) continue;
    auto pf = load<float>(w, w.map);
    auto pd = load<double>(w, w.map);
    REQUIRE(align(pf->obs, align_options<float>(), pf->ws, pf->out) == Status::kOk);
    REQUIRE(align(pd->obs, align_options<double>(), pd->ws, pd->out) == Status::kOk);
    CAPTURE(seed);
    REQUIRE(pf->out.accepted == pd->out.accepted);
    if (!pd->out.accepted) continue;
    CHECK(pf->out.inliers == pd->out.inliers);
    CHECK(pose_error_m(to_double(pf->out.pose), to_double(pd->out.pose)) < 1e-3);
    CHECK(heading_error_rad(to_double(pf->out.pose), to_double(pd->out.pose)) < 1e-4);
  }
}
