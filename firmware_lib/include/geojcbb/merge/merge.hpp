// merge: the union of the groups' hypotheses (ARCHITECTURE.md step 3d).
// 1. Mutual exclusion across groups (each group's JCBB already excludes within itself): a feature
//    claimed by several observations goes to one of them.
//    - Optimal criterion on: every claimant is tried as the keeper. The hypothesis with the most
//      pairings wins; a tie goes to the smaller joint d2 (eq. 14 applied to the merge).
//    - Otherwise: the claimant with the smallest individual d2 keeps the feature (the most likely
//      true match by the gate's own measure).
//    Each other claimant takes its next individually compatible feature that no observation holds
//    (nearest first), or becomes unmatched. Taking only free features creates no new conflict, so
//    one pass over the features resolves every conflict.
// 2. Joint re-check (our addition): the groups share the robot's pose error, so the union can fail
//    the joint test. The union is tested jointly. When it fails, JCBB runs again with each
//    observation's candidates reduced to its merged pairing. The result is the union's largest
//    jointly compatible subset (with the optimal criterion: the smallest D2 among those). The
//    dropped observations become unmatched.
// Bounds: features x claimants x (joint d2, O(m^3)) for the optimal resolution; the repair search
// has the remaining node budget, but at least 2 * MaxObservations (one greedy descent).
#pragma once

#include "geojcbb/jcbb/icnn.hpp"
#include "geojcbb/jcbb/jcbb.hpp"

namespace geojcbb {

struct MergeStats {
  std::uint16_t conflicts = 0;       ///< features claimed by more than one observation
  bool recheck_failed = false;       ///< the union failed the joint test and was repaired
  std::uint16_t repair_dropped = 0;  ///< pairings the repair removed
  NodeCount repair_nodes = 0;
  bool repair_budget_hit = false;
};

template <typename T, class B>
struct MergeWorkspace {
  CompatibilityTable<T, B, 1> reduced;  ///< one candidate per observation, for the repair search
  Hypothesis<B> trial;
  SearchOutcome<T, B> repair;
};

namespace merge_detail {

/// True when some observation other than `except` holds candidate c. Bound: m.
template <class Hyp>
bool held(const Hyp& hyp, int m, int c, int except) {
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (i != except && hyp[i] == c) return true;
  }
  return false;
}

/// Moves observation i to its nearest compatible candidate that nobody holds, or to -1.
template <typename T, class B, class Hyp>
void reassign(const CompatibilityTable<T, B>& table, int m, int i, Hyp& hyp) {
  hyp[i] = -1;
  for (int q = 0; q < table.count[i]; ++q) {  // <= kMaxCandidates
    const int c = table.cand[i][q];
    if (!held(hyp, m, c, i)) {
      hyp[i] = static_cast<CandidateIndex>(c);
      return;
    }
  }
}

template <typename T, class B>
T pair_d2(const CompatibilityTable<T, B>& table, int i, int c) {
  for (int q = 0; q < table.count[i]; ++q) {  // <= kMaxCandidates
    if (table.cand[i][q] == c) return table.d2[i][q];
  }
  return std::numeric_limits<T>::infinity();
}

}  // namespace merge_detail

/// Merges per-group hypotheses in place and, when configured, re-checks and repairs the union.
/// @param[in,out] hyp        per observation: candidate or -1 (the union of the groups' answers)
/// @param[in,out] joint_d2   in: D2 of `hyp` when it came from one search and is unchanged, or a
///                           negative value if unknown. Out: the D2 of the returned hypothesis.
/// @param nodes_left         JCBB nodes left in the scan's budget
/// @return kOk; kNotPositiveDefinite from a joint factorisation (C not PSD).
template <typename T, class B>
[[nodiscard]] Status merge_groups(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                  const AssociationConfig<T, B>& cfg, const CompatibilityTable<T, B>& table,
                                  std::uint32_t nodes_left, MergeWorkspace<T, B>& ws, JcbbWorkspace<T, B>& jws,
                                  Hypothesis<B>& hyp, T& joint_d2, MergeStats& st) {
  const int m = obs.count;
  st = MergeStats{};
  if (cfg.mutual_exclusion) {
    for (int c = 0; c < pred.count; ++c) {  // <= kMaxCandidates
      int claimants = 0;
      int nearest = -1;
      for (int i = 0; i < m; ++i) {  // <= kMaxObservations
        if (hyp[i] != c) continue;
        ++claimants;
        if (nearest < 0 || merge_detail::pair_d2(table, i, c) < merge_detail::pair_d2(table, nearest, c)) nearest = i;
      }
      if (claimants < 2) continue;
      ++st.conflicts;
      int keeper = nearest;
      if (cfg.optimal_criterion) {
        int best_pairs = -1;
        T best_d2 = std::numeric_limits<T>::infinity();
        for (int k = 0; k < m; ++k) {  // <= kMaxObservations candidate keepers
          if (hyp[k] != c) continue;
          ws.trial = hyp;
          for (int i = 0; i < m; ++i) {  // <= kMaxObservations
            if (i != k && hyp[i] == c) merge_detail::reassign(table, m, i, ws.trial);
          }
          int pairs = 0;
          for (int i = 0; i < m; ++i) pairs += ws.trial[i] >= 0;  // <= kMaxObservations
          T d2 = T(0);
          const Status s = hypothesis_joint_d2(obs, pred, ws.trial, jws.joint, d2);
          if (s != Status::kOk) return s;
          if (pairs > best_pairs || (pairs == best_pairs && d2 < best_d2)) {
            best_pairs = pairs;
            best_d2 = d2;
            keeper = k;
          }
        }
      }
      for (int i = 0; i < m; ++i) {  // <= kMaxObservations
        if (i != keeper && hyp[i] == c) merge_detail::reassign(table, m, i, hyp);
      }
      joint_d2 = T(-1);  // the hypothesis changed
    }
  }
  if (joint_d2 < T(0)) {
    const Status s = hypothesis_joint_d2(obs, pred, hyp, jws.joint, joint_d2);
    if (s != Status::kOk) return s;
  }
  if (!cfg.joint_recheck) return Status::kOk;
  int pairs = 0;
  for (int i = 0; i < m; ++i) pairs += hyp[i] >= 0;  // <= kMaxObservations
  if (joint_d2 <= cfg.gate.joint[pairs]) return Status::kOk;

  st.recheck_failed = true;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    ws.reduced.count[i] = hyp[i] >= 0 ? 1 : 0;
    ws.reduced.cand[i][0] = hyp[i];
    ws.reduced.d2[i][0] = hyp[i] >= 0 ? merge_detail::pair_d2(table, i, hyp[i]) : T(0);
  }
  const std::uint32_t floor = 2 * B::kMaxObservations;
  const Status s = jcbb_search(obs, pred, cfg, ws.reduced, ObservationSubset{}, nodes_left > floor ? nodes_left : floor,
                               jws, ws.repair);
  if (s != Status::kOk) return s;
  st.repair_nodes = ws.repair.nodes;
  st.repair_budget_hit = ws.repair.budget_hit;
  st.repair_dropped = static_cast<std::uint16_t>(pairs - ws.repair.pairings);
  for (int i = 0; i < m; ++i) hyp[i] = ws.repair.best[i];  // <= kMaxObservations
  joint_d2 = ws.repair.joint_d2;
  return Status::kOk;
}

}  // namespace geojcbb
