// k-means and DBSCAN: small hand-checkable cases, and brute-force checks on random point sets.
#include <doctest/doctest.h>

#include <random>
#include <set>
#include <vector>

#include "geojcbb/cluster/dbscan.hpp"
#include "geojcbb/cluster/kmeans.hpp"

using namespace geojcbb;

namespace {
using Wide = Bounds<16, 8, 16, 100, 8>;  // MaxGroups = MaxObservations: no capacity merging
using Narrow = Bounds<16, 8, 3, 100, 8>;

template <typename T, class B>
Points<T, B> pts_of(std::initializer_list<std::pair<double, double>> xy) {
  Points<T, B> p;
  int i = 0;
  for (auto [x, y] : xy) p[i++] = Vec2<T>(T(x), T(y));
  return p;
}
}  // namespace

TEST_CASE_TEMPLATE("k-means separates two obvious blobs", T, float, double) {
  auto p = pts_of<T, Wide>({{0, 0}, {0, 1}, {1, 0}, {10, 10}, {10, 11}});
  Groups<Wide> g;
  const KMeansStats st = kmeans(p, 5, 2, kMaxKMeansIterations, g);
  CHECK(st.converged);
  CHECK(g.count == 2);
  CHECK(g.label[0] == g.label[1]);
  CHECK(g.label[1] == g.label[2]);
  CHECK(g.label[3] == g.label[4]);
  CHECK(g.label[0] != g.label[3]);
}

TEST_CASE_TEMPLATE("k-means on random sets ends at a Lloyd fixed point (brute force)", T, float, double) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int trial = 0; trial < 300; ++trial) {
    const int m = 1 + static_cast<int>(rng() % 16);
    const int k = 1 + static_cast<int>(rng() % 5);
    Points<T, Wide> p;
    for (int i = 0; i < m; ++i) p[i] = Vec2<T>(T(u(rng)), T(u(rng)));
    Groups<Wide> g;
    const KMeansStats st = kmeans(p, m, k, kMaxKMeansIterations, g);
    REQUIRE(st.converged);
    CHECK(g.count >= 1);
    CHECK(g.count <= std::min(k, m));
    // Brute force: centroids from the labels; every point is (one of) nearest to its own.
    std::vector<Vec2<double>> c(g.count, Vec2<double>::Zero());
    std::vector<int> n(g.count, 0);
    for (int i = 0; i < m; ++i) {
      REQUIRE(g.label[i] >= 0);
      REQUIRE(g.label[i] < g.count);
      c[g.label[i]] += p[i].template cast<double>();
      ++n[g.label[i]];
    }
    for (int q = 0; q < g.count; ++q) {
      REQUIRE(n[q] > 0);
      c[q] /= n[q];
    }
    for (int i = 0; i < m; ++i) {
      const double own = (p[i].template cast<double>() - c[g.label[i]]).squaredNorm();
      for (int q = 0; q < g.count; ++q) {
        CHECK(own <= (p[i].template cast<double>() - c[q]).squaredNorm() * (1 + 1e-5) + 1e-9);
      }
    }
  }
}

TEST_CASE_TEMPLATE("DBSCAN: chain, border and noise points (hand-checked)", T, float, double) {
  // A chain 0-1-2 (spacing 1), a pair 3-4, and a lone point 5. eps = 1.1, min_points = 2.
  auto p = pts_of<T, Wide>({{0, 0}, {1, 0}, {2, 0}, {10, 0}, {10, 1}, {20, 20}});
  Groups<Wide> g;
  const DbscanStats st = dbscan(p, 6, T(1.1), 2, g);
  CHECK(st.clusters == 2);
  CHECK(st.noise == 1);
  CHECK(g.count == 3);
  CHECK(g.label[0] == g.label[1]);
  CHECK(g.label[1] == g.label[2]);
  CHECK(g.label[3] == g.label[4]);
  CHECK(g.label[5] != g.label[0]);
  CHECK(g.label[5] != g.label[3]);
  // min_points = 3: the pair is noise now (two singletons), the chain's middle is core.
  const DbscanStats st3 = dbscan(p, 6, T(1.1), 3, g);
  CHECK(st3.clusters == 1);
  CHECK(st3.noise == 3);
  CHECK(g.count == 4);
  CHECK(g.label[0] == g.label[2]);  // ends are border points of the middle's cluster
}

TEST_CASE_TEMPLATE("DBSCAN on random sets equals connected components of core points (brute force)", T, float, double) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0, 8);
  for (int trial = 0; trial < 300; ++trial) {
    const int m = 1 + static_cast<int>(rng() % 16);
    const int min_points = 1 + static_cast<int>(rng() % 3);
    const double eps = 0.5 + 1.5 * static_cast<double>(rng() % 100) / 100.0;
    Points<T, Wide> p;
    for (int i = 0; i < m; ++i) p[i] = Vec2<T>(T(u(rng)), T(u(rng)));
    Groups<Wide> g;
    dbscan(p, m, T(eps), min_points, g);
    auto near = [&](int a, int b) { return (p[a] - p[b]).squaredNorm() <= T(eps) * T(eps); };
    std::vector<bool> core(m);
    for (int i = 0; i < m; ++i) {
      int n = 0;
      for (int j = 0; j < m; ++j) n += near(i, j);
      core[i] = n >= min_points;
    }
    // Union-find over core points linked within eps.
    std::vector<int> parent(m);
    for (int i = 0; i < m; ++i) parent[i] = i;
    auto find = [&](int a) {
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      return a;
    };
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b)
        if (core[a] && core[b] && near(a, b)) parent[find(a)] = find(b);
    for (int a = 0; a < m; ++a) {
      for (int b = 0; b < m; ++b) {
        if (core[a] && core[b]) CHECK((find(a) == find(b)) == (g.label[a] == g.label[b]));
      }
      if (!core[a]) {
        bool border = false;
        for (int b = 0; b < m; ++b) {
          if (core[b] && near(a, b) && g.label[a] == g.label[b]) border = true;
        }
        bool reachable = false;
        for (int b = 0; b < m; ++b) reachable = reachable || (core[b] && near(a, b));
        if (reachable) {
          CHECK(border);  // a border point sits with one of its core neighbours
        } else {
          for (int b = 0; b < m; ++b) CHECK((b == a || g.label[b] != g.label[a]));  // noise: alone
        }
      }
    }
  }
}

TEST_CASE_TEMPLATE("DBSCAN never drops an observation; surplus groups merge into the last", T, float, double) {
  // Six isolated points, MaxGroups = 3: groups 0, 1 and the rest.
  auto p = pts_of<T, Narrow>({{0, 0}, {10, 0}, {20, 0}, {30, 0}, {40, 0}, {50, 0}});
  Groups<Narrow> g;
  const DbscanStats st = dbscan(p, 6, T(1), 2, g);
  CHECK(st.merged_for_capacity);
  CHECK(g.count == 3);
  std::set<int> labels;
  for (int i = 0; i < 6; ++i) {
    CHECK(g.label[i] >= 0);
    CHECK(g.label[i] < 3);
    labels.insert(g.label[i]);
  }
  CHECK(labels.size() == 3);
}
