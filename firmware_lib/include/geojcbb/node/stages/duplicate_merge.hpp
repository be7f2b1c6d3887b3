// node/stages: duplicates merged by evidence (StepSettings::duplicate_merge_d2 > 0; docs/design.md,
// "Duplicates merged by evidence"). Its state across scans: the pairs of landmarks known to be distinct.
//   note()   after augment: every two landmarks observed in this scan (paired, or added from it) are
//            distinct for good; the pairs of them close enough to pass the merge test later
//            (ekf::Slam::duplicate_d2 below max(4 duplicate_merge_d2, the individual gate): the
//            difference's covariance only shrinks) are remembered
//   merge()  after the review: a landmark paired by this scan and a landmark of the scan's prediction
//            it did not pair, never observed together, whose difference is within duplicate_merge_d2
//            (the joint test at a strict level) are one landmark: merged, the earlier id kept
// Map upkeep: merge() edits the filter (ekf::Slam::merge). Bounds: note O(kMaxObservations^2
// kMaxDistinct), merge O(kMaxMergesPerScan (kMaxObservations kMaxCandidates + kMaxDistinct + n^2)).
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/step_result.hpp"

namespace geojcbb::node {

template <typename T, class B>
class DuplicateMerge {
 public:
  /// Merges after one scan's review, at most.
  static constexpr int kMaxMergesPerScan = 4;
  /// Distinct pairs remembered; when the memory is full a new pair overwrites the oldest.
  static constexpr int kMaxDistinct = 2 * B::kMaxObservations;

  void reset() {
    count_ = 0;
    next_ = 0;
  }

  /// After augment: the pairs of this scan's observed landmarks (out: kPaired and kNewLandmark) that
  /// could pass the merge test later (above) are remembered as distinct. A removed landmark's pairs
  /// stay until overwritten (ids are never reused, so they never match again).
  [[gnu::noinline]] void note(const ekf::Slam<T, B>& slam, const StepResult<T, B>& out, T merge_d2, T gate_d2) {
    const T watch_d2 = T(4) * merge_d2 > gate_d2 ? T(4) * merge_d2 : gate_d2;
    for (int a = 0; a < out.count; ++a) {  // <= kMaxObservations
      if (!observed(out, a)) continue;
      const int ja = slam.index_of(out.feature[a]);
      for (int b = a + 1; b < out.count && ja >= 0; ++b) {  // <= kMaxObservations
        if (!observed(out, b) || out.feature[b] == out.feature[a]) continue;
        if (!(slam.duplicate_d2(ja, slam.index_of(out.feature[b])) < watch_d2)) continue;
        remember(out.feature[a], out.feature[b]);
      }
    }
  }

  /// After the review: up to kMaxMergesPerScan merges, the closest pair first (a landmark paired by
  /// the scan, one of the scan's prediction it did not pair; never observed together; duplicate_d2
  /// below merge_d2). The survivor is the earlier (smaller) id; it takes the other's distinct pairs.
  /// @return landmarks merged
  [[gnu::noinline]] int merge(T merge_d2, const Prediction<T, B>& pred, const StepResult<T, B>& out,
                              ekf::Slam<T, B>& slam, ekf::SlamWorkspace<T, B>& ws) {
    bool paired[B::kMaxCandidates];
    for (int c = 0; c < pred.count; ++c) {  // <= kMaxCandidates
      paired[c] = false;
      for (int i = 0; i < out.count && !paired[c]; ++i) {  // <= kMaxObservations
        paired[c] = out.outcome[i] == Outcome::kPaired && out.feature[i] == pred.id[c];
      }
    }
    int merged = 0;
    for (int m = 0; m < kMaxMergesPerScan; ++m) {  // <= kMaxMergesPerScan
      int keep = -1, drop = -1;
      T best = merge_d2;
      for (int i = 0; i < out.count; ++i) {  // <= kMaxObservations
        if (out.outcome[i] != Outcome::kPaired) continue;
        const int ja = slam.index_of(out.feature[i]);
        for (int c = 0; c < pred.count && ja >= 0; ++c) {  // <= kMaxCandidates
          if (paired[c]) continue;
          const int jb = slam.index_of(pred.id[c]);
          if (jb < 0) continue;  // removed by the review, or merged
          const T d2 = slam.duplicate_d2(ja, jb);
          if (!(d2 < best) || known_distinct(out.feature[i], pred.id[c])) continue;
          best = d2;
          keep = ja < jb ? ja : jb;
          drop = ja < jb ? jb : ja;
        }
      }
      if (keep < 0) break;
      const FeatureId kept = slam.id(keep), gone = slam.id(drop);
      if (slam.merge(keep, drop, ws) != Status::kOk) break;
      for (int k = 0; k < count_; ++k) {  // <= kMaxDistinct: what was distinct from the copy is from the survivor
        auto& p = pair_[static_cast<std::size_t>(k)];
        if (p[0] == gone) p[0] = kept;
        if (p[1] == gone) p[1] = kept;
      }
      ++merged;
    }
    return merged;
  }

 private:
  static bool observed(const StepResult<T, B>& out, int i) {
    return out.outcome[i] == Outcome::kPaired || out.outcome[i] == Outcome::kNewLandmark;
  }
  [[gnu::noinline]] bool known_distinct(FeatureId a, FeatureId b) const {
    for (int k = 0; k < count_; ++k) {  // <= kMaxDistinct
      const auto& p = pair_[static_cast<std::size_t>(k)];
      if ((p[0] == a && p[1] == b) || (p[0] == b && p[1] == a)) return true;
    }
    return false;
  }
  void remember(FeatureId a, FeatureId b) {
    if (known_distinct(a, b)) return;
    if (count_ < kMaxDistinct) {
      pair_[static_cast<std::size_t>(count_++)] = {a, b};
      return;
    }
    pair_[static_cast<std::size_t>(next_)] = {a, b};  // full: the oldest slot
    next_ = (next_ + 1) % kMaxDistinct;
  }

  int count_ = 0;  ///< distinct pairs remembered
  int next_ = 0;   ///< the slot a new pair overwrites when the memory is full
  std::array<std::array<FeatureId, 2>, kMaxDistinct> pair_{};
};

}  // namespace geojcbb::node
