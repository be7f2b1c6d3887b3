// consistency: exact maximum clique of a BitsetGraph by branch and bound with greedy colouring bounds
// (Tomita & Seki's MCQ, 2003, on San Segundo et al.'s bitset encoding BBMC, 2011), iterative on an
// explicit stack. In: graph, node budget. Out: a maximum clique (anytime: the best so far and a flag
// when the budget ran out). Bounds: depth <= MaxDepth; search nodes <= budget <= kMaxCliqueSearchNodes;
// each node O(MaxNodes * colours) word operations for its colouring. All arrays in the workspace.
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/consistency/bitset_graph.hpp"
#include "geojcbb/core/consistency_options.hpp"
#include "geojcbb/core/status.hpp"

namespace geojcbb {

/// Caller-owned working memory of max_clique().
/// @tparam MaxDepth  largest clique the search can hold (its stack depth). A graph whose clique
///                   number exceeds it gets a clique of MaxDepth nodes and the depth_capped flag.
template <int MaxNodes, int MaxDepth = MaxNodes>
struct MaxCliqueWorkspace {
  static_assert(MaxDepth >= 1 && MaxDepth <= MaxNodes, "a clique has at most MaxNodes nodes");
  using Set = NodeSet<MaxNodes>;
  /// One level of the search tree: its candidate set P and the vertices still to branch on, in
  /// colouring order with their colours (only those whose colour can still beat the best).
  struct Level {
    Set P;
    std::array<std::uint8_t, MaxNodes> vertex;
    std::array<std::uint8_t, MaxNodes> colour;
    std::int16_t pos;  ///< vertex[0 .. pos-1] not yet branched on; branched from the end
  };
  std::array<Set, MaxNodes> adj;             ///< the graph renumbered by the initial order
  std::array<std::uint8_t, MaxNodes> order;  ///< search index -> graph node
  std::array<Level, MaxDepth> level;
  std::array<std::uint8_t, MaxDepth> clique;  ///< current clique (search indices), level by level
  std::array<std::uint8_t, MaxDepth> best;    ///< best clique so far (search indices)
};

template <int MaxNodes>
struct CliqueResult {
  NodeSet<MaxNodes> members;  ///< graph node indices of the clique
  int size = 0;
  std::uint32_t nodes = 0;    ///< search nodes expanded (a node: one vertex added to the clique)
  bool budget_hit = false;    ///< the budget ran out: `members` is the best clique found so far
  bool depth_capped = false;  ///< the graph has a clique larger than MaxDepth: `members` has MaxDepth
};

namespace clique_detail {

/// Greedy sequential colouring of L.P (BBMC): colour classes are built one after another, each
/// taking the lowest-indexed vertices not adjacent to the class so far. Only vertices of colour
/// >= kmin are listed (a smaller colour cannot beat the best: Tomita's MCQ pruning).
/// Bound: every vertex of P is coloured once; <= MaxNodes classes of <= MaxNodes steps.
/// Adjacency: std::array of NodeSet rows, Level: MaxCliqueWorkspace::Level.
template <class Adjacency, class Level>
void colour(const Adjacency& adj, int kmin, Level& L) {
  L.pos = 0;
  auto uncoloured = L.P;
  if (uncoloured.count() < kmin) return;  // at most |P| colours
  int n = 0;
  for (int k = 1; uncoloured.any(); ++k) {  // <= MaxNodes colour classes
    auto free = uncoloured;
    for (int v = free.lowest(); v >= 0; v = free.lowest()) {  // <= MaxNodes vertices
      uncoloured.reset(v);
      free.reset(v);
      free.subtract(adj[v]);
      if (k >= kmin) {
        L.vertex[n] = static_cast<std::uint8_t>(v);
        L.colour[n] = static_cast<std::uint8_t>(k);
        ++n;
      }
    }
  }
  L.pos = static_cast<std::int16_t>(n);
}

}  // namespace clique_detail

/// Maximum clique of g.
/// Initial order: nodes by non-increasing degree (ties by index), so the colouring meets the densely
/// connected nodes first and the search branches on the sparse ones first (MCQ). A greedy clique
/// along that order seeds the best so far, so even a budget of 0 returns a maximal clique.
/// @param[in]  g       the graph (g.count nodes)
/// @param[in]  node_budget  search nodes this call may expand, 0 .. kMaxCliqueSearchNodes
/// @param[in,out] ws   working memory
/// @param[out] out     written only on kOk
/// @return kOk (also when the budget ran out or the depth was capped: see the flags);
///         kInvalidInput for g.count outside 0 .. MaxNodes or a budget over kMaxCliqueSearchNodes.
template <int MaxNodes, int MaxDepth>
[[nodiscard]] Status max_clique(const BitsetGraph<MaxNodes>& g, std::uint32_t node_budget,
                                MaxCliqueWorkspace<MaxNodes, MaxDepth>& ws, CliqueResult<MaxNodes>& out) {
  using Set = NodeSet<MaxNodes>;
  const int n = g.count;
  if (n < 0 || n > MaxNodes || node_budget > kMaxCliqueSearchNodes) return Status::kInvalidInput;

  // Initial order: stable insertion sort by non-increasing degree.
  std::array<std::uint8_t, MaxNodes> deg;
  for (int v = 0; v < n; ++v) {  // <= MaxNodes
    deg[v] = static_cast<std::uint8_t>(g.degree(v));
    int k = v;
    for (; k > 0 && deg[ws.order[k - 1]] < deg[v]; --k) ws.order[k] = ws.order[k - 1];  // <= MaxNodes
    ws.order[k] = static_cast<std::uint8_t>(v);
  }
  for (int a = 0; a < n; ++a) {  // <= MaxNodes
    ws.adj[a].clear();
    const Set& row = g.adj[ws.order[a]];
    for (int b = 0; b < n; ++b) {  // <= MaxNodes
      if (row.test(ws.order[b])) ws.adj[a].set(b);
    }
  }

  CliqueResult<MaxNodes> r;
  // Greedy seed: repeatedly the first remaining node adjacent to all taken so far.
  Set P;
  P.fill(n);
  int best = 0;
  for (int v = P.lowest(); v >= 0 && best < MaxDepth; v = P.lowest()) {  // <= MaxDepth
    ws.best[best++] = static_cast<std::uint8_t>(v);
    P.assign_and(P, ws.adj[v]);
  }
  r.depth_capped = P.any();

  if (!r.depth_capped && n > 0) {
    int depth = 0;  // the current clique is ws.clique[0 .. depth-1]
    ws.level[0].P.fill(n);
    clique_detail::colour(ws.adj, best + 1, ws.level[0]);
    // Each iteration expands a node (<= budget), closes a level (<= once per expansion, plus the
    // root), or stops: at most 2 * budget + 2 iterations.
    for (;;) {
      auto& L = ws.level[depth];
      if (L.pos == 0) {
        if (depth == 0) break;
        --depth;
        continue;
      }
      const int j = --L.pos;
      const int v = L.vertex[j];
      if (depth + L.colour[j] <= best) {  // colours only fall from here on: the level is done
        L.pos = 0;
        continue;
      }
      if (r.nodes >= node_budget) {
        r.budget_hit = true;
        break;
      }
      ++r.nodes;
      ws.clique[depth] = static_cast<std::uint8_t>(v);
      Set child;
      child.assign_and(L.P, ws.adj[v]);
      L.P.reset(v);
      const int size = depth + 1;
      if (!child.any() || size == MaxDepth) {
        if (size > best) {
          best = size;
          for (int k = 0; k < size; ++k) ws.best[k] = ws.clique[k];  // <= MaxDepth
        }
        if (child.any()) {  // a clique of MaxDepth + 1 nodes exists
          r.depth_capped = true;
          break;
        }
        continue;
      }
      auto& K = ws.level[size];
      K.P = child;
      clique_detail::colour(ws.adj, best - size + 1, K);
      depth = size;
    }
  }

  r.members.clear();
  for (int k = 0; k < best; ++k) r.members.set(ws.order[ws.best[k]]);  // <= MaxDepth
  r.size = best;
  out = r;
  return Status::kOk;
}

}  // namespace geojcbb
