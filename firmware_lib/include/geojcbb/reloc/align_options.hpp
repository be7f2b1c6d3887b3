// reloc: what an alignment (reloc/align.hpp) is asked: its options (the table's, bind_options), the
// set likelihood's model, the distinct-pose scale, and the pose prior N(x_f, P_f + hypothesis_floor)
// with its d2 (set_prior, prior_d2). The posterior that ranks the poses is docs/design.md's
// "Decisions with the prior". Bounds: O(1) each.
#pragma once

#include <cmath>

#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/math.hpp"
#include "geojcbb/core/range_bearing.hpp"

namespace geojcbb::reloc {

/// Most observed base pairs one call tries.
constexpr int kMaxBasePairs = 8;
/// Most pose hypotheses one call scores (every base pair together); past it the call stops early
/// and says so (AlignResult::truncated).
constexpr int kMaxAlignHypotheses = 4096;
/// Distinct poses remembered while scoring (the best and its rivals).
constexpr int kTopPoses = 4;
/// Refinement rounds (inliers, then Procrustes).
constexpr int kRefineRounds = 2;

/// The set likelihood's model of a scan (set_log_likelihood).
template <typename T>
struct SetModel {
  T p_detect = T(0.9);              ///< probability that a landmark in view is observed, (0, 1)
  T unexplained_density = T(3e-3);  ///< observations per m^2 no landmark of the hypothesis explains
  bool valid() const {
    return p_detect > T(0) && p_detect < T(1) && unexplained_density > T(0) && std::isfinite(unexplained_density);
  }
};

/// What the prior adds to the filter's covariance: the two-point hypothesis's own error before
/// refinement, and a filter that drifted somewhat past its covariance (an EKF's estimate is
/// optimistic after a long drift): 1 m in x and y, 0.2 rad, the alignment's scale of distinct poses.
template <typename T>
Mat3<T> hypothesis_floor() {
  return Vec3<T>(T(1), T(1), T(0.04)).asDiagonal();
}

template <typename T>
struct AlignOptions {
  int base_pairs = 4;                 ///< observed pairs tried, 1 .. kMaxBasePairs
  int min_inliers = 5;                ///< a pose needs at least this many inliers, >= 3
  T margin_nats = T(10);              ///< log posterior by which the best pose must lead the best distinct pose
  T gate_d2 = T(13.815510557964274);  ///< inlier test, chi2inv(0.999, 2)
  T pair_d2 = T(10.827566170662733);  ///< pair distance test, chi2inv(0.999, 1)
  T min_base_m = T(2);                ///< shorter observed pairs fix the heading too poorly [m]
  T distinct_m = T(1);                ///< poses farther apart than this are distinct [m] ...
  T distinct_rad = T(0.2);            ///< ... or turned by more than this [rad]
  /// The sensor's view, for the misses of a pose: map landmarks it would see there and did not.
  /// max_range_m 0: misses not counted.
  T min_range_m = T(0);
  T max_range_m = T(0);
  T half_fov_rad = kPi<T>;
  /// A pose is plausible when its inliers are at least this share of inliers + misses.
  T min_inlier_ratio = T(0.6);
  /// The set likelihood's model (detection probability, density of unexplained observations).
  SetModel<T> model{};
  /// The pose prior N(prior_mean, prior_info^-1) (set_prior); has_prior false: pose-free.
  bool has_prior = false;
  Pose2<T> prior_mean{};
  Mat3<T> prior_info = Mat3<T>::Zero();
  T prior_gate_d2 = T(25.9);   ///< hypotheses scored within this prior d2, chi2inv(1 - 1e-5, 3)
  T prior_half_logdet = T(0);  ///< log sqrt(det) of the prior's covariance (set_prior)
  /// The scan against "not of the map" (each observation unexplained): the best pose is accepted
  /// only when its evidence (log posterior + log sqrt(det) of its fit's covariance - the prior's)
  /// leads that by margin_nats. Pose-free, the prior is uniform over free_log_volume = log(area 2 pi).
  bool test_unmapped = false;
  T free_log_volume = T(0);

  bool valid() const {
    return base_pairs >= 1 && base_pairs <= kMaxBasePairs && min_inliers >= 3 && margin_nats >= T(0) &&
           std::isfinite(margin_nats) && model.valid() && all_finite(prior_info) && gate_d2 > T(0) && pair_d2 > T(0) &&
           min_base_m >= T(0) && distinct_m > T(0) && distinct_rad > T(0) && std::isfinite(gate_d2) &&
           std::isfinite(pair_d2) && std::isfinite(min_base_m) && std::isfinite(distinct_m) &&
           std::isfinite(distinct_rad) && min_range_m >= T(0) && max_range_m >= T(0) && half_fov_rad > T(0) &&
           min_inlier_ratio >= T(0) && min_inlier_ratio <= T(1) && std::isfinite(max_range_m) &&
           std::isfinite(free_log_volume);
  }
};
/// AlignOptions' members from the table, besides min_inliers (bind_options, bind_loop_options); the rest are constants.
#define GEOJCBB_ALIGN_OPTIONS(F)    \
  F(base_pairs, reloc_base_pairs)   \
  F(margin_nats, reloc_margin_nats) \
  F(min_range_m, min_range_m)       \
  F(max_range_m, max_range_m)       \
  F(half_fov_rad, half_fov_rad)     \
  F(model.p_detect, loop_detection_probability) F(model.unexplained_density, loop_unexplained_density)
/// The relocaliser's alignment from the settings `in` (core/settings.hpp, GEOJCBB_BIND_OPTION).
template <class In, typename T>
void bind_options(const In& in, AlignOptions<T>& out) {
  GEOJCBB_ALIGN_OPTIONS(GEOJCBB_BIND_OPTION)
  GEOJCBB_BIND_OPTION(min_inliers, reloc_min_inliers)
}
/// The loop check's alignment (also the window's and clusters-first's): loop_min_inliers.
template <class In, typename T>
void bind_loop_options(const In& in, AlignOptions<T>& out) {
  GEOJCBB_ALIGN_OPTIONS(GEOJCBB_BIND_OPTION)
  GEOJCBB_BIND_OPTION(min_inliers, loop_min_inliers)
}

/// Poses farther apart than opt.distinct_m, or turned by more than opt.distinct_rad, are distinct.
template <typename T>
bool distinct(const Pose2<T>& a, const Pose2<T>& b, const AlignOptions<T>& opt) {
  const T dx = a.x - b.x, dy = a.y - b.y;
  return dx * dx + dy * dy > opt.distinct_m * opt.distinct_m ||
         std::abs(wrap_angle(a.theta - b.theta)) > opt.distinct_rad;
}

/// Sets the pose prior N(mean, P + hypothesis_floor()). @return false (no prior set: pose-free)
/// when P is not finite or the sum is not positive definite.
template <typename T>
bool set_prior(const Pose2<T>& mean, const Mat3<T>& P, AlignOptions<T>& opt) {
  opt.has_prior = false;
  if (!all_finite(P) || !std::isfinite(mean.x) || !std::isfinite(mean.y) || !std::isfinite(mean.theta)) return false;
  const Mat3<T> A = T(0.5) * (P + P.transpose()) + hypothesis_floor<T>();
  // Positive definite by its leading minors; the inverse by cofactors (3 x 3, symmetric).
  const T m2 = A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1);
  const T c00 = A(1, 1) * A(2, 2) - A(1, 2) * A(1, 2), c01 = A(0, 2) * A(1, 2) - A(0, 1) * A(2, 2);
  const T c02 = A(0, 1) * A(1, 2) - A(0, 2) * A(1, 1), c11 = A(0, 0) * A(2, 2) - A(0, 2) * A(0, 2);
  const T c12 = A(0, 1) * A(0, 2) - A(0, 0) * A(1, 2), c22 = m2;
  const T det = A(0, 0) * c00 + A(0, 1) * c01 + A(0, 2) * c02;
  if (!(A(0, 0) > T(0)) || !(m2 > T(0)) || !(det > T(0))) return false;
  opt.prior_info << c00, c01, c02, c01, c11, c12, c02, c12, c22;
  opt.prior_info /= det;
  opt.prior_half_logdet = T(0.5) * fmath::log(det);
  opt.prior_mean = mean;
  opt.has_prior = all_finite(opt.prior_info);
  return opt.has_prior;
}

/// The prior's d2 of pose x (heading difference wrapped); 0 without a prior.
template <typename T>
T prior_d2(const AlignOptions<T>& opt, const Pose2<T>& x) {
  if (!opt.has_prior) return T(0);
  const Vec3<T> e(x.x - opt.prior_mean.x, x.y - opt.prior_mean.y, wrap_angle(x.theta - opt.prior_mean.theta));
  return e.dot(opt.prior_info * e);
}

}  // namespace geojcbb::reloc
