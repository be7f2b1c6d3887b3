// The maximum-clique search (consistency/max_clique.hpp): against brute force on thousands of random
// graphs of at most 20 nodes; on constructed hard graphs with known clique numbers (Hamming, Johnson,
// Keller, Mycielski, complements of cycle powers, Paley), cross-checked by an independent
// Bron-Kerbosch search; its node budget respected exactly and flagged; its depth cap.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "geojcbb/consistency/max_clique.hpp"
#include "support/alloc_counter.hpp"

using namespace geojcbb;

namespace {

using Graph = BitsetGraph<64>;
using Set = NodeSet<64>;
using Ws = MaxCliqueWorkspace<64>;

// ---- oracles (host code: recursion and allocation allowed) ----

/// Clique number by enumerating every subset (n <= 20): clique[mask] from clique[mask - lowest].
int brute_force_clique_number(const Graph& g) {
  const int n = g.count;
  std::vector<std::uint8_t> is_clique(std::size_t(1) << n, 0);
  is_clique[0] = 1;
  int best = 0;
  for (std::uint32_t mask = 1; mask < (1u << n); ++mask) {
    const int v = __builtin_ctz(mask);
    const std::uint32_t rest = mask & (mask - 1);
    const std::uint32_t nbrs = static_cast<std::uint32_t>(g.adj[v].w[0]);
    if (is_clique[rest] && (rest & ~nbrs) == 0) {
      is_clique[mask] = 1;
      best = std::max(best, __builtin_popcount(mask));
    }
  }
  return best;
}

/// Bron-Kerbosch with Tomita's pivot (recursive; an oracle independent of the colouring bound).
void bron_kerbosch(const Graph& g, std::uint64_t R, std::uint64_t P, std::uint64_t X, int& best) {
  if (P == 0 && X == 0) {
    best = std::max(best, __builtin_popcountll(R));
    return;
  }
  if (__builtin_popcountll(R) + __builtin_popcountll(P) <= best) return;
  std::uint64_t PX = P | X;
  int pivot = -1, most = -1;
  while (PX) {
    const int u = __builtin_ctzll(PX);
    PX &= PX - 1;
    const int c = __builtin_popcountll(P & g.adj[u].w[0]);
    if (c > most) most = c, pivot = u;
  }
  std::uint64_t cand = P & ~g.adj[pivot].w[0];
  while (cand) {
    const int v = __builtin_ctzll(cand);
    cand &= cand - 1;
    const std::uint64_t bit = std::uint64_t(1) << v;
    bron_kerbosch(g, R | bit, P & g.adj[v].w[0], X & g.adj[v].w[0], best);
    P &= ~bit;
    X |= bit;
  }
}
int oracle_clique_number(const Graph& g) {
  int best = 0;
  const std::uint64_t all = g.count == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << g.count) - 1;
  bron_kerbosch(g, 0, all, 0, best);
  return best;
}

Graph random_graph(int n, double density, std::mt19937_64& rng) {
  std::bernoulli_distribution edge(density);
  Graph g;
  g.reset(n);
  for (int u = 0; u < n; ++u) {
    for (int v = u + 1; v < n; ++v) {
      if (edge(rng)) g.add_edge(u, v);
    }
  }
  return g;
}

CliqueResult<64> solve(const Graph& g, std::uint32_t budget = kMaxCliqueSearchNodes) {
  auto ws = std::make_unique<Ws>();
  CliqueResult<64> r;
  REQUIRE(max_clique(g, budget, *ws, r) == Status::kOk);
  return r;
}

// ---- constructed hard graphs (DIMACS-style families) ----

/// Binary words of length `bits`, adjacent when their Hamming distance is >= d (DIMACS hamming
/// graphs). The clique number is A(bits, d), the largest binary code of minimum distance d.
Graph hamming(int bits, int d) {
  Graph g;
  g.reset(1 << bits);
  for (int u = 0; u < g.count; ++u) {
    for (int v = u + 1; v < g.count; ++v) {
      if (__builtin_popcount(u ^ v) >= d) g.add_edge(u, v);
    }
  }
  return g;
}

/// w-subsets of an n-set, adjacent when they share at most w - d/2 elements (DIMACS johnson graphs):
/// the clique number is A(n, d, w), the largest constant-weight code.
Graph johnson(int n, int w, int d) {
  std::vector<int> subsets;
  for (int s = 0; s < (1 << n); ++s) {
    if (__builtin_popcount(s) == w) subsets.push_back(s);
  }
  Graph g;
  g.reset(static_cast<int>(subsets.size()));
  for (int u = 0; u < g.count; ++u) {
    for (int v = u + 1; v < g.count; ++v) {
      if (__builtin_popcount(subsets[u] ^ subsets[v]) >= d) g.add_edge(u, v);
    }
  }
  return g;
}

/// Keller graph of dimension `dim`: tuples over {0,1,2,3}, adjacent when they differ in at least two
/// coordinates and by exactly 2 (mod 4) in at least one. omega(K2) = 2, omega(K3) = 5
/// (Debroni et al., "The Keller graph of dimension 7", and the DIMACS keller4 = K4 with 12).
Graph keller(int dim) {
  int n = 1;
  for (int k = 0; k < dim; ++k) n *= 4;
  Graph g;
  g.reset(n);
  for (int u = 0; u < n; ++u) {
    for (int v = u + 1; v < n; ++v) {
      int differ = 0;
      bool by_two = false;
      for (int k = 0, a = u, b = v; k < dim; ++k, a /= 4, b /= 4) {
        if (a % 4 != b % 4) ++differ;
        if ((a % 4 + 4 - b % 4) % 4 == 2) by_two = true;
      }
      if (differ >= 2 && by_two) g.add_edge(u, v);
    }
  }
  return g;
}

/// Mycielski graph M_k (M_2 = K2): triangle-free (omega = 2) with chromatic number k, so every
/// colouring bound is k and the search cannot prune on colour alone. M_6 has 47 nodes.
Graph mycielski(int k) {
  Graph g;
  g.reset(2);
  g.add_edge(0, 1);
  for (int step = 2; step < k; ++step) {
    const int n = g.count;
    Graph h;
    h.reset(2 * n + 1);
    for (int u = 0; u < n; ++u) {
      for (int v = 0; v < n; ++v) {
        if (u < v && g.has_edge(u, v)) h.add_edge(u, v);
        if (g.has_edge(u, v)) h.add_edge(n + u, v);  // the shadow of u sees u's neighbours
      }
      h.add_edge(n + u, 2 * n);  // the apex sees every shadow
    }
    g = h;
  }
  return g;
}

/// Complement of the k-th power of the n-cycle: i ~ j when their circular distance exceeds k.
/// omega = floor(n / (k + 1)).
Graph complement_cycle_power(int n, int k) {
  Graph g;
  g.reset(n);
  for (int u = 0; u < n; ++u) {
    for (int v = u + 1; v < n; ++v) {
      const int d = std::min(v - u, n - (v - u));
      if (d > k) g.add_edge(u, v);
    }
  }
  return g;
}

/// Paley graph of prime order q = 1 mod 4: i ~ j when i - j is a nonzero square mod q.
Graph paley(int q) {
  std::vector<bool> square(q, false);
  for (int x = 1; x < q; ++x) square[(x * x) % q] = true;
  Graph g;
  g.reset(q);
  for (int u = 0; u < q; ++u) {
    for (int v = u + 1; v < q; ++v) {
      if (square[(v - u) % q]) g.add_edge(u, v);
    }
  }
  return g;
}

}  // namespace

TEST_CASE("max clique: bitset graph basics") {
  Graph g;
  g.reset(70);  // clamped to the capacity
  CHECK(g.count == 64);
  g.add_edge(0, 63);
  g.add_edge(5, 5);  // self loop ignored
  CHECK(g.has_edge(63, 0));
  CHECK_FALSE(g.has_edge(5, 5));
  CHECK(g.edges() == 1);
  Set s;
  s.clear();
  s.set(0);
  s.set(63);
  CHECK(g.is_clique(s));
  s.set(1);
  CHECK_FALSE(g.is_clique(s));
  g.reset(10);
  s.clear();
  s.set(12);  // not a node of a 10-node graph
  CHECK_FALSE(g.is_clique(s));
  NodeSet<130> big;
  big.fill(130);
  CHECK(big.count() == 130);
  big.fill(65);
  CHECK(big.count() == 65);
  CHECK(big.test(64));
  CHECK_FALSE(big.test(65));
}

namespace {
/// The search against an oracle on `per_density` random graphs per density, of min_n..max_n nodes.
/// Returns the number of graphs checked.
template <class Oracle>
int check_random_graphs(std::uint64_t seed, std::initializer_list<double> densities, int min_n, int max_n,
                        int per_density, Oracle oracle) {
  std::mt19937_64 rng(seed);
  int graphs = 0;
  for (const double density : densities) {
    CAPTURE(density);
    std::uniform_int_distribution<int> size(min_n, max_n);
    for (int k = 0; k < per_density; ++k) {
      const Graph g = random_graph(size(rng), density, rng);
      CAPTURE(g.count);
      const CliqueResult<64> r = solve(g);
      REQUIRE_FALSE(r.budget_hit);
      REQUIRE_FALSE(r.depth_capped);
      REQUIRE(r.size == oracle(g));
      REQUIRE(r.members.count() == r.size);
      REQUIRE(g.is_clique(r.members));
      ++graphs;
    }
  }
  return graphs;
}
}  // namespace

TEST_CASE("max clique equals brute force on thousands of random graphs (<= 20 nodes)") {
  CHECK(check_random_graphs(20240612, {0.1, 0.3, 0.5, 0.7, 0.9, 0.97}, 0, 20, 600, brute_force_clique_number) == 3600);
}

TEST_CASE("max clique equals Bron-Kerbosch on random graphs of 21..64 nodes") {
  CHECK(check_random_graphs(77, {0.2, 0.5, 0.8, 0.9}, 21, 64, 60, oracle_clique_number) == 240);
}

TEST_CASE("max clique on known hard graphs (DIMACS-style families, <= 64 nodes)") {
  struct Case {
    std::string name;
    Graph g;
    int omega;
  };
  const Case cases[] = {
      {"hamming6-2", hamming(6, 2), 32},      // the even-weight code
      {"hamming6-3", hamming(6, 3), 8},       // A(6,3) = 8
      {"hamming6-4", hamming(6, 4), 4},       // DIMACS hamming6-4
      {"johnson8-2-4", johnson(8, 2, 4), 4},  // DIMACS johnson8-2-4: disjoint pairs of 8
      {"johnson7-3-4", johnson(7, 3, 4), 7},  // A(7,4,3) = 7: the Fano plane's lines
      {"johnson8-3-4", johnson(8, 3, 4), 8},  // A(8,4,3) = 8
      {"keller2", keller(2), 2},
      {"keller3", keller(3), 5},
      {"mycielski5", mycielski(5), 2},  // 23 nodes, chromatic number 5
      {"mycielski6", mycielski(6), 2},  // 47 nodes, chromatic number 6
      {"co-C64^1", complement_cycle_power(64, 1), 32},
      {"co-C63^2", complement_cycle_power(63, 2), 21},
      {"co-C64^3", complement_cycle_power(64, 3), 16},
      {"co-C61^4", complement_cycle_power(61, 4), 12},
      {"paley37", paley(37), 4},
      {"paley61", paley(61), 5},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const CliqueResult<64> r = solve(c.g);
    CHECK_FALSE(r.budget_hit);
    CHECK(oracle_clique_number(c.g) == c.omega);
    CHECK(r.size == c.omega);
    CHECK(c.g.is_clique(r.members));
    MESSAGE(c.name << ": " << c.g.count << " nodes, " << c.g.edges() << " edges, omega " << r.size << ", " << r.nodes
                   << " search nodes");
  }
}

TEST_CASE("max clique: the node budget is respected exactly and flagged; best so far is a clique") {
  std::mt19937_64 rng(5);
  int checked = 0;
  for (int k = 0; k < 40; ++k) {
    const Graph g = random_graph(64, 0.5 + 0.01 * k, rng);
    const CliqueResult<64> full = solve(g);
    REQUIRE_FALSE(full.budget_hit);
    const std::uint32_t n = full.nodes;
    for (const std::uint32_t budget : {0u, 1u, n / 3, n / 2, n - 1, n, n + 1}) {
      CAPTURE(budget);
      const CliqueResult<64> r = solve(g, budget);
      CHECK(r.nodes == std::min(budget, n));
      CHECK(r.budget_hit == (budget < n));
      CHECK(r.size >= 1);  // the greedy seed: a maximal clique even at budget 0
      CHECK(r.size <= full.size);
      CHECK(r.members.count() == r.size);
      CHECK(g.is_clique(r.members));
      if (!r.budget_hit) CHECK(r.size == full.size);
      ++checked;
    }
  }
  CHECK(checked == 280);
}

TEST_CASE("max clique: a clique larger than the depth cap is reported, not overrun") {
  const Graph g = complement_cycle_power(64, 1);  // omega 32
  for (const std::uint32_t budget : {0u, kMaxCliqueSearchNodes}) {
    auto ws = std::make_unique<MaxCliqueWorkspace<64, 10>>();
    CliqueResult<64> r;
    REQUIRE(max_clique(g, budget, *ws, r) == Status::kOk);
    CHECK(r.depth_capped);
    CHECK(r.size == 10);
    CHECK(g.is_clique(r.members));
  }
  // A cap equal to the clique number is not reached beyond it: exact, no flag.
  auto ws = std::make_unique<MaxCliqueWorkspace<64, 32>>();
  CliqueResult<64> r;
  REQUIRE(max_clique(g, kMaxCliqueSearchNodes, *ws, r) == Status::kOk);
  CHECK_FALSE(r.depth_capped);
  CHECK(r.size == 32);
}

TEST_CASE("max clique: bad arguments return a status and leave the result untouched") {
  auto ws = std::make_unique<Ws>();
  CliqueResult<64> r;
  r.size = 77;
  r.nodes = 99;
  Graph g = hamming(6, 4);
  CHECK(max_clique(g, kMaxCliqueSearchNodes + 1, *ws, r) == Status::kInvalidInput);
  g.count = 65;
  CHECK(max_clique(g, 10, *ws, r) == Status::kInvalidInput);
  g.count = -1;
  CHECK(max_clique(g, 10, *ws, r) == Status::kInvalidInput);
  CHECK(r.size == 77);
  CHECK(r.nodes == 99);
  // The empty graph and a single node.
  g.reset(0);
  REQUIRE(max_clique(g, 10, *ws, r) == Status::kOk);
  CHECK(r.size == 0);
  CHECK_FALSE(r.members.any());
  g.reset(1);
  REQUIRE(max_clique(g, 10, *ws, r) == Status::kOk);
  CHECK(r.size == 1);
  CHECK(r.members.test(0));
}

TEST_CASE("max clique: the answer does not depend on the node numbering") {
  std::mt19937_64 rng(11);
  for (int k = 0; k < 50; ++k) {
    const Graph g = random_graph(64, 0.7, rng);
    std::vector<int> perm(64);
    for (int v = 0; v < 64; ++v) perm[v] = v;
    std::shuffle(perm.begin(), perm.end(), rng);
    Graph h;
    h.reset(64);
    for (int u = 0; u < 64; ++u) {
      for (int v = u + 1; v < 64; ++v) {
        if (g.has_edge(u, v)) h.add_edge(perm[u], perm[v]);
      }
    }
    CHECK(solve(g).size == solve(h).size);
  }
}

TEST_CASE("max clique allocates nothing") {
  std::mt19937_64 rng(3);
  auto ws = std::make_unique<Ws>();
  for (int k = 0; k < 20; ++k) {
    const Graph g = random_graph(64, 0.3 + 0.03 * k, rng);
    CliqueResult<64> r;
    Status s = Status::kInvalidInput;
    CHECK(test::allocations_during([&] { s = max_clique(g, 5000, *ws, r); }) == 0);
    CHECK(s == Status::kOk);
  }
}

TEST_CASE("max clique: search nodes on random 64-node graphs (reported for docs/results/consistency.md)") {
  for (const double density : {0.1, 0.3, 0.5, 0.7, 0.8, 0.9, 0.95}) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(1000 * density));
    std::vector<std::uint32_t> nodes;
    std::vector<int> sizes;
    for (int k = 0; k < 500; ++k) {
      const Graph g = random_graph(64, density, rng);
      const CliqueResult<64> r = solve(g);
      REQUIRE_FALSE(r.budget_hit);
      REQUIRE(g.is_clique(r.members));
      nodes.push_back(r.nodes);
      sizes.push_back(r.size);
    }
    std::sort(nodes.begin(), nodes.end());
    std::sort(sizes.begin(), sizes.end());
    MESSAGE("density " << density << ": omega median " << sizes[250] << " (max " << sizes.back()
                       << "); search nodes median " << nodes[250] << ", p99 " << nodes[495] << ", max "
                       << nodes.back());
  }
}
