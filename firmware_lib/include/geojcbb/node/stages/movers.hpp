// node/stages: movers, the things that move (docs/design.md, "The world model"). A landmark whose
// motion test fails (ekf/motion_test.hpp, ekf::Slam::test_motion) leaves the map and becomes a
// mover: one of kMaxTracks tracks of a point on a random walk, in the world frame, that takes the
// observations in its gate before the update and never moves the robot or the map.
// Its state across scans: the tracks (position, covariance, scans unseen) and the movers caught.
//   take()    before the update: every track predicted (random walk), then each takes the nearest
//             observation inside its gate (marked kMoverFeature: not paired, not made new); the
//             track is updated with it (a Kalman update on the observation's world point)
//   run()     take(), then the motion test (ekf::Slam::test_motion); each landmark that fails leaves
//             the map and its observation begins a track (start(): the longest unseen makes room)
// A mover is not re-admitted: while its track lives, what it takes is neither paired nor mapped. A
// track unseen for kForgetScans scans is dropped, and so is one whose sightings a point standing
// still explains better than the walk by kStillNats (a static landmark the test flagged, or a mover
// that stopped for good): what it saw is then new again, and the motion test must catch it again.
// Bounds: O(kMaxObservations kMaxTracks) per scan (a world point per observation).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/node/stages/map_view.hpp"

namespace geojcbb::node {

/// An observation a mover's track took: neither paired nor a new landmark (StepResult: kMover).
constexpr FeatureId kMoverFeature = -3;
/// Observation i taken by a mover (kMoverFeature). Keeps assoc.pairings true.
template <typename T, class B>
void set_mover(Association<T, B>& assoc, int i) {
  assoc.pairings -= assoc.feature[i] >= 0;
  assoc.feature[i] = kMoverFeature;
  assoc.candidate[i] = -1;
}

/// The movers' stand-in in a configuration without the world model (OptionalStages::kWorldModel).
struct NoMovers {
  void reset() {}
  template <class... A>
  static int run(A&&...) {
    return 0;
  }
  std::uint32_t caught() const { return 0; }
  int tracks() const { return 0; }
};

template <typename T, class B>
class Movers {
 public:
  /// Tracks at once: MRCLAM has four other robots; a fifth mover replaces the longest unseen.
  static constexpr int kMaxTracks = 4;
  /// Scans a track lives without an observation.
  static constexpr int kForgetScans = 50;
  /// The random walk's variance per scan and axis [m^2]: (0.1 m)^2, a robot at 7 cm/s seen every
  /// 1.5 s (MRCLAM's), a person at 1 m/s seen every 0.1 s. Chosen on MRCLAM data set 6 (0.25 let
  /// static tubes the test flagged keep their tracks: docs/results/world_model.md).
  static constexpr T kWalk_m2 = T(0.01);
  /// A track whose sightings a point standing still explains better than the random walk, by this
  /// log-likelihood ratio [nats], was a static landmark the motion test flagged (a pairing's bias, not
  /// motion): it is dropped and what it saw is mapped again. Wald's threshold for 1 % errors both
  /// ways (the existence test's landmark_confirm_nats); the ratio is floored at its negative, so a
  /// mover that stops for good is given back after a bounded number of sightings.
  static constexpr T kStillNats = T(4.6);

  void reset() {
    count_ = 0;
    caught_ = 0;
  }
  /// Movers caught since reset() (landmarks that failed the motion test).
  std::uint32_t caught() const { return caught_; }
  /// Tracks alive now (at most kMaxTracks).
  int tracks() const { return count_; }
  /// Track k's position (world) [m].
  Vec2<T> track(int k) const { return tracks_[static_cast<std::size_t>(k)].walk.at; }

  /// Before the update: every track a scan older (predicted, dropped after kForgetScans unseen),
  /// then each in turn takes the nearest observation inside its gate that no track before it took
  /// (d2 <= gate_d2 on the observation's world point, with the pose's uncertainty), whatever the
  /// association made of it. @return the observations taken.  O(kMaxObservations kMaxTracks)
  [[gnu::noinline]] int take(const Observations<T, B>& obs, const MapView<T, B>& map, T gate_d2,
                             Association<T, B>& assoc) {
    int kept = 0;
    for (int k = 0; k < count_; ++k) {  // <= kMaxTracks
      Track t = tracks_[static_cast<std::size_t>(k)];
      if (++t.unseen >= kForgetScans) continue;
      t.walk.P(0, 0) += kWalk_m2;
      t.walk.P(1, 1) += kWalk_m2;
      tracks_[static_cast<std::size_t>(kept++)] = t;
    }
    count_ = kept;
    // Each track's nearest observation in its gate; each observation's world point computed once.
    std::array<int, kMaxTracks> best;
    std::array<T, kMaxTracks> best_d2;
    std::array<Vec2<T>, kMaxTracks> best_p;
    std::array<Mat2<T>, kMaxTracks> best_R;
    best.fill(-1);
    best_d2.fill(gate_d2);
    // Observation i (world point p, covariance Rw) for track u: kept when it is the nearest yet.
    const auto consider = [&](std::size_t u, int i, const Vec2<T>& p, const Mat2<T>& Rw) {
      const T d2 = mahalanobis2(p - tracks_[u].walk.at, tracks_[u].walk.P + Rw);
      if (!(d2 <= best_d2[u])) return;
      best_d2[u] = d2;
      best[u] = i;
      best_p[u] = p;
      best_R[u] = Rw;
    };
    for (int i = 0; i < obs.count && count_ > 0; ++i) {  // <= kMaxObservations
      if (assoc.feature[i] == kMoverFeature) continue;
      Mat2<T> Rw;
      const Vec2<T> p = world_point(obs, map, i, Rw);
      for (int k = 0; k < count_; ++k) consider(static_cast<std::size_t>(k), i, p, Rw);  // <= kMaxTracks
    }
    int taken = 0;
    for (int k = 0; k < count_; ++k) {  // <= kMaxTracks
      const auto u = static_cast<std::size_t>(k);
      // An earlier track took this one's nearest: its nearest among the rest, as if the tracks had
      // looked in turn (the rare case pays the world points again).
      if (best[u] >= 0 && assoc.feature[best[u]] == kMoverFeature) {
        best[u] = -1;
        best_d2[u] = gate_d2;
        for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
          if (assoc.feature[i] == kMoverFeature) continue;
          Mat2<T> Rw;
          const Vec2<T> p = world_point(obs, map, i, Rw);
          consider(u, i, p, Rw);
        }
      }
      if (best[u] < 0) continue;
      Track& t = tracks_[u];
      // Which explains the sighting better, a point on a random walk or one that stands still?
      t.still =
          std::max(t.still + t.stand.update(best_p[u], best_R[u]) - t.walk.update(best_p[u], best_R[u]), -kStillNats);
      t.unseen = 0;
      if (t.still >= kStillNats) {  // it stands still: not a mover after all, the observation is free
        t.unseen = kForgetScans;    // dropped at the next scan
        continue;
      }
      set_mover(assoc, best[u]);
      ++taken;
    }
    return taken;
  }

  /// The world model's motion, before the update (map upkeep by name: it removes landmarks from the
  /// filter, as DuplicateMerge::merge merges them): the tracks take the observations in their gates
  /// (take), each remaining pair's landmark takes the motion test and the static gate
  /// (ekf::Slam::test_motion, `threshold`, `static_gate_d2`), and one that fails leaves the map
  /// (marginalised) while its observation begins a track (start). The update and the review then see
  /// neither. `map` views `slam`. @return the landmarks that became movers.
  /// O(kMaxObservations kMaxTracks) and test_motion's
  [[gnu::noinline]] int run(const Observations<T, B>& obs, const MapView<T, B>& map, const Prediction<T, B>& pred,
                            T gate_d2, T threshold, T static_gate_d2, Association<T, B>& assoc, ekf::Slam<T, B>& slam) {
    take(obs, map, gate_d2, assoc);
    std::array<std::int16_t, B::kMaxObservations> moved;
    const int n = slam.test_motion(obs, pred, assoc, threshold, static_gate_d2, moved);
    int caught = 0;
    for (int k = 0; k < n; ++k) {  // <= kMaxObservations
      const int i = moved[static_cast<std::size_t>(k)];
      const FeatureId id = assoc.feature[i];
      start(obs, map, i, assoc);
      caught += slam.forget(id) == Status::kOk;
    }
    return caught;
  }

  /// Observation i, whose landmark failed the motion test, begins a track (the longest unseen makes
  /// room when kMaxTracks live) and is marked kMoverFeature.  O(kMaxTracks)
  [[gnu::noinline, gnu::cold]] void start(const Observations<T, B>& obs, const MapView<T, B>& map, int i,
                                          Association<T, B>& assoc) {
    int slot = count_;
    if (slot == kMaxTracks) {
      slot = 0;
      for (int k = 1; k < kMaxTracks; ++k) {  // <= kMaxTracks
        if (tracks_[static_cast<std::size_t>(k)].unseen > tracks_[static_cast<std::size_t>(slot)].unseen) slot = k;
      }
    } else {
      ++count_;
    }
    Track& t = tracks_[static_cast<std::size_t>(slot)];
    t.walk.at = world_point(obs, map, i, t.walk.P);
    t.stand = t.walk;
    t.still = T(0);
    t.unseen = 0;
    set_mover(assoc, i);
    ++caught_;
  }

 private:
  /// A point in the world and its covariance, with a Kalman update on a sighting of it.
  struct Point {
    Vec2<T> at = Vec2<T>::Zero();  ///< [m]
    Mat2<T> P = Mat2<T>::Zero();   ///< [m^2]
    /// The sighting p (covariance R) taken. @return its log-likelihood, -(d2 + log|S|) / 2 (+ const).
    T update(const Vec2<T>& p, const Mat2<T>& R) {
      const Mat2<T> S = P + R;
      const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
      if (!(det > T(0))) return T(0);
      Mat2<T> Si;
      Si << S(1, 1) / det, -S(0, 1) / det, -S(1, 0) / det, S(0, 0) / det;
      const Vec2<T> nu = p - at;
      const T d2 = nu.dot(Si * nu);
      const Mat2<T> K = P * Si;
      at += K * nu;
      P = symmetric_part(Mat2<T>((Mat2<T>::Identity() - K) * P));
      return -T(0.5) * (d2 + fmath::log(det));
    }
  };
  struct Track {
    Point walk;      ///< on a random walk (kWalk_m2 a scan): the gate
    Point stand;     ///< standing still since the track began
    T still = T(0);  ///< log-likelihood ratio, standing over walking, floored at -kStillNats [nats]
    int unseen = 0;  ///< scans since it took an observation
  };
  /// Observation i's point in the world at the map's pose, and its covariance Rw (the observation's
  /// noise and the pose's uncertainty, through the inverse observation's Jacobians).
  static Vec2<T> world_point(const Observations<T, B>& obs, const MapView<T, B>& map, int i, Mat2<T>& Rw) {
    Mat23<T> Jx;
    Mat2<T> Jz;
    Vec2<T> p = inverse_observe(map.pose(), map.mount(), obs.z[i], &Jx, &Jz);
    Rw = symmetric_part(Mat2<T>(Jz * obs.R[i] * Jz.transpose() + Jx * map.pose_covariance() * Jx.transpose()));
    return p;
  }
  static T mahalanobis2(const Vec2<T>& d, const Mat2<T>& S) {
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(det > T(0))) return std::numeric_limits<T>::infinity();
    return (S(1, 1) * d.x() * d.x() - (S(0, 1) + S(1, 0)) * d.x() * d.y() + S(0, 0) * d.y() * d.y()) / det;
  }
  std::array<Track, kMaxTracks> tracks_{};
  int count_ = 0;
  std::uint32_t caught_ = 0;  ///< since reset()
};

}  // namespace geojcbb::node
