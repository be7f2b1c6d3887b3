// node/stages: what the stages of a SLAM step share, and nothing else.
//   MapView      the map read-only: landmarks by slot (0 .. size() - 1, valid within one scan) and by
//                feature id, their means, 2x2 covariance blocks, hits, age, unseen, confirmed
//   AlignScratch the one alignment buffer (reloc::AlignWorkspace and its result) the stages use in
//                turn within a scan, with the slot of every landmark pushed into it
//   pair/unpair  the only edits of an association after associate(): pairings stays true
// Stages keep feature ids across scans; slots live within one scan. No heap; O(1) per access but
// slot_of (O(n), the landmark book's lookup).
#pragma once

#include <array>
#include <cstdint>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/reloc/align.hpp"

namespace geojcbb::node {

/// The map as a stage sees it: read-only. Built by the step for one scan (two pointers).
template <typename T, class B>
class MapView {
 public:
  MapView(const ekf::Slam<T, B>& slam, const ekf::LandmarkPolicy& policy) : slam_(&slam), policy_(&policy) {}

  int size() const { return slam_->landmarks(); }
  FeatureId id(int k) const { return slam_->id(k); }
  FeatureId next_id() const { return slam_->next_id(); }
  /// The slot of feature `id`, or -1 (never mapped, removed, or not a feature: kNewFeature, kUnmatched).
  int slot_of(FeatureId id) const { return slam_->index_of(id); }
  Vec2<T> mean(int k) const { return slam_->landmark(k); }
  /// The landmark's 2x2 covariance block.
  Mat2<T> cov(int k) const {
    const int r = ekf::Layout::landmark(k);
    Mat2<T> P;
    P << slam_->cov(r, r), slam_->cov(r, r + 1), slam_->cov(r, r + 1), slam_->cov(r + 1, r + 1);
    return P;
  }
  /// Trace of the 2x2 block [m^2].
  T position_var(int k) const {
    const int r = ekf::Layout::landmark(k);
    return slam_->cov(r, r) + slam_->cov(r + 1, r + 1);
  }
  int hits(int k) const { return slam_->hits(k); }
  int expected(int k) const { return slam_->expected(k); }
  int unseen(int k) const { return slam_->unseen(k); }
  int age(int k) const { return slam_->age(k); }
  /// Confirmed by its log-odds of existence (ekf::LandmarkPolicy), or known: the map the lost
  /// test, the window, the clusters and the alignments use. False for slot -1.
  bool confirmed(int k) const { return k >= 0 && slam_->confirmed(k); }
  /// Fails the static gate: the review removes it as moved if it is paired.
  bool moved(int k) const { return slam_->has_moved(k, T(policy_->static_gate_d2)); }
  const ekf::LandmarkPolicy& policy() const { return *policy_; }

  Pose2<T> pose() const { return slam_->pose(); }
  Mat3<T> pose_covariance() const { return slam_->pose_covariance(); }
  T pose_cov(int r, int c) const { return slam_->cov(r, c); }
  const Mount<T>& mount() const { return slam_->mount(); }

 private:
  const ekf::Slam<T, B>* slam_;
  const ekf::LandmarkPolicy* policy_;
};

/// The one alignment buffer of a step, used by one stage at a time within a scan (the relocaliser,
/// the loop check, the window and clusters-first each fill it anew).
template <typename T, class B>
struct AlignScratch {
  reloc::AlignWorkspace<T, B> ws;
  reloc::AlignResult<T, B> result;
  std::array<std::int16_t, B::kMaxLandmarks> slot{};  ///< push order -> the landmark's slot

  void clear() { ws.clear_map(); }
  /// Pushes the landmark in slot k. @return the statuses of AlignWorkspace::push_landmark.
  [[nodiscard]] Status push(const MapView<T, B>& map, int k) {
    slot[static_cast<std::size_t>(ws.n)] = static_cast<std::int16_t>(k);
    return ws.push_landmark(map.mean(k), map.cov(k));
  }
  /// The slot of push-order landmark p (the window's picks are in push order).
  int slot_at(int p) const { return slot[static_cast<std::size_t>(p)]; }
  /// The slot of sorted landmark s (after reloc::align sorted the map).
  int slot_sorted(int s) const { return slot[static_cast<std::size_t>(ws.index[static_cast<std::size_t>(s)])]; }
};

/// Observation i paired with feature `id` at d2; its candidate found in `pred` (-1 when the feature is
/// not a candidate). Keeps assoc.pairings true.  O(kMaxCandidates)
template <typename T, class B>
void pair(Association<T, B>& assoc, const Prediction<T, B>& pred, int i, FeatureId id, T d2) {
  assoc.pairings += assoc.feature[i] < 0;
  assoc.feature[i] = id;
  assoc.d2[i] = d2;
  assoc.candidate[i] = -1;
  for (int a = 0; a < pred.count; ++a) {  // <= kMaxCandidates
    if (pred.id[a] == id) assoc.candidate[i] = static_cast<std::int16_t>(a);
  }
}
/// Observation i held: kUnmatched (neither paired nor made new). Keeps assoc.pairings true.
template <typename T, class B>
void unpair(Association<T, B>& assoc, int i) {
  assoc.pairings -= assoc.feature[i] >= 0;
  assoc.feature[i] = kUnmatched;
  assoc.candidate[i] = -1;
}
/// assoc.pairings recounted (after an association that was not made by associate()).
template <typename T, class B>
void recount(Association<T, B>& assoc) {
  int pairings = 0;
  for (int i = 0; i < assoc.count; ++i) pairings += assoc.feature[i] >= 0;  // <= kMaxObservations
  assoc.pairings = pairings;
}

/// A pose correction a stage decided on (a committed loop closure or hypothesis): the pose block is
/// inflated by Q and the update linearised at `at` (ekf::Slam::inflate_pose, update's `at`).
template <typename T>
struct Closure {
  bool commit = false;
  Pose2<T> at{};
  Mat3<T> Q = Mat3<T>::Zero();
};

}  // namespace geojcbb::node
