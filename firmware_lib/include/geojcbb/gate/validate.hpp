// gate: validation of one association call's inputs and options, before any state is touched.
// Checks: counts within capacity, C sized 2n x 2n, every value the call reads finite, ranges >= 0,
// |bearing| <= pi, R_i symmetric positive definite, C's 2x2 diagonal blocks symmetric and positive
// semidefinite. C is checked on the candidates inside the local region only (all when the region is
// off): the call reads nothing else, and the region exists to make a large map cheap.
// C's cross blocks (packed covariance): with CovarianceCheck::kWhereRead (the default)
// they are checked where a stage reads them (IncrementalJoint::try_push, pair_statistic), with the
// same statuses; with kFull, here, every pair of candidates in the region. The Prediction holds C's
// lower block triangle (BlockCovariance), so a cross block is symmetric by storage: kNotSymmetric
// here is a diagonal block's; a dense C's asymmetric cross block is refused where it comes in
// (assign_dense). C's off-diagonal definiteness is checked where it is used: a non-positive
// Cholesky pivot in the joint test.
// Bounds: O(n) over h and C's diagonal blocks (kFull: O(n_region^2) over C), O(m) over observations.
#pragma once

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/gate/compatibility.hpp"

namespace geojcbb {

/// @return kOk; kCapacityExceeded for a count over capacity; kInvalidInput for a negative count, a
///         mis-sized C, a negative range, |bearing| > pi, or bad options; kNonFinite for NaN/Inf;
///         kNotSymmetric / kNotPositiveDefinite for a bad R_i or C.
template <typename T, class B>
[[nodiscard]] Status validate(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                              const AssociationConfig<T, B>& cfg) {
  if (obs.count > B::kMaxObservations || pred.count > B::kMaxCandidates) {
    return Status::kCapacityExceeded;
  }
  if (obs.count < 0 || pred.count < 0) return Status::kInvalidInput;
  if (pred.C.rows() != 2 * pred.count || pred.C.cols() != 2 * pred.count) {
    return Status::kInvalidInput;
  }
  if (cfg.node_budget > B::kMaxJcbbNodes || !cfg.gate.valid()) {
    return Status::kInvalidInput;
  }
  if (cfg.local_region && !(std::isfinite(cfg.local_radius_m) && cfg.local_radius_m > T(0))) {
    return Status::kInvalidInput;
  }
  const int min_groups = cfg.grouping == Grouping::kGmmEm ? 0 : 1;  // EM: 0 chooses K by BIC
  if (cfg.groups < min_groups || cfg.groups > B::kMaxGroups || cfg.kmeans_max_iterations < 1 ||
      cfg.kmeans_max_iterations > kMaxKMeansIterations || cfg.em.max_iterations < 1 ||
      cfg.em.max_iterations > kMaxEmIterations || !(std::isfinite(cfg.em.tolerance) && cfg.em.tolerance >= T(0)) ||
      !(std::isfinite(cfg.em.covariance_floor_m2) && cfg.em.covariance_floor_m2 > T(0)) ||
      (cfg.em.stop != EmStop::kObjective && cfg.em.stop != EmStop::kGroupsStable) ||
      (cfg.em.start != EmStart::kFarthestFirst && cfg.em.start != EmStart::kKMeans) || cfg.em.stable_iterations < 1 ||
      cfg.em.stable_iterations > kMaxEmIterations || !(cfg.em.hard_margin >= T(0) && cfg.em.hard_margin <= T(1)) ||
      (cfg.covariance_check != CovarianceCheck::kWhereRead && cfg.covariance_check != CovarianceCheck::kFull) ||
      !(std::isfinite(cfg.dbscan_eps_m) && cfg.dbscan_eps_m > T(0)) || cfg.dbscan_min_points < 1) {
    return Status::kInvalidInput;
  }
  if ((cfg.verify || cfg.seed) && !consistency_options(cfg).valid()) return Status::kInvalidInput;
  if (cfg.seed && (!(std::isfinite(cfg.seed_min_position_var_m2) && cfg.seed_min_position_var_m2 > T(0)) ||
                   cfg.seed_min_pairings < 2 || cfg.search != SearchMethod::kJcbb)) {
    return Status::kInvalidInput;
  }
  if (cfg.rjc && (cfg.rjc_tries < 1 || cfg.rjc_tries > kMaxRjcTries ||
                  cfg.search_nodes() < static_cast<NodeCount>(cfg.rjc_tries) || cfg.rjc_subset < 1 ||
                  cfg.rjc_subset > B::kMaxObservations || cfg.search != SearchMethod::kJcbb ||
                  cfg.grouping != Grouping::kNone || cfg.margin() > T(0))) {
    return Status::kInvalidInput;
  }
  const Status s = validate_observations(obs);
  if (s != Status::kOk) return s;
  return validate_prediction(
      pred, [&cfg](const Vec2<T>& h) { return in_local_region(cfg, h); },
      cfg.covariance_check == CovarianceCheck::kFull);
}

/// The observations' values (counts are checked by the caller).
/// @return kOk; kNonFinite; kInvalidInput for a negative range or |bearing| > pi; kNotSymmetric /
///         kNotPositiveDefinite for a bad R_i.
template <typename T, class B>
[[nodiscard]] Status validate_observations(const Observations<T, B>& obs) {
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    if (!obs.z[i].allFinite() || !obs.R[i].allFinite()) return Status::kNonFinite;
    if (obs.z[i].x() < T(0) || std::abs(obs.z[i].y()) > kPi<T>) return Status::kInvalidInput;
    if (!nearly_equal(obs.R[i](0, 1), obs.R[i](1, 0))) return Status::kNotSymmetric;
    if (!is_spd(obs.R[i])) return Status::kNotPositiveDefinite;
  }
  return Status::kOk;
}

/// C's 2x2 diagonal block of candidate j: finite, symmetric, positive semidefinite.
/// @return kOk; kNonFinite; kNotSymmetric; kNotPositiveDefinite.
template <typename T, class B>
[[nodiscard]] Status check_diagonal_block(const Prediction<T, B>& pred, int j) {
  const Mat2<T> Cjj = pred.C.block(j, j);
  if (!Cjj.allFinite()) return Status::kNonFinite;
  if (!nearly_equal(Cjj(0, 1), Cjj(1, 0))) return Status::kNotSymmetric;
  return is_psd(Cjj) ? Status::kOk : Status::kNotPositiveDefinite;
}

/// The prediction's values (counts and C's size are checked by the caller); C only on the candidates
/// for which in_region(h) holds: their diagonal blocks, and with `full` every cross block between
/// two of them (otherwise the stages check a cross block when they read it).
/// @return kOk; kNonFinite; kInvalidInput for a negative id; kNotSymmetric / kNotPositiveDefinite
///         for a bad C.
template <typename T, class B, class InRegion>
[[nodiscard]] Status validate_prediction(const Prediction<T, B>& pred, InRegion in_region, bool full = true) {
  for (int j = 0; j < pred.count; ++j) {  // <= kMaxCandidates
    if (!pred.h[j].allFinite()) return Status::kNonFinite;
    if (pred.id[j] < 0) return Status::kInvalidInput;
  }
  if (!full) {
    for (int j = 0; j < pred.count; ++j) {  // <= kMaxCandidates
      if (!in_region(pred.h[j])) continue;
      const Status s = check_diagonal_block(pred, j);
      if (s != Status::kOk) return s;
    }
    return Status::kOk;
  }
  // Every block of candidates inside the local region (all candidates when the region is off),
  // lower triangle against upper.
  for (int j = 0; j < pred.count; ++j) {  // <= kMaxCandidates
    if (!in_region(pred.h[j])) continue;
    for (int k = j; k < pred.count; ++k) {  // <= kMaxCandidates
      if (!in_region(pred.h[k])) continue;
      for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
          if (k == j && a < b) continue;
          const T x = pred.C(2 * k + a, 2 * j + b);
          const T y = pred.C(2 * j + b, 2 * k + a);
          if (!std::isfinite(x) || !std::isfinite(y)) return Status::kNonFinite;
          if (!nearly_equal(x, y)) return Status::kNotSymmetric;
        }
      }
    }
    if (!is_psd(Mat2<T>(pred.C.block(j, j)))) return Status::kNotPositiveDefinite;
  }
  return Status::kOk;
}

}  // namespace geojcbb
