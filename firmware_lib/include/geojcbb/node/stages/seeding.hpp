// node/stages: the pose hypotheses of one scan, shared by the hypothesis window and clusters-first
// (reloc/window.hpp, docs/hypotheses.md).
//   load_frozen()        the frozen map: the region's confirmed landmarks, their own covariances
//   association_picks()  the association's pairs with the frozen map, as picks
//   Seeds::score()       the association's pairs and one per anchor choice (an ambiguous observation
//                        and one of its nearest compatible landmarks), each grown by nearest neighbour
//                        as a pose-only filter and scored with the set likelihood
// Scratch of one scan (the step owns one Seeds and passes it by reference).
// Bounds: O(kMaxSeeds kMaxObservations kMaxLandmarks) per scan.
#pragma once

#include <array>

#include "geojcbb/node/stages/map_view.hpp"
#include "geojcbb/reloc/window.hpp"

namespace geojcbb::node {

/// The frozen map into scratch: the prediction's confirmed landmarks.
/// @return kOk; the statuses of AlignWorkspace::push_landmark.
template <typename T, class B>
[[nodiscard]] Status load_frozen(const Prediction<T, B>& pred, const MapView<T, B>& map, AlignScratch<T, B>& scratch) {
  scratch.clear();
  for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
    const int k = map.slot_of(pred.id[a]);
    if (!map.confirmed(k)) continue;
    const Status st = scratch.push(map, k);
    if (st != Status::kOk) return st;
  }
  return Status::kOk;
}

/// scratch.ws.pick: the association's pairs with the frozen map (`use`), or none.  O(m n)
template <typename T, class B>
void association_picks(const Association<T, B>& assoc, const MapView<T, B>& map, AlignScratch<T, B>& scratch,
                       bool use) {
  reloc::AlignWorkspace<T, B>& ws = scratch.ws;
  for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
    ws.pick[i] = -1;
    const int k = use ? map.slot_of(assoc.feature[i]) : -1;
    for (int p = 0; p < ws.n && k >= 0; ++p) {  // <= kMaxLandmarks
      if (scratch.slot_at(p) == k) ws.pick[i] = static_cast<std::int16_t>(p);
    }
  }
}

/// What the seeds are scored with: the filter's pose and its covariance, the set model, the
/// alignment's view and the individual gate.
template <typename T>
struct SeedModel {
  Pose2<T> x;
  Mat3<T> P;
  reloc::SetModel<T> set;
  const reloc::AlignOptions<T>* view;
  T gate;
};

template <typename T, class B>
struct Seeds {
  std::array<reloc::PoseHypothesis<T>, reloc::kMaxSeeds> h;
  std::array<std::array<std::int16_t, B::kMaxObservations>, reloc::kMaxSeeds> pick{};

  /// The seed of the highest set likelihood among the first `seeds` (the first of equals).
  int best(int seeds) const {
    int b = 0;
    for (int s = 1; s < seeds; ++s) {  // <= kMaxSeeds
      if (h[static_cast<std::size_t>(s)].ll > h[static_cast<std::size_t>(b)].ll) b = s;
    }
    return b;
  }

  /// The seeds of this scan (the association's first), scored from the filter's pose, over the
  /// observations not skipped in scratch; none when no observation is ambiguous. Out of line and
  /// cold: it runs on ambiguous scans only. @return the seeds
  /// O(kMaxSeeds kMaxObservations kMaxLandmarks)
  [[gnu::noinline, gnu::cold]] int score(const Observations<T, B>& obs, const Association<T, B>& assoc,
                                         const MapView<T, B>& map, AlignScratch<T, B>& scratch,
                                         const SeedModel<T>& sm) {
    const reloc::AlignWorkspace<T, B>& ws = scratch.ws;
    const int m = obs.count;
    // Anchors: the first observations with two or more landmarks in the individual gate at the
    // filter's pose, each with its nearest kMaxAnchorChoices.
    std::array<std::array<std::int16_t, reloc::kMaxAnchorChoices>, reloc::kMaxAnchors> choice{};
    std::array<std::int16_t, reloc::kMaxAnchors> anchor{};
    int anchors = 0;
    Vec2<T> nu;
    Mat2<T> S;
    Mat23<T> Jx;
    for (int i = 0; i < m && anchors < reloc::kMaxAnchors; ++i) {  // <= kMaxObservations
      if (ws.skip[i]) continue;
      std::array<T, reloc::kMaxAnchorChoices> d2s{};
      auto& c = choice[static_cast<std::size_t>(anchors)];
      c.fill(-1);
      int found = 0;
      for (int j = 0; j < ws.n; ++j) {  // <= kMaxLandmarks
        const T d2 = reloc::pair_d2(obs, i, ws, j, sm.x, sm.P, nu, S, Jx);
        if (!(d2 <= sm.gate)) continue;
        ++found;
        // Insert among the nearest kMaxAnchorChoices.
        int at = reloc::kMaxAnchorChoices;
        while (at > 0 && (c[static_cast<std::size_t>(at - 1)] < 0 || d2s[static_cast<std::size_t>(at - 1)] > d2)) {
          --at;  // <= kMaxAnchorChoices
        }
        if (at >= reloc::kMaxAnchorChoices) continue;
        for (int k = reloc::kMaxAnchorChoices - 1; k > at; --k) {  // <= kMaxAnchorChoices
          c[static_cast<std::size_t>(k)] = c[static_cast<std::size_t>(k - 1)];
          d2s[static_cast<std::size_t>(k)] = d2s[static_cast<std::size_t>(k - 1)];
        }
        c[static_cast<std::size_t>(at)] = static_cast<std::int16_t>(j);
        d2s[static_cast<std::size_t>(at)] = d2;
      }
      if (found >= 2) anchor[static_cast<std::size_t>(anchors++)] = static_cast<std::int16_t>(i);
    }
    if (anchors == 0) return 0;
    // Seed 0: the association's pairs with the frozen map.
    int seeds = 0;
    for (int s = 0; s < 1 + anchors * reloc::kMaxAnchorChoices; ++s) {  // <= kMaxSeeds
      int ai = -1, aj = -1;
      if (s > 0) {
        ai = anchor[static_cast<std::size_t>((s - 1) / reloc::kMaxAnchorChoices)];
        aj = choice[static_cast<std::size_t>((s - 1) / reloc::kMaxAnchorChoices)]
                   [static_cast<std::size_t>((s - 1) % reloc::kMaxAnchorChoices)];
        if (aj < 0) continue;
      }
      association_picks(assoc, map, scratch, s == 0);
      if (s > 0) scratch.ws.pick[ai] = static_cast<std::int16_t>(aj);
      reloc::PoseHypothesis<T>& hs = h[static_cast<std::size_t>(seeds)];
      hs.x = sm.x;
      hs.P = sm.P;
      hs.ll = reloc::run_hypothesis(obs, scratch.ws, sm.set, *sm.view, sm.gate, s > 0, hs);
      pick[static_cast<std::size_t>(seeds)] = scratch.ws.pick;
      ++seeds;
    }
    return seeds;
  }
};

}  // namespace geojcbb::node
