// node/stages: clusters first (StepSettings::cluster_first, docs/hypotheses.md). No state across
// scans. With the frozen map loaded (load_frozen) and the window closed, the scan's observations are
// linked into clusters (two within dbscan_eps_m of each other in the sensor frame are in one), and
// each cluster of kMinPosePairs or more is paired as a unit: its seeds (Seeds, every other
// observation skipped) scored alone, and the best, when it conflicts with the association's, leads
// it by hypothesis_margin_nats and pairs kMinPosePairs or more, replaces the association's pairs in
// the cluster.
// Bounds: O(m^2) to label; per cluster O(kMaxSeeds m n + m^2).
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/node/stages/seeding.hpp"

namespace geojcbb::node {

template <typename T, class B>
class ClustersFirst {
 public:
  /// @return the observations paired anew.
  int run(const AssociationConfig<T, B>& cfg, const Observations<T, B>& obs, const Prediction<T, B>& pred,
          const MapView<T, B>& map, AlignScratch<T, B>& scratch, Seeds<T, B>& seeds, const SeedModel<T>& sm,
          Association<T, B>& assoc) {
    const int m = obs.count;
    const int clusters = label(cfg, obs);
    int regrouped = 0;
    for (int c = 0; c < clusters; ++c) {  // <= kMaxObservations
      int size = 0;
      for (int i = 0; i < m; ++i) {  // <= kMaxObservations
        scratch.ws.skip[i] = label_[i] != c;
        size += label_[i] == c;
      }
      if (size < reloc::kMinPosePairs) continue;
      const int n = seeds.score(obs, assoc, map, scratch, sm);
      regrouped += pair_cluster(cfg, obs, pred, map, scratch, seeds, sm, n, c, assoc);
    }
    scratch.ws.skip.fill(false);
    return regrouped;
  }

 private:
  /// The observations linked into clusters in label_: connected components of the eps-graph, grown
  /// through a queue (each observation is queued once). Distances by the law of cosines. Out of line
  /// and cold. @return the clusters  O(kMaxObservations^2)
  [[gnu::noinline, gnu::cold]] int label(const AssociationConfig<T, B>& cfg, const Observations<T, B>& obs) {
    const int m = obs.count;
    std::array<std::uint8_t, B::kMaxObservations> queue;
    auto near = [&](int p, int q) {
      const T rp = obs.z[p].x(), rq = obs.z[q].x();
      return rp * rp + rq * rq - T(2) * rp * rq * fmath::cos(obs.z[p].y() - obs.z[q].y()) <=
             cfg.dbscan_eps_m * cfg.dbscan_eps_m;
    };
    label_.fill(-1);
    int clusters = 0;
    for (int s = 0; s < m; ++s) {  // <= kMaxObservations
      if (label_[s] >= 0) continue;
      int head = 0, tail = 0;
      label_[s] = static_cast<std::int8_t>(clusters);
      queue[tail++] = static_cast<std::uint8_t>(s);
      while (head < tail) {  // each observation is queued once: <= kMaxObservations
        const int p = queue[head++];
        for (int q = 0; q < m; ++q) {  // <= kMaxObservations
          if (label_[q] < 0 && near(p, q)) {
            label_[q] = static_cast<std::int8_t>(clusters);
            queue[tail++] = static_cast<std::uint8_t>(q);
          }
        }
      }
      ++clusters;
    }
    return clusters;
  }

  /// Cluster c with its `n` seeds: the best again (for its d2s) in seed 0's place, its pairs replace
  /// the association's in the cluster: an observation it leaves unexplained is held unless the
  /// association made it new or paired it outside the frozen map; an observation elsewhere paired
  /// with a landmark it took is held. Out of line and cold (a sibling of Seeds::score in the call
  /// chain). @return the observations paired anew
  [[gnu::noinline, gnu::cold]] int pair_cluster(const AssociationConfig<T, B>& cfg, const Observations<T, B>& obs,
                                                const Prediction<T, B>& pred, const MapView<T, B>& map,
                                                AlignScratch<T, B>& scratch, Seeds<T, B>& seeds, const SeedModel<T>& sm,
                                                int n, int c, Association<T, B>& assoc) {
    const int m = obs.count;
    if (n <= 1) return 0;
    const int best = seeds.best(n);
    const std::int16_t* const bp = seeds.pick[static_cast<std::size_t>(best)].data();
    if (best == 0 || !reloc::conflict(bp, seeds.pick[0].data(), m) ||
        seeds.h[static_cast<std::size_t>(best)].ll < seeds.h[0].ll + cfg.hypothesis_margin_nats ||
        reloc::pairs(bp, m) < reloc::kMinPosePairs) {
      return 0;
    }
    reloc::AlignWorkspace<T, B>& ws = scratch.ws;
    ws.pick = seeds.pick[static_cast<std::size_t>(best)];
    reloc::PoseHypothesis<T>& h = seeds.h[0];
    h.x = sm.x;
    h.P = sm.P;
    (void)reloc::run_hypothesis(obs, ws, sm.set, *sm.view, sm.gate, true, h);
    int regrouped = 0;
    for (int i = 0; i < m; ++i) {  // <= kMaxObservations
      const int k = ws.pick[i];
      const int j = map.slot_of(assoc.feature[i]);
      if (label_[i] == c) {
        if (k >= 0) {
          regrouped += j != scratch.slot_at(k);
          pair(assoc, pred, i, map.id(scratch.slot_at(k)), ws.pick_d2[i]);
        } else if (map.confirmed(j)) {
          unpair(assoc, i);
          ++regrouped;
        }
        continue;
      }
      // Elsewhere: a landmark this cluster took is not paired twice.
      for (int q = 0; q < m && j >= 0; ++q) {  // <= kMaxObservations
        if (label_[q] == c && ws.pick[q] >= 0 && scratch.slot_at(ws.pick[q]) == j) {
          unpair(assoc, i);
          ++regrouped;
          break;
        }
      }
    }
    return regrouped;
  }

  std::array<std::int8_t, B::kMaxObservations> label_{};
};

}  // namespace geojcbb::node
