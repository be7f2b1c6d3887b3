// The association pipeline: the only file that knows the order of the stages.
//   validate -> local region + individual gate
//   -> seed (when the pose is uncertain: the pose-free max clique, tested jointly; the pose-free
//      consistency )
//   -> group (none | k-means | DBSCAN | GMM-EM; skipped when seeded)
//   -> search per group (ICNN | JCBB, one node budget shared by the groups; extends the seed;
//      RJC instead of JCBB for a large ungrouped scan when asked)
//   -> merge (mutual exclusion across groups, joint re-check)
//   -> decline (ambiguous pairings left kUnmatched, when an ambiguity margin is set)
//   -> verify (pairings outside the answer's largest pairwise consistent subset dropped; the
//      pose-free consistency )
//   -> the answer's joint D2 (computed once, unless the search knows it and nothing changed it)
//   -> result
// No heap: all working memory is the caller's AssociationWorkspace; outputs are written only on
// kOk, at the end, so a stage may check what it reads (C's cross blocks, the packed
// covariance) and still leave them untouched.
#pragma once

#include "geojcbb/cluster/group.hpp"
#include "geojcbb/consistency/consistent_hypothesis.hpp"
#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/strategy.hpp"
#include "geojcbb/gate/compatibility.hpp"
#include "geojcbb/gate/validate.hpp"
#include "geojcbb/jcbb/icnn.hpp"
#include "geojcbb/jcbb/jcbb.hpp"
#include "geojcbb/jcbb/rjc.hpp"
#include "geojcbb/merge/merge.hpp"

namespace geojcbb {

/// Caller-owned working memory of associate(); typically a static object on the device.
template <typename T, class B>
struct AssociationWorkspace {
  CompatibilityTable<T, B> table;
  JcbbWorkspace<T, B> jcbb;
  SearchOutcome<T, B> outcome;
  Groups<B> groups;
  GroupingWorkspace<T, B> grouping;
  MergeWorkspace<T, B> merge;
  Hypothesis<B> hyp;
  std::array<bool, B::kMaxObservations> declined;  ///< per observation: ambiguous (decline stage)
  /// Graph nodes of the seed's and the verification's consistency graphs: the verification needs one
  /// per observation.
  static constexpr int kGraphNodes = B::kMaxObservations <= kDefaultGraphNodes ? kDefaultGraphNodes : 128;
  ConsistencyWorkspace<T, B, kGraphNodes> consistency;      ///< seed and verify (pose-free consistency)
  Hypothesis<B> seed;                                       ///< the seed's hypothesis; verify's scratch
  std::array<std::int8_t, B::kMaxObservations> seed_label;  ///< 1: pairing fixed by the seed
  RjcWorkspace<B> rjc;                                      ///< RJC's subsets and tries (pose-free consistency)
};

namespace pipeline_detail {

/// Step 3b: splits the observations into groups (cluster/group.hpp, with the grouping options
/// only). Returns the groups in ws.groups.
template <typename T, class B>
void group(const Observations<T, B>& obs, const AssociationConfig<T, B>& cfg, AssociationWorkspace<T, B>& ws,
           AssociationDiagnostics& diag) {
  const GroupingStats st = group_observations(obs, cfg, ws.grouping, ws.groups);
  diag.cluster_iterations = static_cast<std::uint16_t>(st.iterations);
  diag.cluster_bound_hit = st.bound_hit;
}

/// Decline stage: the pairings of observations marked ambiguous are removed (they become
/// kUnmatched). Returns whether any was.
template <typename T, class B>
bool apply_decline(int m, AssociationWorkspace<T, B>& ws, AssociationDiagnostics& diag) {
  bool any = false;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (!ws.declined[i]) continue;
    if (ws.hyp[i] >= 0) {
      ws.hyp[i] = -1;
      ++diag.declined;
      any = true;
    } else {
      ws.declined[i] = false;  // unpaired anyway: nothing to decline
    }
  }
  return any;
}

/// Observations with at least one compatible candidate.
template <typename T, class B>
int compatible_observations(int m, const CompatibilityTable<T, B>& table) {
  int n = 0;
  for (int i = 0; i < m; ++i) n += table.count[i] > 0;  // <= kMaxObservations
  return n;
}

/// Seed stage: when the pose is uncertain, the pose-free clique in ws.seed; `seeded` when it has at
/// least seed_min_pairings pairings and passes the joint test at its size.
/// @return kOk; kNotPositiveDefinite (C not PSD).
template <typename T, class B>
[[nodiscard]] Status seed(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                          const AssociationConfig<T, B>& cfg, AssociationWorkspace<T, B>& ws,
                          AssociationDiagnostics& diag, bool& seeded) {
  seeded = false;
  const ConsistencyOptions<T> opt = consistency_options(cfg);
  ws.consistency.geometry.prepare(obs, pred);
  if (!(least_position_variance(ws.consistency, pred, opt) >= cfg.seed_min_position_var_m2)) return Status::kOk;
  diag.seed_tried = true;
  Status s = clique_of_validated(obs, pred, opt, ws.consistency);
  if (s != Status::kOk) return s;
  clique_hypothesis(ws.consistency, obs.count, ws.seed);
  const ConsistencyDiagnostics cd = clique_diagnostics(ws.consistency);
  diag.seed_pairings = cd.clique_size;
  diag.clique_graph_nodes = cd.graph_nodes;
  diag.clique_search_nodes += cd.search_nodes;
  diag.clique_budget_hit = diag.clique_budget_hit || cd.budget_hit;
  diag.clique_nodes_truncated = cd.nodes_truncated;
  if (cd.clique_size < cfg.seed_min_pairings) return Status::kOk;
  T d2 = T(0);
  s = hypothesis_joint_d2(obs, pred, ws.seed, ws.jcbb.joint, d2);
  if (s != Status::kOk) return s;
  seeded = d2 <= cfg.gate.joint[cd.clique_size];
  return Status::kOk;
}

/// Verify stage: ws.hyp reduced to its largest pairwise consistent subset; `dropped` counts the
/// pairings removed.
/// @return kOk; kNotPositiveDefinite (C not PSD).
template <typename T, class B>
[[nodiscard]] Status verify(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                            const AssociationConfig<T, B>& cfg, AssociationWorkspace<T, B>& ws,
                            AssociationDiagnostics& diag, int& dropped) {
  dropped = 0;
  const Status s = consistent_subset(obs, pred, consistency_options(cfg), ws.hyp, ws.consistency);
  if (s != Status::kOk) return s;
  clique_hypothesis(ws.consistency, obs.count, ws.seed);
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    if (ws.hyp[i] >= 0 && ws.seed[i] < 0) {
      ws.hyp[i] = -1;
      ++dropped;
    }
  }
  diag.verify_dropped = static_cast<std::uint16_t>(dropped);
  diag.clique_graph_nodes = static_cast<std::uint16_t>(ws.consistency.pairings.count);
  diag.clique_search_nodes += ws.consistency.clique.nodes;
  diag.clique_budget_hit = diag.clique_budget_hit || ws.consistency.clique.budget_hit;
  return Status::kOk;
}

/// Search stage, one per branch: ICNN; JCBB extending the seed; RJC for a large ungrouped scan; or
/// JCBB per group and the merge. Each leaves in ws the hypothesis, ws.declined (ambiguous
/// observations, marked only when an ambiguity margin is set) and in `joint_d2` the hypothesis's D2
/// when the search knows it, -1 otherwise.
/// @return kOk; kNotPositiveDefinite (C not PSD) from a joint test.
/// Inlined into associate(): as a frame of its own it took the seed's call chain over the
/// association's 1 KiB budget on the Cortex-M4F.
template <typename T, class B>
[[nodiscard, gnu::always_inline]] inline Status search(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                                       const AssociationConfig<T, B>& cfg,
                                                       AssociationWorkspace<T, B>& ws, AssociationDiagnostics& diag,
                                                       T& joint_d2) {
  const int m = obs.count;
  const T margin = cfg.margin();
  const bool decline = margin > T(0);
  joint_d2 = T(-1);
  SearchOutcome<T, B>& o = ws.outcome;
  if (cfg.search == SearchMethod::kIcnn) {
    icnn_search(m, cfg.mutual_exclusion, ws.table, ws.jcbb, pred.count, o);
    const CompatibilityTable<T, B>& t = ws.table;
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      ws.hyp[i] = o.best[i];
      if (!decline || o.best[i] < 0) continue;
      // Ambiguous: another compatible candidate within the margin of the chosen one.
      T chosen = T(0);
      for (int q = 0; q < t.count[i]; ++q)  // <= kMaxCandidates
        if (t.cand[i][q] == o.best[i]) chosen = t.d2[i][q];
      for (int q = 0; q < t.count[i]; ++q) {  // <= kMaxCandidates
        const T gap = t.d2[i][q] > chosen ? t.d2[i][q] - chosen : chosen - t.d2[i][q];
        if (t.cand[i][q] != o.best[i] && gap < margin) ws.declined[i] = true;
      }
    }
    return Status::kOk;
  }
  bool seeded = false;
  if (cfg.seed) {
    const Status s = seed(obs, pred, cfg, ws, diag, seeded);
    if (s != Status::kOk) return s;
  }
  if (seeded) {  // one search over the unseeded observations, extending the seed
    for (int i = 0; i < m; ++i) ws.seed_label[i] = ws.seed[i] >= 0 ? 1 : 0;  // <= kMaxObservations
    diag.seed_used = true;
    diag.groups = 1;
    const Status s = jcbb_search(obs, pred, cfg, ws.table, ObservationSubset{ws.seed_label.data(), 0},
                                 cfg.search_nodes(), ws.jcbb, o, &ws.seed);
    if (s != Status::kOk) return s;
    diag.jcbb_nodes = o.nodes;
    diag.node_budget_hit = o.budget_hit;
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      ws.hyp[i] = ws.seed[i] >= 0 ? ws.seed[i] : o.best[i];
      ws.declined[i] = ws.seed[i] < 0 && decline && o.ambiguous(i, margin);
    }
    joint_d2 = o.joint_d2;
    return Status::kOk;
  }
  if (cfg.rjc && compatible_observations(m, ws.table) > cfg.rjc_subset) {
    RjcStats st;
    const Status s = rjc_search(obs, pred, cfg, ws.table, cfg.search_nodes(), cfg.rjc_tries, cfg.rjc_subset,
                                cfg.rjc_seed, ws.jcbb, o, ws.rjc, ws.hyp, joint_d2, st);
    if (s != Status::kOk) return s;
    diag.rjc_used = true;
    diag.groups = 1;
    diag.jcbb_nodes = st.nodes;
    diag.node_budget_hit = st.budget_hit;
    return Status::kOk;
  }
  group(obs, cfg, ws, diag);
  diag.groups = static_cast<std::uint8_t>(ws.groups.count);
  NodeCount nodes_left = cfg.search_nodes();
  for (int i = 0; i < m; ++i) ws.hyp[i] = -1;  // <= kMaxObservations
  for (int g = 0; g < ws.groups.count; ++g) {  // <= kMaxGroups
    const Status s = jcbb_search(obs, pred, cfg, ws.table, ObservationSubset{ws.groups.label.data(), g}, nodes_left,
                                 ws.jcbb, o, cfg.condition_groups ? &ws.hyp : nullptr);
    if (s != Status::kOk) return s;
    nodes_left -= o.nodes;
    diag.jcbb_nodes += o.nodes;
    diag.node_budget_hit = diag.node_budget_hit || o.budget_hit;
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      if (ws.groups.label[i] != g) continue;
      ws.hyp[i] = o.best[i];
      ws.declined[i] = decline && o.ambiguous(i, margin);
    }
    joint_d2 = o.joint_d2;
  }
  // Conditioned groups: the last search's D2 covers the whole union. Independent groups: the union's
  // D2 is computed by the merge.
  if (ws.groups.count != 1 && !cfg.condition_groups) joint_d2 = T(-1);
  MergeStats ms;
  const Status s = merge_groups(obs, pred, cfg, ws.table, nodes_left, ws.merge, ws.jcbb, ws.hyp, joint_d2, ms);
  if (s != Status::kOk) return s;
  diag.merge_conflicts = ms.conflicts;
  diag.recheck_failed = ms.recheck_failed;
  diag.recheck_dropped = ms.repair_dropped;
  diag.jcbb_nodes += ms.repair_nodes;
  diag.node_budget_hit = diag.node_budget_hit || ms.repair_budget_hit;
  return Status::kOk;
}

}  // namespace pipeline_detail

/// Associates one scan's observations with the predicted candidates.
/// @param[in]  obs   observations (range, bearing) and their noise
/// @param[in]  pred  candidate ids, predicted measurements h and their joint covariance C
/// @param[in]  cfg   options (see AssociationConfig; presets in core/strategy.hpp)
/// @param[in,out] ws working memory
/// @param[out] out   the hypothesis; written only when kOk is returned
/// @return kOk (an empty scan gives an empty answer; spent budgets are flagged in out.diag);
///         otherwise the first failing check of validate(); kNonFinite / kNotSymmetric for a cross
///         entry of C found bad where a joint or pairwise test reads it (CovarianceCheck::kWhereRead);
///         or kNotPositiveDefinite when C is found indefinite during a joint test or a pairwise
///         distance test (seed, verify).
template <typename T, class B>
[[nodiscard]] Status associate(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                               const AssociationConfig<T, B>& cfg, AssociationWorkspace<T, B>& ws,
                               Association<T, B>& out) {
  Status s = validate(obs, pred, cfg);
  if (s != Status::kOk) return s;
  // C's cross blocks are checked where the joint tests read them, unless validate() checked them all.
  ws.jcbb.joint.check_reads(cfg.covariance_check != CovarianceCheck::kFull);
  const int m = obs.count;
  AssociationDiagnostics diag{};
  build_compatibility(obs, pred, cfg, ws.table, diag);
  for (int i = 0; i < m; ++i) ws.declined[i] = false;  // <= kMaxObservations

  T joint_d2 = T(-1);  // < 0: the hypothesis's D2 is not known
  s = pipeline_detail::search(obs, pred, cfg, ws, diag, joint_d2);
  if (s != Status::kOk) return s;
  bool changed = cfg.margin() > T(0) && pipeline_detail::apply_decline(m, ws, diag);
  if (cfg.verify) {
    int dropped = 0;
    s = pipeline_detail::verify(obs, pred, cfg, ws, diag, dropped);
    if (s != Status::kOk) return s;
    changed = changed || dropped > 0;
  }
  if (changed || joint_d2 < T(0)) {
    s = hypothesis_joint_d2(obs, pred, ws.hyp, ws.jcbb.joint, joint_d2);
    if (s != Status::kOk) return s;
  }

  // With mutual exclusion a feature explains one observation: an unpaired observation whose every
  // compatible candidate is taken by another's pairing cannot be any of them (a new landmark, or
  // clutter), so its d2 for the filter's augmentation gate is the nearest over the others.
  const bool taken_rule = cfg.mutual_exclusion && cfg.new_if_candidates_taken;
  if (taken_rule) {
    for (int j = 0; j < pred.count; ++j) ws.jcbb.used[j] = 0;  // <= kMaxCandidates
    for (int i = 0; i < m; ++i)                                // <= kMaxObservations
      if (ws.hyp[i] >= 0) ws.jcbb.used[ws.hyp[i]] = 1;
  }
  int pairings = 0;
  out.count = m;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    const int c = ws.hyp[i];
    out.candidate[i] = static_cast<std::int16_t>(c);
    if (c >= 0) {
      ++pairings;
      out.feature[i] = pred.id[c];
      const Mat2<T> S = pred.C.block(c, c) + obs.R[i];
      out.d2[i] = mahalanobis2(innovation(obs.z[i], pred.h[c]), S);
    } else {
      bool free_compatible = false;                                    // a compatible candidate that no pairing holds
      for (int q = 0; q < ws.table.count[i] && !free_compatible; ++q)  // <= kMaxCandidates
        free_compatible = !taken_rule || ws.jcbb.used[ws.table.cand[i][q]] == 0;
      out.feature[i] = free_compatible || ws.declined[i] ? kUnmatched : kNewFeature;
      T nearest = T(0), nearest_incompatible = T(0);
      nearest_d2(obs, pred, ws.table, cfg.gate.individual, i, nearest, nearest_incompatible);
      out.d2[i] = ws.table.count[i] > 0 && !free_compatible ? nearest_incompatible : nearest;
    }
  }
  out.pairings = pairings;
  out.joint_d2 = joint_d2;
  out.jointly_compatible = joint_d2 <= cfg.gate.joint[pairings];
  out.diag = diag;
  return Status::kOk;
}

}  // namespace geojcbb
