// ekf: fixed-capacity EKF-SLAM, the filter: the state x, and the steps that move and correct it.
//   state  x = [x_r, y_r, theta_r, l1x, l1y, l2x, l2y, ...]   (Layout: named blocks), n = dim()
//   its covariance P in ekf/packed_covariance.hpp, each landmark's record in ekf/landmark_book.hpp
// Every operation it offers:
//   reset / relocalise: the map started at a pose; the pose re-set (the map kept, no correlation)
//   relocalise_fitted:  the pose re-set at a fit to mapped landmarks, correlated with them     O(n p)
//   inflate_pose:       Q added to the pose block (a committed closure), correlations kept     O(1)
//   predict:        x_r <- f(x_r, u),  P_rr <- F P_rr F^T + G Q G^T,  P_rl <- F P_rl          O(n)
//   predict_local:  candidates within r + d (eq. 5), their h_j and C = H P H^T (all cross terms) O(n^2)
//   update:         the associated pairs fused sequentially, kUpdateBlockPairs pairs (rows of H
//                   touching the pose and one landmark each) at a time, linearised once: per block
//                   A = P H_b^T (O(n)), S_b = H_b A + R_b = L L^T, V = A L^-T, x <- x + V L^-1 nu_b,
//                   P <- P - V V^T (PackedCovariance::downdate); equal to one batch update (design.md,
//                   "Covariance engine"); scratch O(n); optionally linearised at another point
//                   (`at`, an iterated step) and in rounds (`rounds`, a closure's most certain first) O(n^2 p)
//   update_alone:   one pair that moves only its landmark (a Schmidt update, tentative landmarks) O(n)
//   augment / add_known_landmark / seed_landmark: a new landmark from the inverse model, a known
//                   one, or one of the global map                                           O(n)
//   review, duplicate_d2, merge, evict: the map's upkeep (ekf/map_upkeep.hpp): landmark
//                   bookkeeping (the book's rules, LandmarkPolicy, and the static gate on x and P):
//                   each landmark's log-odds of existence grows with pairings and falls with misses
//                   in view; a new one is tentative until it passes the confirm threshold, and any
//                   one at the delete threshold is removed (marginalised: x and P compacted, which
//                   is exact for an EKF); a duplicate merged;
//                   the least-seen landmark beyond r + d evicted from a full map            O(n^2)
// Where each is defined: reset, restart, relocalise, relocalise_fitted, inflate_pose and the
// accessors here; predict and predict_local in ekf/slam_predict.hpp; update and update_alone in
// ekf/slam_update.hpp; augment, add_known_landmark and seed_landmark in ekf/slam_augment.hpp; the
// upkeep in ekf/map_upkeep.hpp. Each is declared and documented in the class below.
// First-estimates Jacobians (Huang, Mourikis, Roumeliotis, ICRA 2008; FilterOptions): the
// measurement Jacobians use each landmark's first estimate, and the first prediction after an
// update uses the pose before that update, so the filter gains no information along the directions
// that SLAM cannot observe (global position and heading); the innovations still use the current
// estimate. Without them the heading's variance shrinks while its error grows (docs/mrclam.md).
// Landmark ids are stable (the book hands them out in increasing order and keeps the order), so
// index_of() is a binary search. Predictions, associations and update() speak ids; indices are
// internal, the same in x, P and the book. Bounds: n <= kMaxState = 3 + 2 MaxLandmarks; every loop
// is over the state, the landmarks, the candidates or the pairs of one scan.
// No heap: x, P (packed, K (K + 1) / 2 scalars for K = kMaxState; only cov() reads it from outside)
// and the book are fixed arrays in the object. Every call validates first and changes no state
// unless it returns kOk.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/fmath.hpp"
#include "geojcbb/core/range_bearing.hpp"
#include "geojcbb/ekf/detection.hpp"
#include "geojcbb/ekf/landmark_book.hpp"
#include "geojcbb/ekf/motion.hpp"
#include "geojcbb/ekf/packed_covariance.hpp"

namespace geojcbb::ekf {

/// The state layout as named constant blocks.
struct Layout {
  static constexpr int kPose = 0;  ///< x, y, theta
  static constexpr int kPoseSize = 3;
  static constexpr int landmark(int j) { return kPoseSize + 2 * j; }  ///< first row of landmark j
};

/// Pairs fused per block of the sequential update: 2 x kUpdateBlockPairs columns of scratch per
/// state row. Two pairs (four columns) let the downdate share each row's loads between four
/// products; one pair would halve the scratch and cost more instructions per covariance entry.
constexpr int kUpdateBlockPairs = 2;
constexpr int kUpdateBlockCols = 2 * kUpdateBlockPairs;

/// Caller-owned scratch of predict_local() and update(); typically a static object on the device.
/// O(n): the update's gain is one block of columns at a time (design.md, "Covariance engine").
template <typename T, class B>
struct SlamWorkspace {
  static constexpr int kRows = Layout::landmark(B::kMaxLandmarks);
  std::array<T, static_cast<std::size_t>(kRows) * kUpdateBlockCols> V;  ///< P H_b^T, then P H_b^T L^-T (row-major)
  std::array<T, 2 * B::kMaxObservations> nu;          ///< per pair: innovation at the linearisation point
  std::array<Vec2<T>, B::kMaxObservations> l0;        ///< per pair: its landmark before the update
  std::array<std::int16_t, B::kMaxObservations> obs;  ///< pair -> observation
  std::array<std::int16_t, B::kMaxObservations> lm;   ///< pair -> landmark
  std::array<Mat23<T>, B::kMaxObservations> Hp;       ///< pair -> dh/dpose
  std::array<Mat2<T>, B::kMaxObservations> Hl;        ///< pair -> dh/dlandmark
  /// Diagnostics of the last update(): blocks after the first whose S, or whose resulting pose or
  /// landmark blocks, rounding left not positive definite, or whose mean would overflow (their
  /// fusion skipped, PX4-style), and variances floored (kMinVarianceRatio).
  int rejected_blocks = 0;
  int floored_variances = 0;
  std::array<std::uint16_t, B::kMaxCandidates> cand;  ///< local map: candidate -> landmark
  std::array<T, B::kMaxCandidates> cand_range;        ///< local map: predicted range [m]
  std::array<Mat23<T>, B::kMaxCandidates> cand_Hp;    ///< local map: dh/dpose
  std::array<Mat2<T>, B::kMaxCandidates> cand_Hl;     ///< local map: dh/dlandmark
};

/// Where the sensor can see: review() counts a landmark as expected only when its predicted
/// measurement lies inside. Shrink it by a few sigma so landmarks on the edge are not penalised.
/// Occlusion: with occlusion_rad > 0, a landmark with a nearer one within occlusion_rad of its
/// bearing is hidden behind it, so not expected (tubes in a row, seen along the row).
template <typename T>
struct Visibility {
  T min_range_m = T(0);
  T max_range_m = T(0);
  T half_fov_rad = T(0);
  T occlusion_rad = T(0);
};
/// Candidate a of the prediction is in view: within range and field of view, and no nearer candidate
/// within occlusion_rad of its bearing. The review's and the lost test's one rule. Bound: n with
/// occlusion, else O(1).
template <typename T, class B>
bool in_view(const Prediction<T, B>& pred, int a, const Visibility<T>& view) {
  const Vec2<T>& h = pred.h[a];
  bool seen = h.x() >= view.min_range_m && h.x() <= view.max_range_m && std::abs(h.y()) <= view.half_fov_rad;
  for (int b = 0; b < pred.count && seen && view.occlusion_rad > T(0); ++b) {  // <= kMaxCandidates
    seen = !(b != a && pred.h[b].x() < h.x() && std::abs(wrap_angle(pred.h[b].y() - h.y())) < view.occlusion_rad);
  }
  return seen;
}
/// Visibility's members, all options of the table (core/settings.hpp, bind_options).
#define GEOJCBB_VISIBILITY_OPTIONS(F) \
  F(min_range_m, min_range_m) F(max_range_m, max_range_m) F(half_fov_rad, half_fov_rad) F(occlusion_rad, occlusion_rad)
/// out from the settings `in`.
template <class In, typename T>
void bind_options(const In& in, Visibility<T>& out) {
  GEOJCBB_VISIBILITY_OPTIONS(GEOJCBB_BIND_OPTION)
}

/// How the filter linearises.
struct FilterOptions {
  /// First-estimates Jacobians (see the top of this file). Off: every Jacobian at the current
  /// estimate (the standard EKF).
  bool first_estimates_jacobians = true;
};
/// FilterOptions' members, options of the table (core/settings.hpp, bind_options).
#define GEOJCBB_FILTER_OPTIONS(F) F(first_estimates_jacobians, first_estimates_jacobians)
/// out from the settings `in`.
template <class In>
void bind_options(const In& in, FilterOptions& out) {
  GEOJCBB_FILTER_OPTIONS(GEOJCBB_BIND_OPTION)
}

struct LocalMapStats {
  int in_region = 0;       ///< landmarks within the radius
  bool truncated = false;  ///< more than MaxCandidates were: the nearest were kept
  int confirmed = 0;       ///< the leading candidates that are confirmed (all, unless asked to sort them)
};

template <typename T, class B>
class Slam {
 public:
  static constexpr int kMaxState = Layout::landmark(B::kMaxLandmarks);
  using Covariance = PackedCovariance<T, kMaxState>;
  /// Scalars of the packed covariance: the upper triangle of a kMaxState x kMaxState matrix.
  static constexpr std::size_t kPackedSize = Covariance::kPackedSize;
  /// Variance floor of the update: no fusion may shrink a variance below this fraction of its
  /// value before the block (Covariance::kMinVarianceRatio).
  static constexpr T kMinVarianceRatio = Covariance::kMinVarianceRatio;
  /// merge()'s constraint noise: (1 mm)^2 on each axis of l_keep - l_drop, so S stays definite.
  static constexpr T kMergeNoise_m2 = T(1e-6);

  /// Starts a map at pose x0 with covariance P0 (3x3, symmetric positive definite).
  /// @return kOk; kNonFinite; kNotSymmetric; kNotPositiveDefinite.
  [[nodiscard]] Status reset(const Pose2<T>& x0, const Mat3<T>& P0, const FilterOptions& options = {}) {
    const Status s = check_pose_prior(x0, P0);
    if (s != Status::kOk) return s;
    book_.clear();
    detect_ready_ = false;
    options_ = options;
    updated_ = false;
    x_[0] = x0.x;
    x_[1] = x0.y;
    x_[2] = wrap_angle(x0.theta);
    P_.template set_sym<3>(0, symmetric_part(P0));
    return Status::kOk;
  }

  /// Starts the next local map (sequential map joining with conditionally independent local maps,
  /// Pinies and Tardos 2008; docs/submaps.md): the robot's pose becomes the new map's origin,
  /// (0, 0, 0) with covariance P0 (3x3, symmetric positive definite), uncorrelated with the map.
  /// Landmarks keep[0 .. kept) (increasing indices) stay, expressed in the new frame,
  /// l' = R(theta)^T (l - p), their covariance J [P_rr P_rl; P_lr P_ll] J^T (J with respect to the
  /// pose and the landmark): their estimate conditioned on the new origin. The rest are gone: the
  /// closed map must have been read (handed over) before. The ids go on from the closed map's (a
  /// kept landmark keeps its id, so the host knows the two maps share it). The filter options and
  /// the mount are kept.  O(kept^2), in place.
  /// @return as reset(); kInvalidInput for kept out of range or indices not increasing in range.
  ///         Nothing changes unless kOk.
  [[nodiscard, gnu::noinline, gnu::cold]] Status restart(const Mat3<T>& P0,
                                                         const std::int16_t (&keep)[B::kMaxLandmarks], int kept) {
    const Status s = check_pose_prior(Pose2<T>{T(0), T(0), T(0)}, P0);
    if (s != Status::kOk) return s;
    if (kept < 0 || kept > landmarks()) return Status::kInvalidInput;
    for (int k = 0; k < kept; ++k) {  // <= kMaxLandmarks
      if (keep[k] < 0 || keep[k] >= landmarks() || (k > 0 && keep[k] <= keep[k - 1])) return Status::kInvalidInput;
    }
    move_kept(keep, kept);
    book_.retain(keep, kept);
    reanchor();
    P_.template set_sym<3>(0, symmetric_part(P0));
    return Status::kOk;
  }

  /// Relocalisation (pose-free consistency): the robot was carried somewhere unknown. The
  /// pose estimate becomes x with covariance Pxx and its correlation with the map is removed (the
  /// map no longer says anything about where the robot is); the map and its covariance are kept.
  /// @return as reset(); nothing changes unless kOk.
  [[nodiscard]] Status relocalise(const Pose2<T>& x, const Mat3<T>& Pxx) {
    const Status s = check_pose_prior(x, Pxx);
    if (s != Status::kOk) return s;
    x_[0] = x.x;
    x_[1] = x.y;
    x_[2] = wrap_angle(x.theta);
    updated_ = false;
    P_.template set_sym<3>(0, symmetric_part(Pxx));
    for (int j = 0; j < landmarks(); ++j) {  // <= kMaxLandmarks
      P_.template set_block<3, 2>(0, Layout::landmark(j), Mat32<T>::Zero());
    }
    return Status::kOk;
  }

  /// Relocalisation at a pose fitted to mapped landmarks (reloc::fit_sensitivities): linearised,
  /// x - x* = sum_i A_i (l_i - l_i*) + e, e the observations' part with covariance Pobs. The pose gets
  /// covariance Pobs + sum_ik A_i P_{l_i l_k} A_k^T and cross-covariance sum_i A_i P_{l_i, c} with every
  /// landmark column c: the map's own error moves the fitted pose with it, so it is not counted as
  /// the pose's alone (relocalise() would: the pose independent of the map it was fitted to).
  /// At[i] = A_i^T (2x3) and lm[i] (a landmark index) for i < pairs.  O(n pairs + pairs^2)
  /// @return as relocalise(); kInvalidInput for pairs or an index out of range. Nothing changes
  ///         unless kOk.
  [[nodiscard, gnu::cold]] Status relocalise_fitted(const Pose2<T>& x, const Mat3<T>& Pobs, int pairs,
                                                    const std::int16_t* lm, const Mat23<T>* At) {
    const Status s = check_pose_prior(x, Pobs);
    if (s != Status::kOk) return s;
    if (pairs < 0 || pairs > B::kMaxObservations) return Status::kInvalidInput;
    for (int i = 0; i < pairs; ++i) {  // <= kMaxObservations
      if (lm[i] < 0 || lm[i] >= landmarks()) return Status::kInvalidInput;
    }
    Mat3<T> Prr = symmetric_part(Pobs);
    for (int i = 0; i < pairs; ++i) {    // <= kMaxObservations
      for (int k = 0; k < pairs; ++k) {  // <= kMaxObservations
        const Mat2<T> Pik = P_.template block<2, 2>(Layout::landmark(lm[i]), Layout::landmark(lm[k]));
        Prr += At[i].transpose() * Pik * At[k];
      }
    }
    Prr = symmetric_part(Prr);
    if (!Prr.allFinite()) return Status::kNonFinite;
    if (!is_spd_scaled<T>(Prr)) return Status::kNotPositiveDefinite;
    // The cross blocks read landmark-landmark entries only: written in place, column by column.
    for (int j = 0; j < landmarks(); ++j) {  // <= kMaxLandmarks
      Mat32<T> Prl = Mat32<T>::Zero();
      for (int i = 0; i < pairs; ++i) {  // <= kMaxObservations
        Prl += At[i].transpose() * P_.template block<2, 2>(Layout::landmark(lm[i]), Layout::landmark(j));
      }
      P_.template set_block<3, 2>(0, Layout::landmark(j), Prl);
    }
    x_[0] = x.x;
    x_[1] = x.y;
    x_[2] = wrap_angle(x.theta);
    updated_ = false;
    P_.template set_sym<3>(0, Prr);
    return Status::kOk;
  }

  /// Adds Q (3x3, symmetric positive semi-definite) to the pose block, keeping the pose's
  /// correlation with the map: a loop closure's commit (reloc/loop.hpp) lets the closure move the
  /// pose, and through the correlations the landmarks mapped during the drift.
  /// @return kOk; kNonFinite; kNotSymmetric; kNotPositiveDefinite when Q + eps I is not, or the sum
  ///         would not be. Nothing changes unless kOk.
  [[nodiscard]] Status inflate_pose(const Mat3<T>& Q) {
    if (!Q.allFinite()) return Status::kNonFinite;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < r; ++c)
        if (!nearly_equal(Q(r, c), Q(c, r))) return Status::kNotSymmetric;
    if (Q(0, 0) < T(0) || Q(1, 1) < T(0) || Q(2, 2) < T(0)) return Status::kNotPositiveDefinite;
    const Mat3<T> Prr = pose_covariance() + symmetric_part(Q);
    if (!Prr.allFinite()) return Status::kNonFinite;
    if (!is_spd_scaled<T>(Prr)) return Status::kNotPositiveDefinite;
    P_.template set_sym<3>(0, Prr);
    return Status::kOk;
  }

  /// The pose block of the covariance.
  Mat3<T> pose_covariance() const {
    Mat3<T> Prr;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Prr(r, c) = cov(r, c);
    return Prr;
  }
  /// Writes the pose block back (undoes inflate_pose when the update that followed it failed).
  /// @return kOk; kNotPositiveDefinite (nothing changes).
  [[nodiscard]] Status replace_pose_covariance(const Mat3<T>& Prr) {
    if (!Prr.allFinite() || !is_spd_scaled<T>(symmetric_part(Prr))) return Status::kNotPositiveDefinite;
    P_.template set_sym<3>(0, symmetric_part(Prr));
    return Status::kOk;
  }

  int landmarks() const { return book_.size(); }
  /// The id the next landmark gets: every landmark with a smaller id was mapped before.
  FeatureId next_id() const { return book_.next_id(); }
  /// The stable id of landmark index j (0 <= j < landmarks()).
  FeatureId id(int j) const { return book_[j].id; }
  /// Hits so far of landmark index j (saturating at 65535).
  int hits(int j) const { return book_[j].hits; }
  /// Reviews landmark j was in view or paired (its detection rate's denominator).
  int expected(int j) const { return book_[j].expected; }
  /// Reviews since landmark index j was last paired (saturating at 255).
  int unseen(int j) const { return book_[j].unseen; }
  /// Reviews since landmark j was added (saturating at 255).
  int age(int j) const { return book_[j].age; }
  /// Landmark j fails the static gate (LandmarkPolicy::static_gate_d2 = gate_d2): the review
  /// will remove it as moved if it is paired.
  bool has_moved(int j, T gate_d2) const { return gate_d2 > T(0) && moved(j, gate_d2); }
  /// Landmark j's log-odds of existence has reached the confirm threshold (LandmarkPolicy), or it is known.
  bool confirmed(int j) const { return book_.confirmed(j); }
  /// The landmarks removed since clear_removed(), by every rule (a device reports a scan's in POSE).
  const RemovedIds& removed() const { return book_.removed(); }
  void clear_removed() { book_.clear_removed(); }
  /// Landmark j's log-odds of existence [nats] (LandmarkPolicy).
  T existence(int j) const { return book_.existence(j); }
  /// The index of the landmark with this id, or -1 when there is none (never mapped, or removed).
  int index_of(FeatureId id) const { return book_.index_of(id); }
  int dim() const { return Layout::landmark(landmarks()); }
  Pose2<T> pose() const { return {x_[0], x_[1], x_[2]}; }
  /// Where the sensor sits on the robot (core/range_bearing.hpp); every measurement prediction,
  /// Jacobian and new landmark goes through it. Kept by reset().
  const Mount<T>& mount() const { return mount_; }
  /// @return kOk; kNonFinite for a non-finite mount (then the mount is unchanged).
  [[nodiscard]] Status set_mount(const Mount<T>& m) {
    if (!std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.theta)) return Status::kNonFinite;
    mount_ = m;
    return Status::kOk;
  }
  Vec2<T> landmark(int j) const { return Vec2<T>(x_[Layout::landmark(j)], x_[Layout::landmark(j) + 1]); }
  /// Where the measurement Jacobians of landmark j are evaluated: its first estimate with
  /// first-estimates Jacobians, else its current estimate.
  Vec2<T> linearisation_point(int j) const {
    return options_.first_estimates_jacobians ? Vec2<T>(book_[j].l0[0], book_[j].l0[1]) : landmark(j);
  }
  const FilterOptions& options() const { return options_; }
  T x(int i) const { return x_[i]; }
  /// Entry (r, c) of the covariance (symmetric: cov(r, c) == cov(c, r), one stored scalar).
  T cov(int r, int c) const { return P_.cov(r, c); }
  /// Where entry (r, c) lives in the packed upper triangle (column by column).
  static constexpr std::size_t packed_index(int r, int c) { return Covariance::packed_index(r, c); }

  /// Moves the robot by one odometry interval.
  /// @return kOk; kNonFinite (also when the new pose or covariance would overflow); kInvalidInput
  ///         for dt < 0 or a negative standard deviation. No state changes unless kOk.
  /// Out of line (as apply_motion): the Jacobians stay out of the caller's frame (Node::handle's,
  /// on the stack budget's deepest call chain).
  [[nodiscard, gnu::noinline]] Status predict(const Odometry<T>& u);

  /// The motion of one interval given as a pose increment in the robot's frame with its covariance
  /// (ekf::compose): the pose moved, its covariance F P F^T + J Q J^T, the pose-landmark blocks F P.
  /// @return kOk; kNonFinite (an input, or the result); kNotSymmetric or kNotPositiveDefinite for an
  ///         increment covariance that is not symmetric positive semi-definite (is_psd3);
  ///         kNotPositiveDefinite when the new pose block is not positive definite. Nothing changes
  ///         unless kOk.  O(n)
  [[nodiscard]] Status predict(const PoseIncrement<T>& u);

 private:
  /// predict()'s common part: the pose moves to `next` with Jacobian F and process noise Qx (in
  /// the world frame); F's heading column taken from the pose before the last update (FEJ).
  [[nodiscard, gnu::noinline]] Status apply_motion(const Pose2<T>& next, Mat3<T> F, const Mat3<T>& Qx);

 public:
  /// The association input for the current scan: the landmarks with predicted range < radius_m
  /// (r + d, eq. 5), nearest first and at most MaxCandidates, with their stable ids, predicted
  /// measurements h and C = H P H^T. With `confirmed_first`, the confirmed landmarks
  /// come first (each part nearest first): the first `stats.confirmed` candidates are a prediction
  /// of their own (C's leading blocks), the ones after them tentative.
  /// When the region holds more than MaxCandidates, those behind the sensor make room first: a
  /// landmark whose bearing is nearer the back than the edge of the field of view (|bearing| >
  /// (half_fov_rad + pi) / 2; none when half_fov_rad is pi) cannot be observed, and a tree in view
  /// left out of the candidates would be mapped again. The kept ones are then nearest first.
  /// @return kOk; kInvalidInput for a radius that is not positive and finite, or a half field of
  /// view outside (0, pi].
  [[nodiscard]] Status predict_local(T radius_m, SlamWorkspace<T, B>& ws, Prediction<T, B>& out, LocalMapStats& stats,
                                     bool confirmed_first = false, T half_fov_rad = kPi<T>) const;

  /// One batch update with every paired observation of `assoc` (feature ids are landmark ids).
  /// @return kOk (also with no pairs); kInvalidInput for a count mismatch or an unknown landmark;
  ///         kNonFinite / kNotPositiveDefinite for bad observations or an S that is not positive
  ///         definite; kNotPositiveDefinite also when the covariance that would result has a pose or
  ///         landmark block that rounding left not positive definite, kNonFinite when the mean would
  ///         overflow. No state changes unless kOk. Blocks of pairs after the first that meet any of
  ///         these are skipped (SlamWorkspace::rejected_blocks).
  ///
  /// `at` (nullptr: the estimate): the pose the measurements are linearised at, an iterated EKF's
  /// step from a better point than the estimate (a loop closure's fitted pose, reloc/loop.hpp): the
  /// innovation becomes z - h(at) - H (x - at), the correction still applies to the estimate x.
  ///
  /// `rounds` (nullptr: every pair): observation i's pair takes part only when rounds[i] ==
  /// this_round; a loop closure's pairs applied in rounds, most certain first, each round
  /// linearised at the estimate the rounds before it left (node::SlamStep::step).
  [[nodiscard]] Status update(const Observations<T, B>& obs, const Association<T, B>& assoc, SlamWorkspace<T, B>& ws,
                              const Pose2<T>* at = nullptr, const std::uint8_t* rounds = nullptr, int this_round = 0);

  /// One observation z (noise R) of landmark j that moves only that landmark (a tentative one,
  /// node::SlamStep with tentative_isolated): a Schmidt (consider) update. S = H P H^T + R counts
  /// the pose's and the other landmarks' uncertainty, but the gain is kept only in landmark j's
  /// rows, K_l = P_l. H^T S^-1: x_l += K_l nu, P_ll -= K_l S K_l^T, P_lo -= K_l (H P)_o for every
  /// other row o; the pose and every other landmark keep their mean and their covariance among
  /// themselves. (I - K H) P (I - K H)^T + K R K^T with that K reduces to exactly this, so P stays
  /// positive semi-definite. Jacobians at the landmark's first estimate (FEJ), as update().
  /// @param ws       scratch (its V: P H^T)
  /// @param[out] d2  the pair's nu^T S^-1 nu
  /// @return kOk; kInvalidInput for an index out of range; kNonFinite; kNotPositiveDefinite for R,
  ///         for S or for a landmark block that rounding would leave not positive definite. No
  ///         state changes unless kOk.  O(n)
  [[nodiscard, gnu::noinline, gnu::cold]] Status update_alone(int j, const Vec2<T>& z, const Mat2<T>& R,
                                                              SlamWorkspace<T, B>& ws, T& d2);

  /// Adds a landmark observed at z = (range, bearing) with noise R from the current pose.
  /// The landmark starts tentative with one hit and log-odds 0 (see LandmarkPolicy).
  /// @param[out] id  the new landmark's id (stable for the map's life; never reused)
  /// @return kOk; kCapacityExceeded when MaxLandmarks are mapped or the ids are used up; kNonFinite
  ///         (also when the new landmark's mean or covariance would overflow); kInvalidInput for a
  ///         negative range; kNotPositiveDefinite for R (or a new block that rounding left not
  ///         positive definite). No state changes unless kOk.
  [[nodiscard]] Status augment(const Vec2<T>& z, const Mat2<T>& R, FeatureId& id);

  /// Adds a landmark known beforehand (a surveyed map, localisation only): at l with covariance Pll,
  /// uncorrelated with the rest of the state. It starts with one hit, confirmed, and the evidence
  /// never removes it (LandmarkPolicy).
  /// @param[out] id  the new landmark's id
  /// @return kOk; kNonFinite; kNotPositiveDefinite for Pll; kCapacityExceeded. No state changes
  ///         unless kOk.
  [[nodiscard]] Status add_known_landmark(const Vec2<T>& l, const Mat2<T>& Pll, FeatureId& id);

  /// A landmark of the global map given to this local map (docs/submaps.md, "Seed"; node::seed_map):
  /// at l in this map's frame with covariance Pll, uncorrelated with the pose and with every other
  /// landmark (the seeds' prior is block-diagonal, as SUBMAP_SEED carries it). It starts confirmed,
  /// with `exist_nats` of existence (the evidence the global map banked for it in the maps that made
  /// it, which this one cannot see, capped by the caller at its policy's saturation).
  /// @param[out] id  the new landmark's id
  /// @return kOk; kNonFinite; kNotPositiveDefinite for Pll (checked as augment() does);
  ///         kCapacityExceeded. No state changes unless kOk.  O(n)
  [[nodiscard]] Status seed_landmark(const Vec2<T>& l, const Mat2<T>& Pll, T exist_nats, FeatureId& id);

  /// Landmark bookkeeping after a scan's update and augment: every landmark of `pred` (this scan's
  /// prediction) whose predicted measurement is in `view` was expected; paired by `assoc` (with
  /// observation i of `obs`), it gains a hit, otherwise a miss, and its log-odds of existence the
  /// evidence of either (LandmarkPolicy, ExistenceEvidence; S = C_jj + R, R the paired
  /// observation's, for a miss the scan's first observation's, none in an empty scan). A landmark
  /// at the delete threshold, or tentative for max_tentative_reviews reviews, is removed: its rows
  /// and columns dropped from x and P (marginalised; the other ids are unchanged).
  /// `clock` (nullptr: none) times the evidence alone, without the removals, into *counted.
  /// @return kOk; kInvalidInput for a bad policy or view, or counts out of range. No state changes
  ///         unless kOk.
  /// Out of line: its keep[] (2 bytes a landmark) inlined into the caller's frame took
  /// node::SlamStep::step past 512 B at the large bounds.
  [[nodiscard, gnu::noinline]] Status review(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                             const Association<T, B>& assoc, const Visibility<T>& view,
                                             const LandmarkPolicy& policy, ReviewStats& stats,
                                             std::uint32_t (*clock)() = nullptr, std::uint32_t* counted = nullptr);

  /// The motion test over one scan's pairs, before the update (ekf/motion_test.hpp): with two pairs
  /// or more, each paired landmark (not a known one) takes its innovation less the others' mean; the
  /// observations whose landmark's statistic exceeds `threshold` (> 0; 0: only the evidence is kept),
  /// or whose landmark fails the static gate `static_gate_d2` (> 0; 0: off; moved()), go to
  /// moved[0 .. return), in order. O(kMaxObservations), plus O(kMaxCandidates) for a pair without
  /// its candidate index.
  [[gnu::noinline]] int test_motion(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                    const Association<T, B>& assoc, T threshold, T static_gate_d2,
                                    std::array<std::int16_t, B::kMaxObservations>& moved);
  /// The detection and clutter model the review learns (learn_detection, learn_clutter; reset by
  /// reset(), kept across restart(): it belongs to the sensor and the world, not to a local map).
  const DetectionModel<T>& detection() const { return detect_; }
  /// The motion statistic of landmark j now (0 before its first pairing).
  T motion_statistic(int j) const {
    if constexpr (OptionalStages<B>::kWorldModel) {
      return book_[j].motion.statistic();
    } else {
      (void)j;
      return T(0);
    }
  }

 private:
  /// Pair i's world-frame innovation (world_innovation), its information Sigma^-1 (upper triangle)
  /// and its landmark's index j. @return false for a pair that is none, or a Sigma not definite.
  bool motion_pair(const Observations<T, B>& obs, const Prediction<T, B>& pred, const Association<T, B>& assoc, int i,
                   int& j, T (&delta)[2], T (&Sigma)[3], T (&info)[3]) const;

 public:
  /// Removes the landmark with this id, which the caller knows is not one (a mover): its rows and
  /// columns dropped (marginalised), every other id unchanged.
  /// @return kOk; kInvalidInput when no landmark has this id (then nothing changes).  O(n^2)
  [[nodiscard]] Status forget(FeatureId id) {
    const int j = index_of(id);
    if (j < 0) return Status::kInvalidInput;
    remove(j);
    return Status::kOk;
  }

  /// How far apart landmarks a and b (indices) are, in their own uncertainty: d = l_a - l_b, its
  /// covariance P_aa + P_bb - P_ab - P_ba (their correlation counts: two estimates of one landmark
  /// made from one drifting pose are close in this metric even when far in metres).
  /// @return d^T S^-1 d; +inf for an index out of range, a == b, or S not positive definite. Reads
  ///         only.  O(1). Out of line: the merge stage calls it from two loops.
  [[gnu::noinline]] T duplicate_d2(int a, int b) const;

  /// Landmarks keep and drop (indices) are one landmark mapped twice (a duplicate a loop closure
  /// reveals): the constraint l_keep - l_drop = 0 is fused as an update (H = [0 .. I .. -I ..],
  /// noise kMergeNoise_m2 I, which keeps S definite), then drop is removed (x and P compacted; every
  /// other id unchanged, keep's record takes drop's sightings, LandmarkBook::absorb).
  /// @return kOk; kInvalidInput for an index out of range or keep == drop; kNotPositiveDefinite when
  ///         S, or a pose or landmark block after the downdate, is not; kNonFinite when the mean
  ///         would overflow. No state changes unless kOk.  O(n^2)
  [[nodiscard]] Status merge(int keep, int drop, SlamWorkspace<T, B>& ws);

  /// Makes room in a full map: removes the landmark with the fewest hits among those farther than
  /// radius_m from the robot (beyond the local region, so not in this scan's prediction), the
  /// farthest of equals; every other landmark keeps its id.  O(n^2)
  /// @param[out] evicted  its id (-1 when none)
  /// @return kOk; kCapacityExceeded when no landmark is beyond radius_m (nothing changed).
  [[nodiscard]] Status evict(T radius_m, FeatureId& evicted);

 private:
  /// Removes landmark j (x, P and its record; the others keep their ids and order). Out of line:
  /// its keep[] (2 bytes a landmark) stays out of the caller's frame.  O(n^2)
  [[gnu::noinline]] void remove(int j);
  /// The static gate (LandmarkPolicy::static_gate_d2) on landmark j: a static landmark's estimate
  /// only refines its first one, so l - l0 has covariance P0 - P (the information gained), floored
  /// by kStaticFloor_m2 against a near-singular gain. Whether its d2 exceeds gate_d2.
  bool moved(int j, T gate_d2) const;
  /// review()'s first half: every landmark of pred gains a hit, a miss or nothing (out of view),
  /// its log-odds of existence the evidence of it, and the static gate marks the ones that moved. Out of line so review()'s frame (which holds
  /// keep) stays within the 512-byte budget at the large bounds.
  [[gnu::noinline]] void count_evidence(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                                        const Association<T, B>& assoc, const Visibility<T>& view,
                                        const LandmarkPolicy& policy, ReviewStats& stats);
  /// review()'s compaction of x and P: landmark keep[k] (increasing) becomes landmark k. Every
  /// source index is at or after its destination, so nothing is overwritten before it is read.
  /// Out of line so review()'s frame (which holds keep) stays within the 512-byte budget.
  [[gnu::noinline]] void move_kept(const std::int16_t (&keep)[B::kMaxLandmarks], int kept);
  /// restart()'s change of frame: every landmark, its covariance (with the pose's, then zeroed) and
  /// its first estimate expressed in the robot's frame, the pose at the origin. Each landmark block
  /// is read once, before it is written; the pose rows only at the end.  O(n^2)
  [[gnu::noinline, gnu::cold]] void reanchor();
  /// Landmark index landmarks() at l, whose covariance columns are already set: its state and its
  /// record. @return its id
  FeatureId add_landmark(const Vec2<T>& l, bool known = false);
  /// A pose and its covariance fit to start from: finite, P symmetric positive definite.
  /// @return kOk; kNonFinite; kNotSymmetric; kNotPositiveDefinite.
  [[nodiscard]] static Status check_pose_prior(const Pose2<T>& x0, const Mat3<T>& P0) {
    if (!std::isfinite(x0.x) || !std::isfinite(x0.y) || !std::isfinite(x0.theta) || !P0.allFinite()) {
      return Status::kNonFinite;
    }
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < r; ++c)
        if (!nearly_equal(P0(r, c), P0(c, r))) return Status::kNotSymmetric;
    // Positive definite beyond rounding, on the correlation matrix: Sylvester on the raw entries
    // overflows (a variance of 1e20 in float) and then calls an indefinite matrix definite.
    if (!is_spd_scaled<T>(symmetric_part(P0))) return Status::kNotPositiveDefinite;
    return Status::kOk;
  }
  static bool spd_block(const Mat2<T>& m) { return is_spd_scaled<T>(m(0, 0), m(0, 1), m(1, 1)); }
  /// Whether P - V V^T (Covariance::downdated) keeps the pose block and every landmark's 2x2 block
  /// positive definite beyond rounding (is_spd_scaled). Reads only.  O(n K)
  bool downdate_keeps_blocks_definite(int n, const SlamWorkspace<T, B>& ws) const;

  static constexpr T kStaticFloor_m2 = T(1e-4);  ///< (1 cm)^2: see LandmarkPolicy::static_gate_d2
  std::array<T, kMaxState> x_{};
  Mount<T> mount_{};
  DetectionModel<T> detect_{};
  bool detect_ready_ = false;  ///< detect_ holds the policy's priors (the first review since reset)
  T prior_[2] = {T(0), T(0)};  ///< the position before the updates since the last predict (FEJ)
  Covariance P_;               ///< P, packed
  LandmarkBook<T, B::kMaxLandmarks, OptionalStages<B>::kWorldModel>
      book_;              ///< one record per landmark, in the index order of x and P
  bool updated_ = false;  ///< an update since the last predict
  FilterOptions options_;
};

}  // namespace geojcbb::ekf

// The operations defined in files of their own, one concern each: the prediction (predict,
// apply_motion, predict_local), the correction (update, update_alone), new landmarks (augment,
// add_known_landmark, seed_landmark) and the map's upkeep (review, duplicate_d2, merge, evict,
// remove, moved).
#include "geojcbb/ekf/slam_predict.hpp"  // IWYU pragma: export
#include "geojcbb/ekf/slam_update.hpp"   // IWYU pragma: export
#include "geojcbb/ekf/slam_augment.hpp"  // IWYU pragma: export
#include "geojcbb/ekf/map_upkeep.hpp"    // IWYU pragma: export
