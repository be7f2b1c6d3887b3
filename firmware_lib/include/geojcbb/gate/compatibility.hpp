// gate: the local region (2019 paper, eq. 5) and the individual compatibility test of every
// (observation i, candidate j) pair:
//   nu_ij = z_i - h_j (bearing wrapped),  S_ij = C_jj + R_i,  d2_ij = nu_ij^T S_ij^-1 nu_ij <= chi2(a, 2)
// Output: per observation, its compatible candidates sorted by d2 (nearest first).
// Packed covariance: a pair is first tested against two lower bounds of its d2
// (Cauchy-Schwarz: for S PD, d2 >= nu_r^2 / S_rr and d2 >= nu_b^2 / S_bb), with a factor 2 of
// margin over rounding; a pair they reject is incompatible without its 2x2 inverse. The nearest d2
// of an unpaired observation (Association::d2) is computed when the answer is written, for those
// observations only.
// Bounds: MaxObservations x MaxCandidates pairs; insertion sort of at most MaxCandidates entries.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "geojcbb/core/association_config.hpp"
#include "geojcbb/core/association_types.hpp"
#include "geojcbb/core/range_bearing.hpp"  // innovation()

namespace geojcbb {

/// d2 = nu^T S^-1 nu for a 2x2 symmetric S (closed form), never negative: +inf when S is not
/// positive definite, so that such a pair fails every gate, and 0 where rounding takes the form of
/// a nearly singular S below 0. (C's blocks are only checked positive semidefinite within rounding,
/// so C + R can be indefinite for a tiny R; the quotient was then negative and passed the gate:
/// fuzz_node's finding, an ASSOC_RESULT with d2 = -4154 that the device could not encode.)
template <typename T>
T mahalanobis2(const Vec2<T>& nu, const Mat2<T>& S) {
  const T det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
  if (!(det > T(0)) || !(S(0, 0) > T(0))) return std::numeric_limits<T>::infinity();
  const T d2 = (S(1, 1) * nu.x() * nu.x() - (S(0, 1) + S(1, 0)) * nu.x() * nu.y() + S(0, 0) * nu.y() * nu.y()) / det;
  return d2 < T(0) ? T(0) : d2;  // NaN stays NaN: no gate passes it
}

/// The local association region (2019 paper, eq. 5): predicted range < r + d, or everything when the
/// region is off. The sensor sits at the robot's origin, so the predicted range is the distance.
template <typename T, class B>
bool in_local_region(const AssociationConfig<T, B>& cfg, const Vec2<T>& h) {
  return !cfg.local_region || h.x() < cfg.local_radius_m;
}

/// @tparam PerObservation  candidates held per observation: all of them for the gate's table; the
///                         merge's repair search holds one (packed covariance: 4.4 KB
///                         less on the M4F).
template <typename T, class B, int PerObservation = B::kMaxCandidates>
struct CompatibilityTable {
  static constexpr int kPerObservation = PerObservation;
  std::array<std::int16_t, B::kMaxObservations> count;  ///< compatible candidates per observation
  /// cand[i][k]: k-th nearest compatible candidate of observation i (k < count[i]).
  std::array<std::array<std::int16_t, PerObservation>, B::kMaxObservations> cand;
  std::array<std::array<T, PerObservation>, B::kMaxObservations> d2;  ///< d2 of cand[i][k]
  std::array<bool, B::kMaxCandidates> in_region;
};

/// d2 of observation i and candidate j (the individual test's statistic).
template <typename T, class B>
T individual_d2(const Observations<T, B>& obs, const Prediction<T, B>& pred, int i, int j) {
  const Mat2<T> S = pred.C.block(j, j) + obs.R[i];
  return mahalanobis2(innovation(obs.z[i], pred.h[j]), S);
}

/// The smallest d2 of observation i over the candidates in the region (`nearest`), and over those
/// the individual gate rejects (`nearest_incompatible`); infinity when there is none.
/// Bound: MaxCandidates.
template <typename T, class B>
void nearest_d2(const Observations<T, B>& obs, const Prediction<T, B>& pred, const CompatibilityTable<T, B>& table,
                T gate, int i, T& nearest, T& nearest_incompatible) {
  nearest = std::numeric_limits<T>::infinity();
  nearest_incompatible = nearest;
  for (int j = 0; j < pred.count; ++j) {  // <= kMaxCandidates
    if (!table.in_region[j]) continue;
    const T d2 = individual_d2(obs, pred, i, j);
    if (d2 < nearest) nearest = d2;
    if (!(d2 <= gate) && d2 < nearest_incompatible) nearest_incompatible = d2;
  }
}

/// Builds the table. Inputs must already be validated (see validate.hpp).
template <typename T, class B>
void build_compatibility(const Observations<T, B>& obs, const Prediction<T, B>& pred,
                         const AssociationConfig<T, B>& cfg, CompatibilityTable<T, B>& table,
                         AssociationDiagnostics& diag) {
  diag.candidates_in_region = 0;
  diag.compatible_pairs = 0;
  for (int j = 0; j < pred.count; ++j) {  // <= kMaxCandidates
    table.in_region[j] = in_local_region(cfg, pred.h[j]);
    if (table.in_region[j]) ++diag.candidates_in_region;
  }
  const T gate = cfg.gate.individual;
  const T bound = T(2) * gate;           // the lower bounds' margin over rounding
  for (int i = 0; i < obs.count; ++i) {  // <= kMaxObservations
    int n = 0;
    const Mat2<T>& R = obs.R[i];
    for (int j = 0; j < pred.count; ++j) {  // <= kMaxCandidates
      if (!table.in_region[j]) continue;
      const Vec2<T> nu = innovation(obs.z[i], pred.h[j]);
      const T s_rr = pred.C(2 * j, 2 * j) + R(0, 0);
      const T s_bb = pred.C(2 * j + 1, 2 * j + 1) + R(1, 1);
      if (nu.x() * nu.x() > bound * s_rr || nu.y() * nu.y() > bound * s_bb) continue;
      const Mat2<T> S = pred.C.block(j, j) + R;
      const T d2 = mahalanobis2(nu, S);
      if (!(d2 <= gate)) continue;
      int k = n++;                                     // insertion sort by d2, ties by candidate index (stable)
      for (; k > 0 && table.d2[i][k - 1] > d2; --k) {  // <= kMaxCandidates
        table.d2[i][k] = table.d2[i][k - 1];
        table.cand[i][k] = table.cand[i][k - 1];
      }
      table.d2[i][k] = d2;
      table.cand[i][k] = static_cast<std::int16_t>(j);
    }
    table.count[i] = static_cast<std::int16_t>(n);
    diag.compatible_pairs = static_cast<std::uint16_t>(diag.compatible_pairs + n);
  }
}

}  // namespace geojcbb
