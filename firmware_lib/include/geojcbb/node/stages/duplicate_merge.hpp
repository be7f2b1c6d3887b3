// node/stages: a loop closure's duplicates merged (StepSettings::loop_merge_d2 > 0). Its state across
// scans: the last closure's old landmarks (ids, with the age a duplicate of each may have) and the
// reviews left after which merge() runs.
//   note()   before the review: a scan that pairs old landmarks (confirmed, unpaired for loop_age
//            reviews) is a closure; its old landmarks become the closure set
//   merge()  after the review, on that scan and the next kLoopSettleScans - 1: the closest landmark
//            of the region added while an old one was unseen, within loop_merge_d2 of it in
//            ekf::Slam::duplicate_d2 and not paired by this scan with it, is merged into it
// Map upkeep: merge() edits the filter (ekf::Slam::merge). Bounds: O(kMaxMergesPerScan (m n_c + n^2)).
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/node/stages/map_view.hpp"
#include "geojcbb/reloc/loop.hpp"

namespace geojcbb::node {

template <typename T, class B>
class DuplicateMerge {
 public:
  /// Merges of a loop closure's duplicates after one scan's review, at most.
  static constexpr int kMaxMergesPerScan = 4;

  void reset() {
    left_ = 0;
    count_ = 0;
  }
  /// Whether this scan's review is followed by merge().
  bool due() const { return left_ > 0; }

  /// Before the review: the scan's pairs with old landmarks, each with the reviews it was unseen
  /// plus one (a landmark added later has at most that age after this review). A scan that pairs
  /// none keeps the set of the last closure.
  void note(const AssociationConfig<T, B>& cfg, const MapView<T, B>& map, const Association<T, B>& assoc) {
    int n = 0;
    for (int i = 0; i < assoc.count; ++i) {  // <= kMaxObservations
      const int k = map.slot_of(assoc.feature[i]);
      if (k < 0 || map.unseen(k) < cfg.loop_age || !map.confirmed(k)) continue;
      id_[static_cast<std::size_t>(n)] = assoc.feature[i];
      limit_[static_cast<std::size_t>(n)] = static_cast<std::int16_t>(map.unseen(k) + 1);
      ++n;
    }
    if (n == 0) return;
    count_ = n;
    left_ = reloc::kLoopSettleScans;
  }

  /// After the review (due()): up to kMaxMergesPerScan merges, the closest pair first. Two
  /// landmarks both seen since the original's last sighting are never merged, however close.
  /// Out of line: its flags stay out of the step's frame. @return landmarks merged
  [[gnu::noinline]] int merge(const AssociationConfig<T, B>& cfg, const Prediction<T, B>& pred,
                              const Association<T, B>& assoc, ekf::Slam<T, B>& slam, ekf::SlamWorkspace<T, B>& ws) {
    --left_;
    bool paired[B::kMaxCandidates];
    for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
      paired[a] = false;
      for (int i = 0; i < assoc.count && !paired[a]; ++i) {  // <= kMaxObservations
        paired[a] = assoc.feature[i] == pred.id[a];
      }
    }
    int merged = 0;
    for (int m = 0; m < kMaxMergesPerScan; ++m) {  // <= kMaxMergesPerScan
      int keep = -1, drop = -1;
      T best = cfg.loop_merge_d2;
      for (int k = 0; k < count_; ++k) {  // <= kMaxObservations: the closure's old landmarks
        const FeatureId id = id_[static_cast<std::size_t>(k)];
        const int ja = slam.index_of(id);
        if (ja < 0) continue;  // removed since
        bool a_paired = false;
        for (int i = 0; i < assoc.count && !a_paired; ++i) a_paired = assoc.feature[i] == id;  // <= kMaxObservations
        for (int b = 0; b < pred.count; ++b) {                                                 // <= kMaxCandidates
          const int jb = slam.index_of(pred.id[b]);
          if (jb < 0 || jb == ja || (a_paired && paired[b])) continue;
          if (slam.age(jb) > limit_[static_cast<std::size_t>(k)]) continue;  // older than the absence
          const T d2 = slam.duplicate_d2(ja, jb);
          if (!(d2 < best)) continue;
          best = d2;
          keep = ja;
          drop = jb;
        }
      }
      if (keep < 0 || slam.merge(keep, drop, ws) != Status::kOk) break;
      ++merged;
    }
    for (int k = 0; k < count_; ++k) ++limit_[static_cast<std::size_t>(k)];  // <= kMaxObservations: a review later
    return merged;
  }

 private:
  int left_ = 0;   ///< reviews after a loop closure that are followed by merge()
  int count_ = 0;  ///< the last closure's old landmarks
  std::array<FeatureId, B::kMaxObservations> id_{};
  std::array<std::int16_t, B::kMaxObservations> limit_{};  ///< the age a duplicate may have, at most
};

}  // namespace geojcbb::node
