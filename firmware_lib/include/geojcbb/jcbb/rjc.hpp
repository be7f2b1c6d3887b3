// jcbb: randomized joint compatibility (RJC; Paz, Guivant, Tardos, Neira, "Data association in
// O(n) for divide and conquer SLAM", RSS 2007, section IV). For a large scan, JCBB runs on a random
// subset of the observations; the rest are completed by nearest neighbour under the joint test
// (each takes its nearest free compatible candidate that keeps the whole hypothesis jointly
// compatible). A fixed number of tries, each with its own subset drawn by a seeded PCG32; the answer
// is the try with the most pairings, then the smallest joint d2 (ties: the earliest try).
// Bounds: tries <= kMaxRjcTries; each try's JCBB gets node_budget / tries nodes; the completion
// tries <= MaxCandidates candidates for each of <= MaxObservations observations, O(p^2) each.
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/core/rng.hpp"
#include "geojcbb/jcbb/jcbb.hpp"

namespace geojcbb {

template <class B>
struct RjcWorkspace {
  std::array<std::int8_t, B::kMaxObservations> pool;    ///< observations with a compatible candidate
  std::array<std::int8_t, B::kMaxObservations> label;   ///< 0: in this try's subset, 1: completed
  std::array<std::int16_t, B::kMaxObservations> trial;  ///< this try's hypothesis
};

struct RjcStats {
  int pairings = 0;
  std::uint32_t nodes = 0;  ///< JCBB nodes over every try
  bool budget_hit = false;  ///< some try's JCBB stopped at its share of the budget
  int best_try = -1;
};

/// RJC over every observation. Inputs validated, table built for the same inputs and config.
/// @param tries        1 .. kMaxRjcTries
/// @param subset_size  observations searched by JCBB in a try (>= 1); the others are completed
/// @param seed         the generator's seed: the same inputs and seed give the same answer
/// @param[out] best    per observation: candidate or -1 (the best try's)
/// @param[out] d2      its joint d2
/// @return kOk; kNotPositiveDefinite from a joint test (C not PSD).
template <typename T, class B>
[[nodiscard]] Status rjc_search(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                const AssociationConfig<T, B>& cfg, const CompatibilityTable<T, B>& table,
                                NodeCount node_budget, int tries, int subset_size, std::uint64_t seed,
                                JcbbWorkspace<T, B>& jws, SearchOutcome<T, B>& scratch, RjcWorkspace<B>& rws,
                                std::array<std::int16_t, B::kMaxObservations>& best, T& d2, RjcStats& stats) {
  const int m = obs.count;
  Pcg32 rng(seed);
  int pool = 0;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    best[i] = -1;
    if (table.count[i] > 0) rws.pool[pool++] = static_cast<std::int8_t>(i);
  }
  stats = RjcStats{};
  d2 = T(0);
  const NodeCount per_try = node_budget / static_cast<NodeCount>(tries);
  for (int t = 0; t < tries; ++t) {  // <= kMaxRjcTries
    // A random subset: the first subset_size entries of a partial Fisher-Yates shuffle of the pool.
    for (int i = 0; i < m; ++i) rws.label[i] = 1;  // <= kMaxObservations
    const int k = subset_size < pool ? subset_size : pool;
    for (int x = 0; x < k; ++x) {  // <= kMaxObservations
      const int y = x + static_cast<int>(rng.below(static_cast<std::uint32_t>(pool - x)));
      const std::int8_t o = rws.pool[y];
      rws.pool[y] = rws.pool[x];
      rws.pool[x] = o;
      rws.label[o] = 0;
    }
    Status s = jcbb_search(obs, pred, cfg, table, ObservationSubset{rws.label.data(), 0}, per_try, jws, scratch);
    if (s != Status::kOk) return s;
    stats.nodes += scratch.nodes;
    stats.budget_hit = stats.budget_hit || scratch.budget_hit;
    // The subset's answer, then nearest neighbour under the joint test for the others.
    jws.joint.clear();
    for (int j = 0; j < pred.count; ++j) jws.used[j] = 0;  // <= kMaxCandidates
    for (int i = 0; i < m; ++i) {                          // <= kMaxObservations
      rws.trial[i] = scratch.best[i];
      const int c = scratch.best[i];
      if (c < 0) continue;
      T e = T(0);
      s = jws.joint.try_push(pred.C, c, obs.R[i], innovation(obs.z[i], pred.h[c]), e);
      if (s != Status::kOk) return s;
      jws.joint.commit();
      ++jws.used[c];
    }
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      if (rws.label[i] == 0) continue;
      for (int q = 0; q < table.count[i]; ++q) {  // <= kMaxCandidates
        const int c = table.cand[i][q];
        if (cfg.mutual_exclusion && jws.used[c] != 0) continue;
        T e = T(0);
        s = jws.joint.try_push(pred.C, c, obs.R[i], innovation(obs.z[i], pred.h[c]), e);
        if (s != Status::kOk) return s;
        if (!(e <= cfg.gate.joint[jws.joint.pairs() + 1])) continue;
        jws.joint.commit();
        ++jws.used[c];
        rws.trial[i] = static_cast<std::int16_t>(c);
        break;
      }
    }
    const int p = jws.joint.pairs();
    const T e = jws.joint.d2();
    if (stats.best_try < 0 || p > stats.pairings || (p == stats.pairings && e < d2)) {
      stats.best_try = t;
      stats.pairings = p;
      d2 = e;
      for (int i = 0; i < m; ++i) best[i] = rws.trial[i];  // <= kMaxObservations
    }
  }
  return Status::kOk;
}

}  // namespace geojcbb
