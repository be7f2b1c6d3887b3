// GMM-EM: the EM objective never decreases; well-separated mixtures are recovered; the iteration
// bound holds; degenerate inputs give valid groups and no NaN; BIC finds the number of blobs.
#include <doctest/doctest.h>

#include <memory>
#include <random>
#include <set>
#include <vector>

#include <Eigen/Dense>

#include "geojcbb/cluster/gmm_em.hpp"

using namespace geojcbb;

namespace {
using Big = Bounds<120, 8, 5, 100, 8>;   // enough points to estimate parameters
using Small = Bounds<24, 8, 5, 100, 8>;  // the controller's observation capacity

template <typename T>
constexpr double kRounding = std::is_same<T, float>::value ? 1e-5 : 1e-12;

struct Blob {
  Eigen::Vector2d mu;
  Eigen::Matrix2d sigma;
  int n;
};

template <typename T, class B>
int draw(const std::vector<Blob>& blobs, std::mt19937_64& rng, Points<T, B>& p, std::vector<int>& truth) {
  std::normal_distribution<double> g(0, 1);
  int m = 0;
  for (std::size_t b = 0; b < blobs.size(); ++b) {
    const Eigen::Matrix2d L = blobs[b].sigma.llt().matrixL();
    for (int k = 0; k < blobs[b].n; ++k) {
      p[m++] = (blobs[b].mu + L * Eigen::Vector2d(g(rng), g(rng))).cast<T>();
      truth.push_back(static_cast<int>(b));
    }
  }
  return m;
}
}  // namespace

TEST_CASE_TEMPLATE("EM never decreases its objective (within rounding) on random point sets", T, float, double) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-8, 8);
  auto ws = std::make_unique<EmWorkspace<T, Small>>();
  for (int trial = 0; trial < 400; ++trial) {
    const int m = 1 + static_cast<int>(rng() % 24);
    Points<T, Small> p;
    for (int i = 0; i < m; ++i) p[i] = Vec2<T>(T(u(rng)), T(u(rng)));
    EmOptions<T> opt;
    opt.tolerance = T(0);  // run to the bound: the longest trace
    Groups<Small> g;
    gmm_em(p, m, 1 + static_cast<int>(rng() % 5), opt, *ws, g);
    for (int t = 1; t < ws->trace_length; ++t) {
      const double prev = ws->trace[t - 1], next = ws->trace[t];
      CHECK(next >= prev - kRounding<T> * (1 + std::abs(prev)));
    }
  }
}

TEST_CASE_TEMPLATE("EM recovers the parameters of a well-separated mixture", T, float, double) {
  std::mt19937_64 rng(5);
  Eigen::Matrix2d s1, s2, s3;
  s1 << 0.25, 0.1, 0.1, 0.5;
  s2 << 0.6, -0.2, -0.2, 0.3;
  s3 << 0.4, 0.0, 0.0, 0.4;
  const std::vector<Blob> blobs{{{0, 0}, s1, 60}, {{12, 2}, s2, 30}, {{4, 14}, s3, 30}};
  for (int rep = 0; rep < 5; ++rep) {
    Points<T, Big> p;
    std::vector<int> truth;
    const int m = draw<T, Big>(blobs, rng, p, truth);
    auto ws = std::make_unique<EmWorkspace<T, Big>>();
    Groups<Big> g;
    EmOptions<T> opt;
    opt.covariance_floor_m2 = T(1e-3);
    const EmStats st = gmm_em(p, m, 3, opt, *ws, g);
    CHECK(st.converged);
    REQUIRE(g.count == 3);
    // Each blob lands in one group of its own.
    for (std::size_t b = 0; b < blobs.size(); ++b) {
      std::set<int> seen;
      for (int i = 0; i < m; ++i)
        if (truth[i] == static_cast<int>(b)) seen.insert(g.label[i]);
      CHECK(seen.size() == 1);
    }
    for (const Blob& b : blobs) {
      int q = 0;  // the fitted component nearest this blob
      for (int k = 1; k < ws->k; ++k)
        if ((ws->mu[k].template cast<double>() - b.mu).norm() < (ws->mu[q].template cast<double>() - b.mu).norm())
          q = k;
      CHECK((ws->mu[q].template cast<double>() - b.mu).norm() < 0.4);
      CHECK(std::exp(static_cast<double>(ws->log_pi[q])) == doctest::Approx(double(b.n) / m).epsilon(1e-3));
      CHECK((ws->sigma[q].template cast<double>() - b.sigma).norm() < 0.5 * b.sigma.norm());
    }
  }
}

TEST_CASE_TEMPLATE("EM respects its iteration bound and reports it", T, float, double) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-5, 5);
  Points<T, Small> p;
  for (int i = 0; i < 24; ++i) p[i] = Vec2<T>(T(u(rng)), T(u(rng)));
  auto ws = std::make_unique<EmWorkspace<T, Small>>();
  Groups<Small> g;
  EmOptions<T> opt;
  opt.tolerance = T(0);
  opt.max_iterations = 3;
  EmStats st = gmm_em(p, 24, 4, opt, *ws, g);
  CHECK(st.iterations <= 3);
  opt.max_iterations = 1000;  // clamped to kMaxEmIterations
  st = gmm_em(p, 24, 4, opt, *ws, g);
  CHECK(st.iterations <= kMaxEmIterations);
  CHECK(ws->trace_length <= kMaxEmIterations + 1);
}

TEST_CASE_TEMPLATE("EM on degenerate inputs: valid groups, no NaN", T, float, double) {
  auto ws = std::make_unique<EmWorkspace<T, Small>>();
  auto check_valid = [&](const Points<T, Small>& p, int m, int k) {
    Groups<Small> g;
    const EmStats st = gmm_em(p, m, k, EmOptions<T>{}, *ws, g);
    CHECK(std::isfinite(st.objective));
    CHECK(g.count >= 1);
    CHECK(g.count <= std::min(m, Small::kMaxGroups));
    for (int i = 0; i < m; ++i) {
      CHECK(g.label[i] >= 0);
      CHECK(g.label[i] < g.count);
    }
    for (int q = 0; q < ws->k; ++q) {
      CHECK(ws->mu[q].allFinite());
      CHECK(ws->sigma[q].allFinite());
      CHECK(ws->sigma[q].determinant() > T(0));
      CHECK(std::isfinite(ws->log_pi[q]));
    }
  };
  Points<T, Small> p;
  p[0] = Vec2<T>(T(1), T(2));
  check_valid(p, 1, 3);  // one point, K = 3
  p[1] = Vec2<T>(T(4), T(-1));
  check_valid(p, 2, 5);  // m < K
  for (int i = 0; i < 10; ++i) p[i] = Vec2<T>(T(3), T(3));
  check_valid(p, 10, 3);  // all identical
  for (int i = 0; i < 12; ++i) p[i] = Vec2<T>(T(i), T(2 * i));
  check_valid(p, 12, 3);  // collinear
  check_valid(p, 12, 0);  // collinear, K by BIC
  Groups<Small> g;
  CHECK(gmm_em(p, 0, 3, EmOptions<T>{}, *ws, g).components == 0);  // no points
  CHECK(g.count == 0);
}

// With the default covariance floor (0.04 m^2). A floor far below the blobs' spread lets BIC
// over-split 8-point blobs now and then (measured: 0.01 m^2 picks K = 4 or 5 in 5 of 200 draws;
// docs/algorithms.md).
TEST_CASE_TEMPLATE("EM with K = 0 chooses the number of well-separated blobs by BIC", T, float, double) {
  std::mt19937_64 rng(17);
  const Eigen::Matrix2d s = Eigen::Matrix2d::Identity() * 0.09;
  const std::vector<Blob> blobs{{{0, 0}, s, 8}, {{8, 0}, s, 8}, {{0, 8}, s, 8}};
  for (int rep = 0; rep < 10; ++rep) {
    Points<T, Small> p;
    std::vector<int> truth;
    const int m = draw<T, Small>(blobs, rng, p, truth);
    auto ws = std::make_unique<EmWorkspace<T, Small>>();
    Groups<Small> g;
    gmm_em(p, m, 0, EmOptions<T>{}, *ws, g);
    CHECK(g.count == 3);
  }
}

namespace {
/// True when two labelings are the same partition (labels compacted: equal arrays).
template <class B>
bool same_groups(const Groups<B>& a, const Groups<B>& b, int m) {
  if (a.count != b.count) return false;
  for (int i = 0; i < m; ++i)
    if (a.label[i] != b.label[i]) return false;
  return true;
}
}  // namespace

// Packed covariance: the default start (k-means) and stop (an E-step leaves the groups
// unchanged) return the groups of the start and stop before it (farthest-first seeds, objective
// tolerance) on mixtures whose groups are clear, in fewer iterations; with a hardness margin, where
// the groups are not clear (soft responsibilities) the stop is the papers' rule.
TEST_CASE_TEMPLATE("EM stopped when its groups are stable gives the papers' groups, sooner", T, float, double) {
  std::mt19937_64 rng(29);
  const Eigen::Matrix2d s = Eigen::Matrix2d::Identity() * 0.09;
  int fewer = 0;
  for (int rep = 0; rep < 50; ++rep) {
    std::uniform_real_distribution<double> u(-12, 12);
    std::vector<Blob> blobs;
    blobs.reserve(3);
    for (int b = 0; b < 3; ++b) blobs.push_back({{u(rng), u(rng)}, s, 4 + static_cast<int>(rng() % 5)});
    Points<T, Small> p;
    std::vector<int> truth;
    const int m = draw<T, Small>(blobs, rng, p, truth);
    auto ws = std::make_unique<EmWorkspace<T, Small>>();
    for (int k : {3, 0}) {
      CAPTURE(rep);
      CAPTURE(k);
      EmOptions<T> papers;  // before packed covariance: farthest-first start, objective tolerance
      papers.stop = EmStop::kObjective;
      papers.start = EmStart::kFarthestFirst;
      Groups<Small> g_papers, g_stable;
      const EmStats<T> a = gmm_em(p, m, k, papers, *ws, g_papers);
      const EmStats<T> b = gmm_em(p, m, k, EmOptions<T>{}, *ws, g_stable);
      CHECK(b.total_iterations <= a.total_iterations);
      fewer += b.total_iterations < a.total_iterations;
      CHECK(same_groups(g_papers, g_stable, m));
    }
  }
  CHECK(fewer > 20);
  // With a hardness margin: soft responsibilities (one blob, K = 2) are never "hard", so the stop is
  // the papers' rule and the fit runs as long.
  Points<T, Small> p;
  std::vector<int> truth;
  const int m = draw<T, Small>({{{0, 0}, Eigen::Matrix2d::Identity(), 20}}, rng, p, truth);
  auto ws = std::make_unique<EmWorkspace<T, Small>>();
  EmOptions<T> papers, hard;
  papers.stop = EmStop::kObjective;
  papers.start = hard.start = EmStart::kFarthestFirst;  // the same start: only the stop differs
  hard.hard_margin = T(0.01);
  Groups<Small> g_papers, g_hard;
  const EmStats<T> a = gmm_em(p, m, 2, papers, *ws, g_papers);
  const EmStats<T> b = gmm_em(p, m, 2, hard, *ws, g_hard);
  CHECK_FALSE(ws->hard);
  CHECK(b.iterations == a.iterations);
  CHECK(same_groups(g_papers, g_hard, m));
}

// Packed covariance: EM and its BIC run in the Scalar (float on the controller; the BIC
// was double). Float and double fits of the same points find the same groups and the same K where
// the data decide them.
TEST_CASE("EM in float finds the groups and the K of EM in double") {
  std::mt19937_64 rng(31);
  const Eigen::Matrix2d s = Eigen::Matrix2d::Identity() * 0.09;
  for (int rep = 0; rep < 40; ++rep) {
    std::uniform_real_distribution<double> u(-15, 15);
    std::vector<Blob> blobs;
    const int nb = 1 + static_cast<int>(rng() % 4);
    blobs.reserve(static_cast<std::size_t>(nb));
    for (int b = 0; b < nb; ++b) blobs.push_back({{u(rng), u(rng)}, s, 5});
    Points<double, Small> pd;
    std::vector<int> truth;
    const int m = draw<double, Small>(blobs, rng, pd, truth);
    Points<float, Small> pf;
    for (int i = 0; i < m; ++i) pf[i] = pd[i].cast<float>();
    auto wd = std::make_unique<EmWorkspace<double, Small>>();
    auto wf = std::make_unique<EmWorkspace<float, Small>>();
    for (int k : {0, 3}) {
      for (EmStop stop : {EmStop::kObjective, EmStop::kGroupsStable}) {
        CAPTURE(rep);
        CAPTURE(k);
        EmOptions<double> od;
        EmOptions<float> of;
        od.stop = stop;
        of.stop = stop;
        od.start = of.start = stop == EmStop::kObjective ? EmStart::kFarthestFirst : EmStart::kKMeans;
        Groups<Small> gd, gf;
        const EmStats<double> sd = gmm_em(pd, m, k, od, *wd, gd);
        const EmStats<float> sf = gmm_em(pf, m, k, of, *wf, gf);
        CHECK(sd.components == sf.components);
        CHECK(same_groups(gd, gf, m));
        CHECK(sf.log_likelihood == doctest::Approx(sd.log_likelihood).epsilon(1e-3));
      }
    }
  }
}
