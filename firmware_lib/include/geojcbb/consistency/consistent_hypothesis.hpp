// consistency: the pose-free hypothesis, the largest set of pairwise consistent pairings (Bailey's
// CCDA 2002; Mangelson et al.'s PCM 2018): validate -> wide gate -> consistency graph -> max clique.
// In: observations, prediction (ids, h, C), options. Out: per observation a candidate or -1, with
// diagnostics. Bounds: graph nodes <= MaxNodes (64: 512 B of adjacency), search nodes <= budget <=
// kMaxCliqueSearchNodes, clique <= min(MaxNodes, MaxObservations, MaxCandidates). No heap.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/consistency/max_clique.hpp"
#include "geojcbb/core/consistency_options.hpp"
#include "geojcbb/consistency/pairwise.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/gate/validate.hpp"

namespace geojcbb {

/// Per-call counters of consistent_hypothesis().
struct ConsistencyDiagnostics {
  std::uint32_t offered_pairings = 0;  ///< pairings through the wide gate (before the node cap)
  std::uint16_t graph_nodes = 0;       ///< pairings kept as graph nodes (<= MaxNodes)
  std::uint16_t graph_edges = 0;       ///< pairwise consistent pairs of them
  std::uint16_t clique_size = 0;       ///< pairings of the hypothesis
  std::uint32_t search_nodes = 0;      ///< max-clique search nodes expanded
  bool nodes_truncated = false;        ///< more pairings than MaxNodes: the smallest d2 were kept
  bool budget_hit = false;             ///< the search budget ran out: the best clique so far
};

template <class B>
struct ConsistencyResult {
  int count = 0;  ///< equals the number of observations
  /// Per observation: the candidate (index into the Prediction) of the clique's pairing, or -1.
  Hypothesis<B> candidate;
  int pairings = 0;
  ConsistencyDiagnostics diag;
};

namespace consistency_detail {
constexpr int min3(int a, int b, int c) { return a < b ? (a < c ? a : c) : (b < c ? b : c); }
}  // namespace consistency_detail

/// Caller-owned working memory of consistent_hypothesis(); typically a static object on the device.
/// The search depth is the largest possible clique: one pairing per observation and per candidate.
template <typename T, class B, int MaxNodes = kDefaultGraphNodes>
struct ConsistencyWorkspace {
  static constexpr int kMaxClique = consistency_detail::min3(MaxNodes, B::kMaxObservations, B::kMaxCandidates);
  PairwiseGeometry<T, B> geometry;
  PairingList<T, MaxNodes> pairings;
  BitsetGraph<MaxNodes> graph;
  MaxCliqueWorkspace<MaxNodes, kMaxClique> search;
  CliqueResult<MaxNodes> clique;
};

/// The stage without its validation (associate() has validated the same inputs): wide gate ->
/// graph -> max clique, left in ws.pairings, ws.graph and ws.clique.
/// @return kOk; kNotPositiveDefinite from the graph (C not PSD).
template <typename T, class B, int MaxNodes>
[[nodiscard]] Status clique_of_validated(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                         const ConsistencyOptions<T>& opt, ConsistencyWorkspace<T, B, MaxNodes>& ws) {
  ws.geometry.prepare(obs, pred);
  select_pairings(obs, pred, opt, ws.pairings);
  const Status s = build_consistency_graph(ws.geometry, pred, ws.pairings, opt.pair_d2, ws.graph);
  if (s != Status::kOk) return s;
  return max_clique(ws.graph, opt.node_budget, ws.search, ws.clique);
}

/// The clique in ws (after clique_of_validated or consistent_subset) as a hypothesis: per
/// observation its candidate, or -1.
template <typename T, class B, int MaxNodes>
void clique_hypothesis(const ConsistencyWorkspace<T, B, MaxNodes>& ws, int m, Hypothesis<B>& hyp) {
  for (int i = 0; i < m; ++i) hyp[i] = -1;       // <= kMaxObservations
  for (int x = 0; x < ws.pairings.count; ++x) {  // <= MaxNodes
    if (ws.clique.members.test(x)) hyp[ws.pairings.node[x].obs] = ws.pairings.node[x].cand;
  }
}

/// The counters of the last clique search in ws.
template <typename T, class B, int MaxNodes>
ConsistencyDiagnostics clique_diagnostics(const ConsistencyWorkspace<T, B, MaxNodes>& ws) {
  ConsistencyDiagnostics d;
  d.offered_pairings = static_cast<std::uint32_t>(ws.pairings.offered);
  d.graph_nodes = static_cast<std::uint16_t>(ws.pairings.count);
  d.graph_edges = static_cast<std::uint16_t>(ws.graph.edges());
  d.clique_size = static_cast<std::uint16_t>(ws.clique.size);
  d.search_nodes = ws.clique.nodes;
  d.nodes_truncated = ws.pairings.truncated;
  d.budget_hit = ws.clique.budget_hit;
  return d;
}

/// Verification: the largest pairwise consistent subset of a given hypothesis (per observation a
/// candidate or -1), i.e. the max clique of the consistency graph whose nodes are the hypothesis's
/// own pairings. Inputs validated (as associate() does); the hypothesis has at most one pairing per
/// observation, so it fits the graph when MaxObservations <= MaxNodes. The subset is left in ws
/// (clique_hypothesis() reads it).
/// @return kOk; kNotPositiveDefinite from the graph (C not PSD).
template <typename T, class B, int MaxNodes>
[[nodiscard]] Status consistent_subset(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                       const ConsistencyOptions<T>& opt, const Hypothesis<B>& hyp,
                                       ConsistencyWorkspace<T, B, MaxNodes>& ws) {
  static_assert(B::kMaxObservations <= MaxNodes, "a hypothesis must fit the verification graph");
  ws.geometry.prepare(obs, pred);
  PairingList<T, MaxNodes>& list = ws.pairings;
  list.count = 0;
  list.truncated = false;
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    if (hyp[i] < 0) continue;
    Pairing<T>& p = list.node[list.count++];
    p.obs = static_cast<std::int8_t>(i);
    p.cand = hyp[i];
    p.d2 = T(0);  // not used: no gate, no cap
  }
  list.offered = list.count;
  const Status s = build_consistency_graph(ws.geometry, pred, list, opt.pair_d2, ws.graph);
  if (s != Status::kOk) return s;
  return max_clique(ws.graph, opt.node_budget, ws.search, ws.clique);
}

/// How well the prediction places its best-known candidate: the smallest, over the candidates in
/// the region, of tr(J_a C_aa J_a^T) [m^2], the Cartesian position variance of the predicted feature
/// in the sensor frame. C_aa = H_a P H_a^T holds the pose's share (translation in full, heading
/// times range^2) plus the feature's own, so this is a lower bound on the pose's translation
/// variance seen through the map; large only when the pose itself is uncertain. Infinity when no
/// candidate is in the region. Inputs validated; ws.geometry prepared.
template <typename T, class B, int MaxNodes>
T least_position_variance(const ConsistencyWorkspace<T, B, MaxNodes>& ws, const Prediction<T, B>& pred,
                          const ConsistencyOptions<T>& opt) {
  T least = std::numeric_limits<T>::infinity();
  for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
    if (!opt.in_region(pred.h[a])) continue;
    const Mat2<T>& J = ws.geometry.cand_J[a];
    const Mat2<T> S = J * pred.C.block(a, a) * J.transpose();
    const T v = S(0, 0) + S(1, 1);
    if (v < least) least = v;
  }
  return least;
}

/// The largest set of pairwise consistent pairings (a maximum clique of the consistency graph). It
/// does not use the predicted pose beyond the candidates' h and C, and is meant for when that pose
/// cannot be trusted (loop closure, relocalisation) or to verify a hypothesis found with it. Among
/// several maximum cliques the search keeps the first it finds (deterministic for given inputs).
/// @param[in]  obs   observations (range, bearing) and their noise
/// @param[in]  pred  candidate ids, predicted measurements h and their joint covariance C
/// @param[in]  opt   options (thresholds set, e.g. with set_confidence)
/// @param[in,out] ws working memory
/// @param[out] out   the hypothesis; written only when kOk is returned
/// @return kOk (a spent search budget or a node cap are flagged in out.diag); kCapacityExceeded for a
///         count over capacity; kInvalidInput for a negative count, a mis-sized C, invalid options or
///         an out-of-range value; kNonFinite; kNotSymmetric / kNotPositiveDefinite for a bad R_i or C
///         (also when C's off-diagonal blocks make a distance variance negative).
template <typename T, class B, int MaxNodes>
[[nodiscard]] Status consistent_hypothesis(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                           const ConsistencyOptions<T>& opt, ConsistencyWorkspace<T, B, MaxNodes>& ws,
                                           ConsistencyResult<B>& out) {
  if (obs.count > B::kMaxObservations || pred.count > B::kMaxCandidates) return Status::kCapacityExceeded;
  if (obs.count < 0 || pred.count < 0) return Status::kInvalidInput;
  if (pred.C.rows() != 2 * pred.count || pred.C.cols() != 2 * pred.count) return Status::kInvalidInput;
  if (!opt.valid()) return Status::kInvalidInput;
  Status s = validate_observations(obs);
  if (s != Status::kOk) return s;
  s = validate_prediction(pred, [&opt](const Vec2<T>& h) { return opt.in_region(h); });
  if (s != Status::kOk) return s;

  s = clique_of_validated(obs, pred, opt, ws);
  if (s != Status::kOk) return s;
  out.count = obs.count;
  clique_hypothesis(ws, obs.count, out.candidate);
  out.pairings = ws.clique.size;
  out.diag = clique_diagnostics(ws);
  return Status::kOk;
}

}  // namespace geojcbb
