// node/stages: the seed of a local map from the host's global map (docs/submaps.md, "Seed";
// SUBMAP_SEED on the link). The host gives landmarks of the global map near the robot that this
// local map does not hold, each in the map's frame with its own covariance and the global map's
// log-odds of its existence; each is added (ekf::Slam::seed_landmark: confirmed, with that existence
// capped at what a landmark can bank, uncorrelated with the map and with the other seeds) unless
//   - a landmark the map holds is individually compatible with it (the map made it anew: the join
//     pairs the two, a seed would be a duplicate), or
//   - the map has no room: `limit` landmarks, its closing size (submap_landmarks) or its capacity
//     less one scan's new landmarks, whichever is smaller, so that seeds alone never make the map
//     due. The local region's candidates do not bound it: the prediction keeps the kMaxCandidates
//     nearest, and a seed beyond them waits until the robot is nearer. (Bounding the seed by the
//     region's free candidates kept Victoria Park's maps from their old trees on the default image:
//     its region held 31-71 landmarks at the seeds, nearly always more than the image's 32;
//     docs/submaps.md.)
// One function, called by SlamStep::seed on the device and in the host's process alike.
// Bounds: O(count kMaxLandmarks), count <= kMaxSeeds.
#pragma once

#include <cmath>
#include <limits>

#include "geojcbb/core/math.hpp"
#include "geojcbb/ekf/slam.hpp"
#include "geojcbb/node/step_result.hpp"

namespace geojcbb::node {

/// Seeds per call: SUBMAP_SEED's kSeedsPerFrame (node/wire.hpp static_asserts the agreement).
constexpr int kMaxSeeds = 8;

/// One landmark of the global map, in the local map's frame.
template <typename T>
struct MapSeed {
  Vec2<T> l = Vec2<T>::Zero();
  Mat2<T> P = Mat2<T>::Identity();
  T exist_nats = T(0);  ///< the global map's log-odds of its existence
};

/// What became of a seed: kNewLandmark (id: the landmark it became), kUnmatched (d2: its distance to
/// the compatible landmark the map holds) or kNotAugmented (no room).
template <typename T>
struct SeedAnswer {
  Outcome outcome = Outcome::kNotAugmented;
  FeatureId id = kNewFeature;
  T d2 = std::numeric_limits<T>::infinity();  ///< the smallest to a landmark of the map (+inf: none)
};

/// Seeds `count` landmarks into `slam` (see the file's comment). gate_d2: the individual
/// compatibility gate (chi-square, 2 dof); max_nats: the log-odds a landmark can bank (the policy's
/// saturation, LandmarkPolicy::max_nats), which caps each seed's; limit: the
/// landmarks the map may hold with its seeds (at most kMaxLandmarks - kMaxObservations).
/// @return kOk; kInvalidInput for count out of range, max_nats not finite or limit over that
///         capacity; kNonFinite or kNotPositiveDefinite for a seed (then nothing is seeded). No state
///         changes unless kOk.
template <typename T, class B>
[[nodiscard, gnu::cold, gnu::noinline]] Status seed_map(ekf::Slam<T, B>& slam, T gate_d2, T max_nats, int limit,
                                                        const MapSeed<T>* seeds, int count, SeedAnswer<T>* out) {
  if (count < 0 || count > kMaxSeeds || !std::isfinite(max_nats) || limit > B::kMaxLandmarks - B::kMaxObservations) {
    return Status::kInvalidInput;
  }
  for (int k = 0; k < count; ++k) {  // <= kMaxSeeds: all valid before any is seeded
    const MapSeed<T>& s = seeds[k];
    if (!s.l.allFinite() || !s.P.allFinite() || !std::isfinite(s.exist_nats)) return Status::kNonFinite;
    const Mat2<T> Ps = symmetric_part(s.P);
    if (!is_spd(s.P) || !is_spd_scaled<T>(Ps(0, 0), Ps(0, 1), Ps(1, 1))) return Status::kNotPositiveDefinite;
  }
  int room = limit - slam.landmarks();
  for (int k = 0; k < count; ++k) {  // <= kMaxSeeds
    const MapSeed<T>& s = seeds[k];
    SeedAnswer<T>& a = out[k];
    a = SeedAnswer<T>{};
    for (int j = 0; j < slam.landmarks(); ++j) {  // <= kMaxLandmarks
      const int r = ekf::Layout::landmark(j);
      Mat2<T> S;
      S << s.P(0, 0) + slam.cov(r, r), s.P(0, 1) + slam.cov(r, r + 1), s.P(1, 0) + slam.cov(r + 1, r),
          s.P(1, 1) + slam.cov(r + 1, r + 1);
      const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
      if (!(det > T(0))) continue;
      const Vec2<T> e = s.l - slam.landmark(j);
      const T d2 = (S(1, 1) * e.x() * e.x() - (S(0, 1) + S(1, 0)) * e.x() * e.y() + S(0, 0) * e.y() * e.y()) / det;
      if (d2 < a.d2) a.d2 = d2;
    }
    if (a.d2 < gate_d2) {
      a.outcome = Outcome::kUnmatched;
      a.id = kUnmatched;
      continue;
    }
    if (room <= 0) continue;  // kNotAugmented
    const Status st = slam.seed_landmark(s.l, s.P, s.exist_nats < max_nats ? s.exist_nats : max_nats, a.id);
    if (st != Status::kOk) return st;  // not reached: validated above, and the room is within capacity
    a.outcome = Outcome::kNewLandmark;
    --room;
  }
  return Status::kOk;
}

}  // namespace geojcbb::node
