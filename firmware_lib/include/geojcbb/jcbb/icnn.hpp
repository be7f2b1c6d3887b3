// jcbb: individual compatibility nearest neighbour (ICNN). Each observation takes its nearest
// individually compatible candidate. With mutual exclusion the pairs are taken greedily, globally
// nearest first, and a taken candidate is skipped by the others.
// Bounds: O(m) without exclusion; <= MaxObservations rounds of O(m * n) with it.
#pragma once

#include <limits>

#include "geojcbb/jcbb/jcbb.hpp"

namespace geojcbb {

/// Fills out.best and out.pairings (out.joint_d2 is left to the caller: see hypothesis_joint_d2).
template <typename T, class B>
void icnn_search(int m, bool exclusion, const CompatibilityTable<T, B>& table, JcbbWorkspace<T, B>& ws,
                 int n_candidates, SearchOutcome<T, B>& out) {
  out.pairings = 0;
  out.nodes = 0;
  out.budget_hit = false;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    out.best[i] = (!exclusion && table.count[i] > 0) ? table.cand[i][0] : std::int16_t{-1};
    if (out.best[i] >= 0) ++out.pairings;
  }
  if (!exclusion) return;
  for (int j = 0; j < n_candidates; ++j) ws.used[j] = 0;  // <= kMaxCandidates
  for (int round = 0; round < m; ++round) {               // <= kMaxObservations
    int best_i = -1;
    int best_c = -1;
    T best_d2 = std::numeric_limits<T>::infinity();
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      if (out.best[i] >= 0) continue;
      for (int q = 0; q < table.count[i]; ++q) {  // <= kMaxCandidates
        const int c = table.cand[i][q];
        if (ws.used[c] != 0) continue;
        if (table.d2[i][q] < best_d2) {
          best_d2 = table.d2[i][q];
          best_i = i;
          best_c = c;
        }
        break;  // sorted: the first free candidate is this observation's nearest
      }
    }
    if (best_i < 0) break;
    out.best[best_i] = static_cast<std::int16_t>(best_c);
    ws.used[best_c] = 1;
    ++out.pairings;
  }
}

/// Joint d2 of an arbitrary hypothesis (per observation: candidate or -1), built with the same
/// incremental factor as JCBB, pairings in observation order.
/// @return kOk; kNotPositiveDefinite for a non-positive pivot.
template <typename T, class B>
[[nodiscard]] Status hypothesis_joint_d2(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                         const Hypothesis<B>& hyp, IncrementalJoint<T, B::kMaxObservations>& joint,
                                         T& d2_out) {
  joint.clear();
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    const int c = hyp[i];
    if (c < 0) continue;
    T d2 = T(0);
    const Status s = joint.try_push(pred.C, c, obs.R[i], innovation(obs.z[i], pred.h[c]), d2);
    if (s != Status::kOk) return s;
    joint.commit();
  }
  d2_out = joint.d2();
  return Status::kOk;
}

}  // namespace geojcbb
