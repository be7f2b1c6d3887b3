// node/stages: the hypothesis window (StepSettings::hypothesis_rivals > 0, reloc/window.hpp,
// docs/hypotheses.md). Its state across scans: up to kMaxHypotheses pose hypotheses (each a
// correction of the filter's pose with its own covariance and summed set likelihood), their pairs
// of the last scan, the member that follows the association, the scans the window has lasted.
//   run()    with the frozen map loaded (load_frozen): closed -> the scan's seeds scored (Seeds); when
//            the best pairs kMinPosePairs or more and a conflicting seed is within the margin, or the
//            best conflicts with the association's, the window opens. Open -> each hypothesis moved
//            as the filter moved, paired and scored; a leader by hypothesis_margin_nats closes it
//            (the association's stands, or the leader's pairs replace it with a Closure); pairings
//            alike or hypothesis_window_scans without a leader close it with nothing committed.
//            Meanwhile, with hypothesis_hold, what the hypotheses dispute is held.
//   rebase() after the update: the hypotheses are corrections of the filter's pose as it is now
// Bounds: O(kMaxSeeds m n) on an opening scan, O(kMaxHypotheses m n) on an open one.
#pragma once

#include <algorithm>
#include <array>
#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/node/stages/seeding.hpp"

namespace geojcbb::node {

template <typename T, class B>
class HypothesisWindow {
 public:
  void reset() { count_ = 0; }
  bool open() const { return count_ > 0; }
  /// After the update: the hypotheses are corrections of the filter's pose as it is now.
  void rebase(const Pose2<T>& x, const Mat3<T>& P) {
    if (count_ == 0) return;
    pose_ = x;
    cov_ = P;
  }

  /// One tracked scan with no loop closure pending or committed, the frozen map in scratch.
  /// `hold`: the scan is no evidence for the review (hypothesis_hold left no pair).
  /// Inlined into its one caller (SlamStep::hypotheses): a frame of its own took the device's
  /// deepest call chain past 2,048 B.
  [[gnu::always_inline]] void run(const AssociationConfig<T, B>& cfg, const Observations<T, B>& obs,
                                  const Prediction<T, B>& pred, const MapView<T, B>& map, AlignScratch<T, B>& scratch,
                                  Seeds<T, B>& seeds, const SeedModel<T>& sm, Association<T, B>& assoc,
                                  reloc::WindowStats<T>& out, Closure<T>& close, bool& hold) {
    const int m = obs.count;
    const T margin = cfg.hypothesis_margin_nats;
    if (count_ == 0) {
      const int n = seeds.score(obs, assoc, map, scratch, sm);
      out.seeds = n;
      if (n <= 1) return;
      const int best = seeds.best(n);
      const std::int16_t* const bp = seeds.pick[static_cast<std::size_t>(best)].data();
      bool rival = false;
      for (int s = 0; s < n; ++s) {  // <= kMaxSeeds
        rival =
            rival || (reloc::conflict(bp, seeds.pick[static_cast<std::size_t>(s)].data(), m) &&
                      seeds.h[static_cast<std::size_t>(s)].ll > seeds.h[static_cast<std::size_t>(best)].ll - margin);
      }
      if (!rival && !reloc::conflict(bp, seeds.pick[0].data(), m)) return;  // the association stands
      if (reloc::pairs(bp, m) < reloc::kMinPosePairs) return;               // no pose in doubt: the gate's business
      // Members: the best; the association's when it conflicts with the best (else the best is the
      // association's path); then the best-scoring seeds that conflict with every member.
      std::array<int, reloc::kMaxHypotheses> member{};
      int count = 0;
      member[static_cast<std::size_t>(count++)] = best;
      assoc_member_ = 0;
      if (reloc::conflict(bp, seeds.pick[0].data(), m)) {
        assoc_member_ = count;
        member[static_cast<std::size_t>(count++)] = 0;
      }
      for (int round = count; round <= cfg.hypothesis_rivals; ++round) {  // <= kMaxHypotheses
        int next = -1;
        for (int s = 0; s < n; ++s) {  // <= kMaxSeeds
          bool apart = true;
          for (int k = 0; k < count && apart; ++k) {  // <= kMaxHypotheses
            const int mk = member[static_cast<std::size_t>(k)];
            apart = s != mk && reloc::conflict(seeds.pick[static_cast<std::size_t>(mk)].data(),
                                               seeds.pick[static_cast<std::size_t>(s)].data(), m);
          }
          if (apart &&
              (next < 0 || seeds.h[static_cast<std::size_t>(s)].ll > seeds.h[static_cast<std::size_t>(next)].ll)) {
            next = s;
          }
        }
        if (next < 0) break;
        member[static_cast<std::size_t>(count++)] = next;
      }
      for (int k = 0; k < count; ++k) {  // <= kMaxHypotheses
        const auto s = static_cast<std::size_t>(member[static_cast<std::size_t>(k)]);
        h_[static_cast<std::size_t>(k)] = seeds.h[s];
        pick_[static_cast<std::size_t>(k)] = seeds.pick[s];
        d2_[static_cast<std::size_t>(k)].fill(T(0));
      }
      count_ = count;
      age_ = 1;
      pose_ = sm.x;  // rebase() moves it to the filter's pose after the update
      cov_ = sm.P;
      out.verdict = reloc::WindowVerdict::kOpened;
      out.hypotheses = count;
      out.held = keep_agreed(cfg, pred, map, scratch, assoc, hold);
      return;
    }
    // The window is open: each hypothesis moved as the filter moved, paired and scored.
    Mat3<T> grown = sm.P - cov_;
    grown = T(0.5) * (grown + grown.transpose());
    const bool moved = grown(0, 0) >= T(0) && grown(1, 1) >= T(0) && grown(2, 2) >= T(0);
    std::array<Pose2<T>, reloc::kMaxHypotheses> at{};
    for (int k = 0; k < count_; ++k) {  // <= kMaxHypotheses
      reloc::PoseHypothesis<T>& h = h_[static_cast<std::size_t>(k)];
      h.x = reloc::corrected(reloc::correction_between(pose_, h.x), sm.x);
      if (moved) h.P += grown;
      at[static_cast<std::size_t>(k)] = h.x;
      // The association's path takes the association's pairs; every other grows its own.
      association_picks(assoc, map, scratch, k == assoc_member_);
      h.ll += reloc::run_hypothesis(obs, scratch.ws, sm.set, *sm.view, sm.gate, k != assoc_member_, h);
      pick_[static_cast<std::size_t>(k)] = scratch.ws.pick;
      for (int i = 0; i < m; ++i) d2_[static_cast<std::size_t>(k)][i] = scratch.ws.pick_d2[i];  // <= kMaxObservations
    }
    pose_ = sm.x;
    cov_ = sm.P;
    int lead = 0;
    for (int k = 1; k < count_; ++k) {  // <= kMaxHypotheses
      if (h_[static_cast<std::size_t>(k)].ll > h_[static_cast<std::size_t>(lead)].ll) lead = k;
    }
    T second = -std::numeric_limits<T>::infinity();
    for (int k = 0; k < count_; ++k) {  // <= kMaxHypotheses
      if (k != lead) second = std::max(second, h_[static_cast<std::size_t>(k)].ll);
    }
    out.lead = h_[static_cast<std::size_t>(lead)].ll - second;
    out.hypotheses = count_;
    if (out.lead >= margin && lead == assoc_member_) {  // the association's path won
      count_ = 0;
      out.verdict = reloc::WindowVerdict::kMerged;
      return;
    }
    // A correction needs a pose: the leader's pairs on this scan, kMinPosePairs at least.
    if (reloc::pairs(pick_[static_cast<std::size_t>(lead)].data(), m) < reloc::kMinPosePairs) out.lead = T(0);
    if (out.lead >= margin) {
      // Committed: the leader's pairs, at its pose before this scan's pairs moved it.
      const Pose2<T> x = at[static_cast<std::size_t>(lead)];
      int pairings = 0;
      for (int i = 0; i < m; ++i) {  // <= kMaxObservations
        const int k = pick_[static_cast<std::size_t>(lead)][static_cast<std::size_t>(i)];
        if (k < 0) {
          unpair(assoc, i);
          continue;
        }
        pair(assoc, pred, i, map.id(scratch.slot_at(k)),
             d2_[static_cast<std::size_t>(lead)][static_cast<std::size_t>(i)]);
        ++pairings;
      }
      const T dx = x.x - sm.x.x, dy = x.y - sm.x.y, dth = wrap_angle(x.theta - sm.x.theta);
      close.Q = Mat3<T>::Zero();
      close.Q(0, 0) = cfg.loop_inflation * dx * dx;
      close.Q(1, 1) = cfg.loop_inflation * dy * dy;
      close.Q(2, 2) = cfg.loop_inflation * dth * dth;
      close.at = x;
      close.commit = true;
      count_ = 0;
      out.verdict = reloc::WindowVerdict::kCommitted;
      out.held = pairings;
      return;
    }
    bool disputed = false;                    // do two hypotheses pair this scan differently?
    for (int a = 0; a < count_; ++a) {        // <= kMaxHypotheses
      for (int b = a + 1; b < count_; ++b) {  // <= kMaxHypotheses
        disputed = disputed || reloc::conflict(pick_[static_cast<std::size_t>(a)].data(),
                                               pick_[static_cast<std::size_t>(b)].data(), m);
      }
    }
    if (!disputed) {  // no scan can tell them apart any more: the association stands
      count_ = 0;
      out.verdict = reloc::WindowVerdict::kMerged;
      return;
    }
    out.held = keep_agreed(cfg, pred, map, scratch, assoc, hold);
    out.verdict = reloc::WindowVerdict::kHeld;
    if (++age_ > cfg.hypothesis_window_scans) {
      count_ = 0;
      out.verdict = reloc::WindowVerdict::kExpired;
    }
  }

 private:
  /// While the window is open (hypothesis_hold): an observation every hypothesis pairs with the same
  /// landmark is paired so; every other is held. A scan with no pair left is no evidence for the
  /// review (`hold`). @return the observations held
  int keep_agreed(const AssociationConfig<T, B>& cfg, const Prediction<T, B>& pred, const MapView<T, B>& map,
                  const AlignScratch<T, B>& scratch, Association<T, B>& assoc, bool& hold) const {
    if (!cfg.hypothesis_hold) return 0;
    int held = 0;
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      const int k = pick_[0][static_cast<std::size_t>(i)];
      bool agreed = true;
      for (int h = 1; h < count_ && agreed; ++h) {  // <= kMaxHypotheses
        agreed = pick_[static_cast<std::size_t>(h)][static_cast<std::size_t>(i)] == k;
      }
      if (agreed && k < 0 && !map.confirmed(map.slot_of(assoc.feature[i]))) {
        // No hypothesis pairs it with the frozen map: the association's answer (new, or a
        // tentative landmark) stands.
        continue;
      }
      if (!agreed || k < 0) {
        unpair(assoc, i);
        ++held;
        continue;
      }
      pair(assoc, pred, i, map.id(scratch.slot_at(k)), d2_[0][static_cast<std::size_t>(i)]);
    }
    hold = assoc.pairings == 0;
    return held;
  }

  std::array<reloc::PoseHypothesis<T>, reloc::kMaxHypotheses> h_;
  int count_ = 0;
  int age_ = 0;
  int assoc_member_ = 0;  ///< the member that follows the association's pairs
  Pose2<T> pose_{};       ///< the filter's pose when the hypotheses were last moved
  Mat3<T> cov_;           ///< and its covariance
  std::array<std::array<std::int16_t, B::kMaxObservations>, reloc::kMaxHypotheses> pick_{};
  std::array<std::array<T, B::kMaxObservations>, reloc::kMaxHypotheses> d2_{};
};

}  // namespace geojcbb::node
