// jcbb: joint compatibility branch and bound (Neira & Tardos 2001), iterative on an explicit stack.
// Input: the compatibility table (gate/compatibility.hpp). Output: per observation a candidate or -1,
// the number of pairings and the joint d2 of the best hypothesis found.
// - The joint test runs at every node (not only at leaves), incrementally (joint_compatibility.hpp).
// - Bound: pairings so far + remaining observations that still have a free compatible candidate.
// - Options: mutual exclusion; optimal criterion (2019 paper, eq. 14: among the most pairings, the
//   smallest joint d2, pruned with the monotone d2); fewest-candidates-first ordering; node budget
//   (anytime: the best hypothesis so far and a flag); ambiguity margin (also find the runner-up: a
//   different hypothesis with as many pairings whose joint d2 is within the margin of the best's).
// Bounds: stack depth <= MaxObservations; nodes <= node_budget <= MaxJcbbNodes; each node O(p^2).
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/gate/compatibility.hpp"
#include "geojcbb/jcbb/joint_compatibility.hpp"

namespace geojcbb {

template <typename T, class B>
struct SearchOutcome {
  Hypothesis<B> best;  ///< per observation: candidate or -1
  int pairings = 0;
  T joint_d2 = T(0);
  std::uint32_t nodes = 0;
  bool budget_hit = false;
  /// With an ambiguity margin: the closest other hypothesis with as many pairings (valid when
  /// have_runner_up), and its joint d2.
  Hypothesis<B> runner_up;
  bool have_runner_up = false;
  T runner_up_d2 = T(0);
  /// Observations the best and the runner-up pair differently, when the runner-up is within the
  /// margin; set by jcbb_search.
  bool ambiguous(int i, T margin) const {
    return have_runner_up && runner_up_d2 - joint_d2 < margin && runner_up_d2 - joint_d2 > -margin &&
           runner_up[i] != best[i];
  }
};

template <typename T, class B>
struct JcbbWorkspace {
  IncrementalJoint<T, B::kMaxObservations> joint;
  std::array<std::uint8_t, B::kMaxObservations> order;  ///< level -> observation
  std::array<std::int16_t, B::kMaxObservations> next;   ///< level -> next candidate position
  std::array<bool, B::kMaxObservations> paired;         ///< level -> holds a pairing
  Hypothesis<B> current;                                ///< observation -> candidate or -1
  std::array<std::uint8_t, B::kMaxCandidates> used;     ///< candidate -> pairings holding it
};

/// The observations one search covers: all, or those of one group.
struct ObservationSubset {
  const std::int8_t* label = nullptr;  ///< per observation group label; null: every observation
  int group = 0;
  bool contains(int i) const { return label == nullptr || label[i] == group; }
};

/// The levels of the interpretation tree: observations of the subset with at least one compatible
/// candidate, in observation order or (stably) by fewest candidates first. Returns the number of
/// levels.  Bound: insertion sort of <= MaxObservations entries.
template <typename T, class B, int K>
int search_order(const CompatibilityTable<T, B, K>& table, int m, bool fewest_first, ObservationSubset subset,
                 std::array<std::uint8_t, B::kMaxObservations>& order) {
  int levels = 0;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (table.count[i] == 0 || !subset.contains(i)) continue;
    int k = levels++;
    for (; fewest_first && k > 0 && table.count[order[k - 1]] > table.count[i]; --k) {
      order[k] = order[k - 1];
    }
    order[k] = static_cast<std::uint8_t>(i);
  }
  return levels;
}

/// Runs JCBB over a subset of the observations. Inputs must be validated and the table built for
/// the same inputs and config.
/// @param node_budget  nodes this search may expand (>= 0; 0 returns the empty hypothesis, flagged)
/// @param prefix  when not null: pairings already fixed (per observation: candidate or -1; entries of
///                the subset must be -1). The search extends them: every joint test covers prefix and
///                extension, with thresholds for their total, and mutual exclusion counts the
///                prefix's features as taken. out.pairings and out.joint_d2 are totals.
/// @return kOk (also when the node budget ran out: see out.budget_hit); kNotPositiveDefinite when a
///         joint covariance has a non-positive pivot (C not PSD). On error `out` is unspecified.
///         out.best is -1 outside the subset.
template <typename T, class B, int K>
[[nodiscard]] Status jcbb_search(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                 const AssociationConfig<T, B>& cfg, const CompatibilityTable<T, B, K>& table,
                                 ObservationSubset subset, NodeCount node_budget, JcbbWorkspace<T, B>& ws,
                                 SearchOutcome<T, B>& out,
                                 const std::array<std::int16_t, B::kMaxObservations>* prefix = nullptr) {
  const int levels = search_order(table, obs.count, cfg.order_fewest_candidates_first, subset, ws.order);
  const bool exclusion = cfg.mutual_exclusion;
  const bool optimal = cfg.optimal_criterion;
  const T margin = cfg.margin();
  const NodeCount budget = node_budget;
  ws.joint.clear();
  for (int j = 0; j < pred.count; ++j) ws.used[j] = 0;  // <= kMaxCandidates
  for (int i = 0; i < obs.count; ++i) {                 // <= kMaxObservations
    ws.current[i] = -1;
    out.best[i] = -1;
  }
  out.nodes = 0;
  out.budget_hit = false;
  out.have_runner_up = false;
  if (prefix != nullptr) {
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      const int c = (*prefix)[i];
      if (c < 0) continue;
      T d2 = T(0);
      const Status s = ws.joint.try_push(pred.C, c, obs.R[i], innovation(obs.z[i], pred.h[c]), d2);
      if (s != Status::kOk) return s;
      ws.joint.commit();
      ++ws.used[c];
    }
  }
  out.pairings = ws.joint.pairs();  // the prefix alone: the empty extension
  out.joint_d2 = ws.joint.d2();

  // Levels after k whose observation still has a compatible candidate free to take.
  auto remaining_after = [&](int k) {
    if (!exclusion) return levels - 1 - k;
    int n = 0;
    for (int l = k + 1; l < levels; ++l) {  // <= kMaxObservations
      const int i = ws.order[l];
      for (int q = 0; q < table.count[i]; ++q) {  // <= kMaxCandidates
        if (ws.used[table.cand[i][q]] == 0) {
          ++n;
          break;
        }
      }
    }
    return n;
  };
  // Can a subtree reaching at most `bound` pairings, with joint d2 at least `d2`, beat the best (or,
  // with a margin, become the runner-up)?
  auto can_improve = [&](int bound, T d2) {
    return bound > out.pairings || (optimal && bound == out.pairings && d2 < out.joint_d2) ||
           (margin > T(0) && bound == out.pairings && d2 < out.joint_d2 + margin);
  };

  int k = 0;
  if (levels > 0) {
    ws.next[0] = 0;
    ws.paired[0] = false;
  }
  // Each iteration expands a node (<= budget), skips one candidate of the current level
  // (<= kMaxCandidates + 1 per expansion) or backtracks one level (<= one per expansion): at most
  // (budget + 1) * (kMaxCandidates + 3) iterations.
  for (;;) {
    bool backtrack = true;
    if (k == levels) {
      const int p = ws.joint.pairs();
      const T d2 = ws.joint.d2();
      if (p > out.pairings || (optimal && p == out.pairings && d2 < out.joint_d2)) {
        if (margin > T(0)) {  // the replaced best is the runner-up when it has as many pairings
          out.have_runner_up = p == out.pairings && p > 0;
          out.runner_up_d2 = out.joint_d2;
          for (int i = 0; i < obs.count; ++i) out.runner_up[i] = out.best[i];  // <= kMaxObservations
        }
        out.pairings = p;
        out.joint_d2 = d2;
        for (int i = 0; i < obs.count; ++i) out.best[i] = ws.current[i];  // <= kMaxObservations
      } else if (margin > T(0) && p == out.pairings && p > 0) {
        const T gap = d2 > out.joint_d2 ? d2 - out.joint_d2 : out.joint_d2 - d2;
        const T held =
            out.runner_up_d2 > out.joint_d2 ? out.runner_up_d2 - out.joint_d2 : out.joint_d2 - out.runner_up_d2;
        if (!out.have_runner_up || gap < held) {
          out.have_runner_up = true;
          out.runner_up_d2 = d2;
          for (int i = 0; i < obs.count; ++i) out.runner_up[i] = ws.current[i];  // <= kMaxObservations
        }
      }
    } else {
      const int i = ws.order[k];
      const int nc = table.count[i];
      std::int16_t& next = ws.next[k];
      if (next < nc) {
        backtrack = false;
        const int c = table.cand[i][next++];
        if (exclusion && ws.used[c] != 0) continue;
        const int p1 = ws.joint.pairs() + 1;
        const int bound = p1 + remaining_after(k);
        if (!can_improve(bound, ws.joint.d2())) continue;  // adding a pairing never lowers d2
        if (out.nodes >= budget) {
          out.budget_hit = true;
          break;
        }
        ++out.nodes;
        T d2 = T(0);
        const Status s = ws.joint.try_push(pred.C, c, obs.R[i], innovation(obs.z[i], pred.h[c]), d2);
        if (s != Status::kOk) return s;
        if (!(d2 <= cfg.gate.joint[p1]) || !can_improve(bound, d2)) continue;
        ws.joint.commit();
        ++ws.used[c];
        ws.current[i] = static_cast<std::int16_t>(c);
        ws.paired[k] = true;
      } else if (next == nc) {
        backtrack = false;
        ++next;  // the star branch: observation i left unpaired
        if (!can_improve(ws.joint.pairs() + remaining_after(k), ws.joint.d2())) continue;
        if (out.nodes >= budget) {
          out.budget_hit = true;
          break;
        }
        ++out.nodes;
        ws.paired[k] = false;
      }
      if (!backtrack) {
        ++k;
        if (k < levels) {
          ws.next[k] = 0;
          ws.paired[k] = false;
        }
        continue;
      }
    }
    if (k == 0) break;
    --k;
    if (ws.paired[k]) {
      const int i = ws.order[k];
      ws.joint.pop();
      --ws.used[ws.current[i]];
      ws.current[i] = -1;
      ws.paired[k] = false;
    }
  }
  return Status::kOk;
}

}  // namespace geojcbb
