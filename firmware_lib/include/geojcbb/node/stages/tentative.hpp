// node/stages: tentative landmarks and movers (StepSettings::tentative_isolated, docs/tentative.md).
// Its state across scans: up to kMaxMovers movers (where each was last seen, reviews since) and
// the movers caught since reset.
//   pair()       after associate() over the confirmed candidates: the observations it made new are
//                offered to the tentative candidates (smallest d2 first, one each); a tentative
//                landmark that jumped is a mover, and its landmark is removed after the review
//   follow()     after pair(): an observation at a remembered mover is that mover
//   set_aside()  before the update: the pairs with a tentative landmark move only it (the update's
//                plan holds them alone, node/update_plan.hpp)
//   catch_movers() before the review: a paired landmark that fails the static gate is a mover
// Bounds: O(m^2 n_c) to pair; O(m kMaxMovers) for the movers.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/gate/compatibility.hpp"
#include "geojcbb/node/stages/map_view.hpp"
#include "geojcbb/node/update_plan.hpp"

namespace geojcbb::node {

template <typename T, class B>
class Tentative {
 public:
  /// Movers remembered: landmarks the static gate removes as moved, and tentative landmarks that
  /// jumped (paired on the last scan, their nearest sighting now outside the pairing gate but inside
  /// the augmentation gate). An observation the association made new within kMoverReach_m of one is
  /// the mover again: it is left unmatched and the mover follows it. A mover unseen for
  /// kMoverMemoryScans reviews is forgotten; a new one replaces the longest unseen.
  static constexpr int kMaxMovers = 4;
  static constexpr int kMoverMemoryScans = 50;
  static constexpr T kMoverReach_m = T(1);

  void reset() {
    count_ = 0;
    caught_ = 0;
    jumped_count_ = 0;
  }
  std::uint32_t caught() const { return caught_; }
  /// The tentative landmarks that jumped on this scan (pair()): movers, for the step to remove.
  int jumped() const { return jumped_count_; }
  FeatureId jumped(int k) const { return jumped_[static_cast<std::size_t>(k)]; }
  int movers() const { return count_; }

  /// After associate() over the first `confirmed` candidates of pred. `augment_d2`: the
  /// augmentation gate. Out of line: its flags stay out of the callers' frames.
  /// O(kMaxObservations^2 kMaxCandidates)
  [[gnu::noinline, gnu::cold]] void pair(const AssociationConfig<T, B>& cfg, const Observations<T, B>& obs,
                                         const Prediction<T, B>& pred, int confirmed, T augment_d2,
                                         const MapView<T, B>& map, Association<T, B>& out) {
    bool taken[B::kMaxCandidates] = {};
    for (int a = confirmed; a < pred.count; ++a) {  // <= kMaxCandidates: a mover's stale landmark
      const int k = map.slot_of(pred.id[a]);
      taken[a] = k < 0 || near_mover(map.mean(k));
    }
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations: the nearest tentative landmark
      if (out.feature[i] != kNewFeature) continue;
      for (int a = confirmed; a < pred.count; ++a) {  // <= kMaxCandidates
        out.d2[i] = std::min(out.d2[i], individual_d2(obs, pred, i, a));
      }
    }
    for (int round = 0; round < obs.count; ++round) {  // <= kMaxObservations: one pair each
      int bi = -1, ba = -1;
      T best = cfg.gate.individual;
      for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
        if (out.feature[i] != kNewFeature) continue;
        for (int a = confirmed; a < pred.count; ++a) {  // <= kMaxCandidates
          if (taken[a]) continue;
          const T d2 = individual_d2(obs, pred, i, a);
          if (d2 <= best) {
            best = d2;
            bi = i;
            ba = a;
          }
        }
      }
      if (bi < 0) break;
      taken[ba] = true;
      node::pair(out, pred, bi, pred.id[ba], best);
    }
    // A tentative landmark paired on the last scan whose nearest sighting now falls outside the
    // pairing gate but inside the augmentation gate has jumped: a mover (the sighting is it), and
    // its landmark is not one.
    const Pose2<T> x = map.pose();
    jumped_count_ = 0;
    for (int a = confirmed; a < pred.count; ++a) {  // <= kMaxCandidates
      const int k = map.slot_of(pred.id[a]);
      if (taken[a] || k < 0 || map.unseen(k) != 0) continue;
      int bi = -1;
      T best = std::numeric_limits<T>::infinity();
      for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
        if (out.feature[i] != kNewFeature) continue;
        const T d2 = individual_d2(obs, pred, i, a);
        if (d2 < best) {
          best = d2;
          bi = i;
        }
      }
      if (bi < 0 || !(best > cfg.gate.individual) || !(best <= augment_d2)) continue;
      unpair(out, bi);
      remember(inverse_observe(x, map.mount(), obs.z[bi]));
      if (jumped_count_ < kMaxMovers) jumped_[static_cast<std::size_t>(jumped_count_++)] = pred.id[a];
    }
  }

  /// An observation still new within kMoverReach_m of a remembered mover (where the pose puts it) is
  /// that mover: unmatched, and the mover moves there.  O(kMaxObservations kMaxMovers)
  [[gnu::noinline, gnu::cold]] void follow(const Observations<T, B>& obs, const MapView<T, B>& map,
                                           Association<T, B>& out) {
    const Pose2<T> x = map.pose();
    for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
      if (out.feature[i] != kNewFeature) continue;
      const Vec2<T> p = inverse_observe(x, map.mount(), obs.z[i]);
      for (int k = 0; k < count_; ++k) {  // <= kMaxMovers
        Mover& mv = movers_[static_cast<std::size_t>(k)];
        if ((p - mv.at).norm() < kMoverReach_m) {
          unpair(out, i);
          mv.at = p;
          mv.unseen = 0;
          break;
        }
      }
    }
  }

  /// Before the update: the pairs with a tentative landmark held alone in the plan (round kAlone),
  /// the others in round 0 unless a closure ordered them.  O(kMaxObservations)
  [[gnu::noinline, gnu::cold]] void set_aside(const MapView<T, B>& map, const Association<T, B>& assoc,
                                              UpdatePlan<T, B>& plan) const {
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      const int k = map.slot_of(assoc.feature[i]);
      const bool alone = k >= 0 && !map.confirmed(k);
      if (alone) {
        plan.round[static_cast<std::size_t>(i)] = UpdatePlan<T, B>::kAlone;
      } else if (!plan.close.commit) {
        plan.round[static_cast<std::size_t>(i)] = 0;
      }
      plan.alone = plan.alone || alone;
    }
  }

  /// Before the review: a paired landmark that fails the static gate (the review removes it) is
  /// remembered as a mover; every mover a scan older, the ones unseen for kMoverMemoryScans
  /// forgotten.  O(kMaxObservations kMaxMovers)
  [[gnu::noinline, gnu::cold]] void catch_movers(const MapView<T, B>& map, const Association<T, B>& assoc) {
    int kept = 0;
    for (int k = 0; k < count_; ++k) {  // <= kMaxMovers
      Mover mv = movers_[static_cast<std::size_t>(k)];
      if (++mv.unseen >= kMoverMemoryScans) continue;
      movers_[static_cast<std::size_t>(kept++)] = mv;
    }
    count_ = kept;
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      const int k = map.slot_of(assoc.feature[i]);
      if (k >= 0 && map.moved(k)) remember(map.mean(k));
    }
  }

 private:
  struct Mover {
    Vec2<T> at;      ///< where it was last seen (world) [m]
    int unseen = 0;  ///< reviews since
  };
  /// A point within kMoverReach_m of a remembered mover.
  bool near_mover(const Vec2<T>& p) const {
    for (int k = 0; k < count_; ++k) {  // <= kMaxMovers
      if ((p - movers_[static_cast<std::size_t>(k)].at).norm() < kMoverReach_m) return true;
    }
    return false;
  }
  /// A mover caught at p; when kMaxMovers are remembered, the longest unseen makes room.
  [[gnu::noinline, gnu::cold]] void remember(const Vec2<T>& p) {
    int slot = count_;
    if (slot == kMaxMovers) {
      slot = 0;
      for (int k = 1; k < kMaxMovers; ++k) {  // <= kMaxMovers
        if (movers_[static_cast<std::size_t>(k)].unseen > movers_[static_cast<std::size_t>(slot)].unseen) slot = k;
      }
    } else {
      ++count_;
    }
    movers_[static_cast<std::size_t>(slot)] = Mover{p, 0};
    ++caught_;
  }
  std::array<Mover, kMaxMovers> movers_{};
  int count_ = 0;
  std::uint32_t caught_ = 0;  ///< since reset()
  std::array<FeatureId, kMaxMovers> jumped_{};
  int jumped_count_ = 0;
};

}  // namespace geojcbb::node
