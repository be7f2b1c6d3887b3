// reloc: loop closures scored, unique and confirmed before they are committed.
// A closure is the scan's pairing with old landmarks (confirmed landmarks not paired for the
// settings' loop_age scans). Two hypotheses compete for them:
//   the association's   its pairs with old landmarks, at the pose fitted to them (the predicted
//                       pose when it has fewer than two)
//   the alignment's     reloc::align over the old landmarks alone, with the filter's pose as its
//                       prior (unique by reloc_margin_nats of log posterior)
// each scored at its own pose by its log posterior: the set likelihood (set_log_likelihood, paired
// terms log p_D - d2/2 - log|2 pi S|/2, log(1 - p_D) for every old landmark in view and not paired,
// log(density) for every observation no old landmark explains) plus the log prior of that pose
// (-d2/2 under the filter's pose and covariance). When the poses agree, or the association's scores
// within loop_margin_nats of the alignment's, the association stands. Otherwise the
// alignment's closure is pending: the disputed pairs are held (left unmatched, not augmented) and
// the closure must win again, with the same correction (alignment pose against the filter's), on
// loop_confirm_scans scans in a row; then it is committed: the pose block inflated by the correction,
// the alignment's pairs replace the association's, and the update linearised at the alignment's
// pose (ekf::Slam::update's `at`, an iterated EKF step), so the correlations carry the correction to
// the landmarks mapped during the drift. node::LoopCheck (node/stages/loop_check.hpp) runs it, reading its options
// from the step's settings; docs/relocalisation.md ("Loop closures").
// Bounds: one align() call; two fits (kFitSteps Gauss-Newton steps) and two scores, each
// O(m + n); the association's rewrite O(m n).
#pragma once

#include <cmath>
#include <cstdint>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/reloc/align.hpp"

namespace geojcbb::reloc {

/// Gauss-Newton steps of a hypothesis's pose fit.
constexpr int kFitSteps = 2;

/// The largest pose-free d2 of the pairs in ws.pick at pose x (S = R Sigma R^T + P_j: no pose
/// uncertainty), 0 without pairs. Bound: m.
template <typename T, class B>
T max_pair_d2(const AlignWorkspace<T, B>& ws, int m, const Pose2<T>& x) {
  using namespace align_detail;
  const Mat2<T> Rot = rotation(x.theta);
  T worst = T(0);
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    const int j = ws.pick[i];
    const Vec2<T> e = Rot * ws.q[i] + Vec2<T>(x.x, x.y) - ws.m[j];
    const Mat2<T> S = Rot * ws.S[i] * Rot.transpose() + ws.P[j];
    const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(det > T(0))) return std::numeric_limits<T>::infinity();
    const T d2 = (S(1, 1) * e.x() * e.x() - (S(0, 1) + S(1, 0)) * e.x() * e.y() + S(0, 0) * e.y() * e.y()) / det;
    worst = std::max(worst, d2);
  }
  return worst;
}

/// The pose that best explains the pairs in ws.pick (Procrustes, then kFitSteps Gauss-Newton
/// steps) and its covariance (`cov`: two pairs or more); one pair: x moved onto it, heading kept.
/// `x` and `cov` unchanged without pairs or on a failed fit. @return the pairs. Bound: (kFitSteps + 1) m.
template <typename T, class B>
int fit_picked(const AlignWorkspace<T, B>& ws, int m, Pose2<T>& x, Mat3<T>& cov) {
  using namespace align_detail;
  int pairs = 0, last = -1;
  for (int i = 0; i < m; ++i) {  // <= kMaxObservations
    if (ws.pick[i] < 0) continue;
    ++pairs;
    last = i;
  }
  if (pairs == 1) {
    const Vec2<T> e = ws.m[ws.pick[last]] - transform(x, ws.q[last]);
    x.x += e.x();
    x.y += e.y();
  }
  if (pairs < 2) return pairs;
  Pose2<T> y = procrustes(ws, m);
  Mat3<T> c;
  for (int k = 0; k < kFitSteps; ++k) {  // <= kFitSteps
    if (!gauss_newton_step(ws, m, y, c)) return pairs;
  }
  x = y;
  cov = c;
  return pairs;
}

/// Agreeing checks after which the closure check rests until the old landmarks leave the region.
constexpr int kLoopSettleScans = 5;

/// What the check did with one scan.
enum class LoopVerdict : std::uint8_t {
  kNone = 0,       ///< not checked (off, lost, no old landmark in the region, or resting)
  kNoAlternative,  ///< checked: the alignment found no unique pose
  kAgreed,         ///< the alignment's pose is the association's
  kConsistent,     ///< the association stands: no alternative and its pairs fit the pose as it is (pose-free
                   ///< d2), or its closure leads by loop_margin_nats with a correction within the distinct scale
  kKept,           ///< they differ, and the association's closure scores within the margin
  kPending,        ///< a closure wins (as kCommitted), not yet confirmed: disputed pairs held
  kCommitted,      ///< a closure (the alignment's, or the association's with loop_min_inliers pairs) won
                   ///< confirm_scans times: committed
};

template <typename T>
struct LoopStats {
  LoopVerdict verdict = LoopVerdict::kNone;
  /// log posteriors [nats] (checked scans): set log-likelihood + log prior (-d2/2 of the filter's pose);
  /// ll_none: no closure (the scan's observations unexplained, the old landmarks in view missed)
  T ll_association = T(0), ll_alignment = T(0), ll_none = T(0);
  bool ambiguous = false;              ///< the alignment found distinct poses within reloc_margin_nats: no alternative
  int old_landmarks = 0;               ///< old landmarks within reach (checked scans)
  int inliers = 0, rival_inliers = 0;  ///< the alignment's best pose's and its rival's
  int held = 0;                        ///< observations held (kPending) or re-paired (kCommitted)
  Pose2<T> association_pose{}, alignment_pose{};  ///< where each closure was scored (checked scans)
};

/// The closure check's memory across scans (bounded: a few scalars).
template <typename T>
struct LoopState {
  int pending = 0;        ///< consecutive wins of the alignment's closure
  int agreed = 0;         ///< consecutive agreeing checks
  Pose2<T> correction{};  ///< of the pending closure: alignment pose composed with the filter's inverse
};

/// world_T_b composed with the inverse of world_T_a: the transform that moves a onto b.
template <typename T>
Pose2<T> correction_between(const Pose2<T>& a, const Pose2<T>& b) {
  const T dth = wrap_angle(b.theta - a.theta);
  const T c = fmath::cos(dth), s = fmath::sin(dth);
  return Pose2<T>{b.x - (c * a.x - s * a.y), b.y - (s * a.x + c * a.y), dth};
}

/// The correction applied to pose a.
template <typename T>
Pose2<T> corrected(const Pose2<T>& corr, const Pose2<T>& a) {
  const T c = fmath::cos(corr.theta), s = fmath::sin(corr.theta);
  return Pose2<T>{corr.x + c * a.x - s * a.y, corr.y + s * a.x + c * a.y, wrap_angle(a.theta + corr.theta)};
}

}  // namespace geojcbb::reloc
